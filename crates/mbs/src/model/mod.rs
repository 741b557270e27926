//! [`Model`]: the multibody model as plain serde data (what a study file describes).
//!
//! Nodes carry the configuration (position and orientation). Bodies, masses, springs and
//! loads act on nodes; supports, joints and drivers decide which node coordinates are
//! independent (theory guide §8). A body's interface *is* a node: two bodies sharing a node are welded.
//! Every reference is a newtype id ([`NodeId`], [`BodyId`], [`JointId`]) checked by
//! [`crate::System::new`], which reports an unknown id with the entity that refers to it.
//!
//! Geometry is in the inertial frame at the initial configuration: joint axes, support
//! directions and loads (dead and follower) are inertial vectors there; rigid-body mass data
//! are in the axes of their reference node.

pub mod force_law;
pub mod merge;
pub mod time_function;
pub mod units;
pub mod user_force;

pub use crate::ids::{BodyId, JointId, NodeId};
use nalgebra::{Isometry3, Matrix3, UnitQuaternion, Vector3};
use reduction::ReducedBody;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use superelement::{Damping, FrameChoice, MassVariant};
use time_function::TimeFunction;

/// Serde of a shared reduced body: written as the body itself, read into a new `Arc`.
mod shared_body {
    use reduction::ReducedBody;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    use std::sync::Arc;

    pub fn serialize<S: Serializer>(body: &Arc<ReducedBody>, s: S) -> Result<S::Ok, S::Error> {
        body.as_ref().serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Arc<ReducedBody>, D::Error> {
        ReducedBody::deserialize(d).map(Arc::new)
    }
}

/// A node: a point with an orientation, $\mathbf r \in \mathbb R^3$, $\mathbf R \in SO(3)$.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Node {
    pub name: String,
    /// Initial position.
    pub position: Vector3<f64>,
    /// Initial orientation (node axes to inertial axes).
    pub orientation: UnitQuaternion<f64>,
}

/// A body of the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Body {
    /// An AIC-FFR superelement ([`superelement::Superelement`]).
    Flexible(Box<FlexibleBody>),
    /// A rigid body: its nodes move rigidly with its reference node.
    Rigid(RigidBody),
}

impl Body {
    pub fn name(&self) -> &str {
        match self {
            Body::Flexible(b) => &b.name,
            Body::Rigid(b) => &b.name,
        }
    }
}

/// A flexible body: a reduced body placed in the model, its interfaces mapped to nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlexibleBody {
    pub name: String,
    /// The reduced body, shared (not copied) with the system built from the model, its
    /// superelement and every caller that keeps it: a large solid's mesh and stress shapes
    /// are hundreds of MB.
    #[serde(with = "shared_body")]
    pub reduced: Arc<ReducedBody>,
    /// Node of each interface, in the order of `reduced.interfaces`.
    pub nodes: Vec<NodeId>,
    /// Placement of the FE model's axes in the inertial frame at the initial configuration:
    /// interface $k$ sits at `placement * x_k`, which must be its node's position.
    pub placement: Isometry3<f64>,
    pub frame: FrameChoice,
    pub mass: MassVariant,
    pub damping: Damping,
    /// Evaluated as a planar body in the global xy-plane
    /// (`superelement::Superelement::into_planar`: the in-plane coordinates of its interfaces
    /// and its modes only): for a body reduced as a planar part (`reduction::CbSettings::planar`)
    /// whose nodes the supports and joints keep in the plane, and whose placement is a rotation
    /// about z; [`crate::System::new`] checks both ([`crate::assembly::planar`]). Off by default.
    #[serde(default)]
    pub planar: bool,
}

/// A rigid body with mass properties about its reference node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigidBody {
    pub name: String,
    /// The node its mass properties are attached to.
    pub reference: NodeId,
    /// Further nodes, rigidly attached (their initial offsets from the reference are kept).
    pub nodes: Vec<NodeId>,
    pub mass: f64,
    /// Centre of mass from the reference node, in the reference node's axes.
    pub center_of_mass: Vector3<f64>,
    /// Inertia tensor about the centre of mass, in the reference node's axes.
    pub inertia: Matrix3<f64>,
}

