//! Errors of the FE stage. Each names the entity (node, element, material, set) it is about.

use crate::mesh::NodeId;
use thiserror::Error;

/// A material or section value outside its physical range.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum PropertyError {
    #[error("material '{name}': {what} (got {value})")]
    Material { name: String, what: String, value: f64 },
    #[error("beam section '{name}': {what} (got {value})")]
    Section { name: String, what: String, value: f64 },
}

/// An element whose geometry or data cannot give matrices.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ElementError {
    /// The two nodes of a beam coincide (length below 1e-12 of the model size).
    #[error("element {element}: beam has zero length (nodes {n1} and {n2} coincide)")]
    ZeroLength { element: usize, n1: u64, n2: u64 },
    /// The orientation vector has no component perpendicular to the beam axis.
    #[error("element {element}: orientation vector {v:?} is parallel to the beam axis")]
    OrientationParallel { element: usize, v: [f64; 3] },
    /// A solid element's Jacobian determinant is not positive at a quadrature point.
    #[error("element {element}: inverted or degenerate geometry, det J = {det_j:.3e} at quadrature point {point}")]
    NonPositiveJacobian { element: usize, point: usize, det_j: f64 },
    /// An element refers to a section or material that the model does not have.
    #[error("element {element}: {what} {index} does not exist (the model has {count})")]
    MissingProperty {
        element: usize,
        what: &'static str,
        index: usize,
        count: usize,
    },
    /// An element refers to a node that the model does not have.
    #[error("element {element}: node index {node} does not exist (the model has {count} nodes)")]
    MissingNode { element: usize, node: u32, count: usize },
    /// An element has the wrong number of nodes for its kind.
    #[error("element {element}: a {kind} needs {expected} nodes, got {got}")]
    WrongNodeCount {
        element: usize,
        kind: &'static str,
        expected: usize,
        got: usize,
    },
}

/// Errors of dof numbering, assembly and linear solution.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FeError {
    #[error(transparent)]
    Element(#[from] ElementError),
    #[error(transparent)]
    Property(#[from] PropertyError),
    /// A load, support or set refers to a node that is not in the model.
    #[error("{context}: node {node:?} does not exist (the model has {count} nodes)")]
    UnknownNode {
        context: String,
        node: NodeId,
        count: usize,
    },
    /// A named node set is not in the mesh.
    #[error("{context}: node set '{name}' does not exist (known sets: {known})")]
    UnknownNodeSet {
        context: String,
        name: String,
        known: String,
    },
    /// A named cell set (gmsh physical group of volumes) is not in the mesh.
    #[error("{context}: cell set '{name}' does not exist (known sets: {known})")]
    UnknownCellSet {
        context: String,
        name: String,
        known: String,
    },
    /// A volume cell has no material, or two: every 3D cell must lie in exactly one of the
    /// cell sets that are given materials.
    #[error("{context}: cell {cell_tag} ({kind}) {why}")]
    CellMaterial {
        context: String,
        cell_tag: u64,
        kind: &'static str,
        why: String,
    },
    /// An interface (spider) cannot be built: too few or collinear surface nodes, a surface node
    /// already constrained, or no surface nodes at all.
    #[error("interface '{name}': {why}")]
    Interface { name: String, why: String },
    /// A load or constraint acts on a dof that no element gives stiffness to and no
    /// constraint defines (a rotation of a node that only solids touch, for instance).
    #[error("{context}: node {node_tag} dof {dof} is not active (no element or constraint uses it)")]
    InactiveDof {
        context: String,
        node_tag: u64,
        dof: &'static str,
    },
    /// A dependent dof of a constraint is itself dependent, supported, or defined twice.
    #[error("constraint '{name}': node {node_tag} dof {dof} {why}")]
    Constraint {
        name: String,
        node_tag: u64,
        dof: &'static str,
        why: String,
    },
    /// The stiffness is singular: the structure can move without straining.
    #[error("the stiffness matrix is singular near node {node_tag} dof {dof}: the model is a mechanism there (add a support, or check the connectivity)")]
    Mechanism { node_tag: u64, dof: &'static str },
    /// The mass matrix is not positive definite on the free dofs.
    #[error("the mass matrix is not positive definite (a free dof without mass near node {node_tag} dof {dof})")]
    MasslessDof { node_tag: u64, dof: &'static str },
    /// A dense eigenvalue or sparse factorisation failed for a reason other than the above.
    /// Nested dissection needs one finite position per dof (`ordering::nested_dissection`).
    #[error("fill-reducing ordering: {n_dofs} dofs but {n_points} dof positions: {why}")]
    OrderingPoints {
        n_dofs: usize,
        n_points: usize,
        why: String,
    },
    #[error("linear algebra failed: {0}")]
    LinearAlgebra(String),
    /// A generator was asked for something it cannot build.
    #[error("{generator}: {what}")]
    Generator { generator: &'static str, what: String },
    /// The model is too large for the dense path.
    #[error("dense modal analysis is limited to {limit} dofs; the model has {n} (use the sparse eigensolver of `reduction`)")]
    TooLargeForDense { n: usize, limit: usize },
}

/// Names of the six dofs of a node, in our order.
pub const DOF_NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];
