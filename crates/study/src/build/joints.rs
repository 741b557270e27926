//! Joints and what acts on their coordinates: drivers, joint springs, joint limits and
//! actuators.

use super::builder::Builder;
use super::mechanism::located;
use crate::error::BoxError;
use crate::input::source::KeyPath;
use crate::input::validate::mechanism::{EffortSpec, PointRef};
use mbs::{DriverTarget, NodeId, Support};
use std::collections::BTreeMap;

impl Builder<'_> {
    /// Joints (fixed ones are merged nodes, [`Builder::new`]); a joint to the ground gets a
    /// clamped node.
    pub(super) fn joints(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        let mut joint_ids: Vec<Option<mbs::JointId>> = Vec::new();
        let mut ground_nodes: Vec<Option<NodeId>> = Vec::new();
        for j in &m.joints {
            let Some(kind) = &j.kind else {
                joint_ids.push(None);
                ground_nodes.push(None);
                continue;
            };
            let child = self.node(&j.child, &j.path)?;
            let (parent_node, ground) = match &j.parent {
                PointRef::Ground => {
                    let model = &mut self.model;
                    let g = model.add_node(&format!("ground.{}", j.name), model.nodes[child.index()].position);
                    self.entities.insert(mbs::Entity::Node(g), j.path.clone());
                    self.entities
                        .insert(mbs::Entity::Support(model.supports.len()), j.path.clone());
                    model.add_support(Support::clamp(g));
                    (g, Some(g))
                }
                p => (self.node(p, &j.path)?, None),
            };
            let id = self.model.add_joint(&j.name, parent_node, child, kind.clone());
            self.entities.insert(mbs::Entity::Joint(id), j.path.clone());
            joint_ids.push(Some(id));
            ground_nodes.push(ground);
        }
        self.joint_ids = joint_ids;
        self.ground_nodes = ground_nodes;
        Ok(())
    }

    /// The drivers of joint coordinates.
    pub(super) fn drivers(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        for d in &m.drivers {
            let Some(joint) = self.joint_ids[d.joint] else {
                return Err(located(self.study, &d.path, "a fixed joint cannot be driven"));
            };
            self.entities
                .insert(mbs::Entity::Driver(self.model.drivers.len()), d.path.clone());
            self.model.add_driver(
                &d.name,
                DriverTarget::Joint {
                    joint,
                    coordinate: d.coordinate,
                },
                d.motion.clone(),
            );
        }
        Ok(())
    }

    /// The joint of study joint `j`, described at `path`; a fixed joint has none.
    pub(super) fn joint_of(&self, j: usize, path: &KeyPath) -> Result<mbs::JointId, BoxError> {
        self.joint_ids[j].ok_or_else(|| located(self.study, path, "a fixed joint has no coordinate"))
    }

    /// The forces on joint coordinates: joint springs, joint limits and actuators.
    pub(super) fn joint_forces(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        for s in &m.joint_springs {
            let spring = mbs::JointSpring {
                joint: self.joint_of(s.joint, &s.path)?,
                coordinate: s.coordinate,
                stiffness: s.stiffness,
                damping: s.damping,
                rest: s.rest,
                preload: s.preload,
            };
            let springs = &mut self.model.joint_springs;
            push_located(&mut self.entities, springs, mbs::Entity::JointSpring, &s.path, spring);
        }
        for l in &m.joint_limits {
            let limit = mbs::JointLimit {
                name: l.name.clone(),
                joint: self.joint_of(l.joint, &l.path)?,
                coordinate: l.coordinate,
                lower: l.lower,
                upper: l.upper,
                stiffness: l.stiffness,
                damping: l.damping,
            };
            let limits = &mut self.model.joint_limits;
            push_located(&mut self.entities, limits, mbs::Entity::JointLimit, &l.path, limit);
        }
        for a in &m.actuators {
            let effort = match &a.effort {
                EffortSpec::Time(f) => mbs::Effort::Time(f.clone()),
                EffortSpec::Pid {
                    joint,
                    coordinate,
                    setpoint,
                    kp,
                    ki,
                    kd,
                    max_effort,
                } => mbs::Effort::Pid(mbs::Pid {
                    joint: self.joint_of(*joint, &a.path)?,
                    coordinate: *coordinate,
                    setpoint: setpoint.clone(),
                    kp: *kp,
                    ki: *ki,
                    kd: *kd,
                    max_effort: *max_effort,
                }),
            };
            let actuator = mbs::JointActuator {
                name: a.name.clone(),
                joint: self.joint_of(a.joint, &a.path)?,
                coordinate: a.coordinate,
                effort,
            };
            let actuators = &mut self.model.actuators;
            push_located(&mut self.entities, actuators, mbs::Entity::Actuator, &a.path, actuator);
        }
        Ok(())
    }
}

/// Pushes `element` onto `list` (one of the model's lists), recording `path` as where the
/// entity `entity(index)` it becomes is described, so that errors about it are located.
pub(super) fn push_located<T>(
    entities: &mut BTreeMap<mbs::Entity, KeyPath>,
    list: &mut Vec<T>,
    entity: fn(usize) -> mbs::Entity,
    path: &KeyPath,
    element: T,
) {
    entities.insert(entity(list.len()), path.clone());
    list.push(element);
}
