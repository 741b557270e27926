//! Reader for gmsh `.msh` files: MSH 4.1 and MSH 2.2, ASCII and binary.
//!
//! [`parse`] turns the bytes of a file into a [`Mesh`] and does no I/O; `origin` only names
//! the file in errors, so tests feed it inline text. [`read`] reads a file and calls
//! [`parse`].
//!
//! # Why our own parser
//!
//! The `mshio` crate (0.4) reads MSH 4.1 only, skips `$PhysicalNames`, and its errors are a
//! backtrace of nom error kinds pointing into the input: no line, no element or node tag.
//! MSH 2.2 needs a parser of our own anyway, and both versions share what matters here
//! (tokens, binary values, the mapping of tags to dense ids, physical groups), so one small
//! reader for both (about 1,000 lines of code) gives every error its file, line (ASCII) or
//! byte offset (binary), section and entity, without a dependency.
//!
//! # What is read
//!
//! | section | MSH 4.1 | MSH 2.2 (also 2.0, 2.1) |
//! |---|---|---|
//! | `$MeshFormat` | required first; ASCII or binary (data size 8, either endianness) | same |
//! | `$PhysicalNames` | names of physical groups | same |
//! | `$Entities` | entity → physical tags | (absent in 2.2) |
//! | `$Nodes` | entity blocks; parametric coordinates skipped | flat list |
//! | `$Elements` | entity blocks | one line (ASCII) or typed blocks (binary) per element |
//! | `$PartitionedEntities` | refused ([`MshError::UnsupportedFeature`]) | — |
//! | anything else | skipped up to its `$End…` marker | same |
//!
//! Lines between sections that do not start with `$` are ignored, as gmsh does.
//!
//! # Mesh produced
//!
//! * **Nodes** get dense [`NodeId`]s in order of appearance; gmsh's tags, which may be sparse
//!   and unordered, are kept in [`Mesh::node_tags`]. A tag defined twice is an error.
//! * **Cells** keep the gmsh element tag in [`Cell::tag`](crate::mesh::Cell::tag). Points
//!   (gmsh type 15) are not cells but their nodes join node sets. MSH 2.2 writes an element
//!   once per physical group it belongs to, with the same tag: the copies are one cell. Any
//!   other repeated element tag is an error.
//! * **Named sets**, one per physical group `(dim, tag)`, named from `$PhysicalNames` or
//!   `physical_<dim>_<tag>` without a name: a node set with all nodes of the group's elements
//!   (points included) and, for `dim >= 1`, a cell set with its cells. In 4.1 an element is
//!   in the groups of its entity (`$Entities`); in 2.2 in the group of its first tag. A
//!   named group without elements still gets (empty) sets, so both versions of the same mesh
//!   read the same; groups of different dimensions with the same name share their sets.
//!
//! # Element types and node orderings
//!
//! | gmsh type | [`CellKind`] | nodes |
//! |---|---|---|
//! | 1 | `Line2` | 2 |
//! | 2 | `Tri3` | 3 |
//! | 3 | `Quad4` | 4 |
//! | 4 | `Tet4` | 4 |
//! | 5 | `Hex8` | 8 |
//! | 6 | `Wedge6` (gmsh "prism") | 6 |
//! | 9 | `Tri6` | 6 |
//! | 11 | `Tet10` | 10 |
//! | 16 | `Quad8` | 8 |
//! | 17 | `Hex20` | 20 |
//! | 15 | point: no cell, skipped | 1 |
//!
//! Any other type is [`MshError::UnsupportedElementType`]. Our node orderings are gmsh's
//! (gmsh reference manual, "Node ordering"), so [`node_permutation_from_gmsh`] is the identity
//! for every kind; the conversion still goes through it so a kind with a different order
//! would need one table changed. `tests/data/gmsh/gmsh_reference_elements.txt` holds gmsh's own
//! reference coordinates of each type's nodes (written by `make_fixtures.py`), and the unit
//! tests check the edge tables below against it and against the fixtures' geometry.
//!
//! ```text
//! Hex8 (5)                   Hex20 (17)               Tet4 (4) / Tet10 (11)
//!
//!        v
//! 3----------2             3----13----2                        2
//! |\     ^   |\            |\         |\                     ,/|`\
//! | \    |   | \           | 15       | 14                  ,/  |  `\
//! |  \   |   |  \          9  \       11 \               ,6    '.   `5
//! |   7------+---6         |   7----19+---6             ,/       8     `\
//! |   |  +-- |-- | -> u    |   |      |   |           ,/         |       `\
//! 0---+---\--1   |         0---+-8----1   |          0--------4--'.--------1
//!  \  |    \  \  |          \  17      \  18          `\.         |      ,/
//!   \ |     \  \ |          10 |        12|             `\.      |    ,9
//!    \|      w  \|            \|         \|                `7.   '. ,/
//!     4----------5             4----16----5                   `\. |/
//!                                                                 `3
//! Wedge6 (6)
//!
//!            w
//!            ^
//!            |
//!            3
//!          ,/|`\
//!        ,/  |  `\
//!      ,/    |    `\
//!     4------+------5
//!     |      |      |
//!     |    ,/|`\    |
//!     |  ,/  |  `\  |
//!     |,/    |    `\|
//!    ,|      |      |\
//!  ,/ |      0      | `\
//! u   |    ,/ `\    |    v
//!     |  ,/     `\  |
//!     |,/         `\|
//!     1-------------2
//! ```
//!
//! Corners: hex 0-3 on the face $\zeta = -1$ counter-clockwise seen from $+\zeta$, 4-7 above
//! them; tet 0 at the origin of $(\xi, \eta, \zeta)$ and 1, 2, 3 on the axes; wedge 0-2 the
//! triangle $(0,0), (1,0), (0,1)$ at $\zeta = -1$, 3-5 above them. Mid-edge nodes (between
//! the two corners named):
//!
//! | kind | mid-edge nodes |
//! |---|---|
//! | `Tri6` | 3: (0,1), 4: (1,2), 5: (2,0) |
//! | `Quad8` | 4: (0,1), 5: (1,2), 6: (2,3), 7: (3,0) |
//! | `Tet10` | 4: (0,1), 5: (1,2), 6: (2,0), 7: (3,0), 8: (3,2), 9: (3,1) |
//! | `Hex20` | 8: (0,1), 9: (0,3), 10: (0,4), 11: (1,2), 12: (1,5), 13: (2,3), 14: (2,6), 15: (3,7), 16: (4,5), 17: (4,7), 18: (5,6), 19: (6,7) |
//!
//! # Errors and robustness
//!
//! Every [`MshError`] names the file and, except for I/O and a missing `$MeshFormat`, where:
//! a 1-based line in ASCII files, a byte offset in binary files (line numbers mean nothing
//! past binary data), plus the section and the entity involved. No input makes the reader
//! panic, and no count in a header is trusted for an allocation: capacities are capped by
//! what the rest of the input can hold, and a binary block is checked to fit before it is
//! read. The unit tests feed random bytes, every prefix of each fixture, and mutated fixtures.

