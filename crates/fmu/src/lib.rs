//! # flexmbs-fmu: the FMI 2.0 and FMI 3.0 Co-Simulation functions of a flexmbs FMU
//!
//! The shared library an FMU written by `flexmbs export-fmu` carries
//! (`binaries/linux64/<modelIdentifier>.so` in an FMI 2.0 FMU,
//! `binaries/x86_64-linux/<modelIdentifier>.so` in an FMI 3.0 one). It exports the C
//! functions of the FMI 2.0 standard for Co-Simulation (`fmi2Instantiate` to
//! `fmi2FreeInstance`, the setters and getters, `fmi2DoStep`, the FMU state functions) and
//! those of FMI 3.0 ([`fmi3`]: `fmi3InstantiateCoSimulation`, `fmi3DoStep`, ...; the names of
//! the two versions do not clash, so one library serves both), and hands every call to a
//! [`study::fmu::Instance`], which holds the study, its mechanism and the simulation; all the
//! modelling is there, in safe code.
//!
//! ## The unsafe boundary
//!
//! This is the one crate of the workspace allowed `unsafe` (its own lints: every unsafe
//! operation in a block with a `// SAFETY:` comment, `unsafe_op_in_unsafe_fn` denied). What
//! crosses the boundary is checked before use:
//!
//! - an instance (`fmi2Component`) or FMU state (`fmi2FMUstate`) pointer must be one this
//!   library returned and has not freed: both are kept in registries and a pointer that is
//!   not there is refused with `fmi2Error` (a null one too), never dereferenced;
//! - arrays (value references, values) must be non-null and aligned when their length is not
//!   zero; strings must be non-null and UTF-8;
//! - values are checked by the instance: an unknown value reference, a variable of another
//!   type, a NaN or infinite input is an error with a message;
//! - no panic crosses: every call runs under `catch_unwind`; a panic is reported as
//!   `fmi2Fatal` through the logger and the instance refuses further calls.
//!
//! Errors reach the master as `fmi2Error` and a message through its logger callback (category
//! `logStatusError`), located in the study as `flexmbs` locates them.
//!
//! ## The crates `fmi` and `fmi-export`
//!
//! Neither is used. `fmi-export` builds FMI 3.0 FMUs whose variables are the fields of a Rust
//! struct fixed at compile time (a derive macro); an FMU of flexmbs has the variables of a
//! study (its sensors, actuators, loads, parameters), known only when it is exported. `fmi` imports FMUs (it loads their libraries
//! and reads their model descriptions); its type definitions would bring that importer's
//! dependencies into the library and the program for the dozen C types below.

// The names of the C standard: `fmi2Status`, `fmi2DoStep`, `fmi2True`.
#![allow(non_camel_case_types, non_snake_case, non_upper_case_globals)]

pub mod fmi3;

use std::collections::BTreeSet;
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::Mutex;
use study::error::BoxError;
use study::fmu::{Instance, SavedInstance, Value, VarType};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = f64;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;

pub const fmi2True: fmi2Boolean = 1;
pub const fmi2False: fmi2Boolean = 0;

/// `fmi2Status`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum fmi2Status {
    fmi2OK = 0,
    fmi2Warning = 1,
    fmi2Discard = 2,
    fmi2Error = 3,
    fmi2Fatal = 4,
    fmi2Pending = 5,
}

use fmi2Status::*;

/// `fmi2Type` (an `int` in C: the value is checked as one).
pub const fmi2ModelExchange: c_int = 0;
pub const fmi2CoSimulation: c_int = 1;

/// `fmi2StatusKind`.
pub const fmi2DoStepStatus: c_int = 0;
pub const fmi2PendingStatus: c_int = 1;
pub const fmi2LastSuccessfulTime: c_int = 2;
pub const fmi2Terminated: c_int = 3;

/// `fmi2CallbackLogger`: variadic, as the standard declares it (the format is the message).
pub type fmi2CallbackLogger =
    Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...)>;
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// `fmi2CallbackFunctions`. The memory functions are not used (the model description says
/// `canNotUseMemoryManagementFunctions`); only the logger and the environment are kept.
#[repr(C)]
pub struct fmi2CallbackFunctions {
    pub logger: fmi2CallbackLogger,
    pub allocateMemory: fmi2CallbackAllocateMemory,
    pub freeMemory: fmi2CallbackFreeMemory,
    pub stepFinished: fmi2StepFinished,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// Where an instance is in the FMI state machine (the calls each phase takes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Instantiated,
    Initialization,
    Stepping,
    Terminated,
    /// A call panicked: only `fmi2FreeInstance` is taken.
    Broken,
}

