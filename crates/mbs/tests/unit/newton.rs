//! Newton strategies and linear solvers of the dynamic step: modified Newton against full
//! Newton (flexible slider-crank, rigid pendulum, adaptive steps, failures), and the dense LU
//! against the sparse one (same steps; both refuse a singular mass matrix).

use crate::fixtures::{released, slider_crank};
use mbs::{
    solve_dynamic, solve_dynamic_adaptive, AdaptiveSettings, DynamicSettings, LinearSolver, NewtonStrategy, SolveError,
    System, Trajectory,
};
use reduction::ModeSelection;

/// Largest difference of sensor `name` (component `k`) between two runs with the same
/// output times, relative to its largest magnitude in `a`.
fn relative_difference(a: &Trajectory, b: &Trajectory, name: &str, k: usize) -> f64 {
    assert_eq!(a.sensors.times, b.sensors.times);
    let (x, y) = (a.sensors.column(name, k).unwrap(), b.sensors.column(name, k).unwrap());
    let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    x.iter().zip(&y).map(|(u, v)| (u - v).abs()).fold(0.0, f64::max) / peak
}

/// The slider-crank (C2, the rod as two superelements with two modes) over a quarter revolution at
/// h = T/400 with `newton` and the linear solver `solver`.
fn crank_run(newton: NewtonStrategy, solver: LinearSolver) -> Trajectory {
    let speed = 150.0;
    let (model, _, _) = slider_crank(2, ModeSelection::Count(2), speed);
    let mut sys = System::new(&model).unwrap();
    sys.set_linear_solver(solver);
    let period = 2.0 * std::f64::consts::PI / speed;
    let settings = DynamicSettings {
        newton,
        ..DynamicSettings::new(period / 400.0, 0.25 * period, 0.9)
    };
    solve_dynamic(&sys, sys.initial_state(), &settings).unwrap()
}

#[test]
fn modified_newton_follows_full_newton_on_the_flexible_slider_crank() {
    let full = crank_run(NewtonStrategy::Full, LinearSolver::Auto);
    let modified = crank_run(NewtonStrategy::Modified, LinearSolver::Auto);
    let (w, x) = (
        relative_difference(&full, &modified, "midpoint", 0),
        relative_difference(&full, &modified, "slider", 0),
    );
    let sum = |v: &[usize]| v.iter().sum::<usize>();
    eprintln!(
        "slider-crank, {} steps: full {} iterations / {} Jacobians, modified {} / {}; midpoint deflection differs by {w:.2e}, slider by {x:.2e} of their peaks",
        full.iterations.len(),
        sum(&full.iterations),
        sum(&full.jacobians),
        sum(&modified.iterations),
        sum(&modified.jacobians)
    );
    // Both stop at a relative residual of 1e-9, so the two converged iterates of a step differ
    // by about that fraction of the motion, and the differences of 100 stable steps add up to
    // at most 100 x 1e-9 (measured 7e-11 for the deflection). An error of the modified
    // iteration itself (a wrong correction) stops far from the solution or not at all.
    assert!(w < 1e-7 && x < 1e-7, "{w:.3e}, {x:.3e}");
    // Full Newton factorises at every correction; modified Newton keeps its matrix.
    assert_eq!(full.iterations, full.jacobians);
    assert!(
        sum(&modified.jacobians) < sum(&full.jacobians) / 2,
        "{:?}",
        modified.jacobians
    );
    assert_eq!(modified.jacobians[0], 1, "the first step has no matrix to reuse");
}

#[test]
fn fitted_predictor_converges_to_the_same_steps_with_fewer_corrections() {
    // Full Newton starts from the fitted predictor (module docs of `dynamic_solver`,
    // "Predictor"); the reference starts every step from constant accelerations (modified
    // Newton, which keeps that predictor) and converges to a 1000 times tighter tolerance.
    // Each step of the fitted run stops at a relative residual of 1e-9, so 100 stable steps
    // differ from the reference by at most 100 x 1e-9 of the motion (as modified against full
    // Newton above); a predictor that led Newton elsewhere would differ by the motion itself.
    let full = crank_run(NewtonStrategy::Full, LinearSolver::Auto);
    let speed = 150.0;
    let (model, _, _) = slider_crank(2, ModeSelection::Count(2), speed);
    let sys = System::new(&model).unwrap();
    let period = 2.0 * std::f64::consts::PI / speed;
    let settings = DynamicSettings {
        tolerance: 1e-12,
        newton: NewtonStrategy::Modified,
        ..DynamicSettings::new(period / 400.0, 0.25 * period, 0.9)
    };
    let tight = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
    let w = relative_difference(&tight, &full, "midpoint", 0);
    let x = relative_difference(&tight, &full, "slider", 0);
    let steps = full.iterations.len();
    let corrections = full.iterations.iter().sum::<usize>() as f64 / steps as f64;
    // The first PREDICTOR_WINDOW + 1 steps start from constant accelerations.
    let fitted = full.iterations[mbs::PREDICTOR_WINDOW + 1..].iter().sum::<usize>() as f64
        / (steps - mbs::PREDICTOR_WINDOW - 1) as f64;
    eprintln!(
        "fitted predictor: {corrections:.3} corrections per step ({fitted:.3} once fitted); against the tight run the deflection differs by {w:.2e}, the slider by {x:.2e} of their peaks"
    );
    assert!(w < 1e-7 && x < 1e-7, "{w:.3e}, {x:.3e}");
    // Measured 2.00 corrections per step on the C2 rod of the benchmark (2.19 from constant
    // accelerations); here, once the window is full, no step needs a third correction.
    assert!(fitted <= 2.0, "{fitted}");
}

