//! Force laws (`mbs::force_law`): the finite-difference Jacobians against a law's exact ones,
//! the law's tangents in the iteration matrix against central differences of the residual,
//! a damper law against the built-in PID on a flexible double pendulum, and a failing law.

use crate::joint_setup::double_pendulum;
use crate::kinematics::{chain, random_state};
use crate::tangent::check_tangents;
use faer::{Mat, MatMut};
use mbs::force_law::{finite_difference_jacobian, Differences};
use mbs::{
    solve_dynamic, DynamicSettings, Effort, ForceLaw, JointActuator, JointId, LawError, LawInput, LawOutput, LawPorts,
    LawTarget, Load, LoadAxes, LoadKind, Pid, SensorKind, SolveError, System, TimeFunction,
};
use nalgebra::Vector3;
use std::sync::Arc;

/// A nonlinear spring-damper law on two inputs with its exact Jacobians:
/// $u_0 = -k\sin y_0 - c\dot y_1 + a y_0\dot y_0$ (an actuator), and a load
/// $\mathbf f = (b y_1, -c\dot y_0^3, k y_0 y_1)$.
#[derive(Debug)]
struct Spring {
    ports: LawPorts,
    k: f64,
    c: f64,
    a: f64,
    b: f64,
    exact: bool,
    differences: Differences,
}

impl Spring {
    fn new(ports: LawPorts, exact: bool) -> Self {
        Self {
            ports,
            k: 3.0,
            c: 0.7,
            a: 0.4,
            b: 2.5,
            exact,
            differences: Differences::default(),
        }
    }
}

impl ForceLaw for Spring {
    fn name(&self) -> &str {
        "spring"
    }
    fn ports(&self) -> &LawPorts {
        &self.ports
    }
    fn evaluate(&self, _t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        let (k, c, a, b) = (self.k, self.c, self.a, self.b);
        u[0] = -k * x[0].sin() - c * xd[1] + a * x[0] * xd[0];
        u[1] = b * x[1];
        u[2] = -c * xd[0].powi(3);
        u[3] = k * x[0] * x[1];
        Ok(())
    }
    fn jacobian(
        &self,
        _t: f64,
        x: &[f64],
        xd: &[f64],
        mut du_dx: MatMut<'_, f64>,
        mut du_dxd: MatMut<'_, f64>,
    ) -> Result<bool, LawError> {
        if !self.exact {
            return Ok(false);
        }
        let (k, c, a, b) = (self.k, self.c, self.a, self.b);
        du_dx[(0, 0)] = -k * x[0].cos() + a * xd[0];
        du_dxd[(0, 0)] = a * x[0];
        du_dxd[(0, 1)] = -c;
        du_dx[(1, 1)] = b;
        du_dxd[(2, 0)] = -3.0 * c * xd[0].powi(2);
        du_dx[(3, 0)] = k * x[1];
        du_dx[(3, 1)] = k * x[0];
        Ok(true)
    }
    fn differences(&self) -> Differences {
        self.differences
    }
}

fn ports(inputs: [(u32, usize); 2], actuator: usize, load: usize) -> LawPorts {
    LawPorts {
        inputs: inputs
            .iter()
            .enumerate()
            .map(|(i, &(j, c))| LawInput {
                name: format!("in{i}"),
                joint: JointId(j),
                coordinate: c,
            })
            .collect(),
        outputs: vec![
            LawOutput {
                name: "motor".into(),
                target: LawTarget::Actuator(actuator),
            },
            LawOutput {
                name: "push".into(),
                target: LawTarget::Load(load),
            },
        ],
    }
}

fn max_abs_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let mut d: f64 = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            d = d.max((a[(i, j)] - b[(i, j)]).abs());
        }
    }
    d
}

#[test]
fn finite_difference_jacobians_match_the_exact_ones() {
    let mut law = Spring::new(ports([(0, 0), (1, 0)], 0, 0), true);
    let (x, xd) = ([0.8, -0.3], [1.7, -2.2]);
    let mut ex = Mat::zeros(4, 2);
    let mut exd = Mat::zeros(4, 2);
    assert!(law.jacobian(0.0, &x, &xd, ex.as_mut(), exd.as_mut()).unwrap());
    // Central differences with h = 1e-6 max(|y|, 1): truncation h^2 |g'''| ~ 1e-11 and
    // round-off eps |g| / h ~ 1e-10 (|g| below 10): 1e-8.
    let (dx, dxd) = finite_difference_jacobian(&law, 0.0, &x, &xd).unwrap();
    assert!(max_abs_diff(&dx, &ex) < 1e-8, "{:?} vs {:?}", dx, ex);
    assert!(max_abs_diff(&dxd, &exd) < 1e-8, "{:?} vs {:?}", dxd, exd);
    // Forward differences: error h |g''| / 2 with |g''| below 12 (3 c |y'| of the cubic): 1e-5.
    law.differences = Differences::Forward { relative: 1e-6 };
    let (dx, dxd) = finite_difference_jacobian(&law, 0.0, &x, &xd).unwrap();
    let (ex_err, exd_err) = (max_abs_diff(&dx, &ex), max_abs_diff(&dxd, &exd));
    assert!(ex_err < 1e-5 && exd_err < 1e-5, "forward: {ex_err:e}, {exd_err:e}");
    // ... and they are forward differences: their error is well above the central ones'.
    assert!(exd_err > 1e-7, "forward error {exd_err:e}");
}

