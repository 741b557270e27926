// The diagnostics table (`reduction::diagnostics`): effective masses from M_CB against an
// independent dense solution of the full FE model, the identity "all fixed-interface modes
// plus what the interface carries = the body's rigid mass", the static residual, and the
// warnings.
//
// The identity checked (module docs of `diagnostics`): for a free body clamped at its
// interface set, summed over all fixed-interface modes,
//   sum_k L_kd^2 / m_k + [R_b^T (M_bb - M_bi M_ii^-1 M_ib) R_b]_dd = [R^T M R]_dd,
// where the bracket on the left is the mass the interface carries. With a lumped (diagonal)
// mass matrix it is the interface node's own mass, m / (2n) for a uniform beam of n elements
// clamped at one end: a hand value.

use fe_model::{
    assemble, BeamSection, DofMap, DofMask, FeModel, MassKind, NodeId,
    SystemPattern,
};
use nalgebra::{DMatrix, Vector3};
use reduction::diagnostics::DIRECTIONS;
use reduction::{diagnostics, reduce, CbSettings, DiagnosticWarning, Diagnostics, ModeSelection, ReducedBody};

/// A free steel beam of rectangular section 30 x 20 mm (distinct bending frequencies in the
/// two planes, so every mode is unique), `n` elements along a skewed axis; returns its nodes
/// in order along the axis.
fn beam(n: usize, mass: MassKind) -> (FeModel, Vec<NodeId>) {
    super::common::skew_steel_beam(n, BeamSection::rectangle("30x20", 0.03, 0.02, 0.3).unwrap(), mass)
}

/// Effective masses of every fixed-interface mode of the full FE model, clamped at `clamp`,
/// by a dense generalised eigen-solution (nalgebra, independent of the crate's solver), and
/// the mass the interface carries, both about the centre of mass `c`.
struct Reference {
    /// Per mode (ascending frequency), the six effective masses.
    effective: Vec<[f64; 6]>,
    /// diag R_b^T (M_bb - M_bi M_ii^-1 M_ib) R_b.
    interface: [f64; 6],
    /// diag R^T M R.
    rigid: [f64; 6],
}

fn reference(model: &FeModel, clamp: NodeId, c: [f64; 3]) -> Reference {
    let dofs = DofMap::new(model).unwrap();
    let a = assemble(model, &SystemPattern::new(model, &dofs)).unwrap();
    let n = dofs.n_free();
    let dense = |A: &faer::sparse::SparseColMat<usize, f64>| {
        let mut D = DMatrix::zeros(n, n);
        for j in 0..n {
            for (&i, &v) in A.as_ref().row_idx_of_col_raw(j).iter().zip(A.as_ref().val_of_col(j)) {
                D[(i, j)] += v;
            }
        }
        D
    };
    let (K, M) = (dense(&a.K), dense(&a.M));
    // Rigid modes about c on the free dofs.
    let mut R = DMatrix::zeros(n, 6);
    for d in 0..n {
        let slot = dofs.full_slot(fe_model::Dof(d as u32));
        let (node, k) = (slot / 6, slot % 6);
        let r = model.mesh.nodes[node].coords - Vector3::from(c);
        R[(d, k)] = 1.0;
        if k < 3 {
            for l in 0..3 {
                R[(d, 3 + l)] = Vector3::ith(l, 1.0).cross(&r)[k];
            }
        }
    }
    let boundary: Vec<usize> = (0..6).map(|k| dofs.free_dof(clamp, k).unwrap().index()).collect();
    let internal: Vec<usize> = (0..n).filter(|d| !boundary.contains(d)).collect();
    let pick = |A: &DMatrix<f64>, rows: &[usize], cols: &[usize]| {
        DMatrix::from_fn(rows.len(), cols.len(), |i, j| A[(rows[i], cols[j])])
    };
    let (K_ii, M_ii, M_ib, M_bb) = (
        pick(&K, &internal, &internal),
        pick(&M, &internal, &internal),
        pick(&M, &internal, &boundary),
        pick(&M, &boundary, &boundary),
    );
    // K_ii phi = lambda M_ii phi via M_ii = L L^T: C = L^-1 K_ii L^-T, phi = L^-T y, which are
    // M_ii-orthonormal.
    let L = M_ii.clone().cholesky().unwrap().l();
    let X = L.solve_lower_triangular(&K_ii).unwrap();
    let C = L.solve_lower_triangular(&X.transpose()).unwrap();
    let eig = ((&C + C.transpose()) * 0.5).symmetric_eigen();
    let Phi = L.transpose().solve_upper_triangular(&eig.eigenvectors).unwrap();
    let MR = &M * &R;
    let MR_i = pick(&MR, &internal, &[0, 1, 2, 3, 4, 5]);
    let Lk = Phi.transpose() * &MR_i;
    let mut order: Vec<usize> = (0..internal.len()).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let effective = order
        .iter()
        .map(|&k| [0, 1, 2, 3, 4, 5].map(|d| Lk[(k, d)] * Lk[(k, d)]))
        .collect();
    let R_b = pick(&R, &boundary, &[0, 1, 2, 3, 4, 5]);
    let schur = &M_bb - M_ib.transpose() * M_ii.clone().cholesky().unwrap().solve(&M_ib);
    let carried = R_b.transpose() * schur * &R_b;
    let rigid = R.transpose() * &M * &R;
    Reference {
        effective,
        interface: [0, 1, 2, 3, 4, 5].map(|d| carried[(d, d)]),
        rigid: [0, 1, 2, 3, 4, 5].map(|d| rigid[(d, d)]),
    }
}

