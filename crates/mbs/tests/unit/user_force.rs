//! User-defined forces ([`mbs::UserForce`], user_force.rs): Jacobians, assembly, equality with a
//! built-in load, refusals.

use crate::fixtures::cantilever;
use crate::kinematics::{chain, random_state};
use crate::tangent::{check_tangents, mixed};
use faer::{Mat, MatMut};
use mbs::user_force::finite_difference_jacobian;
use mbs::{
    solve_dynamic, solve_static, DynamicSettings, Load, LoadAxes, LoadKind, ModelError, NodeId, NodeMotion, SensorKind,
    SolveError, StaticSettings, System, TimeFunction, UserForce, Wrench,
};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use reduction::ModeSelection;
use std::sync::Arc;
use superelement::so3::skew;
use superelement::testing::Rng;

/// A nonlinear bushing between two nodes with a follower force and a gyroscopic moment on the
/// first: $\mathbf f_a = k l\mathbf d + c(\mathbf v_b - \mathbf v_a) + \mathbf R_a\mathbf g_0$,
/// $\mathbf f_b = -k l\mathbf d - c(\mathbf v_b - \mathbf v_a)$ ($\mathbf d = \mathbf r_b - \mathbf r_a$,
/// $l = |\mathbf d|$), $\mathbf m_a = \mu(\mathbf R_a\mathbf n_0)\times\boldsymbol\omega_a$: every
/// kind of dependence (positions, orientation, velocity, angular velocity). With `analytic`, it
/// gives its Jacobians; without, the solver differentiates it.
#[derive(Debug)]
pub(crate) struct Bushing {
    pub nodes: [NodeId; 2],
    pub k: f64,
    pub c: f64,
    pub g0: Vector3<f64>,
    pub n0: Vector3<f64>,
    pub mu: f64,
    pub analytic: bool,
}

impl Bushing {
    fn new(a: NodeId, b: NodeId, analytic: bool) -> Self {
        Self {
            nodes: [a, b],
            k: 30.0,
            c: 1.5,
            g0: Vector3::new(0.4, -1.0, 0.7),
            n0: Vector3::new(0.2, 0.5, -0.3),
            mu: 0.8,
            analytic,
        }
    }
}

fn put(w: &mut Wrench, at: usize, x: &Vector3<f64>) {
    for i in 0..3 {
        w[at + i] += x[i];
    }
}

fn block(m: &mut MatMut<'_, f64>, r: usize, c: usize, b: &Matrix3<f64>) {
    for i in 0..3 {
        for j in 0..3 {
            m[(r + i, c + j)] += b[(i, j)];
        }
    }
}

impl UserForce for Bushing {
    fn name(&self) -> &str {
        "bushing"
    }
    fn nodes(&self) -> &[NodeId] {
        &self.nodes
    }
    fn force(&self, _t: f64, m: &[NodeMotion], w: &mut [Wrench]) {
        let d = m[1].r - m[0].r;
        let f = self.k * d.norm() * d + self.c * (m[1].v - m[0].v);
        put(&mut w[0], 0, &(f + m[0].R * self.g0));
        put(&mut w[0], 3, &(self.mu * (m[0].R * self.n0).cross(&m[0].omega)));
        put(&mut w[1], 0, &-f);
    }
    fn jacobian(&self, _t: f64, m: &[NodeMotion], mut dx: MatMut<'_, f64>, mut dv: MatMut<'_, f64>) -> bool {
        if !self.analytic {
            return false;
        }
        let d = m[1].r - m[0].r;
        let l = d.norm();
        // d(k l d)/dd = k (l I + d d^T / l).
        let A = self.k * (Matrix3::identity() * l + d * d.transpose() / l);
        let C = Matrix3::identity() * self.c;
        let (g, p) = (m[0].R * self.g0, m[0].R * self.n0);
        block(&mut dx, 0, 0, &-A);
        block(&mut dx, 0, 6, &A);
        block(&mut dx, 6, 0, &A);
        block(&mut dx, 6, 6, &-A);
        // delta(R g0) = delta pi x g = -g~ delta pi.
        block(&mut dx, 0, 3, &-skew(&g));
        // m = -mu w~ p, delta p = -p~ delta pi: delta m = mu w~ p~ delta pi; dm/dw = mu p~.
        block(&mut dx, 3, 3, &(self.mu * skew(&m[0].omega) * skew(&p)));
        block(&mut dv, 3, 9, &Matrix3::zeros());
        block(&mut dv, 3, 3, &(self.mu * skew(&p)));
        block(&mut dv, 0, 0, &-C);
        block(&mut dv, 0, 6, &C);
        block(&mut dv, 6, 0, &C);
        block(&mut dv, 6, 6, &-C);
        true
    }
}

