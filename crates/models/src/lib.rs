//! # models: the standard problems, built once
//!
//! The problems that the mbs tests, the validation suite (`validation`) and the benchmarks
//! (`flexmbs-benchmarks`) all need, built by library calls on `fe_model`, `reduction` and
//! `mbs`: beam and solid segments reduced by Craig-Bampton, chains of superelements, the
//! elastica cantilever, the 45-degree bend, the linear transient cantilever, the spin-up beam,
//! the planar and spatial slider-cranks, the free-floating beam and the rigid pendulum. The
//! problem definitions (ids A1-A5, B1-B3, C1-C4) are those of the validation guide
//! (`docs/validation.md`).
//!
//! Every builder of a flexible model takes a [`Variant`] (frame choice and inertia variant), so
//! the AIC-FFR paper's comparison runs the same model six ways. The `auxiliary-node` frame
//! needs an interface at the centre of mass held fixed in the reduction: segments are meshed
//! with an even number of elements, the middle node is that interface, and [`add_segment`]
//! gives it its own (free) multibody node.
//!
//! The crate sits above `mbs` and below the programs that run problems: it uses the four
//! solver crates and nothing else of the workspace, so the mbs tests (as a dev-dependency),
//! the validation suite and the benchmarks can all use it.
//!
//! | symbol | meaning | code |
//! |---|---|---|
//! | $r$ | crank length, 0.15 m | [`CRANK`] |
//! | $l$ | rod length, 0.30 m | [`ROD`] |
//! | $d$ | rod diameter, 6 mm | [`ROD_D`] |
//! | $a$ | side of the square section with the round rod's $I$: $a^4/12 = \pi d^4/64$ | [`square_rod_side`] |
//! | $EI$ | bending stiffness of the elastica section | [`elastica_EI`] |

#![allow(non_snake_case)]

use fe_model::interface::{add_interface_on_set, SpiderKind};
use fe_model::{BeamProperties, BeamSection, BeamTheory, CellKind, FeModel, IsotropicMaterial, MassKind};
use mbs::{Body, BodyId, JointId, JointKind, Model, NodeId, RigidBody, SensorKind, Support};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use reduction::{reduce, CbSettings, ModeSelection, ReducedBody};
use superelement::{FrameChoice, MassVariant};

/// Any failure while building a model: the FE stage or the reduction.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error("model '{model}': FE model: {source}")]
    Fe {
        model: String,
        #[source]
        source: fe_model::FeError,
    },
    #[error("model '{model}': section or material: {source}")]
    Property {
        model: String,
        #[source]
        source: fe_model::PropertyError,
    },
    #[error("model '{model}': reduction: {source}")]
    Reduction {
        model: String,
        #[source]
        source: reduction::ReductionError,
    },
}

/// The formulation's switches compared in the report (theory guide §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    pub frame: FrameChoice,
    pub mass: MassVariant,
}

impl Variant {
    /// The default of the suite: frame at the centre of mass \[E17\], exact inertia.
    pub const REFERENCE: Variant = Variant {
        frame: FrameChoice::CenterOfMass,
        mass: MassVariant::Exact,
    };

    /// The six combinations, in report order.
    pub fn all() -> [Variant; 6] {
        let frames = [
            FrameChoice::CenterOfMass,
            FrameChoice::InterfaceNode(0),
            FrameChoice::AuxiliaryNode,
        ];
        let mut v = [Self::REFERENCE; 6];
        for (i, f) in frames.iter().enumerate() {
            v[2 * i] = Variant {
                frame: *f,
                mass: MassVariant::Exact,
            };
            v[2 * i + 1] = Variant {
                frame: *f,
                mass: MassVariant::Lumped,
            };
        }
        v
    }

    /// "center-of-mass / exact".
    pub fn label(&self) -> String {
        let mass = match self.mass {
            MassVariant::Exact => "exact",
            MassVariant::Lumped => "lumped",
        };
        format!("{} / {mass}", self.frame)
    }
}

/// A beam cross-section and material by value.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamSpec {
    pub E: f64,
    pub nu: f64,
    pub rho: f64,
    pub section: BeamSection,
    pub theory: BeamTheory,
}

impl BeamSpec {
    fn properties(
        &self,
        fe: &mut FeModel,
        orientation: Vector3<f64>,
        model: &str,
    ) -> Result<BeamProperties, BuildError> {
        let material = fe.add_material(IsotropicMaterial::new("material", self.E, self.nu, self.rho).map_err(
            |source| BuildError::Property {
                model: model.into(),
                source,
            },
        )?);
        let section = fe.add_section(self.section.clone());
        Ok(BeamProperties {
            section,
            material,
            orientation,
            theory: self.theory,
            mass: MassKind::Consistent,
        })
    }
}

/// One reduced segment in its own FE axes (placed by [`add_segment`], possibly many times).
#[derive(Clone, Debug)]
pub struct Segment {
    pub body: ReducedBody,
}

/// Whether a builder keeps the reduced basis on every FE node (`ReducedBody::mesh`, for
/// deformed meshes and recovered node motions) or only the interface and modal data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshShapes {
    /// Not kept (the default of the builders: the standard problems draw no meshes, and the
    /// shapes of a large body cost memory).
    Drop,
    Keep,
}

/// Reduces `fe` with interfaces `ends` (and, for the auxiliary-node frame, `middle` as the
/// auxiliary interface) with `settings`, the mesh shapes kept as `mesh` says (whatever
/// `settings.keep_mesh_shapes` holds).
fn reduce_segment(
    fe: &FeModel,
    name: &str,
    ends: &[(String, fe_model::NodeId)],
    middle: fe_model::NodeId,
    settings: &CbSettings,
    frame: FrameChoice,
    mesh: MeshShapes,
) -> Result<Segment, BuildError> {
    let mut settings = settings.clone();
    settings.keep_mesh_shapes = mesh == MeshShapes::Keep;
    if frame == FrameChoice::AuxiliaryNode {
        settings.auxiliary_node = Some(middle);
    }
    let mut body = reduce(fe, name, ends, &settings).map_err(|source| BuildError::Reduction {
        model: name.into(),
        source,
    })?;
    body.name = name.into();
    Ok(Segment { body })
}

