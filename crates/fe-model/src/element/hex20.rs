//! 20-node serendipity hexahedron.
//!
//! # Node ordering (gmsh's, used as ours)
//!
//! ```text
//! 3----13----2
//! |\         |\
//! | 15       | 14
//! 9  \       11 \
//! |   7----19+---6
//! |   |      |   |
//! 0---+-8----1   |
//!  \  17      \  18
//!  10 |        12|
//!    \|         \|
//!     4----16----5
//! ```
//!
//! Corners 0-7 as in [`super::hex8`]; edge nodes 8: (0,1), 9: (0,3), 10: (0,4), 11: (1,2),
//! 12: (1,5), 13: (2,3), 14: (2,6), 15: (3,7), 16: (4,5), 17: (4,7), 18: (5,6), 19: (6,7).
//!
//! This is gmsh's order (element type 17, gmsh reference manual "Node ordering"), which sorts
//! the edges by their first corner. It is **not** VTK's (`VTK_QUADRATIC_HEXAHEDRON`: the
//! bottom face's edges, the top face's, then the vertical ones: 8: (0,1), 9: (1,2), 10: (2,3),
//! 11: (3,0), 12: (4,5), ..., 16: (0,4), ...) nor Abaqus C3D20's (the same as VTK's); a VTK
//! writer must permute.
//!
//! # Shape functions
//!
//! With $(\xi_i, \eta_i, \zeta_i)$ the reference coordinates of node $i$ (Zienkiewicz, Taylor
//! & Zhu, *The Finite Element Method*, 7th ed., §6.4.2): corners
//! $N_i = \tfrac18 (1 + \xi_i\xi)(1 + \eta_i\eta)(1 + \zeta_i\zeta)(\xi_i\xi + \eta_i\eta + \zeta_i\zeta - 2)$;
//! an edge node with $\xi_i = 0$: $N_i = \tfrac14 (1 - \xi^2)(1 + \eta_i\eta)(1 + \zeta_i\zeta)$,
//! and likewise for $\eta_i = 0$ or $\zeta_i = 0$.
//!
//! # Quadrature
//!
//! Stiffness: 3 x 3 x 3 Gauss (full integration: a single element has exactly the six rigid
//! modes as null space; 2 x 2 x 2 would leave spurious zero-energy modes). Mass: 4 x 4 x 4
//! Gauss, exact for $\rho N_a N_b \det\mathbf J$ on straight-edged geometry (degree 6 per
//! variable).

#![allow(non_snake_case)]

use crate::quadrature::{self, Rule};
use std::sync::OnceLock;

/// Number of nodes.
pub const NODE_COUNT: usize = 20;

/// The corner pair of each edge node 8..19, in node order.
pub const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (0, 3),
    (0, 4),
    (1, 2),
    (1, 5),
    (2, 3),
    (2, 6),
    (3, 7),
    (4, 5),
    (4, 7),
    (5, 6),
    (6, 7),
];

/// Reference coordinates of the nodes, in node order: the corners of [`super::hex8`], then
/// the midpoint of each edge of [`EDGES`].
pub const REFERENCE_NODES: [[f64; 3]; 20] = reference_nodes();

const fn reference_nodes() -> [[f64; 3]; 20] {
    let corners = super::hex8::REFERENCE_NODES;
    let mut nodes = [[0.0; 3]; 20];
    let mut i = 0;
    while i < 8 {
        nodes[i] = corners[i];
        i += 1;
    }
    let mut e = 0;
    while e < EDGES.len() {
        let (a, b) = EDGES[e];
        let mut k = 0;
        while k < 3 {
            // Exact: the corners' coordinates are +-1.
            nodes[8 + e][k] = 0.5 * (corners[a][k] + corners[b][k]);
            k += 1;
        }
        e += 1;
    }
    nodes
}

/// Faces as local node lists (8-node quadrilaterals: corners anticlockwise seen from outside,
/// then the edge nodes of edges (c0,c1), (c1,c2), (c2,c3), (c3,c0)).
pub const FACES: [&[usize]; 6] = [
    &[0, 3, 2, 1, 9, 13, 11, 8],
    &[4, 5, 6, 7, 16, 18, 19, 17],
    &[0, 1, 5, 4, 8, 12, 16, 10],
    &[1, 2, 6, 5, 11, 14, 18, 12],
    &[2, 3, 7, 6, 13, 15, 19, 14],
    &[3, 0, 4, 7, 9, 10, 17, 15],
];

/// Shape functions `N` and their reference derivatives `dN[i] = dN_i/d(xi, eta, zeta)` at `xi`.
pub fn shape_functions(xi: &[f64; 3], N: &mut [f64], dN: &mut [[f64; 3]]) {
    for (i, r) in REFERENCE_NODES.iter().enumerate() {
        // f[k] = 1 + r_k xi_k for corner directions; the edge direction (r_k = 0) gets the
        // bubble 1 - xi_k^2 instead.
        match r.iter().position(|&c| c == 0.0) {
            None => {
                let f = [1.0 + r[0] * xi[0], 1.0 + r[1] * xi[1], 1.0 + r[2] * xi[2]];
                let s = r[0] * xi[0] + r[1] * xi[1] + r[2] * xi[2] - 2.0;
                N[i] = 0.125 * f[0] * f[1] * f[2] * s;
                // d/dxi_k [f_k g s] = r_k g s + f_k g r_k = r_k g (s + f_k), g the other two f.
                for k in 0..3 {
                    let g = f[(k + 1) % 3] * f[(k + 2) % 3];
                    dN[i][k] = 0.125 * r[k] * g * (s + f[k]);
                }
            }
            Some(m) => {
                let mut f = [0.0; 3];
                let mut df = [0.0; 3];
                for k in 0..3 {
                    if k == m {
                        f[k] = 1.0 - xi[k] * xi[k];
                        df[k] = -2.0 * xi[k];
                    } else {
                        f[k] = 1.0 + r[k] * xi[k];
                        df[k] = r[k];
                    }
                }
                N[i] = 0.25 * f[0] * f[1] * f[2];
                dN[i] = [
                    0.25 * df[0] * f[1] * f[2],
                    0.25 * f[0] * df[1] * f[2],
                    0.25 * f[0] * f[1] * df[2],
                ];
            }
        }
    }
}

/// Stiffness rule: 3 x 3 x 3 Gauss (degree 5 per variable).
pub fn stiffness_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::hexahedron(3))
}

/// Mass rule: 4 x 4 x 4 Gauss (degree 7 per variable).
pub fn mass_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::hexahedron(4))
}
