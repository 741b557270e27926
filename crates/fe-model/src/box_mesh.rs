//! Structured meshes of a box $[0, L_x] \times [0, L_y] \times [0, L_z]$ with any solid kind,
//! and the step from a [`Mesh`] to a solid [`FeModel`].
//!
//! # How the box is cut
//!
//! The box is divided into $n_x \times n_y \times n_z$ equal cells (bricks). Each brick is one
//! hex8 or hex20; or six tetrahedra (the Kuhn/Freudenthal split: the tets
//! $\mathbf v_0 \to \mathbf v_0 + \mathbf e_{\pi_1} \to \ldots \to \mathbf v_0 + (1,1,1)$ for
//! the six permutations $\pi$ of the axes, all sharing the brick's main diagonal); or two wedges
//! (the brick's $z = $ const faces cut along the diagonal from its $(x_0, y_0)$ corner to its
//! $(x_1, y_1)$ corner, then extruded in $z$). Every brick is cut the same way, so the cut of a
//! shared brick face is the same seen from both sides: the meshes are conforming.
//!
//! ```text
//!   one brick, z = const face, wedges:     Kuhn split, the six tets share the diagonal
//!     (0,1) +-------+ (1,1)                 (0,0,0) -> (1,1,1); each face is cut along
//!           |     / |                       its diagonal from the lowest to the highest
//!           |   /   |                       corner
//!           | /     |
//!     (0,0) +-------+ (1,0)
//! ```
//!
//! Nodes live on a grid of half-cell spacing (so that quadratic kinds find their edge nodes);
//! only the grid points that some cell uses become nodes, numbered with $x$ fastest, then $y$,
//! then $z$. Node sets: `"x0"`, `"x1"`, `"y0"`, `"y1"`, `"z0"`, `"z1"` (the nodes on the faces
//! $x = 0$, $x = L_x$, ...); cell set `"volume"` (all cells).

use crate::element::{hex20, hex8, tet10};
use crate::element::{MassKind, Solid, SolidKind};
use crate::error::FeError;
use crate::mesh::{CellKind, Mesh, NodeId};
use crate::model::FeModel;
use crate::property::{IsotropicMaterial, MaterialId};
use nalgebra::Point3;
use std::collections::BTreeMap;

