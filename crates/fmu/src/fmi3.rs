//! The FMI 3.0 Co-Simulation functions: the same instances (`Component`) and the same checks
//! as the FMI 2.0 functions of the crate, with the calling conventions of FMI 3.0 (a native resource
//! path, `fmi3Boolean` a C `bool`, array lengths `nValues` beside the value references, the
//! out arguments of `fmi3DoStep`). The variables of an FMU are `Float64`, `Int32`, `Boolean`
//! and `String`; the getters and setters of the other types exist (a master binds them all)
//! and refuse every value reference with `fmi3Error`. The functions of Model Exchange,
//! Scheduled Execution, event mode, clocks and derivatives exist for the same reason and
//! return `fmi3Error` (the model description declares none of them).

use super::*;

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = c_uint;
pub type fmi3Float64 = f64;
pub type fmi3Int32 = i32;
/// A C `bool` (the standard's `fmi3Boolean`).
pub type fmi3Boolean = bool;
pub type fmi3Char = c_char;
pub type fmi3String = *const fmi3Char;

/// `fmi3Status`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum fmi3Status {
    fmi3OK = 0,
    fmi3Warning = 1,
    fmi3Discard = 2,
    fmi3Error = 3,
    fmi3Fatal = 4,
}

use fmi3Status::*;

/// `fmi3LogMessageCallback`.
pub type fmi3LogMessageCallback =
    Option<unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String)>;

/// The FMI 3.0 status of an FMI 2.0 one (the boundary's guards speak FMI 2.0).
pub(crate) fn status(s: fmi2Status) -> fmi3Status {
    match s {
        fmi2OK => fmi3OK,
        fmi2Warning => fmi3Warning,
        fmi2Discard => fmi3Discard,
        fmi2Error | fmi2Pending => fmi3Error,
        fmi2Fatal => fmi3Fatal,
    }
}

/// [`with`] with an FMI 3.0 status.
///
/// # Safety
///
/// As [`component`].
unsafe fn with3(c: fmi3Instance, call: &str, f: impl FnOnce(&mut Component) -> Result<(), BoxError>) -> fmi3Status {
    // SAFETY: the caller's contract.
    status(unsafe { with(c, call, f) })
}

/// `fmi3GetVersion`: `"3.0"`.
#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> fmi3String {
    c"3.0".as_ptr()
}

/// `fmi3InstantiateCoSimulation`: reads the FMU's resources (the study) from `resourcePath`,
/// the resources folder; null, with the reason sent to `logMessage`, when they cannot be read,
/// the token is not this FMU's, or event mode is asked for (the FMU has none).
///
/// # Safety
///
/// The arguments as the FMI 3.0 standard gives them: strings NUL-terminated or null,
/// `logMessage` null or a function that lives as long as the instance.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    _earlyReturnAllowed: fmi3Boolean,
    _requiredIntermediateVariables: *const fmi3ValueReference,
    _nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _intermediateUpdate: *mut c_void,
) -> fmi3Instance {
    let logger = Logger::Fmi3(logMessage);
    // SAFETY: a string argument of the standard.
    let name = unsafe { text(instanceName, "instanceName") }
        .unwrap_or("flexmbs")
        .to_string();
    let cname = CString::new(name.replace('\0', " ")).unwrap_or_default();
    let fail = |message: String| {
        log_to(
            logger,
            instanceEnvironment,
            &cname,
            fmi2Error,
            c"logStatusError",
            &format!("fmi3InstantiateCoSimulation: {message}"),
        );
        std::ptr::null_mut()
    };
    if eventModeUsed {
        return fail("this FMU has no event mode (hasEventMode is false)".into());
    }
    // SAFETY: string arguments of the standard.
    let (token, folder) = match unsafe {
        (
            text(instantiationToken, "instantiationToken"),
            text(resourcePath, "resourcePath"),
        )
    } {
        (Ok(t), Ok(f)) => (t, PathBuf::from(f)),
        (Err(e), _) | (_, Err(e)) => return fail(e),
    };
    let made = catch_unwind(AssertUnwindSafe(|| Instance::new(&folder, Some(token))));
    let instance = match made {
        Ok(Ok(i)) => i,
        Ok(Err(e)) => return fail(e.to_string()),
        Err(_) => return fail("internal error while reading the FMU".into()),
    };
    let c = Box::new(Component {
        instance,
        name: cname.clone(),
        logger,
        environment: instanceEnvironment,
        phase: Phase::Instantiated,
        strings: Vec::new(),
        last_time: 0.0,
    });
    let p = Box::into_raw(c) as fmi3Instance;
    register(&INSTANCES, p, true);
    p
}

