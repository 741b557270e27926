//! Element geometry checked on the mesh, before any matrix: an inverted or degenerate solid
//! element is named by its label in the mesh file (the deck's element number, gmsh's element
//! tag), not by its position in the model, so that a user can find it.
//!
//! The test is the one the element matrices make ([`solid::check_jacobians`]): $\det\mathbf J$
//! above $10^{-12}\,h^3$ at every point of the stiffness and mass rules.

use super::Mesh;
use crate::element::solid::{self, SolidKind};
use crate::error::ElementError;
use nalgebra::Point3;
use thiserror::Error;

/// A solid element whose geometry cannot give matrices, by its label in the mesh file.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum CellGeometryError {
    /// $\det\mathbf J < 0$: the element's nodes are in mirrored order (or the element is
    /// folded over itself).
    #[error("element {label} ({kind}) is inverted: det J = {det_j:.3e} < 0 at quadrature point {point} (its nodes are in mirrored order, or it folds over itself)")]
    Inverted {
        label: u64,
        kind: &'static str,
        point: usize,
        det_j: f64,
    },
    /// $\det\mathbf J$ at round-off of the element's size (coincident or coplanar corners),
    /// or not a number (a non-finite coordinate).
    #[error("element {label} ({kind}) is degenerate: det J = {det_j:.3e} at quadrature point {point}, at round-off of its size (coincident or coplanar corners)")]
    Degenerate {
        label: u64,
        kind: &'static str,
        point: usize,
        det_j: f64,
    },
}

/// The first solid cell of `mesh` (in file order) that is inverted or degenerate. Cells
/// with a node outside the mesh or a wrong node count are left to the model builder, which
/// reports them with their own errors.
pub fn check_solid_cells(mesh: &Mesh) -> Result<(), CellGeometryError> {
    let mut X_e: Vec<Point3<f64>> = Vec::new();
    for cell in &mesh.cells {
        let Some(kind) = SolidKind::from_cell_kind(cell.kind) else {
            continue;
        };
        X_e.clear();
        for node in &cell.nodes {
            match mesh.nodes.get(node.index()) {
                Some(x) => X_e.push(*x),
                None => break,
            }
        }
        if X_e.len() != cell.nodes.len() {
            continue;
        }
        if let Err(ElementError::NonPositiveJacobian { point, det_j, .. }) = solid::check_jacobians(kind, 0, &X_e) {
            let (label, kind) = (cell.tag, kind.name());
            return Err(if det_j < 0.0 {
                CellGeometryError::Inverted {
                    label,
                    kind,
                    point,
                    det_j,
                }
            } else {
                CellGeometryError::Degenerate {
                    label,
                    kind,
                    point,
                    det_j,
                }
            });
        }
    }
    Ok(())
}
