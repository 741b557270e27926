//! What the readers of other FE codes' input files ([`super::abaqus`], [`super::nastran`])
//! deliver: a [`Mesh`] with its node and cell sets, plus the materials, sections, spiders and
//! supports the file defines, and the cards or keywords it skipped ([`ImportedModel`]); and
//! the one error type both readers report with ([`ImportError`]: file, line, entity).
//!
//! [`ImportedModel::to_fe_model`] turns the result into an [`FeModel`] with the file's
//! materials, or with materials given per cell set instead.

use crate::element::{Beam2, BeamTheory, Element, MassKind, Solid, SolidKind};
use crate::error::{FeError, PropertyError};
use crate::interface::SpiderKind;
use crate::mesh::{CellKind, Mesh, NodeId};
use crate::model::{DofMask, FeModel};
use crate::property::{IsotropicMaterial, MaterialId};
use crate::section::BeamSection;
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A solid section: the 3D cells of `cell_set` are made of `material`.
#[derive(Clone, Debug, PartialEq)]
pub struct SolidSection {
    pub cell_set: String,
    /// Name of one of [`ImportedModel::materials`].
    pub material: String,
}

/// A beam section: the line cells of `cell_set` are beams of `section` made of `material`,
/// with `orientation` in their local $x$-$y$ plane.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamSectionAssignment {
    pub cell_set: String,
    pub material: String,
    pub section: BeamSection,
    pub orientation: Vector3<f64>,
}

/// A spider the file defines (Nastran RBE2 or RBE3): an interface node at `position` tied to
/// `surface`. `reference` is the file's own grid of the interface node (RBE2's independent
/// grid, RBE3's reference grid): a mesh node that no element uses, kept so that supports on it
/// can be moved to the interface node.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedSpider {
    /// `RBE2_<eid>` or `RBE3_<eid>`; also the name of the node set of `surface`.
    pub name: String,
    pub kind: SpiderKind,
    pub reference: NodeId,
    pub position: Point3<f64>,
    pub surface: Vec<NodeId>,
}

/// A support the file defines (Nastran SPC1): `dofs` of every node of `nodes` held.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedSupport {
    /// `SPC1_<sid>`; also the name of the node set of all nodes of that SID.
    pub name: String,
    pub nodes: Vec<NodeId>,
    pub dofs: DofMask,
}

/// A card or keyword the reader skipped: listed once, with how often it occurred and where
/// first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ignored {
    pub name: String,
    pub count: usize,
    pub first_file: PathBuf,
    pub first_line: usize,
}

/// What an input file of another FE code defines, in flexmbs' terms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportedModel {
    /// Nodes, cells (our node orderings) and the named node and cell sets.
    pub mesh: Mesh,
    /// The materials, by their names in the file (Nastran: `MAT1_<mid>`).
    pub materials: Vec<IsotropicMaterial>,
    pub solid_sections: Vec<SolidSection>,
    pub beam_sections: Vec<BeamSectionAssignment>,
    pub spiders: Vec<ImportedSpider>,
    pub supports: Vec<ImportedSupport>,
    /// Cards or keywords that were skipped, each listed once, in order of first occurrence.
    pub ignored: Vec<Ignored>,
    /// What was read but approximated or looks wrong, one sentence each (RBE3 weights, a
    /// material whose constants no solid has in SI).
    pub notes: Vec<String>,
}

impl ImportedModel {
    /// The material called `name`.
    pub fn material(&self, name: &str) -> Option<&IsotropicMaterial> {
        self.materials.iter().find(|m| m.name() == name)
    }

    /// One line naming every skipped card and how often, or `None` if nothing was skipped.
    pub fn ignored_summary(&self) -> Option<String> {
        (!self.ignored.is_empty()).then(|| {
            self.ignored
                .iter()
                .map(|i| {
                    format!(
                        "{} ({}x, first at {}:{})",
                        i.name,
                        i.count,
                        i.first_file.display(),
                        i.first_line
                    )
                })
                .collect::<Vec<_>>()
                .join(", ")
        })
    }

