//! 4-node linear tetrahedron (constant strain). Kept for contrast only: it locks in bending
//! (theory guide §2), which `tests/unit/solid.rs` states as a test.
//!
//! # Node ordering (gmsh's, used as ours)
//!
//! ```text
//!                    eta
//!                  .
//!                ,/
//!               /
//!            2
//!          ,/|`\
//!        ,/  |  `\
//!      ,/    '.   `\
//!    ,/       |     `\
//!  ,/         |       `\
//! 0-----------'.--------1 --> xi
//!  `\.         |      ,/
//!     `\.      |    ,/
//!        `\.   '. ,/
//!           `\. |/
//!              `3
//!                 `\.
//!                    ` zeta
//! ```
//!
//! Reference coordinates: 0 (0,0,0), 1 (1,0,0), 2 (0,1,0), 3 (0,0,1). Positive orientation
//! (det J > 0) means node 3 lies on the side of the face 0-1-2 that $\mathbf x_1 - \mathbf x_0$
//! × $\mathbf x_2 - \mathbf x_0$ points to. Gmsh element type 4.
//!
//! # Shape functions
//!
//! $N_0 = 1 - \xi - \eta - \zeta$, $N_1 = \xi$, $N_2 = \eta$, $N_3 = \zeta$.
//!
//! # Quadrature
//!
//! Stiffness: 1 point (degree 1; $\mathbf B$ is constant, so exact). Mass: 4 points (degree
//! 2; $N_a N_b$ is quadratic, so exact).

#![allow(non_snake_case)]

use crate::quadrature::{self, Rule};
use std::sync::OnceLock;

/// Number of nodes.
pub const NODE_COUNT: usize = 4;

/// Reference coordinates of the nodes, in node order.
pub const REFERENCE_NODES: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Faces as local node lists (3-node triangles), numbered anticlockwise seen from outside.
pub const FACES: [&[usize]; 4] = [&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]];

/// Shape functions `N` and their reference derivatives `dN[i] = dN_i/d(xi, eta, zeta)` at `xi`.
pub fn shape_functions(xi: &[f64; 3], N: &mut [f64], dN: &mut [[f64; 3]]) {
    N[0] = 1.0 - xi[0] - xi[1] - xi[2];
    N[1] = xi[0];
    N[2] = xi[1];
    N[3] = xi[2];
    dN[0] = [-1.0, -1.0, -1.0];
    dN[1] = [1.0, 0.0, 0.0];
    dN[2] = [0.0, 1.0, 0.0];
    dN[3] = [0.0, 0.0, 1.0];
}

/// Stiffness rule: the centroid (degree 1).
pub fn stiffness_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::tetrahedron(1))
}

/// Mass rule: 4 points (degree 2).
pub fn mass_rule() -> &'static Rule<3> {
    static RULE: OnceLock<Rule<3>> = OnceLock::new();
    RULE.get_or_init(|| quadrature::tetrahedron(2))
}