/// The master's logger: FMI 2.0's variadic one or FMI 3.0's.
#[derive(Clone, Copy)]
enum Logger {
    Fmi2(fmi2CallbackLogger),
    Fmi3(fmi3::fmi3LogMessageCallback),
}

/// One instance: the model and what the boundary keeps for the master.
struct Component {
    instance: Instance,
    name: CString,
    logger: Logger,
    environment: fmi2ComponentEnvironment,
    phase: Phase,
    /// The strings the last `fmi2GetString` returned (valid until the next call).
    strings: Vec<CString>,
    /// The time of the last successful communication step.
    last_time: f64,
}

/// The addresses of the live instances and FMU states this library returned: a pointer
/// from the master is used only if it is here.
static INSTANCES: Mutex<BTreeSet<usize>> = Mutex::new(BTreeSet::new());
static STATES: Mutex<BTreeSet<usize>> = Mutex::new(BTreeSet::new());

fn registered(set: &Mutex<BTreeSet<usize>>, p: *mut c_void) -> bool {
    !p.is_null() && set.lock().is_ok_and(|s| s.contains(&(p as usize)))
}

fn register(set: &Mutex<BTreeSet<usize>>, p: *mut c_void, add: bool) {
    if let Ok(mut s) = set.lock() {
        if add {
            s.insert(p as usize);
        } else {
            s.remove(&(p as usize));
        }
    }
}

/// Sends `message` to `logger` (if the master gave one). The message is passed as the
/// format: its `%` are doubled so that a master that formats it prints them once.
/// FMI 3.0's logger takes the message as it is.
fn log_to(
    logger: Logger,
    environment: fmi2ComponentEnvironment,
    name: &CStr,
    status: fmi2Status,
    category: &CStr,
    message: &str,
) {
    match logger {
        Logger::Fmi2(Some(logger)) => {
            let text = message.replace('\0', " ").replace('%', "%%");
            let Ok(text) = CString::new(text) else { return };
            // SAFETY: `logger` is the function the master gave in `fmi2CallbackFunctions`
            // for this purpose; every pointer passed is a valid NUL-terminated string that
            // outlives the call, and the format has no conversion, so no variadic argument
            // is read.
            unsafe { logger(environment, name.as_ptr(), status, category.as_ptr(), text.as_ptr()) };
        }
        Logger::Fmi3(Some(logger)) => {
            let Ok(text) = CString::new(message.replace('\0', " ")) else {
                return;
            };
            // SAFETY: `logger` is the `logMessage` function the master gave to
            // `fmi3InstantiateCoSimulation`; both strings are valid, NUL-terminated and
            // outlive the call.
            unsafe { logger(environment, fmi3::status(status), category.as_ptr(), text.as_ptr()) };
        }
        Logger::Fmi2(None) | Logger::Fmi3(None) => {}
    }
}

impl Component {
    fn log(&self, status: fmi2Status, category: &CStr, message: &str) {
        log_to(self.logger, self.environment, &self.name, status, category, message);
    }

    /// Runs `f` on the instance, its error logged and returned as `fmi2Error`, a panic as
    /// `fmi2Fatal` (the instance is then refused).
    fn guard(&mut self, call: &str, f: impl FnOnce(&mut Self) -> Result<(), BoxError>) -> fmi2Status {
        if self.phase == Phase::Broken {
            self.log(
                fmi2Error,
                c"logStatusError",
                &format!("{call}: an earlier call failed fatally; only fmi2FreeInstance is possible"),
            );
            return fmi2Error;
        }
        match catch_unwind(AssertUnwindSafe(|| f(self))) {
            Ok(Ok(())) => fmi2OK,
            Ok(Err(e)) => {
                self.log(fmi2Error, c"logStatusError", &format!("{call}: {e}"));
                fmi2Error
            }
            Err(panic) => {
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic".into());
                self.phase = Phase::Broken;
                self.log(fmi2Fatal, c"logStatusFatal", &format!("{call}: internal error: {what}"));
                fmi2Fatal
            }
        }
    }