/// A structured box mesh of `kind` cells (see the module docs for how bricks are cut and what
/// sets are made).
///
/// Sizes come from study files, so bad ones are errors, not panics: a kind that is not a
/// solid, a zero division count, or a length that is not positive and finite.
pub fn box_mesh(kind: CellKind, lengths: [f64; 3], divisions: [usize; 3]) -> Result<Mesh, FeError> {
    let bad = |what: String| FeError::Generator {
        generator: "box_mesh",
        what,
    };
    let solid = SolidKind::from_cell_kind(kind).ok_or_else(|| bad(format!("needs a solid cell kind, got {kind:?}")))?;
    if !divisions.iter().all(|&d| d > 0) {
        return Err(bad(format!("every division count must be >= 1, got {divisions:?}")));
    }
    if !lengths.iter().all(|&l| l > 0.0 && l.is_finite()) {
        return Err(bad(format!(
            "every length must be positive and finite, got {lengths:?}"
        )));
    }
    let [nx, ny, nz] = divisions;
    // Cells as lists of points on the half-spacing grid, G in 0..=2n per axis.
    let mut cells: Vec<Vec<[usize; 3]>> = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let o = [2 * i, 2 * j, 2 * k];
                match solid {
                    SolidKind::Hex8 => cells.push(hex_cell(o, &hex8::REFERENCE_NODES)),
                    SolidKind::Hex20 => cells.push(hex_cell(o, &hex20::REFERENCE_NODES)),
                    SolidKind::Tet4 | SolidKind::Tet10 => {
                        for corners in kuhn_tets() {
                            let c = corners.map(|v| [o[0] + v[0], o[1] + v[1], o[2] + v[2]]);
                            let mut cell = c.to_vec();
                            if solid == SolidKind::Tet10 {
                                for (a, b) in tet10::EDGES {
                                    cell.push([
                                        (c[a][0] + c[b][0]) / 2,
                                        (c[a][1] + c[b][1]) / 2,
                                        (c[a][2] + c[b][2]) / 2,
                                    ]);
                                }
                            }
                            cells.push(cell);
                        }
                    }
                    SolidKind::Wedge6 => {
                        // Both triangles anticlockwise about +z, so det J > 0 with zeta along +z.
                        for tri in [[[0, 0], [2, 0], [2, 2]], [[0, 0], [2, 2], [0, 2]]] {
                            let mut cell = Vec::with_capacity(6);
                            for dz in [0, 2] {
                                for v in tri {
                                    cell.push([o[0] + v[0], o[1] + v[1], o[2] + dz]);
                                }
                            }
                            cells.push(cell);
                        }
                    }
                }
            }
        }
    }
    // Number the used grid points with x fastest.
    let (gx, gy, gz) = (2 * nx + 1, 2 * ny + 1, 2 * nz + 1);
    let flat = |g: &[usize; 3]| g[0] + gx * (g[1] + gy * g[2]);
    let mut used = vec![false; gx * gy * gz];
    for g in cells.iter().flatten() {
        used[flat(g)] = true;
    }
    let mut mesh = Mesh::default();
    let mut id = vec![u32::MAX; used.len()];
    let h = [
        lengths[0] / (2 * nx) as f64,
        lengths[1] / (2 * ny) as f64,
        lengths[2] / (2 * nz) as f64,
    ];
    let mut sets: BTreeMap<&str, Vec<NodeId>> = BTreeMap::new();
    for gk in 0..gz {
        for gj in 0..gy {
            for gi in 0..gx {
                let f = flat(&[gi, gj, gk]);
                if !used[f] {
                    continue;
                }
                let x = Point3::new(gi as f64 * h[0], gj as f64 * h[1], gk as f64 * h[2]);
                let node = mesh.add_node(x);
                id[f] = node.0;
                for (name, on) in [
                    ("x0", gi == 0),
                    ("x1", gi == gx - 1),
                    ("y0", gj == 0),
                    ("y1", gj == gy - 1),
                    ("z0", gk == 0),
                    ("z1", gk == gz - 1),
                ] {
                    if on {
                        sets.entry(name).or_default().push(node);
                    }
                }
            }
        }
    }
    for (name, nodes) in sets {
        mesh.add_to_node_set(name, nodes);
    }
    let mut all = Vec::with_capacity(cells.len());
    for cell in &cells {
        let nodes = cell.iter().map(|g| NodeId(id[flat(g)])).collect();
        all.push(mesh.add_cell(kind, nodes));
    }
    mesh.cell_sets.insert("volume".to_string(), all);
    Ok(mesh)
}

/// The grid points of the hexahedron with lowest corner `o` (half-spacing grid) for reference
/// nodes in $[-1, 1]^3$: grid index $o + \xi + 1$.
fn hex_cell(o: [usize; 3], reference: &[[f64; 3]]) -> Vec<[usize; 3]> {
    reference
        .iter()
        .map(|r| {
            let g = |k: usize| o[k] + (r[k] + 1.0).round() as usize;
            [g(0), g(1), g(2)]
        })
        .collect()
}

/// The six Kuhn tetrahedra of the brick $[0, 2]^3$ (half-spacing units), each positively
/// oriented.
fn kuhn_tets() -> [[[usize; 3]; 4]; 6] {
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    perms.map(|p| {
        let mut v = [[0usize; 3]; 4];
        for s in 1..4 {
            v[s] = v[s - 1];
            v[s][p[s - 1]] += 2;
        }
        // An odd permutation gives a negatively oriented tet; swapping two vertices fixes it.
        let d = |a: usize, k: usize| v[a][k] as f64 - v[0][k] as f64;
        let det = d(1, 0) * (d(2, 1) * d(3, 2) - d(2, 2) * d(3, 1)) - d(1, 1) * (d(2, 0) * d(3, 2) - d(2, 2) * d(3, 0))
            + d(1, 2) * (d(2, 0) * d(3, 1) - d(2, 1) * d(3, 0));
        if det < 0.0 {
            v.swap(1, 2);
        }
        v
    })
}

