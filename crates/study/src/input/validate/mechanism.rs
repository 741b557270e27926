//! Validation of the mechanism: `[[bodies]]`, `[[rigid_bodies]]`, `[[point_masses]]`,
//! `[[springs]]`, `[[supports]]`, `[[joints]]`, `[[drivers]]`, `[[loads]]`, `[[sensors]]`,
//! `[[initial]]`, `[output]` and the multibody analyses, into a [`Mechanism`] in which every
//! name is resolved (bodies, interfaces, points, joints, drivers) and every value checked.
//!
//! What needs the reduced bodies (interface positions, the tree of joints, unheld
//! coordinates, rigid loops) is checked by `mbs::System::new` when the study runs;
//! `crate::build` (`BuiltMechanism::system`) turns those errors back into a located message.

use super::Validator;
use crate::input::keys;
use crate::input::schema::*;
use crate::input::source::{suggestions, unknown_reference, KeyPath};
use mbs::{Interpolation, JointKind, LoadAxes, LoadKind, RotationSupport, TimeFunction, TranslationSupport};
use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};
use reduction::ReducedBody;
use std::collections::HashMap;
use std::path::PathBuf;
use superelement::{Damping, MassVariant};

/// Name of the fixed point of the world in `between`, `at`, ...
pub const GROUND: &str = "ground";

/// A point of the mechanism as named in the file, `"body.point"` or `"ground"`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PointRef {
    Ground,
    /// Interface (by name) of flexible body `body` (index into [`Mechanism::bodies`]).
    Flexible {
        body: usize,
        interface: String,
    },
    /// Point `point` (index into its `points`) of rigid body `body`.
    Rigid {
        body: usize,
        point: usize,
    },
}

/// Where a flexible body's reduced body comes from.
#[derive(Clone, Debug)]
pub enum BodySource {
    /// A part of the study, reduced through the cache when the study runs.
    Part(usize),
    /// A reduced-body file, read during validation.
    File(PathBuf, std::sync::Arc<ReducedBody>),
}

/// The floating frame of a flexible body, by interface name for the interface-node choice
/// (resolved against the reduced body when it exists).
#[derive(Clone, Debug, PartialEq)]
pub enum FrameSpec {
    CenterOfMass,
    InterfaceNode(String),
    AuxiliaryNode,
}

#[derive(Clone, Debug)]
pub struct FlexibleSpec {
    pub name: String,
    pub path: KeyPath,
    pub source: BodySource,
    pub interfaces: Vec<String>,
    /// The named load points inside the body (the part's `load_points`, or the reduced-body
    /// file's), where `[[loads]]` may act besides the interfaces.
    pub load_points: Vec<String>,
    pub frame: FrameSpec,
    pub inertia: MassVariant,
    /// The part's axes in the inertial frame at t = 0.
    pub placement: Isometry3<f64>,
    /// Rayleigh factors and one modal ratio for every fixed-interface mode (expanded when the
    /// number of modes is known).
    pub damping: Damping,
    pub modal_ratio: Option<f64>,
    /// `mbs::FlexibleBody::planar`: the body's `planar`, else its part's reduction's.
    pub planar: bool,
}

#[derive(Clone, Debug)]
pub struct RigidSpec {
    pub name: String,
    pub path: KeyPath,
    pub mass: f64,
    pub center_of_mass: Vector3<f64>,
    pub inertia: Matrix3<f64>,
    pub points: Vec<(String, Vector3<f64>)>,
}

#[derive(Clone, Debug)]
pub struct PointMassSpec {
    pub name: String,
    pub path: KeyPath,
    pub at: PointRef,
    pub mass: f64,
}

#[derive(Clone, Debug)]
pub struct SpringSpec {
    pub name: String,
    pub path: KeyPath,
    pub a: PointRef,
    /// `None`: the ground point.
    pub b: Option<PointRef>,
    pub ground_point: Vector3<f64>,
    pub stiffness: f64,
    pub damping: f64,
    pub rest_length: Option<f64>,
}

#[derive(Clone, Debug)]
pub struct SupportSpec {
    pub path: KeyPath,
    pub at: PointRef,
    pub translation: TranslationSupport,
    pub rotation: RotationSupport,
}

#[derive(Clone, Debug)]
pub struct JointSpec {
    pub name: String,
    pub path: KeyPath,
    pub parent: PointRef,
    pub child: PointRef,
    /// `None`: a fixed joint (the two points become one node).
    pub kind: Option<JointKind>,
    /// The joint had errors (reported): kept so that later references resolve, never run.
    pub invalid: bool,
}

#[derive(Clone, Debug)]
pub struct DriverSpec {
    pub name: String,
    pub path: KeyPath,
    /// Index into [`Mechanism::joints`].
    pub joint: usize,
    pub coordinate: usize,
    pub motion: TimeFunction,
}

#[derive(Clone, Debug)]
pub struct PointLoadSpec {
    pub name: String,
    pub path: KeyPath,
    pub at: PointRef,
    pub axes: LoadAxes,
    /// Force and/or moment.
    pub values: Vec<(LoadKind, Vector3<f64>)>,
    pub time: TimeFunction,
}

/// A `[[loads]]` point load at a load point inside a flexible body (`"body.point"` where
/// `point` is no interface): the name is resolved against the reduced body's load points when
/// the study runs (`crate::build`).
#[derive(Clone, Debug)]
pub struct BodyLoadSpec {
    pub name: String,
    pub path: KeyPath,
    /// Index into [`Mechanism::bodies`].
    pub body: usize,
    pub point: String,
    pub axes: LoadAxes,
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
    pub time: TimeFunction,
}

/// Which mesh nodes a `stress` sensor reads (resolved against the body's mesh when the study
/// runs).
#[derive(Clone, Debug, PartialEq)]
pub enum StressNodes {
    /// One node by index in the part's mesh (0-based, as the VTU files and the hot spot).
    Index(usize),
    /// One node by its label in the part's mesh file (the deck's node number; the 1-based
    /// position for generated meshes).
    Label(u64),
    /// The mesh node at this position (part axes) \[m\].
    At(Vector3<f64>),
    /// The largest von Mises stress over a node set of the part's mesh.
    Set(String),
}

/// What a sensor measures, with its references resolved.
#[derive(Clone, Debug)]
pub enum SensorTarget {
    Position(PointRef),
    Displacement(PointRef),
    RelativePosition(PointRef, PointRef),
    Rotation(PointRef),
    Velocity(PointRef),
    AngularVelocity(PointRef),
    /// The point and the axes (`axes = "body"`: the point's own).
    Acceleration(PointRef, mbs::SensorAxes),
    AngularAcceleration(PointRef, mbs::SensorAxes),
    Deflection {
        of: PointRef,
        chord: [PointRef; 2],
        normal: Option<Vector3<f64>>,
    },
    JointCoordinate(usize, usize),
    JointRate(usize, usize),
    Modal(usize),
    /// Reaction at a supported point, or at the ground side of a joint to the ground.
    Reaction(ReactionAt),
    DriverEffort(usize),
    /// Index into [`Mechanism::actuators`].
    ActuatorEffort(usize),
    Energy,
    /// Work, energies, dissipation and their balance error over a dynamic run.
    EnergyBalance,
    Momentum,
    /// Stresses of flexible body `body` (index into [`Mechanism::bodies`]).
    Stress {
        body: usize,
        nodes: StressNodes,
    },
}

#[derive(Clone, Debug)]
pub enum ReactionAt {
    Point(PointRef),
    GroundJoint(usize),
}

#[derive(Clone, Debug)]
pub struct SensorSpec {
    pub name: String,
    pub path: KeyPath,
    pub target: SensorTarget,
}

#[derive(Clone, Debug)]
pub enum InitialSpec {
    Joint {
        path: KeyPath,
        joint: usize,
        coordinate: usize,
        value: Option<f64>,
        rate: Option<f64>,
    },
    Point {
        path: KeyPath,
        at: PointRef,
        velocity: Vector3<f64>,
        angular_velocity: Vector3<f64>,
    },
    /// A body's rigid velocity about `point` (default: its centre of mass), given to it and to
    /// everything attached to it.
    Body {
        path: KeyPath,
        body: BodyRef,
        velocity: Vector3<f64>,
        angular_velocity: Vector3<f64>,
        point: Option<Vector3<f64>>,
    },
}

/// A flexible body (index into [`Mechanism::bodies`]) or a rigid one (into
/// [`Mechanism::rigid_bodies`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyRef {
    Flexible(usize),
    Rigid(usize),
}

/// `[[joint_springs]]`.
#[derive(Clone, Debug)]
pub struct JointSpringSpec {
    pub name: String,
    pub path: KeyPath,
    pub joint: usize,
    pub coordinate: usize,
    pub stiffness: f64,
    pub damping: f64,
    pub rest: f64,
    pub preload: f64,
}

/// `[[joint_limits]]`.
#[derive(Clone, Debug)]
pub struct JointLimitSpec {
    pub name: String,
    pub path: KeyPath,
    pub joint: usize,
    pub coordinate: usize,
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub stiffness: f64,
    pub damping: f64,
}

/// What gives an actuator's effort.
#[derive(Clone, Debug)]
pub enum EffortSpec {
    Time(TimeFunction),
    Pid {
        /// The measured joint coordinate.
        joint: usize,
        coordinate: usize,
        setpoint: TimeFunction,
        kp: f64,
        ki: f64,
        kd: f64,
        max_effort: Option<f64>,
    },
}

/// `[[actuators]]`.
#[derive(Clone, Debug)]
pub struct ActuatorSpec {
    pub name: String,
    pub path: KeyPath,
    pub joint: usize,
    pub coordinate: usize,
    pub effort: EffortSpec,
}

/// `[output]`.
#[derive(Clone, Debug)]
pub struct OutputSpec {
    pub every: usize,
    pub vtu_every: Option<usize>,
    pub plots: bool,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            every: 1,
            vtu_every: None,
            plots: true,
        }
    }
}