    fn expect(&self, call: &str, phases: &[Phase]) -> Result<(), BoxError> {
        if phases.contains(&self.phase) {
            return Ok(());
        }
        Err(format!("{call} is not allowed now (the instance is in {:?})", self.phase).into())
    }
}

/// The instance behind `c`, if it is one this library returned and has not freed.
///
/// # Safety
///
/// No other reference to the instance may be alive: the master calls an instance from one
/// thread at a time (FMI 2.0, section 2.1.3), and no function of this library keeps one
/// across calls.
unsafe fn component<'a>(c: fmi2Component) -> Option<&'a mut Component> {
    if !registered(&INSTANCES, c) {
        return None;
    }
    // SAFETY: `c` is registered: it is a `Box<Component>` leaked by `fmi2Instantiate` and
    // not yet freed (`fmi2FreeInstance` unregisters before freeing), so it points to a live,
    // aligned `Component`; the caller guarantees no other reference to it.
    Some(unsafe { &mut *(c as *mut Component) })
}

/// A string from the master: non-null and UTF-8.
///
/// # Safety
///
/// `s`, when not null, points to a NUL-terminated string that lives for the call (the
/// FMI contract for every `fmi2String` argument).
unsafe fn text<'a>(s: fmi2String, what: &str) -> Result<&'a str, String> {
    if s.is_null() {
        return Err(format!("{what} is a null pointer"));
    }
    // SAFETY: non-null and NUL-terminated by the caller's contract.
    let c = unsafe { CStr::from_ptr(s) };
    c.to_str().map_err(|_| format!("{what} is not UTF-8"))
}

/// `n` elements at `p` as a slice; `None` when `p` is null or misaligned and `n` is not zero.
///
/// # Safety
///
/// `p`, when not null, points to `n` initialised elements that live for the call.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() || !p.is_aligned() {
        return None;
    }
    // SAFETY: non-null, aligned, and `n` elements by the caller's contract.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

/// [`slice()`] for an array the library writes.
///
/// # Safety
///
/// `p`, when not null, points to `n` elements writable for the call, not aliased.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() || !p.is_aligned() {
        return None;
    }
    // SAFETY: non-null, aligned, and `n` writable elements by the caller's contract.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// The folder of a `file:` URI (`file:///tmp/x/resources`, `file:/tmp/x`), percent-decoded.
fn resource_folder(uri: &str) -> Result<PathBuf, String> {
    let rest = uri
        .strip_prefix("file://")
        .map(|r| {
            // `file://localhost/path` or `file:///path`.
            r.strip_prefix("localhost").unwrap_or(r)
        })
        .or_else(|| uri.strip_prefix("file:"))
        .ok_or_else(|| format!("the resource location '{uri}' is not a file: URI"))?;
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(b) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(b);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    let path = String::from_utf8(out).map_err(|_| format!("the resource location '{uri}' is not UTF-8"))?;
    Ok(PathBuf::from(path))
}

/// `fmi2GetTypesPlatform`: `"default"`.
#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> fmi2String {
    c"default".as_ptr()
}

/// `fmi2GetVersion`: `"2.0"`.
#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> fmi2String {
    c"2.0".as_ptr()
}

