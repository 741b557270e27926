//! The raw schema of a study file: what serde reads from the TOML, before any check.
//!
//! Every struct here is plain data that mirrors the file one to one (`deny_unknown_fields`,
//! so a misspelt key is an error with its line and column). Nothing is resolved: names are
//! strings, numbers are unchecked. [`crate::input::validate::validate`] turns a [`StudyFile`] into a
//! [`crate::input::validate::Study`] in which every reference is resolved and every value checked,
//! before any computation. `docs/study-file.md` documents the same schema for
//! users; keep the two in step.
//!
//! Choices are *kind* keys (`type`, `shape`, `kind`) next to flat optional fields rather than
//! serde's tagged enums: a tagged enum buffers its table and loses the positions of the keys
//! inside it, so an error in a support of an analysis could only point at the whole analysis.
//! With flat structs every error points at its own key; the validator checks which keys each
//! kind takes.
//!
//! Units are SI throughout (m, kg, s, N, Pa); angles are in degrees and their keys end in
//! `_deg`.
//!
//! The sections `bodies`, `rigid_bodies`, `point_masses`, `springs`, `supports`, `joints`,
//! `drivers`, `loads`, `sensors`, `initial`, `output` and the analyses `equilibrium`,
//! `dynamic` and `linearized` are the multibody part of a study (the mechanism), validated by
//! `crate::input::validate::mechanism`, built into an `mbs` system by `crate::build` and run
//! by `crate::run::mechanism`.

use serde::Deserialize;
use std::collections::BTreeMap;

/// A point or vector in the study's global axes, in metres (or newtons, for forces).
pub type Vec3 = [f64; 3];

/// The whole file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Title and description, for reports.
    pub study: Option<StudyInfo>,
    #[serde(default)]
    pub materials: Vec<MaterialFile>,
    #[serde(default)]
    pub sections: Vec<SectionFile>,
    #[serde(default)]
    pub parts: Vec<PartFile>,
    // --- multibody sections ---------------------------------------------------------------
    #[serde(default)]
    pub bodies: Vec<BodyFile>,
    #[serde(default)]
    pub rigid_bodies: Vec<RigidBodyFile>,
    #[serde(default)]
    pub point_masses: Vec<PointMassFile>,
    #[serde(default)]
    pub springs: Vec<SpringFile>,
    #[serde(default)]
    pub supports: Vec<MbsSupportFile>,
    #[serde(default)]
    pub joints: Vec<JointFile>,
    #[serde(default)]
    pub drivers: Vec<DriverFile>,
    #[serde(default)]
    pub loads: Vec<LoadFile>,
    #[serde(default)]
    pub sensors: Vec<SensorFile>,
    #[serde(default)]
    pub initial: Vec<InitialFile>,
    #[serde(default)]
    pub joint_springs: Vec<JointSpringFile>,
    #[serde(default)]
    pub joint_limits: Vec<JointLimitFile>,
    #[serde(default)]
    pub actuators: Vec<ActuatorFile>,
    pub output: Option<OutputFile>,
    /// `[fmu]`: the parameters of the study's FMU.
    pub fmu: Option<FmuFile>,
    // ----------------------------------------------------------------------------------------
    #[serde(default)]
    pub analyses: Vec<AnalysisFile>,
}

/// `[study]`
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyInfo {
    pub title: Option<String>,
    pub description: Option<String>,
}

/// `[[materials]]`: linear isotropic elastic. Give `nu` or `G`, not both.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct MaterialFile {
    pub name: String,
    /// Young's modulus (Pa).
    pub E: f64,
    /// Poisson's ratio (-).
    pub nu: Option<f64>,
    /// Shear modulus (Pa).
    pub G: Option<f64>,
    /// Density (kg/m^3).
    pub rho: f64,
}

/// `[[sections]]`: a beam cross-section, by shape or by values.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct SectionFile {
    pub name: String,
    pub shape: SectionShape,
    /// Rectangle: width along local y (m).
    pub b: Option<f64>,
    /// Rectangle: height along local z (m).
    pub h: Option<f64>,
    /// Circle: diameter (m).
    pub d: Option<f64>,
    /// Tube: outer diameter (m).
    pub d_outer: Option<f64>,
    /// Tube: inner diameter (m).
    pub d_inner: Option<f64>,
    /// Values: area (m^2).
    pub A: Option<f64>,
    /// Values: second moment about local y (m^4).
    pub Iy: Option<f64>,
    /// Values: second moment about local z (m^4).
    pub Iz: Option<f64>,
    /// Values: torsion constant (m^4).
    pub J: Option<f64>,
    /// Values: shear factor for shear along local y (default 5/6).
    pub ky: Option<f64>,
    /// Values: shear factor for shear along local z (default 5/6).
    pub kz: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SectionShape {
    Rectangle,
    Circle,
    Tube,
    Values,
}

