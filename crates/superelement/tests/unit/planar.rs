//! The planar body ([`Superelement::into_planar`]) against the spatial one: on planar states
//! (deformed, turned by more than 1 rad about z, moving, with modal coordinates, rates,
//! accelerations and gravity in the plane) its residual, force parts, M, C_t and K_t equal the
//! in-plane rows and columns of the spatial body's (the same reduced body), and its
//! out-of-plane rows are zero; its tangents against central differences; rigid motion; the
//! NotPlanar errors.
//!
//! Tolerance of the comparison: the two evaluations form the same quantities by different
//! sums (3 coordinates per interface against 6, dual numbers against the closed-form tangents,
//! two frame solves each converged to 1e-12); the differences measured are up to 8e-14 of each
//! block's largest entry (`SUPERELEMENT_FD_VERBOSE=1` prints them), and 1e-10 leaves room for
//! the frame tolerance.

use nalgebra::{Point3, UnitQuaternion, Vector3};
use reduction::{CbSettings, ModeSelection, ReducedBody};
use std::sync::OnceLock;
use superelement::testing::{check_jacobian, fixtures, perturb_state, perturb_velocity, planar_test_state, FdReport};
use superelement::{BodyState, Damping, Frame, FrameChoice, MassVariant, Superelement, SuperelementError};

const TOL: f64 = 1e-10;

/// A beam in the plane z = 0.05, 4 elements, interfaces at both ends, 2 fixed-interface modes
/// and geometric stiffening; with `supported`, the out-of-plane dofs of its internal nodes held,
/// so its modes are in-plane.
fn planar_beam(supported: bool) -> ReducedBody {
    let settings = CbSettings {
        geometric_stiffening: true,
        ..CbSettings::new(ModeSelection::Count(2))
    };
    fixtures::planar_beam(
        Point3::new(0.1, -0.2, 0.05),
        Point3::new(1.0, 0.3, 0.05),
        4,
        settings,
        supported,
    )
    .2
}

fn body() -> &'static ReducedBody {
    static B: OnceLock<ReducedBody> = OnceLock::new();
    B.get_or_init(|| planar_beam(true))
}

fn damping() -> Damping {
    damping_for(2)
}

/// Rayleigh damping and a modal ratio for each of `modes` modes.
fn damping_for(modes: usize) -> Damping {
    Damping {
        alpha: 0.3,
        beta: 2e-4,
        modal_ratios: (0..modes).map(|i| 0.02 + 0.03 * i as f64).collect(),
    }
}

/// The spatial body and the planar one built from the same reduced body.
fn pair(frame: FrameChoice) -> (Superelement, Superelement) {
    let se = Superelement::new(body(), frame, MassVariant::Exact, damping()).unwrap();
    let planar = se.clone().into_planar().unwrap();
    assert!(planar.is_planar() && !se.is_planar());
    (se, planar)
}

fn rot_z(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a)
}

fn planar_state(se: &Superelement, angle: f64, seed: u64) -> (BodyState, Vec<f64>) {
    planar_test_state(se, angle, seed)
}

/// The in-plane index set of the 6N + m layout.
fn in_plane(se: &Superelement) -> Vec<usize> {
    let N = se.n_interfaces();
    let mut idx: Vec<usize> = (0..N).flat_map(|k| [6 * k, 6 * k + 1, 6 * k + 5]).collect();
    idx.extend(6 * N..6 * N + se.n_modes());
    idx
}

fn verbose(what: &str, planar: &[f64], spatial: &[f64], big: f64, keep: impl Fn(usize) -> bool) {
    if std::env::var_os("SUPERELEMENT_FD_VERBOSE").is_some() {
        let worst = (0..planar.len())
            .filter(|&i| keep(i))
            .map(|i| (planar[i] - spatial[i]).abs())
            .fold(0.0, f64::max);
        eprintln!("{what}: largest difference {:.3e} of the largest entry", worst / big);
    }
}

