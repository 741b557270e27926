//! Saturated PID actuators and joint limits (stops): Newton through the saturation, its
//! tangent on both branches, the first step after a release, the energy of a driven arm
//! hitting stops of any stiffness, and a stop no step resolves refused.

use crate::fixtures::pendulum;
use crate::kinematics::{chain, random_state};
use crate::tangent::check_tangents;
use mbs::{
    solve_dynamic, solve_dynamic_retrying, DynamicSettings, Effort, Integrator, JointActuator, JointId, JointLimit,
    Model, Pid, SensorKind, SolveError, System, TimeFunction,
};
use std::sync::Arc;

/// A servo of gains (kp, ki, kd) saturated at `max` on joint 0's coordinate 0, measuring it.
fn servo(setpoint: f64, (kp, ki, kd): (f64, f64, f64), max: f64) -> JointActuator {
    JointActuator {
        name: "servo".into(),
        joint: JointId(0),
        coordinate: 0,
        effort: Effort::Pid(Pid {
            joint: JointId(0),
            coordinate: 0,
            setpoint: TimeFunction::constant(setpoint),
            kp,
            ki,
            kd,
            max_effort: Some(max),
        }),
    }
}

/// The fixture pendulum of 10 kg, centre of mass 0.5 m below the hinge (I = 2.6 kg m^2 about
/// it), under gravity, with a stiff servo to 1 rad saturated at 300 N m and the sensors
/// "theta" and "torque".
fn stiff_servo_pendulum() -> Model {
    let (mut m, j) = pendulum(10.0, 0.5, 0.1);
    m.add_sensor(
        "theta",
        SensorKind::JointCoordinate {
            joint: j,
            coordinate: 0,
        },
    );
    m.actuators.push(servo(1.0, (1e5, 1e4, 1e3), 300.0));
    m.add_sensor("torque", SensorKind::ActuatorEffort { actuator: 0 });
    m
}

#[test]
fn a_stiff_saturated_servo_converges_in_few_newton_iterations() {
    // The servo saturates on its way to 1 rad and holds m g d sin 1 = 41.3 N m there, far
    // below its 300 N m. With the exact piecewise derivative Newton cycled between the two
    // saturated branches (the iteration matrix of a saturated iterate has inertia alone, 1e5
    // against the servo's K_p + gamma' K_d = 3e5): "relative residual 8.8e-1 after 20
    // iterations" at t = 0.9 s. Solved on one branch per step it converges as on a smooth law.
    let sys = System::new(&stiff_servo_pendulum()).unwrap();
    let tr = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(0.01, 2.0, 0.8)).unwrap();
    let most = *tr.iterations.iter().max().unwrap();
    let torque = tr.sensors.column("torque", 0).unwrap();
    let theta = *tr.sensors.column("theta", 0).unwrap().last().unwrap();
    let hold = 10.0 * 9.81 * 0.5 * 1f64.sin();
    eprintln!(
        "at most {most} iterations; torque {:?} ... {}",
        &torque[..4],
        torque.last().unwrap()
    );
    // On one branch Newton converges quadratically from the predictor: 4 corrections
    // measured; 5 leaves one for a switch of branch (the cycling ran to the limit, 20).
    assert!(most <= 5, "{most} iterations");
    // It saturated (the first steps push at the bound: the saturated branch is u_max itself)
    // and settled where it holds the weight.
    assert_eq!(torque[1], 300.0);
    // At rest at theta = 1 - 2.8e-4 rad the torque is m g d sin(theta), below m g d sin 1 by
    // cot(1) 2.8e-4 = 1.8e-4 of it (as measured): 1e-3.
    assert!((torque.last().unwrap() - hold).abs() < 1e-3 * hold, "{torque:?}");
    // The integral, frozen while saturated, has yet to remove the last 2.8e-4 rad (the loop's
    // slow pole, near -ki/kp = -0.1/s, takes it out over tens of seconds): 1e-3.
    assert!((theta - 1.0).abs() < 1e-3, "{theta}");
}

