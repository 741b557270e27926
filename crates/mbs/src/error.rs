//! Errors of the multibody stage: [`ModelError`] when a [`crate::Model`] cannot become a
//! [`crate::System`], [`SolveError`] when an analysis stops, and [`Incomplete`], which carries
//! a `SolveError` together with everything computed before it.

use crate::ids::{BodyId, JointId, NodeId};
use superelement::SuperelementError;
use thiserror::Error;

/// An entity of a [`crate::Model`] by its id or its index in the model's list, carried by the
/// errors so that a caller maps an error to its own description of the entity (a line of a
/// study file) without reading the message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Entity {
    Node(NodeId),
    Body(BodyId),
    Joint(JointId),
    /// Index in `Model::point_masses`.
    PointMass(usize),
    /// Index in `Model::springs`.
    Spring(usize),
    /// Index in `Model::joint_springs`.
    JointSpring(usize),
    /// Index in `Model::joint_limits`.
    JointLimit(usize),
    /// Index in `Model::actuators`.
    Actuator(usize),
    /// Index in `Model::supports`.
    Support(usize),
    /// Index in `Model::drivers`.
    Driver(usize),
    /// Index in `Model::loads`.
    Load(usize),
    /// Index in `Model::body_loads`.
    BodyLoad(usize),
    /// Index in `Model::sensors`.
    Sensor(usize),
    /// Index in `Model::initial`.
    InitialCondition(usize),
    /// Index in the user forces given to [`crate::System::with_user_forces`].
    UserForce(usize),
}

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
        /// The entity that refers to it.
        by: Entity,
    },
    /// An entity refers to a body id that is not in `Model::bodies`.
    #[error("{referenced_by} refers to body {id}, but the model has {count} bodies")]
    UnknownBody {
        id: u32,
        count: usize,
        referenced_by: String,
        /// The entity that refers to it.
        by: Entity,
    },
    /// An entity refers to a joint id that is not in `Model::joints`.
    #[error("{referenced_by} refers to joint {id}, but the model has {count} joints")]
    UnknownJoint {
        id: u32,
        count: usize,
        referenced_by: String,
        /// The entity that refers to it.
        by: Entity,
    },
    /// A closed kinematic loop made of rigid bodies, joints and supports only. Minimal
    /// coordinates cannot describe it without a constraint equation (theory guide §8): close the loop
    /// through a flexible body, whose interface nodes are independent.
    #[error("closed loop of rigid bodies and joints (no flexible body in it): bodies [{}], joints [{}], supported nodes [{}]; minimal coordinates need the loop to close through a flexible body", bodies.join(", "), joints.join(", "), supports.join(", "))]
    RigidLoop {
        bodies: Vec<String>,
        joints: Vec<String>,
        supports: Vec<String>,
        /// The bodies, joints and supported nodes of the loop.
        ids: Vec<Entity>,
    },
    /// A rigid group (a node, or nodes welded by rigid bodies) is the child of two joints: the
    /// tree of dependent coordinates cannot be oriented. Reverse one of the joints.
    #[error("nodes [{}] (one rigid group) are the child of joints [{}]; a group can have one parent joint: declare one of them the other way round", nodes.join(", "), joints.join(", "))]
    TwoParentJoints {
        nodes: Vec<String>,
        joints: Vec<String>,
        joint_ids: Vec<JointId>,
    },
    /// A support (or node driver) acts on a node whose motion follows a joint: its coordinates
    /// are not independent. Support the joint's root instead, or reverse the joint.
    #[error("support on node '{node}', whose motion is given by joint '{joint}'; supports act on independent nodes only (reverse the joint so that '{node}' is its parent)")]
    SupportOnDependentNode {
        node: String,
        joint: String,
        node_id: NodeId,
        joint_id: JointId,
    },
    /// Two supports on one node: merge them into one.
    #[error("node '{node}' has {count} supports; give one support per node")]
    DuplicateSupport {
        node: String,
        count: usize,
        node_id: NodeId,
        /// The supports on the node.
        supports: Vec<usize>,
    },
    /// A coordinate that no body, mass or spring holds: the system matrices would be singular.
    #[error("{coordinate} is held by nothing (no flexible body, mass, inertia or spring moves with it, and it is not supported)")]
    UnheldCoordinate {
        coordinate: String,
        /// The independent node, joint or flexible body the coordinate belongs to.
        owner: Option<Entity>,
    },
    /// A flexible body's interface does not sit at its node.
    #[error("body '{body}': interface {interface} ('{name}') is {distance:.3e} m from its node '{node}' (placement * x_k must equal the node position within {tolerance:.1e} m)")]
    InterfaceMismatch {
        body: String,
        interface: usize,
        name: String,
        node: String,
        distance: f64,
        tolerance: f64,
        body_id: BodyId,
        node_id: NodeId,
    },
    /// Joint nodes that must coincide (spherical, revolute, universal) do not.
    #[error("joint '{joint}' ({kind}): parent '{parent}' and child '{child}' are {distance:.3e} m apart; they must coincide")]
    JointNodesApart {
        joint: String,
        kind: String,
        parent: String,
        child: String,
        distance: f64,
        joint_id: JointId,
    },
    /// A driver's target is not a coordinate that can be driven.
    #[error("driver '{driver}': {what}")]
    InvalidDriver {
        driver: String,
        what: String,
        /// Index in `Model::drivers`.
        driver_id: usize,
    },
    /// A value out of its range (a negative mass, a zero axis, a table with decreasing times...).
    #[error("{entity}: {what}")]
    InvalidValue {
        entity: String,
        what: String,
        /// The entity, when the value belongs to one of the model (not to a table read alone).
        id: Option<Entity>,
    },
    /// A node of a planar flexible body can leave the global xy-plane (or turn about another
    /// axis than z): `what` says what lets it ([`crate::assembly::planar`]). The body gives its
    /// out-of-plane coordinates no stiffness or mass.
    #[error("body '{body}' is planar, but its node '{node}' can leave the xy-plane: {what}")]
    LeavesPlane {
        body: String,
        node: String,
        what: String,
        body_id: BodyId,
        node_id: NodeId,
    },
    /// The superelement could not be built from the reduced body (the cause is the
    /// source, so a report walking the chain names it once).
    #[error("body '{body}'")]
    Superelement {
        body: String,
        body_id: BodyId,
        source: SuperelementError,
    },
}

