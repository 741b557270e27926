//! The floating frame $\{\mathbf r_j, \mathbf R_j\}$: the three frame choices and the Newton
//! solve of $\boldsymbol\Phi_j\mathbf q^{jj} = \mathbf 0$ (4.4), warm-started from the last frame.

#![allow(non_snake_case)]

use crate::body::{BodyState, Superelement};
use crate::error::SuperelementError;
use crate::local_coordinates::{local_coordinates, u_of};
use crate::so3::{self, skew};
use nalgebra::{Matrix3, Matrix6, UnitQuaternion, Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// Where the floating frame sits and which six equations (4.4) fix it to the body
/// (theory guide §4.3). One switch, so that the validation suite can compare them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FrameChoice {
    /// \[E17\]: $\boldsymbol\Phi_j$ = the CB modes evaluated at the undeformed centre of mass by
    /// the mass-weighted rigid fit (`ReducedBody::Phi_com`). The frame origin is the centre
    /// of mass; "no elastic deformation at the frame" means $\int\rho\mathbf S\,dV\,\mathbf q^{jj} = 0$
    /// and $\int\rho\tilde{\mathbf x}\mathbf S\,dV\,\mathbf q^{jj} = 0$ (a linearised mean-axis
    /// condition). Solved by Newton.
    CenterOfMass,
    /// Cardona & Géradin (1991): the frame sits at interface $k$ (0-based), whose CB
    /// coordinates are then identically zero (its six static modes drop out through
    /// $\mathbf T_j$). The solve is explicit: $\mathbf r_j = \mathbf r_k$, $\mathbf R_j = \mathbf R_k$.
    InterfaceNode(usize),
    /// Cardona (2000): the frame sits at the auxiliary interface placed at the centre of mass
    /// and held fixed during the reduction (`ReducedBody::auxiliary_interface`); it is an
    /// interface of the superelement (6 more coordinates). Explicit, like `InterfaceNode`.
    AuxiliaryNode,
}

impl std::fmt::Display for FrameChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameChoice::CenterOfMass => write!(f, "center-of-mass"),
            FrameChoice::InterfaceNode(k) => write!(f, "interface-node({k})"),
            FrameChoice::AuxiliaryNode => write!(f, "auxiliary-node"),
        }
    }
}

/// The floating frame: origin $\mathbf r_j$ (where the frame's material point $P_j$ is) and
/// orientation $\mathbf R_j$ (body axes to inertial axes).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    pub r: Vector3<f64>,
    pub R: UnitQuaternion<f64>,
}

impl Frame {
    /// The frame at `r` with orientation `R`.
    pub fn new(r: Vector3<f64>, R: UnitQuaternion<f64>) -> Self {
        Self { r, R }
    }

    /// The frame at the origin, aligned with the inertial axes.
    pub fn identity() -> Self {
        Self {
            r: Vector3::zeros(),
            R: UnitQuaternion::identity(),
        }
    }
}

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
/// $\boldsymbol\Lambda$ blocks ($N$ each).
pub(crate) struct FrameScratch<'a> {
    pub q: &'a mut [f64],
    pub r_loc: &'a mut [Vector3<f64>],
    pub Lambda: &'a mut [Matrix3<f64>],
}

/// How the frame is found, decided once from the [`FrameChoice`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FrameSolve {
    /// General $\boldsymbol\Phi_j$: Newton.
    Newton,
    /// $\boldsymbol\Phi_j$ selects interface $k$, at the frame origin: explicit.
    AtInterface(usize),
}