/// `fmi2Instantiate`: reads the FMU's resources (the study); null, with the reason sent to
/// the logger, when they cannot be read or the arguments are not those of this FMU.
///
/// # Safety
///
/// The arguments as the FMI 2.0 standard gives them: strings NUL-terminated or null,
/// `functions` null or pointing to an `fmi2CallbackFunctions` that lives as long as the
/// instance.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: c_int,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    _loggingOn: fmi2Boolean,
) -> fmi2Component {
    let (logger, environment) = if functions.is_null() || !functions.is_aligned() {
        (None, std::ptr::null_mut())
    } else {
        // SAFETY: non-null and aligned; the master's struct lives for the instance.
        let f = unsafe { &*functions };
        (f.logger, f.componentEnvironment)
    };
    // SAFETY: a string argument of the standard.
    let name = unsafe { text(instanceName, "instanceName") }
        .unwrap_or("flexmbs")
        .to_string();
    let cname = CString::new(name.replace('\0', " ")).unwrap_or_default();
    let fail = |message: String| {
        log_to(
            Logger::Fmi2(logger),
            environment,
            &cname,
            fmi2Error,
            c"logStatusError",
            &format!("fmi2Instantiate: {message}"),
        );
        std::ptr::null_mut()
    };
    if functions.is_null() {
        return fail("the callback functions are a null pointer".into());
    }
    if fmuType != fmi2CoSimulation {
        return fail(format!(
            "this FMU is for Co-Simulation (fmuType {fmi2CoSimulation}), not fmuType {fmuType}"
        ));
    }
    // SAFETY: string arguments of the standard.
    let (guid, location) = match unsafe {
        (
            text(fmuGUID, "fmuGUID"),
            text(fmuResourceLocation, "fmuResourceLocation"),
        )
    } {
        (Ok(g), Ok(l)) => (g, l),
        (Err(e), _) | (_, Err(e)) => return fail(e),
    };
    let folder = match resource_folder(location) {
        Ok(f) => f,
        Err(e) => return fail(e),
    };
    let made = catch_unwind(AssertUnwindSafe(|| Instance::new(&folder, Some(guid))));
    let instance = match made {
        Ok(Ok(i)) => i,
        Ok(Err(e)) => return fail(e.to_string()),
        Err(_) => return fail("internal error while reading the FMU".into()),
    };
    let c = Box::new(Component {
        instance,
        name: cname.clone(),
        logger: Logger::Fmi2(logger),
        environment,
        phase: Phase::Instantiated,
        strings: Vec::new(),
        last_time: 0.0,
    });
    let p = Box::into_raw(c) as fmi2Component;
    register(&INSTANCES, p, true);
    p
}

/// `fmi2FreeInstance`: frees an instance this library returned (others are ignored).
///
/// # Safety
///
/// `c` is null or a pointer returned by `fmi2Instantiate`; it is not used again.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !registered(&INSTANCES, c) {
        return;
    }
    register(&INSTANCES, c, false);
    // SAFETY: registered until the line above, so a live `Box<Component>` from
    // `fmi2Instantiate`, freed once (it is no longer registered).
    let b = unsafe { Box::from_raw(c as *mut Component) };
    let _ = catch_unwind(AssertUnwindSafe(move || drop(b)));
}

/// Runs `f` on the instance `c` (refused when `c` is not one).
///
/// # Safety
///
/// As [`component`].
unsafe fn with(c: fmi2Component, call: &str, f: impl FnOnce(&mut Component) -> Result<(), BoxError>) -> fmi2Status {
    // SAFETY: the caller's contract.
    match unsafe { component(c) } {
        Some(comp) => comp.guard(call, f),
        None => fmi2Error,
    }
}

/// `fmi2SetDebugLogging`: accepted (errors are always logged).
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    _loggingOn: fmi2Boolean,
    _nCategories: usize,
    _categories: *const fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe { with(c, "fmi2SetDebugLogging", |_| Ok(())) }
}

/// `fmi2SetupExperiment`: the start time and, when defined, the stop time (an analysis
/// that ends earlier is extended to it).
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _toleranceDefined: fmi2Boolean,
    _tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2SetupExperiment", |comp| {
            comp.expect("fmi2SetupExperiment", &[Phase::Instantiated])?;
            let stop = (stopTimeDefined != fmi2False).then_some(stopTime);
            comp.instance.setup_experiment(startTime, stop)
        })
    }
}

/// `fmi2EnterInitializationMode`.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2EnterInitializationMode", |comp| {
            comp.expect("fmi2EnterInitializationMode", &[Phase::Instantiated])?;
            comp.phase = Phase::Initialization;
            Ok(())
        })
    }
}

/// `fmi2ExitInitializationMode`: builds the mechanism and starts the analysis (the start
/// chain of the study: equilibrium, consistent initial state).
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2ExitInitializationMode", |comp| {
            comp.expect("fmi2ExitInitializationMode", &[Phase::Initialization])?;
            comp.instance.initialize()?;
            comp.last_time = comp.instance.time().unwrap_or(0.0);
            comp.phase = Phase::Stepping;
            Ok(())
        })
    }
}

/// `fmi2Terminate`.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2Terminate", |comp| {
            comp.expect("fmi2Terminate", &[Phase::Stepping, Phase::Initialization])?;
            comp.phase = Phase::Terminated;
            Ok(())
        })
    }
}

/// `fmi2Reset`: back to the instantiated state (parameters and inputs at their start values).
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2Reset", |comp| {
            comp.instance.reset()?;
            comp.phase = Phase::Instantiated;
            comp.last_time = 0.0;
            Ok(())
        })
    }
}