mod builder;
mod cursor;
mod msh2;
mod msh4;

use crate::mesh::{CellKind, Mesh, NodeId};
use builder::{Builder, DimTag};
use cursor::{excerpt, Cursor};
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file an error was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line of an ASCII file.
    Line(usize),
    /// 0-based byte offset into a binary file.
    Byte(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(line) => write!(f, "line {line}"),
            Location::Byte(offset) => write!(f, "byte {offset}"),
        }
    }
}

/// A gmsh file that cannot be read into a [`Mesh`].
///
/// The message of each variant starts with the file and the [`Location`]; `section` is the
/// section being read, such as `$Nodes`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MshError {
    /// The file could not be read from disk.
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The first section is not `$MeshFormat`: not an MSH file, or MSH 1 (`$NOD`).
    #[error("{path}: not a gmsh MSH file: the first section must be $MeshFormat, found {found}")]
    MissingMeshFormat { path: PathBuf, found: String },
    /// The version, or the data size of a binary file, is not one we read (4.1 and 2.x,
    /// ASCII or binary with 8-byte `size_t`).
    #[error(
        "{path}: {at}: MSH {format} is not supported (supported: 4.1 and 2.2, ASCII or binary with \
         data size 8); re-export with `gmsh -save -format msh41` or `-format msh22`"
    )]
    UnsupportedVersion {
        path: PathBuf,
        at: Location,
        format: String,
    },
    /// The input ends, or the section's end marker comes, before the records its header
    /// announced. `at` is where the missing record should have been.
    #[error("{path}: {at}: section {section} is truncated: expected {expected}, found {found}")]
    Truncated {
        path: PathBuf,
        at: Location,
        section: String,
        expected: String,
        found: String,
    },
    /// A token that should be a number is not one of the expected kind (a negative count, a
    /// letter in a coordinate, a non-finite coordinate).
    #[error("{path}: {at}: in section {section}: expected {expected}, found '{found}'")]
    MalformedNumber {
        path: PathBuf,
        at: Location,
        section: String,
        expected: String,
        found: String,
    },
    /// Something other than a number is wrong: a missing end marker, an unquoted physical
    /// name, a bad flag or endianness marker.
    #[error("{path}: {at}: in section {section}: expected {expected}, found {found}")]
    Malformed {
        path: PathBuf,
        at: Location,
        section: String,
        expected: String,
        found: String,
    },
    /// The element type is not one fe-model meshes with; `at` is the element's record.
    #[error(
        "{path}: {at}: element {element} has gmsh type {gmsh_type}, which fe-model does not read \
         (supported: 1 line2, 2 tri3, 3 quad4, 4 tet4, 5 hex8, 6 wedge6, 9 tri6, 11 tet10, 16 quad8, \
         17 hex20; 15 points are skipped)"
    )]
    UnsupportedElementType {
        path: PathBuf,
        at: Location,
        element: u64,
        gmsh_type: i32,
    },
    /// An element refers to a node tag that no `$Nodes` section (before it) defines.
    #[error("{path}: {at}: element {element} references node {node}, which is not defined in $Nodes")]
    MissingNode {
        path: PathBuf,
        at: Location,
        element: u64,
        node: u64,
    },
    /// Two nodes have the same tag.
    #[error("{path}: {at}: node {node} is defined twice")]
    DuplicateNode { path: PathBuf, at: Location, node: u64 },
    /// Two elements have the same tag but different types or nodes.
    #[error("{path}: {at}: element {element} is defined twice, with different types or nodes")]
    DuplicateElement { path: PathBuf, at: Location, element: u64 },
    /// A valid MSH feature we do not read (partitioned meshes, more than 2^32 nodes).
    #[error("{path}: {at}: {what} is not supported")]
    UnsupportedFeature { path: PathBuf, at: Location, what: String },
    /// A total of an MSH 4.1 section header (number of nodes or elements, smallest or
    /// largest tag) disagrees with the blocks that follow it; `at` is the header's value.
    #[error("{path}: {at}: in section {section}: the header gives {what} = {header}, but the blocks hold {found}")]
    HeaderMismatch {
        path: PathBuf,
        at: Location,
        section: String,
        what: String,
        header: u64,
        found: u64,
    },
}

