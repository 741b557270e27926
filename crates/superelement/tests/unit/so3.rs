//! Rotations (`superelement::so3`).

use faer::Mat;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use superelement::so3::*;
use superelement::testing::{check_jacobian, Rng};

fn mat3(A: &Matrix3<f64>) -> Mat<f64> {
    Mat::from_fn(3, 3, |i, j| A[(i, j)])
}

/// Angles covering the series/closed-form switches of every coefficient (1e-4, 0.1, 0.5)
/// and large rotations.
fn thetas() -> Vec<Vector3<f64>> {
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    [1e-9, 1e-5, 0.05, 0.099, 0.101, 0.3, 0.49, 0.51, 1.0, 2.0, 3.0]
        .iter()
        .map(|t| axis * *t)
        .collect()
}

#[test]
fn log_inverts_exp_away_from_pi() {
    let mut rng = Rng::new(1);
    for _ in 0..200 {
        let th = rng.vector() * 1.8; // |theta| < 3.12
        let back = log(&exp(&th));
        // Round-off: atan2 and the sinc are accurate to a few ulps of pi.
        assert!(
            (back - th).norm() <= 8.0 * f64::EPSILON * (1.0 + th.norm()),
            "{th} -> {back}"
        );
    }
    for th in thetas() {
        assert!((log(&exp(&th)) - th).norm() <= 8.0 * f64::EPSILON * (1.0 + th.norm()));
    }
}

#[test]
fn exp_matches_nalgebra_and_log_is_robust_near_pi() {
    let axis = Vector3::new(-0.2, 0.7, 0.4).normalize();
    for t in [0.0, 1e-12, 0.7, 3.0, std::f64::consts::PI - 1e-9, std::f64::consts::PI] {
        let q = exp(&(axis * t));
        let r = UnitQuaternion::from_scaled_axis(axis * t);
        assert!(q.angle_to(&r) < 1e-14, "exp at t = {t}");
        let back = log(&q);
        // Near pi the rotation vector is defined up to sign; exp(log(q)) = q always.
        assert!(exp(&back).angle_to(&q) < 1e-14, "exp(log(q)) at t = {t}");
        assert!((back.norm() - t).abs() < 1e-14, "angle at t = {t}");
    }
    // Just past pi the log returns the short way round.
    let q = exp(&(axis * (std::f64::consts::PI + 0.1)));
    assert!((log(&q) + axis * (std::f64::consts::PI - 0.1)).norm() < 1e-14);
}

#[test]
fn left_and_right_jacobians_match_fd() {
    for th in thetas() {
        let h = [1e-6; 3];
        // exp(theta + d) exp(theta)^T = exp(J_l d)
        let rep = check_jacobian("J_l", mat3(&left_jacobian(&th)).as_ref(), &h, |d| {
            let d = Vector3::new(d[0], d[1], d[2]);
            log(&(exp(&(th + d)) * exp(&th).inverse())).as_slice().to_vec()
        });
        assert!(rep.worst < 1e-8, "{rep}");
        let rep = check_jacobian("J_r", mat3(&right_jacobian(&th)).as_ref(), &h, |d| {
            let d = Vector3::new(d[0], d[1], d[2]);
            log(&(exp(&th).inverse() * exp(&(th + d)))).as_slice().to_vec()
        });
        assert!(rep.worst < 1e-8, "{rep}");
        let I = left_jacobian(&th) * left_jacobian_inv(&th);
        assert!((I - Matrix3::identity()).norm() < 1e-13, "J_l J_l^-1 at {}", th.norm());
        let I = right_jacobian(&th) * right_jacobian_inv(&th);
        assert!((I - Matrix3::identity()).norm() < 1e-13);
    }
}

#[test]
fn jacobian_inverse_derivatives_match_fd() {
    let x = Vector3::new(0.4, -1.1, 0.7);
    let c = Vector3::new(-0.6, 0.2, 0.9);
    for th in thetas() {
        let h = [1e-6; 3];
        let rep = check_jacobian(
            "H = d(Jl^-1 x)/dtheta",
            mat3(&left_jacobian_inv_derivative(&th, &x)).as_ref(),
            &h,
            |d| {
                (left_jacobian_inv(&(th + Vector3::new(d[0], d[1], d[2]))) * x)
                    .as_slice()
                    .to_vec()
            },
        );
        assert!(rep.worst < 1e-8, "|theta| = {}: {rep}", th.norm());
        // D Jl^-1 [c] x = H(theta, x) c
        let lhs = left_jacobian_inv_directional(&th, &c) * x;
        let rhs = left_jacobian_inv_derivative(&th, &x) * c;
        assert!((lhs - rhs).norm() < 1e-14);
        let rep = check_jacobian(
            "Q = d(H c)/dtheta",
            mat3(&left_jacobian_inv_second(&th, &x, &c)).as_ref(),
            &h,
            |d| {
                (left_jacobian_inv_derivative(&(th + Vector3::new(d[0], d[1], d[2])), &x) * c)
                    .as_slice()
                    .to_vec()
            },
        );
        assert!(rep.worst < 1e-7, "|theta| = {}: {rep}", th.norm());
    }
}

/// Below 0.25 rad `log` takes the series of atan(x)/x in x^2 (no atan2, no square root): it
/// equals the closed form 2 atan2(|v|, w) v / |v| to a few ulps on both sides of the switch, at
/// tiny angles and on random axes.
#[test]
fn log_series_matches_atan2() {
    let closed = |q: &UnitQuaternion<f64>| {
        let q = q.quaternion();
        let (w, v) = if q.w < 0.0 { (-q.w, -q.imag()) } else { (q.w, q.imag()) };
        let s = v.norm();
        v * (2.0 * s.atan2(w) / s)
    };
    let mut rng = Rng::new(7);
    let mut worst: f64 = 0.0;
    for t in [
        1e-12, 1e-7, 1e-3, 0.01, 0.05, 0.1, 0.2, 0.2449, 0.2451, 0.249, 0.251, 0.3,
    ] {
        for _ in 0..50 {
            let axis = rng.vector().normalize();
            for sign in [1.0, -1.0] {
                let q = exp(&(axis * t));
                let q = UnitQuaternion::new_unchecked(q.into_inner() * sign);
                let (a, b) = (log(&q), closed(&q));
                worst = worst.max((a - b).norm() / b.norm());
            }
        }
    }
    assert!(worst <= 4.0 * f64::EPSILON, "relative gap {worst:e}");
}
