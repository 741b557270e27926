//! Geometry and topology: nodes, cells and named sets, as read from gmsh or generated.
//!
//! A [`Mesh`] knows nothing about materials or dofs; [`crate::FeModel`] adds those. Node and
//! element indices are newtypes so a node index cannot be passed where an element is expected.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Index of a node in [`Mesh::nodes`] (0-based, dense). Gmsh's own (possibly sparse) tags are
/// kept in [`Mesh::node_tags`] for error messages and output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct NodeId(pub u32);

impl NodeId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Index of a cell in [`Mesh::cells`] (0-based, dense).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct CellId(pub u32);

impl CellId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Topology of a mesh cell. Node orderings are gmsh's (drawn on each element kind in
/// `crate::element`), so the gmsh reader's permutations are the identity; a VTK writer must
/// reorder (tet10 swaps nodes 8 and 9; hex20 differs more).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CellKind {
    Line2,
    Tri3,
    Quad4,
    Tri6,
    Quad8,
    Tet4,
    Tet10,
    Hex8,
    Hex20,
    Wedge6,
}

impl CellKind {
    /// Number of nodes of the cell.
    pub fn node_count(self) -> usize {
        match self {
            CellKind::Line2 => 2,
            CellKind::Tri3 => 3,
            CellKind::Quad4 => 4,
            CellKind::Tri6 => 6,
            CellKind::Quad8 => 8,
            CellKind::Tet4 => 4,
            CellKind::Tet10 => 10,
            CellKind::Hex8 => 8,
            CellKind::Hex20 => 20,
            CellKind::Wedge6 => 6,
        }
    }

    /// Topological dimension (1 for lines, 2 for faces, 3 for volumes).
    pub fn dimension(self) -> usize {
        match self {
            CellKind::Line2 => 1,
            CellKind::Tri3 | CellKind::Quad4 | CellKind::Tri6 | CellKind::Quad8 => 2,
            CellKind::Tet4 | CellKind::Tet10 | CellKind::Hex8 | CellKind::Hex20 | CellKind::Wedge6 => 3,
        }
    }
}

/// One cell: its kind, its nodes in our ordering, and the tag it had in its source file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    pub kind: CellKind,
    pub nodes: Vec<NodeId>,
    /// Tag in the source (gmsh element tag), or the 1-based position for generated meshes.
    pub tag: u64,
}

/// Nodes, cells and named sets. Plain data, serialisable.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    /// Reference coordinates of the nodes.
    pub nodes: Vec<Point3<f64>>,
    /// Source tag of each node (gmsh node tag; 1-based position for generated meshes).
    pub node_tags: Vec<u64>,
    pub cells: Vec<Cell>,
    /// Named node sets (gmsh physical groups of any dimension, or generator sets such as
    /// `"x0"`, `"tip"`), sorted and unique.
    pub node_sets: BTreeMap<String, Vec<NodeId>>,
    /// Named cell sets (gmsh physical groups), sorted and unique.
    pub cell_sets: BTreeMap<String, Vec<CellId>>,
}

impl Mesh {
    /// Appends a node and returns its id; its tag is its 1-based position.
    pub fn add_node(&mut self, x: Point3<f64>) -> NodeId {
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(x);
        self.node_tags.push(self.nodes.len() as u64);
        id
    }

    /// Appends a node the source file does not have (a spider's interface node) and returns its
    /// id; its tag is one above the largest tag so far, so that messages naming nodes by tag
    /// never give it the number of one of the file's nodes. For meshes numbered 1, 2, ..., n
    /// (generated meshes) that is its 1-based position, as [`Mesh::add_node`] gives.
    pub fn add_node_after_tags(&mut self, x: Point3<f64>) -> NodeId {
        let tag = self
            .node_tags
            .iter()
            .copied()
            .max()
            .unwrap_or(0)
            .max(self.nodes.len() as u64)
            + 1;
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(x);
        self.node_tags.push(tag);
        id
    }

    /// Appends a cell and returns its id; its tag is its 1-based position.
    pub fn add_cell(&mut self, kind: CellKind, nodes: Vec<NodeId>) -> CellId {
        let id = CellId(self.cells.len() as u32);
        let tag = self.cells.len() as u64 + 1;
        self.cells.push(Cell { kind, nodes, tag });
        id
    }

    /// Adds nodes to a named set, keeping it sorted and unique.
    pub fn add_to_node_set(&mut self, name: &str, nodes: impl IntoIterator<Item = NodeId>) {
        let set = self.node_sets.entry(name.to_string()).or_default();
        set.extend(nodes);
        set.sort_unstable();
        set.dedup();
    }

    /// The nodes of a named set, or `None` if there is no such set.
    pub fn node_set(&self, name: &str) -> Option<&[NodeId]> {
        self.node_sets.get(name).map(|v| v.as_slice())
    }

    /// The node nearest to `x` (ties: lowest id), or `None` for an empty mesh.
    pub fn nearest_node(&self, x: &Point3<f64>) -> Option<NodeId> {
        self.nodes
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (p - x).norm_squared()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| NodeId(i as u32))
    }
}
pub mod abaqus;
pub mod gmsh;
pub mod import;
pub mod nastran;
pub mod quality;