/// A point mass on a node (translational inertia only: it does not hold the node's rotation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointMass {
    /// The name messages use (the study's); empty: "point mass `<index>`".
    #[serde(default)]
    pub name: String,
    pub node: NodeId,
    pub mass: f64,
}

impl PointMass {
    /// The point mass at `index` of the model's list as messages name it: by its name, or
    /// by its index when it has none.
    pub fn label(&self, index: usize) -> String {
        if self.name.is_empty() {
            format!("point mass {index}")
        } else {
            format!("point mass '{}'", self.name)
        }
    }
}

/// A point-to-point spring-damper along the line between two nodes (or a node and a fixed
/// point): $f = k(l - l_0) + c\,\dot l$.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    pub name: String,
    pub a: NodeId,
    /// The other end: a node, or a fixed point when `None` (then `ground_point` is used).
    pub b: Option<NodeId>,
    pub ground_point: Vector3<f64>,
    pub stiffness: f64,
    pub damping: f64,
    /// Unstretched length; `None`: the initial length.
    pub rest_length: Option<f64>,
}

/// A spring-damper on a joint coordinate (linear on a length, torsional on an angle):
/// $Q = -f_0 - k(x - x_0) - c\dot x$, with $f_0$ the preload (the force or moment the spring
/// exerts against a positive coordinate at its rest value $x_0$).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSpring {
    pub joint: JointId,
    pub coordinate: usize,
    pub stiffness: f64,
    pub damping: f64,
    pub rest: f64,
    /// $f_0$ (N on a length, N m on an angle).
    #[serde(default)]
    pub preload: f64,
}

/// Which translations of a supported node are removed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum TranslationSupport {
    Free,
    Fixed,
    /// `fixed[i]` removes the translation along inertial axis `i`.
    Components {
        fixed: [bool; 3],
    },
    /// A slider along a fixed line through the initial position.
    Line {
        direction: Vector3<f64>,
    },
    /// Motion in a fixed plane through the initial position.
    Plane {
        normal: Vector3<f64>,
    },
}

/// Which rotations of a supported node are removed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum RotationSupport {
    Free,
    Fixed,
    /// Rotation about a fixed inertial axis only (a revolute joint to the ground). Removing a
    /// single rotation component is not offered: it is not integrable (not a coordinate).
    Axis {
        axis: Vector3<f64>,
    },
}

/// A support: coordinates of an independent node removed (ground, clamp, pin, slider).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Support {
    pub node: NodeId,
    pub translation: TranslationSupport,
    pub rotation: RotationSupport,
}

impl Support {
    /// All six dofs removed.
    pub fn clamp(node: NodeId) -> Self {
        Self {
            node,
            translation: TranslationSupport::Fixed,
            rotation: RotationSupport::Fixed,
        }
    }
    /// Translations removed, rotation free.
    pub fn pin(node: NodeId) -> Self {
        Self {
            node,
            translation: TranslationSupport::Fixed,
            rotation: RotationSupport::Free,
        }
    }
    /// Translations removed, rotation about `axis` only.
    pub fn hinge(node: NodeId, axis: Vector3<f64>) -> Self {
        Self {
            node,
            translation: TranslationSupport::Fixed,
            rotation: RotationSupport::Axis { axis },
        }
    }
    /// A slider along `direction` with its rotation removed.
    pub fn slider(node: NodeId, direction: Vector3<f64>) -> Self {
        Self {
            node,
            translation: TranslationSupport::Line { direction },
            rotation: RotationSupport::Fixed,
        }
    }
}

