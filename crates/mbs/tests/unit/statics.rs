//! Geometrically nonlinear statics of a cantilever made of N beam superelements.

use crate::fixtures::{cantilever, elastica_tip as tip, ELASTICA, ELASTICA_E as E, ELASTICA_SIDE as SIDE};
use mbs::{solve_static, SensorKind, StaticSettings, System};
use nalgebra::Vector3;
use reduction::ModeSelection;

/// Order of the last Newton correction above round-off (1e-11 of the model size):
/// log d_{k+1} / log d_k for corrections below 0.1 (2 for d_{k+1} = d_k^2).
pub fn last_order(history: &[f64]) -> f64 {
    (1..history.len())
        .filter(|&k| history[k - 1] < 0.1 && history[k] > 1e-11)
        .map(|k| history[k].ln() / history[k - 1].ln())
        .next_back()
        .unwrap_or(0.0)
}

#[test]
fn elastica_approaches_the_table_at_second_order() {
    for &(a, reference) in ELASTICA.iter().filter(|(a, _)| [1.0, 2.0, 5.0].contains(a)) {
        let mut errors = Vec::new();
        for n in [1, 2, 4, 8] {
            let (t, _) = tip(n, a, false);
            let err = (0..3).map(|i| (t[i] - reference[i]).abs()).fold(0.0, f64::max);
            eprintln!(
                "a = {a}, N = {n}: w/L {:.5} u/L {:.5} rot {:.5}  (max error {err:.2e})",
                t[0], t[1], t[2]
            );
            errors.push(err);
        }
        // Each superelement is a linear beam in its own frame, so the error of the chain falls
        // as the square of the element size: ratio 4 per halving (3 allows for the table's
        // five digits and the O(1/N^3) terms).
        for w in errors.windows(2).skip(1) {
            assert!(w[0] / w[1] > 3.0, "a = {a}: errors {errors:?}");
        }
        assert!(errors[3] < 5e-3 * a.max(1.0), "a = {a}: N = 8 error {}", errors[3]);
    }
}

#[test]
fn roll_up_approaches_the_arc() {
    let b = std::f64::consts::FRAC_PI_2;
    let exact = [(1.0 - b.cos()) / b, 1.0 - b.sin() / b, b];
    let mut errors = Vec::new();
    for n in [1, 2, 4, 8] {
        let (t, _) = tip(n, b, true);
        let err = (0..3).map(|i| (t[i] - exact[i]).abs()).fold(0.0, f64::max);
        eprintln!(
            "b = pi/2, N = {n}: w/L {:.5} u/L {:.5} rot {:.5} (max error {err:.2e})",
            t[0], t[1], t[2]
        );
        errors.push(err);
    }
    for w in errors.windows(2).skip(1) {
        assert!(w[0] / w[1] > 3.0, "errors {errors:?}");
    }
}

#[test]
fn newton_converges_quadratically() {
    let (_, steps) = tip(4, 5.0, false);
    let last = steps.last().unwrap();
    let order = last_order(&last.increments);
    eprintln!("last load step: residuals {:?}", last.residuals);
    eprintln!("                corrections {:?}, order {order:.2}", last.increments);
    // Quadratic: the last correction above round-off is the square of the one before. The
    // residuals jump in the first iterations of a large load step (a correction with large
    // rotations strains the stiff axial direction) and show it less clearly.
    assert!(order > 1.8, "{:?}", last.increments);
    // The residual's last drop is quadratic too (3e-5 to 4e-12 here).
    let r = &last.residuals;
    let k = r.len() - 1;
    assert!(r[k].ln() / r[k - 1].ln() > 1.8, "{r:?}");
}

#[test]
fn clamp_reaction_balances_the_tip_load() {
    // The reaction is the force and moment the support applies to the model: -P and
    // -(x_tip P) about z for the elastica a = 2 (tip load P = 2 EI/L^2 along y).
    let (mut model, nodes) = cantilever(4, 1.0, SIDE, E, 1000.0, ModeSelection::StaticOnly, 3);
    let EI = E * SIDE.powi(4) / 12.0;
    let P = 2.0 * EI;
    model.add_dead_force(nodes[4], Vector3::new(0.0, P, 0.0));
    model.add_sensor("reaction", SensorKind::Reaction { node: nodes[0] });
    model.add_sensor("tip", SensorKind::NodePosition { node: nodes[4] });
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(2)).unwrap();
    let r = sol.sensors.series("reaction").unwrap().last().unwrap().clone();
    let x = sol.sensors.series("tip").unwrap().last().unwrap().clone();
    // Equilibrium holds to the Newton tolerance (1e-10 of the force scale, about P).
    let expected = [0.0, -P, 0.0, 0.0, 0.0, -x[0] * P];
    for i in 0..6 {
        assert!((r[i] - expected[i]).abs() < 1e-8 * P, "reaction {r:?} vs {expected:?}");
    }
}

/// A static analysis that stops says where in its own terms: the load factor and the load
/// step, never a time (a dynamic analysis says `t = ...`: `newton.rs`, `user_force.rs`).
/// Newton allowed one iteration below round-off stops in the first load step at the full
/// load; a user force that is never finite stops the load stepping at its smallest increment,
/// named at the load factor of that last attempt. (A body whose floating frame fails in an
/// equilibrium: the study test `a_solver_failure_at_a_body_is_located_at_the_body_in_the_study_file`.)
#[test]
fn a_static_failure_names_the_load_factor_and_the_load_step() {
    let (mut model, nodes) = cantilever(4, 1.0, SIDE, E, 1000.0, ModeSelection::StaticOnly, 3);
    let EI = E * SIDE.powi(4) / 12.0;
    model.add_dead_force(nodes[4], Vector3::new(0.0, 2.0 * EI, 0.0));
    let sys = System::new(&model).unwrap();
    let settings = StaticSettings {
        max_iterations: 1,
        tolerance: 1e-30,
        min_increment: 0.6,
        ..StaticSettings::new(1)
    };
    let fail = solve_static(&sys, sys.initial_state(), &settings).unwrap_err();
    match &fail.error {
        mbs::SolveError::NotConverged {
            at: mbs::At::LoadFactor(l),
            step,
            ..
        } => assert_eq!((*l, *step), (1.0, 1)),
        e => panic!("{e:?}"),
    }
    let msg = fail.error.to_string();
    assert!(
        msg.contains("at load factor 1.000000 (step 1)") && !msg.contains("t ="),
        "{msg}"
    );

    let broken: std::sync::Arc<dyn mbs::UserForce> = std::sync::Arc::new(crate::user_force::Broken {
        node: [nodes[4]],
        t_bad: -1.0,
    });
    let sys = System::with_user_forces(&model, vec![broken]).unwrap();
    let fail = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap_err();
    let tried = fail.partial.rejected.last().unwrap().lambda;
    assert!(tried < 1e-5, "halved to the smallest increment: {tried}");
    match &fail.error {
        mbs::SolveError::UserForce { at, .. } => assert_eq!(*at, mbs::At::LoadFactor(tried)),
        e => panic!("expected the user force to stop it: {e:?}"),
    }
    let msg = fail.error.to_string();
    assert!(
        msg.contains(&format!("user force 'broken' at load factor {tried:.6}")) && !msg.contains("t ="),
        "{msg}"
    );
}