/// The rigid chain of kinematics.rs with an actuator on its prismatic joint and a dead load
/// at node n6 (both zero by themselves), set by `law`.
fn chain_with_law(exact: bool) -> (System, mbs::State) {
    let mut model = chain();
    model.actuators.push(JointActuator {
        name: "motor".into(),
        joint: JointId(1),
        coordinate: 0,
        effort: Effort::Time(TimeFunction::constant(0.0)),
    });
    let n6 = model.nodes.iter().position(|n| n.name == "n6").unwrap();
    model.loads.push(Load {
        node: mbs::NodeId(n6 as u32),
        kind: LoadKind::Force,
        axes: LoadAxes::Dead,
        value: Vector3::zeros(),
        time: TimeFunction::constant(1.5),
    });
    // Inputs: the revolute joint (0) and the prismatic one (1).
    let law = Spring::new(ports([(0, 0), (1, 0)], 0, model.loads.len() - 1), exact);
    let sys = System::with_force_law(&model, Arc::new(law)).unwrap();
    let s = random_state(&sys, 13);
    (sys, s)
}

#[test]
fn a_force_laws_tangents_match_central_differences_of_the_residual() {
    // A rotated, moving state at t = 0.37: the law's effort on the prismatic row and its load
    // through J^T of node n6 (with the node's geometric term), with the law's exact Jacobians
    // and with its finite differences. Tolerance of the chain without the law (tangent.rs).
    for exact in [true, false] {
        let (sys, s) = chain_with_law(exact);
        check_tangents(&sys, &s, 1e-6, 1e-6);
    }
}

#[test]
fn without_its_tangent_the_check_fails() {
    // The check above can fail: the same law with its tangent zeroed (a law that claims a
    // zero Jacobian) disagrees with the residual's differences.
    #[derive(Debug)]
    struct NoTangent(Spring);
    impl ForceLaw for NoTangent {
        fn name(&self) -> &str {
            "no tangent"
        }
        fn ports(&self) -> &LawPorts {
            self.0.ports()
        }
        fn evaluate(&self, t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
            self.0.evaluate(t, x, xd, u)
        }
        fn jacobian(
            &self,
            _: f64,
            _: &[f64],
            _: &[f64],
            _: MatMut<'_, f64>,
            _: MatMut<'_, f64>,
        ) -> Result<bool, LawError> {
            Ok(true)
        }
    }
    let (sys, _) = chain_with_law(true);
    let law = NoTangent(Spring::new(sys.force_law().unwrap().ports().clone(), true));
    let sys = System::with_force_law(sys.model(), Arc::new(law)).unwrap();
    let s = random_state(&sys, 13);
    let failed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| check_tangents(&sys, &s, 1e-6, 1e-6)));
    assert!(failed.is_err(), "a zero tangent passed the check");
}

/// $u = -c\,\dot y$ on the elbow of the double pendulum (input: the elbow's rate).
#[derive(Debug)]
struct Damper {
    ports: LawPorts,
    c: f64,
    fail_after: Option<f64>,
}

impl ForceLaw for Damper {
    fn name(&self) -> &str {
        "damper"
    }
    fn ports(&self) -> &LawPorts {
        &self.ports
    }
    fn evaluate(&self, t: f64, _x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        u[0] = -self.c * xd[0];
        if self.fail_after.is_some_and(|t_fail| t > t_fail) {
            u[0] = f64::NAN;
        }
        Ok(())
    }
}