/// The FE model of a straight beam from `a` to `b` of exactly `elements` elements: the model
/// and its nodes, first to last.
fn straight_beam_fe(
    name: &str,
    spec: &BeamSpec,
    (a, b): (Vector3<f64>, Vector3<f64>),
    elements: usize,
    orientation: Vector3<f64>,
) -> Result<(FeModel, Vec<fe_model::NodeId>), BuildError> {
    let mut fe = FeModel::default();
    let props = spec.properties(&mut fe, orientation, name)?;
    let nodes = fe_model::generate::straight_beam(
        &mut fe,
        Point3::from(a),
        Point3::from(b),
        elements,
        &props,
        Some("beam"),
    )
    .map_err(|source| BuildError::Fe {
        model: name.into(),
        source,
    })?;
    Ok((fe, nodes))
}

/// The interfaces "a" and "b" at a straight beam's ends.
type EndInterfaces = [(String, fe_model::NodeId); 2];

/// A straight beam from `ends.0` to `ends.1` (FE axes) of `elements` elements, named `name`:
/// what [`BeamSegment`] and [`BeamBody`] share.
#[derive(Clone, Debug)]
pub struct StraightBeam<'a> {
    pub name: &'a str,
    pub spec: &'a BeamSpec,
    pub ends: (Vector3<f64>, Vector3<f64>),
    pub elements: usize,
    /// The beam elements' orientation vector (FE axes).
    pub orientation: Vector3<f64>,
}

impl StraightBeam<'_> {
    /// The FE model of the beam with exactly `elements` elements, its nodes first to last,
    /// and its end interfaces "a" and "b".
    fn fe(&self, elements: usize) -> Result<(FeModel, Vec<fe_model::NodeId>, EndInterfaces), BuildError> {
        let (fe, nodes) = straight_beam_fe(self.name, self.spec, self.ends, elements, self.orientation)?;
        let ends = [("a".to_string(), nodes[0]), ("b".to_string(), nodes[elements])];
        Ok((fe, nodes, ends))
    }
}

/// A straight beam segment of `beam.elements` elements (rounded up to even, so the middle
/// node exists for the auxiliary-node frame), interfaces "a" and "b" at its ends: the
/// parameters of [`beam_segment`].
#[derive(Clone, Debug)]
pub struct BeamSegment<'a> {
    pub beam: StraightBeam<'a>,
    /// The reduction's settings (e.g. `geometric_stiffening`); mesh shapes are not kept.
    pub settings: CbSettings,
    pub frame: FrameChoice,
}

impl<'a> BeamSegment<'a> {
    /// The segment `beam` reduced with `modes` fixed-interface modes and the default settings,
    /// for the centre-of-mass frame.
    pub fn new(beam: StraightBeam<'a>, modes: ModeSelection) -> Self {
        BeamSegment {
            beam,
            settings: CbSettings::new(modes),
            frame: FrameChoice::CenterOfMass,
        }
    }
}

/// The straight beam segment `p` reduced ([`BeamSegment`]).
pub fn beam_segment(p: &BeamSegment<'_>) -> Result<Segment, BuildError> {
    let elements = p.beam.elements + p.beam.elements % 2;
    let (fe, nodes, ends) = p.beam.fe(elements)?;
    reduce_segment(
        &fe,
        p.beam.name,
        &ends,
        nodes[elements / 2],
        &p.settings,
        p.frame,
        MeshShapes::Drop,
    )
}

/// A straight beam body of exactly `beam.elements` elements (odd counts too: no auxiliary
/// interface), reduced with interfaces "a" and "b" at its ends and `modes` fixed-interface
/// modes for the centre-of-mass frame: the parameters of [`beam_body`].
#[derive(Clone, Debug)]
pub struct BeamBody<'a> {
    pub beam: StraightBeam<'a>,
    pub modes: ModeSelection,
    /// Kept: the body's deformed mesh and every FE node's motion can be recovered.
    pub mesh: MeshShapes,
}

impl<'a> BeamBody<'a> {
    /// The body `beam` reduced with `modes` fixed-interface modes, without its mesh shapes.
    pub fn new(beam: StraightBeam<'a>, modes: ModeSelection) -> Self {
        BeamBody {
            beam,
            modes,
            mesh: MeshShapes::Drop,
        }
    }
}

/// The straight beam body `p` reduced ([`BeamBody`]).
pub fn beam_body(p: &BeamBody<'_>) -> Result<ReducedBody, BuildError> {
    let (fe, nodes, ends) = p.beam.fe(p.beam.elements)?;
    Ok(reduce_segment(
        &fe,
        p.beam.name,
        &ends,
        nodes[0],
        &CbSettings::new(p.modes),
        FrameChoice::CenterOfMass,
        p.mesh,
    )?
    .body)
}

/// A circular-arc beam segment about `center` and `axis` from `start` through `angle`.
pub fn arc_segment(
    name: &str,
    spec: &BeamSpec,
    center: Point3<f64>,
    start: Point3<f64>,
    axis: Vector3<f64>,
    angle: f64,
    elements: usize,
    modes: ModeSelection,
    frame: FrameChoice,
) -> Result<Segment, BuildError> {
    let mut fe = FeModel::default();
    // The arc lies in the plane normal to `axis`: that normal is every element's orientation.
    let props = spec.properties(&mut fe, axis, name)?;
    let elements = elements + elements % 2;
    let nodes = fe_model::generate::beam_arc(&mut fe, center, start, axis, angle, elements, &props, Some("arc"))
        .map_err(|source| BuildError::Fe {
            model: name.into(),
            source,
        })?;
    let ends = [("a".to_string(), nodes[0]), ("b".to_string(), nodes[elements])];
    reduce_segment(
        &fe,
        name,
        &ends,
        nodes[elements / 2],
        &CbSettings::new(modes),
        frame,
        MeshShapes::Drop,
    )
}

/// A solid rod segment: a box of `length` x `side` x `side` of hex20 or tet10 cells
/// (`divisions` along the length, rounded up to even, one or two across), RBE2 interfaces at
/// the centroids of the end faces. The FE axes put the rod's axis on the x axis (the box is
/// shifted by -side/2). The parameters of [`solid_rod_segment`].
#[derive(Clone, Debug)]
pub struct SolidRod<'a> {
    pub name: &'a str,
    pub kind: CellKind,
    pub material: IsotropicMaterial,
    pub length: f64,
    pub side: f64,
    pub divisions: [usize; 3],
    /// The reduction's settings; mesh shapes are not kept.
    pub settings: CbSettings,
    pub frame: FrameChoice,
}

