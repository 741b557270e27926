//! The model being built, shared by the concerns that add to it in turn.

use super::mechanism::{BodyOut, FlexibleSources, NamedLoad};
use crate::input::source::KeyPath;
use crate::input::validate::Study;
use crate::sensor_group::SensorGroup;
use mbs::{Model, NodeId};
use std::collections::BTreeMap;

/// Key of a point before merging: flexible (body, interface index) or rigid (body, point).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Key {
    Flexible(usize, usize),
    Rigid(usize, usize),
}

/// The model being built, with what the later concerns look up in what the earlier ones
/// added.
pub(super) struct Builder<'s> {
    pub(super) study: &'s Study,
    pub(super) model: Model,
    pub(super) entities: BTreeMap<mbs::Entity, KeyPath>,
    pub(super) reduced: FlexibleSources,
    /// Every point of every body ([`Key`]), and its node once merged.
    pub(super) keys: Vec<Key>,
    pub(super) node_of: Vec<NodeId>,
    pub(super) bodies: Vec<BodyOut>,
    pub(super) rigid: Vec<Vec<NodeId>>,
    /// Per joint of the study: its joint in the model (none for a fixed joint), and its
    /// clamped ground node (a joint to the ground).
    pub(super) joint_ids: Vec<Option<mbs::JointId>>,
    pub(super) ground_nodes: Vec<Option<NodeId>>,
    /// The fixed joints between bodies: the study's joint name and the node its points merge into.
    pub(super) welds: Vec<(String, NodeId)>,
    pub(super) loads: Vec<NamedLoad>,
    pub(super) groups: Vec<SensorGroup>,
}
