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
//! Instructions per evaluation (gravity on, warm frame), before and after the work on
//! the evaluation (the G_k products as column-major matrix-vector products, forces-only calls
//! without the FFR partials, one product for the FFR contractions and one for their qq blocks,
//! no gravity partials without gravity, slice access in the frame and block loops):
//!
//! | case | with tangents | forces + M only |
//! |---|---|---|
//! | `block14-G` | 186.4k -> 170.0k (-8.8 %) | 97.2k -> 67.7k (-30.3 %) |
//! | `block16-G` | 205.9k -> 191.4k (-7.1 %) | 105.1k -> 75.2k (-28.4 %) |
//! | `beam22-com-exact` | 260.9k -> 251.6k (-3.6 %) | 128.0k -> 93.2k (-27.2 %) |
//! | `beam72-G` | 2888k -> 2816k (-2.5 %) | 1233k -> 969k (-21.4 %) |
//!
//! Then the compressed geometric stiffness (`superelement::compressed`: of a straight beam's G_k
//! only the few of the coordinates that stretch it are nonzero, kept by their nonzero entries)
//! and one X^T pass for all tangent terms: `beam14-G` 169k -> 151.4k with tangents, 67k ->
//! 61.4k without; `beam72-G` 2816k -> 1904k and 969k -> 584k; `block14-G` 170.0k -> 166.9k,
//! `beam22-com-exact` 251.6k -> 246.9k (the X^T pass only).
//!
//! Then fewer products per evaluation with tangents (19 -> 11: K^L with one product by Y, the
//! W(.) products as block loops, one Psi product in the exact inertia partials, M_ffr X and
//! the gravity partial in the common X^T pass): `beam14-G` 151.4k -> 145.9k, `block14-G`
//! 166.9k -> 161.5k, `beam22-com-exact` 247.1k -> 243.4k, `beam72-G` 1905k -> 1850k with
//! tangents; forces only unchanged.
//!
//! Then the 3-block column kernels, Lambda from the right, the configuration update and the
//! partial of P^T F compiled for AVX2 through `pulp`'s runtime dispatch (bit-identical
//! results) and the transposed copies of the update with their column slices taken once:
//! `beam14-G` 145.9k -> 138.1k with tangents, 61.5k -> 57.6k without; `block14-G` 161.5k ->
//! 153.7k, 67.5k -> 63.5k; `beam22-com-exact` 243.5k -> 227.8k, 92.6k -> 86.7k; `beam72-G`
//! 1850k -> 1798k, 585k -> 567k. (The chord steps of the frame solve gain nothing here: these calls start at the
//! converged frame.)
//!
//! Then the two products with the stacked inertia invariants (9n x n by 2-3 columns, n^2 x 9
//! by 2) by 8-row strips of a packed copy with fused multiply-adds (`transform::PackedTall`,
//! n <= 24) instead of faer's general gemm path, the contractions read in place from the
//! product: `beam14-G` 138.1k -> 135.3k with tangents, 57.6k -> 56.7k without; `block14-G`
//! 153.6k -> 150.7k; `beam22-com-exact` 227.7k -> 219.9k, 86.7k -> 84.2k; `beam72-G`
//! unchanged (faer's product kept). In time the gain is larger
//! than in instructions: `beam14-G` 11.0 -> 9.3 us with tangents (BENCHMARKS.md).
//!
//! Then the configuration update forming without tangents only what the forces read (not the
//! T_j, B rows nor Y_r^T), the Psi products by 3x3 blocks (`transform::psi_product`) and plain
//! fixed-length column loops in the update and the frame residual, and the 6x6 inverse by 3x3
//! blocks; the calls alternate between two nearby states since then (a repeated state reuses
//! the configuration it formed): `beam14-G` 135.3k -> 127.9k with tangents, 56.7k -> 46.2k
//! without; `block14-G` 150.8k -> 143.5k, 62.6k -> 52.1k; `beam22-com-exact` 220.0k -> 207.7k,
//! 84.2k -> 69.0k; `beam72-G` 1798k -> 1762k, 566k -> 518k.
//!
//! Then the residual alone (`residual_into`: no FFR mass matrix, no body-axis mass and no
//! rotation of it, only the inertia contractions the force needs) for the Newton iterations
//! without tangents, against the forces-only call before (`--profile=forces` then):
//! `beam14-G` 56.7k -> 36.9k; `block14-G` 62.7k -> 42.9k; `beam22-com-exact` 84.3k -> 52.0k;
//! `beam72-G` 566k -> 391k. The FFR force's column sums in one pass made the forces with the
//! mass 56.7k -> 54.0k and the tangents 135.3k -> 134.2k (`beam14-G`).
//!
//! Then the multi-column kernels as functions of distinct slices, so that they vectorise (they
//! ran scalar: the compiler could not tell the columns of one matrix apart), A Psi by its
//! blocks instead of two dense products, K_t rotated from its two parts without forming K^L,
//! Lambda^T from the left block by block and j_q unrolled: with tangents `beam14-G` 134.2k ->
//! 127.0k, `block14-G` 149.7k -> 142.7k, `beam22-com-exact` 218.9k -> 209.8k, `beam72-G`
//! 1796k -> 1762k; forces and M 54.0k -> 52.3k and the residual alone 36.9k -> 36.1k
//! (`beam14-G`).
//!
//! Then the FFR force's products with [S_t; S_r; S_x] by 16-entry columns in pulp's vectors
//! and its transposed product by rows, the force compiled for AVX2, and log below 0.25 rad by
//! the atan(x)/x series: the residual alone (`--profile=residual`) `beam14-G` 27.0k -> 23.9k,
//! `block14-G` 33.1k -> 29.9k, `beam22-com-exact` 38.2k -> 32.2k, `beam72-G` 349k -> 318k; with
//! tangents `beam14-G` 120.7k -> 121.7k, `beam72-G` 1742k -> 1733k (BENCHMARKS.md).
//!
//! What is left is spread thin: 11 faer products per evaluation with tangents, each
//! about 1.7k instructions of fixed cost (nano-gemm's planning and driver) beside its kernel,
//! and plain loops compiled for the baseline x86-64 target (two-wide SIMD, no FMA). Replacing
//! the small products by plain loops was measured slower (2-3 instructions a multiply-add
//! against about 0.7 in faer's kernels), and so was a column-loop kernel compiled for AVX2 and
//! FMA through faer's runtime dispatch (`pulp`): 3.2k instructions for a 14x6x14 product
//! against faer's 1.7k, winning only on tall thin ones (BENCHMARKS.md). Building with
//! `-C target-cpu=x86-64-v3` took `block14-G` (at 166.9k then) to 153.9k with tangents and
//! 61.1k without.
//!
//! The planar body (`Superelement::into_planar`, theory guide §7.4): `beam14-G-planar` (8
//! coordinates) against `beam14-G-xy` (the same reduced body evaluated spatially, 14), planar
//! states, in-plane gravity, `--profile=...`:
//!
//! | | residual alone | forces + M | with tangents |
//! |---|---|---|---|
//! | `beam14-G-xy` (spatial) | 23.9k | 39.6k | 122.9k |
//! | `beam14-G-planar`, tangents all by dual numbers | 13.8k | 60.7k | 151.7k |
//! | M and C_t in closed form | 13.8k | 20.3k | 65.7k |
//! | the residual pass for AVX2, the congruence loops over slices | 13.6k | 20.1k | 63.6k |
//! | G_k q once per nonzero G_k, dual products by rows | 10.7k | 17.2k | 47.8k |
//! | wrap without fmod, the tilt by its square | 10.4k | 16.9k | 47.5k |
//! | K_CB q, W q, S~_z q in one pass for dual numbers | 10.4k | 16.9k | 47.1k |
//! | the frame angle's sin, cos from the frame solve, \|g_t\| without hypot | 10.3k | 16.8k | 47.0k |
//! | the residual pass on slices of its buffers (no vector reloads through the buffer struct) | 9.8k | 16.3k | 45.9k |
//! | the frame Newton, the output scatter and the closed-form M, C_t on slices too | 9.7k | 16.2k | 45.4k |
//!
//! In time (at the 47.1k row; medians of 400 batches, three alternating runs on a loaded
//! machine): residual 1.3 against 3.2 us, forces and M 2.0 against 5.1 us, with tangents 5.7
//! against 12.8-14.2 us. The tangent pass by dual numbers ($\mathbf K_t$, 8 directions) is 19.6k
//! of the 45.4k, the closed-form $\mathbf M$ and $\mathbf C_t$ 11.1k, the residual pass 6.3k; the
//! rest is the frame solve, reading the state and writing the $6N + m$ layout. A body of 9 to
//! 12 planar coordinates takes one tangent pass of 12 directions instead of two of 8: the C2
//! rod as one segment with 3 modes (9 coordinates) 41.9k -> 27.0k for $\mathbf K_t$, 72.1k ->
//! 57.2k with tangents.