/// The flexible double pendulum (two stiff aluminium links of 0.5 m, 1 cm square) from the
/// shoulder at 0.6 rad and the elbow at -0.4 rad, with an actuator on the elbow: `effort`,
/// and the elbow angle as sensor.
fn pendulum_with_actuator(effort: Effort) -> mbs::Model {
    let (mut m, _) = double_pendulum(0.5, 0.01, 70e9);
    for (j, v) in [(0, 0.6), (1, -0.4)] {
        m.initial.push(mbs::InitialCondition::JointValue {
            joint: JointId(j),
            coordinate: 0,
            value: v,
        });
    }
    m.actuators.push(JointActuator {
        name: "elbow motor".into(),
        joint: JointId(1),
        coordinate: 0,
        effort,
    });
    m.add_sensor(
        "elbow",
        SensorKind::JointCoordinate {
            joint: JointId(1),
            coordinate: 0,
        },
    );
    m
}

fn damper(c: f64, fail_after: Option<f64>) -> Arc<Damper> {
    Arc::new(Damper {
        ports: LawPorts {
            inputs: vec![LawInput {
                name: "elbow".into(),
                joint: JointId(1),
                coordinate: 0,
            }],
            outputs: vec![LawOutput {
                name: "elbow motor".into(),
                target: LawTarget::Actuator(0),
            }],
        },
        c,
        fail_after,
    })
}

#[test]
fn a_damper_law_follows_the_builtin_pid() {
    // u = -c y' in the step is the PID with kd = c (set-point 0, kp = ki = 0): the same
    // equations, the same Newton tolerance; only the iteration matrices differ (central
    // differences against the exact derivative), so the trajectories agree to the Newton
    // tolerance's share, far below 1e-6 of the motion's peak.
    let c = 1.0;
    let pid = pendulum_with_actuator(Effort::Pid(Pid {
        joint: JointId(1),
        coordinate: 0,
        setpoint: TimeFunction::constant(0.0),
        kp: 0.0,
        ki: 0.0,
        kd: c,
        max_effort: None,
    }));
    let law = pendulum_with_actuator(Effort::Time(TimeFunction::constant(0.0)));
    let settings = DynamicSettings::new(1e-3, 0.3, 0.9);
    let elbow = |sys: &System| {
        let tr = solve_dynamic(sys, sys.initial_state(), &settings).unwrap();
        tr.sensors.column("elbow", 0).unwrap()
    };
    let a = elbow(&System::new(&pid).unwrap());
    let law_sys = System::with_force_law(&law, damper(c, None)).unwrap();
    let b = elbow(&law_sys);
    let peak = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    eprintln!("elbow peak {peak:.4} rad, law vs PID {diff:.3e} rad");
    assert!(a.len() == b.len() && a.len() > 100);
    assert!(diff < 1e-6 * peak, "law vs PID: {diff:e} (peak {peak})");
    // And the damper does act: without it the elbow moves differently.
    let free = elbow(&System::new(&law).unwrap());
    let off = a.iter().zip(&free).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(off > 1e-3 * peak, "damper had no effect: {off:e}");
    // The law's effort is what the actuator reports.
    let s = law_sys.initial_state();
    assert_eq!(law_sys.actuator_efforts(&s)[0], 0.0);
}

#[test]
fn a_law_value_that_is_not_finite_stops_the_run_where_it_happened() {
    let law = pendulum_with_actuator(Effort::Time(TimeFunction::constant(0.0)));
    let sys = System::with_force_law(&law, damper(1.0, Some(0.0105))).unwrap();
    let Err(err) = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(1e-3, 0.1, 0.9)) else {
        panic!("the NaN stops the run")
    };
    match &err.error {
        SolveError::ForceLaw { name, output, at, .. } => {
            assert_eq!(name, "damper");
            assert_eq!(output.as_deref(), Some("elbow motor"));
            let t = at.time().unwrap();
            assert!((t - 0.011).abs() < 1e-12, "at {t}");
        }
        other => panic!("expected a force-law error, got {other}"),
    }
    let message = study_chain(&err.error);
    assert!(
        message.contains("force law 'damper' (output 'elbow motor') at t = 0.011000"),
        "{message}"
    );
    assert!(message.contains("its value is NaN"), "{message}");
}

/// The error and its sources, joined as the study layer reports them.
fn study_chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut parts = vec![e.to_string()];
    let mut s = e.source();
    while let Some(x) = s {
        parts.push(x.to_string());
        s = x.source();
    }
    parts.join(": ")
}

#[test]
fn ports_that_name_nothing_are_refused_by_name() {
    let model = pendulum_with_actuator(Effort::Time(TimeFunction::constant(0.0)));
    let mut law = Damper {
        ports: damper(1.0, None).ports.clone(),
        c: 1.0,
        fail_after: None,
    };
    law.ports.outputs[0].target = LawTarget::Actuator(3);
    let err = System::with_force_law(&model, Arc::new(law)).unwrap_err();
    assert!(
        err.to_string()
            .contains("output 'elbow motor' sets actuator 3, which does not exist"),
        "{err}"
    );
}
