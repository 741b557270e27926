//! Static equilibrium paths through limit points: arc-length continuation in the unknowns and
//! the load factor together (Riks 1979; Crisfield 1981, the spherical constraint), and the
//! choice between it and Newton load stepping ([`StaticMethod`]).
//!
//! The unknowns are $(\mathbf q, \lambda)$ with $\mathbf F(\mathbf q; \lambda) = \mathbf F_{int}(\mathbf q) -
//! \lambda\mathbf P(\mathbf q) = \mathbf 0$: every load and gravity scale with $\lambda$, so $\mathbf P =
//! -\partial\mathbf F/\partial\lambda$ is the generalised external force at $\lambda = 1$ (it depends on
//! $\mathbf q$ for follower loads). Each step of length $\Delta s$ from the converged $(\mathbf q_n,
//! \lambda_n)$ adds the constraint
//!
//! $$c = \sum_i\Big(\frac{\Delta q_i}{s_i}\Big)^2 + \Delta\lambda^2 - \Delta s^2 = 0,\qquad
//! \Delta\mathbf q = \mathbf q\ominus\mathbf q_n,\ \Delta\lambda = \lambda - \lambda_n,$$
//!
//! with the unknowns' scales $s_i$ ([`System::increment_norm`]: model size for lengths, 1 for
//! angles). Predictor: the tangent $\hat{\mathbf K}\mathbf t = \mathbf P$, $(\Delta\mathbf q, \Delta\lambda) =
//! \pm\Delta s\,(\mathbf t, 1)/\|(\mathbf t, 1)\|$, the sign keeping the direction of the previous step
//! (positive scaled dot product), which is what carries the path past a limit point where
//! $\Delta\lambda$ changes sign. Corrector: Newton on the bordered system, with
//! $\hat{\mathbf K}\mathbf a = -\mathbf F$, $\hat{\mathbf K}\mathbf b = \mathbf P$ (one factorisation),
//! $\delta\lambda = -\big(c + 2\,\Delta\bar{\mathbf q}\cdot\bar{\mathbf a}\big)/\big(2\,\Delta\bar{\mathbf q}\cdot\bar{\mathbf b} +
//! 2\Delta\lambda\big)$ (bars: scaled by $s_i$), $\delta\mathbf q = \mathbf a + \delta\lambda\,\mathbf b$; the
//! linearisation of $c$ is exact for scalars and first order in the rotation increments, which
//! keeps Newton quadratic near the solution. The step length follows the iterations,
//! $\Delta s \leftarrow \Delta s\sqrt{n_{target}/n}$ (Crisfield), bounded, and is halved on failure.
//!
//! The path stops at [`ArcLengthSettings::lambda_end`] (the last step is replaced by a Newton
//! solve at $\lambda_{end}$ exactly, started on the secant) or after `max_steps` steps.

#![allow(non_snake_case)]

use crate::assembly::system::{System, Workspace};
use crate::error::{At, Incomplete, SolveError};
use crate::solvers::static_solver::{
    check_finite, check_finite_tangent, newton_static, record, solve_static, LoadStep, StaticSettings, StaticSolution,
};
use crate::state::State;

/// Settings of [`solve_arc_length`].
#[derive(Clone, Debug, PartialEq)]
pub struct ArcLengthSettings {
    /// Converged when $\|\mathbf F\| \le$ `tolerance` $\cdot f_{scale}$ + round-off floor (as
    /// [`StaticSettings::tolerance`]) and $|c| \le 10^{-8}\Delta s^2$.
    pub tolerance: f64,
    pub max_iterations: usize,
    /// First arc length $\Delta s$ (scaled norm: model size for lengths, 1 for $\lambda$).
    pub initial_length: f64,
    pub min_length: f64,
    pub max_length: f64,
    /// Newton iterations per step the arc length adapts to.
    pub target_iterations: usize,
    /// The path ends when $\lambda$ reaches this value.
    pub lambda_end: f64,
    /// The path ends after this many steps in any case.
    pub max_steps: usize,
    /// Time at which drivers and load functions are evaluated.
    pub time: f64,
}

impl ArcLengthSettings {
    /// Arc length `initial_length`, up to `lambda_end` or `max_steps` steps.
    pub fn new(initial_length: f64, lambda_end: f64, max_steps: usize) -> Self {
        Self {
            tolerance: StaticSettings::DEFAULT_TOLERANCE,
            max_iterations: StaticSettings::DEFAULT_MAX_ITERATIONS,
            initial_length,
            min_length: initial_length * 1e-4,
            max_length: initial_length * 10.0,
            target_iterations: 4,
            lambda_end,
            max_steps,
            time: 0.0,
        }
    }
}

/// How [`solve_static_with`] finds the equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub enum StaticMethod {
    /// Newton with adaptive load stepping to $\lambda = 1$ ([`solve_static`]); stops at a limit point.
    LoadStepping(StaticSettings),
    /// Arc-length continuation ([`solve_arc_length`]); passes limit points.
    ArcLength(ArcLengthSettings),
}

