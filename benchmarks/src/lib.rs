//! Speed comparisons and scaling studies.
//!
//! The dynamics comparison against Exudyn runs the planar flexible slider-crank of
//! validation problem C2 with the connecting rod as a Craig-Bampton body reduced from a solid
//! (hex20) bar mesh. Both programs read the same mesh and the same assembled $\mathbf K$,
//! $\mathbf M$ (exported by the `export_rod` binary in Matrix Market), reduce it with RBE2
//! interfaces on the two end faces and the same number of fixed-interface modes, and integrate
//! with generalized-α at the same step. This crate holds the model builder shared by the
//! binaries (`slider_crank`, `export_rod`); the Exudyn side is `benchmarks/exudyn/`. The same
//! binary runs the rod as beam superelements ([`beam_rod_body`]): the round Euler-Bernoulli rod
//! of C2 is what `benchmarks/compare_all.sh` compares with Exudyn's own beam elements.
//!
//! | symbol | meaning | code |
//! |---|---|---|
//! | $r$ | crank length, 0.15 m | [`SliderCrank::crank`] |
//! | $l$ | rod length, 0.30 m | [`SliderCrank::rod`] |
//! | $\Omega$ | crank speed, 150 rad/s | [`SliderCrank::speed`] |
//! | $d$ | rod diameter, 6 mm | [`SliderCrank::diameter`] |
//! | $a$ | side of the square section with the round rod's $I$: $a^4/12 = \pi d^4/64$ | [`SliderCrank::side`] |
//! | $w$ | midpoint deflection relative to the chord (signed along $\mathbf e_z \times$ chord) | [`chord_distance`] |

#![allow(non_snake_case)]

use fe_model::{
    add_interface_on_set, box_mesh, solid_model, BeamProperties, BeamSection, BeamTheory, CellKind, FeModel,
    IsotropicMaterial, MassKind, SpiderKind,
};
use mbs::{Model, NodeId, SensorKind};
use nalgebra::{Point3, UnitQuaternion, Vector3};
use reduction::{reduce, CbSettings, ModeSelection, ReducedBody};
use superelement::{BodyState, Damping, Frame, FrameChoice, MassVariant, Superelement};
use thiserror::Error;