impl SectionShape {
    /// The value of `shape`, as in the file.
    pub fn name(self) -> &'static str {
        match self {
            SectionShape::Rectangle => "rectangle",
            SectionShape::Circle => "circle",
            SectionShape::Tube => "tube",
            SectionShape::Values => "values",
        }
    }
}

/// `[[parts]]`: one FE model (a beam structure or a solid), with its interfaces and how to
/// reduce it. Exactly one of `beam`, `box`, `mesh`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartFile {
    pub name: String,
    /// The material of every element (for a gmsh mesh with several volumes, use
    /// `mesh.materials` instead).
    pub material: Option<String>,
    /// `consistent` (default) or `lumped`.
    pub mass: Option<MassFile>,
    pub beam: Option<BeamFile>,
    #[serde(rename = "box")]
    pub box_: Option<BoxFile>,
    pub mesh: Option<MeshFile>,
    #[serde(default)]
    pub interfaces: Vec<InterfaceFile>,
    pub reduction: Option<ReductionFile>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassFile {
    Consistent,
    Lumped,
}

/// `[parts.beam]`: a generated beam structure.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamFile {
    pub kind: BeamKind,
    /// The section of every element (a frame member may override it).
    pub section: String,
    /// `timoshenko` (default) or `euler-bernoulli`.
    pub theory: Option<TheoryFile>,
    /// Any vector in the local x-y plane of the elements (straight beams and frames).
    pub orientation: Option<Vec3>,
    /// Number of elements (straight, arc).
    pub elements: Option<usize>,
    /// Straight: first and last point (m).
    pub from: Option<Vec3>,
    pub to: Option<Vec3>,
    /// Arc: centre, first point, axis (normal of the arc's plane), swept angle.
    pub center: Option<Vec3>,
    pub start: Option<Vec3>,
    pub axis: Option<Vec3>,
    pub angle_deg: Option<f64>,
    /// Frame: joint points and members between them.
    pub points: Option<Vec<Vec3>>,
    pub members: Option<Vec<MemberFile>>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BeamKind {
    Straight,
    Arc,
    Frame,
}

impl BeamKind {
    /// The value of `kind`, as in the file.
    pub fn name(self) -> &'static str {
        match self {
            BeamKind::Straight => "straight",
            BeamKind::Arc => "arc",
            BeamKind::Frame => "frame",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TheoryFile {
    Timoshenko,
    EulerBernoulli,
}

/// A member of a frame: between points `from` and `to` (0-based indices into `points`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemberFile {
    pub from: usize,
    pub to: usize,
    pub elements: usize,
    pub section: Option<String>,
    pub orientation: Option<Vec3>,
}

/// `[parts.box]`: a structured box mesh from `origin` to `origin + size`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxFile {
    pub size: Vec3,
    pub divisions: [usize; 3],
    pub element: ElementFile,
    pub origin: Option<Vec3>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ElementFile {
    Hex8,
    Hex20,
    Tet4,
    Tet10,
    Wedge6,
}

/// `[parts.mesh]`: a gmsh mesh (MSH 4.1 or 2.2), path relative to the study file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    pub file: String,
    /// Material per physical volume (cell set): `{ body = "steel" }`.
    pub materials: Option<BTreeMap<String, String>>,
    /// The unit system the file is written in (default SI).
    pub units: Option<UnitsFile>,
}

/// `units` of `[parts.mesh]`: a consistent unit system, converted to SI on read. Its names
/// are fe-model's ([`fe_model::units::UnitSystem::parse`]), defined there once.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(try_from = "String")]
pub struct UnitsFile(fe_model::units::UnitSystem);

impl TryFrom<String> for UnitsFile {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        use fe_model::units::UnitSystem;
        UnitSystem::parse(&name)
            .map(UnitsFile)
            .ok_or_else(|| format!("unknown unit system '{name}', expected {}", UnitSystem::NAMES))
    }
}

impl UnitsFile {
    /// The unit system it names.
    pub fn system(self) -> fe_model::units::UnitSystem {
        self.0
    }
}

