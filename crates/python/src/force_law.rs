//! `flexmbs.ForceLaw`: a Python callable of the time, the joint coordinates and the position
//! and velocity sensors that gives actuator efforts and point-load values inside the implicit
//! step ([`mbs::force_law`]), passed to `Study.run(forces=...)` and
//! `Study.simulation(forces=...)`.
//!
//! The callable is `function(t, q, qd) -> {name: value}` with `q`, `qd` dicts of what it reads
//! and the rates (by joint name, `name[k]` for a joint of several coordinates; a position
//! sensor's `tip.position_x`, ... with the velocity as rate; a velocity sensor's
//! `tipv.velocity_x`, ..., in `q` only: it has no rate). It runs at every Newton iteration,
//! and (without `jacobian`) at perturbed values for its finite-difference derivatives: the
//! GIL is taken for each call only. A Python exception, a value that is not finite, a name it
//! should return but does not, or one it should not return, stops the solve with a
//! `SolveError` located at the time and step, naming the output, with the Python exception
//! as its `__cause__`.

use crate::signature::{Class, Member::*};
use mbs::force_law::{Differences, ForceLaw as MbsLaw, LawError, LawPorts, LawTarget};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;

/// A force law evaluated in every Newton iteration of the implicit time step (and of an
/// equilibrium), its derivatives in the iteration matrix.
///
/// `function(t, q, qd)` gets the time [s] and dicts `q`, `qd` of the values and rates it
/// reads (`reads`, default every joint): a joint's coordinate [rad or m] by the joint's name
/// (`name[0]`, `name[1]`, ... for a joint of several coordinates); a `position` sensor's
/// coordinates in global axes [m] as its CSV columns are named, `tip.position_x`,
/// `tip.position_y`, `tip.position_z`, their rates the velocity [m/s]; a `velocity` sensor's
/// components `tipv.velocity_x`, ... [m/s], in `q` only (no rate). A sensor's name reads its
/// three columns. It returns a dict with one entry per name of `outputs`: an actuator's effort
/// [N m or N], or a point load's force [N] (its moment [N m] when the load gives no force) as
/// three numbers in global axes, which the load's time function multiplies. The outputs
/// replace the actuators' `function`/`pid` and the loads' values. Without `jacobian`, the
/// derivatives by the values and rates read come from finite differences (`differences`:
/// `"central"`, 4 calls per joint coordinate or position read, 2 per velocity, or
/// `"forward"`, half as many; step `step` times max(|value|, 1)); `jacobian(t, q, qd)`
/// returns instead `{output: {name read: (d/dq, d/dqd)}}` (three numbers each for a load;
/// entries left out are zero; d/dqd of a velocity is not used). The solver takes them through
/// the motion of the sensor's point to every coordinate it depends on.
#[pyclass(module = "flexmbs", name = "ForceLaw", frozen)]
pub struct ForceLaw {
    source: Arc<Source>,
}

/// The law as the study crate takes it: what it reads and sets, and the callables.
#[derive(Debug)]
struct Source {
    function: Py<PyAny>,
    jacobian: Option<Py<PyAny>>,
    outputs: Vec<String>,
    reads: Option<Vec<String>>,
    differences: Differences,
}

/// `ForceLaw` as the type stubs declare it.
pub(crate) const STUB: Class = Class {
    name: "ForceLaw",
    bases: "",
    members: &[
        Method(
            "__init__",
            "(self, function: Callable[[float, Dict[str, float], Dict[str, float]], Dict[str, Any]], outputs: Sequence[str], reads: Optional[Sequence[str]] = None, jacobian: Optional[Callable[[float, Dict[str, float], Dict[str, float]], Dict[str, Dict[str, Any]]]] = None, differences: str = \"central\", step: float = 1e-6) -> None",
        ),
        Property("outputs", "List[str]"),
        Property("reads", "Optional[List[str]]"),
    ],
};