impl<'a> SolidRod<'a> {
    /// A rod reduced with `modes` fixed-interface modes and the default settings, for the
    /// centre-of-mass frame.
    pub fn new(
        name: &'a str,
        kind: CellKind,
        material: IsotropicMaterial,
        (length, side): (f64, f64),
        divisions: [usize; 3],
        modes: ModeSelection,
    ) -> Self {
        SolidRod {
            name,
            kind,
            material,
            length,
            side,
            divisions,
            settings: CbSettings::new(modes),
            frame: FrameChoice::CenterOfMass,
        }
    }
}

/// The solid rod segment `p` meshed and reduced ([`SolidRod`]).
pub fn solid_rod_segment(p: &SolidRod<'_>) -> Result<Segment, BuildError> {
    let fe_err = |source| BuildError::Fe {
        model: p.name.into(),
        source,
    };
    let (length, side) = (p.length, p.side);
    let mut divisions = p.divisions;
    // An even count along the length puts a node layer at mid-length for the auxiliary node.
    divisions[0] += divisions[0] % 2;
    let mut mesh = fe_model::box_mesh::box_mesh(p.kind, [length, side, side], divisions).map_err(fe_err)?;
    for x in mesh.nodes.iter_mut() {
        x.y -= side / 2.0;
        x.z -= side / 2.0;
    }
    let mut fe = fe_model::box_mesh::solid_model(mesh, p.material.clone(), MassKind::Consistent).map_err(fe_err)?;
    let a = add_interface_on_set(&mut fe, "a", "x0", Some(Point3::origin()), SpiderKind::Rbe2).map_err(fe_err)?;
    let b = add_interface_on_set(
        &mut fe,
        "b",
        "x1",
        Some(Point3::new(length, 0.0, 0.0)),
        SpiderKind::Rbe2,
    )
    .map_err(fe_err)?;
    // The auxiliary interface: an RBE3 (no added stiffness) on the mid-length node layer.
    let middle = if p.frame == FrameChoice::AuxiliaryNode {
        let layer: Vec<fe_model::NodeId> = (0..fe.mesh.nodes.len())
            .filter(|&i| (fe.mesh.nodes[i].x - length / 2.0).abs() < 1e-9 * length)
            .map(|i| fe_model::NodeId(i as u32))
            .collect();
        fe_model::interface::add_interface(
            &mut fe,
            "aux",
            &layer,
            Some(Point3::new(length / 2.0, 0.0, 0.0)),
            SpiderKind::Rbe3,
        )
        .map_err(fe_err)?
    } else {
        a
    };
    reduce_segment(
        &fe,
        p.name,
        &[("a".into(), a), ("b".into(), b)],
        middle,
        &p.settings,
        p.frame,
        MeshShapes::Drop,
    )
}

/// The FE model of a steel bar 1 x 0.1 x 0.1 m of hex8 bricks (`divisions` along x, y, z)
/// with an RBE2 interface "root" on x = 0 and an RBE3 interface "tip" on x = 1 (the stress
/// output's benchmark and tests), and those interface nodes.
pub fn steel_bar(divisions: [usize; 3]) -> Result<(FeModel, [fe_model::NodeId; 2]), BuildError> {
    let fe_err = |source| BuildError::Fe {
        model: "bar".into(),
        source,
    };
    let mesh = fe_model::box_mesh::box_mesh(CellKind::Hex8, [1.0, 0.1, 0.1], divisions).map_err(fe_err)?;
    let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).map_err(|source| BuildError::Property {
        model: "bar".into(),
        source,
    })?;
    let mut fe = fe_model::box_mesh::solid_model(mesh, steel, MassKind::Consistent).map_err(fe_err)?;
    let root = add_interface_on_set(&mut fe, "root", "x0", None, SpiderKind::Rbe2).map_err(fe_err)?;
    let tip = add_interface_on_set(&mut fe, "tip", "x1", None, SpiderKind::Rbe3).map_err(fe_err)?;
    Ok((fe, [root, tip]))
}

/// A one-body model of `body` (two interfaces, centre-of-mass frame, exact mass) clamped at its
/// first interface with a dead `force` at its second: the model, the body and the two nodes.
pub fn clamped_with_tip_force(body: &ReducedBody, force: Vector3<f64>) -> (Model, BodyId, [NodeId; 2]) {
    let mut m = Model::new(&body.name);
    let ids: Vec<NodeId> = body
        .interfaces
        .iter()
        .map(|i| m.add_node(&i.name, Vector3::from(i.position)))
        .collect();
    let b = m.add_flexible_body(
        body.clone(),
        ids.clone(),
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    m.add_support(Support::clamp(ids[0]));
    m.add_dead_force(ids[1], force);
    (m, b, [ids[0], ids[1]])
}

/// Places `segment` in `model` with `placement` (FE axes to inertial), on the nodes `ends`;
/// for the auxiliary-node frame adds the auxiliary node (free, carried by the body alone).
pub fn add_segment(
    model: &mut Model,
    segment: &Segment,
    name: &str,
    ends: [NodeId; 2],
    placement: Isometry3<f64>,
    variant: Variant,
) -> BodyId {
    let mut body = segment.body.clone();
    body.name = name.into();
    let mut nodes = ends.to_vec();
    if let Some(k) = body.auxiliary_interface {
        let x = body.interfaces[k].position;
        let p = placement * Point3::new(x[0], x[1], x[2]);
        nodes.push(model.add_node(&format!("{name}.aux"), p.coords));
    }
    model.add_flexible_body(body, nodes, placement, variant.frame, variant.mass)
}

/// Axis-to-axis rotation taking the FE x axis onto `direction`.
pub fn x_onto(direction: Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::x(), &direction).unwrap_or_else(|| {
        // Antiparallel: half a turn about z.
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
    })
}

/// A straight chain of `n` identical beam segments from `ends.0` to `ends.1` (one reduction,
/// placed `n` times), nodes named `prefix0..prefixN`: the parameters of [`beam_chain`].
#[derive(Clone, Debug)]
pub struct BeamChain<'a> {
    pub prefix: &'a str,
    pub spec: &'a BeamSpec,
    pub ends: (Vector3<f64>, Vector3<f64>),
    pub n: usize,
    pub elements_per_segment: usize,
    /// The segment's reduction settings (e.g. `geometric_stiffening`).
    pub settings: CbSettings,
    pub variant: Variant,
}