    /// An [`FeModel`] of the file's elements: solids with the materials of their solid
    /// sections and beams (Timoshenko) with their beam sections. `materials`, if given,
    /// replaces the file's assignment of materials: pairs of cell-set name and material, every
    /// 3D and beam cell in exactly one of the sets. No supports or spiders are added (they
    /// depend on which interfaces a study wants).
    ///
    /// # Errors
    /// [`FeError::CellMaterial`] for a 3D or beam cell without a section (or in two);
    /// [`FeError::UnknownCellSet`] for a set in `materials` that the mesh does not have.
    pub fn to_fe_model(
        &self,
        mass: MassKind,
        materials: Option<&[(&str, IsotropicMaterial)]>,
    ) -> Result<FeModel, FeError> {
        const CONTEXT: &str = "imported model";
        let mut model = FeModel {
            mesh: self.mesh.clone(),
            ..FeModel::default()
        };
        // Material of each cell (by index into `model.materials`), and the beam section.
        let mut cell_material: Vec<Option<(MaterialId, String)>> = vec![None; self.mesh.cells.len()];
        let mut cell_beam: Vec<Option<usize>> = vec![None; self.mesh.cells.len()];
        let set_cells = |name: &str| {
            self.mesh.cell_sets.get(name).ok_or_else(|| FeError::UnknownCellSet {
                context: CONTEXT.to_string(),
                name: name.to_string(),
                known: self.mesh.cell_sets.keys().cloned().collect::<Vec<_>>().join(", "),
            })
        };
        let assign = |cell_material: &mut Vec<Option<(MaterialId, String)>>,
                      set: &str,
                      material: MaterialId|
         -> Result<(), FeError> {
            for &c in set_cells(set)? {
                let cell = &self.mesh.cells[c.index()];
                if cell.kind.dimension() == 2 {
                    continue;
                }
                if let Some((_, first)) = &cell_material[c.index()] {
                    if first != set {
                        return Err(FeError::CellMaterial {
                            context: CONTEXT.to_string(),
                            cell_tag: cell.tag,
                            kind: kind_name(cell.kind),
                            why: format!("is in both sets '{first}' and '{set}', which are given materials"),
                        });
                    }
                }
                cell_material[c.index()] = Some((material, set.to_string()));
            }
            Ok(())
        };
        match materials {
            Some(given) => {
                for (set, material) in given {
                    let id = model.add_material(material.clone());
                    assign(&mut cell_material, set, id)?;
                }
            }
            None => {
                let mut ids: BTreeMap<&str, MaterialId> = BTreeMap::new();
                for m in &self.materials {
                    ids.insert(m.name(), model.add_material(m.clone()));
                }
                for s in &self.solid_sections {
                    // The readers check that every section's material exists.
                    if let Some(&id) = ids.get(s.material.as_str()) {
                        assign(&mut cell_material, &s.cell_set, id)?;
                    }
                }
                for s in &self.beam_sections {
                    if let Some(&id) = ids.get(s.material.as_str()) {
                        assign(&mut cell_material, &s.cell_set, id)?;
                    }
                }
            }
        }
        for (k, s) in self.beam_sections.iter().enumerate() {
            for &c in set_cells(&s.cell_set)? {
                if self.mesh.cells[c.index()].kind == CellKind::Line2 {
                    cell_beam[c.index()] = Some(k);
                }
            }
        }
        let section_ids: Vec<_> = self
            .beam_sections
            .iter()
            .map(|s| model.add_section(s.section.clone()))
            .collect();
        for (c, cell) in self.mesh.cells.iter().enumerate() {
            let solid = SolidKind::from_cell_kind(cell.kind);
            let beam = cell.kind == CellKind::Line2;
            if solid.is_none() && !beam {
                continue;
            }
            let missing = |why: String| FeError::CellMaterial {
                context: CONTEXT.to_string(),
                cell_tag: cell.tag,
                kind: kind_name(cell.kind),
                why,
            };
            let Some((material, _)) = cell_material[c].clone() else {
                return Err(missing(if beam {
                    "has no beam section (line cells are beams and need one)".into()
                } else {
                    "has no solid section or material".into()
                }));
            };
            if let Some(kind) = solid {
                model.elements.push(Element::new_solid(
                    kind,
                    Solid {
                        nodes: cell.nodes.clone(),
                        material,
                        mass,
                    },
                ));
            } else {
                let Some(k) = cell_beam[c] else {
                    return Err(missing("has a material but no beam section".into()));
                };
                model.elements.push(Element::Beam2(Beam2 {
                    nodes: [cell.nodes[0], cell.nodes[1]],
                    section: section_ids[k],
                    material,
                    orientation: self.beam_sections[k].orientation,
                    theory: BeamTheory::Timoshenko,
                    mass,
                }));
            }
        }
        Ok(model)
    }
}

