//! The acceleration sensors against analytic motions (uniform circular motion, the rigid
//! pendulum from its own angle and rate) and against the velocity sensor (central differences,
//! the trapezoidal rule's increments on a flexible node), and the energy-balance sensor on a
//! conservative pendulum, on driven, loaded and damped ones and on the flexible slider-crank.

use mbs::{
    solve_dynamic, solve_static, DriverTarget, DynamicSettings, Effort, InitialCondition, JointActuator, JointId,
    JointKind, JointSpring, Model, NodeId, SensorAxes, SensorKind, StaticSettings, Support, System, TimeFunction,
    Trajectory,
};
use models::rigid;
use nalgebra::Vector3;

const G: f64 = 9.81;
/// Pendulum: mass, distance of the centre of mass from the hinge, inertia about it, and the
/// distance of the sensed point ("tip") from the hinge.
const M: f64 = 1.0;
const D: f64 = 1.0;
const I_G: f64 = 0.01;
const L: f64 = 1.2;

/// A rigid pendulum on a revolute joint about z at the origin, hanging along -y, with a point
/// "tip" of the body at distance `L` from the hinge; sensors of the joint angle and rate and
/// of the tip's motion. Gravity `g` along -y.
fn pendulum(g: f64) -> (Model, JointId, NodeId) {
    let mut model = Model::new("pendulum");
    let ground = model.add_node("ground", Vector3::zeros());
    let hinge = model.add_node("hinge", Vector3::zeros());
    let tip = model.add_node("tip", Vector3::new(0.0, -L, 0.0));
    model.add_support(Support::clamp(ground));
    let j = model.add_joint("hinge", ground, hinge, JointKind::Revolute { axis: Vector3::z() });
    model.add_rigid_body(rigid(
        "bob",
        hinge,
        vec![tip],
        M,
        Vector3::new(0.0, -D, 0.0),
        [I_G, I_G, I_G],
    ));
    model.gravity = Vector3::new(0.0, -g, 0.0);
    let (joint, coordinate) = (j, 0);
    model.add_sensor("theta", SensorKind::JointCoordinate { joint, coordinate });
    model.add_sensor("rate", SensorKind::JointRate { joint, coordinate });
    model.add_sensor("v", SensorKind::NodeVelocity { node: tip });
    let axes = SensorAxes::Global;
    model.add_sensor("a", SensorKind::NodeAcceleration { node: tip, axes });
    model.add_sensor("alpha", SensorKind::NodeAngularAcceleration { node: tip, axes });
    let axes = SensorAxes::Node;
    model.add_sensor("a body", SensorKind::NodeAcceleration { node: tip, axes });
    model.add_sensor("alpha body", SensorKind::NodeAngularAcceleration { node: tip, axes });
    (model, j, tip)
}

fn run(model: &Model, h: f64, end: f64, rho: f64) -> Trajectory {
    let sys = System::new(model).unwrap();
    let mut settings = DynamicSettings::new(h, end, rho);
    settings.tolerance = 1e-12;
    solve_dynamic(&sys, sys.initial_state(), &settings).unwrap()
}

fn released(model: &mut Model, j: JointId, theta0: f64) {
    model.initial.push(InitialCondition::JointValue {
        joint: j,
        coordinate: 0,
        value: theta0,
    });
}

/// The tangential and normal unit vectors of the tip at angle `theta` (tangent along
/// increasing theta, normal towards the hinge).
fn frame(theta: f64) -> (Vector3<f64>, Vector3<f64>) {
    (
        Vector3::new(theta.cos(), theta.sin(), 0.0),
        Vector3::new(-theta.sin(), theta.cos(), 0.0),
    )
}