/// $\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig}$ (the 6x6 of (5.4), with the exact
/// rotation factor $\boldsymbol\Lambda$; see [`crate::transform`]), from the deformed local
/// positions `r_loc` $= \mathbf x_k + \mathbf u_k$ and the blocks of $\boldsymbol\Lambda$.
pub(crate) fn phi_j_psi(Phi_j: faer::MatRef<'_, f64>, r_loc: &[Vector3<f64>], Lambda: &[Matrix3<f64>]) -> Matrix6<f64> {
    let mut G = Matrix6::zeros();
    let column = |c| Vector6::from_column_slice(crate::transform::col(Phi_j, c));
    for (k, (r, L)) in r_loc.iter().zip(Lambda).enumerate() {
        // Block rows of Psi for interface k: u_k -> [I, -r~], theta_k -> [0, Lambda_k].
        let mr = -skew(r);
        for c in 0..3 {
            let (pu, pt) = (column(6 * k + c), column(6 * k + 3 + c));
            let mut gc = G.column_mut(c);
            gc += pu;
            for b in 0..3 {
                let mut gb = G.column_mut(3 + b);
                gb += pu * mr[(c, b)] + pt * L[(c, b)];
            }
        }
    }
    G
}

/// Inverse of a 6x6 with its reciprocal condition number in the 1-norm,
/// $1/(\|\mathbf G\|_1\|\mathbf G^{-1}\|_1)$; `None` when LU finds it singular.
pub(crate) fn inverse_with_rcond(G: &Matrix6<f64>) -> Option<(Matrix6<f64>, f64)> {
    let Gi = G.try_inverse()?;
    let norm1 = |A: &Matrix6<f64>| (0..6).map(|j| A.column(j).abs().sum()).fold(0.0, f64::max);
    Some((Gi, 1.0 / (norm1(G) * norm1(&Gi))))
}

/// Below this reciprocal condition number $\boldsymbol\Phi_j\boldsymbol\Phi_{rig}$ is treated as
/// singular: about $10^4$ times machine precision, where a solve loses all but four digits.
pub(crate) const RCOND_MIN: f64 = 1e-12;

impl Superelement {
    /// Solves (4.4) $\boldsymbol\Phi_j\mathbf q^{jj}(\mathbf r_j, \mathbf R_j) = \mathbf 0$ for the frame,
    /// starting from `state.frame` (the last step's frame).
    ///
    /// # Derivation
    /// With the local frame variation $\delta\boldsymbol\Xi = [\mathbf R_j^T\delta\mathbf r_j;\
    /// \mathbf R_j^T\delta\boldsymbol\pi_j]$ and the interface coordinates held,
    /// $\delta\mathbf q^{jj} = -\boldsymbol\Lambda\boldsymbol\Phi_{rig}\delta\boldsymbol\Xi$ ((5.3) with the exact
    /// rotation factor, see [`crate::local_coordinates::elastic_rotation`]), so the Jacobian
    /// of $\mathbf g = \boldsymbol\Phi_j\mathbf q^{jj}$ is $-\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig}$
    /// and the Newton step is $\delta\boldsymbol\Xi = (\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig})^{-1}\mathbf g$,
    /// applied as $\mathbf r_j \leftarrow \mathbf r_j + \mathbf R_j\delta\boldsymbol\Xi_t$,
    /// $\mathbf R_j \leftarrow \mathbf R_j\exp(\delta\boldsymbol\Xi_r)$. The eta columns of
    /// $\boldsymbol\Phi_j$ enter $\mathbf g$ with the given $\boldsymbol\eta$. Checked by
    /// `tests/unit/fd_tangent.rs::frame_jacobian` and `tests/unit/frame.rs`.
    ///
    /// For [`FrameChoice::InterfaceNode`] and [`FrameChoice::AuxiliaryNode`] the solution is
    /// explicit, $\mathbf r_j = \mathbf r_k$, $\mathbf R_j = \mathbf R_k$.
    pub fn solve_frame(&self, state: &BodyState) -> Result<(Frame, usize), SuperelementError> {
        let (mut q, mut r_loc, mut Lambda) = (
            vec![0.0; self.n],
            vec![Vector3::zeros(); self.n_interfaces],
            vec![Matrix3::identity(); self.n_interfaces],
        );
        let mut scratch = FrameScratch {
            q: &mut q,
            r_loc: &mut r_loc,
            Lambda: &mut Lambda,
        };
        self.solve_frame_in(state, &mut scratch)
    }

