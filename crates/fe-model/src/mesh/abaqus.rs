//! Reader for Abaqus input files (`.inp`): the model data of a flat (part-less) input file.
//!
//! [`read`] reads a file and the files it includes; [`parse`] takes the text of the main file
//! (for tests) and still reads `*INCLUDE`d files from disk, relative to `origin`'s directory.
//!
//! # What is read
//!
//! | keyword | read as |
//! |---|---|
//! | `*NODE` (`NSET=`) | nodes; `id, x, y[, z]` |
//! | `*ELEMENT, TYPE=` (`ELSET=`) | cells: `C3D4`, `C3D10`, `C3D8`, `C3D20`, `C3D6` solids, `B31` beams; data lines ending in a comma continue on the next line |
//! | `*NSET`, `*ELSET` (`GENERATE`) | named node and cell sets; members are ids or earlier sets; `GENERATE` lines are `first, last[, step]` |
//! | `*MATERIAL, NAME=` with `*ELASTIC` (isotropic, one line `E, nu`) and `*DENSITY` (`rho`) | materials |
//! | `*SOLID SECTION, ELSET=, MATERIAL=` | the material of the 3D cells of a set |
//! | `*BEAM SECTION, ELSET=, MATERIAL=, SECTION=` `RECT` (`a, b`), `CIRC` (`r`), `PIPE` (`r, t`); second line the direction $\mathbf n_1$ (default $(0, 0, -1)$) | the beam section of the `B31` cells of a set, local $y = \mathbf n_1$ |
//! | `*BOUNDARY` (model data, zero values) | supports: `node or set, first dof[, last dof]`, or `ENCASTRE` / `PINNED` |
//! | `*INCLUDE, INPUT=` | the included file, in place (paths relative to the including file) |
//! | `*PART`, `*ASSEMBLY`, `*INSTANCE` | refused: write the input without parts and assemblies |
//! | `*STEP` … `*END STEP` | skipped with everything inside (listed once) |
//! | any other keyword | skipped with its data lines, listed once in [`ImportedModel::ignored`] |
//!
//! Keywords, parameter names and set or material names are case-insensitive, as in Abaqus;
//! sets and materials keep the spelling of their first definition.
//!
//! # Units
//!
//! [`read`] and [`parse`] take the [`UnitSystem`] the deck is written in; in another than SI,
//! coordinates, section dimensions, `E` and densities are converted to SI as they are read.
//! A material whose constants no solid has in SI is a note in [`ImportedModel::notes`] that
//! names it, its line and the unit system its numbers fit.
//!
//! # Bounds
//!
//! A `GENERATE` range may name at most as many ids as the deck has data lines under `*NODE`
//! (node sets) or `*ELEMENT` (element sets), and all sets together (copies of earlier sets
//! counted), like the `*BOUNDARY` lines on sets, at most 32 times the nodes and elements; a
//! deck with its included files (each counted every time it is included) holds at most
//! [`MAX_INCLUDED_FILES`](super::import::MAX_INCLUDED_FILES) files and
//! [`MAX_EXPANDED_BYTES`](super::import::MAX_EXPANDED_BYTES) bytes. Past a bound the error is
//! [`ImportError::Limit`].
//!
//! # Node orderings
//!
//! Abaqus orders corners as gmsh does; mid-edge nodes differ (`C3D10`: the last two are
//! swapped; `C3D20`: Abaqus lists the bottom ring, the top ring, then the vertical edges).
//! [`ours_from_abaqus`] gives the permutation, `tests/unit/import.rs` checks it on the
//! fixtures' geometry (the same solid gives the same frequencies from gmsh and Abaqus files).

use super::import::{
    excerpt, malformed, material, node_order, read_text, unsupported, BeamSectionAssignment, Entity, IgnoredList,
    ImportError, ImportedModel, ImportedSupport, Includes, MeshBuilder, SolidSection,
};
use crate::mesh::{CellId, CellKind, NodeId};
use crate::model::DofMask;
use crate::section::BeamSection;
use crate::units::{deck_material_warning, Quantity, UnitSystem};
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Reads the Abaqus input file at `path`, written in `units` (`UnitSystem::Si` for SI), and
/// the files it includes; every quantity converted to SI.
pub fn read(path: &Path, units: UnitSystem) -> Result<ImportedModel, ImportError> {
    let text = read_text(path)?;
    parse(text, path, units)
}

/// Parses the text of an Abaqus input file written in `units`, every quantity converted to
/// SI; `origin` names it in errors and is where `*INCLUDE`d paths start from.
pub fn parse(text: impl AsRef<[u8]>, origin: &Path, units: UnitSystem) -> Result<ImportedModel, ImportError> {
    let mut files = Vec::new();
    let mut lines = Vec::new();
    let mut includes = Includes::default();
    includes.start(origin, text.as_ref())?;
    expand(text.as_ref(), origin, &mut includes, &mut files, &mut lines)?;
    Reader::new(&files, units).run(&lines)
}

