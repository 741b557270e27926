//! The built mechanism: the `mbs::Model` with what the analyses and outputs need beside it,
//! and the reduced bodies the build is handed.

use crate::error::{BoxError, SolverStopped};
use crate::input::source::KeyPath;
use crate::input::validate::Study;
use crate::mesh::VtuMesh;
use crate::sensor_group::SensorGroup;
use mbs::{Model, NodeId, System};
use nalgebra::Isometry3;
use reduction::ReducedBody;
use serde_json::json;
use std::collections::BTreeMap;
use std::sync::Arc;
use superelement::FrameChoice;

/// The mechanism as an `mbs::Model`, with what the outputs need.
pub struct BuiltMechanism {
    pub model: Model,
    pub groups: Vec<SensorGroup>,
    /// Per flexible body: the reduced body and its FE mesh for drawing (bodies from parts).
    pub bodies: Vec<BodyOut>,
    /// Per rigid body: its reference node and point nodes.
    pub rigid: Vec<Vec<NodeId>>,
    /// The fixed joints between bodies, which the model has no joint for: the study's joint
    /// name and the node their points merged into.
    pub welds: Vec<(String, NodeId)>,
    /// Where each entity of the model is described in the study (the first description of a
    /// node: the body it belongs to), for locating `mbs::ModelError`s by their entity ids.
    pub entities: BTreeMap<mbs::Entity, KeyPath>,
    /// Reductions: (part, coordinates, modes, from cache).
    pub reductions: Vec<serde_json::Value>,
    /// The point loads of the study by name, with their `mbs` loads.
    pub loads: Vec<NamedLoad>,
}

/// A `[[loads]]` point load of the study and where the model holds its values.
#[derive(Clone, Debug)]
pub struct NamedLoad {
    pub name: String,
    pub path: KeyPath,
    pub target: LoadTarget,
}

/// Where the model holds the values of a [`NamedLoad`].
#[derive(Clone, Debug)]
pub enum LoadTarget {
    /// A load at a node: the indices in `Model::loads` of the force and the moment the study
    /// file gives.
    Node(Vec<(mbs::LoadKind, usize)>),
    /// A load at a load point inside a flexible body: its index in `Model::body_loads` (force
    /// and moment both, zero where the file gives none).
    Body(usize),
}

pub struct BodyOut {
    pub name: String,
    /// Shared with the model's body and the system's superelement.
    pub reduced: Arc<ReducedBody>,
    pub mesh: Option<VtuMesh>,
    pub placement: Isometry3<f64>,
    pub frame: FrameChoice,
    pub nodes: Vec<NodeId>,
    /// The body in the multibody model.
    pub id: mbs::BodyId,
    /// The label of each mesh node in its source (the deck's or gmsh's node number; 1-based
    /// positions for generated meshes), when the body is made of a part of the study; nodes
    /// past its end (interface spiders) have none.
    pub node_labels: Option<Vec<u64>>,
}

impl BodyOut {
    /// Mesh node `k` (0-based index, as in the VTU files) as users read it: `node 205 (index
    /// 4)` with its label from the mesh file, `node index 4` without one.
    pub fn node_name(&self, k: usize) -> String {
        match self.node_label(k) {
            Some(label) => format!("node {label} (index {k})"),
            None => format!("node index {k}"),
        }
    }

    /// The label of mesh node `k` in its source file, if known.
    pub fn node_label(&self, k: usize) -> Option<u64> {
        self.node_labels.as_ref().and_then(|l| l.get(k).copied())
    }
}

/// An error about the entity at `path` of the study, located in the file.
pub(super) fn located(study: &Study, path: &KeyPath, message: impl std::fmt::Display) -> BoxError {
    format!("{}: {path}: {message}", study.location(path)).into()
}

/// Each flexible body's reduced body (shared by the bodies made of one part), with its FE
/// mesh for drawing when the body comes from a part of the study.
pub type FlexibleSources = Vec<(Arc<ReducedBody>, Option<VtuMesh>)>;

/// What the reduction service hands the build: the reduced body of each flexible body, and a
/// summary entry per reduction.
pub type ReducedBodies = (FlexibleSources, Vec<serde_json::Value>);

impl BuiltMechanism {
    /// `System::new`, with a model error located at the first of its entities
    /// (`mbs::ModelError::entities`) that the study describes.
    pub fn system(&self, study: &Study) -> Result<System, BoxError> {
        self.system_with(study, System::new)
    }

    /// The system `build` makes of the model (`System::new` with something added, a force
    /// law), with a model error located as by [`Self::system`].
    pub fn system_with(
        &self,
        study: &Study,
        build: impl FnOnce(&Model) -> Result<System, mbs::ModelError>,
    ) -> Result<System, BoxError> {
        build(&self.model).map_err(|e| {
            let message = format!("the mechanism cannot be assembled: {}", crate::error::sentence(&e));
            match self.locate(&e.entities()) {
                Some(path) => located(study, path, message),
                None => format!("{}: {message}", study.source.path.display()).into(),
            }
        })
    }

    /// Where the first of `entities` that the study describes is.
    pub fn locate(&self, entities: &[mbs::Entity]) -> Option<&KeyPath> {
        entities.iter().find_map(|e| self.entities.get(e))
    }

    /// A solver failure of an analysis, located at the study's description of the entity it
    /// failed at (`mbs::SolveError::entity`: the body whose floating frame failed), when the
    /// study describes it.
    pub fn stopped(
        &self,
        study: &Study,
        message: String,
        step: Option<usize>,
        source: mbs::SolveError,
    ) -> SolverStopped {
        let location = source
            .entity()
            .and_then(|e| self.locate(&[e]))
            .map(|path| study.at(path));
        SolverStopped {
            message,
            step,
            location,
            source,
        }
    }

    /// Model size for the summary.
    pub fn size(&self, sys: &System) -> serde_json::Value {
        json!({
            "nodes": self.model.nodes.len(),
            "flexible_bodies": self.bodies.len(),
            "rigid_bodies": self.rigid.len(),
            "joints": self.model.joints.len(),
            "drivers": self.model.drivers.len(),
            "unknowns": sys.n_dof(),
            "system_nonzeros": sys.nnz(),
            "modes_kept": self.bodies.iter().map(|b| json!({"body": b.name, "modes": b.reduced.n_modes, "coordinates": b.reduced.n_coordinates()})).collect::<Vec<_>>(),
            "reductions": self.reductions,
        })
    }
}

/// "5 joints (3 fixed)": every joint of the study, the fixed ones (which weld two points
/// into one node and so are no joint of the solver) counted and named as such.
pub fn joint_count(study: &Study) -> String {
    let joints = &study.mechanism.joints;
    let fixed = joints.iter().filter(|j| j.kind.is_none()).count();
    let plural = if joints.len() == 1 { "" } else { "s" };
    if fixed > 0 {
        format!("{} joint{plural} ({fixed} fixed)", joints.len())
    } else {
        format!("{} joint{plural}", joints.len())
    }
}