/// The value references and the values of a get or set call.
///
/// # Safety
///
/// `vr` points to `nvr` value references (when `nvr` is not zero).
unsafe fn references<'a>(vr: *const fmi2ValueReference, nvr: usize) -> Result<&'a [fmi2ValueReference], BoxError> {
    // SAFETY: the caller's contract.
    unsafe { slice(vr, nvr) }.ok_or_else(|| "the value references are a null or misaligned pointer".into())
}

fn get_values<T>(
    comp: &mut Component,
    vrs: &[fmi2ValueReference],
    ty: VarType,
    out: &mut [T],
    convert: impl Fn(&mut Component, Value) -> Result<T, BoxError>,
) -> Result<(), BoxError> {
    comp.expect(
        "a get function",
        &[
            Phase::Instantiated,
            Phase::Initialization,
            Phase::Stepping,
            Phase::Terminated,
        ],
    )?;
    for (k, &r) in vrs.iter().enumerate() {
        let v = comp.instance.get(r, ty)?;
        out[k] = convert(comp, v)?;
    }
    Ok(())
}

fn set_values<T: Copy>(
    comp: &mut Component,
    vrs: &[fmi2ValueReference],
    values: &[T],
    convert: impl Fn(T) -> Result<Value, BoxError>,
) -> Result<(), BoxError> {
    comp.expect(
        "a set function",
        &[Phase::Instantiated, Phase::Initialization, Phase::Stepping],
    )?;
    for (&r, &x) in vrs.iter().zip(values) {
        comp.instance.set(r, convert(x)?)?;
    }
    Ok(())
}

/// `fmi2GetReal`.
///
/// # Safety
///
/// `c` as the standard gives it; `vr` and `value` arrays of `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; the arrays by `references` and `slice_mut` (non-null,
    // aligned, `nvr` elements by the caller's contract).
    unsafe {
        with(c, "fmi2GetReal", |comp| {
            let vrs = references(vr, nvr)?;
            let out = slice_mut(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            get_values(comp, vrs, VarType::Real, out, |_, v| match v {
                Value::Real(x) => Ok(x),
                _ => Err("not a Real".into()),
            })
        })
    }
}

/// `fmi2GetInteger`.
///
/// # Safety
///
/// As [`fmi2GetReal`].
#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    // SAFETY: as in `fmi2GetReal`.
    unsafe {
        with(c, "fmi2GetInteger", |comp| {
            let vrs = references(vr, nvr)?;
            let out = slice_mut(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            get_values(comp, vrs, VarType::Integer, out, |_, v| match v {
                Value::Integer(x) => Ok(x),
                _ => Err("not an Integer".into()),
            })
        })
    }
}

/// `fmi2GetBoolean`.
///
/// # Safety
///
/// As [`fmi2GetReal`].
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: as in `fmi2GetReal`.
    unsafe {
        with(c, "fmi2GetBoolean", |comp| {
            let vrs = references(vr, nvr)?;
            let out = slice_mut(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            get_values(comp, vrs, VarType::Boolean, out, |_, v| match v {
                Value::Boolean(b) => Ok(if b { fmi2True } else { fmi2False }),
                _ => Err("not a Boolean".into()),
            })
        })
    }
}

/// `fmi2GetString`: the strings stay valid until the next call on the instance.
///
/// # Safety
///
/// As [`fmi2GetReal`].
#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: as in `fmi2GetReal`.
    unsafe {
        with(c, "fmi2GetString", |comp| {
            let vrs = references(vr, nvr)?;
            let out = slice_mut(value, nvr).ok_or("the values are a null or misaligned pointer")?;
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

/// `fmi2SetReal`: inputs (held from the next communication step) and Real parameters
/// (before the initialisation ends). A value that is not finite is refused.
///
/// # Safety
///
/// `c` as the standard gives it; `vr` and `value` arrays of `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; the arrays by `references` and `slice`.
    unsafe {
        with(c, "fmi2SetReal", |comp| {
            let vrs = references(vr, nvr)?;
            let values = slice(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |x| Ok(Value::Real(x)))
        })
    }
}

/// `fmi2SetInteger`.
///
/// # Safety
///
/// As [`fmi2SetReal`].
#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    // SAFETY: as in `fmi2SetReal`.
    unsafe {
        with(c, "fmi2SetInteger", |comp| {
            let vrs = references(vr, nvr)?;
            let values = slice(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |x| Ok(Value::Integer(x)))
        })
    }
}

/// `fmi2SetBoolean`.
///
/// # Safety
///
/// As [`fmi2SetReal`].
#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    // SAFETY: as in `fmi2SetReal`.
    unsafe {
        with(c, "fmi2SetBoolean", |comp| {
            let vrs = references(vr, nvr)?;
            let values = slice(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |x| Ok(Value::Boolean(x != fmi2False)))
        })
    }
}