/// The kinematics of a joint between a parent node and a child node; axes are inertial at
/// the initial configuration, where every joint coordinate is zero.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum JointKind {
    /// Shared position, own orientations (3 rotation coordinates of the child, on SO(3)).
    Spherical,
    /// Shared position; child orientation = parent's times $\exp(\theta\,\mathbf a)$. Coordinate: $\theta$.
    Revolute { axis: Vector3<f64> },
    /// Child translates along the parent-fixed axis; same rotation. Coordinate: $s$.
    Prismatic { axis: Vector3<f64> },
    /// Prismatic and revolute along one axis. Coordinates: $s$, $\theta$.
    Cylindrical { axis: Vector3<f64> },
    /// Two rotations: about `axis1` (parent-fixed), then `axis2` (fixed to the intermediate
    /// link). Coordinates: $\theta_1$, $\theta_2$.
    Universal { axis1: Vector3<f64>, axis2: Vector3<f64> },
    /// Translations in the parent-fixed plane and rotation about its normal. Coordinates:
    /// $s_1$, $s_2$ (along two in-plane axes), $\theta$.
    Planar { normal: Vector3<f64> },
}

impl JointKind {
    /// Number of scalar joint coordinates (the spherical joint's rotation is an SO(3)
    /// coordinate, counted as 0 here).
    pub fn n_scalar(&self) -> usize {
        match self {
            JointKind::Spherical => 0,
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => 1,
            JointKind::Cylindrical { .. } | JointKind::Universal { .. } => 2,
            JointKind::Planar { .. } => 3,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Spherical => "spherical",
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
            JointKind::Cylindrical { .. } => "cylindrical",
            JointKind::Universal { .. } => "universal",
            JointKind::Planar { .. } => "planar",
        }
    }
}

/// A joint as minimal coordinates: the child node's configuration is a function of the
/// parent's and the joint coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    pub name: String,
    pub parent: NodeId,
    pub child: NodeId,
    pub kind: JointKind,
}

/// What a driver prescribes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DriverTarget {
    /// Scalar coordinate `coordinate` of a joint (in the order of [`JointKind`]).
    Joint { joint: JointId, coordinate: usize },
    /// Translation of an independent node along support direction `component` (inertial axis
    /// `component` for `Free`/`Components`; 0 = along the line of a `Line`; 0, 1 = the
    /// in-plane axes of a `Plane`). The node is otherwise supported as declared.
    NodeTranslation { node: NodeId, component: usize },
    /// Rotation angle of an independent node about its support axis (`RotationSupport::Axis`).
    NodeRotation { node: NodeId },
}

/// A prescribed coordinate: removed from the unknowns and fed in with its rate and
/// acceleration. The value is measured from the initial configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Driver {
    pub name: String,
    pub target: DriverTarget,
    pub motion: TimeFunction,
}

/// Force or moment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LoadKind {
    Force,
    Moment,
}

/// In which axes a load keeps its direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LoadAxes {
    /// Fixed inertial direction.
    Dead,
    /// Turns with the node: `value` is the inertial vector at the initial configuration, and
    /// the load keeps its direction relative to the node's axes.
    Follower,
}

/// A nodal load $\mathbf f(t) = \mathbf f_0\,x(t)$.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Load {
    pub node: NodeId,
    pub kind: LoadKind,
    pub axes: LoadAxes,
    pub value: Vector3<f64>,
    pub time: TimeFunction,
}

/// A force and moment at a load point inside a flexible body (a named node of its FE model,
/// reduced with attachment modes: `reduction::LoadPoint`), $\mathbf f(t) = \mathbf f_0\,x(t)$,
/// $\mathbf m(t) = \mathbf m_0\,x(t)$. It acts on the body's rigid motion and elastic
/// coordinates through its reduced load vector ([`superelement::point_load`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyLoad {
    pub body: BodyId,
    /// Index into the body's `ReducedBody::load_points`.
    pub point: usize,
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
    /// `Dead`: fixed inertial direction; `Follower`: the vectors are inertial at the initial
    /// configuration and turn with the body's floating frame.
    pub axes: LoadAxes,
    pub time: TimeFunction,
}

