//! Named outputs ([`crate::model::SensorKind`]) recorded at converged steps, and the energy and
//! momentum of the whole system.
//!
//! * Reactions are the residual of the removed (prescribed) coordinates, $\sum_c\mathbf J_{c,p}^T\mathbf r_c$:
//!   the generalised force the support or driver must supply.
//! * Momentum: the generalised momentum $\mathbf M\mathbf V$ of every body paired with the rigid
//!   velocity fields $[\mathbf e; \mathbf 0]$ (linear) and $[\mathbf e\times\mathbf r_k; \mathbf e]$ (angular,
//!   about the origin) — Noether's conserved quantities of a kinetic energy invariant under
//!   rigid motions.
//! * Accelerations read the node motions at the state's true accelerations $\ddot{\mathbf q}$
//!   (the integrator's algorithmic accelerations $\mathbf a_n$ never reach a state); a node
//!   carried by a body or a joint gets $\mathbf a_{node} + \boldsymbol\alpha\times\mathbf r +
//!   \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf r)$ from the coordinate maps
//!   ([`crate::assembly::coordinates`]). A static state has $\ddot{\mathbf q} = \mathbf 0$.
//! * Energy balance: with $E = T + U + V$ (kinetic, strain, gravity: [`System::energies`]),
//!   the exact motion obeys $E - E_0 = W_{in} - D$, with $W_{in} = \int P_{in}\,dt$ the work of
//!   the actuators ($u\dot x$), the drivers (effort times prescribed rate) and the loads
//!   ($\mathbf f\cdot\mathbf v + \mathbf m\cdot\boldsymbol\omega$, the loads a force law sets
//!   among them; user forces and loads at flexible bodies' load points as
//!   $\mathbf Q\cdot\dot{\mathbf q}$), and $D = \int P_d\,dt$ the
//!   dissipation of the dampers (springs' $c\dot l^2$, joint springs' $c\dot x^2$, the limits,
//!   the flexible bodies' damping forces $\mathbf f_d\cdot\dot{\mathbf q}$). The powers are
//!   evaluated at each accepted step and integrated by the trapezoid rule (`EnergyAccount`,
//!   carried in the [`State`]), so the balance error $E - E_0 - W_{in} + D$ measures the
//!   integrator's energy error: second order in the step, like generalized-α itself. Outside
//!   a dynamic run (a static state) no work is counted and $E_0$ is the state's own energy.

#![allow(non_snake_case)]

use crate::assembly::coordinates::unknown;
use crate::assembly::coordinates::Slot;
use crate::assembly::system::{ElementKind, System, Workspace};
use crate::assembly::topology::RootRotation;
use crate::error::SolveError;
use crate::model::SensorAxes;
use crate::model::{BodyId, SensorKind};
use crate::node::NodeMotion;
use crate::state::{EnergyAccount, State};
use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use superelement::so3;

/// Sensor rows waiting for the values of their largest-von-Mises sensors
/// ([`crate::Integrator::record_deferred`], [`System::complete_rows`]). Those values are found
/// for a batch of rows at once: one search per row reads the body's stress shapes per row,
/// a batch reads them once.
#[derive(Clone, Debug, Default)]
pub struct PendingRows {
    rows: Vec<PendingRow>,
    /// When the oldest waiting row was recorded.
    since: Option<std::time::Instant>,
}

impl PendingRows {
    /// Rows held before they are completed.
    pub const BATCH: usize = 64;
    /// The longest a row waits (wall time) before it is completed at the next record, so that
    /// a live sensor file lags a slow run by at most this.
    pub const WAIT: std::time::Duration = std::time::Duration::from_secs(1);

    /// The number of rows waiting.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether no row waits.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Whether the rows should be completed now: a whole batch, or waiting too long.
    pub(crate) fn due(&self) -> bool {
        self.rows.len() >= Self::BATCH || self.since.is_some_and(|t| t.elapsed() >= Self::WAIT)
    }
}

/// A recorded row whose largest-von-Mises values wait.
#[derive(Clone, Debug)]
struct PendingRow {
    time: f64,
    /// The step it was recorded at (for a located error).
    step: usize,
    row: Vec<f64>,
    maxima: Vec<DeferredMaximum>,
}

