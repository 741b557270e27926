//! Force laws: a function of the time and of joint coordinates, node positions and
//! velocities and their rates that gives actuator efforts and nodal load values *inside* the
//! implicit time step, added to a system with [`crate::System::with_force_law`].
//!
//! A controller that sets an actuator between steps ([`crate::System::set_actuator_effort`])
//! acts with the state of the step before: its effort lags one step, and a stiff loop closed
//! that way (a damper on a fast joint) goes unstable. A force law is evaluated in every Newton
//! iteration of the step, at the iterate, and its derivatives enter the iteration matrix, so
//! the loop is closed implicitly, as the built-in PID law is:
//!
//! $$\mathbf u = \mathbf g(t, \mathbf y, \dot{\mathbf y}),\qquad
//! \hat{\mathbf K} \mathrel{-}= \mathbf B\Big(\frac{\partial\mathbf g}{\partial\mathbf y}\frac{\partial\mathbf y}{\partial\mathbf q} +
//! \frac{\partial\mathbf g}{\partial\dot{\mathbf y}}\frac{\partial\dot{\mathbf y}}{\partial\mathbf q}\Big),\qquad
//! \hat{\mathbf C} \mathrel{-}= \mathbf B\Big(\frac{\partial\mathbf g}{\partial\mathbf y}\frac{\partial\mathbf y}{\partial\dot{\mathbf q}} +
//! \frac{\partial\mathbf g}{\partial\dot{\mathbf y}}\frac{\partial\dot{\mathbf y}}{\partial\dot{\mathbf q}}\Big),$$
//!
//! with $\mathbf y$ what the law reads ([`LawPorts::inputs`], [`LawRead`]), over the unknowns
//! $\mathbf q$ (a driven coordinate has no column). A joint coordinate is an unknown:
//! $\partial y/\partial\mathbf q = \partial\dot y/\partial\dot{\mathbf q} = \mathbf e_i$. A node's
//! position $y = r_a$ along axis $a$ has $\partial y/\partial\mathbf q = \partial\dot y/\partial\dot{\mathbf q} =
//! \mathbf J^v_a$ (the row of the node's motion Jacobian, every unknown the node hangs on: the
//! joints above it, a flexible body's frame and modes) and the convective
//! $\partial\dot y/\partial\mathbf q = \partial(\mathbf J^v_a\dot{\mathbf q})/\partial\mathbf q$; a node's
//! velocity $y = v_a$ has $\partial y/\partial\mathbf q$ that convective term and
//! $\partial y/\partial\dot{\mathbf q} = \mathbf J^v_a$, and no rate. $\mathbf u$ are its output values
//! ([`LawPorts::outputs`]: one effort per actuator, three components per load) and $\mathbf B$
//! where they act: an effort $u$ on its actuated coordinate's row ($\mathbf F \mathrel{-}= u$,
//! as [`crate::assembly::joint_forces`]), a load $\lambda\,x(t)\,\mathbf f$ on its node through
//! $\mathbf J^T$ ($\mathbf F \mathrel{-}= \lambda x(t)\mathbf J^T\mathbf f$; the geometric term
//! of $\mathbf J^T$ is the node's, as for every nodal force).
//!
//! A law that does not give its Jacobians ([`ForceLaw::jacobian`] returns `Ok(false)`) gets them
//! by finite differences of [`ForceLaw::evaluate`] ([`finite_difference_jacobian`]: central,
//! $4n$ evaluations for $n$ inputs, or forward, $2n$; [`Differences`]).
//!
//! The outputs replace the targets' own values: an actuator driven by the law does not apply
//! its time function or PID law (an effort held by [`crate::System::set_actuator_effort`] still
//! takes precedence: a co-simulation partner keeps the last word), and a load's value
//! $\mathbf f_0$ becomes the law's $\mathbf f$ (inertial axes; its time function still
//! multiplies it, as it does a value set between steps). Follower loads are refused: their
//! axes turn with the node, which the law does not read.
//!
//! An evaluation that fails (the law's own error, a value that is not finite) stops the
//! analysis with [`crate::SolveError::ForceLaw`], which names the law, the output, the time
//! and carries the law's error as its source.
//!
//! # Notation
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\mathbf y$, $\dot{\mathbf y}$ | `x`, `xd` | what the law reads and its rates, [`LawPorts::inputs`] order (NaN for an input without a rate) |
//! | $\mathbf u$ | `u` | the output values, [`LawPorts::outputs`] order (1 per actuator, 3 per load) |
//! | $\partial\mathbf g/\partial\mathbf y$, $\partial\mathbf g/\partial\dot{\mathbf y}$ | `du_dx`, `du_dxd` | `u.len()` $\times$ `x.len()` |

