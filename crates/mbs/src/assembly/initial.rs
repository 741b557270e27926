//! Initial states that follow the joints ([`crate::InitialCondition`]).
//!
//! A joint coordinate is relative: its value turns (or slides) the joint's child with respect
//! to its parent. For the initial state to mean what it says, everything *behind* the joint
//! moves with the child as one rigid body: the **subtree** of joint $j$ is the set of nodes
//! reached from its child through bodies (the interfaces of a flexible body, the nodes of a
//! rigid body) and other joints, without crossing $j$. With the child's motion from
//! $\mathbf T_{old}$ to $\mathbf T_{new}$ (rotation $\mathbf R_\Delta = \mathbf R_{new}\mathbf R_{old}^T$),
//! every independent node $n$ of the subtree is placed at
//! $$\mathbf r_n' = \mathbf r_{c,new} + \mathbf R_\Delta(\mathbf r_n - \mathbf r_{c,old}),\qquad \mathbf R_n' = \mathbf R_\Delta\mathbf R_n,$$
//! and a rate adds the child's change of velocity $(\delta\mathbf v_c, \delta\boldsymbol\omega)$ as a
//! rigid field, $\mathbf v_n \mathrel{+}= \delta\mathbf v_c + \delta\boldsymbol\omega\times(\mathbf r_n - \mathbf r_c)$,
//! $\boldsymbol\omega_n \mathrel{+}= \delta\boldsymbol\omega$. Dependent nodes follow through their own
//! joints, whose relative coordinates are unchanged, and modal coordinates stay zero, so the
//! flexible bodies start undeformed and without strain rate. Joint values are applied first,
//! then body velocities, then joint rates (additive), then node velocities and the rigid motion
//! of the whole model, each item in the order given.
//!
//! A subtree that reaches the joint's own parent or a node held by the ground (a support or a
//! node driver) closes a **loop**: no rigid motion of its bodies follows the coordinate, which
//! is then set alone, and the start's analysis below closes the loop.
//!
//! A body velocity gives the body and everything attached to it (its **component**, through
//! bodies and joints) the rigid field $\mathbf v(\mathbf x) = \mathbf v_p + \boldsymbol\omega\times(\mathbf x -
//! \mathbf p)$; for a body held by the ground it is a condition of the velocity analysis alone.
//!
//! # The consistent start (`System::new`)
//!
//! After these carries, the start is made consistent, as Adams and Simpack do before the first
//! step. Every flexible body must sit rigidly on its interface nodes (it starts undeformed):
//! with $a$ its first node, each other node $k$ satisfies
//! $$\mathbf r_k - \mathbf r_a - \mathbf R_a\mathbf R_{a0}^T(\mathbf r_{k0} - \mathbf r_{a0}) = 0,\qquad
//! \log\big(\mathbf R_k(\mathbf R_a\mathbf R_{a0}^T\mathbf R_{k0})^T\big) = 0 .$$
//! **Position assembly**: where this fails (a closed loop at a driver's or an initial value),
//! Gauss-Newton steps of least change in the unknowns (but the modal coordinates and the
//! initial joint values) restore it. **Velocity analysis**: the time derivative of the same
//! conditions, $\mathbf v_k - \mathbf v_a - \boldsymbol\omega_a\times(\mathbf r_k - \mathbf r_a) = 0$,
//! $\boldsymbol\omega_k - \boldsymbol\omega_a = 0$ (no strain rate; modal rates zero), with the
//! drivers' rates at $t = 0$ and the initial rates and velocities as further linear conditions
//! $\mathbf A\dot{\mathbf q} = \mathbf b$: the rates carried above change by the least
//! $\delta = \mathbf A^+(\mathbf b - \mathbf A\dot{\mathbf q}^0)$ (scaled unknowns). Conditions that no
//! rates meet (over-determined) are refused naming the drivers and initial conditions involved;
//! a change of a joint or translation coordinate that the conditions leave open
//! (under-determined: a mobility that nothing given fixes, moved by what was given) is refused
//! naming the coordinates. A node whose velocity an initial condition gives is left out of
//! its body's conditions (the user's strain rate). Where the carries already meet every
//! condition (trees; starts given in full) nothing changes.

use crate::assembly::coordinates::Slot;
use crate::assembly::topology::{RootRotation, Topology};
use crate::error::{Entity, ModelError};
use crate::model::time_function::CompiledFunction;
use crate::model::{Body, DriverTarget, InitialCondition, Model, NodeId};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// How one initial condition acts (computed once by [`crate::System::new`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum InitialPlan {
    /// A joint value or rate: the free independent nodes of the subtree behind the joint.
    Subtree(Vec<usize>),
    /// A joint rate in a closed loop: the coordinate alone.
    CoordinateOnly,
    /// A body velocity: the free independent nodes of the body's component.
    Component(Vec<usize>),
    /// Node velocities and the rigid motion of the model.
    Direct,
}