/// The state of one largest-von-Mises sensor in a waiting row.
#[derive(Clone, Debug)]
pub(crate) struct DeferredMaximum {
    /// Index in `Model::sensors`.
    sensor: usize,
    /// Its first column in the row (value, then node).
    column: usize,
    /// The body's CB coordinates $\mathbf q^{jj}$.
    q: Vec<f64>,
}

/// Sensor values over time: one row per output time, sensors side by side.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SensorRecord {
    pub names: Vec<String>,
    /// Number of values of each sensor.
    pub widths: Vec<usize>,
    pub times: Vec<f64>,
    pub rows: Vec<Vec<f64>>,
}

impl SensorRecord {
    /// The first value of the last row that is not finite, as
    /// [`SolveError::NonFiniteSensor`] at `step` (sensor, its index in the record, which is its
    /// index in `Model::sensors` for a record of [`System::sensor_record`], component within
    /// it, time).
    pub fn check_last_row(&self, step: usize) -> Result<(), SolveError> {
        let (Some(row), Some(&t)) = (self.rows.last(), self.times.last()) else {
            return Ok(());
        };
        let Some(k) = row.iter().position(|x| !x.is_finite()) else {
            return Ok(());
        };
        let (mut start, mut i) = (0, 0);
        while i + 1 < self.widths.len() && start + self.widths[i] <= k {
            start += self.widths[i];
            i += 1;
        }
        Err(SolveError::NonFiniteSensor {
            sensor: self.names.get(i).cloned().unwrap_or_default(),
            index: i,
            component: k - start,
            value: row[k],
            at: crate::error::At::Time(t),
            step,
        })
    }

    /// Values of sensor `name` at each time.
    pub fn series(&self, name: &str) -> Option<Vec<Vec<f64>>> {
        let i = self.names.iter().position(|n| n == name)?;
        let start: usize = self.widths[..i].iter().sum();
        Some(
            self.rows
                .iter()
                .map(|r| r[start..start + self.widths[i]].to_vec())
                .collect(),
        )
    }

    /// Component `k` of sensor `name` at each time.
    pub fn column(&self, name: &str, k: usize) -> Option<Vec<f64>> {
        Some(self.series(name)?.into_iter().map(|v| v[k]).collect())
    }
}

/// Energies of the system.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energies {
    pub kinetic: f64,
    /// Flexible bodies, springs, joint springs.
    pub strain: f64,
    /// $-\mathbf g\cdot\sum m\mathbf r_G$.
    pub gravity: f64,
}

impl Energies {
    pub fn total(&self) -> f64 {
        self.kinetic + self.strain + self.gravity
    }
}

impl System {
    /// Kinetic, strain and gravity energy at `state`.
    pub fn energies(&self, state: &State) -> Result<Energies, SolveError> {
        self.energies_with(state, &self.node_motions(state), None)
    }

    /// [`Self::energies`] at the state a workspace was evaluated at (the sensors of a solver's
    /// converged state): a flexible body's configuration ($\mathbf q^{jj}$, frame, the
    /// transformations) is taken from its last evaluation instead of solving its frame again, when
    /// that evaluation is of this state (same interface positions and orientations, same
    /// modal coordinates); the velocities always come from the state.
    fn energies_in(&self, state: &State, ws: &Workspace) -> Result<Energies, SolveError> {
        self.energies_with(state, &ws.nodes, Some(ws))
    }

