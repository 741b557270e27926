//! Stresses from a multibody state: the axial force of a beam in a steady spin against the
//! centrifugal formula, through the section forces recovered from the beam superelements'
//! stress shapes.
//!
//! A steel rod ($E$ = 210 GPa, $\rho$ = 7850 kg/m³, square 20 mm, $L$ = 1 m) clamped at hub
//! radius $R$ = 0.2 m to a light rigid hub on the $z$ axis, spun up smoothly to $\Omega$ = 30
//! rad/s (the C1 profile over 1 s, 16 periods of the first bending mode) and held at that
//! speed, with stiffness-proportional damping so that the bending left by the spin-up dies
//! out. The rod is 8 superelements of one element each with both nodes as interfaces (no
//! internal dofs: each is its beam element exactly, consistent mass included). In the steady
//! spin the axial force is
//! $$N(r) = \tfrac12\rho A\Omega^2\big[(R + L)^2 - r^2\big],\qquad R \le r \le R + L,$$
//! and a two-node element, nodally exact for a bar under its consistent loads, carries the
//! mean of $N$ over its length, $\tfrac12\rho A\Omega^2[(R + L)^2 - (r_1^2 + r_1r_2 + r_2^2)/3]$.

use mbs::{solve_dynamic, DriverTarget, DynamicSettings, Model, RigidBody, Support, System, TimeFunction};
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use reduction::{CbSettings, ModeSelection};
use superelement::{Damping, FrameChoice, MassVariant};

#[test]
fn a_spinning_beam_carries_the_centrifugal_axial_force() {
    let (E, rho, b) = (210e9, 7850.0, 0.02);
    let (R, L, n, omega) = (0.2, 1.0, 8, 30.0);
    let A = b * b;
    let seg = L / n as f64;
    let mut fe = fe_model::FeModel::default();
    let material = fe.add_material(fe_model::IsotropicMaterial::new("steel", E, 0.3, rho).unwrap());
    let section = fe.add_section(fe_model::BeamSection::rectangle("rod", b, b, 0.3).unwrap());
    let props = fe_model::BeamProperties {
        section,
        material,
        orientation: Vector3::y(),
        theory: fe_model::BeamTheory::EulerBernoulli,
        mass: fe_model::MassKind::Consistent,
    };
    let nodes =
        fe_model::generate::straight_beam(&mut fe, Point3::origin(), Point3::new(seg, 0.0, 0.0), 1, &props, None)
            .unwrap();
    let mut settings = CbSettings::new(ModeSelection::StaticOnly);
    settings.stress_shapes = true;
    let body = reduction::reduce(&fe, "seg", &[("a".into(), nodes[0]), ("b".into(), nodes[1])], &settings).unwrap();

    let mut m = Model::new("spinning rod");
    let hub = m.add_node("hub", Vector3::zeros());
    let rod: Vec<_> = (0..=n)
        .map(|i| m.add_node(&format!("r{i}"), Vector3::new(R + seg * i as f64, 0.0, 0.0)))
        .collect();
    m.add_rigid_body(RigidBody {
        name: "hub".into(),
        reference: hub,
        nodes: vec![rod[0]],
        mass: 1e-3,
        center_of_mass: Vector3::zeros(),
        inertia: Matrix3::identity() * 1e-6,
    });
    for i in 0..n {
        let mut b = body.clone();
        b.name = format!("seg{i}");
        m.add_flexible_body(
            b,
            vec![rod[i], rod[i + 1]],
            Isometry3::translation(R + seg * i as f64, 0.0, 0.0),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
    }
    // beta = 0.02 s: about critical damping of the first bending mode (105 rad/s), so the
    // bending left by the spin-up is gone after the hold; no damping force in a steady spin.
    for b in m.bodies.iter_mut() {
        if let mbs::Body::Flexible(f) = b {
            f.damping = Damping::rayleigh(0.0, 0.02);
        }
    }
    m.add_support(Support::hinge(hub, Vector3::z()));
    m.add_driver(
        "spin",
        DriverTarget::NodeRotation { node: hub },
        TimeFunction::SpinUp { omega, duration: 1.0 },
    );
    let sys = System::new(&m).unwrap();
    let traj = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(1e-3, 2.0, 0.8)).unwrap();
    let state = traj.final_state;
    let mut worst: f64 = 0.0;
    let N_hub = 0.5 * rho * A * omega * omega * ((R + L).powi(2) - R * R);
    for i in 0..n {
        let id = mbs::BodyId(1 + i as u32);
        let se = sys.superelement(id).unwrap();
        let kin = se.kinematics(&sys.flexible_body_state(id, &state).unwrap()).unwrap();
        let forces = se.recover_stress(&kin.q_jj).unwrap().beams[0];
        let (r1, r2) = (R + seg * i as f64, R + seg * (i + 1) as f64);
        let exact = 0.5 * rho * A * omega * omega * ((R + L).powi(2) - (r1 * r1 + r1 * r2 + r2 * r2) / 3.0);
        for end in forces {
            worst = worst.max((end[0] - exact).abs() / N_hub);
        }
    }
    // What is left is the time discretisation of the steady rotation: generalized-alpha turns
    // the rod by h Omega = 0.03 rad a step, and its discrete centripetal acceleration differs
    // from the continuous one by O((h Omega)^2) ~ 1e-3 (measured 5.2e-4 at h = 1 ms, 2.1e-3 at
    // 2 ms); the stretch (u/L ~ N/(EA) = 2e-5) and the damped bending of the spin-up are far
    // smaller.
    assert!(
        worst < 1e-3,
        "largest error of the axial force, relative to N(R) = {N_hub:.1} N: {worst:.3e}"
    );
}