/// Static equilibrium by the chosen method. The solution's `steps` and sensor rows are the
/// converged points of the path, with the load factor in the time column.
pub fn solve_static_with(
    system: &System,
    start: State,
    method: &StaticMethod,
) -> Result<StaticSolution, Box<Incomplete<StaticSolution>>> {
    match method {
        StaticMethod::LoadStepping(s) => solve_static(system, start, s),
        StaticMethod::ArcLength(s) => solve_arc_length(system, start, s),
    }
}

/// $\mathbf P = -\partial\mathbf F/\partial\lambda$ at `state`: the generalised external force at $\lambda = 1$.
/// Uses its own workspace so that `ws` keeps the tangent of the current iterate.
fn load_vector(system: &System, state: &mut State, ws1: &mut Workspace) -> Result<Vec<f64>, SolveError> {
    system.evaluate_into(state, 1.0, false, ws1)?;
    Ok(ws1.gparts[2].clone())
}

/// $\sum_i x_i y_i/s_i^2$.
fn scaled_dot(system: &System, x: &[f64], y: &[f64]) -> f64 {
    x.iter()
        .zip(y)
        .zip(&system.dof_scale)
        .map(|((a, b), s)| a * b / (s * s))
        .sum()
}

/// A converged point of the path: the state, its load factor, the Newton history and the
/// step $(\Delta\mathbf q, \Delta\lambda)$ that reached it.
struct ArcPoint {
    state: State,
    lambda: f64,
    history: LoadStep,
    direction: (Vec<f64>, f64),
}

/// A failed step: its Newton history and why it failed.
type ArcFailure = Box<(LoadStep, SolveError)>;

/// One arc-length step from the converged `(base, lambda_n)` (module docs).
#[allow(clippy::too_many_arguments)]
fn arc_step(
    system: &System,
    base: &State,
    lambda_n: f64,
    ds: f64,
    previous: Option<&(Vec<f64>, f64)>,
    settings: &ArcLengthSettings,
    ws: &mut Workspace,
    ws1: &mut Workspace,
) -> Result<ArcPoint, ArcFailure> {
    let n = system.n_dof();
    let mut hist = LoadStep {
        lambda: lambda_n,
        residuals: Vec::new(),
        increments: Vec::new(),
    };
    let singular = |what: String| SolveError::Singular {
        at: At::LoadFactor(lambda_n),
        step: 0,
        what: format!("tangent stiffness in the arc-length step ({what})"),
    };
    macro_rules! tryit {
        ($e:expr, $h:expr) => {
            match $e {
                Ok(v) => v,
                Err(e) => return Err(Box::new(($h.clone(), e))),
            }
        };
    }
    // Predictor along the tangent.
    let mut st = base.clone();
    tryit!(system.evaluate_into(&mut st, lambda_n, true, ws), hist);
    let mut t = tryit!(load_vector(system, &mut st, ws1), hist);
    tryit!(check_finite(system, "load vector", &t, At::LoadFactor(lambda_n)), hist);
    tryit!(check_finite_tangent(system, ws, At::LoadFactor(lambda_n)), hist);
    ws.S.copy_from_slice(&ws.K);
    tryit!(system.solve(ws, &mut t).map_err(singular), hist);
    let norm_t = (scaled_dot(system, &t, &t) + 1.0).sqrt();
    let sign = match previous {
        Some((dq, dl)) if scaled_dot(system, &t, dq) + dl < 0.0 => -1.0,
        _ => 1.0,
    };
    let mut dl = sign * ds / norm_t;
    let dq: Vec<f64> = t.iter().map(|x| x * dl).collect();
    let mut lambda = lambda_n + dl;
    system.retract_in_place(&mut st, base, &dq);
    hist.lambda = lambda;
    let mut ab = vec![0.0; 2 * n];
    for it in 0..=settings.max_iterations {
        tryit!(system.evaluate_into(&mut st, lambda, true, ws), hist);
        let norm = ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
        let rel = if ws.scale > 0.0 { norm / ws.scale } else { norm };
        hist.residuals.push(rel);
        let dq = system.difference(&st, base);
        dl = lambda - lambda_n;
        let c = scaled_dot(system, &dq, &dq) + dl * dl - ds * ds;
        tryit!(check_finite(system, "residual", &ws.F, At::LoadFactor(lambda)), hist);
        if norm <= settings.tolerance * ws.scale + ws.floor && c.abs() <= 1e-8 * ds * ds {
            hist.lambda = lambda;
            return Ok(ArcPoint {
                state: st,
                lambda,
                history: hist,
                direction: (dq, dl),
            });
        }
        if it == settings.max_iterations {
            break;
        }
        let P = tryit!(load_vector(system, &mut st, ws1), hist);
        for i in 0..n {
            ab[i] = -ws.F[i];
            ab[n + i] = P[i];
        }
        tryit!(check_finite_tangent(system, ws, At::LoadFactor(lambda)), hist);
        ws.S.copy_from_slice(&ws.K);
        tryit!(system.solve(ws, &mut ab).map_err(singular), hist);
        let (a, b) = ab.split_at(n);
        let den = 2.0 * scaled_dot(system, &dq, b) + 2.0 * dl;
        let dlam = -(c + 2.0 * scaled_dot(system, &dq, a)) / den;
        let corr: Vec<f64> = (0..n).map(|i| a[i] + dlam * b[i]).collect();
        let size = system.increment_norm(&corr).max(dlam.abs());
        hist.increments.push(size);
        if !size.is_finite() {
            break;
        }
        let cur = st.clone();
        system.retract_in_place(&mut st, &cur, &corr);
        lambda += dlam;
        hist.lambda = lambda;
    }
    let iterations = hist.residuals.len().saturating_sub(1);
    let residual = *hist.residuals.last().unwrap_or(&f64::NAN);
    let e = SolveError::NotConverged {
        at: At::LoadFactor(lambda),
        step: 0,
        residual,
        iterations,
    };
    Err(Box::new((hist, e)))
}

