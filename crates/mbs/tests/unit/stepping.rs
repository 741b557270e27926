//! An integrator that owns its system (`Integrator::new_owned`) and loads changed between
//! steps (`System::set_load_value`), for callers that step a simulation themselves.

use crate::fixtures::pendulum;
use mbs::{DynamicSettings, Integrator, Load, LoadAxes, LoadKind, Model, System, TimeFunction};
use nalgebra::Vector3;
use std::sync::Arc;

/// The fixture pendulum with a moment (dead or follower) on the hinge node.
fn loaded(axes: LoadAxes, mz: f64) -> Model {
    let (mut model, _) = pendulum(1.0, 1.0, 0.01);
    let hinge = model.nodes.iter().position(|n| n.name == "hinge").unwrap();
    model.add_load(Load {
        node: mbs::NodeId(hinge as u32),
        kind: LoadKind::Moment,
        axes,
        value: Vector3::new(0.0, 0.0, mz),
        time: TimeFunction::constant(1.0),
    });
    model
}

fn settings() -> DynamicSettings {
    DynamicSettings::new(1e-3, 0.05, 0.9)
}

/// The state after `n` steps, as numbers.
fn after(integ: &mut Integrator<'_>, n: usize) -> Vec<f64> {
    for _ in 0..n {
        integ.step().unwrap();
    }
    let (q, _) = integ.state().coordinates();
    let mut x = q.to_vec();
    x.extend_from_slice(integ.state().velocity());
    x
}

#[test]
fn an_owned_integrator_steps_exactly_like_a_borrowing_one() {
    let sys = System::new(&loaded(LoadAxes::Dead, 0.3)).unwrap();
    let mut borrowed = Integrator::new(&sys, sys.initial_state(), settings()).unwrap();
    assert!(borrowed.system_mut().is_none());
    let shared = Arc::new(sys.clone());
    let mut owned = Integrator::new_owned(shared, sys.initial_state(), settings()).unwrap();
    // The same arithmetic on the same system: equal to the bit.
    assert_eq!(after(&mut borrowed, 20), after(&mut owned, 20));
}

