//! Initial states that follow the joints, body velocities, the hand-over from an equilibrium,
//! joint springs with preload, limits and actuators (tangents against central differences,
//! behaviour against analytic solutions) and the retry of failed fixed steps.

use crate::fixtures::{beam_body, cantilever, pendulum};
use crate::kinematics::{chain, random_state};
use crate::tangent::{check_tangents, deformed_state, mixed};
use mbs::{
    solve_dynamic, solve_dynamic_retrying, solve_static, spectrum, BodyId, DynamicSettings, Effort, InitialCondition,
    JointActuator, JointId, JointKind, JointLimit, JointSpring, Model, Pid, SensorKind, StaticSettings, Support,
    System, TimeFunction,
};
use nalgebra::{Isometry3, Matrix3, Rotation3, Vector3};
use reduction::{ModeSelection, ReducedBody};
use superelement::{FrameChoice, MassVariant};

/// Two flexible links of length `L` hanging from the origin along -y: revolute "shoulder"
/// (ground to A) and "elbow" (B to C) about z; aluminium square section of side `side`, two
/// fixed-interface modes each. Returns the model and the two reduced links.
pub fn double_pendulum(L: f64, side: f64, E: f64) -> (Model, [ReducedBody; 2]) {
    let mut m = Model::new("double pendulum");
    let y = |k: f64| Vector3::new(0.0, -k * L, 0.0);
    let ground = m.add_node("ground", y(0.0));
    let a = m.add_node("A", y(0.0));
    let b = m.add_node("B", y(1.0));
    let c = m.add_node("C", y(1.0));
    let d = m.add_node("D", y(2.0));
    m.add_support(Support::clamp(ground));
    let links = [
        beam_body("upper", y(0.0), y(1.0), 6, side, E, 2700.0, ModeSelection::Count(2)),
        beam_body("lower", y(1.0), y(2.0), 6, side, E, 2700.0, ModeSelection::Count(2)),
    ];
    for (body, nodes) in links.iter().zip([[a, b], [c, d]]) {
        m.add_flexible_body(
            body.clone(),
            nodes.to_vec(),
            Isometry3::identity(),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    m.add_joint("shoulder", ground, a, JointKind::Revolute { axis: Vector3::z() });
    m.add_joint("elbow", b, c, JointKind::Revolute { axis: Vector3::z() });
    m.gravity = Vector3::new(0.0, -9.81, 0.0);
    (m, links)
}

fn joint_value(joint: u32, value: f64) -> InitialCondition {
    InitialCondition::JointValue {
        joint: JointId(joint),
        coordinate: 0,
        value,
    }
}

fn joint_rate(joint: u32, rate: f64) -> InitialCondition {
    InitialCondition::JointRate {
        joint: JointId(joint),
        coordinate: 0,
        rate,
    }
}

/// Kinetic energy of a reduced body moving rigidly with `v_c` at its centre of mass and
/// `omega`, turned by `R` from its FE axes.
fn rigid_kinetic_energy(body: &ReducedBody, R: &Matrix3<f64>, v_c: &Vector3<f64>, omega: &Vector3<f64>) -> f64 {
    let I = R * Matrix3::from_fn(|i, j| body.inertia.inertia_com[i][j]) * R.transpose();
    0.5 * body.inertia.mass * v_c.norm_squared() + 0.5 * omega.dot(&(I * omega))
}

#[test]
fn joint_values_and_rates_move_the_subtree_rigidly() {
    let (L, side) = (0.5, 0.01);
    let (mut m, links) = double_pendulum(L, side, 70e9);
    let (t1, t2, w1, w2) = (0.5, 0.3, 2.0, -1.0);
    m.initial = vec![
        joint_value(0, t1),
        joint_value(1, t2),
        joint_rate(0, w1),
        joint_rate(1, w2),
    ];
    let sys = System::new(&m).unwrap();
    let s = sys.initial_state();
    let nodes = sys.node_motions(&s);
    let rot = |a: f64| Rotation3::from_axis_angle(&Vector3::z_axis(), a);
    let down = Vector3::new(0.0, -L, 0.0);
    let B = rot(t1) * down;
    let D = B + rot(t1 + t2) * down;
    let z = Vector3::z();
    let vB = (z * w1).cross(&B);
    let vD = vB + (z * (w1 + w2)).cross(&(D - B));
    // Positions and velocities are sums of a few products of unit-size numbers: 1e-12.
    for (n, r, v, w) in [(2usize, B, vB, w1), (3, B, vB, w1 + w2), (4, D, vD, w1 + w2)] {
        assert!((nodes[n].r - r).norm() < 1e-12, "node {n}: {} vs {r}", nodes[n].r);
        assert!((nodes[n].v - v).norm() < 1e-12, "node {n}: {} vs {v}", nodes[n].v);
        assert!((nodes[n].omega - z * w).norm() < 1e-12, "node {n}");
    }
    let e = sys.energies(&s).unwrap();
    // Undeformed links: the strain energy is the round-off of EA (7e6 N) times eps-sized
    // local displacements, below 1e-12 J.
    assert!(e.strain.abs() < 1e-12, "strain energy {}", e.strain);
    let centre = |a: &Vector3<f64>, b: &Vector3<f64>| 0.5 * (a + b);
    let c1 = centre(&Vector3::zeros(), &B);
    let c2 = centre(&B, &D);
    let T = rigid_kinetic_energy(&links[0], rot(t1).matrix(), &(z * w1).cross(&c1), &(z * w1))
        + rigid_kinetic_energy(
            &links[1],
            rot(t1 + t2).matrix(),
            &(vB + (z * (w1 + w2)).cross(&(c2 - B))),
            &(z * (w1 + w2)),
        );
    // The flexible bodies' kinetic energy in the same rigid motion: equal to round-off of the
    // mass matrix products, 1e-10 relative.
    assert!((e.kinetic - T).abs() < 1e-10 * T, "kinetic {} vs rigid {T}", e.kinetic);
}

#[test]
fn one_line_gives_a_free_body_its_rigid_spin() {
    let L = 0.8;
    let body = beam_body(
        "free",
        Vector3::zeros(),
        Vector3::new(L, 0.0, 0.0),
        8,
        0.02,
        70e9,
        2700.0,
        ModeSelection::Count(3),
    );
    let mut m = Model::new("free body");
    let a = m.add_node("a", Vector3::zeros());
    let b = m.add_node("b", Vector3::new(L, 0.0, 0.0));
    m.add_flexible_body(
        body.clone(),
        vec![a, b],
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    let (v, w, p) = (
        Vector3::new(0.3, -0.2, 0.1),
        Vector3::new(0.4, -1.5, 6.0),
        Vector3::new(0.1, 0.2, -0.3),
    );
    m.initial.push(InitialCondition::BodyVelocity {
        body: BodyId(0),
        velocity: v,
        angular_velocity: w,
        point: p,
    });
    let sys = System::new(&m).unwrap();
    let s = sys.initial_state();
    let c = Vector3::from(body.inertia.center_of_mass);
    let T = rigid_kinetic_energy(&body, &Matrix3::identity(), &(v + w.cross(&(c - p))), &w);
    let e = sys.energies(&s).unwrap();
    // Round-off of the mass-matrix products: 1e-10 relative (the required accuracy).
    assert!((e.kinetic - T).abs() < 1e-10 * T, "kinetic {} vs rigid {T}", e.kinetic);
    let (v_p, w_p) = sys.body_velocity(&s, BodyId(0), &p);
    assert!((v_p - v).norm() < 1e-12 && (w_p - w).norm() < 1e-12);
}

/// `model` with a preloaded spring, active lower and upper limits and a time-function
/// actuator on scalar joint coordinates, and a PID actuator measuring another joint.
fn with_joint_forces(model: &mut Model, sys: &System, s: &mbs::State, joints: [(u32, usize); 4]) {
    let value = |(j, c): (u32, usize)| sys.joint_value(s, JointId(j), c);
    let limit = |(j, c): (u32, usize), lower: Option<f64>, upper: Option<f64>| JointLimit {
        name: format!("stop {j}.{c}"),
        joint: JointId(j),
        coordinate: c,
        lower,
        upper,
        stiffness: 200.0,
        damping: 1.5,
    };
    // 0.05 inside the stop: k d = 10 dominates c * rate (|rate| < 2): active.
    model
        .joint_limits
        .push(limit(joints[0], None, Some(value(joints[0]) - 0.05)));
    model
        .joint_limits
        .push(limit(joints[1], Some(value(joints[1]) + 0.05), None));
    model.joint_springs.push(JointSpring {
        joint: JointId(joints[2].0),
        coordinate: joints[2].1,
        stiffness: 30.0,
        damping: 0.7,
        rest: 0.2,
        preload: 4.0,
    });
    model.actuators.push(JointActuator {
        name: "push".into(),
        joint: JointId(joints[2].0),
        coordinate: joints[2].1,
        effort: Effort::Time(TimeFunction::Sine {
            offset: 1.0,
            amplitude: 2.0,
            omega: 3.0,
            phase: 0.1,
        }),
    });
    model.actuators.push(JointActuator {
        name: "servo".into(),
        joint: JointId(joints[3].0),
        coordinate: joints[3].1,
        effort: Effort::Pid(Pid {
            joint: JointId(joints[0].0),
            coordinate: joints[0].1,
            setpoint: TimeFunction::Linear {
                initial: 0.3,
                rate: 0.5,
            },
            kp: 40.0,
            ki: 25.0,
            kd: 3.0,
            max_effort: None,
        }),
    });
}

#[test]
fn joint_force_tangents_match_fd_on_a_rigid_chain() {
    // The chain's revolute (0), prismatic (1), universal (2) and cylindrical (4) joints, at a
    // rotated, moving state at t = 0.37 (the PID integral's weight (t - t_n)/2 is 0.185).
    // Tolerance as for the chain without these forces (tangent.rs): 1e-6.
    let base = chain();
    let sys = System::new(&base).unwrap();
    let s = random_state(&sys, 11);
    let mut model = base.clone();
    with_joint_forces(&mut model, &sys, &s, [(1, 0), (2, 1), (4, 0), (0, 0)]);
    let sys = System::new(&model).unwrap();
    let s = random_state(&sys, 11);
    check_tangents(&sys, &s, 1e-6, 1e-6);
}

#[test]
fn joint_force_tangents_match_fd_on_deformed_superelements() {
    // The mixed model of tangent.rs (two soft superelements, a revolute joint at index 0):
    // all four forces on its one scalar joint coordinate, at a deformed, rotated, moving
    // state. Tolerance of that test (floating frames solved to 1e-12): 1e-5.
    let base = mixed();
    let sys = System::new(&base).unwrap();
    let s = deformed_state(&sys);
    let mut model = base.clone();
    with_joint_forces(&mut model, &sys, &s, [(0, 0), (0, 0), (0, 0), (0, 0)]);
    model.joint_limits.pop(); // one stop: both would leave no range
    let sys = System::new(&model).unwrap();
    let s2 = deformed_state(&sys);
    check_tangents(&sys, &s2, 1e-6, 1e-5);
}

/// The fixture pendulum (m = 1 kg, centre of mass 1 m below the hinge, I_G = 0.01 kg m^2:
/// I = 1.01 kg m^2 about the hinge) with the sensor "theta" on its joint.
fn sensed_pendulum() -> Model {
    let (mut m, j) = pendulum(1.0, 1.0, 0.01);
    m.add_sensor(
        "theta",
        SensorKind::JointCoordinate {
            joint: j,
            coordinate: 0,
        },
    );
    m
}

fn theta(sys: &System, settings: &DynamicSettings) -> (Vec<f64>, Vec<f64>) {
    let tr = solve_dynamic(sys, sys.initial_state(), settings).unwrap();
    (tr.sensors.times.clone(), tr.sensors.column("theta", 0).unwrap())
}

#[test]
fn a_pid_actuator_brings_a_pendulum_to_its_set_point() {
    // Under gravity the set-point 0.5 rad needs the torque m g d sin 0.5 = 4.70 N m, which
    // only the integral term can hold with zero error. Closed-loop poles of
    // I s^3 + kd s^2 + (kp + m g d cos 0.5) s + ki: all in Re s < -2.6 (Routh: kd (kp + 8.6) / I
    // = 580 > ki), so after 10 s the error is below e^-26 of the start's.
    let mut m = sensed_pendulum();
    m.actuators.push(JointActuator {
        name: "motor".into(),
        joint: JointId(0),
        coordinate: 0,
        effort: Effort::Pid(Pid {
            joint: JointId(0),
            coordinate: 0,
            setpoint: TimeFunction::constant(0.5),
            kp: 50.0,
            ki: 200.0,
            kd: 10.0,
            max_effort: None,
        }),
    });
    m.add_sensor("torque", SensorKind::ActuatorEffort { actuator: 0 });
    let sys = System::new(&m).unwrap();
    let tr = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(0.01, 10.0, 0.8)).unwrap();
    let th = tr.sensors.column("theta", 0).unwrap();
    let torque = *tr.sensors.column("torque", 0).unwrap().last().unwrap();
    let hold = 9.81 * 0.5f64.sin();
    // The torque that holds the pendulum, to the error of the angle times m g d: 1e-6.
    assert!((torque - hold).abs() < 1e-6, "torque {torque} vs {hold}");
    let end = *th.last().unwrap();
    let peak = th.iter().copied().fold(0.0, f64::max);
    eprintln!("theta(10 s) = {end:.12}, peak {peak:.4}");
    // The discrete closed loop has the same fixed point e = 0 (the trapezoidal integral stops
    // growing only there): 1e-8 rad is the Newton tolerance's share.
    assert!((end - 0.5).abs() < 1e-8, "theta(10 s) = {end}");
    assert!(peak > 0.45, "it moved: peak {peak}");
}

#[test]
fn a_torsional_spring_damper_has_the_analytic_damped_frequency() {
    // No gravity: I theta'' + c theta' + k theta = 0, omega_d = sqrt(k/I - (c/2I)^2).
    let (k, c, I): (f64, f64, f64) = (4.0, 0.2, 1.01);
    let omega_d = (k / I - (c / (2.0 * I)).powi(2)).sqrt();
    let mut m = sensed_pendulum();
    m.gravity = Vector3::zeros();
    m.joint_springs.push(JointSpring {
        joint: JointId(0),
        coordinate: 0,
        stiffness: k,
        damping: c,
        rest: 0.0,
        preload: 0.0,
    });
    m.initial.push(joint_value(0, 0.1));
    let sys = System::new(&m).unwrap();
    // Linearised: the state-space eigenvalue is -c/2I +- i omega_d up to the eigensolver's
    // round-off (1e-10 relative).
    let sp = spectrum(&sys, &sys.initial_state()).unwrap();
    let (re, im) = sp.state_space[0];
    assert!((im - omega_d).abs() < 1e-10 * omega_d, "{im} vs {omega_d}");
    assert!((re + c / (2.0 * I)).abs() < 1e-10, "{re}");
    // In time: zero crossings of theta are pi/omega_d apart for any damping. With h = 1 ms and
    // rho_inf = 1 the period error of the trapezoidal rule is (omega h)^2/12 = 3e-7 and the
    // linear interpolation of the crossings is of the same order: 1e-4 (the required bound)
    // holds with margin.
    let (t, th) = theta(&sys, &DynamicSettings::new(1e-3, 12.0, 1.0));
    let crossings: Vec<f64> = (1..th.len())
        .filter(|&i| th[i - 1] * th[i] < 0.0)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * th[i - 1] / (th[i - 1] - th[i]))
        .collect();
    let n = crossings.len() - 1;
    let measured = std::f64::consts::PI * n as f64 / (crossings[n] - crossings[0]);
    eprintln!("omega_d {omega_d:.10}, measured {measured:.10} over {n} half periods");
    assert!(n >= 6 && (measured - omega_d).abs() < 1e-4 * omega_d);
}

#[test]
fn a_joint_limit_stops_a_pendulum() {
    // Released at 1.2 rad, the pendulum swings towards -1.2 rad; a stop at -0.5 rad
    // (k = 1e5 N m/rad) takes the m g d (cos 0.5 - cos 1.2) = 5.05 J in a penetration of
    // sqrt(2 * 5.05 / 1e5) = 0.010 rad, and the damping (50 N m s/rad) makes it lose energy.
    let mut m = sensed_pendulum();
    m.initial.push(joint_value(0, 1.2));
    m.joint_limits.push(JointLimit {
        name: "stop".into(),
        joint: JointId(0),
        coordinate: 0,
        lower: Some(-0.5),
        upper: None,
        stiffness: 1e5,
        damping: 50.0,
    });
    let sys = System::new(&m).unwrap();
    let (_, th) = theta(&sys, &DynamicSettings::new(1e-3, 3.0, 0.8));
    let lowest = th.iter().copied().fold(f64::INFINITY, f64::min);
    eprintln!("lowest {lowest:.5}");
    // Penetration below the 0.010 rad of the undamped stop, and well inside the free swing.
    assert!(lowest > -0.511 && lowest < -0.5, "lowest {lowest}");
    let after = th.iter().position(|&x| x < -0.5).unwrap();
    assert!(th[after..].iter().any(|&x| x > 0.0), "it bounces back");
}

#[test]
fn a_beam_started_from_its_equilibrium_stays_there() {
    // A cantilever of four superelements (aluminium, 1 m, 10 mm square) sagging under
    // gravity: the static tip deflection is rho A g L^4 / (8 EI) = 5.7 mm.
    let (mut m, nodes) = cantilever(4, 1.0, 0.01, 70e9, 2700.0, ModeSelection::Count(2), 4);
    m.gravity = Vector3::new(0.0, -9.81, 0.0);
    let tip = *nodes.last().unwrap();
    m.add_sensor("tip", SensorKind::NodePosition { node: tip });
    let sys = System::new(&m).unwrap();
    let mut st = StaticSettings::new(1);
    st.tolerance = 1e-13;
    let eq = solve_static(&sys, sys.initial_state(), &st).unwrap();
    let y_eq = *eq.sensors.column("tip", 1).unwrap().last().unwrap();
    assert!((y_eq + 5.7e-3).abs() < 0.2e-3, "static tip {y_eq}");
    let settings = DynamicSettings::new(1e-3, 0.2, 0.8);
    let run = |start| {
        let tr = solve_dynamic(&sys, start, &settings).unwrap();
        tr.sensors.column("tip", 1).unwrap()
    };
    let from_equilibrium = run(sys.at_rest(&eq.state, 0.0));
    let drift = from_equilibrium.iter().map(|y| (y - y_eq).abs()).fold(0.0, f64::max);
    // The required bound, 1e-9 m: the equilibrium's residual (1e-13 of the weight) moves the
    // tip by far less.
    eprintln!("drift from the equilibrium {drift:.3e} m");
    assert!(drift < 1e-9, "drift {drift}");
    // Started undeformed, gravity arrives as a step: the tip overshoots to about twice the
    // static deflection.
    let lowest = run(sys.initial_state()).into_iter().fold(0.0, f64::min);
    assert!(lowest < 1.5 * y_eq, "step response {lowest} vs {y_eq}");
}

#[test]
fn a_failed_fixed_step_is_retried_with_halved_steps() {
    // The pendulum of the stop test with 5 ms steps: the impact steps need the most Newton
    // iterations. With one iteration fewer allowed, the fixed step fails there; halved steps
    // start closer to the solution and get through.
    let mut m = sensed_pendulum();
    m.initial.push(joint_value(0, 1.2));
    m.joint_limits.push(JointLimit {
        name: "stop".into(),
        joint: JointId(0),
        coordinate: 0,
        lower: Some(-0.5),
        upper: None,
        stiffness: 1e5,
        damping: 50.0,
    });
    let sys = System::new(&m).unwrap();
    let mut settings = DynamicSettings::new(5e-3, 1.5, 0.8);
    let reference = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
    let most = *reference.iterations.iter().max().unwrap();
    settings.max_iterations = most - 1;
    let failure = solve_dynamic(&sys, sys.initial_state(), &settings).expect_err("the fixed step fails");
    eprintln!("{most} iterations at most; with {}: {}", most - 1, failure.error);
    let run = solve_dynamic_retrying(&sys, sys.initial_state(), &settings, 1e-5).unwrap();
    for r in &run.retries {
        eprintln!(
            "retried the step at t = {:.4}: {} steps down to {:.2e} s ({})",
            r.time, r.substeps, r.smallest_step, r.cause
        );
    }
    assert!(!run.retries.is_empty() && run.retries.iter().all(|r| r.substeps >= 2));
    let th = run.trajectory.sensors.column("theta", 0).unwrap();
    // Recorded on the grid of the fixed step (1.5 s / 5 ms = 300 steps and the start).
    assert_eq!(th.len(), 301);
    // The stop holds (penetration below the 0.010 rad of the undamped impact, as in the stop
    // test) and the pendulum swings back.
    let lowest = th.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(lowest > -0.511 && lowest < -0.5, "lowest {lowest}");
    let after = th.iter().position(|&x| x < -0.5).unwrap();
    assert!(th[after..].iter().any(|&x| x > 0.0), "it bounces back");
    // A minimum step above the 0.32 ms that resolve the stop (0.1 / omega, omega =
    // sqrt(1e5 / 1.01) = 315 rad/s; joint_forces, stops): refused before the first step, with
    // the stop named.
    let stopped = solve_dynamic_retrying(&sys, sys.initial_state(), &settings, 2.5e-3).unwrap_err();
    assert!(
        matches!(stopped.error, mbs::SolveError::UnresolvableLimit { .. }),
        "{}",
        stopped.error
    );
    assert!(stopped.partial.trajectory.iterations.is_empty());
}

#[test]
fn a_column_beyond_eulers_load_is_reported_past_its_critical_point() {
    // The straight clamped-free column of four superelements stays straight under any axial
    // load in statics (no imperfection); above Euler's load (within the 1/N^2 error of the
    // chain, arc_length.rs) that equilibrium is unstable in the two bending planes.
    let (E, side): (f64, f64) = (2.1e11, 0.01);
    let p_euler = std::f64::consts::PI.powi(2) * E * side.powi(4) / 12.0 / 4.0;
    for (factor, unstable) in [(0.8, 0usize), (1.3, 2)] {
        let (mut model, nodes) = cantilever(4, 1.0, side, E, 7800.0, ModeSelection::StaticOnly, 2);
        model.add_dead_force(nodes[4], Vector3::new(-factor * p_euler, 0.0, 0.0));
        let sys = System::new(&model).unwrap();
        let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(2)).unwrap();
        let s = mbs::stability(&sys, &sol.state, 1.0).unwrap();
        eprintln!("P = {factor} P_E: {s:?}");
        assert_eq!(s.negative, unstable, "{s:?}");
        assert_eq!(s.past_critical_point(), unstable > 0);
    }
}