impl<'a> BeamChain<'a> {
    /// A chain of segments reduced with `modes` fixed-interface modes and the default
    /// settings, in the reference variant.
    pub fn new(
        prefix: &'a str,
        spec: &'a BeamSpec,
        ends: (Vector3<f64>, Vector3<f64>),
        n: usize,
        elements_per_segment: usize,
        modes: ModeSelection,
    ) -> Self {
        BeamChain {
            prefix,
            spec,
            ends,
            n,
            elements_per_segment,
            settings: CbSettings::new(modes),
            variant: Variant::REFERENCE,
        }
    }
}

/// Adds the chain `p` to `model` ([`BeamChain`]): the nodes `n_0..n_N` and the bodies.
pub fn beam_chain(model: &mut Model, p: &BeamChain<'_>) -> Result<(Vec<NodeId>, Vec<BodyId>), BuildError> {
    let (prefix, (start, end), n, variant) = (p.prefix, p.ends, p.n, p.variant);
    let length = (end - start).norm();
    let e = (end - start) / length;
    let seg = length / n as f64;
    // Orientation vector: any direction not along the axis; z for a beam in the x-y plane.
    let orientation = if e.z.abs() < 0.9 { Vector3::z() } else { Vector3::x() };
    let q = x_onto(e);
    let segment = beam_segment(&BeamSegment {
        beam: StraightBeam {
            name: prefix,
            spec: p.spec,
            ends: (Vector3::zeros(), Vector3::new(seg, 0.0, 0.0)),
            elements: p.elements_per_segment,
            orientation: q.inverse() * orientation,
        },
        settings: p.settings.clone(),
        frame: variant.frame,
    })?;
    let nodes: Vec<NodeId> = (0..=n)
        .map(|i| model.add_node(&format!("{prefix}{i}"), start + e * (seg * i as f64)))
        .collect();
    let bodies = (0..n)
        .map(|i| {
            let placement = Isometry3::from_parts(Translation3::from(start + e * (seg * i as f64)), q);
            add_segment(
                model,
                &segment,
                &format!("{prefix}.seg{i}"),
                [nodes[i], nodes[i + 1]],
                placement,
                variant,
            )
        })
        .collect();
    Ok((nodes, bodies))
}

/// A rigid body with mass `m`, centre of mass `c` and a diagonal inertia.
pub fn rigid(name: &str, reference: NodeId, nodes: Vec<NodeId>, m: f64, c: Vector3<f64>, I: [f64; 3]) -> RigidBody {
    RigidBody {
        name: name.into(),
        reference,
        nodes,
        mass: m,
        center_of_mass: c,
        inertia: Matrix3::from_diagonal(&Vector3::new(I[0], I[1], I[2])),
    }
}

/// The rigid pendulum: ground node clamped at the origin, revolute joint "hinge" about z to the
/// hinge node, a rigid body "bob" of mass `m` \[kg\] with its centre of mass at distance `d`
/// \[m\] below the hinge and inertia `I_G` \[kg m^2\] about its centre of mass (all axes),
/// gravity -y, g = 9.81 m/s^2. Returns the model and the joint.
pub fn pendulum(m: f64, d: f64, I_G: f64) -> (Model, JointId) {
    let mut model = Model::new("pendulum");
    let ground = model.add_node("ground", Vector3::zeros());
    let hinge = model.add_node("hinge", Vector3::zeros());
    model.add_support(Support::clamp(ground));
    let j = model.add_joint("hinge", ground, hinge, JointKind::Revolute { axis: Vector3::z() });
    model.add_rigid_body(rigid(
        "bob",
        hinge,
        vec![],
        m,
        Vector3::new(0.0, -d, 0.0),
        [I_G, I_G, I_G],
    ));
    model.gravity = Vector3::new(0.0, -9.81, 0.0);
    (model, j)
}

// ---------------------------------------------------------------------------------------
// B1, B2: the elastica cantilever.

/// Mattiasson's elastica (validation problem B1): the cantilever's tip under an end load
/// a = P L^2 / EI -> (w/L, u/L, tip rotation \[rad\]), Mattiasson (1981), table 1.
pub const MATTIASSON: [(f64, [f64; 3]); 7] = [
    (1.0, [0.30172, 0.05643, 0.46135]),
    (2.0, [0.49346, 0.16064, 0.78175]),
    (3.0, [0.60325, 0.25442, 0.98602]),
    (4.0, [0.66996, 0.32894, 1.12124]),
    (5.0, [0.71379, 0.38763, 1.21537]),
    (7.0, [0.76737, 0.47293, 1.33496]),
    (10.0, [0.81061, 0.55500, 1.43029]),
];

/// Square section 10 mm, L = 1, E chosen for EI = 1 N m^2: slenderness L/r = 346 and axial
/// strain a/(EA) < 1e-4, far below the table's five digits.
pub const ELASTICA_SIDE: f64 = 0.01;
pub const ELASTICA_E: f64 = 1.2e9;

/// The elastica cantilever: L = 1 along x, clamped at the origin, `n` superelements of
/// `elements` Euler-Bernoulli elements each (static modes only: statics), sensors "tip"
/// (displacement) and "rot" (rotation vector) at the tip. Returns the model and the tip node.
pub fn elastica_cantilever(n: usize, elements: usize, variant: Variant) -> Result<(Model, NodeId), BuildError> {
    let spec = square_spec("elastica", ELASTICA_E, 1000.0, ELASTICA_SIDE)?;
    let (mut model, nodes) = cantilever("elastica", &spec, n, elements, ModeSelection::StaticOnly, variant)?;
    let tip = nodes[n];
    model.add_sensor("tip", SensorKind::NodeDisplacement { node: tip });
    model.add_sensor("rot", SensorKind::NodeRotation { node: tip });
    Ok((model, tip))
}

/// A beam spec with a square section of side `side`, Poisson's ratio 0.3, Euler-Bernoulli
/// theory.
pub fn square_spec(model: &str, E: f64, rho: f64, side: f64) -> Result<BeamSpec, BuildError> {
    Ok(BeamSpec {
        E,
        nu: 0.3,
        rho,
        section: BeamSection::rectangle("square", side, side, 0.3).map_err(|source| BuildError::Property {
            model: model.into(),
            source,
        })?,
        theory: BeamTheory::EulerBernoulli,
    })
}

