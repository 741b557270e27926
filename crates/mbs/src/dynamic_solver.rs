//! Generalized-α time integration on the Lie group of the coordinates (Chung & Hulbert 1993;
//! Brüls, Cardona & Arnold 2012, *Mech. Mach. Theory* 48, "Lie group generalized-α time
//! integration of constrained flexible multibody systems", Algorithm 1 without constraints).
//!
//! With the step $h$, the user's spectral radius at infinity $\rho_\infty\in[0, 1]$ and
//! $\alpha_m = \frac{2\rho_\infty - 1}{\rho_\infty + 1}$, $\alpha_f = \frac{\rho_\infty}{\rho_\infty + 1}$,
//! $\gamma = \tfrac12 + \alpha_f - \alpha_m$, $\beta = \tfrac14(\gamma + \tfrac12)^2$:
//!
//! $$\mathbf q_{n+1} = \mathbf q_n\oplus h\Delta\mathbf q_n,\quad h\Delta\mathbf q_n = h\dot{\mathbf q}_n + h^2(\tfrac12 - \beta)\mathbf a_n + h^2\beta\mathbf a_{n+1},$$
//! $$\dot{\mathbf q}_{n+1} = \dot{\mathbf q}_n + h(1-\gamma)\mathbf a_n + h\gamma\mathbf a_{n+1},\quad
//! (1-\alpha_m)\mathbf a_{n+1} + \alpha_m\mathbf a_n = (1-\alpha_f)\ddot{\mathbf q}_{n+1} + \alpha_f\ddot{\mathbf q}_n,$$
//!
//! and $\mathbf F(\mathbf q_{n+1}, \dot{\mathbf q}_{n+1}, \ddot{\mathbf q}_{n+1}, t_{n+1}) = \mathbf 0$, where $\oplus$ adds
//! scalars and left-multiplies rotations, $\mathbf R \leftarrow \exp(\widetilde{h\Delta\boldsymbol\pi})\mathbf R$
//! (spatial increments, the superelement's convention). Newton corrects the increment:
//! $(\beta'\hat{\mathbf M} + \gamma'\hat{\mathbf C} + \hat{\mathbf K}\mathbf T)\Delta\mathbf x = -\mathbf F$,
//! $\ddot{\mathbf q} \mathrel{+}= \beta'\Delta\mathbf x$, $\dot{\mathbf q} \mathrel{+}= \gamma'\Delta\mathbf x$,
//! $h\Delta\mathbf q \mathrel{+}= \Delta\mathbf x$, with $\beta' = \frac{1-\alpha_m}{h^2\beta(1-\alpha_f)}$,
//! $\gamma' = \frac{\gamma}{h\beta}$ and $\mathbf T$ the tangent operator $\mathbf J_l(h\Delta\boldsymbol\pi)$ on each
//! rotation (a variation of the increment moves the rotation by $\mathbf J_l\,\delta$).
//!
//! The initial accelerations are consistent ($\hat{\mathbf M}\ddot{\mathbf q}_0 = -\mathbf F(\mathbf q_0, \dot{\mathbf q}_0,
//! \mathbf 0)$; $\mathbf F$ is linear in $\ddot{\mathbf q}$) and $\mathbf a_0 = \ddot{\mathbf q}_0$. Each flexible body's last
//! frame stays in the state, so the frame solve (2.6) is warm-started from the previous
//! iteration or step.

#![allow(non_snake_case)]

use crate::error::{Incomplete, SolveError};
use crate::sensors::SensorRecord;
use crate::system::{State, System, Workspace};

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
}

impl DynamicSettings {
    pub fn new(step: f64, end_time: f64, rho_inf: f64) -> Self {
        Self {
            step,
            end_time,
            rho_inf,
            tolerance: 1e-9,
            max_iterations: 20,
            output_every: 1,
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
    /// Relative residual before each correction and at convergence.
    pub residuals: Vec<f64>,
}

/// A generalized-α integrator over a [`System`], one step at a time.
pub struct Integrator<'a> {
    system: &'a System,
    state: State,
    /// The algorithmic acceleration $\mathbf a_n$.
    a: Vec<f64>,
    settings: DynamicSettings,
    p: AlphaParameters,
    ws: Workspace,
    steps: usize,
    /// Scratch: the state at $t_n$ and the increment.
    prev: State,
    incr: Vec<f64>,
    dx: Vec<f64>,
}

impl<'a> Integrator<'a> {
    /// Starts at `state` with consistent initial accelerations.
    pub fn new(system: &'a System, state: State, settings: DynamicSettings) -> Result<Self, SolveError> {
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
        let mut acc: Vec<f64> = ws.F.iter().map(|f| -f).collect();
        ws.S.copy_from_slice(&ws.M);
        system.solve(&ws.S, &mut acc).map_err(|what| SolveError::Singular {
            t: state.time,
            step: 0,
            what: format!("mass matrix for the initial accelerations ({what}); every unknown needs mass"),
        })?;
        state.acceleration.copy_from_slice(&acc);
        system.evaluate_into(&mut state, 1.0, false, &mut ws)?;
        Ok(Self {
            system,
            a: acc,
            p: AlphaParameters::from_rho_inf(settings.rho_inf),
            settings,
            ws,
            steps: 0,
            prev: state.clone(),
            state,
            incr: vec![0.0; n],
            dx: vec![0.0; n],
        })
    }

    pub fn state(&self) -> &State {
        &self.state
    }

