//! Linear and angular momentum of the system, the six rigid velocity fields, and the momentum
//! projection that makes generalized-α conserve both to round-off on a free, unloaded model.
//!
//! # Momentum map
//!
//! The kinetic energy of every body (rigid, point mass, and either inertia variant of a
//! superelement) is invariant under rigid motions, and its Noether charges are the linear
//! momentum $\mathbf L$ and the angular momentum $\mathbf H$ about the origin: with each body's
//! generalised momentum $\mathbf p = \mathbf M\mathbf V$ on its ports (node velocities and modal
//! rates), $\mathbf L = \sum_k\mathbf p^f_k$, $\mathbf H = \sum_k\mathbf r_k\times\mathbf p^f_k + \mathbf p^m_k$
//! (force and moment slots of port $k$). In independent coordinates this is
//! $\mathbf J(\mathbf q, \dot{\mathbf q}) = \mathbf T_{rig}^T\hat{\mathbf M}(\mathbf q)\dot{\mathbf q}$, linear in
//! $\dot{\mathbf q}$ for fixed $\mathbf q$, with $\mathbf T_{rig}$ ([`System::rigid_velocities`]) the
//! independent velocities of the six rigid velocity fields: translation along $\mathbf e_k$, and
//! rotation about $\mathbf e_k$ through the origin ($\mathbf v = \mathbf e_k\times\mathbf r$,
//! $\boldsymbol\omega = \mathbf e_k$). `MomentumMap` holds the body mass matrices at one
//! configuration, so $\mathbf J$ at many velocities costs one evaluation of the bodies.
//!
//! # Why generalized-α needs a projection
//!
//! The updates of $\dot{\mathbf q}$ and $\mathbf q$ are linear in the algorithmic accelerations, so a
//! momentum that is a constant linear form $\mathbf c^T\dot{\mathbf q}$ of the velocities (the linear
//! momentum of point masses) is conserved to round-off. The momenta of a flexible or rigid body
//! in absolute interface coordinates are nonlinear in $(\mathbf q, \dot{\mathbf q})$: the centre of
//! mass follows the frame (4.4) and the CB shapes, and $\mathbf H$ involves the rotations. The
//! scheme makes their rates vanish at each $t_{n+1}$ but conserves $\mathbf L$ and $\mathbf H$ to its
//! order only (2: a drift of $2\cdot10^{-5}$ over 0.3 s at $h = 0.5$ ms on validation problem C4).
//!
//! # Projection
//!
//! The standard projection method (Hairer, Lubich & Wanner, *Geometric Numerical Integration*,
//! 2nd ed., Springer 2006, §IV.4, Algorithm 4.2) applied to the momentum map: after each
//! converged step, the velocities are moved to the level set $\mathbf J(\mathbf q_{n+1}, \dot{\mathbf q}) =
//! \mathbf J_0$ along the $\hat{\mathbf M}$-orthogonal direction, the closest point in the kinetic-energy
//! metric:
//!
//! $$\dot{\mathbf q} \leftarrow \dot{\mathbf q} + \mathbf T_{rig}\boldsymbol\lambda,\quad
//! (\mathbf T_{rig}^T\hat{\mathbf M}\mathbf T_{rig})\boldsymbol\lambda = \mathbf J_0 - \mathbf J(\mathbf q_{n+1}, \dot{\mathbf q}).$$
//!
//! (Minimising $\tfrac12\Delta\dot{\mathbf q}^T\hat{\mathbf M}\Delta\dot{\mathbf q}$ subject to
//! $\mathbf T_{rig}^T\hat{\mathbf M}\Delta\dot{\mathbf q} = \Delta\mathbf J$ gives $\Delta\dot{\mathbf q} =
//! \mathbf T_{rig}\boldsymbol\lambda$.) Since $\mathbf J$ is linear in $\dot{\mathbf q}$, one solve puts it
//! on the level set exactly, and the $6\times6$ locked inertia $\mathbf T_{rig}^T\hat{\mathbf M}\mathbf T_{rig}$
//! is $\mathbf J(\mathbf q, \mathbf T_{rig}\mathbf e_k)$ column by column: no assembled mass matrix. The
//! positions are not touched: $\mathbf J$ does not constrain them. The defect $\mathbf J_0 - \mathbf J$ is
//! the local momentum error of one step, $O(h^3)$, so the projection keeps the order of the
//! integrator (Hairer, Lubich & Wanner, Theorem IV.4.1). The correction is a rigid velocity
//! field, so it leaves the elastic rates and the strain energy alone; it changes the kinetic
//! energy by $O(h^3)$ per step, and the energy still drifts at order 2.
//!
//! # When it applies
//!
//! [`System::rigid_invariance`] decides from the model whether the Lagrangian and the forces are
//! invariant under rigid translations and rotations, so that $\mathbf L$ and $\mathbf H$ are conserved
//! by the exact motion: no coordinate is removed (a support that removes a translation or a
//! rotation, a ground, a slider, a hinge) and no coordinate is driven; no loads; zero gravity;
//! no spring attached to a fixed point. Joints between nodes, joint springs, springs and dampers
//! between two nodes, and the bodies' internal damping act within the model and keep both
//! momenta. With any of those conditions broken, [`MomentumProjection::Auto`] does not project,
//! even where some component is still conserved (the angular momentum about the vertical under
//! gravity): it projects all six or none.