/// The equilibrium path from `start` ($\lambda = 0$) by arc-length continuation (module docs).
pub fn solve_arc_length(
    system: &System,
    start: State,
    settings: &ArcLengthSettings,
) -> Result<StaticSolution, Box<Incomplete<StaticSolution>>> {
    let mut state = start;
    state.time = settings.time;
    let mut ws = system.workspace();
    let mut ws1 = system.workspace();
    let mut sol = StaticSolution::start(system, &state);
    let fail = |error: SolveError, sol: StaticSolution| Box::new(Incomplete { error, partial: sol });
    let ok = settings.initial_length > 0.0
        && settings.min_length > 0.0
        && settings.max_length >= settings.initial_length
        && settings.tolerance > 0.0
        && settings.target_iterations > 0;
    if !ok {
        let what = "arc lengths and tolerance must be positive, max_length >= initial_length".into();
        return Err(fail(SolveError::InvalidSettings { what }, sol));
    }
    let mut lambda = 0.0;
    let mut ds = settings.initial_length;
    let mut previous: Option<(Vec<f64>, f64)> = None;
    let mut step = 0;
    while step < settings.max_steps && lambda < settings.lambda_end {
        match arc_step(
            system,
            &state,
            lambda,
            ds,
            previous.as_ref(),
            settings,
            &mut ws,
            &mut ws1,
        ) {
            Ok(ArcPoint {
                state: mut new,
                lambda: new_lambda,
                history: mut hist,
                direction: dir,
            }) => {
                step += 1;
                if new_lambda > settings.lambda_end {
                    // Land on lambda_end: Newton at fixed load from the secant point.
                    let f = (settings.lambda_end - lambda) / (new_lambda - lambda);
                    let dq: Vec<f64> = dir.0.iter().map(|x| x * f).collect();
                    let mut land = system.retract(&state, &dq);
                    let newton = StaticSettings {
                        tolerance: settings.tolerance,
                        max_iterations: settings.max_iterations,
                        ..StaticSettings::new(1)
                    };
                    match newton_static(system, &mut land, settings.lambda_end, &newton, &mut ws) {
                        Ok((h, true)) => {
                            new = land;
                            hist = h;
                        }
                        Ok((h, false)) => sol.rejected.push(h),
                        Err(_) => sol.rejected.push(LoadStep {
                            lambda: settings.lambda_end,
                            residuals: Vec::new(),
                            increments: Vec::new(),
                        }),
                    }
                    // The sensors need the workspace at the recorded state.
                    if let Err(e) = system.evaluate_into(&mut new, hist.lambda, false, &mut ws) {
                        return Err(fail(e.in_load_step(hist.lambda, step), sol));
                    }
                }
                state = new;
                lambda = hist.lambda;
                let iterations = hist.residuals.len().saturating_sub(1).max(1);
                sol.steps.push(hist);
                if let Err(e) = record(system, &state, &ws, lambda, step, &mut sol.sensors) {
                    sol.state = state;
                    return Err(fail(e, sol));
                }
                previous = Some(dir);
                let grow = (settings.target_iterations as f64 / iterations as f64)
                    .sqrt()
                    .clamp(0.5, 2.0);
                ds = (ds * grow).clamp(settings.min_length, settings.max_length);
            }
            Err(failure) => {
                let (hist, error) = *failure;
                let error = error.in_load_step(hist.lambda, step + 1);
                sol.rejected.push(hist);
                ds *= 0.5;
                if ds < settings.min_length {
                    sol.state = state;
                    return Err(fail(error, sol));
                }
            }
        }
    }
    sol.state = state;
    Ok(sol)
}