fn assert_vec(what: &str, planar: &[f64], spatial: &[f64], idx: &[usize]) {
    let big = idx.iter().map(|&i| spatial[i].abs()).fold(0.0, f64::max);
    verbose(what, planar, spatial, big, |i| idx.contains(&i));
    for i in 0..planar.len() {
        if idx.contains(&i) {
            let e = (planar[i] - spatial[i]).abs();
            assert!(
                e <= TOL * big,
                "{what}[{i}]: planar {:e}, spatial {:e} (difference {:.3e} of {big:.3e})",
                planar[i],
                spatial[i],
                e / big
            );
        } else {
            assert_eq!(planar[i], 0.0, "{what}[{i}] out of plane");
        }
    }
}

fn assert_mat(what: &str, planar: &faer::Mat<f64>, spatial: &faer::Mat<f64>, idx: &[usize]) {
    let big = idx
        .iter()
        .flat_map(|&i| idx.iter().map(move |&j| (i, j)))
        .map(|(i, j)| spatial[(i, j)].abs())
        .fold(0.0, f64::max);
    let flat = |m: &faer::Mat<f64>| {
        m.col_iter()
            .flat_map(|c| c.iter().copied().collect::<Vec<_>>())
            .collect::<Vec<f64>>()
    };
    let n = planar.nrows();
    verbose(what, &flat(planar), &flat(spatial), big, |r| {
        idx.contains(&(r % n)) && idx.contains(&(r / n))
    });
    for j in 0..planar.ncols() {
        for i in 0..planar.nrows() {
            if idx.contains(&i) && idx.contains(&j) {
                let e = (planar[(i, j)] - spatial[(i, j)]).abs();
                assert!(
                    e <= TOL * big,
                    "{what}({i}, {j}): planar {:e}, spatial {:e} (difference {:.3e} of {big:.3e})",
                    planar[(i, j)],
                    spatial[(i, j)],
                    e / big
                );
            } else {
                assert_eq!(planar[(i, j)], 0.0, "{what}({i}, {j}) out of plane");
            }
        }
    }
}

#[test]
fn planar_body_equals_the_in_plane_block_of_the_spatial_one() {
    let g = Vector3::new(1.5, -9.81, 0.0);
    for frame in [
        FrameChoice::CenterOfMass,
        FrameChoice::InterfaceNode(0),
        FrameChoice::InterfaceNode(1),
    ] {
        let (se, planar) = pair(frame);
        let idx = in_plane(&se);
        for (angle, seed) in [(1.3, 1), (-2.6, 2), (3.1, 3)] {
            let (state, acc) = planar_state(&se, angle, seed);
            let a = se.evaluate(&state, &acc, &g).unwrap();
            let b = planar.evaluate(&state, &acc, &g).unwrap();
            let what = |s: &str| format!("{s} ({frame}, {angle} rad)");
            assert_vec(&what("residual"), &b.residual, &a.residual, &idx);
            assert_vec(&what("f_inertia"), &b.f_inertia, &a.f_inertia, &idx);
            assert_vec(&what("q_v"), &b.q_v, &a.q_v, &idx);
            assert_vec(&what("f_elastic"), &b.f_elastic, &a.f_elastic, &idx);
            assert_vec(&what("f_damping"), &b.f_damping, &a.f_damping, &idx);
            assert_vec(&what("f_gravity"), &b.f_gravity, &a.f_gravity, &idx);
            assert_vec(&what("q_jj"), &b.q_jj, &a.q_jj, &idx);
            assert_mat(&what("M"), &b.mass, &a.mass, &idx);
            assert_mat(&what("C_t"), &b.damping, &a.damping, &idx);
            assert_mat(&what("K_t"), &b.stiffness, &a.stiffness, &idx);
            // Both frame solves converge to the tolerance of section 4.4, 1e-12.
            assert!((b.frame.r - a.frame.r).norm() <= 1e-12, "{}", what("frame origin"));
            assert!(b.frame.R.angle_to(&a.frame.R) <= 1e-12, "{}", what("frame rotation"));
            // Energies. T is formed from velocities that agree to round-off (the frames to 1e-12
            // enter only through sin and cos of an angle that is the same to 1e-16): 1e-12.
            let (T3, Tp) = (
                se.kinetic_energy(&state).unwrap(),
                planar.kinetic_energy(&state).unwrap(),
            );
            assert!(
                (T3 - Tp).abs() <= 1e-12 * T3,
                "{}: {T3} vs {Tp}",
                what("kinetic energy")
            );
            let kin3 = se.kinematics(&state).unwrap();
            let kinp = planar.kinematics(&state).unwrap();
            let (U3, Up) = (se.strain_energy(&kin3), planar.strain_energy(&kinp));
            // U is quadratic in a small q_jj that agrees to the frame tolerance (1e-12 of the body
            // size): its relative error is that over the relative deformation, 1e-9 with margin.
            assert!((U3 - Up).abs() <= 1e-9 * U3, "{}: {U3} vs {Up}", what("strain energy"));
            // V is linear in the frame origin and q_jj, which agree to 1e-12 of the body size; the
            // potential is of the size m g L, so its relative error is 1e-12.
            let (V3, Vp) = (se.gravity_potential(&kin3, &g), planar.gravity_potential(&kinp, &g));
            assert!(
                (V3 - Vp).abs() <= 1e-12 * V3.abs(),
                "{}: {V3} vs {Vp}",
                what("gravity potential")
            );
            // Frame and elastic velocities.
            let (v3, w3) = se.frame_velocity(&kin3, &state);
            let (vp, wp) = planar.frame_velocity(&kinp, &state);
            // The same products by different sums, as the residual (module docs): 1e-10.
            assert!((v3 - vp).norm() <= 1e-10 * v3.norm() && (w3 - wp).norm() <= 1e-10 * w3.norm());
            let (c3, cp) = (se.local_velocity(&kin3, &state), planar.local_velocity(&kinp, &state));
            assert_vec(&what("local velocity"), &cp, &c3, &idx);
        }
    }
}

