//! Quadrature rules: each integrates every monomial up to its stated degree exactly, and fails
//! for some monomial of the next degree (so the stated degree is neither too high nor too low);
//! weights sum to the measure of the reference domain.

use fe_model::quadrature::{self, Rule};

/// $n!$ as a float (small n only).
fn factorial(n: usize) -> f64 {
    (1..=n).map(|k| k as f64).product()
}

/// $\int_{-1}^{1} x^a dx$.
fn line_moment(a: usize) -> f64 {
    if a % 2 == 1 {
        0.0
    } else {
        2.0 / (a as f64 + 1.0)
    }
}

/// $\int x^a y^b$ over the reference triangle: $a!\,b!/(a+b+2)!$.
fn triangle_moment(a: usize, b: usize) -> f64 {
    factorial(a) * factorial(b) / factorial(a + b + 2)
}

/// $\int x^a y^b z^c$ over the reference tetrahedron: $a!\,b!\,c!/(a+b+c+3)!$.
fn tet_moment(a: usize, b: usize, c: usize) -> f64 {
    factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3)
}

/// Largest relative error of `rule` over the monomials `x^e` with exponents from `exps`, each
/// scaled by the sum of |terms| so that odd (zero-integral) monomials are judged fairly.
fn worst<const D: usize>(rule: &Rule<D>, exps: &[[usize; D]], exact: impl Fn(&[usize; D]) -> f64) -> f64 {
    exps.iter()
        .map(|e| {
            let f = |x: &[f64; D]| (0..D).map(|k| x[k].powi(e[k] as i32)).product::<f64>();
            let q = rule.integrate(f);
            let scale = rule.integrate(|x| f(x).abs()).max(exact(e).abs());
            (q - exact(e)).abs() / scale
        })
        .fold(0.0, f64::max)
}

/// Exponents with total degree exactly `p` (simplex rules) in `D` variables.
fn total_degree<const D: usize>(p: usize) -> Vec<[usize; D]> {
    let mut out = vec![];
    let mut e = [0usize; D];
    fn rec<const D: usize>(k: usize, left: usize, e: &mut [usize; D], out: &mut Vec<[usize; D]>) {
        if k == D - 1 {
            e[k] = left;
            out.push(*e);
            return;
        }
        for a in 0..=left {
            e[k] = a;
            rec(k + 1, left - a, e, out);
        }
    }
    rec(0, p, &mut e, &mut out);
    out
}

/// Exponents with every variable's exponent exactly `p` in one variable and <= p in the
/// others (tensor rules).
fn per_variable<const D: usize>(p: usize) -> Vec<[usize; D]> {
    let mut out = vec![];
    let count = (p + 1).pow(D as u32);
    for i in 0..count {
        let mut e = [0usize; D];
        let mut r = i;
        for k in 0..D {
            e[k] = r % (p + 1);
            r /= p + 1;
        }
        if e.contains(&p) {
            out.push(e);
        }
    }
    out
}

// Round-off: each rule sums at most 64 terms of size <= the scale; the tabulated points and
// weights carry 15-16 significant digits. 64 eps relative covers both.
const EXACT: f64 = 64.0 * f64::EPSILON;
// A rule that is not exact for a monomial misses it by far more than round-off; 1e-6 keeps
// the "fails at degree p + 1" check well clear of the EXACT band.
const INEXACT: f64 = 1e-6;

fn check_simplex<const D: usize>(rule: &Rule<D>, exact: impl Fn(&[usize; D]) -> f64 + Copy, measure: f64) {
    let w_sum: f64 = rule.weights.iter().sum();
    assert!(
        (w_sum - measure).abs() <= EXACT * measure,
        "weights sum to {w_sum}, not {measure}"
    );
    for p in 0..=rule.degree {
        let e = worst(rule, &total_degree::<D>(p), exact);
        assert!(
            e <= EXACT,
            "degree-{} rule, {} points: error {e:.2e} at total degree {p}",
            rule.degree,
            rule.len()
        );
    }
    let e = worst(rule, &total_degree::<D>(rule.degree + 1), exact);
    assert!(
        e > INEXACT,
        "degree-{} rule is exact at degree {} too ({e:.2e}): understated",
        rule.degree,
        rule.degree + 1
    );
}

