//! What the fe-model timing examples (`factor_time`, `solve_time`) share: the steel hex8 blocks
//! of the `craig_bampton` bench of `reduction` (RBE2 interfaces on both end faces, their twelve
//! dofs removed), their $\mathbf K_{ii}$, and the process's CPU time and load.

#![allow(dead_code)]

use faer::sparse::{SparseColMat, Triplet};
use fe_model::{
    add_interface_on_set, assemble, box_mesh, dof_points, solid_model, CellKind, DofMap, IsotropicMaterial, MassKind,
    SpiderKind, SystemPattern,
};

/// CPU seconds (user + system, all threads) of this process so far.
pub fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let Some(close) = stat.rfind(')') else { return f64::NAN };
    let f: Vec<&str> = stat[close + 2..].split_whitespace().collect();
    let ticks = |k: usize| f.get(k).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN);
    (ticks(11) + ticks(12)) / 100.0
}

/// The 1-minute load average.
pub fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .split_whitespace()
        .next()
        .unwrap_or("?")
        .to_string()
}

/// The elements `(ex, ey, ez)` of a block size: 3k, 10k, 50k, 200k (the bench's sizes) or
/// `ex,ey,ez`.
pub fn elements(size: &str) -> (usize, usize, usize) {
    match size {
        "3k" => (12, 8, 8),
        "10k" => (17, 13, 13),
        "50k" => (30, 23, 23),
        "200k" => (48, 37, 37),
        other => {
            let e: Vec<usize> = other.split(',').filter_map(|v| v.parse().ok()).collect();
            assert_eq!(e.len(), 3, "size: 3k, 10k, 50k, 200k or ex,ey,ez");
            (e[0], e[1], e[2])
        }
    }
}

/// $\mathbf K_{ii}$ (lower triangle) of the hex8 block of `ex x ey x ez` elements with RBE2
/// interfaces on both end faces, and the positions of its dofs.
pub fn block(ex: usize, ey: usize, ez: usize) -> (SparseColMat<usize, f64>, Vec<[f64; 3]>) {
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