/// A cantilever of length 1 along x, clamped at the origin, as a chain of `n` superelements:
/// the model and its nodes `n_0..n_N`.
fn cantilever(
    name: &str,
    spec: &BeamSpec,
    n: usize,
    elements: usize,
    modes: ModeSelection,
    variant: Variant,
) -> Result<(Model, Vec<NodeId>), BuildError> {
    let mut model = Model::new(name);
    let chain = BeamChain {
        variant,
        ..BeamChain::new("n", spec, (Vector3::zeros(), Vector3::x()), n, elements, modes)
    };
    let (nodes, _) = beam_chain(&mut model, &chain)?;
    model.add_support(Support::clamp(nodes[0]));
    Ok((model, nodes))
}

/// Bending stiffness of the elastica section, EI = E a^4 / 12.
pub fn elastica_EI() -> f64 {
    ELASTICA_E * ELASTICA_SIDE.powi(4) / 12.0
}

// ---------------------------------------------------------------------------------------
// B3: the 45-degree bend.

/// Bathe-Bolourchi bend: radius 100, 45 degrees from the origin along x curving towards y,
/// centre (0, 100, 0); square 1 x 1 (A = 1, I = 1/12), E = 1e7, nu = 0 (G = 5e6), and the
/// torsion constant J = 0.141 so that GJ = 7.05e5 (the benchmark's value; the exact
/// Saint-Venant constant of the unit square is 0.1406). `n` superelements of `elements`
/// elements each, clamped at the origin; sensor "tip" (position).
pub fn bend_45(n: usize, elements: usize, variant: Variant) -> Result<(Model, NodeId), BuildError> {
    let (R, E) = (100.0, 1e7);
    let spec = BeamSpec {
        E,
        nu: 0.0,
        rho: 1.0,
        section: BeamSection::from_values(
            "square",
            1.0,
            1.0 / 12.0,
            1.0 / 12.0,
            BEND_GJ / 5e6,
            5.0 / 6.0,
            5.0 / 6.0,
        )
        .map_err(|source| BuildError::Property {
            model: "bend".into(),
            source,
        })?,
        // Timoshenko: the section's shear factors (5/6) give GA; at R/h = 100 shear is small.
        theory: BeamTheory::Timoshenko,
    };
    let center = Point3::new(0.0, R, 0.0);
    let dphi = std::f64::consts::FRAC_PI_4 / n as f64;
    // One arc segment starting at the origin; segment i is it turned by i dphi about the
    // centre (the z axis through `center`).
    let segment = arc_segment(
        "bend",
        &spec,
        center,
        Point3::origin(),
        Vector3::z(),
        dphi,
        elements,
        ModeSelection::StaticOnly,
        variant.frame,
    )?;
    let mut model = Model::new("45-degree bend");
    let nodes: Vec<NodeId> = (0..=n)
        .map(|i| {
            let p =
                center + Rotation3::from_axis_angle(&Vector3::z_axis(), dphi * i as f64) * (Point3::origin() - center);
            model.add_node(&format!("b{i}"), p.coords)
        })
        .collect();
    for i in 0..n {
        let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), dphi * i as f64);
        // Rotation about the centre: x -> c + q (x - c).
        let placement = Isometry3::from_parts(Translation3::from(center.coords - q * center.coords), q);
        add_segment(
            &mut model,
            &segment,
            &format!("bend{i}"),
            [nodes[i], nodes[i + 1]],
            placement,
            variant,
        );
    }
    model.add_support(Support::clamp(nodes[0]));
    model.add_sensor("tip", SensorKind::NodePosition { node: nodes[n] });
    Ok((model, nodes[n]))
}

/// GJ of the 45-degree bend (validation problem B3).
pub const BEND_GJ: f64 = 7.05e5;

// ---------------------------------------------------------------------------------------
// A5: linear transient cantilever; C1: spin-up.

/// A5 cantilever: steel, L = 1 m along x, square 20 mm (L/h = 50, rotary inertia and shear
/// shift the first modes by < 1e-3 of the Euler-Bernoulli values; Euler-Bernoulli elements
/// ignore both anyway), `n` superelements with `modes` fixed-interface modes each; sensor
/// "tip" (displacement). Returns the model, tip node, and (EI, rho A).
pub fn a5_cantilever(
    n: usize,
    elements: usize,
    modes: ModeSelection,
    variant: Variant,
) -> Result<(Model, NodeId, f64, f64), BuildError> {
    let (E, rho, side) = (210e9, 7850.0, 0.02);
    let spec = square_spec("A5", E, rho, side)?;
    let (mut model, nodes) = cantilever("A5 cantilever", &spec, n, elements, modes, variant)?;
    model.add_sensor("tip", SensorKind::NodeDisplacement { node: nodes[n] });
    Ok((model, nodes[n], E * side.powi(4) / 12.0, rho * side * side))
}

/// The spin-up beam of validation problem C1 (Simo & Vu-Quoc 1986): L = 10 m, EA = 2.8e7 N,
/// EI = 1.4e4 N m^2 (both bending planes), rho A = 1.2 kg/m, clamped to a hub on the z axis
/// whose angle follows the spin-up profile to `omega` in 15 s; `n` superelements reduced with
/// `settings` (with `CbSettings::geometric_stiffening`, each segment carries its reduced
/// geometric stiffness). The parameters of [`spin_up`].
#[derive(Clone, Debug)]
pub struct SpinUp {
    pub n: usize,
    pub settings: CbSettings,
    /// Final hub speed \[rad/s\].
    pub omega: f64,
    pub variant: Variant,
}

impl SpinUp {
    /// `n` superelements with `modes` fixed-interface modes each and the default settings,
    /// in the reference variant.
    pub fn new(n: usize, modes: ModeSelection, omega: f64) -> Self {
        SpinUp {
            n,
            settings: CbSettings::new(modes),
            omega,
            variant: Variant::REFERENCE,
        }
    }
}