/// Nodes connected by bodies and joints: neighbours with the joint of the edge (`None` for a body).
fn adjacency(model: &Model) -> Vec<Vec<(usize, Option<usize>)>> {
    let mut adj = vec![Vec::new(); model.nodes.len()];
    let mut link = |a: usize, b: usize, j: Option<usize>| {
        if a != b {
            adj[a].push((b, j));
            adj[b].push((a, j));
        }
    };
    for b in &model.bodies {
        let nodes: Vec<usize> = match b {
            Body::Flexible(f) => f.nodes.iter().map(|n| n.index()).collect(),
            Body::Rigid(r) => std::iter::once(r.reference)
                .chain(r.nodes.iter().copied())
                .map(NodeId::index)
                .collect(),
        };
        for &n in nodes.iter().skip(1) {
            link(nodes[0], n, None);
        }
    }
    for (ji, j) in model.joints.iter().enumerate() {
        link(j.parent.index(), j.child.index(), Some(ji));
    }
    adj
}

/// An independent node whose six coordinates are all unknowns (free translation and rotation).
fn free_root(topo: &Topology, n: usize) -> bool {
    let Some(rc) = &topo.roots[n] else { return false };
    rc.translation
        .iter()
        .all(|(s, _)| matches!(topo.map.scalars[*s].slot, Slot::Unknown(_)))
        && matches!(rc.rotation, RootRotation::Free(_))
}

/// The nodes reached from `start` without the edge of joint `skip`; `Err(node)` when one of
/// them is `stop` or held by the ground (an independent node that is not free).
fn reach(
    adj: &[Vec<(usize, Option<usize>)>],
    topo: &Topology,
    start: &[usize],
    skip: Option<usize>,
    stop: Option<usize>,
) -> Result<Vec<usize>, usize> {
    let mut seen = vec![false; adj.len()];
    let mut queue: VecDeque<usize> = start.iter().copied().collect();
    let mut out = Vec::new();
    for &s in start {
        seen[s] = true;
    }
    while let Some(n) = queue.pop_front() {
        if Some(n) == stop || (topo.roots[n].is_some() && !free_root(topo, n)) {
            return Err(n);
        }
        out.push(n);
        for &(m, j) in &adj[n] {
            if j.is_some() && j == skip || seen[m] {
                continue;
            }
            seen[m] = true;
            queue.push_back(m);
        }
    }
    out.sort_unstable();
    Ok(out)
}

/// How each of the model's initial conditions acts; refuses a joint value in a closed loop and a
/// body velocity on a body held by the ground. References must have been checked.
pub(crate) fn plan(model: &Model, topo: &Topology) -> Result<Vec<InitialPlan>, ModelError> {
    let adj = adjacency(model);
    let roots = |nodes: Vec<usize>| nodes.into_iter().filter(|&n| topo.roots[n].is_some()).collect();
    let node_name = |n: usize| model.nodes[n].name.clone();
    model
        .initial
        .iter()
        .enumerate()
        .map(|(i, c)| match c {
            InitialCondition::JointValue { joint, .. } | InitialCondition::JointRate { joint, .. } => {
                let j = &model.joints[joint.index()];
                match reach(&adj, topo, &[j.child.index()], Some(joint.index()), Some(j.parent.index())) {
                    Ok(nodes) => Ok(InitialPlan::Subtree(roots(nodes))),
                    // In a closed loop the coordinate is set alone and the start's loop closure
                    // (`System::new`) places and moves the rest of the loop.
                    Err(_) => Ok(InitialPlan::CoordinateOnly),
                }
            }
            InitialCondition::BodyVelocity { body, .. } => {
                let b = &model.bodies[body.index()];
                let nodes: Vec<usize> = match b {
                    Body::Flexible(f) => f.nodes.iter().map(|n| n.index()).collect(),
                    Body::Rigid(r) => vec![r.reference.index()],
                };
                // A body held by the ground moves through its joints: its velocity is a
                // condition of the start's velocity analysis alone, which solves the joints'
                // rates from it.
                match reach(&adj, topo, &nodes, None, None) {
                    Ok(nodes) => Ok(InitialPlan::Component(roots(nodes))),
                    Err(_) => Ok(InitialPlan::Direct),
                }
            }
            InitialCondition::NodeVelocity { node, .. } if topo.roots[node.index()].is_none() => {
                Err(ModelError::InvalidValue {
                    entity: format!("initial velocity of node '{}'", node_name(node.index())),
                    what: "the node follows a joint (its velocity is its parent's and the joint's rates), so a velocity given to it would be ignored; give the joint's initial `rate` or the body's velocity instead".into(),
                    id: Some(Entity::InitialCondition(i)),
                })
            }
            InitialCondition::NodeVelocity {
                node,
                velocity,
                angular_velocity,
            } => {
                held_velocity(model, topo, node.index(), velocity, angular_velocity).map_err(|what| {
                    ModelError::InvalidValue {
                        entity: format!("initial velocity of node '{}'", node_name(node.index())),
                        what,
                        id: Some(Entity::InitialCondition(i)),
                    }
                })?;
                Ok(InitialPlan::Direct)
            }
            InitialCondition::RigidMotion { .. } => Ok(InitialPlan::Direct),
        })
        .collect()
}

