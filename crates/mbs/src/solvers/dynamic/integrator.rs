//! The generalized-α integrator ([`Integrator`]) and its settings: one step, fixed or adaptive,
//! from the state at $t_n$ (the method is described in the docs of [`crate::solvers::dynamic`]).

#![allow(non_snake_case)]

use crate::assembly::joint_forces::STOP_RESOLUTION;
use crate::assembly::system::momentum::MomentumProjection;
use crate::assembly::system::sensors::{PendingRows, SensorRecord};
use crate::assembly::system::{Stop, System, Workspace};
use crate::error::{At, SolveError};
use crate::state::State;
use nalgebra::{Matrix3, UnitQuaternion, Vector3, Vector6};
use std::sync::Arc;
use superelement::so3;

/// Exponents of the PI step controller (module docs, "Adaptive step"), $h_{n+1} = 0.9\,h_n
/// (\mathrm{tol}/e_n)^{0.7/k}(e_{n-1}/\mathrm{tol})^{0.4/k}$ for a local error of order $k = 3$
/// (Gustafsson 1991; Hairer & Wanner, *Solving ODEs II*, §IV.2).
pub const PI_INTEGRAL: f64 = 0.7 / 3.0;
pub const PI_PROPORTIONAL: f64 = 0.4 / 3.0;

/// Settings of the adaptive step (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// Largest accepted local error estimate, in the scaled norm (model size for lengths,
    /// radians for angles).
    pub tolerance: f64,
    pub min_step: f64,
    pub max_step: f64,
}

impl AdaptiveSettings {
    pub fn new(tolerance: f64, min_step: f64, max_step: f64) -> Self {
        Self {
            tolerance,
            min_step,
            max_step,
        }
    }
}

/// What one accepted adaptive step took.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveStep {
    pub report: StepReport,
    /// The step size $h$ of the accepted step.
    pub step: f64,
    /// Its local error estimate.
    pub error: f64,
    /// Attempts rejected before it (error too large or Newton failed).
    pub rejected: usize,
}

/// Settings of the generalized-α integrator.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicSettings {
    /// Time step $h$.
    pub step: f64,
    pub end_time: f64,
    /// Spectral radius at infinity $\rho_\infty \in [0, 1]$: 1 keeps all frequencies (no
    /// numerical damping), 0 annihilates the highest in one step.
    pub rho_inf: f64,
    /// Converged when $\|\mathbf F\| \le$ `tolerance` $\cdot f_{scale}$ + round-off floor (see
    /// [`crate::StaticSettings::tolerance`]).
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Record sensors every this many steps (and at the start and the end).
    pub output_every: usize,
    /// Momentum projection after each step ([`crate::assembly::system::momentum`]): `Auto` (the default) projects
    /// when the model is free and unloaded ([`System::rigid_invariance`]).
    pub momentum: MomentumProjection,
    /// Full Newton (the default: tangents and a factorisation at every correction) or modified
    /// Newton (the factorised iteration matrix kept across corrections and steps; module docs).
    pub newton: NewtonStrategy,
    /// Carry the translations of free independent nodes in body axes (SE(3) update; module
    /// docs, "Body axes"). Off by default: it keeps a chain of many short superelements stable
    /// at $\rho_\infty = 1$, at the cost of more Newton iterations.
    pub body_axis_translations: bool,
}

/// How the Newton corrections of a step get their iteration matrix (module docs, "Newton
/// strategy").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NewtonStrategy {
    /// Tangents and a new factorisation at every correction: quadratic convergence.
    #[default]
    Full,
    /// The last factorised iteration matrix is reused across corrections and steps, with
    /// forces-only evaluations; it is rebuilt when $h$ changes, after a correction that
    /// contracts the residual by less than [`MODIFIED_NEWTON_RATE`] (or lets it grow), and after
    /// a failed step. A step that still fails is retried with full Newton before
    /// [`SolveError::NotConverged`] is reported.
    Modified,
}

/// Modified Newton schedules a new iteration matrix when one correction leaves more than this
/// fraction of the residual, $\|\mathbf F_{k+1}\| > 0.01\|\mathbf F_k\|$ (module docs). Measured on the
/// slider-crank (validation problem C2, `slider_crank --newton modified --geometric-stiffening`,
/// callgrind instructions of 800 steps): with 2 modes 0.1 gives 500M (5.5 iterations, 0.10
/// Jacobians per step), 0.03 423M, 0.01 400M (3.5, 0.56), 0.003 410M (3.1, 0.92), full Newton
/// 460M; with 4 modes 0.1 538M, 0.03 465M, 0.01 438M, 0.003 454M, full Newton 679M. A matrix
/// kept over many steps contracts by only 0.05-0.2 there (the rod turns 0.016 rad per step), so
/// a threshold in 0.1-0.5 costs more evaluations than the Jacobians it saves.
///
/// Retuned with the kept matrix turned with the free nodes (module docs) on the rod as two beam
/// superelements (13 unknowns, 1600 steps; iterations / factorisations per step): 0.003
/// 3.03 / 0.98, 0.005 3.14 / 0.89, 0.007 3.27 / 0.75, 0.01 3.44 / 0.58, 0.015 3.70 / 0.42, 0.02
/// 3.92 / 0.33, 0.03 4.22 / 0.23, 0.1 5.40 / 0.08. A refresh (tangents, iteration matrix, LU)
/// costs 1.6 forces-only system evaluations there (callgrind: 139k instructions per forces-only
/// evaluation, 220k more per refresh), so a step costs 5.37 evaluations at 0.01 and 0.015,
/// 5.45 at 0.02 and 5.47 at 0.007; with forces 40 % cheaper (a refresh at 1.2 evaluations)
/// 0.01 stays the cheapest (5.14 against 5.17 and 5.20). A looser threshold for the first
/// correction alone, whose contraction the predictor's nonlinearity limits, cost more (0.02:
/// 4.00 / 0.43). The rule counts evaluations, never time, so a run is reproducible.
pub const MODIFIED_NEWTON_RATE: f64 = 0.01;

impl DynamicSettings {
    /// $\rho_\infty$ when a study gives none: damps the highest frequencies a little (the
    /// spectral radius of a mode at $\omega h \to \infty$ is 0.9 per step) and keeps second
    /// order.
    pub const DEFAULT_RHO_INF: f64 = 0.9;
    /// Default [`DynamicSettings::tolerance`].
    pub const DEFAULT_TOLERANCE: f64 = 1e-9;
    /// Default [`DynamicSettings::max_iterations`].
    pub const DEFAULT_MAX_ITERATIONS: usize = 20;

    pub fn new(step: f64, end_time: f64, rho_inf: f64) -> Self {
        Self {
            step,
            end_time,
            rho_inf,
            tolerance: Self::DEFAULT_TOLERANCE,
            max_iterations: Self::DEFAULT_MAX_ITERATIONS,
            output_every: 1,
            momentum: MomentumProjection::Auto,
            newton: NewtonStrategy::Full,
            body_axis_translations: false,
        }
    }
}

/// The four generalized-α coefficients of $\rho_\infty$ (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaParameters {
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub gamma: f64,
    pub beta: f64,
}

impl AlphaParameters {
    /// $(\alpha_m, \alpha_f, \gamma, \beta)$, for the step's formulas.
    fn symbols(&self) -> (f64, f64, f64, f64) {
        (self.alpha_m, self.alpha_f, self.gamma, self.beta)
    }

    /// Chung & Hulbert's optimal parameters for $\rho_\infty$.
    pub fn from_rho_inf(rho: f64) -> Self {
        let alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
        let alpha_f = rho / (rho + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        let beta = 0.25 * (gamma + 0.5) * (gamma + 0.5);
        Self {
            alpha_m,
            alpha_f,
            gamma,
            beta,
        }
    }
}

/// What one step took.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    pub time: f64,
    /// Relative residual before each correction and at convergence (with a fallback from
    /// modified to full Newton, those of both attempts).
    pub residuals: Vec<f64>,
    /// Iteration matrices built and factorised in the step (tangents evaluated): one per
    /// correction with full Newton, the refreshes with modified Newton.
    pub jacobians: usize,
    /// With the momentum projection: the defect $\mathbf J_0 - \mathbf J$ = $[\Delta\mathbf L;\ \Delta\mathbf H]$
    /// it corrected ($O(h^3)$, [`crate::assembly::system::momentum`]).
    pub momentum_defect: Option<[f64; 6]>,
}