/// A largest-von-Mises sensor over every node of a solid body: `solve_dynamic` finds its
/// values a batch of output rows at a time (`Integrator::record_deferred`), the same rows to
/// the bit as recording each row alone (`Integrator::record`, one bounded search per row),
/// over 150 rows (two whole batches and a partial one). A clamped hex8 bar, 4 modes, a step
/// force at its tip.
#[test]
fn largest_von_mises_rows_found_in_batches_equal_rows_found_one_by_one() {
    let (fe, [root, tip]) = models::steel_bar([10, 2, 2]).unwrap();
    let mut settings = CbSettings::new(ModeSelection::Count(4));
    settings.stress_shapes = true;
    let body = reduction::reduce(&fe, "bar", &[("root".into(), root), ("tip".into(), tip)], &settings).unwrap();
    let count = body.stress.as_ref().unwrap().node_count();
    let (mut m, b, ids) = models::clamped_with_tip_force(&body, Vector3::new(0.0, 2e3, -1e4));
    m.add_sensor("tip", mbs::SensorKind::NodeDisplacement { node: ids[1] });
    m.add_sensor(
        "hot",
        mbs::SensorKind::MaxVonMises {
            body: b,
            nodes: (0..count).collect(),
        },
    );
    let sys = System::new(&m).unwrap();
    let settings = DynamicSettings::new(1e-4, 0.015, 0.9);
    let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
    let mut integ = mbs::Integrator::new(&sys, sys.initial_state(), settings).unwrap();
    let mut one_by_one = sys.sensor_record();
    integ.record(&mut one_by_one).unwrap();
    for _ in 0..150 {
        integ.step().unwrap();
        integ.record(&mut one_by_one).unwrap();
    }
    assert_eq!(traj.sensors.rows.len(), 151);
    assert_eq!(traj.sensors.times, one_by_one.times);
    for (k, (a, b)) in traj.sensors.rows.iter().zip(&one_by_one.rows).enumerate() {
        let bits = |r: &[f64]| r.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(a), bits(b), "row {k}: {a:?} against {b:?}");
    }
    let peak = traj.sensors.rows.iter().map(|r| r[3]).fold(0.0, f64::max);
    assert!(peak > 1e6, "{peak}");
}
