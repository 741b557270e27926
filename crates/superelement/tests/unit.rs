//! superelement unit tests, one binary (fast, debug build). Each module says what
//! belongs in it; shared fixtures live in `common`, the finite-difference helper in
//! `superelement::testing`.
#![allow(non_snake_case)]

mod unit {
    /// Shared fixtures: reduced bodies (built once per binary), frame choices, variants.
    pub mod common;
    /// The compressed invariants: what is stored, the round-off threshold, equality with the
    /// dense path.
    mod compressed;
    /// Kinetic energy of rigid motion, power balance of the inertia forces, potentials.
    mod energy;
    /// The cheap forms of an evaluation against the full one: forces only, reused workspaces.
    mod evaluation;
    /// Every tangent against central differences: local coordinates, frame Jacobian, FFR
    /// partials, K_t, C_t, M for all frame choices and both inertia variants.
    mod fd_tangent;
    /// The frame solve (4.4): convergence from warm and cold starts, errors, explicit frames.
    mod frame;
    /// Geometric stiffening (the cubic strain energy U_3 of the G_k): gradient, tangents
    /// against central differences, rigid-motion invariance, errors; G = 0 is bit-identical to
    /// a body without G.
    mod geometric;
    /// Rigid motions: zero elastic force, the frame moves with the body, centre-of-mass frame.
    mod invariance;
    /// Small motions reproduce the linear FE model: statics exactly, frequencies to the
    /// accuracy of the modes kept.
    mod linear_limit;
    /// The planar body against the in-plane block of the spatial one, its tangents against
    /// central differences, its errors.
    mod planar;
    /// Loads at load points inside a body: work and tangents against central differences.
    mod point_load;
    /// Recovery of the deformed mesh.
    mod recovery;
    /// Rotations: exp/log round trips (also near pi), Jacobians and their derivatives vs
    /// central differences.
    mod so3;
}
