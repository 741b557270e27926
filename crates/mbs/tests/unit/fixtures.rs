//! Model builders shared by the tests.
#![allow(dead_code)]

use fe_model::{BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind};
use mbs::{JointKind, Model, NodeId, RigidBody, Support};
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
    settings.keep_mesh_shapes = false;
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

/// The planar flexible slider-crank of benchmarks.md C2: rigid crank 0.15 m driven at
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
