// Tests of `reduction::eigen` (included by `tests/unit.rs`).
//
// - chains of springs and masses, lumped and consistent mass, fixed-free and free-free,
//   against their analytic spectra;
// - a random sparse SPD pencil against a dense reference;
// - free bodies with a negative shift (1D chain, 3D lattice with six rigid modes) and the
//   singular-stiffness error with sigma = 0;
// - a 3D lattice of ~30k dofs: residuals and M-orthonormality; the `ShiftInvert` solve;
// - a spectrum spread over ten decades (soft mount) against a dense reference;
// - a clamped beam with many modes (graded spectrum, operator of norm 1e-6) against a dense
//   reference;
// - the error cases.

use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Mat, MatRef, Side};
use reduction::eigen::{lowest_modes, EigenSettings, EigenSolution, FactorPrecision, FactorSettings, Shift, ShiftInvert};
use reduction::ReductionError;
use std::f64::consts::PI;

const EPS: f64 = f64::EPSILON;

// ---------------------------------------------------------------------------------------
// Fixtures
// ---------------------------------------------------------------------------------------

fn from_triplets(n: usize, t: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
    let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(n, n, &t).expect("valid triplets")
}

#[derive(Clone, Copy, Debug)]
enum Ends {
    /// Mass 0 tied to a wall by a spring, the last mass free.
    FixedFree,
    /// No wall: one rigid-body mode.
    FreeFree,
}

#[derive(Clone, Copy, Debug)]
enum Mass {
    /// Point masses `m`.
    Lumped,
    /// Bar elements of mass `m` each, consistent mass $m/6\,[2, 1; 1, 2]$.
    Consistent,
}

/// A chain of `n` dofs with springs `k` (bars of stiffness `k` and mass `m`).
///
/// FixedFree: dofs 1..n of a bar clamped at node 0 (lumped: n masses, n springs).
/// FreeFree: n nodes, n - 1 springs.
fn chain(n: usize, ends: Ends, mass: Mass, k: f64, m: f64) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mut tk = Vec::new();
    let mut tm = Vec::new();
    // Element e joins nodes (a, b); None is the wall.
    let elements: Vec<(Option<usize>, usize)> = match ends {
        Ends::FixedFree => (0..n).map(|i| (i.checked_sub(1), i)).collect(),
        Ends::FreeFree => (1..n).map(|i| (Some(i - 1), i)).collect(),
    };
    for (a, b) in elements {
        let (me_d, me_o) = match mass {
            Mass::Lumped => (0.0, 0.0),
            Mass::Consistent => (m / 3.0, m / 6.0),
        };
        tk.push((b, b, k));
        tm.push((b, b, me_d));
        if let Some(a) = a {
            tk.extend([(a, a, k), (a, b, -k), (b, a, -k)]);
            tm.extend([(a, a, me_d), (a, b, me_o), (b, a, me_o)]);
        }
    }
    if let Mass::Lumped = mass {
        for i in 0..n {
            tm.push((i, i, m));
        }
    }
    (from_triplets(n, &tk), from_triplets(n, &tm))
}

/// The j-th (0-based) eigenvalue of [`chain`], from the discrete wave $u_i = \sin(i\theta)$
/// (fixed-free) or $\cos(i\theta)$ (free-free), and the largest eigenvalue bound.
///
/// Lumped: $\lambda = 4k/m\,\sin^2(\theta/2)$; consistent: $\lambda = 6k(1-\cos\theta) /
/// (m(2+\cos\theta))$. The free end (or ends) fix $\theta$: fixed-free lumped
/// $\theta = (2j+1)\pi/(2n+1)$, fixed-free consistent $(2j+1)\pi/(2n)$, free-free lumped
/// $j\pi/n$, free-free consistent $j\pi/(n-1)$.
fn chain_exact(n: usize, ends: Ends, mass: Mass, k: f64, m: f64, j: usize) -> (f64, f64) {
    let (n, j) = (n as f64, j as f64);
    let theta = match (ends, mass) {
        (Ends::FixedFree, Mass::Lumped) => (2.0 * j + 1.0) * PI / (2.0 * n + 1.0),
        (Ends::FixedFree, Mass::Consistent) => (2.0 * j + 1.0) * PI / (2.0 * n),
        (Ends::FreeFree, Mass::Lumped) => j * PI / n,
        (Ends::FreeFree, Mass::Consistent) => j * PI / (n - 1.0),
    };
    match mass {
        Mass::Lumped => (4.0 * k / m * (theta / 2.0).sin().powi(2), 4.0 * k / m),
        Mass::Consistent => (6.0 * k * (1.0 - theta.cos()) / (m * (2.0 + theta.cos())), 12.0 * k / m),
    }
}