use crate::ids::{JointId, NodeId};
use faer::{Mat, MatMut};
use std::fmt::Debug;
use std::sync::Arc;

/// What a force law input reads: a value $y$ and its rate $\dot y$.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LawRead {
    /// Scalar coordinate `coordinate` of joint `joint` (in the order of [`crate::JointKind`])
    /// and its rate.
    Coordinate { joint: JointId, coordinate: usize },
    /// The position of node `node` along inertial axis `axis` (0, 1, 2: x, y, z) \[m\] and
    /// its velocity \[m/s\]: a position sensor.
    NodePosition { node: NodeId, axis: usize },
    /// The velocity of node `node` along inertial axis `axis` \[m/s\]; it has no rate (an
    /// acceleration would put the law in the mass matrix): its `xd` is NaN, and the law's
    /// derivative by it is not taken.
    NodeVelocity { node: NodeId, axis: usize },
}

impl LawRead {
    /// Whether the input has a rate the law may read (all but [`Self::NodeVelocity`]).
    pub fn has_rate(self) -> bool {
        !matches!(self, Self::NodeVelocity { .. })
    }
}

/// An input of a force law: what it reads, by the name the law knows it by.
#[derive(Clone, Debug, PartialEq)]
pub struct LawInput {
    /// The name the law knows it by (a joint's name, a sensor's column; for messages and
    /// bindings).
    pub name: String,
    pub reads: LawRead,
}

impl LawInput {
    /// Coordinate `coordinate` of joint `joint`, named `name`.
    pub fn coordinate(name: impl Into<String>, joint: JointId, coordinate: usize) -> Self {
        Self {
            name: name.into(),
            reads: LawRead::Coordinate { joint, coordinate },
        }
    }
}

/// What a force law's output acts on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LawTarget {
    /// The effort of actuator `Model::actuators[i]` (one value, N on a length, N m on an angle).
    Actuator(usize),
    /// The value $\mathbf f_0$ of load `Model::loads[i]` (three values, inertial axes, N or N m).
    Load(usize),
}

impl LawTarget {
    /// How many values of $\mathbf u$ the target takes.
    pub fn width(self) -> usize {
        match self {
            Self::Actuator(_) => 1,
            Self::Load(_) => 3,
        }
    }
}

/// A force law's output.
#[derive(Clone, Debug, PartialEq)]
pub struct LawOutput {
    /// The name the law knows it by (an actuator's or a load's name).
    pub name: String,
    pub target: LawTarget,
}

/// What a force law reads and what it sets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LawPorts {
    pub inputs: Vec<LawInput>,
    pub outputs: Vec<LawOutput>,
}

impl LawPorts {
    /// $\dim\mathbf u$: the values of all outputs.
    pub fn n_values(&self) -> usize {
        self.outputs.iter().map(|o| o.target.width()).sum()
    }

    /// The output whose values include value `k` of $\mathbf u$.
    pub fn output_of_value(&self, k: usize) -> Option<&LawOutput> {
        let mut first = 0;
        self.outputs.iter().find(|o| {
            first += o.target.width();
            k < first
        })
    }
}

/// The steps of the finite differences of a force law without Jacobians. The step of input
/// $y_i$ is `relative` $\cdot\max(|y_i|, 1)$ (the same for its rate), in the inputs' SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Differences {
    /// $(\mathbf g(y + h) - \mathbf g(y - h))/2h$: error $O(h^2)$, two evaluations per input.
    Central { relative: f64 },
    /// $(\mathbf g(y + h) - \mathbf g(y))/h$: error $O(h)$, one evaluation per input.
    Forward { relative: f64 },
}

impl Default for Differences {
    /// Central, $h = 10^{-6}$: near the optimum $\varepsilon^{1/3}$ for a law that varies over
    /// a radian or a radian per second.
    fn default() -> Self {
        Self::Central { relative: 1e-6 }
    }
}

/// Why a force law's evaluation failed; `source` is the law's own error (a Python exception,
/// say), kept as the cause.
#[derive(Clone, Debug, thiserror::Error)]
#[error("{what}")]
pub struct LawError {
    /// The output (or input) name the failure is about, when there is one.
    pub name: Option<String>,
    pub what: String,
    #[source]
    pub source: Option<LawCause>,
}