    /// Number of steps taken.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Records the sensors at the current state into `rec`.
    pub fn record(&self, rec: &mut SensorRecord) -> Result<(), SolveError> {
        self.system.record(&self.state, &self.ws, rec)
    }

    /// One step of size `settings.step` (module docs). On failure the state is left at the
    /// last converged step.
    pub fn step(&mut self) -> Result<StepReport, SolveError> {
        let sys = self.system;
        let n = sys.n_dof();
        let h = self.settings.step;
        let AlphaParameters {
            alpha_m: am,
            alpha_f: af,
            gamma: g,
            beta: b,
        } = self.p;
        let bp = (1.0 - am) / (h * h * b * (1.0 - af));
        let gp = g / (h * b);
        self.prev.clone_from(&self.state);
        let prev = &self.prev;
        let t = prev.time + h;
        // Predictor: constant acceleration.
        let mut st = prev.clone();
        st.time = t;
        let mut a_new = vec![0.0; n];
        for i in 0..n {
            let qdd = prev.acceleration[i];
            a_new[i] = ((1.0 - af) * qdd + af * prev.acceleration[i] - am * self.a[i]) / (1.0 - am);
            st.velocity[i] = prev.velocity[i] + h * (1.0 - g) * self.a[i] + h * g * a_new[i];
            self.incr[i] = h * prev.velocity[i] + h * h * (0.5 - b) * self.a[i] + h * h * b * a_new[i];
            st.acceleration[i] = qdd;
        }
        sys.retract_in_place(&mut st, prev, &self.incr);
        let mut residuals = Vec::new();
        let step = self.steps + 1;
        for it in 0..=self.settings.max_iterations {
            // After a correction the step has usually converged: test with the forces alone
            // and build the tangents only when another correction is needed.
            sys.evaluate_into(&mut st, 1.0, it == 0, &mut self.ws)?;
            let mut norm = self.ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
            if it > 0 && norm > self.settings.tolerance * self.ws.scale + self.ws.floor && norm.is_finite() {
                sys.evaluate_into(&mut st, 1.0, true, &mut self.ws)?;
                norm = self.ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
            }
            let rel = if self.ws.scale > 0.0 {
                norm / self.ws.scale
            } else {
                norm
            };
            residuals.push(rel);
            if norm <= self.settings.tolerance * self.ws.scale + self.ws.floor {
                for i in 0..n {
                    self.a[i] =
                        ((1.0 - af) * st.acceleration[i] + af * prev.acceleration[i] - am * self.a[i]) / (1.0 - am);
                }
                self.state = st;
                self.steps += 1;
                return Ok(StepReport { time: t, residuals });
            }
            if it == self.settings.max_iterations || !rel.is_finite() {
                // Leave the workspace consistent with the last converged state.
                let mut s = self.state.clone();
                sys.evaluate_into(&mut s, 1.0, false, &mut self.ws)?;
                return Err(SolveError::NotConverged {
                    t,
                    step,
                    residual: rel,
                    iterations: it,
                });
            }
            sys.iteration_matrix(&mut self.ws, bp, gp, Some(&self.incr));
            for i in 0..n {
                self.dx[i] = -self.ws.F[i];
            }
            sys.solve(&self.ws.S, &mut self.dx)
                .map_err(|what| SolveError::Singular {
                    t,
                    step,
                    what: format!("iteration matrix ({what})"),
                })?;
            for i in 0..n {
                st.acceleration[i] += bp * self.dx[i];
                st.velocity[i] += gp * self.dx[i];
                self.incr[i] += self.dx[i];
            }
            sys.retract_in_place(&mut st, prev, &self.incr);
        }
        unreachable!("the loop returns at max_iterations")
    }
}

/// Result of [`solve_dynamic`].
#[derive(Clone, Debug)]
pub struct Trajectory {
    pub sensors: SensorRecord,
    /// Newton iterations of each step.
    pub iterations: Vec<usize>,
    pub final_state: State,
}

/// Integrates from `start` to `settings.end_time` (module docs), recording the sensors.
pub fn solve_dynamic(
    system: &System,
    start: State,
    settings: &DynamicSettings,
) -> Result<Trajectory, Box<Incomplete<Trajectory>>> {
    let mut traj = Trajectory {
        sensors: system.sensor_record(),
        iterations: Vec::new(),
        final_state: start.clone(),
    };
    let fail = |error: SolveError, traj: Trajectory| Box::new(Incomplete { error, partial: traj });
    let mut integ = match Integrator::new(system, start, settings.clone()) {
        Ok(i) => i,
        Err(e) => return Err(fail(e, traj)),
    };
    if let Err(e) = integ.record(&mut traj.sensors) {
        return Err(fail(e, traj));
    }
    let n_steps = ((settings.end_time - integ.state().time) / settings.step - 1e-9)
        .ceil()
        .max(0.0) as usize;
    let every = settings.output_every.max(1);
    for k in 1..=n_steps {
        match integ.step() {
            Ok(rep) => traj.iterations.push(rep.residuals.len() - 1),
            Err(e) => {
                traj.final_state = integ.state().clone();
                return Err(fail(e, traj));
            }
        }
        if k % every == 0 || k == n_steps {
            if let Err(e) = integ.record(&mut traj.sensors) {
                traj.final_state = integ.state().clone();
                return Err(fail(e, traj));
            }
        }
    }
    traj.final_state = integ.state().clone();
    Ok(traj)
}