/// Truss lattice: nodes on an `nx x ny x nz` grid of spacing 1, axial springs (EA = 1) to all
/// 26 neighbours (edges, face and body diagonals: a 27-point stencil with 3 coupled dofs per
/// node, like hex8 elasticity), unit lumped masses. With `clamped`, the nodes at x = 0 are
/// removed. The free lattice has exactly six rigid-body modes.
fn lattice(nx: usize, ny: usize, nz: usize, clamped: bool) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let first = usize::from(clamped);
    let dof = |i: usize, j: usize, k: usize| (i >= first).then(|| 3 * ((i - first) + (nx - first) * (j + ny * k)));
    let n = 3 * (nx - first) * ny * nz;
    let (mut tk, mut tm) = (Vec::new(), Vec::new());
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if let Some(a) = dof(i, j, k) {
                    tm.extend((0..3).map(|c| (a + c, a + c, 1.0)));
                }
                for dk in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let b = [i as i64 + di, j as i64 + dj, k as i64 + dk];
                            // Each bond once: only the "positive" half of the neighbours.
                            if (dk, dj, di) <= (0, 0, 0)
                                || b.iter().any(|&x| x < 0)
                                || b[0] >= nx as i64
                                || b[1] >= ny as i64
                                || b[2] >= nz as i64
                            {
                                continue;
                            }
                            let e = [di as f64, dj as f64, dk as f64];
                            let len: f64 = e.iter().map(|x| x * x).sum::<f64>().sqrt();
                            let (a, b) = (dof(i, j, k), dof(b[0] as usize, b[1] as usize, b[2] as usize));
                            for c in 0..3 {
                                for d in 0..3 {
                                    // EA/len * e e^T / len^2
                                    let v = e[c] * e[d] / len.powi(3);
                                    if let Some(a) = a {
                                        tk.push((a + c, a + d, v));
                                    }
                                    if let Some(b) = b {
                                        tk.push((b + c, b + d, v));
                                    }
                                    if let (Some(a), Some(b)) = (a, b) {
                                        tk.push((a + c, b + d, -v));
                                        tk.push((b + c, a + d, -v));
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    (from_triplets(n, &tk), from_triplets(n, &tm))
}

/// SplitMix64 in [0, 1): fixed-seed fixtures without a `rand` dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A random sparse SPD pencil: K = B^T B + 1e-2 I (B sparse, ~4 entries per column, so K has
/// eigenvalues from ~1e-2 up), M = diagonally dominant random sparse.
fn random_spd_pair(n: usize, seed: u64) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mut rng = Rng(seed);
    let mut B = Mat::<f64>::zeros(n, n);
    for j in 0..n {
        for _ in 0..4 {
            let i = (rng.next() * n as f64) as usize;
            B[(i, j)] += rng.next() - 0.5;
        }
    }
    let mut tk = Vec::new();
    let Kd = B.transpose() * &B;
    for j in 0..n {
        for i in 0..n {
            let v = Kd[(i, j)] + if i == j { 1e-2 } else { 0.0 };
            if v != 0.0 {
                tk.push((i, j, v));
            }
        }
    }
    let mut tm = Vec::new();
    for i in 0..n {
        tm.push((i, i, 1.0 + rng.next()));
        let j = (rng.next() * n as f64) as usize;
        if j != i {
            let v = 0.2 * (rng.next() - 0.5);
            tm.extend([(i, j, v), (j, i, v)]);
        }
    }
    (from_triplets(n, &tk), from_triplets(n, &tm))
}

fn dense(A: SparseColMatRef<'_, usize, f64>) -> Mat<f64> {
    A.to_dense()
}

/// $\max_{ij} |(\boldsymbol\Phi^T\mathbf M\boldsymbol\Phi - \mathbf I)_{ij}|$.
fn m_orthonormality_error(Phi: MatRef<'_, f64>, M: SparseColMatRef<'_, usize, f64>) -> f64 {
    let G = Phi.transpose() * (M * Phi);
    let mut worst = 0.0_f64;
    for j in 0..G.ncols() {
        for i in 0..G.nrows() {
            worst = worst.max((G[(i, j)] - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    worst
}

/// Dense reference: the eigenpairs of $\mathbf L^{-1}\mathbf K\mathbf L^{-T}$ with
/// $\mathbf M = \mathbf L\mathbf L^T$, back-transformed, ascending.
fn dense_reference(K: SparseColMatRef<'_, usize, f64>, M: SparseColMatRef<'_, usize, f64>) -> (Vec<f64>, Mat<f64>) {
    let Md = dense(M);
    let llt = Md.llt(Side::Lower).expect("M is SPD");
    let L = llt.L();
    let mut A = dense(K);
    let par = faer::Par::Seq;
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(L, A.as_mut(), par);
    let mut A = A.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(L, A.as_mut(), par);
    // Scaled to unit size: faer 0.24's divide and conquer (from dimension 128) is not
    // scale-invariant. On the clamped beam (norm 3e12) it gave lambda_1 0.4 % off, and at
    // n = 1194 a negative eigenvalue of this positive definite matrix.
    let (lambda, mut Phi) = fe_model::scaled_self_adjoint_eigen(A.as_ref()).expect("dense evd");
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(L.transpose(), Phi.as_mut(), par);
    (lambda, Phi)
}

fn solve(K: &SparseColMat<usize, f64>, M: &SparseColMat<usize, f64>, settings: &EigenSettings) -> EigenSolution {
    lowest_modes(K.as_ref(), M.as_ref(), settings).expect("eigensolver")
}

// ---------------------------------------------------------------------------------------
// 1. Chains against analytic spectra
// ---------------------------------------------------------------------------------------

/// Compares the lowest `m` computed eigenvalues of a chain with the analytic ones, skipping
/// `skip` rigid modes.
fn check_chain(ends: Ends, mass: Mass, shift: Shift, skip: usize) -> EigenSolution {
    let (n, m_modes) = (2000, 10);
    let (k, m) = (2.0e7, 0.5); // not unit values, so that scaling errors show
    let (K, M) = chain(n, ends, mass, k, m);
    let sol = solve(&K, &M, &EigenSettings::new(m_modes, shift));
    assert_eq!(sol.eigenvalues.len(), m_modes);
    for j in skip..m_modes {
        let (exact, lambda_max) = chain_exact(n, ends, mass, k, m, j);
        let rel = (sol.eigenvalues[j] - exact).abs() / exact;
        // The eigenvalue is a Rayleigh quotient: its error is quadratic in the vector error
        // (residual <= 1e-8 gives ~1e-16), so what is left is the round-off of phi^T K phi,
        // about eps * lambda_max / lambda_j per entry, summed over n entries with random
        // signs: eps (lambda_max / lambda_j) / sqrt(n). Factor 4 for the constants, 16 eps
        // for the analytic formula. For mode 1 of the lumped fixed-free chain this is 1.3e-10.
        let tol = 4.0 * EPS * (lambda_max / exact) / (n as f64).sqrt() + 16.0 * EPS;
        assert!(
            rel <= tol,
            "{ends:?} {mass:?} mode {j}: lambda = {:.16e}, exact {exact:.16e}, rel. error {rel:.3e} > {tol:.3e}",
            sol.eigenvalues[j]
        );
    }
    // Ascending, M-orthonormal.
    assert!(sol.eigenvalues.windows(2).all(|w| w[0] <= w[1]));
    // Round-off of length-n dot products with a tridiagonal M: n eps (Higham 2002, §3.1).
    let tol = n as f64 * EPS;
    let err = m_orthonormality_error(sol.vectors.as_ref(), M.as_ref());
    assert!(err <= tol, "Phi^T M Phi - I = {err:.3e} > {tol:.3e}");
    // Mode shapes: the analytic wave, M-normalised, against the computed one.
    for j in skip..m_modes {
        let (n_f, jf) = (n as f64, j as f64);
        let u = Mat::<f64>::from_fn(n, 1, |i, _| {
            let i = i as f64;
            match (ends, mass) {
                (Ends::FixedFree, Mass::Lumped) => ((i + 1.0) * (2.0 * jf + 1.0) * PI / (2.0 * n_f + 1.0)).sin(),
                (Ends::FixedFree, Mass::Consistent) => ((i + 1.0) * (2.0 * jf + 1.0) * PI / (2.0 * n_f)).sin(),
                (Ends::FreeFree, Mass::Lumped) => ((i + 0.5) * jf * PI / n_f).cos(),
                (Ends::FreeFree, Mass::Consistent) => (i * jf * PI / (n_f - 1.0)).cos(),
            }
        });
        let u_M = (u.transpose() * (M.as_ref() * &u))[(0, 0)].sqrt();
        let cos = ((u.transpose() * (M.as_ref() * sol.vectors.col(j).as_mat()))[(0, 0)] / u_M).abs();
        // The angle to the exact mode is ~ residual / relative gap ~ 1e-9, so 1 - cos ~ 1e-18:
        // what remains is the round-off of the dot products, n eps.
        let tol = n as f64 * EPS;
        assert!(
            (1.0 - cos).abs() <= tol,
            "{ends:?} {mass:?} mode {j}: 1 - |cos| = {:.3e} > {tol:.3e}",
            1.0 - cos
        );
    }
    sol
}

#[test]
fn chain_fixed_free_lumped_matches_analytic() {
    check_chain(Ends::FixedFree, Mass::Lumped, Shift::Zero, 0);
}

#[test]
fn chain_fixed_free_consistent_matches_analytic() {
    check_chain(Ends::FixedFree, Mass::Consistent, Shift::Zero, 0);
}

// ---------------------------------------------------------------------------------------
// 3. Free bodies: negative shift, singular stiffness
// ---------------------------------------------------------------------------------------

/// Free-free chain with [`Shift::Auto`]: one rigid mode with lambda ~ 0, the rest analytic.
fn check_free_free(mass: Mass, shift: Shift) {
    let sol = check_chain(Ends::FreeFree, mass, shift, 1);
    assert!(sol.shift < 0.0);
    let (k, m) = (2.0e7, 0.5);
    let (_, lambda_max) = chain_exact(2000, Ends::FreeFree, mass, k, m, 0);
    // A Rayleigh quotient of K is exact to eps ||K|| / ||M||-ish round-off: 16 eps lambda_max.
    let tol = 16.0 * EPS * lambda_max;
    assert!(
        sol.eigenvalues[0].abs() <= tol,
        "rigid mode lambda = {:.3e} > {tol:.3e}",
        sol.eigenvalues[0]
    );
    assert!(sol.eigenvalues[0].abs() <= 1e-9 * sol.eigenvalues[1]); // "tiny relative to lambda_2"
}

#[test]
fn chain_free_free_lumped_auto_shift() {
    check_free_free(Mass::Lumped, Shift::Auto);
}

#[test]
fn chain_free_free_consistent_auto_shift() {
    check_free_free(Mass::Consistent, Shift::Auto);
}

#[test]
fn chain_free_free_explicit_negative_shift() {
    // Below the first flexible eigenvalue (98.7 for the lumped chain), as Auto would pick.
    check_free_free(Mass::Lumped, Shift::Value(-1.0));
}

#[test]
fn chain_free_free_zero_shift_is_singular_stiffness() {
    let (K, M) = chain(2000, Ends::FreeFree, Mass::Lumped, 2.0e7, 0.5);
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(10, Shift::Zero)).unwrap_err();
    match &err {
        ReductionError::SingularStiffness { dof, pivot_ratio } => {
            assert!(*dof < 2000);
            // Exactly singular: the pivot is round-off (or the factorisation stopped, 0).
            assert!(*pivot_ratio <= reduction::eigen::SINGULAR_PIVOT_RATIO);
        }
        other => panic!("expected SingularStiffness, got {other:?}"),
    }
    assert!(
        err.to_string().contains("negative shift"),
        "the message suggests the fix: {err}"
    );
    // The same with the lower-level API.
    assert!(matches!(
        ShiftInvert::new(K.as_ref(), M.as_ref(), 0.0),
        Err(ReductionError::SingularStiffness { .. })
    ));
}

/// A free 3D lattice has six rigid-body modes (three translations, three rotations): all six
/// copies of the zero eigenvalue must be found, and they must span the rigid motions.
#[test]
fn lattice_free_six_rigid_modes() {
    let (nx, ny, nz) = (9, 8, 7);
    let (K, M) = lattice(nx, ny, nz, false);
    let sol = solve(&K, &M, &EigenSettings::new(12, Shift::Auto));
    let lambda_flex = sol.eigenvalues[6];
    // Rigid: Rayleigh quotients at round-off, eps * lambda_max, with lambda_max < 30 for the
    // lattice (Gershgorin: each row of K sums to < 25 in absolute value, M = I); factor 64 for
    // the length of the sums. Far below the first flexible eigenvalue.
    let tol = 64.0 * EPS * 30.0;
    for j in 0..6 {
        assert!(
            sol.eigenvalues[j].abs() <= tol,
            "mode {j}: lambda = {:.3e}",
            sol.eigenvalues[j]
        );
    }
    assert!(lambda_flex > 1e-3, "first flexible eigenvalue {lambda_flex:.3e}");
    // Span: each analytic rigid motion r (M-normalised) lies in span(Phi_rigid):
    // || r - Phi (Phi^T M r) ||_M = 0 up to the vector error of the modes.
    let n = K.nrows();
    let c = [(nx - 1) as f64 / 2.0, (ny - 1) as f64 / 2.0, (nz - 1) as f64 / 2.0];
    let Phi_r = sol.vectors.get(.., 0..6);
    for r_kind in 0..6 {
        let r = Mat::<f64>::from_fn(n, 1, |dof, _| {
            let (node, comp) = (dof / 3, dof % 3);
            let x = [
                (node % nx) as f64 - c[0],
                ((node / nx) % ny) as f64 - c[1],
                (node / (nx * ny)) as f64 - c[2],
            ];
            if r_kind < 3 {
                f64::from(u8::from(comp == r_kind))
            } else {
                // rotation about axis a: (e_a x x)_comp
                let a = r_kind - 3;
                let (b, d) = ((a + 1) % 3, (a + 2) % 3);
                if comp == d {
                    x[b]
                } else if comp == b {
                    -x[d]
                } else {
                    0.0
                }
            }
        });
        let r_M = (r.transpose() * (M.as_ref() * &r))[(0, 0)].sqrt();
        let r = r / r_M;
        let coef = Phi_r.transpose() * (M.as_ref() * &r);
        let rest = &r - Phi_r * &coef;
        let rest_M = (rest.transpose() * (M.as_ref() * &rest))[(0, 0)].abs().sqrt();
        // The rigid vectors carry flexible components of relative size ~ residual (<= 1e-8
        // against the shift, see `relative_residual`) times sqrt(|sigma| / lambda_flex).
        assert!(
            rest_M <= 1e-6,
            "rigid motion {r_kind} is {rest_M:.3e} outside the computed rigid modes"
        );
    }
    // The flexible modes are M-orthogonal to the rigid ones (round-off, n eps).
    let err = m_orthonormality_error(sol.vectors.as_ref(), M.as_ref());
    assert!(err <= n as f64 * EPS, "Phi^T M Phi - I = {err:.3e}");
}

// ---------------------------------------------------------------------------------------
// 2. Random sparse SPD pencil against a dense reference
// ---------------------------------------------------------------------------------------

#[test]
fn random_sparse_spd_matches_dense_reference() {
    let n = 300;
    let (K, M) = random_spd_pair(n, 7);
    let m = 12;
    let sol = solve(&K, &M, &EigenSettings::new(m, Shift::Zero));
    let (lambda_ref, Phi_ref) = dense_reference(K.as_ref(), M.as_ref());
    let lambda_max = lambda_ref[n - 1];
    for j in 0..m {
        let rel = (sol.eigenvalues[j] - lambda_ref[j]).abs() / lambda_ref[j];
        // Both are backward stable: errors of n eps lambda_max in absolute terms (the dense
        // reference is the weaker one), relative to lambda_j.
        let tol = n as f64 * EPS * lambda_max / lambda_ref[j];
        assert!(
            rel <= tol,
            "mode {j}: {:.16e} vs {:.16e}, rel {rel:.3e} > {tol:.3e}",
            sol.eigenvalues[j],
            lambda_ref[j]
        );
        // Subspace: |phi_ref^T M phi| = 1 for simple eigenvalues. The angle between the two
        // vectors is bounded by (errors ~ n eps lambda_max) / (gap to the nearest eigenvalue).
        let gap = (lambda_ref[j + 1] - lambda_ref[j]).min(if j > 0 {
            lambda_ref[j] - lambda_ref[j - 1]
        } else {
            f64::INFINITY
        });
        let cos = (Phi_ref.col(j).transpose() * (M.as_ref() * sol.vectors.col(j).as_mat()))[0].abs();
        let angle_tol = n as f64 * EPS * lambda_max / gap;
        assert!(
            1.0 - cos <= angle_tol * angle_tol + n as f64 * EPS,
            "mode {j}: 1 - |cos| = {:.3e}",
            1.0 - cos
        );
    }
    // Residuals as reported must be what they claim (sigma = 0, so the scale is
    // max(||K phi||, lambda ||M phi||)).
    for j in 0..m {
        let phi = sol.vectors.col(j).as_mat();
        let Kphi = K.as_ref() * phi;
        let Mphi = M.as_ref() * phi;
        let lambda = sol.eigenvalues[j];
        let r = (&Kphi - &Mphi * faer::Scale(lambda)).norm_l2() / Kphi.norm_l2().max(lambda * Mphi.norm_l2());
        // Both are round-off (~1e-14) computed in different orders; they differ by the
        // round-off floor of the residual, n eps lambda_max / lambda_j.
        let tol = n as f64 * EPS * lambda_max / lambda_ref[j];
        assert!(
            (r - sol.residuals[j]).abs() <= tol,
            "mode {j}: {r:.3e} vs {:.3e}",
            sol.residuals[j]
        );
    }
}

/// When the Krylov basis would not fit (n <= p + 1, here p = max(2m, m + 32) = 37 > n = 30),
/// the problem is solved densely through the same operator; same answer as the analytic one.
#[test]
fn small_problem_takes_the_dense_path() {
    let (n, k, m) = (30, 3.0, 2.0);
    let (K, M) = chain(n, Ends::FixedFree, Mass::Lumped, k, m);
    let sol = solve(&K, &M, &EigenSettings::new(5, Shift::Zero));
    for j in 0..5 {
        let (exact, lambda_max) = chain_exact(n, Ends::FixedFree, Mass::Lumped, k, m, j);
        // Dense eigendecomposition of C (backward stable: n eps mu_max, relative to mu_j, i.e.
        // n eps lambda_j / lambda_1), then the Rayleigh-Ritz step's round-off as in `check_chain`.
        let tol =
            n as f64 * EPS * (exact / chain_exact(n, Ends::FixedFree, Mass::Lumped, k, m, 0).0 + lambda_max / exact);
        assert!((sol.eigenvalues[j] - exact).abs() / exact <= tol, "mode {j}");
    }
}

// ---------------------------------------------------------------------------------------
// 4. 3D lattice, ~30k dofs; one factorisation for solves and modes
// ---------------------------------------------------------------------------------------

#[test]
fn lattice_3d_clamped_residuals_and_orthonormality() {
    // 21 x 22 x 22 nodes, the x = 0 face clamped: 3 * 20 * 22 * 22 = 29040 dofs. The square
    // cross-section gives double eigenvalues (bending in y and in z), which a single-vector
    // Krylov method must find from round-off.
    let (K, M) = lattice(21, 22, 22, true);
    let n = K.nrows();
    assert_eq!(n, 29040);
    let settings = EigenSettings::new(10, Shift::Zero);
    let factor = ShiftInvert::new(K.as_ref(), M.as_ref(), 0.0).expect("clamped lattice is SPD");
    let sol = factor.lowest_modes(K.as_ref(), M.as_ref(), &settings).expect("modes");
    // Residuals are checked inside against the tolerance (or the round-off floor, far below it
    // here: lambda_max / lambda_1 ~ 1e4); check that they are reported and small.
    for (j, r) in sol.residuals.iter().enumerate() {
        assert!(*r <= settings.tolerance, "mode {j}: residual {r:.3e}");
    }
    assert!(sol.eigenvalues.windows(2).all(|w| w[0] <= w[1]));
    // Both copies of the double eigenvalues (the first two bending pairs, modes 0-1 and 4-5):
    // equal to their round-off, n eps lambda_max / lambda (lambda_max < 30, as below).
    for (a, b) in [(0, 1), (4, 5)] {
        let (la, lb) = (sol.eigenvalues[a], sol.eigenvalues[b]);
        let tol = n as f64 * EPS * 30.0 / la;
        assert!(
            (lb - la).abs() / la <= tol,
            "modes {a}, {b}: {la:.16e} vs {lb:.16e} are not a double eigenvalue"
        );
    }
    // Rayleigh-Ritz makes Phi^T M Phi = I to round-off: dot products of length n, bounded by
    // n eps (Higham 2002, §3.1).
    let err = m_orthonormality_error(sol.vectors.as_ref(), M.as_ref());
    assert!(
        err <= n as f64 * EPS,
        "Phi^T M Phi - I = {err:.3e} > {:.3e}",
        n as f64 * EPS
    );
    // Phi^T K Phi = Lambda: off-diagonal round-off of n eps max|K| |phi|^2 ~ n eps lambda_max
    // (lambda_max <= 2 max K_ii/M_ii < 30 for the lattice).
    let KP = sol.vectors.transpose() * (K.as_ref() * &sol.vectors);
    for i in 0..10 {
        for j in 0..10 {
            let expected = if i == j { sol.eigenvalues[i] } else { 0.0 };
            assert!(
                (KP[(i, j)] - expected).abs() <= n as f64 * EPS * 30.0,
                "Phi^T K Phi ({i},{j})"
            );
        }
    }
    // Same answer from the one-call API (same start vector: identical up to round-off).
    let sol2 = solve(&K, &M, &settings);
    for j in 0..10 {
        assert!(
            (sol2.eigenvalues[j] - sol.eigenvalues[j]).abs() <= 1e-12 * sol.eigenvalues[j],
            "mode {j}"
        );
    }
    // The factor also solves: K x = b for two right-hand sides (the constraint-mode use).
    let b = Mat::<f64>::from_fn(n, 2, |i, j| ((i * (j + 3)) % 17) as f64 - 8.0);
    let mut x = b.clone();
    factor.solve_in_place(x.as_mut());
    let r = K.as_ref() * &x - &b;
    // Backward-stable Cholesky solve: ||r|| <= c n eps ||K|| ||x||, ||K|| < 30.
    let tol = n as f64 * EPS * 30.0 * x.norm_l2();
    assert!(r.norm_l2() <= tol, "||K x - b|| = {:.3e} > {tol:.3e}", r.norm_l2());
}

// ---------------------------------------------------------------------------------------
// Spectrum spread over many decades
// ---------------------------------------------------------------------------------------

/// A chain on a very soft mount: lambda_1 is 1e5 times below lambda_2. A Krylov tolerance in
/// absolute units of mu (as faer's) would be relative to mu_1 and far too loose for the other
/// modes; ours is relative to each Ritz value (module docs, "Tolerance").
#[test]
fn soft_mount_spread_spectrum_matches_dense_reference() {
    let n = 400;
    let (k, m) = (1.0, 1.0);
    let (K, M) = {
        let (K, M) = chain(n, Ends::FixedFree, Mass::Lumped, k, m);
        // Replace the wall spring k by 1e-7 k.
        let mut K = K.to_dense();
        K[(0, 0)] -= k * (1.0 - 1e-7);
        let t: Vec<_> = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .filter(|&(i, j)| K[(i, j)] != 0.0)
            .map(|(i, j)| (i, j, K[(i, j)]))
            .collect();
        (from_triplets(n, &t), M)
    };
    let sol = solve(&K, &M, &EigenSettings::new(8, Shift::Zero));
    let (lambda_ref, _) = dense_reference(K.as_ref(), M.as_ref());
    assert!(lambda_ref[1] / lambda_ref[0] > 1e4, "the fixture spreads the spectrum");
    for j in 0..8 {
        let rel = (sol.eigenvalues[j] - lambda_ref[j]).abs() / lambda_ref[j];
        // As in `random_sparse_spd_matches_dense_reference`: n eps lambda_max / lambda_j.
        let tol = n as f64 * EPS * lambda_ref[n - 1] / lambda_ref[j];
        assert!(rel <= tol, "mode {j}: rel {rel:.3e} > {tol:.3e}");
    }
}

// ---------------------------------------------------------------------------------------
// 5. Errors
// ---------------------------------------------------------------------------------------

fn small_chain() -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    chain(200, Ends::FixedFree, Mass::Lumped, 1.0, 1.0)
}

#[test]
fn error_zero_modes() {
    let (K, M) = small_chain();
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(0, Shift::Zero)).unwrap_err();
    assert_eq!(err, ReductionError::InvalidModeCount { requested: 0, n: 200 });
}

#[test]
fn error_too_many_modes() {
    let (K, M) = small_chain();
    for m in [200, 201] {
        let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(m, Shift::Zero)).unwrap_err();
        assert_eq!(err, ReductionError::InvalidModeCount { requested: m, n: 200 });
    }
}

#[test]
fn error_shape_mismatch() {
    let (K, _) = small_chain();
    let (_, M) = chain(199, Ends::FixedFree, Mass::Lumped, 1.0, 1.0);
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(5, Shift::Zero)).unwrap_err();
    assert!(
        matches!(
            err,
            ReductionError::DimensionMismatch {
                rows: 199,
                cols: 199,
                ..
            }
        ),
        "{err:?}"
    );
    // Non-square K.
    let K = SparseColMat::<usize, f64>::try_new_from_triplets(200, 199, &[Triplet::new(0, 0, 1.0)]).unwrap();
    let (_, M) = small_chain();
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(5, Shift::Zero)).unwrap_err();
    assert!(matches!(err, ReductionError::DimensionMismatch { .. }), "{err:?}");
    // A factor used with matrices of another size.
    let (K, M) = small_chain();
    let factor = ShiftInvert::new(K.as_ref(), M.as_ref(), 0.0).unwrap();
    let (K2, M2) = chain(150, Ends::FixedFree, Mass::Lumped, 1.0, 1.0);
    let err = factor
        .lowest_modes(K2.as_ref(), M2.as_ref(), &EigenSettings::new(5, Shift::Zero))
        .unwrap_err();
    assert!(matches!(err, ReductionError::DimensionMismatch { .. }), "{err:?}");
}