/// Reads the gmsh file at `path` (MSH 4.1 or 2.2, ASCII or binary) into a [`Mesh`].
pub fn read(path: &Path) -> Result<Mesh, MshError> {
    let bytes = crate::input::read(path).map_err(|source| MshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(bytes, path)
}

/// Parses the contents of a gmsh file (text or bytes); `origin` names it in errors only.
///
/// See the [module docs](self) for what is read and how physical groups become sets.
pub fn parse(input: impl AsRef<[u8]>, origin: &Path) -> Result<Mesh, MshError> {
    parse_bytes(input.as_ref(), origin)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Version {
    Msh2,
    Msh41,
}

fn parse_bytes(data: &[u8], origin: &Path) -> Result<Mesh, MshError> {
    let mut cur = Cursor::new(data, origin);
    let (version, binary) = read_mesh_format(&mut cur)?;
    let mut builder = Builder::new(origin, cur.locator());
    let mut names = BTreeMap::new();
    let mut entity_groups = HashMap::new();
    while let Some((pos, marker)) = cur.next_section() {
        cur.set_section(&String::from_utf8_lossy(marker));
        match (marker, version) {
            (b"$PhysicalNames", _) => read_physical_names(&mut cur, &mut names)?,
            (b"$Entities", Version::Msh41) => msh4::read_entities(&mut cur, binary, &mut entity_groups)?,
            (b"$Nodes", Version::Msh41) => msh4::read_nodes(&mut cur, binary, &mut builder)?,
            (b"$Elements", Version::Msh41) => msh4::read_elements(&mut cur, binary, &mut builder)?,
            (b"$Nodes", Version::Msh2) => msh2::read_nodes(&mut cur, binary, &mut builder)?,
            (b"$Elements", Version::Msh2) => msh2::read_elements(&mut cur, binary, &mut builder)?,
            (b"$PartitionedEntities", _) => {
                return Err(MshError::UnsupportedFeature {
                    path: origin.to_path_buf(),
                    at: cur.at(pos),
                    what: "a partitioned mesh ($PartitionedEntities; save it unpartitioned)".to_string(),
                })
            }
            _ => cur.skip_section(marker)?,
        }
    }
    let entity_groups = (version == Version::Msh41).then_some(&entity_groups);
    Ok(builder.finish(&names, entity_groups))
}

/// `$MeshFormat`: `version file-type data-size`, then in binary files the `int` 1 that
/// tells the endianness.
fn read_mesh_format(cur: &mut Cursor<'_>) -> Result<(Version, bool), MshError> {
    let path = cur.path();
    let missing = |found: String| MshError::MissingMeshFormat {
        path: path.to_path_buf(),
        found,
    };
    match cur.next_section() {
        None => return Err(missing("no section at all".to_string())),
        Some((_, marker)) if marker == b"$MeshFormat" => {}
        Some((_, marker)) => return Err(missing(format!("'{}'", excerpt(marker)))),
    }
    cur.set_section("$MeshFormat");
    let (version_number, version_pos) = cur.number_at::<f64>("MSH version number, such as 4.1")?;
    let (file_type, file_type_pos) = cur.number_at::<i32>("file type, 0 (ASCII) or 1 (binary)")?;
    let data_size = cur.number::<i32>("data size")?;
    let binary = match file_type {
        0 => false,
        1 => true,
        other => return Err(cur.malformed(file_type_pos, "file type 0 (ASCII) or 1 (binary)", other.to_string())),
    };
    let unsupported = |format: String| MshError::UnsupportedVersion {
        path: cur.path().to_path_buf(),
        at: cur.at(version_pos),
        format,
    };
    let kind = if binary { "binary" } else { "ASCII" };
    // Exact comparisons: the header holds the literal "4.1" or "2.2", and 4.1_f64 is the value
    // both parse to.
    let version = if version_number == 4.1 {
        Version::Msh41
    } else if (2.0..3.0).contains(&version_number) {
        Version::Msh2
    } else {
        return Err(unsupported(format!("{version_number} {kind}")));
    };
    if binary && data_size != 8 {
        return Err(unsupported(format!(
            "{version_number} binary with data size {data_size}"
        )));
    }
    if binary {
        cur.set_binary(true);
        cur.skip_line();
        let marker_pos = cur.pos();
        match cur.raw4("the integer 1 (endianness marker)")? {
            [1, 0, 0, 0] => cur.set_big_endian(false),
            [0, 0, 0, 1] => cur.set_big_endian(true),
            other => {
                return Err(cur.malformed(
                    marker_pos,
                    "the integer 1 in binary (endianness marker)",
                    format!("bytes {other:02x?}"),
                ))
            }
        }
    }
    cur.expect_end("$EndMeshFormat")?;
    Ok((version, binary))
}

/// `$PhysicalNames`: a count, then `dim tag "name"` per line (ASCII in binary files too).
fn read_physical_names(cur: &mut Cursor<'_>, names: &mut BTreeMap<DimTag, String>) -> Result<(), MshError> {
    let n = cur.number::<u64>("number of physical names")?;
    for _ in 0..n {
        let dim = cur.number::<i32>("physical group dimension")?;
        let tag = cur.number::<i32>("physical group tag")?;
        let (start, line) = cur.rest_of_line();
        match line.trim_ascii() {
            [b'"', name @ .., b'"'] => {
                names.insert((dim, tag), String::from_utf8_lossy(name).into_owned());
            }
            other => {
                return Err(cur.malformed(
                    start,
                    "a quoted name such as \"clamp\"",
                    format!("'{}'", excerpt(other)),
                ))
            }
        }
    }
    cur.expect_end("$EndPhysicalNames")
}

/// What a gmsh element type becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GmshElement {
    Cell(CellKind),
    /// gmsh type 15: not a cell, its node still joins the node sets of its groups.
    Point,
}

impl GmshElement {
    fn dimension(self) -> i32 {
        match self {
            GmshElement::Cell(kind) => kind.dimension() as i32,
            GmshElement::Point => 0,
        }
    }
}

/// The element a supported gmsh type becomes, with its node count; `None` if unsupported.
fn gmsh_element(gmsh_type: i32) -> Option<(GmshElement, usize)> {
    if gmsh_type == 15 {
        return Some((GmshElement::Point, 1));
    }
    let kind = cell_kind_from_gmsh_type(gmsh_type)?;
    Some((GmshElement::Cell(kind), kind.node_count()))
}

fn unsupported_element_type(cur: &Cursor<'_>, pos: usize, element: u64, gmsh_type: i32) -> MshError {
    MshError::UnsupportedElementType {
        path: cur.path().to_path_buf(),
        at: cur.at(pos),
        element,
        gmsh_type,
    }
}

/// The [`CellKind`] of a gmsh element type, or `None` if we do not read that type.
pub fn cell_kind_from_gmsh_type(gmsh_type: i32) -> Option<CellKind> {
    Some(match gmsh_type {
        1 => CellKind::Line2,
        2 => CellKind::Tri3,
        3 => CellKind::Quad4,
        4 => CellKind::Tet4,
        5 => CellKind::Hex8,
        6 => CellKind::Wedge6,
        9 => CellKind::Tri6,
        11 => CellKind::Tet10,
        16 => CellKind::Quad8,
        17 => CellKind::Hex20,
        _ => return None,
    })
}

/// The gmsh element type of a [`CellKind`] (for writers and tests).
pub fn gmsh_type(kind: CellKind) -> i32 {
    match kind {
        CellKind::Line2 => 1,
        CellKind::Tri3 => 2,
        CellKind::Quad4 => 3,
        CellKind::Tet4 => 4,
        CellKind::Hex8 => 5,
        CellKind::Wedge6 => 6,
        CellKind::Tri6 => 9,
        CellKind::Tet10 => 11,
        CellKind::Quad8 => 16,
        CellKind::Hex20 => 17,
    }
}

// Our node `i` is gmsh's node `P[i]`. All identities today (our orderings are gmsh's, see the
// module docs); one table per kind so that adopting another convention for one kind is a
// one-line change here.
const LINE2_FROM_GMSH: [usize; 2] = [0, 1];
const TRI3_FROM_GMSH: [usize; 3] = [0, 1, 2];
const QUAD4_FROM_GMSH: [usize; 4] = [0, 1, 2, 3];
const TRI6_FROM_GMSH: [usize; 6] = [0, 1, 2, 3, 4, 5];
const QUAD8_FROM_GMSH: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
const TET4_FROM_GMSH: [usize; 4] = [0, 1, 2, 3];
const TET10_FROM_GMSH: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9];
const HEX8_FROM_GMSH: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
const HEX20_FROM_GMSH: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19];
const WEDGE6_FROM_GMSH: [usize; 6] = [0, 1, 2, 3, 4, 5];

