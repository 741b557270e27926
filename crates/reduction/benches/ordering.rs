//! Fill-reducing orderings of $\mathbf K_{ii}$ compared: faer's AMD against our
//! nested dissection (`fe_model::ordering`) with several leaf sizes, on the hex8 blocks of
//! `benches/craig_bampton.rs` (RBE2 interfaces on both end faces, interface dofs removed as
//! Craig-Bampton removes them). Prints the ordering time, the factor size and its flops
//! ($\sum_j c_j^2$); with `REDUCTION_ORDERING_NUMERIC=1` also the numeric factorisation
//! time (memory: 8 bytes per factor value).
//!
//! `cargo bench -p reduction --bench ordering -- --bench` runs 10k to 200k dofs
//! (`REDUCTION_CB_SIZES` to choose); without `--bench`, a 3k block.
//!
//! `REDUCTION_ORDERING_MESH=<file.msh>` instead analyses a gmsh solid mesh (steel, RBE2
//! interfaces on its physical surfaces "root" and "tip", as
//! `benchmarks/scripts/tet10_block.py` writes them) with nested dissection only, symbolic
//! only: the factor size and flops that `flexmbs reduce` of that mesh will need, before
//! running it.

#![allow(non_snake_case)]

mod common;

use common::{block, divisions, internal_block};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering};
use fe_model::{
    add_interface_on_set, assemble, factor_flops, nested_dissection_with_leaves, solid_model, symbolic_cholesky,
    DofMap, FillOrdering, IsotropicMaterial, MassKind, SparseCholesky, SpiderKind, SystemPattern,
};
use std::time::Instant;

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let sizes = std::env::var("REDUCTION_CB_SIZES").unwrap_or_else(|_| {
        if full {
            "10k,25k,50k,100k,200k".into()
        } else {
            "3k".into()
        }
    });
    let numeric = std::env::var("REDUCTION_ORDERING_NUMERIC").is_ok();
    if let Ok(file) = std::env::var("REDUCTION_ORDERING_MESH") {
        mesh_factor_size(std::path::Path::new(&file));
        return;
    }
    println!(
        "reduction/benches/ordering: K_ii of hex8 blocks; load average {}",
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    for size in sizes.split(',').map(str::trim) {
        let (model, a, b) = block(divisions(size).unwrap_or_else(|| panic!("unknown size {size}")));
        let dofs = DofMap::new(&model).unwrap();
        let K = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap().K;
        // K_ii: the free dofs but the interface nodes' twelve.
        let (K_ii, points) = internal_block(&model, &dofs, &K, &[a, b]);
        let ni = K_ii.nrows();
        let report = |what: String,
                      seconds: f64,
                      symbolic: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>| {
            println!(
                "{size:>5} {ni:>7} dofs  {what:<22} ordering + symbolic {seconds:6.2} s, factor {:7.1} M values ({:5.2} GB), {:9.1} Gflop",
                symbolic.len_val() as f64 / 1e6,
                symbolic.len_val() as f64 * 8.0 / 1e9,
                factor_flops(symbolic) / 1e9
            );
        };
        let t = Instant::now();
        let (amd, _) = symbolic_cholesky(K_ii.symbolic(), None, FillOrdering::Amd).unwrap();
        report("AMD".into(), t.elapsed().as_secs_f64(), &amd);
        drop(amd);
        for leaf in [32, 128, 512] {
            let t = Instant::now();
            let (fwd, inv) = nested_dissection_with_leaves(K_ii.symbolic(), &points, leaf).unwrap();
            let nd = factorize_symbolic_cholesky(
                K_ii.symbolic(),
                faer::Side::Lower,
                SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, ni)),
                CholeskySymbolicParams::default(),
            )
            .unwrap();
            report(format!("ND, leaves <= {leaf}"), t.elapsed().as_secs_f64(), &nd);
        }
        if let Ok(dir) = std::env::var("REDUCTION_ORDERING_EXPORT") {
            export_pattern(std::path::Path::new(&dir), size, K_ii.symbolic());
        }
        if let Ok(dir) = std::env::var("REDUCTION_ORDERING_IMPORT") {
            let file = std::path::Path::new(&dir).join(format!("perm_{size}.bin"));
            match std::fs::read(&file) {
                Ok(bytes) => {
                    let fwd: Vec<usize> = bytes
                        .chunks_exact(8)
                        .map(|b| u64::from_le_bytes(b.try_into().unwrap()) as usize)
                        .collect();
                    assert_eq!(fwd.len(), ni, "{}: one entry per row of K_ii", file.display());
                    let mut inv = vec![0usize; ni];
                    fwd.iter().enumerate().for_each(|(k, &d)| inv[d] = k);
                    let imported = factorize_symbolic_cholesky(
                        K_ii.symbolic(),
                        faer::Side::Lower,
                        SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, ni)),
                        CholeskySymbolicParams::default(),
                    )
                    .unwrap();
                    report(format!("imported {}", file.display()), 0.0, &imported);
                }
                Err(e) => println!("{size:>5} no imported ordering ({}: {e})", file.display()),
            }
        }
        if numeric {
            for ordering in [FillOrdering::Amd, FillOrdering::NestedDissection] {
                let t = Instant::now();
                let factor = SparseCholesky::new(K_ii.as_ref(), Some(&points), ordering).unwrap();
                println!(
                    "{size:>5} {ni:>7} dofs  {ordering:?}: ordering + symbolic + numeric factorisation {:.2} s ({} values)",
                    t.elapsed().as_secs_f64(),
                    factor.factor_len()
                );
            }
        }
    }
}

