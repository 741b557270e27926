//! A force law of a run (`study::ForceLawSource`) on the shared study
//! `tests/studies/flexible_double_pendulum.toml`: an elbow damper written as a force law
//! gives the motion of the study's PID (kd = 1), through `run_selected_with` and through a
//! `Simulation`; names that are neither actuator nor point load, or joints that do not exist,
//! are refused with the names there are. (The Python package runs the same study through
//! its `ForceLaw`, crates/python/tests/test_force_law.py.) A PD on the height of a rigid
//! link's tip read from its position sensor (and from its velocity sensor) moves the link
//! as the same PD written on the joint angle; sensors a law cannot read are refused.

use mbs::force_law::{ForceLaw, LawError, LawPorts};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use study::{ForceLawSource, Forces, Options, Recorder, Selection};

/// $u = -c\,\dot y$ on its one output from its one input.
#[derive(Debug)]
struct Damper {
    ports: LawPorts,
    c: f64,
}

impl ForceLaw for Damper {
    fn name(&self) -> &str {
        "damper"
    }
    fn ports(&self) -> &LawPorts {
        &self.ports
    }
    fn evaluate(&self, _t: f64, _x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        u[0] = -self.c * xd[0];
        Ok(())
    }
}

/// The damper on `output`, reading `reads`.
#[derive(Debug)]
struct Source {
    output: String,
    reads: String,
}

impl ForceLawSource for Source {
    fn outputs(&self) -> Vec<String> {
        vec![self.output.clone()]
    }
    fn reads(&self) -> Option<Vec<String>> {
        Some(vec![self.reads.clone()])
    }
    fn law(&self, ports: LawPorts) -> Result<Arc<dyn ForceLaw>, study::BoxError> {
        Ok(Arc::new(Damper { ports, c: 1.0 }))
    }
}

fn forces(output: &str, reads: &str) -> Forces {
    Some(Arc::new(Source {
        output: output.into(),
        reads: reads.into(),
    }))
}

/// The study in a fresh folder (runs write beside it).
fn study(dir: &str) -> (study::Study, PathBuf) {
    let root = std::env::temp_dir().join(format!("flexmbs-force-law-{dir}-{}", std::process::id()));
    std::fs::create_dir_all(&root).unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/studies/flexible_double_pendulum.toml");
    let path = root.join("flexible_double_pendulum.toml");
    std::fs::copy(src, &path).unwrap();
    (study::load(&path).unwrap(), root)
}

/// The elbow angle of a 0.1 s run with `forces`.
fn elbow(st: &study::Study, root: &Path, forces: &Forces, out: &str) -> Vec<f64> {
    let options = Options {
        out: Some(root.join(out)),
        t_end: Some(0.1),
        ..Default::default()
    };
    let mut rec = Recorder::default();
    study::run_selected_with(st, &options, Selection::All, forces, &mut rec).unwrap();
    rec.analyses[0].sensors.as_ref().unwrap().column("elbow", 0).unwrap()
}

#[test]
fn a_damper_law_gives_the_pid_motion() {
    let (st, root) = study("pid");
    let pid = elbow(&st, &root, &None, "pid");
    let law = elbow(&st, &root, &forces("elbow-damper", "elbow"), "law");
    assert_eq!(pid.len(), law.len());
    let peak = pid.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = pid.iter().zip(&law).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    // The same equations to Newton's tolerance: only the iteration matrices differ (the law's
    // central differences against the PID's exact derivative), so each converged step may
    // differ by Newton's tolerance, 1e-9 of the force scale; over 100 steps at most ~1e-7 of
    // the motion's peak: 1e-6 of it.
    assert!(diff <= 1e-6 * peak, "law vs PID {diff:e} (peak {peak})");
    // A simulation stepped by hand with the law: the run's numbers, bit for bit (the same
    // steps of the same integrator on the same system).
    let options = Options {
        cache: Some(root.join(".flexmbs-cache")),
        ..Default::default()
    };
    let mut sim = study::Simulation::new_with(&st, "swing", &options, &forces("elbow-damper", "elbow")).unwrap();
    let mut stepped = vec![sim.sensor("elbow").unwrap()[0]];
    for _ in 0..100 {
        sim.step().unwrap();
        stepped.push(sim.sensor("elbow").unwrap()[0]);
    }
    assert_eq!(stepped, law);
    let _ = std::fs::remove_dir_all(root);
}

