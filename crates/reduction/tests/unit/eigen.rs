use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use reduction::eigen::{lowest_modes, EigenSettings, Shift};
use std::time::Instant;

fn from_triplets(n: usize, t: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
    let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
}

/// Fixed-free chain: n masses, spring k to the wall at mass 0, springs between neighbours.
fn chain_fixed_free_lumped(n: usize, k: f64, m: f64) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mut tk = Vec::new();
    let mut tm = Vec::new();
    for i in 0..n {
        tk.push((i, i, if i + 1 == n { k } else { 2.0 * k }));
        if i + 1 < n {
            tk.push((i, i + 1, -k));
            tk.push((i + 1, i, -k));
        }
        tm.push((i, i, m));
    }
    (from_triplets(n, &tk), from_triplets(n, &tm))
}

#[test]
fn experiment_chain() {
    let n = 2000;
    let (k, m) = (2.0e7, 0.5);
    let (K, M) = chain_fixed_free_lumped(n, k, m);
    let s = EigenSettings::new(10, Shift::Zero);
    let t = Instant::now();
    let sol = lowest_modes(K.as_ref(), M.as_ref(), &s).unwrap();
    println!("time {:?}", t.elapsed());
    for j in 0..10 {
        let th = (2.0 * (j as f64 + 1.0) - 1.0) * std::f64::consts::PI / (2.0 * (2.0 * n as f64 + 1.0));
        let ex = 4.0 * k / m * th.sin().powi(2);
        println!("{j} {:.16e} {:.16e} rel {:.3e} res {:.3e}", sol.eigenvalues[j], ex, (sol.eigenvalues[j] - ex) / ex, sol.residuals[j]);
    }
    let _ = Mat::<f64>::zeros(1, 1);
}

/// Free-free chain: n masses, n - 1 springs.
fn chain_free_free_lumped(n: usize, k: f64, m: f64) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mut tk = Vec::new();
    let mut tm = Vec::new();
    for i in 0..n {
        let d = if i == 0 || i + 1 == n { k } else { 2.0 * k };
        tk.push((i, i, d));
        if i + 1 < n {
            tk.push((i, i + 1, -k));
            tk.push((i + 1, i, -k));
        }
        tm.push((i, i, m));
    }
    (from_triplets(n, &tk), from_triplets(n, &tm))
}

#[test]
fn experiment_free() {
    let n = 2000;
    let (k, m) = (2.0e7, 0.5);
    let (K, M) = chain_free_free_lumped(n, k, m);
    let r = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(10, Shift::Zero));
    println!("sigma=0: {:?}", r.as_ref().err());
    let t = Instant::now();
    let sol = lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(10, Shift::Auto)).unwrap();
    println!("time {:?} shift {}", t.elapsed(), sol.shift);
    for j in 0..10 {
        let th = (j as f64) * std::f64::consts::PI / (2.0 * n as f64);
        let ex = 4.0 * k / m * th.sin().powi(2);
        println!("{j} {:.16e} {:.16e} rel {:.3e} res {:.3e}", sol.eigenvalues[j], ex, (sol.eigenvalues[j] - ex) / ex, sol.residuals[j]);
    }
}
