//! Unit tests of the multibody crate (fast, debug build with opt-level 2). Index:

#![allow(non_snake_case)]

/// Model builders shared by the tests: beam superelements, chains, pendulums.
#[path = "unit/fixtures.rs"]
mod fixtures;

/// Central differences of the kinematic maps: node configuration, J, the convective term
/// Jdot qdot, dV/dq, dA/dq, dA/dqdot and the joints' geometric term G_r, on a chain with every
/// joint kind, rigid offsets, a slider and a driver.
#[path = "unit/kinematics.rs"]
mod kinematics;

/// Central differences of the assembled tangents M, C, K (dF/dqdd, dF/dqd, dF/dq) on deformed,
/// rotated, moving states of models with superelements, joints, rigid bodies, springs and
/// follower loads.
#[path = "unit/tangent.rs"]
mod tangent;

/// Rigid pendulum: small- and large-amplitude periods, second-order convergence in time.
#[path = "unit/pendulum.rs"]
mod pendulum;

/// Free-floating flexible body (benchmarks.md C4): momentum and energy.
#[path = "unit/free_body.rs"]
mod free_body;

/// Geometrically nonlinear statics: elastica B1 and roll-up B2 with N superelements (quick
/// subset), quadratic convergence of Newton.
#[path = "unit/statics.rs"]
mod statics;

/// Every refused model gives its named error.
#[path = "unit/errors.rs"]
mod errors;

/// Time functions (values against their derivatives), CSV tables, serde round trip of a model.
#[path = "unit/data.rs"]
mod data;

/// The planar flexible slider-crank (benchmarks.md C2): runs, stays planar, and its slider
/// follows the rigid mechanism with a small elastic correction.
#[path = "unit/slider_crank.rs"]
mod slider_crank;

/// Linearised analysis: clamped-free beam frequencies (benchmarks.md A1) from superelements,
/// and the geometric stiffness of an axial preload.
#[path = "unit/linearized.rs"]
mod linearized;

/// Arc-length continuation through the limit point of the von Mises truss (exact curve), and
/// linearised buckling of a column of N superelements against Euler's load.
#[path = "unit/arc_length.rs"]
mod arc_length;
