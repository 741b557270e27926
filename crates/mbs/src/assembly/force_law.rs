//! A [`ForceLaw`] bound to a system: what its inputs read (scalar coordinates, node
//! kinematics), the unknowns they hang on, where its outputs act, and the slots of its
//! tangent entries in the system pattern ([`crate::model::force_law`] gives the equations).

#![allow(non_snake_case)]

use crate::assembly::coordinates::{scalar_values, Motion, NodeDerivatives, Slot, Values};
use crate::assembly::topology::Topology;
use crate::error::{At, Entity, ModelError, SolveError};
use crate::model::force_law::{ForceLaw, LawBuffer, LawError, LawInput, LawRead, LawTarget};
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

/// What one input reads, resolved on the system.
#[derive(Clone, Copy, Debug)]
enum Read {
    /// A scalar coordinate (index in the map's scalars).
    Scalar(usize),
    /// The position of node `node` along inertial axis `axis`, with its velocity as rate.
    Position { node: usize, axis: usize },
    /// The velocity of node `node` along inertial axis `axis` (no rate).
    Velocity { node: usize, axis: usize },
}

/// A force law bound to a system.
#[derive(Clone, Debug)]
pub(crate) struct BoundLaw {
    pub law: Arc<dyn ForceLaw>,
    /// What each input reads.
    inputs: Vec<Read>,
    /// Per output: where it acts and the index of its first value in $\mathbf u$.
    outputs: Vec<(Acts, usize)>,
    /// The unknowns the inputs hang on (sorted): the columns of the law's tangent.
    columns: Vec<usize>,
    /// Per input: the position in `columns` of each unknown it hangs on (a scalar's own; a
    /// node's unknown columns, in the order of its [`NodeDerivatives::unknown`]).
    input_columns: Vec<Vec<usize>>,
    /// Per output and per column: the slots of its tangent entries, one per row it acts on
    /// (the actuated row; each unknown column of the node).
    slots: Vec<Vec<Vec<usize>>>,
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
        let inputs = ports
            .inputs
            .iter()
            .map(|i| Self::read(i, model, topo).map_err(|(what, id)| invalid(what, id)))
            .collect::<Result<Vec<_>, _>>()?;
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
        let n = topo.map.n_dof;
        // The unknowns each input hangs on, then their positions in the sorted union.
        let unknowns: Vec<Vec<usize>> = inputs
            .iter()
            .map(|r| match *r {
                Read::Scalar(s) => match topo.map.scalars[s].slot {
                    Slot::Unknown(d) => vec![d],
                    Slot::Prescribed(_) => Vec::new(),
                },
                Read::Position { node, .. } | Read::Velocity { node, .. } => topo.map.chains[node]
                    .cols
                    .iter()
                    .copied()
                    .filter(|&id| id < n)
                    .collect(),
            })
            .collect();
        let mut columns: Vec<usize> = unknowns.iter().flatten().copied().collect();
        columns.sort_unstable();
        columns.dedup();
        let input_columns = unknowns
            .iter()
            .map(|u| u.iter().map(|d| columns.binary_search(d).expect("a column")).collect())
            .collect();
        Ok(Self {
            law,
            inputs,
            outputs,
            columns,
            input_columns,
            slots: Vec::new(),
        })
    }

    /// What input `i` reads on the system, or why it cannot (message, entity).
    fn read(i: &LawInput, model: &Model, topo: &Topology) -> Result<Read, (String, Option<Entity>)> {
        match i.reads {
            LawRead::Coordinate { joint, coordinate } => {
                let scalars = topo.joint_scalars.get(joint.index()).ok_or_else(|| {
                    (
                        format!("input '{}' reads joint {}, which does not exist", i.name, joint.0),
                        None,
                    )
                })?;
                scalars.get(coordinate).map(|&s| Read::Scalar(s)).ok_or_else(|| {
                    (
                        format!(
                            "input '{}' reads coordinate {coordinate} of joint '{}', which has {}",
                            i.name,
                            model.joints[joint.index()].name,
                            scalars.len()
                        ),
                        Some(Entity::Joint(joint)),
                    )
                })
            }
            LawRead::NodePosition { node, axis } | LawRead::NodeVelocity { node, axis } => {
                if node.index() >= model.nodes.len() {
                    return Err((
                        format!("input '{}' reads node {}, which does not exist", i.name, node.0),
                        None,
                    ));
                }
                if axis > 2 {
                    return Err((
                        format!("input '{}' reads axis {axis}: the axes are 0, 1, 2 (x, y, z)", i.name),
                        Some(Entity::Node(node)),
                    ));
                }
                let node = node.index();
                Ok(match i.reads {
                    LawRead::NodePosition { .. } => Read::Position { node, axis },
                    _ => Read::Velocity { node, axis },
                })
            }
        }
    }

    /// A buffer for the law's evaluations and tangents on this system.
    pub(crate) fn buffer(&self) -> LawBuffer {
        LawBuffer::new(self.law.ports(), self.columns.len())
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
    /// every unknown the inputs hang on. `node_unknown`: the unknown columns of each node.
    pub(crate) fn pattern_sets(&self, node_unknown: &[Vec<usize>]) -> Vec<Vec<usize>> {
        let mut one = [0];
        self.outputs
            .iter()
            .map(|(acts, _)| {
                let mut s: Vec<usize> = Self::rows(acts, node_unknown, &mut one).to_vec();
                s.extend(&self.columns);
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
                self.columns
                    .iter()
                    .map(|&d| rows.iter().map(|&r| slot(r, d)).collect())
                    .collect()
            })
            .collect();
    }

    /// The inputs' values and rates at `x` (node motions `motions`) into `buf`; an input
    /// without a rate gets NaN.
    fn gather(&self, topo: &Topology, x: &Values, motions: &[Motion], buf: &mut LawBuffer) {
        for (k, r) in self.inputs.iter().enumerate() {
            (buf.x[k], buf.xd[k]) = match *r {
                Read::Scalar(s) => {
                    let (v, d, _) = scalar_values(&topo.map, x, s);
                    (v, d)
                }
                Read::Position { node, axis } => (motions[node].p[axis], motions[node].v[axis]),
                Read::Velocity { node, axis } => (motions[node].v[axis], f64::NAN),
            };
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

    /// Evaluates the law at `x` (node motions `motions`; with `tangents` its Jacobians) into
    /// `buf`.
    pub(crate) fn evaluate(
        &self,
        topo: &Topology,
        (x, motions): (&Values, &[Motion]),
        t: f64,
        tangents: bool,
        buf: &mut LawBuffer,
    ) -> Result<(), SolveError> {
        self.gather(topo, x, motions, buf);
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

    /// The law's derivatives by the unknowns into `buf.dq`, `buf.dqd` (module docs of
    /// [`crate::model::force_law`]: $\partial\mathbf u/\partial\mathbf q$ and
    /// $\partial\mathbf u/\partial\dot{\mathbf q}$ over [`Self::columns`]) from its Jacobians in
    /// `buf` and the nodes' $\mathbf J$ (`motions`) and $\partial\mathbf V/\partial\mathbf q$
    /// (`derivs`).
    fn chain_rule(&self, buf: &mut LawBuffer, motions: &[Motion], derivs: &[NodeDerivatives]) {
        buf.dq.fill(0.0);
        buf.dqd.fill(0.0);
        let m = buf.u.len();
        for (i, (r, cols)) in self.inputs.iter().zip(&self.input_columns).enumerate() {
            for (j, &c) in cols.iter().enumerate() {
                // (dy/dq, dy/dqd, dyd/dq, dyd/dqd) of the input by unknown column `c`.
                let (y_q, y_qd, yd_q, yd_qd) = match *r {
                    Read::Scalar(_) => (1.0, 0.0, 0.0, 1.0),
                    Read::Position { node, axis } => {
                        let Jv = motions[node].Jv[derivs[node].unknown[j]][axis];
                        (Jv, 0.0, derivs[node].DV[j][axis], Jv)
                    }
                    Read::Velocity { node, axis } => {
                        let Jv = motions[node].Jv[derivs[node].unknown[j]][axis];
                        (derivs[node].DV[j][axis], Jv, 0.0, 0.0)
                    }
                };
                for k in 0..m {
                    let (g_y, g_yd) = (buf.du_dx[(k, i)], buf.du_dxd[(k, i)]);
                    buf.dq[(k, c)] += g_y * y_q + g_yd * yd_q;
                    buf.dqd[(k, c)] += g_y * y_qd + g_yd * yd_qd;
                }
            }
        }
    }

    /// Adds $-\mathbf B\,\partial\mathbf u/\partial\mathbf q$ to `K` and
    /// $-\mathbf B\,\partial\mathbf u/\partial\dot{\mathbf q}$ to `C` from the Jacobians in `buf`
    /// and the node kinematics `(motions, derivs)`. `node_unknown`: each node's unknown
    /// columns as (position in its columns, unknown).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn add_tangents(
        &self,
        buf: &mut LawBuffer,
        (t, lambda): (f64, f64),
        held: impl Fn(usize) -> bool,
        node_unknown: &[Vec<(usize, usize)>],
        (motions, derivs): (&[Motion], &[NodeDerivatives]),
        K: &mut [f64],
        C: &mut [f64],
    ) {
        self.chain_rule(buf, motions, derivs);
        for ((acts, k), slots) in self.outputs.iter().zip(&self.slots) {
            for (c, rows) in slots.iter().enumerate() {
                match acts {
                    Acts::Actuator { index, .. } => {
                        if !held(*index) {
                            K[rows[0]] -= buf.dq[(*k, c)];
                            C[rows[0]] -= buf.dqd[(*k, c)];
                        }
                    }
                    Acts::Load { node, moment, time } => {
                        let s = lambda * time.eval(t).0;
                        let at = if *moment { 3 } else { 0 };
                        for (&(col, _), &slot) in node_unknown[*node].iter().zip(rows) {
                            let J = motions[*node].col(col);
                            let (mut kx, mut cx) = (0.0, 0.0);
                            for i in 0..3 {
                                kx += J[at + i] * buf.dq[(k + i, c)];
                                cx += J[at + i] * buf.dqd[(k + i, c)];
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
