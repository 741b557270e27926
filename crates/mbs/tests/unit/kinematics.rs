//! Central differences of the kinematic maps (coordinates.rs `# Derivatives for Newton`).

use crate::fixtures::rigid;
use faer::Mat;
use mbs::{DriverTarget, JointKind, Model, RotationSupport, State, Support, System, TimeFunction, TranslationSupport};
use nalgebra::{UnitQuaternion, Vector3};
use superelement::so3;
use superelement::testing::{check_jacobian, Rng};

/// A chain with every joint kind: a free root carrying a rigid body, revolute, prismatic,
/// universal, spherical, cylindrical and planar joints between rigid bodies; plus a slider
/// with a driven rotation axis and a driven revolute joint on it.
pub fn chain() -> Model {
    let mut m = Model::new("chain");
    let q = |x: f64, y: f64, z: f64, a: f64| UnitQuaternion::from_scaled_axis(Vector3::new(x, y, z).normalize() * a);
    let n0 = m.add_node_oriented("n0", Vector3::new(0.1, 0.2, 0.3), q(0.2, 1.0, -0.3, 0.7));
    let n1 = m.add_node_oriented("n1", Vector3::new(0.6, 0.1, 0.4), q(1.0, 0.0, 0.2, 0.3));
    let n2 = m.add_node_oriented("n2", Vector3::new(0.6, 0.1, 0.4), q(0.0, 1.0, 0.5, -0.4));
    let n3 = m.add_node("n3", Vector3::new(0.9, -0.3, 0.5));
    let n4 = m.add_node("n4", Vector3::new(1.1, -0.2, 0.7));
    let n5 = m.add_node_oriented("n5", Vector3::new(1.1, -0.2, 0.7), q(0.3, 0.3, 1.0, 1.1));
    let n6 = m.add_node("n6", Vector3::new(1.4, 0.2, 0.6));
    let n7 = m.add_node_oriented("n7", Vector3::new(1.4, 0.2, 0.6), q(1.0, -1.0, 0.0, 0.5));
    let n8 = m.add_node("n8", Vector3::new(1.7, 0.4, 0.3));
    let n9 = m.add_node("n9", Vector3::new(1.7, 0.4, 0.3));
    let n10 = m.add_node("n10", Vector3::new(1.9, 0.5, 0.1));
    let n11 = m.add_node("n11", Vector3::new(2.3, 0.6, -0.2));
    let s0 = m.add_node("s0", Vector3::new(-0.5, 0.3, 0.0));
    let s1 = m.add_node("s1", Vector3::new(-0.5, 0.3, 0.0));
    m.add_rigid_body(rigid(
        "b0",
        n0,
        vec![n1],
        2.0,
        Vector3::new(0.1, 0.0, 0.05),
        [0.1, 0.2, 0.15],
    ));
    m.add_joint(
        "rev",
        n1,
        n2,
        JointKind::Revolute {
            axis: Vector3::new(0.3, 0.2, 1.0),
        },
    );
    m.add_rigid_body(rigid(
        "b1",
        n2,
        vec![n3],
        1.5,
        Vector3::new(0.0, 0.1, 0.0),
        [0.1, 0.1, 0.2],
    ));
    m.add_joint(
        "pri",
        n3,
        n4,
        JointKind::Prismatic {
            axis: Vector3::new(1.0, 0.5, 0.2),
        },
    );
    m.add_rigid_body(rigid(
        "b2",
        n4,
        vec![],
        1.0,
        Vector3::new(0.05, 0.0, 0.1),
        [0.05, 0.06, 0.07],
    ));
    m.add_joint(
        "uni",
        n4,
        n5,
        JointKind::Universal {
            axis1: Vector3::new(1.0, 0.0, 0.2),
            axis2: Vector3::new(0.1, 1.0, 0.3),
        },
    );
    m.add_rigid_body(rigid(
        "b3",
        n5,
        vec![n6],
        1.2,
        Vector3::new(0.0, 0.0, 0.1),
        [0.08, 0.09, 0.05],
    ));
    m.add_joint("sph", n6, n7, JointKind::Spherical);
    m.add_rigid_body(rigid(
        "b4",
        n7,
        vec![n8],
        0.9,
        Vector3::new(0.1, 0.1, 0.0),
        [0.04, 0.05, 0.06],
    ));
    m.add_joint(
        "cyl",
        n8,
        n9,
        JointKind::Cylindrical {
            axis: Vector3::new(0.2, -0.4, 1.0),
        },
    );
    m.add_rigid_body(rigid(
        "b5",
        n9,
        vec![n10],
        0.8,
        Vector3::new(0.0, 0.05, 0.05),
        [0.03, 0.04, 0.05],
    ));
    m.add_joint(
        "pla",
        n10,
        n11,
        JointKind::Planar {
            normal: Vector3::new(0.5, 0.5, 1.0),
        },
    );
    m.add_rigid_body(rigid(
        "b6",
        n11,
        vec![],
        0.7,
        Vector3::new(0.02, 0.0, 0.03),
        [0.02, 0.03, 0.04],
    ));
    // Slider along a line with a rotation axis driven in time, and a driven revolute on it.
    m.add_support(Support {
        node: s0,
        translation: TranslationSupport::Line {
            direction: Vector3::new(1.0, 1.0, 0.0),
        },
        rotation: RotationSupport::Axis {
            axis: Vector3::new(0.0, 0.3, 1.0),
        },
    });
    m.add_driver(
        "spin",
        DriverTarget::NodeRotation { node: s0 },
        TimeFunction::Sine {
            offset: 0.1,
            amplitude: 0.4,
            omega: 3.0,
            phase: 0.2,
        },
    );
    m.add_joint(
        "drv",
        s0,
        s1,
        JointKind::Revolute {
            axis: Vector3::new(1.0, 0.0, 0.0),
        },
    );
    let j = mbs::JointId(m.joints.len() as u32 - 1);
    m.add_driver(
        "tilt",
        DriverTarget::Joint {
            joint: j,
            coordinate: 0,
        },
        TimeFunction::Sine {
            offset: 0.0,
            amplitude: 0.3,
            omega: 2.0,
            phase: 0.5,
        },
    );
    m.add_rigid_body(rigid("slider", s0, vec![], 1.0, Vector3::zeros(), [0.1, 0.1, 0.1]));
    m.add_rigid_body(rigid(
        "arm",
        s1,
        vec![],
        1.0,
        Vector3::new(0.0, 0.2, 0.0),
        [0.1, 0.1, 0.1],
    ));
    m
}

