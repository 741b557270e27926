//! Quadrature rules on the reference domains of the solid elements, each with its degree of
//! exactness: a rule of degree $p$ integrates every polynomial of total degree $\le p$ exactly
//! (for the tensor rules: of degree $\le p$ in each variable). The degrees are proved by
//! `tests/unit/quadrature.rs`, which integrates all monomials up to the degree and checks that
//! degree $p + 1$ fails for at least one.
//!
//! # Reference domains
//!
//! ```text
//!  line        [-1, 1]                          -1 ---------- 1     length 2
//!
//!  quadrilateral, hexahedron: [-1, 1]^2, [-1, 1]^3                   area 4, volume 8
//!
//!  triangle {xi, eta >= 0, xi + eta <= 1}        eta
//!                                                 1 +
//!                                                   |`\
//!                                                   |  `\           area 1/2
//!                                                 0 +----+ xi
//!                                                   0    1
//!
//!  tetrahedron {xi, eta, zeta >= 0, xi + eta + zeta <= 1}: corners (0,0,0), (1,0,0),
//!  (0,1,0), (0,0,1)                                                  volume 1/6
//!
//!  wedge (prism): triangle x [-1, 1] in zeta                         volume 1
//! ```
//!
//! The weights of every rule sum to the measure of its domain. Rules with the same points are
//! cached: the `*_rule` accessors of the element kinds hand out `&'static` references.
//!
//! # Sources
//!
//! - Gauss-Legendre: nodes are the roots of $P_n$, found by Newton's method from the
//!   Chebyshev-like initial guess $\cos(\pi (i + 3/4) / (n + 1/2))$ (Press et al., *Numerical
//!   Recipes*, 3rd ed., §4.6.1, `gauleg`); weights $2 / ((1 - x_i^2) P_n'(x_i)^2)$.
//! - Triangle: centroid (degree 1); three interior points (degree 2, Strang & Fix, *An analysis
//!   of the finite element method*, 1973, table 4.1); six points (degree 3, Strang & Fix);
//!   seven points (degree 5, Radon 1948, as in Zienkiewicz, Taylor & Zhu, *The Finite Element
//!   Method*, 7th ed., table 6.3).
//! - Tetrahedron: centroid (degree 1); four points (degree 2); five points with a negative
//!   centroid weight (degree 3; Keast, "Moderate-degree tetrahedral quadrature formulas",
//!   CMAME 55 (1986) 339-348, rule 2, = Stroud T3:3-1); fourteen points with positive weights
//!   (degree 5; Walkington, "Quadrature on simplices of arbitrary dimension", CMU 2000, the
//!   rule also used by FEniCS/FIAT).

use std::f64::consts::PI;

/// Points and weights of a quadrature rule in `D` reference coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Rule<const D: usize> {
    /// Reference coordinates of the points.
    pub points: Vec<[f64; D]>,
    /// Weights; they sum to the measure of the reference domain.
    pub weights: Vec<f64>,
    /// Degree of exactness (see the module docs).
    pub degree: usize,
}

impl<const D: usize> Rule<D> {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True for a rule without points (never produced by this module).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// $\sum_q w_q f(\boldsymbol\xi_q)$.
    pub fn integrate(&self, f: impl Fn(&[f64; D]) -> f64) -> f64 {
        self.points.iter().zip(&self.weights).map(|(x, w)| w * f(x)).sum()
    }
}

/// Gauss-Legendre nodes and weights on $[-1, 1]$ with `n >= 1` points: degree $2n - 1$.
///
/// # Panics
/// If `n == 0` (a programming error: no element asks for an empty rule).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "a Gauss-Legendre rule needs at least one point");
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    // Roots come in +- pairs; compute the upper half by Newton on P_n and mirror.
    for i in 0..n.div_ceil(2) {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (p, dpz) = legendre_and_derivative(n, z);
            dp = dpz;
            let dz = p / dpz;
            z -= dz;
            // Newton converges quadratically; stop once the step is at round-off level.
            if dz.abs() <= 4.0 * f64::EPSILON {
                break;
            }
        }
        let (_, dpz) = legendre_and_derivative(n, z);
        if dpz != 0.0 {
            dp = dpz;
        }
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        x[i] = z;
        w[i] = wi;
        x[n - 1 - i] = -z;
        w[n - 1 - i] = wi;
    }
    // The middle root of an odd rule is exactly zero.
    if n % 2 == 1 {
        x[n / 2] = 0.0;
    }
    // Ascending order, for readability of printed rules.
    x.reverse();
    w.reverse();
    (x, w)
}