/// A body of 10 planar coordinates (4 modes): the tangent pass by dual numbers takes two passes
/// of 8 directions.
#[test]
fn planar_body_with_more_coordinates_than_one_dual_pass() {
    // 10 planar coordinates: one wide dual pass; 14: two passes of 8 directions.
    for modes in [4, 8] {
        let settings = CbSettings {
            geometric_stiffening: true,
            ..CbSettings::new(ModeSelection::Count(modes))
        };
        let body = fixtures::planar_beam(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.05),
            4,
            settings,
            true,
        )
        .2;
        let se = Superelement::new(&body, FrameChoice::CenterOfMass, MassVariant::Exact, damping_for(modes)).unwrap();
        let planar = se.clone().into_planar().unwrap();
        let idx = in_plane(&se);
        assert_eq!(idx.len(), 6 + modes);
        let g = Vector3::new(1.5, -9.81, 0.0);
        let (state, acc) = planar_state(&se, 2.2, 9);
        let a = se.evaluate(&state, &acc, &g).unwrap();
        let b = planar.evaluate(&state, &acc, &g).unwrap();
        let what = |m: &str| format!("{m} ({} coordinates)", 6 + modes);
        assert_vec(&what("residual"), &b.residual, &a.residual, &idx);
        assert_mat(&what("M"), &b.mass, &a.mass, &idx);
        assert_mat(&what("C_t"), &b.damping, &a.damping, &idx);
        assert_mat(&what("K_t"), &b.stiffness, &a.stiffness, &idx);
    }
}

