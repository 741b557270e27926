//! [`System::initial_state`]: the state at the model's initial conditions, with the subtrees
//! behind the joints moved as the plans of [`crate::assembly::initial`] say.

#![allow(non_snake_case)]

use super::{values, System};
use crate::assembly::coordinates::{unknown, Motion};
use crate::assembly::initial::{least_change, InitialPlan, StartReport};
use crate::error::{Entity, ModelError};
use crate::ids::NodeId;
use crate::model::{Body, InitialCondition};
use crate::node::NodeMotion;
use crate::state::State;
use nalgebra::{UnitQuaternion, Vector3};
use superelement::so3;

impl System {
    /// Places the nodes behind each driver that is not zero at $t = 0$ ([`DriverStart`](crate::assembly::initial::DriverStart)): the
    /// pivot's motion from the coordinate at zero to its value in `state` (drivers applied),
    /// carried rigidly to the free nodes behind it, positions and velocities.
    fn assemble_at_drivers(&self, state: &mut State) {
        let np = self.topo.map.n_prescribed();
        for ds in &self.driver_starts {
            let motions = |s: &State, zero: bool| {
                let mut s = s.clone();
                let (mut pr, mut pa) = (vec![0.0; np], vec![0.0; np]);
                self.apply_drivers(&mut s, &mut pr, &mut pa);
                if zero {
                    s.scalars[ds.scalar] = 0.0;
                    pr[ds.prescribed] = 0.0;
                }
                let mut m = vec![crate::assembly::coordinates::Motion::ground(); self.model.nodes.len()];
                self.topo
                    .map
                    .motions_into(&crate::assembly::coordinates::values(&s, &pr, &pa), &mut m);
                m.iter().map(crate::node::NodeMotion::from).collect::<Vec<_>>()
            };
            let (before, after) = (motions(state, true), motions(state, false));
            let (a, b) = (&before[ds.pivot], &after[ds.pivot]);
            let R = b.R * a.R.inverse();
            for &n in &ds.roots {
                let m = &before[n];
                let r = b.r + R * (m.r - a.r);
                // Velocities relative to the pivot are carried along with it.
                let w = b.omega + R * (m.omega - a.omega);
                let v = b.v + b.omega.cross(&(r - b.r)) + R * (m.v - a.v - a.omega.cross(&(m.r - a.r)));
                self.set_node_pose(state, NodeId(n as u32), r, R * m.R);
                self.set_root_velocity(state, n, &v, &w);
            }
        }
    }

