//! Force laws (`mbs::force_law`): the finite-difference Jacobians against a law's exact ones,
//! the law's tangents in the iteration matrix against central differences of the residual (a
//! rigid chain; deformed flexible bodies with a saturated PID beside the law, and a law
//! reading node positions and velocities there), a damper law
//! against the built-in PID on a flexible double pendulum and over a 100 s run, and a failing
//! law.

use crate::joint_setup::double_pendulum;
use crate::kinematics::{chain, random_state};
use crate::tangent::{check_tangents, deformed_state, mixed};
use faer::{Mat, MatMut};
use mbs::force_law::{finite_difference_jacobian, Differences};
use mbs::{
    solve_dynamic, DynamicSettings, Effort, ForceLaw, JointActuator, JointId, JointKind, LawError, LawInput, LawOutput,
    LawPorts, LawRead, LawTarget, Load, LoadAxes, LoadKind, Pid, SensorKind, SolveError, System, TimeFunction,
};
use nalgebra::Vector3;
use std::sync::Arc;
use superelement::testing::fd_jacobian;

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
            .map(|(i, &(j, c))| LawInput::coordinate(format!("in{i}"), JointId(j), c))
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
    // ... and they are forward differences: their error is well above the central ones'
    // (below 1e-8): on the cubic's entry h |g''| / 2 = 1.7e-6 * 7.1 / 2 = 6e-6, far above 1e-7.
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
    // and with its finite differences. Tolerance of the chain without the law (tangent.rs),
    // 1e-6: central differences with h = 1e-6 of entries of unit size carry truncation
    // ~1e-12 and round-off eps |F| / h ~ 1e-10, the law's own central differences ~1e-8 of
    // its entries (measured: 1.2e-9 of the row's or column's largest entry); a missing law
    // tangent is off by 0.26 of it (without_its_tangent_the_check_fails).
    for exact in [true, false] {
        let (sys, s) = chain_with_law(exact);
        check_tangents(&sys, &s, 1e-6, 1e-6);
    }
}

