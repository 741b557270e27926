//! The cheap forms of an evaluation against the full one: `forces` (no tangents: the FFR
//! partials, the geometric Hessian and the gravity partials are skipped) gives the residual,
//! its parts and the mass matrix of `evaluate`; `residual_into` (no mass matrix either) gives
//! the residual and its parts, and `kinetic_energy_in` after it the kinetic energy; a workspace reused across states and across
//! forces-only and full calls (`evaluate_into`, the hot-loop form) gives exactly the result of a
//! fresh `evaluate`, so no buffer that a forces-only call leaves stale is read by a later call.
//! Every fixture, frame choice and inertia variant, with damping, with and without gravity, and
//! the hex8 block with a synthetic geometric stiffness.

use super::common::*;
use faer::Mat;
use nalgebra::{Point3, Vector3};
use reduction::{CbSettings, ModeSelection, ReducedBody};
use superelement::testing::{coordinate_scales, fixtures, synthetic_geometric_stiffness, test_state, StateSpec};
use superelement::{Damping, Evaluation, FrameChoice, MassVariant, Superelement};

/// Every (name, superelement) to check: all fixtures x frames x variants with Rayleigh
/// damping, and the block with a synthetic G.
fn cases() -> Vec<(String, Superelement)> {
    let damping = Damping::rayleigh(0.3, 2e-4);
    let mut bodies: Vec<(String, ReducedBody)> = all_fixtures()
        .into_iter()
        .map(|fx| (fx.name.to_string(), fx.body.clone()))
        .collect();
    let block = &solid_block().body;
    let se = superelement(block, FrameChoice::CenterOfMass, MassVariant::Exact);
    let mut with_g = block.clone();
    with_g.geometric_stiffness = Some(synthetic_geometric_stiffness(
        block,
        &coordinate_scales(&se, 0.02),
        1.0,
        7,
    ));
    bodies.push(("solid-block-G".into(), with_g));
    bodies.extend(beams());
    let mut out = Vec::new();
    for (name, body) in &bodies {
        for frame in frame_choices(body) {
            for mass in VARIANTS {
                let se = Superelement::new(body, frame, mass, damping.clone()).unwrap();
                out.push((format!("{name} {frame} {mass:?}"), se));
            }
        }
    }
    out
}

/// Beams of the sizes the mechanism and the benchmarks use: a segment of the C2 rod (4
/// elements, 2 modes, n = 14) with the geometric stiffness of its reduction, a 22-coordinate
/// beam and a 32-coordinate one with geometric stiffness (n > 24: the inertia contractions go
/// through faer's product instead of the packed one).
fn beams() -> Vec<(String, ReducedBody)> {
    let beam = |elements, modes, geometric| {
        let settings = CbSettings {
            geometric_stiffening: geometric,
            ..CbSettings::new(ModeSelection::Count(modes))
        };
        let b = Point3::new(0.9, 0.2, -0.1);
        fixtures::straight_beam_with(Point3::origin(), b, elements, settings, false).2
    };
    vec![
        ("beam14-G".into(), beam(4, 2, true)),
        ("beam22".into(), beam(20, 10, false)),
        ("beam32-G".into(), beam(20, 20, true)),
    ]
}

/// Largest |a - b| over the entries, against the largest |a|.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

fn mat_entries(A: &Mat<f64>) -> Vec<f64> {
    (0..A.ncols())
        .flat_map(|j| (0..A.nrows()).map(move |i| A[(i, j)]))
        .collect()
}

/// The force vectors and the mass matrix of an evaluation, named.
fn forces_and_mass(ev: &Evaluation) -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("residual", ev.residual.clone()),
        ("f_inertia", ev.f_inertia.clone()),
        ("q_v", ev.q_v.clone()),
        ("f_elastic", ev.f_elastic.clone()),
        ("f_damping", ev.f_damping.clone()),
        ("f_gravity", ev.f_gravity.clone()),
        ("q_jj", ev.q_jj.clone()),
        ("mass", mat_entries(&ev.mass)),
    ]
}

/// `forces` skips only tangent work: its forces and mass are those of `evaluate` to round-off
/// (the FFR contractions go through a product with one column fewer, which may round
/// differently in the last bit).
#[test]
fn forces_only_matches_the_full_evaluation() {
    for (name, se) in cases() {
        for g in [gravity(), Vector3::zeros()] {
            let (state, acc) = test_state(&se, &StateSpec::moving(75.0, 3));
            let full = se.evaluate(&state, &acc, &g).unwrap();
            let cheap = se.forces(&state, &acc, &g).unwrap();
            assert_eq!(full.frame, cheap.frame, "{name}: frame");
            for ((what, a), (_, b)) in forces_and_mass(&full).into_iter().zip(forces_and_mass(&cheap)) {
                let d = rel_diff(&a, &b);
                assert!(d <= 1e-13, "{name}, g = {g:?}: {what} differs by {d:e} (relative)");
            }
        }
    }
}

