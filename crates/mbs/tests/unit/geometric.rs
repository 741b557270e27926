//! Geometric stiffening of ONE superelement (`reduction::CbSettings::geometric_stiffening`,
//! `superelement::GeometricStiffness`): a clamped-free column of 16 Euler-Bernoulli elements
//! (aluminium 50 x 30 mm, L = 1 m; `superelement::testing::fixtures::straight_beam_with`)
//! reduced to one superelement with 4 fixed-interface modes.
//!
//! * Linearised buckling (`mbs::buckling`) matches Euler's load $\pi^2EI/(4L^2)$ with $\mathbf G$
//!   (measured +3.5e-4 with the frame at the centre of mass, +1.6e-5 at the clamped interface);
//!   without $\mathbf G$ one body sees the axial force only through its frame rotation: +22 %, and
//!   with the frame at the clamp not at all (no buckling load).
//! * A lateral tip force under axial compression $P$: the nonlinear static tip deflection
//!   against the exact beam-column amplification $3(\tan kL - kL)/(kL)^3$, $k^2 = P/EI$ (close
//!   to $1/(1 - P/P_{cr})$), in both principal bending planes: within 2e-4 with $\mathbf G$, 10 %
//!   low without at $P/P_{cr} = 0.4$.
//! * Membrane stiffening of a beam clamped at both ends under a large central force (the
//!   quartic term $U_4$): two superelements with $\mathbf G$ against a converged chain of 32.

use mbs::{buckling, solve_static, Model, NodeId, SensorKind, StaticSettings, Support, System};
use nalgebra::{Isometry3, Point3, Vector3};
use reduction::{CbSettings, ModeSelection};
use superelement::testing::fixtures::straight_beam_with;
use superelement::{FrameChoice, MassVariant};

const L: f64 = 1.0;
const E: f64 = 70e9;
/// The fixture's section (`superelement::testing::fixtures::properties`): 50 x 30 mm.
const WIDTH: f64 = 0.05;
const DEPTH: f64 = 0.03;

/// The two second moments of area of the section, weak first.
fn inertias() -> [f64; 2] {
    [WIDTH * DEPTH.powi(3) / 12.0, DEPTH * WIDTH.powi(3) / 12.0]
}

/// Euler's load of the clamped-free column in its weak plane.
fn p_euler() -> f64 {
    std::f64::consts::PI.powi(2) * E * inertias()[0] / (4.0 * L * L)
}

/// The column along x as one superelement (nodes "base", clamped, and "tip", with a position
/// sensor "tip"), with or without geometric stiffening.
fn column(geometric: bool, frame: FrameChoice) -> (Model, NodeId) {
    let mut settings = CbSettings::new(ModeSelection::Count(4));
    settings.keep_mesh_shapes = false;
    settings.geometric_stiffening = geometric;
    let (_, _, body) = straight_beam_with(Point3::origin(), Point3::new(L, 0.0, 0.0), 16, settings, false);
    assert_eq!(body.geometric_stiffness.is_some(), geometric, "the reduction's G");
    let mut model = Model::new("column");
    let base = model.add_node("base", Vector3::zeros());
    let tip = model.add_node("tip", Vector3::new(L, 0.0, 0.0));
    model.add_flexible_body(body, vec![base, tip], Isometry3::identity(), frame, MassVariant::Exact);
    model.add_support(Support::clamp(base));
    model.add_sensor("tip", SensorKind::NodePosition { node: tip });
    (model, tip)
}

/// Critical load of the column by linearised buckling about the state under a tenth of
/// Euler's load.
fn critical_load(geometric: bool, frame: FrameChoice) -> f64 {
    let (mut model, tip) = column(geometric, frame);
    let p = 0.1 * p_euler();
    model.add_dead_force(tip, Vector3::new(-p, 0.0, 0.0));
    let sys = System::new(&model).unwrap();
    let unloaded = sys.initial_state();
    let sol = solve_static(&sys, unloaded.clone(), &StaticSettings::new(1)).unwrap();
    let b = buckling(&sys, &unloaded, &sol.state, 1.0).unwrap();
    b.load_factors[0] * p
}

#[test]
fn one_superelement_buckles_at_eulers_load_with_geometric_stiffening() {
    let pe = p_euler();
    for frame in [FrameChoice::CenterOfMass, FrameChoice::InterfaceNode(0)] {
        let with = (critical_load(true, frame) - pe) / pe;
        let without = (critical_load(false, frame) - pe) / pe;
        eprintln!("frame {frame}: P_cr error against Euler {with:+.3e} with G, {without:+.3e} without");
        assert!(with.abs() < 2e-3, "frame {frame}: {with:e} with G");
        assert!(without.abs() > 0.15, "frame {frame}: {without:e} without G");
    }
}

/// Tip deflection of the column under the axial compression `p` and the lateral tip force `h`
/// (both dead, applied together in load steps), from the nonlinear static solution.
fn tip_deflection(geometric: bool, p: f64, h: Vector3<f64>) -> Vector3<f64> {
    let (mut model, tip) = column(geometric, FrameChoice::CenterOfMass);
    model.add_dead_force(tip, Vector3::new(-p, 0.0, 0.0) + h);
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(4)).unwrap();
    let r = sol.sensors.series("tip").unwrap();
    let last = r.last().unwrap();
    Vector3::new(last[0] - L, last[1], last[2])
}

