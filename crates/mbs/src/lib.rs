//! # mbs: flexible multibody systems in minimal coordinates
//!
//! Bodies (AIC-FFR superelements from [`superelement`], rigid bodies, point masses) act on
//! shared *nodes*; joints, supports and drivers make some node coordinates explicit functions
//! of others, so the unknowns are independent coordinates only and no Lagrange multipliers
//! appear (theory guide §8). Static, dynamic and linearised analyses work on these coordinates.
//!
//! ```text
//! Model (serde data)  --System::new-->  System (coordinate tree, elements, sparse pattern)
//!   System::initial_state -> State -> solve_static | solve_dynamic (Integrator) | spectrum
//!                                      -> SensorRecord (+ Incomplete with the history on error)
//!   solve_static_with(StaticMethod::{LoadStepping, ArcLength}), buckling, solve_dynamic_adaptive
//! ```
//!
//! * A body's interface *is* a node: bodies sharing a node are welded. A flexible body's nodes
//!   stay independent, which is how a kinematic loop closes; a loop of rigid bodies and joints
//!   only is refused ([`ModelError::RigidLoop`], [`topology`](assembly::topology)).
//! * Joints are directed, parent node to child node: the child's configuration follows from the
//!   parent's and the joint coordinates ([`JointKind`]). Supports and node drivers act on
//!   independent nodes.
//! * Reactions ([`SensorKind::Reaction`], [`SensorKind::DriverEffort`]) are the residual of the
//!   removed coordinates: the force (moment) the support or driver applies *to* the model.
//! * Forces the model data do not describe (a controller, a co-simulation partner, a bushing
//!   law) are [`UserForce`]s: a Rust type gives the wrench on its nodes and, optionally, its
//!   Jacobians (central differences otherwise), [`System::with_user_forces`].
//!
//! # Quick start
//!
//! A pendulum: a ground node, a revolute joint, a rigid bob under gravity, released from
//! 30 degrees and integrated for half a second with the Lie-group generalized-α method
//! (theory guide, section 9.2). Energy is conserved to the integrator's accuracy:
//!
//! ```
//! use mbs::{solve_dynamic, DynamicSettings, JointKind, Model, RigidBody, SensorKind, Support, System};
//! use nalgebra::{Matrix3, Vector3};
//!
//! let mut model = Model::new("pendulum");
//! let ground = model.add_node("ground", Vector3::zeros());
//! let hinge = model.add_node("hinge", Vector3::zeros());
//! model.add_support(Support::clamp(ground));
//! let joint = model.add_joint("hinge", ground, hinge, JointKind::Revolute { axis: Vector3::z() });
//! model.add_rigid_body(RigidBody {
//!     name: "bob".into(),
//!     reference: hinge,
//!     nodes: vec![],
//!     mass: 2.0,
//!     center_of_mass: Vector3::new(0.0, -0.5, 0.0),
//!     inertia: Matrix3::identity() * 0.01,
//! });
//! model.gravity = Vector3::new(0.0, -9.81, 0.0);
//! model.add_sensor("kinetic", SensorKind::KineticEnergy);
//! model.add_sensor("potential", SensorKind::GravityPotential);
//!
//! let system = System::new(&model)?;
//! let mut start = system.initial_state();
//! system.set_joint(&mut start, joint, 0, 30_f64.to_radians(), 0.0);
//! // h = 1 ms to t = 0.5 s, rho_inf = 1: no numerical damping.
//! let run = solve_dynamic(&system, start, &DynamicSettings::new(1e-3, 0.5, 1.0)).map_err(|e| e.error)?;
//! let kinetic = run.sensors.series("kinetic").expect("the kinetic energy sensor");
//! let potential = run.sensors.series("potential").expect("the potential sensor");
//! let total = |i: usize| kinetic[i][0] + potential[i][0];
//! let (first, last) = (total(0), total(kinetic.len() - 1));
//! // Undamped generalized-alpha at h = 1 ms (omega h = 4e-3): the energy error is of order
//! // (omega h)^2, far below 1e-3 of the 1.3 J the bob swings through.
//! assert!((last - first).abs() < 1e-3 * 1.3, "energy {first} -> {last}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Notation
//!
//! Equation numbers such as (8.2) are those of the theory guide (`docs/theory.md`); other
//! sources are keys of the bibliography (`docs/bibliography.md`).
//!
//! | symbol | Rust | meaning | source |
//! |---|---|---|---|
//! | $\mathbf r_c,\ \mathbf R_c$ | [`NodeMotion`] `r`, `R` | node position, orientation (node axes to inertial) | theory guide §8 |
//! | $\mathbf V_c = [\mathbf v_c; \boldsymbol\omega_c]$ | `v`, `omega` | node velocity, spatial angular velocity ($\dot{\mathbf R} = \tilde{\boldsymbol\omega}\mathbf R$) | so3 |
//! | $\mathbf A_c = [\mathbf a_c; \boldsymbol\alpha_c]$ | `a`, `alpha` | node acceleration | |
//! | $\mathbf q$ | [`State`] | independent coordinates: scalars and SO(3) rotations | theory guide §8 |
//! | $\dot{\mathbf q},\ \ddot{\mathbf q}$ | [`State::velocity`], [`State::acceleration`] | rates (spatial $\boldsymbol\omega$ for rotations) | |
//! | $\mathbf q\oplus\delta\mathbf q$ | [`System::retract`] | scalars added, $\mathbf R \leftarrow \exp(\widetilde{\delta\boldsymbol\pi})\mathbf R$ | so3 |
//! | $\mathbf J_c$ | [`NodeKinematics`] `J` | $\mathbf V_c = \mathbf J_c\dot{\mathbf q}$ (+ driver columns) | theory guide §8 |
//! | $\dot{\mathbf J}_c\dot{\mathbf q}$ | `NodeKinematics::motion.a` at $\ddot{\mathbf q} = 0$ | convective acceleration | theory guide §8 |
//! | $\mathbf r_c$ | (internal) | node residual: inertia + internal − external force | |
//! | $\mathbf F$ | [`System::residual`] | $\sum_c\mathbf J_c^T\mathbf r_c$ (+ modal rows, joint springs) | theory guide §8 |
//! | $\mathbf G_r$ | [`System::generalized_force`] | $\partial(\mathbf J^T\mathbf r)/\partial\mathbf q$ at fixed $\mathbf r$: the joints' geometric term | [`coordinates`](assembly::coordinates) |
//! | $\hat{\mathbf M},\ \hat{\mathbf C},\ \hat{\mathbf K}$ | [`Matrices`] | $\partial\mathbf F/\partial\ddot{\mathbf q}$, $\partial\mathbf F/\partial\dot{\mathbf q}$, $\partial\mathbf F/\partial\mathbf q$ | [`coordinates`](assembly::coordinates) |
//! | $\mathbf K_t,\ \mathbf C_t,\ \mathbf M$ | `ElementOutput` | element tangents on its node ports | \[S19\], [`body`](assembly::body) |
//! | $\lambda$ | `lambda`, [`At::LoadFactor`] | load factor (statics) | |
//! | $f_{scale}$, floors | `Workspace::scale`, [`System::residual_floor`], `System::inertia_floor` | Newton's test $\lVert\mathbf F\rVert \le \mathrm{tol}\,f_{scale}$ + the round-off of the elastic forces + (time steps) $10\varepsilon\lVert\hat{\mathbf M}\dot{\mathbf q}\rVert/h$ | [`system`](assembly::system) |
//! | $\mathbf P$ | `arc_length::load_vector` | $-\partial\mathbf F/\partial\lambda$: generalised external force at $\lambda = 1$ | Riks 1979 |
//! | $\Delta s,\ s_i$ | [`ArcLengthSettings`], `System::dof_scale` | arc length; scale of unknown $i$ in its norm | Crisfield 1981 |
//! | $\hat{\mathbf K}_0,\ \Delta\hat{\mathbf K},\ \mu$ | [`buckling`] | unloaded tangent, its change to the loaded state, buckling multiplier | Bathe §6.8.2 |
//! | $\mathbf e_{n+1}$ | [`Integrator::step_adaptive`] | local error estimate $h^2\lvert\beta-\frac16\rvert(\mathbf a_{n+1}-\mathbf a_n)$ | Zienkiewicz & Xie 1991 |
//! | $\rho_\infty,\ \alpha_m,\ \alpha_f,\ \beta,\ \gamma$ | [`AlphaParameters`] | generalized-α parameters | Chung & Hulbert 1993 |
//! | $\beta',\ \gamma'$ | `bp`, `gp` | iteration-matrix factors | BCA 2012 |
//! | $\mathbf a_n$ | `Integrator::a` | algorithmic acceleration (body axes for rotations, and for free nodes' translations with `DynamicSettings::body_axis_translations`) | BCA 2012 |
//! | $\boldsymbol\omega_b,\ \mathbf v_b$ | `vb` (`solvers::dynamic`) | body-axis angular and translational velocity of a node, $\mathbf R^T\boldsymbol\omega_s$, $\mathbf R^T\dot{\mathbf x}$ | [`solvers::dynamic`] |
//! | $\mathrm{Re}\,s$ | [`LinearSpectrum::growing`], [`ModeEnergy::growth_rate`] | growth rate of an unstable mode \[1/s\] | [`linearized`](solvers::linearized) |
//! | $\mathbf T(h\Delta\mathbf q)$ | `System::iteration_matrix` | tangent operator $\mathbf J_l$ of each rotation increment | BCA 2012 |
//! | $\mathbf S = \beta'\hat{\mathbf M} + \gamma'\hat{\mathbf C} + \hat{\mathbf K}\mathbf T$ | `Workspace::S`, [`LinearSolver`] | iteration matrix; dense LU up to [`DENSE_MAX`] unknowns, sparse above | BCA 2012 |
//! | $\lVert\mathbf F_{k+1}\rVert/\lVert\mathbf F_k\rVert$ | [`MODIFIED_NEWTON_RATE`] | contraction above which modified Newton ([`NewtonStrategy`]) refactorises | [`solvers::dynamic`] |
//! | $\mathbf S_f,\ \mathbf R_f,\ \mathbf Q = \mathbf R\mathbf R_f^T,\ \mathbf T$ | `Integrator::factor_rotations`, `corotate` | modified Newton's kept iteration matrix, a free node's rotation where it was built, the node's turn since, and the block rotation $\mathbf S \approx \mathbf T\mathbf S_f\mathbf T^T$ | [`solvers::dynamic`] |
//! | $c_1,\ c_2$ | `AccelerationHistory::predict`, [`PREDICTOR_WINDOW`] | least-squares coefficients of the full-Newton predictor $\ddot q_{n+1} = c_1\ddot q_n + c_2\ddot q_{n-1}$ | [`solvers::dynamic`] |
//! | $\mathbf J = [\mathbf L;\ \mathbf H]$ | [`System::momentum`] | linear momentum, angular momentum about the origin: $\mathbf T_{rig}^T\hat{\mathbf M}\dot{\mathbf q}$ | Noether |
//! | $\mathbf T_{rig}$ | [`System::rigid_velocities`] | $n_{dof}\times6$: independent velocities of the translations along and rotations about $\mathbf e_k$ | [`momentum`](assembly::system::momentum) |
//! | $\mathbf J_0,\ \boldsymbol\lambda$ | `Integrator::J0`, `lambda` | momenta of the start; rigid correction $\dot{\mathbf q} \mathrel{+}= \mathbf T_{rig}\boldsymbol\lambda$ | HLW §IV.4 |
//! | $x,\ \dot x$ | [`State`] scalars | a joint coordinate (m or rad) and its rate | [`JointKind`] |
//! | $Q$ | (internal) | generalised force on a joint coordinate, $\mathbf F \mathrel{-}= Q$ (N or N m) | [`joint_forces`](assembly::joint_forces) |
//! | $k,\ c,\ x_0,\ f_0$ | [`JointSpring`] | joint spring: stiffness, damping, rest value, preload | [`model`] |
//! | $x_{lo},\ x_{hi},\ d$ | [`JointLimit`] | stop bounds; penetration beyond them | [`joint_forces`](assembly::joint_forces) |
//! | $u,\ r(t),\ y,\ e = r - y$ | [`JointActuator`], [`Pid`] | actuator effort, set-point, measured coordinate, error | [`joint_forces`](assembly::joint_forces) |
//! | $K_p,\ K_i,\ K_d,\ z$ | [`Pid`], `Control` | PID gains; integral of $e$ (trapezoidal, moved on by accepted steps) | [`joint_forces`](assembly::joint_forces) |
//! | $u_h$ | [`System::set_actuator_effort`] | an actuator's effort held at a value set between steps, in place of its law | [`joint_forces`](assembly::joint_forces) |
//! | $\mathbf R_\Delta$ | [`initial`](assembly::initial) | rigid rotation of a joint's subtree by an initial joint value | [`initial`](assembly::initial) |
//! | $\hat{\mathbf K}_s$ | [`stability`](mod@solvers::stability) | symmetric part of $\hat{\mathbf K}$, scaled by its diagonal; negative eigenvalues: past a critical point | Bathe (1996) §6.8 |
//! | $\mathbf f_e$ | [`Wrench`] | a user force's force and moment on a node, inertial | [`user_force`] |
//!
//! Vectors are inertial unless said otherwise; rigid-body mass data are in their reference
//! node's axes. BCA 2012: Brüls, Cardona, Arnold, *Mech. Mach. Theory* 48 (2012). HLW: Hairer,
//! Lubich, Wanner, *Geometric Numerical Integration*, 2nd ed., Springer (2006).
//!
//! # Equation map
//!
//! | eq. | meaning | function |
//! |---|---|---|
//! | theory guide §8 | node configurations, velocities, accelerations and $\mathbf J$ from the independent coordinates | `mbs::assembly::coordinates::CoordinateMap::motions_into` |
//! | this crate | $\partial\mathbf V/\partial\mathbf q$, $\partial\mathbf A/\partial\mathbf q$, $\partial\mathbf A/\partial\dot{\mathbf q}$, $\partial\mathbf J/\partial\mathbf q$ | `mbs::assembly::coordinates::CoordinateMap::derivatives_into` |
//! | this crate | geometric term $\mathbf G_r$ | `mbs::assembly::coordinates::CoordinateMap::geometric_term` |
//! | theory guide §8 | $\mathbf J^T(\mathbf M\mathbf J\ddot{\mathbf q} + \mathbf M\dot{\mathbf J}\dot{\mathbf q} + \mathbf Q_v - \mathbf Q) = 0$ | `mbs::System::residual` |
//! | this crate | $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ | `mbs::System::matrices` |
//! | Newton-Euler | rigid body about its reference node | `mbs::assembly::body::rigid_element` |
//! | (6.4)-(6.7), \[S19\] | flexible body | `mbs::assembly::body::FlexibleElement::element` (calls `superelement::Superelement::evaluate`) |
//! | theory guide §9 | Newton with load stepping | `mbs::solve_static` |
//! | Riks 1979, Crisfield 1981 | arc-length continuation (spherical constraint, bordered Newton) | `mbs::solve_arc_length`, `mbs::solve_static_with` |
//! | Bathe §6.8.2 | linearised buckling $(\hat{\mathbf K}_0 + \mu\Delta\hat{\mathbf K})\boldsymbol\phi = \mathbf 0$ | `mbs::buckling` |
//! | Zienkiewicz & Xie 1991 | local error estimate and step control | `mbs::Integrator::step_adaptive`, `mbs::solve_dynamic_adaptive` |
//! | BCA 2012, Alg. 1 | Lie-group generalized-α step; full or modified Newton ([`NewtonStrategy`]) | `mbs::Integrator::step` |
//! | HLW §IV.4 | momentum projection $(\mathbf T_{rig}^T\hat{\mathbf M}\mathbf T_{rig})\boldsymbol\lambda = \mathbf J_0 - \mathbf J$, $\dot{\mathbf q} \mathrel{+}= \mathbf T_{rig}\boldsymbol\lambda$ on free, unloaded models | `mbs::System::project_momentum` (crate-private, `assembly/system/momentum.rs`) |
//! | theory guide §9 | linearised spectrum; each mode's energy by body and node | `mbs::spectrum`, `mbs::mode_energies` |
//! | this crate | initial joint values and rates moving the subtree behind the joint rigidly; the consistent start (position assembly of closed loops, velocity analysis from the drivers' and initial rates) | `mbs::System::initial_state` (`assembly/system/initial_state.rs`) |
//! | this crate | joint limits, actuators (time function, PID with trapezoidal integral) and their tangents | `mbs::assembly::joint_forces` |
//! | Bathe (1996) §6.8 | stability of a static state (inertia of $\hat{\mathbf K}_s$) | `mbs::stability` |
//! | this crate | fixed step retried with halved steps | `mbs::step_retrying`, `mbs::solve_dynamic_retrying` |
//! | this crate | user force: residual $-\lambda\mathbf f_e$, $\mathbf K_t = -\lambda\partial\mathbf f_e/\partial\mathbf x$, $\mathbf C_t = -\lambda\partial\mathbf f_e/\partial\mathbf V$ (central differences when not given) | `mbs::assembly::body::user_force_element` (crate-private), `mbs::user_force::finite_difference_jacobian` |
//!
//! # Not implemented
//!
//! * Joints reversed automatically (a tree that can only be built by reversing a joint is
//!   refused with a message saying so).
//! * Momentum conservation on models that are not free: the momentum projection
//!   ([`momentum`](assembly::system::momentum)) acts only when all six momenta are conserved (no supports, drivers, loads,
//!   gravity or springs to the ground); a component conserved alone (the angular momentum
//!   about the vertical under gravity) drifts at the integrator's order, 2.
//! * A cure for the out-of-plane growth of the spin-up to 10 rad/s with 4 superelements,
//!   $\rho_\infty \ge 0.8$ and $h$ = 3-10 ms: measured in `tests/convergence.rs`
//!   (`spin_up_out_of_plane_growth_study`), it is an instability of the converged discrete map
//!   in that window (independent of the Newton tolerance; stable at 2.5 ms for every
//!   $\rho_\infty$, and for 2 or 8 superelements), not a defect of the tangents or the update;
//!   $\rho_\infty = 0.5$ or a smaller step avoid it.
//! * Arc-length, buckling and the stability check are dense ([`buckling`], [`stability()`]).
//! * Initial joint values in closed loops (a value that no rigid motion of the loop follows
//!   is refused; the loop is assembled by an equilibrium instead).
//!
//! # Modules
//!
//! Leaves first; a module uses only those above it.
//!
//! | module | what |
//! |---|---|
//! | [`ids`], [`state`], [`node`] | entity ids; [`State`]; node motions (plain data) |
//! | [`error`] | [`ModelError`], [`SolveError`], [`Incomplete`] |
//! | [`model`] | the serde data, [`time_function`](model::time_function), [`user_force`] ([`UserForce`], added with [`System::with_user_forces`]), [`units`](model::units), [`merge`] |
//! | [`assembly`] | [`coordinates`](assembly::coordinates) (the maps and their derivatives), [`dense_lu`](assembly::dense_lu) (the LU of small iteration matrices), [`planar`](mod@assembly::planar) (the checks of planar flexible bodies), [`body`](assembly::body) (elements), [`topology`](assembly::topology) (the tree and its checks), [`initial`](assembly::initial) (how initial conditions act), [`joint_forces`](assembly::joint_forces) (limits and actuators), [`system`](assembly::system) ([`System`]: construction, assembly, initial states, sensors, momenta, recovery) |
//! | [`solvers`] | [`static_solver`](solvers::static_solver), [`arc_length`](solvers::arc_length), [`stability`](mod@solvers::stability), [`linearized`](solvers::linearized) (spectrum, mode energies and buckling), [`dynamic`](solvers::dynamic) (the integrator, its runs, [`retry`](solvers::dynamic::retry) with halved steps after a failure, [`streaming`](solvers::dynamic::streaming)) |

