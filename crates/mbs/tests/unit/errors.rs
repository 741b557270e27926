//! Each refused model gives its named error.

use crate::fixtures::{beam_body, rigid};
use mbs::{BodyId, DriverTarget, Entity, JointId, JointKind, Model, ModelError, NodeId, Support, System, TimeFunction};
use nalgebra::{Isometry3, Vector3};
use reduction::ModeSelection;
use superelement::{FrameChoice, MassVariant};

fn err(model: &Model) -> ModelError {
    match System::new(model) {
        Ok(_) => panic!("model accepted"),
        Err(e) => {
            eprintln!("{e}");
            e
        }
    }
}

/// A planar four-bar of rigid bodies: ground pivots A, D; crank AB, coupler BC, rocker CD.
fn four_bar(rigid_coupler: bool) -> Model {
    let mut m = Model::new("four-bar");
    let z = Vector3::z();
    let a = m.add_node("A", Vector3::zeros());
    let a1 = m.add_node("A1", Vector3::zeros());
    let b = m.add_node("B", Vector3::new(0.0, 1.0, 0.0));
    let b1 = m.add_node("B1", Vector3::new(0.0, 1.0, 0.0));
    let c = m.add_node("C", Vector3::new(2.0, 1.0, 0.0));
    let c1 = m.add_node("C1", Vector3::new(2.0, 1.0, 0.0));
    let d = m.add_node("D", Vector3::new(2.0, 0.0, 0.0));
    m.add_support(Support::clamp(a));
    m.add_support(Support::hinge(d, z));
    m.add_joint("jA", a, a1, JointKind::Revolute { axis: z });
    m.add_rigid_body(rigid("crank", a1, vec![b], 1.0, Vector3::new(0.0, 0.5, 0.0), [0.1; 3]));
    m.add_joint("jB", b, b1, JointKind::Revolute { axis: z });
    if rigid_coupler {
        m.add_rigid_body(rigid(
            "coupler",
            b1,
            vec![c],
            1.0,
            Vector3::new(1.0, 0.0, 0.0),
            [0.1; 3],
        ));
    } else {
        let body = beam_body(
            "coupler",
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(2.0, 1.0, 0.0),
            3,
            0.02,
            2e11,
            7800.0,
            ModeSelection::StaticOnly,
        );
        m.add_flexible_body(
            body,
            vec![b1, c],
            Isometry3::identity(),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    // Oriented from the supported rocker to the coupler, so that the flexible coupler's end
    // C is the dependent node (the rocker's group enters at its supported node D).
    m.add_joint("jC", c1, c, JointKind::Revolute { axis: z });
    m.add_rigid_body(rigid(
        "rocker",
        c1,
        vec![d],
        1.0,
        Vector3::new(0.0, -0.5, 0.0),
        [0.1; 3],
    ));
    m
}

#[test]
fn rigid_loop_is_refused_with_its_members() {
    let model = four_bar(true);
    match err(&model) {
        ModelError::RigidLoop {
            bodies,
            joints,
            supports,
            ids,
        } => {
            assert_eq!(bodies, ["coupler", "crank", "rocker"]);
            assert_eq!(joints, ["jA", "jB", "jC"]);
            assert_eq!(supports, ["A", "D"]);
            // The ids name the same entities as the names.
            let mut named: Vec<String> = ids
                .iter()
                .map(|e| match e {
                    Entity::Body(b) => model.bodies[b.index()].name().to_string(),
                    Entity::Joint(j) => model.joints[j.index()].name.clone(),
                    Entity::Node(n) => model.nodes[n.index()].name.clone(),
                    other => panic!("{other:?}"),
                })
                .collect();
            named.sort();
            assert_eq!(named, ["A", "D", "coupler", "crank", "jA", "jB", "jC", "rocker"]);
        }
        e => panic!("{e:?}"),
    }
    // The same loop closed through a flexible coupler is accepted.
    System::new(&four_bar(false)).unwrap();
}

#[test]
fn unheld_coordinate_names_node_and_direction() {
    let mut m = Model::new("unheld");
    let a = m.add_node("a", Vector3::zeros());
    m.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: a,
        mass: 1.0,
    });
    match err(&m) {
        ModelError::UnheldCoordinate { coordinate, owner } => {
            assert_eq!(coordinate, "node 'a' rotation, component x");
            assert_eq!(owner, Some(Entity::Node(a)));
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn unknown_references_are_named() {
    let mut m = Model::new("refs");
    let a = m.add_node("a", Vector3::zeros());
    m.add_rigid_body(rigid("r", a, vec![NodeId(7)], 1.0, Vector3::zeros(), [1.0; 3]));
    assert!(matches!(err(&m), ModelError::UnknownNode { id: 7, referenced_by, .. } if referenced_by == "body 'r'"));
    assert_eq!(err(&m).entities(), [Entity::Body(BodyId(0))]);
    let mut m = Model::new("refs");
    let a = m.add_node("a", Vector3::zeros());
    m.add_rigid_body(rigid("r", a, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    m.add_driver(
        "d",
        DriverTarget::Joint {
            joint: mbs::JointId(3),
            coordinate: 0,
        },
        TimeFunction::constant(0.0),
    );
    assert!(matches!(err(&m), ModelError::UnknownJoint { id: 3, .. }));
    assert_eq!(err(&m).entities(), [Entity::Driver(0)]);
}

#[test]
fn conflicting_trees_are_refused() {
    // Two joints into one rigid group.
    let mut m = Model::new("two parents");
    let n: Vec<NodeId> = (0..4)
        .map(|i| m.add_node(&format!("n{i}"), Vector3::new(i as f64, 0.0, 0.0)))
        .collect();
    let p = m.add_node("p", Vector3::new(1.0, 0.0, 0.0));
    let q = m.add_node("q", Vector3::new(2.0, 0.0, 0.0));
    for &k in &n {
        m.add_rigid_body(rigid(&format!("b{}", k.0), k, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    }
    m.add_rigid_body(rigid("pq", p, vec![q], 1.0, Vector3::zeros(), [1.0; 3]));
    m.add_joint("j1", n[1], p, JointKind::Spherical);
    m.add_joint("j2", n[2], q, JointKind::Spherical);
    assert!(matches!(err(&m), ModelError::TwoParentJoints { .. }));
    let mut joints = err(&m).entities();
    joints.sort();
    assert_eq!(joints, [Entity::Joint(JointId(0)), Entity::Joint(JointId(1))]);
    // A support on a joint child.
    let mut m = Model::new("support on child");
    let a = m.add_node("a", Vector3::zeros());
    let b = m.add_node("b", Vector3::zeros());
    m.add_rigid_body(rigid("ra", a, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    m.add_rigid_body(rigid("rb", b, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    m.add_joint("j", a, b, JointKind::Spherical);
    m.add_support(Support::pin(b));
    assert!(matches!(err(&m), ModelError::SupportOnDependentNode { node, joint, .. } if node == "b" && joint == "j"));
    assert_eq!(err(&m).entities(), [Entity::Joint(JointId(0)), Entity::Node(b)]);
    m.supports.clear();
    m.add_support(Support::pin(a));
    m.add_support(Support::clamp(a));
    assert!(matches!(err(&m), ModelError::DuplicateSupport { count: 2, .. }));
    assert_eq!(
        err(&m).entities(),
        [Entity::Support(0), Entity::Support(1), Entity::Node(a)]
    );
}

/// A steel beam body "beam" reduced from (0, 0, 0) to (1, 0, 0), on the nodes a at the
/// origin and b at `b`, with the frame `frame`.
fn one_beam(name: &str, b: Vector3<f64>, frame: FrameChoice) -> Model {
    let mut m = Model::new(name);
    let a = m.add_node("a", Vector3::zeros());
    let b = m.add_node("b", b);
    let body = beam_body(
        "beam",
        Vector3::zeros(),
        Vector3::new(1.0, 0.0, 0.0),
        3,
        0.02,
        2e11,
        7800.0,
        ModeSelection::StaticOnly,
    );
    m.add_flexible_body(body, vec![a, b], Isometry3::identity(), frame, MassVariant::Exact);
    m
}

#[test]
fn geometry_mismatches_are_refused() {
    let m = one_beam("mismatch", Vector3::new(1.1, 0.0, 0.0), FrameChoice::CenterOfMass);
    assert!(matches!(err(&m), ModelError::InterfaceMismatch { interface: 1, .. }));
    assert_eq!(err(&m).entities(), [Entity::Body(BodyId(0)), Entity::Node(NodeId(1))]);
    let mut m = Model::new("apart");
    let a = m.add_node("a", Vector3::zeros());
    let b = m.add_node("b", Vector3::new(0.1, 0.0, 0.0));
    m.add_support(Support::clamp(a));
    m.add_joint("hinge", a, b, JointKind::Revolute { axis: Vector3::z() });
    m.add_rigid_body(rigid("r", b, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    assert!(matches!(err(&m), ModelError::JointNodesApart { .. }));
    assert_eq!(err(&m).entities(), [Entity::Joint(JointId(0))]);
}

#[test]
fn invalid_drivers_are_refused() {
    let mut m = Model::new("driver");
    let a = m.add_node("a", Vector3::zeros());
    m.add_rigid_body(rigid("r", a, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    m.add_driver(
        "spin",
        DriverTarget::NodeRotation { node: a },
        TimeFunction::constant(1.0),
    );
    assert!(matches!(err(&m), ModelError::InvalidDriver { .. }));
    assert_eq!(err(&m).entities(), [Entity::Driver(0)]);
    m.drivers.clear();
    m.add_support(Support::clamp(a));
    m.add_driver(
        "push",
        DriverTarget::NodeTranslation { node: a, component: 0 },
        TimeFunction::constant(1.0),
    );
    assert!(matches!(err(&m), ModelError::InvalidDriver { .. }));
}

/// Values out of range carry the entity they belong to; a time function checked for a driver
/// names the driver.
#[test]
fn invalid_values_carry_their_entity() {
    let mut m = Model::new("values");
    let a = m.add_node("a", Vector3::zeros());
    m.add_rigid_body(rigid("r", a, vec![], 1.0, Vector3::zeros(), [1.0; 3]));
    m.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: a,
        mass: 1.0,
    });
    m.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: a,
        mass: -1.0,
    });
    assert!(matches!(err(&m), ModelError::InvalidValue { .. }));
    assert_eq!(err(&m).entities(), [Entity::PointMass(1)]);
    // A named point mass is named in the message, as its study file names it.
    m.point_masses[1].name = "tip".into();
    let message = err(&m).to_string();
    assert!(message.contains("point mass 'tip'"), "{message}");
    m.point_masses.clear();
    m.add_driver(
        "d",
        DriverTarget::NodeTranslation { node: a, component: 0 },
        TimeFunction::constant(f64::NAN),
    );
    assert!(matches!(err(&m), ModelError::InvalidValue { .. }));
    assert_eq!(err(&m).entities(), [Entity::Driver(0)]);
}

/// The error and its causes as a report walking the chain prints them, one per line.
fn walked(e: &(dyn std::error::Error + 'static)) -> Vec<String> {
    let mut lines = vec![e.to_string()];
    let mut source = e.source();
    while let Some(s) = source {
        lines.push(s.to_string());
        source = s.source();
    }
    lines
}

/// A body error keeps the superelement's error as its source and does not repeat it in its
/// own message, so a report walking the chain names the cause once (and the body once).
#[test]
fn body_errors_name_their_cause_once() {
    let cause = superelement::SuperelementError::SingularFrame { rcond: 1e-17 };
    let model = ModelError::Superelement {
        body: "rod".into(),
        body_id: BodyId(0),
        source: cause.clone(),
    };
    let solve = mbs::SolveError::Body {
        body: "rod".into(),
        id: BodyId(0),
        at: mbs::At::Time(0.25),
        step: None,
        source: Box::new(cause.clone()),
    };
    for (e, top) in [
        (&model as &(dyn std::error::Error + 'static), "body 'rod'"),
        (&solve, "body 'rod' at t = 0.250000"),
    ] {
        let lines = walked(e);
        assert_eq!(lines, vec![top.to_string(), cause.to_string()]);
        let all = lines.join("\n");
        assert_eq!(all.matches("floating frame is undetermined").count(), 1, "{all}");
    }
    // A real failure: a body whose frame choice does not fit it is refused with the body named
    // at the top and the superelement's reason once below it.
    let mut m = one_beam("bad frame", Vector3::x(), FrameChoice::InterfaceNode(5));
    m.add_support(Support::clamp(NodeId(0)));
    let e = err(&m);
    let lines = walked(&e);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(
        lines[0].contains("'beam'") && !lines[0].contains("does not fit"),
        "{lines:?}"
    );
    assert!(lines[1].contains("does not fit"), "{lines:?}");
}

/// A reaction is the residual of a node's removed coordinates: a reaction sensor at a node a
/// joint moves (no coordinates of its own) or at a node no support or driver holds is refused
/// by name, not recorded as NaN (which would stop a dynamic run) or as a meaningless zero. At
/// a pinned or hinged node it is accepted.
#[test]
fn a_reaction_sensor_needs_a_held_node() {
    for (node, why) in [(1, "follows a joint or a body"), (4, "no support or driver holds it")] {
        let mut m = four_bar(false);
        let free = m.add_node("free", Vector3::new(5.0, 0.0, 0.0));
        m.add_rigid_body(rigid("lump", free, vec![], 1.0, Vector3::zeros(), [0.1; 3]));
        let node = if node == 4 { free } else { NodeId(node) };
        m.add_sensor("r", mbs::SensorKind::Reaction { node });
        match err(&m) {
            ModelError::InvalidValue { entity, what, id } => {
                assert_eq!(entity, "sensor 'r'");
                assert!(
                    what.contains(&format!("node '{}' has no reaction", m.nodes[node.index()].name))
                        && what.contains(why),
                    "{what}"
                );
                assert_eq!(id, Some(Entity::Sensor(0)));
            }
            e => panic!("{e:?}"),
        }
    }
    for held in [NodeId(0), NodeId(6)] {
        let mut m = four_bar(false);
        m.add_sensor("r", mbs::SensorKind::Reaction { node: held });
        assert!(System::new(&m).is_ok());
    }
}

/// An initial velocity of a node is set on its free components: a component that is not zero
/// along a direction its support holds (or a driver moves) is refused with the node and the
/// component named; zero there, and any angular velocity about a free axis, is accepted.
#[test]
fn an_initial_node_velocity_along_a_held_direction_is_refused() {
    let with = |velocity: Vector3<f64>, angular_velocity: Vector3<f64>| {
        let mut m = four_bar(false);
        m.initial.push(mbs::InitialCondition::NodeVelocity {
            node: NodeId(6),
            velocity,
            angular_velocity,
        });
        m
    };
    match err(&with(Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0))) {
        ModelError::InvalidValue { entity, what, id } => {
            assert_eq!(entity, "initial velocity of node 'D'");
            assert!(
                what.contains("angular velocity component x is 1 rad/s, but its support holds it"),
                "{what}"
            );
            assert_eq!(id, Some(Entity::InitialCondition(0)));
        }
        e => panic!("{e:?}"),
    }
    match err(&with(Vector3::new(0.0, -2.0, 0.0), Vector3::zeros())) {
        ModelError::InvalidValue { what, .. } => {
            assert!(what.contains("the velocity component y is -2 m/s"), "{what}")
        }
        e => panic!("{e:?}"),
    }
    assert!(System::new(&with(Vector3::zeros(), Vector3::new(0.0, 0.0, 3.0))).is_ok());
}
