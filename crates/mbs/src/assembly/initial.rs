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
//! node driver) closes a **loop**: no rigid motion of its bodies follows the coordinate. An
//! initial *value* there is refused (drive the joint to the value and start from an equilibrium
//! instead); an initial *rate* sets the coordinate alone and the loop's other velocities must be
//! given (node velocities), as the bodies in the loop otherwise start with a strain rate.
//!
//! A body velocity gives the body and everything attached to it (its **component**, through
//! bodies and joints) the rigid field $\mathbf v(\mathbf x) = \mathbf v_p + \boldsymbol\omega\times(\mathbf x -
//! \mathbf p)$; a body held by the ground is refused (its motion is its joints' rates).

use crate::assembly::coordinates::Slot;
use crate::assembly::topology::{RootRotation, Topology};
use crate::error::{Entity, ModelError};
use crate::model::time_function::CompiledFunction;
use crate::model::{Body, DriverTarget, InitialCondition, Model, NodeId};
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
                    Err(_) if matches!(c, InitialCondition::JointRate { .. }) => Ok(InitialPlan::CoordinateOnly),
                    Err(n) => Err(ModelError::InvalidValue {
                        entity: format!("initial value of joint '{}'", j.name),
                        what: format!(
                            "the joint is in a closed loop (the bodies behind it reach node '{}', {}), so no rigid motion of them follows its value; drive the joint to the value and start from an equilibrium instead",
                            node_name(n),
                            if n == j.parent.index() { "its own parent" } else { "held by the ground" }
                        ),
                        id: Some(Entity::InitialCondition(i)),
                    }),
                }
            }
            InitialCondition::BodyVelocity { body, .. } => {
                let b = &model.bodies[body.index()];
                let nodes: Vec<usize> = match b {
                    Body::Flexible(f) => f.nodes.iter().map(|n| n.index()).collect(),
                    Body::Rigid(r) => vec![r.reference.index()],
                };
                match reach(&adj, topo, &nodes, None, None) {
                    Ok(nodes) => Ok(InitialPlan::Component(roots(nodes))),
                    Err(n) => Err(ModelError::InvalidValue {
                        entity: format!("initial velocity of body '{}'", b.name()),
                        what: format!(
                            "the body is held by the ground through node '{}'; give the initial rates of its joints instead",
                            node_name(n)
                        ),
                        id: Some(Entity::InitialCondition(i)),
                    }),
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

/// A driver whose function is not zero at $t = 0$: the mechanism is assembled at its initial
/// value by moving the free independent nodes behind the driven coordinate rigidly with it
/// (`roots`), as for an initial joint value (module docs).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DriverStart {
    /// Index into the prescribed coordinates and the driven scalar.
    pub prescribed: usize,
    pub scalar: usize,
    /// The node the coordinate moves: a joint's child, or the driven node.
    pub pivot: usize,
    pub roots: Vec<usize>,
}

/// The drivers with a non-zero value at $t = 0$ and the nodes that move with them; refuses one
/// whose driven coordinate closes a loop (no rigid motion of the bodies behind it follows it).
pub(crate) fn driver_starts(
    model: &Model,
    topo: &Topology,
    drivers: &[CompiledFunction],
) -> Result<Vec<DriverStart>, ModelError> {
    let adj = adjacency(model);
    let mut out = Vec::new();
    for (p, &(driver, scalar)) in topo.map.prescribed.iter().enumerate() {
        let Some(d) = driver else { continue };
        let x0 = drivers[d].eval(0.0).0;
        if x0 == 0.0 {
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
        match reached {
            Ok(nodes) => out.push(DriverStart {
                prescribed: p,
                scalar,
                pivot,
                roots: nodes.into_iter().filter(|&n| topo.roots[n].is_some()).collect(),
            }),
            Err(n) => {
                return Err(ModelError::InvalidDriver {
                    driver: def.name.clone(),
                    what: format!(
                        "its function is {x0} (not zero) at t = 0, and the driven coordinate is in a closed loop (the bodies it moves reach node '{}', {}), so the mechanism cannot be assembled at that value by moving them rigidly; start the function at zero (values are measured from the initial configuration) or model the mechanism in its position at t = 0",
                        model.nodes[n].name,
                        if n == pivot { "the driven node itself" } else { "held by the ground or the joint's parent" }
                    ),
                    driver_id: d,
                })
            }
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
