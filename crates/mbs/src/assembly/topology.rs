//! From a [`Model`] to the tree of dependent coordinates (`CoordinateMap`), with the checks
//! that make it well defined.
//!
//! # The tree
//!
//! Rigid bodies weld their nodes into *rigid groups* (a node alone is a group too). Joints
//! connect groups, from the parent node's group to the child node's group. Supports and node
//! drivers connect a node to the ground. Flexible bodies connect nothing: their interface
//! nodes stay independent, which is how a loop closes (theory guide §8).
//!
//! * The undirected graph of nodes and the ground, with an edge per rigid-body attachment, joint
//!   and grounded node, must be a forest: a cycle is a closed loop of rigid bodies and joints,
//!   refused with [`ModelError::RigidLoop`] naming its bodies, joints and supported nodes.
//! * A group has at most one parent joint ([`ModelError::TwoParentJoints`]); a group with a
//!   parent joint cannot be supported ([`ModelError::SupportOnDependentNode`]).
//! * A group without a parent joint is independent: its *entry* node (the supported or driven
//!   node, else the reference node of its first rigid body) carries the independent coordinates
//!   (free translations along the support basis and the free rotation); the group's other nodes
//!   follow by rigid offsets. A group with a parent joint enters at the joint's child node.
//! * Every coordinate must be held by something ([`ModelError::UnheldCoordinate`]): a flexible
//!   body, a mass or inertia, a spring, moving with it.

#![allow(non_snake_case)]

use crate::assembly::coordinates::{Chain, CoordinateMap, Motion, Op, Rotation, Scalar, Slot, Values};
use crate::error::{Entity, ModelError};
use crate::model::{
    Body, BodyId, DriverTarget, InitialCondition, JointId, JointKind, Model, NodeId, RotationSupport, SensorKind,
    Support, TranslationSupport,
};
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::{HashMap, VecDeque};

/// How the independent coordinates of a root node are laid out (for reactions and drivers).
#[derive(Clone, Debug)]
pub(crate) struct RootCoordinates {
    /// Scalar index and inertial direction of the three translations.
    pub translation: [(usize, Vector3<f64>); 3],
    pub rotation: RootRotation,
}

#[derive(Clone, Debug)]
pub(crate) enum RootRotation {
    /// Index into the rotation coordinates.
    Free(usize),
    /// Three scalar rotations (zero where supported) about inertial axes.
    Axes([(usize, Vector3<f64>); 3]),
}

/// The coordinate map and the indices the rest of the crate needs.
#[derive(Clone, Debug)]
pub(crate) struct Topology {
    pub map: CoordinateMap,
    /// Scalar index of each joint coordinate.
    pub joint_scalars: Vec<Vec<usize>>,
    /// Independent nodes' coordinates.
    pub roots: Vec<Option<RootCoordinates>>,
    /// Scalar indices of each body's modal coordinates (empty for rigid bodies).
    pub modal_scalars: Vec<Vec<usize>>,
    /// Dimension of each unknown.
    pub dims: Vec<Dimension>,
    /// The entity each unknown belongs to: the independent node, the joint or the flexible
    /// body (modal coordinates).
    pub dof_owners: Vec<Option<Entity>>,
}

struct UnionFind(Vec<usize>);

impl UnionFind {
    fn new(n: usize) -> Self {
        Self((0..n).collect())
    }
    fn find(&mut self, mut a: usize) -> usize {
        while self.0[a] != a {
            self.0[a] = self.0[self.0[a]];
            a = self.0[a];
        }
        a
    }
    /// False when `a` and `b` were already connected.
    fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.0[ra] = rb;
        true
    }
}

#[derive(Clone, Copy, Debug)]
enum Edge {
    Body(usize),
    Joint(usize),
    Ground(usize),
}

/// Two unit vectors completing `a` (unit) to a right-handed orthonormal basis.
pub(crate) fn perpendicular_pair(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let i = a.iamin();
    let e = Vector3::ith(i, 1.0);
    let b1 = a.cross(&e).normalize();
    let b2 = a.cross(&b1);
    (b1, b2)
}

fn unit(v: &Vector3<f64>, entity: &str, id: Entity, what: &str) -> Result<Vector3<f64>, ModelError> {
    let n = v.norm();
    if !(n > 1e-300) || !n.is_finite() {
        return Err(ModelError::InvalidValue {
            entity: entity.into(),
            what: format!("{what} must be a finite non-zero vector, got {v:?}"),
            id: Some(id),
        });
    }
    Ok(v / n)
}

/// Checks every reference of the model to a node, body or joint.
pub(crate) fn check_references(model: &Model) -> Result<(), ModelError> {
    check_element_references(model)?;
    check_body_load_references(model)?;
    check_sensor_references(model)?;
    check_initial_references(model)
}

/// Who refers to an id, for the message and the error's entity.
type Referrer<'a> = &'a dyn Fn() -> (String, Entity);

/// `id` is a node of the model.
fn check_node(model: &Model, id: NodeId, who: Referrer) -> Result<(), ModelError> {
    let nn = model.nodes.len();
    if id.index() < nn {
        Ok(())
    } else {
        let (referenced_by, by) = who();
        Err(ModelError::UnknownNode {
            id: id.0,
            count: nn,
            referenced_by,
            by,
        })
    }
}

/// `body` is a body of the model.
fn check_body(model: &Model, body: BodyId, who: Referrer) -> Result<(), ModelError> {
    let count = model.bodies.len();
    if body.index() < count {
        return Ok(());
    }
    let (referenced_by, by) = who();
    Err(ModelError::UnknownBody {
        id: body.0,
        count,
        referenced_by,
        by,
    })
}