#[test]
fn planar_workspace_paths_agree_with_evaluate() {
    let g = Vector3::new(1.5, -9.81, 0.0);
    let (se, planar) = pair(FrameChoice::CenterOfMass);
    let (state, acc) = planar_state(&se, 1.3, 4);
    let full = planar.evaluate(&state, &acc, &g).unwrap();
    let mut ws = planar.workspace();
    let mut out = superelement::Evaluation::zeros(planar.n_coordinates());
    planar.residual_into(&state, &acc, &g, &mut ws, &mut out).unwrap();
    assert_eq!(out.residual, full.residual, "residual_into");
    assert_eq!(out.f_elastic, full.f_elastic);
    // The energy sensors read the workspace.
    let kin = planar.kinematics(&state).unwrap();
    let U = planar.strain_energy(&kin);
    // The same workspace read by the same arithmetic: round-off of one sum, 1e-12.
    assert!((planar.strain_energy_in(&ws) - U).abs() <= 1e-12 * U);
    let T = planar.kinetic_energy(&state).unwrap();
    let Tin = planar.kinetic_energy_in(&ws, &state.velocity_vector()).unwrap();
    // The same formula on the same frame solve, its terms summed in another order: 1e-12.
    assert!((T - Tin).abs() <= 1e-12 * T);
    // The same velocities are read from the evaluation's buffers, other ones recomputed: both
    // equal the spatial body's kinetic energy (the same state; sums in another order, 1e-12).
    let T3 = se.kinetic_energy(&state).unwrap();
    assert!((Tin - T3).abs() <= 1e-12 * T3, "{Tin} vs {T3}");
    let mut faster = state.clone();
    for k in 0..faster.v.len() {
        faster.v[k] *= 1.7;
        faster.omega[k] *= -0.6;
    }
    faster.eta_dot.iter_mut().for_each(|x| *x *= 2.5);
    let T_other = planar.kinetic_energy_in(&ws, &faster.velocity_vector()).unwrap();
    let T3_other = se.kinetic_energy(&faster).unwrap();
    assert!(
        (T_other - T3_other).abs() <= 1e-12 * T3_other,
        "{T_other} vs {T3_other}"
    );
    // Velocities scaled by 1.7, -0.6 and 2.5 change T by tens of per cent: 1e-3 only proves the
    // recomputed path was taken.
    assert!((T_other - Tin).abs() > 1e-3 * Tin, "other velocities, another energy");
    // The workspace's configuration: no matrices until completed, then the spatial body's.
    assert!(!ws.kinematics().is_complete() && ws.kinematics().T().is_none());
    assert!(ws.kinematics().Z()[(0, 0)].is_nan() && ws.kinematics().Y()[(5, 0)].is_nan());
    assert_eq!(ws.kinematics().q_jj, full.q_jj);
    // The deformed mesh from the workspace's configuration, against the spatial body's.
    let kin3 = se.kinematics(&state).unwrap();
    match (se.recover_mesh(&kin3), planar.recover_mesh(ws.kinematics())) {
        (Some(a), Some(b)) => {
            for (p, q) in a.positions.iter().zip(&b.positions) {
                // q_jj and the frame agree to 1e-12 (the frame tolerance), so the points do.
                assert!((p - q).norm() <= 1e-12, "recovered mesh: {p} vs {q}");
            }
        }
        _ => panic!("the planar beam keeps its mesh shapes"),
    }
    let done = ws.complete_kinematics();
    let (Z3, Zw) = (kin3.Z(), done.Z());
    for j in 0..Z3.ncols() {
        for i in 0..6 {
            // Formed from frames that agree to 1e-12 through the inverse of Phi_j Psi: 1e-9 leaves
            // three orders for its condition.
            assert!((Z3[(i, j)] - Zw[(i, j)]).abs() <= 1e-9, "Z({i}, {j})");
        }
    }
    let (T3, Tw) = (kin3.T().unwrap(), done.T().unwrap());
    for j in 0..T3.ncols() {
        for i in 0..T3.nrows() {
            assert!((T3[(i, j)] - Tw[(i, j)]).abs() <= 1e-9, "T({i}, {j})");
        }
    }
    // The evaluation at a given configuration (the state rebuilt from its frame and q_jj: the
    // interface positions to round-off, 1e-16 of the body size, times the stiffness).
    let at = planar.evaluate_kinematics(&kin, &state.velocity_vector(), &acc, &g);
    let big = full.residual.iter().fold(0.0_f64, |m, r| m.max(r.abs()));
    for (a, b) in at.residual.iter().zip(&full.residual) {
        // As Z and T above: frames agreeing to 1e-12 through the inverse of Phi_j Psi.
        assert!((a - b).abs() <= 1e-9 * big, "evaluate_kinematics: {a} vs {b}");
    }
    // A z component of gravity does no work in the plane: ignored.
    let with_z = planar.evaluate(&state, &acc, &Vector3::new(1.5, -9.81, 4.0)).unwrap();
    assert_eq!(with_z.residual, full.residual);
}