#![allow(non_snake_case)]

use crate::assembly::coordinates::unknown;
use crate::assembly::coordinates::Slot;
use crate::assembly::system::{System, Workspace};
use crate::assembly::topology::RootRotation;
use crate::error::SolveError;
use crate::model::{RotationSupport, TranslationSupport};
use crate::state::State;
use faer::Mat;
use nalgebra::{Matrix6, Vector3, Vector6};

/// Whether the dynamic solver projects the velocities onto the initial momenta after each step
/// (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MomentumProjection {
    /// Project when [`System::rigid_invariance`] holds (the model is free and unloaded);
    /// otherwise integrate as with `Off`.
    #[default]
    Auto,
    /// Never project: plain generalized-α.
    Off,
}

/// What makes a model's momenta change, the first found by [`System::rigid_invariance`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExternalAction {
    /// A support removes a translation or a rotation of the node (clamp, pin, slider, hinge, ...).
    #[error("the support of node '{node}' removes some of its coordinates")]
    Support { node: String },
    /// A driver prescribes a coordinate.
    #[error("driver '{driver}' prescribes a coordinate")]
    Driver { driver: String },
    /// A load acts on a node.
    #[error("a load acts on node '{node}'")]
    Load { node: String },
    /// Gravity is not zero.
    #[error("gravity is {gravity:?}")]
    Gravity { gravity: [f64; 3] },
    /// A spring or damper is attached to a fixed point.
    #[error("spring '{spring}' is attached to a fixed point")]
    GroundSpring { spring: String },
    /// A user-defined force acts (it may depend on the absolute position or orientation).
    #[error("user force '{name}' acts on the model")]
    UserForce { name: String },
}

/// The body mass matrices at one configuration: $\mathbf J(\mathbf q, \cdot)$ as a linear map of the
/// velocities (module docs).
pub(crate) struct MomentumMap {
    /// $\mathbf M$ of each flexible element on its ports ($6N + m$ square).
    flexible: Vec<Mat<f64>>,
}

impl System {
    /// `Ok` when the model's forces are invariant under rigid motions, so its linear and angular
    /// momenta are conserved (module docs, "When it applies"); otherwise the first external
    /// action found.
    pub fn rigid_invariance(&self) -> Result<(), ExternalAction> {
        let model = &self.model;
        let name = |n: crate::ids::NodeId| model.nodes[n.index()].name.clone();
        for s in &model.supports {
            let translation_free = match &s.translation {
                TranslationSupport::Free => true,
                TranslationSupport::Components { fixed } => fixed.iter().all(|f| !f),
                _ => false,
            };
            if !translation_free || s.rotation != RotationSupport::Free {
                return Err(ExternalAction::Support { node: name(s.node) });
            }
        }
        if let Some(d) = model.drivers.first() {
            return Err(ExternalAction::Driver { driver: d.name.clone() });
        }
        if let Some(l) = model.loads.first() {
            return Err(ExternalAction::Load { node: name(l.node) });
        }
        if model.gravity != Vector3::zeros() {
            return Err(ExternalAction::Gravity {
                gravity: model.gravity.into(),
            });
        }
        if let Some(s) = model.springs.iter().find(|s| s.b.is_none()) {
            return Err(ExternalAction::GroundSpring { spring: s.name.clone() });
        }
        if let Some(u) = self.user_forces.first() {
            return Err(ExternalAction::UserForce {
                name: u.name().to_string(),
            });
        }
        // Every coordinate that a support or driver removes is prescribed; none is left.
        debug_assert!(self.topo.map.prescribed.is_empty());
        Ok(())
    }

