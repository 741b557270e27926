//! # superelement: the AIC-FFR body
//!
//! The absolute-interface-coordinate floating frame of reference superelement of the seed
//! paper (Schilder, Ellenbroek, de Boer; \[E17\], \[S19\]): from a Craig-Bampton
//! [`reduction::ReducedBody`] and a state in absolute interface coordinates, the frame (2.6),
//! the local CB coordinates, the velocity transformation (3.9)-(3.11), the forces (4.3)-(4.4)
//! and the tangent matrices for Newton, for one body at a time.
//!
//! ```text
//! ReducedBody + FrameChoice + MassVariant + Damping  --Superelement::new-->  Superelement
//! BodyState (r_k, R_k, v_k, omega_k, eta, eta_dot, last frame) + accelerations + gravity
//!     --evaluate / evaluate_into-->  Evaluation { frame, q_jj, residual, M, K_t, C_t, force parts }
//! ```
//!
//! # API
//!
//! * [`Superelement::new`]`(&ReducedBody, FrameChoice, MassVariant, Damping)` checks every
//!   shape and precomputes the invariants about the frame origin.
//! * [`Superelement::solve_frame`] solves (2.6) from `state.frame` (warm start);
//!   [`Superelement::kinematics`] adds $\mathbf q^{jj}$, $\mathbf Z_j$, $\mathbf T_j$, $\mathbf A$
//!   ([`Kinematics`]); [`Superelement::frame_velocity`] and [`Superelement::local_velocity`] give
//!   (3.9) and (3.10) applied to the state's velocities.
//! * [`Superelement::evaluate`] returns the residual $\mathbf r = \mathbf M\ddot{\mathbf q} + \mathbf Q_v +
//!   \mathbf f_{el} + \mathbf f_d - \mathbf f_g$, its parts and $\mathbf M$, $\mathbf K_t$, $\mathbf C_t$
//!   as faer matrices; [`Superelement::evaluate_into`] does the same into a reused
//!   [`Workspace`] and [`Evaluation`] (no allocation; the hot-loop form);
//!   [`Superelement::forces`] skips the tangents.
//! * [`Superelement::kinetic_energy`], [`Superelement::strain_energy`],
//!   [`Superelement::gravity_potential`]; [`Superelement::recover_mesh`] for the deformed mesh.
//! * [`testing`]: the central-difference helper, state perturbations through exp, test states,
//!   and (feature `testing`) reduced-body fixtures.
//!
//! //! The superelement's coordinates are $\mathbf q = [\mathbf r_1, \boldsymbol\pi_1, \dots,
//! \mathbf r_N, \boldsymbol\pi_N, \boldsymbol\eta]$ ($6N + m$): absolute interface positions and
//! orientations (varied spatially, $\delta\mathbf R_k = \widetilde{\delta\boldsymbol\pi}_k\mathbf R_k$)
//! and the fixed-interface modal coordinates, which stay independent coordinates of the body.
//!
//! ## Where this crate goes beyond the seed
//!
//! * The CB rotation coordinates are rotation vectors, so their variation carries
//!   $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ ($\boldsymbol\Lambda$): (3.7)-(3.11) are used in their
//!   exact form ([`transform`]); for small elastic rotations they are the seed's.
//! * The `Lumped` inertia of (4.4) is given a kinetic energy, so its $\mathbf Q_v$ is derived
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
//! | symbol | Rust | meaning | source |
//! |---|---|---|---|
//! | $\{P_j, E_j\}$ → $\mathbf r_j,\ \mathbf R_j$ | [`Frame`] `r`, `R`; `R_j` | floating frame: origin (material point $P_j$), rotation | §2 |
//! | $\mathbf r_k,\ \mathbf R_k$ | [`BodyState`] `r`, `R` | absolute interface position, orientation | §3 |
//! | $\mathbf v_k,\ \boldsymbol\omega_k$ | `v`, `omega` | interface velocity, spatial angular velocity | |
//! | $\delta\mathbf q^{OO}$ | `dq` | $[\delta\mathbf r_1, \delta\boldsymbol\pi_1, \dots, \delta\boldsymbol\eta]$, spatial | (3.5) |
//! | $\mathbf x_k$ | `x` | undeformed interface position from $P_j$, body axes | §2 |
//! | $\mathbf u_k,\ \boldsymbol\theta_k$ | `q_jj` blocks | $\mathbf R_j^T(\mathbf r_k - \mathbf r_j) - \mathbf x_k$, $\log(\mathbf R_j^T\mathbf R_k)$ | brief §4 |
//! | $\mathbf q^{j,j}$ | `q_jj` | local CB coordinates $[\mathbf u_1, \boldsymbol\theta_1, \dots, \boldsymbol\eta]$ | (2.3) |
//! | $[\boldsymbol\Phi_j]$ | `Phi_j` | 6 frame-fixing rows, $\boldsymbol\Phi_j\mathbf q^{jj} = 0$ | (2.6) |
//! | $[\boldsymbol\Phi_{rig}]$ | `Phi_rig` | rigid modes of the deformed interface set | (3.6) |
//! | $\boldsymbol\Lambda$ | `Lambda` | $\mathrm{diag}(\mathbf I, \mathbf J_l^{-1}(\boldsymbol\theta_k), \dots, \mathbf I)$ | this crate |
//! | $\mathbf Z_j,\ \mathbf T_j$ | `Z`, `T` | frame and deformation projectors (with $\boldsymbol\Psi = \boldsymbol\Lambda\boldsymbol\Phi_{rig}$) | (3.9)-(3.10) |
//! | $[\bar{\mathbf R}^j_O]$ | `rotate(.., false)` | block-diagonal $\mathbf R_j^T$ (identity on $\boldsymbol\eta$) | (3.6) |
//! | $\mathbf A$ | `velocity_transform` | FFR velocities from absolute ones | (3.11) |
//! | $\mathbf Y,\ \mathbf B$ | `Y`, `B` | $\mathbf Z_j\boldsymbol\Lambda$, $\mathbf T_j\boldsymbol\Lambda$; $\mathbf P = [\mathbf Y; \mathbf B]$ | this crate |
//! | $\mathbf y,\ \mathbf a$ | `y`, `a` | $\bar{\mathbf R}^T\dot{\mathbf q}$, $\bar{\mathbf R}^T\ddot{\mathbf q}$ | |
//! | $\boldsymbol\nu = [\mathbf V; \boldsymbol\Omega; \dot{\mathbf q}^{jj}]$ | `nu` | FFR body-axis quasi-velocities | [`mass`] |
//! | $\mathbf M_{CB},\ \mathbf K_{CB}$ | `M_CB`, `K_CB` | reduced mass, stiffness | (4.4) |
//! | $\mathbf G_k$ | [`GeometricStiffness`] `G[k]` | reduced geometric stiffness of the stress of CB coordinate $k$ ($n\times n$, symmetric) | \[WW03\], `reduction` |
//! | $U_3$ | `GeometricStiffness::energy` | $\tfrac12\sum_k q_k\,\mathbf q^{jjT}\mathbf G_k\mathbf q^{jj}$, cubic strain energy | \[WW03\] |
//! | $\mathbf b,\ \mathbf p$ | `G_b`, `G_p` | $b_m = \tfrac12\mathbf q^{jjT}\mathbf G_m\mathbf q^{jj}$, $\mathbf p = \mathbf K_{CB}^+\mathbf b$ | this crate |
//! | $U_4$ | `GeometricStiffness::energy` | $\tfrac12\mathbf b^T\mathbf K_{CB}^+\mathbf b$, projected quartic strain energy | this crate |
//! | $\mathbf g_G,\ \mathbf H_G$ | `g_G`, `K_g` | gradient and Hessian of $U_3 + U_4$ in $\mathbf q^{jj}$ | this crate |
//! | $\mathbf M_{ffr}$ | `FfrInertia::mass_matrix` | FFR mass matrix from the invariants | (4.1) |
//! | $\mathbf Q_v$ | `q_v` | quadratic velocity forces | (4.4) |
//! | $\mathbf K_t,\ \mathbf C_t$ | `stiffness`, `damping` | $\partial\mathbf r/\partial\mathbf q$, $\partial\mathbf r/\partial\dot{\mathbf q}$ | \[S19\] |
//!
//! Superscripts: a quantity without a frame marker is in inertial axes; body-axis quantities
//! are named in the docs ("body axes", superscript $L$). Vectors are columns.
//!
//! # Equation map
//!
//! | eq. | meaning | function |
//! |---|---|---|
//! | (2.3), brief §4 | local CB coordinates $\mathbf u_k$, $\boldsymbol\theta_k$ | `superelement::local_coordinates::local_coordinates` |
//! | (2.6) | frame fixed to body, $\boldsymbol\Phi_j\mathbf q^{jj} = 0$ (Newton) | `superelement::Superelement::solve_frame` (`frame.rs`) |
//! | (3.6) | rigid modes of the deformed interface set | `superelement::transform::phi_rig` |
//! | (3.9)-(3.10) | $\mathbf Z_j$, $\mathbf T_j$ (exact form, with $\boldsymbol\Lambda$) | `superelement::transform::Kinematics::update` |
//! | (3.9) | frame velocity | `superelement::Superelement::frame_velocity` (`body.rs`) |
//! | (3.11) | velocity transformation $\mathbf A$ | `superelement::transform::Kinematics::velocity_transform` |
//! | (4.1) | FFR mass matrix from the inertia invariants | `superelement::mass::FfrInertia::mass_matrix` |
//! | (4.3) | FFR inertia force $\mathbf M_{ffr}\dot{\boldsymbol\nu} + \mathbf h$ and partials | `superelement::mass::FfrInertia::force_into` |
//! | (4.3) | `Exact` inertia in absolute coordinates, $\mathbf A^T(\dots)$ | `superelement::Superelement::exact_inertia` (`forces.rs`) |
//! | (4.4) | elastic force $\bar{\mathbf R}\mathbf T_j^T\mathbf K_{CB}\mathbf q^{jj}$ (plus $\mathbf g_G$) | `superelement::Superelement::elastic` (`forces.rs`) |
//! | \[WW03\], this crate | geometric stiffening $\mathbf g_G$, $\mathbf H_G$ of $U_3 + U_4$ | `superelement::GeometricStiffness::gradient_into` (`forces.rs`) |
//! | (4.4) | `Lumped` inertia, $\bar{\mathbf R}\mathbf M_{CB}\bar{\mathbf R}^T$ and its $\mathbf Q_v$ | `superelement::Superelement::lumped_inertia` (`forces.rs`) |
//! | \[S19\] | tangents $\mathbf K_t$, $\mathbf C_t$, $\mathbf M$ (chain rule to absolute coordinates) | `superelement::Superelement::evaluate_local` (`tangent.rs`) |
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
//! [`so3`] rotations; [`local_coordinates`]; [`frame`] (2.6); [`transform`] (3.6)-(3.11) and
//! their derivatives; [`mass`] FFR inertia; [`forces`] body-axis forces and partials;
//! [`tangent`] the residual and tangents; [`recovery`] the deformed mesh; [`testing`] helpers.

#![allow(non_snake_case)]

pub mod body;
pub mod error;
pub mod forces;
pub mod frame;
pub mod local_coordinates;
pub mod mass;
pub mod recovery;
pub mod so3;
pub mod tangent;
pub mod testing;
pub mod transform;

pub use body::{BodyState, Damping, GeometricStiffness, Superelement};
pub use error::SuperelementError;
pub use frame::{Frame, FrameChoice, FrameSettings};
pub use mass::{FfrForce, FfrInertia, FfrScratch, MassVariant};
pub use recovery::{BodyStress, MeshState};
pub use tangent::{Evaluation, Workspace};
pub use transform::Kinematics;