    fn energies_with(
        &self,
        state: &State,
        nodes: &[NodeMotion],
        ws: Option<&Workspace>,
    ) -> Result<Energies, SolveError> {
        let g = self.model.gravity;
        let mut e = Energies::default();
        let body_err = |f: &crate::assembly::body::FlexibleElement, source| SolveError::Body {
            body: self.model.bodies[f.body].name().to_string(),
            id: crate::model::BodyId(f.body as u32),
            at: crate::error::At::Time(state.time),
            step: None,
            source: Box::new(source),
        };
        let evaluated = |i: usize| {
            let ws = ws?;
            let e = self
                .elements
                .iter()
                .position(|e| matches!(e.kind, ElementKind::Flexible(k) if k == i))?;
            let buf = ws.elems[e].flex.as_ref()?;
            let f = &self.flexible[i];
            let same = f
                .nodes
                .iter()
                .zip(&f.offsets)
                .enumerate()
                .all(|(k, (&n, C))| buf.state.r[k] == nodes[n].r && buf.state.R[k] == nodes[n].R * C)
                && f.modal.iter().zip(&buf.state.eta).all(|(&s, x)| state.scalars[s] == *x);
            same.then_some(buf)
        };
        for (i, f) in self.flexible.iter().enumerate() {
            match evaluated(i) {
                Some(buf) => {
                    // 1/2 qd^T M qd at the configuration of the evaluation (a forces-only one
                    // forms no mass matrix: `kinetic_energy_in` needs none). The velocities
                    // alone, not a whole body state: this runs at every recorded step.
                    let qd = self.body_velocities(i, state, nodes);
                    e.kinetic += f.se.kinetic_energy_in(&buf.ws, &qd).map_err(|s| body_err(f, s))?;
                    e.strain += f.se.strain_energy_in(&buf.ws);
                    e.gravity += f.se.gravity_potential(buf.ws.kinematics(), &g);
                }
                None => {
                    let bs = self.body_state(i, state, nodes);
                    e.kinetic += f.se.kinetic_energy(&bs).map_err(|s| body_err(f, s))?;
                    let kin = f.se.kinematics(&bs).map_err(|s| body_err(f, s))?;
                    e.strain += f.se.strain_energy(&kin);
                    e.gravity += f.se.gravity_potential(&kin, &g);
                }
            }
        }
        for r in &self.rigid {
            let m = &nodes[r.node];
            let R = m.R.to_rotation_matrix();
            let b = R * r.c;
            let IG = R.matrix() * r.J * R.matrix().transpose();
            let vG = m.v + m.omega.cross(&b);
            e.kinetic += 0.5 * r.mass * vG.norm_squared() + 0.5 * m.omega.dot(&(IG * m.omega));
            e.gravity -= r.mass * g.dot(&(m.r + b));
        }
        for p in &self.model.point_masses {
            let m = &nodes[p.node.index()];
            e.kinetic += 0.5 * p.mass * m.v.norm_squared();
            e.gravity -= p.mass * g.dot(&m.r);
        }
        for s in &self.springs {
            e.strain += crate::assembly::body::spring_energy(s, &nodes[s.a], s.b.map(|b| &nodes[b]));
        }
        for &(s, k, _, rest, preload) in &self.joint_springs {
            let x = state.scalars[s];
            // The preload's potential is linear in the coordinate.
            e.strain += preload * (x - rest) + 0.5 * k * (x - rest) * (x - rest);
        }
        e.strain += self.joint_forces.limit_energy(&state.scalars);
        Ok(e)
    }

    /// Linear momentum and angular momentum about the origin (module docs; computed by
    /// [`crate::assembly::system::momentum`], which the dynamic solver's momentum projection shares).
    pub fn momentum(&self, state: &State) -> Result<(Vector3<f64>, Vector3<f64>), SolveError> {
        let map = self.momentum_map(state)?;
        let J = self.momentum_at(&map, state, &state.velocity);
        Ok((J.fixed_rows::<3>(0).into(), J.fixed_rows::<3>(3).into()))
    }

    /// The stress shapes and kinematics of flexible body `body` at `state`, for its nodal
    /// stresses (`reduction::StressShapes::node_stresses`, `reduction::StressShapes::von_mises`);
    /// the body's stress shapes are checked by [`System::new`] for every stress sensor.
    fn body_stress_state(
        &self,
        body: BodyId,
        state: &State,
    ) -> Result<(&reduction::StressShapes, superelement::Kinematics), SolveError> {
        let i = self
            .flexible
            .iter()
            .position(|f| f.body == body.index())
            .expect("stress sensors are on flexible bodies (System::new)");
        let f = &self.flexible[i];
        let bs = self.body_state(i, state, &self.node_motions(state));
        let kin = f.se.kinematics(&bs).map_err(|source| SolveError::Body {
            body: self.model.bodies[f.body].name().to_string(),
            id: body,
            at: crate::error::At::Time(state.time),
            step: None,
            source: Box::new(source),
        })?;
        let shapes = f.se.stress_shapes().expect("stress shapes (System::new)");
        Ok((shapes, kin))
    }