/// The time at the end of a step of `h` from `t`: $t + h$, rounded to the decimals of $h$
/// when that moves it by round-off only. A step of 0.005 s then reaches 30 s as 30, not
/// 29.999999999998316 after 6000 additions; a step with no short decimal form (such as
/// $T/400$) or a start time off its grid is left as computed.
pub fn step_end_time(t: f64, h: f64) -> f64 {
    step_end_time_with(t, h, step_decimals(h))
}

/// The decimals of the shortest form of `h` that [`step_end_time`] rounds to (formatted once
/// per step size by the integrator, not once per step).
fn step_decimals(h: f64) -> usize {
    let shown = format!("{h}");
    shown.split_once('.').map_or(0, |(_, d)| d.len())
}

/// [`step_end_time`] with the decimals of `h` given ([`step_decimals`]).
fn step_end_time_with(t: f64, h: f64, decimals: usize) -> f64 {
    let sum = t + h;
    if decimals > 15 || !sum.is_finite() {
        return sum;
    }
    match format!("{sum:.decimals$}").parse::<f64>() {
        // Round-off of the additions is about 1e-16 of t per step: far below 1e-6 h.
        Ok(rounded) if (rounded - sum).abs() <= 1e-6 * h.abs() => rounded,
        _ => sum,
    }
}

/// The size of the last fixed step, from `t` to `t_end`, of nominal size `h`: `h` itself when
/// a step of `h` ends on `t_end` ([`step_end_time`]), so the run takes the steps a caller
/// stepping by `h` takes, bit for bit; otherwise `t_end - t`, so the step ends on `t_end`
/// exactly.
pub fn last_step_size(t: f64, t_end: f64, h: f64) -> f64 {
    if step_end_time(t, h) == t_end {
        h
    } else {
        t_end - t
    }
}

/// The fixed steps from `t_start` to `t_end` with step `h`: their number and the size of the
/// last one. Steps of $h$ cover the interval, and the last is shortened to end exactly at
/// `t_end` when the interval is not a multiple of $h$ (an end within $10^{-9}h$ of a multiple
/// counts as one, so round-off in `t_end / h` adds no sliver of a step). No steps when
/// `t_end <= t_start`.
pub fn fixed_steps(t_start: f64, t_end: f64, h: f64) -> (usize, f64) {
    let span = t_end - t_start;
    if !(span > 0.0 && h > 0.0) {
        return (0, h);
    }
    let n = (span / h - 1e-9).ceil().max(1.0) as usize;
    let last = span - (n - 1) as f64 * h;
    (n, last.min(h))
}

/// The system an [`Integrator`] steps: borrowed from the caller, or shared and owned (an
/// integrator that lives on its own, with loads that can change between steps).
#[derive(Clone)]
enum Held<'a> {
    Borrowed(&'a System),
    Shared(Arc<System>),
}

impl std::ops::Deref for Held<'_> {
    type Target = System;
    fn deref(&self) -> &System {
        match self {
            Held::Borrowed(s) => s,
            Held::Shared(s) => s,
        }
    }
}

/// A generalized-α integrator over a [`System`], one step at a time. A clone is the
/// integrator at the same point with everything a step reads (state, algorithmic
/// accelerations, the factorised iteration matrix, the predictor's history, the workspace):
/// stepping the clone gives the steps of the original bit for bit, so a caller can keep one
/// to go back to (a co-simulation master that rejects a step). The system is shared until
/// one of them changes it ([`Integrator::system_mut`]).
#[derive(Clone)]
pub struct Integrator<'a> {
    system: Held<'a>,
    state: State,
    /// The algorithmic acceleration $\mathbf a_n$.
    a: Vec<f64>,
    settings: DynamicSettings,
    p: AlphaParameters,
    ws: Workspace,
    steps: usize,
    /// Scratch: the state at $t_n$, the iterate of $t_{n+1}$, the increment, the correction and
    /// $\mathbf a_n$ of an adaptive attempt (sized once: a step allocates only its report).
    prev: State,
    trial: State,
    incr: Vec<f64>,
    dx: Vec<f64>,
    a_prev: Vec<f64>,
    /// Body-axis iterates of the step: velocity, acceleration, increment, and the velocity
    /// and acceleration at $t_n$.
    vb: Vec<f64>,
    qb: Vec<f64>,
    incr_b: Vec<f64>,
    vb_n: Vec<f64>,
    qb_n: Vec<f64>,
    /// The step size of the iteration matrix factorised in the workspace, `None` when there
    /// is none to reuse (start, failed step): modified Newton refactorises when it differs from
    /// the current $h$.
    factor_h: Option<f64>,
    /// Factorisations in the current step (its [`StepReport::jacobians`]).
    jacobians: usize,
    /// Modified Newton: the last correction contracted poorly, so the next evaluation brings
    /// tangents and the matrix is refactorised.
    refresh_next: bool,
    /// The momenta $\mathbf J_0 = [\mathbf L_0;\ \mathbf H_0]$ of the start, when projecting.
    J0: Option<Vector6<f64>>,
    /// Corrections the last converged step needed: the next step builds its tangents at once
    /// for that many iterations instead of first testing the forces alone.
    last_corrections: usize,
    /// Free independent nodes whose translations the recursion carries in body axes.
    trans: Vec<BodyTranslation>,
    /// The error estimate of the last accepted adaptive step (the PI controller's memory).
    last_error: Option<f64>,
    /// Free independent nodes whose unknowns modified Newton turns with the node
    /// ([`CoRotated`]), and their rotations at the iterate of the factorised matrix.
    corotated: Vec<CoRotated>,
    factor_rotations: Vec<UnitQuaternion<f64>>,
    /// Nodes held in a plane and turning about its normal ([`PlaneRotated`]), and their
    /// angles at the iterate of the factorised matrix.
    plane_rotated: Vec<PlaneRotated>,
    factor_angles: Vec<f64>,
    /// The start accelerations of the last steps (the full-Newton predictor's data).
    history: AccelerationHistory,
    /// The step size of the last step and its decimals ([`step_end_time`]).
    step_decimals: (f64, usize),
    /// The joint limits' stops with their inertias at the start (stops that a step resolves,
    /// [`crate::assembly::joint_forces`]).
    stops: Vec<Stop>,
}

/// Steps of one size whose start accelerations the full-Newton predictor fits (module docs,
/// "Predictor"). On the slider-crank (validation problem C2) windows of 6, 12 and 20 steps
/// gave the same Newton iterations.
pub const PREDICTOR_WINDOW: usize = 8;

/// The body-axis accelerations $\ddot{\mathbf q}_b$ at the starts of the last accepted steps
/// of one size $h$ (the predictor's data, module docs "Predictor"): component by component,
/// the last `len` values oldest first (`values[i * W1 + j]`, `W1` = [`PREDICTOR_WINDOW`] + 1),
/// so that a fit reads one contiguous slice.
#[derive(Clone, Debug, Default)]
struct AccelerationHistory {
    values: Vec<f64>,
    len: usize,
    h: Option<f64>,
}

impl AccelerationHistory {
    const W1: usize = PREDICTOR_WINDOW + 1;

    /// Forgets the steps (after a rejected step: the state went back).
    fn clear(&mut self) {
        self.len = 0;
        self.h = None;
    }

    /// Adds the start accelerations `x` of an accepted step of size `h` (a new size starts a
    /// new history). Allocates only at the first step.
    fn push(&mut self, x: &[f64], h: f64) {
        if self.h != Some(h) || self.values.len() != x.len() * Self::W1 {
            self.values.clear();
            self.values.resize(x.len() * Self::W1, 0.0);
            self.len = 0;
            self.h = Some(h);
        }
        let w = Self::W1;
        if self.len == w {
            for col in self.values.chunks_exact_mut(w) {
                col.copy_within(1.., 0);
            }
            self.len -= 1;
        }
        for (col, &xi) in self.values.chunks_exact_mut(w).zip(x) {
            col[self.len] = xi;
        }
        self.len += 1;
    }