    /// $\mathbf T_{rig}$ ($n_{dof}\times6$): the independent velocities of the rigid velocity fields,
    /// translation along $\mathbf e_k$ (column $k$) and rotation about $\mathbf e_k$ through the origin
    /// (column $3 + k$), at the configuration of `state` (module docs).
    ///
    /// Which coordinate carries what, from the maps of [`crate::assembly::coordinates`]: an independent
    /// node's translations are inertial ($\mathbf r = \mathbf r_0 + \sum_i s_i\mathbf e_i$ along its
    /// support basis), so $\dot s_i = \mathbf e_i\cdot(\mathbf v + \boldsymbol\omega\times\mathbf r)$; every
    /// SO(3) coordinate (an independent node's orientation, a spherical joint's child) is absolute
    /// with spatial angular velocity, so it gets $\boldsymbol\omega$; joint coordinates are relative
    /// and modal coordinates elastic, so both get 0. Dependent nodes (joint children, rigid
    /// bodies' further nodes) then move rigidly with their parents: checked for every node kind
    /// by `tests/unit/momentum.rs::rigid_velocities_move_every_node_rigidly`. Only free directions
    /// are set: on a supported model the columns are not rigid fields.
    pub fn rigid_velocities(&self, state: &State) -> Mat<f64> {
        let map = &self.topo.map;
        let nodes = self.node_motions(state);
        let mut T = Mat::zeros(map.n_dof, 6);
        for (root, node) in self.topo.roots.iter().zip(&nodes) {
            let Some(rc) = root else { continue };
            for (s, e) in &rc.translation {
                if let Slot::Unknown(d) = map.scalars[*s].slot {
                    for k in 0..3 {
                        let ek = Vector3::ith(k, 1.0);
                        T[(d, k)] = e.dot(&ek);
                        T[(d, 3 + k)] = e.dot(&ek.cross(&node.r));
                    }
                }
            }
            if let RootRotation::Axes(axes) = &rc.rotation {
                for (s, e) in axes {
                    if let Slot::Unknown(d) = map.scalars[*s].slot {
                        for k in 0..3 {
                            T[(d, 3 + k)] = e[k];
                        }
                    }
                }
            }
        }
        for r in &map.rotations {
            for k in 0..3 {
                T[(r.dof + k, 3 + k)] = 1.0;
            }
        }
        T
    }

    /// The body mass matrices at the configuration of `state` (the one evaluation of the bodies
    /// behind [`Self::momentum_at`]).
    pub(crate) fn momentum_map(&self, state: &State) -> Result<MomentumMap, SolveError> {
        let nodes = self.node_motions(state);
        let mut flexible = Vec::with_capacity(self.flexible.len());
        for (i, f) in self.flexible.iter().enumerate() {
            let bs = self.body_state(i, state, &nodes);
            let n = f.se.n_coordinates();
            let ev =
                f.se.forces(&bs, &vec![0.0; n], &Vector3::zeros())
                    .map_err(|source| self.body_error(f.body, state.time, source))?;
            flexible.push(ev.mass);
        }
        Ok(MomentumMap { flexible })
    }

