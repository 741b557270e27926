//! Whole Craig-Bampton reduction of a generated solid block, as a user runs it: hex8 box
//! mesh, RBE2 interfaces on the two end faces, 20 fixed-interface modes, through
//! `reduction::reduce_with_progress` (factorisation of K_ii, 12 constraint-mode solves,
//! Lanczos, the projections and the inertia invariants). Prints wall time per stage, the
//! factor size and the peak RSS; each size runs in its own process, so that its peak RSS is
//! its own (reduction time against mesh size).
//!
//! `cargo bench -p reduction --bench craig_bampton -- --bench` runs 50k and 200k dofs;
//! `REDUCTION_CB_SIZES=10k,25k,50k,100k,200k` chooses sizes (also 3k, 600k), and
//! `REDUCTION_ORDERING=amd,nd` the fill-reducing orderings to compare (`auto` by default).
//! `REDUCTION_CB_FACTOR=single` (or `double`, default `auto`) sets the precision of the
//! factor of K_ii (`CbSettings::factor`); the line then names the precision and the number of
//! solves with the factor per operator application (the refinement steps).
//! Without `--bench` (as `cargo test --benches` runs it) a 3k-dof block with both orderings,
//! so CI checks that it runs.
//!
//! With `REDUCTION_CB_MTX_DIR` set, each size then (after its figures are printed) writes the
//! fixed-interface problem that the reduction's 20 modes solve -- K_ii and M_ii, the block with
//! both interface nodes clamped -- as `K_<size>.mtx`, `M_<size>.mtx` for scipy's `eigsh`
//! (`benchmarks/scripts/reduction_vs_scipy.sh`), solves it once more with our eigensolver
//! alone (time, worst relative residual, written to `eigenvalues_<size>.txt`); with
//! `REDUCTION_CB_EIGEN_ONLY=0` as well it skips that solve and writes the reduction's own 20
//! fixed-interface eigenvalues there (`benchmarks/compare_all.sh`). Every size ends with a
//! `RESULT` line for the scripts (time, CPU time, peak RSS, factorisation time).
//!
//! With `REDUCTION_CB_EIGENVALUES` set to a directory, each size compares its results with
//! `cb_eigenvalues_<size>_<ordering>.txt` there: the 20 fixed-interface eigenvalues
//! $\omega_j^2$ and the free-free eigenvalues of the reduced pair $(\mathbf K_{CB},
//! \mathbf M_{CB})$ (rigid-body zeros left out), written by the first run, compared by every
//! later one: it prints the largest relative difference and `MISMATCH` above 1e-10 (a change
//! of ordering, kernels or eigensolver settings must not change the reduced body).

#![allow(non_snake_case)]

mod common;

use common::{block, cpu_seconds, divisions, parse_ordering};
use fe_model::{assemble, DofMap, DofMask, FeModel, FillOrdering, NodeId, SystemPattern};
use reduction::{lowest_modes, reduce_with_progress, write_matrix_market, CbSettings, EigenSettings, ModeSelection};
use reduction::{FactorPrecision, ReducedBody, Shift, Stage};
use std::path::Path;
use std::time::Instant;

fn peak_rss_mib() -> f64 {
    status_mib("VmHWM")
}

