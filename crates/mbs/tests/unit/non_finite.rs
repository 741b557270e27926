//! A tangent that is not finite stops the static analyses with what made it named.

use crate::user_force::Bushing;
use mbs::{
    solve_arc_length, solve_static, ArcLengthSettings, Model, PointMass, SolveError, StaticSettings, Support, System,
    UserForce,
};
use nalgebra::Vector3;
use std::sync::Arc;

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
    model.point_masses.push(PointMass {
        name: String::new(),
        node: b,
        mass: 1.0,
    });
    // The bushing of the user-force tests as a pure spring f = k |d| d with its analytic
    // Jacobian k (|d| I + d d^T / |d|): where the nodes coincide the force is 0 but the
    // Jacobian is 0/0.
    let bushing: Arc<dyn UserForce> = Arc::new(Bushing {
        nodes: [a, b],
        k: 1e3,
        c: 0.0,
        g0: Vector3::zeros(),
        n0: Vector3::zeros(),
        mu: 0.0,
        analytic: true,
    });
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
