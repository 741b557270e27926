//! Rotations: exponential and logarithm of SO(3), the skew operator, the left and right
//! Jacobians (tangent operators) and the derivatives of the inverse left Jacobian that the
//! exact tangents of the superelement need. Reused by the multibody crate.
//!
//! # Conventions
//!
//! * Rotations of state are [`UnitQuaternion`]s; matrices ($3\times3$) appear only inside
//!   kernels.
//! * Variations and angular velocities are **spatial**: $\delta\mathbf R =
//!   \widetilde{\delta\boldsymbol\pi}\,\mathbf R$, $\dot{\mathbf R} = \tilde{\boldsymbol\omega}
//!   \mathbf R$ (theory guide (1.1)). A rotation is perturbed as $\mathbf R \leftarrow
//!   \exp(\widetilde{\delta\boldsymbol\pi})\mathbf R$ ([`perturb`]).
//! * Left Jacobian: $\exp(\boldsymbol\theta + \delta\boldsymbol\theta) = \exp(\mathbf J_l(\boldsymbol\theta)
//!   \delta\boldsymbol\theta)\exp(\boldsymbol\theta)$ to first order;
//!   $\mathbf J_l(\boldsymbol\theta) = \mathbf I + \frac{1-\cos t}{t^2}\tilde{\boldsymbol\theta} +
//!   \frac{t - \sin t}{t^3}\tilde{\boldsymbol\theta}^2$, $t = |\boldsymbol\theta|$.
//!   Right Jacobian $\mathbf J_r(\boldsymbol\theta) = \mathbf J_l(-\boldsymbol\theta) =
//!   \mathbf J_l^T(\boldsymbol\theta)$: $\exp(\boldsymbol\theta + \delta\boldsymbol\theta) =
//!   \exp(\boldsymbol\theta)\exp(\mathbf J_r\delta\boldsymbol\theta)$.
//! * Inverse: $\mathbf J_l^{-1}(\boldsymbol\theta) = \mathbf I - \tfrac12\tilde{\boldsymbol\theta} +
//!   \beta(t)\,\tilde{\boldsymbol\theta}^2$ with $\beta(t) = \frac{1}{t^2} -
//!   \frac{1+\cos t}{2t\sin t}$, singular at $t = 2\pi$ only.
//!
//! Every function is tested in `tests/unit/so3.rs` (round trips and central differences).

#![allow(non_snake_case)]

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

/// $\tilde{\mathbf v}$: the matrix of the cross product, $\tilde{\mathbf v}\mathbf a = \mathbf v
/// \times \mathbf a$.
#[inline]
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// $\exp(\tilde{\boldsymbol\theta})$ as a unit quaternion $[\cos\frac t2,\ \frac{\sin(t/2)}{t}
/// \boldsymbol\theta]$.
pub fn exp(theta: &Vector3<f64>) -> UnitQuaternion<f64> {
    let t = theta.norm();
    let half = 0.5 * t;
    // sin(t/2)/t: the series keeps full precision below 1e-4 (next term t^4/3840 < 3e-20).
    let s = if t < 1e-4 { 0.5 - t * t / 48.0 } else { half.sin() / t };
    UnitQuaternion::new_unchecked(Quaternion::new(half.cos(), s * theta.x, s * theta.y, s * theta.z))
}

/// $\log$: the rotation vector $\boldsymbol\theta$, $|\boldsymbol\theta| \le \pi$, with
/// $\exp(\boldsymbol\theta) = \mathbf q$.
///
/// Robust at every angle: the angle comes from `atan2(|v|, w)` (well conditioned near $0$
/// and near $\pi$, unlike `acos(w)`), and the quaternion is taken with $w \ge 0$ so that the
/// angle is at most $\pi$. At exactly $\pi$ either of the two opposite vectors is returned.
pub fn log(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = q.quaternion();
    let (w, v) = if q.w < 0.0 { (-q.w, -q.imag()) } else { (q.w, q.imag()) };
    let s2 = v.norm_squared();
    // 2 atan2(s, w) / s = (2 / w) atan(x) / x with x = s / w. Below x^2 = 1/64 (angles up to
    // 0.25 rad: the elastic rotations of the local coordinates in every frame solve) by the
    // series of atan(x) / x in x^2 (`atan_x_over_x`), which needs neither atan2 nor the
    // square root: about a fifth of the instructions.
    let f = if s2 < LOG_SERIES_X2 * (w * w) {
        let iw = 1.0 / w;
        2.0 * iw * atan_x_over_x(s2 * iw * iw)
    } else {
        let s = s2.sqrt();
        2.0 * s.atan2(w) / s
    };
    v * f
}

