//! User-defined forces: a Rust type that computes a force and moment on some nodes from their
//! motion and the time, added to a system with [`crate::System::with_user_forces`].
//!
//! This is how a controller, a co-simulation partner, a tyre or a bushing model, or any force
//! law the model data do not offer, acts on a model without changing this crate. The solver
//! treats the force like a nodal load: it enters the residual as an external force
//! $\mathbf f_e(t, \mathbf x, \mathbf V)$ on each of its nodes (inertial axes, $[\mathbf f;
//! \mathbf m]$ per node), scaled by the load factor $\lambda$ in statics (so load stepping ramps
//! it with the loads and gravity), and its Jacobians enter the iteration matrix:
//!
//! $$\mathbf K_t \mathrel{-}= \lambda\,\frac{\partial\mathbf f_e}{\partial\mathbf x},\qquad
//! \mathbf C_t \mathrel{-}= \lambda\,\frac{\partial\mathbf f_e}{\partial\mathbf V},$$
//!
//! with $\mathbf x$ varied as the rest of the crate does it: positions added, orientations by
//! a spatial rotation $\mathbf R \leftarrow \exp(\widetilde{\delta\boldsymbol\pi})\mathbf R$;
//! $\mathbf V = [\mathbf v; \boldsymbol\omega]$ with the spatial angular velocity.
//!
//! A force that does not give its Jacobians ([`UserForce::jacobian`] returns `false`, the
//! default) gets them by central differences of [`UserForce::force`]
//! ([`finite_difference_jacobian`], $24N$ evaluations for $N$ nodes, steps from
//! [`UserForce::fd_steps`]). Newton converges with either; exact Jacobians save the
//! evaluations and converge in fewer iterations when the force is stiff.
//!
//! The force is a function of the state: it must not depend on anything that changes during
//! a step's Newton iterations except its arguments. A value that a controller sets *between*
//! steps (a target, a gain, a measured signal) lives in the implementing type behind interior
//! mutability (an atomic or a mutex), and the caller keeps an `Arc` to it:
//!
//! ```
//! use mbs::user_force::{UserForce, Wrench};
//! use mbs::{NodeId, NodeMotion};
//! use std::sync::Mutex;
//!
//! /// A torque about z on one node, set by a controller between steps.
//! #[derive(Debug)]
//! struct Torque { node: [NodeId; 1], value: Mutex<f64> }
//!
//! impl UserForce for Torque {
//!     fn name(&self) -> &str { "motor" }
//!     fn nodes(&self) -> &[NodeId] { &self.node }
//!     fn force(&self, _t: f64, _motions: &[NodeMotion], wrench: &mut [Wrench]) {
//!         wrench[0][5] = *self.value.lock().unwrap();
//!     }
//!     // A constant torque does not depend on the state: its Jacobians are zero.
//!     fn jacobian(&self, _t: f64, _m: &[NodeMotion], _dx: faer::MatMut<f64>, _dv: faer::MatMut<f64>) -> bool {
//!         true
//!     }
//! }
//! ```
//!
//! The momentum projection of free models ([`crate::assembly::system::momentum`]) is off with a user force: it
//! cannot know whether the force is an internal one.
//!
//! # Notation
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\mathbf f_e = [\mathbf f; \mathbf m]$ | [`Wrench`] | force and moment on a node, inertial axes |
//! | $\partial\mathbf f_e/\partial\mathbf x$ | `dx` | $6N\times6N$: row block $a$ the wrench on node $a$, column block $b$ $[\delta\mathbf r_b; \delta\boldsymbol\pi_b]$ |
//! | $\partial\mathbf f_e/\partial\mathbf V$ | `dv` | $6N\times6N$: column block $b$ $[\delta\mathbf v_b; \delta\boldsymbol\omega_b]$ |
//! | $h_r,\ h_\pi,\ h_v,\ h_\omega$ | [`FdSteps`] | central-difference steps |

#![allow(non_snake_case)]

use crate::model::NodeId;
use crate::node::NodeMotion;
use faer::{Mat, MatMut};
use nalgebra::Vector3;
use std::fmt::Debug;

/// Force and moment $[\mathbf f; \mathbf m]$ on one node, inertial axes (N, N m).
pub type Wrench = [f64; 6];

/// Central-difference steps of [`finite_difference_jacobian`]. Each should be about
/// $\varepsilon^{1/3}\approx 6\cdot10^{-6}$ times the scale over which the force changes
/// appreciably: the truncation error is $O(h^2)$, the round-off $O(\varepsilon/h)$.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FdSteps {
    /// Position step \[m\].
    pub position: f64,
    /// Spatial rotation step \[rad\].
    pub rotation: f64,
    /// Velocity step \[m/s\].
    pub velocity: f64,
    /// Angular velocity step \[rad/s\].
    pub angular_velocity: f64,
}

impl Default for FdSteps {
    /// $10^{-6}$ in SI units for all four: forces that vary over metres, radians, metres per
    /// second (a relative error near $10^{-10}$ there).
    fn default() -> Self {
        Self {
            position: 1e-6,
            rotation: 1e-6,
            velocity: 1e-6,
            angular_velocity: 1e-6,
        }
    }
}

/// A user-defined force on some nodes of a model (module docs).
///
/// `Send + Sync`: the system evaluates elements in parallel on large models.
pub trait UserForce: Send + Sync + Debug {
    /// A name for messages ("user force 'motor' at t = ... is not finite").
    fn name(&self) -> &str;

    /// The nodes the force acts on; `force` receives their motions in this order.
    fn nodes(&self) -> &[NodeId];