#[test]
fn names_that_are_not_there_are_refused_with_those_that_are() {
    let (st, root) = study("names");
    let options = Options {
        out: Some(root.join("out")),
        ..Default::default()
    };
    let mut rec = Recorder::default();
    let err = study::run_selected_with(&st, &options, Selection::All, &forces("wrist", "elbow"), &mut rec).unwrap_err();
    let err = study::error::chain(err.as_ref());
    assert!(err.contains("'wrist'") && err.contains("elbow-damper"), "{err}");
    let err =
        study::run_selected_with(&st, &options, Selection::All, &forces("elbow-damper", "knee"), &mut rec).unwrap_err();
    let err = study::error::chain(err.as_ref());
    assert!(err.contains("'knee'") && err.contains("shoulder"), "{err}");
    let _ = std::fs::remove_dir_all(root);
}

/// A rigid link of length `L` = 0.8 m (1 kg, its centre of mass halfway) on a pivot about z,
/// level at the start, released at 30 degrees under gravity, with an actuator on the pivot
/// (zero by itself) and the tip's position and velocity sensors.
const LINK: &str = r#"
[[rigid_bodies]]
name = "link"
mass = 1.0
center_of_mass = [0.4, 0.0, 0.0]
inertia = [[0.001, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.05]]
points = { O = [0.0, 0.0, 0.0], T = [0.8, 0.0, 0.0] }
[[joints]]
name = "pivot"
type = "revolute"
between = ["ground", "link.O"]
axis = [0.0, 0.0, 1.0]
[[actuators]]
name = "motor"
joint = "pivot"
function = { type = "constant-speed", speed = 0.0 }
[[loads]]
name = "weight"
type = "gravity"
g = [0.0, -9.81, 0.0]
[[initial]]
joint = "pivot"
value_deg = 30.0
[[sensors]]
name = "tip"
type = "position"
of = "link.T"
[[sensors]]
name = "tipv"
type = "velocity"
of = "link.T"
[[sensors]]
name = "angle"
type = "joint"
of = "pivot"
[[analyses]]
name = "hold"
type = "dynamic"
t_end = 0.5
dt = 1e-3
"#;

/// The link's length [m].
const L: f64 = 0.8;

/// Where the PD of [`TipPd`] reads the tip's height $y$ and its rate.
#[derive(Clone, Copy, Debug)]
enum Reading {
    /// The joint angle: $y = L\sin\theta$, $\dot y = L\cos\theta\,\dot\theta$.
    Angle,
    /// The position sensor `tip` (its three columns; `tip.position_y` the second), its rate
    /// the velocity.
    Position,
    /// `tip.position_y` and the velocity sensor's `tipv.velocity_y`.
    PositionAndVelocity,
}

/// $u = -k_p(y - y_r) - k_d\dot y$ on the tip's height, to $y_r$ = 0.1 m.
#[derive(Debug)]
struct TipPd {
    ports: LawPorts,
    reading: Reading,
}

impl ForceLaw for TipPd {
    fn name(&self) -> &str {
        "tip-pd"
    }
    fn ports(&self) -> &LawPorts {
        &self.ports
    }
    fn evaluate(&self, _t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        let (y, yd) = match self.reading {
            Reading::Angle => (L * x[0].sin(), L * x[0].cos() * xd[0]),
            Reading::Position => (x[1], xd[1]),
            Reading::PositionAndVelocity => (x[0], x[1]),
        };
        let (kp, kd, target) = (60.0, 4.0, 0.1);
        u[0] = -kp * (y - target) - kd * yd;
        Ok(())
    }
}

/// The PD on the motor, reading `reads`.
#[derive(Debug)]
struct PdSource {
    reads: Vec<String>,
    reading: Reading,
}

impl ForceLawSource for PdSource {
    fn outputs(&self) -> Vec<String> {
        vec!["motor".into()]
    }
    fn reads(&self) -> Option<Vec<String>> {
        Some(self.reads.clone())
    }
    fn law(&self, ports: LawPorts) -> Result<Arc<dyn ForceLaw>, study::BoxError> {
        Ok(Arc::new(TipPd {
            ports,
            reading: self.reading,
        }))
    }
}

fn pd(reads: &[&str], reading: Reading) -> Forces {
    Some(Arc::new(PdSource {
        reads: reads.iter().map(|r| r.to_string()).collect(),
        reading,
    }))
}