    /// The predicted $\ddot q_{b,i}$ at the end of a step of size `h` whose start value is
    /// `x`: $c_1x_n + c_2x_{n-1}$ with $c_1$, $c_2$ the least-squares fit of
    /// $x_{k+1} \approx c_1x_k + c_2x_{k-1}$ over the window, kept within twice the largest
    /// change of one step there; `x` itself (constant acceleration) without a full window of
    /// steps of size `h` or when the fit is singular.
    fn predict(&self, i: usize, x: f64, h: f64) -> f64 {
        let w = Self::W1;
        if self.h != Some(h) || self.len < w {
            return x;
        }
        let v = &self.values[i * w..(i + 1) * w];
        let (mut s11, mut s12, mut s22, mut b1, mut b2, mut change) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut add = |x2: f64, x1: f64, y: f64| {
            s11 += x1 * x1;
            s12 += x1 * x2;
            s22 += x2 * x2;
            b1 += x1 * y;
            b2 += x2 * y;
            change = change.max((y - x1).abs());
        };
        for t in v.windows(3) {
            add(t[0], t[1], t[2]);
        }
        add(v[w - 2], v[w - 1], x);
        let det = s11 * s22 - s12 * s12;
        // A window of (nearly) collinear values (a constant, a zero) has no unique fit.
        if !(det > 1e-12 * s11 * s22) {
            return x;
        }
        let c1 = (b1 * s22 - b2 * s12) / det;
        let c2 = (s11 * b2 - s12 * b1) / det;
        let p = c1 * x + c2 * v[w - 1];
        if (p - x).abs() <= 2.0 * change {
            p
        } else {
            x
        }
    }
}

/// A free independent node (its own rotation coordinate) whose unknowns modified Newton turns
/// with the node (module docs, "Newton strategy"): the kept factor of $\mathbf S_f$, built where
/// the node's rotation was $\mathbf R_f$, is used as $\mathbf T\mathbf S_f\mathbf T^T$ with
/// $\mathbf Q = \mathbf R\mathbf R_f^T$ on the node's rotation unknowns and on its translations
/// when all three are unknown.
#[derive(Clone, Debug)]
struct CoRotated {
    /// The node's rotation coordinate and its first unknown.
    rot: usize,
    rdof: usize,
    /// The unknowns of its three translations, along the columns of $\mathbf B$ (inertial
    /// axes), $\mathbf B$ and $\mathbf B^{-1}$.
    translation: Option<([usize; 3], Matrix3<f64>, Matrix3<f64>)>,
}

/// What `node` makes of the coordinates of each independent node of `system`, where it makes
/// something.
fn root_nodes<T>(
    system: &System,
    node: impl FnMut(&crate::assembly::topology::RootCoordinates) -> Option<T>,
) -> Vec<T> {
    system.topo.roots.iter().flatten().filter_map(node).collect()
}

/// Every free independent node of `system` ([`CoRotated`]).
fn corotated_nodes(system: &System) -> Vec<CoRotated> {
    let map = &system.topo.map;
    root_nodes(system, |rc| {
        let crate::assembly::topology::RootRotation::Free(rot) = rc.rotation else {
            return None;
        };
        let mut dofs = [0; 3];
        let mut free = true;
        for (k, (sc, _)) in rc.translation.iter().enumerate() {
            match map.scalars[*sc].slot {
                crate::assembly::coordinates::Slot::Unknown(d) => dofs[k] = d,
                crate::assembly::coordinates::Slot::Prescribed(_) => free = false,
            }
        }
        let B = Matrix3::from_columns(&[rc.translation[0].1, rc.translation[1].1, rc.translation[2].1]);
        let translation = if free {
            B.try_inverse().map(|Bi| (dofs, B, Bi))
        } else {
            None
        };
        Some(CoRotated {
            rot,
            rdof: map.rotations[rot].dof,
            translation,
        })
    })
}

/// Turns the residual `v` of the current iterate (rotations `R`) into the axes of the kept
/// factor (`to_factor`: $\mathbf T^T$; rotations `Rf` of the factorised iterate) or a
/// correction solved there back ($\mathbf T$): $\mathbf Q^T$ and $\mathbf Q$ on a node's
/// rotation rows, $\mathbf B^T\mathbf Q^T\mathbf B^{-T}$ and $\mathbf B^{-1}\mathbf Q\mathbf B$ on its
/// translation rows ($\mathbf F$ is the generalised force along the columns of $\mathbf B$, the
/// correction the coordinates along them).
fn corotate(
    nodes: &[CoRotated],
    R: &[UnitQuaternion<f64>],
    Rf: &[UnitQuaternion<f64>],
    v: &mut [f64],
    to_factor: bool,
) {
    for (c, Rf) in nodes.iter().zip(Rf) {
        let Q = (R[c.rot] * Rf.inverse()).to_rotation_matrix().into_inner();
        let r = [c.rdof, c.rdof + 1, c.rdof + 2];
        let w = get3(v, &r);
        set3(v, &r, &if to_factor { Q.transpose() * w } else { Q * w });
        if let Some((d, B, Bi)) = &c.translation {
            let x = get3(v, d);
            let y = if to_factor {
                B.transpose() * (Q.transpose() * (Bi.transpose() * x))
            } else {
                Bi * (Q * (B * x))
            };
            set3(v, d, &y);
        }
    }
}

/// An independent node held in a plane and turning about its normal (a
/// `TranslationSupport::Plane` with the `RotationSupport::Axis` along the same normal: the
/// node between two planar bodies), whose two in-plane translation unknowns modified Newton
/// turns with the node as [`CoRotated`] turns a free node's: $\mathbf Q$ is the rotation by
/// $\theta - \theta_f$ about the normal, which leaves the rotation unknown as it is.
#[derive(Clone, Debug)]
struct PlaneRotated {
    /// The scalar coordinate of the rotation about the normal (an unknown).
    angle: usize,
    /// The unknowns of the two in-plane translations, along the orthonormal pair
    /// $\mathbf b_1$, $\mathbf b_2$ of the support.
    dofs: [usize; 2],
    /// $(\mathbf b_1\times\mathbf b_2)\cdot\mathbf a$ for the rotation axis $\mathbf a$: $\pm 1$.
    sign: f64,
}

/// Every node of `system` held in a plane and turning about its normal ([`PlaneRotated`]).
fn plane_rotated_nodes(system: &System) -> Vec<PlaneRotated> {
    use crate::assembly::coordinates::Slot;
    let map = &system.topo.map;
    root_nodes(system, |rc| {
        let crate::assembly::topology::RootRotation::Axes(axes) = &rc.rotation else {
            return None;
        };
        let (angle, a) = axes[2];
        let Slot::Unknown(_) = map.scalars[angle].slot else {
            return None;
        };
        let unknown = |k: usize| match map.scalars[rc.translation[k].0].slot {
            Slot::Unknown(d) => Some(d),
            Slot::Prescribed(_) => None,
        };
        let (d1, d2) = (unknown(0)?, unknown(1)?);
        if unknown(2).is_some() {
            return None;
        }
        let (b1, b2) = (rc.translation[0].1, rc.translation[1].1);
        let sign = b1.cross(&b2).dot(&a);
        let orthonormal =
            (b1.norm() - 1.0).abs() < 1e-12 && (b2.norm() - 1.0).abs() < 1e-12 && b1.dot(&b2).abs() < 1e-12;
        (orthonormal && (sign.abs() - 1.0).abs() < 1e-12).then_some(PlaneRotated {
            angle,
            dofs: [d1, d2],
            sign: sign.signum(),
        })
    })
}