/// `[[parts.interfaces]]`: a 6-dof point where the part connects to the rest of a model.
///
/// Solids: the surface nodes by `set` or by `near` + `radius`, tied by a `spider`. Beams: one
/// beam node, by `set` (a one-node set such as `beam.end`) or by `node_at`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterfaceFile {
    pub name: String,
    pub set: Option<String>,
    pub near: Option<Vec3>,
    pub radius: Option<f64>,
    pub node_at: Option<Vec3>,
    pub spider: Option<SpiderFile>,
    /// Solids: where the interface node goes (default: the area centroid of the surface).
    pub node_position: Option<Vec3>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpiderFile {
    Rbe2,
    Rbe3,
}

/// `[parts.reduction]`: Craig-Bampton settings. Give `modes` or `cutoff_hz`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReductionFile {
    /// Number of fixed-interface modes (0: static modes only).
    pub modes: Option<usize>,
    /// Keep every fixed-interface mode below this frequency (Hz).
    pub cutoff_hz: Option<f64>,
    /// Add an auxiliary interface at the centre of mass (default false).
    pub auxiliary_node: Option<bool>,
    /// Keep the mode shapes on the mesh in the reduced-body file (default true).
    pub keep_mesh_shapes: Option<bool>,
    /// Reduce with the geometric stiffness of the CB coordinates' stresses (default false).
    pub geometric_stiffening: Option<bool>,
    /// Append the static response to the interfaces' inertia to the modes (default false).
    pub inertia_correction: Option<bool>,
    /// Reduce a beam part lying in its xy-plane as a planar part, its bodies evaluated in the
    /// plane (default false).
    pub planar: Option<bool>,
    /// Keep the stress of every CB vector for stress recovery (default false).
    pub stress_shapes: Option<bool>,
    /// Named points inside the body where loads act, with static correction.
    pub load_points: Option<Vec<LoadPointFile>>,
    /// Precision of the factor of K_ii: "auto" (default), "double" or "single".
    pub factor: Option<String>,
}

/// `[[parts.reduction.load_points]]`: a node by `set` (a one-node set) or `node_at`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadPointFile {
    pub name: String,
    pub set: Option<String>,
    pub node_at: Option<Vec3>,
}

/// `[[analyses]]`: what to compute. `type` says which keys apply.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisFile {
    #[serde(rename = "type")]
    pub kind: AnalysisKind,
    /// Names the results folder of the analysis (default `<type>-<part>`).
    pub name: Option<String>,
    /// static, modal, reduce: the part (multibody analyses run on the mechanism).
    pub part: Option<String>,
    /// static, modal: held dofs.
    pub supports: Option<Vec<SupportFile>>,
    /// static: nodal loads.
    pub loads: Option<Vec<NodalLoadFile>>,
    /// modal: number of modes; linearized: number of modes.
    pub modes: Option<usize>,
    /// modal: `auto` (default), `dense` or `sparse`.
    pub solver: Option<SolverFile>,
    // --- multibody analyses ---------------------------------------------------------------
    /// equilibrium: load steps.
    pub steps: Option<usize>,
    /// equilibrium, dynamic: Newton tolerance on the relative residual.
    pub tolerance: Option<f64>,
    /// equilibrium: `newton`.
    pub method: Option<String>,
    /// equilibrium, dynamic: Newton iterations per step (default 25, 20).
    pub max_iterations: Option<usize>,
    /// dynamic: end time (s).
    pub t_end: Option<f64>,
    /// dynamic: time step (s).
    pub dt: Option<f64>,
    /// dynamic: spectral radius at infinity of generalized-alpha, in [0, 1].
    pub rho_inf: Option<f64>,
    /// dynamic: `full` (default) or `modified` Newton (`mbs::NewtonStrategy`).
    pub newton: Option<String>,
    /// dynamic: the axes in which the time integration carries the translations of free
    /// nodes, `fixed` (default) or `body` (`mbs::DynamicSettings::body_axis_translations`).
    pub translations: Option<String>,
    /// linearized: about `initial` (default), `equilibrium`, or the state at time `at_time`
    /// of a dynamic run with step `dt`; equilibrium: the time at which drivers and load
    /// functions are evaluated (default 0).
    pub about: Option<String>,
    pub at_time: Option<f64>,
    /// equilibrium, dynamic, linearized, buckling: start from the final state of the earlier
    /// analysis of this name.
    pub start: Option<String>,
    /// dynamic: smallest step (s) of the retry after a failed step and of the adaptive step.
    pub dt_min: Option<f64>,
    /// dynamic: largest adaptive step (s).
    pub dt_max: Option<f64>,
    /// dynamic: local error tolerance of the adaptive step (selects it).
    pub error_tolerance: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AnalysisKind {
    Static,
    Modal,
    Reduce,
    Equilibrium,
    Dynamic,
    Linearized,
    Buckling,
}