fn kind_name(kind: CellKind) -> &'static str {
    match SolidKind::from_cell_kind(kind) {
        Some(k) => k.name(),
        None if kind == CellKind::Line2 => "beam",
        None => "cell",
    }
}

/// An input file of another FE code that cannot be read. Every variant names the file and
/// the 1-based line (the line where the card or keyword starts), and the entity: the card or
/// keyword and, where there is one, the node, element, material or set.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A field that should be a number, a name or a keyword parameter is not one.
    #[error("{path}:{line}: {entity}: expected {expected}, found '{found}'")]
    Malformed {
        path: PathBuf,
        line: usize,
        entity: String,
        expected: String,
        found: String,
    },
    /// A valid feature of the format that flexmbs does not read (an element type, an
    /// assembly, a coordinate system kind), with what to do instead.
    #[error("{path}:{line}: {entity}: {what}")]
    Unsupported {
        path: PathBuf,
        line: usize,
        entity: String,
        what: String,
    },
    /// A reference to something the file does not define.
    #[error("{path}:{line}: {entity}: {kind} {id} is not defined{hint}")]
    Undefined {
        path: PathBuf,
        line: usize,
        entity: String,
        kind: Entity,
        id: String,
        /// Empty, or a sentence starting with "; " (the names that exist, for instance).
        hint: String,
    },
    /// The same id defined twice.
    #[error("{path}:{line}: {kind} {id} is defined twice (first at line {first_line})")]
    Duplicate {
        path: PathBuf,
        line: usize,
        kind: Entity,
        id: String,
        first_line: usize,
    },
    /// The deck asks for more than its own size allows: a range of ids longer than the
    /// nodes or elements the deck defines, more set members or included input than the
    /// readers' budgets. `chain` is empty in the main file, else the including lines.
    #[error("{path}:{line}: {entity}: {what}{chain}")]
    Limit {
        path: PathBuf,
        line: usize,
        entity: String,
        what: String,
        chain: String,
    },
    /// A material or section value outside its physical range.
    #[error("{path}:{line}: {entity}: {source}")]
    Property {
        path: PathBuf,
        line: usize,
        entity: String,
        #[source]
        source: PropertyError,
    },
}

/// What an [`ImportError::Undefined`] or [`ImportError::Duplicate`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Entity {
    Node,
    Element,
    Material,
    NodeSet,
    ElementSet,
    CoordinateSystem,
    Property,
    /// A Nastran PSOLID (by PID).
    Psolid,
    /// A Nastran MAT1 (by MID).
    Mat1,
}

impl std::fmt::Display for Entity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Entity::Node => "node",
            Entity::Element => "element",
            Entity::Material => "material",
            Entity::NodeSet => "node set",
            Entity::ElementSet => "element set",
            Entity::CoordinateSystem => "coordinate system",
            Entity::Property => "property",
            Entity::Psolid => "PSOLID",
            Entity::Mat1 => "MAT1",
        })
    }
}