/// A memory figure of `/proc/self/status` (`VmHWM` peak, `VmRSS` current) in MiB (2^20 bytes;
/// the file gives kB of 1024 bytes).
fn status_mib(field: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

/// One reduction in this process; prints one line.
fn run_one(size: &str, ordering: FillOrdering) {
    let (ex, ey, ez) = divisions(size).expect("checked by the parent");
    let t0 = Instant::now();
    let (model, a, b) = block((ex, ey, ez));
    let n_free = DofMap::new(&model).unwrap().n_free();
    let t_model = t0.elapsed().as_secs_f64();
    // Stage start times; the eigen iteration reports many times, only its first counts.
    let mut marks: Vec<(&'static str, f64, f64, f64)> = Vec::new();
    let mut factor = (0usize, 0.0f64, FillOrdering::Auto, fe_model::Precision::Double);
    let precision = match std::env::var("REDUCTION_CB_FACTOR").as_deref() {
        Ok("single") => FactorPrecision::Single,
        Ok("double") => FactorPrecision::Double,
        _ => FactorPrecision::Auto,
    };
    let mut applications = 0;
    let mut solves = (0usize, 0usize);
    let t1 = Instant::now();
    let body = reduce_with_progress(
        &model,
        "block",
        &[("root".into(), a), ("tip".into(), b)],
        &CbSettings {
            modes: ModeSelection::Count(20),
            keep_mesh_shapes: false,
            factor: precision,
            ..CbSettings::new(ModeSelection::Count(20))
        },
        ordering,
        &mut |stage| {
            let t = t1.elapsed().as_secs_f64();
            let name = match stage {
                Stage::Assembling => "assemble",
                Stage::Factorising { .. } => "factor",
                Stage::Factorised {
                    factor_len,
                    flops,
                    ordering,
                    precision,
                } => {
                    factor = (factor_len, flops, ordering, precision);
                    return;
                }
                Stage::ConstraintModes { .. } => "Psi",
                Stage::Solved {
                    constraint_steps,
                    factor_solves,
                    ..
                } => {
                    solves = (constraint_steps, factor_solves);
                    return;
                }
                Stage::EigenIteration { applications: k, .. } => {
                    applications = k;
                    "Lanczos"
                }
                Stage::Projecting => "project",
                Stage::Invariants => "invariants",
                _ => "other",
            };
            if marks.last().map(|m| m.0) != Some(name) {
                marks.push((name, t, cpu_seconds(), status_mib("VmRSS")));
            }
        },
    )
    .unwrap();
    let total = t1.elapsed().as_secs_f64();
    let cpu_end = cpu_seconds();
    let mut stages = String::new();
    let mut rss = String::new();
    for (k, (name, t, cpu, mb)) in marks.iter().enumerate() {
        rss += &format!("{name} {:.0}, ", mb);
        let end = marks.get(k + 1).map_or(total, |m| m.1);
        let cpu_next = marks.get(k + 1).map_or(cpu_end, |m| m.2);
        stages += &format!("{name} {:.2}/{:.2}, ", end - t, cpu_next - cpu);
    }
    println!(
        "{size:>5} {:<17} {ex} x {ey} x {ez} hex8, {n_free} free dofs: model {t_model:.2} s, reduce {total:.2} s (stage wall/CPU s: {stages}{applications} operator applications, {} solves with the factor per constraint mode, {:.2} per Lanczos vector), factor {:.1} M values ({:.2} GB in {} precision, {:.0} Gflop), peak RSS {:.0} MiB (RSS at stage start, MiB: {rss}), f1 = {:.4} Hz",
        format!("{:?}", factor.2),
        solves.0,
        solves.1 as f64 / applications.max(1) as f64,
        factor.0 as f64 / 1e6,
        factor.0 as f64 * factor.3.bytes() as f64 / 1e9,
        factor.3.name(),
        factor.1 / 1e9,
        peak_rss_mib(),
        body.fixed_interface_omega[0] / (2.0 * std::f64::consts::PI)
    );
    if let Ok(dir) = std::env::var("REDUCTION_CB_EIGENVALUES") {
        compare_eigenvalues(Path::new(&dir), &format!("{size}_{ordering:?}"), &body);
    }
    // The factorisation stage (ordering included): wall and CPU seconds.
    let factor_s = marks
        .iter()
        .position(|m| m.0 == "factor")
        .map_or((f64::NAN, f64::NAN), |k| {
            let next = marks.get(k + 1);
            (
                next.map_or(total, |m| m.1) - marks[k].1,
                next.map_or(cpu_end, |m| m.2) - marks[k].2,
            )
        });
    let peak = peak_rss_mib();
    let mut result = format!(
        "RESULT size={size} dofs={n_free} reduce_s={total:.3} reduce_cpu_s={:.3} peak_mib={peak:.0} factor_s={:.3} factor_cpu_s={:.3}",
        cpu_end - marks.first().map_or(cpu_end, |m| m.2),
        factor_s.0,
        factor_s.1
    );
    if let Ok(dir) = std::env::var("REDUCTION_CB_MTX_DIR") {
        let eigen_only = std::env::var("REDUCTION_CB_EIGEN_ONLY").map_or(true, |v| v != "0");
        let (n_ii, eigen_s, residual, difference) =
            fixed_interface_problem(size, &model, [a, b], &body, Path::new(&dir), eigen_only);
        result += &format!(
            " interior={n_ii} eigen_s={eigen_s:.3} worst_residual={residual:.3e} cb_difference={difference:.2e}"
        );
    }
    println!("{result}");
}

/// The fixed-interface eigenvalues $\omega_j^2$ of `body`, then the eigenvalues of its reduced
/// pair $(\mathbf K_{CB}, \mathbf M_{CB})$ above $10^{-8}$ of the largest (the rigid-body
/// zeros are round-off and not comparable relatively), both ascending.
fn reduced_eigenvalues(body: &ReducedBody) -> Vec<f64> {
    use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
    let dense = |d: &reduction::DenseMatrix| faer::Mat::from_fn(d.nrows, d.ncols, |i, j| d.data[i + j * d.nrows]);
    let (K, M) = (dense(&body.K_CB), dense(&body.M_CB));
    let llt = M.llt(faer::Side::Lower).expect("M_CB is positive definite");
    // L^-1 K L^-T, symmetric, with the eigenvalues of (K, M).
    let mut X = K.clone();
    solve_lower_triangular_in_place(llt.L(), X.as_mut(), faer::Par::Seq);
    let mut Y = X.transpose().to_owned();
    solve_lower_triangular_in_place(llt.L(), Y.as_mut(), faer::Par::Seq);
    let mut free = Y
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .expect("dense eigenvalues");
    let largest = free.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    free.retain(|&l| l > 1e-8 * largest);
    let mut all: Vec<f64> = body.fixed_interface_omega.iter().map(|w| w * w).collect();
    all.extend(free);
    all
}

/// Writes `dir/cb_eigenvalues_<tag>.txt` from `body` if it does not exist, else prints the
/// largest relative difference of `body`'s eigenvalues to the file's.
fn compare_eigenvalues(dir: &Path, tag: &str, body: &ReducedBody) {
    let values = reduced_eigenvalues(body);
    let file = dir.join(format!("cb_eigenvalues_{tag}.txt"));
    match std::fs::read_to_string(&file) {
        Ok(text) => {
            let reference: Vec<f64> = text.split_whitespace().map(|x| x.parse().unwrap()).collect();
            if reference.len() != values.len() {
                println!(
                    "eigenvalues MISMATCH: {} values against {} in {}",
                    values.len(),
                    reference.len(),
                    file.display()
                );
                return;
            }
            let worst = values
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs() / b.abs())
                .fold(0.0f64, f64::max);
            println!(
                "eigenvalues: {} values, largest relative difference {worst:.2e} to {}{}",
                values.len(),
                file.display(),
                if worst > 1e-10 { " MISMATCH" } else { "" }
            );
        }
        Err(_) => {
            std::fs::create_dir_all(dir).unwrap();
            let text: String = values.iter().map(|v| format!("{v:.17e}\n")).collect();
            std::fs::write(&file, text).unwrap();
            println!("eigenvalues: {} values written to {}", values.len(), file.display());
        }
    }
}

/// Writes K_ii and M_ii (the block with the interface nodes clamped) to `dir`, solves them with
/// our eigensolver alone (`eigen_only`) and writes its eigenvalues. Returns the interior size,
/// the solve's wall time, its worst relative residual and the largest relative difference of
/// its eigenvalues to the reduction's fixed-interface ones. Without `eigen_only` it writes the
/// reduction's own fixed-interface eigenvalues $\omega_j^2$ instead and returns NaN for the
/// solve.
fn fixed_interface_problem(
    size: &str,
    model: &FeModel,
    interfaces: [NodeId; 2],
    body: &ReducedBody,
    dir: &Path,
    eigen_only: bool,
) -> (usize, f64, f64, f64) {
    let mut clamped = model.clone();
    for node in interfaces {
        clamped.add_support(node, DofMask::ALL);
    }
    let dofs = DofMap::new(&clamped).unwrap();
    let m = assemble(&clamped, &SystemPattern::new(&clamped, &dofs)).unwrap();
    std::fs::create_dir_all(dir).unwrap();
    write_matrix_market(&dir.join(format!("K_{size}.mtx")), m.K.as_ref()).unwrap();
    write_matrix_market(&dir.join(format!("M_{size}.mtx")), m.M.as_ref()).unwrap();
    if !eigen_only {
        let text: String = body
            .fixed_interface_omega
            .iter()
            .map(|w| format!("{:.17e}\n", w * w))
            .collect();
        std::fs::write(dir.join(format!("eigenvalues_{size}.txt")), text).unwrap();
        return (dofs.n_free(), f64::NAN, f64::NAN, f64::NAN);
    }
    let t = Instant::now();
    let sol = lowest_modes(m.K.as_ref(), m.M.as_ref(), &EigenSettings::new(20, Shift::Zero)).unwrap();
    let eigen_s = t.elapsed().as_secs_f64();
    let text: String = sol.eigenvalues.iter().map(|l| format!("{l:.17e}\n")).collect();
    std::fs::write(dir.join(format!("eigenvalues_{size}.txt")), text).unwrap();
    let residual = sol.residuals.iter().fold(0.0f64, |a, &r| a.max(r));
    let difference = sol
        .eigenvalues
        .iter()
        .zip(&body.fixed_interface_omega)
        .map(|(l, w)| (l - w * w).abs() / (w * w))
        .fold(0.0f64, f64::max);
    (dofs.n_free(), eigen_s, residual, difference)
}

fn main() {
    if let Ok(child) = std::env::var("REDUCTION_CB_CHILD") {
        let (size, ordering) = child.split_once(':').expect("size:ordering");
        run_one(size, parse_ordering(ordering).expect("checked by the parent"));
        return;
    }
    let full = std::env::args().any(|a| a == "--bench");
    let list = |var: &str, bench: &str, test: &str| -> Vec<String> {
        let s = std::env::var(var).unwrap_or_else(|_| if full { bench.into() } else { test.into() });
        s.split(',').map(|x| x.trim().to_string()).collect()
    };
    let sizes = list("REDUCTION_CB_SIZES", "50k,200k", "3k");
    let orderings = list("REDUCTION_ORDERING", "auto", "amd,nd");
    println!(
        "reduction/benches/craig_bampton: hex8 block, RBE2 interfaces on both end faces, 20 modes; {} threads; load average {}",
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    for size in &sizes {
        if divisions(size).is_none() {
            eprintln!("unknown size {size} (3k, 10k, 25k, 50k, 100k, 200k, 600k)");
            std::process::exit(2);
        }
        for ordering in &orderings {
            if parse_ordering(ordering).is_none() {
                eprintln!("unknown ordering {ordering} (auto, amd, nd)");
                std::process::exit(2);
            }
            let status = std::process::Command::new(std::env::current_exe().unwrap())
                .env("REDUCTION_CB_CHILD", format!("{size}:{ordering}"))
                .status()
                .unwrap();
            assert!(status.success(), "the {size} {ordering} run failed: {status}");
        }
    }
}
