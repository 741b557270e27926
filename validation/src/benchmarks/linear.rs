//! The linear references of the validation guide (`docs/validation.md`) A: beam frequencies (A1), cantilever statics
//! (A2), Craig-Bampton convergence (A3) and NAFEMS FV32 (A4). Every model lies along a
//! skewed axis (or in a general plane) so that no global axis is special.

use crate::{Extent, Row, Table};
use fe_model::generate::straight_beam;
use fe_model::{
    box_mesh, modal_dense, solid_model, solve_static, BeamProperties, BeamSection, BeamTheory, CellKind, DofMask,
    FeModel, IsotropicMaterial, MassKind, NodalLoad, NodeId,
};
use nalgebra::{Point3, Vector3};
use reduction::{modal_sparse, reduce, CbSettings, ModeSelection, Shift};
use std::error::Error;
use std::f64::consts::PI;

type Result<T> = std::result::Result<T, Box<dyn Error>>;

const E: f64 = 210e9;
const NU: f64 = 0.3;
const RHO: f64 = 7850.0;
const G: f64 = E / (2.0 * (1.0 + NU));

/// The skewed axis and local y, z of every beam here.
fn axes() -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let x = Vector3::new(1.0, 2.0, 2.0).normalize();
    let y = Vector3::new(0.3, -0.4, 0.1).cross(&x).normalize();
    (x, y, x.cross(&y))
}

/// A steel beam of `n` elements along the skewed axis, rectangle `b` (local y) x `h` (local z).
fn beam(L: f64, b: f64, h: f64, n: usize, theory: BeamTheory) -> Result<(FeModel, Vec<NodeId>, BeamSection)> {
    let (x, y, _) = axes();
    let mut model = FeModel::default();
    let material = model.add_material(IsotropicMaterial::new("steel", E, NU, RHO)?);
    let s = BeamSection::rectangle("rect", b, h, NU)?;
    let section = model.add_section(s.clone());
    let props = BeamProperties {
        section,
        material,
        orientation: y,
        theory,
        mass: MassKind::Consistent,
    };
    let nodes = straight_beam(
        &mut model,
        Point3::origin(),
        Point3::from(x * L),
        n,
        &props,
        Some("beam"),
    )?;
    Ok((model, nodes, s))
}

fn along(u: &[f64; 6], k0: usize, d: &Vector3<f64>) -> f64 {
    Vector3::new(u[k0], u[k0 + 1], u[k0 + 2]).dot(d)
}

/// Circular frequencies of the modes that bend mainly along local y (in the x-y plane).
fn bending_y(model: &FeModel, n_modes: usize) -> Result<Vec<f64>> {
    let (x, y, z) = axes();
    let modes = modal_dense(model, n_modes)?;
    Ok(modes
        .omega
        .iter()
        .zip(&modes.shapes)
        .filter(|(w, shape)| {
            let (mut ey, mut eo) = (0.0, 0.0);
            for u in shape.iter() {
                ey += along(u, 0, &y).powi(2);
                // Torsion moves no node of the axis: weigh its rotation by a section size
                // (0.05 m) so that torsion modes do not pass as bending.
                eo += along(u, 0, &x).powi(2) + along(u, 0, &z).powi(2) + (0.05 * along(u, 3, &x)).powi(2);
            }
            // Skip rigid modes (round-off frequencies) and other families.
            **w > 1.0 && ey > eo
        })
        .map(|(w, _)| *w)
        .collect())
}

/// A1: clamped-free and free-free bending frequencies of a slender Euler-Bernoulli beam,
/// one table per mesh.
pub fn a1_cantilever_frequencies(extent: Extent) -> Result<Vec<Table>> {
    let meshes: &[usize] = if extent == Extent::Quick {
        &[16]
    } else {
        &[4, 8, 16, 32]
    };
    let (L, b, h) = (1.0, 0.003, 0.002);
    let mut tables = Vec::new();
    for &n in meshes {
        let mut rows = Vec::new();
        for (label, clamped, betas) in [
            ("clamped-free", true, [1.87510407, 4.69409113, 7.85475744, 10.99554073]),
            ("free-free", false, [4.73004074, 7.85320462, 10.99560784, 14.13716549]),
        ] {
            let (mut model, nodes, s) = beam(L, b, h, n, BeamTheory::EulerBernoulli)?;
            if clamped {
                model.add_support(nodes[0], DofMask::ALL);
            }
            let w = bending_y(&model, 30)?;
            let scale = (E * s.Iz() / (RHO * s.A() * L.powi(4))).sqrt();
            for (i, bl) in betas.iter().enumerate() {
                // The convergence study's coarse levels are reported, not held to 0.1 %.
                let tol = if n >= 16 { 1e-3 } else { f64::INFINITY };
                rows.push(Row::new(
                    format!("{label} w_{} [rad/s]", i + 1),
                    bl * bl * scale,
                    w[i],
                    tol,
                ));
            }
        }
        tables.push(Table {
            title: format!("A1 beam bending frequencies, {n} Euler-Bernoulli elements"),
            note: "Slender steel beam (L/h = 500, so rotary inertia shifts the 4th mode by < 5e-5) along a skewed axis; \
                   cubic elements with consistent mass converge as h^4. Tolerance: the issue's 0.1 % from 16 elements on \
                   (coarser meshes are reported to show the convergence)."
                .into(),
            rows,
        });
    }
    Ok(tables)
}

