//! A small writer for ParaView: VTK XML UnstructuredGrid files (`.vtu`, ASCII) with the mesh
//! and nodal fields, and `.pvd` collections that list several of them (the modes of a modal
//! analysis, the shapes of a reduced body) as steps.
//!
//! # Cells and node orders
//!
//! | our kind | VTK cell | VTK type | node order |
//! |---|---|---|---|
//! | `Line2`, beam elements | `VTK_LINE` | 3 | same |
//! | `Tri3` | `VTK_TRIANGLE` | 5 | same |
//! | `Quad4` | `VTK_QUAD` | 9 | same |
//! | `Tet4` | `VTK_TETRA` | 10 | same |
//! | `Hex8` | `VTK_HEXAHEDRON` | 12 | same |
//! | `Wedge6` | `VTK_WEDGE` | 13 | same (VTK 9.7 and later; see below) |
//! | `Tri6` | `VTK_QUADRATIC_TRIANGLE` | 22 | same |
//! | `Quad8` | `VTK_QUADRATIC_QUAD` | 23 | same |
//! | `Tet10` | `VTK_QUADRATIC_TETRA` | 24 | nodes 8 and 9 swapped |
//! | `Hex20` | `VTK_QUADRATIC_HEXAHEDRON` | 25 | mid-edge nodes reordered, see [`HEX20_TO_VTK`] |
//! | interface node | `VTK_VERTEX` | 1 | |
//!
//! Our node orders are gmsh's (`fe_model::mesh::gmsh`). VTK's are defined by the parametric
//! coordinates of its cell classes (`GetParametricCoords` of `vtkTetra`, `vtkHexahedron`,
//! `vtkQuadraticTetra`, `vtkQuadraticHexahedron`, `vtkWedge`). The tests in `tests/cli.rs`
//! map our reference nodes through each permutation and compare them with those coordinates,
//! one test per cell type; the files were also read back with VTK 9.7.2 (Python `vtk`), whose
//! Cell Size filter gives every element its positive volume and whose quadratic edges have
//! their middle nodes at the midpoints.
//!
//! The wedge needs care: VTK's documentation used to say that the normal of triangle
//! (0, 1, 2) points *away* from triangle (3, 4, 5), the opposite of gmsh, and converters
//! reversed the triangles for it (meshio, pull request 863); VTK has since made its
//! documentation, parametric coordinates and volumes agree with gmsh's order ("(0, 2, 1) is
//! the base ... whose normal points away from the triangular face (3, 4, 5)", vtkWedge in VTK
//! 9.7). We write gmsh's order, which VTK 9.7 reads with positive volumes; older ParaView
//! versions show these wedges with negative volume (their shading is unaffected).
//!
//! ASCII rather than appended raw binary: the files are read by ParaView either way, ASCII
//! can be checked by eye and by tests, and the meshes this tool writes are small next to the
//! cost of the analyses that produce them.

use std::fmt::Write as _;
use std::path::Path;

pub use crate::mesh::{vtk_cell, CellRole, VtuMesh, HEX20_TO_VTK, TET10_TO_VTK};

/// A nodal field: name, components per node, values node by node.
pub struct PointField<'a> {
    pub name: &'a str,
    pub components: usize,
    pub values: &'a [f64],
}

/// The fields `displacement` and `rotation` of a frame, three components a node each.
pub fn motion_fields<'a>(displacement: &'a [f64], rotation: &'a [f64]) -> [PointField<'a>; 2] {
    [
        PointField {
            name: "displacement",
            components: 3,
            values: displacement,
        },
        PointField {
            name: "rotation",
            components: 3,
            values: rotation,
        },
    ]
}

/// The stress fields of a frame: `stress` (six components a node), `von_mises` and
/// `max_principal` (one each).
pub fn stress_fields<'a>(tensor: &'a [f64], von_mises: &'a [f64], principal: &'a [f64]) -> [PointField<'a>; 3] {
    [
        PointField {
            name: "stress",
            components: 6,
            values: tensor,
        },
        PointField {
            name: "von_mises",
            components: 1,
            values: von_mises,
        },
        PointField {
            name: "max_principal",
            components: 1,
            values: principal,
        },
    ]
}

/// The two vector fields of six-dof nodal values: `displacement` and `rotation`.
pub fn six_dof_fields(values: &[[f64; 6]]) -> (Vec<f64>, Vec<f64>) {
    let u = values.iter().flat_map(|v| [v[0], v[1], v[2]]).collect();
    let r = values.iter().flat_map(|v| [v[3], v[4], v[5]]).collect();
    (u, r)
}

fn push_values(out: &mut String, values: impl Iterator<Item = String>, per_line: usize) {
    for (i, v) in values.enumerate() {
        if i % per_line == 0 {
            out.push_str("\n          ");
        } else {
            out.push(' ');
        }
        out.push_str(&v);
    }
    out.push_str("\n        ");
}

/// A finite value as VTK reads it (shortest round-trip decimal); NaN and infinities, which
/// ParaView's XML reader rejects, become 0 (a failed analysis writes no file, so they do
/// not occur in practice).
fn number(x: f64) -> String {
    if x.is_finite() {
        format!("{x:e}")
    } else {
        "0".to_string()
    }
}

/// The text of a `.vtu` file.
pub fn vtu_text(mesh: &VtuMesh, fields: &[PointField<'_>]) -> String {
    let mut s = String::new();
    let n = mesh.points.len();
    let _ = write!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{}\">\n",
        mesh.cells.len()
    );
    if !fields.is_empty() {
        s.push_str("      <PointData>\n");
        for f in fields {
            let _ = write!(
                s,
                "        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">",
                f.name, f.components
            );
            push_values(&mut s, f.values.iter().map(|&x| number(x)), 3 * f.components.max(1));
            s.push_str("</DataArray>\n");
        }
        s.push_str("      </PointData>\n");
    }
    s.push_str("      <CellData>\n        <DataArray type=\"Int32\" Name=\"kind\" format=\"ascii\">");
    push_values(&mut s, mesh.cells.iter().map(|c| (c.2 as i32).to_string()), 20);
    s.push_str("</DataArray>\n      </CellData>\n");
    s.push_str("      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">");
    push_values(&mut s, mesh.points.iter().flat_map(|p| p.map(number)), 3);
    s.push_str("</DataArray>\n      </Points>\n      <Cells>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">");
    push_values(
        &mut s,
        mesh.cells.iter().flat_map(|c| c.1.iter().map(|i| i.to_string())),
        20,
    );
    s.push_str("</DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">");
    let mut offset = 0;
    push_values(
        &mut s,
        mesh.cells.iter().map(|c| {
            offset += c.1.len();
            offset.to_string()
        }),
        20,
    );
    s.push_str("</DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">");
    push_values(&mut s, mesh.cells.iter().map(|c| c.0.to_string()), 20);
    s.push_str("</DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// Writes a `.vtu` file.
pub fn write_vtu(path: &Path, mesh: &VtuMesh, fields: &[PointField<'_>]) -> std::io::Result<()> {
    crate::output::summary::write_atomic(path, vtu_text(mesh, fields).as_bytes())
}

/// Writes a `.pvd` collection: each entry a step value and a file name relative to the
/// collection.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> std::io::Result<()> {
    crate::output::summary::write_atomic(path, pvd_text(entries).as_bytes())
}

/// The text of a `.pvd` collection ([`write_pvd`]).
pub fn pvd_text(entries: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (step, file) in entries {
        let _ = writeln!(
            s,
            "    <DataSet timestep=\"{step}\" group=\"\" part=\"0\" file=\"{file}\"/>"
        );
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    s
}