#[test]
fn error_mass_with_nonpositive_diagonal() {
    let (K, _) = small_chain();
    let t: Vec<_> = (0..200).map(|i| (i, i, if i == 57 { -1.0 } else { 1.0 })).collect();
    let M = from_triplets(200, &t);
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(5, Shift::Zero)).unwrap_err();
    assert!(
        matches!(err, ReductionError::MassNotPositiveDefinite { dof: Some(57), .. }),
        "{err:?}"
    );
    // Same with the automatic shift (which reads the diagonal first).
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(5, Shift::Auto)).unwrap_err();
    assert!(
        matches!(err, ReductionError::MassNotPositiveDefinite { dof: Some(57), .. }),
        "{err:?}"
    );
}

/// An indefinite M with a positive diagonal: the 2 x 2 block [1, -100; -100, 1] at dofs
/// (100, 101) is negative along e_100 + e_101, a smooth direction of small stiffness, so the
/// pencil has an eigenvalue near -k/(99 m), which shift-invert finds among the largest |mu|.
/// (An indefiniteness that only shows at high frequencies is not detected: module docs.)
#[test]
fn error_indefinite_mass_found_by_the_eigensolver() {
    let (K, _) = small_chain();
    let mut t: Vec<_> = (0..200).map(|i| (i, i, 1.0)).collect();
    t.extend([(100, 101, -100.0), (101, 100, -100.0)]);
    let M = from_triplets(200, &t);
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(10, Shift::Zero)).unwrap_err();
    assert!(
        matches!(err, ReductionError::MassNotPositiveDefinite { dof: None, .. }),
        "{err:?}"
    );
    // With a negative shift, K - sigma M itself is indefinite if |sigma| is large enough.
    let err = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(10, Shift::Value(-1.0))).unwrap_err();
    assert!(
        matches!(err, ReductionError::ShiftedNotPositiveDefinite { .. }),
        "{err:?}"
    );
}

