//! 8-node trilinear hexahedron.
//!
//! # Node ordering (gmsh's, used as ours)
//!
//! ```text
//!        eta
//! 3----------2
//! |\     ^   |\
//! | \    |   | \
//! |  \   |   |  \
//! |   7------+---6
//! |   |  +-- |-- | -> xi
//! 0---+---\--1   |
//!  \  |    \  \  |
//!   \ |     \  \ |
//!    \|    zeta \|
//!     4----------5
//! ```
//!
//! Reference coordinates in $[-1, 1]^3$: 0 (-1,-1,-1), 1 (1,-1,-1), 2 (1,1,-1), 3 (-1,1,-1),
//! 4 (-1,-1,1), 5 (1,-1,1), 6 (1,1,1), 7 (-1,1,1): the face $\zeta = -1$ anticlockwise about
//! $+\zeta$, then the face $\zeta = +1$. Gmsh element type 5; the same as VTK_HEXAHEDRON.
//!
//! # Shape functions
//!
//! $N_i = \tfrac18 (1 + \xi_i \xi)(1 + \eta_i \eta)(1 + \zeta_i \zeta)$.
//!
//! # Quadrature
//!
//! Stiffness: 2 x 2 x 2 Gauss (full integration; rank-sufficient, no hourglass modes; it
//! shear-locks in bending, as every fully integrated trilinear hexahedron does). Mass:
//! 3 x 3 x 3 Gauss, exact for $\rho N_a N_b \det\mathbf J$ on any trilinear geometry (degree
//! 4 in each variable).

#![allow(non_snake_case)]

use crate::quadrature::{self, Rule};
use std::sync::OnceLock;

/// Number of nodes.
pub const NODE_COUNT: usize = 8;

/// Reference coordinates of the nodes, in node order.
pub const REFERENCE_NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Faces as local node lists (4-node quadrilaterals, anticlockwise seen from outside).
pub const FACES: [&[usize]; 6] = [
    &[0, 3, 2, 1],
    &[4, 5, 6, 7],
    &[0, 1, 5, 4],
    &[1, 2, 6, 5],
    &[2, 3, 7, 6],
    &[3, 0, 4, 7],
];

/// Shape functions `N` and their reference derivatives `dN[i] = dN_i/d(xi, eta, zeta)` at `xi`.
pub fn shape_functions(xi: &[f64; 3], N: &mut [f64], dN: &mut [[f64; 3]]) {
    for (i, r) in REFERENCE_NODES.iter().enumerate() {
        let p = 1.0 + r[0] * xi[0];
        let q = 1.0 + r[1] * xi[1];
        let s = 1.0 + r[2] * xi[2];
        N[i] = 0.125 * p * q * s;
        dN[i] = [0.125 * r[0] * q * s, 0.125 * p * r[1] * s, 0.125 * p * q * r[2]];
    }
}

/// Stiffness rule: 2 x 2 x 2 Gauss (degree 3 per variable).
pub fn stiffness_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::hexahedron(2))
}

/// Mass rule: 3 x 3 x 3 Gauss (degree 5 per variable).
pub fn mass_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::hexahedron(3))
}