/// [`corotate`] for the nodes held in a plane: the rotation by $\theta - \theta_f$ about the
/// normal on their in-plane translation rows, its transpose into the factor's axes.
fn corotate_in_plane(nodes: &[PlaneRotated], angles: &[f64], factor: &[f64], v: &mut [f64], to_factor: bool) {
    for (c, theta_f) in nodes.iter().zip(factor) {
        let delta = c.sign * (angles[c.angle] - theta_f);
        let (s, co) = if to_factor { (-delta).sin_cos() } else { delta.sin_cos() };
        let [i, j] = c.dofs;
        let (x, y) = (v[i], v[j]);
        v[i] = co * x - s * y;
        v[j] = s * x + co * y;
    }
}

/// The translations of a free independent node (three unknown translations and a free
/// rotation), carried by the recursion in the node's axes with its rotation (module docs,
/// "Body axes"): $\mathbf v_b = \mathbf R^T\dot{\mathbf x}$, $\dot{\mathbf v}_b$, and the increment of the
/// SE(3) update.
#[derive(Clone, Debug)]
struct BodyTranslation {
    /// Unknowns of the three translations, along the columns of `B` (inertial axes).
    dofs: [usize; 3],
    B: Matrix3<f64>,
    /// The node's rotation coordinate and its first unknown.
    rot: usize,
    rdof: usize,
}

/// Every free independent node of `system` whose three translations are unknown
/// ([`BodyTranslation`]).
fn body_translations(system: &System) -> Vec<BodyTranslation> {
    corotated_nodes(system)
        .into_iter()
        .filter_map(|c| {
            let (dofs, B, _) = c.translation?;
            Some(BodyTranslation {
                dofs,
                B,
                rot: c.rot,
                rdof: c.rdof,
            })
        })
        .collect()
}

fn get3(v: &[f64], d: &[usize; 3]) -> Vector3<f64> {
    Vector3::new(v[d[0]], v[d[1]], v[d[2]])
}

fn set3(v: &mut [f64], d: &[usize; 3], x: &Vector3<f64>) {
    for k in 0..3 {
        v[d[k]] = x[k];
    }
}

/// Body-axis velocities `vb` of the spatial `velocity` at the rotations `R`.
fn body_velocity(sys: &System, trans: &[BodyTranslation], R: &[UnitQuaternion<f64>], velocity: &[f64], vb: &mut [f64]) {
    vb.copy_from_slice(velocity);
    sys.rotate_components(R, vb, true);
    for p in trans {
        let v = R[p.rot].inverse_transform_vector(&(p.B * get3(velocity, &p.dofs)));
        set3(vb, &p.dofs, &v);
    }
}

/// Body-axis accelerations of the spatial `acceleration`, given the body velocities `vb`:
/// $\dot{\boldsymbol\omega}_b = \mathbf R^T\dot{\boldsymbol\omega}_s$ and
/// $\dot{\mathbf v}_b = \mathbf R^T\ddot{\mathbf x} - \boldsymbol\omega_b\times\mathbf v_b$.
fn body_acceleration(
    sys: &System,
    trans: &[BodyTranslation],
    R: &[UnitQuaternion<f64>],
    vb: &[f64],
    acceleration: &[f64],
    qb: &mut [f64],
) {
    qb.copy_from_slice(acceleration);
    sys.rotate_components(R, qb, true);
    for p in trans {
        let w = get3(vb, &[p.rdof, p.rdof + 1, p.rdof + 2]);
        let a = R[p.rot].inverse_transform_vector(&(p.B * get3(acceleration, &p.dofs))) - w.cross(&get3(vb, &p.dofs));
        set3(qb, &p.dofs, &a);
    }
}

impl<'a> Integrator<'a> {
    /// Starts at `state` with consistent initial accelerations.
    pub fn new(system: &'a System, state: State, settings: DynamicSettings) -> Result<Self, SolveError> {
        Self::start(Held::Borrowed(system), state, settings)
    }