impl ModelError {
    /// This error with `id` as the entity of an [`ModelError::InvalidValue`] that has none (a
    /// time function checked for the entity that uses it).
    pub fn with_id(mut self, entity: Entity) -> Self {
        if let Self::InvalidValue { id: id @ None, .. } = &mut self {
            *id = Some(entity);
        }
        self
    }

    /// The entities the error is about, the one to point at first (the entity that refers to
    /// a missing one, the body of an interface, the joint of a dependent support); empty when
    /// the error belongs to no single entity (a table read alone).
    pub fn entities(&self) -> Vec<Entity> {
        match self {
            Self::UnknownNode { by, .. } | Self::UnknownBody { by, .. } | Self::UnknownJoint { by, .. } => vec![*by],
            Self::RigidLoop { ids, .. } => ids.clone(),
            Self::TwoParentJoints { joint_ids, .. } => joint_ids.iter().map(|&j| Entity::Joint(j)).collect(),
            Self::SupportOnDependentNode { node_id, joint_id, .. } => {
                vec![Entity::Joint(*joint_id), Entity::Node(*node_id)]
            }
            Self::DuplicateSupport { node_id, supports, .. } => supports
                .iter()
                .map(|&s| Entity::Support(s))
                .chain([Entity::Node(*node_id)])
                .collect(),
            Self::UnheldCoordinate { owner, .. } => owner.iter().copied().collect(),
            Self::InterfaceMismatch { body_id, node_id, .. } => vec![Entity::Body(*body_id), Entity::Node(*node_id)],
            Self::JointNodesApart { joint_id, .. } => vec![Entity::Joint(*joint_id)],
            Self::InvalidDriver { driver_id, .. } => vec![Entity::Driver(*driver_id)],
            Self::InvalidValue { id, .. } => id.iter().copied().collect(),
            Self::Superelement { body_id, .. } => vec![Entity::Body(*body_id)],
            Self::LeavesPlane { body_id, node_id, .. } => vec![Entity::Body(*body_id), Entity::Node(*node_id)],
        }
    }
}

/// Where in an analysis a solver stopped: a time of a dynamic analysis, or a load factor of a
/// static one (load stepping, arc length, buckling).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum At {
    /// Time $t$ \[s\].
    Time(f64),
    /// Load factor $\lambda$ of a static analysis (1 = the full load).
    LoadFactor(f64),
}