/// The link's study in a fresh folder.
fn link_study(dir: &str) -> (study::Study, PathBuf) {
    let root = std::env::temp_dir().join(format!("flexmbs-force-law-{dir}-{}", std::process::id()));
    std::fs::create_dir_all(&root).unwrap();
    let path = root.join("link.toml");
    std::fs::write(&path, LINK).unwrap();
    (study::load(&path).unwrap(), root)
}

/// The columns `(sensor, c)` over a run with `forces`.
fn columns(st: &study::Study, root: &Path, forces: &Forces, out: &str, which: &[(&str, usize)]) -> Vec<Vec<f64>> {
    let options = Options {
        out: Some(root.join(out)),
        ..Default::default()
    };
    let mut rec = Recorder::default();
    study::run_selected_with(st, &options, Selection::All, forces, &mut rec).unwrap();
    let sensors = rec.analyses[0].sensors.as_ref().unwrap();
    which.iter().map(|&(s, c)| sensors.column(s, c).unwrap()).collect()
}

#[test]
fn a_pd_on_a_tip_position_sensor_moves_the_link_as_the_pd_on_the_joint_angle() {
    let (st, root) = link_study("tip");
    let angle = |forces: &Forces, out: &str| columns(&st, &root, forces, out, &[("angle", 0)]).remove(0);
    let free = angle(&None, "free");
    let joint = angle(&pd(&["pivot"], Reading::Angle), "angle");
    // The law holds the tip near 0.1 m (the angle near 2.5 degrees, under gravity) where the
    // free link falls from 30 degrees towards -90: the runs are the law's.
    let last = |v: &[f64]| *v.last().unwrap();
    assert!(
        last(&free) < -0.5 && last(&joint) > -0.1,
        "free {} law {}",
        last(&free),
        last(&joint)
    );
    let peak = joint.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (reads, reading) in [
        (&["tip"][..], Reading::Position),
        (&["tip.position_y", "tipv.velocity_y"][..], Reading::PositionAndVelocity),
    ] {
        let run = columns(&st, &root, &pd(reads, reading), "sensed", &[("angle", 0), ("tip", 1)]);
        let (sensed, tip) = (&run[0], &run[1]);
        assert_eq!(sensed.len(), joint.len());
        let diff = sensed.iter().zip(&joint).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        eprintln!("{reads:?}: {diff:e} (peak {peak})");
        // The same equations (the tip's height is L sin(angle), its velocity L cos(angle)
        // times the angle's rate, to round-off): only the iteration matrices differ (central
        // differences of two laws, through the node's Jacobian or directly), so each
        // converged step may differ by Newton's tolerance, 1e-9 of the force scale, and the
        // difference carries on over 500 steps of a damped link: 1e-6 of the motion's peak
        // (measured: 1.4e-11 of it).
        assert!(diff <= 1e-6 * peak, "{reads:?}: {diff:e} of the peak {peak}");
        // The sensor the law reads is the tip's: L sin(angle) to round-off.
        assert!((last(tip) - L * last(sensed).sin()).abs() < 1e-12, "{}", last(tip));
    }
    let _ = std::fs::remove_dir_all(root);
}

#[test]
fn sensors_a_law_cannot_read_are_refused_located() {
    let (st, root) = link_study("sensor-names");
    let options = Options {
        out: Some(root.join("out")),
        ..Default::default()
    };
    let mut rec = Recorder::default();
    let mut refuse = |reads: &str| {
        let forces = pd(&[reads], Reading::Position);
        let err = study::run_selected_with(&st, &options, Selection::All, &forces, &mut rec).unwrap_err();
        study::error::chain(err.as_ref())
    };
    // A column the sensor does not have: its columns.
    let err = refuse("tip.position_w");
    assert!(
        err.contains("'tip.position_w'") && err.contains("did you mean") && err.contains("'tip.position_y'"),
        "{err}"
    );
    // A name that is nothing: the joint coordinates and the sensors' columns there are.
    let err = refuse("tipp");
    assert!(
        err.contains("'tipp'") && err.contains("pivot") && err.contains("tipv.velocity_z"),
        "{err}"
    );
    // A sensor of another kind: located at its entry in the study file.
    let err = refuse("angle");
    assert!(
        err.contains("link.toml:") && err.contains("sensors[2]") && err.contains("sensor 'angle' is not a position"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(root);
}