/// How the mechanism starts at t = 0 (`[[initial]] start`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StartChoice {
    /// The consistent start: the closed loops assembled at the drivers' and initial values,
    /// every rate solved from the drivers' and initial rates (`mbs::System::initial_state`).
    #[default]
    Consistent,
    /// The same configuration with every coordinate's rate zero; the drivers keep their rates
    /// (`mbs::System::initial_state_at_rest`).
    AtRest,
}

/// The validated mechanism.
#[derive(Clone, Debug, Default)]
pub struct Mechanism {
    pub bodies: Vec<FlexibleSpec>,
    pub rigid_bodies: Vec<RigidSpec>,
    pub point_masses: Vec<PointMassSpec>,
    pub springs: Vec<SpringSpec>,
    pub supports: Vec<SupportSpec>,
    pub joints: Vec<JointSpec>,
    pub drivers: Vec<DriverSpec>,
    pub gravity: Option<(KeyPath, Vector3<f64>)>,
    pub loads: Vec<PointLoadSpec>,
    /// Point loads at load points inside flexible bodies.
    pub body_loads: Vec<BodyLoadSpec>,
    pub sensors: Vec<SensorSpec>,
    pub initial: Vec<InitialSpec>,
    /// How the mechanism starts (`[[initial]] start`).
    pub start: StartChoice,
    pub joint_springs: Vec<JointSpringSpec>,
    pub joint_limits: Vec<JointLimitSpec>,
    pub actuators: Vec<ActuatorSpec>,
    pub output: OutputSpec,
}

impl Mechanism {
    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty() && self.rigid_bodies.is_empty() && self.point_masses.is_empty()
    }

    /// `"body.point"` for messages and node names.
    pub fn point_name(&self, p: &PointRef) -> String {
        match p {
            PointRef::Ground => GROUND.into(),
            PointRef::Flexible { body, interface } => format!("{}.{interface}", self.bodies[*body].name),
            PointRef::Rigid { body, point } => {
                let b = &self.rigid_bodies[*body];
                format!("{}.{}", b.name, b.points[*point].0)
            }
        }
    }
}

/// An analysis of the mechanism.
#[derive(Clone, Debug)]
pub enum MbsAnalysis {
    Equilibrium {
        steps: usize,
        tolerance: f64,
        max_iterations: usize,
        time: f64,
        /// Arc-length continuation (passes limit points) instead of Newton with load stepping.
        arc_length: bool,
    },
    Dynamic {
        t_end: f64,
        dt: f64,
        rho_inf: f64,
        tolerance: f64,
        max_iterations: usize,
        /// Full or modified Newton (`newton = "full" | "modified"`).
        newton: mbs::NewtonStrategy,
        /// `translations = "body"`: the free nodes' translations carried in body axes
        /// (`mbs::DynamicSettings::body_axis_translations`).
        body_axis_translations: bool,
        /// Smallest step \[s\]: a failed fixed step is retried with halved steps down to it;
        /// the adaptive step's lower bound.
        dt_min: f64,
        /// The adaptive step (`error_tolerance`, with `dt_max`), or `None`: fixed steps.
        adaptive: Option<mbs::AdaptiveSettings>,
    },
    Linearized {
        modes: usize,
        about: About,
    },
    /// Linearised buckling about the equilibrium under the full load (or the state of
    /// `start`), `modes` critical load factors.
    Buckling {
        modes: usize,
        steps: usize,
        tolerance: f64,
        max_iterations: usize,
    },
}

/// The state a linearized analysis is about.
#[derive(Clone, Debug)]
pub enum About {
    Initial,
    Equilibrium,
    Time { t: f64, dt: f64 },
}

/// Whether scalar coordinate `c` of joint `j` is an angle (else a length).
pub fn joint_is_angle(m: &Mechanism, j: usize, c: usize) -> bool {
    match &m.joints[j].kind {
        Some(JointKind::Prismatic { .. }) => false,
        Some(JointKind::Cylindrical { .. }) => c == 1,
        Some(JointKind::Planar { .. }) => c == 2,
        _ => true,
    }
}

/// A modal damping ratio from which a warning says it is unusually high (structures have
/// 0.5 % to 5 %); above 1 (critical) it is refused.
pub const MODAL_RATIO_WARNING: f64 = 0.2;

fn unit(v: Vector3<f64>) -> Option<Unit<Vector3<f64>>> {
    (v.norm() > 0.0 && v.iter().all(|x| x.is_finite())).then(|| Unit::new_normalize(v))
}

/// Where a flexible body's reduced body comes from, and what it brings.
struct BodyOrigin {
    source: BodySource,
    /// Its interfaces' names (`auxiliary` too, with an auxiliary node).
    interfaces: Vec<String>,
    /// Whether it has an auxiliary node.
    auxiliary: bool,
    load_points: Vec<String>,
    /// The part's `planar` (a body's default).
    planar_part: bool,
}