impl AnalysisKind {
    pub fn name(self) -> &'static str {
        match self {
            AnalysisKind::Static => "static",
            AnalysisKind::Modal => "modal",
            AnalysisKind::Reduce => "reduce",
            AnalysisKind::Equilibrium => "equilibrium",
            AnalysisKind::Dynamic => "dynamic",
            AnalysisKind::Linearized => "linearized",
            AnalysisKind::Buckling => "buckling",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverFile {
    Auto,
    Dense,
    Sparse,
}

/// Held dofs at `at` (an interface or a node set of the part) or at the node at `node_at`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportFile {
    pub at: Option<String>,
    pub node_at: Option<Vec3>,
    /// `all` (default), `translations`, `rotations`, or a list such as `["ux", "rz"]`.
    pub dofs: Option<DofsFile>,
}

/// `dofs = "all"` or `dofs = ["ux", "rz"]`. Deserialized by hand: serde's untagged enums
/// answer a type error with "data did not match any variant", which helps nobody.
#[derive(Debug)]
pub enum DofsFile {
    Named(String),
    List(Vec<String>),
}

impl<'de> Deserialize<'de> for DofsFile {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = DofsFile;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("\"all\", \"translations\", \"rotations\" or a list of dof names such as [\"ux\", \"rz\"]")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<DofsFile, E> {
                Ok(DofsFile::Named(v.to_string()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<DofsFile, A::Error> {
                let mut list = Vec::new();
                while let Some(name) = seq.next_element::<String>()? {
                    list.push(name);
                }
                Ok(DofsFile::List(list))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// A force (N) and moment (N m) in global axes at one node: an interface, a one-node set, or
/// the node at `node_at`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodalLoadFile {
    pub at: Option<String>,
    pub node_at: Option<Vec3>,
    pub force: Option<Vec3>,
    pub moment: Option<Vec3>,
}

// --- multibody sections -------------------------------------------------------------------

/// `[[bodies]]`: a flexible body, an instance of a reduced part placed in the mechanism.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyFile {
    pub name: String,
    /// A part with a `[parts.reduction]`, or `file`: a reduced-body file (`.rbody`) or an
    /// MBDyn modal element file (`.fem`), or `matrices`: K and M from another FE code.
    pub part: Option<String>,
    pub file: Option<String>,
    pub matrices: Option<MatricesFile>,
    /// Floating frame: `center-of-mass` (default), `interface-node`, `auxiliary-node`.
    pub frame: Option<String>,
    /// With `frame = "interface-node"`: which interface.
    pub frame_interface: Option<String>,
    /// `exact` (default) or `lumped` inertia (theory guide §6).
    pub inertia: Option<String>,
    /// Where the part's origin is placed (m), and its rotation.
    pub position: Option<Vec3>,
    pub rotation: Option<RotationFile>,
    /// Damping: `{ alpha = .., beta = .. }` (Rayleigh, on the CB matrices) and/or
    /// `{ modal_ratio = .. }` (the same ratio for every fixed-interface mode).
    pub damping: Option<DampingFile>,
    /// Evaluate the body in the global xy-plane (default: its part's `planar`).
    pub planar: Option<bool>,
}

/// `[bodies.matrices]`: a body reduced from another FE code's stiffness and mass (Matrix
/// Market files) with a node table and a dof table; paths relative to the study file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatricesFile {
    pub stiffness: String,
    pub mass: String,
    /// Node table: `x y z` per line (m); node k is the k-th data line (0-based).
    pub nodes: String,
    /// Dof table: `node dof` per matrix row (dof: ux uy uz rx ry rz).
    pub dofs: Option<String>,
    /// Without `dofs`: 3 or 6 dofs per node, in node order.
    pub dofs_per_node: Option<usize>,
    /// Interfaces: name = node (0-based index into the node table); each needs six dofs.
    pub interfaces: BTreeMap<String, usize>,
    /// Fixed-interface modes: a count, or every mode below `cutoff_hz` (Hz).
    pub modes: Option<usize>,
    pub cutoff_hz: Option<f64>,
}

/// A rotation by axis and angle (Euler angles appear nowhere).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotationFile {
    pub axis: Vec3,
    pub angle_deg: f64,
}

/// Damping of a flexible body.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DampingFile {
    /// Rayleigh mass factor (1/s).
    pub alpha: Option<f64>,
    /// Rayleigh stiffness factor (s).
    pub beta: Option<f64>,
    /// Damping ratio of every fixed-interface mode (-).
    pub modal_ratio: Option<f64>,
}

/// `[[rigid_bodies]]`
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidBodyFile {
    pub name: String,
    /// Mass (kg).
    pub mass: f64,
    pub center_of_mass: Vec3,
    /// Inertia tensor about the centre of mass in global axes at t = 0 (kg m^2).
    pub inertia: [[f64; 3]; 3],
    /// Named points of the body (its nodes), `{ A = [0, 0, 0] }`.
    #[serde(default)]
    pub points: BTreeMap<String, Vec3>,
}

/// `[[point_masses]]`: a mass on a point (translational inertia only).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMassFile {
    pub name: String,
    /// `"body.point"`.
    pub at: String,
    /// Mass (kg).
    pub mass: f64,
}

