//! Forces on joint coordinates besides the joint springs: limits and actuators.
//!
//! A joint coordinate $x$ (an angle in rad or a length in m, [`crate::JointKind`]) takes a
//! generalised force $Q$ (N m or N) in the equations, $\mathbf F \mathrel{-}= Q$ on its row:
//!
//! * **Limit** ([`crate::JointLimit`]): a stiff unilateral spring-damper outside $[x_{lo}, x_{hi}]$.
//!   With the penetration $d = x - x_{lo} < 0$ (or $d = x - x_{hi} > 0$),
//!   $Q = -(k d + c\dot x)$ while it pushes the coordinate back into the range, and $Q = 0$
//!   when the damping term would pull it out (the stop does not stick). Tangents
//!   $\partial\mathbf F/\partial x = k$, $\partial\mathbf F/\partial\dot x = c$ while active.
//! * **Actuator** ([`crate::JointActuator`]) with an effort $u$ from a time function, $Q = u(t)$, or
//!   from a PID law on a measured joint coordinate $y$ with the set-point $r(t)$:
//!   $$e = r - y,\quad u = K_p e + K_i z + K_d(\dot r - \dot y),\quad z(t) = \int_0^t e\,d\tau,$$
//!   optionally saturated at $|u| \le u_{max}$: $u = \mathrm{sat}(v)$ of the linear law $v$ above.
//! * **Held effort** ([`crate::System::set_actuator_effort`]): a caller (a controller or a
//!   co-simulation partner outside the model) replaces an actuator's law by a value $u_h$ set
//!   between time steps, $Q = u_h$ (no tangent) from the end of the next step, until it releases
//!   the actuator to its law again. While a PID actuator is held its integral $z$ is frozen
//!   (no wind-up from an error its own law did not act on); released, the law resumes from it.
//!
//! # The PID integral in time integration
//!
//! The integral $z$ is a state of the controller, carried in [`crate::State`] from step to
//! step. Within a step from $t_n$ to $t$ it follows the trapezoidal rule,
//! $z(t) = z_n + \tfrac12(t - t_n)(e_n + e(t))$, which makes the effort at $t_{n+1}$ an implicit
//! function of the new configuration with the tangent
//! $\partial\mathbf F/\partial y = K_p + \tfrac12 K_i (t - t_n)$, $\partial\mathbf F/\partial\dot y = K_d$
//! ($y$'s row and the actuated column; zero while saturated). A converged step moves the base
//! $(t_n, z_n, e_n)$ to its end ([`crate::System::accept_step`], called by the integrator), so
//! a rejected or retried step restarts from the integral of the last accepted one. In statics
//! the time does not advance and the integral is held.
//!
//! # Saturation: one branch per Newton solve
//!
//! $\mathrm{sat}(v)$ has a kink at $|v| = u_{max}$, and Newton with its exact piecewise
//! derivative cycles across it: an iterate on a saturated branch has no PID term in the
//! iteration matrix, so its correction (inertia alone against a gain $K_p + \gamma' K_d$ many
//! times larger) overshoots onto the other saturated branch, and back (the residual stays near
//! its start, e.g. 0.95 after 20 iterations, while the converged effort is far below $u_{max}$).
//! A smooth saturation would not help: its derivative far out on a branch is as small. So each
//! step is solved on one *branch* (a `Branch` in the controller's state): linear, $u = v$ with
//! the tangent above, or saturated, $u = \pm u_{max}$ with zero tangent. On a branch the law is
//! smooth and its tangent exact, so Newton converges as without a limit. The integrator picks
//! the branch from $v$ at the predictor (`JointForces::settle_branches`) and checks it at the
//! converged iterate: when $v$ there belongs to another branch, it switches and iterates on,
//! one branch at a time (from a saturated branch to the linear one, never straight to the
//! opposite bound: the two saturated solutions can each lie beyond the other's bound). A
//! converged step is thus on the branch of its own $v$: the exact $\mathrm{sat}(v)$ (for one
//! coordinate $F$ is monotone in $y$, so at most two switches are made).
//! Anti-windup, consistent with the zero tangent: over a step solved on a saturated branch the
//! integral is frozen, $z_{n+1} = z_n$ (conditional integration), so that $u$ depends on nothing
//! and the controller leaves the saturation as soon as $v$ does. An undecided branch (statics,
//! the start) evaluates $\mathrm{sat}(v)$ as it comes.
//!
//! # Stops that a step resolves
//!
//! A limit is a stiff spring: on the coordinate's inertia $m$ (the diagonal of $\mathbf M$ at
//! the start) it rings at $\omega = \sqrt{k/m}$. A step much longer than $1/\omega$ enters it
//! deep within one step and the contact's energy is not conserved (the work of a force that
//! was zero for part of the step). The integrator therefore takes back a step that starts or
//! ends in a stop with $\omega h > $ [`STOP_RESOLUTION`] and cuts it (retried fixed steps,
//! adaptive steps), and refuses at the start a stop that the smallest step cannot resolve
//! ([`crate::SolveError::UnresolvableLimit`]).

