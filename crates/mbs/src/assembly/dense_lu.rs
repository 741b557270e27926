//! LU with partial pivoting of a small dense matrix, in place in a column-major buffer.
//!
//! The iteration matrix of a mechanism with a few superelements has some 5-30 unknowns. At that
//! size faer's recursive, blocked `lu_in_place` spends most of its instructions on its
//! bookkeeping: on the C2 slider-crank with the rod as two beam superelements (13 unknowns)
//! 11.7k instructions per factorisation and 4.9k per solve, against 9.3k and 1.8k for the
//! textbook right-looking elimination below (Golub & Van Loan, Algorithm 3.4.1, partial
//! pivoting with the row interchanges recorded as in LAPACK's `ipiv`; callgrind).
//! [`crate::assembly::system`] uses it up to [`SMALL_LU_MAX`] unknowns and faer's kernels above.

/// Up to this many unknowns the dense iteration matrix is factorised by [`factor`] instead of
/// faer's blocked LU: the whole matrix (8 KB) stays in the L1 cache, where blocking gains
/// nothing; above it faer's SIMD kernels take over. Measured at 13 unknowns only (module
/// docs); the chain bench (`cargo bench -p mbs --bench step -- chain 4 10 dense`, 24 unknowns)
/// exercises the other end.
pub const SMALL_LU_MAX: usize = 32;

/// Factorises the $n\times n$ column-major `a` in place into $\mathbf P\mathbf A = \mathbf L\mathbf U$:
/// $\mathbf L$ (unit lower) below the diagonal, $\mathbf U$ on and above it; `piv[k]` is the row
/// interchanged with row `k` at step `k`. `Err(k)` names the first column without a nonzero,
/// finite pivot (the matrix is singular or not finite; `a` is then partly eliminated).
pub fn factor(a: &mut [f64], n: usize, piv: &mut [usize]) -> Result<(), usize> {
    assert!(a.len() >= n * n && piv.len() >= n, "LU buffers smaller than {n} x {n}");
    for k in 0..n {
        let ck = &a[k * n..(k + 1) * n];
        // `!(v <= best)`: a NaN below the diagonal becomes the pivot and is refused below.
        let (mut p, mut best) = (k, ck[k].abs());
        if best.is_nan() {
            return Err(k);
        }
        for (i, v) in ck.iter().enumerate().skip(k + 1) {
            if !(v.abs() <= best) {
                (p, best) = (i, v.abs());
            }
        }
        piv[k] = p;
        if best == 0.0 || !best.is_finite() {
            return Err(k);
        }
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let (left, right) = a.split_at_mut((k + 1) * n);
        let lk = &mut left[k * n + k..k * n + n];
        let inv = 1.0 / lk[0];
        for l in &mut lk[1..] {
            *l *= inv;
        }
        let lk = &lk[1..];
        for cj in right.chunks_exact_mut(n) {
            let u = cj[k];
            if u != 0.0 {
                for (c, l) in cj[k + 1..].iter_mut().zip(lk) {
                    *c -= l * u;
                }
            }
        }
    }
    Ok(())
}

/// Solves $\mathbf A\mathbf X = \mathbf B$ in place with the factors of [`factor`]; `b` holds the
/// right-hand sides column after column (`b.len()` a multiple of $n$).
pub fn solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    if n == 0 {
        return;
    }
    for x in b.chunks_exact_mut(n) {
        for (k, &p) in piv[..n].iter().enumerate() {
            if p != k {
                x.swap(k, p);
            }
        }
        // L y = P b (unit lower), column by column.
        for k in 0..n {
            let xk = x[k];
            if xk != 0.0 {
                for (xi, l) in x[k + 1..].iter_mut().zip(&a[k * n + k + 1..(k + 1) * n]) {
                    *xi -= l * xk;
                }
            }
        }
        // U x = y, column by column from the last.
        for k in (0..n).rev() {
            x[k] /= a[k * n + k];
            let xk = x[k];
            if xk != 0.0 {
                for (xi, u) in x[..k].iter_mut().zip(&a[k * n..k * n + k]) {
                    *xi -= u * xk;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic, non-symmetric test matrix whose natural pivots are poor (small
    /// diagonal), so that the row interchanges are exercised.
    fn matrix(n: usize) -> Vec<f64> {
        let mut a = vec![0.0; n * n];
        for j in 0..n {
            for i in 0..n {
                let x = ((i * 7 + j * 13 + 3) % 17) as f64 / 17.0 - 0.5;
                a[j * n + i] = if i == j { 1e-3 * x } else { x };
            }
        }
        a
    }

    fn mul(a: &[f64], n: usize, x: &[f64]) -> Vec<f64> {
        (0..n).map(|i| (0..n).map(|j| a[j * n + i] * x[j]).sum()).collect()
    }

    #[test]
    fn solves_with_row_interchanges() {
        for n in [1, 2, 5, 13, 32] {
            let a = matrix(n);
            let x: Vec<f64> = (0..2 * n).map(|i| 1.0 + (i as f64).sin()).collect();
            let mut b: Vec<f64> = x.chunks(n).flat_map(|c| mul(&a, n, c)).collect();
            let mut lu = a.clone();
            let mut piv = vec![0; n];
            factor(&mut lu, n, &mut piv).expect("nonsingular");
            if n > 1 {
                assert!(piv.iter().enumerate().any(|(k, &p)| p != k), "n = {n}: no interchange");
            }
            solve(&lu, n, &piv, &mut b);
            // Backward-stable LU: the error is the condition number (below 1e4 for these
            // matrices) times a few n epsilon.
            let err = x.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(err < 1e-10, "n = {n}: error {err:.2e}");
        }
    }

    #[test]
    fn names_the_column_without_a_pivot() {
        // A zero column 2: elimination leaves it zero (exactly), so it has no pivot.
        let n = 4;
        let mut a = matrix(n);
        a[2 * n..3 * n].fill(0.0);
        let mut piv = vec![0; n];
        assert_eq!(factor(&mut a, n, &mut piv), Err(2));
        let mut z = vec![0.0; 9];
        assert_eq!(factor(&mut z, 3, &mut [0; 3]), Err(0));
        let mut nan = vec![1.0, f64::NAN, 0.0, 1.0];
        assert_eq!(factor(&mut nan, 2, &mut [0; 2]), Err(0));
    }
}
