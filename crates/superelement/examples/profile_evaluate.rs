//! Runs `evaluate_into` of the bench body (`benches/evaluate.rs`) a given number of times for one
//! frame choice and inertia variant, for instruction counts under callgrind:
//! `valgrind --tool=callgrind --toggle-collect='*evaluate_into*' target/release/examples/profile_evaluate exact com 1000`.
//! Instruction counts are reliable on a loaded machine, where timings are not.
//!
//! `profile_evaluate planar planar|spatial COUNT`: the C2 rod segment in the xy-plane
//! (`testing::fixtures::planar_beam`, 4 elements, 2 modes, geometric stiffening, centre of mass)
//! as a planar body or the same body evaluated spatially, on a planar state, `evaluate_into` with
//! tangents and `residual_into` in turn.

use nalgebra::{Point3, Vector3};
use reduction::ModeSelection;
use superelement::testing::{fixtures, planar_test_state, test_state, StateSpec};
use superelement::{Damping, FrameChoice, MassVariant, Superelement};

/// The planar rows (module docs).
fn planar(args: &[String]) {
    let settings = reduction::CbSettings {
        geometric_stiffening: true,
        ..reduction::CbSettings::new(ModeSelection::Count(2))
    };
    let body = fixtures::planar_beam(Point3::origin(), Point3::new(0.15, 0.0, 0.0), 4, settings, true).2;
    let spatial = Superelement::new(&body, FrameChoice::CenterOfMass, MassVariant::Exact, Damping::none()).unwrap();
    let se = match args.get(2).map(String::as_str) {
        Some("spatial") => spatial,
        _ => spatial.into_planar().unwrap(),
    };
    let count: usize = args.get(3).and_then(|c| c.parse().ok()).unwrap_or(1000);
    let g = Vector3::new(0.0, -9.81, 0.0);
    let (mut state, acc) = planar_test_state(&se, 2.0, 1);
    state.frame = se.solve_frame(&state).unwrap().0;
    let mut ws = se.workspace();
    let mut out = superelement::Evaluation::zeros(se.n_coordinates());
    let mut sink = 0.0;
    for _ in 0..count {
        se.evaluate_into(&state, &acc, &g, &mut ws, &mut out).unwrap();
        se.residual_into(&state, &acc, &g, &mut ws, &mut out).unwrap();
        sink += out.residual[0] + out.stiffness[(0, 0)];
    }
    println!(
        "{count} evaluations of the planar rod segment (planar: {}): [{sink:.3e}]",
        se.is_planar()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("planar") {
        return planar(&args);
    }
    let mass = match args.get(1).map(String::as_str) {
        Some("lumped") => MassVariant::Lumped,
        _ => MassVariant::Exact,
    };
    let frame = match args.get(2).map(String::as_str) {
        Some("node") => FrameChoice::InterfaceNode(0),
        _ => FrameChoice::CenterOfMass,
    };
    let count: usize = args.get(3).and_then(|c| c.parse().ok()).unwrap_or(1000);
    // `SE_BODY=path`: the reduced body is read from that JSON file (written there on the first
    // run), so that before/after comparisons see the same body while the reduction changes.
    let saved = std::env::var("SE_BODY").ok();
    let body: reduction::ReducedBody = match saved.as_ref().and_then(|p| std::fs::read_to_string(p).ok()) {
        Some(text) => serde_json::from_str(&text).unwrap(),
        None => {
            let body = fixtures::straight_beam(
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.2, 0.1),
                20,
                ModeSelection::Count(10),
                false,
            )
            .2;
            if let Some(p) = &saved {
                std::fs::write(p, serde_json::to_string(&body).unwrap()).unwrap();
            }
            body
        }
    };
    let g = Vector3::new(0.0, 0.0, -9.81);
    let se = Superelement::new(&body, frame, mass, Damping::rayleigh(0.0, 1e-4)).unwrap();
    let (mut state, acc) = test_state(&se, &StateSpec::moving(120.0, 1));
    state.frame = se.solve_frame(&state).unwrap().0;
    let mut ws = se.workspace();
    let mut out = superelement::Evaluation::zeros(se.n_coordinates());
    if let Some(path) = args.get(4) {
        // All outputs, for before/after comparisons of a refactoring.
        let mut text = String::new();
        se.evaluate_into(&state, &acc, &g, &mut ws, &mut out).unwrap();
        for v in [&out.residual, &out.q_v, &out.f_elastic, &out.f_damping, &out.f_gravity] {
            for x in v.iter() {
                text += &format!("{x:.17e}\n");
            }
        }
        for m in [&out.mass, &out.stiffness, &out.damping] {
            for j in 0..m.ncols() {
                for i in 0..m.nrows() {
                    text += &format!("{:.17e}\n", m[(i, j)]);
                }
            }
        }
        std::fs::write(path, text).unwrap();
    }
    let mut sink = 0.0;
    for _ in 0..count {
        se.evaluate_into(&state, &acc, &g, &mut ws, &mut out).unwrap();
        sink += out.residual[0] + out.stiffness[(0, 0)];
    }
    println!("{count} evaluations of {frame} {mass:?}: [{sink:.3e}]");
}