    /// Applies the model's initial conditions to `state` (module docs).
    pub(crate) fn apply_initial(&self, state: &mut State) {
        self.assemble_at_drivers(state);
        let map = &self.topo.map;
        let items = || self.model.initial.iter().zip(&self.initial_plan);
        for (c, plan) in items() {
            let InitialCondition::JointValue {
                joint,
                coordinate,
                value,
            } = c
            else {
                continue;
            };
            let child = self.model.joints[joint.index()].child.index();
            let before = self.node_motions(state);
            state.scalars[self.topo.joint_scalars[joint.index()][*coordinate]] = *value;
            if let InitialPlan::Subtree(roots) = plan {
                let after = self.node_motions(state);
                let (a, b) = (&before[child], &after[child]);
                let R = b.R * a.R.inverse();
                for &n in roots {
                    let m = &before[n];
                    self.set_node_pose(state, NodeId(n as u32), b.r + R * (m.r - a.r), R * m.R);
                }
            }
        }
        let motions = self.node_motions(state);
        for (c, plan) in items() {
            if let (
                InitialCondition::BodyVelocity {
                    velocity,
                    angular_velocity: w,
                    point,
                    ..
                },
                InitialPlan::Component(roots),
            ) = (c, plan)
            {
                for &n in roots {
                    self.set_root_velocity(state, n, &(velocity + w.cross(&(motions[n].r - point))), w);
                }
            }
        }
        for (c, plan) in items() {
            let InitialCondition::JointRate {
                joint,
                coordinate,
                rate,
            } = c
            else {
                continue;
            };
            let child = self.model.joints[joint.index()].child.index();
            let before = self.node_motions(state);
            let s = self.topo.joint_scalars[joint.index()][*coordinate];
            // A driven coordinate has its driver's rate: the given one is checked against it
            // by the velocity analysis.
            if !matches!(map.scalars[s].slot, crate::assembly::coordinates::Slot::Unknown(_)) {
                continue;
            }
            state.velocity[unknown(map.scalars[s].slot)] = *rate;
            if let InitialPlan::Subtree(roots) = plan {
                let after = self.node_motions(state);
                let (a, b) = (&before[child], &after[child]);
                let (dv, dw) = (b.v - a.v, b.omega - a.omega);
                for &n in roots {
                    let m = &before[n];
                    let v = m.v + dv + dw.cross(&(m.r - a.r));
                    self.set_root_velocity(state, n, &v, &(m.omega + dw));
                }
            }
        }
        let motions = self.node_motions(state);
        for c in &self.model.initial {
            match c {
                InitialCondition::NodeVelocity {
                    node,
                    velocity,
                    angular_velocity,
                } => {
                    self.set_root_velocity(state, node.index(), velocity, angular_velocity);
                }
                InitialCondition::RigidMotion {
                    velocity,
                    angular_velocity,
                } => {
                    for n in 0..self.model.nodes.len() {
                        if self.topo.roots[n].is_some() {
                            let v = velocity + angular_velocity.cross(&motions[n].r);
                            self.set_root_velocity(state, n, &v, angular_velocity);
                        }
                    }
                }
                _ => {}
            }
        }
    }

    /// A state at rest in the configuration of `state` (elastic coordinates and floating frames
    /// included) at time `time`: velocities and accelerations zero, controllers' integrals
    /// restarted. The hand-over from an equilibrium to a dynamic or linearised analysis.
    pub fn at_rest(&self, state: &State, time: f64) -> State {
        let mut s = state.clone();
        s.time = time;
        s.velocity.iter_mut().for_each(|v| *v = 0.0);
        s.acceleration.iter_mut().for_each(|a| *a = 0.0);
        self.start_controls(&mut s);
        s
    }

    /// The rigid velocity $(\mathbf v_p, \boldsymbol\omega)$ of a body about the point $\mathbf p$:
    /// the least-squares fit of $\mathbf v_k = \mathbf v_p + \boldsymbol\omega\times(\mathbf r_k - \mathbf p)$
    /// to the velocities of its nodes, with $\boldsymbol\omega$ their mean angular velocity (exact for a
    /// rigid body and for a flexible body without strain rate).
    pub fn body_velocity(
        &self,
        state: &State,
        body: crate::ids::BodyId,
        point: &nalgebra::Vector3<f64>,
    ) -> (nalgebra::Vector3<f64>, nalgebra::Vector3<f64>) {
        let motions = self.node_motions(state);
        let nodes: Vec<usize> = match &self.model.bodies[body.index()] {
            Body::Flexible(f) => f.nodes.iter().map(|n| n.index()).collect(),
            Body::Rigid(r) => vec![r.reference.index()],
        };
        let k = nodes.len() as f64;
        let w = nodes.iter().map(|&n| motions[n].omega).sum::<nalgebra::Vector3<f64>>() / k;
        let v = nodes
            .iter()
            .map(|&n| motions[n].v - w.cross(&(motions[n].r - point)))
            .sum::<nalgebra::Vector3<f64>>()
            / k;
        (v, w)
    }
}