#[test]
fn modified_newton_follows_full_newton_on_a_rigid_pendulum() {
    let sys = released(2.0);
    let run = |newton| {
        let settings = DynamicSettings {
            newton,
            ..DynamicSettings::new(2e-3, 2.0, 0.9)
        };
        solve_dynamic(&sys, sys.initial_state(), &settings).unwrap()
    };
    let (full, modified) = (run(NewtonStrategy::Full), run(NewtonStrategy::Modified));
    let d = relative_difference(&full, &modified, "theta", 0);
    let sum = |v: &[usize]| v.iter().sum::<usize>();
    eprintln!(
        "pendulum: full {} Jacobians, modified {} Jacobians and {} iterations; theta differs by {d:.2e}",
        sum(&full.jacobians),
        sum(&modified.jacobians),
        sum(&modified.iterations)
    );
    // As for the slider-crank: 1000 steps that each stop at 1e-9 (measured 7e-10).
    assert!(d < 1e-6, "{d:.3e}");
    assert!(sum(&modified.jacobians) < sum(&full.jacobians));
}

#[test]
fn modified_newton_with_adaptive_steps() {
    // The pendulum released from 2 rad with the adaptive step: every change of h refactorises,
    // the trajectories agree, and each accepted step reports its Jacobians.
    let sys = released(2.0);
    let run = |newton| {
        let settings = DynamicSettings {
            newton,
            tolerance: 1e-12,
            ..DynamicSettings::new(1e-3, 2.0, 1.0)
        };
        let adaptive = AdaptiveSettings::new(1e-6, 1e-6, 0.1);
        solve_dynamic_adaptive(&sys, sys.initial_state(), &settings, &adaptive).unwrap()
    };
    let (full, modified) = (run(NewtonStrategy::Full), run(NewtonStrategy::Modified));
    let (xf, xm) = (
        *full.sensors.column("theta", 0).unwrap().last().unwrap(),
        *modified.sensors.column("theta", 0).unwrap().last().unwrap(),
    );
    eprintln!(
        "adaptive pendulum: full {} steps, modified {} steps ({} Jacobians); theta(2 s) {xf:.9} vs {xm:.9}",
        full.iterations.len(),
        modified.iterations.len(),
        modified.jacobians.iter().sum::<usize>()
    );
    assert_eq!(modified.jacobians.len(), modified.iterations.len());
    // Both step sequences meet the local tolerance 1e-6 per step; they differ only through the
    // Newton tolerance (1e-12) in the error estimates, so the end states agree far inside
    // the global error of either (steps x 1e-6 ~ 1e-4).
    assert!((xf - xm).abs() < 1e-6, "{xf} vs {xm}");
    assert_eq!(modified.jacobians[0], 1, "the first step has no matrix to reuse");
}

