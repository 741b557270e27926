//! [`System::initial_state`]: the state at the model's initial conditions, with the subtrees
//! behind the joints moved as the plans of [`crate::assembly::initial`] say.

use super::System;
use crate::assembly::coordinates::unknown;
use crate::assembly::initial::InitialPlan;
use crate::ids::NodeId;
use crate::model::{Body, InitialCondition};
use crate::state::State;

impl System {
    /// Places the nodes behind each driver that is not zero at $t = 0$ ([`DriverStart`](crate::assembly::initial::DriverStart)): the
    /// pivot's motion from the coordinate at zero to its value in `state` (drivers applied),
    /// carried rigidly to the free nodes behind it, positions and velocities.
    fn assemble_at_drivers(&self, state: &mut State) {
        let np = self.topo.map.n_prescribed();
        for ds in &self.driver_starts {
            let motions = |s: &State, zero: bool| {
                let mut s = s.clone();
                let (mut pr, mut pa) = (vec![0.0; np], vec![0.0; np]);
                self.apply_drivers(&mut s, &mut pr, &mut pa);
                if zero {
                    s.scalars[ds.scalar] = 0.0;
                    pr[ds.prescribed] = 0.0;
                }
                let mut m = vec![crate::assembly::coordinates::Motion::ground(); self.model.nodes.len()];
                self.topo
                    .map
                    .motions_into(&crate::assembly::coordinates::values(&s, &pr, &pa), &mut m);
                m.iter().map(crate::node::NodeMotion::from).collect::<Vec<_>>()
            };
            let (before, after) = (motions(state, true), motions(state, false));
            let (a, b) = (&before[ds.pivot], &after[ds.pivot]);
            let R = b.R * a.R.inverse();
            for &n in &ds.roots {
                let m = &before[n];
                let r = b.r + R * (m.r - a.r);
                // Velocities relative to the pivot are carried along with it.
                let w = b.omega + R * (m.omega - a.omega);
                let v = b.v + b.omega.cross(&(r - b.r)) + R * (m.v - a.v - a.omega.cross(&(m.r - a.r)));
                self.set_node_pose(state, NodeId(n as u32), r, R * m.R);
                self.set_root_velocity(state, n, &v, &w);
            }
        }
    }

    /// Applies the model's initial conditions to `state` (module docs).
    pub(crate) fn apply_initial(&self, state: &mut State) {
        self.assemble_at_drivers(state);
        let map = &self.topo.map;
        let items = || self.model.initial.iter().zip(&self.initial_plan);
        for (c, plan) in items() {
            let InitialCondition::JointValue {
                joint,
                coordinate,
                value,
            } = c
            else {
                continue;
            };
            let child = self.model.joints[joint.index()].child.index();
            let before = self.node_motions(state);
            state.scalars[self.topo.joint_scalars[joint.index()][*coordinate]] = *value;
            if let InitialPlan::Subtree(roots) = plan {
                let after = self.node_motions(state);
                let (a, b) = (&before[child], &after[child]);
                let R = b.R * a.R.inverse();
                for &n in roots {
                    let m = &before[n];
                    self.set_node_pose(state, NodeId(n as u32), b.r + R * (m.r - a.r), R * m.R);
                }
            }
        }
        let motions = self.node_motions(state);
        for (c, plan) in items() {
            if let (
                InitialCondition::BodyVelocity {
                    velocity,
                    angular_velocity: w,
                    point,
                    ..
                },
                InitialPlan::Component(roots),
            ) = (c, plan)
            {
                for &n in roots {
                    self.set_root_velocity(state, n, &(velocity + w.cross(&(motions[n].r - point))), w);
                }
            }
        }
        for (c, plan) in items() {
            let InitialCondition::JointRate {
                joint,
                coordinate,
                rate,
            } = c
            else {
                continue;
            };
            let child = self.model.joints[joint.index()].child.index();
            let before = self.node_motions(state);
            let s = self.topo.joint_scalars[joint.index()][*coordinate];
            state.velocity[unknown(map.scalars[s].slot)] = *rate;
            if let InitialPlan::Subtree(roots) = plan {
                let after = self.node_motions(state);
                let (a, b) = (&before[child], &after[child]);
                let (dv, dw) = (b.v - a.v, b.omega - a.omega);
                for &n in roots {
                    let m = &before[n];
                    let v = m.v + dv + dw.cross(&(m.r - a.r));
                    self.set_root_velocity(state, n, &v, &(m.omega + dw));
                }
            }
        }
        let motions = self.node_motions(state);
        for c in &self.model.initial {
            match c {
                InitialCondition::NodeVelocity {
                    node,
                    velocity,
                    angular_velocity,
                } => {
                    self.set_root_velocity(state, node.index(), velocity, angular_velocity);
                }
                InitialCondition::RigidMotion {
                    velocity,
                    angular_velocity,
                } => {
                    for n in 0..self.model.nodes.len() {
                        if self.topo.roots[n].is_some() {
                            let v = velocity + angular_velocity.cross(&motions[n].r);
                            self.set_root_velocity(state, n, &v, angular_velocity);
                        }
                    }
                }
                _ => {}
            }
        }
    }

    /// A state at rest in the configuration of `state` (elastic coordinates and floating frames
    /// included) at time `time`: velocities and accelerations zero, controllers' integrals
    /// restarted. The hand-over from an equilibrium to a dynamic or linearised analysis.
    pub fn at_rest(&self, state: &State, time: f64) -> State {
        let mut s = state.clone();
        s.time = time;
        s.velocity.iter_mut().for_each(|v| *v = 0.0);
        s.acceleration.iter_mut().for_each(|a| *a = 0.0);
        self.start_controls(&mut s);
        s
    }

    /// The rigid velocity $(\mathbf v_p, \boldsymbol\omega)$ of a body about the point $\mathbf p$:
    /// the least-squares fit of $\mathbf v_k = \mathbf v_p + \boldsymbol\omega\times(\mathbf r_k - \mathbf p)$
    /// to the velocities of its nodes, with $\boldsymbol\omega$ their mean angular velocity (exact for a
    /// rigid body and for a flexible body without strain rate).
    pub fn body_velocity(
        &self,
        state: &State,
        body: crate::ids::BodyId,
        point: &nalgebra::Vector3<f64>,
    ) -> (nalgebra::Vector3<f64>, nalgebra::Vector3<f64>) {
        let motions = self.node_motions(state);
        let nodes: Vec<usize> = match &self.model.bodies[body.index()] {
            Body::Flexible(f) => f.nodes.iter().map(|n| n.index()).collect(),
            Body::Rigid(r) => vec![r.reference.index()],
        };
        let k = nodes.len() as f64;
        let w = nodes.iter().map(|&n| motions[n].omega).sum::<nalgebra::Vector3<f64>>() / k;
        let v = nodes
            .iter()
            .map(|&n| motions[n].v - w.cross(&(motions[n].r - point)))
            .sum::<nalgebra::Vector3<f64>>()
            / k;
        (v, w)
    }
}