impl LawError {
    /// A failure described by `what` alone.
    pub fn new(what: impl Into<String>) -> Self {
        Self {
            name: None,
            what: what.into(),
            source: None,
        }
    }

    /// This failure about the output or input `name`.
    pub fn about(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// This failure caused by `source`.
    pub fn caused_by(mut self, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        self.source = Some(LawCause(Arc::new(source)));
        self
    }
}

/// The law's own error, shared (errors of the solver are `Clone`). Two causes are equal when
/// they are the same error.
#[derive(Clone, Debug)]
pub struct LawCause(pub Arc<dyn std::error::Error + Send + Sync>);

impl PartialEq for LawCause {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl std::fmt::Display for LawCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(&self.0, f)
    }
}

/// The cause stands for the law's error (same message), so the chain goes on with that
/// error's own source.
impl std::error::Error for LawCause {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

impl PartialEq for LawError {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name && self.what == other.what && self.source == other.source
    }
}

/// A force law (module docs).
///
/// `Send + Sync`: a system is shared between threads. A law must be a function of its
/// arguments within a step (Newton evaluates it at every iterate and at perturbed inputs).
pub trait ForceLaw: Send + Sync + Debug {
    /// A name for messages ("force law 'damper' at t = ...").
    fn name(&self) -> &str;

    /// What it reads and what it sets.
    fn ports(&self) -> &LawPorts;

    /// Writes $\mathbf u = \mathbf g(t, \mathbf y, \dot{\mathbf y})$ into `u` (zeroed,
    /// [`LawPorts::n_values`] long); `x`, `xd` hold the inputs' values and rates.
    fn evaluate(&self, t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError>;

    /// Optionally writes $\partial\mathbf g/\partial\mathbf y$ into `du_dx` and
    /// $\partial\mathbf g/\partial\dot{\mathbf y}$ into `du_dxd` (zeroed) and returns `Ok(true)`;
    /// the default returns `Ok(false)`: finite differences of [`Self::evaluate`] then.
    fn jacobian(
        &self,
        t: f64,
        x: &[f64],
        xd: &[f64],
        du_dx: MatMut<'_, f64>,
        du_dxd: MatMut<'_, f64>,
    ) -> Result<bool, LawError> {
        let _ = (t, x, xd, du_dx, du_dxd);
        Ok(false)
    }

    /// The finite differences used when [`Self::jacobian`] returns `Ok(false)`.
    fn differences(&self) -> Differences {
        Differences::default()
    }
}

/// The reused buffers of a law's evaluation and its Jacobians (sized once per analysis).
#[derive(Clone, Debug)]
pub(crate) struct LawBuffer {
    pub(crate) x: Vec<f64>,
    pub(crate) xd: Vec<f64>,
    pub(crate) u: Vec<f64>,
    plus: Vec<f64>,
    minus: Vec<f64>,
    pub(crate) du_dx: Mat<f64>,
    pub(crate) du_dxd: Mat<f64>,
    /// $\partial\mathbf u/\partial\mathbf q$, $\partial\mathbf u/\partial\dot{\mathbf q}$ over the
    /// unknowns the inputs hang on (`crate::assembly::force_law`).
    pub(crate) dq: Mat<f64>,
    pub(crate) dqd: Mat<f64>,
}

impl LawBuffer {
    /// Buffers for a law on `ports` whose inputs hang on `columns` unknowns.
    pub(crate) fn new(ports: &LawPorts, columns: usize) -> Self {
        let (n, m) = (ports.inputs.len(), ports.n_values());
        // Inputs x and their rates (n), outputs u and the two difference evaluations (m), the
        // two Jacobians (m x n) and the two by the unknowns (m x columns).
        let (inputs, outputs) = (vec![0.0; n], vec![0.0; m]);
        Self {
            x: inputs.clone(),
            xd: inputs,
            u: outputs.clone(),
            plus: outputs.clone(),
            minus: outputs,
            du_dx: Mat::zeros(m, n),
            du_dxd: Mat::zeros(m, n),
            dq: Mat::zeros(m, columns),
            dqd: Mat::zeros(m, columns),
        }
    }