#[pymethods]
impl ForceLaw {
    #[new]
    #[pyo3(signature = (function, outputs, reads=None, jacobian=None, differences="central", step=1e-6))]
    fn new(
        function: Py<PyAny>,
        outputs: Vec<String>,
        reads: Option<Vec<String>>,
        jacobian: Option<Py<PyAny>>,
        differences: &str,
        step: f64,
    ) -> PyResult<Self> {
        let value_err = pyo3::exceptions::PyValueError::new_err;
        if !(step > 0.0 && step.is_finite()) {
            return Err(value_err(format!(
                "ForceLaw: step must be a positive number (got {step})"
            )));
        }
        let differences = match differences {
            "central" => Differences::Central { relative: step },
            "forward" => Differences::Forward { relative: step },
            other => {
                return Err(value_err(format!(
                    "ForceLaw: differences must be \"central\" or \"forward\" (got {other:?})"
                )))
            }
        };
        if outputs.is_empty() {
            return Err(value_err(
                "ForceLaw: name at least one output (an actuator or a point load)".to_string(),
            ));
        }
        Ok(Self {
            source: Arc::new(Source {
                function,
                jacobian,
                outputs,
                reads,
                differences,
            }),
        })
    }

    /// The actuators and point loads the law sets.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.source.outputs.clone()
    }

    /// The joints and sensors it reads (`None`: every joint).
    #[getter]
    fn reads(&self) -> Option<Vec<String>> {
        self.source.reads.clone()
    }

    fn __repr__(&self) -> String {
        format!("ForceLaw(outputs={:?})", self.source.outputs)
    }
}

impl ForceLaw {
    /// The law for the study crate's runs.
    pub(crate) fn forces(&self) -> study::Forces {
        Some(Arc::clone(&self.source) as Arc<dyn study::ForceLawSource>)
    }
}

impl study::ForceLawSource for Source {
    fn outputs(&self) -> Vec<String> {
        self.outputs.clone()
    }

    fn reads(&self) -> Option<Vec<String>> {
        self.reads.clone()
    }

    fn law(&self, ports: LawPorts) -> Result<Arc<dyn MbsLaw>, study::error::BoxError> {
        let (function, jacobian) = Python::attach(|py| {
            (
                self.function.clone_ref(py),
                self.jacobian.as_ref().map(|j| j.clone_ref(py)),
            )
        });
        Ok(Arc::new(PythonLaw {
            function,
            jacobian,
            ports,
            differences: self.differences,
        }))
    }
}

/// The law on its ports: calls the Python callables.
#[derive(Debug)]
struct PythonLaw {
    function: Py<PyAny>,
    jacobian: Option<Py<PyAny>>,
    ports: LawPorts,
    differences: Differences,
}

/// A Python exception as the law's error: its cause, which the messages show after it.
fn raised(_py: Python<'_>, what: &str, e: PyErr) -> LawError {
    LawError::new(format!("{what} raised")).caused_by(e)
}

impl PythonLaw {
    /// `q`, `qd` as the callables take them.
    fn arguments<'py>(
        &self,
        py: Python<'py>,
        x: &[f64],
        xd: &[f64],
    ) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyDict>)> {
        let (q, qd) = (PyDict::new(py), PyDict::new(py));
        for (i, input) in self.ports.inputs.iter().enumerate() {
            q.set_item(&input.name, x[i])?;
            if input.reads.has_rate() {
                qd.set_item(&input.name, xd[i])?;
            }
        }
        Ok((q, qd))
    }

    /// The output named `name` and the index of its first value, or the error naming the
    /// outputs there are.
    fn output(&self, name: &str) -> Result<(usize, LawTarget), LawError> {
        let mut first = 0;
        for o in &self.ports.outputs {
            if o.name == name {
                return Ok((first, o.target));
            }
            first += o.target.width();
        }
        let names: Vec<&str> = self.ports.outputs.iter().map(|o| o.name.as_str()).collect();
        Err(LawError::new(format!(
            "it returned '{name}', which is not one of its outputs ({})",
            names.join(", ")
        ))
        .about(name))
    }

    /// `value` as `width` numbers (a number, or a sequence of three).
    fn numbers(value: &Bound<'_, PyAny>, width: usize, out: &mut [f64]) -> PyResult<()> {
        if width == 1 {
            out[0] = value.extract::<f64>()?;
        } else {
            let v: Vec<f64> = value.extract()?;
            if v.len() != width {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "expected {width} numbers, got {}",
                    v.len()
                )));
            }
            out.copy_from_slice(&v);
        }
        Ok(())
    }
}

