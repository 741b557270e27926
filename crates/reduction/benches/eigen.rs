//! Sparse eigensolver timings on a clamped hex8 block (theory guide §3).
//!
//! `cargo bench -p reduction --bench eigen` runs the ~50k- and ~200k-dof problems (select with
//! `REDUCTION_BENCH_SIZES=50k,200k`); `cargo test --benches` runs a ~3k-dof smoke problem so
//! that CI executes the code once. Timings are printed, never asserted.
//!
//! The matrices: a block of `ex x ey x ez` trilinear hex8 elements (linear isotropic
//! elasticity, 2x2x2 Gauss, consistent mass) on a uniform grid, clamped on the face x = 0.
//! The element matrices are computed here, inline, because `fe-model`'s solid elements do not
//! exist yet; all elements of a uniform grid share one 24 x 24 pair, assembled straight into
//! the 27-point CSC pattern. Replace with `fe-model`'s Hex8 once it exists.
//!
//! If `REDUCTION_BENCH_MTX_DIR` is set, `K_<n>.mtx`, `M_<n>.mtx` (Matrix Market, coordinate
//! real symmetric, lower triangle) and `eigenvalues_<n>.txt` are written there for
//! `benches/scipy_eigsh.py`, which times scipy's `eigsh(K, M=M, sigma=0, k=20)` on the same
//! matrices. `REDUCTION_ORDERING=amd|nd|auto` chooses the fill-reducing ordering (`auto`, the
//! default: nested dissection on the grid's node positions from `fe_model::ordering::ND_MIN_DOFS` dofs).
//!
//! Experiments: `REDUCTION_BENCH_BLOCK`, `REDUCTION_BENCH_KRYLOV_DIM`, `REDUCTION_BENCH_TOL` set
//! `EigenSettings::block_size`, `krylov_dim`, `tolerance`; `REDUCTION_BENCH_SOLVE_RHS=1,2,4,8`
//! also times one solve with each number of right-hand sides; `REDUCTION_BENCH_SOLVE_ONLY=1,8`
//! times only the solves, with the parallel subtree solves and then with faer's sequential
//! supernodal solves, and skips the eigensolver.

#![allow(non_snake_case)]

use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use fe_model::FillOrdering;
use reduction::eigen::{EigenSettings, FactorSettings, Shift, ShiftInvert};
use std::io::Write;
use std::time::Instant;

/// Young's modulus (Pa), Poisson ratio, density (kg/m^3), element size (m): steel, 10 mm.
const E: f64 = 210e9;
const NU: f64 = 0.3;
const RHO: f64 = 7850.0;
const H: f64 = 0.01;
const N_MODES: usize = 20;

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let sizes: Vec<String> = match std::env::var("REDUCTION_BENCH_SIZES") {
        Ok(s) => s.split(',').map(|x| x.trim().to_string()).collect(),
        Err(_) if full => vec!["50k".into(), "200k".into()],
        Err(_) => vec!["3k".into()],
    };
    println!("reduction/benches/eigen: clamped hex8 block (hex8 element written inline in the bench, see file docs)");
    println!(
        "threads: faer {:?}, rayon {}; load average at start: {}",
        faer::get_global_parallelism(),
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    for size in sizes {
        // Elements (ex, ey, ez); nodes at x = 0 clamped, so dofs = 3 ex (ey+1) (ez+1).
        let (ex, ey, ez) = match size.as_str() {
            "3k" => (10, 9, 9),
            "50k" => (26, 24, 24),
            "200k" => (41, 39, 39),
            other => panic!("unknown size {other} (3k, 50k, 200k)"),
        };
        run(ex, ey, ez);
    }
}