/// `j` is a joint of the model.
fn check_joint(model: &Model, j: JointId, who: Referrer) -> Result<(), ModelError> {
    if j.index() < model.joints.len() {
        Ok(())
    } else {
        let (referenced_by, by) = who();
        Err(ModelError::UnknownJoint {
            id: j.0,
            count: model.joints.len(),
            referenced_by,
            by,
        })
    }
}

/// The nodes and joints of the bodies, masses, springs, supports, joints, joint springs,
/// drivers and loads.
fn check_element_references(model: &Model) -> Result<(), ModelError> {
    for (bi, b) in model.bodies.iter().enumerate() {
        let who = || (format!("body '{}'", b.name()), Entity::Body(BodyId(bi as u32)));
        match b {
            Body::Flexible(f) => {
                for &n in &f.nodes {
                    check_node(model, n, &who)?;
                }
            }
            Body::Rigid(r) => {
                check_node(model, r.reference, &who)?;
                for &n in &r.nodes {
                    check_node(model, n, &who)?;
                }
            }
        }
    }
    for (i, p) in model.point_masses.iter().enumerate() {
        check_node(model, p.node, &|| (p.label(i), Entity::PointMass(i)))?;
    }
    for (i, s) in model.springs.iter().enumerate() {
        let who = || (format!("spring '{}'", s.name), Entity::Spring(i));
        check_node(model, s.a, &who)?;
        if let Some(b) = s.b {
            check_node(model, b, &who)?;
        }
    }
    for (i, s) in model.supports.iter().enumerate() {
        check_node(model, s.node, &|| (format!("support {i}"), Entity::Support(i)))?;
    }
    for (ji, j) in model.joints.iter().enumerate() {
        let who = || (format!("joint '{}'", j.name), Entity::Joint(JointId(ji as u32)));
        check_node(model, j.parent, &who)?;
        check_node(model, j.child, &who)?;
    }
    for (i, s) in model.joint_springs.iter().enumerate() {
        check_joint(model, s.joint, &|| {
            (format!("joint spring {i}"), Entity::JointSpring(i))
        })?;
    }
    for (i, d) in model.drivers.iter().enumerate() {
        let who = || (format!("driver '{}'", d.name), Entity::Driver(i));
        match &d.target {
            DriverTarget::Joint { joint: j, .. } => check_joint(model, *j, &who)?,
            DriverTarget::NodeTranslation { node: n, .. } | DriverTarget::NodeRotation { node: n } => {
                check_node(model, *n, &who)?
            }
        }
    }
    for (i, l) in model.loads.iter().enumerate() {
        check_node(model, l.node, &|| (format!("load {i}"), Entity::Load(i)))?;
    }
    Ok(())
}

/// Each load at a load point is on a flexible body of the model.
fn check_body_load_references(model: &Model) -> Result<(), ModelError> {
    for (i, l) in model.body_loads.iter().enumerate() {
        match model.bodies.get(l.body.index()) {
            Some(Body::Flexible(_)) => {}
            Some(b) => {
                return Err(ModelError::InvalidValue {
                    entity: format!("body load {i}"),
                    what: format!(
                        "body '{}' is rigid: loads at load points act on flexible bodies",
                        b.name()
                    ),
                    id: Some(Entity::BodyLoad(i)),
                })
            }
            None => {
                return Err(ModelError::UnknownBody {
                    id: l.body.0,
                    count: model.bodies.len(),
                    referenced_by: format!("body load {i}"),
                    by: Entity::BodyLoad(i),
                })
            }
        }
    }
    Ok(())
}

/// The nodes, joints, bodies and drivers the sensors read.
fn check_sensor_references(model: &Model) -> Result<(), ModelError> {
    for (i, s) in model.sensors.iter().enumerate() {
        let who = || (format!("sensor '{}'", s.name), Entity::Sensor(i));
        match &s.kind {
            SensorKind::NodePosition { node: n }
            | SensorKind::NodeDisplacement { node: n }
            | SensorKind::NodeRotation { node: n }
            | SensorKind::NodeVelocity { node: n }
            | SensorKind::NodeAngularVelocity { node: n }
            | SensorKind::NodeAcceleration { node: n, .. }
            | SensorKind::NodeAngularAcceleration { node: n, .. }
            | SensorKind::Reaction { node: n } => check_node(model, *n, &who)?,
            SensorKind::RelativePosition { node: n, reference } => {
                check_node(model, *n, &who)?;
                check_node(model, *reference, &who)?;
            }
            SensorKind::LineDistance { node: n, a, b, .. } => {
                check_node(model, *n, &who)?;
                check_node(model, *a, &who)?;
                check_node(model, *b, &who)?;
            }
            SensorKind::JointCoordinate { joint: j, .. } | SensorKind::JointRate { joint: j, .. } => {
                check_joint(model, *j, &who)?
            }
            SensorKind::ModalCoordinates { body }
            | SensorKind::Stress { body, .. }
            | SensorKind::MaxVonMises { body, .. } => check_body(model, *body, &who)?,
            SensorKind::DriverEffort { driver } if *driver >= model.drivers.len() => {
                return Err(ModelError::InvalidValue {
                    entity: who().0,
                    what: format!("driver {driver} does not exist ({} drivers)", model.drivers.len()),
                    id: Some(Entity::Sensor(i)),
                });
            }
            _ => {}
        }
    }
    Ok(())
}

/// The joints, nodes and bodies of the initial conditions.
fn check_initial_references(model: &Model) -> Result<(), ModelError> {
    for (i, c) in model.initial.iter().enumerate() {
        let who = || ("initial condition".to_string(), Entity::InitialCondition(i));
        match c {
            InitialCondition::JointValue { joint: j, .. } | InitialCondition::JointRate { joint: j, .. } => {
                check_joint(model, *j, &who)?
            }
            InitialCondition::NodeVelocity { node: n, .. } => check_node(model, *n, &who)?,
            InitialCondition::RigidMotion { .. } => {}
            InitialCondition::BodyVelocity { body, .. } => check_body(model, *body, &who)?,
        }
    }
    Ok(())
}