/// A1: the Timoshenko pinned-pinned frequency equation on a stocky beam.
pub fn a1_timoshenko_pinned_pinned(extent: Extent) -> Result<Table> {
    let (L, b, h) = (0.8, 0.06, 0.1);
    let meshes: &[usize] = if extent == Extent::Quick {
        &[80]
    } else {
        &[20, 40, 80, 160]
    };
    let mut rows = Vec::new();
    for &n_el in meshes {
        let (mut model, nodes, s) = beam(L, b, h, n_el, BeamTheory::Timoshenko)?;
        model.add_support(nodes[0], DofMask::TRANSLATIONS);
        model.add_support(nodes[n_el], DofMask::TRANSLATIONS);
        let w = bending_y(&model, 30)?;
        let (I, A, kappa) = (s.Iz(), s.A(), s.ky());
        for n in 1..=4 {
            let k = n as f64 * PI / L;
            let kGA = kappa * G * A;
            let a = RHO * A * RHO * I;
            let bq = -(kGA * k * k * RHO * I + RHO * A * (E * I * k * k + kGA));
            let c = kGA * E * I * k.powi(4);
            let exact = ((-bq - (bq * bq - 4.0 * a * c).sqrt()) / (2.0 * a)).sqrt();
            let tol = if n_el >= 80 { 1e-3 } else { f64::INFINITY };
            rows.push(Row::new(
                format!("{n_el:3} elements: w_{n} [rad/s]"),
                exact,
                w[n - 1],
                tol,
            ));
        }
    }
    Ok(Table {
        title: "A1 Timoshenko pinned-pinned frequencies".into(),
        note: "Stocky steel beam (L/h = 8): shear and rotary inertia matter. The two-node Timoshenko element \
               converges as h^2 in frequency. Tolerance: 0.1 % from 80 elements on."
            .into(),
        rows,
    })
}

/// A2: every cantilever formula, Timoshenko elements, skewed axis.
pub fn a2_cantilever_statics() -> Result<Table> {
    let (L, b, h, P, Mt) = (1.5, 0.03, 0.05, 2500.0, 300.0);
    let (x, y, z) = axes();
    let (mut model, nodes, s) = beam(L, b, h, 8, BeamTheory::Timoshenko)?;
    model.add_support(nodes[0], DofMask::ALL);
    let tip = nodes[8];
    let u = |load: NodalLoad| -> Result<[f64; 6]> { Ok(solve_static(&model, &[load])?.displacements[tip.index()]) };
    let uf = u(NodalLoad::force(tip, z * P))?;
    let um = u(NodalLoad::moment(tip, z * Mt))?;
    let ua = u(NodalLoad::force(tip, x * P))?;
    let ut = u(NodalLoad::moment(tip, x * Mt))?;
    // Round-off: nodal values are exact for end loads; cond(K) * eps < 1e-10.
    let tol = 1e-10;
    Ok(Table {
        title: "A2 cantilever statics, 8 Timoshenko elements".into(),
        note: "Steel cantilever on a skewed axis; the element is exact for end loads, so only round-off remains."
            .into(),
        rows: vec![
            Row::new(
                "tip force: w = PL^3/3EI + PL/kGA",
                P * L.powi(3) / (3.0 * E * s.Iy()) + P * L / (s.kz() * G * s.A()),
                along(&uf, 0, &z),
                tol,
            ),
            Row::new(
                "tip force: slope PL^2/2EI",
                P * L * L / (2.0 * E * s.Iy()),
                -along(&uf, 3, &y),
                tol,
            ),
            Row::new(
                "tip moment: w = ML^2/2EI",
                Mt * L * L / (2.0 * E * s.Iz()),
                along(&um, 0, &y),
                tol,
            ),
            Row::new("tip moment: slope ML/EI", Mt * L / (E * s.Iz()), along(&um, 3, &z), tol),
            Row::new("axial: PL/EA", P * L / (E * s.A()), along(&ua, 0, &x), tol),
            Row::new("torsion: TL/GJ", Mt * L / (G * s.J()), along(&ut, 3, &x), tol),
        ],
    })
}

