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

/// The consistent start: position assembly of closed loops, the velocity analysis against
/// central differences of it, hand-computed starts, contradicting rates refused.
#[path = "unit/start.rs"]
mod start;

/// Rigid pendulum: small- and large-amplitude periods, second-order convergence in time.
#[path = "unit/pendulum.rs"]
mod pendulum;

/// Free-floating flexible body (validation problem C4): momentum to round-off with the projection
/// (measured by a second path, and on the FE mesh of a solid block), energy and trajectory at
/// order 2, adaptive steps, no projection when the model is not free.
#[path = "unit/free_body.rs"]
mod free_body;

/// The momentum map: rigid velocity fields on every coordinate kind, and a free chain of
/// superelements with revolute joints keeping its momenta.
#[path = "unit/momentum.rs"]
mod momentum;

/// The acceleration sensors (uniform circular motion, the pendulum, central differences of
/// the velocity sensor, the trapezoidal rule's velocity increments of a flexible node, zero in
/// statics) and the energy balance (a conservative pendulum, a driven, damped and loaded one, a
/// prescribed swing, the flexible slider-crank), with its order in the step.
#[path = "unit/sensor_accelerations.rs"]
mod sensor_accelerations;

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

/// The planar flexible slider-crank (validation problem C2): runs, stays planar, and its slider
/// follows the rigid mechanism with a small elastic correction.
#[path = "unit/slider_crank.rs"]
mod slider_crank;

/// Planar flexible bodies: the C2 slider-crank evaluated in the plane agrees with the same
/// mechanism in 3D; a planar body whose node can leave the plane is refused by name.
#[path = "unit/planar.rs"]
mod planar;

/// A flexible double pendulum whose beams went through MBDyn `.fem` files and back has the
/// same linearised frequencies to 1e-10.
#[path = "unit/mbdyn_fem.rs"]
mod mbdyn_fem;

/// Linearised analysis: clamped-free beam frequencies (validation problem A1) from superelements,
/// and the geometric stiffness of an axial preload.
#[path = "unit/linearized.rs"]
mod linearized;

/// Arc-length continuation through the limit point of the von Mises truss (exact curve), and
/// linearised buckling of a column of N superelements against Euler's load.
#[path = "unit/arc_length.rs"]
mod arc_length;

/// Geometric stiffening of superelements: linearised buckling of a clamped-free column
/// against Euler's load, the amplification of a lateral deflection by an axial load, and the
/// membrane stiffening of a beam clamped at both ends.
#[path = "unit/geometric.rs"]
mod geometric;

/// Newton strategies (modified against full on the flexible slider-crank, a rigid pendulum,
/// adaptive steps, failures) and the dense against the sparse LU of the iteration matrix (same
/// steps, same refusal of a singular matrix).
#[path = "unit/newton.rs"]
mod newton;

/// Initial states that follow the joints (a flexible double pendulum set by joint values and
/// rates, a free body spun by one line), refused loops, joint springs with preload, limits and
/// actuators (tangents against central differences; a PID reaching its set-point, the damped
/// frequency of a torsional spring-damper, a stop), the hand-over from an equilibrium, and the
/// retry of failed fixed steps.
#[path = "unit/joint_setup.rs"]
mod joint_setup;

/// User-defined forces (the `UserForce` trait): analytic Jacobians against central
/// differences on deformed, rotated, moving nodes; the assembled tangents with a user force
/// (analytic or finite-difference Jacobian); a user force equal to a follower load gives the
/// load's statics and dynamics; non-finite forces and unknown nodes refused by name.
#[path = "unit/user_force.rs"]
mod user_force;

/// Force laws evaluated in the step (the `ForceLaw` trait): finite-difference Jacobians
/// against exact ones; the law's tangents in the iteration matrix, on a rigid chain and, with
/// a saturated PID on both branches, on deformed flexible bodies; a damper law against the
/// built-in PID on a flexible double pendulum, and damping it for 100 s without gaining
/// energy; a law value that is not finite, and ports that name nothing, refused by name.
#[path = "unit/force_law.rs"]
mod force_law;

/// An integrator that owns its system; loads changed between steps.
#[path = "unit/stepping.rs"]
mod stepping;

/// What each joint coordinate measures (units of sensors and efforts).
#[path = "unit/units.rs"]
mod units;

/// Modal coordinates and deformed meshes of a state; points welded into nodes.
#[path = "unit/recovery.rs"]
mod recovery;

/// Stresses from a multibody state: the centrifugal axial force of a spinning beam.
#[path = "unit/stress.rs"]
mod stress;

/// Linearised verdicts and frequencies at every size and in any units: steel cantilevers of
/// 20 mm, 2 m, 200 m and in mm-t-s units stable with their reduced matrices' frequencies to
/// 1e-6; inverted pendulums unstable at the analytic rate.
#[path = "unit/scale_invariance.rs"]
mod scale_invariance;

/// A user force whose Jacobian is 0/0 stops load stepping and arc length with the force and
/// the load factor named.
#[path = "unit/non_finite.rs"]
mod non_finite;

/// Saturated PID actuators (Newton through the saturation, the first step after a release)
/// and joint limits (the energy at the contact onset, stiffnesses no step resolves).
#[path = "unit/stops.rs"]
mod stops;