fn check_tensor<const D: usize>(rule: &Rule<D>, measure: f64) {
    let exact = |e: &[usize; D]| e.iter().map(|&a| line_moment(a)).product::<f64>();
    let w_sum: f64 = rule.weights.iter().sum();
    assert!((w_sum - measure).abs() <= EXACT * measure);
    for p in 0..=rule.degree {
        let e = worst(rule, &per_variable::<D>(p), exact);
        assert!(
            e <= EXACT,
            "tensor rule of degree {}: error {e:.2e} at degree {p}",
            rule.degree
        );
    }
    let e = worst(rule, &per_variable::<D>(rule.degree + 1), exact);
    assert!(
        e > INEXACT,
        "tensor rule of degree {} is exact one degree higher",
        rule.degree
    );
}

#[test]
fn gauss_legendre_has_degree_2n_minus_1() {
    for n in 1..=8 {
        let r = quadrature::line(n);
        assert_eq!(r.degree, 2 * n - 1);
        check_tensor(&r, 2.0);
        // Points ascending and symmetric about 0.
        for i in 0..n {
            // Round-off of Newton's method on P_n: the roots converge to a few ulps.
            assert!((r.points[i][0] + r.points[n - 1 - i][0]).abs() <= 4.0 * f64::EPSILON);
        }
    }
}

#[test]
fn quadrilateral_and_hexahedron_are_tensor_exact() {
    for n in 1..=4 {
        check_tensor(&quadrature::quadrilateral(n), 4.0);
        check_tensor(&quadrature::hexahedron(n), 8.0);
    }
}

#[test]
fn triangle_rules_have_their_stated_degree() {
    for (asked, degree, points) in [(1, 1, 1), (2, 2, 3), (3, 3, 6), (5, 5, 7)] {
        let r = quadrature::triangle(asked);
        assert_eq!((r.degree, r.len()), (degree, points));
        check_simplex(&r, |e: &[usize; 2]| triangle_moment(e[0], e[1]), 0.5);
        assert!(
            r.weights.iter().all(|&w| w > 0.0),
            "triangle rule {degree} has a non-positive weight"
        );
        assert!(
            r.points.iter().all(|p| p[0] > 0.0 && p[1] > 0.0 && p[0] + p[1] < 1.0),
            "points inside"
        );
    }
}

#[test]
fn tetrahedron_rules_have_their_stated_degree() {
    for (asked, degree, points) in [(1, 1, 1), (2, 2, 4), (3, 3, 5), (5, 5, 14)] {
        let r = quadrature::tetrahedron(asked);
        assert_eq!((r.degree, r.len()), (degree, points));
        check_simplex(&r, |e: &[usize; 3]| tet_moment(e[0], e[1], e[2]), 1.0 / 6.0);
        assert!(
            r.points
                .iter()
                .all(|p| p.iter().all(|&x| x > 0.0) && p.iter().sum::<f64>() < 1.0),
            "tetrahedron rule {degree}: a point outside"
        );
        // Only Keast's degree-3 rule has a negative (centroid) weight, as documented.
        assert_eq!(r.weights.iter().any(|&w| w < 0.0), degree == 3);
    }
}

#[test]
fn wedge_rule_is_triangle_times_line() {
    for (td, n) in [(2, 2), (3, 3), (5, 3)] {
        let r = quadrature::wedge(td, n);
        let tri = quadrature::triangle(td);
        assert_eq!(r.len(), tri.len() * n);
        let w_sum: f64 = r.weights.iter().sum();
        // Round-off of a sum of <= 21 products of tabulated weights.
        assert!((w_sum - 1.0).abs() <= EXACT);
        // Exact for x^a y^b z^c with a + b <= triangle degree and c <= 2n - 1.
        let mut worst_err: f64 = 0.0;
        for p in 0..=tri.degree {
            for e2 in total_degree::<2>(p) {
                for c in 0..=(2 * n - 1) {
                    let e = [e2[0], e2[1], c];
                    let err = worst(&r, &[e], |e| triangle_moment(e[0], e[1]) * line_moment(e[2]));
                    worst_err = worst_err.max(err);
                }
            }
        }
        assert!(worst_err <= EXACT, "wedge({td}, {n}): error {worst_err:.2e}");
    }
}