fn run(ex: usize, ey: usize, ez: usize) {
    let t = Instant::now();
    let (K, M) = assemble_block(ex, ey, ez);
    let n = K.nrows();
    println!(
        "\n== {ex} x {ey} x {ez} hex8 elements, n = {n} dofs, nnz(K) = {} (assembly {:.0} ms)",
        K.val().len(),
        ms(t)
    );
    if let Ok(dir) = std::env::var("REDUCTION_BENCH_MTX_DIR") {
        let t = Instant::now();
        std::fs::create_dir_all(&dir).expect("create REDUCTION_BENCH_MTX_DIR");
        write_mtx(&format!("{dir}/K_{n}.mtx"), K.as_ref());
        write_mtx(&format!("{dir}/M_{n}.mtx"), M.as_ref());
        println!("wrote {dir}/K_{n}.mtx, M_{n}.mtx ({:.0} ms)", ms(t));
    }

    let t_total = Instant::now();
    let cpu_total = cpu_ms();
    let t = Instant::now();
    let cpu = cpu_ms();
    // Node of dof d: (i - 1, j, k) from d / 3 in the numbering of `assemble_block`; unit spacing.
    let points: Vec<[f64; 3]> = (0..n)
        .map(|d| {
            let q = d / 3;
            [
                (q % ex + 1) as f64,
                ((q / ex) % (ey + 1)) as f64,
                (q / (ex * (ey + 1))) as f64,
            ]
        })
        .collect();
    let ordering = match std::env::var("REDUCTION_ORDERING").as_deref() {
        Ok("amd") => FillOrdering::Amd,
        Ok("nd") => FillOrdering::NestedDissection,
        _ => FillOrdering::Auto,
    };
    let factor = ShiftInvert::with_settings(
        K.as_ref(),
        M.as_ref(),
        0.0,
        Some(&points),
        ordering,
        &FactorSettings::DOUBLE,
    )
    .expect("factorisation");
    println!("ordering: {:?} (REDUCTION_ORDERING=amd|nd|auto)", factor.ordering());
    let (subtrees, top) = factor.parallel_subtrees();
    println!(
        "triangular solves: {subtrees} subtrees in parallel, {:.1} % of the factor above them",
        100.0 * top
    );
    let t_factor = ms(t);
    let cpu_factor = cpu_ms() - cpu;
    if let Ok(list) = std::env::var("REDUCTION_BENCH_SOLVE_ONLY") {
        solve_timings(&factor, &list);
        faer::set_global_parallelism(faer::Par::Seq);
        println!("with faer's sequential supernodal solves (Par::Seq):");
        solve_timings(&factor, &list);
        faer::set_global_parallelism(faer::Par::rayon(0));
        return;
    }
    let t = Instant::now();
    let cpu = cpu_ms();
    // Experiment knobs (unset: the defaults of `EigenSettings::new`).
    let knob = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<f64>().ok());
    let mut settings = EigenSettings::new(N_MODES, Shift::Zero);
    if let Some(p) = knob("REDUCTION_BENCH_KRYLOV_DIM") {
        settings.krylov_dim = p as usize;
    }
    if let Some(b) = knob("REDUCTION_BENCH_BLOCK") {
        settings.block_size = b as usize;
    }
    if let Some(tol) = knob("REDUCTION_BENCH_TOL") {
        settings.tolerance = tol;
    }
    println!(
        "settings: krylov_dim {} (0 = automatic), block {}, tolerance {:.0e}",
        settings.krylov_dim, settings.block_size, settings.tolerance
    );
    let sol = factor
        .lowest_modes(K.as_ref(), M.as_ref(), &settings)
        .expect("eigensolver");
    let t_eig = ms(t);
    let cpu_eig = cpu_ms() - cpu;
    let t_total = ms(t_total);
    let cpu_total = cpu_ms() - cpu_total;
    let worst = sol.residuals.iter().cloned().fold(0.0, f64::max);
    let f: Vec<String> = sol
        .eigenvalues
        .iter()
        .map(|l| format!("{:.2}", l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)))
        .collect();
    println!(
        "factor values: {} ({:.0} MB)",
        factor.factor_len(),
        factor.factor_len() as f64 * 8e-6
    );
    println!("                                     wall (ms)   CPU user+sys (ms)");
    println!("factorisation (symbolic + numeric): {t_factor:>10.0} {cpu_factor:>10.0}");
    println!("Lanczos + Rayleigh-Ritz, {N_MODES} modes:   {t_eig:>10.0} {cpu_eig:>10.0}");
    println!("total:                              {t_total:>10.0} {cpu_total:>10.0}");
    println!("peak RSS (VmHWM, whole process):     {:>10.0} MiB", peak_rss_mib());
    println!("operator applications (L^-T, M, L^-1): {}", sol.operator_applications);
    println!("worst relative residual: {worst:.2e}");
    println!("frequencies (Hz): {}", f.join(" "));
    let r: Vec<String> = sol.residuals.iter().map(|r| format!("{r:.1e}")).collect();
    println!("relative residuals: {}", r.join(" "));
    if let Ok(list) = std::env::var("REDUCTION_BENCH_SOLVE_RHS") {
        solve_timings(&factor, &list);
    }
    if let Ok(dir) = std::env::var("REDUCTION_BENCH_MTX_DIR") {
        let mut file = std::fs::File::create(format!("{dir}/eigenvalues_{n}.txt")).unwrap();
        for l in &sol.eigenvalues {
            writeln!(file, "{l:.17e}").unwrap();
        }
    }
}