#[test]
fn modified_newton_still_reports_a_step_that_does_not_converge() {
    // One iteration allowed and a tolerance below round-off: modified Newton fails, full
    // Newton is tried and fails too, and the error names the time, step and residual.
    let sys = released(1.0);
    let settings = DynamicSettings {
        max_iterations: 1,
        tolerance: 1e-30,
        newton: NewtonStrategy::Modified,
        ..DynamicSettings::new(0.01, 1.0, 0.8)
    };
    let err = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap_err();
    let text = err.to_string();
    match err.error {
        SolveError::NotConverged {
            at: mbs::At::Time(t),
            step,
            residual,
            ..
        } => {
            assert_eq!(step, 1);
            assert!((t - 0.01).abs() < 1e-15);
            assert!(residual > 0.0 && residual.is_finite());
            assert!(text.contains("t = 0.010000") && text.contains("step 1"), "{text}");
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(err.partial.sensors.times, vec![0.0]);
}

#[test]
fn dense_and_sparse_lu_give_the_same_steps() {
    // The slider-crank (13 unknowns: dense under `Auto`) with each factorisation forced: the
    // corrections agree to round-off, so the runs agree far inside the Newton tolerance.
    let dense = crank_run(NewtonStrategy::Full, LinearSolver::Dense);
    let sparse = crank_run(NewtonStrategy::Full, LinearSolver::Sparse);
    let w = relative_difference(&dense, &sparse, "midpoint", 0);
    eprintln!("dense against sparse LU: midpoint deflection differs by {w:.2e} of its peak");
    assert_eq!(dense.iterations, sparse.iterations);
    // Round-off of two LU factorisations (pivoting orders differ) propagated over 100 steps:
    // 100 x 1e-12 (measured 1.5e-14), far below the Newton tolerance.
    assert!(w < 1e-10, "{w:.3e}");
    let modified = crank_run(NewtonStrategy::Modified, LinearSolver::Sparse);
    let m = relative_difference(&dense, &modified, "midpoint", 0);
    // Modified against full Newton, as in the test above: 100 x 1e-9.
    assert!(m < 1e-7, "modified Newton on the sparse LU: {m:.3e}");
}

#[test]
fn both_factorisations_refuse_a_massless_coordinate() {
    // A slider held by a spring and nothing else: the system builds (the spring holds the
    // coordinate), but its mass matrix is zero, so the consistent initial accelerations are
    // refused as singular by either LU (the dense one at its zero pivot, naming the unknown).
    let mut m = mbs::Model::new("massless slider");
    let a = m.add_node("a", nalgebra::Vector3::new(1.0, 0.0, 0.0));
    m.add_support(mbs::Support::slider(a, nalgebra::Vector3::x()));
    m.springs.push(mbs::Spring {
        name: "k".into(),
        a,
        b: None,
        ground_point: nalgebra::Vector3::zeros(),
        stiffness: 100.0,
        damping: 0.0,
        rest_length: None,
    });
    for solver in [LinearSolver::Dense, LinearSolver::Sparse] {
        let mut sys = System::new(&m).unwrap();
        sys.set_linear_solver(solver);
        let settings = DynamicSettings::new(1e-3, 1.0, 0.9);
        match mbs::Integrator::new(&sys, sys.initial_state(), settings) {
            Err(SolveError::Singular { what, .. }) => {
                assert!(what.contains("mass matrix"), "{solver:?}: {what}");
                if solver == LinearSolver::Dense {
                    assert!(what.contains("zero pivot at unknown 0"), "{what}");
                }
            }
            Err(e) => panic!("{solver:?}: {e}"),
            Ok(_) => panic!("{solver:?}: a zero mass matrix was factorised"),
        }
    }
}

/// A clone of the integrator steps as the original does, to the last bit, with either
/// factorisation kept across steps by modified Newton (the faer dense LU above 32 unknowns,
/// its scratch allocated anew by the clone; the sparse LU): what `study::Simulation::save`
/// rests on.
#[test]
fn a_cloned_integrator_repeats_the_steps_bit_for_bit() {
    let speed = 150.0;
    // Eight superelements: above the small dense LU's 32 unknowns.
    let (model, _, _) = slider_crank(8, ModeSelection::Count(2), speed);
    for solver in [LinearSolver::Dense, LinearSolver::Sparse] {
        let mut sys = System::new(&model).unwrap();
        assert!(sys.n_dof() > 32, "{} unknowns", sys.n_dof());
        sys.set_linear_solver(solver);
        let period = 2.0 * std::f64::consts::PI / speed;
        let settings = DynamicSettings {
            newton: NewtonStrategy::Modified,
            ..DynamicSettings::new(period / 400.0, 0.25 * period, 0.9)
        };
        let mut integ = mbs::Integrator::new(&sys, sys.initial_state(), settings).unwrap();
        for _ in 0..15 {
            integ.step().unwrap();
        }
        let mut copy = integ.clone();
        for k in 0..15 {
            let (a, b) = (integ.step().unwrap(), copy.step().unwrap());
            assert_eq!(a, b, "{solver:?}: report of step {k}");
            let (s, t) = (integ.state(), copy.state());
            assert_eq!(s.time().to_bits(), t.time().to_bits());
            assert_eq!(s.coordinates(), t.coordinates(), "{solver:?}: step {k}");
            assert_eq!(s.velocity(), t.velocity(), "{solver:?}: step {k}");
            assert_eq!(s.acceleration(), t.acceleration(), "{solver:?}: step {k}");
        }
    }
}