/// Our node `i` of an Abaqus element is the Abaqus node `ours_from_abaqus(kind)[i]`.
pub fn ours_from_abaqus(kind: CellKind) -> &'static [usize] {
    // C3D10: 4-6 on edges 1-2, 2-3, 3-1; 7, 8, 9 on 1-4, 2-4, 3-4; ours has 8 on (3, 2), 9 on (3, 1).
    const TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];
    // C3D20: 8-11 bottom ring (0-1, 1-2, 2-3, 3-0), 12-15 top ring, 16-19 vertical edges.
    const HEX20: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 16, 9, 17, 10, 18, 19, 12, 15, 13, 14];
    node_order(kind, &TET10, &HEX20)
}

/// The cell kind of an Abaqus element type, if we read it.
fn cell_kind(element_type: &str) -> Option<CellKind> {
    Some(match element_type {
        "C3D4" => CellKind::Tet4,
        "C3D10" => CellKind::Tet10,
        "C3D8" => CellKind::Hex8,
        "C3D20" => CellKind::Hex20,
        "C3D6" => CellKind::Wedge6,
        "B31" => CellKind::Line2,
        _ => return None,
    })
}

const SUPPORTED_TYPES: &str = "C3D4, C3D10, C3D8, C3D20, C3D6, B31";

/// One line of input: the file (index into the file list), the 1-based line, the text.
struct Line {
    file: usize,
    line: usize,
    text: String,
}

/// Reads `data` (from `path`) into `lines`, replacing each `*INCLUDE` by the lines of the file
/// it names. Comment lines (`**`) and blank lines are dropped.
fn expand(
    data: &[u8],
    path: &Path,
    includes: &mut Includes,
    files: &mut Vec<PathBuf>,
    lines: &mut Vec<Line>,
) -> Result<(), ImportError> {
    let file = files.len();
    files.push(path.to_path_buf());
    let text = String::from_utf8_lossy(data);
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with("**") {
            continue;
        }
        if trimmed.starts_with('*') {
            let keyword = Keyword::parse(trimmed, path, line)?;
            if keyword.name == "INCLUDE" {
                let input = keyword.required("INPUT", path, line)?;
                let (target, data) = includes.open(path, line, "*INCLUDE", input)?;
                expand(&data, &target, includes, files, lines)?;
                includes.close();
                continue;
            }
        }
        lines.push(Line {
            file,
            line,
            text: trimmed.to_string(),
        });
    }
    Ok(())
}

/// The name of a keyword line: upper case, single spaces, without `*` and parameters.
fn keyword_name(text: &str) -> String {
    text.trim_start_matches('*')
        .split(',')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_uppercase()
}

/// A keyword line: its name (upper case, single spaces) and parameters (names upper case).
struct Keyword {
    name: String,
    params: Vec<(String, Option<String>)>,
}

impl Keyword {
    fn parse(text: &str, path: &Path, line: usize) -> Result<Self, ImportError> {
        let name = keyword_name(text);
        let mut parts = text.split(',');
        parts.next();
        let mut params = Vec::new();
        for part in parts {
            let part = part.trim();
            if part.is_empty() {
                continue;
            }
            match part.split_once('=') {
                Some((k, v)) => {
                    let v = v.trim().trim_matches('"').trim();
                    if v.is_empty() {
                        return Err(ImportError::Malformed {
                            path: path.to_path_buf(),
                            line,
                            entity: format!("*{name}"),
                            expected: format!("a value after '{}='", k.trim()),
                            found: excerpt(part),
                        });
                    }
                    params.push((k.trim().to_uppercase(), Some(v.to_string())));
                }
                None => params.push((part.to_uppercase(), None)),
            }
        }
        Ok(Keyword { name, params })
    }

    fn get(&self, name: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == name)
            .and_then(|(_, v)| v.as_deref())
    }

    fn flag(&self, name: &str) -> bool {
        self.params.iter().any(|(k, _)| k == name)
    }

    fn required(&self, name: &str, path: &Path, line: usize) -> Result<&str, ImportError> {
        self.get(name).ok_or_else(|| ImportError::Malformed {
            path: path.to_path_buf(),
            line,
            entity: format!("*{}", self.name),
            expected: format!("the parameter {name}="),
            found: "none".into(),
        })
    }
}

/// A material being defined.
struct MaterialDef {
    name: String,
    line: usize,
    file: usize,
    elastic: Option<(f64, f64)>,
    density: Option<f64>,
}

/// A named set: its spelling, and members in order: (file id, file, line where listed).
#[derive(Default)]
struct SetDef {
    name: String,
    members: Vec<(u64, usize, usize)>,
}