/// A condition of the start's velocity analysis (and, for [`Condition::Rigid`], of its
/// position assembly), in rows comparable across translations and rotations: rotational rows
/// times the model size $L$.
enum Condition {
    /// Node `k` of a flexible body moves rigidly with node `a` of the same body:
    /// $\mathbf v_k - \mathbf v_a - \boldsymbol\omega_a\times(\mathbf r_k - \mathbf r_a) = 0$,
    /// $L(\boldsymbol\omega_k - \boldsymbol\omega_a) = 0$ (no strain rate at the start).
    Rigid { body: usize, a: usize, k: usize },
    /// The rate of scalar coordinate `scalar` (initial condition `item`), row scale `scale`.
    Rate {
        scalar: usize,
        rate: f64,
        scale: f64,
        item: usize,
    },
    /// Velocity components of node `node` along `axes` (translation: `false`, rotation: `true`).
    Node {
        node: usize,
        axes: Vec<(Vector3<f64>, bool)>,
        v: Vector3<f64>,
        w: Vector3<f64>,
        item: usize,
    },
    /// A rigid velocity field on the nodes of a body.
    Field {
        nodes: Vec<usize>,
        v: Vector3<f64>,
        w: Vector3<f64>,
        point: Vector3<f64>,
        item: usize,
    },
}

impl Condition {
    fn item(&self) -> Option<usize> {
        match self {
            Condition::Rigid { .. } => None,
            Condition::Rate { item, .. } | Condition::Node { item, .. } | Condition::Field { item, .. } => Some(*item),
        }
    }
}

impl System {
    /// Node motions at `state` with prescribed rates `pr` (the drivers' values applied).
    fn motions_with_rates(&self, state: &State, pr: &[f64]) -> Vec<NodeMotion> {
        let mut s = state.clone();
        let np = self.topo.map.n_prescribed();
        let (mut dummy, pa) = (vec![0.0; np], vec![0.0; np]);
        self.apply_drivers(&mut s, &mut dummy, &mut pa.clone());
        let mut m = vec![Motion::ground(); self.model.nodes.len()];
        self.topo.map.motions_into(&values(&s, pr, &pa), &mut m);
        m.iter().map(NodeMotion::from).collect()
    }

    /// The size $L$ that makes rotations comparable with translations (at least 1 mm).
    fn start_length(&self) -> f64 {
        let nodes = &self.model.nodes;
        let mut l: f64 = 1e-3;
        for a in nodes {
            for b in nodes {
                l = l.max((a.position - b.position).norm());
            }
            if nodes.len() > 200 {
                break;
            }
        }
        l
    }

    /// The flexible bodies' rigid-motion conditions: every node of a body with the first of its
    /// nodes, leaving out the nodes in `own` (whose velocity an initial condition sets: the
    /// user's strain rate).
    fn rigid_conditions(&self, own: &[bool]) -> Vec<Condition> {
        let mut out = Vec::new();
        for (body, b) in self.model.bodies.iter().enumerate() {
            let Body::Flexible(f) = b else { continue };
            let nodes: Vec<usize> = f.nodes.iter().map(|n| n.index()).filter(|&n| !own[n]).collect();
            for &k in nodes.iter().skip(1) {
                out.push(Condition::Rigid { body, a: nodes[0], k });
            }
        }
        out
    }