/// Reads a file for a reader, with the I/O error naming it.
pub(super) fn read_text(path: &Path) -> Result<Vec<u8>, ImportError> {
    crate::input::read(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Longest excerpt of offending input quoted in an error message.
const FOUND_MAX_CHARS: usize = 40;

/// Quotes a piece of input for an error message: at most [`FOUND_MAX_CHARS`] characters.
pub(super) fn excerpt(text: &str) -> String {
    let mut out: String = text.chars().take(FOUND_MAX_CHARS).collect();
    if text.chars().count() > FOUND_MAX_CHARS {
        out.push('…');
    }
    out
}

/// A malformed field at `line` of `path`: what was `expected` and (an excerpt of) what was found.
pub(super) fn malformed(path: &Path, line: usize, entity: &str, expected: &str, found: &str) -> ImportError {
    ImportError::Malformed {
        path: path.to_path_buf(),
        line,
        entity: entity.to_string(),
        expected: expected.to_string(),
        found: excerpt(found),
    }
}

/// A feature of the format that we do not read, at `line` of `path`.
pub(super) fn unsupported(path: &Path, line: usize, entity: &str, what: String) -> ImportError {
    ImportError::Unsupported {
        path: path.to_path_buf(),
        line,
        entity: entity.to_string(),
        what,
    }
}

/// Deepest nesting of included files (a file that includes itself stops here).
pub(super) const MAX_INCLUDE_DEPTH: usize = 16;

/// Most files a deck may include, counting a file each time it is included: a nesting of a
/// few small files, each including the next several times, would otherwise multiply into
/// billions of reads within the depth limit.
pub const MAX_INCLUDED_FILES: usize = 10_000;

/// Most bytes of input a deck may expand to, the main file and every included file counted
/// each time it is included: a generous 1 GiB (a solid model at the 2,000,000-cell maximum
/// of a study takes a few hundred MB); the readers hold every line, a few times its bytes, so
/// the expanded text bounds their memory.
pub const MAX_EXPANDED_BYTES: usize = 1 << 30;

/// The budget of a deck's included files: the chain of including lines (for the errors and
/// the depth), the files opened so far and the bytes read so far, all files counted each
/// time they are included ([`MAX_INCLUDE_DEPTH`], [`MAX_INCLUDED_FILES`],
/// [`MAX_EXPANDED_BYTES`]).
#[derive(Default)]
pub(super) struct Includes {
    /// The including lines from the main file to the current one: (file, line).
    chain: Vec<(PathBuf, usize)>,
    files: usize,
    bytes: usize,
}

impl Includes {
    /// Counts the main file, `data` read from `path`.
    pub(super) fn start(&mut self, path: &Path, data: &[u8]) -> Result<(), ImportError> {
        self.add_bytes(path, 0, "the deck", data.len())
    }

    fn add_bytes(&mut self, path: &Path, line: usize, entity: &str, len: usize) -> Result<(), ImportError> {
        self.bytes = self.bytes.saturating_add(len);
        if self.bytes > MAX_EXPANDED_BYTES {
            return Err(self.limit(
                path,
                line,
                entity,
                format!("the deck with its included files expands to more than {MAX_EXPANDED_BYTES} bytes"),
            ));
        }
        Ok(())
    }

    fn limit(&self, path: &Path, line: usize, entity: &str, what: String) -> ImportError {
        ImportError::Limit {
            path: path.to_path_buf(),
            line,
            entity: entity.to_string(),
            what,
            chain: self.chain_text(),
        }
    }

    /// The including lines as `a.inp:3 -> b.inc:7`, or empty in the main file.
    fn chain_text(&self) -> String {
        if self.chain.is_empty() {
            return String::new();
        }
        let lines: Vec<String> = self.chain.iter().map(|(p, l)| format!("{}:{l}", p.display())).collect();
        format!(" (included by {})", lines.join(" -> "))
    }

    /// The file that `line` of `path` includes (`name`, relative to `path`'s folder): its
    /// path and bytes, or the error naming the including line (`entity`: the keyword or card)
    /// or the file that cannot be read. Every `open` that succeeds is followed by a
    /// [`Includes::close`] when the included file has been read.
    pub(super) fn open(
        &mut self,
        path: &Path,
        line: usize,
        entity: &str,
        name: &str,
    ) -> Result<(PathBuf, Vec<u8>), ImportError> {
        if self.chain.len() >= MAX_INCLUDE_DEPTH {
            return Err(unsupported(
                path,
                line,
                entity,
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)"),
            ));
        }
        self.files += 1;
        if self.files > MAX_INCLUDED_FILES {
            return Err(self.limit(
                path,
                line,
                entity,
                format!("more than {MAX_INCLUDED_FILES} files included (each counted every time it is included)"),
            ));
        }
        let target = path.parent().unwrap_or(Path::new("")).join(name);
        // Refused before it is read: a file past the budget is never held in memory.
        if let Ok(meta) = std::fs::metadata(&target) {
            let len = usize::try_from(meta.len()).unwrap_or(usize::MAX);
            if self.bytes.saturating_add(len) > MAX_EXPANDED_BYTES {
                return Err(self.limit(
                    path,
                    line,
                    entity,
                    format!(
                        "'{name}' ({len} bytes) would expand the deck with its included files past {MAX_EXPANDED_BYTES} bytes"
                    ),
                ));
            }
        }
        let data = crate::input::read(&target).map_err(|source| ImportError::Io {
            path: target.clone(),
            source,
        })?;
        self.add_bytes(path, line, entity, data.len())?;
        self.chain.push((path.to_path_buf(), line));
        Ok((target, data))
    }

    /// Ends the file opened last.
    pub(super) fn close(&mut self) {
        self.chain.pop();
    }
}

/// Our node `i` of a cell of `kind` is the file's node `order[i]`: the given orders of the
/// quadratic tetrahedron and hexahedron, the file's own order for every other kind (Abaqus
/// and Nastran order tet4, hex8, wedge6 and lines as gmsh does).
pub(super) fn node_order(kind: CellKind, tet10: &'static [usize; 10], hex20: &'static [usize; 20]) -> &'static [usize] {
    const IDENTITY: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19];
    match kind {
        CellKind::Tet10 => tet10,
        CellKind::Hex20 => hex20,
        other => &IDENTITY[..other.node_count()],
    }
}