impl MbsLaw for PythonLaw {
    fn name(&self) -> &str {
        "forces"
    }

    fn ports(&self) -> &LawPorts {
        &self.ports
    }

    fn evaluate(&self, t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        Python::attach(|py| {
            let (q, qd) = self
                .arguments(py, x, xd)
                .map_err(|e| raised(py, "building its arguments", e))?;
            let result = self
                .function
                .bind(py)
                .call1((t, q, qd))
                .map_err(|e| raised(py, "the function", e))?;
            let dict = result.cast::<PyDict>().map_err(|_| {
                LawError::new(format!(
                    "the function returned {}, not a dict {{output name: value}}",
                    result.get_type().name().map(|n| n.to_string()).unwrap_or_default()
                ))
            })?;
            let mut seen = vec![false; self.ports.outputs.len()];
            for (k, v) in dict.iter() {
                let name: String = k.extract().map_err(|e| raised(py, "a key of its result", e))?;
                let (first, target) = self.output(&name)?;
                let width = target.width();
                Self::numbers(&v, width, &mut u[first..first + width])
                    .map_err(|e| raised(py, &format!("its value of '{name}'"), e).about(name.clone()))?;
                if let Some(i) = self.ports.outputs.iter().position(|o| o.name == name) {
                    seen[i] = true;
                }
            }
            if let Some(i) = seen.iter().position(|s| !s) {
                let name = &self.ports.outputs[i].name;
                return Err(LawError::new(format!("it returned no value for '{name}'")).about(name.clone()));
            }
            Ok(())
        })
    }

    fn jacobian(
        &self,
        t: f64,
        x: &[f64],
        xd: &[f64],
        mut du_dx: faer::MatMut<'_, f64>,
        mut du_dxd: faer::MatMut<'_, f64>,
    ) -> Result<bool, LawError> {
        let Some(jacobian) = &self.jacobian else {
            return Ok(false);
        };
        Python::attach(|py| {
            let (q, qd) = self
                .arguments(py, x, xd)
                .map_err(|e| raised(py, "building its arguments", e))?;
            let result = jacobian
                .bind(py)
                .call1((t, q, qd))
                .map_err(|e| raised(py, "the jacobian", e))?;
            let dict = result
                .cast::<PyDict>()
                .map_err(|_| LawError::new("the jacobian returned no dict {output: {coordinate: (d/dq, d/dqd)}}"))?;
            for (k, v) in dict.iter() {
                let name: String = k.extract().map_err(|e| raised(py, "a key of its jacobian", e))?;
                let (first, target) = self.output(&name)?;
                let width = target.width();
                let row = v.cast::<PyDict>().map_err(|_| {
                    LawError::new(format!(
                        "the jacobian of '{name}' is no dict {{coordinate: (d/dq, d/dqd)}}"
                    ))
                    .about(name.clone())
                })?;
                for (c, d) in row.iter() {
                    let coordinate: String = c.extract().map_err(|e| raised(py, "a key of its jacobian", e))?;
                    let Some(i) = self.ports.inputs.iter().position(|p| p.name == coordinate) else {
                        return Err(LawError::new(format!(
                            "the jacobian of '{name}' names '{coordinate}', which the law does not read"
                        ))
                        .about(name.clone()));
                    };
                    let pair: (Bound<'_, PyAny>, Bound<'_, PyAny>) = d
                        .extract()
                        .map_err(|e| raised(py, &format!("the jacobian of '{name}' by '{coordinate}'"), e))?;
                    let (mut dq, mut dqd) = ([0.0; 3], [0.0; 3]);
                    Self::numbers(&pair.0, width, &mut dq[..width])
                        .and_then(|()| Self::numbers(&pair.1, width, &mut dqd[..width]))
                        .map_err(|e| raised(py, &format!("the jacobian of '{name}' by '{coordinate}'"), e))?;
                    for w in 0..width {
                        du_dx[(first + w, i)] = dq[w];
                        du_dxd[(first + w, i)] = dqd[w];
                    }
                }
            }
            Ok(true)
        })
    }

    fn differences(&self) -> Differences {
        self.differences
    }
}