#![allow(non_snake_case)]

use crate::assembly::coordinates::{Slot, Values};
use crate::assembly::topology::Topology;
use crate::error::{Entity, ModelError};
use crate::ids::JointId;
use crate::model::time_function::CompiledFunction;
use crate::model::{Effort, Model, SensorKind};
use crate::state::{Branch, Control};

/// The largest $\omega h$ of a step in contact with a stop (module docs): the entry's
/// penetration within one step is at most $\dot x h$, holding at most
/// $\tfrac12 k(\dot x h)^2 = (\omega h)^2\,\tfrac12 m\dot x^2$, 1 % of the impact's kinetic
/// energy, and a contact of duration $\pi/\omega$ takes some 30 steps.
pub const STOP_RESOLUTION: f64 = 0.1;

#[derive(Clone, Debug)]
struct Limit {
    scalar: usize,
    lower: f64,
    upper: f64,
    k: f64,
    c: f64,
    slot: Option<usize>,
}

#[derive(Clone, Debug)]
enum Law {
    Time(CompiledFunction),
    Pid(Pid),
}

/// A PID controller of one measured coordinate.
#[derive(Clone, Debug)]
struct Pid {
    /// Scalar of the measured coordinate.
    scalar: usize,
    setpoint: CompiledFunction,
    kp: f64,
    ki: f64,
    kd: f64,
    max: f64,
    /// Slot of (actuated row, measured column) when the measured coordinate is unknown.
    slot: Option<usize>,
}

impl Pid {
    /// The effort at time `t` for the measured value `y` and rate `yd`, with the integral's
    /// base, on the base's branch (module docs; undecided: the branch of $v$).
    fn effort(&self, y: f64, yd: f64, t: f64, base: &Control) -> PidEffort {
        let (kp, ki, kd, max) = (self.kp, self.ki, self.kd, self.max);
        let (r, rd, _) = self.setpoint.eval(t);
        let e = r - y;
        let w = 0.5 * (t - base.t);
        let z = base.z + w * (base.e + e);
        let v = kp * e + ki * z + kd * (rd - yd);
        let branch = match base.branch {
            Branch::Undecided => self.branch(v),
            b => b,
        };
        let saturated = |u: f64| PidEffort {
            u,
            v,
            du_dy: 0.0,
            du_dyd: 0.0,
        };
        match branch {
            Branch::Upper => saturated(max),
            Branch::Lower => saturated(-max),
            _ => PidEffort {
                u: v,
                v,
                du_dy: -kp - ki * w,
                du_dyd: -kd,
            },
        }
    }

    /// The branch of $\mathrm{sat}$ the linear law's value `v` lies on.
    fn branch(&self, v: f64) -> Branch {
        if v > self.max {
            Branch::Upper
        } else if v < -self.max {
            Branch::Lower
        } else {
            Branch::Linear
        }
    }
}

#[derive(Clone, Debug)]
struct Actuator {
    /// Unknown of the actuated coordinate.
    dof: usize,
    law: Law,
    /// $u_h$: the effort set by the caller in place of the law (module docs).
    held: Option<f64>,
    /// Set by a force law in place of its own law ([`crate::model::force_law`], which
    /// adds the effort and its tangent); a PID's integral is frozen, as while held.
    by_law: bool,
}

