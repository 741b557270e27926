//! 6-node linear wedge (triangular prism).
//!
//! # Node ordering (gmsh's, used as ours)
//!
//! ```text
//!            zeta
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
//! xi  |    ,/ `\    |   eta
//!     |  ,/     `\  |
//!     |,/         `\|
//!     1-------------2
//! ```
//!
//! Reference coordinates: 0 (0,0,-1), 1 (1,0,-1), 2 (0,1,-1), 3 (0,0,1), 4 (1,0,1),
//! 5 (0,1,1): the triangle $\zeta = -1$ anticlockwise about $+\zeta$, then the triangle
//! $\zeta = +1$ above it. Gmsh element type 6 ("prism"); the same as VTK_WEDGE up to VTK's
//! opposite triangle orientation (VTK orders the bottom triangle 0, 2, 1).
//!
//! # Shape functions
//!
//! With $L_0 = 1 - \xi - \eta$, $L_1 = \xi$, $L_2 = \eta$: $N_i = L_{i \bmod 3}\,
//! \tfrac12 (1 + \zeta_i \zeta)$.
//!
//! # Quadrature
//!
//! Stiffness: the 3-point degree-2 triangle rule x 2-point Gauss in $\zeta$ (6 points). Mass:
//! the degree-3 triangle rule x 3-point Gauss (18 points), exact for $\rho N_a N_b \det\mathbf J$
//! (degree 3 in the triangle, 4 in $\zeta$).

#![allow(non_snake_case)]

use crate::quadrature::{self, Rule};
use std::sync::OnceLock;

/// Number of nodes.
pub const NODE_COUNT: usize = 6;

/// Reference coordinates of the nodes, in node order.
pub const REFERENCE_NODES: [[f64; 3]; 6] = [
    [0.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
];

/// Faces as local node lists (3-node triangles and 4-node quadrilaterals, anticlockwise seen
/// from outside).
pub const FACES: [&[usize]; 5] = [&[0, 2, 1], &[3, 4, 5], &[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]];

/// Shape functions `N` and their reference derivatives `dN[i] = dN_i/d(xi, eta, zeta)` at `xi`.
pub fn shape_functions(xi: &[f64; 3], N: &mut [f64], dN: &mut [[f64; 3]]) {
    let L = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let dL = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    for i in 0..6 {
        let t = i % 3;
        let z = REFERENCE_NODES[i][2];
        let h = 0.5 * (1.0 + z * xi[2]);
        N[i] = L[t] * h;
        dN[i] = [dL[t][0] * h, dL[t][1] * h, L[t] * 0.5 * z];
    }
}

/// Stiffness rule: 6 points (degree 2 in the triangle, 3 in $\zeta$).
pub fn stiffness_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::wedge(2, 2))
}

/// Mass rule: 18 points (degree 3 in the triangle, 5 in $\zeta$).
pub fn mass_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::wedge(3, 3))
}
