//! The assembled tangents against central differences of F (system.rs, coordinates.rs).

use crate::fixtures::{beam_body, rigid};
use crate::kinematics::{chain, random_state};
use mbs::{JointKind, Load, LoadAxes, LoadKind, Model, PointMass, Spring, State, Support, System, TimeFunction};
use nalgebra::{Isometry3, Vector3};
use reduction::ModeSelection;
use superelement::testing::check_jacobian;
use superelement::{FrameChoice, MassVariant};

/// Two soft beam superelements (exact and lumped inertia, centre-of-mass and interface-node
/// frames, with modes) joined through a rigid body and a revolute joint, a spherical joint to
/// another rigid body, a spring closing back to the pinned root, a point mass, dead and
/// follower loads, gravity. Soft (E = 2 MPa) so that inertia and elastic terms are of one order.
pub fn mixed() -> Model {
    let mut m = Model::new("mixed");
    let p = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(1.2, 0.1, 0.0),
        Vector3::new(1.2, 0.1, 0.0),
        Vector3::new(2.0, 0.3, 0.2),
        Vector3::new(2.0, 0.3, 0.2),
        Vector3::new(2.3, 0.1, 0.4),
    ];
    let n: Vec<mbs::NodeId> = p
        .iter()
        .enumerate()
        .map(|(i, x)| m.add_node(&format!("n{i}"), *x))
        .collect();
    let b1 = beam_body("b1", p[0], p[1], 4, 0.05, 2e6, 2000.0, ModeSelection::Count(2));
    m.add_flexible_body(
        b1,
        vec![n[0], n[1]],
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    m.add_rigid_body(rigid(
        "r1",
        n[1],
        vec![n[2]],
        0.7,
        Vector3::new(0.1, 0.05, 0.0),
        [0.01, 0.02, 0.015],
    ));
    m.add_joint(
        "rev",
        n[2],
        n[3],
        JointKind::Revolute {
            axis: Vector3::new(0.2, 0.1, 1.0),
        },
    );
    let b2 = beam_body("b2", p[3], p[4], 4, 0.05, 2e6, 2000.0, ModeSelection::Count(1));
    m.add_flexible_body(
        b2,
        vec![n[3], n[4]],
        Isometry3::identity(),
        FrameChoice::InterfaceNode(0),
        MassVariant::Lumped,
    );
    m.add_joint("sph", n[4], n[5], JointKind::Spherical);
    m.add_rigid_body(rigid(
        "r2",
        n[5],
        vec![n[6]],
        0.5,
        Vector3::new(0.1, -0.05, 0.1),
        [0.01, 0.01, 0.02],
    ));
    m.point_masses.push(PointMass {
        name: String::new(),
        node: n[3],
        mass: 0.3,
    });
    m.springs.push(Spring {
        name: "tie".into(),
        a: n[6],
        b: Some(n[0]),
        ground_point: Vector3::zeros(),
        stiffness: 50.0,
        damping: 2.0,
        rest_length: Some(2.0),
    });
    m.add_support(Support::pin(n[0]));
    m.add_load(Load {
        node: n[4],
        kind: LoadKind::Force,
        axes: LoadAxes::Follower,
        value: Vector3::new(0.0, 3.0, 1.0),
        time: TimeFunction::constant(1.0),
    });
    m.add_load(Load {
        node: n[6],
        kind: LoadKind::Moment,
        axes: LoadAxes::Follower,
        value: Vector3::new(0.5, 0.0, 0.8),
        time: TimeFunction::constant(1.0),
    });
    m.add_dead_force(n[1], Vector3::new(0.0, 0.0, -2.0));
    m.gravity = Vector3::new(0.0, -9.81, 0.0);
    m
}

/// A deformed, rotated, moving state at t = 0.37: the start moved by up to 0.05 (rad or m) in
/// every unknown (deformations of a few percent on top of the start's rigid placement), with
/// the velocities and accelerations of `random_state` (seed 21), the floating frames re-guessed.
pub fn deformed_state(sys: &System) -> State {
    let r = random_state(sys, 21);
    let n = sys.n_dof();
    let mut rng = superelement::testing::Rng::new(5);
    let dq: Vec<f64> = (0..n).map(|_| 0.05 * rng.uniform()).collect();
    let mut s = sys.retract(&sys.initial_state(), &dq);
    s.velocity_mut().copy_from_slice(r.velocity());
    s.acceleration_mut().copy_from_slice(r.acceleration());
    s.set_time(0.37);
    sys.reset_frames(&mut s);
    s
}

/// Checks M = dF/dqdd, C = dF/dqd, K = dF/dq at `s` (central differences; rotations perturbed
/// through exp). `tol`: see the callers.
pub fn check_tangents(sys: &System, s: &State, h: f64, tol: f64) {
    let mut s0 = s.clone();
    let mats = sys.matrices(&mut s0, 1.0).unwrap();
    let n = sys.n_dof();
    let steps = vec![h; n];
    let rep = check_jacobian("K = dF/dq", mats.K.as_ref(), &steps, |d| {
        let mut st = sys.retract(&s0, d);
        sys.residual(&mut st, 1.0).unwrap()
    });
    eprintln!("{rep}");
    assert!(rep.worst < tol, "{rep}");
    let rep = check_jacobian("C = dF/dqd", mats.C.as_ref(), &steps, |d| {
        let mut st = s0.clone();
        for i in 0..n {
            st.velocity_mut()[i] += d[i];
        }
        sys.residual(&mut st, 1.0).unwrap()
    });
    eprintln!("{rep}");
    assert!(rep.worst < tol, "{rep}");
    let rep = check_jacobian("M = dF/dqdd", mats.M.as_ref(), &steps, |d| {
        let mut st = s0.clone();
        for i in 0..n {
            st.acceleration_mut()[i] += d[i];
        }
        sys.residual(&mut st, 1.0).unwrap()
    });
    eprintln!("{rep}");
    assert!(rep.worst < tol, "{rep}");
}