/// The symbolic factor of $\mathbf K_{ii}$ for a gmsh solid mesh with RBE2 interfaces on its
/// sets "root" and "tip" (nested dissection): values, memory and flops, and the memory of
/// $\mathbf K$ itself.
fn mesh_factor_size(file: &std::path::Path) {
    let t = Instant::now();
    let mesh = fe_model::mesh::gmsh::read(file).unwrap();
    let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
    let mut model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let a = add_interface_on_set(&mut model, "root", "root", None, SpiderKind::Rbe2).unwrap();
    let b = add_interface_on_set(&mut model, "tip", "tip", None, SpiderKind::Rbe2).unwrap();
    let dofs = DofMap::new(&model).unwrap();
    let K = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap().K;
    let nnz = K.compute_nnz();
    let (K_ii, points) = internal_block(&model, &dofs, &K, &[a, b]);
    drop((model, K));
    let ni = K_ii.nrows();
    let (symbolic, _) = symbolic_cholesky(K_ii.symbolic(), Some(&points), FillOrdering::NestedDissection).unwrap();
    println!(
        "{}: {} free dofs, K {nnz} entries ({:.2} GB with indices); K_ii {ni} rows; nested dissection: factor {:.1} M values ({:.2} GB), {:.0} Gflop ({:.0} s)",
        file.display(),
        dofs.n_free(),
        nnz as f64 * 16.0 / 1e9,
        symbolic.len_val() as f64 / 1e6,
        symbolic.len_val() as f64 * 8.0 / 1e9,
        factor_flops(&symbolic) / 1e9,
        t.elapsed().as_secs_f64()
    );
}

/// Writes the pattern of `A` without its diagonal, both triangles, as `graph_<size>.bin`:
/// `n` (u64), `n + 1` row pointers (u64), then the column indices (u32), little-endian; the
/// adjacency graph that METIS's `METIS_NodeND` orders (`benchmarks/scripts/metis_ordering.py`).
fn export_pattern(dir: &std::path::Path, size: &str, A: faer::sparse::SymbolicSparseColMatRef<'_, usize>) {
    let n = A.nrows();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
    for j in 0..n {
        for &i in A.row_idx_of_col_raw(j) {
            if i != j {
                adj[i].push(j as u32);
                adj[j].push(i as u32);
            }
        }
    }
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&(n as u64).to_le_bytes());
    let mut ptr = 0u64;
    bytes.extend_from_slice(&ptr.to_le_bytes());
    for row in &mut adj {
        row.sort_unstable();
        row.dedup();
        ptr += row.len() as u64;
        bytes.extend_from_slice(&ptr.to_le_bytes());
    }
    for row in &adj {
        for &j in row {
            bytes.extend_from_slice(&j.to_le_bytes());
        }
    }
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join(format!("graph_{size}.bin")), bytes).unwrap();
}