    /// The initial conditions' rates as conditions (joint rates, node velocities, body
    /// velocities), and the nodes whose own velocity one of them sets.
    fn rate_conditions(&self, l: f64) -> (Vec<Condition>, Vec<bool>) {
        let map = &self.topo.map;
        let mut own = vec![false; self.model.nodes.len()];
        let mut out = Vec::new();
        for (item, c) in self.model.initial.iter().enumerate() {
            match c {
                InitialCondition::JointRate {
                    joint,
                    coordinate,
                    rate,
                } => {
                    let scalar = self.topo.joint_scalars[joint.index()][*coordinate];
                    let scale = match map.scalars[scalar].slot {
                        crate::assembly::coordinates::Slot::Unknown(d) => l / self.dof_scale[d],
                        _ => l,
                    };
                    out.push(Condition::Rate {
                        scalar,
                        rate: *rate,
                        scale,
                        item,
                    });
                }
                InitialCondition::NodeVelocity {
                    node,
                    velocity,
                    angular_velocity,
                } => {
                    own[node.index()] = true;
                    out.push(Condition::Node {
                        node: node.index(),
                        axes: self.free_axes(node.index()),
                        v: *velocity,
                        w: *angular_velocity,
                        item,
                    });
                }
                InitialCondition::BodyVelocity {
                    body,
                    velocity,
                    angular_velocity,
                    point,
                } => {
                    let nodes = match &self.model.bodies[body.index()] {
                        Body::Flexible(f) => f.nodes.iter().map(|n| n.index()).collect(),
                        Body::Rigid(r) => vec![r.reference.index()],
                    };
                    out.push(Condition::Field {
                        nodes,
                        v: *velocity,
                        w: *angular_velocity,
                        point: *point,
                        item,
                    });
                }
                _ => {}
            }
        }
        (out, own)
    }

    /// The directions of independent node `n`'s velocity that are unknowns.
    fn free_axes(&self, n: usize) -> Vec<(Vector3<f64>, bool)> {
        use crate::assembly::coordinates::Slot;
        use crate::assembly::topology::RootRotation;
        let map = &self.topo.map;
        let Some(rc) = &self.topo.roots[n] else {
            return Vec::new();
        };
        let mut axes: Vec<(Vector3<f64>, bool)> = rc
            .translation
            .iter()
            .filter(|(s, _)| matches!(map.scalars[*s].slot, Slot::Unknown(_)))
            .map(|(_, e)| (*e, false))
            .collect();
        match &rc.rotation {
            RootRotation::Free(_) => axes.extend((0..3).map(|k| (Vector3::ith(k, 1.0), true))),
            RootRotation::Axes(a) => axes.extend(
                a.iter()
                    .filter(|(s, _)| matches!(map.scalars[*s].slot, Slot::Unknown(_)))
                    .map(|(_, e)| (*e, true)),
            ),
        }
        axes
    }

    /// The conditions' left sides at motions `m` and coordinate rates `rate(scalar)`, and
    /// their right sides, appended row by row.
    fn condition_rows(
        &self,
        conds: &[Condition],
        m: &[NodeMotion],
        rate: &dyn Fn(usize) -> f64,
        l: f64,
        lhs: &mut Vec<f64>,
        rhs: &mut Vec<f64>,
    ) {
        for c in conds {
            match c {
                Condition::Rigid { a, k, .. } => {
                    let (ma, mk) = (&m[*a], &m[*k]);
                    let e = mk.v - ma.v - ma.omega.cross(&(mk.r - ma.r));
                    let f = (mk.omega - ma.omega) * l;
                    lhs.extend(e.iter().chain(f.iter()));
                    rhs.extend([0.0; 6]);
                }
                Condition::Rate {
                    scalar,
                    rate: given,
                    scale,
                    ..
                } => {
                    lhs.push(rate(*scalar) * scale);
                    rhs.push(given * scale);
                }
                Condition::Node { node, axes, v, w, .. } => {
                    for (e, rot) in axes {
                        let (have, want, s) = if *rot {
                            (m[*node].omega, w, l)
                        } else {
                            (m[*node].v, v, 1.0)
                        };
                        lhs.push(e.dot(&have) * s);
                        rhs.push(e.dot(want) * s);
                    }
                }
                Condition::Field { nodes, v, w, point, .. } => {
                    for &n in nodes {
                        let want = v + w.cross(&(m[n].r - point));
                        lhs.extend(m[n].v.iter().copied().chain(m[n].omega.iter().map(|x| x * l)));
                        rhs.extend(want.iter().copied().chain(w.iter().map(|x| x * l)));
                    }
                }
            }
        }
    }
}

