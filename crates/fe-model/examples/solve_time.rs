//! Times the triangular solves with the sparse Cholesky factor of $\mathbf K_{ii}$ of a steel
//! hex8 block (the blocks of the `craig_bampton` bench of `reduction`, as `factor_time`):
//!
//! `cargo run --release -p fe-model --example solve_time -- <size> [runs] [k,k,...]`
//!
//! `size`: 3k, 10k, 50k, 200k (or `ex,ey,ez` elements). For each number of right-hand sides
//! `k` (default 1,4,8): the forward solve $\mathbf L\mathbf x = \mathbf b$ and the backward
//! solve $\mathbf L^T\mathbf x = \mathbf b$ with the rayon pool's threads (parallel over
//! subtrees of the elimination tree) and with faer's sequential supernodal solves, `runs`
//! times each, alternating; wall and CPU seconds (user + system of all threads, from
//! `/proc/self/stat`) and the factor's bytes read per wall second.

#![allow(non_snake_case)]

#[path = "common/mod.rs"]
mod common;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{Mat, Par};
use fe_model::{FillOrdering, SparseCholesky};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size = args.first().map(String::as_str).unwrap_or("10k");
    let runs: usize = args.get(1).and_then(|r| r.parse().ok()).unwrap_or(3);
    let ks: Vec<usize> = args
        .get(2)
        .map_or("1,4,8", String::as_str)
        .split(',')
        .filter_map(|k| k.parse().ok())
        .collect();
    let (ex, ey, ez) = common::elements(size);
    let (K_ii, points) = common::block(ex, ey, ez);
    let n = K_ii.nrows();
    let threads = rayon::current_num_threads();
    faer::set_global_parallelism(Par::rayon(threads));
    let factor = SparseCholesky::new(K_ii.as_ref(), Some(&points), FillOrdering::NestedDissection).unwrap();
    drop(K_ii);
    let (subtrees, top) = factor.parallel_subtrees();
    let gb = factor.factor_len() as f64 * 8.0 / 1e9;
    println!(
        "{size}: {n} rows, factor {gb:.2} GB; {subtrees} subtrees for {threads} threads, {:.1} % of the values above them; load {}",
        100.0 * top,
        common::load()
    );
    for &k in &ks {
        let b = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
        for run in 0..runs {
            for (name, par) in [("tree", Par::rayon(threads)), ("seq", Par::Seq)] {
                let mut mem = MemBuffer::new(factor.solve_scratch(k, par));
                let mut x = b.clone();
                let (t0, c0) = (Instant::now(), common::cpu_seconds());
                factor.l_solve(x.as_mut(), par, MemStack::new(&mut mem));
                let (t1, c1) = (Instant::now(), common::cpu_seconds());
                factor.l_transpose_solve(x.as_mut(), par, MemStack::new(&mut mem));
                let (t2, c2) = (Instant::now(), common::cpu_seconds());
                let (wf, wb) = ((t1 - t0).as_secs_f64(), (t2 - t1).as_secs_f64());
                println!(
                    "k {k} run {run} {name:<4}: forward {wf:.3} s ({:.2} CPU-s, {:.1} GB/s), backward {wb:.3} s ({:.2} CPU-s, {:.1} GB/s); load {}",
                    c1 - c0,
                    gb / wf,
                    c2 - c1,
                    gb / wb,
                    common::load()
                );
            }
        }
    }
}
