//! The floating frame $\{\mathbf r_j, \mathbf R_j\}$: the three frame choices and the Newton
//! solve of $\boldsymbol\Phi_j\mathbf q^{jj} = \mathbf 0$ (4.4), warm-started from the last frame.

#![allow(non_snake_case)]

use crate::error::SuperelementError;
use crate::local_coordinates::{local_coordinates, u_of};
use crate::so3;
use crate::state::BodyState;
pub use crate::state::{Frame, FrameChoice};
use crate::transform::{col, inverse_with_rcond, phi_j_psi, RCOND_MIN};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// Settings of the Newton solve of (4.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Converged when $\max(|\mathbf g_t|/L,\ |\mathbf g_r|) \le$ `tolerance` $+ 64\epsilon(1 +
    /// \max_k|\mathbf r_k|/L)$, $\mathbf g = \boldsymbol\Phi_j\mathbf q^{jj}$, $L$ the body size.
    /// The second term is the round-off floor of $\mathbf r_k - \mathbf r_j$ for a body far
    /// from the origin; $10^{-12}$ is far below any elastic deformation of interest and still
    /// reached in two or three quadratic steps from the previous frame.
    pub tolerance: f64,
    /// Newton iterations before giving up; from a warm start 2-4 are normal ([AIC-FFR] §4), and 30
    /// covers a cold start from a frame half a turn away.
    pub max_iterations: usize,
}

impl Default for FrameSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-12,
            max_iterations: 30,
        }
    }
}

/// Buffers of the Newton solve of (4.4): $\mathbf q^{jj}$ ($n$), $\mathbf r_k^{jj}$ and
/// $\boldsymbol\Lambda$ blocks ($N$ each), and the inverse Jacobian
/// $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$ of the body's last evaluation, if there is one (the
/// chord steps of [`solve_frame_in`]).
pub(crate) struct FrameScratch<'a> {
    pub q: &'a mut [f64],
    pub r_loc: &'a mut [Vector3<f64>],
    pub Lambda: &'a mut [Matrix3<f64>],
    pub last_G_inv: Option<Matrix6<f64>>,
}

/// A chord step with the last evaluation's Jacobian is kept while each step cuts the residual
/// at least by this factor; above it the solve changes to Newton for good. The Jacobian
/// $\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig}$ depends on the deformation only (not
/// on the rigid motion), which changes little from one evaluation of a time step to the next,
/// so chord steps contract by far more than this; from an unrelated configuration they do not,
/// and Newton takes over after one step.
const CHORD_CONTRACTION: f64 = 0.01;

/// How the frame is found, decided once from the [`FrameChoice`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FrameSolve {
    /// General $\boldsymbol\Phi_j$: Newton.
    Newton,
    /// $\boldsymbol\Phi_j$ selects interface $k$, at the frame origin: explicit.
    AtInterface(usize),
}

/// What the frame solve reads of a body: its undeformed interface positions $\mathbf x_k$,
/// $\boldsymbol\Phi_j$, its size $L$, the settings and how the frame is found.
pub(crate) struct FrameProblem<'a> {
    pub x: &'a [Vector3<f64>],
    pub Phi_j: faer::MatRef<'a, f64>,
    pub length: f64,
    pub settings: FrameSettings,
    pub solve: FrameSolve,
}