/// The spin-up model `p` ([`SpinUp`]). Sensor "tip": the tip in the hub's axes.
pub fn spin_up(p: &SpinUp) -> Result<Model, BuildError> {
    let n = p.n;
    let (L, E, A, I, rho) = (10.0, 7e10, 4e-4, 2e-7, 3000.0);
    let spec = BeamSpec {
        E,
        nu: 0.3,
        rho,
        section: BeamSection::from_values("c1", A, I, I, 2.0 * I, 5.0 / 6.0, 5.0 / 6.0).map_err(|source| {
            BuildError::Property {
                model: "spin-up".into(),
                source,
            }
        })?,
        theory: BeamTheory::EulerBernoulli,
    };
    let mut m = Model::new("spin-up");
    let chain = BeamChain {
        prefix: "b",
        spec: &spec,
        ends: (Vector3::zeros(), Vector3::x() * L),
        n,
        elements_per_segment: 4,
        settings: p.settings.clone(),
        variant: p.variant,
    };
    let (beam, _) = beam_chain(&mut m, &chain)?;
    m.add_support(Support::hinge(beam[0], Vector3::z()));
    m.add_driver(
        "hub",
        mbs::DriverTarget::NodeRotation { node: beam[0] },
        mbs::TimeFunction::SpinUp {
            omega: p.omega,
            duration: 15.0,
        },
    );
    m.add_sensor(
        "tip",
        SensorKind::RelativePosition {
            node: beam[n],
            reference: beam[0],
        },
    );
    Ok(m)
}

// ---------------------------------------------------------------------------------------
// C2, C3: slider-cranks.

/// How the connecting rod is modelled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RodModel {
    /// Round steel section d = 6 mm (the benchmark), `elements` Euler-Bernoulli elements per
    /// superelement.
    Beam { elements: usize },
    /// A square section of the same bending stiffness as the 6 mm round one (side
    /// d (3 pi / 16)^(1/4) = 5.24 mm) as beam elements: the beam twin of [`RodModel::Solid`].
    SquareBeam { elements: usize },
    /// The same square rod as a solid mesh (hex20 or tet10), `divisions` cells along each
    /// superelement and one (hex20) or two (tet10) across.
    Solid { kind: CellKind, divisions: usize },
}

/// Crank length, rod length, rod diameter, steel E and rho (validation problem C2).
pub const CRANK: f64 = 0.15;
pub const ROD: f64 = 0.30;
pub const ROD_D: f64 = 0.006;
pub const STEEL_E: f64 = 200e9;
pub const STEEL_RHO: f64 = 7870.0;
/// Mass \[kg\] and principal inertia about the centre of mass \[kg m^2\] of the rigid crank
/// (driven at a given speed or angle: they only change the drive torque).
pub const CRANK_MASS: f64 = 0.1;
pub const CRANK_INERTIA: [f64; 3] = [1e-5, 2e-4, 2e-4];

/// Side of the square section with the bending stiffness of the round rod: a^4/12 = pi d^4/64.
pub fn square_rod_side() -> f64 {
    ROD_D * (3.0 * std::f64::consts::PI / 16.0).powf(0.25)
}

/// One rod segment of length `seg` along the FE x axis (for [`slider_crank_planar`] with
/// any number of segments): the parameters of [`rod_segment`].
#[derive(Clone, Debug)]
pub struct RodSegment {
    pub rod: RodModel,
    pub seg: f64,
    /// The reduction's settings (e.g. `planar`, for a rod evaluated in the plane of the
    /// mechanism: [`confine_to_plane`]).
    pub settings: CbSettings,
    pub frame: FrameChoice,
}

impl RodSegment {
    /// A segment reduced with `modes` fixed-interface modes and the default settings, for
    /// the `frame`.
    pub fn new(rod: RodModel, seg: f64, modes: ModeSelection, frame: FrameChoice) -> Self {
        RodSegment {
            rod,
            seg,
            settings: CbSettings::new(modes),
            frame,
        }
    }
}

/// The rod segment `p` reduced ([`RodSegment`]).
pub fn rod_segment(p: &RodSegment) -> Result<Segment, BuildError> {
    let prop_err = |source| BuildError::Property {
        model: "rod".into(),
        source,
    };
    match p.rod {
        RodModel::Beam { elements } | RodModel::SquareBeam { elements } => {
            let section = match p.rod {
                RodModel::Beam { .. } => BeamSection::circle("rod", ROD_D, 0.3).map_err(prop_err)?,
                _ => {
                    let a = square_rod_side();
                    BeamSection::rectangle("rod", a, a, 0.3).map_err(prop_err)?
                }
            };
            let spec = BeamSpec {
                E: STEEL_E,
                nu: 0.3,
                rho: STEEL_RHO,
                section,
                theory: BeamTheory::EulerBernoulli,
            };
            beam_segment(&BeamSegment {
                beam: StraightBeam {
                    name: "rod",
                    spec: &spec,
                    ends: (Vector3::zeros(), Vector3::new(p.seg, 0.0, 0.0)),
                    elements,
                    orientation: Vector3::y(),
                },
                settings: p.settings.clone(),
                frame: p.frame,
            })
        }
        RodModel::Solid { kind, divisions } => {
            let across = if kind == CellKind::Tet10 { 2 } else { 1 };
            solid_rod_segment(&SolidRod {
                name: "rod",
                kind,
                material: IsotropicMaterial::new("steel", STEEL_E, 0.3, STEEL_RHO).map_err(prop_err)?,
                length: p.seg,
                side: square_rod_side(),
                divisions: [divisions, across, across],
                settings: p.settings.clone(),
                frame: p.frame,
            })
        }
    }
}

/// The rigid crank of C2 and C3: ground node O at the origin, a revolute joint about `axis`
/// driven by `angle`, and a rigid crank of 0.1 kg from O to the crank pin A at (0.15, 0, 0).
/// Returns the crank joint and node A.
fn add_crank(m: &mut Model, axis: Vector3<f64>, angle: mbs::TimeFunction) -> (JointId, NodeId) {
    let o = m.add_node("O", Vector3::zeros());
    let c0 = m.add_node("crank", Vector3::zeros());
    let a = m.add_node("A", Vector3::new(CRANK, 0.0, 0.0));
    m.add_support(Support::clamp(o));
    let jc = m.add_joint("crank", o, c0, JointKind::Revolute { axis });
    m.add_driver(
        "crank angle",
        mbs::DriverTarget::Joint {
            joint: jc,
            coordinate: 0,
        },
        angle,
    );
    m.add_rigid_body(rigid(
        "crank",
        c0,
        vec![a],
        CRANK_MASS,
        Vector3::new(CRANK / 2.0, 0.0, 0.0),
        CRANK_INERTIA,
    ));
    (jc, a)
}