/// `fmi3FreeInstance`: frees an instance this library returned (others are ignored).
///
/// # Safety
///
/// `instance` is null or a pointer returned by `fmi3InstantiateCoSimulation`; it is not used
/// again.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    // SAFETY: the same registry and the same `Box<Component>` as FMI 2.0's instances.
    unsafe { fmi2FreeInstance(instance) }
}

/// `fmi3SetDebugLogging`: accepted (errors are always logged).
///
/// # Safety
///
/// `instance` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    _loggingOn: fmi3Boolean,
    _nCategories: usize,
    _categories: *const fmi3String,
) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`.
    unsafe { with3(instance, "fmi3SetDebugLogging", |_| Ok(())) }
}

/// `fmi3EnterInitializationMode`: the start time and, when defined, the stop time (an
/// analysis that ends earlier is extended to it); the tolerance is not used (the analysis
/// keeps its own).
///
/// # Safety
///
/// `instance` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    _toleranceDefined: fmi3Boolean,
    _tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`.
    unsafe {
        with3(instance, "fmi3EnterInitializationMode", |comp| {
            comp.expect("fmi3EnterInitializationMode", &[Phase::Instantiated])?;
            comp.instance
                .setup_experiment(startTime, stopTimeDefined.then_some(stopTime))?;
            comp.phase = Phase::Initialization;
            Ok(())
        })
    }
}

/// `fmi3ExitInitializationMode`: builds the mechanism and starts the analysis; the instance
/// is then in step mode.
///
/// # Safety
///
/// `instance` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`.
    unsafe {
        with3(instance, "fmi3ExitInitializationMode", |comp| {
            comp.expect("fmi3ExitInitializationMode", &[Phase::Initialization])?;
            comp.instance.initialize()?;
            comp.last_time = comp.instance.time().unwrap_or(0.0);
            comp.phase = Phase::Stepping;
            Ok(())
        })
    }
}

/// `fmi3Terminate`.
///
/// # Safety
///
/// `instance` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`.
    unsafe {
        with3(instance, "fmi3Terminate", |comp| {
            comp.expect("fmi3Terminate", &[Phase::Stepping, Phase::Initialization])?;
            comp.phase = Phase::Terminated;
            Ok(())
        })
    }
}

/// `fmi3Reset`: back to the instantiated state (parameters and inputs at their start values).
///
/// # Safety
///
/// `instance` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`.
    unsafe {
        with3(instance, "fmi3Reset", |comp| {
            comp.instance.reset()?;
            comp.phase = Phase::Instantiated;
            comp.last_time = 0.0;
            Ok(())
        })
    }
}