fn clamped_body(model: &FeModel, clamp: NodeId, m: usize) -> ReducedBody {
    let selection = if m == 0 {
        ModeSelection::StaticOnly
    } else {
        ModeSelection::Count(m)
    };
    reduce(model, "beam", &[("A".to_string(), clamp)], &CbSettings::new(selection)).unwrap()
}

fn check_against_reference(n: usize, mass: MassKind) {
    let (model, nodes) = beam(n, mass);
    let clamp = nodes[0];
    let ni = 6 * (n + 1) - 6;
    let first = clamped_body(&model, clamp, 1);
    let reference = reference(&model, clamp, first.inertia.center_of_mass);
    let total: [f64; 6] = std::array::from_fn(|d| reference.effective.iter().map(|e| e[d]).sum());
    let rigid = diagnostics(&first, None, 3.0).rigid_mass;
    for d in 0..6 {
        // The identity on the dense reference: all modes + what the interface carries = the
        // rigid mass; round-off of dense solves of condition ~1e8, relative.
        let sum = total[d] + reference.interface[d];
        assert!(
            (sum - reference.rigid[d]).abs() <= 1e-8 * reference.rigid[d],
            "{}: {sum} vs {}",
            DIRECTIONS[d],
            reference.rigid[d]
        );
        // And the rigid mass is the body's mass data (round-off).
        assert!(
            (rigid[d] - reference.rigid[d]).abs() <= 1e-10 * rigid[d],
            "{}: {} vs {}",
            DIRECTIONS[d],
            rigid[d],
            reference.rigid[d]
        );
    }
    let mut previous: Option<Diagnostics> = None;
    for m in [0, 3, 10, ni - 1] {
        let body = clamped_body(&model, clamp, m);
        let diag = diagnostics(&body, None, 3.0);
        assert_eq!(diag.modes.len(), m);
        let mut worst = 0.0f64;
        for (k, mode) in diag.modes.iter().enumerate() {
            for d in 0..6 {
                worst = worst.max((mode.effective_mass[d] - reference.effective[k][d]).abs() / rigid[d]);
            }
        }
        println!("{mass:?}, m = {m:2}: per-mode effective masses within {worst:.2e} of the dense reference (fraction of the rigid mass)");
        // Modes from the crate's solver against dense ones. The solver guarantees relative
        // residuals of 1e-8 (vectors to about 1e-8); measured 1.7e-11 (consistent) and
        // 1.4e-12 (lumped). 1e-9 keeps a margin of 50 over the measurement and still catches
        // any error in the formula (which would be of order one).
        assert!(worst <= 1e-9, "m = {m}: worst {worst:.3e}");
        for d in 0..6 {
            // kept + static = 1 for a free body: the same projection, round-off only.
            assert!(
                (diag.kept_fraction[d] + diag.static_fraction[d] - 1.0).abs() <= 1e-10,
                "{diag}"
            );
            // The static share is what the interface carries plus the modes not kept.
            let unkept: f64 = reference.effective[m..].iter().map(|e| e[d]).sum();
            let expected = (reference.interface[d] + unkept) / rigid[d];
            assert!(
                // Same accuracy argument as the per-mode values, summed over the modes.
                (diag.static_fraction[d] - expected).abs() <= 1e-9,
                "m = {m}, {}: static {} vs interface + unkept {expected}",
                DIRECTIONS[d],
                diag.static_fraction[d]
            );
            if let Some(p) = &previous {
                assert!(
                    diag.static_fraction[d] <= p.static_fraction[d] + 1e-12,
                    "static share grew with more modes"
                );
            }
        }
        if m == 10 {
            println!("{diag}");
        }
        previous = Some(diag);
    }
}

#[test]
fn effective_masses_sum_to_rigid_mass_minus_what_the_interface_carries_consistent_mass() {
    check_against_reference(6, MassKind::Consistent);
}

