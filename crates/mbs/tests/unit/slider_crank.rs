//! The planar flexible slider-crank of validation problem C2.

use crate::fixtures::slider_crank;
use mbs::{solve_dynamic, DynamicSettings, System};
use reduction::ModeSelection;

#[test]
fn slider_follows_the_rigid_mechanism() {
    // Two crank revolutions at 150 rad/s with the rod as two superelements with two modes.
    let speed = 150.0;
    let (model, _, _) = slider_crank(2, ModeSelection::Count(2), speed);
    let sys = System::new(&model).unwrap();
    let period = 2.0 * std::f64::consts::PI / speed;
    let settings = DynamicSettings {
        output_every: 5,
        ..DynamicSettings::new(period / 400.0, 2.0 * period, 0.9)
    };
    let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
    let x = traj.sensors.column("slider", 0).unwrap();
    let z = traj.sensors.column("slider", 2).unwrap();
    let mid = traj.sensors.column("midpoint", 0).unwrap();
    let (mut worst, mut peak) = (0.0f64, 0.0f64);
    for (i, t) in traj.sensors.times.iter().enumerate() {
        // Rigid slider-crank: x = r cos(wt) + sqrt(l^2 - r^2 sin^2(wt)).
        let th = speed * t;
        let rigid = 0.15 * th.cos() + (0.09 - 0.0225 * th.sin() * th.sin()).sqrt();
        worst = worst.max((x[i] - rigid).abs());
        peak = peak.max(mid[i].abs());
        assert!(z[i].abs() < 1e-12, "out of the plane: {}", z[i]);
    }
    let iters: usize = traj.iterations.iter().sum();
    eprintln!(
        "slider-crank: {} steps, {:.2} Newton iterations per step, largest slider deviation from the rigid mechanism {worst:.3e} m, peak midpoint deflection {peak:.3e} m",
        traj.iterations.len(),
        iters as f64 / traj.iterations.len() as f64
    );
    // The rod's elastic shortening is a fraction of a millimetre (axial force of the order of
    // m_rod r w^2 = 20 N on EA = 5.7 MN gives 1e-6 m; bending of the rod changes the chord
    // by ~w^2/l), so the slider stays within 1 mm of the rigid mechanism.
    assert!(worst < 1e-3);
    // Static estimate: the rod carries up to r w^2 = 3400 m/s^2 across its span, a sag of a few
    // millimetres on EI = 12.7 N m^2.
    assert!(peak > 1e-4 && peak < 1e-2, "midpoint deflection {peak}");
}

/// The slider-crank with sensors on the crank tip (driven by time alone: its motion is kept
/// within a step) and on the rod's first node (hung on it), and optionally the crank driver's
/// effort (a reaction: with it the crank's rigid body is evaluated too).
fn sensed_slider_crank(with_reaction: bool) -> (System, usize, usize) {
    let (mut model, rod, _) = slider_crank(2, ModeSelection::Count(2), 150.0);
    let tip = model.nodes.iter().position(|n| n.name == "A").unwrap();
    let tip_id = mbs::NodeId(tip as u32);
    model.add_sensor("tip v", mbs::SensorKind::NodeVelocity { node: tip_id });
    model.add_sensor("tip x", mbs::SensorKind::NodePosition { node: tip_id });
    model.add_sensor("rod0 v", mbs::SensorKind::NodeVelocity { node: rod[0] });
    if with_reaction {
        model.add_sensor("crank torque", mbs::SensorKind::DriverEffort { driver: 0 });
    }
    (System::new(&model).unwrap(), tip, rod[0].0 as usize)
}

#[test]
fn kept_node_motions_are_those_of_a_fresh_evaluation() {
    // The integrator recomputes the time-driven crank once per step and keeps it across the
    // corrections; the sensors read the kept motions, which must be those of the step's time.
    let (sys, tip, rod0) = sensed_slider_crank(false);
    let n = sys.model().sensors.len();
    let period = 2.0 * std::f64::consts::PI / 150.0;
    for newton in [mbs::NewtonStrategy::Modified, mbs::NewtonStrategy::Full] {
        let settings = DynamicSettings {
            newton,
            ..DynamicSettings::new(period / 400.0, period / 20.0, 0.9)
        };
        let mut it = mbs::Integrator::new(&sys, sys.initial_state(), settings).unwrap();
        for _ in 0..20 {
            it.step().unwrap();
            let fresh = sys.node_motions(it.state());
            let got = it.sensor_values(&[n - 3, n - 2, n - 1]).unwrap();
            let want: Vec<f64> = [fresh[tip].v, fresh[tip].r, fresh[rod0].v]
                .iter()
                .flat_map(|v| [v.x, v.y, v.z])
                .collect();
            assert_eq!(got, want, "{newton:?} at t = {}", it.state().time());
        }
    }
}

#[test]
fn a_reaction_sensor_leaves_the_trajectory_unchanged() {
    // Without a sensor of the reactions the crank's rigid body (no unknowns) is not evaluated
    // and the reactions are not summed: the unknowns' equations are the same, bit for bit.
    let period = 2.0 * std::f64::consts::PI / 150.0;
    let settings = DynamicSettings {
        newton: mbs::NewtonStrategy::Modified,
        ..DynamicSettings::new(period / 400.0, period / 10.0, 0.9)
    };
    let run = |with_reaction: bool| {
        let (sys, _, _) = sensed_slider_crank(with_reaction);
        let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
        (
            traj.sensors.column("midpoint", 0).unwrap(),
            traj.sensors.column("crank torque", 0),
        )
    };
    let (without, none) = run(false);
    let (with, torque) = run(true);
    assert!(none.is_none());
    assert_eq!(without, with);
    // The driver carries the rod's inertia: a torque of the order of m_rod r^2 w^2 / l ~ 1 N m.
    let torque = torque.unwrap();
    let peak = torque.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(peak > 1e-2 && peak < 1e2, "crank torque {peak}");
}
