//! One evaluation of forces and all tangents (K_t, C_t, M) of a superelement, warm-started
//! frame, through `evaluate_into` with a reused workspace (the hot-loop form) and through the
//! allocating `evaluate`. Prints microseconds per evaluation (median of batches); timings are
//! never asserted. Run: `cargo bench -p superelement --bench evaluate`.
//!
//! Cases (a substring of the name as an argument selects cases):
//!
//! * `beam22-*`: a 2-interface beam with 10 fixed-interface modes (n = 22), for each frame
//!   choice and inertia variant, Rayleigh damping, no geometric stiffening;
//! * `block14-G`, `block16-G`: the slider-crank-like body of the Exudyn comparison (a solid rod with two
//!   interfaces, 2 or 4 fixed-interface modes, geometric stiffening, frame at the centre of
//!   mass, `Exact` inertia, no damping): the hex8 block of `testing::fixtures::solid_block_with`;
//! * `beam14-G`: a segment of the slider-crank rod of validation problem C2 as a beam
//!   superelement (4 Timoshenko elements, 2 interfaces, 2 fixed-interface modes, geometric
//!   stiffening, centre of mass, `Exact`, no damping): the body the mechanism step evaluates;
//! * `beam14-G-xy`, `beam14-G-planar`: the same segment (0.15 m) in the xy-plane with the
//!   section axis along z and the out-of-plane dofs of its internal nodes supported
//!   (`testing::fixtures::planar_beam`), evaluated as a spatial body and as a planar one
//!   (`Superelement::into_planar`: 8 coordinates instead of 14), on planar states
//!   (`testing::planar_test_state`) under in-plane gravity;
//! * `beam72-G`: a large body (2 interfaces, 60 modes, geometric stiffening, centre of mass,
//!   `Exact`), to check that the small-n work does not slow big n.
//!
//! Instruction counts (repeatable on a loaded machine): `--profile=tangents`,
//! `--profile=forces` (forces and the mass matrix) or `--profile=residual` (`residual_into`,
//! the forces alone) runs 1 + 20 evaluations of each selected case and nothing else, e.g.
//!
//! ```text
//! valgrind --tool=callgrind --callgrind-out-file=/tmp/se.out '--toggle-collect=*evaluate_into*' \
//!     target/release/deps/evaluate-HASH --profile=tangents block14
//! callgrind_annotate /tmp/se.out | head -40     # total / 21 = instructions per evaluation
//! ```
//!
//! The current figures, times and instruction counts: BENCHMARKS.md, "Superelement
//! evaluation".

use nalgebra::{Point3, Vector3};
use reduction::{CbSettings, ModeSelection, ReducedBody};
use std::time::Instant;
use superelement::testing::{fixtures, planar_test_state, test_state, StateSpec};
use superelement::{Damping, FrameChoice, MassVariant, Superelement};

/// Evaluations per case of `--profile` (after one warm-up call).
const PROFILE_CALLS: usize = 20;

/// The evaluation a timed batch calls.
#[derive(Clone, Copy)]
enum Call {
    /// `evaluate_into`: forces, mass matrix and tangents.
    Evaluate,
    /// `forces_into`: forces and mass matrix.
    Forces,
    /// `residual_into`: the residual and its force parts.
    Residual,
}

struct Case {
    name: String,
    se: Superelement,
    /// Planar states (`testing::planar_test_state`) and in-plane gravity.
    planar: bool,
}