/// `fmi3DoStep`: from `currentCommunicationPoint` over `communicationStepSize`, the inputs
/// held; never an event, an early return or a request to terminate; `lastSuccessfulTime` the
/// time reached (the last converged step when the step fails).
///
/// # Safety
///
/// `instance` as the standard gives it; the four out arguments point to writable values.
#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`; each out pointer is written only when it is
    // non-null and aligned (the standard's contract makes it writable).
    unsafe {
        with3(instance, "fmi3DoStep", |comp| {
            comp.expect("fmi3DoStep", &[Phase::Stepping])?;
            let flags = [eventHandlingNeeded, terminateSimulation, earlyReturn];
            if flags.iter().any(|p| p.is_null() || !p.is_aligned())
                || lastSuccessfulTime.is_null()
                || !lastSuccessfulTime.is_aligned()
            {
                return Err("an out argument (eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime) is a null or misaligned pointer".into());
            }
            for p in flags {
                *p = false;
            }
            let stepped = comp.instance.do_step(currentCommunicationPoint, communicationStepSize);
            comp.last_time = comp.instance.time().unwrap_or(comp.last_time);
            *lastSuccessfulTime = comp.last_time;
            stepped
        })
    }
}

/// The value references of a get or set call and the length of its values, which must be
/// `nvr` (every variable is a scalar).
///
/// # Safety
///
/// As [`references`].
unsafe fn scalars<'a>(
    vr: *const fmi3ValueReference,
    nvr: usize,
    nValues: usize,
) -> Result<&'a [fmi3ValueReference], BoxError> {
    if nValues != nvr {
        return Err(
            format!("{nvr} value references and {nValues} values: every variable of this FMU is a scalar").into(),
        );
    }
    // SAFETY: the caller's contract.
    unsafe { references(vr, nvr) }
}

/// `fmi3GetFloat64`: outputs, inputs, Real parameters and the independent variable `time`
/// (the time reached).
///
/// # Safety
///
/// `instance` as the standard gives it; `vr` an array of `nvr` elements, `values` of
/// `nValues`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`; the arrays by `scalars` and `slice_mut`.
    unsafe {
        with3(instance, "fmi3GetFloat64", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let out = slice_mut(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            let time = study::fmu::time_reference(comp.instance.manifest());
            for (k, &r) in vrs.iter().enumerate() {
                if r == time {
                    out[k] = comp.last_time;
                } else {
                    get_values(comp, &[r], VarType::Real, &mut out[k..=k], |_, v| match v {
                        Value::Real(x) => Ok(x),
                        _ => Err("not a Float64".into()),
                    })?;
                }
            }
            Ok(())
        })
    }
}