/// Largest $x^2 = |\mathbf v|^2/w^2$ at which [`log`] takes the series ([`atan_x_over_x`]).
const LOG_SERIES_X2: f64 = 1.0 / 64.0;

/// $\arctan(x)/x = \sum_k (-1)^k x^{2k}/(2k+1)$ from $x^2 < 1/64$, to $x^{16}$ by Horner: the first
/// term left out, $x^{18}/19 < 3\cdot10^{-18}$, is below half an ulp of the sum (about 1), so
/// the result is the function to round-off (checked against `atan` by
/// `tests/unit/so3.rs::log_series_matches_atan2`).
#[inline]
fn atan_x_over_x(x2: f64) -> f64 {
    const C: [f64; 9] = [
        1.0,
        -1.0 / 3.0,
        1.0 / 5.0,
        -1.0 / 7.0,
        1.0 / 9.0,
        -1.0 / 11.0,
        1.0 / 13.0,
        -1.0 / 15.0,
        1.0 / 17.0,
    ];
    let mut p = C[8];
    for c in C[..8].iter().rev() {
        p = c + x2 * p;
    }
    p
}

/// $\exp$ as a rotation matrix.
pub fn exp_rotation(theta: &Vector3<f64>) -> Rotation3<f64> {
    exp(theta).to_rotation_matrix()
}

/// $\log$ of a rotation matrix (through the quaternion, see [`log`]).
pub fn log_rotation(R: &Rotation3<f64>) -> Vector3<f64> {
    log(&UnitQuaternion::from_rotation_matrix(R))
}

/// The spatial perturbation $\exp(\widetilde{\delta\boldsymbol\pi})\,\mathbf q$ (module
/// conventions). Used by Newton updates and by every finite-difference test.
pub fn perturb(q: &UnitQuaternion<f64>, delta_pi: &Vector3<f64>) -> UnitQuaternion<f64> {
    exp(delta_pi) * q
}

/// $\mathbf J_l(\boldsymbol\theta) = \mathbf I + a\tilde{\boldsymbol\theta} + b\tilde{\boldsymbol\theta}^2$,
/// $a = \frac{1-\cos t}{t^2}$, $b = \frac{t-\sin t}{t^3}$ (module docs).
pub fn left_jacobian(theta: &Vector3<f64>) -> Matrix3<f64> {
    let t = theta.norm();
    let h = 0.5 * t;
    // a = 2 sin^2(t/2) / t^2 has no cancellation; (sin h / h)^2 / 2 with sin h / h -> 1.
    let sinc_h = if h < 1e-4 { 1.0 - h * h / 6.0 } else { h.sin() / h };
    let a = 0.5 * sinc_h * sinc_h;
    // b: t - sin t cancels; below t = 0.1 the series to t^8 is exact to round-off
    // (next term t^10/6227020800 < 2e-20).
    let b = if t < 0.1 {
        let t2 = t * t;
        1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0 - t2 * t2 * t2 / 362880.0 + t2 * t2 * t2 * t2 / 39916800.0
    } else {
        (t - t.sin()) / (t * t * t)
    };
    let S = skew(theta);
    Matrix3::identity() + S * a + S * S * b
}

/// $\mathbf J_r(\boldsymbol\theta) = \mathbf J_l^T(\boldsymbol\theta)$.
pub fn right_jacobian(theta: &Vector3<f64>) -> Matrix3<f64> {
    left_jacobian(&-theta)
}