/// Two node motions far from the reference: positions, orientations (rotations of about a
/// radian), velocities and angular velocities of unit size.
fn moving_nodes(seed: u64) -> Vec<NodeMotion> {
    let mut rng = Rng::new(seed);
    let mut v3 = |s: f64| Vector3::new(rng.uniform(), rng.uniform(), rng.uniform()) * s;
    (0..2)
        .map(|i| NodeMotion {
            r: v3(1.0) + Vector3::new(i as f64, 0.0, 0.0),
            R: UnitQuaternion::from_scaled_axis(v3(1.5)),
            v: v3(2.0),
            omega: v3(3.0),
            a: v3(1.0),
            alpha: v3(1.0),
        })
        .collect()
}

#[test]
fn analytic_jacobian_matches_the_central_differences() {
    let force = Bushing::new(NodeId(0), NodeId(1), true);
    let m = moving_nodes(7);
    let (mut dx, mut dv) = (Mat::zeros(12, 12), Mat::zeros(12, 12));
    assert!(force.jacobian(0.3, &m, dx.as_mut(), dv.as_mut()));
    let (mut fx, mut fv) = (Mat::zeros(12, 12), Mat::zeros(12, 12));
    finite_difference_jacobian(&force, 0.3, &m, fx.as_mut(), fv.as_mut());
    let worst = |a: &Mat<f64>, b: &Mat<f64>| {
        let scale = (0..12)
            .flat_map(|i| (0..12).map(move |j| (i, j)))
            .map(|(i, j)| a[(i, j)].abs())
            .fold(0.0, f64::max);
        (0..12)
            .flat_map(|i| (0..12).map(move |j| (i, j)))
            .map(|(i, j)| (a[(i, j)] - b[(i, j)]).abs() / scale)
            .fold(0.0, f64::max)
    };
    let (ex, ev) = (worst(&dx, &fx), worst(&dv, &fv));
    eprintln!("bushing Jacobians against central differences: dx {ex:.2e}, dv {ev:.2e} of the largest entry");
    // Steps of 1e-6 on a force whose terms vary over unit scales: truncation ~1e-12,
    // round-off ~1e-16 x |f| (~100) / 1e-6 ~ 1e-8 relative to entries of ~100: 1e-7 holds
    // both with margin, while a wrong sign or a missing term is an O(1) error.
    assert!(ex < 1e-7 && ev < 1e-7, "dx {ex:.3e}, dv {ev:.3e}");
}

#[test]
fn tangents_with_a_user_force_match_fd() {
    // Rigid chain (every joint kind) with the bushing between two distant nodes: both the
    // analytic and the finite-difference Jacobian of the force must give the assembled K and C.
    // Tolerance 1e-6 as for the chain without it (tangent.rs); the finite-difference Jacobian
    // adds errors of ~1e-8 relative (previous test), within it.
    let model = chain();
    for analytic in [true, false] {
        let force: Arc<dyn UserForce> = Arc::new(Bushing::new(NodeId(4), NodeId(10), analytic));
        let sys = System::with_user_forces(&model, vec![force]).unwrap();
        let s = random_state(&sys, 11);
        check_tangents(&sys, &s, 1e-6, 1e-6);
    }
    // Flexible bodies, springs and loads as well, on a state deformed by a few percent: the
    // tolerance of the flexible tangents (frames re-solved to 1e-12 at each evaluation), 1e-5.
    let model = mixed();
    let force: Arc<dyn UserForce> = Arc::new(Bushing::new(NodeId(2), NodeId(6), true));
    let sys = System::with_user_forces(&model, vec![force]).unwrap();
    let base = sys.initial_state();
    let mut rng = Rng::new(5);
    let dq: Vec<f64> = (0..sys.n_dof()).map(|_| 0.05 * rng.uniform()).collect();
    let mut s = sys.retract(&base, &dq);
    for i in 0..sys.n_dof() {
        s.velocity_mut()[i] = rng.uniform();
        s.acceleration_mut()[i] = rng.uniform();
    }
    sys.reset_frames(&mut s);
    check_tangents(&sys, &s, 1e-6, 1e-5);
}