impl At {
    /// The time, when this is one.
    pub fn time(self) -> Option<f64> {
        match self {
            Self::Time(t) => Some(t),
            Self::LoadFactor(_) => None,
        }
    }

    /// The load factor, when this is one.
    pub fn load_factor(self) -> Option<f64> {
        match self {
            Self::LoadFactor(l) => Some(l),
            Self::Time(_) => None,
        }
    }

    /// The time or the load factor.
    pub fn value(self) -> f64 {
        match self {
            Self::Time(x) | Self::LoadFactor(x) => x,
        }
    }
}

/// `t = 0.250000` or `load factor 0.500000`.
impl std::fmt::Display for At {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Time(t) => write!(f, "t = {t:.6}"),
            Self::LoadFactor(l) => write!(f, "load factor {l:.6}"),
        }
    }
}

/// Why an analysis stopped.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SolveError {
    /// Newton did not reach the tolerance. `residual` is the last relative residual
    /// $\|\mathbf F\|/f_{scale}$; `step` the time or load step that failed (1 = the first).
    #[error(
        "Newton did not converge at {at} (step {step}): relative residual {residual:.3e} after {iterations} iterations"
    )]
    NotConverged {
        at: At,
        step: usize,
        residual: f64,
        iterations: usize,
    },
    /// The iteration (or mass) matrix could not be factorised.
    #[error("singular {what} at {at} (step {step}): a coordinate is free without stiffness or mass, or a mechanism is at a singular configuration")]
    Singular { at: At, step: usize, what: String },
    /// A body could not be evaluated (its floating frame did not converge, ...); the cause
    /// is the source, so a report walking the chain names it once. `step` is the time or load
    /// step it failed in, when the solver knows it.
    #[error("body '{body}' at {at}{}", step_suffix(*.step))]
    Body {
        body: String,
        id: BodyId,
        at: At,
        step: Option<usize>,
        /// Boxed: the largest variant would otherwise make every `Result` of the solvers large.
        source: Box<SuperelementError>,
    },
    /// A user-defined force ([`crate::UserForce`]) gave a value the solver cannot use.
    #[error("user force '{name}' at {at}: {what}")]
    UserForce {
        name: String,
        /// Index in the user forces of the system.
        index: usize,
        at: At,
        what: String,
    },
    /// A force law ([`crate::model::force_law::ForceLaw`]) failed or gave a value the solver
    /// cannot use: `output` names the output it is about (when it is about one), `step` the
    /// time or load step, when the solver knows it; the law's error is the source (with its
    /// own cause: a Python exception, say).
    #[error("force law '{name}'{} at {at}{}", output.as_ref().map_or(String::new(), |o| format!(" (output '{o}')")), step_suffix(*.step))]
    ForceLaw {
        name: String,
        output: Option<String>,
        at: At,
        step: Option<usize>,
        /// Boxed: the largest variant would otherwise make every `Result` of the solvers large.
        source: Box<crate::model::force_law::LawError>,
    },
    /// Settings out of range (a negative step, rho_inf outside [0, 1], ...).
    #[error("invalid settings: {what}")]
    InvalidSettings { what: String },
    /// A sensor read a value that is not finite (inf or NaN): the motion or a force has
    /// diverged. `component` counts from 0 within the sensor; `index` is the sensor's index in
    /// `Model::sensors`.
    #[error("sensor '{sensor}' component {component} is {value} at {at} (step {step}): the motion or a force is no longer finite")]
    NonFiniteSensor {
        sensor: String,
        index: usize,
        component: usize,
        value: f64,
        at: At,
        step: usize,
    },
    /// A value the analysis computed is not finite (inf or NaN): `what` is the quantity (the
    /// residual, a tangent matrix, a Newton correction) and `coordinate` the unknown it belongs
    /// to ([`crate::System::dof_labels`], `index` its position). A load, a force or the motion
    /// is no longer finite there; the analysis stops rather than carry it on.
    #[error(
        "{what} of {coordinate} is {value} at {at} (step {step}): a load, a force or the motion is no longer finite"
    )]
    NonFinite {
        what: String,
        coordinate: String,
        index: usize,
        value: f64,
        at: At,
        step: usize,
    },
    /// A joint limit's stop rings faster than the smallest step allowed can resolve: its
    /// frequency $\omega = \sqrt{k/m}$ on the coordinate's inertia $m$ needs steps of at most
    /// `needed` $= $ [`crate::STOP_RESOLUTION`]$/\omega$ (`crate::assembly::joint_forces`,
    /// stops). Refused before the first step.
    #[error(
        "joint limit '{limit}' on joint '{joint}': stiffness {stiffness:e} on the coordinate's inertia {inertia:.4e} (kg m^2 on an angle, kg on a length) is a stop of frequency sqrt(k/m) = {frequency:.4e} rad/s, which only steps of at most {needed:.4e} s resolve (omega h <= 0.1), but the smallest step is {min_step:e} s (dt_min, or the adaptive min_step): lower the stiffness or the smallest step"
    )]
    UnresolvableLimit {
        limit: String,
        /// Index in `Model::joint_limits`.
        index: usize,
        joint: String,
        stiffness: f64,
        inertia: f64,
        frequency: f64,
        needed: f64,
        min_step: f64,
    },
    /// A step in contact with a joint limit's stop was longer than `needed` (see
    /// [`SolveError::UnresolvableLimit`]): it was taken back, to be cut (retried fixed steps,
    /// adaptive steps).
    #[error("joint limit '{limit}' at {at} (step {step}): a step of {h:.4e} s in contact with its stop (frequency {frequency:.4e} rad/s) is longer than the {needed:.4e} s that resolve it")]
    LimitNotResolved {
        limit: String,
        /// Index in `Model::joint_limits`.
        index: usize,
        at: At,
        step: usize,
        h: f64,
        frequency: f64,
        needed: f64,
    },
}