/// One workspace through a full call at one state, a forces-only call at another and a full
/// call at that other state: the last result is bit for bit that of a fresh workspace that
/// made a forces-only call at the first state and the same two calls after. Nothing of the
/// first full call leaks into the result. What a workspace does carry on purpose is its last
/// configuration, whose inverse frame Jacobian starts the next frame solve (`frame.rs`), and
/// a forces-only call leaves the same configuration as a full one, so both workspaces go
/// through the same configurations (the frame against a fresh solve:
/// `frame::chord_steps_from_the_last_evaluation_find_the_same_frame`).
#[test]
fn a_reused_workspace_gives_the_fresh_result() {
    for (name, se) in cases() {
        let g = gravity();
        let (a, acc_a) = test_state(&se, &StateSpec::moving(30.0, 11));
        let (b, acc_b) = test_state(&se, &StateSpec::moving(140.0, 12));
        let mut ws = se.workspace();
        let mut out = Evaluation::zeros(se.n_coordinates());
        se.evaluate_into(&a, &acc_a, &g, &mut ws, &mut out).unwrap();
        se.forces_into(&b, &acc_b, &g, &mut ws, &mut out).unwrap();
        se.evaluate_into(&b, &acc_b, &g, &mut ws, &mut out).unwrap();
        let mut ws_fresh = se.workspace();
        let mut fresh = Evaluation::zeros(se.n_coordinates());
        se.forces_into(&a, &acc_a, &g, &mut ws_fresh, &mut fresh).unwrap();
        se.forces_into(&b, &acc_b, &g, &mut ws_fresh, &mut fresh).unwrap();
        se.evaluate_into(&b, &acc_b, &g, &mut ws_fresh, &mut fresh).unwrap();
        for ((what, x), (_, y)) in forces_and_mass(&out).into_iter().zip(forces_and_mass(&fresh)) {
            assert!(x == y, "{name}: {what} differs after reuse");
        }
        // The same with a residual-only call in the middle.
        let mut ws_residual = se.workspace();
        let mut after_residual = Evaluation::zeros(se.n_coordinates());
        se.evaluate_into(&a, &acc_a, &g, &mut ws_residual, &mut after_residual)
            .unwrap();
        se.residual_into(&b, &acc_b, &g, &mut ws_residual, &mut after_residual)
            .unwrap();
        se.evaluate_into(&b, &acc_b, &g, &mut ws_residual, &mut after_residual)
            .unwrap();
        for ((what, x), (_, y)) in forces_and_mass(&after_residual)
            .into_iter()
            .zip(forces_and_mass(&fresh))
        {
            assert!(x == y, "{name}: {what} differs after a residual-only call");
        }
        assert!(
            mat_entries(&after_residual.stiffness) == mat_entries(&fresh.stiffness),
            "{name}: K_t differs after a residual-only call"
        );
        assert!(
            mat_entries(&out.stiffness) == mat_entries(&fresh.stiffness),
            "{name}: K_t differs after reuse"
        );
        assert!(
            mat_entries(&out.damping) == mat_entries(&fresh.damping),
            "{name}: C_t differs after reuse"
        );
    }
}

/// `residual_into` forms no mass matrix and skips the contractions only the mass and the
/// partials need: its residual and force parts are those of `evaluate` to round-off, and
/// `mass`, `q_v`, `K_t`, `C_t` of the output keep the values they had. Deformed, rotated and
/// moving states, every case of `cases` (the C2 rod's segment `beam14-G` among them), with and
/// without gravity.
#[test]
fn residual_only_matches_the_full_evaluation() {
    for (name, se) in cases() {
        let n = se.n_coordinates();
        for g in [gravity(), Vector3::zeros()] {
            let (state, acc) = test_state(&se, &StateSpec::moving(75.0, 3));
            let full = se.evaluate(&state, &acc, &g).unwrap();
            let mut ws = se.workspace();
            let mut cheap = Evaluation::zeros(n);
            let sentinel = 0.125;
            for A in [&mut cheap.mass, &mut cheap.stiffness, &mut cheap.damping] {
                A.fill(sentinel);
            }
            cheap.q_v.fill(sentinel);
            se.residual_into(&state, &acc, &g, &mut ws, &mut cheap).unwrap();
            assert_eq!(full.frame, cheap.frame, "{name}: frame");
            // The residual is a sum of parts computed in a different order (the inertia force
            // without M_ffr): round-off of the largest part, a few hundred ulp.
            let largest = [&full.f_inertia, &full.f_elastic, &full.f_damping, &full.f_gravity]
                .iter()
                .flat_map(|v| v.iter())
                .fold(0.0f64, |m, x| m.max(x.abs()));
            for (what, a, b) in [
                ("residual", &full.residual, &cheap.residual),
                ("f_inertia", &full.f_inertia, &cheap.f_inertia),
                ("f_elastic", &full.f_elastic, &cheap.f_elastic),
                ("f_damping", &full.f_damping, &cheap.f_damping),
                ("f_gravity", &full.f_gravity, &cheap.f_gravity),
                ("q_jj", &full.q_jj, &cheap.q_jj),
            ] {
                let d = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                let scale = if what == "q_jj" {
                    a.iter().fold(f64::MIN_POSITIVE, |m, x| m.max(x.abs()))
                } else {
                    largest.max(f64::MIN_POSITIVE)
                };
                assert!(
                    d <= 1e-13 * scale,
                    "{name}, g = {g:?}: {what} differs by {d:e} (scale {scale:e})"
                );
            }
            for (what, A) in [
                ("mass", &cheap.mass),
                ("K_t", &cheap.stiffness),
                ("C_t", &cheap.damping),
            ] {
                assert!(
                    mat_entries(A).iter().all(|x| *x == sentinel),
                    "{name}: residual_into wrote {what}"
                );
            }
            assert!(
                cheap.q_v.iter().all(|x| *x == sentinel),
                "{name}: residual_into wrote q_v"
            );
            // The kinetic energy from the workspace of a residual-only call, against the one of
            // the full mass matrix (another summation order: round-off of T).
            let qd = state.velocity_vector();
            let T = se.kinetic_energy(&state).unwrap();
            let T_ws = se.kinetic_energy_in(&ws, &qd).unwrap();
            assert!(
                (T - T_ws).abs() <= 1e-12 * T,
                "{name}: kinetic energy {T_ws} against {T}"
            );
        }
    }
}
