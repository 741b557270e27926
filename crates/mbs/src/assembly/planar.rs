//! Planar flexible bodies ([`crate::FlexibleBody::planar`]): the checks that make their
//! evaluation in the global xy-plane exact.
//!
//! A planar body is evaluated by `superelement::Superelement::into_planar`: only the in-plane
//! coordinates of its interfaces ($x$, $y$, the rotation about $z$) and its modes get
//! stiffness and mass from it. Its nodes must therefore stay in the global xy-plane, turning
//! about $z$ only, for all time, whatever the loads: otherwise an out-of-plane coordinate that
//! only the body holds would leave the system matrices singular. A node is confined to the
//! plane when its rigid group (the nodes welded to it by rigid bodies, [`crate::assembly::topology`])
//! is either
//!
//! * independent and supported in $z$ and in the rotations about $x$ and $y$: translation
//!   `Fixed`, `Components` with $z$ fixed, `Line` along an in-plane direction or `Plane` with
//!   normal $z$; rotation `Fixed` or `Axis` $z$ (node drivers act along these supports), or
//! * the child of a joint that keeps it in the plane (revolute about $z$, prismatic along an
//!   in-plane axis, planar with normal $z$) whose parent node is confined.
//!
//! The body's placement must also map its FE model's xy-plane onto the global one: a
//! rotation about $z$.

use crate::error::ModelError;
use crate::model::{Body, BodyId, FlexibleBody, JointKind, Model, NodeId, RotationSupport, TranslationSupport};
use nalgebra::Vector3;

/// Whether `v` is along $\pm z$ (to $10^{-9}$ of its length).
fn along_z(v: &Vector3<f64>) -> bool {
    v.xy().norm() <= 1e-9 * v.norm()
}

/// `(x, y, z)` for messages.
fn vector(v: &Vector3<f64>) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

/// Whether `v` lies in the xy-plane (to $10^{-9}$ of its length).
fn in_plane(v: &Vector3<f64>) -> bool {
    v.z.abs() <= 1e-9 * v.norm()
}

/// Checks that the planar flexible body `body` (index `bi`) is placed in the global xy-plane
/// and that each of its nodes is confined to it (module docs).
///
/// # Errors
/// [`ModelError::InvalidValue`] for a placement that tilts the FE xy-plane;
/// [`ModelError::LeavesPlane`] naming the body, its node and what lets that node leave the plane.
pub(crate) fn check_planar_body(model: &Model, bi: usize, body: &FlexibleBody) -> Result<(), ModelError> {
    let e_z = body.placement.rotation * Vector3::z();
    if !((e_z - Vector3::z()).norm() <= 1e-9) {
        return Err(ModelError::InvalidValue {
            entity: format!("body '{}'", body.name),
            what: format!(
                "it is planar, but its placement turns the FE model's z axis onto {}: the placement of a planar body must be a rotation about z (its FE xy-plane onto the global one)",
                vector(&e_z)
            ),
            id: Some(crate::error::Entity::Body(BodyId(bi as u32))),
        });
    }
    let confinement = Confinement::new(model);
    for &node in &body.nodes {
        if let Err(what) = confinement.confined(node, 0) {
            return Err(ModelError::LeavesPlane {
                body: body.name.clone(),
                node: model.nodes[node.index()].name.clone(),
                what,
                body_id: BodyId(bi as u32),
                node_id: node,
            });
        }
    }
    Ok(())
}

/// The rigid groups, their parent joints and the supports of a model.
struct Confinement<'a> {
    model: &'a Model,
    /// Group (a representative node) of each node.
    group: Vec<usize>,
}

impl<'a> Confinement<'a> {
    fn new(model: &'a Model) -> Self {
        let n = model.nodes.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut a: usize) -> usize {
            while p[a] != a {
                p[a] = p[p[a]];
                a = p[a];
            }
            a
        }
        for body in &model.bodies {
            if let Body::Rigid(r) = body {
                for node in &r.nodes {
                    let (a, b) = (find(&mut parent, r.reference.index()), find(&mut parent, node.index()));
                    parent[a] = b;
                }
            }
        }
        let group = (0..n).map(|k| find(&mut parent, k)).collect();
        Self { model, group }
    }

    fn name(&self, node: usize) -> &str {
        &self.model.nodes[node].name
    }

    /// `Ok` when `node` stays in the xy-plane turning about z, else what lets it leave.
    /// `depth` guards against a cycle (the topology has refused them before).
    fn confined(&self, node: NodeId, depth: usize) -> Result<(), String> {
        let m = self.model;
        let g = self.group[node.index()];
        let members: Vec<usize> = (0..m.nodes.len()).filter(|&k| self.group[k] == g).collect();
        // "it" when `k` is the node asked about, else the node of its rigid group.
        let subject = |k: usize| {
            if k == node.index() {
                "it".to_string()
            } else {
                format!("it is welded by a rigid body to node '{}', which", self.name(k))
            }
        };
        if let Some(joint) = m.joints.iter().find(|j| members.contains(&j.child.index())) {
            let keeps = match &joint.kind {
                JointKind::Revolute { axis } => along_z(axis),
                JointKind::Prismatic { axis } => in_plane(axis),
                JointKind::Planar { normal } => along_z(normal),
                _ => false,
            };
            if !keeps {
                return Err(format!(
                    "{} follows the {} joint '{}' from node '{}', which does not keep it in the plane (a revolute joint about z, a prismatic joint along an in-plane axis or a planar joint with normal z does)",
                    subject(joint.child.index()),
                    joint.kind.name(),
                    joint.name,
                    self.name(joint.parent.index()),
                ));
            }
            if depth > m.nodes.len() {
                return Err("its chain of joints has no end".into());
            }
            return self.confined(joint.parent, depth + 1).map_err(|why| {
                format!(
                    "{} follows joint '{}' from node '{}', which can leave the plane: {why}",
                    subject(joint.child.index()),
                    joint.name,
                    self.name(joint.parent.index()),
                )
            });
        }
        let Some(support) = m.supports.iter().find(|s| members.contains(&s.node.index())) else {
            return Err(format!(
                "it is neither supported nor the child of a joint{}: its translation along z and its rotations about x and y are free, and a planar body gives them no stiffness (support it in the plane: translation in a plane with normal z, rotation about z)",
                if members.len() > 1 { " (nor is any node welded to it by a rigid body)" } else { "" }
            ));
        };
        let at = self.name(support.node.index());
        let translation = match &support.translation {
            TranslationSupport::Fixed => Ok(()),
            TranslationSupport::Components { fixed } if fixed[2] => Ok(()),
            TranslationSupport::Line { direction } if in_plane(direction) => Ok(()),
            TranslationSupport::Plane { normal } if along_z(normal) => Ok(()),
            other => Err(format!(
                "the support of node '{at}' leaves its translation along z free ({})",
                match other {
                    TranslationSupport::Line { direction } => format!("a line along {}", vector(direction)),
                    TranslationSupport::Plane { normal } => format!("a plane with normal {}", vector(normal)),
                    TranslationSupport::Components { .. } => "z not among the fixed components".into(),
                    _ => "translation free".into(),
                }
            )),
        };
        let rotation = match &support.rotation {
            RotationSupport::Fixed => Ok(()),
            RotationSupport::Axis { axis } if along_z(axis) => Ok(()),
            other => Err(format!(
                "the support of node '{at}' leaves its rotations about x and y free ({})",
                match other {
                    RotationSupport::Axis { axis } => format!("rotation about {}", vector(axis)),
                    _ => "rotation free".into(),
                }
            )),
        };
        translation.and(rotation)
    }
}