/// Why a velocity $(\mathbf v, \boldsymbol\omega)$ given to independent node `n` cannot be
/// set: a component that is not zero along a direction its support holds or a driver moves
/// (only the free components are unknowns, so it would be dropped without a word). Zero
/// components there are fine; a component counts as zero below $10^{-12}$ of the norm of the
/// velocity it is part of (the round-off of projecting a velocity along a slider onto the
/// slider's other directions).
fn held_velocity(
    model: &Model,
    topo: &Topology,
    n: usize,
    v: &nalgebra::Vector3<f64>,
    w: &nalgebra::Vector3<f64>,
) -> Result<(), String> {
    let Some(rc) = &topo.roots[n] else { return Ok(()) };
    let map = &topo.map;
    let rotation: &[(usize, nalgebra::Vector3<f64>)] = match &rc.rotation {
        RootRotation::Free(_) => &[],
        RootRotation::Axes(axes) => axes,
    };
    let parts = [
        (&rc.translation[..], v, "velocity", "m/s"),
        (rotation, w, "angular velocity", "rad/s"),
    ];
    for (&(s, e), given, what, unit) in parts
        .iter()
        .flat_map(|&(axes, given, what, unit)| axes.iter().map(move |a| (a, given, what, unit)))
    {
        let Slot::Prescribed(p) = map.scalars[s].slot else {
            continue;
        };
        let c = e.dot(given);
        if c.abs() <= 1e-12 * given.norm() {
            continue;
        }
        let by = match map.prescribed[p].0 {
            Some(d) => format!("driver '{}' moves it", model.drivers[d].name),
            None => "its support holds it".into(),
        };
        // A held global axis by its name and the given component along it; another held
        // direction (across a slider, normal to a plane) by its unit vector.
        let component = match (0..3).find(|&k| (e[k].abs() - 1.0).abs() < 1e-12) {
            Some(k) => format!("component {} is {}", ["x", "y", "z"][k], given[k]),
            None => format!("component along [{:.4}, {:.4}, {:.4}] is {c}", e[0], e[1], e[2]),
        };
        return Err(format!(
            "the {what} {component} {unit}, but {by}: give the held components as zero (a driver sets its own rate)"
        ));
    }
    Ok(())
}

/// A driver whose value or rate is not zero at $t = 0$ and whose driven coordinate closes no
/// loop: the free independent nodes behind the coordinate (`roots`) move rigidly with it, in
/// position and velocity, as for an initial joint value (module docs).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DriverStart {
    /// Index into the prescribed coordinates and the driven scalar.
    pub prescribed: usize,
    pub scalar: usize,
    /// The node the coordinate moves: a joint's child, or the driven node.
    pub pivot: usize,
    pub roots: Vec<usize>,
}

/// The drivers with a non-zero value or rate at $t = 0$ outside closed loops and the nodes that
/// move with them.
pub(crate) fn driver_starts(
    model: &Model,
    topo: &Topology,
    drivers: &[CompiledFunction],
) -> Result<Vec<DriverStart>, ModelError> {
    let adj = adjacency(model);
    let mut out = Vec::new();
    for (p, &(driver, scalar)) in topo.map.prescribed.iter().enumerate() {
        let Some(d) = driver else { continue };
        let (x0, xd0, _) = drivers[d].eval(0.0);
        if x0 == 0.0 && xd0 == 0.0 {
            continue;
        }
        let def = &model.drivers[d];
        let (pivot, reached) = match &def.target {
            DriverTarget::Joint { joint, .. } => {
                let j = &model.joints[joint.index()];
                let r = reach(
                    &adj,
                    topo,
                    &[j.child.index()],
                    Some(joint.index()),
                    Some(j.parent.index()),
                );
                (j.child.index(), r)
            }
            DriverTarget::NodeTranslation { node, .. } | DriverTarget::NodeRotation { node } => {
                let n = node.index();
                let start: Vec<usize> = adj[n].iter().map(|&(m, _)| m).filter(|&m| m != n).collect();
                (n, reach_without(&adj, topo, &start, n))
            }
        };
        // A driven coordinate in a closed loop moves no rigid subtree: the start's loop
        // closure (`System::new`) assembles the loop at its value and rate instead.
        if let Ok(nodes) = reached {
            out.push(DriverStart {
                prescribed: p,
                scalar,
                pivot,
                roots: nodes.into_iter().filter(|&n| topo.roots[n].is_some()).collect(),
            });
        }
    }
    Ok(out)
}

