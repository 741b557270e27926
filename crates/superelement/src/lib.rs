//! # superelement: the AIC-FFR body
//!
//! The absolute-interface-coordinate floating frame of reference superelement of Ellenbroek
//! and Schilder (\[E17\], \[S19\], summarised in \[AIC-FFR\]; docs/bibliography.md): from a Craig-Bampton
//! [`reduction::ReducedBody`] and a state in absolute interface coordinates, the frame (4.4),
//! the local CB coordinates, the velocity transformation (5.4)-(5.6), the forces (6.4)-(6.7)
//! and the tangent matrices for Newton, for one body at a time.
//!
//! ```text
//! ReducedBody + FrameChoice + MassVariant + Damping  --Superelement::new-->  Superelement
//! BodyState (r_k, R_k, v_k, omega_k, eta, eta_dot, last frame) + accelerations + gravity
//!     --evaluate / evaluate_into-->  Evaluation { frame, q_jj, residual, M, K_t, C_t, force parts }
//! ```
//!
//! # Quick start
//!
//! Turn a reduced beam into a superelement, move it rigidly and check that the elastic
//! force vanishes (the frame takes the rigid motion; theory guide, section 6.3):
//!
//! ```
//! use fe_model::{generate, BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind};
//! use nalgebra::{Point3, UnitQuaternion, Vector3};
//! use reduction::{reduce, CbSettings, ModeSelection};
//! use superelement::{Damping, Frame, FrameChoice, MassVariant, Superelement};
//!
//! let mut model = FeModel::default();
//! let steel = model.add_material(IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0)?);
//! let square = model.add_section(BeamSection::rectangle("20 mm square", 0.02, 0.02, 0.3)?);
//! let props = BeamProperties {
//!     section: square,
//!     material: steel,
//!     orientation: Vector3::z(),
//!     theory: BeamTheory::EulerBernoulli,
//!     mass: MassKind::Consistent,
//! };
//! let nodes = generate::straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 4, &props, None)?;
//! let interfaces = vec![("a".to_string(), nodes[0]), ("b".to_string(), nodes[4])];
//! let body = reduce(&model, "beam", &interfaces, &CbSettings::new(ModeSelection::Count(2)))?;
//! let se = Superelement::new(&body, FrameChoice::CenterOfMass, MassVariant::Exact, Damping::none())?;
//!
//! // The undeformed body turned by 1 rad about an oblique axis and moved away.
//! let turned = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.8, 0.5));
//! let mut state = se.undeformed_state(Frame::identity());
//! for k in 0..2 {
//!     state.r[k] = Vector3::new(1.0, 2.0, 3.0) + turned * state.r[k];
//!     state.R[k] = turned * state.R[k];
//! }
//! let accelerations = vec![0.0; se.n_coordinates()];
//! let evaluation = se.evaluate(&state, &accelerations, &Vector3::zeros())?;
//! // Round-off of the frame solve (tolerance 1e-12) times the stiffness scale EA = 8.4e7 N.
//! let largest = evaluation.f_elastic.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
//! assert!(largest < 1e-3, "elastic force {largest} N on a rigid motion");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # API
//!
//! * [`Superelement::new`]`(&ReducedBody, FrameChoice, MassVariant, Damping)` checks every
//!   shape and precomputes the invariants about the frame origin.
//! * [`Superelement::solve_frame`] solves (4.4) from `state.frame` (warm start);
//!   [`Superelement::kinematics`] adds $\mathbf q^{jj}$, $\mathbf Z_j$, $\mathbf T_j$, $\mathbf A$
//!   ([`Kinematics`]); [`Superelement::frame_velocity`] and [`Superelement::local_velocity`] give
//!   (5.4) and (5.5) applied to the state's velocities.
//! * [`Superelement::evaluate`] returns the residual $\mathbf r = \mathbf M\ddot{\mathbf q} + \mathbf Q_v +
//!   \mathbf f_{el} + \mathbf f_d - \mathbf f_g$, its parts and $\mathbf M$, $\mathbf K_t$, $\mathbf C_t$
//!   as faer matrices; [`Superelement::evaluate_into`] does the same into a reused
//!   [`Workspace`] and [`Evaluation`] (no allocation; the hot-loop form);
//!   [`Superelement::forces`] and [`Superelement::forces_into`] skip the tangents (left NaN);
//!   [`Superelement::residual_into`] computes the
//!   residual and its force parts alone (no mass matrix: the Newton iterations that reuse an
//!   iteration matrix).
//! * [`Superelement::kinetic_energy`], [`Superelement::strain_energy`],
//!   [`Superelement::gravity_potential`]; [`Superelement::strain_energy_in`] reads the strain
//!   energy off the workspace of the last `evaluate_into` (an energy sensor at every step),
//!   [`Superelement::kinetic_energy_in`] the kinetic energy at its configuration (also after a
//!   `residual_into`, which forms no mass matrix);
//!   [`Superelement::recover_mesh`] for the deformed mesh.
//! * [`Superelement::into_planar`] makes a body reduced in its FE model's xy-plane a planar one
//!   ([`planar`]): $3N + m$ coordinates evaluated behind the same methods and the same
//!   $6N + m$ layout (out-of-plane rows and columns zero), at 41 % of the spatial body's
//!   instructions for the residual and the mass, 37 % with the tangents (`benches/evaluate.rs`).
//! * [`testing`]: the central-difference helper, state perturbations through exp, test states,
//!   and reduced-body fixtures.
//!
//! //! The superelement's coordinates are $\mathbf q = [\mathbf r_1, \boldsymbol\pi_1, \dots,
//! \mathbf r_N, \boldsymbol\pi_N, \boldsymbol\eta]$ ($6N + m$): absolute interface positions and
//! orientations (varied spatially, $\delta\mathbf R_k = \widetilde{\delta\boldsymbol\pi}_k\mathbf R_k$)
//! and the fixed-interface modal coordinates, which stay independent coordinates of the body.
//!
//! ## Where this crate goes beyond the AIC-FFR papers
//!
//! * The CB rotation coordinates are rotation vectors, so their variation carries
//!   $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ ($\boldsymbol\Lambda$): (5.3)-(5.6) are used in their
//!   exact form ([`transform`]); for small elastic rotations they are the AIC-FFR paper's.
//! * The `Lumped` inertia of (6.6) is given a kinetic energy, so its $\mathbf Q_v$ is derived
//!   rather than assumed ([`forces`], `lumped_inertia`); the `Exact` inertia is the standard
//!   FFR one from the inertia invariants ([`mass`]).
//! * Geometric stiffening (optional, [`GeometricStiffness`]): the strain energy in the floating
//!   frame gains the cubic term $U_3$ of the reduced geometric stiffness $\mathbf G_k$ and a
//!   projected quartic term $U_4$, so that a single body sees how its axial force changes its
//!   bending stiffness (below).
//! * Every tangent is exact (geometric terms of $\mathbf R_j$, $\mathbf T_j$, $\boldsymbol\Lambda$,
//!   the mass matrix and the quadratic velocity forces) and checked against central
//!   differences (`tests/unit/fd_tangent.rs`).
//!
//! # Notation
//!
//! Equation numbers such as (5.4) are those of the theory guide (`docs/theory.md`); keys in
//! brackets are those of the bibliography (`docs/bibliography.md`).
//!
//! | symbol | Rust | meaning | source |
//! |---|---|---|---|
//! | $\{P_j, E_j\}$ → $\mathbf r_j,\ \mathbf R_j$ | [`Frame`] `r`, `R`; `R_j` | floating frame: origin (material point $P_j$), rotation | (4.1) |
//! | $\mathbf r_k,\ \mathbf R_k$ | [`BodyState`] `r`, `R` | absolute interface position, orientation | (5.1) |
//! | $\mathbf v_k,\ \boldsymbol\omega_k$ | `v`, `omega` | interface velocity, spatial angular velocity | |
//! | $\delta\mathbf q^{OO}$ | `dq` | $[\delta\mathbf r_1, \delta\boldsymbol\pi_1, \dots, \delta\boldsymbol\eta]$, spatial | (5.3) |
//! | $\mathbf x_k$ | `x` | undeformed interface position from $P_j$, body axes | (4.3) |
//! | $\mathbf u_k,\ \boldsymbol\theta_k$ | `q_jj` blocks | $\mathbf R_j^T(\mathbf r_k - \mathbf r_j) - \mathbf x_k$, $\log(\mathbf R_j^T\mathbf R_k)$ | (4.3) |
//! | $\mathbf q^{j,j}$ | `q_jj` | local CB coordinates $[\mathbf u_1, \boldsymbol\theta_1, \dots, \boldsymbol\eta]$ | (4.3) |
//! | $[\boldsymbol\Phi_j]$ | `Phi_j` | 6 frame-fixing rows, $\boldsymbol\Phi_j\mathbf q^{jj} = 0$ | (4.4) |
//! | $[\boldsymbol\Phi_{rig}]$ | `Phi_rig` | rigid modes of the deformed interface set | (5.2) |
//! | $\boldsymbol\Lambda$ | `Lambda` | $\mathrm{diag}(\mathbf I, \mathbf J_l^{-1}(\boldsymbol\theta_k), \dots, \mathbf I)$ | this crate |
//! | $\mathbf Z_j,\ \mathbf T_j$ | `Z`, `T` | frame and deformation projectors (with $\boldsymbol\Psi = \boldsymbol\Lambda\boldsymbol\Phi_{rig}$) | (5.4)-(5.5) |
//! | $[\bar{\mathbf R}^j_O]$ | `rotate(.., false)` | block-diagonal $\mathbf R_j^T$ (identity on $\boldsymbol\eta$) | (5.2) |
//! | $\mathbf A$ | `velocity_transform` | FFR velocities from absolute ones | (5.6) |
//! | $\mathbf Y,\ \mathbf B$ | `Y`, `B` | $\mathbf Z_j\boldsymbol\Lambda$, $\mathbf T_j\boldsymbol\Lambda$; $\mathbf P = [\mathbf Y; \mathbf B]$ | this crate |
//! | $\mathbf y,\ \mathbf a$ | `y`, `a` | $\bar{\mathbf R}^T\dot{\mathbf q}$, $\bar{\mathbf R}^T\ddot{\mathbf q}$ | |
//! | $\boldsymbol\nu = [\mathbf V; \boldsymbol\Omega; \dot{\mathbf q}^{jj}]$ | `nu` | FFR body-axis quasi-velocities | [`mass`] |
//! | $\mathbf M_{CB},\ \mathbf K_{CB}$ | `M_CB`, `K_CB` | reduced mass, stiffness | (6.5) |
//! | $\mathbf G_k$ | [`GeometricStiffness`] `G[k]` | reduced geometric stiffness of the stress of CB coordinate $k$ ($n\times n$, symmetric) | \[WW03\], `reduction` |
//! | $U_3$ | `GeometricStiffness::energy` | $\tfrac12\sum_k q_k\,\mathbf q^{jjT}\mathbf G_k\mathbf q^{jj}$, cubic strain energy | \[WW03\] |
//! | $\mathbf b,\ \mathbf p$ | `G_b`, `G_p` | $b_m = \tfrac12\mathbf q^{jjT}\mathbf G_m\mathbf q^{jj}$, $\mathbf p = \mathbf K_{CB}^+\mathbf b$ | this crate |
//! | $U_4$ | `GeometricStiffness::energy` | $\tfrac12\mathbf b^T\mathbf K_{CB}^+\mathbf b$, projected quartic strain energy | this crate |
//! | $\mathbf g_G,\ \mathbf H_G$ | `g_G`, `K_g` | gradient and Hessian of $U_3 + U_4$ in $\mathbf q^{jj}$ | this crate |
//! | $\mathbf M_{ffr}$ | `FfrInertia::mass_matrix` | FFR mass matrix from the invariants | (6.1) |
//! | $\mathbf Q_v$ | `q_v` | quadratic velocity forces | (6.5) |
//! | $\mathbf K_t,\ \mathbf C_t$ | `stiffness`, `damping` | $\partial\mathbf r/\partial\mathbf q$, $\partial\mathbf r/\partial\dot{\mathbf q}$ | \[S19\] |
//! | $\mathcal I$ | `PlanarBody::index` | planar index set: x, y, rz of every interface and the modes ($3N + m$) | [`planar`] |
//! | $\varphi_k,\ \varphi_j$ | `angle_of` | angle about z of $\mathbf R_k$, $\mathbf R_j$ (planar body) | [`planar`] |
//! | $\mathbf E$ | | $[0, -1;\ 1, 0]$, the planar cross product with $\mathbf e_z$ | [`planar`] |
//! | $\boldsymbol\rho_k$ | `rho` | deformed local interface position (planar $\mathbf r_k^{jj}$) | [`planar`] |
//! | $\bar{\mathbf y}$ | `ybar` | $\dot{\boldsymbol\nu} = \mathbf P\bar{\mathbf y}$ (planar body) | (7.6) |
//! | $\mathbf p_a,\ \mathbf v_a$ | [`Superelement::recover_mesh`], [`Superelement::recover_mesh_velocities`] | position and velocity of mesh node $a$ | (10.1) |
//!
//! Superscripts: a quantity without a frame marker is in inertial axes; body-axis quantities
//! are named in the docs ("body axes", superscript $L$). Vectors are columns.
//!
//! # Equation map
//!
//! | eq. | meaning | function |
//! |---|---|---|
//! | (4.3) | local CB coordinates $\mathbf u_k$, $\boldsymbol\theta_k$ | `superelement::local_coordinates::local_coordinates` |
//! | (4.4) | frame fixed to body, $\boldsymbol\Phi_j\mathbf q^{jj} = 0$ (Newton) | `superelement::Superelement::solve_frame` (`frame.rs`) |
//! | (5.2) | rigid modes of the deformed interface set | `superelement::transform::phi_rig` |
//! | (5.4)-(5.5) | $\mathbf Z_j$, $\mathbf T_j$ (exact form, with $\boldsymbol\Lambda$) | `superelement::transform::Kinematics::update` |
//! | (5.4) | frame velocity | `superelement::Superelement::frame_velocity` (`body.rs`) |
//! | (5.6) | velocity transformation $\mathbf A$ | `superelement::transform::Kinematics::velocity_transform` |
//! | (6.1) | FFR mass matrix from the inertia invariants | `superelement::mass::FfrInertia::mass_matrix` |
//! | (6.4) | FFR inertia force $\mathbf M_{ffr}\dot{\boldsymbol\nu} + \mathbf h$ and partials | `superelement::mass::FfrInertia::force_into` |
//! | (6.4) | the FFR inertia force alone, without $\mathbf M_{ffr}$ and with the contractions the force needs ($12n^2$ multiply-adds) | `superelement::mass::FfrInertia::force_only_into` |
//! | (6.4)-(6.7) | the residual $\bar{\mathbf R}\mathbf P^T(\dots)$ and its parts without any mass matrix | `superelement::Superelement::residual_into` (`tangent.rs`) |
//! | (6.4) | `Exact` inertia in absolute coordinates, $\mathbf A^T(\dots)$ | `superelement::Superelement::exact_inertia` (`forces.rs`) |
//! | (6.5) | elastic force $\bar{\mathbf R}\mathbf T_j^T\mathbf K_{CB}\mathbf q^{jj}$ (plus $\mathbf g_G$) | `superelement::Superelement::elastic` (`forces.rs`) |
//! | \[WW03\], this crate | geometric stiffening $\mathbf g_G$, $\mathbf H_G$ of $U_3 + U_4$ | `superelement::GeometricStiffness::gradient_into` (`forces.rs`) |
//! | (6.6) | `Lumped` inertia, $\bar{\mathbf R}\mathbf M_{CB}\bar{\mathbf R}^T$ and its $\mathbf Q_v$ | `superelement::Superelement::lumped_inertia` (`forces.rs`) |
//! | \[S19\] | tangents $\mathbf K_t$, $\mathbf C_t$, $\mathbf M$ (chain rule to absolute coordinates) | `superelement::Superelement::evaluate_local` (`tangent.rs`) |
//! | (7.6)-(7.8) | the planar body: residual, closed-form $\mathbf M$, $\mathbf C_t$, $\mathbf K_t$ by dual numbers | `superelement::planar::PlanarBody::core`, `mass_damping`, `stiffness_pass`; `Superelement::planar_evaluate` (`tangent.rs`) |
//!
//! The `forces.rs` and `tangent.rs` functions are crate-private methods of [`Superelement`];
//! [`Superelement::evaluate`] is their public entry point.
//!
//! # Geometric stiffening
//!
//! A Craig-Bampton body in a floating frame has a *linear* elastic field: its strain energy
//! $\tfrac12\mathbf q^{jjT}\mathbf K_{CB}\mathbf q^{jj}$ is that of the small strain
//! $\boldsymbol\varepsilon(\mathbf u)$ of the local displacement $\mathbf u = \mathbf V\mathbf q^{jj}$. The
//! frame carries the large rigid rotation exactly, but what the local field misses is the
//! second-order part of the Green-Lagrange strain, $\mathbf E = \boldsymbol\varepsilon(\mathbf u) +
//! \tfrac12\nabla\mathbf u^T\nabla\mathbf u$: through it an axial force changes the bending stiffness
//! (a column's buckling, a rotor's centrifugal stiffening). With the linear stress
//! $\boldsymbol\sigma(\mathbf u) = \sum_k q_k\boldsymbol\sigma(\mathbf v_k)$ of the CB basis vectors $\mathbf v_k$, the
//! third-order term of $\int\tfrac12\mathbf E:\mathbf C:\mathbf E\,dV$ is
//!
//! $$U_3 = \int_V\boldsymbol\sigma(\mathbf u) : \tfrac12\nabla\mathbf u^T\nabla\mathbf u\,dV =
//! \tfrac12\sum_k q_k\,\mathbf q^T\mathbf G_k\mathbf q,\qquad
//! \mathbf G_k = \mathbf V^T\mathbf K_\sigma(\boldsymbol\sigma(\mathbf v_k))\mathbf V,$$
//!
//! $\mathbf K_\sigma$ the FE geometric (initial-stress) stiffness: the modal geometric stiffening
//! of FFR bodies with one reduced geometric stiffness matrix per elastic coordinate, as in
//! Wallrapp & Wiedemann \[WW03\] (O. Wallrapp, S. Wiedemann, "Comparison of results in
//! flexible multibody dynamics using various approaches", Nonlinear Dynamics 34 (2003); see
//! also the geometric stiffness terms of Simpack's Standard Input Data).
//!
//! **The quartic term.** $U_3$ alone is not enough in a mechanism. In a slender rod the
//! quadratic strain of the bending ($\tfrac12 w'^2 \approx 10^{-3}$ at a deflection of $L/60$)
//! is far larger than the axial strain ($N/EA \approx 5\cdot10^{-5}$ in C2); the axial coordinates
//! take it up (the ends shorten the chord), their linear stress $\boldsymbol\sigma(\mathbf u)$ then
//! holds a spurious compression $-E\tfrac12 w'^2$, and $U_3$ turns it into a softening
//! $-\tfrac12 EA\,w'^3$ that the quartic term of $\mathbf E:\mathbf C:\mathbf E$ would cancel: the C2 rod
//! with $U_3$ only loses Newton convergence within 50 steps. The full quartic term is not
//! usable either: a CB basis cannot represent the non-uniform shortening $\tfrac12 w'^2(x)$, and
//! its energy locks the bending (membrane locking). We keep the part of the quadratic strain
//! that the basis can represent: its energy projection onto the linear strains of the basis,
//! the CB coordinates $\mathbf p = \mathbf K_{CB}^+\mathbf b$ with $b_m = \tfrac12\mathbf q^T\mathbf G_m\mathbf q$ (the
//! work of the quadratic strain on the stress of coordinate $m$). Then
//!
//! $$U = \tfrac12\mathbf q^T\mathbf K_{CB}\mathbf q + U_3 + U_4,\qquad U_4 = \tfrac12\mathbf b^T\mathbf K_{CB}^+\mathbf b,$$
//!
//! which is $\tfrac12(\mathbf q + \mathbf p)^T\mathbf K_{CB}(\mathbf q + \mathbf p)$: the strain energy of
//! $\boldsymbol\varepsilon(\mathbf u) + \Pi\,\tfrac12\nabla\mathbf u^T\nabla\mathbf u$ ($\Pi$: the
//! $\mathbf C$-orthogonal projection on the strains of the basis). For a beam this is the classical
//! consistent model with the mean axial strain $\Delta L/L + \frac1{2L}\int w'^2dx$ (Kane, Ryan &
//! Banerjee's stretch coordinate); to third order it is $U_3$, so linearised buckling and
//! small-deflection results are unchanged. With it one hex20 superelement (frame at the centre
//! of mass) is within 0.1 % of the converged C2 peak.
//!
//! **Why it fits AIC-FFR.** $U$ depends on the body only through $\mathbf q^{jj}$, the
//! deformation measured in the floating frame, and $\delta\mathbf q^{jj} = \mathbf B\bar{\mathbf R}^T\delta\mathbf q$
//! exactly. So the elastic force stays the exact gradient of $U$ in absolute interface
//! coordinates, $\bar{\mathbf R}\mathbf B^T(\mathbf K_{CB}\mathbf q^{jj} + \mathbf g_G)$, its tangent is the old
//! one with $\mathbf K_{CB} \to \mathbf K_{CB} + \mathbf H_G$ (the projector terms fed with the new local
//! force), and it is invariant under rigid motion whatever the frame choice. The frame takes
//! the rigid rotation, the linear local coordinates the small strain, and $U_3 + U_4$ the
//! quadratic strain terms that linear local coordinates leave out. The quadratic strain is
//! accurate while the rotations *relative to the frame* are small: choose the centre-of-mass
//! frame (on C2 the frame at an end interface is 10 % off with $\mathbf G$, the centre of mass
//! 0.1 %).
//!
//! # Modules
//!
//! [`so3`] rotations; [`state`] the plain data (frame, frame choice, body state);
//! [`compressed`] the geometric stiffness by its nonzero entries;
//! [`local_coordinates`]; [`transform`] (5.2)-(5.6) and their derivatives; [`frame`] the Newton
//! solve of (4.4); [`mass`] FFR inertia; [`planar`] the planar kernel (with the dual numbers of
//! `dual`); [`body`] the superelement; [`forces`] body-axis forces
//! and partials; [`tangent`] the residual and tangents; [`recovery`] the deformed mesh;
//! [`testing`] helpers. Each module uses only the ones before it in this list (no circles).

#![allow(non_snake_case)]

pub mod body;
pub mod compressed;
pub(crate) mod dual;
pub mod error;
pub mod forces;
pub mod frame;
pub mod local_coordinates;
pub mod mass;
pub mod planar;
pub mod point_load;
pub mod recovery;
pub mod so3;
pub mod state;
pub mod tangent;
pub mod testing;
pub mod transform;

pub use body::{BodyState, Damping, GeometricStiffness, Superelement};
pub use error::SuperelementError;
pub use frame::{Frame, FrameChoice, FrameSettings};
pub use mass::{FfrForce, FfrInertia, FfrScratch, MassVariant};
pub use point_load::{PointLoad, PointLoadWorkspace};
pub use recovery::{BodyStress, MeshState};
pub use tangent::{Evaluation, Workspace};
pub use transform::Kinematics;