/// The support of each node (at most one).
type Supports<'a> = Vec<Option<&'a Support>>;

/// The driven coordinates: (joint, coordinate), (node, component) and node rotations, each with
/// its driver.
#[derive(Default)]
struct DrivenCoordinates {
    joint: HashMap<(usize, usize), usize>,
    translation: HashMap<(usize, usize), usize>,
    rotation: HashMap<usize, usize>,
}

/// The rigid bodies' node lists (reference first) and, per node, the rigid bodies on it; the
/// rigid group (nodes welded by rigid bodies) of each node and the joints into each group.
struct RigidGroups {
    nodes: Vec<(usize, Vec<usize>)>,
    bodies_of: Vec<Vec<usize>>,
    group: Vec<usize>,
    incoming: HashMap<usize, Vec<usize>>,
}

/// The chains and slots of every node, the order they are computed in, the scalars of each
/// joint and the coordinates of each independent node.
struct Chains {
    chains: Vec<Option<Chain>>,
    chain_slots: Vec<Vec<Slot>>,
    order: Vec<usize>,
    joint_scalars: Vec<Vec<usize>>,
    root_coords: Vec<Option<RootCoordinates>>,
}

/// Builds the coordinate map (module docs). References must have been checked.
pub(crate) fn build(model: &Model) -> Result<Topology, ModelError> {
    let nn = model.nodes.len();
    let support = supports_by_node(model)?;
    let driven = driven_coordinates(model)?;
    let grounded = grounded_nodes(&support, &driven);
    let rigid = rigid_groups(model, &grounded)?;
    let (entry, group_order) = group_order(model, &rigid, &grounded);
    let mut b = Builder::default();
    let Chains {
        chains,
        chain_slots,
        order,
        joint_scalars,
        root_coords,
    } = node_chains(model, &support, &driven, &rigid, &entry, &group_order, &mut b)?;
    debug_assert_eq!(order.len(), nn);
    let modal_scalars = modal_scalars(model, &mut b);

    let n_dof = b.n_dof;
    let col_id = |s: &Slot| match *s {
        Slot::Unknown(d) => d,
        Slot::Prescribed(p) => n_dof + p,
    };
    let chains: Vec<Chain> = chains
        .into_iter()
        .zip(&chain_slots)
        .map(|(c, slots)| {
            let mut c = c.expect("every node is in a group");
            c.cols = slots.iter().map(col_id).collect();
            c
        })
        .collect();
    let map = CoordinateMap {
        scalars: b.scalars,
        rotations: b.rotations,
        n_dof,
        prescribed: b.prescribed,
        chains,
        order,
        dof_labels: b.dof_labels,
    };
    Ok(Topology {
        map,
        joint_scalars,
        roots: root_coords,
        modal_scalars,
        dims: b.dims,
        dof_owners: b.dof_owners,
    })
}

/// Each node's support; two on one node are refused.
fn supports_by_node(model: &Model) -> Result<Supports<'_>, ModelError> {
    let nn = model.nodes.len();
    let name = |i: usize| model.nodes[i].name.clone();
    let mut support = vec![None; nn];
    let mut count = vec![0usize; nn];
    for s in &model.supports {
        count[s.node.index()] += 1;
        support[s.node.index()] = Some(s);
    }
    if let Some(i) = (0..nn).find(|&i| count[i] > 1) {
        return Err(ModelError::DuplicateSupport {
            node: name(i),
            count: count[i],
            node_id: NodeId(i as u32),
            supports: (model.supports.iter().enumerate())
                .filter(|(_, s)| s.node.index() == i)
                .map(|(k, _)| k)
                .collect(),
        });
    }

    Ok(support)
}

/// The coordinate each driver drives, checked (it exists, no other driver drives it).
fn driven_coordinates(model: &Model) -> Result<DrivenCoordinates, ModelError> {
    let mut driven = DrivenCoordinates::default();
    for (di, d) in model.drivers.iter().enumerate() {
        let dup = match &d.target {
            DriverTarget::Joint { joint, coordinate } => {
                let j = &model.joints[joint.index()];
                if *coordinate >= j.kind.n_scalar() {
                    return Err(ModelError::InvalidDriver {
                        driver: d.name.clone(),
                        what: format!(
                            "joint '{}' ({}) has {} scalar coordinates; coordinate {coordinate} does not exist",
                            j.name,
                            j.kind.name(),
                            j.kind.n_scalar()
                        ),
                        driver_id: di,
                    });
                }
                driven.joint.insert((joint.index(), *coordinate), di)
            }
            DriverTarget::NodeTranslation { node, component } => {
                if *component >= 3 {
                    return Err(ModelError::InvalidDriver {
                        driver: d.name.clone(),
                        what: format!("translation component {component} (0, 1 or 2)"),
                        driver_id: di,
                    });
                }
                driven.translation.insert((node.index(), *component), di)
            }
            DriverTarget::NodeRotation { node } => driven.rotation.insert(node.index(), di),
        };
        if let Some(other) = dup {
            return Err(ModelError::InvalidDriver {
                driver: d.name.clone(),
                what: format!("its coordinate is already driven by '{}'", model.drivers[other].name),
                driver_id: di,
            });
        }
    }
    Ok(driven)
}

