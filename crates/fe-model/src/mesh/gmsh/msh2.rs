//! The MSH 2.2 sections `$Nodes` and `$Elements`, ASCII and binary.
//!
//! In MSH 2.2 every element carries its tags: the first is its physical group (0 for none),
//! the second its elementary entity. An element in several physical groups is written once
//! per group with the same tag; the builder merges the copies. The layouts follow the gmsh
//! reference manual, "MSH file format version 2 (Legacy)"; in binary files the counts are
//! ASCII lines, tags and node numbers are 4-byte `int`s, coordinates 8-byte doubles.

use super::builder::Builder;
use super::cursor::Cursor;
use super::{gmsh_element, unsupported_element_type, MshError};
use nalgebra::Point3;

/// Smallest ASCII node record, `"1 0 0 0\n"`.
const MIN_ASCII_NODE_BYTES: usize = 8;
/// Binary node record: an `int` tag and three doubles.
const BINARY_NODE_BYTES: usize = 4 + 3 * 8;

/// `$Nodes`: a count, then tag and coordinates per node.
pub(super) fn read_nodes(cur: &mut Cursor<'_>, binary: bool, builder: &mut Builder<'_>) -> Result<(), MshError> {
    let n = cur.number::<u64>("number of nodes")?;
    if binary {
        cur.skip_line();
        cur.ensure_binary(n, BINARY_NODE_BYTES, "node records (tag and coordinates)")?;
        builder.reserve_nodes(cur.capacity(n, BINARY_NODE_BYTES));
        for _ in 0..n {
            let pos = cur.pos();
            let tag = cur.int_unsigned("node tag")?;
            let x = cur.binary_coordinate("x coordinate")?;
            let y = cur.binary_coordinate("y coordinate")?;
            let z = cur.binary_coordinate("z coordinate")?;
            builder.add_node(tag, Point3::new(x, y, z), pos)?;
        }
    } else {
        builder.reserve_nodes(cur.capacity(n, MIN_ASCII_NODE_BYTES));
        for _ in 0..n {
            let (tag, pos) = cur.number_at::<u64>("node tag")?;
            let x = cur.coordinate("x coordinate")?;
            let y = cur.coordinate("y coordinate")?;
            let z = cur.coordinate("z coordinate")?;
            builder.add_node(tag, Point3::new(x, y, z), pos)?;
        }
    }
    cur.expect_end("$EndNodes")
}

/// `$Elements`: a count, then per element its tag, type, tags and nodes (ASCII: one line
/// each; binary: blocks of elements of one type behind a three-`int` header).
pub(super) fn read_elements(cur: &mut Cursor<'_>, binary: bool, builder: &mut Builder<'_>) -> Result<(), MshError> {
    let n = cur.number::<u64>("number of elements")?;
    let mut node_tags = Vec::new();
    if binary {
        cur.skip_line();
        let mut read = 0u64;
        // Each header consumes 12 bytes, so a corrupt header cannot loop without reaching the
        // end of the input.
        while read < n {
            let gmsh_type = cur.int("element type")?;
            let following = cur.int_unsigned("number of elements following")?;
            let tag_count = cur.int_unsigned("number of tags")?;
            let Some((element, node_count)) = gmsh_element(gmsh_type) else {
                if following == 0 {
                    continue;
                }
                let pos = cur.pos();
                let tag = cur.int_unsigned("element tag")?;
                return Err(unsupported_element_type(cur, pos, tag, gmsh_type));
            };
            // An overflowing record size cannot fit in the input: `ensure_binary` reports it.
            let record = usize::try_from(tag_count)
                .ok()
                .and_then(|tags| tags.checked_add(1 + node_count))
                .and_then(|ints| ints.checked_mul(4))
                .unwrap_or(usize::MAX);
            cur.ensure_binary(following, record, "element records (tag, tags and nodes)")?;
            for _ in 0..following {
                let pos = cur.pos();
                let tag = cur.int_unsigned("element tag")?;
                let mut physical = 0;
                for i in 0..tag_count {
                    let value = cur.int("element tag value")?;
                    if i == 0 {
                        physical = value;
                    }
                }
                node_tags.clear();
                for _ in 0..node_count {
                    node_tags.push(cur.int_unsigned("node tag")?);
                }
                let group = (physical != 0).then_some((element.dimension(), physical));
                builder.add_element(tag, element, &node_tags, pos, group)?;
            }
            read = read.saturating_add(following);
        }
    } else {
        for _ in 0..n {
            let (tag, pos) = cur.number_at::<u64>("element tag")?;
            let gmsh_type = cur.number::<i32>("element type")?;
            let Some((element, node_count)) = gmsh_element(gmsh_type) else {
                return Err(unsupported_element_type(cur, pos, tag, gmsh_type));
            };
            let tag_count = cur.number::<u64>("number of tags")?;
            let mut physical = 0;
            for i in 0..tag_count {
                let value = cur.number::<i32>("element tag value (integer)")?;
                if i == 0 {
                    physical = value;
                }
            }
            node_tags.clear();
            for _ in 0..node_count {
                node_tags.push(cur.number::<u64>("node tag")?);
            }
            let group = (physical != 0).then_some((element.dimension(), physical));
            builder.add_element(tag, element, &node_tags, pos, group)?;
        }
    }
    cur.expect_end("$EndElements")
}