#[test]
fn lateral_deflection_is_amplified_by_the_axial_load() {
    let p = 0.4 * p_euler();
    // The section's principal axes: the fixture's orientation vector and the normal to it.
    let v = Vector3::x().cross(&Vector3::new(0.3, 0.9, -0.2)).normalize();
    for dir in [v, Vector3::x().cross(&v)] {
        // Lateral force for a deflection of about L/2000 in the weak plane.
        let h = dir * (3.0 * E * inertias()[0] / L.powi(3) * L / 2000.0);
        let d0 = tip_deflection(true, 0.0, h).dot(&dir);
        // The bending plane of `dir`: its EI from the unloaded deflection H L^3 / (3 EI)
        // (exact for the Euler-Bernoulli elements under a tip force), one of the two.
        let EI = h.norm() * L.powi(3) / (3.0 * d0);
        let I = *inertias()
            .iter()
            .min_by(|a, b| (E * **a - EI).abs().total_cmp(&(E * **b - EI).abs()))
            .unwrap();
        assert!((EI - E * I).abs() < 1e-3 * E * I, "EI {EI:e} is neither section value");
        let kL = (p / (E * I)).sqrt() * L;
        let exact = 3.0 * (kL.tan() - kL) / kL.powi(3);
        let p_cr = std::f64::consts::PI.powi(2) * E * I / (4.0 * L * L);
        for geometric in [true, false] {
            let amplification = tip_deflection(geometric, p, h).dot(&dir) / d0;
            let err = amplification / exact - 1.0;
            eprintln!(
                "plane {dir:?} (P/P_cr = {:.3}), G {geometric}: amplification {amplification:.5}, exact {exact:.5}, 1/(1 - P/P_cr) = {:.5}, error {err:+.3e}",
                p / p_cr,
                1.0 / (1.0 - p / p_cr)
            );
            if geometric {
                assert!(err.abs() < 1e-3, "plane {dir:?}: {err:e}");
            } else if p / p_cr > 0.3 {
                // One linear-elastic body sees P only through its frame rotation.
                assert!(err < -0.05, "plane {dir:?}: {err:e} without G");
            }
        }
    }
}

/// A beam clamped at both ends along x (L = 1 m) as `n` superelements of `elements` elements
/// with `modes` fixed-interface modes each, with or without geometric stiffening; returns the
/// model and its middle node (`n` even), with a position sensor "mid" there.
fn clamped_beam(n: usize, elements: usize, modes: ModeSelection, geometric: bool) -> (Model, NodeId) {
    let mut settings = CbSettings::new(modes);
    settings.keep_mesh_shapes = false;
    settings.geometric_stiffening = geometric;
    let mut model = Model::new("clamped beam");
    let nodes: Vec<NodeId> = (0..=n)
        .map(|i| model.add_node(&format!("n{i}"), Vector3::new(L * i as f64 / n as f64, 0.0, 0.0)))
        .collect();
    for i in 0..n {
        let (a, b) = (L * i as f64 / n as f64, L * (i + 1) as f64 / n as f64);
        let (_, _, body) = straight_beam_with(
            Point3::new(a, 0.0, 0.0),
            Point3::new(b, 0.0, 0.0),
            elements,
            settings.clone(),
            false,
        );
        model.add_flexible_body(
            body,
            vec![nodes[i], nodes[i + 1]],
            Isometry3::identity(),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    model.add_support(Support::clamp(nodes[0]));
    model.add_support(Support::clamp(nodes[n]));
    model.add_sensor("mid", SensorKind::NodePosition { node: nodes[n / 2] });
    (model, nodes[n / 2])
}

/// Lateral deflection of the middle of the clamped beam under the lateral force `f` there.
fn clamped_deflection(n: usize, elements: usize, modes: ModeSelection, geometric: bool, f: Vector3<f64>) -> f64 {
    let (mut model, mid) = clamped_beam(n, elements, modes, geometric);
    model.add_dead_force(mid, f);
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(8)).unwrap();
    let r = sol.sensors.series("mid").unwrap();
    let last = r.last().unwrap();
    Vector3::new(last[0], last[1], last[2]).dot(&f.normalize())
}

/// Membrane stiffening: a beam clamped at both ends under a central lateral force large enough
/// that the linear deflection is 1.5 times the depth. Its ends cannot approach, so the bending
/// stretches the axis and the force-deflection curve hardens (the membrane energy
/// $\tfrac{EA}{2L}(\tfrac12\int w'^2dx)^2$, the quartic term $U_4$). Two superelements with G
/// against the converged chain of 32 superelements without G (each carries the prestress
/// through its frame rotation, like a chain of co-rotational beams): measured -0.15 % (the
/// deflection is 0.62 of the linear one); two without G are 9 % too flexible.
#[test]
fn membrane_stiffening_of_a_clamped_beam_matches_the_converged_chain() {
    let v = Vector3::x().cross(&Vector3::new(0.3, 0.9, -0.2)).normalize();
    let dir = Vector3::x().cross(&v);
    let EI = E * inertias()[0];
    let w_linear = 1.5 * DEPTH;
    let f = dir * (w_linear * 192.0 * EI / L.powi(3));
    let reference = clamped_deflection(32, 2, ModeSelection::StaticOnly, false, f);
    let with = clamped_deflection(2, 8, ModeSelection::Count(4), true, f);
    let without = clamped_deflection(2, 8, ModeSelection::Count(4), false, f);
    let err = with / reference - 1.0;
    eprintln!(
        "clamped beam: linear {w_linear:.5} m, 32 segments {reference:.5} m, 2 with G {with:.5} m ({err:+.3e}), 2 without G {without:.5} m"
    );
    assert!(reference < 0.7 * w_linear, "the reference must harden: {reference}");
    assert!(err.abs() < 5e-3, "{err:e}");
    assert!(without / reference - 1.0 > 0.05, "{without} vs {reference} without G");
}