/// What can go wrong while building or post-processing the benchmark models.
#[derive(Debug, Error)]
pub enum BenchError {
    #[error("rod mesh: {0}")]
    Mesh(#[from] fe_model::FeError),
    #[error("rod material: {0}")]
    Material(#[from] fe_model::PropertyError),
    #[error("rod reduction: {0}")]
    Reduction(#[from] reduction::ReductionError),
    #[error("rod superelement: {0}")]
    Superelement(#[from] superelement::SuperelementError),
    #[error("the rod mesh has no node on the axis at x = {x} m (use an even number of elements along and across)")]
    NoAxisNode { x: f64 },
    #[error("the reduced rod '{body}' was saved without mesh shapes; the midpoint needs them")]
    NoMeshShapes { body: String },
    #[error("sensor '{name}' is missing from the record")]
    MissingSensor { name: String },
    #[error("argument '{arg}': {why}")]
    Argument { arg: String, why: String },
}

/// The structured solid mesh of the rod: `kind` cells, `along` divisions along the axis and
/// `across` in each direction of the square section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RodMesh {
    pub kind: CellKind,
    pub along: usize,
    pub across: usize,
}

/// The mechanism of validation problem C2 (all SI): the values of the standard problem
/// (`models`); the model builder [`slider_crank_model`] takes its geometry and masses from there
/// and the speed from here, the rod bodies take the section and steel from here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliderCrank {
    pub crank: f64,
    pub rod: f64,
    pub speed: f64,
    pub diameter: f64,
    pub E: f64,
    pub nu: f64,
    pub rho: f64,
    /// Crank mass and inertia (driven at constant speed: they only change the drive torque).
    pub crank_mass: f64,
    pub crank_inertia: [f64; 3],
}

impl SliderCrank {
    /// Jonker & Meijaard's values (validation problem C2); Poisson's ratio 0.3 for the solid rod.
    pub const C2: SliderCrank = SliderCrank {
        crank: models::CRANK,
        rod: models::ROD,
        speed: 150.0,
        diameter: models::ROD_D,
        E: models::STEEL_E,
        nu: 0.3,
        rho: models::STEEL_RHO,
        crank_mass: models::CRANK_MASS,
        crank_inertia: models::CRANK_INERTIA,
    };

    /// Side $a$ of the square section with the round rod's second moment of area:
    /// $a^4/12 = \pi d^4/64$, so $a = (3\pi/16)^{1/4} d$. (Its area is 3 % above the round
    /// rod's, so the rod is 3 % heavier; both programs use this same square rod.)
    pub fn side(&self) -> f64 {
        (3.0 * std::f64::consts::PI / 16.0).powf(0.25) * self.diameter
    }

    /// Crank period $2\pi/\Omega$.
    pub fn period(&self) -> f64 {
        2.0 * std::f64::consts::PI / self.speed
    }

    /// Rod angular velocity at the dead centre (rigid mechanism): $-\Omega r/l$.
    pub fn rod_rate(&self) -> f64 {
        -self.speed * self.crank / self.rod
    }
}

/// The FE model of a rod segment of `length`: a box mesh from x = 0 to `length` with the
/// section centred on the x axis (so the axis nodes are the section centroids), steel as
/// given, consistent mass.
pub fn rod_fe_model(p: &SliderCrank, length: f64, mesh: RodMesh) -> Result<FeModel, BenchError> {
    let a = p.side();
    let mut m = box_mesh(mesh.kind, [length, a, a], [mesh.along, mesh.across, mesh.across])?;
    for x in &mut m.nodes {
        x.y -= a / 2.0;
        x.z -= a / 2.0;
    }
    let steel = IsotropicMaterial::new("steel", p.E, p.nu, p.rho)?;
    Ok(solid_model(m, steel, MassKind::Consistent)?)
}

/// Index of the mesh node at `(x, 0, 0)` (on the axis).
pub fn axis_node(nodes: &[[f64; 3]], x: f64, scale: f64) -> Result<usize, BenchError> {
    nodes
        .iter()
        .position(|n| (n[0] - x).abs() < 1e-9 * scale && n[1].abs() < 1e-9 * scale && n[2].abs() < 1e-9 * scale)
        .ok_or(BenchError::NoAxisNode { x })
}

/// A rod segment reduced with RBE2 interfaces "a" (face x = 0) and "b" (face x = `length`)
/// at the face centroids, and `modes` fixed-interface modes; mesh shapes kept when `keep_mesh`.
pub fn rod_body(
    p: &SliderCrank,
    length: f64,
    mesh: RodMesh,
    modes: ModeSelection,
    keep_mesh: bool,
) -> Result<ReducedBody, BenchError> {
    let mut settings = CbSettings::new(modes);
    settings.keep_mesh_shapes = keep_mesh;
    rod_body_with(p, length, mesh, &settings)
}

/// [`rod_body`] with any reduction settings (e.g. `geometric_stiffening`, which gives the body
/// the geometric stiffness of its CB coordinates' stresses, so one superelement sees how the
/// rod's axial force changes its bending stiffness).
pub fn rod_body_with(
    p: &SliderCrank,
    length: f64,
    mesh: RodMesh,
    settings: &CbSettings,
) -> Result<ReducedBody, BenchError> {
    let mut fe = rod_fe_model(p, length, mesh)?;
    let a = add_interface_on_set(&mut fe, "a", "x0", None, SpiderKind::Rbe2)?;
    let b = add_interface_on_set(&mut fe, "b", "x1", None, SpiderKind::Rbe2)?;
    Ok(reduce(&fe, "rod", &[("a".into(), a), ("b".into(), b)], settings)?)
}

/// The section and beam theory of a beam rod ([`beam_rod_body`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeamRod {
    /// The solid rod's square section (side [`SliderCrank::side`]), Timoshenko: the beam twin
    /// of the solid rod.
    Square,
    /// The round section of validation problem C2 (diameter [`SliderCrank::diameter`]),
    /// Euler-Bernoulli as the problem's rod (and as an ANCF cable).
    Round,
}

/// A rod segment of `length` as `elements` beam elements of section `rod`, reduced with
/// interfaces "a" and "b" at its ends: the beam model of the rod, for the nonlinear reference
/// (its 6-dof junction nodes add no stiffness, unlike the rigid end faces of solid segments),
/// reduced with `settings` (as in [`rod_body_with`]; keep the mesh shapes for the midpoint of a
/// one-segment rod).
pub fn beam_rod_body(
    p: &SliderCrank,
    length: f64,
    elements: usize,
    rod: BeamRod,
    settings: &CbSettings,
) -> Result<ReducedBody, BenchError> {
    let mut fe = FeModel::default();
    let material = fe.add_material(IsotropicMaterial::new("steel", p.E, p.nu, p.rho)?);
    let (section, theory) = match rod {
        BeamRod::Square => (
            BeamSection::rectangle("square", p.side(), p.side(), p.nu)?,
            BeamTheory::Timoshenko,
        ),
        BeamRod::Round => (
            BeamSection::circle("round", p.diameter, p.nu)?,
            BeamTheory::EulerBernoulli,
        ),
    };
    let section = fe.add_section(section);
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::y(),
        theory,
        mass: MassKind::Consistent,
    };
    let nodes = fe_model::generate::straight_beam(
        &mut fe,
        Point3::origin(),
        Point3::new(length, 0.0, 0.0),
        elements,
        &props,
        Some("rod"),
    )?;
    let ends = [("a".to_string(), nodes[0]), ("b".to_string(), nodes[elements])];
    Ok(reduce(&fe, "rod", &ends, settings)?)
}