/// A moved, moving state: every unknown coordinate, rate and acceleration random.
pub fn random_state(sys: &System, seed: u64) -> State {
    let mut rng = Rng::new(seed);
    let mut s = sys.initial_state();
    s.set_time(0.37);
    let n = sys.n_dof();
    let dq: Vec<f64> = (0..n).map(|_| 0.6 * rng.uniform()).collect();
    s = sys.retract(&s, &dq);
    for i in 0..n {
        s.velocity_mut()[i] = 2.0 * rng.uniform();
        s.acceleration_mut()[i] = 5.0 * rng.uniform();
    }
    s
}

/// Node configurations stacked: [r, log(R R_base^T)] per node.
fn configuration(sys: &System, s: &State, base: &[mbs::NodeMotion]) -> Vec<f64> {
    let m = sys.node_motions(s);
    let mut out = Vec::new();
    for (a, b) in m.iter().zip(base) {
        out.extend_from_slice(a.r.as_slice());
        out.extend_from_slice(so3::log(&(a.R * b.R.inverse())).as_slice());
    }
    out
}

fn stack(sys: &System, s: &State, f: impl Fn(&mbs::NodeKinematics) -> Mat<f64>) -> Mat<f64> {
    let k = sys.node_kinematics(s);
    let n = sys.n_dof();
    let mut A = Mat::zeros(6 * k.len(), n);
    for (c, nk) in k.iter().enumerate() {
        let B = f(nk);
        for (j, &d) in nk.dofs.iter().enumerate() {
            for i in 0..6 {
                A[(6 * c + i, d)] += B[(i, j)];
            }
        }
    }
    A
}

fn motion_vector(sys: &System, s: &State, acc: bool) -> Vec<f64> {
    let mut out = Vec::new();
    for m in sys.node_motions(s) {
        if acc {
            out.extend_from_slice(m.a.as_slice());
            out.extend_from_slice(m.alpha.as_slice());
        } else {
            out.extend_from_slice(m.v.as_slice());
            out.extend_from_slice(m.omega.as_slice());
        }
    }
    out
}

/// Worst relative error allowed: central differences with steps 1e-6 have truncation
/// errors ~1e-12 times third derivatives of order one here, and round-off ~1e-16/1e-6; 1e-7
/// leaves two orders of margin over what the checks measure.
const TOL: f64 = 1e-7;

#[test]
fn jacobian_is_the_derivative_of_the_node_configurations() {
    let sys = System::new(&chain()).unwrap();
    let s = random_state(&sys, 1);
    let base = sys.node_motions(&s);
    let J = stack(&sys, &s, |k| k.J.clone());
    let n = sys.n_dof();
    let rep = check_jacobian("J", J.as_ref(), &vec![1e-6; n], |d| {
        configuration(&sys, &sys.retract(&s, d), &base)
    });
    eprintln!("{rep}");
    assert!(rep.worst < TOL, "{rep}");
}