#![allow(non_snake_case)]

pub mod assembly;
pub mod error;
pub mod ids;
pub mod model;
pub mod node;
pub mod solvers;
pub mod state;

/// The paths of the modules before they were grouped, kept for the callers that name them.
pub use model::{force_law, merge, user_force};
pub use solvers::dynamic as dynamic_solver;

pub use assembly::initial::StartReport;
pub use assembly::joint_forces::STOP_RESOLUTION;
pub use assembly::system::momentum::{ExternalAction, MomentumProjection};
pub use assembly::system::sensors::{Energies, PendingRows, SensorRecord};
pub use assembly::system::{LinearSolver, Matrices, NodeKinematics, System, DENSE_MAX};
pub use error::{At, Entity, Incomplete, ModelError, SolveError};
pub use ids::{BodyId, JointId, NodeId};
pub use model::force_law::{ForceLaw, LawError, LawInput, LawOutput, LawPorts, LawRead, LawTarget};
pub use model::merge::{weld_points, WeldError};
pub use model::time_function::{Interpolation, TimeFunction};
pub use model::units::CoordinateQuantity;
pub use model::user_force::{FdSteps, UserForce, Wrench};
pub use model::{
    Body, BodyLoad, Driver, DriverTarget, Effort, FlexibleBody, InitialCondition, Joint, JointActuator, JointKind,
    JointLimit, JointSpring, Load, LoadAxes, LoadKind, Model, Node, Pid, PointMass, RigidBody, RotationSupport, Sensor,
    SensorAxes, SensorKind, Spring, Support, TranslationSupport,
};
pub use node::NodeMotion;
pub use solvers::arc_length::{solve_arc_length, solve_static_with, ArcLengthSettings, StaticMethod};
pub use solvers::dynamic::retry::{
    solve_dynamic_retrying, step_retrying, RetriedStep, RetriedTrajectory, Retry, RetryFailure,
};
pub use solvers::dynamic::streaming::{Interrupted, StepDone, StepTotals, Stepping, Taken};
pub use solvers::dynamic::{
    fixed_steps, last_step_size, solve_dynamic, solve_dynamic_adaptive, step_adaptive_to, AdaptiveSettings,
    AdaptiveStep, AlphaParameters, DynamicSettings, Integrator, NewtonStrategy, StepReport, Trajectory,
    MODIFIED_NEWTON_RATE, PI_INTEGRAL, PI_PROPORTIONAL, PREDICTOR_WINDOW,
};
pub use solvers::linearized::{
    buckling, linearize, mode_energies, spectrum, Buckling, CarrierEnergy, EnergyCarrier, LinearSpectrum, ModeEnergy,
    NodeEnergy,
};
pub use solvers::stability::{stability, Stability};
pub use solvers::static_solver::{solve_static, LoadStep, StaticSettings, StaticSolution};
pub use state::State;