/// The axes a vector sensor reports in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SensorAxes {
    /// Inertial axes.
    #[default]
    Global,
    /// The node's own axes, turning with it: $\mathbf R^T\mathbf x$ (what an accelerometer
    /// fixed to the point reads).
    Node,
}

/// What a sensor measures (each gives a fixed number of values per output time).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SensorKind {
    /// $\mathbf r$ (3).
    NodePosition { node: NodeId },
    /// $\mathbf r - \mathbf r_0$ (3).
    NodeDisplacement { node: NodeId },
    /// Position in the axes of node `reference`, $\mathbf R_{ref}^T(\mathbf r - \mathbf r_{ref})$ (3):
    /// the motion seen from a moving frame (the tip of a rotating beam seen from its hub).
    RelativePosition { node: NodeId, reference: NodeId },
    /// Rotation vector $\log(\mathbf R\mathbf R_0^T)$ from the initial orientation (3).
    NodeRotation { node: NodeId },
    /// $\mathbf v$ (3).
    NodeVelocity { node: NodeId },
    /// Spatial $\boldsymbol\omega$ (3).
    NodeAngularVelocity { node: NodeId },
    /// $\mathbf a = \ddot{\mathbf r}$ (3), from the state's true accelerations
    /// $\ddot{\mathbf q}$ (not generalized-α's algorithmic ones) through the node kinematics (a
    /// point carried by a body: $\mathbf a_{node} + \boldsymbol\alpha\times\mathbf r +
    /// \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf r)$); in global axes or the node's.
    NodeAcceleration { node: NodeId, axes: SensorAxes },
    /// Spatial $\boldsymbol\alpha = \dot{\boldsymbol\omega}$ (3), in global axes or the node's.
    NodeAngularAcceleration { node: NodeId, axes: SensorAxes },
    /// Distance of `node` from the line through `a` and `b` (1): the midpoint deflection of a
    /// rod relative to its chord. With `normal`, signed: $((\mathbf b - \mathbf a)/|\mathbf b - \mathbf a|
    /// \times (\mathbf p - \mathbf a))\cdot\mathbf n$.
    LineDistance {
        node: NodeId,
        a: NodeId,
        b: NodeId,
        normal: Option<Vector3<f64>>,
    },
    /// A scalar joint coordinate (1).
    JointCoordinate { joint: JointId, coordinate: usize },
    /// Its rate (1).
    JointRate { joint: JointId, coordinate: usize },
    /// Modal coordinates $\boldsymbol\eta$ of a flexible body ($m$).
    ModalCoordinates { body: BodyId },
    /// Reaction of a supported node: force and moment in inertial axes (6), from the residual
    /// of its removed coordinates (zero along the free ones).
    Reaction { node: NodeId },
    /// Generalised force needed by a driver (1): a torque for an angle, a force for a length.
    DriverEffort { driver: usize },
    /// Effort $u$ of actuator `actuator` (index in [`Model::actuators`]) (1): a torque on an
    /// angle, a force on a length.
    ActuatorEffort { actuator: usize },
    /// Kinetic energy of all bodies and masses (1).
    KineticEnergy,
    /// Strain energy of flexible bodies and springs (1).
    StrainEnergy,
    /// Gravity potential $-\mathbf g\cdot\sum m\mathbf r_G$ (1).
    GravityPotential,
    /// Linear momentum (3).
    LinearMomentum,
    /// Angular momentum about the inertial origin (3).
    AngularMomentum,
    /// The energy balance of a dynamic run (8, [`crate::assembly::system::sensors`]): the work
    /// put in since the run's start by the actuators, the drivers and the loads, the kinetic,
    /// strain and gravity energies, the energy dissipated by dampers, and the balance error
    /// $(T + U + V) - (T_0 + U_0 + V_0) - W_{in} + D$.
    EnergyBalance,
    /// Stress at mesh node `node` of a flexible body reduced with stress shapes (8), global
    /// axes: the tensor $xx, yy, zz, xy, yz, zx$, von Mises and the largest principal stress
    /// (`reduction::NodeStresses`; a beam node has no tensor, zeros, and the extreme-fibre
    /// stresses).
    Stress { body: BodyId, node: usize },
    /// The largest von Mises stress over the mesh nodes `nodes` of a flexible body reduced with
    /// stress shapes, and the node where it occurs (2: value, node index).
    MaxVonMises { body: BodyId, nodes: Vec<usize> },
}