/// Records skipped cards or keywords, each once with its count and first place.
#[derive(Default)]
pub(super) struct IgnoredList(Vec<Ignored>);

impl IgnoredList {
    pub(super) fn add(&mut self, name: &str, file: &Path, line: usize) {
        match self.0.iter_mut().find(|i| i.name == name) {
            Some(i) => i.count += 1,
            None => self.0.push(Ignored {
                name: name.to_string(),
                count: 1,
                first_file: file.to_path_buf(),
                first_line: line,
            }),
        }
    }

    pub(super) fn into_vec(self) -> Vec<Ignored> {
        self.0
    }
}

/// Builds the mesh from nodes and cells given by file ids: dense [`NodeId`]s in order of
/// definition, the file ids kept as tags.
#[derive(Default)]
pub(super) struct MeshBuilder {
    pub(super) mesh: Mesh,
    /// File id -> (dense id, line of definition).
    pub(super) node_ids: BTreeMap<u64, (NodeId, usize)>,
    /// File id -> (cell index, line of definition).
    pub(super) cell_ids: BTreeMap<u64, (usize, usize)>,
}

impl MeshBuilder {
    /// Adds node `id` at `x`, defined on `line` of `path`.
    pub(super) fn add_node(&mut self, id: u64, x: Point3<f64>, path: &Path, line: usize) -> Result<(), ImportError> {
        if let Some(&(_, first_line)) = self.node_ids.get(&id) {
            return Err(ImportError::Duplicate {
                path: path.to_path_buf(),
                line,
                kind: Entity::Node,
                id: id.to_string(),
                first_line,
            });
        }
        let node = NodeId(self.mesh.nodes.len() as u32);
        self.mesh.nodes.push(x);
        self.mesh.node_tags.push(id);
        self.node_ids.insert(id, (node, line));
        Ok(())
    }

    /// The dense id of file node `id`, or the error naming `entity` that refers to it.
    pub(super) fn node(&self, id: u64, path: &Path, line: usize, entity: &str) -> Result<NodeId, ImportError> {
        self.node_ids
            .get(&id)
            .map(|&(n, _)| n)
            .ok_or_else(|| ImportError::Undefined {
                path: path.to_path_buf(),
                line,
                entity: entity.to_string(),
                kind: Entity::Node,
                id: id.to_string(),
                hint: String::new(),
            })
    }

    /// Adds element `id` of `kind` with `nodes` given in the file's order, converted to ours
    /// by `ours_from_file` (our node `i` is the file's node `ours_from_file[i]`).
    pub(super) fn add_cell(
        &mut self,
        id: u64,
        kind: CellKind,
        nodes: &[NodeId],
        ours_from_file: &[usize],
        path: &Path,
        line: usize,
    ) -> Result<usize, ImportError> {
        if let Some(&(_, first_line)) = self.cell_ids.get(&id) {
            return Err(ImportError::Duplicate {
                path: path.to_path_buf(),
                line,
                kind: Entity::Element,
                id: id.to_string(),
                first_line,
            });
        }
        let index = self.mesh.cells.len();
        self.mesh.cells.push(crate::mesh::Cell {
            kind,
            nodes: ours_from_file.iter().map(|&i| nodes[i]).collect(),
            tag: id,
        });
        self.cell_ids.insert(id, (index, line));
        Ok(index)
    }
}

/// A material from its three constants, with the error located.
pub(super) fn material(
    name: &str,
    E: f64,
    nu: f64,
    rho: f64,
    path: &Path,
    line: usize,
    entity: &str,
) -> Result<IsotropicMaterial, ImportError> {
    IsotropicMaterial::new(name, E, nu, rho).map_err(|source| ImportError::Property {
        path: path.to_path_buf(),
        line,
        entity: entity.to_string(),
        source,
    })
}
