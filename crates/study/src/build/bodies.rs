//! Bodies: the flexible bodies on the nodes of their interfaces, the rigid bodies on the nodes
//! of their points, and the point masses, springs and supports at nodes.

use super::builder::{Builder, Key};
use super::joints::push_located;
use super::mechanism::{located, BodyOut};
use crate::error::BoxError;
use crate::input::validate::mechanism::FrameSpec;
use mbs::{Body, FlexibleBody, NodeId, PointMass, RigidBody, Spring, Support};
use std::sync::Arc;
use superelement::FrameChoice;

impl Builder<'_> {
    /// The flexible bodies, in study order: the first bodies of the model.
    pub(super) fn flexible_bodies(&mut self) -> Result<(), BoxError> {
        let study = self.study;
        let m = &study.mechanism;
        for b in 0..self.reduced.len() {
            // One reduced body per part, shared by the bodies made of it, the model and the
            // system.
            let (body, mesh) = (Arc::clone(&self.reduced[b].0), self.reduced[b].1.clone());
            let spec = &m.bodies[b];
            let nodes: Vec<NodeId> = (0..body.interfaces.len())
                .map(|k| self.node_of_key(Key::Flexible(b, k)))
                .collect::<Result<_, _>>()?;
            let frame = match &spec.frame {
                FrameSpec::CenterOfMass => FrameChoice::CenterOfMass,
                FrameSpec::AuxiliaryNode => FrameChoice::AuxiliaryNode,
                FrameSpec::InterfaceNode(name) => match body.interfaces.iter().position(|i| i.name == *name) {
                    Some(k) => FrameChoice::InterfaceNode(k),
                    None => {
                        return Err(located(
                            study,
                            &spec.path.key("frame_interface"),
                            format!("the reduced body has no interface '{name}'"),
                        ))
                    }
                },
            };
            let mut damping = spec.damping.clone();
            if let Some(z) = spec.modal_ratio {
                damping.modal_ratios = vec![z; body.n_modes];
            }
            self.model.add_body(Body::Flexible(Box::new(FlexibleBody {
                name: spec.name.clone(),
                reduced: Arc::clone(&body),
                nodes: nodes.clone(),
                placement: spec.placement,
                frame,
                mass: spec.inertia,
                damping,
                planar: spec.planar,
            })));
            let id = mbs::BodyId(self.model.bodies.len() as u32 - 1);
            self.entities.insert(mbs::Entity::Body(id), spec.path.clone());
            for &n in &nodes {
                self.entities
                    .entry(mbs::Entity::Node(n))
                    .or_insert_with(|| spec.path.clone());
            }
            let node_labels = match spec.source {
                crate::input::validate::mechanism::BodySource::Part(p) => {
                    Some(study.parts[p].base.mesh.node_tags.clone())
                }
                _ => None,
            };
            self.bodies.push(BodyOut {
                name: spec.name.clone(),
                reduced: body,
                mesh,
                placement: spec.placement,
                frame,
                nodes,
                id,
                node_labels,
            });
        }
        Ok(())
    }

    /// Rigid bodies: the mass data about the first point (nodes have the identity
    /// orientation, so the body's axes are the global axes at t = 0), or about a node at the
    /// centre of mass for a body without points.
    pub(super) fn rigid_bodies(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        for (b, r) in m.rigid_bodies.iter().enumerate() {
            let nodes: Vec<NodeId> = (0..r.points.len())
                .map(|k| self.node_of_key(Key::Rigid(b, k)))
                .collect::<Result<_, _>>()?;
            let model = &mut self.model;
            let (reference, others) = match nodes.split_first() {
                Some((first, rest)) => (*first, rest.to_vec()),
                None => (
                    model.add_node(&format!("{}.(center of mass)", r.name), r.center_of_mass),
                    Vec::new(),
                ),
            };
            let c = r.center_of_mass - model.nodes[reference.index()].position;
            let id = model.add_rigid_body(RigidBody {
                name: r.name.clone(),
                reference,
                nodes: others.clone(),
                mass: r.mass,
                center_of_mass: c,
                inertia: r.inertia,
            });
            self.entities.insert(mbs::Entity::Body(id), r.path.clone());
            let mut all = vec![reference];
            all.extend(others);
            for &n in &all {
                self.entities
                    .entry(mbs::Entity::Node(n))
                    .or_insert_with(|| r.path.clone());
            }
            self.rigid.push(all);
        }
        Ok(())
    }

    /// The point masses, springs and supports, each at the nodes of its points.
    pub(super) fn point_elements(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        for p in &m.point_masses {
            let point_mass = PointMass {
                name: p.name.clone(),
                node: self.node(&p.at, &p.path)?,
                mass: p.mass,
            };
            push_located(
                &mut self.entities,
                &mut self.model.point_masses,
                mbs::Entity::PointMass,
                &p.path,
                point_mass,
            );
        }
        for s in &m.springs {
            let spring = Spring {
                name: s.name.clone(),
                a: self.node(&s.a, &s.path)?,
                b: match &s.b {
                    Some(b) => Some(self.node(b, &s.path)?),
                    None => None,
                },
                ground_point: s.ground_point,
                stiffness: s.stiffness,
                damping: s.damping,
                rest_length: s.rest_length,
            };
            push_located(
                &mut self.entities,
                &mut self.model.springs,
                mbs::Entity::Spring,
                &s.path,
                spring,
            );
        }
        for s in &m.supports {
            let n = self.node(&s.at, &s.path)?;
            let entity = mbs::Entity::Support(self.model.supports.len());
            self.entities.insert(entity, s.path.clone());
            self.model.add_support(Support {
                node: n,
                translation: s.translation.clone(),
                rotation: s.rotation.clone(),
            });
        }
        Ok(())
    }
}