/// The slider-crank model with the rod as `n` identical segments `segment` (reduced from
/// x = 0 to l/n, interfaces a then b), frame and inertia variant as given: the planar
/// slider-crank of the standard problems ([`models::slider_crank_planar`]; crank, rod and
/// slider of validation problem C2) driven at `p.speed`. Starts at the dead centre (crank along
/// x) with the rigid mechanism's velocities. Sensors: "slider" (position), for even `n`
/// "midpoint" (signed distance of the middle node from the chord), and "A", "B" (rod end
/// positions), "rotA", "rotB" (their rotations), "eta0" (modal coordinates of the first
/// segment). Returns the model and the rod's nodes.
pub fn slider_crank_model(
    p: &SliderCrank,
    n: usize,
    segment: &ReducedBody,
    frame: FrameChoice,
    mass: MassVariant,
) -> (Model, Vec<NodeId>) {
    let segment = models::Segment { body: segment.clone() };
    let variant = models::Variant { frame, mass };
    let sc = models::slider_crank_planar(&models::SliderCrankPlanar::of_segment(n, &segment, p.speed, variant))
        .expect("a segment reduced elsewhere is only placed");
    let (mut m, rod) = (sc.model, sc.rod_nodes);
    m.add_sensor("A", SensorKind::NodePosition { node: rod[0] });
    m.add_sensor("B", SensorKind::NodePosition { node: rod[n] });
    m.add_sensor("rotA", SensorKind::NodeRotation { node: rod[0] });
    m.add_sensor("rotB", SensorKind::NodeRotation { node: rod[n] });
    // Body 0 is the crank, body 1 the first rod segment.
    m.add_sensor("eta0", SensorKind::ModalCoordinates { body: mbs::BodyId(1) });
    (m, rod)
}

/// Signed distance of `p` from the line through `a` and `b`, positive along
/// $\mathbf e_z \times (\mathbf b - \mathbf a)$ (the same convention as mbs's `LineDistance`
/// sensor with normal $\mathbf e_z$).
pub fn chord_distance(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let t = (b - a).normalize();
    t.cross(&(p - a)).dot(&Vector3::z())
}

/// Midpoint deflections of a rod made of ONE segment, from the recorded interface poses and
/// modal coordinates: the deformed mesh is recovered by the superelement
/// ([`Superelement::recover_mesh`]) and the axis node at mid-length is measured against the
/// chord through the end-face centre nodes, exactly as the Exudyn script measures its mesh
/// nodes. `placement` is the rod's placement (a translation).
pub fn midpoint_from_mesh(
    body: &ReducedBody,
    frame: FrameChoice,
    placement: &Vector3<f64>,
    record: &mbs::SensorRecord,
) -> Result<Vec<f64>, BenchError> {
    let mesh = body.mesh.as_ref().ok_or_else(|| BenchError::NoMeshShapes {
        body: body.name.clone(),
    })?;
    let length = body.interfaces[1].position[0] - body.interfaces[0].position[0];
    let ends = [
        axis_node(&mesh.nodes, 0.0, length)?,
        axis_node(&mesh.nodes, length, length)?,
    ];
    let mid = axis_node(&mesh.nodes, length / 2.0, length)?;
    let se = Superelement::new(body, frame, MassVariant::Exact, Damping::none())?;
    let series = |name: &str| {
        record
            .series(name)
            .ok_or_else(|| BenchError::MissingSensor { name: name.into() })
    };
    let (rA, rB, qA, qB, eta) = (
        series("A")?,
        series("B")?,
        series("rotA")?,
        series("rotB")?,
        series("eta0")?,
    );
    let v3 = |x: &[f64]| Vector3::new(x[0], x[1], x[2]);
    let mut out = Vec::with_capacity(rA.len());
    let mut last = Frame::new(v3(&rA[0]) - placement, UnitQuaternion::identity());
    for k in 0..rA.len() {
        // The nodes start with identity orientations (R_k0 = I), so NodeRotation is log R_k.
        let state = BodyState {
            r: vec![v3(&rA[k]) - placement, v3(&rB[k]) - placement],
            R: vec![
                UnitQuaternion::from_scaled_axis(v3(&qA[k])),
                UnitQuaternion::from_scaled_axis(v3(&qB[k])),
            ],
            v: vec![Vector3::zeros(); 2],
            omega: vec![Vector3::zeros(); 2],
            eta: eta[k].clone(),
            eta_dot: vec![0.0; eta[k].len()],
            frame: last,
        };
        let kin = se.kinematics(&state)?;
        last = kin.frame;
        let shape = se.recover_mesh(&kin).ok_or_else(|| BenchError::NoMeshShapes {
            body: body.name.clone(),
        })?;
        let x = &shape.positions;
        out.push(chord_distance(&x[mid], &x[ends[0]], &x[ends[1]]));
    }
    Ok(out)
}