/// The planar coordinates' finite-difference steps and their 6N + m slots.
fn planar_steps(se: &Superelement) -> (Vec<usize>, Vec<f64>) {
    let idx = in_plane(se);
    let all = super::fd_tangent::steps(se);
    let h = idx.iter().map(|&i| all[i]).collect();
    (idx, h)
}

fn sub(m: &faer::Mat<f64>, idx: &[usize]) -> faer::Mat<f64> {
    faer::Mat::from_fn(idx.len(), idx.len(), |i, j| m[(idx[i], idx[j])])
}

fn ok(rep: FdReport, what: &str) {
    if std::env::var_os("SUPERELEMENT_FD_VERBOSE").is_some() {
        eprintln!("{what}: {rep}");
    }
    // The tolerance of `fd_tangent.rs` (steps 1e-6: truncation and round-off about 1e-9).
    assert!(rep.worst <= 1e-6, "{what}\n{rep}");
}

#[test]
fn planar_tangents_match_central_differences() {
    let g = Vector3::new(1.5, -9.81, 0.0);
    for frame in [FrameChoice::CenterOfMass, FrameChoice::InterfaceNode(1)] {
        let (_, se) = pair(frame);
        let (idx, h) = planar_steps(&se);
        let n3 = se.n_coordinates();
        let scatter = |d: &[f64]| {
            let mut v = vec![0.0; n3];
            for (&i, x) in idx.iter().zip(d) {
                v[i] = *x;
            }
            v
        };
        let pick = |r: Vec<f64>| idx.iter().map(|&i| r[i]).collect::<Vec<f64>>();
        for (angle, seed) in [(1.3, 5), (-2.9, 6)] {
            let (mut state, acc) = planar_state(&se, angle, seed);
            let ev = se.evaluate(&state, &acc, &g).unwrap();
            state.frame = ev.frame;
            let what = format!("{frame}, {angle} rad");
            let rep = check_jacobian("K_t", sub(&ev.stiffness, &idx).as_ref(), &h, |d| {
                pick(
                    se.evaluate(&perturb_state(&state, &scatter(d)), &acc, &g)
                        .unwrap()
                        .residual,
                )
            });
            ok(rep, &what);
            // Quadratic in the velocities, linear in the accelerations: unit steps are exact.
            let unit = vec![1.0; idx.len()];
            let rep = check_jacobian("C_t", sub(&ev.damping, &idx).as_ref(), &unit, |d| {
                pick(
                    se.evaluate(&perturb_velocity(&state, &scatter(d)), &acc, &g)
                        .unwrap()
                        .residual,
                )
            });
            ok(rep, &what);
            let rep = check_jacobian("M", sub(&ev.mass, &idx).as_ref(), &unit, |d| {
                let a: Vec<f64> = acc.iter().zip(scatter(d)).map(|(a, d)| a + d).collect();
                pick(se.evaluate(&state, &a, &g).unwrap().residual)
            });
            ok(rep, &what);
        }
    }
}

#[test]
fn rigid_planar_motion_has_no_elastic_force() {
    let (_, se) = pair(FrameChoice::CenterOfMass);
    let frame = Frame::new(Vector3::new(2.0, -1.0, 0.25), rot_z(2.2));
    let state = se.rigid_state(frame, Vector3::new(0.5, 0.2, 0.0), Vector3::new(0.0, 0.0, 4.0));
    let acc = vec![0.0; se.n_coordinates()];
    let ev = se.evaluate(&state, &acc, &Vector3::zeros()).unwrap();
    // Round-off of the frame solve (1e-12) times the stiffness scale EA = 1e8 N.
    let largest = ev.f_elastic.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    assert!(largest < 1e-3, "elastic force {largest} N on a rigid motion");
    // The frame solve's tolerance, 1e-12.
    assert!((ev.frame.R.angle_to(&rot_z(2.2))) < 1e-12);
}