/// A named sensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sensor {
    pub name: String,
    pub kind: SensorKind,
}

/// Initial values that differ from the model's initial configuration at rest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum InitialCondition {
    /// A scalar joint coordinate's value: the child and everything behind it (the subtree
    /// reached through bodies and joints) turn or slide rigidly with it ([`crate::assembly::initial`]).
    JointValue {
        joint: JointId,
        coordinate: usize,
        value: f64,
    },
    /// A scalar joint coordinate's rate: the subtree behind the joint gets the matching rigid
    /// velocity ([`crate::assembly::initial`]; in a closed loop, the coordinate alone).
    JointRate {
        joint: JointId,
        coordinate: usize,
        rate: f64,
    },
    /// Velocity of an independent node (its free components).
    NodeVelocity {
        node: NodeId,
        velocity: Vector3<f64>,
        angular_velocity: Vector3<f64>,
    },
    /// A rigid velocity of a body and of everything attached to it by joints and bodies,
    /// $\mathbf v(\mathbf x) = \mathbf v_p + \boldsymbol\omega\times(\mathbf x - \mathbf p)$ about the
    /// point $\mathbf p$ (inertial, at the initial configuration). Refused when the body is held
    /// by the ground (give its joints' rates instead): see [`crate::assembly::initial`].
    BodyVelocity {
        body: BodyId,
        velocity: Vector3<f64>,
        angular_velocity: Vector3<f64>,
        point: Vector3<f64>,
    },
    /// A rigid motion of the whole model, $\mathbf v = \mathbf v_0 + \boldsymbol\omega\times\mathbf r$,
    /// given to every independent node (free components only).
    RigidMotion {
        velocity: Vector3<f64>,
        angular_velocity: Vector3<f64>,
    },
}

/// The multibody model.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub name: String,
    pub nodes: Vec<Node>,
    pub bodies: Vec<Body>,
    pub point_masses: Vec<PointMass>,
    pub springs: Vec<Spring>,
    pub joint_springs: Vec<JointSpring>,
    /// Stops on joint coordinates ([`crate::assembly::joint_forces`]).
    #[serde(default)]
    pub joint_limits: Vec<JointLimit>,
    /// Force and torque actuators on joint coordinates ([`crate::assembly::joint_forces`]).
    #[serde(default)]
    pub actuators: Vec<JointActuator>,
    pub supports: Vec<Support>,
    pub joints: Vec<Joint>,
    pub drivers: Vec<Driver>,
    pub loads: Vec<Load>,
    /// Loads at load points inside flexible bodies.
    #[serde(default)]
    pub body_loads: Vec<BodyLoad>,
    /// Gravitational acceleration.
    pub gravity: Vector3<f64>,
    pub sensors: Vec<Sensor>,
    pub initial: Vec<InitialCondition>,
}

impl Model {
    pub fn new(name: &str) -> Self {
        Self {
            name: name.into(),
            ..Default::default()
        }
    }

    /// Adds a node with identity orientation.
    pub fn add_node(&mut self, name: &str, position: Vector3<f64>) -> NodeId {
        self.add_node_oriented(name, position, UnitQuaternion::identity())
    }