    /// [`Integrator::new`] owning its system: it can outlive the caller's borrow, and
    /// [`Integrator::system_mut`] changes loads between steps.
    pub fn new_owned(
        system: Arc<System>,
        state: State,
        settings: DynamicSettings,
    ) -> Result<Integrator<'static>, SolveError> {
        Integrator::start(Held::Shared(system), state, settings)
    }

    /// The system stepped.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The system, to change between steps (loads: [`System::set_load_value`]); `None` for an
    /// integrator that borrows its system ([`Integrator::new`]). The next step starts from
    /// the current state and acceleration with the changed system.
    pub fn system_mut(&mut self) -> Option<&mut System> {
        match &mut self.system {
            Held::Borrowed(_) => None,
            Held::Shared(s) => Some(Arc::make_mut(s)),
        }
    }

    fn start(held: Held<'a>, state: State, settings: DynamicSettings) -> Result<Self, SolveError> {
        let keep = held.clone();
        let system: &System = &keep;
        if !(settings.step > 0.0 && settings.step.is_finite() && (0.0..=1.0).contains(&settings.rho_inf)) {
            return Err(SolveError::InvalidSettings {
                what: format!(
                    "step must be positive and rho_inf in [0, 1] (got {}, {})",
                    settings.step, settings.rho_inf
                ),
            });
        }
        let n = system.n_dof();
        let mut ws = system.workspace();
        let mut state = state;
        state.acceleration.iter_mut().for_each(|a| *a = 0.0);
        system.evaluate_into(&mut state, 1.0, true, &mut ws)?;
        let stops = system.stops(&ws);
        let mut acc: Vec<f64> = ws.F.iter().map(|f| -f).collect();
        ws.S.copy_from_slice(&ws.M);
        system.solve(&mut ws, &mut acc).map_err(|what| SolveError::Singular {
            at: At::Time(state.time),
            step: 0,
            what: format!("mass matrix for the initial accelerations ({what}); every unknown needs mass"),
        })?;
        state.acceleration.copy_from_slice(&acc);
        system.evaluate_into(&mut state, 1.0, false, &mut ws)?;
        system.start_energy_account(&mut state, &ws)?;
        // The recursion of a_n runs in body axes (module docs).
        let trans = if settings.body_axis_translations {
            body_translations(system)
        } else {
            Vec::new()
        };
        // The initial body velocities, for a_0 only (the steps keep theirs in `vb`).
        let mut vb0 = vec![0.0; n];
        body_velocity(system, &trans, &state.rotations, &state.velocity, &mut vb0);
        body_acceleration(system, &trans, &state.rotations, &vb0, &state.acceleration, &mut acc);
        let J0 = match settings.momentum {
            MomentumProjection::Auto if system.rigid_invariance().is_ok() => {
                let (L, H) = system.momentum(&state)?;
                Some(Vector6::new(L.x, L.y, L.z, H.x, H.y, H.z))
            }
            _ => None,
        };
        // The step's work vectors, one entry an unknown each.
        let [incr, dx, a_prev, vb, qb, incr_b, vb_n, qb_n] = std::array::from_fn(|_| vec![0.0; n]);
        Ok(Self {
            system: held,
            a: acc,
            p: AlphaParameters::from_rho_inf(settings.rho_inf),
            settings,
            ws,
            steps: 0,
            prev: state.clone(),
            trial: state.clone(),
            state,
            incr,
            dx,
            a_prev,
            vb,
            qb,
            incr_b,
            vb_n,
            qb_n,
            // The workspace holds the factorised mass matrix, not an iteration matrix.
            factor_h: None,
            jacobians: 0,
            refresh_next: false,
            J0,
            last_corrections: 0,
            trans,
            last_error: None,
            corotated: corotated_nodes(system),
            factor_rotations: Vec::new(),
            plane_rotated: plane_rotated_nodes(system),
            factor_angles: Vec::new(),
            history: AccelerationHistory::default(),
            step_decimals: (f64::NAN, 0),
            stops,
        })
    }

    /// Refuses a joint limit whose stop steps of `min_step` and more cannot resolve
    /// ([`SolveError::UnresolvableLimit`]): the retried fixed steps and the adaptive steps
    /// check it before they step.
    pub fn check_stops(&self, min_step: f64) -> Result<(), SolveError> {
        for stop in &self.stops {
            let frequency = stop.frequency();
            let needed = STOP_RESOLUTION / frequency;
            if !(needed >= min_step) {
                return Err(SolveError::UnresolvableLimit {
                    limit: stop.name.clone(),
                    index: stop.index,
                    joint: stop.joint.clone(),
                    stiffness: stop.stiffness,
                    inertia: stop.inertia,
                    frequency,
                    needed,
                    min_step,
                });
            }
        }
        Ok(())
    }

    /// [`Self::step`], taken back (the state at $t_n$ again) with
    /// [`SolveError::LimitNotResolved`] when it starts or ends in a stop and is longer than
    /// resolves it, $\omega h >$ [`STOP_RESOLUTION`] (module docs of
    /// [`crate::assembly::joint_forces`]), unless it is no longer than `smallest`: the caller
    /// cuts it.
    pub(crate) fn step_resolving_stops(&mut self, smallest: f64) -> Result<StepReport, SolveError> {
        self.a_prev.clone_from(&self.a);
        let report = self.step()?;
        let h = self.settings.step;
        if h <= smallest {
            return Ok(report);
        }
        let unresolved = self.stops.iter().find(|stop| {
            h * stop.frequency() > STOP_RESOLUTION
                && (self.system.limit_penetrated(stop.index, &self.prev)
                    || self.system.limit_penetrated(stop.index, &self.state))
        });
        let Some(stop) = unresolved else {
            return Ok(report);
        };
        let error = SolveError::LimitNotResolved {
            limit: stop.name.clone(),
            index: stop.index,
            at: At::Time(self.state.time),
            step: self.steps,
            h,
            frequency: stop.frequency(),
            needed: STOP_RESOLUTION / stop.frequency(),
        };
        self.take_back();
        Err(error)
    }

    /// Takes the last accepted step back: the state at $t_n$, its algorithmic accelerations
    /// (kept in `a_prev` before the step), no predictor history.
    fn take_back(&mut self) {
        self.state.clone_from(&self.prev);
        self.history.clear();
        self.a.clone_from(&self.a_prev);
        self.steps -= 1;
    }

    pub fn state(&self) -> &State {
        &self.state
    }

    /// Whether each step ends with the momentum projection ([`crate::assembly::system::momentum`]).
    pub fn projects_momentum(&self) -> bool {
        self.J0.is_some()
    }

    /// Number of steps taken.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The step size $h$ of the next [`Self::step`].
    pub fn step_size(&self) -> f64 {
        self.settings.step
    }

    /// Changes the step size (the generalized-α recursion holds for any $h$).
    pub fn set_step_size(&mut self, h: f64) {
        self.settings.step = h;
    }

    /// One step with the local error control of the module docs: tries the current step
    /// size, rejects and shrinks it while the error estimate exceeds the tolerance (or Newton
    /// fails), then sets the size of the next step. Fails when the step would fall below
    /// `min_step`.
    pub fn step_adaptive(&mut self, adaptive: &AdaptiveSettings) -> Result<AdaptiveStep, SolveError> {
        let ok = adaptive.tolerance > 0.0 && adaptive.min_step > 0.0 && adaptive.max_step >= adaptive.min_step;
        if !ok {
            return Err(SolveError::InvalidSettings {
                what: format!(
                    "adaptive step: tolerance and min_step must be positive, max_step >= min_step (got {}, {}, {})",
                    adaptive.tolerance, adaptive.min_step, adaptive.max_step
                ),
            });
        }
        self.check_stops(adaptive.min_step)?;
        let c = (self.p.beta - 1.0 / 6.0).abs();
        let mut rejected = 0;
        loop {
            let h = self.settings.step.clamp(adaptive.min_step, adaptive.max_step);
            self.settings.step = h;
            match self.step_resolving_stops(adaptive.min_step) {
                Ok(report) => {
                    for i in 0..self.dx.len() {
                        self.dx[i] = h * h * c * (self.a[i] - self.a_prev[i]);
                    }
                    let error = self.system.increment_norm(&self.dx);
                    if error <= adaptive.tolerance || h <= adaptive.min_step {
                        // PI control of the step (Gustafsson 1991): the error's trend as well
                        // as its size; no growth right after a rejection.
                        let factor = if error > 0.0 {
                            let tol = adaptive.tolerance;
                            let e0 = self.last_error.unwrap_or(tol);
                            0.9 * (tol / error).powf(PI_INTEGRAL) * (e0 / tol).powf(PI_PROPORTIONAL)
                        } else {
                            2.0
                        };
                        let factor = factor.clamp(0.2, if rejected > 0 { 1.0 } else { 2.0 });
                        self.last_error = Some(error.max(1e-3 * adaptive.tolerance));
                        self.settings.step = (h * factor).clamp(adaptive.min_step, adaptive.max_step);
                        return Ok(AdaptiveStep {
                            report,
                            step: h,
                            error,
                            rejected,
                        });
                    }
                    // Rejected: back to t_n.
                    self.take_back();
                    self.settings.step = h * (0.9 * (adaptive.tolerance / error).cbrt()).clamp(0.2, 0.9);
                }
                Err(
                    e @ (SolveError::NotConverged { .. }
                    | SolveError::Singular { .. }
                    | SolveError::Body { .. }
                    | SolveError::LimitNotResolved { .. }),
                ) => {
                    self.a.clone_from(&self.a_prev);
                    if h <= adaptive.min_step {
                        return Err(e);
                    }
                    self.settings.step = h * 0.5;
                }
                Err(e) => return Err(e),
            }
            rejected += 1;
        }
    }

    /// Records the sensors at the current state into `rec`. A value that is not finite stops
    /// the run with [`SolveError::NonFiniteSensor`] (the row stays in `rec`, as evidence).
    pub fn record(&self, rec: &mut SensorRecord) -> Result<(), SolveError> {
        self.system.record(&self.state, &self.ws, rec)?;
        rec.check_last_row(self.steps)
    }

    /// [`Self::record`] for a run that records many rows: the values of largest-von-Mises
    /// sensors are found for a batch of rows at once ([`System::complete_rows`], the same
    /// values), so the row waits in `pending` and complete rows reach `rec` in order, a batch
    /// at a time ([`PendingRows::BATCH`] rows, or sooner when the oldest waited
    /// [`PendingRows::WAIT`]). The caller completes the rest with [`System::complete_rows`]
    /// when the run ends, fails or stops. Without such sensors the row reaches `rec` at once.
    ///
    /// # Errors
    /// As [`Self::record`], for the first row of the completed ones with a value that is not
    /// finite (a largest-von-Mises value is checked when its batch completes).
    pub fn record_deferred(&self, pending: &mut PendingRows, rec: &mut SensorRecord) -> Result<(), SolveError> {
        if !self.system.has_deferred_sensors() {
            return self.record(rec);
        }
        let bad = self.system.record_pending(&self.state, &self.ws, self.steps, pending)?;
        if bad || pending.due() {
            self.system.complete_rows(pending, rec)?;
        }
        Ok(())
    }

    /// The values of the sensors `which` (indices in `Model::sensors`, ascending) at the
    /// current state, side by side; the other sensors are not evaluated. A value that is not
    /// finite is [`SolveError::NonFiniteSensor`], as in [`Self::record`].
    pub fn sensor_values(&self, which: &[usize]) -> Result<Vec<f64>, SolveError> {
        debug_assert!(which.windows(2).all(|w| w[0] < w[1]), "sensor indices not ascending");
        let row = self
            .system
            .sensor_row(&self.state, &self.ws, &|i| which.binary_search(&i).is_ok(), None)?;
        if row.iter().all(|x| x.is_finite()) {
            return Ok(row);
        }
        // The error names the sensor: only now are the names and widths looked up.
        let all = self.system.sensor_record();
        let mut picked = SensorRecord {
            names: which.iter().map(|&i| all.names[i].clone()).collect(),
            widths: which.iter().map(|&i| all.widths[i]).collect(),
            times: vec![self.state.time()],
            rows: vec![row],
        };
        // The record's sensor index counts within `which`: back to the model's.
        picked.check_last_row(self.steps).map_err(|mut e| {
            if let SolveError::NonFiniteSensor { index, .. } = &mut e {
                *index = which[*index];
            }
            e
        })?;
        Ok(picked.rows.pop().expect("one row"))
    }

    /// One step of size `settings.step` (module docs). On failure the state is left at the
    /// last converged step. With [`NewtonStrategy::Modified`], a step whose modified Newton
    /// fails is tried again from the predictor with full Newton before the error is reported.
    pub fn step(&mut self) -> Result<StepReport, SolveError> {
        self.prev.clone_from(&self.state);
        self.jacobians = 0;
        // Room for the usual few corrections (a longer history grows once).
        let mut residuals = Vec::with_capacity(8);
        let result = match self.settings.newton {
            NewtonStrategy::Full => self.attempt(false, &mut residuals),
            NewtonStrategy::Modified => match self.attempt(true, &mut residuals) {
                Err(SolveError::NotConverged { .. } | SolveError::Singular { .. } | SolveError::Body { .. }) => {
                    self.attempt(false, &mut residuals)
                }
                other => other,
            },
        };
        match result {
            Ok(momentum_defect) => Ok(StepReport {
                time: self.state.time,
                residuals,
                jacobians: self.jacobians,
                momentum_defect,
            }),
            Err(e) => {
                // The factor may belong to a diverged iterate: the next step rebuilds it.
                self.factor_h = None;
                Err(e)
            }
        }
    }

    /// One Newton solve of the step from the predictor: full (`modified` false: tangents at
    /// every correction) or modified (module docs). On success the state is at $t_{n+1}$ and
    /// the momentum defect is returned; on failure the state is unchanged.
    fn attempt(&mut self, modified: bool, residuals: &mut Vec<f64>) -> Result<Option<[f64; 6]>, SolveError> {
        let held = self.system.clone();
        let sys: &System = &held;
        let h = self.settings.step;
        let (am, af, g, b) = self.p.symbols();
        let bp = (1.0 - am) / (h * h * b * (1.0 - af));
        let gp = g / (h * b);
        if self.step_decimals.0 != h {
            self.step_decimals = (h, step_decimals(h));
        }
        let t = step_end_time_with(self.prev.time, h, self.step_decimals.1);
        self.predict(sys, modified, h, t);
        // A saturated PID is solved on the branch of its predictor (joint_forces, saturation).
        sys.settle_actuator_branches(&mut self.trial);
        let step = self.steps + 1;
        let tol = self.settings.tolerance;
        // The round-off of the inertia forces of this step (from the last mass matrix): the
        // floor that keeps the test meaningful when every force is zero (a coasting rotor).
        let inertia_floor = sys.inertia_floor(&mut self.ws, &self.prev.velocity, h);
        let mut last_rel = f64::INFINITY;
        for it in 0..=self.settings.max_iterations {
            // Modified Newton keeps a factor built for this h; without one it needs tangents now.
            let stale = self.factor_h != Some(h);
            // Full Newton: after a correction the step may have converged, so test with the
            // forces alone and build the tangents only when another correction is needed.
            // Steps of a smooth motion need about as many corrections as the last one, so up
            // to that count the tangents come with the forces (a forces-only test there is
            // wasted work).
            let mut with_tangents = if modified {
                stale || self.refresh_next
            } else {
                it == 0 || it < self.last_corrections
            };
            sys.evaluate_into(&mut self.trial, 1.0, with_tangents, &mut self.ws)?;
            let converged = |ws: &Workspace, norm: f64| norm <= tol * ws.scale + ws.floor + inertia_floor;
            let mut norm = self.ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !modified && !with_tangents && !converged(&self.ws, norm) && norm.is_finite() {
                sys.evaluate_into(&mut self.trial, 1.0, true, &mut self.ws)?;
                with_tangents = true;
                norm = self.ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
            }
            // Converged on a PID saturation's branch that its own effort has left: switch the
            // branch and iterate on (joint_forces, saturation).
            let switched = converged(&self.ws, norm) && sys.settle_actuator_branches(&mut self.trial);
            if switched {
                sys.evaluate_into(&mut self.trial, 1.0, true, &mut self.ws)?;
                with_tangents = true;
                norm = self.ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
            }
            let rel = if self.ws.scale > 0.0 {
                norm / self.ws.scale
            } else {
                norm
            };
            residuals.push(rel);
            if !switched && converged(&self.ws, norm) {
                if modified && with_tangents {
                    // Tangents scheduled by a poor contraction arrived with the converging
                    // evaluation: factorise them for the next step rather than waste them.
                    sys.iteration_matrix(&mut self.ws, bp, gp, Some((&self.incr, &self.trial)));
                    if sys.factor(&mut self.ws).is_ok() {
                        self.keep_factor(h);
                        self.refresh_next = false;
                    }
                }
                return self.accept(sys, modified, it, h);
            }
            if it == self.settings.max_iterations || !rel.is_finite() {
                // Leave the workspace consistent with the last converged state.
                let mut s = self.state.clone();
                sys.evaluate_into(&mut s, 1.0, false, &mut self.ws)?;
                return Err(SolveError::NotConverged {
                    at: At::Time(t),
                    step,
                    residual: rel,
                    iterations: it,
                });
            }
            // Full Newton refactorises at every correction; modified Newton when its matrix is
            // stale or the last correction contracted the residual too little (or it grew).
            // A poor contraction (rel > rate * last_rel) schedules tangents with the next
            // evaluation instead of a second evaluation here; a growing residual refreshes now.
            let refresh = !modified || stale || self.refresh_next || rel > last_rel || switched;
            if modified && !refresh && rel > MODIFIED_NEWTON_RATE * last_rel {
                self.refresh_next = true;
            }
            if refresh {
                self.refresh_next = false;
                if !with_tangents {
                    sys.evaluate_into(&mut self.trial, 1.0, true, &mut self.ws)?;
                }
                sys.iteration_matrix(&mut self.ws, bp, gp, Some((&self.incr, &self.trial)));
                sys.factor(&mut self.ws).map_err(|what| SolveError::Singular {
                    at: At::Time(t),
                    step,
                    what: format!("iteration matrix ({what})"),
                })?;
                self.keep_factor(h);
            }
            last_rel = rel;
            // A kept factor was built where the free nodes stood turned by R R_f^T less: solve
            // in its axes (module docs, "Newton strategy"). A fresh one is at this iterate.
            self.correct(sys, modified && !refresh, bp, gp)
                .map_err(|what| SolveError::Singular {
                    at: At::Time(t),
                    step,
                    what: format!("iteration matrix ({what})"),
                })?;
        }
        unreachable!("the loop returns at max_iterations")
    }

    /// The predictor of the step to `t`: constant acceleration (modified Newton), or
    /// extrapolated from the last steps (full Newton; module docs, "Predictor"), into the
    /// body-axis iterates and the trial state.
    fn predict(&mut self, sys: &System, modified: bool, h: f64, t: f64) {
        let n = sys.n_dof();
        let (am, af, g, b) = self.p.symbols();
        let prev = &self.prev;
        let st = &mut self.trial;
        st.clone_from(prev);
        st.time = t;
        body_velocity(sys, &self.trans, &prev.rotations, &prev.velocity, &mut self.vb_n);
        body_acceleration(
            sys,
            &self.trans,
            &prev.rotations,
            &self.vb_n,
            &prev.acceleration,
            &mut self.qb_n,
        );
        for i in 0..n {
            let qdd = if modified {
                self.qb_n[i]
            } else {
                self.history.predict(i, self.qb_n[i], h)
            };
            let a_new = ((1.0 - af) * qdd + af * self.qb_n[i] - am * self.a[i]) / (1.0 - am);
            self.vb[i] = self.vb_n[i] + h * (1.0 - g) * self.a[i] + h * g * a_new;
            self.incr_b[i] = h * self.vb_n[i] + h * h * (0.5 - b) * self.a[i] + h * h * b * a_new;
            self.qb[i] = qdd;
        }
        self.update_trial(sys);
    }

    /// Keeps the factorised iteration matrix of step size `h` with the rotations and in-plane
    /// angles it was built at (modified Newton turns it with them, module docs).
    /// The trial state from the body-axis iterates of the step ([`to_trial`]), in the
    /// predictor and after each correction alike.
    fn update_trial(&mut self, sys: &System) {
        to_trial(
            sys,
            &self.trans,
            &self.prev,
            &mut self.trial,
            &mut self.incr,
            &self.incr_b,
            &self.vb,
            &self.qb,
        );
    }

    fn keep_factor(&mut self, h: f64) {
        let st = &self.trial;
        self.factor_rotations.clear();
        self.factor_rotations
            .extend(self.corotated.iter().map(|c| st.rotations[c.rot]));
        self.factor_angles.clear();
        self.factor_angles
            .extend(self.plane_rotated.iter().map(|c| st.scalars[c.angle]));
        self.factor_h = Some(h);
        self.jacobians += 1;
    }

    /// The converged trial state becomes the state at $t_{n+1}$: the momentum projection (if
    /// any), the algorithmic accelerations, the controllers and the predictor's history moved
    /// on. Returns the momentum defect.
    fn accept(&mut self, sys: &System, modified: bool, it: usize, h: f64) -> Result<Option<[f64; 6]>, SolveError> {
        let n = sys.n_dof();
        let AlphaParameters {
            alpha_m: am,
            alpha_f: af,
            ..
        } = self.p;
        let st = &mut self.trial;
        let mut momentum_defect = None;
        if let Some(J0) = &self.J0 {
            // Hairer, Lubich & Wanner §IV.4: project the converged velocities onto
            // J(q_{n+1}, v) = J0; the sensors then read the corrected node velocities.
            // (Before the update of a_n, so that a failure leaves the step at t_n.)
            momentum_defect = Some(sys.project_momentum(st, J0)?.into());
            sys.refresh_motions(st, &mut self.ws);
        }
        for i in 0..n {
            self.a[i] = ((1.0 - af) * self.qb[i] + af * self.qb_n[i] - am * self.a[i]) / (1.0 - am);
        }
        sys.accept_step(st);
        sys.advance_energy_account(self.state.account, st, &self.ws);
        self.history.push(&self.qb_n, h);
        std::mem::swap(&mut self.state, &mut self.trial);
        self.steps += 1;
        if !modified {
            self.last_corrections = it;
        }
        Ok(momentum_defect)
    }

    /// One Newton correction $\Delta\mathbf x = -\mathbf S^{-1}\mathbf F$ from the factorised
    /// iteration matrix (in its own axes when `turn`: a kept factor), applied to the body-axis
    /// iterates and the trial state. Fails with the solver's message.
    fn correct(&mut self, sys: &System, turn: bool, bp: f64, gp: f64) -> Result<(), String> {
        let n = sys.n_dof();
        let prev = &self.prev;
        let st = &mut self.trial;
        for i in 0..n {
            self.dx[i] = -self.ws.F[i];
        }
        // Into the kept factor's axes (`to_factor`) and back.
        let turn_dx = |dx: &mut [f64], to_factor: bool| {
            corotate(&self.corotated, &st.rotations, &self.factor_rotations, dx, to_factor);
            corotate_in_plane(&self.plane_rotated, &st.scalars, &self.factor_angles, dx, to_factor);
        };
        if turn {
            turn_dx(&mut self.dx, true);
        }
        sys.solve_factored(&mut self.ws, &mut self.dx)?;
        if turn {
            turn_dx(&mut self.dx, false);
        }
        // dx corrects the spatial increment; the body-axis iterates move by R_n^T dx, and a
        // translation's so that the SE(3) update moves the node by dx exactly.
        sys.rotate_components(&prev.rotations, &mut self.dx, true);
        for p in &self.trans {
            let r = [p.rdof, p.rdof + 1, p.rdof + 2];
            let theta = get3(&self.incr_b, &r) + get3(&self.dx, &r);
            let target = p.B * (get3(&self.incr, &p.dofs) + get3(&self.dx, &p.dofs));
            let u = so3::left_jacobian_inv(&theta) * prev.rotations[p.rot].inverse_transform_vector(&target);
            set3(&mut self.dx, &p.dofs, &(u - get3(&self.incr_b, &p.dofs)));
        }
        for i in 0..n {
            self.qb[i] += bp * self.dx[i];
            self.vb[i] += gp * self.dx[i];
            self.incr_b[i] += self.dx[i];
        }
        self.update_trial(sys);
        Ok(())
    }
}