#[test]
fn error_one_triangle_stored() {
    let (K, M) = small_chain();
    let Kd = K.to_dense();
    let t: Vec<_> = (0..200)
        .flat_map(|j| (j..200).map(move |i| (i, j)))
        .filter(|&(i, j)| Kd[(i, j)] != 0.0)
        .map(|(i, j)| (i, j, Kd[(i, j)]))
        .collect();
    let K_lower = from_triplets(200, &t);
    let err = lowest_modes(K_lower.as_ref(), M.as_ref(), &EigenSettings::new(5, Shift::Zero)).unwrap_err();
    assert!(
        matches!(err, ReductionError::NotSymmetric { matrix: "K", .. }),
        "{err:?}"
    );
}

#[test]
fn error_shift_above_lowest_eigenvalue() {
    let (K, M) = small_chain();
    let (lambda_1, _) = chain_exact(200, Ends::FixedFree, Mass::Lumped, 1.0, 1.0, 0);
    // Between lambda_1 and lambda_2: K - sigma M has exactly one negative eigenvalue.
    let err = lowest_modes(
        K.as_ref(),
        M.as_ref(),
        &EigenSettings::new(5, Shift::Value(2.0 * lambda_1)),
    )
    .unwrap_err();
    assert!(
        matches!(err, ReductionError::ShiftedNotPositiveDefinite { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("above the lowest eigenvalue"), "{err}");
}

#[test]
fn error_not_converged_reports_the_modes() {
    let (K, M) = small_chain();
    let mut settings = EigenSettings::new(5, Shift::Zero);
    // One cycle of a 6-vector Krylov space, no restart: far from 5 converged pairs.
    settings.krylov_dim = 6;
    settings.max_restarts = 0;
    let err = lowest_modes(K.as_ref(), M.as_ref(), &settings).unwrap_err();
    match err {
        ReductionError::EigenNotConverged {
            requested,
            converged,
            failed_modes,
            ..
        } => {
            assert_eq!(requested, 5);
            assert!(converged < 5);
            assert_eq!(failed_modes, (converged..5).collect::<Vec<_>>());
        }
        other => panic!("expected EigenNotConverged, got {other:?}"),
    }
}

#[test]
fn error_invalid_settings() {
    let (K, M) = small_chain();
    for tolerance in [0.0, -1.0, f64::NAN] {
        let mut settings = EigenSettings::new(5, Shift::Zero);
        settings.tolerance = tolerance;
        let err = lowest_modes(K.as_ref(), M.as_ref(), &settings).unwrap_err();
        assert!(matches!(err, ReductionError::InvalidSettings { .. }), "{err:?}");
    }
    let err = lowest_modes(
        K.as_ref(),
        M.as_ref(),
        &EigenSettings::new(5, Shift::Value(f64::INFINITY)),
    )
    .unwrap_err();
    assert!(matches!(err, ReductionError::InvalidSettings { .. }), "{err:?}");
}

/// Block Lanczos (`EigenSettings::block_size` > 1): the same eigenvalues as the dense
/// reference on the random pencil, and the six-fold zero eigenvalue of the free lattice, which
/// a block finds without relying on round-off to seed the copies.
#[test]
fn block_lanczos_matches_dense_reference_and_finds_repeated_eigenvalues() {
    let n = 300;
    let (K, M) = random_spd_pair(n, 7);
    let (lambda_ref, _) = dense_reference(K.as_ref(), M.as_ref());
    let lambda_max = lambda_ref[n - 1];
    for b in [2, 3, 4] {
        let settings = EigenSettings {
            block_size: b,
            ..EigenSettings::new(12, Shift::Zero)
        };
        let sol = solve(&K, &M, &settings);
        for j in 0..12 {
            let rel = (sol.eigenvalues[j] - lambda_ref[j]).abs() / lambda_ref[j];
            // As in `random_sparse_spd_matches_dense_reference`: n eps lambda_max absolute.
            let tol = n as f64 * EPS * lambda_max / lambda_ref[j];
            assert!(rel <= tol, "b = {b}, mode {j}: rel {rel:.3e} > {tol:.3e}");
            assert!(sol.residuals[j] <= 1e-8, "b = {b}, mode {j}: residual {:.2e}", sol.residuals[j]);
        }
    }
    let (K, M) = lattice(9, 8, 7, false);
    let settings = EigenSettings {
        block_size: 4,
        ..EigenSettings::new(12, Shift::Auto)
    };
    let sol = solve(&K, &M, &settings);
    // Tolerances of `lattice_free_six_rigid_modes`.
    for j in 0..6 {
        assert!(sol.eigenvalues[j].abs() <= 64.0 * EPS * 30.0, "mode {j}: {:.3e}", sol.eigenvalues[j]);
    }
    assert!(sol.eigenvalues[6] > 1e-3, "first flexible eigenvalue {:.3e}", sol.eigenvalues[6]);
}

/// Exactly repeated eigenvalues at the top of the wanted range, where a single-vector Krylov
/// method depends on round-off to find the second copy and round-off does not: a diagonal
/// pencil (each operator application scales the components of a pair by the same factor, so
/// the Krylov space never leaves the start vector's combination of the pair). This happened on
/// the 10k-dof Craig-Bampton block of `benches/craig_bampton.rs` (square section: pairs of
/// bending modes), whose reduction kept 2316 and 2353 Hz instead of the second copies of 2199
/// and 2269 Hz. Blocks of 2, the automatic choice below `BLOCK_MIN_DOFS`, find pairs.
#[test]
fn pairs_at_the_top_of_the_wanted_range_are_found() {
    let n = 3000;
    // 1, 2, ..., 7, 8, 8, 9, 9, 10, ...: the lowest 10 are 1..=7, 8, 8, 9.
    let lambda = |i: usize| match i {
        0..=7 => (i + 1) as f64,
        8 => 8.0,
        9 | 10 => 9.0,
        _ => (i - 1) as f64,
    };
    let K = from_triplets(n, &(0..n).map(|i| (i, i, lambda(i))).collect::<Vec<_>>());
    let M = from_triplets(n, &(0..n).map(|i| (i, i, 1.0)).collect::<Vec<_>>());
    let expected = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 8.0, 9.0];
    let run = |b: usize| {
        let settings = EigenSettings {
            block_size: b,
            ..EigenSettings::new(10, Shift::Zero)
        };
        solve(&K, &M, &settings).eigenvalues
    };
    // The problem is discriminating: single vectors miss a copy (the residuals are all fine).
    let single = run(1);
    assert!(
        single.iter().zip(&expected).any(|(a, b)| (a - b).abs() > 1e-6),
        "single vectors found every copy: {single:?}"
    );
    // A Ritz value's error is about the square of its residual (1e-8 requested): 1e-9
    // relative is loose for a found copy and tight against a missed one (off by 1 or more).
    for b in [0, 2, 4] {
        let got = run(b);
        for (j, (a, e)) in got.iter().zip(&expected).enumerate() {
            assert!((a - e).abs() <= 1e-9 * e, "block size {b}, mode {j}: {a} instead of {e} ({got:?})");
        }
    }
}

// ---------------------------------------------------------------------------------------
// 6. A clamped beam with many modes (a dense eigensolver that was not scale-invariant)
// ---------------------------------------------------------------------------------------

/// $\mathbf K$, $\mathbf M$ of a clamped-clamped Euler-Bernoulli beam of `elements` elements
/// (aluminium, 50 x 30 mm, 1.02 m on a skew axis, consistent mass): $n = 6(elements - 1)$.
/// In SI units $\lambda_1 \approx 9\cdot 10^5$, so $\|\mathbf C\| = 1/\lambda_1 \approx
/// 10^{-6}$, and the torsion and axial dofs put $\lambda_{max}$ near $3\cdot 10^{12}$ (60
/// elements) to $3\cdot 10^{13}$ (200).
fn clamped_beam(elements: usize) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    use fe_model::{assemble, BeamProperties, BeamSection, BeamTheory, DofMap, DofMask, FeModel};
    use fe_model::{IsotropicMaterial, MassKind, SystemPattern};
    use nalgebra::{Point3, Vector3};
    let mut model = FeModel::default();
    let (a, b) = (Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.2, 0.1));
    let orientation = (b - a).cross(&Vector3::new(0.3, 0.9, -0.2)).normalize();
    let material = model.add_material(IsotropicMaterial::new("al", 70e9, 0.33, 2700.0).expect("material"));
    let section = model.add_section(BeamSection::rectangle("rect", 0.05, 0.03, 0.33).expect("section"));
    let props = BeamProperties {
        section,
        material,
        orientation,
        theory: BeamTheory::EulerBernoulli,
        mass: MassKind::Consistent,
    };
    let nodes = fe_model::generate::straight_beam(&mut model, a, b, elements, &props, Some("beam")).expect("beam");
    model.add_support(nodes[0], DofMask::ALL);
    model.add_support(nodes[elements], DofMask::ALL);
    let dofs = DofMap::new(&model).expect("dofs");
    let matrices = assemble(&model, &SystemPattern::new(&model, &dofs)).expect("assembly");
    (matrices.K, matrices.M)
}

