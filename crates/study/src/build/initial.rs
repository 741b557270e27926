//! Initial states: joint coordinates and rates, point and body velocities at t = 0.

use super::builder::Builder;
use super::mechanism::located;
use crate::error::BoxError;
use crate::input::validate::mechanism::{BodyRef, InitialSpec};
use mbs::InitialCondition;
use nalgebra::{Point3, Vector3};

impl Builder<'_> {
    /// The initial conditions of the study's `[[initial]]` entries.
    pub(super) fn initial_states(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        for c in &m.initial {
            let first = self.model.initial.len();
            let (InitialSpec::Joint { path, .. } | InitialSpec::Point { path, .. } | InitialSpec::Body { path, .. }) =
                c;
            match c {
                InitialSpec::Joint {
                    path,
                    joint,
                    coordinate,
                    value,
                    rate,
                } => {
                    let Some(j) = self.joint_ids[*joint] else {
                        return Err(located(self.study, path, "a fixed joint has no coordinate"));
                    };
                    if let Some(v) = value {
                        self.model.initial.push(InitialCondition::JointValue {
                            joint: j,
                            coordinate: *coordinate,
                            value: *v,
                        });
                    }
                    if let Some(r) = rate {
                        self.model.initial.push(InitialCondition::JointRate {
                            joint: j,
                            coordinate: *coordinate,
                            rate: *r,
                        });
                    }
                }
                InitialSpec::Point {
                    path,
                    at,
                    velocity,
                    angular_velocity,
                } => {
                    let n = self.node(at, path)?;
                    self.model.initial.push(InitialCondition::NodeVelocity {
                        node: n,
                        velocity: *velocity,
                        angular_velocity: *angular_velocity,
                    })
                }
                InitialSpec::Body {
                    body,
                    velocity,
                    angular_velocity,
                    point,
                    ..
                } => {
                    // Flexible bodies come first in the model, then the rigid ones.
                    let (id, centre) = match body {
                        BodyRef::Flexible(k) => {
                            let c = Point3::from(Vector3::from(self.bodies[*k].reduced.inertia.center_of_mass));
                            (*k, (self.bodies[*k].placement * c).coords)
                        }
                        BodyRef::Rigid(k) => (self.bodies.len() + k, m.rigid_bodies[*k].center_of_mass),
                    };
                    self.model.initial.push(InitialCondition::BodyVelocity {
                        body: mbs::BodyId(id as u32),
                        velocity: *velocity,
                        angular_velocity: *angular_velocity,
                        point: point.unwrap_or(centre),
                    });
                }
            }
            for i in first..self.model.initial.len() {
                self.entities.insert(mbs::Entity::InitialCondition(i), path.clone());
            }
        }
        Ok(())
    }
}
