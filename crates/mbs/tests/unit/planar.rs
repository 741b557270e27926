//! Planar flexible bodies (`FlexibleBody::planar`): the slider-crank of validation problem C2
//! with its rod reduced as a planar part agrees with the same mechanism evaluated in 3D, and a
//! planar body whose node can leave the plane is refused with the node and the reason named.

use mbs::{
    solve_dynamic, Body, DynamicSettings, JointKind, Model, ModelError, RotationSupport, Support, System,
    TranslationSupport,
};
use models::{RodModel, Variant};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use reduction::{CbSettings, ModeSelection};

/// The C2 slider-crank with the rod as `n` beam segments reduced planar with 2 modes (so
/// both are in-plane bending modes), the nodes between the segments supported to the plane,
/// evaluated in the plane when `planar` (else the same bodies evaluated in 3D).
fn c2(n: usize, planar: bool) -> (Model, Vec<mbs::NodeId>) {
    let settings = CbSettings {
        planar: true,
        geometric_stiffening: true,
        ..CbSettings::new(ModeSelection::Count(2))
    };
    let v = Variant::REFERENCE;
    let segment = models::rod_segment(&models::RodSegment {
        rod: RodModel::Beam { elements: 4 },
        seg: models::ROD / n as f64,
        settings,
        frame: v.frame,
    })
    .unwrap();
    let mut sc = models::slider_crank_planar(&models::SliderCrankPlanar::of_segment(n, &segment, 150.0, v)).unwrap();
    models::confine_to_plane(&mut sc.model);
    if !planar {
        for body in &mut sc.model.bodies {
            if let Body::Flexible(f) = body {
                f.planar = false;
            }
        }
    }
    (sc.model, sc.rod_nodes)
}

fn error(model: &Model) -> ModelError {
    match System::new(model) {
        Ok(_) => panic!("model accepted"),
        Err(e) => {
            eprintln!("{e}");
            e
        }
    }
}

/// Half a crank revolution at 150 rad/s, h = T/400: the planar evaluation is the in-plane
/// block of the 3D one on the same coordinates (the out-of-plane ones supported), so Newton
/// takes the same iterations and the two runs agree to round-off (measured: 3e-16 m on a
/// peak of 4.6e-3 m); asserted to 1e-9 of the peak, far below the Newton tolerance.
#[test]
fn the_planar_slider_crank_agrees_with_the_same_mechanism_in_3d() {
    let period = 2.0 * std::f64::consts::PI / 150.0;
    let run = |planar: bool| {
        let (model, _) = c2(2, planar);
        let sys = System::new(&model).unwrap();
        let settings = DynamicSettings::new(period / 400.0, period / 2.0, 0.9);
        let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
        (
            traj.sensors.column("midpoint", 0).unwrap(),
            traj.sensors.column("slider", 0).unwrap(),
        )
    };
    let (w2, x2) = run(true);
    let (w3, x3) = run(false);
    let peak = w3.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    assert!(peak > 1e-4, "{peak}");
    let dw = w2.iter().zip(&w3).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let dx = x2.iter().zip(&x3).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!("planar against 3D: midpoint {dw:.3e} m of {peak:.3e} m, slider {dx:.3e} m");
    assert!(dw < 1e-9 * peak, "midpoint {dw:.3e} of {peak:.3e}");
    // The slider follows the crank and the rod's ends, rigid-body kinematics of about 0.1 m
    // equal to round-off (measured 3e-16 m): 1e-12 m.
    assert!(dx < 1e-12, "slider {dx:.3e}");
}

#[test]
fn a_planar_body_whose_node_can_leave_the_plane_is_refused_by_name() {
    // The node between the segments without its support: free in z.
    let (mut model, rod) = c2(2, true);
    model.supports.retain(|s| s.node != rod[1]);
    let e = error(&model);
    assert!(matches!(e, ModelError::LeavesPlane { .. }), "{e:?}");
    let e = e.to_string();
    assert!(
        e.contains("'rod0'") && e.contains("'rod1'") && e.contains("neither supported"),
        "{e}"
    );

    // Supported in a plane, but free to tilt.
    let (mut model, rod) = c2(2, true);
    for s in &mut model.supports {
        if s.node == rod[1] {
            s.rotation = RotationSupport::Free;
        }
    }
    let e = error(&model).to_string();
    assert!(e.contains("'rod1'") && e.contains("rotations about x and y"), "{e}");

    // Supported on a plane that is not the xy-plane.
    let (mut model, rod) = c2(2, true);
    for s in &mut model.supports {
        if s.node == rod[1] {
            s.translation = TranslationSupport::Plane { normal: Vector3::y() };
        }
    }
    let e = error(&model).to_string();
    assert!(e.contains("'rod1'") && e.contains("translation along z"), "{e}");

    // The rod hung on the crank by a spherical joint: the crank is confined, the joint is not.
    let (mut model, rod) = c2(2, true);
    let pin = model.joints.iter().position(|j| j.child == rod[0]).unwrap();
    model.joints[pin].kind = JointKind::Spherical;
    let e = error(&model).to_string();
    assert!(e.contains("'rod0'") && e.contains("spherical joint 'pin A'"), "{e}");

    // The crank's pivot turned about x: the rod's end follows a crank that leaves the plane.
    let (mut model, rod) = c2(2, true);
    let crank = model.joints.iter().position(|j| j.name == "crank").unwrap();
    model.joints[crank].kind = JointKind::Revolute { axis: Vector3::x() };
    let e = error(&model).to_string();
    assert!(
        e.contains("'rod0'") && e.contains("joint 'crank'") && e.contains("follows joint 'pin A'"),
        "{e}"
    );
    let _ = rod;

    // A placement that tilts the FE xy-plane.
    let (mut model, _) = c2(2, true);
    if let Body::Flexible(f) = &mut model.bodies[1] {
        let shift = f.placement.translation;
        f.placement = Isometry3::from_parts(shift, UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.1));
    }
    let e = error(&model).to_string();
    assert!(e.contains("'rod0'") && e.contains("rotation about z"), "{e}");

    // The same supports as a clamp are accepted by the check (the kernel decides the rest).
    let (mut model, rod) = c2(2, true);
    for s in &mut model.supports {
        if s.node == rod[1] {
            *s = Support::clamp(rod[1]);
        }
    }
    assert!(!matches!(System::new(&model), Err(ModelError::LeavesPlane { .. })));
}