    /// [`Self::solve_frame`] with the Newton iterates in `scratch` (no allocation; the hot loop
    /// passes buffers of its workspace).
    pub(crate) fn solve_frame_in(
        &self,
        state: &BodyState,
        scratch: &mut FrameScratch<'_>,
    ) -> Result<(Frame, usize), SuperelementError> {
        self.check_state(state)?;
        match self.frame_solve {
            FrameSolve::AtInterface(k) => Ok((Frame::new(state.r[k], state.R[k]), 0)),
            FrameSolve::Newton => {
                // The equations have spurious roots with elastic rotations near pi, which
                // Newton can reach from a frame far from the body (a cold start). Interface 0
                // gives a start within the elastic deformation of the solution (R_k0 = I):
                // use it when the warm start implies an elastic rotation above 1 rad (far
                // beyond the small-strain range of the formulation), and retry from it when
                // Newton fails from the warm start.
                let guess = Frame::new(state.r[0] - state.R[0] * self.x[0], state.R[0]);
                let warm_is_far = state
                    .R
                    .iter()
                    .any(|R_k| crate::local_coordinates::elastic_rotation(&state.frame.R, R_k).norm() > 1.0);
                if warm_is_far {
                    return self.newton_frame(state, guess, scratch);
                }
                self.newton_frame(state, state.frame, scratch).or_else(|e| {
                    match self.newton_frame(state, guess, scratch) {
                        Ok(found) => Ok(found),
                        Err(_) => Err(e),
                    }
                })
            }
        }
    }

    fn newton_frame(
        &self,
        state: &BodyState,
        start: Frame,
        scratch: &mut FrameScratch<'_>,
    ) -> Result<(Frame, usize), SuperelementError> {
        let N = self.n_interfaces;
        let L = self.length;
        let r_max = state.r.iter().map(|r| r.norm()).fold(0.0, f64::max);
        let tol = self.frame_settings.tolerance + 64.0 * f64::EPSILON * (1.0 + r_max / L);
        let mut frame = start;
        let FrameScratch { q, r_loc, Lambda } = scratch;
        let mut residual = f64::INFINITY;
        for it in 0..=self.frame_settings.max_iterations {
            local_coordinates(&frame, &state.r, &state.R, &self.x, &state.eta, q);
            let mut g: Vector6<f64> = Vector6::zeros();
            for (c, qc) in q.iter().enumerate() {
                g += Vector6::from_column_slice(crate::transform::col(self.Phi_j.as_ref(), c)) * *qc;
            }
            residual = (g.fixed_rows::<3>(0).norm() / L).max(g.fixed_rows::<3>(3).norm());
            if !residual.is_finite() {
                break;
            }
            if residual <= tol {
                return Ok((frame, it));
            }
            if it == self.frame_settings.max_iterations {
                break;
            }
            for k in 0..N {
                r_loc[k] = self.x[k] + u_of(q, k);
                Lambda[k] = so3::left_jacobian_inv(&crate::local_coordinates::theta_of(q, k));
            }
            let G = phi_j_psi(self.Phi_j.as_ref(), r_loc, Lambda);
            let (Gi, rcond) = inverse_with_rcond(&G).ok_or(SuperelementError::SingularFrame { rcond: 0.0 })?;
            if rcond < RCOND_MIN {
                return Err(SuperelementError::SingularFrame { rcond });
            }
            let d = Gi * g;
            let dt = Vector3::new(d[0], d[1], d[2]);
            let dr = Vector3::new(d[3], d[4], d[5]);
            frame.r += frame.R * dt;
            frame.R *= so3::exp(&dr);
            frame.R.renormalize();
        }
        Err(SuperelementError::FrameNotConverged {
            iterations: self.frame_settings.max_iterations,
            residual,
            tolerance: tol,
        })
    }
}
