//! The plain data of a body's configuration: the floating frame ([`Frame`]), where it sits
//! ([`FrameChoice`]), and the state in absolute interface coordinates ([`BodyState`]). A leaf
//! module: the frame solve, the local coordinates, the transformations and the body read it.

#![allow(non_snake_case)]

use nalgebra::{UnitQuaternion, Vector3};
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

/// The state of one body in absolute interface coordinates, with the last frame as the warm
/// start of (4.4).
///
/// Velocities are spatial: $\dot{\mathbf r}_k = \mathbf v_k$, $\dot{\mathbf R}_k =
/// \tilde{\boldsymbol\omega}_k\mathbf R_k$. The superelement's generalised velocity is
/// $\dot{\mathbf q} = [\mathbf v_1, \boldsymbol\omega_1, \dots, \mathbf v_N, \boldsymbol\omega_N,
/// \dot{\boldsymbol\eta}]$, and accelerations are passed in the same order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// Interface positions $\mathbf r_k$.
    pub r: Vec<Vector3<f64>>,
    /// Interface orientations $\mathbf R_k$ (from the FE model's axes, theory guide §4:
    /// $\mathbf R_{k0} = \mathbf I$).
    pub R: Vec<UnitQuaternion<f64>>,
    /// Interface velocities $\mathbf v_k$.
    pub v: Vec<Vector3<f64>>,
    /// Spatial angular velocities $\boldsymbol\omega_k$.
    pub omega: Vec<Vector3<f64>>,
    /// Modal coordinates $\boldsymbol\eta$.
    pub eta: Vec<f64>,
    /// $\dot{\boldsymbol\eta}$.
    pub eta_dot: Vec<f64>,
    /// The last frame: the Newton start of (4.4). Keep it up to date with the frame returned
    /// by [`crate::Superelement::solve_frame`] or [`crate::Evaluation::frame`].
    pub frame: Frame,
}

impl BodyState {
    /// $\dot{\mathbf q} = [\mathbf v_1, \boldsymbol\omega_1, \dots, \dot{\boldsymbol\eta}]$.
    pub fn velocity_vector(&self) -> Vec<f64> {
        let mut qd = Vec::with_capacity(6 * self.r.len() + self.eta.len());
        for k in 0..self.r.len() {
            qd.extend_from_slice(self.v[k].as_slice());
            qd.extend_from_slice(self.omega[k].as_slice());
        }
        qd.extend_from_slice(&self.eta_dot);
        qd
    }
}
