//! The linearised verdict and frequencies do not depend on the model's size or units: steel
//! cantilevers of 20 mm, 2 m and 200 m (one geometry scaled), and the 2 m one in
//! mm-tonne-second units, are stable with the frequencies of their reduced matrices; unstable
//! equilibria stay unstable with their analytic growth rates.

use crate::fixtures::beam_body;
use mbs::{mode_energies, spectrum, Model, Support, System};
use nalgebra::{DMatrix, Isometry3, Vector3};
use reduction::{ModeSelection, ReducedBody};
use superelement::{FrameChoice, MassVariant};

/// Steel in SI units: E \[Pa\], rho \[kg/m^3\].
const STEEL_SI: [f64; 2] = [2.1e11, 7800.0];
/// The same steel in mm-tonne-second units: E \[MPa = N/mm^2\], rho \[t/mm^3\].
const STEEL_MM: [f64; 2] = [2.1e5, 7.8e-9];

/// A cantilever of length `L` along x (square section of side L/100, slenderness 350), one
/// beam superelement of 8 elements with 4 fixed-interface modes, clamped at x = 0, no gravity.
fn cantilever(L: f64, [E, rho]: [f64; 2]) -> (Model, ReducedBody) {
    let mut model = Model::new("cantilever");
    model.gravity = Vector3::zeros();
    let a = model.add_node("root", Vector3::zeros());
    let b = model.add_node("tip", Vector3::new(L, 0.0, 0.0));
    let body = beam_body(
        "beam",
        Vector3::zeros(),
        Vector3::new(L, 0.0, 0.0),
        8,
        L / 100.0,
        E,
        rho,
        ModeSelection::Count(4),
    );
    model.add_flexible_body(
        body.clone(),
        vec![a, b],
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    model.add_support(Support::clamp(a));
    (model, body)
}

/// The circular frequencies of the reduced body with its first interface clamped: the
/// generalised symmetric eigenproblem of its Craig-Bampton matrices without the first six
/// coordinates, by nalgebra (Cholesky of M, symmetric eigenvalues of L^-1 K L^-T).
fn clamped_frequencies(body: &ReducedBody) -> Vec<f64> {
    let n = body.K_CB.nrows;
    let r = n - 6;
    let sub = |A: &reduction::DenseMatrix| DMatrix::from_fn(r, r, |i, j| A.data[(j + 6) * n + i + 6]);
    let (K, M) = (sub(&body.K_CB), sub(&body.M_CB));
    let L = M.cholesky().expect("mass positive definite").l();
    let Li = L.clone().try_inverse().unwrap();
    let B = &Li * K * Li.transpose();
    let B = (&B + B.transpose()) * 0.5;
    let mut w: Vec<f64> = B.symmetric_eigenvalues().iter().map(|x| x.sqrt()).collect();
    w.sort_by(f64::total_cmp);
    w
}

/// Checks one cantilever: stable (no growing eigenvalue, no unstable mode, every state-space
/// eigenvalue on the imaginary axis, a positive definite tangent stiffness), frequencies those of its clamped reduced matrices to
/// 1e-6 relative. Returns the frequencies.
fn check_stable(L: f64, steel: [f64; 2]) -> Vec<f64> {
    let (model, body) = cantilever(L, steel);
    let sys = System::new(&model).unwrap();
    let state = sys.initial_state();
    let sp = spectrum(&sys, &state).unwrap();
    assert!(sp.growing().is_empty(), "L = {L}: {:?}", sp.growing());
    let modes = mode_energies(&sys, &state).unwrap();
    assert!(modes.iter().all(|m| !m.unstable && !m.rigid_body), "L = {L}: {modes:?}");
    // The static verdict agrees: the tangent stiffness is positive definite.
    let st = mbs::stability(&sys, &state, 1.0).unwrap();
    assert!(st.negative == 0 && st.zero == 0, "L = {L}: {st:?}");
    let w_max = sp.omega.last().copied().unwrap();
    for &(re, im) in &sp.state_space {
        assert!(re.abs() <= 1e-12 * w_max && im > 0.0, "L = {L}: s = {re} + {im} i");
    }
    let reference = clamped_frequencies(&body);
    assert_eq!(sp.omega.len(), reference.len(), "L = {L}");
    for (k, (w, r)) in sp.omega.iter().zip(&reference).enumerate() {
        assert!((w - r).abs() <= 1e-6 * r, "L = {L}, mode {k}: {w} vs {r}");
        // The modes' frequencies are the spectrum's.
        assert!((modes[k].omega - w).abs() <= 1e-9 * w, "L = {L}, mode {k}");
    }
    sp.omega
}

/// 20 mm, 2 m and 200 m: the frequencies scale as 1/L (the same geometry and material), and the
/// 2 m beam in mm-t-s units has the SI frequencies, all to 1e-6 relative, and every one is
/// stable.
#[test]
fn a_stable_cantilever_is_stable_at_every_size_and_in_any_units() {
    let small = check_stable(0.02, STEEL_SI);
    let middle = check_stable(2.0, STEEL_SI);
    let large = check_stable(200.0, STEEL_SI);
    let millimetres = check_stable(2000.0, STEEL_MM);
    // The 20 mm beam spans the badly scaled range: 2.6e3 to 4.5e5 rad/s.
    eprintln!("20 mm: {small:?} rad/s");
    assert!(small[0] > 2e3 && small[small.len() - 1] > 4e5, "{small:?}");
    for k in 0..middle.len() {
        let w = middle[k];
        for (other, factor, what) in [
            (small[k], 100.0, "20 mm"),
            (large[k], 0.01, "200 m"),
            (millimetres[k], 1.0, "2 m in mm-t-s"),
        ] {
            assert!(
                (other / factor - w).abs() <= 1e-6 * w,
                "mode {k}: {what} {other} vs 2 m {w}"
            );
        }
    }
}

/// With stiffness-proportional damping (the general state-space path: scaled, balanced), the
/// 20 mm cantilever's state-space eigenvalues all have Re s < 0, and the first pair has the
/// damping ratio beta omega_1 / 2 of its mode (Rayleigh damping keeps the undamped modes).
#[test]
fn a_damped_small_cantilever_is_stable_with_its_damping_ratio() {
    let (mut model, _) = cantilever(0.02, STEEL_SI);
    let w1 = {
        let sys = System::new(&model).unwrap();
        spectrum(&sys, &sys.initial_state()).unwrap().omega[0]
    };
    let beta = 2.0 * 0.02 / w1;
    if let mbs::Body::Flexible(f) = &mut model.bodies[0] {
        f.damping = superelement::Damping::rayleigh(0.0, beta);
    }
    let sys = System::new(&model).unwrap();
    let state = sys.initial_state();
    let sp = spectrum(&sys, &state).unwrap();
    assert!(sp.growing().is_empty(), "{:?}", sp.growing());
    for &(re, _) in &sp.state_space {
        assert!(re < 0.0, "{:?}", sp.state_space);
    }
    assert!(mode_energies(&sys, &state).unwrap().iter().all(|m| !m.unstable));
    // The lowest pair (by imaginary part) is the first bending mode: zeta = 0.02.
    let (re, im) = sp.state_space.iter().copied().find(|s| s.1 > 0.0).unwrap();
    let zeta = -re / re.hypot(im);
    assert!((zeta - 0.02).abs() < 1e-6 * 0.02, "zeta {zeta}, s = {re} + {im} i");
}

/// The rigid inverted pendulum of `linearized.rs`, 1 m below a hinge with gravity reversed, in
/// SI and in mm-t-s units (mass 1e-3 t, lengths in mm, g = 9810 mm/s^2): unstable with the
/// growth rate sqrt(m g d / (I_G + m d^2)) = sqrt(9.81 / 1.01) 1/s in both.
#[test]
fn an_inverted_pendulum_grows_at_its_analytic_rate_in_any_units() {
    let rate = (9.81f64 / 1.01).sqrt();
    // [mass, length unit, moment of inertia about the centre]
    for (m, unit, I_G) in [(1.0, 1.0, 0.01), (1e-3, 1e3, 0.01 * 1e-3 * 1e6)] {
        let (mut model, _) = models::pendulum(m, unit, I_G);
        model.gravity = Vector3::new(0.0, 9.81 * unit, 0.0);
        let sys = System::new(&model).unwrap();
        let state = sys.initial_state();
        let growing = spectrum(&sys, &state).unwrap().growing();
        assert_eq!(growing.len(), 1, "{growing:?}");
        assert!(
            (growing[0].0 - rate).abs() < 1e-10 * rate && growing[0].1 == 0.0,
            "unit {unit}: {growing:?}"
        );
        let modes = mode_energies(&sys, &state).unwrap();
        assert!(modes[0].unstable, "{:?}", modes[0]);
        // The static verdict agrees: one negative eigenvalue of the tangent stiffness.
        assert_eq!(mbs::stability(&sys, &state, 1.0).unwrap().negative, 1);
        assert!((modes[0].growth_rate.unwrap() - rate).abs() < 1e-10 * rate);
    }
}