/// A clamped beam with 100 of 354 modes (and 100 of 1194) against the dense reference, for
/// several block sizes and the dense path. Used to fail: 97 of 100 pairs passed the residual
/// check at 60 elements (2.7e-6 > 1e-8) and 35-47 at 200 elements, whatever the restarts or
/// block size. faer's divide-and-conquer EVD (from dimension 128, so not with the 60 modes
/// users asked before) deflated with an absolute tolerance on the Lanczos matrix of norm
/// $10^{-6}$, so the Ritz vectors were wrong by $\varepsilon$ absolute while the Krylov
/// estimates said converged (`reduction::eigen`, `scaled_self_adjoint_eigen`).
#[test]
fn clamped_beam_with_many_modes_matches_dense_reference() {
    for (elements, m, b) in [(60, 100, 0), (60, 100, 1), (60, 100, 4), (60, 200, 0), (200, 100, 0)] {
        let (K, M) = clamped_beam(elements);
        let n = K.nrows();
        let settings = EigenSettings {
            block_size: b,
            ..EigenSettings::new(m, Shift::Zero)
        };
        // (60, 200): p = 2m = 400 > n, the dense path through the same operator.
        let sol = lowest_modes(K.as_ref(), M.as_ref(), &settings)
            .unwrap_or_else(|e| panic!("{elements} elements, {m} modes, b = {b}: {e}"));
        let (lambda_ref, _) = dense_reference(K.as_ref(), M.as_ref());
        let lambda_max = lambda_ref[n - 1];
        for j in 0..m {
            let rel = (sol.eigenvalues[j] - lambda_ref[j]).abs() / lambda_ref[j];
            // As in `random_sparse_spd_matches_dense_reference`: n eps lambda_max absolute.
            let tol = n as f64 * EPS * lambda_max / lambda_ref[j];
            assert!(rel <= tol, "{elements} elements, b = {b}, mode {j}: rel {rel:.3e} > {tol:.3e}");
            // The reported residual meets the tolerance or its own round-off floor (module
            // docs, "Tolerance"): recomputed here, so the claim is checked, not trusted.
            let phi = sol.vectors.col(j);
            let (Kphi, Mphi) = (K.as_ref() * phi.as_mat(), M.as_ref() * phi.as_mat());
            let lambda = sol.eigenvalues[j];
            let r = reduction::eigen::relative_residual(Kphi.col(0), Mphi.col(0), lambda, 0.0);
            let floor =
                reduction::eigen::residual_floor(K.as_ref(), M.as_ref(), phi, Kphi.col(0), Mphi.col(0), lambda, 0.0);
            assert!(
                r <= settings.tolerance.max(floor),
                "{elements} elements, b = {b}, mode {j}: residual {r:.3e} (floor {floor:.3e})"
            );
        }
        // M-orthonormal to round-off (n eps, as the chains).
        let err = m_orthonormality_error(sol.vectors.as_ref(), M.as_ref());
        assert!(err <= n as f64 * EPS, "{elements} elements, b = {b}: Phi^T M Phi - I = {err:.3e}");
    }
}