#[test]
fn a_load_value_set_on_the_system_equals_the_model_built_with_it() {
    for axes in [LoadAxes::Dead, LoadAxes::Follower] {
        let target = System::new(&loaded(axes, 0.3)).unwrap();
        let mut changed = System::new(&loaded(axes, 0.0)).unwrap();
        changed.set_load_value(0, Vector3::new(0.0, 0.0, 0.3)).unwrap();
        assert_eq!(changed.model().loads[0].value, Vector3::new(0.0, 0.0, 0.3));
        let mut a = Integrator::new(&target, target.initial_state(), settings()).unwrap();
        let mut b = Integrator::new(&changed, changed.initial_state(), settings()).unwrap();
        assert_eq!(after(&mut a, 10), after(&mut b, 10), "{axes:?}");
    }
    let mut sys = System::new(&loaded(LoadAxes::Dead, 0.0)).unwrap();
    assert!(sys.set_load_value(1, Vector3::zeros()).is_err());
    assert!(sys.set_load_value(0, Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
}

#[test]
fn a_load_changed_between_steps_acts_from_the_next_step() {
    let sys = Arc::new(System::new(&loaded(LoadAxes::Dead, 0.0)).unwrap());
    let mut still = Integrator::new_owned(Arc::clone(&sys), sys.initial_state(), settings()).unwrap();
    let mut pushed = Integrator::new_owned(sys.clone(), sys.initial_state(), settings()).unwrap();
    assert_eq!(after(&mut still, 5), after(&mut pushed, 5));
    // The pendulum hangs at rest: unpushed it stays there; a moment +z turns it to +theta.
    pushed
        .system_mut()
        .unwrap()
        .set_load_value(0, Vector3::new(0.0, 0.0, 0.1))
        .unwrap();
    // `make_mut` gave the pushed integrator its own copy: the other is unchanged.
    assert_eq!(still.system().model().loads[0].value, Vector3::zeros());
    let (a, b) = (after(&mut still, 10), after(&mut pushed, 10));
    // Round-off of a state at rest is below 1e-12 rad; 0.1 N m on 1.01 kg m^2 for 10 ms
    // turns it by about 5e-6 rad.
    // (The first coordinates are the clamped ground node's, zero in both.)
    assert!(a.iter().all(|x| x.abs() < 1e-12), "{a:?}");
    assert!(b.iter().any(|x| *x > 1e-6), "{b:?}");
}

/// `run_to` with fixed steps is the loop of `solve_dynamic`: the same steps, the same final
/// state to the bit, the callback after each step in order; a callback error stops it where it
/// is.
#[test]
fn streamed_steps_are_the_steps_of_solve_dynamic() {
    let sys = crate::fixtures::released(0.4);
    // 0.05 s in steps of 1e-3 s: 50 steps, though 0.05 / 1e-3 rounds to 50.000000000000004.
    let s = settings();
    let traj = mbs::solve_dynamic(&sys, sys.initial_state(), &s).unwrap();
    let mut integ = Integrator::new(&sys, sys.initial_state(), s.clone()).unwrap();
    assert_eq!(integ.steps_to(s.end_time), 50);
    // min_step = h: a failed step is not retried (there is none here).
    let fixed = mbs::Stepping::Fixed { min_step: s.step };
    let mut seen = Vec::new();
    let (totals, failure) = integ
        .run_to(s.end_time, &fixed, |done, i| -> Result<(), ()> {
            assert_eq!(done.time, i.state().time());
            assert_eq!(done.last, done.k == 50);
            assert_eq!(done.planned, Some(50));
            seen.push(done.k);
            Ok(())
        })
        .unwrap();
    assert!(failure.is_none());
    assert_eq!(seen, (1..=50).collect::<Vec<_>>());
    assert_eq!((totals.steps, totals.planned), (50, Some(50)));
    assert!(totals.retries.is_empty());
    assert_eq!(totals.iterations, traj.iterations.iter().sum::<usize>());
    assert_eq!(totals.max_iterations, *traj.iterations.iter().max().unwrap());
    // Steps of 1e-3 s to the round-off of the times they join.
    assert!((totals.smallest_step - s.step).abs() < 1e-15 && (totals.largest_step - s.step).abs() < 1e-15);
    assert_eq!(integ.state().coordinates().0, traj.final_state.coordinates().0);
    assert_eq!(integ.state().velocity(), traj.final_state.velocity());

    let mut integ = Integrator::new(&sys, sys.initial_state(), s.clone()).unwrap();
    let stopped = integ.run_to(
        s.end_time,
        &fixed,
        |done, _| if done.k == 7 { Err(done.k) } else { Ok(()) },
    );
    let stopped = stopped.unwrap_err();
    assert_eq!((stopped.error, stopped.totals.steps), (7, 7));
    assert_eq!(integ.steps(), 7);
}

/// Adaptive streaming lands on the end time, and its last step says so.
#[test]
fn adaptive_streamed_steps_land_on_the_end_time() {
    let sys = crate::fixtures::released(0.4);
    let s = settings();
    let mut integ = Integrator::new(&sys, sys.initial_state(), s.clone()).unwrap();
    let adaptive = mbs::Stepping::Adaptive(mbs::AdaptiveSettings::new(1e-4, 1e-6, 1e-2));
    let mut last = Vec::new();
    let (totals, failure) = integ
        .run_to(s.end_time, &adaptive, |done, _| -> Result<(), ()> {
            assert_eq!(done.planned, None);
            last.push(done.last);
            Ok(())
        })
        .unwrap();
    assert!(failure.is_none());
    assert_eq!(totals.steps, last.len());
    // Only the final step is the last.
    assert_eq!(last.iter().filter(|l| **l).count(), 1);
    assert_eq!(last.last(), Some(&true));
    // On the end time to the round-off of summed steps.
    assert!(
        (integ.state().time() - s.end_time).abs() < 1e-12,
        "{}",
        integ.state().time()
    );
    assert!(totals.smallest_step <= totals.largest_step);
}

/// The fixed steps land on the end time: t_end = 0.25 s with h = 0.1 s takes steps of 0.1,
/// 0.1 and 0.05 s and records t = 0.25 last (it ran a third full step to 0.3 s before); an end
/// within round-off of a multiple of h adds no sliver.
#[test]
fn fixed_steps_end_exactly_at_the_end_time() {
    assert_eq!(mbs::fixed_steps(0.0, 0.25, 0.1).0, 3);
    assert!((mbs::fixed_steps(0.0, 0.25, 0.1).1 - 0.05).abs() < 1e-15);
    // 0.3 / 0.1 = 2.9999999999999996 in floating point: three full steps, no sliver.
    let (n, last) = mbs::fixed_steps(0.0, 0.3, 0.1);
    assert!(n == 3 && (last - 0.1).abs() < 1e-12, "{n} {last}");
    let (model, _) = pendulum(1.0, 1.0, 0.01);
    let sys = System::new(&model).unwrap();
    for solve in [0, 1] {
        let settings = DynamicSettings::new(0.1, 0.25, 0.9);
        let traj = if solve == 0 {
            mbs::solve_dynamic(&sys, sys.initial_state(), &settings).unwrap()
        } else {
            mbs::solve_dynamic_retrying(&sys, sys.initial_state(), &settings, 0.01)
                .unwrap()
                .trajectory
        };
        assert_eq!(
            traj.sensors.times.last().copied(),
            Some(0.25),
            "{:?}",
            traj.sensors.times
        );
        assert_eq!(traj.final_state.time(), 0.25);
        assert_eq!(traj.iterations.len(), 3);
    }
    // Streaming takes the same steps, and leaves the step size at h for a run continued on.
    let settings = DynamicSettings::new(0.1, 0.25, 0.9);
    let mut integ = mbs::Integrator::new(&sys, sys.initial_state(), settings).unwrap();
    assert_eq!(integ.steps_to(0.25), 3);
    let mut seen = Vec::new();
    let (totals, failure) = integ
        .run_to(
            0.25,
            &mbs::Stepping::Fixed { min_step: 0.01 },
            |done, _| -> Result<(), ()> {
                seen.push((done.time, done.last));
                Ok(())
            },
        )
        .unwrap();
    assert!(failure.is_none());
    assert_eq!((totals.steps, totals.planned), (3, Some(3)));
    assert_eq!(seen.last(), Some(&(0.25, true)));
    // The shortened last step is the smallest, 0.05 s to the round-off of the times it joins.
    assert!((totals.smallest_step - 0.05).abs() < 1e-15, "{}", totals.smallest_step);
    assert_eq!(integ.step_size(), 0.1);
}

/// A sensor that reads a value that is not finite stops the run with an error naming the
/// sensor, the time and the step, and keeps the rows before it: node b, driven along x at
/// 10 m/s from 1 m before node a, reaches a at t = 0.1 s (step 10), where the distance from
/// the line a-b is 0/0.
#[test]
fn a_sensor_that_is_not_finite_stops_the_run_where_it_happened() {
    let (mut model, _) = pendulum(1.0, 1.0, 0.01);
    let hinge = mbs::NodeId(1);
    let a = model.add_node("a", Vector3::new(0.0, 2.0, 0.0));
    let b = model.add_node("b", Vector3::new(-1.0, 2.0, 0.0));
    model.add_support(mbs::Support::clamp(a));
    model.add_support(mbs::Support {
        node: b,
        translation: mbs::TranslationSupport::Components {
            fixed: [false, true, true],
        },
        rotation: mbs::RotationSupport::Fixed,
    });
    model.add_driver(
        "b along x",
        mbs::DriverTarget::NodeTranslation { node: b, component: 0 },
        TimeFunction::Linear {
            initial: 0.0,
            rate: 10.0,
        },
    );
    model.add_sensor(
        "chord",
        mbs::SensorKind::LineDistance {
            node: hinge,
            a,
            b,
            normal: None,
        },
    );
    let sys = System::new(&model).unwrap();
    let fail = mbs::solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(0.01, 0.2, 0.9)).unwrap_err();
    match &fail.error {
        mbs::SolveError::NonFiniteSensor {
            sensor,
            index,
            at: mbs::At::Time(t),
            step,
            ..
        } => {
            assert_eq!((sensor.as_str(), *index, *step), ("chord", 0, 10));
            assert_eq!(fail.error.entity(), Some(mbs::Entity::Sensor(0)));
            assert!((t - 0.1).abs() < 1e-12, "{t}");
        }
        e => panic!("{e}"),
    }
    let msg = fail.error.to_string();
    assert!(
        msg.contains("sensor 'chord'") && msg.contains("t = 0.100000") && msg.contains("step 10"),
        "{msg}"
    );
    // The rows of t = 0 .. 0.09 are finite and kept, the offending one is the last.
    let times = &fail.partial.sensors.times;
    assert_eq!(times.len(), 11);
    assert!(fail.partial.sensors.rows[..10]
        .iter()
        .all(|r| r.iter().all(|x| x.is_finite())));
}
