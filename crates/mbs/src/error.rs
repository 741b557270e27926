//! Errors of the multibody stage: [`ModelError`] when a [`crate::Model`] cannot become a
//! [`crate::System`], [`SolveError`] when an analysis stops, and [`Incomplete`], which carries
//! a `SolveError` together with everything computed before it.

use superelement::SuperelementError;
use thiserror::Error;

/// A model that cannot be turned into a system of independent coordinates.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ModelError {
    /// An entity refers to a node id that is not in `Model::nodes`.
    #[error("{referenced_by} refers to node {id}, but the model has {count} nodes")]
    UnknownNode {
        id: u32,
        count: usize,
        referenced_by: String,
    },
    /// An entity refers to a body id that is not in `Model::bodies`.
    #[error("{referenced_by} refers to body {id}, but the model has {count} bodies")]
    UnknownBody {
        id: u32,
        count: usize,
        referenced_by: String,
    },
    /// An entity refers to a joint id that is not in `Model::joints`.
    #[error("{referenced_by} refers to joint {id}, but the model has {count} joints")]
    UnknownJoint {
        id: u32,
        count: usize,
        referenced_by: String,
    },
    /// A closed kinematic loop made of rigid bodies, joints and supports only. Minimal
    /// coordinates cannot describe it without a constraint equation (theory guide §8): close the loop
    /// through a flexible body, whose interface nodes are independent.
    #[error("closed loop of rigid bodies and joints (no flexible body in it): bodies [{}], joints [{}], supported nodes [{}]; minimal coordinates need the loop to close through a flexible body", bodies.join(", "), joints.join(", "), supports.join(", "))]
    RigidLoop {
        bodies: Vec<String>,
        joints: Vec<String>,
        supports: Vec<String>,
    },
    /// A rigid group (a node, or nodes welded by rigid bodies) is the child of two joints: the
    /// tree of dependent coordinates cannot be oriented. Reverse one of the joints.
    #[error("nodes [{}] (one rigid group) are the child of joints [{}]; a group can have one parent joint: declare one of them the other way round", nodes.join(", "), joints.join(", "))]
    TwoParentJoints { nodes: Vec<String>, joints: Vec<String> },
    /// A support (or node driver) acts on a node whose motion follows a joint: its coordinates
    /// are not independent. Support the joint's root instead, or reverse the joint.
    #[error("support on node '{node}', whose motion is given by joint '{joint}'; supports act on independent nodes only (reverse the joint so that '{node}' is its parent)")]
    SupportOnDependentNode { node: String, joint: String },
    /// Two supports on one node: merge them into one.
    #[error("node '{node}' has {count} supports; give one support per node")]
    DuplicateSupport { node: String, count: usize },
    /// A coordinate that no body, mass or spring holds: the system matrices would be singular.
    #[error("{coordinate} is held by nothing (no flexible body, mass, inertia or spring moves with it, and it is not supported)")]
    UnheldCoordinate { coordinate: String },
    /// A flexible body's interface does not sit at its node.
    #[error("body '{body}': interface {interface} ('{name}') is {distance:.3e} m from its node '{node}' (placement * x_k must equal the node position within {tolerance:.1e} m)")]
    InterfaceMismatch {
        body: String,
        interface: usize,
        name: String,
        node: String,
        distance: f64,
        tolerance: f64,
    },
    /// Joint nodes that must coincide (spherical, revolute, universal) do not.
    #[error("joint '{joint}' ({kind}): parent '{parent}' and child '{child}' are {distance:.3e} m apart; they must coincide")]
    JointNodesApart {
        joint: String,
        kind: String,
        parent: String,
        child: String,
        distance: f64,
    },
    /// A driver's target is not a coordinate that can be driven.
    #[error("driver '{driver}': {what}")]
    InvalidDriver { driver: String, what: String },
    /// A value out of its range (a negative mass, a zero axis, a table with decreasing times...).
    #[error("{entity}: {what}")]
    InvalidValue { entity: String, what: String },
    /// The superelement could not be built from the reduced body.
    #[error("body '{body}': {source}")]
    Superelement { body: String, source: SuperelementError },
}

/// Why an analysis stopped.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SolveError {
    /// Newton did not reach the tolerance. `residual` is the last relative residual
    /// $\|\mathbf F\|/f_{scale}$; for a static analysis `t` is the load factor.
    #[error("Newton did not converge at t = {t:.6} (step {step}): relative residual {residual:.3e} after {iterations} iterations")]
    NotConverged {
        t: f64,
        step: usize,
        residual: f64,
        iterations: usize,
    },
    /// The iteration (or mass) matrix could not be factorised.
    #[error("singular {what} at t = {t:.6} (step {step}): a coordinate is free without stiffness or mass, or a mechanism is at a singular configuration")]
    Singular { t: f64, step: usize, what: String },
    /// A body could not be evaluated (its floating frame did not converge, ...).
    #[error("body '{body}' at t = {t:.6}: {source}")]
    Body {
        body: String,
        t: f64,
        source: SuperelementError,
    },
    /// A user-defined force ([`crate::UserForce`]) gave a value the solver cannot use.
    #[error("user force '{name}' at t = {t:.6}: {what}")]
    UserForce { name: String, t: f64, what: String },
    /// Settings out of range (a negative step, rho_inf outside [0, 1], ...).
    #[error("invalid settings: {what}")]
    InvalidSettings { what: String },
}

/// A [`SolveError`] with the part of the result computed before it (the converged steps, their
/// sensors and residual histories), so a failed run can still be inspected.
#[derive(Error)]
#[error("{error}")]
pub struct Incomplete<T> {
    pub error: SolveError,
    pub partial: T,
}

/// Shows the error only: the partial result can be large (every recorded sensor value).
impl<T> std::fmt::Debug for Incomplete<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Incomplete")
            .field("error", &self.error)
            .field("partial", &format_args!("<{}>", std::any::type_name::<T>()))
            .finish()
    }
}
