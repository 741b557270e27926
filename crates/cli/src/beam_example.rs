#![allow(non_snake_case)]

//! The built-in example: a steel cantilever along a skewed axis, 20 Timoshenko elements,
//! loaded at the tip; statics and the first bending frequencies against beam theory
//! (`benchmarks.md` A1, A2).

use fe_model::generate::straight_beam;
use fe_model::{
    modal_dense, solve_static, BeamProperties, BeamSection, BeamTheory, DofMask, FeModel, IsotropicMaterial, MassKind,
    NodalLoad,
};
use nalgebra::{Point3, Vector3};
use std::fmt::Write;

/// Runs the example and returns the printed report.
pub fn run() -> Result<String, Box<dyn std::error::Error>> {
    let (L, E, nu, rho) = (2.0, 210e9, 0.3, 7850.0);
    let (b, h) = (0.02, 0.04);
    let n = 20;
    let mut model = FeModel::default();
    let steel = model.add_material(IsotropicMaterial::new("steel", E, nu, rho)?);
    let section = BeamSection::rectangle("20x40", b, h, nu)?;
    let (A, Iy, Iz, J, kz) = (section.A(), section.Iy(), section.Iz(), section.J(), section.kz());
    let G = E / (2.0 * (1.0 + nu));
    let sid = model.add_section(section);
    // A skewed axis, so that no global axis is special.
    let axis = Vector3::new(1.0, 2.0, 2.0).normalize();
    let v = Vector3::new(0.0, 0.0, 1.0).cross(&axis).normalize(); // local y, perpendicular to the axis
    let w = axis.cross(&v); // local z
    let props = BeamProperties {
        section: sid,
        material: steel,
        orientation: v,
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    };
    let nodes = straight_beam(
        &mut model,
        Point3::origin(),
        Point3::from(axis * L),
        n,
        &props,
        Some("beam"),
    )?;
    model.add_support(nodes[0], DofMask::ALL);
    let tip = nodes[n];

    let mut out = String::new();
    writeln!(out, "flexmbs built-in example: cantilever, L = {L} m, {b} x {h} m steel section, {n} Timoshenko beam elements along a skewed axis")?;
    writeln!(out, "\nstatics (benchmarks.md A2)")?;
    writeln!(
        out,
        "{:<44} {:>14} {:>14} {:>10}",
        "quantity", "analytic", "flexmbs", "rel. error"
    )?;
    let mut row = |name: &str, exact: f64, ours: f64| {
        writeln!(
            out,
            "{name:<44} {exact:>14.6e} {ours:>14.6e} {:>10.1e}",
            ((ours - exact) / exact).abs()
        )
    };
    let P = 1000.0;
    // Tip force along local z: bending about local y (Iy), shear with kz.
    let s = solve_static(&model, &[NodalLoad::force(tip, w * P)])?;
    let d = Vector3::from_row_slice(&s.displacements[tip.index()][0..3]);
    row(
        "tip force P: deflection PL^3/3EI + PL/kGA",
        P * L.powi(3) / (3.0 * E * Iy) + P * L / (kz * G * A),
        d.dot(&w),
    )?;
    let r = Vector3::from_row_slice(&s.displacements[tip.index()][3..6]);
    row("tip force P: slope PL^2/2EI", P * L * L / (2.0 * E * Iy), -r.dot(&v))?;
    let Mt = 100.0;
    let s = solve_static(&model, &[NodalLoad::moment(tip, v * Mt)])?;
    let d = Vector3::from_row_slice(&s.displacements[tip.index()][0..3]);
    let r = Vector3::from_row_slice(&s.displacements[tip.index()][3..6]);
    row(
        "tip moment M: deflection ML^2/2EI",
        Mt * L * L / (2.0 * E * Iy),
        -d.dot(&w),
    )?;
    row("tip moment M: rotation ML/EI", Mt * L / (E * Iy), r.dot(&v))?;
    let s = solve_static(&model, &[NodalLoad::force(tip, axis * P)])?;
    row(
        "axial force: PL/EA",
        P * L / (E * A),
        Vector3::from_row_slice(&s.displacements[tip.index()][0..3]).dot(&axis),
    )?;
    let s = solve_static(&model, &[NodalLoad::moment(tip, axis * Mt)])?;
    row(
        "torque T: TL/GJ",
        Mt * L / (G * J),
        Vector3::from_row_slice(&s.displacements[tip.index()][3..6]).dot(&axis),
    )?;

    writeln!(
        out,
        "\nbending frequencies about local z (Iz), Euler-Bernoulli reference (benchmarks.md A1)"
    )?;
    writeln!(
        out,
        "{:<44} {:>14} {:>14} {:>10}",
        "mode", "analytic [Hz]", "flexmbs [Hz]", "rel. error"
    )?;
    let modes = modal_dense(&model, 12)?;
    let f = modes.frequencies_hz();
    // Pick the modes that bend in the x-y plane (local y motion dominates the tip).
    let in_plane: Vec<f64> = modes
        .shapes
        .iter()
        .zip(&f)
        .filter(|(shape, _)| {
            let t = Vector3::from_row_slice(&shape[tip.index()][0..3]);
            t.dot(&v).abs() > 0.9 * t.norm()
        })
        .map(|(_, f)| *f)
        .collect();
    for (i, beta_L) in [1.87510407, 4.69409113, 7.85475744].iter().enumerate() {
        let exact = beta_L * beta_L * (E * Iz / (rho * A * L.powi(4))).sqrt() / (2.0 * std::f64::consts::PI);
        if let Some(&ours) = in_plane.get(i) {
            writeln!(
                out,
                "{:<44} {exact:>14.4} {ours:>14.4} {:>10.1e}",
                format!("clamped-free bending {}", i + 1),
                ((ours - exact) / exact).abs()
            )?;
        }
    }
    writeln!(out, "\n(higher modes differ from Euler-Bernoulli by shear and rotary inertia, which the Timoshenko element includes)")?;
    Ok(out)
}