/// Coefficients of $\mathbf J_l^{-1}$: $\beta(t)$, $\gamma = \beta'(t)/t$, $\delta = \gamma'(t)/t$.
///
/// Below $t = 0.5$ the Taylor series (from the Bernoulli numbers of $\frac t2\cot\frac t2$,
/// kept to $t^{12}$ in $\beta$) is used: its truncation error there is below $10^{-10}$
/// relative for $\delta$ and far less for $\beta, \gamma$, while the closed forms lose
/// about $6\epsilon/t^6/\delta(0) \approx 3\cdot10^{-10}$ relative to cancellation at $t = 0.5$;
/// both are far below what multiplies them ($\gamma$ and $\delta$ enter with $t^2$ and $t^4$).
fn jinv_coefficients(t: f64) -> (f64, f64, f64) {
    let beta = jinv_beta(t);
    if t < 0.5 {
        let t2 = t * t;
        let mut gamma = 0.0;
        let mut delta = 0.0;
        let mut p = 1.0; // t^{2k}
        for k in 0..7 {
            if k + 1 < 7 {
                gamma += 2.0 * (k + 1) as f64 * JINV_B[k + 1] * p;
            }
            if k + 2 < 7 {
                delta += 4.0 * (k + 1) as f64 * (k + 2) as f64 * JINV_B[k + 2] * p;
            }
            p *= t2;
        }
        (beta, gamma, delta)
    } else {
        let c = 1.0 / (0.5 * t).tan();
        let c2 = 1.0 + c * c;
        let (t2, t3, t4) = (t * t, t * t * t, t * t * t * t);
        let d1 = -2.0 / t3 + c2 / (4.0 * t) + c / (2.0 * t2);
        let d2 = 6.0 / t4 - c * c2 / (4.0 * t) - c2 / (2.0 * t2) - c / t3;
        (beta, d1 / t, d2 / t2 - d1 / t3)
    }
}

/// $b_k$: the coefficient of $t^{2k}$ in $\beta(t) = (1 - \frac t2\cot\frac t2)/t^2$.
const JINV_B: [f64; 7] = [
    1.0 / 12.0,
    1.0 / 720.0,
    1.0 / 30240.0,
    1.0 / 1209600.0,
    1.0 / 47900160.0,
    691.0 / 1307674368000.0,
    7.0 / (6.0 * 87178291200.0),
];

/// $\beta(t)$ of [`jinv_coefficients`] alone ($\mathbf J_l^{-1}$ needs no more).
fn jinv_beta(t: f64) -> f64 {
    if t < 0.5 {
        let t2 = t * t;
        let mut beta = 0.0;
        let mut p = 1.0; // t^{2k}
        for b in JINV_B {
            beta += b * p;
            p *= t2;
        }
        beta
    } else {
        let c = 1.0 / (0.5 * t).tan();
        1.0 / (t * t) - c / (2.0 * t)
    }
}

/// $\mathbf J_l^{-1}(\boldsymbol\theta) = \mathbf I - \tfrac12\tilde{\boldsymbol\theta} +
/// \beta(t)\tilde{\boldsymbol\theta}^2$.
pub fn left_jacobian_inv(theta: &Vector3<f64>) -> Matrix3<f64> {
    let beta = jinv_beta(theta.norm());
    let S = skew(theta);
    Matrix3::identity() - S * 0.5 + S * S * beta
}

/// $\mathbf J_r^{-1}(\boldsymbol\theta) = \mathbf J_l^{-T}(\boldsymbol\theta) = \mathbf J_l^{-1}(-\boldsymbol\theta)$.
pub fn right_jacobian_inv(theta: &Vector3<f64>) -> Matrix3<f64> {
    left_jacobian_inv(&-theta)
}

/// $\mathbf H(\boldsymbol\theta, \mathbf x) = \partial(\mathbf J_l^{-1}(\boldsymbol\theta)\mathbf x)/\partial\boldsymbol\theta$.
///
/// # Derivation
/// $\mathbf J_l^{-1}\mathbf x = \mathbf x - \tfrac12\boldsymbol\theta\times\mathbf x + \beta\mathbf v$,
/// $\mathbf v = \tilde{\boldsymbol\theta}^2\mathbf x = \boldsymbol\theta(\boldsymbol\theta\cdot\mathbf x) -
/// t^2\mathbf x$, and $\partial\beta/\partial\boldsymbol\theta = \gamma\boldsymbol\theta^T$:
/// $\mathbf H = \tfrac12\tilde{\mathbf x} + \beta[(\boldsymbol\theta\cdot\mathbf x)\mathbf I +
/// \boldsymbol\theta\mathbf x^T - 2\mathbf x\boldsymbol\theta^T] + \gamma\mathbf v\boldsymbol\theta^T$.
/// Checked by `tests/unit/so3.rs::jacobian_inverse_derivatives_match_fd`.
pub fn left_jacobian_inv_derivative(theta: &Vector3<f64>, x: &Vector3<f64>) -> Matrix3<f64> {
    let (beta, gamma, _) = jinv_coefficients(theta.norm());
    let tx = theta.dot(x);
    let v = theta * tx - x * theta.norm_squared();
    skew(x) * 0.5
        + (Matrix3::identity() * tx + theta * x.transpose() - x * theta.transpose() * 2.0) * beta
        + v * theta.transpose() * gamma
}