/// The nodes the ground holds in some direction: by a support or a node driver.
fn grounded_nodes(support: &Supports, driven: &DrivenCoordinates) -> Vec<bool> {
    let nn = support.len();
    let mut grounded = vec![false; nn];
    for i in 0..nn {
        if let Some(s) = support[i] {
            grounded[i] = s.translation != TranslationSupport::Free || s.rotation != RotationSupport::Free;
        }
    }
    for &(n, _) in driven.translation.keys() {
        grounded[n] = true;
    }
    for &n in driven.rotation.keys() {
        grounded[n] = true;
    }

    grounded
}

/// The rigid bodies' node lists and the rigid groups, checked: no loop of rigid bodies, joints
/// and the ground, at most one joint into a group, no support in a group that a joint moves.
fn rigid_groups(model: &Model, grounded: &[bool]) -> Result<RigidGroups, ModelError> {
    let nn = model.nodes.len();
    let name = |i: usize| model.nodes[i].name.clone();
    // Node lists (reference first).
    let mut rigid_nodes: Vec<(usize, Vec<usize>)> = Vec::new();
    for (bi, b) in model.bodies.iter().enumerate() {
        if let Body::Rigid(r) = b {
            let mut nodes = vec![r.reference.index()];
            for n in &r.nodes {
                if !nodes.contains(&n.index()) {
                    nodes.push(n.index());
                }
            }
            rigid_nodes.push((bi, nodes));
        }
    }

    check_rigid_loops(model, &rigid_nodes, grounded)?;

    // Groups.
    let mut groups = UnionFind::new(nn);
    let mut bodies_of: Vec<Vec<usize>> = vec![Vec::new(); nn];
    for (k, (_, nodes)) in rigid_nodes.iter().enumerate() {
        for &n in nodes {
            groups.union(nodes[0], n);
            bodies_of[n].push(k);
        }
    }
    let group: Vec<usize> = (0..nn).map(|i| groups.find(i)).collect();
    let mut incoming: HashMap<usize, Vec<usize>> = HashMap::new();
    for (ji, j) in model.joints.iter().enumerate() {
        incoming.entry(group[j.child.index()]).or_default().push(ji);
    }
    let members = |g: usize| -> Vec<usize> { (0..nn).filter(|&i| group[i] == g).collect() };
    for (g, js) in &incoming {
        if js.len() > 1 {
            return Err(ModelError::TwoParentJoints {
                nodes: members(*g).into_iter().map(name).collect(),
                joints: js.iter().map(|&j| model.joints[j].name.clone()).collect(),
                joint_ids: js.iter().map(|&j| JointId(j as u32)).collect(),
            });
        }
        if let Some(n) = members(*g).into_iter().find(|&n| grounded[n]) {
            return Err(ModelError::SupportOnDependentNode {
                node: name(n),
                joint: model.joints[js[0]].name.clone(),
                node_id: NodeId(n as u32),
                joint_id: JointId(js[0] as u32),
            });
        }
    }

    Ok(RigidGroups {
        nodes: rigid_nodes,
        bodies_of,
        group,
        incoming,
    })
}

/// A loop of rigid bodies, joints and the ground is refused ([`ModelError::RigidLoop`], with the
/// bodies, joints and supported nodes on it).
fn check_rigid_loops(model: &Model, rigid_nodes: &[(usize, Vec<usize>)], grounded: &[bool]) -> Result<(), ModelError> {
    let nn = model.nodes.len();
    let name = |i: usize| model.nodes[i].name.clone();
    // On nodes + ground (index nn).
    let mut uf = UnionFind::new(nn + 1);
    let mut adjacency: Vec<Vec<(usize, Edge)>> = vec![Vec::new(); nn + 1];
    let mut edges: Vec<(usize, usize, Edge)> = Vec::new();
    for (bi, nodes) in rigid_nodes {
        for &n in &nodes[1..] {
            edges.push((nodes[0], n, Edge::Body(*bi)));
        }
    }
    for (ji, j) in model.joints.iter().enumerate() {
        edges.push((j.parent.index(), j.child.index(), Edge::Joint(ji)));
    }
    for i in 0..nn {
        if grounded[i] {
            edges.push((i, nn, Edge::Ground(i)));
        }
    }
    for &(a, b, e) in &edges {
        if !uf.union(a, b) {
            let mut path = tree_path(&adjacency, a, b);
            path.push(e);
            let (mut bodies, mut joints, mut supports) = (Vec::new(), Vec::new(), Vec::new());
            // The ids: bodies, then joints, then supported nodes, each by index.
            let mut ids = [Vec::new(), Vec::new(), Vec::new()];
            for e in path {
                match e {
                    Edge::Body(bi) => {
                        bodies.push(model.bodies[bi].name().to_string());
                        ids[0].push(Entity::Body(BodyId(bi as u32)));
                    }
                    Edge::Joint(ji) => {
                        joints.push(model.joints[ji].name.clone());
                        ids[1].push(Entity::Joint(JointId(ji as u32)));
                    }
                    Edge::Ground(n) => {
                        supports.push(name(n));
                        ids[2].push(Entity::Node(NodeId(n as u32)));
                    }
                }
            }
            for v in [&mut bodies, &mut joints, &mut supports] {
                v.sort();
                v.dedup();
            }
            for v in &mut ids {
                v.sort();
                v.dedup();
            }
            let ids = ids.concat();
            return Err(ModelError::RigidLoop {
                bodies,
                joints,
                supports,
                ids,
            });
        }
        adjacency[a].push((b, e));
        adjacency[b].push((a, e));
    }

    Ok(())
}