    /// Writes the wrench on each node at time `t` (`wrench` comes zeroed, one entry per node
    /// of [`Self::nodes`]). `motions` holds each node's position, orientation, velocity, spatial
    /// angular velocity and acceleration; a force must not depend on the accelerations (they are
    /// not differentiated: an acceleration-dependent force is an inertia, which belongs to a
    /// body).
    fn force(&self, t: f64, motions: &[NodeMotion], wrench: &mut [Wrench]);

    /// Optionally writes $\partial\mathbf f_e/\partial\mathbf x$ into `dx` and
    /// $\partial\mathbf f_e/\partial\mathbf V$ into `dv` (both $6N\times6N$, zeroed; layout in the
    /// module's notation table) and returns `true`. The default returns `false`: the Jacobians
    /// then come from central differences of [`Self::force`].
    fn jacobian(&self, t: f64, motions: &[NodeMotion], dx: MatMut<'_, f64>, dv: MatMut<'_, f64>) -> bool {
        let _ = (t, motions, dx, dv);
        false
    }

    /// Steps of the central differences used when [`Self::jacobian`] returns `false`.
    fn fd_steps(&self) -> FdSteps {
        FdSteps::default()
    }
}

/// $\partial\mathbf f_e/\partial\mathbf x$ and $\partial\mathbf f_e/\partial\mathbf V$ of `force` at
/// `motions` by central differences ($24N$ evaluations; rotations perturbed through exp), into
/// `dx`, `dv` ($6N\times6N$). Public so that an implementation can check its own
/// [`UserForce::jacobian`] against it.
pub fn finite_difference_jacobian(
    force: &dyn UserForce,
    t: f64,
    motions: &[NodeMotion],
    dx: MatMut<'_, f64>,
    dv: MatMut<'_, f64>,
) {
    let mut buf = UserBuffer::new(motions.len());
    buf.motions.copy_from_slice(motions);
    buf.fd_jacobian(force, t);
    let (mut dx, mut dv) = (dx, dv);
    dx.copy_from(&buf.dx);
    dv.copy_from(&buf.dv);
}

/// The reused buffers of one user force (sized once per analysis).
#[derive(Clone, Debug)]
pub(crate) struct UserBuffer {
    /// The force's node motions, gathered from the system's.
    pub(crate) motions: Vec<NodeMotion>,
    pub(crate) wrench: Vec<Wrench>,
    plus: Vec<Wrench>,
    minus: Vec<Wrench>,
    pub(crate) dx: Mat<f64>,
    pub(crate) dv: Mat<f64>,
}

impl UserBuffer {
    pub(crate) fn new(n_nodes: usize) -> Self {
        let n = 6 * n_nodes;
        let zero = NodeMotion {
            r: Vector3::zeros(),
            R: nalgebra::UnitQuaternion::identity(),
            v: Vector3::zeros(),
            omega: Vector3::zeros(),
            a: Vector3::zeros(),
            alpha: Vector3::zeros(),
        };
        Self {
            motions: vec![zero; n_nodes],
            wrench: vec![[0.0; 6]; n_nodes],
            plus: vec![[0.0; 6]; n_nodes],
            minus: vec![[0.0; 6]; n_nodes],
            dx: Mat::zeros(n, n),
            dv: Mat::zeros(n, n),
        }
    }

    /// `force` at the buffer's motions into `out` (zeroed first).
    pub(crate) fn eval(force: &dyn UserForce, t: f64, motions: &[NodeMotion], out: &mut [Wrench]) {
        out.iter_mut().for_each(|w| *w = [0.0; 6]);
        force.force(t, motions, out);
    }

    /// Central differences into `dx`, `dv` (column by column: node `b`, slot `j`).
    pub(crate) fn fd_jacobian(&mut self, force: &dyn UserForce, t: f64) {
        let h = force.fd_steps();
        let N = self.motions.len();
        for b in 0..N {
            for j in 0..12 {
                let step = match j {
                    0..=2 => h.position,
                    3..=5 => h.rotation,
                    6..=8 => h.velocity,
                    _ => h.angular_velocity,
                };
                let base = self.motions[b];
                for (sign, out) in [(1.0, &mut self.plus), (-1.0, &mut self.minus)] {
                    let mut m = base;
                    let mut e = Vector3::zeros();
                    e[j % 3] = sign * step;
                    match j / 3 {
                        0 => m.r += e,
                        1 => m.R = superelement::so3::perturb(&m.R, &e),
                        2 => m.v += e,
                        _ => m.omega += e,
                    }
                    self.motions[b] = m;
                    Self::eval(force, t, &self.motions, out);
                }
                self.motions[b] = base;
                let target = if j < 6 { &mut self.dx } else { &mut self.dv };
                let col = 6 * b + j % 6;
                for a in 0..N {
                    for i in 0..6 {
                        target[(6 * a + i, col)] = (self.plus[a][i] - self.minus[a][i]) / (2.0 * step);
                    }
                }
            }
        }
    }
}

/// The nodes of a user force checked against the model's node count.
pub(crate) fn check_nodes(
    force: &dyn UserForce,
    index: usize,
    n_nodes: usize,
) -> Result<Vec<usize>, crate::error::ModelError> {
    force
        .nodes()
        .iter()
        .map(|id| {
            if id.index() < n_nodes {
                Ok(id.index())
            } else {
                Err(crate::error::ModelError::UnknownNode {
                    id: id.0,
                    count: n_nodes,
                    referenced_by: format!("user force '{}'", force.name()),
                    by: crate::error::Entity::UserForce(index),
                })
            }
        })
        .collect()
}