#[test]
fn the_pid_tangent_matches_central_differences_saturated_and_not() {
    // The chain's joint 1 measured and joint 0 actuated (a coupling entry of the tangent) at a
    // rotated, moving state at t = 0.37 (the integral's weight 0.185), with a bound far above
    // the effort (the linear branch) and far below it (saturated: zero tangent). Tolerance of
    // the chain's own tangent test (tangent.rs), 1e-6: central differences with h = 1e-6 of
    // entries of unit size carry truncation ~1e-12 and round-off eps |F| / h ~ 1e-10 (measured
    // up to 2e-9 of the row's or column's largest entry), while a wrong or missing PID entry
    // errs by the order of the entry itself.
    let base = chain();
    for (max, saturated) in [(1e6, false), (0.05, true)] {
        let mut model = base.clone();
        let mut a = servo(0.3, (40.0, 25.0, 3.0), max);
        if let Effort::Pid(p) = &mut a.effort {
            p.joint = JointId(1);
        }
        model.actuators.push(a);
        let sys = System::new(&model).unwrap();
        let mut s = random_state(&sys, 11);
        sys.settle_actuator_branches(&mut s);
        let u = sys.actuator_efforts(&s)[0];
        eprintln!("bound {max}: effort {u}");
        assert_eq!(u.abs() == max, saturated, "effort {u}");
        check_tangents(&sys, &s, 1e-6, 1e-6);
    }
}

#[test]
fn the_first_step_after_a_release_converges() {
    // The stiff servo held at zero effort while the pendulum swings down from 1.4 rad; released
    // at 0.3 s, far from its set-point, its law saturates at once and brings the pendulum to
    // 1 rad. Every step after the release converges, in few iterations.
    let mut m = stiff_servo_pendulum();
    m.initial.push(mbs::InitialCondition::JointValue {
        joint: JointId(0),
        coordinate: 0,
        value: 1.4,
    });
    let sys = Arc::new(System::new(&m).unwrap());
    let start = sys.initial_state();
    let mut integ = Integrator::new_owned(sys, start, DynamicSettings::new(0.01, 3.0, 0.8)).unwrap();
    integ.system_mut().unwrap().set_actuator_effort(0, Some(0.0)).unwrap();
    for _ in 0..30 {
        integ.step().unwrap();
    }
    integ.system_mut().unwrap().set_actuator_effort(0, None).unwrap();
    let mut most = 0;
    for k in 0..270 {
        let report = integ
            .step()
            .unwrap_or_else(|e| panic!("step {k} after the release: {e}"));
        most = most.max(report.residuals.len() - 1);
    }
    let theta = integ.system().joint_value(integ.state(), JointId(0), 0);
    eprintln!("at most {most} iterations after the release; theta {theta}");
    // As for the servo from rest (a_stiff_saturated_servo_converges_in_few_newton_iterations):
    // 4 corrections measured, 5 leaving one for a switch of branch; 3.2e-4 rad left to the
    // integral's slow pole after 3 s: 1e-3.
    assert!(most <= 5, "{most} iterations");
    assert!((theta - 1.0).abs() < 1e-3, "{theta}");
}

/// The arm of a driven stop: the fixture pendulum without gravity (I = 1.01 kg m^2 about the
/// hinge) pushed by a constant 10 N m from rest at 0 onto an upper stop at 0.5 rad of
/// stiffness `k` (no damping), with an energy-balance sensor.
fn driven_arm(k: f64) -> Model {
    let (mut m, j) = pendulum(1.0, 1.0, 0.01);
    m.gravity = nalgebra::Vector3::zeros();
    m.actuators.push(JointActuator {
        name: "motor".into(),
        joint: j,
        coordinate: 0,
        effort: Effort::Time(TimeFunction::constant(10.0)),
    });
    m.joint_limits.push(JointLimit {
        name: "end stop".into(),
        joint: j,
        coordinate: 0,
        lower: None,
        upper: Some(0.5),
        stiffness: k,
        damping: 0.0,
    });
    m.add_sensor(
        "theta",
        SensorKind::JointCoordinate {
            joint: j,
            coordinate: 0,
        },
    );
    m.add_sensor("energy", SensorKind::EnergyBalance);
    m
}

/// The largest excess of the energy over the work put in, (T + U - W_in) / max W_in, over a
/// run's rows, and the largest work.
fn energy_excess(sensors: &mbs::SensorRecord) -> (f64, f64) {
    let col = |c: usize| sensors.column("energy", c).unwrap();
    let (work, kinetic, strain) = (col(0), col(3), col(4));
    let most = work.iter().copied().fold(0.0, f64::max);
    let excess = (0..work.len())
        .map(|i| kinetic[i] + strain[i] - work[i])
        .fold(f64::MIN, f64::max);
    (excess / most, most)
}