fn vec3(x: &[f64]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

#[test]
fn uniform_circular_motion_is_centripetal() {
    // Driven at constant rate w, no gravity: a = -w^2 r towards the hinge, alpha = 0.
    let (mut model, j, _) = pendulum(0.0);
    let w = 3.0;
    model.add_driver(
        "spin",
        DriverTarget::Joint {
            joint: j,
            coordinate: 0,
        },
        TimeFunction::Linear { initial: 0.0, rate: w },
    );
    let traj = run(&model, 0.01, 1.0, 0.8);
    let s = &traj.sensors;
    let (a, alpha, ab) = (
        s.series("a").unwrap(),
        s.series("alpha").unwrap(),
        s.series("a body").unwrap(),
    );
    for (k, t) in s.times.iter().enumerate() {
        let (_, n) = frame(w * t);
        let exact = n * (w * w * L);
        let err = (vec3(&a[k]) - exact).norm();
        assert!(err <= 1e-12 * w * w * L, "t = {t}: a = {:?}, exact {exact:?}", a[k]);
        assert!(vec3(&alpha[k]).norm() <= 1e-12, "t = {t}: alpha = {:?}", alpha[k]);
        // In the body's axes the centripetal acceleration is fixed: along +y (towards the hinge).
        let body = Vector3::new(0.0, w * w * L, 0.0);
        assert!(
            (vec3(&ab[k]) - body).norm() <= 1e-12 * w * w * L,
            "t = {t}: {:?}",
            ab[k]
        );
    }
}

#[test]
fn pendulum_accelerations_follow_its_angle_and_rate() {
    // theta'' = -(m g d / I_O) sin(theta): a_t = L theta'', a_n = L theta'^2, alpha_z = theta''.
    let (mut model, j, _) = pendulum(G);
    released(&mut model, j, 1.2);
    let traj = run(&model, 0.005, 2.0, 0.8);
    let s = &traj.sensors;
    let (theta, rate) = (s.column("theta", 0).unwrap(), s.column("rate", 0).unwrap());
    let (a, alpha) = (s.series("a").unwrap(), s.series("alpha").unwrap());
    let (ab, alb) = (s.series("a body").unwrap(), s.series("alpha body").unwrap());
    let i_o = I_G + M * D * D;
    let mut worst: f64 = 0.0;
    for k in 0..s.times.len() {
        let thdd = -M * G * D / i_o * theta[k].sin();
        let (et, en) = frame(theta[k]);
        let exact = et * (L * thdd) + en * (L * rate[k] * rate[k]);
        let scale = L * (M * G * D / i_o).max(rate[k] * rate[k]);
        let rel = (vec3(&a[k]) - exact).norm() / scale;
        worst = worst.max(rel);
        assert!(rel <= 1e-6, "t = {}: a = {:?}, exact {exact:?}", s.times[k], a[k]);
        let alpha_exact = Vector3::new(0.0, 0.0, thdd);
        assert!((vec3(&alpha[k]) - alpha_exact).norm() <= 1e-6 * M * G * D / i_o);
        // Body axes turn with theta about z: the tangent is their x, the normal their y.
        let body = Vector3::new(L * thdd, L * rate[k] * rate[k], 0.0);
        assert!((vec3(&ab[k]) - body).norm() <= 1e-6 * scale, "t = {}", s.times[k]);
        assert!((vec3(&alb[k]) - alpha_exact).norm() <= 1e-6 * M * G * D / i_o);
    }
    eprintln!("pendulum: largest relative acceleration error {worst:.2e}");
}

#[test]
fn acceleration_is_the_rate_of_the_velocity_sensor() {
    // Central differences of the recorded velocities over small steps: O(h^2) from the sensor.
    let (mut model, j, _) = pendulum(G);
    released(&mut model, j, 1.0);
    let h = 1e-4;
    let traj = run(&model, h, 0.3, 1.0);
    let s = &traj.sensors;
    let (v, a) = (s.series("v").unwrap(), s.series("a").unwrap());
    let mut worst: f64 = 0.0;
    for k in 1..s.times.len() - 1 {
        let fd = (vec3(&v[k + 1]) - vec3(&v[k - 1])) / (s.times[k + 1] - s.times[k - 1]);
        let rel = (fd - vec3(&a[k])).norm() / vec3(&a[k]).norm().max(1.0);
        worst = worst.max(rel);
    }
    eprintln!("central differences of v against a: largest relative difference {worst:.2e}");
    // The velocities of the trapezoidal rule (rho_inf = 1) are exact to O(h^2) = 1e-8.
    assert!(worst < 1e-6, "{worst}");
}

#[test]
fn a_static_state_has_no_acceleration() {
    let (mut model, j, _) = pendulum(G);
    released(&mut model, j, 0.3);
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap();
    for name in ["a", "alpha", "a body", "alpha body"] {
        let last = sol.sensors.series(name).unwrap().pop().unwrap();
        assert!(last.iter().all(|x| *x == 0.0), "{name}: {last:?}");
    }
}

/// The energy-balance columns of a run: (work of actuators, drivers, loads, T, U, V,
/// dissipated, error) at each row.
fn balance(traj: &Trajectory) -> Vec<Vec<f64>> {
    traj.sensors.series("balance").unwrap()
}

#[test]
fn a_free_pendulum_conserves_its_energy() {
    let (mut model, j, _) = pendulum(G);
    released(&mut model, j, 1.5);
    model.add_sensor("balance", SensorKind::EnergyBalance);
    let error = |h: f64| {
        let rows = balance(&run(&model, h, 2.0, 1.0));
        let e0 = rows[0][3] + rows[0][4] + rows[0][5];
        for r in &rows {
            // No actuator, driver, load or damper: no work, nothing dissipated.
            assert_eq!([r[0], r[1], r[2], r[6]], [0.0; 4]);
            // The error is the change of T + U + V.
            assert!((r[7] - (r[3] + r[4] + r[5] - e0)).abs() <= 1e-12 * e0.abs().max(1.0));
        }
        rows.iter().map(|r| r[7].abs()).fold(0.0, f64::max) / (M * G * D)
    };
    let (coarse, fine) = (error(0.01), error(0.005));
    eprintln!("free pendulum: largest |E - E0| / (m g d) {coarse:.2e} (h = 0.01), {fine:.2e} (h = 0.005)");
    // The trapezoidal rule (rho_inf = 1) keeps a pendulum's energy to O(h^2), bounded.
    assert!(coarse < 1e-3 && fine < 0.3 * coarse, "{coarse} {fine}");
}

/// A pendulum driven by a torque actuator `u(t)`, damped by a torsional damper, pushed by a
/// dead force at the tip, all through the energy balance (as `run`).
fn driven_pendulum(h: f64) -> Vec<Vec<f64>> {
    let (mut model, j, tip) = pendulum(G);
    model.actuators.push(JointActuator {
        name: "motor".into(),
        joint: j,
        coordinate: 0,
        effort: Effort::Time(TimeFunction::Sine {
            offset: 2.0,
            amplitude: 3.0,
            omega: 4.0,
            phase: 0.0,
        }),
    });
    model.joint_springs.push(JointSpring {
        joint: j,
        coordinate: 0,
        stiffness: 0.0,
        damping: 0.4,
        rest: 0.0,
        preload: 0.0,
    });
    model.add_dead_force(tip, Vector3::new(1.5, 0.0, 0.0));
    model.add_sensor("balance", SensorKind::EnergyBalance);
    balance(&run(&model, h, 2.0, 0.9))
}

#[test]
fn a_driven_damped_pendulum_balances_work_and_energy() {
    let errors: Vec<(f64, f64)> = [0.01, 0.005, 0.0025]
        .iter()
        .map(|&h| {
            let rows = driven_pendulum(h);
            let last = rows.last().unwrap();
            let put_in = last[0].abs() + last[2].abs();
            assert!(
                last[0] > 1.0 && last[6] > 0.1,
                "work {} dissipated {}",
                last[0],
                last[6]
            );
            assert!(
                last[2].abs() > 0.1 && last[1] == 0.0,
                "loads {} drivers {}",
                last[2],
                last[1]
            );
            let worst = rows.iter().map(|r| r[7].abs()).fold(0.0, f64::max);
            (h, worst / put_in)
        })
        .collect();
    eprintln!("driven pendulum: (h, largest |balance error| / work put in) {errors:?}");
    // Generalized-alpha and the trapezoid rule of the powers are both second order: the
    // error falls by about 4 per halving.
    assert!(errors[0].1 < 1e-2, "{errors:?}");
    for w in errors.windows(2) {
        assert!(w[1].1 < 0.35 * w[0].1, "{errors:?}");
    }
}

#[test]
fn a_driver_puts_in_the_energy_it_gives() {
    // A prescribed swing: no unknowns, the driver's effort is exact at each step, so the
    // balance error is the trapezoid rule's on the driver's power alone, O(h^2).
    let errors: Vec<f64> = [0.01, 0.005]
        .iter()
        .map(|&h| {
            let (mut model, j, _) = pendulum(G);
            model.add_driver(
                "swing",
                DriverTarget::Joint {
                    joint: j,
                    coordinate: 0,
                },
                TimeFunction::Sine {
                    offset: 0.0,
                    amplitude: 0.8,
                    omega: 2.5,
                    phase: 0.3,
                },
            );
            model.add_sensor("balance", SensorKind::EnergyBalance);
            let rows = balance(&run(&model, h, 1.0, 0.8));
            let scale = rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
            assert!(scale > 0.5, "driver work {scale}");
            rows.iter().map(|r| r[7].abs()).fold(0.0, f64::max) / scale
        })
        .collect();
    eprintln!("driven swing: largest |balance error| / driver work {errors:?}");
    assert!(errors[0] < 1e-3 && errors[1] < 0.3 * errors[0], "{errors:?}");
}

/// The flexible slider-crank of validation problem C2 (rod of two superelements with two
/// modes, crank spun up to 150 rad/s) with the energy balance and the velocity and
/// acceleration of the rod's midpoint, a node of both superelements.
fn flexible_slider_crank(steps_per_turn: f64, turns: f64, rho: f64) -> Trajectory {
    let speed = 150.0;
    let (mut model, rod, _) = crate::fixtures::slider_crank(2, reduction::ModeSelection::Count(2), speed);
    let axes = SensorAxes::Global;
    model.add_sensor("v", SensorKind::NodeVelocity { node: rod[1] });
    model.add_sensor("a", SensorKind::NodeAcceleration { node: rod[1], axes });
    model.add_sensor("balance", SensorKind::EnergyBalance);
    let period = 2.0 * std::f64::consts::PI / speed;
    run(&model, period / steps_per_turn, turns * period, rho)
}

#[test]
fn a_flexible_node_acceleration_is_the_rate_of_its_velocity() {
    // At rho_inf = 1 generalized-alpha is the trapezoidal rule with true accelerations,
    // v_{n+1} - v_n = h (a_n + a_{n+1}) / 2 for a node's absolute translation: the sensor's
    // accelerations are the ones the velocities were integrated with. (Central differences of
    // v would differ by O((h w)^2) of the rod's fast axial vibration.)
    let traj = flexible_slider_crank(2000.0, 0.2, 1.0);
    let s = &traj.sensors;
    let (v, a) = (s.series("v").unwrap(), s.series("a").unwrap());
    let scale = a.iter().map(|x| vec3(x).norm()).fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for k in 0..s.times.len() - 1 {
        let h = s.times[k + 1] - s.times[k];
        let rate = (vec3(&v[k + 1]) - vec3(&v[k])) / h;
        worst = worst.max((rate - (vec3(&a[k]) + vec3(&a[k + 1])) * 0.5).norm() / scale);
    }
    eprintln!("flexible midpoint: velocity increments against the mean accelerations within {worst:.2e} of the largest |a| {scale:.3e}");
    assert!(scale > 100.0 && worst < 1e-6, "{worst} {scale}");
}

#[test]
fn a_flexible_slider_crank_balances_the_drivers_work() {
    let errors: Vec<f64> = [200.0, 400.0]
        .iter()
        .map(|&n| {
            let rows = balance(&flexible_slider_crank(n, 1.0, 1.0));
            let work = rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
            let strain = rows.iter().map(|r| r[4]).fold(0.0, f64::max);
            assert!(work > 1.0 && strain > 0.0, "driver work {work}, strain {strain}");
            rows.iter().map(|r| r[7].abs()).fold(0.0, f64::max) / work
        })
        .collect();
    eprintln!("flexible slider-crank: largest |balance error| / driver work {errors:?}");
    assert!(errors[0] < 1e-2 && errors[1] < 0.35 * errors[0], "{errors:?}");
}