/// Time of one solve $(\mathbf K - \sigma\mathbf M)\mathbf X = \mathbf B$ (forward and backward
/// triangular solves, the cost of one operator application) with `k` right-hand sides, for
/// each `k` of the comma-separated `list`: does a block read the factor once for its `k`
/// vectors? Three repetitions, the fastest (wall) and its CPU time.
fn solve_timings(factor: &ShiftInvert, list: &str) {
    let n = factor.nrows();
    for k in list.split(',').filter_map(|x| x.trim().parse::<usize>().ok()) {
        let mut best = (f64::INFINITY, 0.0);
        for _ in 0..3 {
            let mut X = faer::Mat::<f64>::from_fn(n, k, |i, j| ((i * 31 + j * 17) % 97) as f64 - 48.0);
            let (t, cpu) = (Instant::now(), cpu_ms());
            factor.solve_in_place(X.as_mut());
            let (t, cpu) = (ms(t), cpu_ms() - cpu);
            if t < best.0 {
                best = (t, cpu);
            }
        }
        println!(
            "solve with {k:>2} right-hand sides: {:>8.1} ms wall, {:>8.1} ms CPU, {:>7.1} ms wall per vector",
            best.0,
            best.1,
            best.0 / k as f64
        );
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// User + system CPU time of this process (Linux `/proc/self/stat`, clock ticks of 10 ms), 0
/// elsewhere: on a shared machine it is less noisy than wall time.
fn cpu_ms() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the command name (which is in parentheses): utime is field 14, stime 15.
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) * 10.0)
        })
        .unwrap_or(0.0)
}

/// Peak resident set size of this process (Linux `/proc/self/status`), 0 elsewhere.
fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|kb| kb.parse::<f64>().ok()))
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(0.0)
}

/// Stiffness and consistent mass of a cubic hex8 element of side `H` (2x2x2 Gauss, exact
/// for both on a parallelepiped). Local node `a` sits at corner
/// `(a & 1, (a >> 1) & 1, (a >> 2) & 1)`; dofs `3 a + c`.
fn hex8_matrices() -> ([[f64; 24]; 24], [[f64; 24]; 24]) {
    let lam = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU));
    let mu = E / (2.0 * (1.0 + NU));
    let g = 1.0 / 3f64.sqrt();
    let det_j = (H / 2.0).powi(3);
    let mut Ke = [[0.0; 24]; 24];
    let mut Me = [[0.0; 24]; 24];
    let sign = |a: usize, d: usize| if (a >> d) & 1 == 1 { 1.0 } else { -1.0 };
    for gp in 0..8 {
        let xi = [sign(gp, 0) * g, sign(gp, 1) * g, sign(gp, 2) * g];
        let mut N = [0.0; 8];
        let mut dN = [[0.0; 3]; 8]; // d N_a / d x_d
        for a in 0..8 {
            let s = [sign(a, 0), sign(a, 1), sign(a, 2)];
            let f = [
                (1.0 + s[0] * xi[0]) / 2.0,
                (1.0 + s[1] * xi[1]) / 2.0,
                (1.0 + s[2] * xi[2]) / 2.0,
            ];
            N[a] = f[0] * f[1] * f[2];
            // dxi/dx = 2/H
            dN[a][0] = s[0] / 2.0 * f[1] * f[2] * 2.0 / H;
            dN[a][1] = f[0] * s[1] / 2.0 * f[2] * 2.0 / H;
            dN[a][2] = f[0] * f[1] * s[2] / 2.0 * 2.0 / H;
        }
        // K_e[(a,c),(b,d)] = lam dNa_c dNb_d + mu (dNa_d dNb_c + delta_cd sum_k dNa_k dNb_k)
        for a in 0..8 {
            for b in 0..8 {
                let dot: f64 = (0..3).map(|k| dN[a][k] * dN[b][k]).sum();
                for c in 0..3 {
                    for d in 0..3 {
                        let mut v = lam * dN[a][c] * dN[b][d] + mu * dN[a][d] * dN[b][c];
                        if c == d {
                            v += mu * dot;
                            Me[3 * a + c][3 * b + d] += RHO * N[a] * N[b] * det_j;
                        }
                        Ke[3 * a + c][3 * b + d] += v * det_j;
                    }
                }
            }
        }
    }
    (Ke, Me)
}

