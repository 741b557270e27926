//! One generalized-α step (prints µs, asserts nothing).
//!
//! * The planar flexible slider-crank (validation problem C2) with the rod as 1, 2 and 4
//!   superelements (2 modes each).
//! * A cantilever chain of 1..512 identical beam superelements (static modes only) under
//!   gravity: the cost per step should grow linearly with the number of superelements (the
//!   iteration matrix is banded; element evaluation is parallel).
//!
//! Run with `cargo bench -p mbs --bench step` (release) or as a test with `cargo test --benches`.
//! `cargo bench -p mbs --bench step -- crank 2` or `-- chain 128` runs one case (for
//! `valgrind --tool=callgrind --toggle-collect='mbs::solvers::dynamic::integrator::Integrator::step'` on a
//! loaded machine, where instruction counts are the fair comparison). `-- chain N STEPS dense`
//! (or `sparse`, `modified`) forces the factorisation of the iteration matrix or modified
//! Newton (how `mbs::DENSE_MAX` was chosen).

#![allow(non_snake_case)]

#[path = "../tests/unit/fixtures.rs"]
mod fixtures;

use mbs::{DynamicSettings, Integrator, LinearSolver, Model, NewtonStrategy, Support, System};
use nalgebra::{Isometry3, Vector3};
use reduction::ModeSelection;
use std::time::Instant;
use superelement::{FrameChoice, MassVariant};

/// Mean wall time of a step and Newton iterations per step after `warm` steps.
fn time_steps(sys: &System, h: f64, warm: usize, steps: usize, newton: NewtonStrategy) -> (f64, f64) {
    let settings = DynamicSettings {
        newton,
        ..DynamicSettings::new(h, f64::INFINITY, 0.9)
    };
    let mut it = Integrator::new(sys, sys.initial_state(), settings).expect("consistent initial accelerations");
    for _ in 0..warm {
        it.step().expect("step");
    }
    let mut iterations = 0;
    let start = Instant::now();
    for _ in 0..steps {
        iterations += it.step().expect("step").residuals.len() - 1;
    }
    (
        start.elapsed().as_secs_f64() * 1e6 / steps as f64,
        iterations as f64 / steps as f64,
    )
}

/// A cantilever of `n` identical 0.1 m steel beam superelements along x under gravity.
fn chain(n: usize, body: &reduction::ReducedBody) -> Model {
    let mut m = Model::new("chain");
    let nodes: Vec<_> = (0..=n)
        .map(|i| m.add_node(&format!("n{i}"), Vector3::new(0.1 * i as f64, 0.0, 0.0)))
        .collect();
    for i in 0..n {
        let mut b = body.clone();
        b.name = format!("s{i}");
        m.add_flexible_body(
            b,
            vec![nodes[i], nodes[i + 1]],
            Isometry3::translation(0.1 * i as f64, 0.0, 0.0),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    m.add_support(Support::clamp(nodes[0]));
    m.gravity = Vector3::new(0.0, -9.81, 0.0);
    m
}

fn main() {
    // `cargo test --benches` passes `--bench`-less args; keep the run short there.
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let quick = !std::env::args().any(|a| a == "--bench");
    // `-- CASE N [STEPS]`: one case, optionally with its number of timed steps (callgrind
    // counts of two runs with different STEPS give the instructions per step, setup excluded).
    let only: Option<(&str, usize)> = match args.as_slice() {
        [case, n, ..] => Some((case.as_str(), n.parse().expect("a number of superelements"))),
        _ => None,
    };
    let steps_arg: Option<usize> = args.get(2).map(|s| s.parse().expect("a number of steps"));
    let option = args.get(3).map(String::as_str);
    let solver = match option {
        Some("dense") => LinearSolver::Dense,
        Some("sparse") => LinearSolver::Sparse,
        _ => LinearSolver::Auto,
    };
    let newton = match option {
        Some("modified") => NewtonStrategy::Modified,
        _ => NewtonStrategy::Full,
    };
    let run = |case: &str, n: usize| only.is_none_or(|(c, m)| c == case && m == n);
    println!("slider-crank (C2), rod as N superelements with 2 modes, h = T/400:");
    for n in [1, 2, 4] {
        if !run("crank", n) {
            continue;
        }
        let (model, _, _) = fixtures::slider_crank(n, ModeSelection::Count(2), 150.0);
        let mut sys = System::new(&model).unwrap();
        sys.set_linear_solver(solver);
        let h = 2.0 * std::f64::consts::PI / 150.0 / 400.0;
        let (us, its) = time_steps(&sys, h, 20, steps_arg.unwrap_or(if quick { 10 } else { 200 }), newton);
        println!(
            "  N = {n:3}: {:5} unknowns, {us:10.1} µs/step, {its:.2} iterations/step",
            sys.n_dof()
        );
    }
    println!("cantilever chain of N superelements (static modes), gravity, h = 1 ms:");
    let body = fixtures::beam_body(
        "segment",
        Vector3::zeros(),
        Vector3::new(0.1, 0.0, 0.0),
        3,
        0.01,
        2.1e11,
        7800.0,
        ModeSelection::StaticOnly,
    );
    let max = if quick && only.is_none() { 64 } else { 512 };
    let mut n = 1;
    while n <= max {
        if run("chain", n) {
            let mut sys = System::new(&chain(n, &body)).unwrap();
            sys.set_linear_solver(solver);
            let (us, its) = time_steps(&sys, 1e-3, 3, steps_arg.unwrap_or(if quick { 3 } else { 20 }), newton);
            println!(
                "  N = {n:3}: {:5} unknowns, {us:10.1} µs/step, {its:.2} iterations/step, {:8.2} µs per superelement-iteration",
                sys.n_dof(),
                us / (its * n as f64)
            );
        }
        n *= 2;
    }
}