/// $P_n(z)$ and $P_n'(z)$ by the three-term recurrence.
fn legendre_and_derivative(n: usize, z: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, z);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
    (p1, dp)
}

/// Gauss-Legendre rule on the line $[-1, 1]$ with `n` points: degree $2n - 1$.
pub fn line(n: usize) -> Rule<1> {
    let (x, w) = gauss_legendre(n);
    Rule {
        points: x.into_iter().map(|x| [x]).collect(),
        weights: w,
        degree: 2 * n - 1,
    }
}

/// Tensor Gauss rule on $[-1, 1]^2$ with `n x n` points: degree $2n - 1$ in each variable.
pub fn quadrilateral(n: usize) -> Rule<2> {
    let (x, w) = gauss_legendre(n);
    let mut r = Rule {
        points: vec![],
        weights: vec![],
        degree: 2 * n - 1,
    };
    for j in 0..n {
        for i in 0..n {
            r.points.push([x[i], x[j]]);
            r.weights.push(w[i] * w[j]);
        }
    }
    r
}

/// Tensor Gauss rule on $[-1, 1]^3$ with `n x n x n` points: degree $2n - 1$ in each
/// variable. Points are ordered with $\xi$ fastest.
pub fn hexahedron(n: usize) -> Rule<3> {
    let (x, w) = gauss_legendre(n);
    let mut r = Rule {
        points: vec![],
        weights: vec![],
        degree: 2 * n - 1,
    };
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                r.points.push([x[i], x[j], x[k]]);
                r.weights.push(w[i] * w[j] * w[k]);
            }
        }
    }
    r
}

/// Symmetric rule on the reference triangle of total degree `degree` (1, 2, 3, or 4-5 for the
/// 7-point rule); the returned [`Rule::degree`] is the true degree (5 when 4 is asked).
///
/// # Panics
/// If `degree` is 0 or above 5 (a programming error: the elements ask for fixed degrees).
pub fn triangle(degree: usize) -> Rule<2> {
    // Weights below are relative to the triangle's area; scale by the area 1/2 at the end.
    let (pts, ws, deg): (Vec<[f64; 2]>, Vec<f64>, usize) = match degree {
        1 => (vec![[1.0 / 3.0, 1.0 / 3.0]], vec![1.0], 1),
        2 => {
            let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
            (vec![[a, a], [b, a], [a, b]], vec![1.0 / 3.0; 3], 2)
        }
        3 => {
            // Strang & Fix 6-point rule: all permutations of barycentric (a, b, c).
            let (a, b, c) = (0.659_027_622_374_092, 0.231_933_368_553_031, 0.109_039_009_072_877);
            let pts = vec![[a, b], [b, a], [a, c], [c, a], [b, c], [c, b]];
            (pts, vec![1.0 / 6.0; 6], 3)
        }
        4 | 5 => {
            // Radon's 7-point rule.
            let s15 = 15f64.sqrt();
            let a1 = (6.0 - s15) / 21.0;
            let b1 = (9.0 + 2.0 * s15) / 21.0;
            let a2 = (6.0 + s15) / 21.0;
            let b2 = (9.0 - 2.0 * s15) / 21.0;
            let w1 = (155.0 - s15) / 1200.0;
            let w2 = (155.0 + s15) / 1200.0;
            let c = 1.0 / 3.0;
            let pts = vec![[c, c], [a1, a1], [b1, a1], [a1, b1], [a2, a2], [b2, a2], [a2, b2]];
            (pts, vec![9.0 / 40.0, w1, w1, w1, w2, w2, w2], 5)
        }
        _ => panic!("no triangle rule of degree {degree} (available: 1 to 5)"),
    };
    Rule {
        points: pts,
        weights: ws.into_iter().map(|w| 0.5 * w).collect(),
        degree: deg,
    }
}