#[test]
fn effective_masses_sum_to_rigid_mass_minus_the_interface_node_mass_lumped() {
    let n = 6;
    check_against_reference(n, MassKind::Lumped);
    // The hand value: a lumped uniform beam's end node carries half an element's mass.
    let (model, nodes) = beam(n, MassKind::Lumped);
    let body = clamped_body(&model, nodes[0], 1);
    let r = reference(&model, nodes[0], body.inertia.center_of_mass);
    let m = body.inertia.mass;
    for d in 0..3 {
        assert!(
            (r.interface[d] - m / (2.0 * n as f64)).abs() <= 1e-12 * m,
            "{}: {} vs m/2n = {}",
            DIRECTIONS[d],
            r.interface[d],
            m / (2.0 * n as f64)
        );
    }
}

#[test]
fn warnings_fire_when_expected() {
    let (model, nodes) = beam(8, MassKind::Consistent);
    let interfaces = vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[8])];
    let body = reduce(&model, "beam", &interfaces, &CbSettings::new(ModeSelection::Count(4))).unwrap();
    let f: Vec<f64> = body
        .fixed_interface_omega
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect();
    let highest = f[3];
    let kinds = |d: &Diagnostics| {
        d.warnings
            .iter()
            .map(|w| format!("{w:?}"))
            .collect::<Vec<_>>()
            .join("; ")
    };

    // No excitation: no frequency check, and the free body raises nothing.
    let d = diagnostics(&body, None, 4.0);
    assert!(d.warnings.is_empty(), "{}", kinds(&d));
    assert!(d.to_string().contains("warnings: none"));
    // Excitation well below: fine.
    let d = diagnostics(&body, Some(highest / 5.0), 4.0);
    assert!(
        d.warnings
            .iter()
            .all(|w| !matches!(w, DiagnosticWarning::ModesMissing { .. })),
        "{}",
        kinds(&d)
    );
    // Excitation at half the highest kept mode with factor 4: modes missing.
    let d = diagnostics(&body, Some(highest / 2.0), 4.0);
    assert!(
        d.warnings
            .iter()
            .any(|w| matches!(w, DiagnosticWarning::ModesMissing { factor, .. } if *factor == 4.0)),
        "{}",
        kinds(&d)
    );
    println!("{d}");
    assert!(d.to_string().contains("modes are missing"));
    // In the study file's words, not the library's type.
    assert!(d.to_string().contains("`cutoff_hz = ") && !d.to_string().contains("ModeSelection"));
    // Excitation at the first mode: mode 1 (and any below sqrt(2) f_1) is near resonance.
    let d = diagnostics(&body, Some(f[0]), 3.0);
    let near = d.warnings.iter().find_map(|w| match w {
        DiagnosticWarning::NearExcitation { modes, .. } => Some(modes.clone()),
        _ => None,
    });
    let expected: Vec<usize> = (1..=4)
        .filter(|&k| f[k - 1] < std::f64::consts::SQRT_2 * f[0])
        .collect();
    assert_eq!(near, Some(expected));
    // Static modes only, with an excitation.
    let stat = reduce(&model, "beam", &interfaces, &CbSettings::new(ModeSelection::StaticOnly)).unwrap();
    let d = diagnostics(&stat, Some(10.0), 3.0);
    assert!(
        matches!(d.warnings.as_slice(), [DiagnosticWarning::StaticOnly { .. }]),
        "{}",
        kinds(&d)
    );
    assert!(d.to_string().contains("`cutoff_hz`") && !d.to_string().contains("ModeSelection"));
    // Unusable inputs are reported, not panicked on.
    for (f, factor) in [(-1.0, 3.0), (f64::NAN, 3.0), (10.0, 0.5)] {
        let d = diagnostics(&body, Some(f), factor);
        assert!(
            matches!(d.warnings.as_slice(), [DiagnosticWarning::InvalidInput { .. }]),
            "{}",
            kinds(&d)
        );
    }
    // A body supported in its FE model: the effective masses do not add up, and it says so.
    let mut supported = model.clone();
    supported.add_support(nodes[4], DofMask::ALL);
    let body = reduce(
        &supported,
        "beam",
        &interfaces,
        &CbSettings::new(ModeSelection::Count(2)),
    )
    .unwrap();
    let d = diagnostics(&body, None, 3.0);
    assert!(
        d.warnings
            .iter()
            .any(|w| matches!(w, DiagnosticWarning::NotFree { .. })),
        "{}",
        kinds(&d)
    );
    // Plain data: a JSON round trip.
    let json = serde_json::to_string(&d).unwrap();
    assert_eq!(serde_json::from_str::<Diagnostics>(&json).unwrap(), d);
}
