//! Model builders shared by the tests.
#![allow(dead_code)]

use fe_model::{BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind};
use mbs::{
    solve_static, InitialCondition, JointKind, Model, NodeId, RigidBody, SensorKind, StaticSettings, Support, System,
};
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use reduction::{reduce, CbSettings, ModeSelection, ReducedBody};
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
    beam_body_with(name, a, b, elements, side, E, rho, modes, false)
}

/// [`beam_body`], with the mode shapes on every FE node kept when `keep_mesh_shapes`.
pub fn beam_body_with(
    name: &str,
    a: Vector3<f64>,
    b: Vector3<f64>,
    elements: usize,
    side: f64,
    E: f64,
    rho: f64,
    modes: ModeSelection,
    keep_mesh_shapes: bool,
) -> ReducedBody {
    let mut model = FeModel::default();
    let material = model.add_material(IsotropicMaterial::new("steel", E, 0.3, rho).unwrap());
    let section = model.add_section(BeamSection::rectangle("square", side, side, 0.3).unwrap());
    let axis = b - a;
    let orientation = axis.cross(&Vector3::new(0.3, 0.9, -0.2)).normalize();
    let props = BeamProperties {
        section,
        material,
        orientation,
        theory: BeamTheory::EulerBernoulli,
        mass: MassKind::Consistent,
    };
    let nodes = fe_model::generate::straight_beam(
        &mut model,
        Point3::from(a),
        Point3::from(b),
        elements,
        &props,
        Some("beam"),
    )
    .unwrap();
    let interfaces = vec![("a".to_string(), nodes[0]), ("b".to_string(), nodes[elements])];
    let mut settings = CbSettings::new(modes);
    settings.keep_mesh_shapes = keep_mesh_shapes;
    let mut body = reduce(&model, name, &interfaces, &settings).unwrap();
    body.name = name.into();
    body
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

/// Pendulum: ground node clamped at the origin, revolute joint about z to the hinge node, a
/// rigid body of mass `m` with its centre of mass at distance `d` below the hinge and inertia
/// `I_G` about z (gravity -y, g = 9.81). Returns the model and the joint.
pub fn pendulum(m: f64, d: f64, I_G: f64) -> (Model, mbs::JointId) {
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

/// The planar flexible slider-crank of validation problem C2: rigid crank 0.15 m driven at
/// `speed` rad/s (constant), steel rod 0.30 m, d = 6 mm, as `n` beam superelements with
/// `modes` fixed-interface modes each; slider of half the rod's mass on the x axis; pinned
/// joints about z; no gravity. Starts at the dead centre with the rigid-body velocities
/// (crank tip 0.15 * speed along y, rod turning about the slider). Returns the model, the
/// rod's nodes and the two rod-end joints.
pub fn slider_crank(n: usize, modes: ModeSelection, speed: f64) -> (Model, Vec<NodeId>, [mbs::JointId; 2]) {
    let (crank, rod) = (0.15, 0.30);
    let d: f64 = 0.006;
    let (E, rho) = (200e9, 7870.0);
    let mut m = Model::new("slider-crank");
    let z = Vector3::z();
    let o = m.add_node("O", Vector3::zeros());
    let c0 = m.add_node("crank", Vector3::zeros());
    let a = m.add_node("A", Vector3::new(crank, 0.0, 0.0));
    let s = m.add_node("slider", Vector3::new(crank + rod, 0.0, 0.0));
    let rod_nodes: Vec<NodeId> = (0..=n)
        .map(|i| {
            m.add_node(
                &format!("rod{i}"),
                Vector3::new(crank + rod * i as f64 / n as f64, 0.0, 0.0),
            )
        })
        .collect();
    m.add_support(Support::clamp(o));
    let jc = m.add_joint("crank", o, c0, JointKind::Revolute { axis: z });
    m.add_driver(
        "crank speed",
        mbs::DriverTarget::Joint {
            joint: jc,
            coordinate: 0,
        },
        mbs::TimeFunction::Linear {
            initial: 0.0,
            rate: speed,
        },
    );
    m.add_rigid_body(rigid(
        "crank",
        c0,
        vec![a],
        0.1,
        Vector3::new(crank / 2.0, 0.0, 0.0),
        [1e-5, 2e-4, 2e-4],
    ));
    // The rod: identical round-section segments (one reduction, placed n times).
    let seg = rod / n as f64;
    let mut fe = FeModel::default();
    let material = fe.add_material(IsotropicMaterial::new("steel", E, 0.3, rho).unwrap());
    let section = fe.add_section(BeamSection::circle("rod", d, 0.3).unwrap());
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::y(),
        theory: BeamTheory::EulerBernoulli,
        mass: MassKind::Consistent,
    };
    let nodes = fe_model::generate::straight_beam(
        &mut fe,
        Point3::origin(),
        Point3::new(seg, 0.0, 0.0),
        4,
        &props,
        Some("rod"),
    )
    .unwrap();
    let mut settings = CbSettings::new(modes);
    settings.keep_mesh_shapes = false;
    let body = reduce(&fe, "rod", &[("a".into(), nodes[0]), ("b".into(), nodes[4])], &settings).unwrap();
    let rod_mass = body.inertia.mass * n as f64;
    for i in 0..n {
        let mut b = body.clone();
        b.name = format!("rod{i}");
        let place = Isometry3::translation(crank + seg * i as f64, 0.0, 0.0);
        m.add_flexible_body(
            b,
            vec![rod_nodes[i], rod_nodes[i + 1]],
            place,
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    let ja = m.add_joint("pin A", a, rod_nodes[0], JointKind::Revolute { axis: z });
    m.add_support(Support::slider(s, Vector3::x()));
    let jb = m.add_joint("pin B", s, rod_nodes[n], JointKind::Revolute { axis: z });
    m.point_masses.push(mbs::PointMass {
        node: s,
        mass: rod_mass / 2.0,
    });
    m.add_sensor("slider", mbs::SensorKind::NodePosition { node: s });
    if n % 2 == 0 {
        m.add_sensor(
            "midpoint",
            mbs::SensorKind::LineDistance {
                node: rod_nodes[n / 2],
                a: rod_nodes[0],
                b: rod_nodes[n],
                normal: Some(z),
            },
        );
    }
    // Rigid-body velocities at the dead centre: the rod turns about B at -speed * crank / rod.
    let w_rod = -speed * crank / rod;
    for (i, &node) in rod_nodes.iter().enumerate() {
        if i > 0 && i < n {
            let r = Vector3::new(crank + seg * i as f64, 0.0, 0.0) - Vector3::new(crank + rod, 0.0, 0.0);
            m.initial.push(mbs::InitialCondition::NodeVelocity {
                node,
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
    (m, rod_nodes, [ja, jb])
}

/// Mattiasson's elastica (validation problem B1): a -> (w/L, u/L, tip rotation).
pub const ELASTICA: [(f64, [f64; 3]); 7] = [
    (1.0, [0.30172, 0.05643, 0.46135]),
    (2.0, [0.49346, 0.16064, 0.78175]),
    (3.0, [0.60325, 0.25442, 0.98602]),
    (4.0, [0.66996, 0.32894, 1.12124]),
    (5.0, [0.71379, 0.38763, 1.21537]),
    (7.0, [0.76737, 0.47293, 1.33496]),
    (10.0, [0.81061, 0.55500, 1.43029]),
];

/// Square section 10 mm, L = 1, E chosen for EI = 1 N m^2: slenderness L/r = 346 and axial
/// strain a/(EA) < 5e-5, far below the table's 5 digits.
pub const ELASTICA_SIDE: f64 = 0.01;
pub const ELASTICA_E: f64 = 1.2e9;

/// Tip (w/L, u/L, rotation) of the cantilever of `n` superelements under tip load `a` (force,
/// `moment = false`) or `b` (moment), with the Newton histories of the load steps.
pub fn try_elastica_tip(n: usize, load: f64, moment: bool) -> Result<([f64; 3], Vec<mbs::LoadStep>), mbs::SolveError> {
    let (mut model, nodes) = cantilever(n, 1.0, ELASTICA_SIDE, ELASTICA_E, 1000.0, ModeSelection::StaticOnly, 3);
    let tip = *nodes.last().unwrap();
    let EI = ELASTICA_E * ELASTICA_SIDE.powi(4) / 12.0;
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

/// The spin-up beam of validation problem C1 (Simo & Vu-Quoc 1986): L = 10 m, EA = 2.8e7 N,
/// EI = 1.4e4 N m^2 (both bending planes), rho A = 1.2 kg/m, clamped to a hub on the z axis
/// whose angle follows the spin-up profile to `omega` in 15 s; `n` superelements with `modes`
/// fixed-interface modes each. Sensor "tip": the tip in the hub's axes.
pub fn spin_up(n: usize, modes: ModeSelection, omega: f64) -> Model {
    spin_up_with(n, modes, omega, false)
}

/// [`spin_up`], with the reduced geometric stiffness of each segment when `stiffening`
/// (`CbSettings::geometric_stiffening`).
pub fn spin_up_with(n: usize, modes: ModeSelection, omega: f64, stiffening: bool) -> Model {
    let (L, E, A, I, rho) = (10.0, 7e10, 4e-4, 2e-7, 3000.0);
    let mut fe = FeModel::default();
    let material = fe.add_material(IsotropicMaterial::new("c1", E, 0.3, rho).unwrap());
    let section = fe.add_section(BeamSection::from_values("c1", A, I, I, 2.0 * I, 5.0 / 6.0, 5.0 / 6.0).unwrap());
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::y(),
        theory: BeamTheory::EulerBernoulli,
        mass: MassKind::Consistent,
    };
    let seg = L / n as f64;
    let nodes = fe_model::generate::straight_beam(
        &mut fe,
        Point3::origin(),
        Point3::new(seg, 0.0, 0.0),
        4,
        &props,
        Some("seg"),
    )
    .unwrap();
    let mut settings = CbSettings::new(modes);
    settings.keep_mesh_shapes = false;
    settings.geometric_stiffening = stiffening;
    let body = reduce(&fe, "seg", &[("a".into(), nodes[0]), ("b".into(), nodes[4])], &settings).unwrap();
    let mut m = Model::new("spin-up");
    let beam: Vec<NodeId> = (0..=n)
        .map(|i| m.add_node(&format!("b{i}"), Vector3::new(seg * i as f64, 0.0, 0.0)))
        .collect();
    for i in 0..n {
        let mut b = body.clone();
        b.name = format!("seg{i}");
        m.add_flexible_body(
            b,
            vec![beam[i], beam[i + 1]],
            Isometry3::translation(seg * i as f64, 0.0, 0.0),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    m.add_support(Support::hinge(beam[0], Vector3::z()));
    m.add_driver(
        "hub",
        mbs::DriverTarget::NodeRotation { node: beam[0] },
        mbs::TimeFunction::SpinUp { omega, duration: 15.0 },
    );
    m.add_sensor(
        "tip",
        SensorKind::RelativePosition {
            node: beam[n],
            reference: beam[0],
        },
    );
    m
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
