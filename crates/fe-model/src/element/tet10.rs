//! 10-node quadratic tetrahedron.
//!
//! # Node ordering (gmsh's, used as ours)
//!
//! ```text
//!            2
//!          ,/|`\
//!        ,/  |  `\
//!      ,6    '.   `5
//!    ,/       8     `\
//!  ,/         |       `\
//! 0--------4--'.--------1
//!  `\.         |      ,/
//!     `\.      |    ,9
//!        `7.   '. ,/
//!           `\. |/
//!              `3
//! ```
//!
//! Corners 0-3 as in [`super::tet4`]; edge (mid-side) nodes
//! 4: (0,1), 5: (1,2), 6: (0,2), 7: (0,3), **8: (2,3), 9: (1,3)**.
//!
//! Nodes 8 and 9 are where orderings differ: gmsh (element type 11, "Node ordering" in the
//! gmsh reference manual, §9.3 / `MTetrahedron10`) puts edge (2,3) before edge (1,3), while VTK
//! (`VTK_QUADRATIC_TETRA`) and Abaqus (C3D10) use 8: (1,3), 9: (2,3). We use gmsh's, so the
//! gmsh reader copies tet10 connectivity as is; a VTK writer must swap nodes 8 and 9 (meshio
//! does the same).
//!
//! # Shape functions
//!
//! With barycentric $L_0 = 1 - \xi - \eta - \zeta$, $L_1 = \xi$, $L_2 = \eta$, $L_3 = \zeta$:
//! corners $N_i = L_i (2 L_i - 1)$, edge nodes $N_{ab} = 4 L_a L_b$ (Zienkiewicz, Taylor & Zhu,
//! *The Finite Element Method*, 7th ed., §6.5).
//!
//! # Quadrature
//!
//! Stiffness: 4 points (degree 2): exact for straight-edged elements, where $\mathbf B$ is
//! linear; the usual full rule (Abaqus C3D10), rank-sufficient (24 strain samples for 24
//! deformation modes). Mass: 14 points (degree 5 ≥ 4 = degree of $N_a N_b$).

#![allow(non_snake_case)]

use crate::quadrature::{self, Rule};
use std::sync::OnceLock;

/// Number of nodes.
pub const NODE_COUNT: usize = 10;

/// The corner pair of each edge node 4..9, in node order.
pub const EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (0, 2), (0, 3), (2, 3), (1, 3)];

/// Reference coordinates of the nodes, in node order.
pub const REFERENCE_NODES: [[f64; 3]; 10] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
];

/// Faces as local node lists (6-node triangles: corners anticlockwise seen from outside,
/// then the edge nodes of edges (c0,c1), (c1,c2), (c2,c0)).
pub const FACES: [&[usize]; 4] = [
    &[0, 2, 1, 6, 5, 4],
    &[0, 1, 3, 4, 9, 7],
    &[0, 3, 2, 7, 8, 6],
    &[1, 2, 3, 5, 8, 9],
];

/// Shape functions `N` and their reference derivatives `dN[i] = dN_i/d(xi, eta, zeta)` at `xi`.
pub fn shape_functions(xi: &[f64; 3], N: &mut [f64], dN: &mut [[f64; 3]]) {
    let L = [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]];
    let dL = [[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for i in 0..4 {
        N[i] = L[i] * (2.0 * L[i] - 1.0);
        for k in 0..3 {
            dN[i][k] = (4.0 * L[i] - 1.0) * dL[i][k];
        }
    }
    for (e, &(a, b)) in EDGES.iter().enumerate() {
        N[4 + e] = 4.0 * L[a] * L[b];
        for k in 0..3 {
            dN[4 + e][k] = 4.0 * (L[b] * dL[a][k] + L[a] * dL[b][k]);
        }
    }
}

/// Stiffness rule: 4 points (degree 2).
pub fn stiffness_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::tetrahedron(2))
}

/// Mass rule: 14 points (degree 5).
pub fn mass_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::tetrahedron(5))
}