/// K and M of the clamped block, assembled directly in the 27-point CSC pattern (both
/// triangles, sorted rows).
fn assemble_block(ex: usize, ey: usize, ez: usize) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let (Ke, Me) = hex8_matrices();
    let (nx, ny, nz) = (ex + 1, ey + 1, ez + 1);
    // Node (i, j, k), i >= 1 free; dof of free node = 3 * ((i-1) + ex (j + ny k)) + c.
    let node_dof =
        |i: usize, j: usize, k: usize| -> Option<usize> { (i >= 1).then(|| 3 * ((i - 1) + ex * (j + ny * k))) };
    let n = 3 * ex * ny * nz;
    let mut col_ptr = vec![0usize];
    let mut row_idx = Vec::new();
    let (mut kv, mut mv) = (Vec::new(), Vec::new());
    for k in 0..nz {
        for j in 0..ny {
            for i in 1..nx {
                for c in 0..3 {
                    // Column (node (i,j,k), component c): rows of the neighbouring free nodes,
                    // in increasing dof order (k, then j, then i, then component).
                    for dk in -1i64..=1 {
                        for dj in -1i64..=1 {
                            for di in -1i64..=1 {
                                let (bi, bj, bk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                                if bi < 1 || bj < 0 || bk < 0 || bi >= nx as i64 || bj >= ny as i64 || bk >= nz as i64 {
                                    continue;
                                }
                                let (bi, bj, bk) = (bi as usize, bj as usize, bk as usize);
                                let base = node_dof(bi, bj, bk).unwrap();
                                for d in 0..3 {
                                    // Sum over the elements holding both nodes.
                                    let (mut ks, mut ms) = (0.0, 0.0);
                                    for ez_ in k.saturating_sub(1)..=k.min(ez - 1) {
                                        for ey_ in j.saturating_sub(1)..=j.min(ey - 1) {
                                            for ex_ in i.saturating_sub(1)..=i.min(ex - 1) {
                                                let local = |p: usize, q: usize, r: usize| -> Option<usize> {
                                                    let (a, b, c2) =
                                                        (p.wrapping_sub(ex_), q.wrapping_sub(ey_), r.wrapping_sub(ez_));
                                                    (a <= 1 && b <= 1 && c2 <= 1).then(|| a + 2 * b + 4 * c2)
                                                };
                                                if let (Some(la), Some(lb)) = (local(i, j, k), local(bi, bj, bk)) {
                                                    ks += Ke[3 * lb + d][3 * la + c];
                                                    ms += Me[3 * lb + d][3 * la + c];
                                                }
                                            }
                                        }
                                    }
                                    row_idx.push(base + d);
                                    kv.push(ks);
                                    mv.push(ms);
                                }
                            }
                        }
                    }
                    col_ptr.push(row_idx.len());
                }
            }
        }
    }
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    (SparseColMat::new(symbolic.clone(), kv), SparseColMat::new(symbolic, mv))
}

/// Matrix Market, coordinate real symmetric: the lower triangle, 1-based.
fn write_mtx(path: &str, A: SparseColMatRef<'_, usize, f64>) {
    let file = std::fs::File::create(path).expect("create .mtx");
    let mut w = std::io::BufWriter::new(file);
    let n = A.nrows();
    let mut lower = 0;
    for j in 0..n {
        lower += A.col_range(j).filter(|&p| A.row_idx()[p] >= j).count();
    }
    writeln!(w, "%%MatrixMarket matrix coordinate real symmetric").unwrap();
    writeln!(w, "{n} {n} {lower}").unwrap();
    for j in 0..n {
        for p in A.col_range(j) {
            let i = A.row_idx()[p];
            if i >= j {
                writeln!(w, "{} {} {:.17e}", i + 1, j + 1, A.val()[p]).unwrap();
            }
        }
    }
}