/// The built-in follower force $\mathbf f = x(t)\,\mathbf R\mathbf f_0$ written as a user force
/// (the cantilever's nodes start with identity orientation, so $\mathbf f_0$ is the same vector).
#[derive(Debug)]
struct Follower {
    node: [NodeId; 1],
    f0: Vector3<f64>,
    /// $x(t) = x_0 + A\sin(\omega t)$ as `[x_0, A, omega]`, in the arithmetic of
    /// `TimeFunction::Sine`.
    sine: [f64; 3],
    analytic: bool,
}

impl Follower {
    fn x(&self, t: f64) -> f64 {
        let [offset, amplitude, omega] = self.sine;
        let a = omega * t + 0.0;
        offset + amplitude * a.sin()
    }
}

impl UserForce for Follower {
    fn name(&self) -> &str {
        "follower"
    }
    fn nodes(&self) -> &[NodeId] {
        &self.node
    }
    fn force(&self, t: f64, m: &[NodeMotion], w: &mut [Wrench]) {
        let x = self.x(t);
        put(&mut w[0], 0, &(m[0].R * self.f0 * x));
    }
    fn jacobian(&self, t: f64, m: &[NodeMotion], mut dx: MatMut<'_, f64>, _dv: MatMut<'_, f64>) -> bool {
        if self.analytic {
            let x = self.x(t);
            block(&mut dx, 0, 3, &-skew(&(m[0].R * self.f0 * x)));
        }
        self.analytic
    }
}

/// Tip displacements of a cantilever (2 superelements, 2 modes each) under a follower tip
/// force, built in or as a user force: static (load stepping to the force at t = 0) and 80
/// dynamic steps of 1 ms under a sine.
fn cantilever_runs(user: Option<bool>) -> (Vec<f64>, Vec<Vec<f64>>) {
    let (mut model, nodes) = cantilever(2, 1.0, 0.01, 1.2e9, 1000.0, ModeSelection::Count(2), 3);
    let tip = *nodes.last().unwrap();
    model.add_sensor("tip", SensorKind::NodeDisplacement { node: tip });
    let f0 = Vector3::new(0.0, 1.5, 0.2);
    let sine = [1.0, 0.5, 20.0];
    let time = TimeFunction::Sine {
        offset: sine[0],
        amplitude: sine[1],
        omega: sine[2],
        phase: 0.0,
    };
    let mut forces: Vec<Arc<dyn UserForce>> = Vec::new();
    match user {
        None => model.add_load(Load {
            node: tip,
            kind: LoadKind::Force,
            axes: LoadAxes::Follower,
            value: f0,
            time,
        }),
        Some(analytic) => forces.push(Arc::new(Follower {
            node: [tip],
            f0,
            sine,
            analytic,
        })),
    }
    let sys = System::with_user_forces(&model, forces).unwrap();
    let stat = solve_static(&sys, sys.initial_state(), &StaticSettings::new(4)).unwrap();
    let tip_static = stat.sensors.series("tip").unwrap().last().unwrap().clone();
    let traj = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(1e-3, 0.08, 0.9)).unwrap();
    (tip_static, traj.sensors.series("tip").unwrap())
}