/// [`reach`] from `start` that never enters `blocked` (the driven node itself).
fn reach_without(
    adj: &[Vec<(usize, Option<usize>)>],
    topo: &Topology,
    start: &[usize],
    blocked: usize,
) -> Result<Vec<usize>, usize> {
    let pruned: Vec<Vec<(usize, Option<usize>)>> = adj
        .iter()
        .map(|e| e.iter().copied().filter(|&(m, _)| m != blocked).collect())
        .collect();
    reach(&pruned, topo, start, None, None)
}

/// The smallest change $\delta$ of the unknowns that makes the start's linear conditions
/// $\mathbf A(\mathbf x^0 + \delta) = \mathbf b$ hold, in scaled unknowns and rows (both scaled
/// so that their entries are comparable): $\delta = \mathbf A^+\mathbf r$ with
/// $\mathbf r = \mathbf b - \mathbf A\mathbf x^0$, the pseudo-inverse from the singular value
/// decomposition. What is left of $\mathbf r$ (`residual`) is the part no change of the unknowns
/// reaches: conditions that contradict. An unknown with a component in the null space of
/// $\mathbf A$ (`free`) is not fixed by the conditions: a change of it is a choice.
pub(crate) struct LeastChange {
    pub delta: Vec<f64>,
    /// $\mathbf A\delta - \mathbf r$ per row.
    pub residual: Vec<f64>,
    /// Per unknown: $(\mathbf I - \mathbf A^+\mathbf A)_{ii}$ above round-off.
    pub free: Vec<bool>,
}

/// [`LeastChange`] of the `rows` x `cols` matrix `a` (row-major) and the right side `r`.
pub(crate) fn least_change(a: &[f64], rows: usize, cols: usize, r: &[f64]) -> LeastChange {
    if rows == 0 || cols == 0 {
        return LeastChange {
            delta: vec![0.0; cols],
            residual: r.iter().map(|x| -x).collect(),
            free: vec![true; cols],
        };
    }
    let a = nalgebra::DMatrix::from_row_slice(rows, cols, a);
    let svd = a.clone().svd(true, true);
    let smax = svd.singular_values.max();
    // Rank by singular values above round-off of the largest (the conditions are exact:
    // a loop's Jacobian has exact zeros for its mobility).
    let tol = 1e-10 * smax;
    let (u, vt) = (
        svd.u.as_ref().expect("u computed"),
        svd.v_t.as_ref().expect("v computed"),
    );
    let rv = nalgebra::DVector::from_column_slice(r);
    let mut delta = nalgebra::DVector::zeros(cols);
    let mut row_space = vec![0.0; cols];
    for (k, &s) in svd.singular_values.iter().enumerate() {
        if s <= tol || s == 0.0 {
            continue;
        }
        let c = u.column(k).dot(&rv) / s;
        delta += vt.row(k).transpose() * c;
        for (i, p) in row_space.iter_mut().enumerate() {
            *p += vt[(k, i)] * vt[(k, i)];
        }
    }
    let residual = (&a * &delta - rv).iter().copied().collect();
    LeastChange {
        delta: delta.iter().copied().collect(),
        residual,
        free: row_space.iter().map(|p| 1.0 - p > 1e-8).collect(),
    }
}

/// What the start (`System::initial_state`) set and how: the consistent start of
/// `System::new`'s initial position and velocity analysis.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StartReport {
    /// Each driver's name, value and rate at $t = 0$.
    pub drivers: Vec<(String, f64, f64)>,
    /// The initial conditions, each described in the model's names.
    pub initial: Vec<String>,
    /// Unknowns whose rate the velocity analysis solved from the drivers and the initial
    /// conditions (the closed loops and flexible bodies moving rigidly): label and rate.
    pub solved: Vec<(String, f64)>,
    /// Unknowns whose position the position assembly moved (closed loops at a driver's or an
    /// initial value): label and change.
    pub assembled: Vec<(String, f64)>,
    /// Unknowns that nothing sets (degrees of freedom without a driver or an initial rate):
    /// they start at rest, or with the rigid motion an initial condition carries to them.
    pub unset: Vec<String>,
    /// Number of modal coordinates: the flexible bodies start undeformed and without strain
    /// rate (their interface nodes follow the joints rigidly).
    pub modal: usize,
}
