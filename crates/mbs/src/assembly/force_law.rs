//! A [`ForceLaw`] bound to a system: its inputs' scalar coordinates, where its outputs act,
//! and the slots of its tangent entries in the system pattern
//! ([`crate::model::force_law`] gives the equations).

#![allow(non_snake_case)]

use crate::assembly::coordinates::{scalar_values, Slot, Values};
use crate::assembly::topology::Topology;
use crate::error::{At, Entity, ModelError, SolveError};
use crate::model::force_law::{ForceLaw, LawBuffer, LawError, LawTarget};
use crate::model::{LoadAxes, Model};
use std::sync::Arc;

/// Where one output acts.
#[derive(Clone, Debug)]
pub(crate) enum Acts {
    /// On the row of the unknown `dof` (an actuator), as $\mathbf F \mathrel{-}= u$.
    Actuator { index: usize, dof: usize },
    /// On node `node` (rows 0..3 for a force, 3..6 for a moment), as
    /// $\lambda x(t)\mathbf f$ with `time` the load's $x(t)$.
    Load {
        node: usize,
        moment: bool,
        time: crate::model::time_function::CompiledFunction,
    },
}

/// A force law bound to a system.
#[derive(Clone, Debug)]
pub(crate) struct BoundLaw {
    pub law: Arc<dyn ForceLaw>,
    /// Scalar coordinate of each input.
    inputs: Vec<usize>,
    /// Per output: where it acts and the index of its first value in $\mathbf u$.
    outputs: Vec<(Acts, usize)>,
    /// Per output and per unknown input (`(input, unknown)`): the slots of its tangent
    /// entries, one per row it acts on (the actuated row; each unknown column of the node).
    slots: Vec<Vec<Vec<usize>>>,
    /// The inputs that are unknowns: (input, unknown).
    unknown_inputs: Vec<(usize, usize)>,
}

impl BoundLaw {
    /// Checks the law's ports against the model; loads driven by it get the value zero in
    /// `model_loads` (the law gives their whole value).
    pub(crate) fn new(law: Arc<dyn ForceLaw>, model: &Model, topo: &Topology) -> Result<Self, ModelError> {
        let ports = law.ports();
        let invalid = |what: String, id: Option<Entity>| ModelError::InvalidValue {
            entity: format!("force law '{}'", law.name()),
            what,
            id,
        };
        let mut inputs = Vec::new();
        for i in &ports.inputs {
            let scalars = topo.joint_scalars.get(i.joint.index()).ok_or_else(|| {
                invalid(
                    format!("input '{}' reads joint {}, which does not exist", i.name, i.joint.0),
                    None,
                )
            })?;
            let s = scalars.get(i.coordinate).copied().ok_or_else(|| {
                invalid(
                    format!(
                        "input '{}' reads coordinate {} of joint '{}', which has {}",
                        i.name,
                        i.coordinate,
                        model.joints[i.joint.index()].name,
                        scalars.len()
                    ),
                    Some(Entity::Joint(i.joint)),
                )
            })?;
            inputs.push(s);
        }
        let mut outputs = Vec::new();
        let mut first = 0;
        for o in &ports.outputs {
            let acts = match o.target {
                LawTarget::Actuator(a) => {
                    let act = model.actuators.get(a).ok_or_else(|| {
                        invalid(
                            format!("output '{}' sets actuator {a}, which does not exist", o.name),
                            None,
                        )
                    })?;
                    let s = topo.joint_scalars[act.joint.index()][act.coordinate];
                    let Slot::Unknown(dof) = topo.map.scalars[s].slot else {
                        unreachable!("an actuator's coordinate is an unknown (JointForces::new)")
                    };
                    Acts::Actuator { index: a, dof }
                }
                LawTarget::Load(l) => {
                    let load = model.loads.get(l).ok_or_else(|| {
                        invalid(format!("output '{}' sets load {l}, which does not exist", o.name), None)
                    })?;
                    if load.axes == LoadAxes::Follower {
                        return Err(invalid(
                            format!(
                                "output '{}' sets a follower load: a force law sets dead loads only (inertial axes)",
                                o.name
                            ),
                            Some(Entity::Load(l)),
                        ));
                    }
                    let time = load
                        .time
                        .compile(&format!("load {l}"))
                        .map_err(|e| e.with_id(Entity::Load(l)))?;
                    Acts::Load {
                        node: load.node.index(),
                        moment: load.kind == crate::model::LoadKind::Moment,
                        time,
                    }
                }
            };
            outputs.push((acts, first));
            first += o.target.width();
        }
        let unknown_inputs = inputs
            .iter()
            .enumerate()
            .filter_map(|(i, &s)| match topo.map.scalars[s].slot {
                Slot::Unknown(d) => Some((i, d)),
                Slot::Prescribed(_) => None,
            })
            .collect();
        Ok(Self {
            law,
            inputs,
            outputs,
            slots: Vec::new(),
            unknown_inputs,
        })
    }

