// Geometric stiffening of reduced bodies (`reduction::geometric`, `CbSettings::geometric_stiffening`):
// - the reduced matrices against the full model: sum_k w_k G_k = V^T K_G(sigma(V w)) V for
//   random w (beam and hex20 bodies, RBE2 spiders), and sum_k r_k G_k = 0 for a rigid motion r
//   of a free body;
// - the buckling load of a clamped reduced body, K_CB phi = lambda (-sum_k q_k G_k) phi with q
//   the static solution of a unit axial compression, converging from above to the full FE
//   model's (and Euler's) as fixed-interface modes are added: beam and hex20 rods;
// - reduce_external refuses geometric stiffening (no elements); the .rbody file keeps G and
//   still reads format version 1 (a file written before G existed);
// - release only: the cost of G for the C2 hex20 rod and a 50k-dof hex8 block.

use fe_model::generate::straight_beam;
use fe_model::{
    add_interface_on_set, assemble_geometric_stiffness, box_mesh, linear_buckling, solid_model, BeamProperties,
    BeamSection, BeamTheory, BucklingSettings, CellKind, DofMap, DofMask, FeModel, MassKind,
    NodalLoad, NodeId, SpiderKind, SystemPattern,
};
use nalgebra::{DMatrix, Point3, Vector3};
use reduction::file;
use reduction::{reduce, CbSettings, ModeSelection, ReducedBody, ReductionError};
use std::f64::consts::PI;
use std::path::Path;

/// A deterministic pseudo-random sequence in (-0.5, 0.5).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

use super::common::steel;

/// A beam of `n` elements from `p0` along `axis` (length `L`), rectangular 20 x 30 mm, with
/// interfaces "a" and "b" at its ends.
fn beam_body_model(
    n: usize,
    L: f64,
    p0: Point3<f64>,
    axis: Vector3<f64>,
    theory: BeamTheory,
) -> (FeModel, Vec<(String, NodeId)>, BeamSection) {
    let mut model = FeModel::default();
    let material = model.add_material(steel());
    let s = BeamSection::rectangle("rect", 0.02, 0.03, 0.3).unwrap();
    let section = model.add_section(s.clone());
    let orientation = if axis.cross(&Vector3::z()).norm() > 0.1 {
        Vector3::z().cross(&axis)
    } else {
        Vector3::y()
    };
    let props = BeamProperties {
        section,
        material,
        orientation,
        theory,
        mass: MassKind::Consistent,
    };
    let nodes = straight_beam(&mut model, p0, p0 + axis * L, n, &props, None).unwrap();
    let interfaces = vec![("a".to_string(), nodes[0]), ("b".to_string(), nodes[n])];
    (model, interfaces, s)
}

/// A hex20 rod of length `L`, square side `a`, centred on the x axis, `along` x 2 x 2
/// elements, with RBE2 interfaces "a" (x = 0) and "b" (x = L).
fn hex20_rod_model(L: f64, a: f64, along: usize) -> (FeModel, Vec<(String, NodeId)>) {
    let mut mesh = box_mesh(CellKind::Hex20, [L, a, a], [along, 2, 2]).unwrap();
    for x in &mut mesh.nodes {
        x.y -= a / 2.0;
        x.z -= a / 2.0;
    }
    let mut model = solid_model(mesh, steel(), MassKind::Consistent).unwrap();
    let na = add_interface_on_set(&mut model, "a", "x0", None, SpiderKind::Rbe2).unwrap();
    let nb = add_interface_on_set(&mut model, "b", "x1", None, SpiderKind::Rbe2).unwrap();
    (model, vec![("a".to_string(), na), ("b".to_string(), nb)])
}

fn stiffened(modes: ModeSelection) -> CbSettings {
    let mut settings = CbSettings::new(modes);
    settings.geometric_stiffening = true;
    settings
}

fn to_nalgebra(A: &reduction::DenseMatrix) -> DMatrix<f64> {
    DMatrix::from_fn(A.nrows, A.ncols, |i, j| A.get(i, j))
}

/// $\sum_k c_k \mathbf G_k$.
fn contract(body: &ReducedBody, c: &[f64]) -> DMatrix<f64> {
    let n = body.n_coordinates();
    let G = body
        .geometric_stiffness
        .as_ref()
        .expect("reduced with geometric stiffening");
    assert_eq!(G.len(), n);
    let mut sum = DMatrix::zeros(n, n);
    for (G_k, c_k) in G.iter().zip(c) {
        sum += *c_k * to_nalgebra(G_k);
    }
    sum
}