/// A solid model from a mesh: every 3D cell becomes a solid element of its kind with
/// `material` and `mass`; line and face cells are kept in the mesh but make no elements.
///
/// # Errors
/// [`FeError::UnknownNode`] if a cell refers to a node the mesh does not have.
pub fn solid_model(mesh: Mesh, material: IsotropicMaterial, mass: MassKind) -> Result<FeModel, FeError> {
    check_cell_nodes(&mesh)?;
    let mut model = FeModel {
        mesh,
        ..FeModel::default()
    };
    let id = model.add_material(material);
    let elements = model
        .mesh
        .cells
        .iter()
        .filter_map(|c| SolidKind::from_cell_kind(c.kind).map(|k| (k, c.nodes.clone())))
        .map(|(k, nodes)| {
            crate::element::Element::new_solid(
                k,
                Solid {
                    nodes,
                    material: id,
                    mass,
                },
            )
        })
        .collect::<Vec<_>>();
    model.elements.extend(elements);
    Ok(model)
}

/// A solid model from a mesh with one material per named cell set (gmsh physical volume):
/// `materials` pairs a cell-set name with its material. Every 3D cell must lie in exactly one
/// of the named sets; non-3D cells in the sets are ignored.
///
/// # Errors
/// [`FeError::UnknownCellSet`] naming a set the mesh does not have (with the known ones);
/// [`FeError::CellMaterial`] for a 3D cell in none or in two of the sets;
/// [`FeError::UnknownNode`] for a cell that refers to a missing node.
pub fn solid_model_with_materials(
    mesh: Mesh,
    materials: &[(&str, IsotropicMaterial)],
    mass: MassKind,
) -> Result<FeModel, FeError> {
    const CONTEXT: &str = "solid model with materials per cell set";
    check_cell_nodes(&mesh)?;
    let mut assigned: Vec<Option<(MaterialId, usize)>> = vec![None; mesh.cells.len()];
    let mut model = FeModel {
        mesh,
        ..FeModel::default()
    };
    for (s, (name, material)) in materials.iter().enumerate() {
        let cells = model
            .mesh
            .cell_sets
            .get(*name)
            .cloned()
            .ok_or_else(|| FeError::UnknownCellSet {
                context: CONTEXT.to_string(),
                name: name.to_string(),
                known: model.mesh.cell_sets.keys().cloned().collect::<Vec<_>>().join(", "),
            })?;
        let id = model.add_material(material.clone());
        for c in cells {
            let cell = &model.mesh.cells[c.index()];
            if cell.kind.dimension() != 3 {
                continue;
            }
            if let Some((_, first)) = assigned[c.index()] {
                return Err(FeError::CellMaterial {
                    context: CONTEXT.to_string(),
                    cell_tag: cell.tag,
                    kind: SolidKind::from_cell_kind(cell.kind).map_or("cell", |k| k.name()),
                    why: format!("is in both cell sets '{}' and '{name}'", materials[first].0),
                });
            }
            assigned[c.index()] = Some((id, s));
        }
    }
    for (c, cell) in model.mesh.cells.iter().enumerate() {
        let Some(kind) = SolidKind::from_cell_kind(cell.kind) else {
            continue;
        };
        let Some((material, _)) = assigned[c] else {
            return Err(FeError::CellMaterial {
                context: CONTEXT.to_string(),
                cell_tag: cell.tag,
                kind: kind.name(),
                why: format!(
                    "is in none of the cell sets given a material ({})",
                    materials
                        .iter()
                        .map(|m| format!("'{}'", m.0))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        };
        let solid = Solid {
            nodes: cell.nodes.clone(),
            material,
            mass,
        };
        model.elements.push(crate::element::Element::new_solid(kind, solid));
    }
    Ok(model)
}

fn check_cell_nodes(mesh: &Mesh) -> Result<(), FeError> {
    for cell in &mesh.cells {
        if let Some(&node) = cell.nodes.iter().find(|n| n.index() >= mesh.nodes.len()) {
            return Err(FeError::UnknownNode {
                context: format!("cell {}", cell.tag),
                node,
                count: mesh.nodes.len(),
            });
        }
    }
    Ok(())
}