// ---------------------------------------------------------------------------------------
// Single-precision factor: refined solves and the M-inner-product Lanczos
// ---------------------------------------------------------------------------------------

/// `ShiftInvert::with_settings` with `precision`, AMD ordering, no reserve.
fn factor_with(
    K: &SparseColMat<usize, f64>,
    M: &SparseColMat<usize, f64>,
    sigma: f64,
    precision: FactorPrecision,
) -> Result<ShiftInvert, ReductionError> {
    ShiftInvert::with_settings(
        K.as_ref(),
        M.as_ref(),
        sigma,
        None,
        fe_model::FillOrdering::Amd,
        &FactorSettings {
            precision,
            reserve_bytes: 0,
            single_reserve_bytes: 0,
        },
    )
}

/// The clamped and the free 3D lattice (1.5k dofs; the free one with the negative shift
/// $\sigma = -10^{-4}$, so that the refinement's residual takes $\mathbf K - \sigma\mathbf M$
/// from both matrices, and six rigid modes; $\kappa(\mathbf K - \sigma\mathbf M) \approx
/// 30/10^{-4}$, fine for f32, where [`Shift::Auto`]'s $10^8$ is not: see
/// `single_precision_refinement_fails_by_name_on_an_ill_conditioned_matrix`) and a chain small enough for the dense path: the single-precision factor gives
/// the double-precision eigenvalues to 1e-10, M-orthonormal modes, and refines every
/// application in a few solves.
#[test]
fn single_precision_factor_gives_the_double_precision_modes() {
    for clamped in [true, false] {
        let (K, M) = lattice(9, 8, 7, clamped);
        // The first flexible eigenvalue of the free lattice is above 1e-3.
        let settings = EigenSettings::new(12, if clamped { Shift::Zero } else { Shift::Value(-1e-4) });
        let sigma = settings.shift.resolve(K.as_ref(), M.as_ref()).unwrap();
        let double = factor_with(&K, &M, sigma, FactorPrecision::Double)
            .unwrap()
            .lowest_modes(K.as_ref(), M.as_ref(), &settings)
            .unwrap();
        let factor = factor_with(&K, &M, sigma, FactorPrecision::Single).unwrap();
        assert_eq!(factor.precision(), fe_model::Precision::Single);
        let single = factor.lowest_modes(K.as_ref(), M.as_ref(), &settings).unwrap();
        let rigid = if clamped { 0 } else { 6 };
        for j in 0..12 {
            let (a, b) = (double.eigenvalues[j], single.eigenvalues[j]);
            if j < rigid {
                // Rigid modes: both at round-off, eps lambda_max (lambda_max < 30; factor 64 for
                // the sums, as in lattice_free_six_rigid_modes).
                assert!(
                    a.abs() <= 64.0 * EPS * 30.0 && b.abs() <= 64.0 * EPS * 30.0,
                    "clamped {clamped}, rigid mode {j}: double {a:.3e}, single {b:.3e}"
                );
            } else {
                // Both are Rayleigh quotients of vectors with residuals below 1e-8: their
                // errors are of the order of the squared residual (1e-16) plus round-off;
                // 1e-10 is the agreement asked of any change to the reduction.
                assert!((a - b).abs() <= 1e-10 * a, "clamped {clamped}, mode {j}: double {a}, single {b}");
            }
        }
        // Phi^T M Phi = I from the Rayleigh-Ritz step, as in double precision.
        let err = m_orthonormality_error(single.vectors.as_ref(), M.as_ref());
        assert!(err <= 1e-12, "clamped {clamped}: M-orthonormality {err:.2e}");
        // Refinement ran (more solves than applications), and converged fast: the lattice's
        // condition number is about 1e3, so each f32 solve gains about 4 digits and 3 to 4
        // solves reach the double-precision backward error; 5 leaves a margin.
        assert!(
            single.factor_solves > single.operator_applications
                && single.factor_solves <= 5 * single.operator_applications,
            "clamped {clamped}: {} solves for {} applications",
            single.factor_solves,
            single.operator_applications
        );
        assert_eq!(double.factor_solves, double.operator_applications);
    }
    // The dense path (n <= p + 1) with a single-precision factor: the analytic chain.
    let (K, M) = chain(30, Ends::FixedFree, Mass::Lumped, 1.0, 1.0);
    let sol = factor_with(&K, &M, 0.0, FactorPrecision::Single)
        .unwrap()
        .lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(3, Shift::Zero))
        .unwrap();
    for j in 0..3 {
        let (lambda, _) = chain_exact(30, Ends::FixedFree, Mass::Lumped, 1.0, 1.0, j);
        // Rayleigh quotients with residuals below 1e-8, against the closed form: round-off.
        assert!((sol.eigenvalues[j] - lambda).abs() <= 1e-12 * lambda, "dense path, mode {j}");
    }
}