/// $D\mathbf J_l^{-1}(\boldsymbol\theta)[\mathbf c]$, the directional derivative of the matrix:
/// $D\mathbf J_l^{-1}[\mathbf c]\,\mathbf x = \mathbf H(\boldsymbol\theta,\mathbf x)\,\mathbf c$.
///
/// # Derivation
/// Differentiate $-\tfrac12\tilde{\boldsymbol\theta} + \beta\tilde{\boldsymbol\theta}^2$:
/// $-\tfrac12\tilde{\mathbf c} + \beta(\tilde{\mathbf c}\tilde{\boldsymbol\theta} +
/// \tilde{\boldsymbol\theta}\tilde{\mathbf c}) + \gamma(\boldsymbol\theta\cdot\mathbf c)
/// \tilde{\boldsymbol\theta}^2$. Same test as [`left_jacobian_inv_derivative`].
pub fn left_jacobian_inv_directional(theta: &Vector3<f64>, c: &Vector3<f64>) -> Matrix3<f64> {
    let (beta, gamma, _) = jinv_coefficients(theta.norm());
    let S = skew(theta);
    let C = skew(c);
    -C * 0.5 + (C * S + S * C) * beta + S * S * (gamma * theta.dot(c))
}

/// $\mathbf Q(\boldsymbol\theta, \mathbf x, \mathbf c) = \partial\big(\mathbf H(\boldsymbol\theta,
/// \mathbf x)\,\mathbf c\big)/\partial\boldsymbol\theta$: the second derivative of
/// $\mathbf J_l^{-1}(\boldsymbol\theta)\mathbf x$ contracted with $\mathbf c$ (symmetric in the
/// two directions).
///
/// # Derivation
/// With $\mathbf w = (\boldsymbol\theta\cdot\mathbf x)\mathbf c + \boldsymbol\theta(\mathbf x\cdot\mathbf c) -
/// 2\mathbf x(\boldsymbol\theta\cdot\mathbf c)$ we have $\mathbf H\mathbf c = \tfrac12\mathbf x\times\mathbf c +
/// \beta\mathbf w + \gamma(\boldsymbol\theta\cdot\mathbf c)\mathbf v$; differentiating
/// ($\partial\gamma/\partial\boldsymbol\theta = \delta\,\boldsymbol\theta^T$):
/// $\mathbf Q = \gamma\mathbf w\boldsymbol\theta^T + \beta[\mathbf c\mathbf x^T + (\mathbf x\cdot\mathbf c)\mathbf I -
/// 2\mathbf x\mathbf c^T] + \delta(\boldsymbol\theta\cdot\mathbf c)\mathbf v\boldsymbol\theta^T +
/// \gamma\mathbf v\mathbf c^T + \gamma(\boldsymbol\theta\cdot\mathbf c)[(\boldsymbol\theta\cdot\mathbf x)\mathbf I +
/// \boldsymbol\theta\mathbf x^T - 2\mathbf x\boldsymbol\theta^T]$.
/// Checked by `tests/unit/so3.rs::jacobian_inverse_derivatives_match_fd`.
pub fn left_jacobian_inv_second(theta: &Vector3<f64>, x: &Vector3<f64>, c: &Vector3<f64>) -> Matrix3<f64> {
    let (beta, gamma, delta) = jinv_coefficients(theta.norm());
    let tx = theta.dot(x);
    let tc = theta.dot(c);
    let xc = x.dot(c);
    let v = theta * tx - x * theta.norm_squared();
    let w = c * tx + theta * xc - x * (2.0 * tc);
    let I = Matrix3::identity();
    w * theta.transpose() * gamma
        + (c * x.transpose() + I * xc - x * c.transpose() * 2.0) * beta
        + v * theta.transpose() * (delta * tc)
        + v * c.transpose() * gamma
        + (I * tx + theta * x.transpose() - x * theta.transpose() * 2.0) * (gamma * tc)
}