/// The compiled limits and actuators of a system.
#[derive(Clone, Debug, Default)]
pub(crate) struct JointForces {
    limits: Vec<Limit>,
    actuators: Vec<Actuator>,
}

/// The effort of a PID law, the linear law's value $v$, and the effort's derivatives by $y$
/// and $\dot y$ (zero while saturated).
struct PidEffort {
    u: f64,
    v: f64,
    du_dy: f64,
    du_dyd: f64,
}

fn nonnegative(x: f64) -> bool {
    x >= 0.0 && x.is_finite()
}

impl JointForces {
    /// Checks the model's limits and actuators and finds their coordinates.
    pub(crate) fn new(model: &Model, topo: &Topology) -> Result<Self, ModelError> {
        let map = &topo.map;
        type Who<'a> = &'a dyn Fn() -> (String, Entity);
        let scalar = |who: Who, joint: JointId, coordinate: usize| -> Result<usize, ModelError> {
            let j = model.joints.get(joint.index()).ok_or_else(|| {
                let (referenced_by, by) = who();
                ModelError::UnknownJoint {
                    id: joint.0,
                    count: model.joints.len(),
                    referenced_by,
                    by,
                }
            })?;
            topo.joint_scalars[joint.index()]
                .get(coordinate)
                .copied()
                .ok_or_else(|| ModelError::InvalidValue {
                    entity: who().0,
                    what: format!(
                        "joint '{}' ({}) has {} scalar coordinates; coordinate {coordinate} does not exist",
                        j.name,
                        j.kind.name(),
                        j.kind.n_scalar()
                    ),
                    id: Some(who().1),
                })
        };
        let invalid = |(entity, id): (String, Entity), what: String| ModelError::InvalidValue {
            entity,
            what,
            id: Some(id),
        };
        let mut limits = Vec::new();
        for (i, l) in model.joint_limits.iter().enumerate() {
            let who = || (format!("joint limit '{}'", l.name), Entity::JointLimit(i));
            let s = scalar(&who, l.joint, l.coordinate)?;
            let (lower, upper) = (l.lower.unwrap_or(f64::NEG_INFINITY), l.upper.unwrap_or(f64::INFINITY));
            if l.lower.is_none() && l.upper.is_none() {
                return Err(invalid(who(), "give a lower or an upper bound".into()));
            }
            if lower.is_nan() || upper.is_nan() || !(lower < upper) {
                return Err(invalid(
                    who(),
                    format!("lower bound {lower} must be below the upper {upper}"),
                ));
            }
            if !(nonnegative(l.stiffness) && l.stiffness > 0.0 && nonnegative(l.damping)) {
                return Err(invalid(
                    who(),
                    format!(
                        "stiffness must be positive and damping >= 0, both finite (got {}, {})",
                        l.stiffness, l.damping
                    ),
                ));
            }
            limits.push(Limit {
                scalar: s,
                lower,
                upper,
                k: l.stiffness,
                c: l.damping,
                slot: None,
            });
        }
        let mut actuators = Vec::new();
        for (i, a) in model.actuators.iter().enumerate() {
            let who = || (format!("actuator '{}'", a.name), Entity::Actuator(i));
            let s = scalar(&who, a.joint, a.coordinate)?;
            let Slot::Unknown(dof) = map.scalars[s].slot else {
                return Err(invalid(
                    who(),
                    "its joint coordinate is driven: an actuator acts on a free coordinate (the driver's effort is a sensor)"
                        .into(),
                ));
            };
            let law = match &a.effort {
                Effort::Time(f) => Law::Time(f.compile(&who().0).map_err(|e| e.with_id(who().1))?),
                Effort::Pid(p) => {
                    let measured = scalar(
                        &|| (format!("{} (measured coordinate)", who().0), who().1),
                        p.joint,
                        p.coordinate,
                    )?;
                    let gains = [p.kp, p.ki, p.kd];
                    if !gains.iter().all(|&g| nonnegative(g)) || gains.iter().all(|&g| g == 0.0) {
                        return Err(invalid(
                            who(),
                            format!(
                                "PID gains must be finite and >= 0, not all zero (got kp {}, ki {}, kd {})",
                                p.kp, p.ki, p.kd
                            ),
                        ));
                    }
                    let max = p.max_effort.unwrap_or(f64::INFINITY);
                    if !(max > 0.0) {
                        return Err(invalid(who(), format!("max_effort must be positive (got {max})")));
                    }
                    Law::Pid(Pid {
                        scalar: measured,
                        setpoint: (p.setpoint.compile(&format!("{} set-point", who().0)))
                            .map_err(|e| e.with_id(who().1))?,
                        kp: p.kp,
                        ki: p.ki,
                        kd: p.kd,
                        max,
                        slot: None,
                    })
                }
            };
            actuators.push(Actuator {
                dof,
                law,
                held: None,
                by_law: false,
            });
        }
        for (i, sensor) in model.sensors.iter().enumerate() {
            if let SensorKind::ActuatorEffort { actuator } = sensor.kind {
                if actuator >= actuators.len() {
                    return Err(invalid(
                        (format!("sensor '{}'", sensor.name), Entity::Sensor(i)),
                        format!("actuator {actuator} does not exist ({} actuators)", actuators.len()),
                    ));
                }
            }
        }
        Ok(Self { limits, actuators })
    }