impl Validator<'_> {
    /// The whole mechanism; `parts` are the study's parts by name (None when invalid).
    pub(super) fn mechanism(
        &mut self,
        file: &StudyFile,
        parts: &[(String, Option<crate::input::part::Part>)],
    ) -> Mechanism {
        let mut m = Mechanism::default();
        let part_names: Vec<String> = parts.iter().map(|(n, _)| n.clone()).collect();
        let mut names = HashMap::new();
        for (i, b) in file.bodies.iter().enumerate() {
            let path = KeyPath::root().key("bodies").index(i);
            if !self.body_name(&path, &b.name, &mut names) {
                continue;
            }
            if let Some(spec) = self.flexible(&path, b, parts, &part_names) {
                self.register("flexible", &b.name, m.bodies.len());
                m.bodies.push(spec);
            } else {
                self.failed.insert(format!("body:{}", b.name));
            }
        }
        for (i, b) in file.rigid_bodies.iter().enumerate() {
            let path = KeyPath::root().key("rigid_bodies").index(i);
            if !self.body_name(&path, &b.name, &mut names) {
                continue;
            }
            if let Some(spec) = self.rigid(&path, b) {
                self.register("rigid", &b.name, m.rigid_bodies.len());
                m.rigid_bodies.push(spec);
            } else {
                self.failed.insert(format!("body:{}", b.name));
            }
        }
        for (i, p) in file.point_masses.iter().enumerate() {
            let path = KeyPath::root().key("point_masses").index(i);
            let at = self.point(&path.key("at"), &p.at, &m, false);
            let mass = keys::ranged("point_masses", "mass", p.mass);
            if let (Some(at), Some(mass)) = (at, mass) {
                m.point_masses.push(PointMassSpec {
                    name: p.name.clone(),
                    path,
                    at,
                    mass,
                });
            } else {
                self.mark_failed("point_mass", &p.name);
            }
        }
        for (i, s) in file.springs.iter().enumerate() {
            let path = KeyPath::root().key("springs").index(i);
            if let Some(spec) = self.spring(&path, s, &m) {
                m.springs.push(spec);
            }
        }
        for (i, s) in file.supports.iter().enumerate() {
            let path = KeyPath::root().key("supports").index(i);
            if let Some(spec) = self.mbs_support(&path, s, &m) {
                m.supports.push(spec);
            }
        }
        for (i, j) in file.joints.iter().enumerate() {
            let path = KeyPath::root().key("joints").index(i);
            if self.lookup("joint", &j.name).is_some() {
                let first = file.joints.iter().position(|k| k.name == j.name).unwrap_or(i);
                self.duplicate(&path, "joint", &j.name, &KeyPath::root().key("joints").index(first), "");
                continue;
            }
            self.register("joint", &j.name, m.joints.len());
            if let Some(spec) = self.joint(&path, j, &m) {
                m.joints.push(spec);
            } else {
                // Keep the index space of later references: a placeholder that never runs.
                m.joints.push(JointSpec {
                    name: j.name.clone(),
                    path,
                    parent: PointRef::Ground,
                    child: PointRef::Ground,
                    kind: None,
                    invalid: true,
                });
            }
        }
        self.drivers(file, &mut m);
        for (i, l) in file.loads.iter().enumerate() {
            let path = KeyPath::root().key("loads").index(i);
            self.load(&path, l, &mut m);
        }
        // Before the sensors: an `actuator-effort` sensor names an actuator.
        self.joint_forces(file, &mut m);
        self.sensors(file, &mut m);
        let mut start_given: Option<KeyPath> = None;
        for (i, c) in file.initial.iter().enumerate() {
            let path = KeyPath::root().key("initial").index(i);
            if let Some(start) = &c.start {
                if let Some(choice) = self.initial_start(&path, start, start_given.as_ref()) {
                    m.start = choice;
                }
                start_given.get_or_insert(path.key("start"));
                continue;
            }
            if let Some(spec) = self.initial(&path, c, &m) {
                m.initial.push(spec);
            }
        }
        if let Some(o) = &file.output {
            // 0 is out of range, reported by the registry's check.
            let every = o.every.unwrap_or(1);
            m.output = OutputSpec {
                every: every.max(1),
                vtu_every: o.vtu_every.filter(|n| *n > 0),
                plots: o.plots.unwrap_or(true),
            };
        }
        m
    }

    /// `[[drivers]]`: joint coordinates as functions of time.
    fn drivers(&mut self, file: &StudyFile, m: &mut Mechanism) {
        for (i, d) in file.drivers.iter().enumerate() {
            let path = KeyPath::root().key("drivers").index(i);
            if self.lookup("driver", &d.name).is_some() {
                let first = file.drivers.iter().position(|e| e.name == d.name).unwrap_or(i);
                self.duplicate(
                    &path,
                    "driver",
                    &d.name,
                    &KeyPath::root().key("drivers").index(first),
                    "",
                );
                continue;
            }
            let Some(joint) = self.joint_ref(&path.key("joint"), &d.joint, m) else {
                continue;
            };
            let coordinate = d.coordinate.unwrap_or(0);
            if !self.joint_coordinate(&path, m, joint, coordinate) {
                continue;
            }
            // Two motions of one coordinate contradict each other: neither may win.
            if let Some(first) = m
                .drivers
                .iter()
                .find(|x| x.joint == joint && x.coordinate == coordinate)
            {
                let (name, first) = (first.name.clone(), self.first_defined(&first.path.key("joint")));
                self.err(
                    &path.key("joint"),
                    format!(
                        "coordinate {coordinate} of joint '{}' is already driven by driver '{name}' at {first}",
                        d.joint
                    ),
                );
                continue;
            }
            if let Some(motion) = self.time_function(&path.key("function"), &d.function, true) {
                self.register("driver", &d.name, m.drivers.len());
                m.drivers.push(DriverSpec {
                    name: d.name.clone(),
                    path,
                    joint,
                    coordinate,
                    motion,
                });
            }
        }
        // A driver with errors is known, not unknown, to the sensors that name it.
        for d in &file.drivers {
            self.mark_failed("driver", &d.name);
        }
    }

    /// `[[sensors]]`, after the actuators (an `actuator-effort` sensor names one).
    fn sensors(&mut self, file: &StudyFile, m: &mut Mechanism) {
        for (i, s) in file.sensors.iter().enumerate() {
            let path = KeyPath::root().key("sensors").index(i);
            if self.lookup("sensor", &s.name).is_some() || self.has_failed("sensor", &s.name) {
                let first = file.sensors.iter().position(|t| t.name == s.name).unwrap_or(i);
                self.duplicate(
                    &path,
                    "sensor",
                    &s.name,
                    &KeyPath::root().key("sensors").index(first),
                    "",
                );
                continue;
            }
            if let Err(e) = super::check_name(&s.name) {
                self.err(&path.key("name"), e);
                continue;
            }
            if let Some(target) = self.sensor(&path, s, m) {
                self.register("sensor", &s.name, m.sensors.len());
                m.sensors.push(SensorSpec {
                    name: s.name.clone(),
                    path,
                    target,
                });
            } else {
                self.mark_failed("sensor", &s.name);
            }
        }
    }

    fn body_name(&mut self, path: &KeyPath, name: &str, names: &mut HashMap<String, KeyPath>) -> bool {
        if let Err(e) = super::check_name(name) {
            self.err(&path.key("name"), e);
            return false;
        }
        if name == GROUND || name.contains('.') {
            self.err(
                &path.key("name"),
                format!("a body cannot be called '{name}' ('{GROUND}' is the fixed world, and '.' separates a body from its point)"),
            );
            return false;
        }
        if let Some(first) = names.get(name) {
            let first = first.clone();
            self.duplicate(
                path,
                "body",
                name,
                &first,
                " (flexible and rigid bodies share one name space)",
            );
            return false;
        }
        names.insert(name.to_string(), path.clone());
        true
    }

    fn choice<'a>(
        &mut self,
        path: &KeyPath,
        value: &Option<String>,
        default: &'a str,
        allowed: &[&'a str],
        what: &str,
    ) -> Option<&'a str> {
        let Some(v) = value else {
            return Some(default);
        };
        match allowed.iter().find(|a| **a == v) {
            Some(a) => Some(a),
            None => {
                let names: Vec<String> = allowed.iter().map(|s| s.to_string()).collect();
                self.err(path, unknown_reference(what, v, &names));
                None
            }
        }
    }

    fn flexible(
        &mut self,
        path: &KeyPath,
        b: &BodyFile,
        parts: &[(String, Option<crate::input::part::Part>)],
        part_names: &[String],
    ) -> Option<FlexibleSpec> {
        if b.matrices.is_some() && (b.part.is_some() || b.file.is_some()) {
            self.err(
                path,
                "give the reduced body by `part`, `file` or `matrices`, one of them",
            );
            return None;
        }
        let BodyOrigin {
            source,
            interfaces,
            auxiliary,
            load_points,
            planar_part,
        } = self.body_origin(path, b, parts, part_names)?;
        let frame = self.body_frame(path, b, &interfaces, auxiliary)?;
        if b.frame_interface.is_some() && !matches!(frame, FrameSpec::InterfaceNode(_)) {
            self.err_key(
                &path.key("frame_interface"),
                "`frame_interface` applies to frame = \"interface-node\" only",
            );
        }
        let inertia = match self.choice(
            &path.key("inertia"),
            &b.inertia,
            "exact",
            &keys::names("bodies", "inertia"),
            "inertia variant",
        )? {
            "lumped" => MassVariant::Lumped,
            _ => MassVariant::Exact,
        };
        let position = match &b.position {
            Some(p) => self.finite3(&path.key("position"), p, "the position [m]")?,
            None => Vector3::zeros(),
        };
        let rotation = match &b.rotation {
            Some(r) => self.rotation(&path.key("rotation"), r)?,
            None => UnitQuaternion::identity(),
        };
        let (damping, modal_ratio) = match &b.damping {
            Some(d) => self.body_damping(&path.key("damping"), d)?,
            None => (Damping::none(), None),
        };
        Some(FlexibleSpec {
            name: b.name.clone(),
            path: path.clone(),
            source,
            interfaces,
            load_points,
            frame,
            inertia,
            placement: Isometry3::from_parts(Translation3::from(position), rotation),
            damping,
            modal_ratio,
            planar: b.planar.unwrap_or(planar_part),
        })
    }

    /// Where a flexible body's reduced body comes from (`part`, `file` or `matrices`), with its
    /// interfaces and load points.
    fn body_origin(
        &mut self,
        path: &KeyPath,
        b: &BodyFile,
        parts: &[(String, Option<crate::input::part::Part>)],
        part_names: &[String],
    ) -> Option<BodyOrigin> {
        let mut load_points: Vec<String> = Vec::new();
        let mut planar_part = false;
        let (source, interfaces, auxiliary) = match (&b.part, &b.file) {
            (None, None) if b.matrices.is_some() => {
                let m = b.matrices.as_ref()?;
                match crate::input::matrices::reduce_matrices(&b.name, m, &self.src.dir()) {
                    Ok(body) => {
                        let names = body.interfaces.iter().map(|i| i.name.clone()).collect();
                        (
                            BodySource::File(self.src.dir().join(&m.stiffness), std::sync::Arc::new(body)),
                            names,
                            false,
                        )
                    }
                    Err((key, message)) => {
                        self.err(&path.key("matrices").key(key), message);
                        return None;
                    }
                }
            }
            (Some(name), None) => {
                let Some(index) = self.lookup("part", name) else {
                    self.err(&path.key("part"), unknown_reference("part", name, part_names));
                    return None;
                };
                let part = parts[index].1.as_ref()?;
                let Some(reduction) = &part.reduction else {
                    self.err(
                        &path.key("part"),
                        format!("part '{name}' has no [parts.reduction]: a flexible body is a reduced part (add modes or cutoff_hz)"),
                    );
                    return None;
                };
                let index = parts[..index].iter().filter(|(_, p)| p.is_some()).count();
                let mut names: Vec<String> = part.interfaces.iter().map(|i| i.name.clone()).collect();
                if reduction.auxiliary_node {
                    names.push("auxiliary".into());
                }
                load_points = reduction.load_points.iter().map(|(n, _)| n.clone()).collect();
                planar_part = reduction.planar;
                (BodySource::Part(index), names, reduction.auxiliary_node)
            }
            (None, Some(file)) if file.to_lowercase().ends_with(".fem") => {
                // An MBDyn modal element file: every exposed node is an interface.
                let full = self.src.dir().join(file);
                match reduction::mbdyn::read_mbdyn_fem(&full, None) {
                    Ok((body, notes)) => {
                        for note in notes {
                            self.warn(&path.key("file"), format!("{}: {note}", full.display()));
                        }
                        let names = body.interfaces.iter().map(|i| i.name.clone()).collect();
                        (BodySource::File(full, std::sync::Arc::new(body)), names, false)
                    }
                    Err(e) => {
                        self.err(&path.key("file"), format!("cannot read the MBDyn file: {e}"));
                        return None;
                    }
                }
            }
            (None, Some(file)) => {
                let full = self.src.dir().join(file);
                match reduction::file::read(&full) {
                    Ok(body) => {
                        let names = body.interfaces.iter().map(|i| i.name.clone()).collect();
                        let aux = body.auxiliary_interface.is_some();
                        load_points = body.load_points.iter().map(|p| p.name.clone()).collect();
                        (BodySource::File(full, std::sync::Arc::new(body)), names, aux)
                    }
                    Err(e) => {
                        self.err(
                            &path.key("file"),
                            format!("cannot read the reduced body {}: {e}", full.display()),
                        );
                        return None;
                    }
                }
            }
            _ => {
                self.err(path, "give the reduced body by `part` (a part with [parts.reduction]) or by `file` (an .rbody or MBDyn .fem file), one of them");
                return None;
            }
        };
        Some(BodyOrigin {
            source,
            interfaces,
            auxiliary,
            load_points,
            planar_part,
        })
    }

    /// A flexible body's `frame` (and `frame_interface`).
    fn body_frame(
        &mut self,
        path: &KeyPath,
        b: &BodyFile,
        interfaces: &[String],
        auxiliary: bool,
    ) -> Option<FrameSpec> {
        let frame = match self.choice(
            &path.key("frame"),
            &b.frame,
            "center-of-mass",
            &keys::names("bodies", "frame"),
            "frame",
        )? {
            "interface-node" => {
                let Some(name) = &b.frame_interface else {
                    self.err(path, "missing key `frame_interface` (the interface the frame sits at, with frame = \"interface-node\")");
                    return None;
                };
                if !interfaces.contains(name) {
                    self.err(
                        &path.key("frame_interface"),
                        unknown_reference("interface", name, interfaces),
                    );
                    return None;
                }
                FrameSpec::InterfaceNode(name.clone())
            }
            "auxiliary-node" => {
                if !auxiliary {
                    self.err(
                        &path.key("frame"),
                        "frame = \"auxiliary-node\" needs a body reduced with an auxiliary node (auxiliary_node = true in its [parts.reduction])",
                    );
                    return None;
                }
                FrameSpec::AuxiliaryNode
            }
            _ => FrameSpec::CenterOfMass,
        };
        Some(frame)
    }

    /// A flexible body's `damping`: Rayleigh factors and a modal ratio.
    fn body_damping(&mut self, dp: &KeyPath, d: &DampingFile) -> Option<(Damping, Option<f64>)> {
        let values = [("alpha", d.alpha), ("beta", d.beta), ("modal_ratio", d.modal_ratio)];
        if !self.complete("bodies.damping", "", &values) {
            return None;
        }
        if let Some(zeta) = d.modal_ratio {
            if zeta >= MODAL_RATIO_WARNING {
                self.warn(
                    &dp.key("modal_ratio"),
                    format!("modal_ratio = {zeta} is {:.0} % of critical damping in every mode; structures have about 0.5 % to 5 % (the ratio is a fraction, not a percentage)", 100.0 * zeta),
                );
            }
        }
        let mut damping = Damping::none();
        damping.alpha = d.alpha.unwrap_or(0.0);
        damping.beta = d.beta.unwrap_or(0.0);
        Some((damping, d.modal_ratio))
    }

    fn rotation(&mut self, path: &KeyPath, r: &RotationFile) -> Option<UnitQuaternion<f64>> {
        let axis = self.finite3(&path.key("axis"), &r.axis, "the rotation axis")?;
        let Some(axis) = unit(axis) else {
            self.err(&path.key("axis"), "the rotation axis must not be zero");
            return None;
        };
        if !r.angle_deg.is_finite() {
            self.err(&path.key("angle_deg"), "the angle must be finite");
            return None;
        }
        Some(UnitQuaternion::from_axis_angle(&axis, r.angle_deg.to_radians()))
    }

    fn rigid(&mut self, path: &KeyPath, b: &RigidBodyFile) -> Option<RigidSpec> {
        let mass = keys::ranged("rigid_bodies", "mass", b.mass);
        let com = self.finite3(&path.key("center_of_mass"), &b.center_of_mass, "the centre of mass [m]");
        let J = Matrix3::from_fn(|i, j| b.inertia[i][j]);
        let mut ok = mass.is_some() && com.is_some();
        let sym = (J - J.transpose()).abs().max() <= 1e-12 * J.abs().max();
        // The inertia tensor of a body is symmetric positive semi-definite; its principal
        // moments obey the triangle inequality (I1 <= I2 + I3), up to round-off of the input.
        let eig = J.symmetric_eigen().eigenvalues;
        let tol = 1e-9 * eig.abs().max();
        let valid = J.iter().all(|x| x.is_finite())
            && sym
            && eig.iter().all(|l| *l >= -tol)
            && (0..3).all(|k| eig[k] <= eig[(k + 1) % 3] + eig[(k + 2) % 3] + tol);
        if !valid {
            self.err(
                &path.key("inertia"),
                format!("the inertia tensor [kg m^2] must be symmetric with non-negative principal moments that obey I1 <= I2 + I3; principal moments {:.4e}, {:.4e}, {:.4e}", eig[0], eig[1], eig[2]),
            );
            ok = false;
        }
        let mut points = Vec::new();
        for (name, p) in &b.points {
            if name.contains('.') || name.is_empty() {
                self.err_key(
                    &path.key("points").key(name),
                    format!("point name '{name}' must be non-empty without '.'"),
                );
                ok = false;
                continue;
            }
            match self.finite3(&path.key("points").key(name), p, "the point [m]") {
                Some(v) => points.push((name.clone(), v)),
                None => ok = false,
            }
        }
        ok.then(|| RigidSpec {
            name: b.name.clone(),
            path: path.clone(),
            mass: mass.unwrap_or(0.0),
            center_of_mass: com.unwrap_or_default(),
            inertia: J,
            points,
        })
    }

    /// `"body.point"` or `"ground"` (when `ground_ok`).
    pub(super) fn point(&mut self, path: &KeyPath, text: &str, m: &Mechanism, ground_ok: bool) -> Option<PointRef> {
        if text == GROUND {
            if ground_ok {
                return Some(PointRef::Ground);
            }
            self.err(path, format!("'{GROUND}' is not a point of a body here"));
            return None;
        }
        let Some((body, point)) = text.split_once('.') else {
            let known: Vec<String> = m
                .bodies
                .iter()
                .flat_map(|b| b.interfaces.iter().map(move |i| format!("{}.{i}", b.name)))
                .chain(
                    m.rigid_bodies
                        .iter()
                        .flat_map(|b| b.points.iter().map(move |(p, _)| format!("{}.{p}", b.name))),
                )
                .collect();
            self.err(
                path,
                format!("'{text}' is not a point: write \"body.point\" (an interface of a flexible body or a point of a rigid body){}", suggestions(text, &known, "point")),
            );
            return None;
        };
        if let Some(b) = self.lookup("flexible", body) {
            let spec = &m.bodies[b];
            if !spec.interfaces.iter().any(|i| i == point) {
                self.err(
                    path,
                    format!(
                        "flexible body '{body}' has no interface '{point}'{}",
                        suggestions(point, &spec.interfaces, "interface")
                    ),
                );
                return None;
            }
            return Some(PointRef::Flexible {
                body: b,
                interface: point.to_string(),
            });
        }
        if let Some(b) = self.lookup("rigid", body) {
            let spec = &m.rigid_bodies[b];
            let names: Vec<String> = spec.points.iter().map(|(n, _)| n.clone()).collect();
            let Some(k) = names.iter().position(|n| n == point) else {
                self.err(
                    path,
                    format!(
                        "rigid body '{body}' has no point '{point}'{}",
                        suggestions(point, &names, "point")
                    ),
                );
                return None;
            };
            return Some(PointRef::Rigid { body: b, point: k });
        }
        // A body that failed its own checks was reported where it is defined.
        if !self.failed.contains(&format!("body:{body}")) {
            let mut bodies: Vec<String> = m.bodies.iter().map(|b| b.name.clone()).collect();
            bodies.extend(m.rigid_bodies.iter().map(|b| b.name.clone()));
            self.err(path, unknown_reference("body", body, &bodies));
        }
        None
    }

    fn axis(&mut self, path: &KeyPath, table: &KeyPath, v: &Option<Vec3>, what: &str) -> Option<Vector3<f64>> {
        let Some(v) = v else {
            self.err(table, format!("missing key `{}` ({what})", path_key(path)));
            return None;
        };
        let v = self.finite3(path, v, what)?;
        match unit(v) {
            Some(u) => Some(u.into_inner()),
            None => {
                self.err(path, format!("{what} must not be zero"));
                None
            }
        }
    }

    fn spring(&mut self, path: &KeyPath, s: &SpringFile, m: &Mechanism) -> Option<SpringSpec> {
        let a = self.point(&path.key("between").index(0), &s.between[0], m, false);
        let b = if s.between[1] == GROUND {
            None
        } else {
            Some(self.point(&path.key("between").index(1), &s.between[1], m, false)?)
        };
        let ground_point = match (&b, &s.ground_point) {
            (None, Some(p)) => self.finite3(&path.key("ground_point"), p, "the ground point [m]")?,
            (None, None) => {
                self.err(
                    path,
                    "missing key `ground_point` (where the spring is attached to the ground, [x, y, z] m)",
                );
                return None;
            }
            (Some(_), Some(_)) => {
                self.err_key(
                    &path.key("ground_point"),
                    "`ground_point` applies to a spring to \"ground\" only",
                );
                return None;
            }
            (Some(_), None) => Vector3::zeros(),
        };
        let (k, c) = (s.stiffness, s.damping.unwrap_or(0.0));
        let values = [
            ("stiffness", Some(k)),
            ("damping", Some(c)),
            ("rest_length", s.rest_length),
        ];
        if !self.complete("springs", "", &values) {
            return None;
        }
        Some(SpringSpec {
            name: s.name.clone(),
            path: path.clone(),
            a: a?,
            b,
            ground_point,
            stiffness: k,
            damping: c,
            rest_length: s.rest_length,
        })
    }

    fn mbs_support(&mut self, path: &KeyPath, s: &MbsSupportFile, m: &Mechanism) -> Option<SupportSpec> {
        let at = self.point(&path.key("at"), &s.at, m, false);
        let kinds = keys::names("supports", "type");
        let kind = self.choice(
            &path.key("type"),
            &Some(s.kind.clone()),
            "clamp",
            &kinds,
            "support type",
        )?;
        let needs_axis = matches!(kind, "hinge" | "slider" | "plane" | "planar");
        if !needs_axis && s.axis.is_some() {
            self.err_key(
                &path.key("axis"),
                format!("`axis` does not apply to a '{kind}' support (only hinge, slider, plane and planar take one)"),
            );
            return None;
        }
        let axis = if needs_axis {
            Some(self.axis(&path.key("axis"), path, &s.axis, "the support axis")?)
        } else {
            None
        };
        let (translation, rotation) = match (kind, axis) {
            ("pin", _) => (TranslationSupport::Fixed, RotationSupport::Free),
            ("hinge", Some(axis)) => (TranslationSupport::Fixed, RotationSupport::Axis { axis }),
            ("slider", Some(direction)) => (TranslationSupport::Line { direction }, RotationSupport::Fixed),
            ("plane", Some(normal)) => (TranslationSupport::Plane { normal }, RotationSupport::Fixed),
            ("planar", Some(normal)) => (
                TranslationSupport::Plane { normal },
                RotationSupport::Axis { axis: normal },
            ),
            _ => (TranslationSupport::Fixed, RotationSupport::Fixed),
        };
        Some(SupportSpec {
            path: path.clone(),
            at: at?,
            translation,
            rotation,
        })
    }

    fn joint(&mut self, path: &KeyPath, j: &JointFile, m: &Mechanism) -> Option<JointSpec> {
        let kinds = keys::names("joints", "type");
        let kind = self.choice(&path.key("type"), &Some(j.kind.clone()), "fixed", &kinds, "joint type");
        let parent = self.point(&path.key("between").index(0), &j.between[0], m, true);
        let child = self.point(&path.key("between").index(1), &j.between[1], m, true);
        let kind = kind?;
        let (parent, child) = (parent?, child?);
        if parent == child {
            self.err(&path.key("between"), "a joint connects two different points");
            return None;
        }
        if child == PointRef::Ground && parent != PointRef::Ground && kind != "fixed" {
            self.err(
                &path.key("between").index(1),
                "\"ground\" is the parent of a joint: write it first, between = [\"ground\", \"body.point\"]",
            );
            return None;
        }
        let axis_keys: &[&str] = match kind {
            "revolute" | "prismatic" | "cylindrical" | "planar" => &["axis"],
            "universal" => &["axis", "axis2"],
            _ => &[],
        };
        for (key, v) in [("axis", &j.axis), ("axis2", &j.axis2)] {
            if v.is_some() && !axis_keys.contains(&key) {
                self.err_key(&path.key(key), format!("`{key}` does not apply to a {kind} joint"));
                return None;
            }
        }
        let what = if kind == "planar" {
            "the normal of the plane"
        } else {
            "the joint axis"
        };
        let joint_kind = match kind {
            "fixed" => None,
            "spherical" => Some(JointKind::Spherical),
            _ => {
                let axis = self.axis(&path.key("axis"), path, &j.axis, what)?;
                Some(match kind {
                    "revolute" => JointKind::Revolute { axis },
                    "prismatic" => JointKind::Prismatic { axis },
                    "cylindrical" => JointKind::Cylindrical { axis },
                    "planar" => JointKind::Planar { normal: axis },
                    _ => {
                        let axis2 = self.axis(
                            &path.key("axis2"),
                            path,
                            &j.axis2,
                            "the second axis of the universal joint",
                        )?;
                        if axis.cross(&axis2).norm() < 1e-6 {
                            self.err(
                                &path.key("axis2"),
                                "the two axes of a universal joint must not be parallel",
                            );
                            return None;
                        }
                        JointKind::Universal { axis1: axis, axis2 }
                    }
                })
            }
        };
        Some(JointSpec {
            name: j.name.clone(),
            path: path.clone(),
            parent,
            child,
            kind: joint_kind,
            invalid: false,
        })
    }

    fn joint_ref(&mut self, path: &KeyPath, name: &str, m: &Mechanism) -> Option<usize> {
        match self.lookup("joint", name) {
            Some(k) => Some(k),
            None => {
                let names: Vec<String> = m.joints.iter().map(|j| j.name.clone()).collect();
                self.err(path, unknown_reference("joint", name, &names));
                None
            }
        }
    }

    fn joint_coordinate(&mut self, path: &KeyPath, m: &Mechanism, joint: usize, coordinate: usize) -> bool {
        let j = &m.joints[joint];
        if j.invalid {
            // Its own errors are reported already.
            return false;
        }
        let n = j.kind.as_ref().map_or(0, JointKind::n_scalar);
        if coordinate >= n {
            let kind = j.kind.as_ref().map_or("fixed", JointKind::name);
            let at = if n == 0 { path.clone() } else { path.key("coordinate") };
            self.err(
                &at,
                format!(
                    "joint '{}' ({kind}) has {n} scalar coordinate{}; coordinate {coordinate} does not exist{}",
                    j.name,
                    if n == 1 { "" } else { "s" },
                    if n == 0 {
                        " (a spherical joint's rotation and a fixed joint cannot be driven or read as a number)"
                    } else {
                        ""
                    }
                ),
            );
            return false;
        }
        true
    }

    fn time_function(&mut self, path: &KeyPath, f: &TimeFunctionFile, driver: bool) -> Option<TimeFunction> {
        let kind = self.choice(
            &path.key("type"),
            &Some(f.kind.clone()),
            "table",
            keys::table("function").kinds,
            "function type",
        )?;
        self.only_keys(path, "function", kind, &format!("a '{kind}' function"));
        let num = |v: &mut Self, key: &str, x: Option<f64>, default: Option<f64>| -> Option<f64> {
            match x.or(default) {
                Some(x) if x.is_finite() => Some(x),
                Some(x) => {
                    v.err(&path.key(key), format!("`{key}` must be finite, got {x}"));
                    None
                }
                // Missing: the registry's check reported it.
                None => None,
            }
        };
        Some(match kind {
            "constant-speed" => TimeFunction::Linear {
                initial: num(self, "initial", f.initial, Some(0.0))?,
                rate: num(self, "speed", f.speed, None)?,
            },
            "ramp" => {
                let t_start = num(self, "t_start", f.t_start, Some(0.0))?;
                let t_end = num(self, "t_end", f.t_end, None)?;
                if t_end <= t_start {
                    self.err(
                        &path.key("t_end"),
                        format!("t_end must be after t_start ({t_start} s), got {t_end}"),
                    );
                    return None;
                }
                let from = num(self, "from", f.from, Some(0.0))?;
                let to = num(self, "to", f.to, None)?;
                if f.smooth.unwrap_or(true) {
                    TimeFunction::SmoothRamp {
                        t_start,
                        t_end,
                        from,
                        to,
                    }
                } else {
                    TimeFunction::Ramp {
                        t_start,
                        t_end,
                        from,
                        to,
                    }
                }
            }
            "spin-up" => {
                let omega = num(self, "speed", f.speed, None)?;
                let ramp_time = num(self, "ramp_time", f.ramp_time, None)?;
                let duration = keys::ranged("function", "ramp_time", ramp_time)?;
                TimeFunction::SpinUp { omega, duration }
            }
            "harmonic" => {
                let frequency = num(self, "frequency_hz", f.frequency_hz, None)?;
                TimeFunction::Sine {
                    offset: num(self, "offset", f.offset, Some(0.0))?,
                    amplitude: num(self, "amplitude", f.amplitude, None)?,
                    omega: 2.0 * std::f64::consts::PI * frequency,
                    phase: num(self, "phase_deg", f.phase_deg, Some(0.0))?.to_radians(),
                }
            }
            _ => {
                let interpolation = match self.choice(
                    &path.key("interpolation"),
                    &f.interpolation,
                    if driver { "cubic" } else { "linear" },
                    &keys::names("function", "interpolation"),
                    "interpolation",
                )? {
                    "cubic" => Interpolation::CubicSpline,
                    _ => Interpolation::Linear,
                };
                let made = match (&f.t, &f.value, &f.file) {
                    (Some(t), Some(v), None) => {
                        if t.len() != v.len() {
                            self.err(&path.key("value"), format!("`t` has {} entries and `value` {}: give one value per time", t.len(), v.len()));
                            return None;
                        }
                        let text: String = t.iter().zip(v).map(|(t, v)| format!("{t:e},{v:e}\n")).collect();
                        TimeFunction::table_from_csv(&text, interpolation).map_err(|e| (path.key("t"), e.to_string()))
                    }
                    (None, None, Some(file)) => {
                        let full = self.src.dir().join(file);
                        match fe_model::input::read_to_string(&full) {
                            Ok(text) => TimeFunction::table_from_csv(&text, interpolation).map_err(|e| (path.key("file"), format!("{}: {e}", full.display()))),
                            Err(e) => Err((path.key("file"), format!("cannot read the table {}: {e}", full.display()))),
                        }
                    }
                    _ => Err((path.clone(), "a table needs `t` and `value` (lists of equal length), or `file` (a CSV file of `time, value` rows), one of the two".into())),
                };
                match made {
                    Ok(f) => f,
                    Err((at, e)) => {
                        self.err(&at, e);
                        return None;
                    }
                }
            }
        })
    }

    fn load(&mut self, path: &KeyPath, l: &LoadFile, m: &mut Mechanism) {
        let Some(kind) = self.choice(
            &path.key("type"),
            &Some(l.kind.clone()),
            "point",
            keys::table("loads").kinds,
            "load type",
        ) else {
            return;
        };
        if kind == "gravity" {
            self.only_keys(path, "loads", "gravity", "a gravity load");
            // Missing: the registry's check reported it.
            let Some(g) = &l.g else {
                return;
            };
            let Some(g) = self.finite3(&path.key("g"), g, "g [m/s^2]") else {
                return;
            };
            if m.gravity.is_some() {
                self.err(
                    path,
                    "gravity is already defined by another [[loads]]: give one gravity load",
                );
                return;
            }
            m.gravity = Some((path.clone(), g));
            return;
        }
        self.only_keys(path, "loads", "point", "a point load");
        let Some(at_text) = &l.at else {
            return;
        };
        // "body.point" naming no interface of a flexible body: a load point inside it.
        let inner = at_text.split_once('.').and_then(|(body, point)| {
            let b = m.bodies.iter().position(|b| b.name == body)?;
            (!m.bodies[b].interfaces.iter().any(|i| i == point)).then(|| (b, point.to_string()))
        });
        if let Some((b, point)) = &inner {
            let body = &m.bodies[*b];
            if !body.load_points.iter().any(|p| p == point) {
                let mut names = body.interfaces.clone();
                names.extend(body.load_points.iter().cloned());
                self.err(
                    &path.key("at"),
                    format!(
                        "flexible body '{}' has no interface or load point '{point}'{}",
                        body.name,
                        suggestions(point, &names, "interface or load point")
                    ),
                );
                return;
            }
        }
        let at = match inner {
            Some(_) => None,
            None => match self.point(&path.key("at"), at_text, m, false) {
                Some(at) => Some(at),
                None => return,
            },
        };
        let Some(axes) = self.choice(
            &path.key("axes"),
            &l.axes,
            "global",
            &keys::names("loads", "axes"),
            "load axes",
        ) else {
            return;
        };
        let axes = if axes == "body" {
            LoadAxes::Follower
        } else {
            LoadAxes::Dead
        };
        let mut values = Vec::new();
        for (key, v, kind) in [
            ("force", &l.force, LoadKind::Force),
            ("moment", &l.moment, LoadKind::Moment),
        ] {
            if let Some(v) = v {
                let Some(v) = self.finite3(&path.key(key), v, key) else {
                    return;
                };
                values.push((kind, v));
            }
        }
        if values.is_empty() {
            self.err(path, "missing key `force` [N] or `moment` [N m]");
            return;
        }
        let time = match &l.function {
            Some(f) => match self.time_function(&path.key("function"), f, false) {
                Some(f) => f,
                None => return,
            },
            None => TimeFunction::constant(1.0),
        };
        let Some(at) = at else {
            let (body, point) = inner.expect("a load point when not an interface");
            let value = |kind| {
                values
                    .iter()
                    .find(|(k, _)| *k == kind)
                    .map_or(Vector3::zeros(), |v| v.1)
            };
            m.body_loads.push(BodyLoadSpec {
                name: l.name.clone(),
                path: path.clone(),
                body,
                point,
                axes,
                force: value(LoadKind::Force),
                moment: value(LoadKind::Moment),
                time,
            });
            return;
        };
        m.loads.push(PointLoadSpec {
            name: l.name.clone(),
            path: path.clone(),
            at,
            axes,
            values,
            time,
        });
    }

    fn sensor(&mut self, path: &KeyPath, s: &SensorFile, m: &Mechanism) -> Option<SensorTarget> {
        let kind = self.choice(
            &path.key("type"),
            &Some(s.kind.clone()),
            "position",
            keys::table("sensors").kinds,
            "sensor type",
        )?;
        self.only_keys(path, "sensors", kind, &format!("a '{kind}' sensor"));
        match kind {
            "energy" => return Some(SensorTarget::Energy),
            "energy-balance" => return Some(SensorTarget::EnergyBalance),
            "momentum" => return Some(SensorTarget::Momentum),
            _ => {}
        }
        // A required key that is missing: the registry's check reported it.
        let of = s.of.clone()?;
        let op = path.key("of");
        Some(match kind {
            "position" => SensorTarget::Position(self.point(&op, &of, m, false)?),
            "displacement" => SensorTarget::Displacement(self.point(&op, &of, m, false)?),
            "rotation" => SensorTarget::Rotation(self.point(&op, &of, m, false)?),
            "velocity" => SensorTarget::Velocity(self.point(&op, &of, m, false)?),
            "angular-velocity" => SensorTarget::AngularVelocity(self.point(&op, &of, m, false)?),
            "acceleration" | "angular-acceleration" => {
                let p = self.point(&op, &of, m, false);
                let axes =
                    match self.choice(&path.key("axes"), &s.axes, "global", &["global", "body"], "sensor axes")? {
                        "body" => mbs::SensorAxes::Node,
                        _ => mbs::SensorAxes::Global,
                    };
                if kind == "acceleration" {
                    SensorTarget::Acceleration(p?, axes)
                } else {
                    SensorTarget::AngularAcceleration(p?, axes)
                }
            }
            "relative-position" => {
                let p = self.point(&op, &of, m, false);
                let r = s.reference.as_ref()?;
                let r = self.point(&path.key("reference"), r, m, false)?;
                SensorTarget::RelativePosition(p?, r)
            }
            "deflection" => self.deflection_sensor(path, s, m, &of)?,
            "joint" | "joint-rate" => {
                let j = self.joint_ref(&op, &of, m)?;
                let c = s.coordinate.unwrap_or(0);
                if !self.joint_coordinate(path, m, j, c) {
                    return None;
                }
                if kind == "joint" {
                    SensorTarget::JointCoordinate(j, c)
                } else {
                    SensorTarget::JointRate(j, c)
                }
            }
            "stress" => self.stress_sensor(path, s, m, &of)?,
            "modal" => match self.lookup("flexible", &of) {
                Some(b) => SensorTarget::Modal(b),
                None => {
                    if !self.failed.contains(&format!("body:{of}")) {
                        let names: Vec<String> = m.bodies.iter().map(|b| b.name.clone()).collect();
                        self.err(&op, unknown_reference("flexible body", &of, &names));
                    }
                    return None;
                }
            },
            "reaction" => self.reaction_sensor(path, m, &of)?,
            "actuator-effort" => match self.lookup("actuator", &of) {
                Some(a) => SensorTarget::ActuatorEffort(a),
                None if self.has_failed("actuator", &of) => return None,
                None => {
                    let names: Vec<String> = m.actuators.iter().map(|a| a.name.clone()).collect();
                    self.err(&op, unknown_reference("actuator", &of, &names));
                    return None;
                }
            },
            _ => match self.lookup("driver", &of) {
                Some(d) => SensorTarget::DriverEffort(d),
                None if self.has_failed("driver", &of) => return None,
                None => {
                    let names: Vec<String> = m.drivers.iter().map(|d| d.name.clone()).collect();
                    self.err(&op, unknown_reference("driver", &of, &names));
                    return None;
                }
            },
        })
    }

    /// A `deflection` sensor of the point `of`.
    fn deflection_sensor(&mut self, path: &KeyPath, s: &SensorFile, m: &Mechanism, of: &str) -> Option<SensorTarget> {
        let p = self.point(&path.key("of"), of, m, false);
        let chord = s.chord.as_ref()?;
        let a = self.point(&path.key("chord").index(0), &chord[0], m, false);
        let b = self.point(&path.key("chord").index(1), &chord[1], m, false);
        if a.is_some() && a == b {
            self.err(
                &path.key("chord").index(1),
                format!("the chord's two points are both '{}': a deflection is measured from the line through two distinct points", chord[1]),
            );
            return None;
        }
        let normal = match &s.normal {
            Some(n) => Some(self.axis(&path.key("normal"), path, &Some(*n), "the normal")?),
            None => None,
        };
        Some(SensorTarget::Deflection {
            of: p?,
            chord: [a?, b?],
            normal,
        })
    }

    /// A `stress` sensor of the flexible body `of`.
    fn stress_sensor(&mut self, path: &KeyPath, s: &SensorFile, m: &Mechanism, of: &str) -> Option<SensorTarget> {
        let op = path.key("of");
        let Some(body) = m.bodies.iter().position(|b| b.name == *of) else {
            if !self.failed.contains(&format!("body:{of}")) {
                let names: Vec<String> = m.bodies.iter().map(|b| b.name.clone()).collect();
                self.err(&op, unknown_reference("flexible body", of, &names));
            }
            return None;
        };
        let nodes = match (s.node, s.label, &s.node_at, &s.set) {
            (Some(k), None, None, None) => StressNodes::Index(k),
            (None, Some(l), None, None) => StressNodes::Label(l),
            (None, None, Some(x), None) => StressNodes::At(self.finite3(&path.key("node_at"), x, "node_at [m]")?),
            (None, None, None, Some(set)) => StressNodes::Set(set.clone()),
            _ => {
                self.err(
                    path,
                    "give the stress sensor's node by `node` (index in the part's mesh), `label` (the node's number in the part's mesh file), `node_at` = [x, y, z] (part axes) or `set` (a node set: the largest von Mises stress over it), one of them",
                );
                return None;
            }
        };
        Some(SensorTarget::Stress { body, nodes })
    }

    /// A `reaction` sensor at the supported point or ground joint `of`.
    fn reaction_sensor(&mut self, path: &KeyPath, m: &Mechanism, of: &str) -> Option<SensorTarget> {
        let op = path.key("of");
        if let Some(j) = self.lookup("joint", of) {
            if m.joints[j].parent != PointRef::Ground {
                self.err(&op, format!("joint '{of}' is not a joint to the ground; a reaction is measured at a support or at a joint to \"ground\""));
                return None;
            }
            Some(SensorTarget::Reaction(ReactionAt::GroundJoint(j)))
        } else {
            let p = self.point(&op, of, m, false)?;
            if !m.supports.iter().any(|s| s.at == p) {
                self.err(&op, format!("point '{of}' has no [[supports]]: a reaction is measured at a support or at a joint to \"ground\""));
                return None;
            }
            Some(SensorTarget::Reaction(ReactionAt::Point(p)))
        }
    }

    /// The `velocity` and `angular_velocity` of an `[[initial]]` entry (zero when absent).
    fn initial_velocities(&mut self, path: &KeyPath, c: &InitialFile) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let zero = [0.0; 3];
        let velocity = self.finite3(
            &path.key("velocity"),
            c.velocity.as_ref().unwrap_or(&zero),
            "the velocity [m/s]",
        )?;
        let angular_velocity = self.finite3(
            &path.key("angular_velocity"),
            c.angular_velocity.as_ref().unwrap_or(&zero),
            "the angular velocity [rad/s]",
        )?;
        Some((velocity, angular_velocity))
    }

    /// An `[[initial]]` entry with `start`: how the mechanism starts, given once.
    /// `first`: where an earlier `[[initial]]` gave `start`, if one did.
    fn initial_start(&mut self, path: &KeyPath, start: &str, first: Option<&KeyPath>) -> Option<StartChoice> {
        self.only_keys(path, "initial", "start", "the choice of the start");
        if let Some(first) = first {
            let first = self.first_defined(first);
            self.err_key(
                &path.key("start"),
                format!("`start` is given twice in `[[initial]]`: first at {first}"),
            );
            return None;
        }
        match start {
            "consistent" => Some(StartChoice::Consistent),
            "at-rest" => Some(StartChoice::AtRest),
            other => {
                self.err_key(
                    &path.key("start"),
                    format!("unknown start \"{other}\": \"consistent\" (the default: the drivers' and initial rates give every body a consistent velocity) or \"at-rest\" (every coordinate's rate zero, the drivers' impact at the first step included)"),
                );
                None
            }
        }
    }

    fn initial(&mut self, path: &KeyPath, c: &InitialFile, m: &Mechanism) -> Option<InitialSpec> {
        match (&c.joint, &c.at, &c.body) {
            (Some(joint), None, None) => {
                self.only_keys(path, "initial", "joint", "an initial joint value");
                let j = self.joint_ref(&path.key("joint"), joint, m)?;
                let coordinate = c.coordinate.unwrap_or(0);
                if !self.joint_coordinate(path, m, j, coordinate) {
                    return None;
                }
                let value = match (c.value, c.value_deg) {
                    (Some(_), Some(_)) => {
                        self.err_key(
                            &path.key("value_deg"),
                            "give `value` [rad or m] or `value_deg`, not both",
                        );
                        return None;
                    }
                    (v, None) => v,
                    (None, Some(deg)) => {
                        if !joint_is_angle(m, j, coordinate) {
                            self.err(
                                &path.key("value_deg"),
                                format!("coordinate {coordinate} of joint '{joint}' is a length: give `value` [m]"),
                            );
                            return None;
                        }
                        Some(deg.to_radians())
                    }
                };
                if value.is_none() && c.rate.is_none() {
                    self.err(
                        path,
                        "missing key `value` or `rate` (the joint coordinate's initial value or rate)",
                    );
                    return None;
                }
                for (key, v) in [("value", value), ("rate", c.rate)] {
                    if v.is_some_and(|x| !x.is_finite()) {
                        self.err(&path.key(key), format!("`{key}` must be finite"));
                        return None;
                    }
                }
                Some(InitialSpec::Joint {
                    path: path.clone(),
                    joint: j,
                    coordinate,
                    value,
                    rate: c.rate,
                })
            }
            (None, None, Some(body)) => {
                self.only_keys(path, "initial", "body", "an initial body velocity");
                let b = if let Some(k) = self.lookup("flexible", body) {
                    BodyRef::Flexible(k)
                } else if let Some(k) = self.lookup("rigid", body) {
                    BodyRef::Rigid(k)
                } else {
                    let names: Vec<String> = m
                        .bodies
                        .iter()
                        .map(|b| b.name.clone())
                        .chain(m.rigid_bodies.iter().map(|b| b.name.clone()))
                        .collect();
                    self.err(&path.key("body"), unknown_reference("body", body, &names));
                    return None;
                };
                let (velocity, angular_velocity) = self.initial_velocities(path, c)?;
                let point = match &c.point {
                    Some(p) => Some(self.finite3(&path.key("point"), p, "the point [m]")?),
                    None => None,
                };
                Some(InitialSpec::Body {
                    path: path.clone(),
                    body: b,
                    velocity,
                    angular_velocity,
                    point,
                })
            }
            (None, Some(at), None) => {
                self.only_keys(path, "initial", "point", "an initial point velocity");
                let at = self.point(&path.key("at"), at, m, false)?;
                let (velocity, angular_velocity) = self.initial_velocities(path, c)?;
                Some(InitialSpec::Point {
                    path: path.clone(),
                    at,
                    velocity,
                    angular_velocity,
                })
            }
            _ => {
                self.err(path, "give `joint` (with `value` and/or `rate`), `at` (a point, with `velocity` and/or `angular_velocity`) or `body` (with `velocity`, `angular_velocity` and `point`), one of them; or `start` alone");
                None
            }
        }
    }

    /// A number that may be left out (then `default`), finite. A key with a range in the
    /// registry: in range, the message given by the registry's check.
    fn finite_or(&mut self, path: &KeyPath, table: &str, x: Option<f64>, default: f64) -> Option<f64> {
        let key = path_key(path);
        let ranged = keys::table(table).key(&key).is_some_and(|k| !k.range.is_empty());
        let x = x.unwrap_or(default);
        if ranged {
            return keys::ranged(table, &key, x);
        }
        if !x.is_finite() {
            self.err(path, format!("{key} must be finite, got {x}"));
            return None;
        }
        Some(x)
    }

    /// The head every joint spring, limit and actuator shares: a name unique among them
    /// (`names`), a joint reference and one of its coordinates (default 0). Its path, joint and
    /// coordinate, or None after the error is reported.
    #[allow(clippy::too_many_arguments)]
    fn joint_force_head(
        &mut self,
        m: &Mechanism,
        names: &mut HashMap<String, KeyPath>,
        (table, i): (&str, usize),
        name: &str,
        joint: &str,
        coordinate: Option<usize>,
        what: &str,
    ) -> Option<(KeyPath, usize, usize)> {
        let path = KeyPath::root().key(table).index(i);
        if let Some(first) = names.get(name) {
            let first = first.clone();
            self.duplicate(
                &path,
                what,
                name,
                &first,
                " (joint springs, joint limits and actuators share one name space)",
            );
            return None;
        }
        names.insert(name.to_string(), path.clone());
        let joint = self.joint_ref(&path.key("joint"), joint, m)?;
        let coordinate = coordinate.unwrap_or(0);
        self.joint_coordinate(&path, m, joint, coordinate)
            .then_some((path, joint, coordinate))
    }

    /// `[[joint_springs]]`, `[[joint_limits]]` and `[[actuators]]` (their names unique among
    /// all three).
    fn joint_forces(&mut self, file: &StudyFile, m: &mut Mechanism) {
        let mut names = HashMap::new();
        self.joint_springs(file, m, &mut names);
        self.joint_limits(file, m, &mut names);
        self.actuators(file, m, &mut names);
    }

    fn joint_springs(&mut self, file: &StudyFile, m: &mut Mechanism, names: &mut HashMap<String, KeyPath>) {
        for (i, s) in file.joint_springs.iter().enumerate() {
            let Some((path, joint, coordinate)) = self.joint_force_head(
                m,
                names,
                ("joint_springs", i),
                &s.name,
                &s.joint,
                s.coordinate,
                "joint spring",
            ) else {
                continue;
            };
            let k = self.finite_or(&path.key("stiffness"), "joint_springs", s.stiffness, 0.0);
            let c = self.finite_or(&path.key("damping"), "joint_springs", s.damping, 0.0);
            let rest = self.finite_or(&path.key("rest"), "joint_springs", s.rest, 0.0);
            let preload = self.finite_or(&path.key("preload"), "joint_springs", s.preload, 0.0);
            let (Some(stiffness), Some(damping), Some(rest), Some(preload)) = (k, c, rest, preload) else {
                continue;
            };
            if stiffness == 0.0 && damping == 0.0 && preload == 0.0 {
                self.err(&path, "give `stiffness`, `damping` or `preload` (all are zero)");
                continue;
            }
            m.joint_springs.push(JointSpringSpec {
                name: s.name.clone(),
                path,
                joint,
                coordinate,
                stiffness,
                damping,
                rest,
                preload,
            });
        }
    }

    fn joint_limits(&mut self, file: &StudyFile, m: &mut Mechanism, names: &mut HashMap<String, KeyPath>) {
        for (i, l) in file.joint_limits.iter().enumerate() {
            let Some((path, joint, coordinate)) = self.joint_force_head(
                m,
                names,
                ("joint_limits", i),
                &l.name,
                &l.joint,
                l.coordinate,
                "joint limit",
            ) else {
                continue;
            };
            if l.lower.is_none() && l.upper.is_none() {
                self.err(
                    &path,
                    "give `lower` and/or `upper` (the bounds of the coordinate, m or rad)",
                );
                continue;
            }
            if let (Some(lo), Some(hi)) = (l.lower, l.upper) {
                if !(lo < hi) {
                    self.err(&path.key("upper"), format!("upper ({hi}) must be above lower ({lo})"));
                    continue;
                }
            }
            if l.lower.is_some_and(|x| !x.is_finite()) || l.upper.is_some_and(|x| !x.is_finite()) {
                self.err(&path, "the bounds must be finite");
                continue;
            }
            let Some(stiffness) = keys::ranged("joint_limits", "stiffness", l.stiffness) else {
                continue;
            };
            let Some(damping) = self.finite_or(&path.key("damping"), "joint_limits", l.damping, 0.0) else {
                continue;
            };
            m.joint_limits.push(JointLimitSpec {
                name: l.name.clone(),
                path,
                joint,
                coordinate,
                lower: l.lower,
                upper: l.upper,
                stiffness,
                damping,
            });
        }
    }

    fn actuators(&mut self, file: &StudyFile, m: &mut Mechanism, names: &mut HashMap<String, KeyPath>) {
        // The sensors a PID law may measure, by name (the first of a name; a duplicate is
        // reported with the sensors): found once, not searched per actuator.
        let mut sensor_named: HashMap<&str, &SensorFile> = HashMap::with_capacity(file.sensors.len());
        for s in &file.sensors {
            sensor_named.entry(s.name.as_str()).or_insert(s);
        }
        for (i, a) in file.actuators.iter().enumerate() {
            let Some((path, joint, coordinate)) =
                self.joint_force_head(m, names, ("actuators", i), &a.name, &a.joint, a.coordinate, "actuator")
            else {
                continue;
            };
            if m.drivers.iter().any(|d| d.joint == joint && d.coordinate == coordinate) {
                self.err(
                    &path.key("joint"),
                    format!(
                        "coordinate {coordinate} of joint '{}' is driven: an actuator acts on a free coordinate",
                        a.joint
                    ),
                );
                continue;
            }
            let effort = match (&a.function, &a.pid) {
                (Some(f), None) => match self.time_function(&path.key("function"), f, false) {
                    Some(f) => EffortSpec::Time(f),
                    None => continue,
                },
                (None, Some(p)) => match self.pid_effort(file, &sensor_named, m, &path, (joint, coordinate), p) {
                    Some(effort) => effort,
                    None => continue,
                },
                _ => {
                    self.err(
                        &path,
                        "give `function` (the effort as a function of time) or `pid` (a control law), one of them",
                    );
                    continue;
                }
            };
            self.register("actuator", &a.name, m.actuators.len());
            m.actuators.push(ActuatorSpec {
                name: a.name.clone(),
                path,
                joint,
                coordinate,
                effort,
            });
        }
        // An actuator with errors is known, not unknown, to the sensors that name it.
        for a in &file.actuators {
            self.mark_failed("actuator", &a.name);
        }
    }

    /// The PID law of the actuator at `path` on `joint`'s `coordinate` (measured there unless
    /// it names a `joint` sensor).
    fn pid_effort(
        &mut self,
        file: &StudyFile,
        sensor_named: &HashMap<&str, &SensorFile>,
        m: &Mechanism,
        path: &KeyPath,
        (joint, coordinate): (usize, usize),
        p: &PidFile,
    ) -> Option<EffortSpec> {
        let pp = path.key("pid");
        let (mj, mc) = match &p.sensor {
            None => (joint, coordinate),
            // The `[[sensors]]` are validated after the actuators (they may name
            // one): the joint sensor is read from the file here.
            Some(name) => match sensor_named.get(name.as_str()) {
                Some(sf) if sf.kind == "joint" => {
                    let j = self.lookup("joint", sf.of.as_ref()?)?;
                    let c = sf.coordinate.unwrap_or(0);
                    if !self.joint_coordinate(&pp.key("sensor"), m, j, c) {
                        return None;
                    }
                    (j, c)
                }
                Some(_) => {
                    self.err(
                        &pp.key("sensor"),
                        format!("sensor '{name}' is not a 'joint' sensor: the PID law measures a joint coordinate"),
                    );
                    return None;
                }
                None => {
                    let names: Vec<String> = file
                        .sensors
                        .iter()
                        .filter(|s| s.kind == "joint")
                        .map(|s| s.name.clone())
                        .collect();
                    self.err(&pp.key("sensor"), unknown_reference("joint sensor", name, &names));
                    return None;
                }
            },
        };
        let kp = self.finite_or(&pp.key("kp"), "actuators.pid", p.kp, 0.0);
        let ki = self.finite_or(&pp.key("ki"), "actuators.pid", p.ki, 0.0);
        let kd = self.finite_or(&pp.key("kd"), "actuators.pid", p.kd, 0.0);
        let (Some(kp), Some(ki), Some(kd)) = (kp, ki, kd) else {
            return None;
        };
        if kp == 0.0 && ki == 0.0 && kd == 0.0 {
            self.err(&pp, "give at least one of the gains `kp`, `ki`, `kd`");
            return None;
        }
        let max_effort = match p.max_effort {
            Some(x) => Some(keys::ranged("actuators.pid", "max_effort", x)?),
            None => None,
        };
        let setpoint = self.time_function(&pp.key("setpoint"), &p.setpoint, true)?;
        Some(EffortSpec::Pid {
            joint: mj,
            coordinate: mc,
            setpoint,
            kp,
            ki,
            kd,
            max_effort,
        })
    }

    /// A multibody analysis's settings: an analysis of the mechanism (`equilibrium`, `dynamic`, `buckling`, `linearized`).
    pub(super) fn mbs_analysis(&mut self, path: &KeyPath, a: &AnalysisFile) -> Option<MbsAnalysis> {
        match a.kind {
            AnalysisKind::Equilibrium => self.equilibrium_analysis(path, a),
            AnalysisKind::Dynamic => self.dynamic_analysis(path, a),
            AnalysisKind::Buckling => self.buckling_analysis(path, a),
            _ => self.linearized_analysis(path, a),
        }
    }

    /// `max_iterations` of a multibody analysis, or `default`.
    fn mbs_iterations(a: &AnalysisFile, default: usize) -> Option<usize> {
        match a.max_iterations {
            Some(n) => keys::in_range("analyses", "max_iterations", n as f64).then_some(n),
            None => Some(default),
        }
    }

    /// `tolerance` of a multibody analysis (on the relative residual), or `default`.
    fn mbs_tolerance(a: &AnalysisFile, default: f64) -> Option<f64> {
        match a.tolerance {
            Some(t) => keys::ranged("analyses", "tolerance", t),
            None => Some(default),
        }
    }

    fn equilibrium_analysis(&mut self, path: &KeyPath, a: &AnalysisFile) -> Option<MbsAnalysis> {
        self.only_keys(path, "analyses", "equilibrium", "an 'equilibrium' analysis");
        let arc_length = match a.method.as_deref() {
            None | Some("newton") => false,
            Some("arc-length") => true,
            Some(method) => {
                self.err(
                    &path.key("method"),
                    format!("unknown method '{method}': `newton` (load stepping) or `arc-length` (continuation through limit points)"),
                );
                return None;
            }
        };
        let steps = a.steps.unwrap_or(1);
        keys::in_range("analyses", "steps", steps as f64).then_some(())?;
        let time = match a.at_time {
            Some(t) => keys::ranged("analyses", "at_time", t)?,
            None => 0.0,
        };
        Some(MbsAnalysis::Equilibrium {
            steps,
            tolerance: Self::mbs_tolerance(a, mbs::StaticSettings::DEFAULT_TOLERANCE)?,
            max_iterations: Self::mbs_iterations(a, mbs::StaticSettings::DEFAULT_MAX_ITERATIONS)?,
            time,
            arc_length,
        })
    }

    fn dynamic_analysis(&mut self, path: &KeyPath, a: &AnalysisFile) -> Option<MbsAnalysis> {
        self.only_keys(path, "analyses", "dynamic", "a 'dynamic' analysis");
        // `t_end` missing or out of range: the registry's check reported it. `dt` is required
        // by a dynamic analysis only, which the registry cannot say.
        let dt = self.require(path, a.dt, "dt", "time step [s]");
        let t_end = keys::ranged("analyses", "t_end", a.t_end?)?;
        let dt = keys::ranged("analyses", "dt", dt?)?;
        if t_end / dt > 1e7 {
            self.err(
                &path.key("dt"),
                format!("t_end / dt = {:.3e} steps: more than 10 million", t_end / dt),
            );
            return None;
        }
        if dt > t_end {
            self.err(
                &path.key("dt"),
                format!("the time step dt = {dt} s is longer than the run (t_end = {t_end} s)"),
            );
            return None;
        }
        let rho_inf = a.rho_inf.unwrap_or(mbs::DynamicSettings::DEFAULT_RHO_INF);
        keys::in_range("analyses", "rho_inf", rho_inf).then_some(())?;
        let newton = match a.newton.as_deref() {
            None | Some("full") => mbs::NewtonStrategy::Full,
            Some("modified") => mbs::NewtonStrategy::Modified,
            Some(other) => {
                self.err(
                    &path.key("newton"),
                    format!("unknown Newton strategy '{other}': `full` (new tangents at every correction, the default) or `modified` (the factorised iteration matrix kept across corrections and steps)"),
                );
                return None;
            }
        };
        let body_axis_translations = match a.translations.as_deref() {
            None | Some("fixed") => false,
            Some("body") => true,
            Some(other) => {
                self.err(
                    &path.key("translations"),
                    format!("unknown translation axes '{other}': `fixed` (the default) or `body` (free nodes' translations in their body axes, for long runs of fast steady rotation)"),
                );
                return None;
            }
        };
        // Ten halvings of the step by default: a step that fails at dt/1024 is reported.
        let dt_min = match a.dt_min {
            Some(x) => keys::ranged("analyses", "dt_min", x)?,
            None => dt / 1024.0,
        };
        if dt_min > dt {
            self.err(
                &path.key("dt_min"),
                format!("dt_min ({dt_min} s) must not exceed dt ({dt} s)"),
            );
            return None;
        }
        let adaptive = match (a.error_tolerance, a.dt_max) {
            (None, None) => None,
            (None, Some(_)) => {
                self.err_key(
                    &path.key("dt_max"),
                    "`dt_max` bounds the adaptive step: give `error_tolerance` too",
                );
                return None;
            }
            (Some(tol), dt_max) => {
                let tol = keys::ranged("analyses", "error_tolerance", tol)?;
                let dt_max = match dt_max {
                    Some(x) => keys::ranged("analyses", "dt_max", x)?,
                    None => t_end,
                };
                if dt_max < dt_min.max(dt) {
                    self.err(
                        &path.key("dt_max"),
                        format!("dt_max ({dt_max} s) must be at least dt ({dt} s) and dt_min"),
                    );
                    return None;
                }
                Some(mbs::AdaptiveSettings::new(tol, dt_min, dt_max))
            }
        };
        Some(MbsAnalysis::Dynamic {
            t_end,
            dt,
            rho_inf,
            tolerance: Self::mbs_tolerance(a, mbs::DynamicSettings::DEFAULT_TOLERANCE)?,
            max_iterations: Self::mbs_iterations(a, mbs::DynamicSettings::DEFAULT_MAX_ITERATIONS)?,
            newton,
            body_axis_translations,
            dt_min,
            adaptive,
        })
    }

    fn buckling_analysis(&mut self, path: &KeyPath, a: &AnalysisFile) -> Option<MbsAnalysis> {
        self.only_keys(path, "analyses", "buckling", "a 'buckling' analysis");
        let modes = a.modes.unwrap_or(4);
        keys::in_range("analyses", "modes", modes as f64).then_some(())?;
        let steps = a.steps.unwrap_or(1);
        keys::in_range("analyses", "steps", steps as f64).then_some(())?;
        Some(MbsAnalysis::Buckling {
            modes,
            steps,
            tolerance: Self::mbs_tolerance(a, 1e-10)?,
            max_iterations: Self::mbs_iterations(a, 25)?,
        })
    }

    fn linearized_analysis(&mut self, path: &KeyPath, a: &AnalysisFile) -> Option<MbsAnalysis> {
        self.only_keys(path, "analyses", "linearized", "a 'linearized' analysis");
        if a.start.is_some() && (a.about.is_some() || a.at_time.is_some()) {
            self.err_key(&path.key("start"), "give `start` or `about`/`at_time`, not both");
            return None;
        }
        let modes = a.modes.unwrap_or(10);
        keys::in_range("analyses", "modes", modes as f64).then_some(())?;
        let about = match (a.about.as_deref(), a.at_time) {
            (None | Some("initial"), None) => About::Initial,
            (Some("equilibrium"), None) => About::Equilibrium,
            (None, Some(t)) => {
                let t = keys::ranged("analyses", "at_time", t)?;
                if t == 0.0 {
                    self.err(
                        &path.key("at_time"),
                        "at_time [s] must be positive here: the state at 0 is `about = \"initial\"`",
                    );
                    return None;
                }
                let dt = self.require(path, a.dt, "dt", "the time step [s] of the dynamic run up to at_time")?;
                let dt = keys::ranged("analyses", "dt", dt)?;
                About::Time { t, dt }
            }
            (Some(other), None) => {
                let names = ["initial".to_string(), "equilibrium".to_string()];
                self.err(&path.key("about"), unknown_reference("state", other, &names));
                return None;
            }
            (Some(_), Some(_)) => {
                self.err_key(&path.key("at_time"), "give `about` or `at_time`, not both");
                return None;
            }
        };
        Some(MbsAnalysis::Linearized { modes, about })
    }
}

/// The last key of `path`, for "missing key" messages.
fn path_key(path: &KeyPath) -> String {
    match path.0.last() {
        Some(crate::input::source::Segment::Key(k)) => k.clone(),
        _ => String::new(),
    }
}