fn max_abs(A: &DMatrix<f64>) -> f64 {
    A.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// $\mathbf V$ on the free dofs of `model`, from the body's mesh shapes ($\mathbf T\mathbf V$
/// on every slot): the rows of the free dofs' slots.
fn basis_on_free_dofs(model: &FeModel, body: &ReducedBody) -> (DofMap, DMatrix<f64>) {
    let dofs = DofMap::new(model).unwrap();
    let shapes = &body.mesh.as_ref().expect("mesh shapes kept").shapes;
    let V = DMatrix::from_fn(dofs.n_free(), shapes.ncols, |d, c| {
        shapes.get(dofs.full_slot(fe_model::Dof(d as u32)), c)
    });
    (dofs, V)
}

/// Checks $\sum_k w_k\mathbf G_k = \mathbf V^T\mathbf K_G(\boldsymbol\sigma(\mathbf V\mathbf w))
/// \mathbf V$ for two random `w`.
fn check_contraction(model: &FeModel, body: &ReducedBody, what: &str) {
    let (dofs, V) = basis_on_free_dofs(model, body);
    let pattern = SystemPattern::new(model, &dofs);
    let mut rng = Lcg(19);
    for _ in 0..2 {
        let w: Vec<f64> = (0..V.ncols()).map(|_| 1e-3 * rng.next()).collect();
        let u = &V * DMatrix::from_column_slice(w.len(), 1, &w);
        let u: Vec<f64> = u.iter().copied().collect();
        let K_G = assemble_geometric_stiffness(model, &dofs, &pattern, &u)
            .unwrap()
            .to_dense();
        let K_G = DMatrix::from_fn(K_G.nrows(), K_G.ncols(), |i, j| K_G[(i, j)]);
        let full = V.transpose() * K_G * &V;
        let reduced = contract(body, &w);
        // The same element integrals summed in another order: round-off.
        let error = max_abs(&(&reduced - &full)) / max_abs(&full);
        assert!(
            error < 1e-11,
            "{what}: sum_k w_k G_k differs from V^T K_G V by {error:e}"
        );
    }
}

/// CB coordinates of the rigid motion $\mathbf t + \boldsymbol\omega\times\mathbf x$: each
/// interface translates and rotates with it, the modal amplitudes are zero.
fn rigid_coordinates(body: &ReducedBody, t: Vector3<f64>, omega: Vector3<f64>) -> Vec<f64> {
    let mut r = vec![0.0; body.n_coordinates()];
    for (k, interface) in body.interfaces.iter().enumerate() {
        let x = Vector3::from(interface.position);
        let u = t + omega.cross(&x);
        r[6 * k..6 * k + 3].copy_from_slice(u.as_slice());
        r[6 * k + 3..6 * k + 6].copy_from_slice(omega.as_slice());
    }
    r
}

/// `tolerance` relative to a random field's $\sum_k w_k\mathbf G_k$: the constraint modes
/// reproduce a rigid motion to the accuracy of the $\mathbf K_{ii}$ solves (about
/// $\kappa(\mathbf K_{ii})\,\varepsilon$ relative, larger for large meshes), and the strain of
/// what is left over is what $\mathbf G$ sees.
fn check_rigid_motion(body: &ReducedBody, what: &str, tolerance: f64) {
    let r = rigid_coordinates(body, Vector3::new(1e-3, -2e-3, 5e-4), Vector3::new(0.01, -0.02, 0.015));
    let mut rng = Lcg(23);
    let w: Vec<f64> = (0..r.len()).map(|_| 1e-3 * rng.next()).collect();
    let scale = max_abs(&contract(body, &w));
    let rigid = max_abs(&contract(body, &r));
    assert!(
        rigid <= tolerance * scale,
        "{what}: sum_k r_k G_k = {rigid:e} against {scale:e}"
    );
}

#[test]
fn reduced_geometric_stiffness_equals_the_full_model_projection() {
    // A free Timoshenko beam on a skewed axis, 4 modes; the same beam clamped at one end
    // (supports in the FE model); a hex20 rod with RBE2 spiders, 4 modes.
    let axis = Vector3::new(1.0, 0.5, -0.3).normalize();
    let (model, interfaces, _) = beam_body_model(8, 1.0, Point3::new(0.1, 0.2, 0.3), axis, BeamTheory::Timoshenko);
    let body = reduce(&model, "beam", &interfaces, &stiffened(ModeSelection::Count(4))).unwrap();
    check_contraction(&model, &body, "free beam");
    // Small bodies: round-off of ~1e-2 m rigid displacements against 1e-3 strains.
    check_rigid_motion(&body, "free beam", 1e-11);

    let (model, interfaces) = hex20_rod_model(0.3, 0.02, 6);
    let body = reduce(&model, "rod", &interfaces, &stiffened(ModeSelection::Count(4))).unwrap();
    check_contraction(&model, &body, "hex20 rod");
    check_rigid_motion(&body, "hex20 rod", 1e-11);
    for G_k in body.geometric_stiffness.as_ref().unwrap() {
        let G_k = to_nalgebra(G_k);
        assert_eq!(G_k, G_k.transpose());
    }

    // Without the setting, no G.
    let plain = reduce(&model, "rod", &interfaces, &CbSettings::new(ModeSelection::Count(4))).unwrap();
    assert!(plain.geometric_stiffness.is_none());
}

/// Lowest load factor of the reduced body clamped at interface "a" (its six coordinates
/// removed) under a unit compression along `axis` at interface "b":
/// $\mathbf K_{rr}\boldsymbol\phi = \lambda(-\sum_k q_k\mathbf G_k)_{rr}\boldsymbol\phi$.
fn reduced_buckling_load(body: &ReducedBody, axis: Vector3<f64>) -> f64 {
    let n = body.n_coordinates();
    let free: Vec<usize> = (6..n).collect();
    let K = to_nalgebra(&body.K_CB);
    let K_rr = K.select_rows(&free).select_columns(&free);
    let mut f = DMatrix::zeros(n - 6, 1);
    for i in 0..3 {
        f[(i, 0)] = -axis[i];
    }
    let chol = K_rr.clone().cholesky().expect("clamped body is stiff");
    let q_r = chol.solve(&f);
    let mut q = vec![0.0; n];
    for (i, &c) in free.iter().enumerate() {
        q[c] = q_r[(i, 0)];
    }
    let A = -contract(body, &q).select_rows(&free).select_columns(&free);
    // A phi = mu K phi, mu = 1/lambda: L^{-1} A L^{-T}.
    let L_inv = chol.l().try_inverse().unwrap();
    let C = &L_inv * A * L_inv.transpose();
    let mu = nalgebra::SymmetricEigen::new(0.5 * (&C + C.transpose()))
        .eigenvalues
        .max();
    1.0 / mu
}

/// Reduced buckling loads for 0, 2, 4 and 8 modes, relative to `reference`, each below the
/// previous and all above the full model's (Rayleigh-Ritz: the static state is exact with
/// constraint modes, so the reduced problem is the full one on the CB subspace).
fn check_convergence(
    model: &FeModel,
    interfaces: &[(String, NodeId)],
    axis: Vector3<f64>,
    P_full: f64,
    what: &str,
) -> Vec<(usize, f64)> {
    let mut table = Vec::new();
    for m in [0, 2, 4, 8] {
        let modes = if m == 0 {
            ModeSelection::StaticOnly
        } else {
            ModeSelection::Count(m)
        };
        let body = reduce(model, what, interfaces, &stiffened(modes)).unwrap();
        table.push((m, reduced_buckling_load(&body, axis) / P_full - 1.0));
    }
    println!("{what}: (modes, reduced / full - 1) {table:?}");
    assert!(table.iter().all(|&(_, e)| e > -1e-8), "{what}: {table:?}");
    assert!(table.windows(2).all(|w| w[1].1 <= w[0].1 + 1e-9), "{what}: {table:?}");
    table
}

#[test]
fn buckling_of_a_clamped_reduced_beam_converges_to_euler_as_modes_are_added() {
    let L = 1.2;
    let axis = Vector3::new(1.0, 2.0, 2.0).normalize();
    let (mut model, interfaces, s) = beam_body_model(16, L, Point3::origin(), axis, BeamTheory::EulerBernoulli);
    let P_euler = PI * PI * steel().E() * s.Iy().min(s.Iz()) / (4.0 * L * L);
    let body_model = model.clone();
    // The full FE model, clamped at "a".
    model.add_support(interfaces[0].1, DofMask::ALL);
    let P_full = linear_buckling(
        &model,
        &[NodalLoad::force(interfaces[1].1, -axis)],
        &BucklingSettings::new(1),
    )
    .unwrap()
    .load_factors[0];
    assert!(
        (P_full / P_euler - 1.0).abs() < 1e-5,
        "16 beam elements: {P_full} against Euler {P_euler}"
    );
    let table = check_convergence(&body_model, &interfaces, axis, P_full, "beam");
    // Static modes alone are the cubic shapes of one Hermite element: +0.75 %.
    assert!((table[0].1 - 7.522e-3).abs() < 2e-5, "{table:?}");
    assert!(table[3].1 < 1e-4, "{table:?}");
}

#[test]
fn buckling_of_a_clamped_reduced_hex20_rod_converges_as_modes_are_added() {
    // The C2 rod's section (square of the 6 mm round rod's I) on a 0.3 m hex20 rod.
    let (L, a) = (0.3, (3.0 * PI / 16.0).powf(0.25) * 0.006);
    let (model, interfaces) = hex20_rod_model(L, a, 24);
    let mut clamped = model.clone();
    clamped.add_support(interfaces[0].1, DofMask::ALL);
    let axis = Vector3::x();
    let P_full = linear_buckling(
        &clamped,
        &[NodalLoad::force(interfaces[1].1, -axis)],
        &BucklingSettings::new(1),
    )
    .unwrap()
    .load_factors[0];
    let P_euler = PI * PI * steel().E() * a.powi(4) / 12.0 / (4.0 * L * L);
    println!("hex20 rod: full model / Euler - 1 = {:+.3e}", P_full / P_euler - 1.0);
    // Shear and the end plates, as for fe-model's hex20 column: below 1 % here (L/a = 56).
    assert!((P_full / P_euler - 1.0).abs() < 1e-2);
    let table = check_convergence(&model, &interfaces, axis, P_full, "hex20 rod");
    assert!(table[0].1 > 5e-3 && table[3].1 < 1e-3, "{table:?}");
}

#[test]
fn external_matrices_cannot_carry_geometric_stiffening() {
    let (model, interfaces, _) = beam_body_model(4, 1.0, Point3::origin(), Vector3::x(), BeamTheory::EulerBernoulli);
    let dofs = DofMap::new(&model).unwrap();
    let assembled = fe_model::assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap();
    let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    let named: Vec<(String, usize)> = interfaces.iter().map(|(n, id)| (n.clone(), id.index())).collect();
    let e = reduction::reduce_external(
        &nodes,
        assembled.K.as_ref(),
        assembled.M.as_ref(),
        6,
        "beam",
        &named,
        &stiffened(ModeSelection::Count(2)),
    )
    .unwrap_err();
    assert!(
        matches!(&e, ReductionError::ExternalModel { what } if what.contains("geometric stiffening")),
        "{e}"
    );
}

#[test]
fn the_body_file_keeps_g_and_reads_format_version_1() {
    let (model, interfaces) = hex20_rod_model(0.3, 0.02, 4);
    let body = reduce(&model, "rod", &interfaces, &stiffened(ModeSelection::Count(2))).unwrap();
    let origin = Path::new("bodies/rod.rbody");
    let bytes = file::to_bytes(&body, origin).unwrap();
    let back = file::from_bytes(&bytes, origin).unwrap();
    assert_eq!(back, body);
    let bits = |b: &ReducedBody| -> Vec<u64> {
        b.geometric_stiffness
            .iter()
            .flatten()
            .flat_map(|G| G.data.iter().map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&back), bits(&body));
    assert_eq!(bits(&body).len(), 14 * 14 * 14);
    assert!(String::from_utf8_lossy(&bytes[..4000]).contains("\"geometric_stiffness\": true"));

    // A body with the wrong number of G matrices cannot be written.
    let mut broken = body.clone();
    broken.geometric_stiffness.as_mut().unwrap().pop();
    assert!(file::to_bytes(&broken, origin).is_err());

    // A file written by format version 1 (before G existed): `flexmbs run` on the cantilever
    // example with 4 beam elements (L = 2 m, 20 x 40 mm, steel, Timoshenko, interfaces "root"
    // and "tip", 4 modes), at commit 0d2b0ba. It reads as a body without G, and matches the
    // same reduction today.
    let v1 = file::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cantilever_v1.rbody")).unwrap();
    assert!(v1.geometric_stiffness.is_none());
    assert_eq!(v1.format_version, reduction::FORMAT_VERSION);
    let (beam, nodes) = super::common::beam_model(
        steel(),
        BeamSection::rectangle("bar-20x40", 0.02, 0.04, 0.3).unwrap(),
        (BeamTheory::Timoshenko, MassKind::Consistent),
        Vector3::y(),
        (Point3::origin(), Point3::new(2.0, 0.0, 0.0)),
        4,
    );
    let today = reduce(
        &beam,
        "beam",
        &[("root".to_string(), nodes[0]), ("tip".to_string(), nodes[4])],
        &CbSettings::new(ModeSelection::Count(4)),
    )
    .unwrap();
    let (K_v1, K_now) = (to_nalgebra(&v1.K_CB), to_nalgebra(&today.K_CB));
    assert!(
        max_abs(&(&K_v1 - &K_now)) <= 1e-9 * max_abs(&K_now),
        "K_CB of the version-1 file"
    );
    assert_eq!(v1.fixed_interface_omega.len(), 4);
    // And it writes back as version 2 and reads again.
    let again = file::from_bytes(&file::to_bytes(&v1, origin).unwrap(), origin).unwrap();
    assert_eq!(again, v1);
}

/// CPU seconds (user + system, all threads) of this process so far.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: times G for the C2 rod and a 50k-dof block"
)]
fn cost_of_the_geometric_stiffness() {
    // Times are printed, never asserted (machine load). The C2 rod: hex20 24 x 2 x 2, 4 modes;
    // the 50k block of `benches/craig_bampton.rs` (hex8 30 x 23 x 23) with 16 modes.
    let c2 = {
        let (L, a) = (0.3, (3.0 * PI / 16.0).powf(0.25) * 0.006);
        let (model, interfaces) = hex20_rod_model(L, a, 24);
        (model, interfaces, 4, "C2 rod, hex20 24x2x2")
    };
    let block = {
        let mesh = box_mesh(CellKind::Hex8, [2.0 * 30.0 / 23.0, 1.0, 1.0], [30, 23, 23]).unwrap();
        let mut model = solid_model(mesh, steel(), MassKind::Consistent).unwrap();
        let na = add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
        let nb = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe2).unwrap();
        (
            model,
            vec![("root".to_string(), na), ("tip".to_string(), nb)],
            16,
            "block, hex8 30x23x23",
        )
    };
    for (model, interfaces, modes, what) in [c2, block] {
        let (wall_reduce, cpu_reduce) = (std::time::Instant::now(), cpu_seconds());
        let body = reduce(&model, what, &interfaces, &CbSettings::new(ModeSelection::Count(modes))).unwrap();
        let (wall_reduce, cpu_reduce) = (wall_reduce.elapsed().as_secs_f64(), cpu_seconds() - cpu_reduce);
        let shapes = &body.mesh.as_ref().unwrap().shapes;
        let S_full = faer::Mat::from_fn(shapes.nrows, shapes.ncols, |i, j| shapes.get(i, j));
        let (wall, cpu) = (std::time::Instant::now(), cpu_seconds());
        let G = reduction::reduced_geometric_stiffness(&model, S_full.as_ref()).unwrap();
        let (wall, cpu) = (wall.elapsed().as_secs_f64(), cpu_seconds() - cpu);
        let dofs = DofMap::new(&model).unwrap().n_free();
        println!(
            "{what}: {dofs} dofs, {} elements, n = {}: G in {wall:.3} s wall, {cpu:.2} s CPU ({} threads); the reduction without G {wall_reduce:.2} s wall, {cpu_reduce:.2} s CPU",
            model.elements.len(),
            G.len(),
            rayon::current_num_threads()
        );
        let mut with_g = body.clone();
        with_g.geometric_stiffness = Some(G);
        // 50k dofs: 1e-4 against 4e6 measured (2.6e-11).
        check_rigid_motion(&with_g, what, 1e-9);
    }
}
