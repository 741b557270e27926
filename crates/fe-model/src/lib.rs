//! # fe-model: 3D beam and solid finite-element models
//!
//! The first stage of the flexmbs pipeline (see `ARCHITECTURE.md`):
//!
//! ```text
//! mesh (.msh or generated) -> FeModel -> DofMap + SystemPattern -> sparse K, M -> statics / modes
//! ```
//!
//! A [`FeModel`] holds a [`Mesh`] (nodes, cells, named sets), materials, beam sections,
//! elements, supports and linear constraints. [`DofMap`] numbers the independent dofs after
//! eliminating supports and constraints; [`SystemPattern`] is the symbolic phase of assembly
//! (done once); [`assemble`] fills the values in parallel. [`solve_static`] and
//! [`modal_dense`] are the linear analyses of this stage, with [`linear_buckling`] on the
//! geometric stiffness of [`geometric`].
//!
//! Sparse Cholesky factorisations ([`SparseCholesky`], used here by [`solve_static`] and by
//! `reduction`) order the unknowns by nested dissection on the node positions for large
//! models, by AMD otherwise ([`ordering`], [`FillOrdering`]).
//!
//! Meshes come from gmsh ([`mesh::gmsh`]), Abaqus ([`mesh::abaqus`]) and Nastran
//! ([`mesh::nastran`]) files, or from the generators ([`box_mesh`](mod@box_mesh), [`generate`]).
//!
//! What this crate does not do: rotations of bodies, time, reduction.
//!
//! # Quick start
//!
//! A steel cantilever of eight Euler-Bernoulli beams under a tip force; the cubic beam
//! element is exact for end loads, so the tip deflection is $PL^3/(3EI)$ to round-off:
//!
//! ```
//! use fe_model::{generate, solve_static, BeamProperties, BeamSection, BeamTheory, DofMask, FeModel};
//! use fe_model::{IsotropicMaterial, MassKind, NodalLoad};
//! use nalgebra::{Point3, Vector3};
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
//! let nodes = generate::straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 8, &props, None)?;
//! model.add_support(nodes[0], DofMask::ALL);
//!
//! let p = 100.0; // N, along -y at the tip
//! let solution = solve_static(&model, &[NodalLoad::force(nodes[8], Vector3::new(0.0, -p, 0.0))])?;
//! let w = solution.displacements[nodes[8].index()][1];
//! let ei = 210e9 * 0.02_f64.powi(4) / 12.0;
//! let exact = -p / (3.0 * ei);
//! // Round-off of a well-conditioned solve of 48 unknowns: far below 1e-9.
//! assert!((w - exact).abs() < 1e-9 * exact.abs(), "{w} against {exact}");
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
//! | $\mathbf X$ | `X`, `X_e` | reference nodal coordinates (of one element) | |
//! | $\mathbf u$ | `u` | nodal dofs $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$ per node | theory guide §2 |
//! | $\mathbf T$ | `DofMap` rows | full dofs from independent dofs, $\mathbf u = \mathbf T \mathbf u_f$ | elimination of supports and constraints |
//! | $\mathbf K_e,\ \mathbf M_e$ | `K_e`, `M_e` | element stiffness and mass, global axes | element modules |
//! | $\mathbf K,\ \mathbf M$ | `K`, `M` | assembled $\mathbf T^T \mathbf K_{full} \mathbf T$, likewise $\mathbf M$ | [`assemble`] |
//! | $E, \nu, G, \rho$ | `E()`, `nu()`, `G()`, `rho()` | isotropic material | [`IsotropicMaterial`] |
//! | $A, I_y, I_z, J, k_y, k_z$ | `A()`, `Iy()`, ... | beam section, shear factors | [`BeamSection`] |
//! | $\mathbf K_G(\boldsymbol\sigma)$ | `K_G` | geometric (initial-stress) stiffness of the stress field $\boldsymbol\sigma$: $\tfrac12\mathbf u^T\mathbf K_G\mathbf u = \int\boldsymbol\sigma : \tfrac12\nabla\mathbf u^T\nabla\mathbf u\,dV$ | [`geometric`]; McGuire, Gallagher & Ziemian (2000) (9.18) for beams |
//! | $\lambda$ | `load_factors` | linearised buckling, $\mathbf K\boldsymbol\phi = \lambda(-\mathbf K_G)\boldsymbol\phi$ | [`linear_buckling`] |
//! | $\boldsymbol\sigma$ | `Voigt` | stress $[xx, yy, zz, xy, yz, zx]$ at integration points or nodes; $\sigma_{vM}$ von Mises | [`stress`] |
//! | $N, V_y, V_z, T, M_y, M_z$ | section forces | beam section forces, element axes | [`stress::beam_section_forces`] |
//! | $\mathbf L$; $\mathbf L_s = \[\mathbf L_{ss}; \mathbf L_{bs}\]$ | `L`; `Ls` | Cholesky factor $\mathbf P\mathbf A\mathbf P^T = \mathbf L\mathbf L^T$; one supernode's columns of it (its panel), the diagonal block over the rows below | [`sparse_cholesky`] |
//! | $\omega$ | `omega` | circular eigenfrequency, $\mathbf K \boldsymbol\phi = \omega^2 \mathbf M \boldsymbol\phi$ | [`modal_dense`] |
//!
//! Superscripts: every vector is in global axes unless its name ends in `_loc` (element axes).

#![allow(non_snake_case)]

pub mod assembly;
pub mod box_mesh;
pub mod dof;
pub mod element;
pub mod error;
pub mod fuzz;
pub mod generate;
pub mod geometric;
pub mod input;
pub mod interface;
pub mod mass_properties;
pub mod mesh;
pub mod modal;
pub mod model;
pub mod ordering;
pub mod pattern;
pub mod property;
pub mod quadrature;
pub mod rigid;
pub mod section;
pub mod sparse_cholesky;
pub mod statics;
pub mod stress;
pub mod units;

pub use assembly::{assemble, assemble_into, assemble_with_pattern, Assembled};
pub use box_mesh::{box_mesh, solid_model, solid_model_with_materials};
pub use dof::{Dof, DofMap, DofStatus};
pub use element::{Beam2, BeamTheory, Element, LocalMatrices, MassKind, Properties, Solid, SolidKind};
pub use error::{ElementError, FeError, PropertyError, DOF_NAMES};
pub use geometric::{
    assemble_geometric_stiffness, element_dof_slots, element_geometric_stiffness, element_geometric_tensor_into,
    linear_buckling, packed_pair, BucklingSettings, BucklingSolution,
};
pub use interface::{add_interface, add_interface_on_set, Interface, InterfaceSpec, Interfaces, SpiderKind};
pub use mass_properties::center_of_mass;
pub use mesh::import::{ImportError, ImportedModel};
pub use mesh::{Cell, CellId, CellKind, Mesh, NodeId};
pub use modal::{modal_dense, scaled_self_adjoint_eigen, ModalSolution};
pub use model::{BeamProperties, DofMask, FeModel, LinearConstraint, NodalLoad, Support};
pub use ordering::{
    dof_points, factor_flops, nested_dissection, nested_dissection_with_leaves, symbolic_cholesky, FillOrdering,
};
pub use pattern::SystemPattern;
pub use property::{IsotropicMaterial, MaterialId, SectionId};
pub use section::{BeamSection, SectionShape};
pub use sparse_cholesky::{available_memory, CholeskyError, Precision, SparseCholesky, SymbolicFactor};
pub use statics::{solve_static, StaticSolution};
pub use stress::{nodal_stresses, principal_stresses, von_mises, Voigt};