/// A slider-crank and what the benchmarks read from it.
pub struct SliderCrank {
    pub model: Model,
    pub rod_nodes: Vec<NodeId>,
    pub crank_joint: JointId,
    /// The joints at the rod's ends: crank pin A, slider B.
    pub rod_joints: [JointId; 2],
    /// Mass of the whole rod.
    pub rod_mass: f64,
}

/// Where the planar slider-crank's rod comes from.
#[derive(Clone, Copy, Debug)]
pub enum PlanarRod<'a> {
    /// `rod` reduced here with `modes` fixed-interface modes, as an even number of segments
    /// (at least 2): the midpoint is a node.
    Reduced { rod: RodModel, modes: ModeSelection },
    /// Copies of a segment reduced along the FE x axis from 0 to l/n (interfaces a then b),
    /// any number of them from 1.
    Segment(&'a Segment),
}

/// The planar slider-crank of validation problem C2: rigid crank 0.15 m driven at `speed` rad/s
/// from the dead centre with the rigid mechanism's velocities, rod 0.30 m as `n` superelements,
/// slider of half the rod's mass on the x axis, pinned joints about z, no gravity. Sensors
/// "slider" (position) and, when `n` is even, "midpoint" (signed deflection of the midpoint
/// from the chord, in the plane). The parameters of [`slider_crank_planar`].
#[derive(Clone, Copy, Debug)]
pub struct SliderCrankPlanar<'a> {
    pub n: usize,
    pub rod: PlanarRod<'a>,
    pub speed: f64,
    pub variant: Variant,
}

impl<'a> SliderCrankPlanar<'a> {
    /// The rod `rod` reduced with `modes` fixed-interface modes, as `n` segments rounded up
    /// to an even count of at least 2.
    pub fn reduced(n: usize, rod: RodModel, modes: ModeSelection, speed: f64, variant: Variant) -> Self {
        SliderCrankPlanar {
            n,
            rod: PlanarRod::Reduced { rod, modes },
            speed,
            variant,
        }
    }

    /// The rod as `n` copies of `segment`.
    pub fn of_segment(n: usize, segment: &'a Segment, speed: f64, variant: Variant) -> Self {
        SliderCrankPlanar {
            n,
            rod: PlanarRod::Segment(segment),
            speed,
            variant,
        }
    }
}

/// The planar slider-crank `p` ([`SliderCrankPlanar`]).
pub fn slider_crank_planar(p: &SliderCrankPlanar<'_>) -> Result<SliderCrank, BuildError> {
    match p.rod {
        PlanarRod::Reduced { rod, modes } => {
            let n = p.n.max(2) + p.n % 2;
            let segment = rod_segment(&RodSegment::new(rod, ROD / n as f64, modes, p.variant.frame))?;
            Ok(planar_with_segment(n, &segment, p.speed, p.variant))
        }
        PlanarRod::Segment(segment) => Ok(planar_with_segment(p.n, segment, p.speed, p.variant)),
    }
}

/// The planar slider-crank with the rod as `n` copies of `segment`.
fn planar_with_segment(n: usize, segment: &Segment, speed: f64, variant: Variant) -> SliderCrank {
    let mut m = Model::new("planar slider-crank");
    let z = Vector3::z();
    let (jc, a) = add_crank(
        &mut m,
        z,
        mbs::TimeFunction::Linear {
            initial: 0.0,
            rate: speed,
        },
    );
    let s = m.add_node("slider", Vector3::new(CRANK + ROD, 0.0, 0.0));
    let seg = ROD / n as f64;
    let rod_nodes: Vec<NodeId> = (0..=n)
        .map(|i| m.add_node(&format!("rod{i}"), Vector3::new(CRANK + seg * i as f64, 0.0, 0.0)))
        .collect();
    for i in 0..n {
        let place = Isometry3::translation(CRANK + seg * i as f64, 0.0, 0.0);
        add_segment(
            &mut m,
            segment,
            &format!("rod{i}"),
            [rod_nodes[i], rod_nodes[i + 1]],
            place,
            variant,
        );
    }
    let rod_mass = segment.body.inertia.mass * n as f64;
    let ja = m.add_joint("pin A", a, rod_nodes[0], JointKind::Revolute { axis: z });
    m.add_support(Support::slider(s, Vector3::x()));
    let jb = m.add_joint("pin B", s, rod_nodes[n], JointKind::Revolute { axis: z });
    m.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: s,
        mass: rod_mass / 2.0,
    });
    m.add_sensor("slider", SensorKind::NodePosition { node: s });
    if n.is_multiple_of(2) {
        m.add_sensor(
            "midpoint",
            SensorKind::LineDistance {
                node: rod_nodes[n / 2],
                a: rod_nodes[0],
                b: rod_nodes[n],
                normal: Some(z),
            },
        );
    }
    // Rigid-body velocities at the dead centre: the rod turns about B at -speed * crank / rod.
    let w_rod = -speed * CRANK / ROD;
    let B = Vector3::new(CRANK + ROD, 0.0, 0.0);
    for (i, &node) in rod_nodes.iter().enumerate() {
        if i > 0 && i < n {
            let r = Vector3::new(CRANK + seg * i as f64, 0.0, 0.0) - B;
            m.initial.push(mbs::InitialCondition::NodeVelocity {
                node,
                velocity: z.cross(&r) * w_rod,
                angular_velocity: z * w_rod,
            });
        }
    }
    // Auxiliary nodes (at each segment's middle) move with the rod too.
    for k in 0..m.nodes.len() {
        if m.nodes[k].name.ends_with(".aux") {
            let r = m.nodes[k].position - B;
            m.initial.push(mbs::InitialCondition::NodeVelocity {
                node: NodeId(k as u32),
                velocity: z.cross(&r) * w_rod,
                angular_velocity: z * w_rod,
            });
        }
    }
    m.initial.push(mbs::InitialCondition::JointRate {
        joint: ja,
        coordinate: 0,
        rate: w_rod - speed,
    });
    m.initial.push(mbs::InitialCondition::JointRate {
        joint: jb,
        coordinate: 0,
        rate: w_rod,
    });
    SliderCrank {
        model: m,
        rod_nodes,
        crank_joint: jc,
        rod_joints: [ja, jb],
        rod_mass,
    }
}