/// `fmi2SetString`: each string non-null and UTF-8.
///
/// # Safety
///
/// As [`fmi2SetReal`]; every string NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    // SAFETY: as in `fmi2SetReal`; each string is checked by `text`.
    unsafe {
        with(c, "fmi2SetString", |comp| {
            let vrs = references(vr, nvr)?;
            let values = slice(value, nvr).ok_or("the values are a null or misaligned pointer")?;
            set_values(comp, vrs, values, |s| {
                Ok(Value::String(text(s, "a string value")?.to_string()))
            })
        })
    }
}

/// `fmi2DoStep`: from `currentCommunicationPoint` over `communicationStepSize`, the inputs
/// held; several steps of the analysis when the communication step is longer than its step.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2DoStep", |comp| {
            comp.expect("fmi2DoStep", &[Phase::Stepping])?;
            comp.instance
                .do_step(currentCommunicationPoint, communicationStepSize)?;
            comp.last_time = comp.instance.time().unwrap_or(comp.last_time);
            Ok(())
        })
    }
}

/// `fmi2CancelStep`: steps are never asynchronous, so there is none to cancel.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2CancelStep", |_| {
            Err("no step is pending (steps are synchronous)".into())
        })
    }
}

/// The body of `fmi2GetFMUstate` and `fmi3GetFMUState`: `comp`'s whole state into the state
/// `*state` when it is one this library returned, else into a new one stored there.
///
/// # Safety
///
/// `state` is null or points to a state pointer the master owns (checked non-null and aligned
/// here before it is read or written).
unsafe fn get_state(comp: &mut Component, state: *mut *mut c_void) -> Result<(), BoxError> {
    if state.is_null() || !state.is_aligned() {
        return Err("the FMU state pointer is null or misaligned".into());
    }
    let saved = comp.instance.save();
    // SAFETY: `state` is non-null and aligned (above) and points to the master's state
    // pointer; `*state` is written through only if registered (a live `Box<SavedInstance>`
    // of this library).
    unsafe {
        let old = *state;
        if registered(&STATES, old) {
            *(old as *mut SavedInstance) = saved;
        } else {
            let p = Box::into_raw(Box::new(saved)) as *mut c_void;
            register(&STATES, p, true);
            *state = p;
        }
    }
    Ok(())
}

/// The body of `fmi2SetFMUstate` and `fmi3SetFMUState`: `comp` back to the state `state`,
/// which `getter` (the standard's function name) must have returned.
fn set_state(comp: &mut Component, state: *mut c_void, getter: &str) -> Result<(), BoxError> {
    if !registered(&STATES, state) {
        return Err(format!("the FMU state is not one {getter} returned (or it was freed)").into());
    }
    // SAFETY: `state` is registered: a live `Box<SavedInstance>` of this library, read through
    // a shared reference.
    let saved = unsafe { &*(state as *const SavedInstance) };
    comp.instance.restore(saved)?;
    comp.last_time = comp.instance.time().unwrap_or(comp.last_time);
    if comp.instance.time().is_some() && comp.phase == Phase::Terminated {
        comp.phase = Phase::Stepping;
    }
    Ok(())
}

/// The body of `fmi2FreeFMUstate` and `fmi3FreeFMUState`: frees the state `*state` (one
/// `getter` returned) and sets it to null.
///
/// # Safety
///
/// `state` is null or points to a state pointer the master owns (checked here).
unsafe fn free_state(state: *mut *mut c_void, getter: &str) -> Result<(), BoxError> {
    if state.is_null() || !state.is_aligned() {
        return Err("the FMU state pointer is null or misaligned".into());
    }
    // SAFETY: `state` is non-null and aligned (above); `*state` is freed only if registered
    // (a live `Box<SavedInstance>`), once (unregistered first).
    unsafe {
        let p = *state;
        if p.is_null() {
            return Ok(());
        }
        if !registered(&STATES, p) {
            return Err(format!("the FMU state is not one {getter} returned (or it was freed)").into());
        }
        register(&STATES, p, false);
        drop(Box::from_raw(p as *mut SavedInstance));
        *state = std::ptr::null_mut();
    }
    Ok(())
}

