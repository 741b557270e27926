//! The `acceleration`, `angular-acceleration` and `energy-balance` sensors of a study file:
//! their columns, the pendulum's accelerations from its own angle and rate, a constant-speed
//! crank's centripetal acceleration, zero in an equilibrium, and the balance of a driven,
//! damped pendulum whose sensors are written every few steps.

use crate::common::{dynamic, equilibrium, gravity, pendulum, sensor};
use crate::setup::column;
use study::output::observer::Recorder;

const G: f64 = 9.81;
/// The pendulum of `common::pendulum`: m = 1 kg, centre of mass 1 m below the pivot,
/// I_O = 1.01 kg m^2; the sensed point `bob.P` is `L` below the pivot.
const I_O: f64 = 1.01;
const L: f64 = 1.2;

/// `text` run in memory in a scratch folder `name` (`setup::run`); the recorder (a failure
/// panics with its message).
fn run(name: &str, text: &str) -> Recorder {
    let (rec, summary, _) = crate::setup::run(name, text);
    if let Err(e) = summary {
        panic!("{e}");
    }
    rec
}

/// The pendulum with a point `P` at `L` below the pivot and sensors of its angle and rate, the
/// accelerations of `P` in global and body axes, and the energy balance.
fn sensed_pendulum() -> String {
    pendulum(&[("P", [0.0, -L, 0.0])])
        + &sensor("angle", "joint", "pivot")
        + &sensor("rate", "joint-rate", "pivot")
        + &sensor("acc", "acceleration", "bob.P")
        + &sensor("acc-body", "acceleration", "bob.P")
        + "axes = \"body\"\n"
        + &sensor("alpha", "angular-acceleration", "bob.P")
        + "[[sensors]]\nname = \"balance\"\ntype = \"energy-balance\"\n"
}

#[test]
fn the_sensors_write_their_columns_with_units() {
    let text = sensed_pendulum() + &gravity("weight", [0.0, -G, 0.0]) + &dynamic("0.05", "0.01");
    let rec = run("accel-columns", &text);
    let sensors = rec.analysis("dynamic").unwrap().sensors.as_ref().unwrap();
    let columns = |name: &str| {
        let g = sensors.groups.iter().find(|g| g.name == name).unwrap();
        g.columns.join(", ")
    };
    assert_eq!(
        columns("acc"),
        "acceleration_x [m/s^2], acceleration_y [m/s^2], acceleration_z [m/s^2]"
    );
    assert_eq!(
        columns("alpha"),
        "angular_acceleration_x [rad/s^2], angular_acceleration_y [rad/s^2], angular_acceleration_z [rad/s^2]"
    );
    assert_eq!(
        columns("balance"),
        "work_actuators [J], work_drivers [J], work_loads [J], kinetic [J], strain [J], gravity potential [J], dissipated [J], balance_error [J]"
    );
}

#[test]
fn a_pendulum_in_a_study_has_the_accelerations_of_its_angle_and_rate() {
    let text = sensed_pendulum()
        + &gravity("weight", [0.0, -G, 0.0])
        + "[[initial]]\njoint = \"pivot\"\nvalue = 1.0\n"
        + &dynamic("1.0", "0.005");
    let rec = run("accel-pendulum", &text);
    let (theta, rate) = (column(&rec, "dynamic", "angle", 0), column(&rec, "dynamic", "rate", 0));
    let acc: Vec<Vec<f64>> = (0..3).map(|c| column(&rec, "dynamic", "acc", c)).collect();
    let body: Vec<Vec<f64>> = (0..2).map(|c| column(&rec, "dynamic", "acc-body", c)).collect();
    let alpha = column(&rec, "dynamic", "alpha", 2);
    let error = column(&rec, "dynamic", "balance", 7);
    let scale = L * G / I_O;
    for k in 0..theta.len() {
        let (th, w) = (theta[k], rate[k]);
        let thdd = -G / I_O * th.sin();
        // Tangent (cos, sin) times L theta'', normal (-sin, cos) towards the pivot times L w^2.
        let (at, an) = (L * thdd, L * w * w);
        let exact = [at * th.cos() - an * th.sin(), at * th.sin() + an * th.cos(), 0.0];
        for c in 0..3 {
            assert!(
                (acc[c][k] - exact[c]).abs() <= 1e-6 * scale,
                "{k} {c}: {} vs {}",
                acc[c][k],
                exact[c]
            );
        }
        assert!((body[0][k] - at).abs() <= 1e-6 * scale && (body[1][k] - an).abs() <= 1e-6 * scale);
        assert!((alpha[k] - thdd).abs() <= 1e-6 * G / I_O);
    }
    // A conservative pendulum: the balance error is generalized-alpha's energy error, O(h^2).
    let worst = error.iter().map(|e| e.abs()).fold(0.0, f64::max);
    eprintln!("study pendulum: largest |balance error| {worst:.3e} J (m g d = {G} J)");
    assert!(worst < 1e-3 * G, "{worst}");
}

