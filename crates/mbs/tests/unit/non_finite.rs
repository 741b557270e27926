//! A tangent that is not finite stops the static analyses with what made it named.

use faer::MatMut;
use mbs::{
    solve_arc_length, solve_static, ArcLengthSettings, Model, NodeId, NodeMotion, PointMass, SolveError,
    StaticSettings, Support, System, UserForce, Wrench,
};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// A bushing f = k |d| d between two nodes, d = r_b - r_a, with its analytic Jacobian
/// k (|d| I + d d^T / |d|): where the nodes coincide the force is 0 but the Jacobian is 0/0.
#[derive(Debug)]
struct Bushing {
    nodes: [NodeId; 2],
    k: f64,
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
        let f = self.k * d.norm() * d;
        for i in 0..3 {
            w[0][i] += f[i];
            w[1][i] -= f[i];
        }
    }
    fn jacobian(&self, _t: f64, m: &[NodeMotion], mut dx: MatMut<'_, f64>, _dv: MatMut<'_, f64>) -> bool {
        let d = m[1].r - m[0].r;
        let l = d.norm();
        let A = self.k * (Matrix3::identity() * l + d * d.transpose() / l);
        for i in 0..3 {
            for j in 0..3 {
                dx[(i, j)] -= A[(i, j)];
                dx[(i, 6 + j)] += A[(i, j)];
                dx[(6 + i, j)] += A[(i, j)];
                dx[(6 + i, 6 + j)] -= A[(i, j)];
            }
        }
        true
    }
}

/// A point mass on node b under gravity, tied by the bushing to the clamped node a at the
/// same place: Newton's first tangent is 0/0, and load stepping (after its cut-backs, which
/// cannot cure it) and arc length (in its first predictor, at load factor 0) stop with the
/// user force named and the load factor said, and no step converged.
#[test]
fn a_jacobian_that_is_not_finite_stops_the_static_analyses_with_its_force_named() {
    let mut model = Model::new("bushing at its singular point");
    model.gravity = Vector3::new(0.0, -9.81, 0.0);
    let a = model.add_node("a", Vector3::zeros());
    let b = model.add_node("b", Vector3::zeros());
    model.add_support(Support::clamp(a));
    model.add_support(Support {
        node: b,
        translation: mbs::TranslationSupport::Free,
        rotation: mbs::RotationSupport::Fixed,
    });
    model.point_masses.push(PointMass { node: b, mass: 1.0 });
    let bushing: Arc<dyn UserForce> = Arc::new(Bushing { nodes: [a, b], k: 1e3 });
    let sys = System::with_user_forces(&model, vec![bushing]).unwrap();
    let check = |e: &SolveError| match e {
        SolveError::UserForce { name, what, at, .. } => {
            assert_eq!(name, "bushing", "{e}");
            assert!(what.contains("Jacobian is not finite"), "{e}");
            assert!(at.load_factor().is_some_and(|l| (0.0..1e-5).contains(&l)), "{e}");
            assert_eq!(e.entity(), Some(mbs::Entity::UserForce(0)));
        }
        e => panic!("{e}"),
    };
    let fail = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap_err();
    check(&fail.error);
    assert!(fail.partial.steps.is_empty());
    let fail = solve_arc_length(&sys, sys.initial_state(), &ArcLengthSettings::new(0.1, 1.0, 20)).unwrap_err();
    check(&fail.error);
}
