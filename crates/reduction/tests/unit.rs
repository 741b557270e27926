//! Unit tests of the reduction crate: one binary, one module per area.
//! Fast enough for a debug build (the workspace builds tests with opt-level 2).

#![allow(non_snake_case)]

/// Fixtures shared by the areas below: the straight beam models they reduce.
mod common {
    include!("unit/common.rs");
}

/// `reduction::eigen`: the sparse shift-invert eigensolver against analytic chain spectra, a
/// dense reference, free bodies (negative shift), a 3D lattice, and the error cases.
mod eigen {
    include!("unit/eigen.rs");
}

/// `reduction::craig_bampton` and `invariants`: statics exact with static modes, the free
/// body's rigid null space, spectrum convergence from above, mass data, errors.
mod craig_bampton {
    include!("unit/craig_bampton.rs");
}

/// `reduction::modal`: full-model modes through the sparse path (A1 clamped and free).
mod full_model_modes {
    include!("unit/full_model_modes.rs");
}

/// NAFEMS FV32 (A4): in-plane modes of a tapered membrane meshed with hex20.
mod fv32 {
    include!("unit/fv32.rs");
}

/// From a gmsh mesh to a reduced body: physical groups as material and interface sets,
/// RBE2/RBE3 interfaces, interface statics equal to the full model's.
mod solid_body {
    include!("unit/solid_body.rs");
}

/// `reduction::file`: the `.rbody` reduced-body file. Bit-identical round trips (mesh shapes,
/// auxiliary interface, awkward scalars), every error named with the file (magic, version,
/// truncation, checksum, JSON, shapes), and no panic or acceptance on truncation or random
/// byte changes.
mod file_format {
    include!("unit/file_format.rs");
}

/// `reduction::physics`: bodies with valid checksums but physically wrong data (non-symmetric
/// or indefinite K_CB, non-positive modal mass, metadata against the matrices, coincident or
/// duplicate interfaces) are refused on load, each problem named; sound bodies pass.
mod physics {
    include!("unit/physics.rs");
}

/// Fuzzing with a fixed budget (`fe_model::fuzz`): mutants of a reduced-body file (metadata
/// mutants with valid checksums) and of Matrix Market files; none may panic.
mod fuzz {
    include!("unit/fuzz.rs");
}

/// `reduction::matrix_market` and `reduce_external`: exact Matrix Market round trips,
/// symmetric files expanded, errors with file and line; external K, M and node coordinates
/// reduce to the body `reduce` gives for the same FE model (beam; solid with RBE2 spiders).
mod matrix_market {
    include!("unit/matrix_market.rs");
}

/// `reduction::checks` on every source: edited MBDyn records (mass, symmetry, positive mass,
/// coincident and duplicate interfaces) and node tables against K (millimetres, coincident
/// nodes; free and supported matrices pass).
mod checks {
    include!("unit/checks.rs");
}

/// `reduction::mbdyn`: MBDyn `.fem` files. The manual's example reads into its stated inertia;
/// a written file has the layout MBDyn's reader needs; solid and beam bodies come back the
/// same; malformed files are located; no cut or mutated file panics.
mod mbdyn {
    include!("unit/mbdyn.rs");
}

/// `reduction::geometric` (geometric stiffening): sum_k w_k G_k against the full model's
/// V^T K_G V, zero for rigid motions, buckling of clamped reduced beam and hex20 rods
/// converging to the full model's as modes are added, G in the body file and version-1
/// files still read; release only: the cost of G.
mod geometric_stiffening {
    include!("unit/geometric_stiffening.rs");
}

/// `reduction::diagnostics`: effective masses from M_CB against a dense solution of the full
/// model, the sum rule (all modes + what the interface carries = rigid mass, lumped hand
/// value m/2n), the static residual, and the warnings.
mod diagnostics {
    include!("unit/diagnostics.rs");
}

/// `reduction::stress` and `reduction::attachment`: stress shapes and load points with static
/// correction. The proof against the full FE model: a clamped hex20 bar under a point load at
/// its tip, von Mises at the ten most stressed nodes from the reduced body (with and without
/// the load point's attachment modes) against the full static solution; beam section moments
/// of a reduced cantilever against the analytic ones; the file keeps the new arrays and still
/// reads format version 2.
mod stress_shapes {
    include!("unit/stress_shapes.rs");
}

/// `CbSettings::planar`: a beam in its FE xy-plane reduced with the out-of-plane dofs of its
/// interior supported equals the 3D reduction with them supported by hand, keeps the 3D
/// beam's in-plane modes, decouples the plane in K_CB and M_CB; what cannot be planar is
/// refused by name.
mod planar {
    include!("unit/planar.rs");
}