struct Reader<'a> {
    files: &'a [PathBuf],
    /// The deck's units: every quantity is converted to SI as it is read.
    units: UnitSystem,
    builder: MeshBuilder,
    /// Elements read before all nodes are known: (id, kind, node ids, file, line).
    elements: Vec<(u64, CellKind, Vec<u64>, usize, usize)>,
    node_sets: BTreeMap<String, SetDef>,
    cell_sets: BTreeMap<String, SetDef>,
    materials: Vec<MaterialDef>,
    /// (elset, material, file, line), (elset, material, section, file, line).
    solid_sections: Vec<(String, String, usize, usize)>,
    beam_sections: Vec<(String, String, BeamSpec, usize, usize)>,
    /// (node id or set name, dofs, file, line).
    boundaries: Vec<(String, DofMask, usize, usize)>,
    ignored: IgnoredList,
    /// Upper bounds of the nodes and the elements the deck defines (the data lines of its
    /// `*NODE` and `*ELEMENT` keywords), which bound a `GENERATE` range.
    defined: Defined,
    /// Set members listed so far, every copy of an earlier set counted
    /// ([`MEMBERS_PER_ID`]).
    members: usize,
}

/// All sets of a deck together may list at most this many times the nodes and elements it
/// defines: a real deck has a few sets over all of them, and sets of sets of sets would
/// otherwise double with every line.
const MEMBERS_PER_ID: usize = 32;

/// The data lines of the `*NODE` (one node each) and `*ELEMENT` (one or more per element)
/// keywords of a deck.
#[derive(Default)]
struct Defined {
    nodes: usize,
    elements: usize,
}

impl Defined {
    fn count(lines: &[Line]) -> Self {
        let mut defined = Defined::default();
        let mut current: Option<&mut usize> = None;
        for l in lines {
            if l.text.starts_with('*') {
                current = match keyword_name(&l.text).as_str() {
                    "NODE" => Some(&mut defined.nodes),
                    "ELEMENT" => Some(&mut defined.elements),
                    _ => None,
                };
            } else if let Some(n) = current.as_deref_mut() {
                *n += 1;
            }
        }
        defined
    }
}

/// A beam section before its material is known: the shape and dimensions, and $\mathbf n_1$.
struct BeamSpec {
    shape: String,
    dims: Vec<f64>,
    n1: Vector3<f64>,
}

impl<'a> Reader<'a> {
    fn new(files: &'a [PathBuf], units: UnitSystem) -> Self {
        Reader {
            files,
            units,
            builder: MeshBuilder::default(),
            elements: Vec::new(),
            node_sets: BTreeMap::new(),
            cell_sets: BTreeMap::new(),
            materials: Vec::new(),
            solid_sections: Vec::new(),
            beam_sections: Vec::new(),
            boundaries: Vec::new(),
            ignored: IgnoredList::default(),
            defined: Defined::default(),
            members: 0,
        }
    }