/// A3: the free-free spectrum of a reduced beam converges to the full model's from above.
pub fn a3_craig_bampton_convergence(extent: Extent) -> Result<Table> {
    let (mut model, nodes, _) = beam(1.0, 0.02, 0.03, 24, BeamTheory::Timoshenko)?;
    model.supports.clear();
    let interfaces = vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[24])];
    let (full, _) = modal_sparse(&model, 10, Shift::Auto)?;
    let counts: &[usize] = if extent == Extent::Quick {
        &[4, 16]
    } else {
        &[0, 2, 4, 8, 16, 32]
    };
    let mut rows = Vec::new();
    for &m in counts {
        let sel = if m == 0 {
            ModeSelection::StaticOnly
        } else {
            ModeSelection::Count(m)
        };
        let body = reduce(&model, "beam", &interfaces, &CbSettings::new(sel))?;
        let omega = reduced_frequencies(&body);
        for i in [0usize, 3] {
            rows.push(Row::new(
                format!("{m:2} modes: elastic w_{} [rad/s]", i + 1),
                full.omega[6 + i],
                omega[6 + i],
                if m >= 16 { 1e-3 } else { f64::INFINITY },
            ));
        }
    }
    Ok(Table {
        title: "A3 Craig-Bampton: free-free spectrum of a reduced beam against the full model".into(),
        note: "24 Timoshenko elements, interfaces at both ends. Errors are positive (Rayleigh-Ritz) and fall as \
               fixed-interface modes are added; the test holds 0.1 % from 16 modes on."
            .into(),
        rows,
    })
}

/// Sorted circular frequencies of a reduced body's (K_CB, M_CB), by a shift-inverted dense solve.
fn reduced_frequencies(body: &reduction::ReducedBody) -> Vec<f64> {
    let n = body.n_coordinates();
    let K = nalgebra::DMatrix::from_fn(n, n, |i, j| body.K_CB.get(i, j));
    let M = nalgebra::DMatrix::from_fn(n, n, |i, j| body.M_CB.get(i, j));
    let s = 1.0;
    let L = (&K + &M * s).cholesky().expect("K + sM is positive definite").l();
    let X = L.solve_lower_triangular(&M).expect("triangular");
    let C = L.solve_lower_triangular(&X.transpose()).expect("triangular");
    let C = (&C + C.transpose()) * 0.5;
    let mut w: Vec<f64> = C
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .map(|mu| (1.0 / mu - s).max(0.0).sqrt())
        .collect();
    w.sort_by(f64::total_cmp);
    w
}

/// A4: NAFEMS FV32, hex20, in-plane modes.
pub fn a4_fv32(extent: Extent) -> Result<Table> {
    let reference = [44.623, 130.03, 162.70, 246.05, 379.90, 391.44];
    let (nx, ny) = if extent == Extent::Quick { (16, 8) } else { (32, 16) };
    let (t, L) = (0.05, 10.0);
    let mut mesh = box_mesh(CellKind::Hex20, [L, 5.0, t], [nx, ny, 1])?;
    for p in mesh.nodes.iter_mut() {
        p.y = 2.5 + (p.y - 2.5) * (5.0 - 0.4 * p.x) / 5.0;
    }
    let clamp = mesh.node_sets.get("x0").cloned().unwrap_or_default();
    let mid: Vec<NodeId> = (0..mesh.nodes.len() as u32)
        .map(NodeId)
        .filter(|n| (mesh.nodes[n.index()].z - t / 2.0).abs() < 1e-9)
        .collect();
    let mut model = solid_model(
        mesh,
        IsotropicMaterial::new("FV32", 200e9, 0.3, 8000.0)?,
        MassKind::Consistent,
    )?;
    for n in clamp {
        model.add_support(n, DofMask::TRANSLATIONS);
    }
    for n in mid {
        model.add_support(n, DofMask::single(2));
    }
    let (modes, _) = modal_sparse(&model, 12, Shift::Zero)?;
    let f: Vec<f64> = modes
        .frequencies_hz()
        .into_iter()
        .zip(&modes.shapes)
        .filter(|(_, shape)| {
            let (a, b) = shape
                .iter()
                .fold((0.0, 0.0), |(a, b), u| (a + u[0] * u[0] + u[1] * u[1], b + u[2] * u[2]));
            b < 1e-2 * a
        })
        .map(|(f, _)| f)
        .collect();
    Ok(Table {
        title: format!("A4 NAFEMS FV32 tapered membrane, hex20 {nx} x {ny} x 1"),
        note: "Plane stress by holding w at the mid-plane; in-plane modes selected by their displacement. Tolerance: 0.5 %."
            .into(),
        rows: reference.iter().enumerate().map(|(i, &r)| Row::new(format!("f_{} [Hz]", i + 1), r, f[i], 5e-3)).collect(),
    })
}

/// A1-A4 as report blocks, in report order.
pub fn a1_to_a4(extent: Extent) -> Result<Vec<crate::Block>> {
    use crate::Block;
    let mut blocks = vec![Block::Heading("A. Linear references".into())];
    blocks.extend(a1_cantilever_frequencies(extent)?.into_iter().map(Block::Table));
    blocks.push(Block::Table(a1_timoshenko_pinned_pinned(extent)?));
    blocks.push(Block::Table(a2_cantilever_statics()?));
    blocks.push(Block::Table(a3_craig_bampton_convergence(extent)?));
    blocks.push(Block::Table(a4_fv32(extent)?));
    Ok(blocks)
}