fn not_planar(e: SuperelementError) -> String {
    match e {
        SuperelementError::NotPlanar { what, .. } => what,
        other => panic!("expected NotPlanar, got {other}"),
    }
}

#[test]
fn bodies_that_are_not_planar_are_refused_naming_the_coupling() {
    let exact =
        |b: &ReducedBody| Superelement::new(b, FrameChoice::CenterOfMass, MassVariant::Exact, Damping::none()).unwrap();
    // A beam out of the xy-plane.
    let skew = fixtures::straight_beam(
        Point3::new(0.1, -0.2, 0.05),
        Point3::new(1.0, 0.3, 0.45),
        4,
        ModeSelection::Count(2),
        false,
    )
    .2;
    let what = not_planar(exact(&skew).into_planar().unwrap_err());
    assert!(
        what.contains("interface 'end0'") && what.contains("one plane"),
        "{what}"
    );
    // In the plane but with its internal out-of-plane dofs free: a mode bends out of plane.
    let free = planar_beam(false);
    let what = not_planar(exact(&free).into_planar().unwrap_err());
    assert!(what.contains("mode") && what.contains("of its largest"), "{what}");
    // The Lumped inertia.
    let lumped = Superelement::new(body(), FrameChoice::CenterOfMass, MassVariant::Lumped, Damping::none()).unwrap();
    assert!(not_planar(lumped.into_planar().unwrap_err()).contains("Lumped"));
}

#[test]
fn a_state_out_of_the_plane_is_refused_naming_the_interface() {
    let (se, planar) = pair(FrameChoice::CenterOfMass);
    let (state, acc) = planar_state(&se, 1.3, 7);
    let mut tilted = state.clone();
    tilted.R[1] = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 1e-4) * tilted.R[1];
    let what = not_planar(planar.evaluate(&tilted, &acc, &Vector3::zeros()).unwrap_err());
    assert!(what.contains("interface 'b'") && what.contains("tilted"), "{what}");
    let mut lifted = state.clone();
    lifted.r[1].z += 1e-4;
    let what = not_planar(planar.evaluate(&lifted, &acc, &Vector3::zeros()).unwrap_err());
    assert!(
        what.contains("interface 'b'") && what.contains("out of the plane"),
        "{what}"
    );
}

#[test]
fn the_planar_frame_solve_converges_from_a_cold_start_and_reports_failure_as_the_spatial_one() {
    let (_, planar) = pair(FrameChoice::CenterOfMass);
    let (state, acc) = planar_state(&planar, 2.5, 8);
    let solved = planar.solve_frame(&state).unwrap().0;
    // A cold start (the identity frame, 2.5 rad away): the fallback start from interface 0.
    let mut cold = state.clone();
    cold.frame = Frame::identity();
    let (frame, iterations) = planar.solve_frame(&cold).unwrap();
    // The frame solve's tolerance, 1e-12.
    assert!((frame.r - solved.r).norm() <= 1e-12 && frame.R.angle_to(&solved.R) <= 1e-12);
    assert!(iterations > 0);
    // No iterations allowed from a start off the solution: the spatial solve's error.
    let strict = planar.clone().with_frame_settings(superelement::FrameSettings {
        tolerance: 1e-12,
        max_iterations: 0,
    });
    let mut off = state.clone();
    off.frame = Frame::new(solved.r + Vector3::new(1e-3, 0.0, 0.0), solved.R);
    match strict.evaluate(&off, &acc, &Vector3::zeros()) {
        Err(SuperelementError::FrameNotConverged { .. }) => {}
        other => panic!("expected FrameNotConverged, got {other:?}"),
    }
}
