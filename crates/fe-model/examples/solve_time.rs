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

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Par};
use fe_model::{
    add_interface_on_set, assemble, box_mesh, dof_points, solid_model, CellKind, DofMap, FillOrdering,
    IsotropicMaterial, MassKind, SparseCholesky, SpiderKind, SystemPattern,
};
use std::time::Instant;

/// CPU seconds (user + system, all threads) of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let Some(close) = stat.rfind(')') else { return f64::NAN };
    let f: Vec<&str> = stat[close + 2..].split_whitespace().collect();
    let ticks = |k: usize| f.get(k).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN);
    (ticks(11) + ticks(12)) / 100.0
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .split_whitespace()
        .next()
        .unwrap_or("?")
        .to_string()
}

/// $\mathbf K_{ii}$ (lower triangle) of the hex8 block of `ex x ey x ez` elements with RBE2
/// interfaces on both end faces, and the positions of its dofs.
fn block(ex: usize, ey: usize, ez: usize) -> (SparseColMat<usize, f64>, Vec<[f64; 3]>) {
    let mesh = box_mesh(
        CellKind::Hex8,
        [2.0 * ex as f64 / ez as f64, ey as f64 / ez as f64, 1.0],
        [ex, ey, ez],
    )
    .unwrap();
    let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
    let mut model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let a = add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
    let b = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe2).unwrap();
    let dofs = DofMap::new(&model).unwrap();
    let K = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap().K;
    let mut keep = vec![true; dofs.n_free()];
    for node in [a, b] {
        for k in 0..6 {
            if let Some(d) = dofs.free_dof(node, k) {
                keep[d.index()] = false;
            }
        }
    }
    let internal: Vec<usize> = (0..dofs.n_free()).filter(|&d| keep[d]).collect();
    let mut position = vec![usize::MAX; dofs.n_free()];
    internal.iter().enumerate().for_each(|(i, &d)| position[d] = i);
    let mut triplets = Vec::new();
    for j in 0..K.ncols() {
        for (&i, &v) in K.row_idx_of_col_raw(j).iter().zip(K.val_of_col(j)) {
            if keep[i] && keep[j] && position[i] >= position[j] {
                triplets.push(Triplet::new(position[i], position[j], v));
            }
        }
    }
    let ni = internal.len();
    let all_points = dof_points(&model, &dofs);
    let points = internal.iter().map(|&d| all_points[d]).collect();
    (SparseColMat::try_new_from_triplets(ni, ni, &triplets).unwrap(), points)
}

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
    let (ex, ey, ez) = match size {
        "3k" => (12, 8, 8),
        "10k" => (17, 13, 13),
        "50k" => (30, 23, 23),
        "200k" => (48, 37, 37),
        other => {
            let e: Vec<usize> = other.split(',').filter_map(|v| v.parse().ok()).collect();
            assert_eq!(e.len(), 3, "size: 3k, 10k, 50k, 200k or ex,ey,ez");
            (e[0], e[1], e[2])
        }
    };
    let (K_ii, points) = block(ex, ey, ez);
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
        load()
    );
    for &k in &ks {
        let b = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
        for run in 0..runs {
            for (name, par) in [("tree", Par::rayon(threads)), ("seq", Par::Seq)] {
                let mut mem = MemBuffer::new(factor.solve_scratch(k, par));
                let mut x = b.clone();
                let (t0, c0) = (Instant::now(), cpu_seconds());
                factor.l_solve(x.as_mut(), par, MemStack::new(&mut mem));
                let (t1, c1) = (Instant::now(), cpu_seconds());
                factor.l_transpose_solve(x.as_mut(), par, MemStack::new(&mut mem));
                let (t2, c2) = (Instant::now(), cpu_seconds());
                let (wf, wb) = ((t1 - t0).as_secs_f64(), (t2 - t1).as_secs_f64());
                println!(
                    "k {k} run {run} {name:<4}: forward {wf:.3} s ({:.2} CPU-s, {:.1} GB/s), backward {wb:.3} s ({:.2} CPU-s, {:.1} GB/s); load {}",
                    c1 - c0,
                    gb / wf,
                    c2 - c1,
                    gb / wb,
                    load()
                );
            }
        }
    }
}