/// The entry node of each rigid group (the child of the joint into it, else a grounded node,
/// else a rigid body's reference, else its first node) with that joint, and the groups in
/// tree order (parents first).
#[allow(clippy::type_complexity)]
fn group_order(
    model: &Model,
    rigid: &RigidGroups,
    grounded: &[bool],
) -> (HashMap<usize, (usize, Option<usize>)>, Vec<usize>) {
    let nn = model.nodes.len();
    let (group, incoming, rigid_nodes) = (&rigid.group, &rigid.incoming, &rigid.nodes);
    let members = |g: usize| -> Vec<usize> { (0..nn).filter(|&i| group[i] == g).collect() };
    let mut entry: HashMap<usize, (usize, Option<usize>)> = HashMap::new();
    for i in 0..nn {
        let g = group[i];
        if entry.contains_key(&g) {
            continue;
        }
        let e = if let Some(js) = incoming.get(&g) {
            (model.joints[js[0]].child.index(), Some(js[0]))
        } else if let Some(n) = members(g).into_iter().find(|&n| grounded[n]) {
            (n, None)
        } else if let Some(k) = (0..rigid_nodes.len()).find(|&k| group[rigid_nodes[k].1[0]] == g) {
            (rigid_nodes[k].1[0], None)
        } else {
            (i, None)
        };
        entry.insert(g, e);
    }
    let mut group_list: Vec<usize> = entry.keys().copied().collect();
    group_list.sort();
    let mut children: HashMap<usize, Vec<usize>> = HashMap::new();
    let mut roots: Vec<usize> = Vec::new();
    for &g in &group_list {
        match entry[&g].1 {
            Some(j) => children
                .entry(group[model.joints[j].parent.index()])
                .or_default()
                .push(g),
            None => roots.push(g),
        }
    }
    let mut group_order = Vec::new();
    let mut queue: VecDeque<usize> = roots.into_iter().collect();
    while let Some(g) = queue.pop_front() {
        group_order.push(g);
        if let Some(cs) = children.get(&g) {
            queue.extend(cs.iter().copied());
        }
    }
    debug_assert_eq!(
        group_order.len(),
        group_list.len(),
        "the joint tree is acyclic after the loop check"
    );

    (entry, group_order)
}

/// The chain of each node, group by group in tree order: the entry node's from its support or
/// its joint, the group's other nodes by rigid offsets.
fn node_chains(
    model: &Model,
    support: &Supports,
    driven: &DrivenCoordinates,
    rigid: &RigidGroups,
    entry: &HashMap<usize, (usize, Option<usize>)>,
    group_order: &[usize],
    b: &mut Builder,
) -> Result<Chains, ModelError> {
    let nn = model.nodes.len();
    let mut chains: Vec<Option<Chain>> = vec![None; nn];
    let mut chain_slots: Vec<Vec<Slot>> = vec![Vec::new(); nn];
    let mut order = Vec::with_capacity(nn);
    let mut joint_scalars = vec![Vec::new(); model.joints.len()];
    let mut root_coords = vec![None; nn];
    for &g in group_order {
        let (e, joint) = entry[&g];
        // Entry node.
        let (parent, ops, own) = match joint {
            None => {
                b.owner = Some(Entity::Node(NodeId(e as u32)));
                let (ops, own, rc) = root_chain(model, e, support[e], &driven.translation, &driven.rotation, b)?;
                root_coords[e] = Some(rc);
                (None, ops, own)
            }
            Some(ji) => {
                b.owner = Some(Entity::Joint(JointId(ji as u32)));
                let (mut ops, own, scalars) = joint_chain(model, ji, &driven.joint, b)?;
                // Column positions continue after the parent's columns (prefix property).
                let shift = chain_slots[model.joints[ji].parent.index()].len();
                for op in &mut ops {
                    match op {
                        Op::Translate { col, .. } | Op::Rotate { col, .. } | Op::FreeRotation { col, .. } => {
                            *col += shift
                        }
                        Op::Offset { .. } => {}
                    }
                }
                joint_scalars[ji] = scalars;
                (Some(model.joints[ji].parent.index()), ops, own)
            }
        };
        let mut slots = parent.map_or(Vec::new(), |p| chain_slots[p].clone());
        slots.extend(own);
        chains[e] = Some(Chain {
            parent,
            ops,
            cols: Vec::new(),
            root: parent.is_none(),
        });
        chain_slots[e] = slots;
        order.push(e);
        place_rigid_members(model, e, rigid, &mut chains, &mut chain_slots, &mut order);
    }

    Ok(Chains {
        chains,
        chain_slots,
        order,
        joint_scalars,
        root_coords,
    })
}

/// The chains of the nodes rigidly attached to `e`, by rigid offsets (breadth first from `e`).
fn place_rigid_members(
    model: &Model,
    e: usize,
    rigid: &RigidGroups,
    chains: &mut [Option<Chain>],
    chain_slots: &mut [Vec<Slot>],
    order: &mut Vec<usize>,
) {
    let mut queue = VecDeque::from([e]);
    let mut seen = vec![e];
    while let Some(u) = queue.pop_front() {
        for &k in &rigid.bodies_of[u] {
            for &w in &rigid.nodes[k].1 {
                if seen.contains(&w) {
                    continue;
                }
                seen.push(w);
                let (nu, nw) = (&model.nodes[u], &model.nodes[w]);
                let Rinv = nu.orientation.inverse();
                let op = Op::Offset {
                    d: Rinv * (nw.position - nu.position),
                    C: Rinv * nw.orientation,
                };
                chains[w] = Some(Chain {
                    parent: Some(u),
                    ops: vec![op],
                    cols: Vec::new(),
                    root: false,
                });
                chain_slots[w] = chain_slots[u].clone();
                order.push(w);
                queue.push_back(w);
            }
        }
    }
}

