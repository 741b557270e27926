//! Linearised analysis about static states.

use crate::fixtures::cantilever;
use mbs::{solve_static, spectrum, StaticSettings, System};
use nalgebra::Vector3;
use reduction::ModeSelection;

const E: f64 = 2.1e11;
const RHO: f64 = 7800.0;
const SIDE: f64 = 0.01;

/// First bending frequency of the clamped-free Euler-Bernoulli beam (A1), L = 1.
fn omega_1() -> f64 {
    let EI = E * SIDE.powi(4) / 12.0;
    let rhoA = RHO * SIDE * SIDE;
    1.87510407f64.powi(2) * (EI / rhoA).sqrt()
}

#[test]
fn cantilever_frequencies_match_euler_bernoulli() {
    let (model, _) = cantilever(4, 1.0, SIDE, E, RHO, ModeSelection::Count(2), 4);
    let sys = System::new(&model).unwrap();
    let sp = spectrum(&sys, &sys.initial_state()).unwrap();
    let w1 = omega_1();
    let w2 = 4.69409113f64.powi(2) / 1.87510407f64.powi(2) * w1;
    eprintln!(
        "first frequencies {:?} rad/s; Euler-Bernoulli {w1:.4}, {w2:.4}",
        &sp.omega[..6]
    );
    // Square section: each bending frequency twice. 4 superelements of 4 consistent-mass
    // elements with 2 fixed-interface modes each reproduce the 16-element beam, whose first
    // two frequencies are within 1e-5 and 1e-4 of the continuum.
    for (w, exact) in [
        (sp.omega[0], w1),
        (sp.omega[1], w1),
        (sp.omega[2], w2),
        (sp.omega[3], w2),
    ] {
        assert!((w - exact).abs() < 2e-4 * exact, "{w} vs {exact}");
    }
    // No damping: the state-space eigenvalues are ±i omega (to the accuracy of the
    // nonsymmetric eigensolver on the 2n system, ~1e-7 relative here).
    let (re, im) = sp.state_space[0];
    assert!(
        re.abs() < 1e-5 * w1 && (im - sp.omega[0]).abs() < 1e-6 * w1,
        "{re} {im}"
    );
}

#[test]
fn axial_preload_changes_the_bending_frequency() {
    // Tension stiffens, compression softens (geometric stiffness of the superelements, in K).
    let first = |P: f64| {
        let (mut model, nodes) = cantilever(4, 1.0, SIDE, E, RHO, ModeSelection::Count(1), 4);
        model.add_dead_force(nodes[4], Vector3::new(P, 0.0, 0.0));
        let sys = System::new(&model).unwrap();
        let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap();
        spectrum(&sys, &sol.state).unwrap().omega[0]
    };
    // Euler buckling load of the cantilever: pi^2 EI / (4 L^2) = 90 N; use a third of it.
    let P = 30.0;
    let (wt, w0, wc) = (first(P), first(0.0), first(-P));
    eprintln!("first frequency: tension {wt:.4}, none {w0:.4}, compression {wc:.4}");
    // Rayleigh estimate: w^2 changes by about P/P_cr of w^2 * 0.8; here +-15 % in w^2.
    assert!(wt > w0 * 1.03 && wc < w0 * 0.97, "{wt} {w0} {wc}");
}