/// Solves (4.4) $\boldsymbol\Phi_j\mathbf q^{jj}(\mathbf r_j, \mathbf R_j) = \mathbf 0$ for the frame,
/// starting from `state.frame` (the last step's frame), with the Newton iterates in `scratch`
/// (no allocation; the hot loop passes buffers of its workspace). The state is checked by the
/// caller ([`crate::Superelement::solve_frame`], which derives the step).
///
/// From the warm start, when `scratch` carries the inverse Jacobian of the body's last
/// evaluation, the first steps are chord steps with it (no $\boldsymbol\Lambda$, no
/// $\boldsymbol\Phi_j\boldsymbol\Psi$, no inverse), for as long as they contract by
/// [`CHORD_CONTRACTION`]; then Newton. The convergence test is the same either way.
pub(crate) fn solve_frame_in(
    p: &FrameProblem<'_>,
    state: &BodyState,
    scratch: &mut FrameScratch<'_>,
) -> Result<(Frame, usize), SuperelementError> {
    match p.solve {
        FrameSolve::AtInterface(k) => Ok((Frame::new(state.r[k], state.R[k]), 0)),
        FrameSolve::Newton => {
            // The equations have spurious roots with elastic rotations near pi, which
            // Newton can reach from a frame far from the body (a cold start). Interface 0
            // gives a start within the elastic deformation of the solution (R_k0 = I):
            // use it when the warm start implies an elastic rotation above 1 rad (far
            // beyond the small-strain range of the formulation), and retry from it when
            // Newton fails from the warm start.
            let guess = || Frame::new(state.r[0] - state.R[0] * p.x[0], state.R[0]);
            // The angle of R_j^T R_k exceeds 1 rad where the scalar part of the quaternion
            // product, the dot product of the two unit quaternions, is below cos(1/2) in
            // magnitude (no logarithm needed).
            let cos_half = 0.5f64.cos();
            let warm_is_far = state
                .R
                .iter()
                .any(|R_k| state.frame.R.coords.dot(&R_k.coords).abs() < cos_half);
            let chord = scratch.last_G_inv.take();
            if warm_is_far {
                return newton_frame(p, state, guess(), None, scratch);
            }
            newton_frame(p, state, state.frame, chord, scratch).or_else(|e| {
                match newton_frame(p, state, guess(), None, scratch) {
                    Ok(found) => Ok(found),
                    Err(_) => Err(e),
                }
            })
        }
    }
}

/// Newton from `start`, after chord steps with `chord` while they contract
/// ([`solve_frame_in`]). On success `scratch.q` holds $\mathbf q^{jj}$ at the returned frame
/// (the last residual was computed there): `Superelement::evaluate_into` uses it as is.
fn newton_frame(
    p: &FrameProblem<'_>,
    state: &BodyState,
    start: Frame,
    mut chord: Option<Matrix6<f64>>,
    scratch: &mut FrameScratch<'_>,
) -> Result<(Frame, usize), SuperelementError> {
    let N = p.x.len();
    let L = p.length;
    let r_max = state.r.iter().map(|r| r.norm()).fold(0.0, f64::max);
    let tol = p.settings.tolerance + 64.0 * f64::EPSILON * (1.0 + r_max / L);
    let mut frame = start;
    let FrameScratch { q, r_loc, Lambda, .. } = scratch;
    let mut residual = f64::INFINITY;
    let mut last_residual = f64::INFINITY;
    for it in 0..=p.settings.max_iterations {
        local_coordinates(&frame, &state.r, &state.R, p.x, &state.eta, q);
        // g = Phi_j q by columns of fixed length (a plain loop; the same sums in the same
        // order as with nalgebra's vectors).
        let mut ga = [0.0f64; 6];
        for (c, qc) in q.iter().enumerate() {
            let phi: &[f64; 6] = col(p.Phi_j, c)[..6].try_into().expect("6 rows");
            for a in 0..6 {
                ga[a] += phi[a] * qc;
            }
        }
        let g = Vector6::from(ga);
        residual = (g.fixed_rows::<3>(0).norm() / L).max(g.fixed_rows::<3>(3).norm());
        if !residual.is_finite() {
            break;
        }
        if residual <= tol {
            return Ok((frame, it));
        }
        if it == p.settings.max_iterations {
            break;
        }
        if it > 0 && residual > CHORD_CONTRACTION * last_residual {
            chord = None;
        }
        last_residual = residual;
        let Gi = match chord {
            Some(Gi) => Gi,
            None => {
                for k in 0..N {
                    r_loc[k] = p.x[k] + u_of(q, k);
                    Lambda[k] = so3::left_jacobian_inv(&crate::local_coordinates::theta_of(q, k));
                }
                let G = phi_j_psi(p.Phi_j, r_loc, Lambda);
                let (Gi, rcond) = inverse_with_rcond(&G).ok_or(SuperelementError::SingularFrame { rcond: 0.0 })?;
                if rcond < RCOND_MIN {
                    return Err(SuperelementError::SingularFrame { rcond });
                }
                Gi
            }
        };
        let d = Gi * g;
        let dt = Vector3::new(d[0], d[1], d[2]);
        let dr = Vector3::new(d[3], d[4], d[5]);
        frame.r += frame.R * dt;
        frame.R *= so3::exp(&dr);
        frame.R.renormalize();
    }
    Err(SuperelementError::FrameNotConverged {
        iterations: p.settings.max_iterations,
        residual,
        tolerance: tol,
    })
}