/// `fmi3SetFloat64`: inputs (held from the next communication step) and Real parameters
/// (before the initialisation ends). A value that is not finite is refused.
///
/// # Safety
///
/// As [`fmi3GetFloat64`].
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`; the arrays by `scalars` and `slice`.
    unsafe {
        with3(instance, "fmi3SetFloat64", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let values = slice(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |x| Ok(Value::Real(x)))
        })
    }
}

/// `fmi3GetInt32`: Integer parameters.
///
/// # Safety
///
/// As [`fmi3GetFloat64`].
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: as in `fmi3GetFloat64`.
    unsafe {
        with3(instance, "fmi3GetInt32", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let out = slice_mut(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            get_values(comp, vrs, VarType::Integer, out, |_, v| match v {
                Value::Integer(x) => Ok(x),
                _ => Err("not an Int32".into()),
            })
        })
    }
}

/// `fmi3SetInt32`: Integer parameters.
///
/// # Safety
///
/// As [`fmi3GetFloat64`].
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: as in `fmi3SetFloat64`.
    unsafe {
        with3(instance, "fmi3SetInt32", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let values = slice(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |x| Ok(Value::Integer(x)))
        })
    }
}

/// `fmi3GetBoolean`: Boolean parameters.
///
/// # Safety
///
/// As [`fmi3GetFloat64`].
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: as in `fmi3GetFloat64`.
    unsafe {
        with3(instance, "fmi3GetBoolean", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let out = slice_mut(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            get_values(comp, vrs, VarType::Boolean, out, |_, v| match v {
                Value::Boolean(b) => Ok(b),
                _ => Err("not a Boolean".into()),
            })
        })
    }
}

/// `fmi3SetBoolean`: Boolean parameters. The values are read as bytes (any non-zero byte is
/// true), so that a master's byte other than 0 or 1 is no invalid `bool`.
///
/// # Safety
///
/// As [`fmi3GetFloat64`].
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const u8,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: as in `fmi3SetFloat64`; a C `bool` is one byte.
    unsafe {
        with3(instance, "fmi3SetBoolean", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let values = slice(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |x| Ok(Value::Boolean(x != 0)))
        })
    }
}

/// `fmi3GetString`: String parameters; the strings stay valid until the next call on the
/// instance.
///
/// # Safety
///
/// As [`fmi3GetFloat64`].
#[no_mangle]
pub unsafe extern "C" fn fmi3GetString(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3String,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: as in `fmi3GetFloat64`.
    unsafe {
        with3(instance, "fmi3GetString", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let out = slice_mut(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            comp.strings.clear();
            get_values(comp, vrs, VarType::String, out, |comp, v| match v {
                Value::String(s) => {
                    let s = CString::new(s.replace('\0', " "))?;
                    // The CString's buffer does not move when the vector grows.
                    let p = s.as_ptr();
                    comp.strings.push(s);
                    Ok(p)
                }
                _ => Err("not a String".into()),
            })
        })
    }
}

/// `fmi3SetString`: String parameters, each string non-null and UTF-8.
///
/// # Safety
///
/// As [`fmi3GetFloat64`]; every string NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetString(
    instance: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3String,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: as in `fmi3SetFloat64`; each string is checked by `text`.
    unsafe {
        with3(instance, "fmi3SetString", |comp| {
            let vrs = scalars(vr, nvr, nValues)?;
            let values = slice(values, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |s| {
                Ok(Value::String(text(s, "a string value")?.to_string()))
            })
        })
    }
}

/// The error of a get or set call of a type no variable has: the first value reference,
/// named with its variable's type, or unknown.
fn no_variable_of_type(comp: &Component, vrs: &[fmi3ValueReference], ty: &str) -> Result<(), BoxError> {
    let Some(&r) = vrs.first() else { return Ok(()) };
    match comp.instance.manifest().variables.get(r as usize) {
        Some(v) => {
            let is = match v.ty {
                VarType::Real => "Float64",
                VarType::Integer => "Int32",
                VarType::Boolean => "Boolean",
                VarType::String => "String",
            };
            Err(format!("value reference {r} ('{}') is of type {is}, not {ty}", v.name).into())
        }
        None => Err(format!("no variable has the value reference {r} (and no variable of this FMU is a {ty})").into()),
    }
}

/// The getters and setters of the types no variable of a flexmbs FMU has: every value
/// reference is refused. Only the instance, the value references and their count are read
/// (the arguments after them differ between the types and are not used).
macro_rules! other_types {
    ($($name:ident: $ty:literal;)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: no variable of this FMU is a ", $ty, ", so every value reference is refused (none: `fmi3OK`).")]
        ///
        /// # Safety
        ///
        /// `instance` as the standard gives it; `vr` an array of `nvr` elements.
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            instance: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
        ) -> fmi3Status {
            // SAFETY: `instance` is checked by `with3`, `vr` by `references`. The C caller
            // passes more arguments, which are not read: the callers of C functions remove
            // their arguments themselves, so a callee that declares fewer is called correctly.
            unsafe {
                with3(instance, stringify!($name), |comp| {
                    let vrs = references(vr, nvr)?;
                    no_variable_of_type(comp, vrs, $ty)
                })
            }
        }
    )*};
}

other_types! {
    fmi3GetFloat32: "Float32";
    fmi3SetFloat32: "Float32";
    fmi3GetInt8: "Int8";
    fmi3SetInt8: "Int8";
    fmi3GetUInt8: "UInt8";
    fmi3SetUInt8: "UInt8";
    fmi3GetInt16: "Int16";
    fmi3SetInt16: "Int16";
    fmi3GetUInt16: "UInt16";
    fmi3SetUInt16: "UInt16";
    fmi3GetUInt32: "UInt32";
    fmi3SetUInt32: "UInt32";
    fmi3GetInt64: "Int64";
    fmi3SetInt64: "Int64";
    fmi3GetUInt64: "UInt64";
    fmi3SetUInt64: "UInt64";
    fmi3GetBinary: "Binary";
    fmi3SetBinary: "Binary";
    fmi3GetClock: "Clock";
    fmi3SetClock: "Clock";
}

/// `fmi3GetFMUState`: the whole state (simulation, inputs), new or into the state `*state`.
///
/// # Safety
///
/// `instance` as the standard gives it; `state` points to an `fmi3FMUState` (null or one this
/// library returned).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`; `state` is checked non-null and aligned before
    // it is read or written, and `*state` is used only if registered (a live
    // `Box<SavedInstance>` of this library).
    unsafe { with3(instance, "fmi3GetFMUState", |comp| get_state(comp, state)) }
}

