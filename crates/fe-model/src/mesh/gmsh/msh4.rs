//! The MSH 4.1 sections `$Entities`, `$Nodes` and `$Elements`, ASCII and binary.
//!
//! In MSH 4.1 physical groups live on the entities (`$Entities`: entity → physical tags);
//! nodes and elements come in blocks, one per entity. The layouts follow the gmsh reference
//! manual, "MSH file format version 4.1"; in binary files every `size_t` is 8 bytes and every
//! `int` 4 (checked when the header is read).

use super::builder::{Builder, DimTag};
use super::cursor::Cursor;
use super::{gmsh_element, unsupported_element_type, MshError};
use nalgebra::Point3;
use std::collections::HashMap;

/// Smallest ASCII node record: a tag line and a coordinate line, `"1\n0 0 0\n"`.
const MIN_ASCII_NODE_BYTES: usize = 8;
/// Smallest binary node record: a `size_t` tag and three doubles.
const MIN_BINARY_NODE_BYTES: usize = 32;

/// `$Entities`: records the physical tags of every entity that has some.
pub(super) fn read_entities(
    cur: &mut Cursor<'_>,
    binary: bool,
    entity_groups: &mut HashMap<DimTag, Vec<i32>>,
) -> Result<(), MshError> {
    const WHAT: [&str; 4] = [
        "number of points",
        "number of curves",
        "number of surfaces",
        "number of volumes",
    ];
    if binary {
        cur.skip_line();
    }
    let mut counts = [0u64; 4];
    for (count, what) in counts.iter_mut().zip(WHAT) {
        *count = if binary { cur.size(what)? } else { cur.number(what)? };
    }
    for (dim, &count) in (0i32..).zip(&counts) {
        // A point has its coordinates, other entities their bounding box.
        let box_values: u64 = if dim == 0 { 3 } else { 6 };
        for _ in 0..count {
            let (tag, physicals) = if binary {
                let tag = cur.int("entity tag")?;
                cur.skip_binary(box_values, 8, "bounding-box coordinates")?;
                let n = cur.size("number of physical tags")?;
                cur.ensure_binary(n, 4, "physical tags")?;
                let physicals = (0..n)
                    .map(|_| cur.int("physical tag"))
                    .collect::<Result<Vec<i32>, _>>()?;
                if dim > 0 {
                    let bounding = cur.size("number of bounding entities")?;
                    cur.skip_binary(bounding, 4, "bounding entity tags")?;
                }
                (tag, physicals)
            } else {
                let tag = cur.number::<i32>("entity tag")?;
                for _ in 0..box_values {
                    cur.number::<f64>("bounding-box coordinate")?;
                }
                let n = cur.number::<u64>("number of physical tags")?;
                let mut physicals = Vec::with_capacity(cur.capacity(n, 2));
                for _ in 0..n {
                    physicals.push(cur.number::<i32>("physical tag")?);
                }
                if dim > 0 {
                    let bounding = cur.number::<u64>("number of bounding entities")?;
                    for _ in 0..bounding {
                        cur.number::<i32>("bounding entity tag")?;
                    }
                }
                (tag, physicals)
            };
            if !physicals.is_empty() {
                entity_groups.insert((dim, tag), physicals);
            }
        }
    }
    cur.expect_end("$EndEntities")
}

/// Number of parametric coordinates after x, y, z of each node of a block: one per dimension
/// of the entity when the block is parametric.
fn parametric_count(cur: &Cursor<'_>, dim: (i32, usize), parametric: (i32, usize)) -> Result<u64, MshError> {
    let dimension = match dim.0 {
        0..=3 => dim.0 as u64,
        other => return Err(cur.malformed(dim.1, "entity dimension 0, 1, 2 or 3", other.to_string())),
    };
    match parametric.0 {
        0 => Ok(0),
        1 => Ok(dimension),
        other => Err(cur.malformed(parametric.1, "parametric flag 0 or 1", other.to_string())),
    }
}