/// The iterate `st` of $t_{n+1}$ from the body-axis iterates of the step (module docs): the
/// spatial increment `incr` $= \mathbf R_n\,h\Delta\mathbf q$ on each rotation, the
/// configuration $\mathbf q_n\oplus$ `incr`, and the spatial velocity and acceleration
/// $\mathbf R_{n+1}\mathbf v$, $\mathbf R_{n+1}\dot{\mathbf v}$ ($\dot{\boldsymbol\omega}_s =
/// \mathbf R\dot{\boldsymbol\omega}_b$, as $\boldsymbol\omega_s\times\boldsymbol\omega_s = \mathbf 0$).
/// Scalars pass unchanged.
#[allow(clippy::too_many_arguments)]
fn to_trial(
    sys: &System,
    trans: &[BodyTranslation],
    prev: &State,
    st: &mut State,
    incr: &mut [f64],
    incr_b: &[f64],
    vb: &[f64],
    qb: &[f64],
) {
    incr.copy_from_slice(incr_b);
    sys.rotate_components(&prev.rotations, incr, false);
    for p in trans {
        // SE(3): x_{n+1} = x_n + R_n J_l(h dtheta_b) h du_b.
        let theta = get3(incr_b, &[p.rdof, p.rdof + 1, p.rdof + 2]);
        let dx = prev.rotations[p.rot].transform_vector(&(so3::left_jacobian(&theta) * get3(incr_b, &p.dofs)));
        set3(incr, &p.dofs, &(p.B.transpose() * dx));
    }
    sys.retract_in_place(st, prev, incr);
    st.velocity.copy_from_slice(vb);
    st.acceleration.copy_from_slice(qb);
    sys.rotate_components(&st.rotations, &mut st.velocity, false);
    sys.rotate_components(&st.rotations, &mut st.acceleration, false);
    for p in trans {
        let R = &st.rotations[p.rot];
        let (w, v) = (get3(vb, &[p.rdof, p.rdof + 1, p.rdof + 2]), get3(vb, &p.dofs));
        set3(&mut st.velocity, &p.dofs, &(p.B.transpose() * R.transform_vector(&v)));
        let a = get3(qb, &p.dofs) + w.cross(&v);
        set3(
            &mut st.acceleration,
            &p.dofs,
            &(p.B.transpose() * R.transform_vector(&a)),
        );
    }
}