#[test]
fn velocity_and_convective_acceleration_are_time_derivatives() {
    // Along q(t + tau) = q + tau qd + tau^2/2 qdd (rotations through exp, spatial), the node
    // configuration changes at V and V at A = J qdd + Jdot qd (+ driver terms).
    let sys = System::new(&chain()).unwrap();
    let s = random_state(&sys, 2);
    let n = sys.n_dof();
    let at = |tau: f64| {
        let dq: Vec<f64> = (0..n)
            .map(|i| tau * s.velocity()[i] + 0.5 * tau * tau * s.acceleration()[i])
            .collect();
        let mut st = sys.retract(&s, &dq);
        st.set_time(s.time() + tau);
        for i in 0..n {
            st.velocity_mut()[i] = s.velocity()[i] + tau * s.acceleration()[i];
        }
        st
    };
    let base = sys.node_motions(&s);
    let V = motion_vector(&sys, &s, false);
    let A = motion_vector(&sys, &s, true);
    let Vm = Mat::from_fn(V.len(), 1, |i, _| V[i]);
    let Am = Mat::from_fn(A.len(), 1, |i, _| A[i]);
    let rep = check_jacobian("V = d(config)/dt", Vm.as_ref(), &[1e-5], |d| {
        configuration(&sys, &at(d[0]), &base)
    });
    eprintln!("{rep}");
    assert!(rep.worst < 1e-6, "{rep}");
    let rep = check_jacobian("A = dV/dt", Am.as_ref(), &[1e-5], |d| {
        motion_vector(&sys, &at(d[0]), false)
    });
    eprintln!("{rep}");
    assert!(rep.worst < 1e-6, "{rep}");
    // The convective term alone: with qdd = 0 and no drivers moving, A = Jdot qd.
    let mut s0 = s.clone();
    s0.acceleration_mut().iter_mut().for_each(|a| *a = 0.0);
    let a0 = motion_vector(&sys, &s0, true);
    let J = stack(&sys, &s, |k| k.J.clone());
    let a1: Vec<f64> = (0..A.len())
        .map(|i| A[i] - (0..n).map(|j| J[(i, j)] * s.acceleration()[j]).sum::<f64>())
        .collect();
    let scale = a0.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for i in 0..a0.len() {
        assert!(
            (a0[i] - a1[i]).abs() < 1e-12 * scale,
            "A - J qdd differs from the convective term at {i}"
        );
    }
}

#[test]
fn derivatives_of_velocity_and_acceleration_match_fd() {
    let sys = System::new(&chain()).unwrap();
    let s = random_state(&sys, 3);
    let n = sys.n_dof();
    let DV = stack(&sys, &s, |k| k.DV.clone());
    let DA = stack(&sys, &s, |k| k.DA.clone());
    let DAd = stack(&sys, &s, |k| k.DAd.clone());
    let J = stack(&sys, &s, |k| k.J.clone());
    let h = vec![1e-6; n];
    let rep = check_jacobian("dV/dq", DV.as_ref(), &h, |d| {
        motion_vector(&sys, &sys.retract(&s, d), false)
    });
    eprintln!("{rep}");
    assert!(rep.worst < TOL, "{rep}");
    let rep = check_jacobian("dA/dq", DA.as_ref(), &h, |d| {
        motion_vector(&sys, &sys.retract(&s, d), true)
    });
    eprintln!("{rep}");
    assert!(rep.worst < TOL, "{rep}");
    let with_rates = |d: &[f64]| {
        let mut st = s.clone();
        for i in 0..n {
            st.velocity_mut()[i] += d[i];
        }
        st
    };
    let rep = check_jacobian("dA/dqd", DAd.as_ref(), &h, |d| {
        motion_vector(&sys, &with_rates(d), true)
    });
    eprintln!("{rep}");
    assert!(rep.worst < TOL, "{rep}");
    let rep = check_jacobian("dV/dqd = J", J.as_ref(), &h, |d| {
        motion_vector(&sys, &with_rates(d), false)
    });
    eprintln!("{rep}");
    assert!(rep.worst < TOL, "{rep}");
}

#[test]
fn geometric_term_matches_fd() {
    let sys = System::new(&chain()).unwrap();
    let s = random_state(&sys, 4);
    let mut rng = Rng::new(9);
    let forces: Vec<[f64; 6]> = (0..sys.model().nodes.len())
        .map(|_| std::array::from_fn(|_| 10.0 * rng.uniform()))
        .collect();
    let (_, G) = sys.generalized_force(&s, &forces);
    let n = sys.n_dof();
    let rep = check_jacobian("G_r", G.as_ref(), &vec![1e-6; n], |d| {
        sys.generalized_force(&sys.retract(&s, d), &forces).0
    });
    eprintln!("{rep}");
    assert!(rep.worst < TOL, "{rep}");
}