#[test]
fn without_its_tangent_the_check_fails() {
    // The check above can fail: the same law with its tangent zeroed (a law that claims a
    // zero Jacobian) disagrees with the residual's differences, by 0.26 of the entry's scale
    // against the tolerance 1e-6 of the check above.
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

/// $u_i = -c\,\dot y_i$: a damper on each joint coordinate it reads (the elbow of the double
/// pendulum, or both its joints).
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
        for (u, v) in u.iter_mut().zip(xd) {
            *u = -self.c * v;
        }
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
            inputs: vec![LawInput::coordinate("elbow", JointId(1), 0)],
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
    // differences against the exact derivative), so each step's converged state may differ
    // by Newton's tolerance, 1e-9 of the force scale: over 300 steps at most ~3e-7 of the
    // motion's peak, and 1e-6 of it is the bound (measured 1e-15 rad: the last correction
    // lands far below the tolerance).
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
    // And the damper does act: without it the elbow moves differently (its torque changes
    // the motion by a fair fraction of the peak in 0.3 s; 1e-3 only says it acted, far
    // above the 1e-6 the two damped runs agree to).
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
            // Step end times are on the step's decimals (step_end_time): 0.011 to round-off.
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

/// A law on three joint coordinates and one sensor value $s$, with its exact Jacobians: the
/// effort $u_0 = -k\sin y_0 - c\dot y_1 + a y_0\dot y_0 - s y_2$ and the load
/// $\mathbf f = (b y_1 + s, -c\dot y_0^3 + a\dot y_2, k y_0 y_2)$.
///
/// A law's inputs are joint coordinates and node positions and velocities (`LawRead`); another
/// sensor (here the strain energy) is recorded at converged steps, so a law reads it as a
/// controller reads a measurement, between steps (a Python law from `Simulation.sensor`):
/// within the step $s$ is a number of the law.
/// It scales values and Jacobian entries and adds no column.
#[derive(Debug)]
struct Sensed {
    ports: LawPorts,
    sensor: f64,
    exact: bool,
}

impl Sensed {
    const K: f64 = 3.0;
    const C: f64 = 0.7;
    const A: f64 = 0.4;
    const B: f64 = 2.5;
}

impl ForceLaw for Sensed {
    fn name(&self) -> &str {
        "sensed"
    }
    fn ports(&self) -> &LawPorts {
        &self.ports
    }
    fn evaluate(&self, _t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        let (k, c, a, b, s) = (Self::K, Self::C, Self::A, Self::B, self.sensor);
        u[0] = -k * x[0].sin() - c * xd[1] + a * x[0] * xd[0] - s * x[2];
        u[1] = b * x[1] + s;
        u[2] = -c * xd[0].powi(3) + a * xd[2];
        u[3] = k * x[0] * x[2];
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
        let (k, c, a, b, s) = (Self::K, Self::C, Self::A, Self::B, self.sensor);
        du_dx[(0, 0)] = -k * x[0].cos() + a * xd[0];
        du_dx[(0, 2)] = -s;
        du_dxd[(0, 0)] = a * x[0];
        du_dxd[(0, 1)] = -c;
        du_dx[(1, 1)] = b;
        du_dxd[(2, 0)] = -3.0 * c * xd[0].powi(2);
        du_dxd[(2, 2)] = a;
        du_dx[(3, 0)] = k * x[2];
        du_dx[(3, 2)] = k * x[0];
        Ok(true)
    }
}

/// The mixed model of tangent.rs (two soft superelements with modes, rigid bodies, a spring,
/// follower and dead loads, gravity) with its spherical joint made a universal one, turned
/// out of its reference by initial joint values (the subtree behind each joint moved
/// rigidly: revolute 0.7 rad, universal 0.4 and -0.3 rad), with a strain-energy sensor and:
/// actuator 0, "motor", on the universal's first coordinate, and a dead force at n4 (the free
/// end of flexible body b2), both zero by themselves (a force law sets them); actuator 1,
/// "servo", on the revolute joint with the effort `servo`. Returns the model and the load's
/// index.
fn flexible_with_actuators(servo: Effort) -> (mbs::Model, usize) {
    let mut m = mixed();
    assert_eq!(m.joints[1].name, "sph");
    m.joints[1].kind = JointKind::Universal {
        axis1: Vector3::new(1.0, 0.2, 0.0),
        axis2: Vector3::new(-0.2, 1.0, 0.3),
    };
    for (j, c, value) in [(0, 0, 0.7), (1, 0, 0.4), (1, 1, -0.3)] {
        m.initial.push(mbs::InitialCondition::JointValue {
            joint: JointId(j),
            coordinate: c,
            value,
        });
    }
    m.add_sensor("strain", SensorKind::StrainEnergy);
    m.actuators.push(JointActuator {
        name: "motor".into(),
        joint: JointId(1),
        coordinate: 0,
        effort: Effort::Time(TimeFunction::constant(0.0)),
    });
    m.actuators.push(JointActuator {
        name: "servo".into(),
        joint: JointId(0),
        coordinate: 0,
        effort: servo,
    });
    let n4 = m.nodes.iter().position(|n| n.name == "n4").unwrap();
    m.loads.push(Load {
        node: mbs::NodeId(n4 as u32),
        kind: LoadKind::Force,
        axes: LoadAxes::Dead,
        value: Vector3::zeros(),
        time: TimeFunction::constant(1.5),
    });
    let load = m.loads.len() - 1;
    (m, load)
}

/// The PID of the servo: on the revolute joint, measuring the universal's second coordinate
/// (an entry off the diagonal), set-point 0.3 rad, gains (40, 25, 3), saturated at `max`.
fn servo_pid(max: f64) -> Effort {
    Effort::Pid(Pid {
        joint: JointId(1),
        coordinate: 1,
        setpoint: TimeFunction::constant(0.3),
        kp: 40.0,
        ki: 25.0,
        kd: 3.0,
        max_effort: Some(max),
    })
}

/// The unknown of a joint coordinate (the one entry of the difference of a state with it moved).
fn unknown_of(sys: &System, s: &mbs::State, joint: JointId, c: usize) -> usize {
    let mut moved = s.clone();
    let (v, r) = (sys.joint_value(s, joint, c), sys.joint_rate(s, joint, c));
    sys.set_joint(&mut moved, joint, c, v + 1.0, r);
    let d = sys.difference(&moved, s);
    let i = d.iter().position(|x| (x - 1.0).abs() < 1e-12).unwrap();
    assert!(d.iter().enumerate().all(|(k, x)| k == i || *x == 0.0), "{d:?}");
    i
}

/// The share of K and C of what `sys` has and `plain` (the same unknowns) has not, at `s`,
/// against central differences (h = 1e-6) of its share of the residual, each entry's error
/// measured against the share's largest entry; returns the share.
///
/// The elements both systems have (bodies, joints, springs) give the same bits in both, so the
/// difference quotients of the share carry no frame-solve noise, only the round-off of the
/// residual's entries, eps |F| / 2h ~ 1.4e-8 for |F| ~ 1e2, and the truncation h^2 |g'''| ~ 1e-11
/// (and ~1e-9 of a law's own central differences). The share's largest entry is 0.7 (the
/// law's c: C with the servo saturated) to 45 (kp + ki t / 2: K on the linear branch), so the
/// round-off is at most 2e-8 of it (measured: 2.0e-8 at 0.7, 3e-10 at 45): 1e-7.
fn check_share(sys: &System, plain: &System, s: &mbs::State) -> (Mat<f64>, Mat<f64>) {
    let mut s0 = s.clone();
    let full = sys.matrices(&mut s0, 1.0).unwrap();
    let without = plain.matrices(&mut s0.clone(), 1.0).unwrap();
    let (dk, dc) = (&full.K - &without.K, &full.C - &without.C);
    let share = |st: &mbs::State| {
        let f = sys.residual(&mut st.clone(), 1.0).unwrap();
        let g = plain.residual(&mut st.clone(), 1.0).unwrap();
        f.iter().zip(&g).map(|(a, b)| a - b).collect::<Vec<f64>>()
    };
    let steps = vec![1e-6; sys.n_dof()];
    let fd_k = fd_jacobian(&steps, |d| share(&sys.retract(&s0, d)));
    let fd_c = fd_jacobian(&steps, |d| {
        let mut st = s0.clone();
        for (v, dv) in st.velocity_mut().iter_mut().zip(d) {
            *v += dv;
        }
        share(&st)
    });
    for (name, exact, fd) in [("K", &dk, &fd_k), ("C", &dc, &fd_c)] {
        let largest = max_abs_diff(exact, &Mat::zeros(exact.nrows(), exact.ncols()));
        let worst = max_abs_diff(exact, fd) / largest;
        eprintln!("{name} share: largest entry {largest:.4e}, worst error {worst:.3e} of it");
        assert!(largest > 0.1 && worst < 1e-7, "{name} share: {worst:e} of {largest:e}");
    }
    (dk, dc)
}

#[test]
fn law_and_saturated_pid_tangents_match_central_differences_on_a_deformed_flexible_body() {
    // The law (exact Jacobians, then central differences of it) and the servo on its linear
    // branch and saturated, at a deformed, rotated, moving state at t = 0.37 (the PID
    // integral's weight (t - t_n) / 2 = 0.185).
    let (plain_model, load) = flexible_with_actuators(Effort::Time(TimeFunction::constant(0.0)));
    let plain = System::new(&plain_model).unwrap();
    let inputs = [(0, 0), (1, 0), (1, 1)];
    let ports = LawPorts {
        inputs: inputs
            .iter()
            .map(|&(j, c)| LawInput::coordinate(format!("j{j}[{c}]"), JointId(j), c))
            .collect(),
        outputs: ports([(0, 0), (1, 0)], 0, load).outputs,
    };
    // The law's sensor: the strain energy at the state, as recorded between steps.
    let mut rec = plain.sensor_record();
    plain.record_state(&deformed_state(&plain), 1.0, &mut rec).unwrap();
    let strain = rec.column("strain", 0).unwrap()[0];
    let (t, ki) = (0.37, 25.0);
    for exact in [true, false] {
        let mut shares = Vec::new();
        for (max, saturated) in [(1e6, false), (0.05, true)] {
            let (model, _) = flexible_with_actuators(servo_pid(max));
            let law = Sensed {
                ports: ports.clone(),
                sensor: strain,
                exact,
            };
            let sys = System::with_force_law(&model, Arc::new(law)).unwrap();
            let mut s = deformed_state(&sys);
            assert_eq!(s.time(), t);
            sys.settle_actuator_branches(&mut s);
            // Deformed, rotated, moving: both flexible bodies' modal coordinates and rates
            // away from zero (the state moves each by up to 0.05, its rate by up to 2), the
            // joints turned (by 0.3 to 0.7 rad) and moving.
            let mut flexible = 0;
            for b in 0..sys.model().bodies.len() {
                let (eta, eta_d) = sys.modal_coordinates(&s, mbs::BodyId(b as u32));
                assert!(
                    eta.iter().chain(&eta_d).all(|v| v.abs() > 1e-4),
                    "body {b}: {eta:?} {eta_d:?}"
                );
                flexible += usize::from(!eta.is_empty());
            }
            assert_eq!(flexible, 2);
            for (j, c) in inputs {
                let (v, r) = (sys.joint_value(&s, JointId(j), c), sys.joint_rate(&s, JointId(j), c));
                assert!(v.abs() > 0.2 && r.abs() > 1e-2, "joint {j}[{c}]: {v}, {r}");
            }
            let u = sys.actuator_efforts(&s);
            eprintln!("exact {exact}, bound {max}: strain {strain:.4e} J, efforts {u:?}");
            assert!(strain > 1.0, "the sensor reads {strain} J");
            assert_eq!(u[1].abs() == max, saturated, "servo effort {}", u[1]);
            // The whole tangent, as tangent.rs checks the flexible model: the floating frames,
            // re-solved to 1e-12 at each evaluation, can give difference quotients with
            // h = 1e-6 errors up to ~1e-6 of the largest entry (measured here: 2e-8): 1e-5.
            check_tangents(&sys, &s, 1e-6, 1e-5);
            // The law's and the servo's share alone, free of that noise (check_share): 1e-7.
            shares.push(check_share(&sys, &plain, &s));
        }
        // The branches differ by the PID's entries alone: on the linear branch
        // -du/dy = kp + ki (t - t_n) / 2 (t_n = 0) at the servo's row and the measured column
        // of K, -du/dyd = kd in C; saturated, nothing. Every other entry is the law's, the
        // same bits on both; the PID's is added into a slot of entries below 10, so it
        // carries their round-off, 1e-15: 1e-12 of it.
        let s = plain.initial_state();
        let (row, col) = (
            unknown_of(&plain, &s, JointId(0), 0),
            unknown_of(&plain, &s, JointId(1), 1),
        );
        let [(k_lin, c_lin), (k_sat, c_sat)] = [&shares[0], &shares[1]];
        for (lin, sat, pid) in [(k_lin, k_sat, 40.0 + 0.5 * ki * t), (c_lin, c_sat, 3.0)] {
            let n = lin.nrows();
            for (i, j) in (0..n).flat_map(|j| (0..n).map(move |i| (i, j))) {
                let expected = if (i, j) == (row, col) { pid } else { 0.0 };
                let got = lin[(i, j)] - sat[(i, j)];
                assert!((got - expected).abs() < 1e-12 * pid, "({i}, {j}): {got} vs {expected}");
            }
        }
    }
}

/// A law on a node's position (input 0, with its velocity as rate), a joint coordinate
/// (input 1) and a node's velocity (input 2, without a rate), with its exact Jacobians: the
/// effort $u_0 = -k\sin y_0 - c\dot y_1 + a y_0\dot y_0 - y_1 y_2$ and the load
/// $\mathbf f = (b y_1 + y_2, -c\dot y_0^3 + a\dot y_1 y_2, k y_0 y_2)$. It refuses a rate of
/// input 2 that is not NaN (an input without a rate is never differenced by its rate).
#[derive(Debug)]
struct Kinematic {
    ports: LawPorts,
    exact: bool,
}

impl Kinematic {
    const K: f64 = 3.0;
    const C: f64 = 0.7;
    const A: f64 = 0.4;
    const B: f64 = 2.5;

    /// The effort $u_0$ at `x`, `xd`.
    fn effort(x: &[f64], xd: &[f64]) -> f64 {
        let (k, c, a) = (Self::K, Self::C, Self::A);
        -k * x[0].sin() - c * xd[1] + a * x[0] * xd[0] - x[1] * x[2]
    }
}

impl ForceLaw for Kinematic {
    fn name(&self) -> &str {
        "kinematic"
    }
    fn ports(&self) -> &LawPorts {
        &self.ports
    }
    fn evaluate(&self, _t: f64, x: &[f64], xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        if !xd[2].is_nan() {
            return Err(LawError::new(format!("a velocity input has the rate {}", xd[2])));
        }
        let (k, c, a, b) = (Self::K, Self::C, Self::A, Self::B);
        u[0] = Self::effort(x, xd);
        u[1] = b * x[1] + x[2];
        u[2] = -c * xd[0].powi(3) + a * xd[1] * x[2];
        u[3] = k * x[0] * x[2];
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
        let (k, c, a, b) = (Self::K, Self::C, Self::A, Self::B);
        du_dx[(0, 0)] = -k * x[0].cos() + a * xd[0];
        du_dx[(0, 1)] = -x[2];
        du_dx[(0, 2)] = -x[1];
        du_dxd[(0, 0)] = a * x[0];
        du_dxd[(0, 1)] = -c;
        du_dx[(1, 1)] = b;
        du_dx[(1, 2)] = 1.0;
        du_dxd[(2, 0)] = -3.0 * c * xd[0].powi(2);
        du_dxd[(2, 1)] = a * x[2];
        du_dx[(2, 2)] = a * xd[1];
        du_dx[(3, 0)] = k * x[2];
        du_dx[(3, 2)] = k * x[0];
        Ok(true)
    }
}

#[test]
fn a_law_reading_node_kinematics_has_tangents_matching_central_differences_on_a_deformed_flexible_body() {
    // The law reads the position along y of n6 (a point of rigid body r2, behind the
    // universal joint at b2's free interface node), the universal joint's second coordinate,
    // and the velocity along x of n2 (a point of rigid body r1, on b1's interface node): both
    // nodes hang on joint coordinates and turning nodes, so their J changes with q (the
    // convective terms). Exact Jacobians, then central differences.
    let (model, load) = flexible_with_actuators(Effort::Time(TimeFunction::constant(0.0)));
    let plain = System::new(&model).unwrap();
    let node = |name: &str| mbs::NodeId(model.nodes.iter().position(|n| n.name == name).unwrap() as u32);
    let (n6, n2) = (node("n6"), node("n2"));
    let ports = LawPorts {
        inputs: vec![
            LawInput {
                name: "tip.position_y".into(),
                reads: LawRead::NodePosition { node: n6, axis: 1 },
            },
            LawInput::coordinate("sph[1]", JointId(1), 1),
            LawInput {
                name: "end.velocity_x".into(),
                reads: LawRead::NodeVelocity { node: n2, axis: 0 },
            },
        ],
        outputs: ports([(0, 0), (1, 0)], 0, load).outputs,
    };
    for exact in [true, false] {
        let law = Kinematic {
            ports: ports.clone(),
            exact,
        };
        let sys = System::with_force_law(&model, Arc::new(law)).unwrap();
        let s = deformed_state(&sys);
        // The law reads the nodes' motions: its effort is the law of the node motions and
        // the joint's value and rate at the state.
        let motions = sys.node_motions(&s);
        let (tip, end) = (&motions[n6.index()], &motions[n2.index()]);
        let (y, r) = (sys.joint_value(&s, JointId(1), 1), sys.joint_rate(&s, JointId(1), 1));
        let x = [tip.r.y, y, end.v.x];
        let xd = [tip.v.y, r, f64::NAN];
        eprintln!("exact {exact}: inputs {x:?}, rates {xd:?}");
        assert!(x.iter().chain(&xd[..2]).all(|v| v.abs() > 1e-2), "{x:?} {xd:?}");
        let u = sys.actuator_efforts(&s)[0];
        assert!((u - Kinematic::effort(&x, &xd)).abs() < 1e-12 * u.abs().max(1.0), "{u}");
        check_tangents(&sys, &s, 1e-6, 1e-5);
        let (dk, _) = check_share(&sys, &plain, &s);
        // The node's position hangs on more unknowns than the joint coordinate: the effort's
        // row of K has entries in the columns of b1's modes and frame, off the joints.
        let row = unknown_of(&plain, &plain.initial_state(), JointId(1), 0);
        let filled = (0..dk.ncols()).filter(|&j| dk[(row, j)] != 0.0).count();
        assert!(filled > 4, "{filled} entries in the effort's row");
    }
}

#[test]
fn a_flexible_double_pendulum_damped_by_a_law_settles_over_100_s_without_gaining_energy() {
    // The flexible double pendulum (two aluminium links, two modes each) released at 0.6 and
    // -0.4 rad, with a damper law u = -c y' (c = 0.05 N m s/rad) on both joints, run for 100 s
    // as a study run steps it (`Integrator::run_to`, adaptive steps up to 0.1 s: about 2000
    // steps, under a second), an energy-balance row after every step.
    let mut m = pendulum_with_actuator(Effort::Time(TimeFunction::constant(0.0)));
    m.actuators.push(JointActuator {
        name: "shoulder motor".into(),
        joint: JointId(0),
        coordinate: 0,
        effort: Effort::Time(TimeFunction::constant(0.0)),
    });
    m.add_sensor("energy", SensorKind::EnergyBalance);
    let ports = LawPorts {
        inputs: ["shoulder", "elbow"]
            .iter()
            .enumerate()
            .map(|(j, name)| LawInput::coordinate(name.to_string(), JointId(j as u32), 0))
            .collect(),
        outputs: ["shoulder motor", "elbow motor"]
            .iter()
            .zip([1, 0])
            .map(|(name, a)| LawOutput {
                name: name.to_string(),
                target: LawTarget::Actuator(a),
            })
            .collect(),
    };
    let law = Damper {
        ports,
        c: 0.05,
        fail_after: None,
    };
    let sys = System::with_force_law(&m, Arc::new(law)).unwrap();
    let end = 100.0;
    let mut integ = mbs::Integrator::new(&sys, sys.initial_state(), DynamicSettings::new(1e-3, end, 0.9)).unwrap();
    let mut rec = sys.sensor_record();
    integ.record(&mut rec).unwrap();
    let stepping = mbs::Stepping::Adaptive(mbs::AdaptiveSettings::new(1e-5, 1e-6, 0.1));
    let (totals, failure) = integ.run_to(end, &stepping, |_, i| i.record(&mut rec)).unwrap();
    assert!(failure.is_none(), "{failure:?}");
    let col = |c: usize| rec.column("energy", c).unwrap();
    let (work, kinetic, strain, gravity) = (col(0), col(3), col(4), col(5));
    let energy: Vec<f64> = (0..work.len()).map(|i| kinetic[i] + strain[i] + gravity[i]).collect();
    let (e0, e_end) = (energy[0], *energy.last().unwrap());
    let excess = (0..work.len())
        .map(|i| energy[i] - e0 - work[i])
        .fold(f64::MIN, f64::max);
    let grown = energy.iter().map(|e| e - e0).fold(f64::MIN, f64::max);
    let s = integ.state();
    let rates: Vec<f64> = (0..2).map(|j| sys.joint_rate(s, JointId(j), 0)).collect();
    let angles: Vec<f64> = (0..2).map(|j| sys.joint_value(s, JointId(j), 0)).collect();
    eprintln!(
        "{} steps ({:.2e} to {:.2e} s), {} rejected; E0 - E_end {:.4e} J, work {:.4e} J, largest excess {excess:.3e} J, largest growth {grown:.3e} J; angles {angles:?}, rates {rates:?}",
        totals.steps,
        totals.smallest_step,
        totals.largest_step,
        totals.rejected,
        e0 - e_end,
        work.last().unwrap()
    );
    // The dampers' work is what the motion lost: E - E0 - W_in is the balance error of
    // generalized-alpha and of the trapezoidal work integral, second order in the step. With
    // the local error held at tol the steps go as tol^(1/3) and this error as tol^(2/3):
    // 9.7e-4, 3.1e-4, 7.8e-5, 1.5e-5 J for tol = 1e-3 ... 1e-6, here (1e-5) 4.3e-4 of the
    // 0.18 J the dampers take out. Bound: 1e-3 of it. The dampers only take energy out
    // (W_in <= 0), so E never rises above E0 by more either (measured: never above E0).
    let swing = e0 - e_end;
    assert!(swing > 0.1, "the dampers took out {swing} J");
    assert!(excess < 1e-3 * swing, "excess {excess}");
    assert!(grown < 1e-3 * swing, "growth {grown}");
    let (scalars, rotations) = s.coordinates();
    assert!(scalars.iter().chain(s.velocity()).all(|v| v.is_finite()));
    assert!(rotations.iter().all(|r| r.coords.iter().all(|v| v.is_finite())));
    // Settled: the slowest mode (the linearisation at the end: s = -0.254 +- 3.78i) has decayed
    // by e^-25 from 0.6 rad, 1e-11 rad; what is left (5e-10 rad, 4e-9 rad/s measured) is
    // Newton's tolerance and the undamped elastic modes that generalized-alpha's numerical
    // damping takes out. 1e-6 rad and rad/s leave room for both; a run still swinging, or
    // growing, is far above.
    assert!(rates.iter().all(|r| r.abs() < 1e-6), "{rates:?}");
    assert!(angles.iter().all(|a| a.abs() < 1e-6), "{angles:?}");
}

/// A law that pushes the double pendulum's tip (node D) with a force of time and of the
/// joint angles, $\mathbf f = (0.2\sin 5t,\ 0.3\,y_1 - 0.2\,y_2,\ 0)$ N.
#[derive(Debug)]
struct TipPush(LawPorts);

impl ForceLaw for TipPush {
    fn name(&self) -> &str {
        "tip push"
    }
    fn ports(&self) -> &LawPorts {
        &self.0
    }
    fn evaluate(&self, t: f64, x: &[f64], _xd: &[f64], u: &mut [f64]) -> Result<(), LawError> {
        u[0] = 0.2 * (5.0 * t).sin();
        u[1] = 0.3 * x[0] - 0.2 * x[1];
        Ok(())
    }
}

#[test]
fn the_energy_balance_counts_the_work_of_the_loads_a_law_sets() {
    // The flexible double pendulum, its tip pushed by a law for 2 s (adaptive steps). The balance error
    // E - E0 - W_in + D of the energy-balance sensor (column 7) is the integrator's energy
    // error only if W_in holds the work of the law's load (column 2).
    let mut m = pendulum_with_actuator(Effort::Time(TimeFunction::constant(0.0)));
    m.loads.push(Load {
        node: mbs::NodeId(4),
        kind: LoadKind::Force,
        axes: LoadAxes::Dead,
        value: Vector3::zeros(),
        time: TimeFunction::constant(1.0),
    });
    m.add_sensor("energy", SensorKind::EnergyBalance);
    let ports = LawPorts {
        inputs: ["shoulder", "elbow"]
            .iter()
            .enumerate()
            .map(|(j, name)| LawInput::coordinate(name.to_string(), JointId(j as u32), 0))
            .collect(),
        outputs: vec![LawOutput {
            name: "tip push".into(),
            target: LawTarget::Load(0),
        }],
    };
    let sys = System::with_force_law(&m, Arc::new(TipPush(ports))).unwrap();
    let end = 2.0;
    let mut integ = mbs::Integrator::new(&sys, sys.initial_state(), DynamicSettings::new(1e-3, end, 0.9)).unwrap();
    let mut rec = sys.sensor_record();
    integ.record(&mut rec).unwrap();
    let (_, failure) = integ
        .run_to(
            end,
            &mbs::Stepping::Adaptive(mbs::AdaptiveSettings::new(1e-6, 1e-6, 0.01)),
            |_, i| i.record(&mut rec),
        )
        .unwrap();
    assert!(failure.is_none(), "{failure:?}");
    let loads = rec.column("energy", 2).unwrap();
    let error = rec.column("energy", 7).unwrap();
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let (work, err) = (largest(&loads), largest(&error));
    eprintln!("largest |work of the law's load| {work:.4e} J, largest |balance error| {err:.3e} J");
    // The push does 0.08 J of work. Without it in W_in the balance error is that work; with
    // it, the error of generalized-alpha under the adaptive steps' local error control (1e-6)
    // and of the trapezoidal work integral: measured 1.3e-7 J, 1.6e-6 of the work. Bound:
    // 1e-4 of it.
    assert!(work > 1e-2, "the law's load did {work} J");
    assert!(err < 1e-4 * work, "balance error {err} J against {work} J of work");
}