    fn path(&self, file: usize) -> &'a Path {
        &self.files[file]
    }

    fn malformed(&self, l: &Line, entity: &str, expected: &str, found: &str) -> ImportError {
        malformed(self.path(l.file), l.line, entity, expected, found)
    }

    fn unsupported(&self, l: &Line, entity: &str, what: String) -> ImportError {
        unsupported(self.path(l.file), l.line, entity, what)
    }

    fn limit(&self, l: &Line, entity: &str, what: String) -> ImportError {
        ImportError::Limit {
            path: self.path(l.file).to_path_buf(),
            line: l.line,
            entity: entity.to_string(),
            what,
            chain: String::new(),
        }
    }

    fn run(mut self, lines: &[Line]) -> Result<ImportedModel, ImportError> {
        self.defined = Defined::count(lines);
        let mut k = 0;
        while k < lines.len() {
            let head = &lines[k];
            if !head.text.starts_with('*') {
                return Err(self.malformed(
                    head,
                    "data line",
                    "a keyword line (*NODE, *ELEMENT, ...) before data",
                    &head.text,
                ));
            }
            let keyword = Keyword::parse(&head.text, self.path(head.file), head.line)?;
            let start = k + 1;
            let mut end = start;
            while end < lines.len() && !lines[end].text.starts_with('*') {
                end += 1;
            }
            let data = &lines[start..end];
            k = end;
            match keyword.name.as_str() {
                "NODE" => self.nodes(head, &keyword, data)?,
                "ELEMENT" => self.elements(head, &keyword, data)?,
                "NSET" => self.set(head, &keyword, data, true)?,
                "ELSET" => self.set(head, &keyword, data, false)?,
                "MATERIAL" => {
                    let name = keyword.required("NAME", self.path(head.file), head.line)?.to_string();
                    if let Some(first) = self.materials.iter().find(|m| m.name.eq_ignore_ascii_case(&name)) {
                        return Err(ImportError::Duplicate {
                            path: self.path(head.file).to_path_buf(),
                            line: head.line,
                            kind: Entity::Material,
                            id: name,
                            first_line: first.line,
                        });
                    }
                    self.materials.push(MaterialDef {
                        name,
                        line: head.line,
                        file: head.file,
                        elastic: None,
                        density: None,
                    });
                }
                "ELASTIC" => self.elastic(head, &keyword, data)?,
                "DENSITY" => {
                    let values = self.material_values(head, "*DENSITY", data, 1)?;
                    let rho = values[0] * self.units.to_si(Quantity::Density);
                    self.current_material(head, "*DENSITY")?.density = Some(rho);
                }
                "SOLID SECTION" => {
                    let p = self.path(head.file);
                    let elset = keyword.required("ELSET", p, head.line)?.to_string();
                    let material = keyword.required("MATERIAL", p, head.line)?.to_string();
                    self.solid_sections.push((elset, material, head.file, head.line));
                }
                "BEAM SECTION" => self.beam_section(head, &keyword, data)?,
                "BOUNDARY" => self.boundary(head, &keyword, data)?,
                "PART" | "END PART" | "ASSEMBLY" | "END ASSEMBLY" | "INSTANCE" | "END INSTANCE" => {
                    return Err(self.unsupported(
                        head,
                        &format!("*{}", keyword.name),
                        "parts, assemblies and instances are not read; write the input file without them (Abaqus/CAE: Model > Edit Attributes > \"Do not use parts and assemblies in input files\")".into(),
                    ))
                }
                "STEP" => {
                    // Skip the whole step: its boundary conditions and loads are not model data.
                    self.ignored.add("*STEP (with its contents)", self.path(head.file), head.line);
                    while k < lines.len() {
                        let text = &lines[k].text;
                        k += 1;
                        if text.starts_with('*') && keyword_name(text) == "END STEP" {
                            break;
                        }
                    }
                }
                other => self.ignored.add(&format!("*{other}"), self.path(head.file), head.line),
            }
        }
        self.finish()
    }

    fn number<T: std::str::FromStr>(
        &self,
        l: &Line,
        entity: &str,
        expected: &str,
        field: &str,
    ) -> Result<T, ImportError> {
        field
            .trim()
            .parse::<T>()
            .map_err(|_| self.malformed(l, entity, expected, field.trim()))
    }

    fn real(&self, l: &Line, entity: &str, expected: &str, field: &str) -> Result<f64, ImportError> {
        let v: f64 = self.number(l, entity, expected, field)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.malformed(l, entity, expected, field.trim()))
        }
    }

    fn nodes(&mut self, head: &Line, keyword: &Keyword, data: &[Line]) -> Result<(), ImportError> {
        let set = keyword.get("NSET").map(str::to_string);
        for l in data {
            let fields: Vec<&str> = l.text.split(',').map(str::trim).filter(|f| !f.is_empty()).collect();
            if fields.len() < 3 || fields.len() > 4 {
                return Err(self.malformed(l, "*NODE", "'id, x, y[, z]'", &l.text));
            }
            let id: u64 = self.number(l, "*NODE", "a node id (positive integer)", fields[0])?;
            let entity = format!("*NODE {id}");
            let mut x = [0.0; 3];
            for (c, f) in fields[1..].iter().enumerate() {
                x[c] = self.real(l, &entity, "a finite coordinate", f)? * self.units.to_si(Quantity::Length);
            }
            self.builder.add_node(id, Point3::from(x), self.path(l.file), l.line)?;
            if let Some(set) = &set {
                self.set_entry(set, true).members.push((id, l.file, l.line));
            }
        }
        let _ = head;
        Ok(())
    }

    fn set_entry(&mut self, name: &str, nodes: bool) -> &mut SetDef {
        let sets = if nodes {
            &mut self.node_sets
        } else {
            &mut self.cell_sets
        };
        sets.entry(name.to_uppercase()).or_insert_with(|| SetDef {
            name: name.to_string(),
            members: Vec::new(),
        })
    }

    fn elements(&mut self, head: &Line, keyword: &Keyword, data: &[Line]) -> Result<(), ImportError> {
        let element_type = keyword
            .required("TYPE", self.path(head.file), head.line)?
            .to_uppercase();
        let Some(kind) = cell_kind(&element_type) else {
            return Err(self.unsupported(
                head,
                "*ELEMENT",
                format!("element type {element_type} is not read (supported: {SUPPORTED_TYPES})"),
            ));
        };
        let set = keyword.get("ELSET").map(str::to_string);
        // Join data lines that end in a comma with the next one.
        let mut k = 0;
        while k < data.len() {
            let first = &data[k];
            let mut fields: Vec<String> = Vec::new();
            loop {
                let l = &data[k];
                let text = l.text.trim_end();
                fields.extend(text.split(',').map(|f| f.trim().to_string()));
                k += 1;
                if !(text.ends_with(',') && k < data.len()) {
                    break;
                }
            }
            fields.retain(|f| !f.is_empty());
            let id: u64 = self.number(first, "*ELEMENT", "an element id (positive integer)", &fields[0])?;
            let entity = format!("element {id} ({element_type})");
            if fields.len() - 1 != kind.node_count() {
                return Err(self.malformed(
                    first,
                    &entity,
                    &format!("{} node ids", kind.node_count()),
                    &format!("{} ids: {}", fields.len() - 1, fields[1..].join(", ")),
                ));
            }
            let nodes = fields[1..]
                .iter()
                .map(|f| self.number::<u64>(first, &entity, "a node id (positive integer)", f))
                .collect::<Result<Vec<_>, _>>()?;
            self.elements.push((id, kind, nodes, first.file, first.line));
            if let Some(set) = &set {
                self.set_entry(set, false).members.push((id, first.file, first.line));
            }
        }
        Ok(())
    }

    fn set(&mut self, head: &Line, keyword: &Keyword, data: &[Line], nodes: bool) -> Result<(), ImportError> {
        let (param, what) = if nodes { ("NSET", "*NSET") } else { ("ELSET", "*ELSET") };
        let name = keyword.required(param, self.path(head.file), head.line)?.to_string();
        let entity = format!("{what} {name}");
        let mut members = Vec::new();
        for l in data {
            let fields: Vec<&str> = l.text.split(',').map(str::trim).filter(|f| !f.is_empty()).collect();
            if keyword.flag("GENERATE") {
                if fields.len() < 2 || fields.len() > 3 {
                    return Err(self.malformed(l, &entity, "'first, last[, increment]' (GENERATE)", &l.text));
                }
                let first: u64 = self.number(l, &entity, "a first id", fields[0])?;
                let last: u64 = self.number(l, &entity, "a last id", fields[1])?;
                let step: u64 = match fields.get(2) {
                    Some(f) => self.number(l, &entity, "a positive increment", f)?,
                    None => 1,
                };
                if step == 0 || last < first || !(last - first).is_multiple_of(step) {
                    return Err(self.malformed(
                        l,
                        &entity,
                        "first <= last and a positive increment that reaches last (GENERATE)",
                        &l.text,
                    ));
                }
                let count = (last - first) / step + 1;
                let (defined, kind) = if nodes {
                    (self.defined.nodes, "nodes")
                } else {
                    (self.defined.elements, "elements")
                };
                if count > defined as u64 {
                    return Err(self.limit(
                        l,
                        &entity,
                        format!(
                            "GENERATE '{}' names {count} {kind}, more than the {defined} the deck defines",
                            l.text
                        ),
                    ));
                }
                self.count_members(l, &entity, count as usize)?;
                members.extend((first..=last).step_by(step as usize).map(|id| (id, l.file, l.line)));
                continue;
            }
            for f in fields {
                match f.parse::<u64>() {
                    Ok(id) => members.push((id, l.file, l.line)),
                    Err(_) => {
                        let sets = if nodes { &self.node_sets } else { &self.cell_sets };
                        let Some(other) = sets.get(&f.to_uppercase()) else {
                            return Err(ImportError::Undefined {
                                path: self.path(l.file).to_path_buf(),
                                line: l.line,
                                entity: entity.clone(),
                                kind: if nodes { Entity::NodeSet } else { Entity::ElementSet },
                                id: f.to_string(),
                                hint: " (members are ids or earlier sets)".into(),
                            });
                        };
                        let copied = other.members.len();
                        self.count_members(l, &entity, copied)?;
                        let sets = if nodes { &self.node_sets } else { &self.cell_sets };
                        members.extend_from_slice(&sets[&f.to_uppercase()].members);
                    }
                }
            }
        }
        self.set_entry(&name, nodes).members.extend(members);
        Ok(())
    }

    /// Counts `count` more set members listed on `l`, within [`MEMBERS_PER_ID`] times the
    /// nodes and elements of the deck.
    fn count_members(&mut self, l: &Line, entity: &str, count: usize) -> Result<(), ImportError> {
        let budget = MEMBERS_PER_ID.saturating_mul(self.defined.nodes + self.defined.elements);
        self.members = self.members.saturating_add(count);
        if self.members > budget {
            return Err(self.limit(
                l,
                entity,
                format!(
                    "the sets list more than {budget} members ({MEMBERS_PER_ID} times the {} nodes and elements the deck defines)",
                    self.defined.nodes + self.defined.elements
                ),
            ));
        }
        Ok(())
    }

    fn current_material(&mut self, l: &Line, entity: &str) -> Result<&mut MaterialDef, ImportError> {
        let path = self.path(l.file).to_path_buf();
        self.materials.last_mut().ok_or(ImportError::Malformed {
            path,
            line: l.line,
            entity: entity.to_string(),
            expected: "a *MATERIAL keyword before it".into(),
            found: "none".into(),
        })
    }

    /// The single data line of a material option with `count` values (more lines would be
    /// temperature-dependent data).
    fn material_values(&self, head: &Line, entity: &str, data: &[Line], count: usize) -> Result<Vec<f64>, ImportError> {
        let Some(l) = data.first() else {
            return Err(self.malformed(head, entity, &format!("a data line with {count} value(s)"), "none"));
        };
        if data.len() > 1 {
            return Err(self.unsupported(
                &data[1],
                entity,
                "temperature-dependent data (more than one line) is not read; give one line".into(),
            ));
        }
        let fields: Vec<&str> = l.text.split(',').map(str::trim).filter(|f| !f.is_empty()).collect();
        if fields.len() < count {
            return Err(self.malformed(l, entity, &format!("{count} value(s)"), &l.text));
        }
        if fields.len() > count {
            return Err(self.unsupported(
                l,
                entity,
                format!(
                    "{} values: temperature-dependent data is not read; give {count}",
                    fields.len()
                ),
            ));
        }
        fields
            .iter()
            .map(|f| self.real(l, entity, "a finite number", f))
            .collect()
    }

    fn elastic(&mut self, head: &Line, keyword: &Keyword, data: &[Line]) -> Result<(), ImportError> {
        if let Some(t) = keyword.get("TYPE") {
            if !t.eq_ignore_ascii_case("ISOTROPIC") {
                return Err(self.unsupported(
                    head,
                    "*ELASTIC",
                    format!("TYPE={t} is not read (only isotropic elasticity)"),
                ));
            }
        }
        let values = self.material_values(head, "*ELASTIC", data, 2)?;
        let E = values[0] * self.units.to_si(Quantity::Stress);
        self.current_material(head, "*ELASTIC")?.elastic = Some((E, values[1]));
        Ok(())
    }

    fn beam_section(&mut self, head: &Line, keyword: &Keyword, data: &[Line]) -> Result<(), ImportError> {
        let p = self.path(head.file);
        let elset = keyword.required("ELSET", p, head.line)?.to_string();
        let material = keyword.required("MATERIAL", p, head.line)?.to_string();
        let shape = keyword.required("SECTION", p, head.line)?.to_uppercase();
        let entity = format!("*BEAM SECTION {elset}");
        let count = match shape.as_str() {
            "RECT" | "PIPE" => 2,
            "CIRC" => 1,
            other => {
                return Err(self.unsupported(
                    head,
                    &entity,
                    format!("SECTION={other} is not read (supported: RECT, CIRC, PIPE)"),
                ))
            }
        };
        let Some(first) = data.first() else {
            return Err(self.malformed(head, &entity, "a line of section dimensions", "none"));
        };
        let fields: Vec<&str> = first.text.split(',').map(str::trim).filter(|f| !f.is_empty()).collect();
        if fields.len() != count {
            return Err(self.malformed(
                first,
                &entity,
                &format!("{count} dimension(s) for SECTION={shape}"),
                &first.text,
            ));
        }
        let dims = fields
            .iter()
            .map(|f| Ok(self.real(first, &entity, "a finite dimension", f)? * self.units.to_si(Quantity::Length)))
            .collect::<Result<Vec<_>, _>>()?;
        let n1 = match data.get(1) {
            None => Vector3::new(0.0, 0.0, -1.0),
            Some(l) => {
                let fields: Vec<&str> = l.text.split(',').map(str::trim).filter(|f| !f.is_empty()).collect();
                if fields.len() != 3 {
                    return Err(self.malformed(l, &entity, "the direction n1 as 'x, y, z'", &l.text));
                }
                let v = fields
                    .iter()
                    .map(|f| self.real(l, &entity, "a finite component", f))
                    .collect::<Result<Vec<_>, _>>()?;
                Vector3::new(v[0], v[1], v[2])
            }
        };
        if data.len() > 2 {
            return Err(self.malformed(
                &data[2],
                &entity,
                "at most two data lines (dimensions, n1)",
                &data[2].text,
            ));
        }
        self.beam_sections
            .push((elset, material, BeamSpec { shape, dims, n1 }, head.file, head.line));
        Ok(())
    }

    fn boundary(&mut self, head: &Line, keyword: &Keyword, data: &[Line]) -> Result<(), ImportError> {
        if keyword.params.iter().any(|(k, _)| k != "OP") {
            return Err(self.unsupported(head, "*BOUNDARY", "parameters other than OP=MOD are not read".into()));
        }
        for l in data {
            let fields: Vec<&str> = l.text.split(',').map(str::trim).filter(|f| !f.is_empty()).collect();
            if fields.len() < 2 || fields.len() > 4 {
                return Err(self.malformed(
                    l,
                    "*BOUNDARY",
                    "'node or set, first dof[, last dof[, value]]' or 'node or set, ENCASTRE'",
                    &l.text,
                ));
            }
            let dofs = match fields[1].to_uppercase().as_str() {
                "ENCASTRE" => DofMask::ALL,
                "PINNED" => DofMask::TRANSLATIONS,
                _ => {
                    let first: usize = self.number(l, "*BOUNDARY", "a dof 1..6 or ENCASTRE/PINNED", fields[1])?;
                    let last: usize = match fields.get(2) {
                        Some(f) => self.number(l, "*BOUNDARY", "a last dof 1..6", f)?,
                        None => first,
                    };
                    if let Some(v) = fields.get(3) {
                        let v = self.real(l, "*BOUNDARY", "a prescribed value", v)?;
                        if v != 0.0 {
                            return Err(self.unsupported(
                                l,
                                "*BOUNDARY",
                                format!("a non-zero prescribed value {v} is not a support"),
                            ));
                        }
                    }
                    if !(1..=6).contains(&first) || !(first..=6).contains(&last) {
                        return Err(self.malformed(l, "*BOUNDARY", "dofs with 1 <= first <= last <= 6", &l.text));
                    }
                    let mut m = [false; 6];
                    m[first - 1..last].iter_mut().for_each(|b| *b = true);
                    DofMask(m)
                }
            };
            self.boundaries.push((fields[0].to_string(), dofs, l.file, l.line));
        }
        Ok(())
    }

    fn finish(mut self) -> Result<ImportedModel, ImportError> {
        // Cells, now that every node is known.
        for (id, kind, nodes, file, line) in std::mem::take(&mut self.elements) {
            let path = self.files[file].clone();
            let entity = format!("element {id}");
            let nodes = nodes
                .iter()
                .map(|&n| self.builder.node(n, &path, line, &entity))
                .collect::<Result<Vec<_>, _>>()?;
            self.builder
                .add_cell(id, kind, &nodes, ours_from_abaqus(kind), &path, line)?;
        }
        let mut imported = ImportedModel::default();
        // Sets: members resolved to dense ids; an id without a node or element is an error.
        for set in self.node_sets.values() {
            let mut ids: Vec<NodeId> = Vec::with_capacity(set.members.len());
            for &(m, file, line) in &set.members {
                match self.builder.node_ids.get(&m) {
                    Some(&(n, _)) => ids.push(n),
                    None => {
                        return Err(ImportError::Undefined {
                            path: self.files[file].clone(),
                            line,
                            entity: format!("*NSET {}", set.name),
                            kind: Entity::Node,
                            id: m.to_string(),
                            hint: String::new(),
                        })
                    }
                }
            }
            self.builder.mesh.add_to_node_set(&set.name, ids);
        }
        for set in self.cell_sets.values() {
            let mut cells: Vec<CellId> = Vec::with_capacity(set.members.len());
            let mut nodes: Vec<NodeId> = Vec::new();
            for &(m, file, line) in &set.members {
                match self.builder.cell_ids.get(&m) {
                    Some(&(c, _)) => {
                        cells.push(CellId(c as u32));
                        nodes.extend_from_slice(&self.builder.mesh.cells[c].nodes);
                    }
                    None => {
                        return Err(ImportError::Undefined {
                            path: self.files[file].clone(),
                            line,
                            entity: format!("*ELSET {}", set.name),
                            kind: Entity::Element,
                            id: m.to_string(),
                            hint: String::new(),
                        })
                    }
                }
            }
            cells.sort_unstable();
            cells.dedup();
            self.builder.mesh.cell_sets.insert(set.name.clone(), cells);
            // An element set's nodes form a node set of the same name, unless one exists
            // (gmsh's physical groups do the same).
            if !self.node_sets.contains_key(&set.name.to_uppercase()) {
                self.builder.mesh.add_to_node_set(&set.name, nodes);
            }
        }
        // Materials.
        for m in &self.materials {
            let path = &self.files[m.file];
            let entity = format!("*MATERIAL {}", m.name);
            let Some((E, nu)) = m.elastic else {
                return Err(ImportError::Malformed {
                    path: path.clone(),
                    line: m.line,
                    entity,
                    expected: "an *ELASTIC option".into(),
                    found: "none".into(),
                });
            };
            let Some(rho) = m.density else {
                return Err(ImportError::Malformed {
                    path: path.clone(),
                    line: m.line,
                    entity,
                    expected: "a *DENSITY option (a dynamic model needs mass)".into(),
                    found: "none".into(),
                });
            };
            imported
                .materials
                .push(material(&m.name, E, nu, rho, path, m.line, &entity)?);
            let place = format!("{}:{}", path.display(), m.line);
            imported
                .notes
                .extend(deck_material_warning(&m.name, &place, E, rho, self.units));
        }
        let find_material = |name: &str, file: usize, line: usize, entity: &str| {
            self.materials
                .iter()
                .position(|m| m.name.eq_ignore_ascii_case(name))
                .ok_or_else(|| ImportError::Undefined {
                    path: self.files[file].clone(),
                    line,
                    entity: entity.to_string(),
                    kind: Entity::Material,
                    id: name.to_string(),
                    hint: format!(
                        "; materials: {}",
                        self.materials
                            .iter()
                            .map(|m| m.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
        };
        let find_elset = |name: &str, file: usize, line: usize, entity: &str| {
            self.cell_sets
                .get(&name.to_uppercase())
                .map(|s| s.name.clone())
                .ok_or_else(|| ImportError::Undefined {
                    path: self.files[file].clone(),
                    line,
                    entity: entity.to_string(),
                    kind: Entity::ElementSet,
                    id: name.to_string(),
                    hint: format!(
                        "; element sets: {}",
                        self.cell_sets
                            .values()
                            .map(|s| s.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
        };
        for (elset, mat, file, line) in &self.solid_sections {
            let entity = format!("*SOLID SECTION {elset}");
            let m = find_material(mat, *file, *line, &entity)?;
            let cell_set = find_elset(elset, *file, *line, &entity)?;
            imported.solid_sections.push(SolidSection {
                cell_set,
                material: self.materials[m].name.clone(),
            });
        }
        for (elset, mat, spec, file, line) in &self.beam_sections {
            let entity = format!("*BEAM SECTION {elset}");
            let m = find_material(mat, *file, *line, &entity)?;
            let cell_set = find_elset(elset, *file, *line, &entity)?;
            let nu = imported.materials[m].nu();
            let d = &spec.dims;
            let section = match spec.shape.as_str() {
                "RECT" => BeamSection::rectangle(elset, d[0], d[1], nu),
                "CIRC" => BeamSection::circle(elset, 2.0 * d[0], nu),
                _ => BeamSection::tube(elset, 2.0 * d[0], 2.0 * (d[0] - d[1]), nu),
            }
            .map_err(|source| ImportError::Property {
                path: self.files[*file].clone(),
                line: *line,
                entity: entity.clone(),
                source,
            })?;
            imported.beam_sections.push(BeamSectionAssignment {
                cell_set,
                material: self.materials[m].name.clone(),
                section,
                orientation: spec.n1,
            });
        }
        imported.supports = self.supports()?;
        imported.mesh = self.builder.mesh;
        imported.ignored = self.ignored.into_vec();
        Ok(imported)
    }

    /// The supports of the `*BOUNDARY` lines. Each line on a set holds a copy of the set's
    /// nodes, so all of them together may hold at most [`MEMBERS_PER_ID`] times the deck's
    /// nodes and elements (thousands of lines on a set of millions would otherwise be
    /// billions of copies).
    fn supports(&self) -> Result<Vec<ImportedSupport>, ImportError> {
        let budget = MEMBERS_PER_ID.saturating_mul(self.defined.nodes + self.defined.elements);
        let mut held = 0usize;
        let mut supports = Vec::with_capacity(self.boundaries.len());
        for (target, dofs, file, line) in &self.boundaries {
            let path = &self.files[*file];
            let (name, nodes) = match target.parse::<u64>() {
                Ok(id) => (
                    format!("node {id}"),
                    vec![self.builder.node(id, path, *line, "*BOUNDARY")?],
                ),
                Err(_) => {
                    let Some(set) = self.node_sets.get(&target.to_uppercase()) else {
                        return Err(ImportError::Undefined {
                            path: path.clone(),
                            line: *line,
                            entity: "*BOUNDARY".into(),
                            kind: Entity::NodeSet,
                            id: target.clone(),
                            hint: String::new(),
                        });
                    };
                    let nodes = &self.builder.mesh.node_sets[&set.name];
                    held = held.saturating_add(nodes.len());
                    if held > budget {
                        return Err(ImportError::Limit {
                            path: path.clone(),
                            line: *line,
                            entity: format!("*BOUNDARY {}", set.name),
                            what: format!(
                                "the *BOUNDARY lines on sets hold more than {budget} nodes ({MEMBERS_PER_ID} times the {} nodes and elements the deck defines)",
                                self.defined.nodes + self.defined.elements
                            ),
                            chain: String::new(),
                        });
                    }
                    (set.name.clone(), nodes.clone())
                }
            };
            supports.push(ImportedSupport {
                name,
                nodes,
                dofs: *dofs,
            });
        }
        Ok(supports)
    }
}