#[test]
fn a_driven_arm_hitting_a_stop_gets_no_more_energy_than_was_put_in() {
    // The arm reaches the stop at 0.32 s with the 5 J the motor put in, bounces back to rest
    // at 0 and again (no damping: the exact energy T + U equals the motor's work throughout).
    // Fixed steps of 1 ms retried down to 1e-9 s, so that every step in contact has
    // omega h <= 0.1: T + U exceeds the work by at most 0.15 % of it for k = 1e4 ... 1e12
    // (without the stop control: 20 % at 1e6, 116 % at 1e8, 110 % at 1e10, and Newton fails
    // at 1e12). Required: 0.5 %. Bound: a step entering the stop stores at most
    // (omega h)^2 = 1 % of the impact's kinetic energy that the exact motion does not
    // (STOP_RESOLUTION); the contact's other steps, some 30 of them, add generalized-alpha's
    // second-order energy error. 0.5 % lies between the 0.15 % measured and that 1 %.
    for k in [1e4, 1e6, 1e8, 1e10, 1e12] {
        let sys = System::new(&driven_arm(k)).unwrap();
        let settings = DynamicSettings::new(1e-3, 1.0, 0.9);
        let run = solve_dynamic_retrying(&sys, sys.initial_state(), &settings, 1e-9).unwrap();
        let tr = &run.trajectory;
        let (excess, work) = energy_excess(&tr.sensors);
        let highest = tr
            .sensors
            .column("theta", 0)
            .unwrap()
            .into_iter()
            .fold(f64::MIN, f64::max);
        let unchecked = solve_dynamic(&sys, sys.initial_state(), &settings)
            .map(|t| energy_excess(&t.sensors).0)
            .unwrap_or(f64::NAN);
        eprintln!(
            "k = {k:e}: (T + U - W) / W_max at most {excess:.2e} (W_max {work:.4} J), highest {highest:.6} rad, {} steps; without the stop control {unchecked:.3e}",
            tr.iterations.len()
        );
        assert!(excess < 5e-3, "k = {k:e}: {excess}");
        // The deepest penetration d solves k d^2 / 2 = 10 (0.5 + d) (the push's work): just
        // above sqrt(2 5 / k) (3 % above at k = 1e4, where the push's work over d counts), and
        // the 0.5 % energy excess allowed deepens it by 0.25 %. Twice sqrt(2 5 / k) bounds both;
        // 1e-6 rad is slack. (The stiffest stops, k >= 1e10, penetrate 30 micro-radians and
        // less for less than a recorded 1 ms step: their rows stay below 0.5 rad.)
        assert!(
            highest < 0.5 + 2.0 * (2.0 * 5.0 / k).sqrt() + 1e-6,
            "k = {k:e}: {highest}"
        );
    }
}

#[test]
fn a_stop_no_step_resolves_is_refused_before_the_first_step() {
    // k = 1e300 on 1.01 kg m^2 rings at 1e150 rad/s: steps of 1e-151 s would resolve it.
    let sys = System::new(&driven_arm(1e300)).unwrap();
    let settings = DynamicSettings::new(1e-3, 1.0, 0.9);
    let failure = solve_dynamic_retrying(&sys, sys.initial_state(), &settings, 1e-6).unwrap_err();
    let message = failure.error.to_string();
    eprintln!("{message}");
    assert!(
        matches!(failure.error, SolveError::UnresolvableLimit { .. }),
        "{message}"
    );
    assert!(
        message.contains("'end stop'")
            && message.contains("'hinge'")
            && message.contains("1e300")
            && message.contains("e149"),
        "{message}"
    );
    assert_eq!(failure.partial.trajectory.iterations.len(), 0);
    // 1e12 needs steps of 1e-7 s: refused with a smallest step of 1e-6 s, taken with 1e-8 s.
    let sys = System::new(&driven_arm(1e12)).unwrap();
    let failure = solve_dynamic_retrying(&sys, sys.initial_state(), &settings, 1e-6).unwrap_err();
    assert!(
        matches!(failure.error, SolveError::UnresolvableLimit { .. }),
        "{}",
        failure.error
    );
}