impl System {
    /// The state at $t = 0$ before the start's analysis: the initial configuration with the
    /// drivers' values, the initial values and the rigid carries of [`Self::apply_initial`].
    fn guessed_start(&self) -> State {
        let map = &self.topo.map;
        let mut state = State {
            time: 0.0,
            scalars: vec![0.0; map.scalars.len()],
            rotations: vec![UnitQuaternion::identity(); map.rotations.len()],
            velocity: vec![0.0; map.n_dof],
            acceleration: vec![0.0; map.n_dof],
            frames: Vec::new(),
            controls: Vec::new(),
            account: None,
        };
        let (mut pr, mut pa) = (vec![0.0; map.n_prescribed()], vec![0.0; map.n_prescribed()]);
        self.apply_drivers(&mut state, &mut pr, &mut pa);
        self.apply_initial(&mut state);
        state
    }

    /// The consistent start (module docs of [`crate::assembly::initial`]): the guessed start,
    /// its closed loops assembled at the drivers' and initial values, then its rates solved
    /// from the drivers' and initial rates; frames fitted, controllers at rest.
    pub(crate) fn consistent_start(&self) -> Result<(State, StartReport), ModelError> {
        let mut state = self.guessed_start();
        let l = self.start_length();
        let mut report = StartReport {
            drivers: self
                .model
                .drivers
                .iter()
                .zip(&self.drivers)
                .map(|(d, f)| {
                    let (x, xd, _) = f.eval(0.0);
                    (d.name.clone(), x, xd)
                })
                .collect(),
            initial: (0..self.model.initial.len())
                .map(|i| self.describe_initial(i))
                .collect(),
            modal: self.topo.modal_scalars.iter().map(Vec::len).sum(),
            ..Default::default()
        };
        report.assembled = self.assemble_loops(&mut state, l)?;
        self.solve_rates(&mut state, l, &mut report)?;
        let motions = self.node_motions(&state);
        state.frames = self.flexible.iter().map(|f| super::rigid_fit(f, &motions)).collect();
        self.start_controls(&mut state);
        Ok((state, report))
    }

    /// Initial condition `i` in the model's names.
    fn describe_initial(&self, i: usize) -> String {
        let joint = |j: &crate::ids::JointId| self.model.joints[j.index()].name.clone();
        match &self.model.initial[i] {
            InitialCondition::JointValue { joint: j, value, .. } => format!("value {value} of joint '{}'", joint(j)),
            InitialCondition::JointRate { joint: j, rate, .. } => format!("rate {rate} of joint '{}'", joint(j)),
            InitialCondition::NodeVelocity { node, .. } => {
                format!("velocity of node '{}'", self.model.nodes[node.index()].name)
            }
            InitialCondition::BodyVelocity { body, .. } => {
                format!("velocity of body '{}'", self.model.bodies[body.index()].name())
            }
            InitialCondition::RigidMotion { .. } => "rigid motion of the whole model".into(),
        }
    }

    /// The unknowns the start's analysis solves for: all but the modal coordinates (the bodies
    /// start undeformed, without strain rate) and, for the position assembly (`values`), the
    /// joint coordinates an initial value sets.
    fn start_columns(&self, values: bool) -> Vec<usize> {
        let map = &self.topo.map;
        let mut fixed = vec![false; map.n_dof];
        let mut fix = |s: usize| {
            if let crate::assembly::coordinates::Slot::Unknown(d) = map.scalars[s].slot {
                fixed[d] = true;
            }
        };
        self.topo.modal_scalars.iter().flatten().for_each(|&s| fix(s));
        if values {
            for c in &self.model.initial {
                if let InitialCondition::JointValue { joint, coordinate, .. } = c {
                    fix(self.topo.joint_scalars[joint.index()][*coordinate]);
                }
            }
        }
        (0..map.n_dof).filter(|&d| !fixed[d]).collect()
    }