/// A hub driven at a constant 0.3 rad from t = 0 (a function not zero at the start) carries a
/// beam of two superelements clamped to it, no gravity: the mechanism is assembled at the
/// driver's initial value, so the beam starts turned with the hub, unstrained, and stays at
/// rest (no effort at the hub). Before, the hub alone was turned: the first segment started bent
/// (strain energy of order EI theta^2 / L = 1.4e4 * 0.09 / 5 = 250 J) and the beam swung.
#[test]
fn driver_not_zero_at_start_assembles_the_mechanism_there() {
    let mut model = crate::fixtures::spin_up(2, ModeSelection::Count(2), 10.0);
    model.drivers[0].motion = TimeFunction::Constant { value: 0.3 };
    model.add_sensor("effort", SensorKind::DriverEffort { driver: 0 });
    model.add_sensor("strain", SensorKind::StrainEnergy);
    let sys = System::new(&model).unwrap();
    let state = sys.initial_state();
    let e = sys.energies(&state).unwrap();
    // Round-off of the rigid placement (1e-16 of 10 m lengths) in a stiffness of EA/L ~ 6e6.
    assert!(e.strain.abs() < 1e-12, "strain energy at the start {}", e.strain);
    let traj = solve_dynamic(&sys, state, &DynamicSettings::new(0.005, 0.1, 0.9)).unwrap();
    for (t, row) in traj.sensors.times.iter().zip(traj.sensors.series("tip").unwrap()) {
        // The tip in the hub's axes stays at (10, 0, 0): the beam turned with the hub and is at
        // rest; 1e-9 m is round-off of a 10 m beam with margin.
        assert!(
            (row[0] - 10.0).abs() < 1e-9 && row[1].abs() < 1e-9,
            "tip at t = {t}: {row:?}"
        );
    }
    let effort = traj.sensors.series("effort").unwrap();
    // A static hub carrying an unstrained beam needs no torque (a bent segment gave ~1e3 N m).
    assert!(effort.iter().all(|r| r[0].abs() < 1e-6), "{effort:?}");
}
