//! Energies: rigid kinetic energy (both inertia variants), the power balance of the inertia
//! forces (their Q_v belongs to their mass matrix), and forces as gradients of potentials.

use super::common::*;
use faer::Mat;
use nalgebra::{Matrix3, Unit, UnitQuaternion, Vector3};
use superelement::so3;
use superelement::testing::{check_jacobian, perturb_state, test_state, StateSpec};
use superelement::{BodyState, Frame, Superelement};

/// For rigid motion, 1/2 qdot^T M qdot = 1/2 m v_c^2 + 1/2 omega.I omega in both variants and
/// every frame choice. Round-off only: M_CB and the inertia invariants come from the same FE
/// mass matrix, so the two sides agree to ~1e-13 relative.
#[test]
fn rigid_kinetic_energy_is_exact() {
    for fx in all_fixtures() {
        let I_c = Matrix3::from_fn(|i, j| fx.body.inertia.inertia_com[i][j]);
        let m = fx.body.inertia.mass;
        for frame in frame_choices(&fx.body) {
            for mass in VARIANTS {
                let se = superelement(&fx.body, frame, mass);
                let Q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(0.2, 1.0, -0.4)), 2.0);
                let f = Frame::new(Vector3::new(1.0, 2.0, 3.0), Q);
                let v_j = Vector3::new(0.7, -1.2, 0.4);
                let w = Vector3::new(2.0, -0.5, 1.5);
                let state = se.rigid_state(f, v_j, w);
                let T = se.kinetic_energy(&state).unwrap();
                let v_c = v_j + w.cross(&(Q * se.center_of_mass()));
                let I = Q.to_rotation_matrix() * I_c * Q.to_rotation_matrix().transpose();
                let T_ref = 0.5 * m * v_c.norm_squared() + 0.5 * w.dot(&(I * w));
                assert!(
                    (T - T_ref).abs() < 1e-12 * T_ref,
                    "{} {frame} {mass:?}: T = {T}, rigid {T_ref}",
                    fx.name
                );
            }
        }
    }
}

/// The state at time `t` on the curve r_k + t v + t^2/2 a, exp(t w + t^2/2 alpha) R_k,
/// eta + t eta_dot + t^2/2 eta_ddot, with its exact velocities.
fn along(state: &BodyState, acc: &[f64], t: f64) -> BodyState {
    let N = state.r.len();
    let mut s = state.clone();
    for k in 0..N {
        let a = Vector3::new(acc[6 * k], acc[6 * k + 1], acc[6 * k + 2]);
        let al = Vector3::new(acc[6 * k + 3], acc[6 * k + 4], acc[6 * k + 5]);
        s.r[k] = state.r[k] + state.v[k] * t + a * (0.5 * t * t);
        s.v[k] = state.v[k] + a * t;
        let phi = state.omega[k] * t + al * (0.5 * t * t);
        s.R[k] = so3::exp(&phi) * state.R[k];
        // R' R^T = (J_l(phi) phi')~
        s.omega[k] = so3::left_jacobian(&phi) * (state.omega[k] + al * t);
    }
    for i in 0..state.eta.len() {
        let e = acc[6 * N + i];
        s.eta[i] = state.eta[i] + state.eta_dot[i] * t + 0.5 * e * t * t;
        s.eta_dot[i] = state.eta_dot[i] + e * t;
    }
    s
}

/// qdot . f_inertia = dT/dt along a motion with the given accelerations: the quadratic
/// velocity forces of both variants are those of their kinetic energy (no spurious work).
/// dT/dt by central differences in time, step 1e-5 s: truncation ~1e-10 T''' , far below the
/// 1e-7 tolerance relative to sum |qdot_i f_i|.
#[test]
fn inertia_forces_balance_the_kinetic_energy_rate() {
    for fx in [beam_dynamic(), l_frame(), beam_auxiliary(), solid_block()] {
        for frame in frame_choices(&fx.body) {
            for mass in VARIANTS {
                let se = superelement(&fx.body, frame, mass);
                let mut spec = StateSpec::moving(120.0, 31);
                spec.deformation = 0.05;
                spec.spin = 10.0;
                let (state, acc) = test_state(&se, &spec);
                let ev = se.forces(&state, &acc, &Vector3::zeros()).unwrap();
                let qd = state.velocity_vector();
                let power: f64 = qd.iter().zip(&ev.f_inertia).map(|(a, b)| a * b).sum();
                let scale: f64 = qd.iter().zip(&ev.f_inertia).map(|(a, b)| (a * b).abs()).sum();
                let h = 1e-5;
                let mut sp = along(&state, &acc, h);
                let mut sm = along(&state, &acc, -h);
                sp.frame = ev.frame;
                sm.frame = ev.frame;
                let dT = (se.kinetic_energy(&sp).unwrap() - se.kinetic_energy(&sm).unwrap()) / (2.0 * h);
                assert!(
                    (power - dT).abs() < 1e-7 * scale,
                    "{} {frame} {mass:?}: power {power}, dT/dt {dT}",
                    fx.name
                );
            }
        }
    }
}

/// Potential of the state: strain energy plus gravity potential.
fn potential(se: &Superelement, s: &BodyState, g: &Vector3<f64>) -> f64 {
    let kin = se.kinematics(s).unwrap();
    se.strain_energy(&kin) + se.gravity_potential(&kin, g)
}

/// f_elastic - f_gravity = dV/dq (V = strain energy + gravity potential), by central
/// differences with exponential-map perturbations: the elastic force is conservative with the
/// exact Lambda factor, and gravity is the body force of the mass distribution.
#[test]
fn gravity_is_the_gradient_of_its_potential() {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            let se = superelement(&fx.body, frame, superelement::MassVariant::Exact);
            let mut spec = StateSpec::moving(170.0, 13);
            spec.deformation = 0.2;
            spec.spin = 0.0;
            let (state, acc) = test_state(&se, &spec);
            let g = Vector3::new(3.0, -9.81, 2.0) * 1e4; // comparable with the elastic forces
            let ev = se.evaluate(&state, &acc, &g).unwrap();
            let n = se.n_coordinates();
            let grad: Vec<f64> = (0..n).map(|i| ev.f_elastic[i] - ev.f_gravity[i]).collect();
            let mut base = state.clone();
            base.frame = ev.frame;
            let A = Mat::from_fn(1, n, |_, j| grad[j]);
            let rep = check_jacobian("dV/dq", A.as_ref(), &vec![1e-6; n], |d| {
                vec![potential(&se, &perturb_state(&base, d), &g)]
            });
            assert!(rep.worst < 1e-6, "{} {frame}: {rep}", fx.name);
        }
    }
}