    /// $\mathbf g$ at `x`, `xd` into `out` (zeroed first), every value checked finite.
    pub(crate) fn eval(law: &dyn ForceLaw, t: f64, x: &[f64], xd: &[f64], out: &mut [f64]) -> Result<(), LawError> {
        out.fill(0.0);
        law.evaluate(t, x, xd, out)?;
        if let Some(k) = out.iter().position(|v| !v.is_finite()) {
            let name = law.ports().output_of_value(k).map(|o| o.name.clone());
            let err = LawError::new(format!("its value is {}", out[k]));
            return Err(match name {
                Some(n) => err.about(n),
                None => err,
            });
        }
        Ok(())
    }

    /// The law at the buffer's inputs into `u`.
    pub(crate) fn evaluate(&mut self, law: &dyn ForceLaw, t: f64) -> Result<(), LawError> {
        Self::eval(law, t, &self.x, &self.xd, &mut self.u)
    }

    /// The Jacobians at the buffer's inputs into `du_dx`, `du_dxd`: the law's own, or finite
    /// differences (`u` must hold the value at the inputs, for forward differences).
    pub(crate) fn jacobian(&mut self, law: &dyn ForceLaw, t: f64) -> Result<(), LawError> {
        self.du_dx.fill(0.0);
        self.du_dxd.fill(0.0);
        if law.jacobian(t, &self.x, &self.xd, self.du_dx.as_mut(), self.du_dxd.as_mut())? {
            let finite = |m: &Mat<f64>| m.col_iter().all(|c| c.iter().all(|v| v.is_finite()));
            if !(finite(&self.du_dx) && finite(&self.du_dxd)) {
                return Err(LawError::new("its Jacobian is not finite"));
            }
            return Ok(());
        }
        let (relative, central) = match law.differences() {
            Differences::Central { relative } => (relative, true),
            Differences::Forward { relative } => (relative, false),
        };
        let inputs = &law.ports().inputs;
        for i in 0..self.x.len() {
            let has_rate = inputs.get(i).is_none_or(|input| input.reads.has_rate());
            for rate in [false, true].into_iter().filter(|&rate| !rate || has_rate) {
                let v = if rate { &mut self.xd } else { &mut self.x };
                let base = v[i];
                let h = relative * base.abs().max(1.0);
                v[i] = base + h;
                Self::eval(law, t, &self.x, &self.xd, &mut self.plus)?;
                let v = if rate { &mut self.xd } else { &mut self.x };
                if central {
                    v[i] = base - h;
                    Self::eval(law, t, &self.x, &self.xd, &mut self.minus)?;
                } else {
                    self.minus.copy_from_slice(&self.u);
                }
                let v = if rate { &mut self.xd } else { &mut self.x };
                v[i] = base;
                let span = if central { 2.0 * h } else { h };
                let target = if rate { &mut self.du_dxd } else { &mut self.du_dx };
                for (k, (p, m)) in self.plus.iter().zip(&self.minus).enumerate() {
                    target[(k, i)] = (p - m) / span;
                }
            }
        }
        Ok(())
    }
}

/// $\partial\mathbf g/\partial\mathbf y$ and $\partial\mathbf g/\partial\dot{\mathbf y}$ of `law` at
/// `x`, `xd` by the law's [`ForceLaw::differences`] (whether or not it gives its own
/// Jacobians), as `(du_dx, du_dxd)`. Public so that a law can check its own
/// [`ForceLaw::jacobian`] against it.
pub fn finite_difference_jacobian(
    law: &dyn ForceLaw,
    t: f64,
    x: &[f64],
    xd: &[f64],
) -> Result<(Mat<f64>, Mat<f64>), LawError> {
    /// The law without its Jacobians.
    #[derive(Debug)]
    struct Differenced<'a>(&'a dyn ForceLaw);
    impl ForceLaw for Differenced<'_> {
        fn name(&self) -> &str {
            self.0.name()
        }
        fn ports(&self) -> &LawPorts {
            self.0.ports()
        }
        fn evaluate(&self, t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
            self.0.evaluate(t, x, xd, u)
        }
        fn differences(&self) -> Differences {
            self.0.differences()
        }
    }
    let law = Differenced(law);
    let mut buf = LawBuffer::new(law.ports(), 0);
    buf.x.copy_from_slice(x);
    buf.xd.copy_from_slice(xd);
    buf.evaluate(&law, t)?;
    buf.jacobian(&law, t)?;
    Ok((buf.du_dx, buf.du_dxd))
}