    /// [`Self::body_stress_state`] once per body and sensor row: the kinematics of `body` from
    /// `cache`, solved and added to it on first use.
    fn stress_kinematics<'a>(
        &'a self,
        body: BodyId,
        state: &State,
        cache: &'a mut Vec<(BodyId, superelement::Kinematics)>,
    ) -> Result<(&'a reduction::StressShapes, &'a superelement::Kinematics), SolveError> {
        let (shapes, k) = match cache.iter().position(|(b, _)| *b == body) {
            Some(k) => {
                let shapes = self.superelement(body).and_then(|se| se.stress_shapes());
                (shapes.expect("stress shapes (System::new)"), k)
            }
            None => {
                let (shapes, kin) = self.body_stress_state(body, state)?;
                cache.push((body, kin));
                (shapes, cache.len() - 1)
            }
        };
        Ok((shapes, &cache[k].1))
    }

    /// The superelement of flexible body `body` (`None` for a rigid body or an unknown id): for
    /// post-processing with [`Self::flexible_body_state`] (mesh recovery, energies, checks).
    pub fn superelement(&self, body: BodyId) -> Option<&superelement::Superelement> {
        self.flexible.iter().find(|f| f.body == body.index()).map(|f| &f.se)
    }

    /// The superelement state of flexible body `body` at `state`: interface positions,
    /// orientations and velocities from the nodes, modal coordinates and rates, and the last
    /// floating frame (`None` for a rigid body or an unknown id).
    pub fn flexible_body_state(&self, body: BodyId, state: &State) -> Option<superelement::BodyState> {
        let i = self.flexible.iter().position(|f| f.body == body.index())?;
        Some(self.body_state(i, state, &self.node_motions(state)))
    }

    /// The superelement state of flexible element `i`.
    pub(crate) fn body_state(&self, i: usize, state: &State, nodes: &[NodeMotion]) -> superelement::BodyState {
        let f = &self.flexible[i];
        let map = &self.topo.map;
        let eta: Vec<f64> = f.modal.iter().map(|&s| state.scalars[s]).collect();
        let eta_d: Vec<f64> = f
            .modal
            .iter()
            .map(|&s| state.velocity[unknown(map.scalars[s].slot)])
            .collect();
        f.body_state(nodes, &eta, &eta_d, state.frames[i])
    }

    /// The body's velocities $\dot{\mathbf q} = [\mathbf v_1, \boldsymbol\omega_1, \dots, \dot{\boldsymbol\eta}]$
    /// ($6N + m$, the layout of [`superelement::BodyState::velocity_vector`]) from the node
    /// motions and the modal rates.
    fn body_velocities(&self, i: usize, state: &State, nodes: &[NodeMotion]) -> Vec<f64> {
        let f = &self.flexible[i];
        let map = &self.topo.map;
        let mut qd = Vec::with_capacity(6 * f.nodes.len() + f.modal.len());
        for &n in &f.nodes {
            qd.extend_from_slice(nodes[n].v.as_slice());
            qd.extend_from_slice(nodes[n].omega.as_slice());
        }
        qd.extend(f.modal.iter().map(|&s| state.velocity[unknown(map.scalars[s].slot)]));
        qd
    }

    /// A record with this system's sensor names and widths, no rows.
    pub fn sensor_record(&self) -> SensorRecord {
        let widths = self
            .model
            .sensors
            .iter()
            .map(|s| match &s.kind {
                SensorKind::NodePosition { .. }
                | SensorKind::RelativePosition { .. }
                | SensorKind::NodeDisplacement { .. }
                | SensorKind::NodeRotation { .. }
                | SensorKind::NodeVelocity { .. }
                | SensorKind::NodeAngularVelocity { .. }
                | SensorKind::NodeAcceleration { .. }
                | SensorKind::NodeAngularAcceleration { .. }
                | SensorKind::LinearMomentum
                | SensorKind::AngularMomentum => 3,
                SensorKind::Reaction { .. } => 6,
                SensorKind::Stress { .. } => 8,
                SensorKind::MaxVonMises { .. } => 2,
                SensorKind::EnergyBalance => 8,
                SensorKind::ModalCoordinates { body } => self.topo.modal_scalars[body.index()].len(),
                _ => 1,
            })
            .collect();
        SensorRecord {
            names: self.model.sensors.iter().map(|s| s.name.clone()).collect(),
            widths,
            times: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// Generalised residual of scalar coordinate `s` (a reaction when prescribed).
    fn coordinate_effort(&self, ws: &Workspace, s: usize) -> f64 {
        match self.topo.map.scalars[s].slot {
            Slot::Unknown(d) => ws.F[d],
            Slot::Prescribed(p) => ws.reactions[p],
        }
    }

    /// Appends the sensor values at `state` (evaluated into `ws`) to `rec`.
    pub(crate) fn record(&self, state: &State, ws: &Workspace, rec: &mut SensorRecord) -> Result<(), SolveError> {
        let row = self.sensor_row(state, ws, &|_| true, None)?;
        rec.times.push(state.time);
        rec.rows.push(row);
        Ok(())
    }

    /// Whether a sensor's values are found a batch of rows at once
    /// ([`crate::Integrator::record_deferred`]): a largest-von-Mises sensor.
    pub(crate) fn has_deferred_sensors(&self) -> bool {
        self.stress_maxima.iter().any(Option::is_some)
    }

    /// [`Self::record`] into `pending`, with the largest-von-Mises values left for
    /// [`Self::complete_rows`] (placeholders `NaN`). Returns whether the row has a value that
    /// is not finite among the others (it must then be completed at once).
    pub(crate) fn record_pending(
        &self,
        state: &State,
        ws: &Workspace,
        step: usize,
        pending: &mut PendingRows,
    ) -> Result<bool, SolveError> {
        let mut maxima = Vec::new();
        let row = self.sensor_row(state, ws, &|_| true, Some(&mut maxima))?;
        let deferred = |c: usize| {
            maxima
                .iter()
                .any(|m: &DeferredMaximum| c == m.column || c == m.column + 1)
        };
        let bad = row.iter().enumerate().any(|(c, x)| !x.is_finite() && !deferred(c));
        pending.since.get_or_insert_with(std::time::Instant::now);
        pending.rows.push(PendingRow {
            time: state.time,
            step,
            row,
            maxima,
        });
        Ok(bad)
    }

    /// Completes the rows of `pending` (a record's rows waiting for their largest-von-Mises
    /// values, [`crate::Integrator::record_deferred`]) and appends them to `rec` in order:
    /// the maxima of every row of a sensor come from one batched search
    /// ([`reduction::VonMisesMaximum::maxima`]: the same values, to the bit, as a search per
    /// row).
    ///
    /// # Errors
    /// [`SolveError::NonFiniteSensor`] for the first row with a value that is not finite (as
    /// [`crate::Integrator::record`]: that row is the last in `rec`, the later ones are
    /// dropped).
    pub fn complete_rows(&self, pending: &mut PendingRows, rec: &mut SensorRecord) -> Result<(), SolveError> {
        pending.since = None;
        let mut rows = std::mem::take(&mut pending.rows);
        let Some(first) = rows.first() else {
            return Ok(());
        };
        // Every row defers the same sensors, in the same order.
        let deferred: Vec<(usize, usize)> = first.maxima.iter().map(|d| (d.sensor, d.column)).collect();
        for (m, (sensor, column)) in deferred.into_iter().enumerate() {
            let search = &self.stress_maxima[sensor]
                .as_ref()
                .expect("a search per largest-von-Mises sensor (System::new)")
                .search;
            let SensorKind::MaxVonMises { body, .. } = &self.model.sensors[sensor].kind else {
                unreachable!("deferred values are those of largest-von-Mises sensors");
            };
            let shapes = self
                .superelement(*body)
                .and_then(|se| se.stress_shapes())
                .expect("stress shapes (System::new)");
            let states: Vec<&[f64]> = rows.iter().map(|r| r.maxima[m].q.as_slice()).collect();
            let (found, _) = search.maxima(shapes, &states);
            for (r, found) in rows.iter_mut().zip(found) {
                let (node, vm) = found.unwrap_or((0, f64::NAN));
                r.row[column] = vm;
                r.row[column + 1] = node as f64;
            }
        }
        for r in rows {
            rec.times.push(r.time);
            rec.rows.push(r.row);
            rec.check_last_row(r.step)?;
        }
        Ok(())
    }

    /// The values of the sensors `wanted` picks (by index in `Model::sensors`) at `state`
    /// (evaluated into `ws`), side by side in the model's order: the others are not evaluated
    /// (an energy, a momentum or a stress search costs a pass over the bodies). With
    /// `deferred`, the largest-von-Mises sensors' values are placeholders and their states are
    /// pushed there ([`Self::complete_rows`]).
    pub(crate) fn sensor_row(
        &self,
        state: &State,
        ws: &Workspace,
        wanted: &dyn Fn(usize) -> bool,
        mut deferred: Option<&mut Vec<DeferredMaximum>>,
    ) -> Result<Vec<f64>, SolveError> {
        let nodes = &ws.nodes;
        let map = &self.topo.map;
        let mut row = Vec::new();
        let mut energies = None;
        let mut momentum = None;
        // The kinematics of each body with stress sensors, once per row.
        let mut kinematics: Vec<(BodyId, superelement::Kinematics)> = Vec::new();
        let push3 = |row: &mut Vec<f64>, v: Vector3<f64>| row.extend_from_slice(v.as_slice());
        for (i, s) in self.model.sensors.iter().enumerate().filter(|(i, _)| wanted(*i)) {
            match &s.kind {
                SensorKind::NodePosition { node } => push3(&mut row, nodes[node.index()].r),
                SensorKind::NodeDisplacement { node } => push3(
                    &mut row,
                    nodes[node.index()].r - self.model.nodes[node.index()].position,
                ),
                SensorKind::RelativePosition { node, reference } => {
                    let (p, r) = (&nodes[node.index()], &nodes[reference.index()]);
                    push3(&mut row, r.R.inverse() * (p.r - r.r))
                }
                SensorKind::NodeRotation { node } => {
                    let R = nodes[node.index()].R * self.model.nodes[node.index()].orientation.inverse();
                    push3(&mut row, so3::log(&R))
                }
                SensorKind::NodeVelocity { node } => push3(&mut row, nodes[node.index()].v),
                SensorKind::NodeAngularVelocity { node } => push3(&mut row, nodes[node.index()].omega),
                SensorKind::NodeAcceleration { node, axes } => {
                    let m = &nodes[node.index()];
                    push3(&mut row, in_axes(&m.R, *axes, m.a))
                }
                SensorKind::NodeAngularAcceleration { node, axes } => {
                    let m = &nodes[node.index()];
                    push3(&mut row, in_axes(&m.R, *axes, m.alpha))
                }
                SensorKind::LineDistance { node, a, b, normal } => {
                    let (p, a, b) = (nodes[node.index()].r, nodes[a.index()].r, nodes[b.index()].r);
                    let e = (b - a).normalize();
                    let c = e.cross(&(p - a));
                    row.push(match normal {
                        Some(n) => c.dot(&n.normalize()),
                        None => c.norm(),
                    });
                }
                SensorKind::JointCoordinate { joint, coordinate } => {
                    row.push(state.scalars[self.topo.joint_scalars[joint.index()][*coordinate]])
                }
                SensorKind::JointRate { joint, coordinate } => row.push(self.joint_rate(state, *joint, *coordinate)),
                SensorKind::ModalCoordinates { body } => {
                    for &sc in &self.topo.modal_scalars[body.index()] {
                        row.push(state.scalars[sc]);
                    }
                }
                SensorKind::Reaction { node } => match &self.topo.roots[node.index()] {
                    Some(rc) => {
                        let mut f = Vector3::zeros();
                        for (sc, e) in &rc.translation {
                            f += e * self.coordinate_effort(ws, *sc);
                        }
                        let mut m = Vector3::zeros();
                        match &rc.rotation {
                            RootRotation::Free(r) => {
                                let d = map.rotations[*r].dof;
                                m = Vector3::new(ws.F[d], ws.F[d + 1], ws.F[d + 2]);
                            }
                            RootRotation::Axes(axes) => {
                                for (sc, e) in axes {
                                    m += e * self.coordinate_effort(ws, *sc);
                                }
                            }
                        }
                        push3(&mut row, f);
                        push3(&mut row, m);
                    }
                    None => row.extend([f64::NAN; 6]),
                },
                SensorKind::DriverEffort { driver } => {
                    let p = map.prescribed.iter().position(|(d, _)| *d == Some(*driver));
                    row.push(p.map_or(f64::NAN, |p| ws.reactions[p]));
                }
                SensorKind::ActuatorEffort { actuator } => row.push(self.actuator_efforts(state)[*actuator]),
                SensorKind::KineticEnergy | SensorKind::StrainEnergy | SensorKind::GravityPotential => {
                    if energies.is_none() {
                        energies = Some(self.energies_in(state, ws)?);
                    }
                    let e = energies.unwrap();
                    row.push(match s.kind {
                        SensorKind::KineticEnergy => e.kinetic,
                        SensorKind::StrainEnergy => e.strain,
                        _ => e.gravity,
                    });
                }
                SensorKind::EnergyBalance => {
                    if energies.is_none() {
                        energies = Some(self.energies_in(state, ws)?);
                    }
                    row.extend(balance_row(&energies.unwrap(), state.account.as_ref()));
                }
                SensorKind::Stress { body, node } => {
                    let (shapes, kin) = self.stress_kinematics(*body, state, &mut kinematics)?;
                    let (tensor, vm, principal) = shapes.node_stress(*node, &kin.q_jj, &kin.R_j);
                    row.extend_from_slice(&tensor);
                    row.push(vm);
                    row.push(principal);
                }
                SensorKind::MaxVonMises { body, .. } => {
                    // The bounded search over the node set (von Mises is invariant under the
                    // rotation to global axes; the same maximum as every node's), or its state
                    // kept for a batch (Self::complete_rows).
                    let (shapes, kin) = self.stress_kinematics(*body, state, &mut kinematics)?;
                    if let Some(deferred) = deferred.as_deref_mut() {
                        deferred.push(DeferredMaximum {
                            sensor: i,
                            column: row.len(),
                            q: kin.q_jj.clone(),
                        });
                        row.extend([f64::NAN; 2]);
                        continue;
                    }
                    let m = self.stress_maxima[i]
                        .as_ref()
                        .expect("a search per sensor (System::new)");
                    let mut reference = m.reference.lock().unwrap_or_else(|e| e.into_inner());
                    let (node, vm) = m
                        .search
                        .maximum(shapes, &kin.q_jj, &mut reference)
                        .unwrap_or((0, f64::NAN));
                    row.push(vm);
                    row.push(node as f64);
                }
                SensorKind::LinearMomentum | SensorKind::AngularMomentum => {
                    if momentum.is_none() {
                        momentum = Some(self.momentum(state)?);
                    }
                    let (L, H) = momentum.unwrap();
                    push3(
                        &mut row,
                        if matches!(s.kind, SensorKind::LinearMomentum) {
                            L
                        } else {
                            H
                        },
                    );
                }
            }
        }
        Ok(row)
    }
}

/// `x` (global axes) in `axes`, for a node at orientation `R`.
fn in_axes(R: &UnitQuaternion<f64>, axes: SensorAxes, x: Vector3<f64>) -> Vector3<f64> {
    match axes {
        SensorAxes::Global => x,
        SensorAxes::Node => R.inverse_transform_vector(&x),
    }
}

/// The values of an energy-balance sensor (module docs): the work of the actuators, the
/// drivers and the loads, $T$, $U$, $V$, the dissipated energy, the balance error. Without an
/// account (a static state) no work, and the state's own energy as $E_0$.
fn balance_row(e: &Energies, account: Option<&EnergyAccount>) -> [f64; 8] {
    let (work, e0) = account.map_or(([0.0; 4], e.total()), |a| (a.work, a.e0));
    let [actuators, drivers, loads, dissipated] = work;
    let error = e.total() - e0 - (actuators + drivers + loads) + dissipated;
    [
        actuators, drivers, loads, e.kinetic, e.strain, e.gravity, dissipated, error,
    ]
}

/// The energy account of a dynamic run (module docs, "Energy balance").
impl System {
    /// Whether a sensor reads the energy balance (the account is kept only then).
    fn has_energy_balance(&self) -> bool {
        self.model
            .sensors
            .iter()
            .any(|s| matches!(s.kind, SensorKind::EnergyBalance))
    }

    /// Opens the account of a dynamic run starting at `state` (evaluated into `ws`): $E_0$
    /// and the powers at the start, no work yet. Without an energy-balance sensor, none.
    pub(crate) fn start_energy_account(&self, state: &mut State, ws: &Workspace) -> Result<(), SolveError> {
        state.account = None;
        if self.has_energy_balance() {
            state.account = Some(EnergyAccount {
                e0: self.energies_in(state, ws)?.total(),
                t: state.time,
                power: self.powers(state, ws),
                work: [0.0; 4],
            });
        }
        Ok(())
    }

    /// Moves the account `prev` of the last accepted state on to the accepted `state`
    /// (evaluated into `ws`): each work grows by the trapezoid rule, $\tfrac h2(P_n + P_{n+1})$.
    pub(crate) fn advance_energy_account(&self, prev: Option<EnergyAccount>, state: &mut State, ws: &Workspace) {
        state.account = prev.map(|a| {
            let power = self.powers(state, ws);
            let h = state.time - a.t;
            let work = std::array::from_fn(|k| a.work[k] + 0.5 * h * (a.power[k] + power[k]));
            EnergyAccount {
                t: state.time,
                power,
                work,
                ..a
            }
        });
    }

    /// The powers at `state` (evaluated into `ws`, with the reactions summed:
    /// `System::reactions_read`): put in by the actuators, the drivers and the loads, and
    /// dissipated (module docs).
    fn powers(&self, state: &State, ws: &Workspace) -> [f64; 4] {
        let map = &self.topo.map;
        let rate = |s: usize| match map.scalars[s].slot {
            Slot::Unknown(d) => state.velocity[d],
            Slot::Prescribed(p) => ws.presc_rate[p],
        };
        let efforts = self.actuator_efforts(state);
        let actuators = self
            .model
            .actuators
            .iter()
            .zip(&efforts)
            .map(|(a, u)| u * rate(self.topo.joint_scalars[a.joint.index()][a.coordinate]))
            .sum();
        let drivers = ws.reactions.iter().zip(&ws.presc_rate).map(|(r, xd)| r * xd).sum();
        let (mut loads, body_damping) = self.element_powers(state, ws);
        if let (Some(law), Some(buf)) = (&self.force_law, &ws.law) {
            // The loads a force law sets act on their nodes directly, not through a load
            // element; `ws.law` holds the law's values at `state`. A dynamic run's load
            // factor is 1.
            let motion = |n: usize, moment: bool| if moment { ws.nodes[n].omega } else { ws.nodes[n].v };
            loads += law.load_power(&buf.u, (state.time, 1.0), motion);
        }
        let nodes = &ws.nodes;
        let mut dissipated = body_damping;
        for s in &self.springs {
            let (xb, vb) = s.b.map_or((s.ground, Vector3::zeros()), |b| (nodes[b].r, nodes[b].v));
            let d = xb - nodes[s.a].r;
            let l = d.norm();
            if l > 0.0 {
                let ld = d.dot(&(vb - nodes[s.a].v)) / l;
                dissipated += s.c * ld * ld;
            }
        }
        for &(s, _, c, _, _) in &self.joint_springs {
            dissipated += c * rate(s) * rate(s);
        }
        dissipated += self.joint_forces.limit_dissipation(&|s| (state.scalars[s], rate(s)));
        [actuators, drivers, loads, dissipated]
    }

    /// The power of the loads (nodal loads, user forces, loads at flexible bodies' load
    /// points) and of the flexible bodies' damping forces, from the element outputs in `ws`:
    /// each part on the element's ports dotted with the port velocities and modal rates.
    fn element_powers(&self, state: &State, ws: &Workspace) -> (f64, f64) {
        let (mut loads, mut damping) = (0.0, 0.0);
        for (e, b) in self.elements.iter().zip(&ws.elems) {
            let qd = |i: usize| {
                let k = i / 6;
                match e.nodes.get(k) {
                    Some(&n) if i % 6 < 3 => ws.nodes[n].v[i % 6],
                    Some(&n) => ws.nodes[n].omega[i % 6 - 3],
                    None => state.velocity[e.modal[i - 6 * e.nodes.len()]],
                }
            };
            let power = |f: &[f64]| f.iter().enumerate().map(|(i, x)| x * qd(i)).sum::<f64>();
            match e.kind {
                ElementKind::Load(_) | ElementKind::User(_) => loads += power(&b.out.external),
                ElementKind::Flexible(_) => {
                    let ev = &b.flex.as_ref().expect("a flexible element's buffer").ev;
                    // The external part is gravity (counted in V) plus the load-point loads.
                    let point_loads: Vec<f64> = b.out.external.iter().zip(&ev.f_gravity).map(|(x, g)| x - g).collect();
                    loads += power(&point_loads);
                    damping += power(&ev.f_damping);
                }
                _ => {}
            }
        }
        (loads, damping)
    }
}

impl System {
    /// Appends the sensor values at `state` to `rec`, evaluating the forces (reactions and
    /// efforts) at load factor `lambda`: for states that no integrator holds (a buckling mode
    /// drawn on the loaded equilibrium).
    pub fn record_state(&self, state: &State, lambda: f64, rec: &mut SensorRecord) -> Result<(), SolveError> {
        let mut ws = self.workspace();
        let mut s = state.clone();
        self.evaluate_into(&mut s, lambda, false, &mut ws)?;
        self.record(&s, &ws, rec)
    }
}