/// The totals of a `$Nodes` or `$Elements` header with the position of each value:
/// the number of records, the smallest and the largest tag.
struct Header {
    total: (u64, usize),
    min: (u64, usize),
    max: (u64, usize),
}

/// The records of the blocks as read: their number and the range of their tags.
#[derive(Default)]
struct Seen {
    count: u64,
    min: u64,
    max: u64,
}

impl Seen {
    fn add(&mut self, tag: u64) {
        if self.count == 0 {
            (self.min, self.max) = (tag, tag);
        } else {
            self.min = self.min.min(tag);
            self.max = self.max.max(tag);
        }
        self.count += 1;
    }
}

impl Header {
    /// Reads the three totals after the number of blocks.
    fn read(cur: &mut Cursor<'_>, binary: bool, what: &str) -> Result<Self, MshError> {
        let value = |cur: &mut Cursor<'_>, expected: &str| -> Result<(u64, usize), MshError> {
            if binary {
                let pos = cur.pos();
                Ok((cur.size(expected)?, pos))
            } else {
                cur.number_at::<u64>(expected)
            }
        };
        Ok(Self {
            total: value(cur, &format!("number of {what}s"))?,
            min: value(cur, &format!("minimum {what} tag"))?,
            max: value(cur, &format!("maximum {what} tag"))?,
        })
    }

    /// The header's totals against the blocks (gmsh writes them exactly; a file whose totals
    /// disagree was edited or cut, and its blocks cannot be trusted either). The tag range is
    /// checked when the section holds records.
    fn check(&self, cur: &Cursor<'_>, what: &str, seen: &Seen) -> Result<(), MshError> {
        if self.total.0 != seen.count {
            return Err(cur.header_mismatch(
                self.total.1,
                &format!("the number of {what}s"),
                self.total.0,
                seen.count,
            ));
        }
        if seen.count > 0 {
            if self.min.0 != seen.min {
                return Err(cur.header_mismatch(self.min.1, &format!("the smallest {what} tag"), self.min.0, seen.min));
            }
            if self.max.0 != seen.max {
                return Err(cur.header_mismatch(self.max.1, &format!("the largest {what} tag"), self.max.0, seen.max));
            }
        }
        Ok(())
    }
}

/// `$Nodes`: entity blocks of node tags followed by their coordinates.
pub(super) fn read_nodes(cur: &mut Cursor<'_>, binary: bool, builder: &mut Builder<'_>) -> Result<(), MshError> {
    let mut seen = Seen::default();
    let header = if binary {
        cur.skip_line();
        let blocks = cur.size("number of entity blocks")?;
        let header = Header::read(cur, true, "node")?;
        builder.reserve_nodes(cur.capacity(header.total.0, MIN_BINARY_NODE_BYTES));
        for _ in 0..blocks {
            let dim = (cur.int("entity dimension")?, cur.pos() - 4);
            cur.int("entity tag")?;
            let parametric = (cur.int("parametric flag")?, cur.pos() - 4);
            let n = cur.size("number of nodes in the block")?;
            let parameters = parametric_count(cur, dim, parametric)?;
            // Tags and coordinates of the whole block must fit before anything is allocated.
            let record = 8 * (4 + parameters as usize);
            cur.ensure_binary(n, record, "node records (tag and coordinates)")?;
            let tags_start = cur.pos();
            let tags = (0..n).map(|_| cur.size("node tag")).collect::<Result<Vec<u64>, _>>()?;
            for (i, &tag) in tags.iter().enumerate() {
                seen.add(tag);
                let x = cur.binary_coordinate("x coordinate")?;
                let y = cur.binary_coordinate("y coordinate")?;
                let z = cur.binary_coordinate("z coordinate")?;
                cur.skip_binary(parameters, 8, "parametric coordinates")?;
                builder.add_node(tag, Point3::new(x, y, z), tags_start + 8 * i)?;
            }
        }
        header
    } else {
        let blocks = cur.number::<u64>("number of entity blocks")?;
        let header = Header::read(cur, false, "node")?;
        builder.reserve_nodes(cur.capacity(header.total.0, MIN_ASCII_NODE_BYTES));
        let mut tags = Vec::new();
        for _ in 0..blocks {
            let dim = cur.number_at::<i32>("entity dimension")?;
            cur.number::<i32>("entity tag")?;
            let parametric = cur.number_at::<i32>("parametric flag (0 or 1)")?;
            let n = cur.number::<u64>("number of nodes in the block")?;
            let parameters = parametric_count(cur, dim, parametric)?;
            tags.clear();
            tags.reserve(cur.capacity(n, 2));
            for _ in 0..n {
                tags.push(cur.number_at::<u64>("node tag")?);
            }
            for &(tag, pos) in &tags {
                seen.add(tag);
                let x = cur.coordinate("x coordinate")?;
                let y = cur.coordinate("y coordinate")?;
                let z = cur.coordinate("z coordinate")?;
                for _ in 0..parameters {
                    cur.number::<f64>("parametric coordinate")?;
                }
                builder.add_node(tag, Point3::new(x, y, z), pos)?;
            }
        }
        header
    };
    header.check(cur, "node", &seen)?;
    cur.expect_end("$EndNodes")
}