#[test]
fn rigid_chain_tangents_match_fd() {
    // Rigid bodies only: every term of K is kinematic (G_r, C dV/dq, M dA/dq) or from the
    // rigid-body tangents. Tolerance 1e-6: central differences with h = 1e-6 of smooth maps of
    // unit size (errors ~1e-10) plus round-off of F / h (~1e-10 relative).
    let mut model = chain();
    model.gravity = Vector3::new(0.3, -9.81, 0.5);
    let n_last = mbs::NodeId(11);
    model.add_load(Load {
        node: n_last,
        kind: LoadKind::Force,
        axes: LoadAxes::Follower,
        value: Vector3::new(1.0, 2.0, 0.5),
        time: TimeFunction::constant(1.0),
    });
    let sys = System::new(&model).unwrap();
    let s = random_state(&sys, 11);
    check_tangents(&sys, &s, 1e-6, 1e-6);
}

#[test]
fn flexible_mixed_tangents_match_fd() {
    // The floating frames are re-solved to 1e-12 at each evaluation, so a difference quotient
    // with h = 1e-6 carries errors up to ~1e-6 of the largest entry; 1e-5 is the tolerance.
    let sys = System::new(&mixed()).unwrap();
    let mut s = random_state(&sys, 21);
    // Smaller motions for the flexible model: deformations of a few percent.
    let base = sys.initial_state();
    let n = sys.n_dof();
    let mut rng = superelement::testing::Rng::new(5);
    let dq: Vec<f64> = (0..n).map(|_| 0.05 * rng.uniform()).collect();
    let v = s.velocity().to_vec();
    let a = s.acceleration().to_vec();
    s = sys.retract(&base, &dq);
    s.velocity_mut().copy_from_slice(&v);
    s.acceleration_mut().copy_from_slice(&a);
    sys.reset_frames(&mut s);
    check_tangents(&sys, &s, 1e-6, 1e-5);
}

/// Loads at a load point inside a beam superelement (dead and follower force and moment, with
/// a time function): the assembled K against central differences on a deformed, rotated,
/// moving state.
#[test]
fn body_load_tangents_match_fd() {
    let mut settings = reduction::CbSettings::new(ModeSelection::Count(2));
    // `straight_beam` numbers the nodes from 0 along the beam in an empty model.
    settings.load_points = vec![("p".to_string(), fe_model::NodeId(3))];
    let (a, b) = (
        nalgebra::Point3::new(0.1, -0.2, 0.05),
        nalgebra::Point3::new(1.0, 0.3, 0.45),
    );
    let (_, _, body) = superelement::testing::fixtures::straight_beam_with(a, b, 8, settings, false);
    let mut model = Model::new("loaded beam");
    let na = model.add_node("a", a.coords);
    let nb = model.add_node("b", b.coords);
    let id = model.add_flexible_body(
        body,
        vec![na, nb],
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    model.add_support(Support::pin(na));
    for axes in [LoadAxes::Dead, LoadAxes::Follower] {
        model.body_loads.push(mbs::BodyLoad {
            body: id,
            point: 0,
            force: Vector3::new(30.0, -80.0, 20.0),
            moment: Vector3::new(-5.0, 4.0, 9.0),
            axes,
            time: TimeFunction::constant(0.7),
        });
    }
    let sys = System::new(&model).unwrap();
    let mut s = random_state(&sys, 31);
    let base = sys.initial_state();
    let n = sys.n_dof();
    let mut rng = superelement::testing::Rng::new(7);
    let dq: Vec<f64> = (0..n).map(|_| 0.1 * rng.uniform()).collect();
    let (v, acc) = (s.velocity().to_vec(), s.acceleration().to_vec());
    s = sys.retract(&base, &dq);
    s.velocity_mut().copy_from_slice(&v);
    s.acceleration_mut().copy_from_slice(&acc);
    sys.reset_frames(&mut s);
    // K only: the loads depend on the configuration alone (C and M of this stiff steel beam
    // are checked with unit steps by the superelement's tests). As in
    // `flexible_mixed_tangents_match_fd`: frames re-solved to 1e-12, h = 1e-6, tolerance 1e-5.
    let mats = sys.matrices(&mut s, 1.0).unwrap();
    let rep = check_jacobian("K = dF/dq", mats.K.as_ref(), &vec![1e-6; n], |d| {
        let mut st = sys.retract(&s, d);
        sys.residual(&mut st, 1.0).unwrap()
    });
    assert!(rep.worst < 1e-5, "{rep}");
    // Without the loads K changes: the check above saw them.
    let mut unloaded = model.clone();
    unloaded.body_loads.clear();
    let plain = System::new(&unloaded).unwrap().matrices(&mut s.clone(), 1.0).unwrap();
    let diff = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .map(|(i, j)| (mats.K[(i, j)] - plain.K[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(diff > 1.0, "the load tangent is missing ({diff})");
}
