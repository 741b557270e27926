//! Time functions, CSV tables and the serde round trip of a model.

use mbs::{Interpolation, Model, TimeFunction};

/// Rates and accelerations of every time function against central differences of its values.
#[test]
fn time_function_derivatives() {
    let fs = [
        TimeFunction::Linear {
            initial: 0.3,
            rate: 2.0,
        },
        TimeFunction::SmoothRamp {
            t_start: 0.1,
            t_end: 1.3,
            from: -1.0,
            to: 2.0,
        },
        TimeFunction::SpinUp {
            omega: 6.0,
            duration: 1.5,
        },
        TimeFunction::Sine {
            offset: 0.1,
            amplitude: 0.5,
            omega: 3.0,
            phase: 0.2,
        },
        TimeFunction::Table {
            times: vec![0.0, 0.4, 0.9, 1.5, 2.0],
            values: vec![0.0, 1.0, 0.5, 2.0, 1.0],
            interpolation: Interpolation::CubicSpline,
        },
    ];
    let mut m = Model::new("tf");
    for f in &fs {
        m.add_driver("d", mbs::DriverTarget::NodeRotation { node: mbs::NodeId(0) }, f.clone());
    }
    // Evaluate through a pendulum driven by each function: the driver's rate and acceleration
    // appear as the joint rate and the node's angular acceleration.
    for f in &fs {
        let (mut model, j) = crate::fixtures::pendulum(1.0, 1.0, 0.01);
        model.add_driver(
            "drive",
            mbs::DriverTarget::Joint {
                joint: j,
                coordinate: 0,
            },
            f.clone(),
        );
        let sys = mbs::System::new(&model).unwrap();
        for &t in &[0.05, 0.35, 0.7, 1.2, 1.45, 1.7, 2.5] {
            let mut s = sys.initial_state();
            let at = |t: f64, s: &mut mbs::State| {
                s.set_time(t);
                let m = sys.node_motions(s);
                (
                    sys.joint_value(
                        &{
                            let mut c = s.clone();
                            c.set_time(t);
                            c
                        },
                        j,
                        0,
                    ),
                    m[1].omega.z,
                    m[1].alpha.z,
                )
            };
            let h = 1e-5;
            let (_, w, al) = at(t, &mut s);
            let p = sys.node_motions(&{
                let mut c = s.clone();
                c.set_time(t + h);
                c
            });
            let q = sys.node_motions(&{
                let mut c = s.clone();
                c.set_time(t - h);
                c
            });
            let angle = |m: &mbs::NodeMotion| superelement::so3::log(&m.R).z;
            let w_fd = (angle(&p[1]) - angle(&q[1])) / (2.0 * h);
            let al_fd = (p[1].omega.z - q[1].omega.z) / (2.0 * h);
            // Central differences with h = 1e-5 of functions with third derivatives of order
            // 10-100: errors below 1e-7.
            assert!(
                (w - w_fd).abs() < 1e-6 * (1.0 + w.abs()),
                "{f:?} at {t}: rate {w} vs {w_fd}"
            );
            assert!(
                (al - al_fd).abs() < 1e-5 * (1.0 + al.abs()),
                "{f:?} at {t}: acceleration {al} vs {al_fd}"
            );
        }
    }
}

#[test]
fn csv_table() {
    let f = TimeFunction::table_from_csv("time,value\n# comment\n0, 1\n1; 3\n2 2\n", Interpolation::Linear).unwrap();
    assert_eq!(
        f,
        TimeFunction::Table {
            times: vec![0.0, 1.0, 2.0],
            values: vec![1.0, 3.0, 2.0],
            interpolation: Interpolation::Linear
        }
    );
    assert!(TimeFunction::table_from_csv("0,1\n0,2\n", Interpolation::Linear).is_err());
    assert!(TimeFunction::table_from_csv("0,1\nx,2\n", Interpolation::Linear).is_err());
}

#[test]
fn model_serde_round_trip() {
    let (model, _) = crate::fixtures::pendulum(1.0, 1.0, 0.01);
    let text = serde_json::to_string(&model).unwrap();
    let back: Model = serde_json::from_str(&text).unwrap();
    assert_eq!(model, back);
}