/// The modal coordinates of each flexible body (unknowns).
fn modal_scalars(model: &Model, b: &mut Builder) -> Vec<Vec<usize>> {
    let mut modal_scalars = vec![Vec::new(); model.bodies.len()];
    for (bi, body) in model.bodies.iter().enumerate() {
        if let Body::Flexible(f) = body {
            b.owner = Some(Entity::Body(BodyId(bi as u32)));
            modal_scalars[bi] = (0..f.reduced.n_modes)
                .map(|i| {
                    b.scalar(
                        Slot::Unknown(0),
                        format!("body '{}' modal coordinate {i}", f.name),
                        Dimension::Modal(bi),
                    )
                })
                .collect();
        }
    }

    modal_scalars
}

/// Path of edges between `a` and `b` in the forest `adjacency` (breadth first).
fn tree_path(adjacency: &[Vec<(usize, Edge)>], a: usize, b: usize) -> Vec<Edge> {
    let mut prev: Vec<Option<(usize, Edge)>> = vec![None; adjacency.len()];
    let mut seen = vec![false; adjacency.len()];
    seen[a] = true;
    let mut queue = VecDeque::from([a]);
    while let Some(u) = queue.pop_front() {
        if u == b {
            break;
        }
        for &(w, e) in &adjacency[u] {
            if !seen[w] {
                seen[w] = true;
                prev[w] = Some((u, e));
                queue.push_back(w);
            }
        }
    }
    let mut path = Vec::new();
    let mut u = b;
    while let Some((p, e)) = prev[u] {
        path.push(e);
        u = p;
    }
    path
}

/// The physical dimension of an unknown, for the increment test of Newton.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dimension {
    Length,
    Angle,
    /// Modal coordinate of body `b`.
    Modal(usize),
}

/// Allocation of coordinates.
#[derive(Default)]
struct Builder {
    scalars: Vec<Scalar>,
    rotations: Vec<Rotation>,
    n_dof: usize,
    prescribed: Vec<(Option<usize>, usize)>,
    dof_labels: Vec<String>,
    dims: Vec<Dimension>,
    /// The entity the coordinates allocated now belong to.
    owner: Option<Entity>,
    dof_owners: Vec<Option<Entity>>,
}

/// What a new scalar coordinate is.
enum Kind {
    Free,
    Zero,
    Driven(usize),
}

impl Builder {
    /// A scalar; `Slot::Unknown(_)` allocates an unknown (the index given is ignored).
    fn scalar(&mut self, slot: Slot, label: String, dim: Dimension) -> usize {
        let s = self.scalars.len();
        let slot = match slot {
            Slot::Unknown(_) => {
                self.n_dof += 1;
                self.dof_labels.push(label.clone());
                self.dof_owners.push(self.owner);
                self.dims.push(dim);
                Slot::Unknown(self.n_dof - 1)
            }
            p => p,
        };
        self.scalars.push(Scalar { slot });
        s
    }

    fn new_scalar(&mut self, kind: Kind, label: String, dim: Dimension) -> (usize, Slot) {
        let s = match kind {
            Kind::Free => self.scalar(Slot::Unknown(0), label, dim),
            Kind::Zero | Kind::Driven(_) => {
                let p = self.prescribed.len();
                let driver = if let Kind::Driven(d) = kind { Some(d) } else { None };
                self.prescribed.push((driver, self.scalars.len()));
                self.scalar(Slot::Prescribed(p), label, dim)
            }
        };
        (s, self.scalars[s].slot)
    }

    /// The three rotation scalars of node `node` about the axes `about` (axis, kind, what the
    /// scalar is), each with its `Rotate` operation appended to `ops` and its slot to `slots`.
    fn rotation_axes(
        &mut self,
        node: &str,
        about: [(Vector3<f64>, Kind, &str); 3],
        ops: &mut Vec<Op>,
        slots: &mut Vec<Slot>,
    ) -> RootRotation {
        let mut axes = [(0, Vector3::zeros()); 3];
        for (i, (e, kind, what)) in about.into_iter().enumerate() {
            let (s, slot) = self.new_scalar(kind, format!("node '{node}' {what}"), Dimension::Angle);
            ops.push(Op::Rotate {
                axis: e,
                coord: s,
                col: slots.len(),
            });
            slots.push(slot);
            axes[i] = (s, e);
        }
        RootRotation::Axes(axes)
    }

    fn rotation(&mut self, label: String) -> (usize, [Slot; 3]) {
        let dof = self.n_dof;
        for c in ["x", "y", "z"] {
            self.dof_labels.push(format!("{label}, component {c}"));
            self.dof_owners.push(self.owner);
            self.dims.push(Dimension::Angle);
        }
        self.n_dof += 3;
        self.rotations.push(Rotation { dof });
        (
            self.rotations.len() - 1,
            [Slot::Unknown(dof), Slot::Unknown(dof + 1), Slot::Unknown(dof + 2)],
        )
    }
}

type ChainParts = (Vec<Op>, Vec<Slot>, RootCoordinates);

