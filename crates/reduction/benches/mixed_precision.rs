//! Would a single-precision factor of $\mathbf K_{ii}$ with iterative refinement pay? On
//! $\mathbf K_{ii}$ of the Craig-Bampton blocks of `benches/craig_bampton.rs` (nested
//! dissection, the same symbolic analysis for both precisions), it times the numeric
//! factorisation in f64 and in f32, one solve with 4 right-hand sides with each factor, and
//! counts the refinement steps $\mathbf x \leftarrow \mathbf x + \mathbf L_{32}^{-T}
//! \mathbf L_{32}^{-1}(\mathbf b - \mathbf K_{ii}\mathbf x)$ (residual in f64) that bring the
//! relative residual $\|\mathbf b - \mathbf K_{ii}\mathbf x\| / \|\mathbf b\|$ down to that
//! of the f64 solve. Times are CPU seconds of the process (both threads), repeated; faer's
//! own supernodal solves, sequential, for both precisions.
//!
//! `REDUCTION_CB_SIZES=50k cargo bench -p reduction --bench mixed_precision -- --bench`;
//! without `--bench`, the 3k block.

#![allow(non_snake_case)]

mod common;

use common::{block, cpu_seconds, divisions, internal_block};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Mat, Par};
use fe_model::{assemble, symbolic_cholesky, DofMap, FillOrdering, SystemPattern};

/// Repetitions of each timed operation (the minimum is printed).
const REPEAT: usize = 3;

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let sizes = std::env::var("REDUCTION_CB_SIZES").unwrap_or_else(|_| if full { "50k".into() } else { "3k".into() });
    println!(
        "reduction/benches/mixed_precision: K_ii of hex8 blocks; {} threads; load average {}",
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    for size in sizes.split(',').map(str::trim) {
        run(size);
    }
}

fn run(size: &str) {
    let (model, a, b) = block(divisions(size).unwrap_or_else(|| panic!("unknown size {size}")));
    let dofs = DofMap::new(&model).unwrap();
    let K = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap().K;
    let (K_ii, points) = internal_block(&model, &dofs, &K, &[a, b]);
    let n = K_ii.nrows();
    let (symbolic, _) = symbolic_cholesky(K_ii.symbolic(), Some(&points), FillOrdering::NestedDissection).unwrap();
    let par = faer::get_global_parallelism();
    // f64 and f32 factors with the same symbolic analysis.
    let (L64, t64) = factor::<f64>(&symbolic, K_ii.as_ref(), par);
    let values32: Vec<f32> = K_ii.val().iter().map(|&v| v as f32).collect();
    let K32 = SparseColMat::<usize, f32>::new(
        SymbolicSparseColMat::new_checked(n, n, K_ii.col_ptr().to_vec(), None, K_ii.row_idx().to_vec()),
        values32,
    );
    let (L32, t32) = factor::<f32>(&symbolic, K32.as_ref(), par);
    println!(
        "{size:>5} {n} dofs, factor {:.1} M values: numeric factorisation {t64:.2} CPU-s in f64, {} in f32",
        symbolic.len_val() as f64 / 1e6,
        match &L32 {
            Some(_) => format!("{t32:.2} CPU-s"),
            None => "failed (a non-positive pivot)".into(),
        }
    );
    let L64 = L64.expect("K_ii is positive definite");
    let Some(L32) = L32 else { return };
    // Right-hand sides as in the Lanczos operator: 4 columns, K_ii times a smooth-ish block.
    let k = 4;
    let X0 = Mat::<f64>::from_fn(n, k, |i, j| ((i * (j + 3)) % 101) as f64 / 50.0 - 1.0);
    let B = &K_ii * &X0;
    let residual = |X: &Mat<f64>| (&B - &K_ii * X).norm_l2() / B.norm_l2();
    let mut best64 = f64::INFINITY;
    let mut X64 = B.clone();
    for _ in 0..REPEAT {
        X64 = B.clone();
        let c = cpu_seconds();
        solve(&symbolic, &L64, X64.as_mut(), par);
        best64 = best64.min(cpu_seconds() - c);
    }
    let r64 = residual(&X64);
    let mut best32 = f64::INFINITY;
    for _ in 0..REPEAT {
        let mut Y = Mat::<f32>::from_fn(n, k, |i, j| B[(i, j)] as f32);
        let c = cpu_seconds();
        solve(&symbolic, &L32, Y.as_mut(), par);
        best32 = best32.min(cpu_seconds() - c);
    }
    println!("      one solve, {k} right-hand sides: {best64:.3} CPU-s in f64 (relative residual {r64:.1e}), {best32:.3} CPU-s in f32");
    // Refinement: residual in f64, correction with the f32 factor.
    let mut X = Mat::<f64>::zeros(n, k);
    let mut R = B.clone();
    let mut steps = String::new();
    for step in 1..=12 {
        let mut D = Mat::<f32>::from_fn(n, k, |i, j| R[(i, j)] as f32);
        solve(&symbolic, &L32, D.as_mut(), par);
        X += Mat::<f64>::from_fn(n, k, |i, j| D[(i, j)] as f64);
        R = &B - &K_ii * &X;
        let r = R.norm_l2() / B.norm_l2();
        let e = (&X - &X64).norm_l2() / X64.norm_l2();
        steps += &format!("{step}: {r:.1e} (to the f64 solution {e:.1e}); ");
        if r <= r64 {
            break;
        }
    }
    println!("      refinement with the f32 factor, relative residual after each solve: {steps}");
}

/// Numeric factorisation with `symbolic`: the values (None for a non-positive pivot) and the
/// CPU seconds it took.
fn factor<T: faer::traits::ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    A: SparseColMatRef<'_, usize, T>,
    par: Par,
) -> (Option<Vec<T>>, f64) {
    let mut L = vec![T::zero_impl(); symbolic.len_val()];
    let mut mem = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default()));
    let c = cpu_seconds();
    let ok = symbolic
        .factorize_numeric_llt::<T>(
            &mut L,
            A,
            faer::Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .is_ok();
    let t = cpu_seconds() - c;
    (ok.then_some(L), t)
}

/// $\mathbf A^{-1}\mathbf X$ in place with the factor values `L`.
fn solve<T: faer::traits::ComplexField>(symbolic: &SymbolicCholesky<usize>, L: &[T], X: faer::MatMut<'_, T>, par: Par) {
    let mut mem = MemBuffer::new(symbolic.solve_in_place_scratch::<T>(X.ncols(), par));
    faer::sparse::linalg::cholesky::LltRef::<'_, usize, T>::new(symbolic, L).solve_in_place_with_conj(
        Conj::No,
        X,
        par,
        MemStack::new(&mut mem),
    );
}
