//! Model builders of the tests: the standard problems come from the `models` crate (the same
//! builders the validation suite and the benchmarks use); what is only the tests' is here.
#![allow(dead_code)]

use mbs::{solve_static, InitialCondition, Model, NodeId, SensorKind, StaticSettings, Support, System};
// Re-exported for the test targets that include this file; each uses a part of them.
#[allow(unused_imports)]
pub use models::{pendulum, rigid, MeshShapes, ELASTICA_E, ELASTICA_SIDE, MATTIASSON as ELASTICA};
use models::{square_spec, RodModel, Variant};
use nalgebra::{Isometry3, Vector3};
use reduction::{ModeSelection, ReducedBody};
use superelement::{FrameChoice, MassVariant};

/// A straight Euler-Bernoulli beam from `a` to `b` of `elements` elements with a square section
/// of side `side`, reduced with interfaces at both ends.
pub fn beam_body(
    name: &str,
    a: Vector3<f64>,
    b: Vector3<f64>,
    elements: usize,
    side: f64,
    E: f64,
    rho: f64,
    modes: ModeSelection,
) -> ReducedBody {
    square_beam(name, (a, b), elements, [side, E, rho], modes, MeshShapes::Drop)
}

/// The beam of [`beam_body`] (`[side, E, rho]`) by the `models` builder, its mode shapes on
/// every FE node kept (for deformed meshes) or dropped as `mesh` says.
pub fn square_beam(
    name: &str,
    (a, b): (Vector3<f64>, Vector3<f64>),
    elements: usize,
    [side, E, rho]: [f64; 3],
    modes: ModeSelection,
    mesh: MeshShapes,
) -> ReducedBody {
    let spec = square_spec(name, E, rho, side).unwrap();
    // Any orientation off the axis: the section is square.
    let orientation = (b - a).cross(&Vector3::new(0.3, 0.9, -0.2)).normalize();
    let body = models::BeamBody {
        mesh,
        ..models::BeamBody::new(
            models::StraightBeam {
                name,
                spec: &spec,
                ends: (a, b),
                elements,
                orientation,
            },
            modes,
        )
    };
    models::beam_body(&body).unwrap()
}

/// A cantilever of length `L` along x as `n` beam superelements in series (nodes `n_0..n_N`,
/// `n_0` clamped). Section side `side`, modulus `E`. Returns the model and the nodes.
pub fn cantilever(
    n: usize,
    L: f64,
    side: f64,
    E: f64,
    rho: f64,
    modes: ModeSelection,
    elements: usize,
) -> (Model, Vec<NodeId>) {
    let mut model = Model::new("cantilever");
    let nodes: Vec<NodeId> = (0..=n)
        .map(|i| model.add_node(&format!("n{i}"), Vector3::new(L * i as f64 / n as f64, 0.0, 0.0)))
        .collect();
    for i in 0..n {
        let a = model.nodes[nodes[i].index()].position;
        let b = model.nodes[nodes[i + 1].index()].position;
        let body = beam_body(&format!("beam{i}"), a, b, elements, side, E, rho, modes);
        model.add_flexible_body(
            body,
            vec![nodes[i], nodes[i + 1]],
            Isometry3::identity(),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    model.add_support(Support::clamp(nodes[0]));
    (model, nodes)
}

/// The planar flexible slider-crank of validation problem C2 ([`models::slider_crank_planar`]):
/// rigid crank 0.15 m driven at `speed` rad/s, steel rod 0.30 m, d = 6 mm, as `n` (even) beam
/// superelements of 4 elements with `modes` fixed-interface modes each, frame at the centre of
/// mass and exact inertia. Returns the model, the rod's nodes and the two rod-end joints.
pub fn slider_crank(n: usize, modes: ModeSelection, speed: f64) -> (Model, Vec<NodeId>, [mbs::JointId; 2]) {
    // Exactly `n` segments (`slider_crank_planar` rounds `n` up to an even count of at least 2,
    // so that the midpoint is a node): the step bench times the rod as 1, 2 and 4 bodies.
    let v = Variant::REFERENCE;
    let rod = models::RodSegment::new(RodModel::Beam { elements: 4 }, models::ROD / n as f64, modes, v.frame);
    let segment = models::rod_segment(&rod).unwrap();
    let sc = models::slider_crank_planar(&models::SliderCrankPlanar::of_segment(n, &segment, speed, v)).unwrap();
    (sc.model, sc.rod_nodes, sc.rod_joints)
}

/// Tip (w/L, u/L, rotation) of the cantilever of `n` superelements under tip load `a` (force,
/// `moment = false`) or `b` (moment), with the Newton histories of the load steps.
pub fn try_elastica_tip(n: usize, load: f64, moment: bool) -> Result<([f64; 3], Vec<mbs::LoadStep>), mbs::SolveError> {
    let (mut model, nodes) = cantilever(n, 1.0, ELASTICA_SIDE, ELASTICA_E, 1000.0, ModeSelection::StaticOnly, 3);
    let tip = *nodes.last().unwrap();
    let EI = models::elastica_EI();
    if moment {
        model.add_dead_moment(tip, Vector3::new(0.0, 0.0, load * EI));
    } else {
        model.add_dead_force(tip, Vector3::new(0.0, load * EI, 0.0));
    }
    model.add_sensor("tip", SensorKind::NodeDisplacement { node: tip });
    model.add_sensor("rot", SensorKind::NodeRotation { node: tip });
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(4)).map_err(|e| e.error)?;
    let d = sol.sensors.series("tip").unwrap().last().unwrap().clone();
    let r = sol.sensors.series("rot").unwrap().last().unwrap().clone();
    Ok(([d[1], -d[0], r[2]], sol.steps))
}

/// [`try_elastica_tip`] that must converge.
pub fn elastica_tip(n: usize, load: f64, moment: bool) -> ([f64; 3], Vec<mbs::LoadStep>) {
    try_elastica_tip(n, load, moment).unwrap()
}

/// The spin-up beam of validation problem C1 ([`models::spin_up`]): `n` superelements with
/// `modes` fixed-interface modes each, the hub spun up to `omega` in 15 s. Sensor "tip": the
/// tip in the hub's axes.
pub fn spin_up(n: usize, modes: ModeSelection, omega: f64) -> Model {
    spin_up_with(n, modes, omega, false)
}

/// [`spin_up`], with the reduced geometric stiffness of each segment when `stiffening`
/// (`CbSettings::geometric_stiffening`).
pub fn spin_up_with(n: usize, modes: ModeSelection, omega: f64, stiffening: bool) -> Model {
    let mut p = models::SpinUp::new(n, modes, omega);
    p.settings.geometric_stiffening = stiffening;
    models::spin_up(&p).unwrap()
}

/// The fixture pendulum released from rest at `theta0`, with the sensor "theta".
pub fn released(theta0: f64) -> System {
    let (mut model, j) = pendulum(1.0, 1.0, 0.01);
    model.initial.push(InitialCondition::JointValue {
        joint: j,
        coordinate: 0,
        value: theta0,
    });
    model.add_sensor(
        "theta",
        SensorKind::JointCoordinate {
            joint: j,
            coordinate: 0,
        },
    );
    System::new(&model).unwrap()
}