/// `fmi3SetFMUState`: back to a state saved by `fmi3GetFMUState` of this FMU.
///
/// # Safety
///
/// `instance` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(instance: fmi3Instance, state: fmi3FMUState) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`; `state` is used only if registered (a live
    // `Box<SavedInstance>` of this library), read through a shared reference.
    unsafe {
        with3(instance, "fmi3SetFMUState", |comp| {
            set_state(comp, state, "fmi3GetFMUState")
        })
    }
}

/// `fmi3FreeFMUState`: frees the state `*state` and sets it to null.
///
/// # Safety
///
/// `instance` as the standard gives it; `state` points to an `fmi3FMUState`.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    // SAFETY: `instance` is checked by `with3`; `state` is checked non-null and aligned, and
    // `*state` freed only if registered (a live `Box<SavedInstance>`), once (unregistered
    // first).
    unsafe { with3(instance, "fmi3FreeFMUState", |_| free_state(state, "fmi3GetFMUState")) }
}

/// The functions this FMU does not provide (the model description declares none of them):
/// `fmi3Error` with the reason. Only the instance is read (the callers of C functions remove
/// their arguments themselves, so a callee that declares fewer is called correctly).
macro_rules! not_provided {
    ($($name:ident: $why:literal;)*) => {$(
        #[doc = concat!("`", stringify!($name), "`: ", $why, ".")]
        ///
        /// # Safety
        ///
        /// `instance` as the standard gives it.
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: fmi3Instance) -> fmi3Status {
            // SAFETY: `instance` is checked by `with3`; the further arguments are not read.
            unsafe { with3(instance, stringify!($name), |_| Err($why.into())) }
        }
    )*};
}

not_provided! {
    fmi3SerializedFMUStateSize: "not supported (canSerializeFMUState is false)";
    fmi3SerializeFMUState: "not supported (canSerializeFMUState is false)";
    fmi3DeserializeFMUState: "not supported (canSerializeFMUState is false)";
    fmi3GetDirectionalDerivative: "not provided (providesDirectionalDerivatives is false)";
    fmi3GetAdjointDerivative: "not provided (providesAdjointDerivatives is false)";
    fmi3GetOutputDerivatives: "not provided (maxOutputDerivativeOrder is 0)";
    fmi3EnterConfigurationMode: "this FMU has no structural parameters";
    fmi3ExitConfigurationMode: "this FMU has no structural parameters";
    fmi3GetNumberOfVariableDependencies: "the dependencies are not provided";
    fmi3GetVariableDependencies: "the dependencies are not provided";
    fmi3GetIntervalDecimal: "this FMU has no clocks";
    fmi3GetIntervalFraction: "this FMU has no clocks";
    fmi3GetShiftDecimal: "this FMU has no clocks";
    fmi3GetShiftFraction: "this FMU has no clocks";
    fmi3SetIntervalDecimal: "this FMU has no clocks";
    fmi3SetIntervalFraction: "this FMU has no clocks";
    fmi3SetShiftDecimal: "this FMU has no clocks";
    fmi3SetShiftFraction: "this FMU has no clocks";
    fmi3EvaluateDiscreteStates: "this FMU has no discrete states";
    fmi3UpdateDiscreteStates: "this FMU has no event mode (hasEventMode is false)";
    fmi3EnterEventMode: "this FMU has no event mode (hasEventMode is false)";
    fmi3EnterStepMode: "this FMU has no event mode (hasEventMode is false): it is in step mode after the initialisation";
    fmi3EnterContinuousTimeMode: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3CompletedIntegratorStep: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3SetTime: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3SetContinuousStates: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3GetContinuousStateDerivatives: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3GetEventIndicators: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3GetContinuousStates: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3GetNominalsOfContinuousStates: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3GetNumberOfEventIndicators: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3GetNumberOfContinuousStates: "this is a Co-Simulation FMU, not Model Exchange";
    fmi3ActivateModelPartition: "this is a Co-Simulation FMU, not Scheduled Execution";
}

