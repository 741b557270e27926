//! The consistent start (`mbs::System::initial_state`): the initial position assembly of
//! closed loops at the drivers' and initial values, and the velocity analysis that solves the
//! loops' rates from the drivers' and initial rates, against central differences of the
//! position assembly, hand-computed rigid-body velocities and contradicting rates.

use crate::fixtures::{pendulum, slider_crank};
use mbs::{BodyId, InitialCondition, JointId, ModelError, SensorKind, System, TimeFunction};
use nalgebra::Vector3;
use reduction::ModeSelection;

/// The planar slider-crank (two rod segments) with its crank driven at `speed` from `initial`
/// rad and no initial conditions: the start is the drivers' alone.
fn driven_only(initial: f64, speed: f64) -> System {
    let (mut m, _, _) = slider_crank(2, ModeSelection::Count(1), speed);
    m.initial.clear();
    m.drivers[0].motion = TimeFunction::Linear { initial, rate: speed };
    m.add_sensor("strain", SensorKind::StrainEnergy);
    System::new(&m).unwrap()
}

/// A crank driven from 0.4 rad at 10 rad/s closes its loop through the flexible rod: the
/// start assembles the loop at 0.4 rad (the rod unstrained) and its rates are the derivative of
/// the assembly along the driver: the assembled configurations at the driver's value of
/// t = -h and t = +h, differenced centrally, give the solved rates of every unknown.
#[test]
fn velocity_analysis_is_the_derivative_of_the_position_assembly() {
    let (theta, speed, h) = (0.4, 10.0, 1e-5);
    let sys = driven_only(theta, speed);
    let s = sys.initial_state();
    let e = sys.energies(&s).unwrap();
    // Round-off of the assembly (1e-13 m on 0.3 m segments) in EA/L ~ 2e7 N/m.
    assert!(e.strain.abs() < 1e-12, "strain energy at the start {}", e.strain);
    assert!(!sys.start_report().assembled.is_empty() && !sys.start_report().solved.is_empty());
    let minus = driven_only(theta - h * speed, speed).initial_state();
    let plus = driven_only(theta + h * speed, speed).initial_state();
    let dq = sys.difference(&plus, &minus);
    let v = s.velocity();
    let vmax = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(vmax > 1.0, "the loop moves: {v:?}");
    for (k, label) in sys.dof_labels().iter().enumerate() {
        let fd = dq[k] / (2.0 * h);
        // Central differences: error h^2 q''' ~ 1e-10 * 1e3, and the assembly's 1e-13 / h.
        assert!(
            (fd - v[k]).abs() < 1e-6 * vmax,
            "{label}: rate {} vs central difference {fd}",
            v[k]
        );
    }
}

/// The driver's rate alone gives the hand-computed rigid-body velocities at the dead centre
/// (the rod turning about B at -speed * crank / rod): the same start as the fixture's
/// hand-given initial conditions, which the analysis accepts as consistent and leaves as they
/// are.
#[test]
fn the_drivers_rate_alone_gives_the_hand_computed_start() {
    let speed = 150.0;
    let (hand, _, [ja, jb]) = slider_crank(2, ModeSelection::Count(1), speed);
    let given = System::new(&hand).unwrap().initial_state();
    let solved = driven_only(0.0, speed);
    let s = solved.initial_state();
    let w_rod = -speed * 0.15 / 0.3;
    assert!((solved.joint_rate(&s, ja, 0) - (w_rod - speed)).abs() < 1e-9 * speed);
    assert!((solved.joint_rate(&s, jb, 0) - w_rod).abs() < 1e-9 * speed);
    let diff = s
        .velocity()
        .iter()
        .zip(given.velocity())
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff < 1e-9 * speed, "largest difference of rates {diff}");
}

/// Rates for two coordinates of the one-dof loop: consistent ones are accepted as given,
/// contradicting ones are refused naming both (and the driver, whose rate is a third).
#[test]
fn an_over_determined_start_is_refused_naming_the_coordinates() {
    let (mut m, _, [ja, jb]) = slider_crank(2, ModeSelection::Count(1), 10.0);
    m.initial.clear();
    m.drivers[0].motion = TimeFunction::Constant { value: 0.0 };
    let w_rod = -10.0 * 0.15 / 0.3;
    let rate = |joint: JointId, rate: f64| InitialCondition::JointRate {
        joint,
        coordinate: 0,
        rate,
    };
    // The crank held: pin B turning the rod about A is the loop's one motion, pin A follows.
    m.initial.push(rate(jb, w_rod));
    m.initial.push(rate(ja, 0.0));
    let e = System::new(&m).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("joint 'pin A'") && msg.contains("joint 'pin B'") && msg.contains("over-determined"),
        "{msg}"
    );
    assert!(matches!(e, ModelError::InvalidValue { .. }));
    // With the crank turning, pin A at w_rod - speed and pin B at w_rod agree with it.
    m.drivers[0].motion = TimeFunction::Linear {
        initial: 0.0,
        rate: 10.0,
    };
    m.initial = vec![rate(jb, w_rod), rate(ja, w_rod - 10.0)];
    let sys = System::new(&m).unwrap();
    let s = sys.initial_state();
    assert!((sys.joint_rate(&s, ja, 0) - (w_rod - 10.0)).abs() < 1e-12);
    assert!((sys.joint_rate(&s, jb, 0) - w_rod).abs() < 1e-12);
    // A third rate that contradicts names the driver too.
    m.initial[1] = rate(ja, 1.0);
    let msg = System::new(&m).unwrap_err().to_string();
    assert!(
        msg.contains("driver 'crank angle'") && msg.contains("joint 'pin A'"),
        "{msg}"
    );
}

/// A joint value in a closed loop is assembled (the rod unstrained) and the velocity of a body
/// held by the ground is a condition that solves its joint's rate.
#[test]
fn a_loop_joint_value_is_assembled_and_a_held_body_velocity_solves_its_joint() {
    let (mut m, _, [ja, _]) = slider_crank(2, ModeSelection::Count(1), 10.0);
    m.initial.clear();
    m.drivers[0].motion = TimeFunction::Constant { value: 0.0 };
    m.initial.push(InitialCondition::JointValue {
        joint: ja,
        coordinate: 0,
        value: 0.1,
    });
    // The crank held and pin A at 0.1: no position of the loop has it (the rod's ends are
    // 0.3 m apart along a slider line through the crank's tip): refused, not strained.
    let e = System::new(&m).unwrap_err().to_string();
    assert!(e.contains("cannot be assembled"), "{e}");
    let (mut m, j) = pendulum(1.0, 1.0, 0.01);
    m.initial.push(InitialCondition::BodyVelocity {
        body: BodyId(0),
        velocity: Vector3::zeros(),
        angular_velocity: Vector3::z() * 2.0,
        point: Vector3::zeros(),
    });
    let sys = System::new(&m).unwrap();
    let s = sys.initial_state();
    assert!((sys.joint_rate(&s, j, 0) - 2.0).abs() < 1e-12);
}