/// ` (step 3)`, or nothing when the step is not known.
fn step_suffix(step: Option<usize>) -> String {
    step.map_or(String::new(), |s| format!(" (step {s})"))
}

impl SolveError {
    /// The entity the error is about (a body whose frame failed, a user force, a sensor that
    /// is not finite), if any.
    pub fn entity(&self) -> Option<Entity> {
        match self {
            Self::Body { id, .. } => Some(Entity::Body(*id)),
            Self::UserForce { index, .. } => Some(Entity::UserForce(*index)),
            Self::NonFiniteSensor { index, .. } => Some(Entity::Sensor(*index)),
            Self::UnresolvableLimit { index, .. } | Self::LimitNotResolved { index, .. } => {
                Some(Entity::JointLimit(*index))
            }
            _ => None,
        }
    }

    /// Where the solver stopped (time or load factor), if the error says.
    pub fn at(&self) -> Option<At> {
        match self {
            Self::NotConverged { at, .. }
            | Self::Singular { at, .. }
            | Self::Body { at, .. }
            | Self::UserForce { at, .. }
            | Self::ForceLaw { at, .. }
            | Self::NonFiniteSensor { at, .. }
            | Self::NonFinite { at, .. }
            | Self::LimitNotResolved { at, .. } => Some(*at),
            Self::InvalidSettings { .. } | Self::UnresolvableLimit { .. } => None,
        }
    }

    /// The time or load step that failed (1 = the first), if the error says.
    pub fn step(&self) -> Option<usize> {
        match self {
            Self::NotConverged { step, .. }
            | Self::Singular { step, .. }
            | Self::NonFiniteSensor { step, .. }
            | Self::NonFinite { step, .. }
            | Self::LimitNotResolved { step, .. } => Some(*step),
            Self::Body { step, .. } | Self::ForceLaw { step, .. } => *step,
            Self::UserForce { .. } | Self::InvalidSettings { .. } | Self::UnresolvableLimit { .. } => None,
        }
    }

    /// This error of an evaluation at load factor `lambda` in load step `step` of a static
    /// analysis: the place becomes [`At::LoadFactor`] (the bodies and forces below the solver
    /// only know the time at which loads are evaluated) and the step is set.
    pub(crate) fn in_load_step(mut self, lambda: f64, load_step: usize) -> Self {
        match &mut self {
            Self::NotConverged { at, step, .. }
            | Self::Singular { at, step, .. }
            | Self::NonFiniteSensor { at, step, .. }
            | Self::NonFinite { at, step, .. }
            | Self::LimitNotResolved { at, step, .. } => {
                *at = At::LoadFactor(lambda);
                *step = load_step;
            }
            Self::Body { at, step, .. } | Self::ForceLaw { at, step, .. } => {
                *at = At::LoadFactor(lambda);
                *step = Some(load_step);
            }
            Self::UserForce { at, .. } => *at = At::LoadFactor(lambda),
            Self::InvalidSettings { .. } | Self::UnresolvableLimit { .. } => {}
        }
        self
    }
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