/// `fmi2GetFMUstate`: the whole state (simulation, inputs), new or into the state `*state`.
///
/// # Safety
///
/// `c` as the standard gives it; `state` points to an `fmi2FMUstate` (null or one this
/// library returned).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; `state` is checked non-null and aligned before it
    // is read or written, and `*state` is used only if registered (a live
    // `Box<SavedInstance>` of this library).
    unsafe { with(c, "fmi2GetFMUstate", |comp| get_state(comp, state)) }
}

/// `fmi2SetFMUstate`: back to a state saved by `fmi2GetFMUstate` of this FMU.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; `state` is used only if registered (a live
    // `Box<SavedInstance>` of this library), read through a shared reference.
    unsafe { with(c, "fmi2SetFMUstate", |comp| set_state(comp, state, "fmi2GetFMUstate")) }
}

/// `fmi2FreeFMUstate`: frees the state `*state` and sets it to null.
///
/// # Safety
///
/// `c` as the standard gives it; `state` points to an `fmi2FMUstate`.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; `state` is checked non-null and aligned, and `*state`
    // freed only if registered (a live `Box<SavedInstance>`), once (unregistered first).
    unsafe { with(c, "fmi2FreeFMUstate", |_| free_state(state, "fmi2GetFMUstate")) }
}

const NO_SERIALIZATION: &str = "this FMU does not serialize its state (canSerializeFMUstate is false)";

/// `fmi2SerializedFMUstateSize`: not supported.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    _state: fmi2FMUstate,
    _size: *mut usize,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe { with(c, "fmi2SerializedFMUstateSize", |_| Err(NO_SERIALIZATION.into())) }
}

/// `fmi2SerializeFMUstate`: not supported.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    _state: fmi2FMUstate,
    _bytes: *mut fmi2Byte,
    _size: usize,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe { with(c, "fmi2SerializeFMUstate", |_| Err(NO_SERIALIZATION.into())) }
}

/// `fmi2DeSerializeFMUstate`: not supported.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    _bytes: *const fmi2Byte,
    _size: usize,
    _state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe { with(c, "fmi2DeSerializeFMUstate", |_| Err(NO_SERIALIZATION.into())) }
}

/// `fmi2GetDirectionalDerivative`: not provided.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2GetDirectionalDerivative", |_| {
            Err("this FMU provides no directional derivatives".into())
        })
    }
}

/// `fmi2SetRealInputDerivatives`: not supported (inputs are held over a step).
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2SetRealInputDerivatives", |_| {
            Err("this FMU holds its inputs over a step (canInterpolateInputs is false)".into())
        })
    }
}

/// `fmi2GetRealOutputDerivatives`: not supported.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is checked by `with`.
    unsafe {
        with(c, "fmi2GetRealOutputDerivatives", |_| {
            Err("this FMU provides no output derivatives (maxOutputDerivativeOrder is 0)".into())
        })
    }
}

/// `fmi2GetStatus`: steps are synchronous; there is no pending status.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(c: fmi2Component, _s: c_int, _value: *mut fmi2Status) -> fmi2Status {
    // SAFETY: `c` is checked by `component`.
    if unsafe { component(c) }.is_none() {
        return fmi2Error;
    }
    fmi2Discard
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime`, the time of the last communication point
/// reached.
///
/// # Safety
///
/// `c` as the standard gives it; `value` points to an `fmi2Real`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(c: fmi2Component, s: c_int, value: *mut fmi2Real) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; `value` is checked non-null and aligned.
    unsafe {
        with(c, "fmi2GetRealStatus", |comp| {
            if s != fmi2LastSuccessfulTime {
                return Err(format!("status kind {s} is not a Real status").into());
            }
            if value.is_null() || !value.is_aligned() {
                return Err("the value pointer is null or misaligned".into());
            }
            *value = comp.last_time;
            Ok(())
        })
    }
}

/// `fmi2GetIntegerStatus`: none.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(c: fmi2Component, _s: c_int, _value: *mut fmi2Integer) -> fmi2Status {
    // SAFETY: `c` is checked by `component`.
    if unsafe { component(c) }.is_none() {
        return fmi2Error;
    }
    fmi2Discard
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated` is always false (the FMU never ends a
/// simulation by itself).
///
/// # Safety
///
/// `c` as the standard gives it; `value` points to an `fmi2Boolean`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(c: fmi2Component, s: c_int, value: *mut fmi2Boolean) -> fmi2Status {
    // SAFETY: `c` is checked by `with`; `value` is checked non-null and aligned.
    unsafe {
        with(c, "fmi2GetBooleanStatus", |_| {
            if s != fmi2Terminated {
                return Err(format!("status kind {s} is not a Boolean status").into());
            }
            if value.is_null() || !value.is_aligned() {
                return Err("the value pointer is null or misaligned".into());
            }
            *value = fmi2False;
            Ok(())
        })
    }
}

