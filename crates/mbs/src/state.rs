//! [`State`]: the independent coordinates of a system, their rates and the controllers' states
//! at one instant (theory guide §8), the values every analysis carries from step to step.

#![allow(non_snake_case)]

use nalgebra::UnitQuaternion;
use superelement::Frame;

/// The coordinates, velocities and accelerations of a system at one instant, and each
/// flexible body's last floating frame (the warm start of (4.4)).
#[derive(Debug, PartialEq)]
pub struct State {
    pub(crate) time: f64,
    /// Every scalar coordinate (unknown and prescribed).
    pub(crate) scalars: Vec<f64>,
    pub(crate) rotations: Vec<UnitQuaternion<f64>>,
    /// $\dot{\mathbf q}$ (unknowns).
    pub(crate) velocity: Vec<f64>,
    /// $\ddot{\mathbf q}$ (unknowns).
    pub(crate) acceleration: Vec<f64>,
    /// Per flexible element.
    pub(crate) frames: Vec<Frame>,
    /// Per actuator: its controller's state ([`crate::assembly::joint_forces`]).
    pub(crate) controls: Vec<Control>,
    /// The energy-balance sensors' running integrals since the start of the dynamic run
    /// (`None` outside one, or without such a sensor).
    pub(crate) account: Option<EnergyAccount>,
}

/// `clone_from` reuses the buffers (the derived one would allocate a fresh copy): the
/// integrator copies states every step.
impl Clone for State {
    fn clone(&self) -> Self {
        Self {
            time: self.time,
            scalars: self.scalars.clone(),
            rotations: self.rotations.clone(),
            velocity: self.velocity.clone(),
            acceleration: self.acceleration.clone(),
            frames: self.frames.clone(),
            controls: self.controls.clone(),
            account: self.account,
        }
    }

    fn clone_from(&mut self, other: &Self) {
        self.time = other.time;
        self.scalars.clone_from(&other.scalars);
        self.rotations.clone_from(&other.rotations);
        self.velocity.clone_from(&other.velocity);
        self.acceleration.clone_from(&other.acceleration);
        self.frames.clone_from(&other.frames);
        self.controls.clone_from(&other.controls);
        self.account = other.account;
    }
}

impl State {
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Every scalar coordinate (joint coordinates, modal coordinates; unknown and
    /// prescribed) and the node rotations not carried by joints: the configuration.
    pub fn coordinates(&self) -> (&[f64], &[UnitQuaternion<f64>]) {
        (&self.scalars, &self.rotations)
    }
    /// $\dot{\mathbf q}$ in the order of [`crate::System::dof_labels`].
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }
    /// $\ddot{\mathbf q}$.
    pub fn acceleration(&self) -> &[f64] {
        &self.acceleration
    }
    pub fn velocity_mut(&mut self) -> &mut [f64] {
        &mut self.velocity
    }
    pub fn acceleration_mut(&mut self) -> &mut [f64] {
        &mut self.acceleration
    }
    /// Sets the time (prescribed coordinates follow at the next evaluation).
    pub fn set_time(&mut self, t: f64) {
        self.time = t;
    }
}

/// The state of one actuator's controller: the base $(t_n, z_n, e_n)$ of its integral and the
/// branch of its saturation the current step is solved on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Control {
    pub t: f64,
    pub z: f64,
    pub e: f64,
    pub branch: Branch,
}

/// The branch of a saturated PID law $u = \mathrm{sat}(v)$ (`crate::assembly::joint_forces`):
/// undecided (the law as a function of $v$, its kink included), linear ($u = v$), or saturated
/// at $\pm u_{max}$.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Branch {
    #[default]
    Undecided,
    Linear,
    Upper,
    Lower,
}

/// The running time integrals of the energy balance of a dynamic run
/// (`crate::assembly::system::sensors`): the powers at the last accepted step and their
/// trapezoid-rule integrals since the start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct EnergyAccount {
    /// $T_0 + U_0 + V_0$ at the start of the run.
    pub e0: f64,
    /// The time of `power`.
    pub t: f64,
    /// The powers at `t`: put in by the actuators, the drivers, the loads; dissipated.
    pub power: [f64; 4],
    /// Their integrals from the start to `t`.
    pub work: [f64; 4],
}