    /// The rate of every scalar coordinate from the unknowns' rates `v` and prescribed `pr`.
    fn rows_at(&self, state: &State, v: &[f64], pr: &[f64], conds: &[Condition], l: f64) -> (Vec<f64>, Vec<f64>) {
        let mut s = state.clone();
        s.velocity.copy_from_slice(v);
        let m = self.motions_with_rates(&s, pr);
        let map = &self.topo.map;
        let rate = |sc: usize| match map.scalars[sc].slot {
            crate::assembly::coordinates::Slot::Unknown(d) => v[d],
            crate::assembly::coordinates::Slot::Prescribed(p) => pr[p],
        };
        let (mut lhs, mut rhs) = (Vec::new(), Vec::new());
        self.condition_rows(conds, &m, &rate, l, &mut lhs, &mut rhs);
        (lhs, rhs)
    }

    /// The conditions' matrix in the scaled unknowns of `cols` (row-major): column $d$ is the
    /// rows at the unit rate of unknown $d$ times its scale (the rows are linear in the rates).
    fn condition_matrix(&self, state: &State, conds: &[Condition], cols: &[usize], l: f64) -> (Vec<f64>, usize) {
        let np = self.topo.map.n_prescribed();
        let (pr, mut v) = (vec![0.0; np], vec![0.0; self.topo.map.n_dof]);
        let mut columns = Vec::with_capacity(cols.len());
        for &d in cols {
            v[d] = 1.0;
            let (c, _) = self.rows_at(state, &v, &pr, conds, l);
            v[d] = 0.0;
            columns.push(c.into_iter().map(|x| x * self.dof_scale[d]).collect::<Vec<_>>());
        }
        let rows = columns.first().map_or(0, Vec::len);
        let mut a = vec![0.0; rows * cols.len()];
        for (j, c) in columns.iter().enumerate() {
            for (i, x) in c.iter().enumerate() {
                a[i * cols.len() + j] = *x;
            }
        }
        (a, rows)
    }

    /// The flexible bodies' deviation from their rigid placement with respect to their first
    /// node: $\mathbf r_k - \mathbf r_a - \mathbf R_a\mathbf R_{a0}^T(\mathbf r_{k0} - \mathbf r_{a0})$ and
    /// $L\log(\mathbf R_k(\mathbf R_a\mathbf R_{a0}^T\mathbf R_{k0})^T)$, six rows per condition.
    fn closure_error(&self, state: &State, conds: &[Condition], l: f64) -> Vec<f64> {
        let m = self.node_motions(state);
        let n0 = &self.model.nodes;
        let mut out = Vec::with_capacity(6 * conds.len());
        for c in conds {
            let Condition::Rigid { a, k, .. } = c else { continue };
            let R = m[*a].R * n0[*a].orientation.inverse();
            let e = m[*k].r - m[*a].r - R * (n0[*k].position - n0[*a].position);
            let f = so3::log(&(m[*k].R * (R * n0[*k].orientation).inverse())) * l;
            out.extend(e.iter().chain(f.iter()));
        }
        out
    }