    /// Sets of unknowns coupled by these forces (for the sparse pattern): each PID couples the
    /// actuated and the measured coordinate.
    pub(crate) fn pattern_sets(&self, topo: &Topology) -> Vec<Vec<usize>> {
        let map = &topo.map;
        let mut sets = Vec::new();
        for a in &self.actuators {
            if let Law::Pid(Pid { scalar, .. }) = &a.law {
                if let Slot::Unknown(m) = map.scalars[*scalar].slot {
                    sets.push(vec![a.dof.min(m), a.dof.max(m)]);
                }
            }
        }
        sets
    }

    /// Finds the slots of the tangent entries in the system pattern.
    pub(crate) fn bind(&mut self, topo: &Topology, slot: impl Fn(usize, usize) -> usize) {
        let map = &topo.map;
        for l in &mut self.limits {
            l.slot = match map.scalars[l.scalar].slot {
                Slot::Unknown(d) => Some(slot(d, d)),
                Slot::Prescribed(_) => None,
            };
        }
        for a in &mut self.actuators {
            if let Law::Pid(Pid { scalar, slot: s, .. }) = &mut a.law {
                *s = match map.scalars[*scalar].slot {
                    Slot::Unknown(m) => Some(slot(a.dof, m)),
                    Slot::Prescribed(_) => None,
                };
            }
        }
    }

    /// Number of actuators (one controller state each).
    pub(crate) fn n_actuators(&self) -> usize {
        self.actuators.len()
    }

    /// Holds actuator `index` at effort `u` (`Some`), or releases it to its law (`None`).
    pub(crate) fn hold(&mut self, index: usize, u: Option<f64>) -> Result<(), String> {
        let n = self.actuators.len();
        let a = self
            .actuators
            .get_mut(index)
            .ok_or_else(|| format!("there are {n} actuators"))?;
        if let Some(u) = u {
            if !u.is_finite() {
                return Err(format!("the effort must be finite (got {u})"));
            }
        }
        a.held = u;
        Ok(())
    }

    /// Actuator `index` (which exists) takes its effort from the system's force law: its own
    /// law is left out of the forces and tangents here.
    pub(crate) fn set_by_law(&mut self, index: usize) {
        self.actuators[index].by_law = true;
    }

    /// The effort actuator `index` is held at (`None`: its law acts).
    pub(crate) fn held(&self, index: usize) -> Option<f64> {
        self.actuators.get(index).and_then(|a| a.held)
    }