/// A refined solve reaches the double-precision backward error, and agrees with the double
/// solve to the condition number times it.
#[test]
fn refined_solve_reaches_double_precision_accuracy() {
    let (K, M) = lattice(9, 8, 7, true);
    let n = K.nrows();
    let B = Mat::<f64>::from_fn(n, 3, |i, j| ((i * (j + 3)) % 101) as f64 / 50.0 - 1.0);
    let mut X_d = B.clone();
    factor_with(&K, &M, 0.0, FactorPrecision::Double).unwrap().solve_in_place(X_d.as_mut());
    let single = factor_with(&K, &M, 0.0, FactorPrecision::Single).unwrap();
    let mut X_s = B.clone();
    let steps = single
        .solve_refined(K.as_ref(), M.as_ref(), X_s.as_mut(), &|| "test".into())
        .unwrap();
    assert!((2..=5).contains(&steps), "{steps} solves");
    let K_norm = (0..n)
        .map(|j| K.as_ref().col_range(j).map(|p| K.val()[p].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let max_col = (0..n).map(|j| K.as_ref().col_range(j).len()).max().unwrap();
    let target = (n as f64).sqrt().max(max_col as f64 + 2.0) * EPS;
    let R = &B - &K * &X_s;
    for j in 0..3 {
        let eta = R.col(j).norm_max() / (K_norm * X_s.col(j).norm_max() + B.col(j).norm_max());
        assert!(eta <= target, "column {j}: backward error {eta:.2e} > {target:.2e}");
    }
    // Both solutions are within kappa * eta of the exact one; kappa(K) of the clamped lattice
    // is about 1e3 (lambda_max / lambda_min with M = I), eta at most 80 eps: 1e-11 bounds it.
    let diff = (&X_s - &X_d).norm_max() / X_d.norm_max();
    assert!(diff <= 1e-11, "refined against double solve: {diff:.2e}");
}

/// The free lattice shifted by [`Shift::Auto`] ($\sigma = -10^{-8}$ times the median
/// $K_{ii}/M_{ii}$): $\kappa(\mathbf K - \sigma\mathbf M) \approx 10^8$, so
/// $\kappa\,\varepsilon_{32} \approx 10$. The f32 factor exists, but refinement stalls (a
/// correction does not halve the backward error). The solve and the Lanczos say so, naming
/// what was solved, the column and the step, instead of returning a wrong answer.
#[test]
fn single_precision_refinement_fails_by_name_on_an_ill_conditioned_matrix() {
    let (K, M) = lattice(9, 8, 7, false);
    let sigma = Shift::Auto.resolve(K.as_ref(), M.as_ref()).unwrap();
    let factor = factor_with(&K, &M, sigma, FactorPrecision::Single).expect("the f32 pivots stay positive");
    let mut x = Mat::<f64>::from_fn(K.nrows(), 2, |i, j| 1.0 + ((i + j) % 3) as f64);
    let err = factor
        .solve_refined(K.as_ref(), M.as_ref(), x.as_mut(), &|| "the test load".into())
        .unwrap_err();
    match &err {
        ReductionError::RefinementFailed {
            what,
            steps,
            backward_error,
            target,
            ..
        } => {
            assert_eq!(what, "the test load");
            assert!(*steps >= 2 && backward_error > target, "{err}");
        }
        other => panic!("expected RefinementFailed, got {other}"),
    }
    assert!(err.to_string().contains("factor = \"double\""), "{err}");
    let err = factor
        .lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(12, Shift::Auto))
        .unwrap_err();
    assert!(
        matches!(&err, ReductionError::RefinementFailed { what, .. } if what.contains("Lanczos")),
        "{err}"
    );
}

/// Two masses joined by a spring $10^9$ times stiffer than their springs to the wall: in f32
/// $10^9 + 1$ rounds to $10^9$ and the second pivot cancels. The single-precision factor is
/// refused with the dof and the pivot ratio; the double-precision one is fine.
#[test]
fn single_precision_pivot_breakdown_is_located() {
    let s = 1e9;
    let K = from_triplets(2, &[(0, 0, 1.0 + s), (1, 1, 1.0 + s), (0, 1, -s), (1, 0, -s)]);
    let M = from_triplets(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
    let err = factor_with(&K, &M, 0.0, FactorPrecision::Single).unwrap_err();
    match &err {
        ReductionError::SinglePrecisionBreakdown { at, pivot_ratio, .. } => {
            assert!(at == "dof 0" || at == "dof 1", "{at}");
            assert!(*pivot_ratio <= reduction::eigen::SINGLE_PIVOT_RATIO, "{pivot_ratio}");
        }
        other => panic!("expected SinglePrecisionBreakdown, got {other}"),
    }
    assert!(err.to_string().contains("factor = \"double\""), "{err}");
    factor_with(&K, &M, 0.0, FactorPrecision::Double).expect("pivot ratio 2e-9: fine in double precision");
}

/// A factor that does not fit in the available memory (here: a reserve larger than any
/// machine's memory) is refused before any value is computed, in the precision the setting
/// allows, with the sizes in GB; without the reserve `Auto` takes double precision for a small
/// matrix.
#[test]
fn factor_that_does_not_fit_is_refused_with_its_size() {
    if fe_model::available_memory().is_none() {
        return; // not Linux: nothing is refused
    }
    let (K, M) = lattice(5, 5, 5, true);
    let refused = |settings: FactorSettings| {
        ShiftInvert::with_settings(
            K.as_ref(),
            M.as_ref(),
            0.0,
            None,
            fe_model::FillOrdering::Amd,
            &settings,
        )
        .unwrap_err()
    };
    for (precision, named) in [
        (FactorPrecision::Auto, "single"),
        (FactorPrecision::Double, "double"),
        (FactorPrecision::Single, "single"),
    ] {
        let err = refused(FactorSettings {
            precision,
            reserve_bytes: usize::MAX / 4,
            single_reserve_bytes: usize::MAX / 4,
        });
        match &err {
            ReductionError::FactorDoesNotFit {
                precision: p,
                needed_gb,
                available_gb,
                ..
            } => {
                assert_eq!(*p, named, "{precision:?}");
                assert!(needed_gb > available_gb, "{err}");
            }
            other => panic!("{precision:?}: expected FactorDoesNotFit, got {other}"),
        }
    }
    // The workspace of the factorisation is freed before the caller's vectors are allocated:
    // with a reserve larger than the workspace, the peak is the factor plus the reserve, the
    // workspace not added.
    let reserve = 2 * fe_model::available_memory().unwrap() as usize;
    let err = refused(FactorSettings {
        precision: FactorPrecision::Double,
        reserve_bytes: reserve,
        single_reserve_bytes: 0,
    });
    match &err {
        ReductionError::FactorDoesNotFit {
            factor_gb, needed_gb, ..
        } => {
            // The GB figures carry f64 round-off (1e-16 relative); the workspace of this
            // 1.5k-dof factor (kB, 1e-8 of a reserve of tens of GB) would show above 1e-9.
            let expected = factor_gb + reserve as f64 / 1e9;
            assert!((needed_gb - expected).abs() < 1e-9 * expected, "{err}: expected {expected} GB");
        }
        other => panic!("expected FactorDoesNotFit, got {other}"),
    }
    let auto = factor_with(&K, &M, 0.0, FactorPrecision::Auto).unwrap();
    assert_eq!(auto.precision(), fe_model::Precision::Double);
}