/// `fmi2GetStringStatus`: none.
///
/// # Safety
///
/// `c` as the standard gives it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(c: fmi2Component, _s: c_int, _value: *mut fmi2String) -> fmi2Status {
    // SAFETY: `c` is checked by `component`.
    if unsafe { component(c) }.is_none() {
        return fmi2Error;
    }
    fmi2Discard
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointers_this_library_did_not_return_are_refused() {
        // SAFETY: the version strings are static NUL-terminated strings of this library.
        let version = unsafe { CStr::from_ptr(fmi2GetVersion()) };
        assert_eq!(version.to_str(), Ok("2.0"));
        let mut x = 0u64;
        let stranger = &mut x as *mut u64 as fmi2Component;
        let vr = [0 as fmi2ValueReference];
        let mut value = [0.0];
        for c in [std::ptr::null_mut(), stranger] {
            // SAFETY: the functions check `c` against their registry before any use; the
            // arrays are valid for one element.
            unsafe {
                assert_eq!(fmi2DoStep(c, 0.0, 1e-3, fmi2False), fmi2Error);
                assert_eq!(fmi2GetReal(c, vr.as_ptr(), 1, value.as_mut_ptr()), fmi2Error);
                assert_eq!(fmi2SetFMUstate(c, stranger), fmi2Error);
                assert_eq!(fmi2Terminate(c), fmi2Error);
                fmi2FreeInstance(c);
            }
        }
        assert_eq!(x, 0, "nothing was written through a pointer the library did not return");
        // Instantiation without callbacks, or of another type, or without strings: null.
        // SAFETY: null pointers and static strings, as the function's checks expect.
        unsafe {
            let c = fmi2Instantiate(
                c"i".as_ptr(),
                fmi2CoSimulation,
                c"{guid}".as_ptr(),
                c"file:///nonexistent".as_ptr(),
                std::ptr::null(),
                fmi2False,
                fmi2False,
            );
            assert!(c.is_null());
            let callbacks = fmi2CallbackFunctions {
                logger: None,
                allocateMemory: None,
                freeMemory: None,
                stepFinished: None,
                componentEnvironment: std::ptr::null_mut(),
            };
            for (ty, guid, location) in [
                (fmi2ModelExchange, c"{g}".as_ptr(), c"file:///tmp".as_ptr()),
                (fmi2CoSimulation, std::ptr::null(), c"file:///tmp".as_ptr()),
                (fmi2CoSimulation, c"{g}".as_ptr(), c"http://x".as_ptr()),
                (fmi2CoSimulation, c"{g}".as_ptr(), c"file:///nonexistent".as_ptr()),
            ] {
                let c = fmi2Instantiate(c"i".as_ptr(), ty, guid, location, &callbacks, fmi2False, fmi2False);
                assert!(c.is_null());
            }
        }
    }

    #[test]
    fn resource_uris_become_folders() {
        assert_eq!(
            resource_folder("file:///tmp/a%20b/resources").unwrap(),
            PathBuf::from("/tmp/a b/resources")
        );
        assert_eq!(resource_folder("file:/tmp/x").unwrap(), PathBuf::from("/tmp/x"));
        assert_eq!(
            resource_folder("file://localhost/tmp/x").unwrap(),
            PathBuf::from("/tmp/x")
        );
        assert!(resource_folder("http://example.org/x").is_err());
        // A lone `%` is kept as it is.
        assert_eq!(resource_folder("file:///tmp/100%").unwrap(), PathBuf::from("/tmp/100%"));
    }
}