    /// The position assembly: Gauss-Newton steps of least change (`least_change`) on the
    /// unknowns but the modal coordinates and the initial joint values until every flexible
    /// body sits rigidly on its first node (nothing moves when it already does, as in a tree).
    /// Returns the unknowns moved and by how much.
    fn assemble_loops(&self, state: &mut State, l: f64) -> Result<Vec<(String, f64)>, ModelError> {
        let conds = self.rigid_conditions(&vec![false; self.model.nodes.len()]);
        let cols = self.start_columns(true);
        let start = state.clone();
        let norm = |e: &[f64]| e.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let mut e = self.closure_error(state, &conds, l);
        if norm(&e) <= 1e-10 * l {
            return Ok(Vec::new());
        }
        let mut dq = vec![0.0; self.topo.map.n_dof];
        for _ in 0..50 {
            let (a, rows) = self.condition_matrix(state, &conds, &cols, l);
            let minus: Vec<f64> = e.iter().map(|x| -x).collect();
            let step = least_change(&a, rows, cols.len(), &minus);
            dq.iter_mut().for_each(|x| *x = 0.0);
            for (j, &d) in cols.iter().enumerate() {
                dq[d] = step.delta[j] * self.dof_scale[d];
            }
            let base = state.clone();
            self.retract_in_place(state, &base, &dq);
            e = self.closure_error(state, &conds, l);
            if norm(&e) <= 1e-13 * l {
                let moved = self.difference(state, &start);
                let labels = self.dof_labels();
                return Ok(cols
                    .iter()
                    .filter(|&&d| moved[d].abs() > 1e-12 * self.dof_scale[d])
                    .map(|&d| (labels[d].clone(), moved[d]))
                    .collect());
            }
        }
        let worst = conds
            .iter()
            .zip(e.chunks(6))
            .max_by(|x, y| norm(x.1).total_cmp(&norm(y.1)))
            .map(|(c, _)| match c {
                Condition::Rigid { body, .. } => self.model.bodies[*body].name().to_string(),
                _ => String::new(),
            })
            .unwrap_or_default();
        Err(ModelError::InvalidValue {
            entity: "the start (initial position assembly)".into(),
            what: format!(
                "the closed loops cannot be assembled at the drivers' and initial values at t = 0 (body '{worst}' stays {:.3e} m off its rigid placement): the values leave no position of the mechanism; check them",
                norm(&e)
            ),
            id: None,
        })
    }
}

impl System {
    /// The velocity analysis: the smallest change of the guessed rates (scaled unknowns but
    /// the modal ones) that makes every flexible body move rigidly and meets the drivers' and
    /// the initial rates. Refuses rates that contradict (over-determined) and a change of a
    /// joint or translation coordinate the conditions leave open (under-determined).
    fn solve_rates(&self, state: &mut State, l: f64, report: &mut StartReport) -> Result<(), ModelError> {
        let (given, own) = self.rate_conditions(l);
        let mut conds = self.rigid_conditions(&own);
        conds.extend(given);
        let cols = self.start_columns(false);
        let map = &self.topo.map;
        let np = map.n_prescribed();
        let (mut pr, mut pa) = (vec![0.0; np], vec![0.0; np]);
        self.apply_drivers(&mut state.clone(), &mut pr, &mut pa);
        let (lhs, rhs) = self.rows_at(state, &state.velocity, &pr, &conds, l);
        let r: Vec<f64> = rhs.iter().zip(&lhs).map(|(b, a)| b - a).collect();
        let (a, rows) = self.condition_matrix(state, &conds, &cols, l);
        let step = least_change(&a, rows, cols.len(), &r);
        let size = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let scale = size(&rhs) + size(&lhs) + 1e-300;
        let owners: Vec<usize> = conds
            .iter()
            .enumerate()
            .flat_map(|(i, c)| std::iter::repeat_n(i, self.condition_len(c)))
            .collect();
        if size(&step.residual) > 1e-8 * scale {
            return Err(self.contradiction(state, &conds, &owners, &step.residual, l, 1e-8 * scale));
        }
        let labels = self.dof_labels();
        let dmax = step.delta.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        if size(&r) > 1e-13 * scale {
            let open: Vec<String> = cols
                .iter()
                .enumerate()
                .filter(|&(j, &d)| step.free[j] && !self.is_rotation_dof(d) && step.delta[j].abs() > 1e-8 * dmax)
                .map(|(_, &d)| labels[d].clone())
                .collect();
            if !open.is_empty() {
                return Err(ModelError::InvalidValue {
                    entity: "the start (initial velocity analysis)".into(),
                    what: format!(
                        "the drivers' and initial rates leave the rates of {} open (the mechanism has more degrees of freedom than rates given): give an initial `rate` for each of its other degrees of freedom",
                        open.join(", ")
                    ),
                    id: None,
                });
            }
            for (j, &d) in cols.iter().enumerate() {
                state.velocity[d] += step.delta[j] * self.dof_scale[d];
            }
        }
        let rate_given: Vec<usize> = conds
            .iter()
            .filter_map(|c| match c {
                Condition::Rate { scalar, .. } => match map.scalars[*scalar].slot {
                    crate::assembly::coordinates::Slot::Unknown(d) => Some(d),
                    _ => None,
                },
                _ => None,
            })
            .collect();
        for (j, &d) in cols.iter().enumerate() {
            let touched = (0..rows).any(|i| a[i * cols.len() + j] != 0.0);
            if step.free[j] {
                report.unset.push(labels[d].clone());
            } else if touched && !rate_given.contains(&d) {
                report.solved.push((labels[d].clone(), state.velocity[d]));
            }
        }
        Ok(())
    }