/// `[[springs]]`: a point-to-point spring-damper.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringFile {
    pub name: String,
    /// Two points; the second may be `"ground"` (then `ground_point` says where).
    pub between: [String; 2],
    pub ground_point: Option<Vec3>,
    /// Stiffness (N/m).
    pub stiffness: f64,
    /// Damping (N s/m), default 0.
    pub damping: Option<f64>,
    /// Unstretched length (m), default the initial length.
    pub rest_length: Option<f64>,
}

/// `[[supports]]`: dofs of a point held by the ground.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MbsSupportFile {
    /// `"body.point"`.
    pub at: String,
    /// `clamp`, `pin`, `hinge` (with `axis`), `slider` (with `axis`), `plane` (with `axis`, the normal), `planar` (with `axis`, the normal: also the rotation about it free).
    #[serde(rename = "type")]
    pub kind: String,
    pub axis: Option<Vec3>,
}

/// `[[joints]]`: minimal-coordinate joints (theory guide §8).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointFile {
    pub name: String,
    /// `fixed`, `spherical`, `revolute`, `prismatic`, `cylindrical`, `universal`, `planar`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Two points, `"body.point"` (an interface of a flexible body or a point of a rigid
    /// one) or `"ground"`: parent first.
    pub between: [String; 2],
    /// Joint axis in global axes at t = 0 (revolute, prismatic, cylindrical; the normal of a
    /// planar joint; the first axis of a universal joint).
    pub axis: Option<Vec3>,
    /// Second axis (universal joint).
    pub axis2: Option<Vec3>,
}

/// `[[drivers]]`: a joint coordinate given as a function of time.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriverFile {
    pub name: String,
    /// The driven joint.
    pub joint: String,
    /// Which scalar coordinate of the joint (default 0).
    pub coordinate: Option<usize>,
    pub function: TimeFunctionFile,
}

/// A function of time: `constant-speed` (`speed`, `initial`), `ramp` (`t_start`, `t_end`,
/// `from`, `to`, `smooth`), `spin-up` (`speed`, `ramp_time`: the smooth ramp of benchmark
/// C1), `harmonic` (`amplitude`, `frequency_hz`, `phase_deg`, `offset`), `table` (`t`,
/// `value` or `file`, `interpolation`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeFunctionFile {
    #[serde(rename = "type")]
    pub kind: String,
    pub speed: Option<f64>,
    pub initial: Option<f64>,
    pub ramp_time: Option<f64>,
    pub t_start: Option<f64>,
    pub t_end: Option<f64>,
    pub from: Option<f64>,
    pub to: Option<f64>,
    pub smooth: Option<bool>,
    pub amplitude: Option<f64>,
    pub frequency_hz: Option<f64>,
    pub phase_deg: Option<f64>,
    pub offset: Option<f64>,
    pub t: Option<Vec<f64>>,
    pub value: Option<Vec<f64>>,
    /// A CSV file of `time, value` rows, relative to the study file.
    pub file: Option<String>,
    /// `linear` (default) or `cubic`.
    pub interpolation: Option<String>,
}

/// `[[loads]]`: gravity, or a force and moment at a body point.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadFile {
    pub name: String,
    /// `gravity` or `point`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Gravity: acceleration (m/s^2).
    pub g: Option<Vec3>,
    /// Point load: `"body.point"`, force (N), moment (N m), in `global` (default) or `body` axes.
    pub at: Option<String>,
    pub force: Option<Vec3>,
    pub moment: Option<Vec3>,
    pub axes: Option<String>,
    /// Scales the load in time (default 1).
    pub function: Option<TimeFunctionFile>,
}