    pub fn add_node_oriented(
        &mut self,
        name: &str,
        position: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> NodeId {
        self.nodes.push(Node {
            name: name.into(),
            position,
            orientation,
        });
        NodeId(self.nodes.len() as u32 - 1)
    }

    pub fn add_body(&mut self, body: Body) -> BodyId {
        self.bodies.push(body);
        BodyId(self.bodies.len() as u32 - 1)
    }

    /// A flexible body with the given placement, frame choice, inertia variant and no damping.
    pub fn add_flexible_body(
        &mut self,
        reduced: impl Into<Arc<ReducedBody>>,
        nodes: Vec<NodeId>,
        placement: Isometry3<f64>,
        frame: FrameChoice,
        mass: MassVariant,
    ) -> BodyId {
        let reduced = reduced.into();
        let name = reduced.name.clone();
        self.add_body(Body::Flexible(Box::new(FlexibleBody {
            name,
            reduced,
            nodes,
            placement,
            frame,
            mass,
            damping: Damping::none(),
            planar: false,
        })))
    }

    pub fn add_rigid_body(&mut self, body: RigidBody) -> BodyId {
        self.add_body(Body::Rigid(body))
    }

    pub fn add_joint(&mut self, name: &str, parent: NodeId, child: NodeId, kind: JointKind) -> JointId {
        self.joints.push(Joint {
            name: name.into(),
            parent,
            child,
            kind,
        });
        JointId(self.joints.len() as u32 - 1)
    }

    pub fn add_support(&mut self, support: Support) {
        self.supports.push(support);
    }

    /// Adds a driver; returns its index (for [`SensorKind::DriverEffort`]).
    pub fn add_driver(&mut self, name: &str, target: DriverTarget, motion: TimeFunction) -> usize {
        self.drivers.push(Driver {
            name: name.into(),
            target,
            motion,
        });
        self.drivers.len() - 1
    }

    pub fn add_load(&mut self, load: Load) {
        self.loads.push(load);
    }

    /// A dead force with a constant time function (scaled by the load factor in statics).
    pub fn add_dead_force(&mut self, node: NodeId, force: Vector3<f64>) {
        self.add_load(Load {
            node,
            kind: LoadKind::Force,
            axes: LoadAxes::Dead,
            value: force,
            time: TimeFunction::constant(1.0),
        });
    }

    /// A dead moment with a constant time function.
    pub fn add_dead_moment(&mut self, node: NodeId, moment: Vector3<f64>) {
        self.add_load(Load {
            node,
            kind: LoadKind::Moment,
            axes: LoadAxes::Dead,
            value: moment,
            time: TimeFunction::constant(1.0),
        });
    }

    pub fn add_sensor(&mut self, name: &str, kind: SensorKind) {
        self.sensors.push(Sensor {
            name: name.into(),
            kind,
        });
    }
}

/// A stop on a joint coordinate: a stiff unilateral spring-damper outside `[lower, upper]`
/// ([`crate::assembly::joint_forces`]). Units: m or rad for the bounds, N/m or N m/rad for `stiffness`, N s/m or
/// N m s/rad for `damping`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointLimit {
    pub name: String,
    pub joint: JointId,
    pub coordinate: usize,
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub stiffness: f64,
    pub damping: f64,
}

/// A PID law on a measured joint coordinate ([`crate::assembly::joint_forces`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pid {
    /// The measured coordinate $y$ (often the actuated one).
    pub joint: JointId,
    pub coordinate: usize,
    /// $r(t)$, in the measured coordinate's unit.
    pub setpoint: TimeFunction,
    pub kp: f64,
    pub ki: f64,
    pub kd: f64,
    /// Saturation $|u| \le u_{max}$ (`None`: none).
    pub max_effort: Option<f64>,
}

/// What gives an actuator's effort.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Effort {
    /// $u = f(t)$ (N or N m).
    Time(TimeFunction),
    /// A PID law.
    Pid(Pid),
}

/// A force (on a length) or torque (on an angle) acting on a joint coordinate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointActuator {
    pub name: String,
    pub joint: JointId,
    pub coordinate: usize,
    pub effort: Effort,
}
