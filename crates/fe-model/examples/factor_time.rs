//! Times the numeric sparse Cholesky factorisation of $\mathbf K_{ii}$ of a steel hex8 block
//! (the blocks of the `craig_bampton` bench of `reduction`: RBE2 interfaces on both end faces,
//! their twelve dofs removed), nested dissection:
//!
//! `cargo run --release -p fe-model --example factor_time -- <size> <method> [runs] [single]`
//!
//! `size`: 3k, 10k, 50k, 200k (or `ex,ey,ez` elements); `method`: `faer-seq` (faer's
//! supernodal loop, one thread), `faer` (faer's loop, dense kernels on all rayon threads),
//! `subtrees` (ours, parallel over subtrees of the elimination tree; `subtrees:N` split for
//! `N` threads whatever the pool, e.g. with `RAYON_NUM_THREADS=1`), `default` (what
//! [`SymbolicFactor::factor`] chooses), or `compare` (faer's and ours, the largest difference
//! of their values relative to each supernode's norm). Prints wall and CPU seconds (user +
//! system of all threads, from `/proc/self/stat`) of each factorisation, and the load average;
//! and per thread the seconds on a core, waiting for one and idle (asleep, no work to take;
//! `/proc/self/task/*/schedstat`): the idle thread-seconds are the parallel inefficiency
//! whatever the load, where the wall time on a shared machine says little.

#![allow(non_snake_case)]

#[path = "common/mod.rs"]
mod common;

use fe_model::{FillOrdering, Precision, SymbolicFactor};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size = args.first().map(String::as_str).unwrap_or("10k");
    let method = args.get(1).map(String::as_str).unwrap_or("compare");
    let runs: usize = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(1);
    let precision = if args.iter().any(|a| a == "single") {
        Precision::Single
    } else {
        Precision::Double
    };
    let (ex, ey, ez) = common::elements(size);
    let (K_ii, points) = common::block(ex, ey, ez);
    let ni = K_ii.nrows();
    let threads = rayon::current_num_threads();
    let analyse = |parallel: Option<usize>| {
        let mut symbolic =
            SymbolicFactor::analyse(K_ii.symbolic(), Some(&points), FillOrdering::NestedDissection).unwrap();
        if method != "default" {
            symbolic.set_parallel_subtrees(parallel);
        }
        symbolic
    };
    let symbolic = analyse(Some(threads));
    let (subtrees, top) = symbolic.parallel_subtrees();
    println!(
        "{size}: K_ii {ni} rows, factor {:.1} M values, {:.1} Gflop; {subtrees} subtrees for {threads} threads, {:.1} % of the flops above them; load average {}",
        symbolic.factor_len() as f64 / 1e6,
        symbolic.flops() / 1e9,
        100.0 * top,
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    drop(symbolic);
    if method == "compare" {
        faer::set_global_parallelism(faer::Par::rayon(threads));
        let faer_factor = analyse(None).factor(K_ii.as_ref(), precision).unwrap();
        let ours = analyse(Some(threads)).factor(K_ii.as_ref(), precision).unwrap();
        println!(
            "largest difference of the values relative to their supernode's norm: {:.2e}",
            ours.relative_difference(&faer_factor)
        );
        return;
    }
    let (par, parallel) = match method {
        "faer-seq" => (faer::Par::Seq, None),
        "faer" => (faer::Par::rayon(threads), None),
        "subtrees" | "default" => (faer::Par::rayon(threads), Some(threads)),
        // The split for N threads, run on the rayon pool as it is (RAYON_NUM_THREADS=1: the
        // same operations on one thread).
        m if m.starts_with("subtrees:") => (faer::Par::rayon(threads), m[9..].parse().ok()),
        other => panic!("method: faer-seq, faer, subtrees, default or compare, not {other}"),
    };
    faer::set_global_parallelism(par);
    for run in 0..runs {
        let symbolic = analyse(parallel);
        let used = symbolic.parallel_subtrees().0;
        let (t, c, threads_before) = (Instant::now(), common::cpu_seconds(), thread_times());
        let factor = symbolic.factor(K_ii.as_ref(), precision).unwrap();
        let (wall, cpu) = (t.elapsed().as_secs_f64(), common::cpu_seconds() - c);
        // Per thread that ran: on a core, waiting for one (the load), idle (asleep: no work).
        let threads_after = thread_times();
        let mut idle = 0.0;
        let mut per_thread = String::new();
        for (tid, (on, waiting)) in &threads_after {
            let (on0, waiting0) = threads_before.get(tid).copied().unwrap_or((0.0, 0.0));
            let (on, waiting) = (on - on0, waiting - waiting0);
            if on > 0.01 * wall {
                let asleep = (wall - on - waiting).max(0.0);
                idle += asleep;
                per_thread += &format!(" [{on:.2} on a core, {waiting:.2} waiting, {asleep:.2} idle]");
            }
        }
        println!("{size} threads (s):{per_thread}; idle {idle:.2} thread-s");
        println!(
            "{size} {method:<8} {} run {run}: numeric factorisation {wall:6.2} s wall, {cpu:6.2} CPU-s ({used} subtrees); peak RSS {:.0} MB; load {}",
            precision.name(),
            peak_rss_mb(),
            std::fs::read_to_string("/proc/loadavg").unwrap_or_default().split_whitespace().next().unwrap_or("?")
        );
        drop(factor);
    }
}

/// For each thread of this process: seconds on a core and seconds runnable but waiting for
/// one (`/proc/self/task/*/schedstat`), by thread id.
fn thread_times() -> std::collections::HashMap<String, (f64, f64)> {
    let mut times = std::collections::HashMap::new();
    for task in std::fs::read_dir("/proc/self/task").into_iter().flatten().flatten() {
        let stat = std::fs::read_to_string(task.path().join("schedstat")).unwrap_or_default();
        let f: Vec<f64> = stat.split_whitespace().filter_map(|v| v.parse().ok()).collect();
        if f.len() >= 2 {
            times.insert(
                task.file_name().to_string_lossy().into_owned(),
                (f[0] / 1e9, f[1] / 1e9),
            );
        }
    }
    times
}

/// Peak resident memory of this process \[MB\] (`VmHWM`).
fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
            line.split_whitespace().nth(1)?.parse::<f64>().ok()
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}
