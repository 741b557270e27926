//! # reduction: Craig-Bampton reduction of flexible bodies
//!
//! The second stage of the flexmbs pipeline (theory guide §1, §3):
//!
//! ```text
//! FE model (K, M sparse) + interfaces -> constraint modes Psi + fixed-interface modes Phi_i
//!     -> K_CB, M_CB, inertia invariants -> ReducedBody (saved, reused by many simulations)
//! ```
//!
//! [`eigen`] is the sparse generalised eigensolver underneath: the lowest modes of
//! $\mathbf K\boldsymbol\phi = \omega^2\mathbf M\boldsymbol\phi$ by shift-invert Lanczos on a
//! sparse Cholesky factor, and [`ShiftInvert`], the one factorisation of $\mathbf K_{ii}$ that
//! gives both the constraint modes and the fixed-interface modes.
//!
//! # Quick start
//!
//! Reduce a beam with interfaces at both ends and two fixed-interface modes. Its fixed
//! interfaces make it a clamped-clamped beam, whose first frequency is
//! $(4.7300)^2\sqrt{EI/(\rho AL^4)}$ (theory guide, section 3.2):
//!
//! ```
//! use fe_model::{generate, BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind};
//! use nalgebra::{Point3, Vector3};
//! use reduction::{reduce, CbSettings, ModeSelection};
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
//! let nodes = generate::straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 16, &props, None)?;
//! let interfaces = vec![("a".to_string(), nodes[0]), ("b".to_string(), nodes[16])];
//! let body = reduce(&model, "beam", &interfaces, &CbSettings::new(ModeSelection::Count(2)))?;
//!
//! assert_eq!(body.n_coordinates(), 12 + 2); // 6 per interface, one per mode
//! let (ei, rho_a) = (210e9 * 0.02_f64.powi(4) / 12.0, 7850.0 * 0.02 * 0.02);
//! let omega_1 = 4.73004074_f64.powi(2) * (ei / rho_a).sqrt();
//! // The discretisation error of 16 cubic elements is about 1e-6; the section's rotary
//! // inertia, which the Euler-Bernoulli formula leaves out, lowers it by 2e-4 at L/h = 50.
//! let first = body.fixed_interface_omega[0];
//! assert!((first / omega_1 - 1.0).abs() < 1e-3, "{first} rad/s against {omega_1}");
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
//! | $\mathbf K,\ \mathbf M$ | `K`, `M` | sparse symmetric stiffness ($\succeq 0$) and mass ($\succ 0$), both triangles stored | theory guide §3 |
//! | $\mathbf K_{ii},\ \mathbf K_{ib},\ \mathbf K_{bb}$ (and of $\mathbf M$) | `K_ii`, `K_ib`, `K_bb` | blocks of the free-dof matrices on the internal ($i$) and boundary ($b$, the interface nodes' six dofs) dofs; $\mathbf K_{ii}$ sparse, the others dense | [`craig_bampton`] module docs |
//! | $\mathbf V_i$ | `V_i` | internal rows of the CB basis, $[\boldsymbol\Psi\ \boldsymbol\Phi_i]$ | [`craig_bampton`] module docs |
//! | $\lambda_k = \omega_k^2,\ \boldsymbol\phi_k$ | `eigenvalues[k]`, `vectors.col(k)` | eigenpair of $\mathbf K\boldsymbol\phi = \lambda\mathbf M\boldsymbol\phi$, ascending, $\boldsymbol\Phi^T\mathbf M\boldsymbol\Phi = \mathbf I$ | [`eigen::EigenSolution`] |
//! | $m$ | `n_modes` | number of lowest modes wanted | [`eigen::EigenSettings`] |
//! | $\sigma$ | `sigma`, `shift` | spectral shift, $\sigma < \lambda_1$; negative for a free body | [`eigen::Shift`]; Ericsson & Ruhe 1980 |
//! | $\mathbf P$ | `perm_fwd`, `perm_inv` | fill-reducing permutation of the factor (AMD or nested dissection) | `fe_model::ordering` |
//! | $\mathbf L$ | `L_values` | Cholesky factor, $\mathbf P(\mathbf K - \sigma\mathbf M)\mathbf P^T = \mathbf L\mathbf L^T$ | [`eigen::ShiftInvert`] |
//! | $\mathbf C$ | `Operator` | shift-invert operator $\mathbf L^{-1}\mathbf P\mathbf M\mathbf P^T\mathbf L^{-T}$, symmetric | [`eigen`] module docs |
//! | $\hat{\mathbf L}$ | `Values::Single` | the factor in single precision ([`eigen::FactorPrecision`]): half the bytes, solves accurate to $\kappa\,\varepsilon_{32}$ | `fe_model::SparseCholesky` |
//! | $\mathbf R,\ \eta$ | `R`, `eta` | refinement residual $\mathbf B - (\mathbf K - \sigma\mathbf M)\mathbf X$ (f64) and normwise backward error $\|\mathbf r\|_\infty / (\|\mathbf A\|_\infty\|\mathbf x\|_\infty + \|\mathbf b\|_\infty)$, refined to $\max(\sqrt n, c)\,\varepsilon_{64}$ | [`eigen::ShiftInvert::solve_refined`]; Rigal & Gaches 1967 |
//! | $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$ | `WholeOperator` | shift-invert operator by whole refined solves, self-adjoint in the $\mathbf M$ inner product (single-precision factor); basis $\mathbf V$ with $\mathbf V^T\mathbf M\mathbf V = \mathbf I$, `MV` $= \mathbf M\mathbf V$ | [`eigen`] module docs |
//! | $\mu_k,\ \mathbf y_k$ | `mu`, `Y` | eigenpairs of $\mathbf C$: $\mu_k = 1/(\lambda_k - \sigma)$, $\mathbf y_k = \mathbf L^T\mathbf P\boldsymbol\phi_k$ | Grimes, Lewis & Simon 1994, §2 |
//! | $\mathbf V_k,\ \mathbf T_k,\ \beta_k$ | `V`, `T`, `beta` | Lanczos basis, projected matrix, coupling: $\mathbf C\mathbf V_k = \mathbf V_k\mathbf T_k + \beta_k\mathbf v_{k+1}\mathbf e_k^T$ | Wu & Simon 2000 |
//! | $p$ | `krylov_dim` | Krylov subspace dimension, default $\max(2m, m + 32)$ with single vectors, $\max(2m, m + 32, m + 16b)$ with blocks | [`eigen::EigenSettings`] |
//! | $b$ | `block_size` | Lanczos block size: $\mathbf C$ applied to $b$ vectors at once (the factor read once for them); automatic: 4 from 100k dofs, else 1, with a single-vector retry if a block run stalls | [`eigen::AUTO_BLOCK_SIZE`], [`eigen::BLOCK_MIN_DOFS`] |
//! | $\mathbf G_k$ | `geometric_stiffness[k]` | reduced geometric stiffness $\mathbf V^T\mathbf K_G(\boldsymbol\sigma(\mathbf V\mathbf e_k))\mathbf V$; strain energy $\tfrac12\mathbf q^T\mathbf K_{CB}\mathbf q + \tfrac12\sum_k q_k\mathbf q^T\mathbf G_k\mathbf q$ | [`geometric`]; `fe_model::geometric` |
//! | $\boldsymbol\Sigma$ | `StressShapes` | stress of every CB vector: solid nodal stresses ($6n_{nodes}\times n$), beam section forces ($12n_{beams}\times n$) | [`stress`] |
//! | $\mathbf T$, $c_i$ | `VonMisesMaximum` | whitening of the CB coordinates by the von Mises stress they cause over a node set; node $i$'s worst-case von Mises per unit whitened change | [`stress`] |
//! | $\tilde{\mathbf A}_i$, $\hat v_i$, $m_i$ | `screen`, `screen_chunk_factors` | single-precision $\mathbf M^{1/2}\boldsymbol\Sigma_i$ of the batched search; its von Mises estimate and that estimate's bound (theory guide (10.4)) | [`VonMisesMaximum::maxima`] |
//! | $\mathbf u$, $w_i$ | `VonMisesReference` | whitened direction of the first nonzero state; node $i$'s von Mises stress of $\mathbf T^{-1}\mathbf u$ | [`stress`] |
//! | $\mathbf X$, $\hat\omega$ | `attachment_modes` | attachment modes of load points (static correction) and their Rayleigh frequencies | [`attachment`] |
//! | $r_k$ | `residuals[k]` | $\|\mathbf K\boldsymbol\phi_k - \lambda_k\mathbf M\boldsymbol\phi_k\| / \max(\|\mathbf K\boldsymbol\phi_k\|, \lvert\lambda_k - \sigma\rvert\,\|\mathbf M\boldsymbol\phi_k\|)$ | [`eigen::relative_residual`] |
//!
//! Vectors are columns; `^T` is transpose. Dof indices in errors are those of the matrices
//! as given, never of the permuted factor.
#![allow(non_snake_case)]
pub mod attachment;
pub mod checks;
pub mod craig_bampton;
pub mod diagnostics;
pub mod eigen;
pub mod error;
pub mod geometric;
pub mod invariants;
pub mod io;
pub mod modal;
pub mod reduced_body;
pub mod stress;
pub use checks::{check_body, physical_problems, BodyCheckError, Measurements, PhysicsProblem};
pub use craig_bampton::{partition, reduce, reduce_with_progress, CbSettings, ModeSelection, Partition, Stage};
pub use craig_bampton::{planar_model, reduce_external, reduce_external_dofs, IN_PLANE_DOFS, OUT_OF_PLANE_DOFS};
pub use diagnostics::{diagnostics, DiagnosticWarning, Diagnostics, ModeDiagnostics};
pub use eigen::{lowest_modes, EigenSettings, EigenSolution, FactorPrecision, FactorSettings, Shift, ShiftInvert};
pub use error::ReductionError;
/// The rigid modes of six-dof point sets (fe-model's), re-exported for the superelement.
pub use fe_model::rigid::{rigid_modes, rigid_motion_block};
pub use geometric::reduced_geometric_stiffness;
/// [`io::rbody`] under the short path the other crates name, `reduction::file`.
pub use io::rbody as file;
pub use io::rbody::BodyFileProblem;
/// [`io::matrix_market`] and [`io::mbdyn`] under their short paths.
pub use io::{matrix_market, mbdyn};
pub use matrix_market::{read_matrix_market, write_matrix_market};
pub use mbdyn::{read_mbdyn_fem, write_mbdyn_fem, FemError};
pub use modal::modal_sparse;
pub use reduced_body::{
    BeamStressElement, DenseMatrix, InertiaData, InterfacePoint, LoadPoint, MeshModes, ReducedBody, StressShapes,
    ALGORITHM_REVISION, FORMAT_VERSION,
};
pub use stress::{NodeStresses, VonMisesMaximum, VonMisesReference};