use nalgebra::{Point3, Vector3};
use reduction::{CbSettings, ModeSelection, ReducedBody};
use std::time::Instant;
use superelement::testing::{fixtures, planar_test_state, test_state, StateSpec};
use superelement::{Damping, FrameChoice, MassVariant, Superelement};

/// Evaluations per case of `--profile` (after one warm-up call).
const PROFILE_CALLS: usize = 20;

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
                    p => se
                        .evaluate_into(state, &acc, &g, p == "tangents", &mut ws, &mut out)
                        .unwrap(),
                }
            }
            println!("{name}: {} evaluations ({profile})", PROFILE_CALLS + 1);
            continue;
        }
        // Many short batches: on a loaded machine the fastest batches are the uninterrupted ones.
        let (batches, per) = if quick { (1, 2) } else { (400, 25) };
        let mut sink = 0.0;
        // `Some(tangents)`: `evaluate_into`; `None`: `residual_into`.
        let mut time = |tangents: Option<bool>, sink: &mut f64| {
            let mut times = Vec::with_capacity(batches);
            for _ in 0..batches {
                let t = Instant::now();
                for i in 0..per {
                    let state = &states[i % 2];
                    match tangents {
                        Some(t) => se.evaluate_into(state, &acc, &g, t, &mut ws, &mut out).unwrap(),
                        None => se.residual_into(state, &acc, &g, &mut ws, &mut out).unwrap(),
                    }
                    *sink += out.residual[0];
                }
                times.push(t.elapsed().as_secs_f64() * 1e6 / per as f64);
            }
            times.sort_by(|a, b| a.partial_cmp(b).unwrap());
            (times[times.len() / 2], times[0])
        };
        let (all, all_min) = time(Some(true), &mut sink);
        let (forces, _) = time(Some(false), &mut sink);
        let (residual, _) = time(None, &mut sink);
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
