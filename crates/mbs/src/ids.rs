//! The ids by which the entities of a [`crate::Model`] refer to each other: indices into the
//! model's lists, checked by [`crate::System::new`].

use serde::{Deserialize, Serialize};

/// Index of a node in [`crate::Model::nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct NodeId(pub u32);

/// Index of a body in [`crate::Model::bodies`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct BodyId(pub u32);

/// Index of a joint in [`crate::Model::joints`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct JointId(pub u32);

impl NodeId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}
impl BodyId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}
impl JointId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}