/// One adaptive step ([`Integrator::step_adaptive`]) that lands on `end`: a step that would
/// pass it is shortened to it, and one that would leave a sliver of less than half a step is
/// halved.
pub fn step_adaptive_to(
    integ: &mut Integrator,
    end: f64,
    adaptive: &AdaptiveSettings,
) -> Result<AdaptiveStep, SolveError> {
    let left = end - integ.state().time();
    let h = integ.step_size();
    if h >= left || 1.5 * h > left {
        integ.set_step_size(if h >= left { left } else { 0.5 * left });
    }
    let limits = AdaptiveSettings {
        min_step: adaptive.min_step.min(left),
        ..adaptive.clone()
    };
    integ.step_adaptive(&limits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A history of `k` steps of size `h` with values `x(j)`, and the next value predicted from
    /// `x(k)`.
    fn predicted(x: impl Fn(usize) -> f64, k: usize, h: f64) -> f64 {
        let mut hist = AccelerationHistory::default();
        for j in 0..k {
            hist.push(&[x(j)], h);
        }
        hist.predict(0, x(k), h)
    }

    #[test]
    fn the_predictor_continues_an_oscillation_and_a_ramp() {
        let k = PREDICTOR_WINDOW + 1;
        // A sampled oscillation at omega h = 1.4 (consecutive values nearly uncorrelated):
        // x_{n+1} = 2 cos(omega h) x_n - x_{n-1} holds exactly, so the fit finds it; the
        // tolerance is the round-off of the normal equations on values of order 1 (1e-12).
        let w = 1.4;
        let osc = |j: usize| (w * j as f64 + 0.3).sin() + 0.5 * (w * j as f64).cos();
        let p = predicted(osc, k, 1e-3);
        assert!((p - osc(k + 1)).abs() < 1e-12, "{p} vs {}", osc(k + 1));
        // Constant acceleration is off by a step's swing (0.23 here).
        assert!((osc(k) - osc(k + 1)).abs() > 0.2);
        // A linear ramp (smooth motion): extrapolated exactly (c1 = 2, c2 = -1).
        let ramp = |j: usize| 3.0 + 0.25 * j as f64;
        let p = predicted(ramp, k, 1e-3);
        assert!((p - ramp(k + 1)).abs() < 1e-12, "{p}");
    }

    #[test]
    fn the_predictor_falls_back_to_constant_acceleration() {
        let k = PREDICTOR_WINDOW + 1;
        let ramp = |j: usize| 1.0 + j as f64;
        // Too few steps.
        assert_eq!(predicted(ramp, k - 1, 1e-3), ramp(k - 1));
        // A constant (and a zero) window has no unique fit.
        assert_eq!(predicted(|_| 2.0, k, 1e-3), 2.0);
        assert_eq!(predicted(|_| 0.0, k, 1e-3), 0.0);
        // A step of another size, and a history cleared by a rejected step.
        let mut hist = AccelerationHistory::default();
        for j in 0..k {
            hist.push(&[ramp(j)], 1e-3);
        }
        assert_eq!(hist.predict(0, ramp(k), 2e-3), ramp(k));
        hist.push(&[ramp(k)], 2e-3);
        assert_eq!(hist.len, 1, "a new step size starts a new history");
        hist.clear();
        assert_eq!(hist.predict(0, 5.0, 2e-3), 5.0);
        // The window keeps its length.
        for j in 0..3 * k {
            hist.push(&[ramp(j)], 1e-3);
        }
        assert_eq!(hist.len, PREDICTOR_WINDOW + 1);
    }

    #[test]
    fn the_predictor_stays_within_twice_the_largest_change() {
        // x_j = (-3)^j + 2^j follows x_{n+1} = -x_n + 6 x_{n-1} exactly, so the fit would
        // predict x_{k+1}, a change of about 4 * 3^k from x_k, beyond twice the largest change
        // in the window (about 8/3 * 3^k): the prediction is held at the constant one.
        let k = PREDICTOR_WINDOW + 1;
        let x = |j: usize| (-3.0f64).powi(j as i32) + 2.0f64.powi(j as i32);
        assert_eq!(predicted(x, k, 1e-3), x(k));
        // A growth the bound admits (roots 1.2 and -0.5) is extrapolated: round-off 1e-12.
        let y = |j: usize| 1.2f64.powi(j as i32) + (-0.5f64).powi(j as i32);
        let p = predicted(y, k, 1e-3);
        assert!((p - y(k + 1)).abs() < 1e-12 * y(k + 1).abs(), "{p} vs {}", y(k + 1));
    }

    #[test]
    fn corotation_solves_with_the_turned_matrix() {
        // A free node's 6 unknowns (translations along a non-orthonormal basis B, then the
        // rotation) and an uncoupled scalar: the kept matrix S_f, built where the node stood at
        // R_f, is S_x in inertial axes, P^T S_x P with P = diag(B, I). The same matrix turned
        // rigidly by Q = R R_f^T is P^T diag(Q, Q) S_x diag(Q, Q)^T P; solving it must equal
        // T S_f^-1 T^T (`corotate` around the kept solve). Round-off of a 7 x 7 LU on a
        // well-conditioned matrix and of the 3 x 3 products: 1e-12 relative.
        use nalgebra::{DMatrix, DVector, Matrix6};
        let B = Matrix3::new(1.0, 0.2, 0.0, 0.0, 1.0, 0.1, 0.3, 0.0, 1.0);
        let node = CoRotated {
            rot: 0,
            rdof: 3,
            translation: Some(([0, 1, 2], B, B.try_inverse().unwrap())),
        };
        let Rf = [UnitQuaternion::from_euler_angles(0.1, -0.4, 0.7)];
        let R = [UnitQuaternion::from_euler_angles(0.3, 0.2, -0.5)];
        let Q = (R[0] * Rf[0].inverse()).to_rotation_matrix().into_inner();
        let A = Matrix6::from_fn(|i, j| ((i * 7 + j * 3) % 5) as f64 * 0.1 + if i == j { 4.0 } else { 0.0 });
        let Sx = A + A.transpose();
        let mut P = Matrix6::identity();
        P.fixed_view_mut::<3, 3>(0, 0).copy_from(&B);
        let mut G = Matrix6::zeros();
        G.fixed_view_mut::<3, 3>(0, 0).copy_from(&Q);
        G.fixed_view_mut::<3, 3>(3, 3).copy_from(&Q);
        let embed = |S6: Matrix6<f64>| {
            let mut S = DMatrix::zeros(7, 7);
            S.view_mut((0, 0), (6, 6)).copy_from(&S6);
            S[(6, 6)] = 2.5;
            S
        };
        let Sf = embed(P.transpose() * Sx * P);
        let Snow = embed(P.transpose() * G * Sx * G.transpose() * P);
        let F = DVector::from_vec(vec![0.3, -1.2, 0.8, 2.0, -0.4, 0.9, 1.7]);
        let exact = Snow.clone().lu().solve(&F).unwrap();
        let mut v: Vec<f64> = F.iter().copied().collect();
        corotate(std::slice::from_ref(&node), &R, &Rf, &mut v, true);
        let solved = Sf.clone().lu().solve(&DVector::from_vec(v)).unwrap();
        let mut v: Vec<f64> = solved.iter().copied().collect();
        corotate(std::slice::from_ref(&node), &R, &Rf, &mut v, false);
        let err = (DVector::from_vec(v) - &exact).norm() / exact.norm();
        assert!(err < 1e-12, "{err:.3e}");
        // Without the turn the kept matrix solves a different system.
        let unturned = Sf.lu().solve(&F).unwrap();
        assert!((unturned - exact).norm() > 1e-3);
    }

    #[test]
    fn corotation_in_the_plane_is_the_free_nodes_restricted_to_the_plane() {
        // A node held in the plane of normal a, turning about a: its in-plane translation
        // rows turned by `corotate_in_plane` equal those of a free node with the orthonormal
        // basis B = [b1 b2 a] turned by `corotate` (Q = R R_f^T, R = exp(theta a)), whose
        // normal component stays zero; both directions, and both orientations of the pair.
        // The two are different sums of the same products: round-off, 1e-14.
        let a = Vector3::new(0.2, -0.3, 0.9).normalize();
        let (b1, b2) = crate::assembly::topology::perpendicular_pair(&a);
        let (theta, theta_f) = (0.7, -0.25);
        let R = [UnitQuaternion::from_scaled_axis(a * theta)];
        let Rf = [UnitQuaternion::from_scaled_axis(a * theta_f)];
        for (p1, p2) in [(b1, b2), (b2, b1)] {
            let B = Matrix3::from_columns(&[p1, p2, p1.cross(&p2)]);
            let free = CoRotated {
                rot: 0,
                rdof: 3,
                translation: Some(([0, 1, 2], B, B.try_inverse().unwrap())),
            };
            let planar = PlaneRotated {
                angle: 0,
                dofs: [0, 1],
                sign: p1.cross(&p2).dot(&a).signum(),
            };
            for to_factor in [true, false] {
                let mut v3 = vec![0.8, -1.3, 0.0, 0.0, 0.0, 0.0];
                corotate(std::slice::from_ref(&free), &R, &Rf, &mut v3, to_factor);
                let mut v2 = vec![0.8, -1.3];
                corotate_in_plane(std::slice::from_ref(&planar), &[theta], &[theta_f], &mut v2, to_factor);
                assert!(v3[2].abs() < 1e-14, "{v3:?}");
                assert!(
                    (v2[0] - v3[0]).abs() < 1e-14 && (v2[1] - v3[1]).abs() < 1e-14,
                    "{v2:?} {v3:?}"
                );
                assert!((v2[0] - 0.8).abs() > 0.1, "turned");
            }
        }
    }
}