    /// A limit's force $k d + c\dot x$ (the negative of $Q$) and whether it is active.
    fn limit_force(l: &Limit, x: f64, xd: f64) -> Option<f64> {
        if x < l.lower {
            let f = l.k * (x - l.lower) + l.c * xd;
            (f < 0.0).then_some(f)
        } else if x > l.upper {
            let f = l.k * (x - l.upper) + l.c * xd;
            (f > 0.0).then_some(f)
        } else {
            None
        }
    }

    /// The efforts of all actuators at `t` (for sensors): $u$ of each.
    pub(crate) fn efforts(&self, map_values: &dyn Fn(usize) -> (f64, f64), t: f64, controls: &[Control]) -> Vec<f64> {
        self.actuators
            .iter()
            .zip(controls)
            .map(|(a, c)| match (&a.law, a.held) {
                (_, Some(u)) => u,
                // The force law's effort, added by the system.
                _ if a.by_law => 0.0,
                (Law::Time(f), None) => f.eval(t).0,
                (Law::Pid(pid), None) => {
                    let (y, yd) = map_values(pid.scalar);
                    pid.effort(y, yd, t, c).u
                }
            })
            .collect()
    }

    /// Adds the limits' and actuators' terms to $\mathbf F$ (and the reactions of prescribed
    /// coordinates); returns the norm of these forces, their share of the force scale of the
    /// convergence test (kept apart: an actuator holding a load cancels it in $\mathbf F$).
    pub(crate) fn add_forces(
        &self,
        topo: &Topology,
        x: &Values,
        t: f64,
        controls: &[Control],
        F: &mut [f64],
        reactions: &mut [f64],
    ) -> f64 {
        let map = &topo.map;
        let value = |s: usize| {
            let (v, d, _) = crate::assembly::coordinates::scalar_values(map, x, s);
            (v, d)
        };
        let mut sum = 0.0;
        for l in &self.limits {
            let (xv, xd) = value(l.scalar);
            if let Some(f) = Self::limit_force(l, xv, xd) {
                sum += f * f;
                match map.scalars[l.scalar].slot {
                    Slot::Unknown(d) => F[d] += f,
                    Slot::Prescribed(p) => reactions[p] += f,
                }
            }
        }
        for (u, a) in self.efforts(&value, t, controls).into_iter().zip(&self.actuators) {
            F[a.dof] -= u;
            sum += u * u;
        }
        sum.sqrt()
    }

    /// Strain energy of the active limits, $\tfrac12 k d^2$ each.
    pub(crate) fn limit_energy(&self, scalars: &[f64]) -> f64 {
        self.limits
            .iter()
            .map(|l| {
                let x = scalars[l.scalar];
                let d = (x - l.lower).min(0.0) + (x - l.upper).max(0.0);
                0.5 * l.k * d * d
            })
            .sum()
    }

    /// The power the limits dissipate, $\sum f\dot x - \frac{d}{dt}\tfrac12 k d^2$ each: the power
    /// of the force they apply less the rate of the energy [`Self::limit_energy`] counts (the
    /// damper's $c\dot x$ while in contact, and the spring's share while the force would pull).
    /// `value(s)` is the value and rate of scalar coordinate `s`.
    pub(crate) fn limit_dissipation(&self, value: &dyn Fn(usize) -> (f64, f64)) -> f64 {
        self.limits
            .iter()
            .map(|l| {
                let (x, xd) = value(l.scalar);
                let d = (x - l.lower).min(0.0) + (x - l.upper).max(0.0);
                Self::limit_force(l, x, xd).unwrap_or(0.0) * xd - l.k * d * xd
            })
            .sum()
    }