#[test]
fn an_equilibrium_has_no_acceleration_and_no_balance_error() {
    let text = sensed_pendulum() + &gravity("weight", [0.0, -G, 0.0]) + &equilibrium("rest", "1e-10");
    let rec = run("accel-equilibrium", &text);
    for (name, n) in [("acc", 3), ("acc-body", 3), ("alpha", 3)] {
        for c in 0..n {
            assert!(column(&rec, "rest", name, c).iter().all(|x| *x == 0.0), "{name} {c}");
        }
    }
    assert!(column(&rec, "rest", "balance", 7).iter().all(|x| *x == 0.0));
}

#[test]
fn a_constant_speed_crank_has_the_centripetal_acceleration() {
    let w = 2.0;
    let text = sensed_pendulum()
        + &format!(
            "[[drivers]]\nname = \"spin\"\njoint = \"pivot\"\nfunction = {{ type = \"constant-speed\", speed = {w:?} }}\n"
        )
        + &dynamic("1.0", "0.01");
    let rec = run("accel-crank", &text);
    let (ax, ay) = (column(&rec, "dynamic", "acc", 0), column(&rec, "dynamic", "acc", 1));
    for k in 0..ax.len() {
        let a = (ax[k] * ax[k] + ay[k] * ay[k]).sqrt();
        assert!((a - w * w * L).abs() <= 1e-12 * w * w * L, "{a}");
    }
    // No gravity: the driver keeps the kinetic energy; no work once it turns steadily.
    let work = column(&rec, "dynamic", "balance", 1);
    assert!(work.iter().all(|x| x.abs() <= 1e-12), "{work:?}");
}

#[test]
fn a_driven_damped_pendulum_balances_in_a_study_written_every_few_steps() {
    // The work integrates every step although rows are written every 5th: halving the step
    // divides the balance error by about 4 (second order).
    let error = |dt: &str| {
        let text = sensed_pendulum()
            + &gravity("weight", [0.0, -G, 0.0])
            + "[[actuators]]\nname = \"motor\"\njoint = \"pivot\"\n\
               function = { type = \"harmonic\", offset = 2.0, amplitude = 3.0, frequency_hz = 0.6 }\n\
               [[joint_springs]]\nname = \"damper\"\njoint = \"pivot\"\nstiffness = 0.0\ndamping = 0.4\n\
               [output]\nevery = 5\n"
            + &dynamic("2.0", dt);
        let rec = run(&format!("balance-{dt}"), &text);
        let col = |c| column(&rec, "dynamic", "balance", c);
        let (work, dissipated, error) = (col(0), col(6), col(7));
        let put_in = *work.last().unwrap();
        assert!(put_in > 1.0 && *dissipated.last().unwrap() > 0.1, "{put_in}");
        error.iter().map(|e| e.abs()).fold(0.0, f64::max) / put_in
    };
    let (coarse, fine) = (error("0.01"), error("0.005"));
    eprintln!("study driven pendulum: |balance error| / work {coarse:.3e} (dt 0.01), {fine:.3e} (dt 0.005)");
    assert!(coarse < 1e-2 && fine < 0.35 * coarse, "{coarse} {fine}");
}

#[test]
fn a_wrong_axes_value_is_refused_at_its_key() {
    let text = sensed_pendulum().replace("axes = \"body\"", "axes = \"node\"") + &dynamic("0.05", "0.01");
    let dir = crate::scratch("accel-axes");
    let file = dir.join("axes.toml");
    std::fs::write(&file, text).unwrap();
    let e = study::load(&file).unwrap_err().to_string();
    assert!(e.contains("sensors[3].axes") && e.contains("global"), "{e}");
}
