//! Runs of the integrator from a start to an end time, recording the sensors: fixed steps
//! ([`solve_dynamic`]) and adaptive steps ([`solve_dynamic_adaptive`]), and the start and end
//! of a run that the retrying run shares.

use super::integrator::{fixed_steps, last_step_size, step_adaptive_to, AdaptiveSettings, DynamicSettings, Integrator};
use crate::assembly::system::sensors::{PendingRows, SensorRecord};
use crate::assembly::system::System;
use crate::error::{Incomplete, SolveError};
use crate::state::State;

/// Result of [`solve_dynamic`].
#[derive(Clone, Debug)]
pub struct Trajectory {
    pub sensors: SensorRecord,
    /// Newton iterations of each step.
    pub iterations: Vec<usize>,
    /// Iteration matrices factorised in each step ([`StepReport::jacobians`](crate::StepReport::jacobians)).
    pub jacobians: Vec<usize>,
    pub final_state: State,
}

/// The integrator at `start` (consistent accelerations) and a trajectory holding its first
/// sensor row: the common start of [`solve_dynamic`] and [`solve_dynamic_adaptive`].
pub(crate) fn start_trajectory<'a>(
    system: &'a System,
    start: State,
    settings: &DynamicSettings,
) -> Result<(Integrator<'a>, Trajectory), Box<Incomplete<Trajectory>>> {
    let mut traj = Trajectory {
        sensors: system.sensor_record(),
        iterations: Vec::new(),
        jacobians: Vec::new(),
        final_state: start.clone(),
    };
    let integ = match Integrator::new(system, start, settings.clone()).and_then(|i| {
        i.record(&mut traj.sensors)?;
        Ok(i)
    }) {
        Ok(i) => i,
        Err(error) => return Err(Box::new(Incomplete { error, partial: traj })),
    };
    Ok((integ, traj))
}

/// Integrates from `start` to `settings.end_time` (module docs), recording the sensors.
pub fn solve_dynamic(
    system: &System,
    start: State,
    settings: &DynamicSettings,
) -> Result<Trajectory, Box<Incomplete<Trajectory>>> {
    let (mut integ, mut traj) = start_trajectory(system, start, settings)?;
    let (n_steps, _) = fixed_steps(integ.state().time, settings.end_time, settings.step);
    let every = settings.output_every.max(1);
    let mut pending = PendingRows::default();
    for k in 1..=n_steps {
        if k == n_steps {
            // Land on the end time (fixed_steps): the last step may be shorter.
            integ.set_step_size(last_step_size(integ.state().time, settings.end_time, settings.step));
        }
        match integ.step() {
            Ok(rep) => {
                traj.iterations.push(rep.residuals.len() - 1);
                traj.jacobians.push(rep.jacobians);
            }
            Err(e) => return Err(stopped(&integ, e, &mut pending, traj)),
        }
        if k % every == 0 || k == n_steps {
            if let Err(e) = integ.record_deferred(&mut pending, &mut traj.sensors) {
                return Err(stopped(&integ, e, &mut pending, traj));
            }
        }
    }
    finished(&integ, &mut pending, traj)
}

/// The trajectory of a run that stopped with `error`: the rows recorded before it completed
/// (a row that is not finite among them stops them there, the error stays the run's), the
/// integrator's state as the final one.
pub(crate) fn stopped(
    integ: &Integrator,
    error: SolveError,
    pending: &mut PendingRows,
    mut traj: Trajectory,
) -> Box<Incomplete<Trajectory>> {
    let _ = integ.system().complete_rows(pending, &mut traj.sensors);
    traj.final_state = integ.state().clone();
    Box::new(Incomplete { error, partial: traj })
}

/// The trajectory of a run that reached its end, its waiting rows completed.
pub(crate) fn finished(
    integ: &Integrator,
    pending: &mut PendingRows,
    mut traj: Trajectory,
) -> Result<Trajectory, Box<Incomplete<Trajectory>>> {
    traj.final_state = integ.state().clone();
    if let Err(error) = integ.system().complete_rows(pending, &mut traj.sensors) {
        return Err(Box::new(Incomplete { error, partial: traj }));
    }
    Ok(traj)
}

/// Integrates from `start` to `settings.end_time` with the adaptive step (module docs),
/// starting with `settings.step` and recording the sensors after every accepted step
/// (`output_every` is ignored; the step sizes are the differences of the recorded times).
pub fn solve_dynamic_adaptive(
    system: &System,
    start: State,
    settings: &DynamicSettings,
    adaptive: &AdaptiveSettings,
) -> Result<Trajectory, Box<Incomplete<Trajectory>>> {
    let (mut integ, mut traj) = start_trajectory(system, start, settings)?;
    let end = settings.end_time;
    let mut pending = PendingRows::default();
    while end - integ.state().time > 1e-12 * end.abs().max(1.0) {
        // Land on the end time: shorten the step that would pass it (or leave a sliver).
        match step_adaptive_to(&mut integ, end, adaptive) {
            Ok(s) => {
                traj.iterations.push(s.report.residuals.len() - 1);
                traj.jacobians.push(s.report.jacobians);
            }
            Err(e) => return Err(stopped(&integ, e, &mut pending, traj)),
        }
        if let Err(e) = integ.record_deferred(&mut pending, &mut traj.sensors) {
            return Err(stopped(&integ, e, &mut pending, traj));
        }
    }
    finished(&integ, &mut pending, traj)
}
