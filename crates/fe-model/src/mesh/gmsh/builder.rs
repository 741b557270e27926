//! Builds a [`Mesh`] from the records both MSH versions deliver: nodes with their gmsh tags,
//! elements with their gmsh type and node tags, and the group (MSH 2) or entity (MSH 4) each
//! element belongs to. Physical groups become named sets in [`Builder::finish`].

use super::cursor::Locator;
use super::{GmshElement, Location, MshError};
use crate::mesh::{Cell, CellId, Mesh, NodeId};
use nalgebra::Point3;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// `(dimension, tag)` of a gmsh entity or physical group.
pub(super) type DimTag = (i32, i32);

/// Cells and nodes of the elements of one entity (MSH 4) or physical group (MSH 2).
#[derive(Default)]
struct Members {
    cells: Vec<CellId>,
    nodes: Vec<NodeId>,
}

/// What an element tag already stands for, to recognise MSH 2's repeated elements.
enum Seen {
    Cell(CellId),
    /// A point element (gmsh type 15): no cell, but its node joins the groups.
    Point(NodeId),
}

pub(super) struct Builder<'a> {
    path: &'a Path,
    locator: Locator<'a>,
    mesh: Mesh,
    node_ids: HashMap<u64, NodeId>,
    elements: HashMap<u64, Seen>,
    members: BTreeMap<DimTag, Members>,
    /// Resolved nodes of the element being added (reused to avoid an allocation per element).
    scratch: Vec<NodeId>,
}

impl<'a> Builder<'a> {
    pub(super) fn new(path: &'a Path, locator: Locator<'a>) -> Self {
        Builder {
            path,
            locator,
            mesh: Mesh::default(),
            node_ids: HashMap::new(),
            elements: HashMap::new(),
            members: BTreeMap::new(),
            scratch: Vec::new(),
        }
    }

    fn at(&self, pos: usize) -> Location {
        self.locator.at(pos)
    }

    /// Reserves room for `additional` nodes (already capped by the caller to what the input
    /// can hold).
    pub(super) fn reserve_nodes(&mut self, additional: usize) {
        self.mesh.nodes.reserve(additional);
        self.mesh.node_tags.reserve(additional);
        self.node_ids.reserve(additional);
    }

    /// Adds the node with gmsh tag `tag`; its [`NodeId`] is its position of appearance.
    /// `pos` is where its tag was read, for the error.
    pub(super) fn add_node(&mut self, tag: u64, x: Point3<f64>, pos: usize) -> Result<(), MshError> {
        let id = match u32::try_from(self.mesh.nodes.len()) {
            Ok(index) => NodeId(index),
            Err(_) => {
                return Err(MshError::UnsupportedFeature {
                    path: self.path.to_path_buf(),
                    at: self.at(pos),
                    what: "a mesh with more than 2^32 nodes".to_string(),
                })
            }
        };
        if self.node_ids.insert(tag, id).is_some() {
            return Err(MshError::DuplicateNode {
                path: self.path.to_path_buf(),
                at: self.at(pos),
                node: tag,
            });
        }
        self.mesh.nodes.push(x);
        self.mesh.node_tags.push(tag);
        Ok(())
    }

    /// Adds the element with gmsh tag `tag` and node tags `node_tags` (gmsh order), and
    /// records it as a member of `member_of` (its entity in MSH 4, its physical group in MSH
    /// 2). An element tag seen before with the same type and nodes is the same element: MSH 2
    /// repeats an element once per physical group it belongs to. `pos` is where its tag was
    /// read.
    pub(super) fn add_element(
        &mut self,
        tag: u64,
        element: GmshElement,
        node_tags: &[u64],
        pos: usize,
        member_of: Option<DimTag>,
    ) -> Result<(), MshError> {
        self.scratch.clear();
        for &node in node_tags {
            match self.node_ids.get(&node) {
                Some(&id) => self.scratch.push(id),
                None => {
                    return Err(MshError::MissingNode {
                        path: self.path.to_path_buf(),
                        at: self.at(pos),
                        element: tag,
                        node,
                    })
                }
            }
        }
        let cell = match self.elements.get(&tag) {
            Some(seen) => {
                let same = match (seen, element) {
                    (Seen::Cell(id), GmshElement::Cell(kind)) => {
                        let cell = &self.mesh.cells[id.index()];
                        cell.kind == kind && cell.nodes == super::from_gmsh_order(kind, &self.scratch)
                    }
                    (Seen::Point(node), GmshElement::Point) => self.scratch == [*node],
                    _ => false,
                };
                if !same {
                    return Err(MshError::DuplicateElement {
                        path: self.path.to_path_buf(),
                        at: self.at(pos),
                        element: tag,
                    });
                }
                match seen {
                    Seen::Cell(id) => Some(*id),
                    Seen::Point(_) => None,
                }
            }
            None => match element {
                GmshElement::Point => {
                    // A point element's single node was resolved above.
                    if let Some(&node) = self.scratch.first() {
                        self.elements.insert(tag, Seen::Point(node));
                    }
                    None
                }
                GmshElement::Cell(kind) => {
                    let id =
                        CellId(
                            u32::try_from(self.mesh.cells.len()).map_err(|_| MshError::UnsupportedFeature {
                                path: self.path.to_path_buf(),
                                at: self.at(pos),
                                what: "a mesh with more than 2^32 cells".to_string(),
                            })?,
                        );
                    let nodes = super::from_gmsh_order(kind, &self.scratch);
                    self.mesh.cells.push(Cell { kind, nodes, tag });
                    self.elements.insert(tag, Seen::Cell(id));
                    Some(id)
                }
            },
        };
        if let Some(key) = member_of {
            let members = self.members.entry(key).or_default();
            members.cells.extend(cell);
            members.nodes.extend_from_slice(&self.scratch);
        }
        Ok(())
    }

    /// The mesh with one node set and (for dimension >= 1) one cell set per physical group.
    ///
    /// `entity_groups` maps MSH 4 entities to their physical tags; `None` means the members
    /// were recorded per physical group already (MSH 2). Every group in `names` gets its sets
    /// even without elements, so a named but empty group reads the same from both versions;
    /// an unnamed group is called `physical_<dim>_<tag>`. Groups of different dimensions with
    /// the same name share their sets.
    pub(super) fn finish(
        self,
        names: &BTreeMap<DimTag, String>,
        entity_groups: Option<&HashMap<DimTag, Vec<i32>>>,
    ) -> Mesh {
        let mut mesh = self.mesh;
        let mut groups: BTreeMap<DimTag, Members> = match entity_groups {
            None => self.members,
            Some(entity_groups) => {
                let mut groups = BTreeMap::<DimTag, Members>::new();
                for ((dim, entity), members) in &self.members {
                    for &physical in entity_groups.get(&(*dim, *entity)).into_iter().flatten() {
                        let group = groups.entry((*dim, physical)).or_default();
                        group.cells.extend_from_slice(&members.cells);
                        group.nodes.extend_from_slice(&members.nodes);
                    }
                }
                groups
            }
        };
        for key in names.keys() {
            groups.entry(*key).or_default();
        }
        for ((dim, tag), members) in groups {
            let name = names
                .get(&(dim, tag))
                .cloned()
                .unwrap_or_else(|| format!("physical_{dim}_{tag}"));
            mesh.add_to_node_set(&name, members.nodes);
            if dim >= 1 {
                let set = mesh.cell_sets.entry(name).or_default();
                set.extend(members.cells);
                set.sort_unstable();
                set.dedup();
            }
        }
        mesh
    }
}