/// `[[sensors]]`: named outputs, one CSV file each.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorFile {
    pub name: String,
    /// `position`, `displacement`, `relative-position`, `rotation`, `velocity`,
    /// `angular-velocity`, `deflection`, `joint`, `joint-rate`, `modal`, `reaction`,
    /// `driver-effort`, `energy`, `momentum`, `stress`, `acceleration`,
    /// `angular-acceleration`, `energy-balance`.
    #[serde(rename = "type")]
    pub kind: String,
    /// `"body.point"`, a body, a joint or a driver.
    pub of: Option<String>,
    /// Deflection: relative to the chord between two points.
    pub chord: Option<[String; 2]>,
    /// Deflection: signed along this normal.
    pub normal: Option<Vec3>,
    /// Relative position: in the axes of this point.
    pub reference: Option<String>,
    /// Joint, joint-rate: which scalar coordinate (default 0).
    pub coordinate: Option<usize>,
    /// Stress: a mesh node by index, by its label in the mesh file, by position (part axes),
    /// or a node set.
    pub node: Option<usize>,
    pub label: Option<u64>,
    pub node_at: Option<Vec3>,
    pub set: Option<String>,
    /// Acceleration, angular acceleration: `global` (default) or `body` axes.
    pub axes: Option<String>,
}

/// `[[initial]]`: initial values that differ from the assembled configuration at rest.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialFile {
    /// A joint coordinate's `value` and/or `rate` (with `coordinate`, default 0) ...
    pub joint: Option<String>,
    pub coordinate: Option<usize>,
    pub value: Option<f64>,
    pub rate: Option<f64>,
    /// The value in degrees (angles only), instead of `value`.
    pub value_deg: Option<f64>,
    /// ... or the `velocity` (m/s) and `angular_velocity` (rad/s) of a point ...
    pub at: Option<String>,
    pub velocity: Option<Vec3>,
    pub angular_velocity: Option<Vec3>,
    /// ... or of a body (and everything attached to it), about `point` (m, default its centre
    /// of mass).
    pub body: Option<String>,
    pub point: Option<Vec3>,
    /// ... or how the mechanism starts: `"consistent"` (default) or `"at-rest"`.
    pub start: Option<String>,
}

/// `[[joint_springs]]`: a linear or torsional spring-damper on a joint coordinate.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpringFile {
    pub name: String,
    pub joint: String,
    pub coordinate: Option<usize>,
    /// N/m or N m/rad.
    pub stiffness: Option<f64>,
    /// N s/m or N m s/rad.
    pub damping: Option<f64>,
    /// m or rad (default 0).
    pub rest: Option<f64>,
    /// N or N m (default 0).
    pub preload: Option<f64>,
}

/// `[[joint_limits]]`: a stop on a joint coordinate.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointLimitFile {
    pub name: String,
    pub joint: String,
    pub coordinate: Option<usize>,
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub stiffness: f64,
    pub damping: Option<f64>,
}

/// `[[actuators]]`: a force or torque on a joint coordinate, from a function of time or a PID
/// law.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuatorFile {
    pub name: String,
    pub joint: String,
    pub coordinate: Option<usize>,
    /// The effort (N or N m) as a function of time ...
    pub function: Option<TimeFunctionFile>,
    /// ... or a PID law.
    pub pid: Option<PidFile>,
}

/// `pid = { ... }` of an actuator.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PidFile {
    pub kp: Option<f64>,
    pub ki: Option<f64>,
    pub kd: Option<f64>,
    /// The set-point as a function of time (in the measured coordinate's unit).
    pub setpoint: TimeFunctionFile,
    /// A `joint` sensor whose coordinate is measured (default: the actuated coordinate).
    pub sensor: Option<String>,
    pub max_effort: Option<f64>,
}

/// `[fmu]`: what the study's FMU exposes beyond its inputs and outputs.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuFile {
    /// Key paths of study values that become parameters of the FMU.
    #[serde(default)]
    pub parameters: Vec<String>,
}

/// `[output]`: how often the multibody analyses write.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    /// Write sensors every n-th step (default 1).
    pub every: Option<usize>,
    /// Write the deformed meshes for ParaView every n-th step (default: never).
    pub vtu_every: Option<usize>,
    /// Draw a PNG plot per sensor (default true).
    pub plots: Option<bool>,
}
