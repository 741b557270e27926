//! A force law of a run (`study::ForceLawSource`) on the shared study
//! `tests/studies/flexible_double_pendulum.toml`: an elbow damper written as a force law
//! gives the motion of the study's PID (kd = 1), through `run_selected_with` and through a
//! `Simulation`; names that are neither actuator nor point load, or joints that do not exist,
//! are refused with the names there are. (The Python package runs the same study through
//! its `ForceLaw`, crates/python/tests/test_force_law.py.)

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