    /// $[\mathbf L;\ \mathbf H] = \mathbf J(\mathbf q, \dot{\mathbf q})$ with the configuration of `state`, the
    /// velocities `velocity` ($n_{dof}$) and the mass matrices `map` at that configuration.
    pub(crate) fn momentum_at(&self, map: &MomentumMap, state: &State, velocity: &[f64]) -> Vector6<f64> {
        let mut s = state.clone();
        s.velocity.copy_from_slice(velocity);
        let nodes = self.node_motions(&s);
        let cmap = &self.topo.map;
        let (mut L, mut H) = (Vector3::zeros(), Vector3::zeros());
        for (f, M) in self.flexible.iter().zip(&map.flexible) {
            let N = f.nodes.len();
            let mut qd = Vec::with_capacity(6 * N + f.modal.len());
            for &node in &f.nodes {
                qd.extend_from_slice(nodes[node].v.as_slice());
                qd.extend_from_slice(nodes[node].omega.as_slice());
            }
            qd.extend(f.modal.iter().map(|&m| velocity[unknown(cmap.scalars[m].slot)]));
            for (k, &node) in f.nodes.iter().enumerate() {
                // Force and moment slots of port k of p = M qd.
                let p = |i: usize| (0..qd.len()).map(|c| M[(6 * k + i, c)] * qd[c]).sum::<f64>();
                let pf = Vector3::new(p(0), p(1), p(2));
                let pm = Vector3::new(p(3), p(4), p(5));
                L += pf;
                H += nodes[node].r.cross(&pf) + pm;
            }
        }
        for r in &self.rigid {
            let m = &nodes[r.node];
            let R = m.R.to_rotation_matrix();
            let b = R * r.c;
            let IG = R.matrix() * r.J * R.matrix().transpose();
            let p = (m.v + m.omega.cross(&b)) * r.mass;
            L += p;
            H += (m.r + b).cross(&p) + IG * m.omega;
        }
        for pm in &self.model.point_masses {
            let m = &nodes[pm.node.index()];
            let p = m.v * pm.mass;
            L += p;
            H += m.r.cross(&p);
        }
        Vector6::new(L.x, L.y, L.z, H.x, H.y, H.z)
    }

    /// Moves the velocities of `state` onto the level set $\mathbf J = \mathbf J_0$ by the
    /// $\hat{\mathbf M}$-orthogonal projection of the module docs; returns the defect
    /// $\mathbf J_0 - \mathbf J$ before the correction.
    ///
    /// $\mathbf T_{rig}^T\hat{\mathbf M}\mathbf T_{rig}$ is symmetric positive semi-definite; it is solved by
    /// its eigen-decomposition after scaling the angular rows and columns by the radius of gyration, and
    /// eigenvalues below $10^{-12}$ of the largest are dropped (a locked inertia that vanishes
    /// about some axis, as for masses on a line, has no momentum to correct there).
    pub(crate) fn project_momentum(&self, state: &mut State, J0: &Vector6<f64>) -> Result<Vector6<f64>, SolveError> {
        let map = self.momentum_map(state)?;
        let T = self.rigid_velocities(state);
        let n = self.n_dof();
        let mut A = Matrix6::zeros();
        let mut col = vec![0.0; n];
        for k in 0..6 {
            col.copy_from_slice(T.col_as_slice(k));
            A.set_column(k, &self.momentum_at(&map, state, &col));
        }
        let defect = J0 - self.momentum_at(&map, state, &state.velocity);
        // Scale: D = diag(1, 1, 1, 1/l, 1/l, 1/l) with l the radius of gyration about the origin
        // makes the blocks of D A D of one unit (mass) and like size.
        let (tL, tH) = (A[(0, 0)] + A[(1, 1)] + A[(2, 2)], A[(3, 3)] + A[(4, 4)] + A[(5, 5)]);
        let l = if tL > 0.0 && tH > 0.0 { (tH / tL).sqrt() } else { 1.0 };
        let d = Vector6::new(1.0, 1.0, 1.0, 1.0 / l, 1.0 / l, 1.0 / l);
        let As = Matrix6::from_fn(|i, j| 0.5 * (A[(i, j)] + A[(j, i)]) * d[i] * d[j]);
        let eig = As.symmetric_eigen();
        let top = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
        let b = defect.component_mul(&d);
        let mut y = Vector6::zeros();
        for (i, &mu) in eig.eigenvalues.iter().enumerate() {
            if mu > 1e-12 * top {
                let u = eig.eigenvectors.column(i);
                y += u * (u.dot(&b) / mu);
            }
        }
        let lambda = y.component_mul(&d);
        for (i, v) in state.velocity.iter_mut().enumerate() {
            *v += (0..6).map(|k| T[(i, k)] * lambda[k]).sum::<f64>();
        }
        Ok(defect)
    }

    /// Refills the node motions of `ws` from `state` (after the velocities changed outside an
    /// evaluation), so that recorded sensors see the corrected velocities.
    pub(crate) fn refresh_motions(&self, state: &mut State, ws: &mut Workspace) {
        self.update_motions(state, ws);
    }
}
