//! The generated solid blocks shared by the `craig_bampton` and `ordering` benches.

use faer::sparse::{SparseColMat, Triplet};
use fe_model::{add_interface_on_set, box_mesh, solid_model, CellKind, FeModel, IsotropicMaterial, MassKind, NodeId};
use fe_model::{dof_points, DofMap, FillOrdering, SpiderKind};

/// Elements (ex, ey, ez) of a named size: dofs ~ 3 (ex+1)(ey+1)(ez+1).
pub fn divisions(size: &str) -> Option<(usize, usize, usize)> {
    Some(match size {
        "3k" => (12, 8, 8),
        "10k" => (17, 13, 13),
        "25k" => (23, 18, 18),
        "50k" => (30, 23, 23),
        "100k" => (38, 29, 29),
        "200k" => (48, 37, 37),
        "600k" => (70, 53, 53),
        _ => return None,
    })
}

/// A steel hex8 block of `divisions` (ex, ey, ez) elements, 2 ex/ez x ey/ez x 1 m (about
/// 2.6 x 1 x 1 m at every named size), so each element is a 2:1:1 brick, 2/ez m along x and
/// 1/ez m across (not a cube), with RBE2 interface nodes on its end faces x = 0 ("root") and
/// x = max ("tip").
pub fn block((ex, ey, ez): (usize, usize, usize)) -> (FeModel, NodeId, NodeId) {
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
    (model, a, b)
}

/// `auto`, `amd` or `nd`.
#[allow(dead_code)]
pub fn parse_ordering(s: &str) -> Option<FillOrdering> {
    Some(match s {
        "auto" => FillOrdering::Auto,
        "amd" => FillOrdering::Amd,
        "nd" => FillOrdering::NestedDissection,
        _ => return None,
    })
}

/// $\mathbf K_{ii}$: `K` of the free dofs of `model` without the six dofs of each
/// `interfaces` node (as Craig-Bampton removes them), and the positions of its rows.
#[allow(dead_code)]
pub fn internal_block(
    model: &FeModel,
    dofs: &DofMap,
    K: &SparseColMat<usize, f64>,
    interfaces: &[NodeId],
) -> (SparseColMat<usize, f64>, Vec<[f64; 3]>) {
    let mut keep = vec![true; dofs.n_free()];
    for &node in interfaces {
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
            if keep[i] && keep[j] {
                triplets.push(Triplet::new(position[i], position[j], v));
            }
        }
    }
    let ni = internal.len();
    let K_ii = SparseColMat::try_new_from_triplets(ni, ni, &triplets).unwrap();
    let all_points = dof_points(model, dofs);
    (K_ii, internal.iter().map(|&d| all_points[d]).collect())
}

/// CPU seconds (user + system, all threads) of this process so far: less sensitive to the
/// load of a shared machine than wall time.
#[allow(dead_code)]
pub fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the command name (which may hold spaces) in parentheses.
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            // utime and stime are fields 14 and 15 of stat, 12 and 13 after the name; ticks
            // of 1/100 s on Linux.
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(f64::NAN)
}