/// The chain of an independent node: `Offset(r0)`, translations along the support basis,
/// the rotation, `Offset(0, R0)` (see [`crate::assembly::coordinates`]).
fn root_chain(
    model: &Model,
    n: usize,
    support: Option<&Support>,
    trans_driver: &HashMap<(usize, usize), usize>,
    rot_driver: &HashMap<usize, usize>,
    b: &mut Builder,
) -> Result<ChainParts, ModelError> {
    let node = &model.nodes[n];
    let entity = format!("support of node '{}'", node.name);
    let id = model
        .supports
        .iter()
        .position(|s| s.node.index() == n)
        .map_or(Entity::Node(NodeId(n as u32)), Entity::Support);
    let (ts, rs) = match support {
        Some(s) => (s.translation.clone(), s.rotation.clone()),
        None => (TranslationSupport::Free, RotationSupport::Free),
    };
    // The unit vector along `v` (the support's `what`) and a perpendicular pair completing it.
    let unit_frame = |v: &Vector3<f64>, what: &str| {
        let a = unit(v, &entity, id, what)?;
        let (b1, b2) = perpendicular_pair(&a);
        Ok::<_, ModelError>((a, b1, b2))
    };
    let I = [Vector3::<f64>::x(), Vector3::y(), Vector3::z()];
    let (basis, free, names): ([Vector3<f64>; 3], [bool; 3], [&str; 3]) = match &ts {
        TranslationSupport::Free => ([I[0], I[1], I[2]], [true; 3], ["x", "y", "z"]),
        TranslationSupport::Fixed => ([I[0], I[1], I[2]], [false; 3], ["x", "y", "z"]),
        TranslationSupport::Components { fixed } => {
            ([I[0], I[1], I[2]], [!fixed[0], !fixed[1], !fixed[2]], ["x", "y", "z"])
        }
        TranslationSupport::Line { direction } => {
            let (d, b1, b2) = unit_frame(direction, "the slider direction")?;
            (
                [d, b1, b2],
                [true, false, false],
                ["along the line", "across the line (1)", "across the line (2)"],
            )
        }
        TranslationSupport::Plane { normal } => {
            let (nn, b1, b2) = unit_frame(normal, "the plane normal")?;
            (
                [b1, b2, nn],
                [true, true, false],
                ["in-plane 1", "in-plane 2", "normal to the plane"],
            )
        }
    };
    let mut ops = vec![Op::Offset {
        d: node.position,
        C: UnitQuaternion::identity(),
    }];
    let mut slots = Vec::new();
    let mut translation = [(0, Vector3::zeros()); 3];
    for i in 0..3 {
        let kind = match (trans_driver.get(&(n, i)), free[i]) {
            (Some(&d), true) => Kind::Driven(d),
            (Some(&d), false) => {
                return Err(ModelError::InvalidDriver {
                    driver: model.drivers[d].name.clone(),
                    what: format!(
                        "translation component {i} of node '{}' is removed by its support",
                        node.name
                    ),
                    driver_id: d,
                })
            }
            (None, true) => Kind::Free,
            (None, false) => Kind::Zero,
        };
        let (s, slot) = b.new_scalar(
            kind,
            format!("node '{}' translation {}", node.name, names[i]),
            Dimension::Length,
        );
        ops.push(Op::Translate {
            axis: basis[i],
            coord: s,
            col: slots.len(),
        });
        slots.push(slot);
        translation[i] = (s, basis[i]);
    }
    let rot_drv = rot_driver.get(&n).copied();
    let rotation = match &rs {
        RotationSupport::Free | RotationSupport::Fixed if rot_drv.is_some() => {
            return Err(ModelError::InvalidDriver {
                driver: model.drivers[rot_drv.unwrap()].name.clone(),
                what: format!(
                    "node '{}' has no rotation axis to drive: give it a support with `RotationSupport::Axis`",
                    node.name
                ),
                driver_id: rot_drv.unwrap(),
            })
        }
        RotationSupport::Free => {
            let (r, s3) = b.rotation(format!("node '{}' rotation", node.name));
            ops.push(Op::FreeRotation {
                rot: r,
                col: slots.len(),
            });
            slots.extend(s3);
            RootRotation::Free(r)
        }
        RotationSupport::Fixed => {
            let about = [
                (I[0], Kind::Zero, "rotation about x"),
                (I[1], Kind::Zero, "rotation about y"),
                (I[2], Kind::Zero, "rotation about z"),
            ];
            b.rotation_axes(&node.name, about, &mut ops, &mut slots)
        }
        RotationSupport::Axis { axis } => {
            let (a, b1, b2) = unit_frame(axis, "the rotation axis")?;
            let about = [
                (b1, Kind::Zero, "rotation across the axis (1)"),
                (b2, Kind::Zero, "rotation across the axis (2)"),
                (a, rot_drv.map_or(Kind::Free, Kind::Driven), "rotation about its axis"),
            ];
            b.rotation_axes(&node.name, about, &mut ops, &mut slots)
        }
    };
    ops.push(Op::Offset {
        d: Vector3::zeros(),
        C: node.orientation,
    });
    Ok((ops, slots, RootCoordinates { translation, rotation }))
}

type JointParts = (Vec<Op>, Vec<Slot>, Vec<usize>);