#[test]
fn user_force_equal_to_a_follower_load_gives_its_results() {
    let (s_load, d_load) = cantilever_runs(None);
    let peak = d_load.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    let static_scale = s_load.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(static_scale > 0.1, "a large deflection: {static_scale}");
    for (analytic, tol) in [
        // Same force, same Jacobian, same element order: the same arithmetic, so round-off only.
        (true, 1e-12),
        // The finite-difference Jacobian changes the Newton iterates, not the converged
        // solution: both stop at a relative residual of 1e-9 (static and dynamic defaults), so
        // states differ by about that fraction of the motion, summed over 80 stable steps.
        (false, 1e-7),
    ] {
        let (s_user, d_user) = cantilever_runs(Some(analytic));
        let es = s_load
            .iter()
            .zip(&s_user)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / static_scale;
        let ed = d_load
            .iter()
            .flatten()
            .zip(d_user.iter().flatten())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / peak;
        eprintln!(
            "user force (analytic Jacobian: {analytic}) against the follower load: static {es:.2e}, dynamic {ed:.2e}"
        );
        assert_eq!(d_load.len(), d_user.len());
        assert!(es < tol && ed < tol, "static {es:.3e}, dynamic {ed:.3e}");
    }
}

/// A force that becomes NaN after `t_bad`.
#[derive(Debug)]
pub(crate) struct Broken {
    pub(crate) node: [NodeId; 1],
    pub(crate) t_bad: f64,
}

impl UserForce for Broken {
    fn name(&self) -> &str {
        "broken"
    }
    fn nodes(&self) -> &[NodeId] {
        &self.node
    }
    fn force(&self, t: f64, _m: &[NodeMotion], w: &mut [Wrench]) {
        w[0][1] = if t > self.t_bad { f64::NAN } else { 1.0 };
    }
}

#[test]
fn bad_user_forces_are_refused_by_name() {
    let (model, nodes) = cantilever(1, 1.0, 0.01, 1.2e9, 1000.0, ModeSelection::Count(1), 2);
    let tip = nodes[1];
    // A node the model does not have.
    let outside: Arc<dyn UserForce> = Arc::new(Broken {
        node: [NodeId(7)],
        t_bad: 1.0,
    });
    match System::with_user_forces(&model, vec![outside]) {
        Err(ModelError::UnknownNode { id, referenced_by, .. }) => {
            assert_eq!(id, 7);
            assert!(referenced_by.contains("broken"), "{referenced_by}");
        }
        other => panic!("expected UnknownNode, got {other:?}"),
    }
    // A force that turns NaN during a run: the run stops there, names the force and keeps the
    // steps before it.
    let force: Arc<dyn UserForce> = Arc::new(Broken {
        node: [tip],
        t_bad: 0.0105,
    });
    let sys = System::with_user_forces(&model, vec![force]).unwrap();
    assert!(matches!(
        sys.rigid_invariance(),
        Err(mbs::ExternalAction::Support { .. } | mbs::ExternalAction::UserForce { .. })
    ));
    let err = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(1e-3, 0.05, 0.9)).unwrap_err();
    match &err.error {
        SolveError::UserForce {
            name,
            at: mbs::At::Time(t),
            ..
        } => {
            assert_eq!(name, "broken");
            assert!((*t - 0.011).abs() < 1e-9, "{t}");
        }
        other => panic!("expected UserForce, got {other}"),
    }
    assert_eq!(err.partial.sensors.times.len(), 11, "the start and 10 converged steps");
    assert!(err.error.to_string().contains("user force 'broken'"));
}

#[test]
fn a_user_force_stops_the_momentum_projection() {
    // A free model (no support) with a user force: not rigid-invariant as far as the solver
    // can know.
    let (mut model, nodes) = cantilever(1, 1.0, 0.01, 1.2e9, 1000.0, ModeSelection::Count(1), 2);
    model.supports.clear();
    let force: Arc<dyn UserForce> = Arc::new(Broken {
        node: [nodes[1]],
        t_bad: 1.0,
    });
    let sys = System::with_user_forces(&model, vec![force]).unwrap();
    match sys.rigid_invariance() {
        Err(mbs::ExternalAction::UserForce { name }) => assert_eq!(name, "broken"),
        other => panic!("expected UserForce, got {other:?}"),
    }
}