/// `fmi3InstantiateModelExchange`: null (this is a Co-Simulation FMU).
#[no_mangle]
pub extern "C" fn fmi3InstantiateModelExchange() -> fmi3Instance {
    std::ptr::null_mut()
}

/// `fmi3InstantiateScheduledExecution`: null (this is a Co-Simulation FMU).
#[no_mangle]
pub extern "C" fn fmi3InstantiateScheduledExecution() -> fmi3Instance {
    std::ptr::null_mut()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fmi3_pointers_this_library_did_not_return_are_refused() {
        // SAFETY: a static NUL-terminated string of this library.
        let version = unsafe { CStr::from_ptr(fmi3GetVersion()) };
        assert_eq!(version.to_str(), Ok("3.0"));
        let mut x = 0u64;
        let stranger = &mut x as *mut u64 as fmi3Instance;
        let vr = [0 as fmi3ValueReference];
        let mut value = [0.0];
        let (mut a, mut b, mut e, mut t) = (false, false, false, 0.0);
        for c in [std::ptr::null_mut(), stranger] {
            // SAFETY: the functions check `c` against their registry before any use; the
            // arrays and out values are valid.
            unsafe {
                assert_eq!(
                    fmi3DoStep(c, 0.0, 1e-3, false, &mut a, &mut b, &mut e, &mut t),
                    fmi3Error
                );
                assert_eq!(fmi3GetFloat64(c, vr.as_ptr(), 1, value.as_mut_ptr(), 1), fmi3Error);
                assert_eq!(fmi3SetFMUState(c, stranger), fmi3Error);
                assert_eq!(fmi3GetInt8(c, vr.as_ptr(), 1), fmi3Error);
                assert_eq!(fmi3EnterEventMode(c), fmi3Error);
                assert_eq!(fmi3Terminate(c), fmi3Error);
                fmi3FreeInstance(c);
            }
        }
        assert_eq!(x, 0, "nothing was written through a pointer the library did not return");
        // Instantiation without a token, a resource path, or with event mode: null.
        // SAFETY: null pointers and static strings, as the function's checks expect.
        unsafe {
            for (token, path, events) in [
                (std::ptr::null(), c"/tmp/".as_ptr(), false),
                (c"{g}".as_ptr(), std::ptr::null(), false),
                (c"{g}".as_ptr(), c"/nonexistent/".as_ptr(), false),
                (c"{g}".as_ptr(), c"/tmp/".as_ptr(), true),
            ] {
                let c = fmi3InstantiateCoSimulation(
                    c"i".as_ptr(),
                    token,
                    path,
                    false,
                    false,
                    events,
                    false,
                    std::ptr::null(),
                    0,
                    std::ptr::null_mut(),
                    None,
                    std::ptr::null_mut(),
                );
                assert!(c.is_null());
            }
        }
    }
}