/// The operations of a joint, appended to its parent node's frame (axes in the parent's axes).
fn joint_chain(
    model: &Model,
    ji: usize,
    joint_driver: &HashMap<(usize, usize), usize>,
    b: &mut Builder,
) -> Result<JointParts, ModelError> {
    let j = &model.joints[ji];
    let entity = format!("joint '{}'", j.name);
    let id = Entity::Joint(JointId(ji as u32));
    let (p, c) = (&model.nodes[j.parent.index()], &model.nodes[j.child.index()]);
    if j.parent == j.child {
        return Err(ModelError::InvalidValue {
            entity,
            what: "parent and child are the same node".into(),
            id: Some(id),
        });
    }
    let Rp = p.orientation.inverse();
    let d0 = Rp * (c.position - p.position);
    let C0 = Rp * c.orientation;
    let coincide = matches!(
        j.kind,
        JointKind::Spherical | JointKind::Revolute { .. } | JointKind::Universal { .. } | JointKind::Cylindrical { .. }
    );
    let distance = (c.position - p.position).norm();
    if coincide && distance > 1e-9 * (1.0 + p.position.norm()) {
        return Err(ModelError::JointNodesApart {
            joint: j.name.clone(),
            kind: j.kind.name().into(),
            parent: p.name.clone(),
            child: c.name.clone(),
            distance,
            joint_id: JointId(ji as u32),
        });
    }
    let mut ops = Vec::new();
    let mut slots = Vec::new();
    let mut scalars = Vec::new();
    let mut add = |b: &mut Builder, ops: &mut Vec<Op>, rotate: bool, axis: Vector3<f64>, what: &str| {
        let k = scalars.len();
        let kind = joint_driver.get(&(ji, k)).map_or(Kind::Free, |&d| Kind::Driven(d));
        let dim = if rotate { Dimension::Angle } else { Dimension::Length };
        let (s, slot) = b.new_scalar(kind, format!("joint '{}' {what}", j.name), dim);
        let col = slots.len();
        ops.push(if rotate {
            Op::Rotate {
                axis: Rp * axis,
                coord: s,
                col,
            }
        } else {
            Op::Translate {
                axis: Rp * axis,
                coord: s,
                col,
            }
        });
        slots.push(slot);
        scalars.push(s);
    };
    match &j.kind {
        JointKind::Spherical => {
            ops.push(Op::Offset {
                d: d0,
                C: UnitQuaternion::identity(),
            });
            let (r, s3) = b.rotation(format!("joint '{}' rotation", j.name));
            debug_assert!(r < b.rotations.len());
            ops.push(Op::FreeRotation { rot: r, col: 0 });
            slots.extend(s3);
            ops.push(Op::Offset {
                d: Vector3::zeros(),
                C: c.orientation,
            });
        }
        JointKind::Revolute { axis } => {
            add(b, &mut ops, true, unit(axis, &entity, id, "the axis")?, "angle");
        }
        JointKind::Prismatic { axis } => {
            add(b, &mut ops, false, unit(axis, &entity, id, "the axis")?, "displacement");
        }
        JointKind::Cylindrical { axis } => {
            let a = unit(axis, &entity, id, "the axis")?;
            add(b, &mut ops, false, a, "displacement");
            add(b, &mut ops, true, a, "angle");
        }
        JointKind::Universal { axis1, axis2 } => {
            let a1 = unit(axis1, &entity, id, "axis1")?;
            let a2 = unit(axis2, &entity, id, "axis2")?;
            if a1.cross(&a2).norm() < 1e-6 {
                return Err(ModelError::InvalidValue {
                    entity,
                    what: "the two axes are parallel".into(),
                    id: Some(id),
                });
            }
            add(b, &mut ops, true, a1, "angle 1");
            add(b, &mut ops, true, a2, "angle 2");
        }
        JointKind::Planar { normal } => {
            let n = unit(normal, &entity, id, "the normal")?;
            let (b1, b2) = perpendicular_pair(&n);
            add(b, &mut ops, false, b1, "in-plane displacement 1");
            add(b, &mut ops, false, b2, "in-plane displacement 2");
            add(b, &mut ops, true, n, "angle");
        }
    }
    if !matches!(j.kind, JointKind::Spherical) {
        ops.push(Op::Offset { d: d0, C: C0 });
    }
    Ok((ops, slots, scalars))
}

/// Which translations and rotations of each node something holds (module docs).
pub(crate) fn held_coordinates(model: &Model, topo: &Topology) -> Result<(), ModelError> {
    let nn = model.nodes.len();
    let mut held_t = vec![false; nn];
    let mut held_r = vec![false; nn];
    for body in &model.bodies {
        match body {
            Body::Flexible(f) => {
                for n in &f.nodes {
                    held_t[n.index()] = true;
                    held_r[n.index()] = true;
                }
            }
            Body::Rigid(r) => {
                let i = r.reference.index();
                if r.mass > 0.0 {
                    held_t[i] = true;
                }
                if r.inertia.trace() > 0.0 || (r.mass > 0.0 && r.center_of_mass.norm() > 0.0) {
                    held_r[i] = true;
                }
            }
        }
    }
    for p in &model.point_masses {
        if p.mass > 0.0 {
            held_t[p.node.index()] = true;
        }
    }
    for s in &model.springs {
        held_t[s.a.index()] = true;
        if let Some(b) = s.b {
            held_t[b.index()] = true;
        }
    }
    let map = &topo.map;
    let mut held = vec![false; map.n_dof];
    for ms in &topo.modal_scalars {
        for &s in ms {
            if let Slot::Unknown(d) = map.scalars[s].slot {
                held[d] = true;
            }
        }
    }
    for js in &model.joint_springs {
        if let Some(&s) = topo.joint_scalars[js.joint.index()].get(js.coordinate) {
            if let Slot::Unknown(d) = map.scalars[s].slot {
                held[d] = true;
            }
        }
    }
    // J at the initial configuration at rest.
    let scalars = vec![0.0; map.scalars.len()];
    let rotations = vec![UnitQuaternion::identity(); map.rotations.len()];
    let zeros = vec![0.0; map.n_dof];
    let pz = vec![0.0; map.n_prescribed()];
    let x = Values {
        scalars: &scalars,
        rotations: &rotations,
        vel: &zeros,
        acc: &zeros,
        presc_rate: &pz,
        presc_acc: &pz,
    };
    let mut motions = vec![Motion::ground(); nn];
    map.motions_into(&x, &mut motions);
    for c in 0..nn {
        let m = &motions[c];
        for (k, &id) in map.chains[c].cols.iter().enumerate() {
            if id < map.n_dof && ((held_t[c] && m.Jv[k].norm() > 1e-12) || (held_r[c] && m.Jw[k].norm() > 1e-12)) {
                held[id] = true;
            }
        }
    }
    if let Some(d) = held.iter().position(|h| !h) {
        return Err(ModelError::UnheldCoordinate {
            coordinate: map.dof_labels[d].clone(),
            owner: topo.dof_owners[d],
        });
    }
    Ok(())
}
