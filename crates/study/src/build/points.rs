//! Points and nodes: every point of every body, merged by the fixed joints into the model's
//! nodes (`mbs::weld_points`), the points fixed to the ground clamped.

use super::builder::{Builder, Key};
use super::mechanism::{located, FlexibleSources};
use crate::error::BoxError;
use crate::input::source::KeyPath;
use crate::input::validate::mechanism::PointRef;
use crate::input::validate::Study;
use mbs::{Model, NodeId, Support};
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;

/// The points fixed to the ground by fixed joints, the pairs of points welded into one node,
/// and the joint of each weld (indices in the study's joints).
type FixedJoints = (Vec<usize>, Vec<(usize, usize)>, Vec<usize>);

impl<'s> Builder<'s> {
    /// A model of `study`'s mechanism holding its nodes: every point of the bodies of
    /// `reduced` and of the rigid bodies, merged by the fixed joints.
    pub(super) fn new(study: &'s Study, reduced: FlexibleSources) -> Result<Self, BoxError> {
        let m = &study.mechanism;
        // Every point, its position and its name.
        let mut keys: Vec<Key> = Vec::new();
        let mut positions: Vec<Vector3<f64>> = Vec::new();
        for (b, (body, _)) in reduced.iter().enumerate() {
            let place = m.bodies[b].placement;
            for (k, i) in body.interfaces.iter().enumerate() {
                keys.push(Key::Flexible(b, k));
                positions.push((place * Point3::from(Vector3::from(i.position))).coords);
            }
        }
        for (b, r) in m.rigid_bodies.iter().enumerate() {
            for (k, (_, x)) in r.points.iter().enumerate() {
                keys.push(Key::Rigid(b, k));
                positions.push(*x);
            }
        }
        let mut builder = Builder {
            study,
            model: Model::new(study.title.as_deref().unwrap_or("mechanism")),
            entities: BTreeMap::new(),
            reduced,
            keys,
            node_of: Vec::new(),
            bodies: Vec::new(),
            rigid: Vec::new(),
            joint_ids: Vec::new(),
            ground_nodes: Vec::new(),
            welds: Vec::new(),
            loads: Vec::new(),
            groups: Vec::new(),
        };
        builder.merge_points(&positions)?;
        Ok(builder)
    }

    /// Fixed joints merge points into one node (`mbs::weld_points`); a fixed joint to the
    /// ground clamps its node.
    fn merge_points(&mut self, positions: &[Vector3<f64>]) -> Result<(), BoxError> {
        let study = self.study;
        let m = &study.mechanism;
        let (grounded, welds, weld_joint) = self.fixed_joints()?;
        let point_label = |k: &Key| match k {
            Key::Flexible(b, i) => format!("{}.{}", m.bodies[*b].name, self.reduced[*b].0.interfaces[*i].name),
            Key::Rigid(b, i) => format!("{}.{}", m.rigid_bodies[*b].name, m.rigid_bodies[*b].points[*i].0),
        };
        let points: Vec<mbs::merge::Point> = self
            .keys
            .iter()
            .zip(positions)
            .map(|(k, x)| mbs::merge::Point {
                name: point_label(k),
                position: *x,
            })
            .collect();
        self.node_of = mbs::weld_points(&mut self.model, &points, &welds).map_err(|e| {
            let j = &m.joints[weld_joint[e.weld]];
            located(
                study,
                &j.path,
                format!(
                    "fixed joint '{}': '{}' and '{}' are {:.3e} m apart; the points of a fixed joint must coincide",
                    j.name,
                    m.point_name(&j.parent),
                    m.point_name(&j.child),
                    e.distance
                ),
            )
        })?;
        self.welds = welds
            .iter()
            .zip(&weld_joint)
            .map(|((a, _), ji)| (m.joints[*ji].name.clone(), self.node_of[*a]))
            .collect();
        for g in grounded {
            self.model.add_support(Support::clamp(self.node_of[g]));
        }
        Ok(())
    }

    /// The points the fixed joints fix to the ground and the pairs they weld.
    fn fixed_joints(&self) -> Result<FixedJoints, BoxError> {
        let mut grounded: Vec<usize> = Vec::new();
        let mut welds: Vec<(usize, usize)> = Vec::new();
        let mut weld_joint: Vec<usize> = Vec::new();
        let joints = &self.study.mechanism.joints;
        for (ji, j) in joints.iter().enumerate().filter(|(_, j)| j.kind.is_none()) {
            match (&j.parent, &j.child) {
                (PointRef::Ground, PointRef::Ground) => {}
                (PointRef::Ground, p) | (p, PointRef::Ground) => grounded.push(self.resolve(p, &j.path)?),
                (a, b) => {
                    welds.push((self.resolve(a, &j.path)?, self.resolve(b, &j.path)?));
                    weld_joint.push(ji);
                }
            }
        }
        Ok((grounded, welds, weld_joint))
    }

    /// The index of point `p` among the points (`None` for the ground or a point the reduced
    /// body lacks).
    fn key_index(&self, p: &PointRef) -> Option<usize> {
        let key = match p {
            PointRef::Ground => return None,
            PointRef::Flexible { body, interface } => {
                let k = self.reduced[*body]
                    .0
                    .interfaces
                    .iter()
                    .position(|i| i.name == *interface)?;
                Key::Flexible(*body, k)
            }
            PointRef::Rigid { body, point } => Key::Rigid(*body, *point),
        };
        self.keys.iter().position(|k| *k == key)
    }

    /// [`Self::key_index`], a missing point located at `path`.
    fn resolve(&self, p: &PointRef, path: &KeyPath) -> Result<usize, BoxError> {
        self.key_index(p).ok_or_else(|| {
            located(
                self.study,
                path,
                format!(
                    "point '{}' is not in the reduced body",
                    self.study.mechanism.point_name(p)
                ),
            )
        })
    }

    /// The node of point `p` (described at `path`).
    pub(super) fn node(&self, p: &PointRef, path: &KeyPath) -> Result<NodeId, BoxError> {
        Ok(self.node_of[self.resolve(p, path)?])
    }

    /// The node of the point `key`. Every point of every body has a key; a missing one is a
    /// bug, reported, never a silent attachment to another node.
    pub(super) fn node_of_key(&self, key: Key) -> Result<NodeId, BoxError> {
        self.keys
            .iter()
            .position(|x| *x == key)
            .map(|i| self.node_of[i])
            .ok_or_else(|| format!("internal error: point {key:?} of the mechanism has no node").into())
    }
}