/// CPU time of this process in seconds, or NaN where it cannot be read (Linux only). On a
/// machine shared with other builds the wall time of a loop measures the load as much as the
/// loop; the CPU time does not.
///
/// Read from the scheduler's nanosecond run times of the live threads
/// (`/proc/self/task/*/schedstat`, first field): the time loops of the comparison last tens of
/// milliseconds, where the 10 ms clock ticks of `/proc/self/stat` (the fallback, user + system)
/// would quantise a per-step figure by a quarter. Threads that have ended are not counted; the
/// solvers' worker pools live as long as the process.
pub fn cpu_seconds() -> f64 {
    schedstat_seconds().unwrap_or_else(stat_tick_seconds)
}

fn schedstat_seconds() -> Option<f64> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}

fn stat_tick_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name (which may hold spaces) start with the state, field 3;
    // utime and stime are fields 14 and 15.
    let Some(rest) = stat.rfind(')').map(|k| &stat[k + 1..]) else {
        return f64::NAN;
    };
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok()).unwrap_or(f64::NAN);
    // USER_HZ is 100 on every Linux ABI (`getconf CLK_TCK`).
    (tick(11) + tick(12)) / 100.0
}

/// Median of a non-empty sample (NaN for an empty one).
pub fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Command-line options `--name value` of the benchmark binaries.
pub struct Args {
    pairs: Vec<(String, String)>,
}

impl Args {
    /// Reads `--name value` pairs from the process arguments; a `--name` followed by another
    /// `--option` or by nothing is a flag with the value `true` (e.g. `--geometric-stiffening`).
    /// A lone `--bench`, which `cargo bench` passes, is ignored.
    pub fn from_env() -> Result<Self, BenchError> {
        Self::from_args(std::env::args().skip(1))
    }

    /// [`Self::from_env`] on the given arguments (without the program name).
    pub fn from_args(args: impl IntoIterator<Item = String>) -> Result<Self, BenchError> {
        let mut pairs = Vec::new();
        let mut it = args.into_iter().filter(|a| a != "--bench").peekable();
        while let Some(k) = it.next() {
            let name = k.strip_prefix("--").ok_or_else(|| BenchError::Argument {
                arg: k.clone(),
                why: "expected --name value".into(),
            })?;
            let v = match it.peek() {
                Some(v) if !v.starts_with("--") => it.next().unwrap_or_default(),
                _ => "true".to_string(),
            };
            pairs.push((name.to_string(), v));
        }
        Ok(Self { pairs })
    }

    /// Whether the flag `--name` was given (`--name`, `--name true` or `--name false`).
    pub fn flag(&self, name: &str) -> Result<bool, BenchError> {
        self.get(name, false)
    }

    /// The value of `--name`, parsed, or `default`.
    pub fn get<T: std::str::FromStr>(&self, name: &str, default: T) -> Result<T, BenchError> {
        match self.pairs.iter().rev().find(|(k, _)| k == name) {
            None => Ok(default),
            Some((_, v)) => v.parse().map_err(|_| BenchError::Argument {
                arg: format!("--{name}"),
                why: format!("cannot read '{v}'"),
            }),
        }
    }

    /// The raw value of `--name`, if given.
    pub fn text(&self, name: &str) -> Option<&str> {
        self.pairs
            .iter()
            .rev()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// The value of `--name` among the named `choices` (the first is the default), or an
    /// error listing them.
    pub fn choice<T: Copy>(&self, name: &str, choices: &[(&str, T)]) -> Result<T, BenchError> {
        let given = self.text(name).unwrap_or(choices[0].0);
        choices
            .iter()
            .find(|(key, _)| *key == given)
            .map(|&(_, value)| value)
            .ok_or_else(|| BenchError::Argument {
                arg: format!("--{name}"),
                why: format!(
                    "'{given}' is not {}",
                    choices.iter().map(|(key, _)| *key).collect::<Vec<_>>().join(" or ")
                ),
            })
    }

    /// The rod mesh from `--kind hex8|hex20 --along N --across N` (default hex20, 24 x 2 x 2).
    pub fn rod_mesh(&self) -> Result<RodMesh, BenchError> {
        let kind = self.choice("kind", &[("hex20", CellKind::Hex20), ("hex8", CellKind::Hex8)])?;
        Ok(RodMesh {
            kind,
            along: self.get("along", 24)?,
            across: self.get("across", 2)?,
        })
    }
}