    fn condition_len(&self, c: &Condition) -> usize {
        match c {
            Condition::Rigid { .. } => 6,
            Condition::Rate { .. } => 1,
            Condition::Node { axes, .. } => axes.len(),
            Condition::Field { nodes, .. } => 6 * nodes.len(),
        }
    }

    /// Whether unknown `d` is a component of a rotation (a spin the conditions leave open, as a
    /// rod's between two spherical joints, is left at least change).
    fn is_rotation_dof(&self, d: usize) -> bool {
        self.topo.map.rotations.iter().any(|r| (r.dof..r.dof + 3).contains(&d))
    }

    /// The error of rates that contradict: the initial conditions and drivers whose rows keep
    /// a residual above `tol`.
    fn contradiction(
        &self,
        state: &State,
        conds: &[Condition],
        owners: &[usize],
        residual: &[f64],
        l: f64,
        tol: f64,
    ) -> ModelError {
        let mut items: Vec<usize> = Vec::new();
        let mut bodies: Vec<String> = Vec::new();
        for (i, x) in residual.iter().enumerate() {
            if x.abs() <= tol {
                continue;
            }
            match &conds[owners[i]] {
                Condition::Rigid { body, .. } => {
                    let name = format!("body '{}'", self.model.bodies[*body].name());
                    if !bodies.contains(&name) {
                        bodies.push(name);
                    }
                }
                c => {
                    let item = c.item().unwrap_or(0);
                    if !items.contains(&item) {
                        items.push(item);
                    }
                }
            }
        }
        // A driver takes part when its rate moves the rows that keep the residual.
        let map = &self.topo.map;
        let mut drivers: Vec<usize> = Vec::new();
        let v = vec![0.0; map.n_dof];
        for (p, &(driver, _)) in map.prescribed.iter().enumerate() {
            let Some(d) = driver else { continue };
            let mut pr = vec![0.0; map.n_prescribed()];
            pr[p] = 1.0;
            let (c, _) = self.rows_at(state, &v, &pr, conds, l);
            let dot: f64 = c.iter().zip(residual).map(|(a, b)| a * b).sum();
            if dot.abs() > tol * 1e-3 && !drivers.contains(&d) {
                drivers.push(d);
            }
        }
        let mut named: Vec<String> = drivers
            .iter()
            .map(|&d| format!("the rate of driver '{}'", self.model.drivers[d].name))
            .collect();
        named.extend(
            items
                .iter()
                .map(|&i| format!("the initial {}", self.describe_initial(i))),
        );
        let id = items
            .first()
            .map(|&i| Entity::InitialCondition(i))
            .or(drivers.first().map(|&d| Entity::Driver(d)));
        let through = if bodies.is_empty() {
            String::new()
        } else {
            format!(" (through {} moving rigidly)", bodies.join(", "))
        };
        ModelError::InvalidValue {
            entity: "the start (initial velocity analysis)".into(),
            what: format!(
                "{} contradict: no motion of the mechanism{through} has them all (the start is over-determined); give fewer rates, the others are solved",
                named.join(" and ")
            ),
            id,
        }
    }
}
