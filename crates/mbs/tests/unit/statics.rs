//! Geometrically nonlinear statics of a cantilever made of N beam superelements.

use crate::fixtures::cantilever;
use mbs::{solve_static, SensorKind, StaticSettings, System};
use nalgebra::Vector3;
use reduction::ModeSelection;

/// Mattiasson's elastica (benchmarks.md B1): a -> (w/L, u/L, tip rotation).
pub const ELASTICA: [(f64, [f64; 3]); 7] = [
    (1.0, [0.30172, 0.05643, 0.46135]),
    (2.0, [0.49346, 0.16064, 0.78175]),
    (3.0, [0.60325, 0.25442, 0.98602]),
    (4.0, [0.66996, 0.32894, 1.12124]),
    (5.0, [0.71379, 0.38763, 1.21537]),
    (7.0, [0.76737, 0.47293, 1.33496]),
    (10.0, [0.81061, 0.55500, 1.43029]),
];

/// Square section 10 mm, L = 1, E chosen for EI = 1 N m^2: slenderness L/r = 346 and axial
/// strain a/(EA) < 5e-5, far below the table's 5 digits.
pub const SIDE: f64 = 0.01;
pub const E: f64 = 1.2e9;

/// Tip (w/L, u/L, rotation) of the cantilever of `n` superelements under tip load `a` (force,
/// `moment = false`) or `b` (moment), with the Newton histories of the load steps.
pub fn tip(n: usize, load: f64, moment: bool) -> ([f64; 3], Vec<Vec<f64>>) {
    let (mut model, nodes) = cantilever(n, 1.0, SIDE, E, 1000.0, ModeSelection::StaticOnly, 3);
    let tip = *nodes.last().unwrap();
    let EI = E * SIDE.powi(4) / 12.0;
    if moment {
        model.add_dead_moment(tip, Vector3::new(0.0, 0.0, load * EI));
    } else {
        model.add_dead_force(tip, Vector3::new(0.0, load * EI, 0.0));
    }
    model.add_sensor("tip", SensorKind::NodeDisplacement { node: tip });
    model.add_sensor("rot", SensorKind::NodeRotation { node: tip });
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(4)).unwrap();
    let d = sol.sensors.series("tip").unwrap().last().unwrap().clone();
    let r = sol.sensors.series("rot").unwrap().last().unwrap().clone();
    (
        [d[1], -d[0], r[2]],
        sol.steps.iter().map(|s| s.residuals.clone()).collect(),
    )
}

/// Order of the last Newton iteration, log r_last / log r_prev (relative residuals below one:
/// 2 for r_last = r_prev^2).
pub fn last_order(history: &[f64]) -> f64 {
    let k = history.len() - 1;
    history[k].ln() / history[k - 1].ln()
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
    let (_, histories) = tip(4, 5.0, false);
    let last = histories.last().unwrap();
    let order = last_order(last);
    eprintln!("residual history of the last load step: {last:?}, order {order:.2}");
    // Quadratic: the last residual is (at least) the square of the one before. Earlier
    // iterations of a large load step alternate (a correction with large rotations strains the
    // stiff axial direction), as is usual for additive Newton corrections on slender beams.
    assert!(order > 1.8, "{last:?}");
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

#[test]
#[ignore]
fn print_histories() {
    for n in [1, 4, 8] {
        let (_, h) = tip(n, 5.0, false);
        let total: usize = h.iter().map(|s| s.len() - 1).sum();
        eprintln!("N={n}: {} load steps, {total} iterations", h.len());
        for s in &h {
            eprintln!("  {:?}", s.iter().map(|x| format!("{x:.1e}")).collect::<Vec<_>>());
        }
    }
}