    /// Adds the tangents $\partial\mathbf F/\partial\mathbf q$ to `K` and $\partial\mathbf F/\partial\dot{\mathbf q}$ to
    /// `C` (values on the system pattern).
    pub(crate) fn add_tangents(
        &self,
        topo: &Topology,
        x: &Values,
        t: f64,
        controls: &[Control],
        K: &mut [f64],
        C: &mut [f64],
    ) {
        let map = &topo.map;
        for l in &self.limits {
            let Some(slot) = l.slot else { continue };
            let (xv, xd, _) = crate::assembly::coordinates::scalar_values(map, x, l.scalar);
            if Self::limit_force(l, xv, xd).is_some() {
                K[slot] += l.k;
                C[slot] += l.c;
            }
        }
        for (a, c) in self.actuators.iter().zip(controls) {
            if a.held.is_some() || a.by_law {
                // A held effort does not depend on the configuration; a force law's tangent
                // is added by the system.
                continue;
            }
            if let Law::Pid(pid @ Pid { slot: Some(slot), .. }) = &a.law {
                let (y, yd, _) = crate::assembly::coordinates::scalar_values(map, x, pid.scalar);
                let p = pid.effort(y, yd, t, c);
                // F = -u on the actuated row.
                K[*slot] -= p.du_dy;
                C[*slot] -= p.du_dyd;
            }
        }
    }

    /// The controllers' states at the start (`t`, integral zero, the error of the start).
    pub(crate) fn start_controls(&self, x: &Values, t: f64) -> Vec<Control> {
        self.actuators
            .iter()
            .map(|a| match &a.law {
                Law::Time(_) => Control {
                    t,
                    ..Default::default()
                },
                Law::Pid(Pid { scalar, setpoint, .. }) => Control {
                    t,
                    z: 0.0,
                    e: setpoint.eval(t).0 - x.scalars[*scalar],
                    branch: Branch::Undecided,
                },
            })
            .collect()
    }

    /// Moves each controller's base to time `t` at the converged values `x` (module docs).
    pub(crate) fn accept(&self, x: &Values, t: f64, controls: &mut [Control]) {
        for (a, c) in self.actuators.iter().zip(controls.iter_mut()) {
            if let Law::Pid(Pid { scalar, setpoint, .. }) = &a.law {
                let e = setpoint.eval(t).0 - x.scalars[*scalar];
                // Held, saturated or driven by a force law: the integral is frozen (module
                // docs, anti-windup).
                let saturated = matches!(c.branch, Branch::Upper | Branch::Lower);
                if a.held.is_none() && !a.by_law && !saturated {
                    c.z += 0.5 * (t - c.t) * (c.e + e);
                }
                c.e = e;
            }
            c.t = t;
        }
    }

    /// Puts each PID actuator's controller on the branch of its linear law's value $v$ at `t`
    /// (module docs); `value(s)` is the value and rate of scalar coordinate `s`. Returns
    /// whether a branch changed. A held actuator, or one driven by a force law, keeps its
    /// branch (its own law does not act).
    pub(crate) fn settle_branches(
        &self,
        value: &dyn Fn(usize) -> (f64, f64),
        t: f64,
        controls: &mut [Control],
    ) -> bool {
        let mut changed = false;
        for (a, c) in self.actuators.iter().zip(controls.iter_mut()) {
            if let (Law::Pid(pid), None, false) = (&a.law, a.held, a.by_law) {
                let (y, yd) = value(pid.scalar);
                // One branch at a time: from a saturated branch through the linear one, never
                // to the opposite bound (both solutions can lie beyond the other's bound, a
                // cycle, while the linear branch holds the solution).
                let branch = match (c.branch, pid.branch(pid.effort(y, yd, t, c).v)) {
                    (Branch::Upper, Branch::Lower) | (Branch::Lower, Branch::Upper) => Branch::Linear,
                    (_, b) => b,
                };
                changed |= branch != c.branch;
                c.branch = branch;
            }
        }
        changed
    }

    /// The stops on unknown coordinates, with the inertias `M` (values on the system
    /// pattern): (limit index, $k$, the diagonal $m$ of $\mathbf M$ on its coordinate).
    pub(crate) fn stops(&self, M: &[f64]) -> Vec<(usize, f64, f64)> {
        self.limits
            .iter()
            .enumerate()
            .filter_map(|(i, l)| l.slot.map(|slot| (i, l.k, M[slot])))
            .collect()
    }

    /// Whether limit `index` is penetrated at the scalar coordinates `scalars`.
    pub(crate) fn penetrated(&self, index: usize, scalars: &[f64]) -> bool {
        let l = &self.limits[index];
        let x = scalars[l.scalar];
        x < l.lower || x > l.upper
    }
}