/// The cases whose name contains `filter` (all for an empty filter); bodies are reduced only
/// for selected cases.
fn cases(filter: &str) -> Vec<Case> {
    let wanted = |name: &str| name.contains(filter);
    let mut out = Vec::new();
    let damping = Damping::rayleigh(0.0, 1e-4);
    let frames = [
        ("com", FrameChoice::CenterOfMass),
        ("node0", FrameChoice::InterfaceNode(0)),
    ];
    let masses = [("exact", MassVariant::Exact), ("lumped", MassVariant::Lumped)];
    let beam22_names: Vec<String> = frames
        .iter()
        .flat_map(|(f, _)| masses.iter().map(move |(m, _)| format!("beam22-{f}-{m}")))
        .collect();
    if beam22_names.iter().any(|n| wanted(n)) {
        let (_model, _nodes, body) = fixtures::straight_beam(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.2, 0.1),
            20,
            ModeSelection::Count(10),
            false,
        );
        for (f, frame) in frames {
            for (m, mass) in masses {
                let name = format!("beam22-{f}-{m}");
                if wanted(&name) {
                    let se = Superelement::new(&body, frame, mass, damping.clone()).unwrap();
                    out.push(Case {
                        name,
                        se,
                        planar: false,
                    });
                }
            }
        }
    }
    let geometric = |modes| CbSettings {
        geometric_stiffening: true,
        ..CbSettings::new(ModeSelection::Count(modes))
    };
    let com_exact = |body: &ReducedBody| {
        Superelement::new(body, FrameChoice::CenterOfMass, MassVariant::Exact, Damping::none()).unwrap()
    };
    for modes in [2, 4] {
        let name = format!("block{}-G", 12 + modes);
        if wanted(&name) {
            let (_model, _nodes, body) = fixtures::solid_block_with(geometric(modes));
            out.push(Case {
                name,
                se: com_exact(&body),
                planar: false,
            });
        }
    }
    if wanted("beam14-G") {
        let (_model, _nodes, body) = fixtures::straight_beam_with(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.15, 0.0, 0.0),
            4,
            geometric(2),
            false,
        );
        out.push(Case {
            name: "beam14-G".into(),
            se: com_exact(&body),
            planar: false,
        });
    }
    if wanted("beam14-G-xy") || wanted("beam14-G-planar") {
        let (_model, _nodes, body) = fixtures::planar_beam(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.15, 0.0, 0.0),
            4,
            geometric(2),
            true,
        );
        if wanted("beam14-G-xy") {
            out.push(Case {
                name: "beam14-G-xy".into(),
                se: com_exact(&body),
                planar: true,
            });
        }
        if wanted("beam14-G-planar") {
            out.push(Case {
                name: "beam14-G-planar".into(),
                se: com_exact(&body).into_planar().unwrap(),
                planar: true,
            });
        }
    }
    if wanted("beam72-G") {
        let (_model, _nodes, body) = fixtures::straight_beam_with(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.2, 0.1),
            60,
            geometric(60),
            false,
        );
        out.push(Case {
            name: "beam72-G".into(),
            se: com_exact(&body),
            planar: false,
        });
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // `cargo bench` passes `--bench`; `cargo test --benches` does not and runs this once as a
    // smoke test: keep it short there.
    let quick = !args.iter().any(|a| a == "--bench");
    let profile = args.iter().find_map(|a| a.strip_prefix("--profile=")).map(|p| match p {
        "tangents" | "forces" | "residual" => p.to_string(),
        other => panic!("--profile=tangents, --profile=forces or --profile=residual, got {other}"),
    });
    let filter = args.iter().find(|a| !a.starts_with("--")).map_or("", |s| s.as_str());
    for Case { name, se, planar } in cases(filter) {
        let g = if planar {
            Vector3::new(0.0, -9.81, 0.0)
        } else {
            Vector3::new(0.0, 0.0, -9.81)
        };
        // Two nearby states (the last interface 1 um apart), each with its converged frame,
        // taken in turn: every call forms a new configuration, as in a time integration (a
        // repeated state would reuse the last call's), and its frame solve stops at the test
        // of the warm start.
        let (mut state, acc) = if planar {
            planar_test_state(&se, 120f64.to_radians(), 1)
        } else {
            test_state(&se, &StateSpec::moving(120.0, 1))
        };
        state.frame = se.solve_frame(&state).unwrap().0;
        let mut other = state.clone();
        other.r[se.n_interfaces() - 1].x += 1e-6;
        other.frame = se.solve_frame(&other).unwrap().0;
        let states = [state, other];
        let mut ws = se.workspace();
        let mut out = superelement::Evaluation::zeros(se.n_coordinates());
        if let Some(profile) = &profile {
            for i in 0..=PROFILE_CALLS {
                let state = &states[i % 2];
                match profile.as_str() {
                    "residual" => se.residual_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                    "tangents" => se.evaluate_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                    _ => se.forces_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                }
            }
            println!("{name}: {} evaluations ({profile})", PROFILE_CALLS + 1);
            continue;
        }
        // Many short batches: on a loaded machine the fastest batches are the uninterrupted ones.
        let (batches, per) = if quick { (1, 2) } else { (400, 25) };
        let mut sink = 0.0;
        let mut time = |call: Call, sink: &mut f64| {
            let mut times = Vec::with_capacity(batches);
            for _ in 0..batches {
                let t = Instant::now();
                for i in 0..per {
                    let state = &states[i % 2];
                    match call {
                        Call::Evaluate => se.evaluate_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                        Call::Forces => se.forces_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                        Call::Residual => se.residual_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                    }
                    *sink += out.residual[0];
                }
                times.push(t.elapsed().as_secs_f64() * 1e6 / per as f64);
            }
            times.sort_by(|a, b| a.partial_cmp(b).unwrap());
            (times[times.len() / 2], times[0])
        };
        let (all, all_min) = time(Call::Evaluate, &mut sink);
        let (forces, _) = time(Call::Forces, &mut sink);
        let (residual, _) = time(Call::Residual, &mut sink);
        let alloc = {
            let t = Instant::now();
            for _ in 0..per {
                sink += se.evaluate(&states[0], &acc, &g).unwrap().stiffness[(0, 0)];
            }
            t.elapsed().as_secs_f64() * 1e6 / per as f64
        };
        println!(
            "  {name:<18} N = {}, m = {:>3}, n = {:>3}  forces + K_t, C_t, M: {all:6.1} us (median; min {all_min:.1})   forces + M only: {forces:6.1} us   residual only: {residual:6.1} us   allocating evaluate(): {alloc:6.1} us   [{sink:.1e}]",
            se.n_interfaces(),
            se.n_modes(),
            se.n_coordinates(),
        );
    }
}