/// Makes a mechanism in the global xy-plane a planar one: every flexible body is evaluated in
/// the plane ([`mbs::FlexibleBody::planar`]; its part must be reduced planar,
/// `reduction::CbSettings::planar`), and every node of a flexible body that nothing else holds
/// (no support, no parent joint, no rigid body: the nodes between the segments of a rod, the
/// auxiliary nodes) is supported to the plane: translation in the plane through it, rotation
/// about z. The joints and supports already there must keep the other nodes in the plane
/// (`mbs::System::new` checks it).
pub fn confine_to_plane(model: &mut Model) {
    let mut free: Vec<NodeId> = Vec::new();
    for body in &mut model.bodies {
        if let Body::Flexible(f) = body {
            f.planar = true;
            free.extend(&f.nodes);
        }
    }
    free.sort();
    free.dedup();
    let held = |n: &NodeId| {
        model.supports.iter().any(|s| s.node == *n)
            || model.joints.iter().any(|j| j.child == *n)
            || model.bodies.iter().any(|b| match b {
                Body::Rigid(r) => r.reference == *n || r.nodes.contains(n),
                Body::Flexible(_) => false,
            })
    };
    let free: Vec<NodeId> = free.into_iter().filter(|n| !held(n)).collect();
    for node in free {
        model.add_support(Support {
            node,
            translation: mbs::TranslationSupport::Plane { normal: Vector3::z() },
            rotation: mbs::RotationSupport::Axis { axis: Vector3::z() },
        });
    }
}

/// Offset of the spatial slider-crank's guide from the crank's plane of rotation (C3).
pub const GUIDE_OFFSET: f64 = 0.1;

/// The spatial slider-crank of validation problem C3: the crank turns about the y axis in the plane
/// y = 0 (tip at (0.15 cos, 0, -0.15 sin)); the slider moves along the line
/// (x, 0.1, 0), perpendicular to the crank axis and offset from the crank's plane by 0.1 m.
/// The rod (same as C2) is joined to the crank by a spherical joint and to the slider by a
/// universal joint whose two axes are normal to the rod (no spin of the rod about its axis).
/// Starts at rest with the crank at the outer dead centre and spins it up smoothly
/// (the C1 profile) to `speed` within `ramp` seconds. Sensors "slider", "mid_y" and "mid_z":
/// the midpoint's deflection from the chord measured about the fixed y and z axes
/// (`LineDistance` with normal y: the component along y x chord, in the crank's plane of
/// rotation; normal z: along z x chord, out of that plane).
pub fn slider_crank_spatial(
    n: usize,
    modes: ModeSelection,
    rod: RodModel,
    speed: f64,
    ramp: f64,
    variant: Variant,
) -> Result<SliderCrank, BuildError> {
    let n = n.max(2) + n % 2;
    let mut m = Model::new("spatial slider-crank");
    let y = Vector3::y();
    let A = Vector3::new(CRANK, 0.0, 0.0);
    let dx = (ROD * ROD - GUIDE_OFFSET * GUIDE_OFFSET).sqrt();
    let B = Vector3::new(CRANK + dx, GUIDE_OFFSET, 0.0);
    let (jc, a) = add_crank(
        &mut m,
        y,
        mbs::TimeFunction::SpinUp {
            omega: speed,
            duration: ramp,
        },
    );
    let s = m.add_node("slider", B);
    let e = (B - A).normalize();
    let q = x_onto(e);
    let seg = ROD / n as f64;
    let segment = rod_segment(&RodSegment::new(rod, seg, modes, variant.frame))?;
    let rod_nodes: Vec<NodeId> = (0..=n)
        .map(|i| m.add_node(&format!("rod{i}"), A + e * (seg * i as f64)))
        .collect();
    for i in 0..n {
        let place = Isometry3::from_parts(Translation3::from(A + e * (seg * i as f64)), q);
        add_segment(
            &mut m,
            &segment,
            &format!("rod{i}"),
            [rod_nodes[i], rod_nodes[i + 1]],
            place,
            variant,
        );
    }
    let rod_mass = segment.body.inertia.mass * n as f64;
    let ja = m.add_joint("ball A", a, rod_nodes[0], JointKind::Spherical);
    m.add_support(Support::slider(s, Vector3::x()));
    let axis1 = e.cross(&Vector3::z()).normalize();
    let axis2 = e.cross(&axis1).normalize();
    let jb = m.add_joint("universal B", s, rod_nodes[n], JointKind::Universal { axis1, axis2 });
    m.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: s,
        mass: rod_mass / 2.0,
    });
    m.add_sensor("slider", SensorKind::NodePosition { node: s });
    for (name, normal) in [("mid_y", y), ("mid_z", Vector3::z())] {
        m.add_sensor(
            name,
            SensorKind::LineDistance {
                node: rod_nodes[n / 2],
                a: rod_nodes[0],
                b: rod_nodes[n],
                normal: Some(normal),
            },
        );
    }
    Ok(SliderCrank {
        model: m,
        rod_nodes,
        crank_joint: jc,
        rod_joints: [ja, jb],
        rod_mass,
    })
}

// ---------------------------------------------------------------------------------------
// C4: free-floating beam.

/// C4: an aluminium-like beam 1 m along x, square 50 mm, E = 7e7 (soft: first elastic
/// frequency about 52 rad/s), one superelement of 6 elements with 2 modes, no supports and no
/// loads. Returns the model and its two end nodes.
pub fn free_beam(variant: Variant) -> Result<(Model, [NodeId; 2]), BuildError> {
    let spec = square_spec("free beam", 7e7, 2700.0, 0.05)?;
    let mut m = Model::new("free beam");
    let chain = BeamChain {
        variant,
        ..BeamChain::new(
            "f",
            &spec,
            (Vector3::zeros(), Vector3::x()),
            1,
            6,
            ModeSelection::Count(2),
        )
    };
    let (nodes, _) = beam_chain(&mut m, &chain)?;
    for (name, kind) in [
        ("L", SensorKind::LinearMomentum),
        ("H", SensorKind::AngularMomentum),
        ("T", SensorKind::KineticEnergy),
        ("U", SensorKind::StrainEnergy),
    ] {
        m.add_sensor(name, kind);
    }
    Ok((m, [nodes[0], nodes[1]]))
}