/// Symmetric rule on the reference tetrahedron of total degree `degree`: 1 (1 point), 2 (4
/// points), 3 (5 points, one negative weight), 4 or 5 (14 points, degree 5). The returned
/// [`Rule::degree`] is the true degree.
///
/// The degree-3 rule has a negative centroid weight ($-4/5$ of the volume), harmless for
/// integrating polynomials but it can make an integrated positive quantity negative; the
/// elements here use degrees 1, 2 and 5 only.
///
/// # Panics
/// If `degree` is 0 or above 5 (a programming error: the elements ask for fixed degrees).
pub fn tetrahedron(degree: usize) -> Rule<3> {
    // Points as barycentric orbits; weights relative to the volume, scaled by 1/6 at the end.
    let mut r = Rule {
        points: vec![],
        weights: vec![],
        degree: 0,
    };
    // (a, a, a, 1 - 3a) and its 4 permutations; the reference coordinates are barycentric
    // coordinates 1..3.
    fn orbit4(a: f64, w: f64, r: &mut Rule<3>) {
        let b = 1.0 - 3.0 * a;
        for p in [[a, a, a], [b, a, a], [a, b, a], [a, a, b]] {
            r.points.push(p);
            r.weights.push(w);
        }
    }
    match degree {
        1 => {
            r.points.push([0.25; 3]);
            r.weights.push(1.0);
            r.degree = 1;
        }
        2 => {
            // a = (5 - sqrt 5) / 20.
            orbit4((5.0 - 5f64.sqrt()) / 20.0, 0.25, &mut r);
            r.degree = 2;
        }
        3 => {
            r.points.push([0.25; 3]);
            r.weights.push(-0.8);
            orbit4(1.0 / 6.0, 0.45, &mut r);
            r.degree = 3;
        }
        4 | 5 => {
            // Walkington's 14-point rule; weights quoted relative to the volume 1/6 in the
            // literature, hence the factor 6.
            orbit4(0.092_735_250_310_891_2, 6.0 * 0.012_248_840_519_393_66, &mut r);
            orbit4(0.310_885_919_263_300_6, 6.0 * 0.018_781_320_953_002_64, &mut r);
            // (a, a, b, b) with b = 1/2 - a: six permutations.
            let a = 0.045_503_704_125_649_6;
            let b = 0.5 - a;
            let w = 6.0 * 0.007_091_003_462_846_911;
            for p in [[a, a, b], [a, b, a], [b, a, a], [a, b, b], [b, a, b], [b, b, a]] {
                r.points.push(p);
                r.weights.push(w);
            }
            r.degree = 5;
        }
        _ => panic!("no tetrahedron rule of degree {degree} (available: 1 to 5)"),
    }
    for w in &mut r.weights {
        *w /= 6.0;
    }
    r
}

/// Product rule on the reference wedge: the triangle rule of degree `triangle_degree` times
/// the `n`-point Gauss rule in $\zeta$. Degree: the triangle degree in $(\xi, \eta)$ and
/// $2n - 1$ in $\zeta$; [`Rule::degree`] holds the smaller of the two.
pub fn wedge(triangle_degree: usize, n: usize) -> Rule<3> {
    let t = triangle(triangle_degree);
    let (z, wz) = gauss_legendre(n);
    let mut r = Rule {
        points: vec![],
        weights: vec![],
        degree: t.degree.min(2 * n - 1),
    };
    for k in 0..n {
        for (p, w) in t.points.iter().zip(&t.weights) {
            r.points.push([p[0], p[1], z[k]]);
            r.weights.push(w * wz[k]);
        }
    }
    r
}