/// `$Elements`: entity blocks of one element type each; every element joins its entity.
pub(super) fn read_elements(cur: &mut Cursor<'_>, binary: bool, builder: &mut Builder<'_>) -> Result<(), MshError> {
    let mut node_tags = Vec::new();
    let mut seen = Seen::default();
    let header = if binary {
        cur.skip_line();
        let blocks = cur.size("number of entity blocks")?;
        let header = Header::read(cur, true, "element")?;
        for _ in 0..blocks {
            let dim = cur.int("entity dimension")?;
            let entity = cur.int("entity tag")?;
            let gmsh_type = cur.int("element type")?;
            let n = cur.size("number of elements in the block")?;
            let Some((element, node_count)) = gmsh_element(gmsh_type) else {
                if n == 0 {
                    continue;
                }
                let pos = cur.pos();
                let tag = cur.size("element tag")?;
                return Err(unsupported_element_type(cur, pos, tag, gmsh_type));
            };
            cur.ensure_binary(n, 8 * (1 + node_count), "element records (tag and nodes)")?;
            for _ in 0..n {
                let pos = cur.pos();
                let tag = cur.size("element tag")?;
                seen.add(tag);
                node_tags.clear();
                for _ in 0..node_count {
                    node_tags.push(cur.size("node tag")?);
                }
                builder.add_element(tag, element, &node_tags, pos, Some((dim, entity)))?;
            }
        }
        header
    } else {
        let blocks = cur.number::<u64>("number of entity blocks")?;
        let header = Header::read(cur, false, "element")?;
        for _ in 0..blocks {
            let dim = cur.number::<i32>("entity dimension")?;
            let entity = cur.number::<i32>("entity tag")?;
            let gmsh_type = cur.number::<i32>("element type")?;
            let n = cur.number::<u64>("number of elements in the block")?;
            let Some((element, node_count)) = gmsh_element(gmsh_type) else {
                if n == 0 {
                    continue;
                }
                let (tag, pos) = cur.number_at::<u64>("element tag")?;
                return Err(unsupported_element_type(cur, pos, tag, gmsh_type));
            };
            for _ in 0..n {
                let (tag, pos) = cur.number_at::<u64>("element tag")?;
                seen.add(tag);
                node_tags.clear();
                for _ in 0..node_count {
                    node_tags.push(cur.number::<u64>("node tag")?);
                }
                builder.add_element(tag, element, &node_tags, pos, Some((dim, entity)))?;
            }
        }
        header
    };
    header.check(cur, "element", &seen)?;
    cur.expect_end("$EndElements")
}
