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
//! scalars and moves rotations in body axes, $\mathbf R_{n+1} = \mathbf R_n\exp(\widetilde{h\Delta\boldsymbol\theta})$,
//! as in Brüls, Cardona & Arnold: the angular components of $\dot{\mathbf q}$, $\ddot{\mathbf q}$, $\mathbf a$ and
//! $h\Delta\mathbf q$ in the recursion are body-axis ones, $\boldsymbol\omega_b = \mathbf R^T\boldsymbol\omega_s$ and
//! $\dot{\boldsymbol\omega}_b = \mathbf R^T\dot{\boldsymbol\omega}_s$ (see "Body axes" below). The state keeps the
//! spatial ones of the superelement's convention; the same update in spatial terms is
//! $\mathbf R_{n+1} = \exp(\widetilde{\mathbf R_n h\Delta\boldsymbol\theta})\mathbf R_n$. Newton corrects the
//! spatial increment $\mathbf h = \mathbf R_n h\Delta\boldsymbol\theta$:
//! $\mathbf S\Delta\mathbf x = -\mathbf F$, $\ddot{\mathbf q}_b \mathrel{+}= \beta'\mathbf R_n^T\Delta\mathbf x$,
//! $\dot{\mathbf q}_b \mathrel{+}= \gamma'\mathbf R_n^T\Delta\mathbf x$, $h\Delta\mathbf q \mathrel{+}= \mathbf R_n^T\Delta\mathbf x$
//! (scalars unrotated), with $\beta' = \frac{1-\alpha_m}{h^2\beta(1-\alpha_f)}$, $\gamma' = \frac{\gamma}{h\beta}$ and
//! $\mathbf S = \beta'\hat{\mathbf M} + \gamma'\hat{\mathbf C} + \hat{\mathbf K}$ with each rotation's columns made the
//! exact derivative: $\hat{\mathbf K}\mathbf J_l(\mathbf h) + \hat{\mathbf C}(\gamma'\mathbf E - \tilde{\boldsymbol\omega}_s\mathbf J_l)
//! \;+\; \hat{\mathbf M}(\beta'\mathbf E - \tilde{\dot{\boldsymbol\omega}}_s\mathbf J_l)$, $\mathbf E = \exp(\tilde{\mathbf h})$
//! (`System::iteration_matrix`).
//!
//! # Body axes
//!
//! The recursion compares velocities and accelerations of different steps component by
//! component. With spatial angular velocities it did so in fixed axes, while the modal
//! coordinates $\boldsymbol\eta$ live in the body's floating frame: in a body turning at
//! $\Omega$, an elastic mode of frequency $\omega$ appears at $\omega$ in $\boldsymbol\eta$ and at
//! $\omega\pm\Omega$ in the nodes' spatial rotation components, and the scheme's frequency error,
//! which grows with $\omega h$, then moves the parts of one mode by different phases each step.
//! The discrete map is no longer the generalized-α map of the linearised motion in the
//! turning frame, and it pumps energy into that mode. On the spin-up beam (validation problem C1, four
//! superelements, h = 5 ms) the out-of-plane fixed-interface modes of the segments, 346 rad/s
//! ($\omega h = 1.7$), grew from round-off at 3.4 /s at $\Omega$ = 10 rad/s with $\rho_\infty \ge 0.8$
//! (more at 15 rad/s, none at 4); the rate was the same for every Newton tolerance and with
//! more Newton corrections (the converged map itself), it vanished at $\omega h = 0.9$ and was
//! damped by $\rho_\infty = 0.5$; the frozen linearised spectrum showed no growing mode. In body
//! axes the nodes' rotation components turn with the body, all parts of a mode share its
//! frequency, and the runs stay at round-off for 100 s at $\rho_\infty$ = 0.8, 0.9 and 1
//! (`tests/convergence.rs`, `spin_up_steady_rotation_stays_in_plane`).
//!
//! With [`DynamicSettings::body_axis_translations`], the translations of a free independent
//! node (three unknown translations and a free rotation: the interfaces of a floating chain of
//! superelements) are carried the same way, as the SE(3) form of the paper: $\mathbf v_b = \mathbf R^T\dot{\mathbf x}$ with the node's
//! rotation, the recursion's acceleration $\dot{\mathbf v}_b = \mathbf R^T\ddot{\mathbf x} -
//! \boldsymbol\omega_b\times\mathbf v_b$, and the update
//! $\mathbf x_{n+1} = \mathbf x_n + \mathbf R_n\mathbf J_l(h\Delta\boldsymbol\theta_b)\,h\Delta\mathbf u_b$
//! ($\mathbf J_l$ the left Jacobian of SO(3), the translation of the SE(3) exponential), which is
//! second-order consistent with $\dot{\mathbf x} = \mathbf R\mathbf v_b$. A steady rotation then has
//! constant $\mathbf v_b$ and zero $\dot{\mathbf v}_b$, and an axial mode of a turning member appears in
//! $\mathbf v_b$ at its own frequency only. With the translations in fixed axes, the spin-up beam
//! with eight superelements (axial modes at $\omega h \approx 40$) grew an in-plane mode at
//! $\rho_\infty = 1$ and stopped at t = 26.2 s; in body axes it runs the 100 s. Newton still
//! corrects the spatial increment: a correction $\Delta\mathbf x$ of a translation moves the
//! node by exactly $\Delta\mathbf x$ ($h\Delta\mathbf u_b = \mathbf J_l^{-1}\mathbf R_n^T(\mathbf x_{n+1} -
//! \mathbf x_n)$), and the iteration matrix keeps its fixed-axis translation columns, which differ
//! from the exact derivative by $O(h\Omega)$ in the velocity and acceleration (about 3 Newton
//! iterations per step on the spin-up beam). Translations of supported or dependent nodes
//! (joint coordinates) stay scalars. The option is off by default (the R^3 x SO(3) form, the
//! translations in fixed axes): on the free flexible beam of validation problem C4 the
//! energy drift with it fell only from 9.1e-7 to 3.1e-7 between h = 2 and 1 ms (order 1.6,
//! against 2 in fixed axes), and modified Newton refactorises more often with the inexact
//! translation columns.
//!
//! The initial accelerations are consistent ($\hat{\mathbf M}\ddot{\mathbf q}_0 = -\mathbf F(\mathbf q_0, \dot{\mathbf q}_0,
//! \mathbf 0)$; $\mathbf F$ is linear in $\ddot{\mathbf q}$) and $\mathbf a_0 = \ddot{\mathbf q}_0$. Each flexible body's last
//! frame stays in the state, so the frame solve (4.4) is warm-started from the previous
//! iteration or step.
//!
//! # Newton strategy
//!
//! [`DynamicSettings::newton`] chooses how the corrections get their iteration matrix
//! $\mathbf S = \beta'\hat{\mathbf M} + \gamma'\hat{\mathbf C} + \hat{\mathbf K}\mathbf T$:
//!
//! * [`NewtonStrategy::Full`] (the default): the tangents are evaluated and $\mathbf S$ is
//!   factorised at every correction (quadratic convergence). After a correction the residual is
//!   tested with the forces alone, and tangents are evaluated only if another correction is
//!   needed.
//! * [`NewtonStrategy::Modified`]: the factorised $\mathbf S$ stays in the workspace across
//!   corrections and steps, and the iterations evaluate forces only (linear convergence, each
//!   iteration cheaper). The refresh rule: $\mathbf S$ is rebuilt from new tangents and
//!   refactorised (i) when there is none for the current $h$ ($\beta'$, $\gamma'$ depend on it: the
//!   first step, every change of $h$ by the adaptive step, after a failed step), (ii) at once when
//!   a correction lets the residual grow, and (iii) with the next evaluation (no second
//!   evaluation of the same iterate) when a correction contracts it by less than
//!   [`MODIFIED_NEWTON_RATE`], $\|\mathbf F_{k+1}\| > 0.01\|\mathbf F_k\|$; tangents scheduled by (iii)
//!   that arrive with the converging evaluation are factorised for the next step. A step whose
//!   modified iterations fail (no convergence in `max_iterations`, a singular matrix, a body
//!   that cannot be evaluated) is solved again from the predictor with full Newton before
//!   [`SolveError::NotConverged`](crate::SolveError::NotConverged) is reported. Both converge to the same tolerance, so their
//!   trajectories agree to it. [`StepReport::jacobians`] and [`Trajectory::jacobians`] count the
//!   factorisations.
//!
//! A kept matrix was built where the mechanism stood some steps before, and the iteration
//! matrix of a turning body turns with it: in the spatial unknowns of a free node (the
//! interface between two superelements) $\mathbf S \approx \mathbf T\mathbf S_f\mathbf T^T$, with
//! $\mathbf T$ the node's rotation since the factorisation, $\mathbf Q = \mathbf R\mathbf R_f^T$, on
//! its rotation and translation unknowns (scalar joint and modal coordinates do not turn).
//! Modified Newton therefore solves in the kept factor's axes,
//! $\Delta\mathbf x = \mathbf T\mathbf S_f^{-1}\mathbf T^T(-\mathbf F)$ (`corotate`, free nodes with their
//! own rotation coordinate; fixed-axis translations of a free node $\mathbf B^{-1}\mathbf Q\mathbf B$;
//! `corotate_in_plane`, a node held in a plane and turning about its normal, the node between
//! two planar bodies: the rotation by $\theta - \theta_f$ on its two in-plane translations).
//! Any matrix that contracts gives the same solution; this one contracts more. On the
//! slider-crank with the rod as two beam superelements (validation problem C2, 13 unknowns,
//! the rod turning 0.008 rad per step) a kept matrix contracted the residual by about 0.012
//! per correction a step after its factorisation, just above [`MODIFIED_NEWTON_RATE`], so
//! 0.91 factorisations per step were needed; turned, it contracts by 0.004-0.006 after the
//! first correction, and the run takes 0.58 factorisations per step at the same 3.44
//! iterations (0.747M instead of 0.822M instructions per step).
//!
//! Modified Newton pays when a kept matrix contracts strongly and tangents cost much more than
//! forces. On the slider-crank (validation problem C2, one superelement with geometric stiffening)
//! the tangents cost 2-3 times the forces and a kept matrix contracts by 0.05-0.2 after a few
//! steps: it takes 3.5 iterations and 0.55 factorisations per step against full Newton's 2 and
//! 2, and 13 % (2 modes) to 35 % (4 modes) fewer instructions ([`MODIFIED_NEWTON_RATE`]).
//!
//! # Predictor
//!
//! A step starts from constant accelerations, $\ddot{\mathbf q}_{n+1} = \ddot{\mathbf q}_n$ (body
//! axes), with $\mathbf a_{n+1}$, $\dot{\mathbf q}_{n+1}$ and $h\Delta\mathbf q$ from the recursion.
//! Full Newton extrapolates instead once [`PREDICTOR_WINDOW`] + 1 steps of the current $h$
//! are known: each component from its last two values,
//! $\ddot q_{n+1} = c_1\ddot q_n + c_2\ddot q_{n-1}$, with $c_1$, $c_2$ fitted by least squares to
//! the window (`AccelerationHistory::predict`), the recursion of a sampled oscillation
//! ($c_1 = 2\cos\omega h$, $c_2 = -1$) as well as linear extrapolation of a smooth motion
//! ($c_1 = 2$, $c_2 = -1$), kept within twice the largest change of one step in the window.
//! On the C2 rod the accelerations of the interface rotation and of the modal coordinates
//! are dominated by a vibration at $\omega h \approx 1.4$ (consecutive values nearly
//! uncorrelated): linear extrapolation makes their predictor error a third larger and takes 2.42 instead of
//! 2.19 corrections per step, the fit divides it by 7-17 (from the recorded accelerations) and
//! leaves the residual after the first correction 6 times smaller (it is quadratic in the
//! predictor's error), so most steps converge after 2 corrections: 2.00 per step. Modified
//! Newton keeps the constant predictor: its corrections contract linearly, by the kept
//! matrix's rate, from the first residual, which the fit does not lower there (the joint
//! coordinates' accelerations, several frequencies mixed, dominate it); with the fit it took
//! 3.75 iterations and 0.47 factorisations per step against 3.44 and 0.58.
//! The predictor changes only where Newton starts: both converge to the same tolerance. A
//! change of $h$ (the adaptive step, the halved steps of a retried one, the last step that
//! lands on the end time) and a rejected step start the window again.
//!
//! The iteration matrix is factorised densely (LU with partial pivoting) up to
//! [`crate::DENSE_MAX`] unknowns and by the sparse LU on the system pattern above
//! ([`crate::LinearSolver`]).
//!
//! # Adaptive step
//!
//! [`Integrator::step_adaptive`] and [`solve_dynamic_adaptive`] estimate the local error of the
//! configuration by the Newmark-family estimate (Zienkiewicz & Xie 1991, *Earthquake Eng.
//! Struct. Dyn.* 20; with the algorithmic accelerations of generalized-α):
//! $\mathbf e_{n+1} = h^2\,|\beta - \tfrac16|\,(\mathbf a_{n+1} - \mathbf a_n)$, the $O(h^3)$ term the
//! update of $\mathbf q$ misses, measured as $\max_i|e_i|/s_i$ with the unknowns' scales
//! ([`System::increment_norm`](crate::System::increment_norm)). A step with $e >$ `tolerance` is rejected and retried with
//! $h\min(0.9, \max(0.2, 0.9(\mathrm{tol}/e)^{1/3}))$; after an accepted one the PI controller
//! ([`PI_INTEGRAL`], [`PI_PROPORTIONAL`]) sets the next,
//! $h_{n+1} = 0.9\,h_n(\mathrm{tol}/e_n)^{0.7/3}(e_{n-1}/\mathrm{tol})^{0.4/3}$, growing by at most 2
//! (not at all right after a rejection) within `[min_step, max_step]`: it follows the error's
//! trend, so a smoothly varying error is met without the cycle of growth and rejection of the
//! plain $(\mathrm{tol}/e)^{1/3}$ rule.
//! The fixed-step path ([`Integrator::step`]) is unchanged. With modified Newton
//! every accepted change of $h$ refactorises the iteration matrix (rule (i) above).
//!
//! # What is conserved
//!
//! The updates of $\dot{\mathbf q}$ and $\mathbf q$ are linear in the algorithmic accelerations, so a
//! momentum that is a constant linear form $\mathbf c^T\dot{\mathbf q}$ of the velocities (the linear
//! momentum of point masses) is conserved to round-off when $\mathbf c^T\mathbf F$ is free of internal
//! forces. The momenta of a flexible or rigid body in these absolute coordinates are nonlinear
//! in $(\mathbf q, \dot{\mathbf q})$ (the centre of mass follows the frame (4.4) and the CB shapes;
//! $\mathbf H$ involves the rotations), so the scheme alone makes their rates vanish at each
//! $t_{n+1}$ but conserves $\mathbf L$, $\mathbf H$ and the energy to its order, 2. On a free, unloaded
//! model ([`System::rigid_invariance`](crate::System::rigid_invariance)) the step therefore ends with the momentum projection of
//! [`crate::assembly::system::momentum`] (Hairer, Lubich & Wanner, §IV.4; `DynamicSettings::momentum`): the
//! velocities get the $\hat{\mathbf M}$-orthogonal rigid correction that restores $\mathbf L$ and
//! $\mathbf H$ of the start, so both are constant to round-off, and the energy still drifts at
//! order 2 (validation problem C4: `tests/unit/free_body.rs`). The correction is $O(h^3)$ per step and
//! keeps the order of the trajectory; the initial accelerations are not projected.

#![allow(non_snake_case)]

mod integrator;
pub mod retry;
pub mod streaming;
mod trajectory;

pub use integrator::{
    fixed_steps, last_step_size, step_adaptive_to, step_end_time, AdaptiveSettings, AdaptiveStep, AlphaParameters,
    DynamicSettings, Integrator, NewtonStrategy, StepReport, MODIFIED_NEWTON_RATE, PI_INTEGRAL, PI_PROPORTIONAL,
    PREDICTOR_WINDOW,
};
pub use trajectory::{solve_dynamic, solve_dynamic_adaptive, Trajectory};