/// Node permutation from gmsh's ordering to ours: our node `i` is gmsh's node
/// `node_permutation_from_gmsh(kind)[i]`. The identity for every kind (see the module docs).
pub fn node_permutation_from_gmsh(kind: CellKind) -> &'static [usize] {
    match kind {
        CellKind::Line2 => &LINE2_FROM_GMSH,
        CellKind::Tri3 => &TRI3_FROM_GMSH,
        CellKind::Quad4 => &QUAD4_FROM_GMSH,
        CellKind::Tri6 => &TRI6_FROM_GMSH,
        CellKind::Quad8 => &QUAD8_FROM_GMSH,
        CellKind::Tet4 => &TET4_FROM_GMSH,
        CellKind::Tet10 => &TET10_FROM_GMSH,
        CellKind::Hex8 => &HEX8_FROM_GMSH,
        CellKind::Hex20 => &HEX20_FROM_GMSH,
        CellKind::Wedge6 => &WEDGE6_FROM_GMSH,
    }
}

/// The nodes of one element, given in gmsh's order, in ours. `gmsh_nodes` has
/// `kind.node_count()` entries (the readers read exactly that many).
fn from_gmsh_order(kind: CellKind, gmsh_nodes: &[NodeId]) -> Vec<NodeId> {
    node_permutation_from_gmsh(kind)
        .iter()
        .filter_map(|&i| gmsh_nodes.get(i).copied())
        .collect()
}
