//! One evaluation of forces and all tangents (K_t, C_t, M) of a 2-interface beam with 10
//! fixed-interface modes (n = 22), warm-started frame, for each frame choice and inertia
//! variant, through `evaluate_into` with a reused workspace (the hot-loop form) and through the
//! allocating `evaluate`. Prints microseconds per evaluation (median of batches); timings are never asserted
//! (style R20). Run: `cargo bench -p superelement --bench evaluate`.

use nalgebra::{Point3, Vector3};
use reduction::ModeSelection;
use std::time::Instant;
use superelement::testing::{fixtures, test_state, StateSpec};
use superelement::{Damping, FrameChoice, MassVariant, Superelement};

fn main() {
    // `cargo bench` passes `--bench`; `cargo test --benches` does not and runs this once as a
    // smoke test (style R20): keep it short there.
    let quick = !std::env::args().any(|a| a == "--bench");
    let (_model, _nodes, body) = fixtures::straight_beam(
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(1.0, 0.2, 0.1),
        20,
        ModeSelection::Count(10),
        false,
    );
    println!(
        "superelement evaluate: N = {}, m = {}, n = {}",
        body.interfaces.len(),
        body.n_modes,
        body.n_coordinates()
    );
    let g = Vector3::new(0.0, 0.0, -9.81);
    for frame in [FrameChoice::CenterOfMass, FrameChoice::InterfaceNode(0)] {
        for mass in [MassVariant::Exact, MassVariant::Lumped] {
            let se = Superelement::new(&body, frame, mass, Damping::rayleigh(0.0, 1e-4)).unwrap();
            let (mut state, acc) = test_state(&se, &StateSpec::moving(120.0, 1));
            state.frame = se.solve_frame(&state).unwrap().0;
            // Many short batches: on a loaded machine the fastest batches are the uninterrupted ones.
            let (batches, per) = if quick { (1, 2) } else { (400, 25) };
            let mut ws = se.workspace();
            let mut out = superelement::Evaluation::zeros(se.n_coordinates());
            let mut sink = 0.0;
            let mut time = |tangents: bool, sink: &mut f64| {
                let mut times = Vec::with_capacity(batches);
                for _ in 0..batches {
                    let t = Instant::now();
                    for _ in 0..per {
                        se.evaluate_into(&state, &acc, &g, tangents, &mut ws, &mut out).unwrap();
                        *sink += out.residual[0];
                    }
                    times.push(t.elapsed().as_secs_f64() * 1e6 / per as f64);
                }
                times.sort_by(|a, b| a.partial_cmp(b).unwrap());
                (times[times.len() / 2], times[0])
            };
            let (all, all_min) = time(true, &mut sink);
            let (forces, _) = time(false, &mut sink);
            let alloc = {
                let t = Instant::now();
                for _ in 0..per {
                    sink += se.evaluate(&state, &acc, &g).unwrap().stiffness[(0, 0)];
                }
                t.elapsed().as_secs_f64() * 1e6 / per as f64
            };
            println!(
                "  {:<18} {:<7} forces + K_t, C_t, M: {all:6.1} us (median; min {all_min:.1})   forces + M only: {forces:6.1} us   allocating evaluate(): {alloc:6.1} us   [{sink:.1e}]",
                frame.to_string(),
                format!("{mass:?}")
            );
        }
    }
}