    /// The loads the law sets (indices in `Model::loads`).
    pub(crate) fn loads(&self) -> impl Iterator<Item = usize> + '_ {
        self.law.ports().outputs.iter().filter_map(|o| match o.target {
            LawTarget::Load(l) => Some(l),
            LawTarget::Actuator(_) => None,
        })
    }

    /// The actuators the law sets (indices in `Model::actuators`).
    pub(crate) fn actuators(&self) -> impl Iterator<Item = usize> + '_ {
        self.outputs.iter().filter_map(|(a, _)| match a {
            Acts::Actuator { index, .. } => Some(*index),
            Acts::Load { .. } => None,
        })
    }

    /// The unknowns each output's rows are: the actuated one, or the node's unknown columns.
    fn rows<'a>(acts: &Acts, node_unknown: &'a [Vec<usize>], one: &'a mut [usize; 1]) -> &'a [usize] {
        match acts {
            Acts::Actuator { dof, .. } => {
                one[0] = *dof;
                &one[..]
            }
            Acts::Load { node, .. } => &node_unknown[*node],
        }
    }

    /// Sets of unknowns coupled by the law (for the sparse pattern): each output's rows with
    /// every unknown input. `node_unknown`: the unknown columns of each node.
    pub(crate) fn pattern_sets(&self, node_unknown: &[Vec<usize>]) -> Vec<Vec<usize>> {
        let mut one = [0];
        self.outputs
            .iter()
            .map(|(acts, _)| {
                let mut s: Vec<usize> = Self::rows(acts, node_unknown, &mut one).to_vec();
                s.extend(self.unknown_inputs.iter().map(|&(_, d)| d));
                s.sort_unstable();
                s.dedup();
                s
            })
            .collect()
    }

    /// Finds the slots of the tangent entries in the system pattern.
    pub(crate) fn bind(&mut self, node_unknown: &[Vec<usize>], slot: impl Fn(usize, usize) -> usize) {
        let mut one = [0];
        self.slots = self
            .outputs
            .iter()
            .map(|(acts, _)| {
                let rows = Self::rows(acts, node_unknown, &mut one);
                self.unknown_inputs
                    .iter()
                    .map(|&(_, d)| rows.iter().map(|&r| slot(r, d)).collect())
                    .collect()
            })
            .collect();
    }

    /// The inputs' values and rates at `x` into `buf`.
    fn gather(&self, topo: &Topology, x: &Values, buf: &mut LawBuffer) {
        for (k, &s) in self.inputs.iter().enumerate() {
            let (v, d, _) = scalar_values(&topo.map, x, s);
            buf.x[k] = v;
            buf.xd[k] = d;
        }
    }

    /// `error` of the law at time `t` as the solver's error.
    pub(crate) fn error(&self, t: f64, error: LawError) -> SolveError {
        SolveError::ForceLaw {
            name: self.law.name().to_string(),
            output: error.name.clone(),
            at: At::Time(t),
            step: None,
            source: Box::new(error),
        }
    }

    /// Evaluates the law at `x` (and with `tangents` its Jacobians) into `buf`.
    pub(crate) fn evaluate(
        &self,
        topo: &Topology,
        x: &Values,
        t: f64,
        tangents: bool,
        buf: &mut LawBuffer,
    ) -> Result<(), SolveError> {
        self.gather(topo, x, buf);
        let law = self.law.as_ref();
        buf.evaluate(law, t).map_err(|e| self.error(t, e))?;
        if tangents {
            buf.jacobian(law, t).map_err(|e| self.error(t, e))?;
        }
        Ok(())
    }

    /// The efforts of the actuators the law sets, from the law's values `u`: (actuator, $u$).
    pub(crate) fn efforts<'a>(&'a self, u: &'a [f64]) -> impl Iterator<Item = (usize, f64)> + 'a {
        self.outputs.iter().filter_map(move |(acts, k)| match acts {
            Acts::Actuator { index, .. } => Some((*index, u[*k])),
            Acts::Load { .. } => None,
        })
    }

    /// The power $\lambda x(t)\,\mathbf f\cdot\mathbf v$ of the loads the law sets, from its
    /// values `u` (the energy balance's work of the loads): `motion(node, moment)` is the
    /// node's velocity, or its angular velocity for a moment.
    pub(crate) fn load_power(
        &self,
        u: &[f64],
        (t, lambda): (f64, f64),
        motion: impl Fn(usize, bool) -> nalgebra::Vector3<f64>,
    ) -> f64 {
        let mut power = 0.0;
        for (acts, k) in &self.outputs {
            if let Acts::Load { node, moment, time } = acts {
                let v = motion(*node, *moment);
                power += lambda * time.eval(t).0 * (0..3).map(|i| u[k + i] * v[i]).sum::<f64>();
            }
        }
        power
    }

    /// Adds the law's values `u` to the residual: each effort not held (`held(actuator)`) on
    /// its row of `F`, each load as the external force $\lambda x(t)\mathbf f$ of its node
    /// (`node_forces`: $-$ into the node residual, + into its external part). Returns the
    /// efforts' sum of squares (their share of the force scale).
    pub(crate) fn add_forces(
        &self,
        u: &[f64],
        (t, lambda): (f64, f64),
        held: impl Fn(usize) -> bool,
        F: &mut [f64],
        mut node_forces: impl FnMut(usize, usize, f64),
    ) -> f64 {
        let mut sum = 0.0;
        for (acts, k) in &self.outputs {
            match acts {
                Acts::Actuator { index, dof } => {
                    if !held(*index) {
                        F[*dof] -= u[*k];
                        sum += u[*k] * u[*k];
                    }
                }
                Acts::Load { node, moment, time } => {
                    let s = lambda * time.eval(t).0;
                    let at = if *moment { 3 } else { 0 };
                    for i in 0..3 {
                        node_forces(*node, at + i, s * u[k + i]);
                    }
                }
            }
        }
        sum
    }

    /// Adds $-\mathbf B\,\partial\mathbf g/\partial\mathbf y\,\mathbf P$ to `K` and the same of
    /// $\dot{\mathbf y}$ to `C` from the Jacobians in `buf`. `column(node, unknown)`: the
    /// column of $\mathbf J$ of the node for one of its unknowns.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn add_tangents(
        &self,
        buf: &LawBuffer,
        (t, lambda): (f64, f64),
        held: impl Fn(usize) -> bool,
        node_unknown: &[Vec<(usize, usize)>],
        column: impl Fn(usize, usize) -> [f64; 6],
        K: &mut [f64],
        C: &mut [f64],
    ) {
        for ((acts, k), slots) in self.outputs.iter().zip(&self.slots) {
            for (&(i, _), rows) in self.unknown_inputs.iter().zip(slots) {
                match acts {
                    Acts::Actuator { index, .. } => {
                        if !held(*index) {
                            K[rows[0]] -= buf.du_dx[(*k, i)];
                            C[rows[0]] -= buf.du_dxd[(*k, i)];
                        }
                    }
                    Acts::Load { node, moment, time } => {
                        let s = lambda * time.eval(t).0;
                        let at = if *moment { 3 } else { 0 };
                        for (&(col, _), &slot) in node_unknown[*node].iter().zip(rows) {
                            let J = column(*node, col);
                            let (mut kx, mut cx) = (0.0, 0.0);
                            for c in 0..3 {
                                kx += J[at + c] * buf.du_dx[(k + c, i)];
                                cx += J[at + c] * buf.du_dxd[(k + c, i)];
                            }
                            K[slot] -= s * kx;
                            C[slot] -= s * cx;
                        }
                    }
                }
            }
        }
    }
}
