//! The cheap forms of an evaluation against the full one: `forces` (no tangents: the FFR
//! partials, the geometric Hessian and the gravity partials are skipped) gives the residual,
//! its parts and the mass matrix of `evaluate`; a workspace reused across states and across
//! forces-only and full calls (`evaluate_into`, the hot-loop form) gives exactly the result of a
//! fresh `evaluate`, so no buffer that a forces-only call leaves stale is read by a later call.
//! Every fixture, frame choice and inertia variant, with damping, with and without gravity, and
//! the hex8 block with a synthetic geometric stiffness.

use super::common::*;
use faer::Mat;
use nalgebra::Vector3;
use reduction::ReducedBody;
use superelement::testing::{coordinate_scales, synthetic_geometric_stiffness, test_state, StateSpec};
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
        se.evaluate_into(&a, &acc_a, &g, true, &mut ws, &mut out).unwrap();
        se.evaluate_into(&b, &acc_b, &g, false, &mut ws, &mut out).unwrap();
        se.evaluate_into(&b, &acc_b, &g, true, &mut ws, &mut out).unwrap();
        let mut ws_fresh = se.workspace();
        let mut fresh = Evaluation::zeros(se.n_coordinates());
        se.evaluate_into(&a, &acc_a, &g, false, &mut ws_fresh, &mut fresh)
            .unwrap();
        se.evaluate_into(&b, &acc_b, &g, false, &mut ws_fresh, &mut fresh)
            .unwrap();
        se.evaluate_into(&b, &acc_b, &g, true, &mut ws_fresh, &mut fresh)
            .unwrap();
        for ((what, x), (_, y)) in forces_and_mass(&out).into_iter().zip(forces_and_mass(&fresh)) {
            assert!(x == y, "{name}: {what} differs after reuse");
        }
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
