//! The mechanism of a validated study as an `mbs::Model`: the bodies (reduced beforehand by
//! the reduction service, handed in as [`ReducedBodies`]), points merged by fixed joints into
//! nodes, ground nodes for the joints to the ground, the names of the study's loads and the
//! sensor groups, and where the study describes each entity of the model.

#![allow(non_snake_case)]

use crate::error::{BoxError, SolverStopped};
use crate::input::source::KeyPath;
use crate::input::validate::mechanism::{
    joint_is_angle, BodyLoadSpec, BodyRef, BodySource, EffortSpec, FrameSpec, InitialSpec, PointRef, ReactionAt,
    SensorTarget, StressNodes,
};
use crate::input::validate::Study;
use crate::output::observer::SensorGroup;
use crate::output::vtu::VtuMesh;
use mbs::{
    Body, DriverTarget, FlexibleBody, InitialCondition, Load, Model, NodeId, PointMass, RigidBody, SensorKind, Spring,
    Support, System,
};
use nalgebra::{Isometry3, Point3, Vector3};
use reduction::ReducedBody;
use serde_json::json;
use std::collections::BTreeMap;
use std::sync::Arc;
use superelement::FrameChoice;

/// The mechanism as an `mbs::Model`, with what the outputs need.
pub struct BuiltMechanism {
    pub model: Model,
    pub groups: Vec<SensorGroup>,
    /// Per flexible body: the reduced body and its FE mesh for drawing (bodies from parts).
    pub bodies: Vec<BodyOut>,
    /// Per rigid body: its reference node and point nodes.
    pub rigid: Vec<Vec<NodeId>>,
    /// Where each entity of the model is described in the study (the first description of a
    /// node: the body it belongs to), for locating `mbs::ModelError`s by their entity ids.
    pub entities: BTreeMap<mbs::Entity, KeyPath>,
    /// Reductions: (part, coordinates, modes, from cache).
    pub reductions: Vec<serde_json::Value>,
    /// The point loads of the study by name, with their `mbs` loads.
    pub loads: Vec<NamedLoad>,
}

/// A `[[loads]]` point load of the study and where the model holds its values.
#[derive(Clone, Debug)]
pub struct NamedLoad {
    pub name: String,
    pub path: KeyPath,
    pub target: LoadTarget,
}

/// Where the model holds the values of a [`NamedLoad`].
#[derive(Clone, Debug)]
pub enum LoadTarget {
    /// A load at a node: the indices in `Model::loads` of the force and the moment the study
    /// file gives.
    Node(Vec<(mbs::LoadKind, usize)>),
    /// A load at a load point inside a flexible body: its index in `Model::body_loads` (force
    /// and moment both, zero where the file gives none).
    Body(usize),
}

pub struct BodyOut {
    pub name: String,
    /// Shared with the model's body and the system's superelement.
    pub reduced: Arc<ReducedBody>,
    pub mesh: Option<VtuMesh>,
    pub placement: Isometry3<f64>,
    pub frame: FrameChoice,
    pub nodes: Vec<NodeId>,
    /// The body in the multibody model.
    pub id: mbs::BodyId,
}

/// Key of a point before merging: flexible (body, interface index) or rigid (body, point).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Key {
    Flexible(usize, usize),
    Rigid(usize, usize),
}

/// An error about the entity at `path` of the study, located in the file.
fn located(study: &Study, path: &KeyPath, message: impl std::fmt::Display) -> BoxError {
    format!("{}: {path}: {message}", study.location(path)).into()
}

/// Each flexible body's reduced body with its FE mesh for drawing, and a summary entry per
/// reduction.
pub type ReducedBodies = (Vec<(Arc<ReducedBody>, Option<VtuMesh>)>, Vec<serde_json::Value>);

/// The `mbs` load of a `[[loads]]` point load at a load point inside a flexible body, its
/// point name resolved against the body's reduced load points.
fn body_load(study: &Study, l: &BodyLoadSpec, body: &BodyOut) -> Result<mbs::BodyLoad, BoxError> {
    let Some(point) = body.reduced.load_points.iter().position(|p| p.name == l.point) else {
        let interfaces: Vec<&str> = body.reduced.interfaces.iter().map(|i| i.name.as_str()).collect();
        let points: Vec<&str> = body.reduced.load_points.iter().map(|p| p.name.as_str()).collect();
        return Err(located(
            study,
            &l.path.key("at"),
            format!(
                "body '{}' has no interface or load point '{}' (interfaces: {}; load points: {})",
                body.name,
                l.point,
                interfaces.join(", "),
                if points.is_empty() {
                    "none: add `load_points` to the part's reduction".to_string()
                } else {
                    points.join(", ")
                }
            ),
        ));
    };
    Ok(mbs::BodyLoad {
        body: body.id,
        point,
        force: l.force,
        moment: l.moment,
        axes: l.axes,
        time: l.time.clone(),
    })
}

/// The `mbs` sensor and CSV columns of a `stress` sensor on flexible body `b` (module docs of
/// `docs/study-file.md`, `[[sensors]]`): its nodes resolved against the body's mesh.
fn stress_sensor(
    study: &Study,
    path: &KeyPath,
    b: usize,
    nodes: &StressNodes,
    body: &BodyOut,
) -> Result<(SensorKind, Vec<String>), BoxError> {
    let Some(shapes) = &body.reduced.stress else {
        return Err(located(
            study,
            &path.key("of"),
            format!(
                "body '{}' was reduced without stress shapes: set `stress_shapes = true` in its part's [parts.reduction]",
                body.name
            ),
        ));
    };
    let count = shapes.node_count();
    let part = match &study.mechanism.bodies[b].source {
        BodySource::Part(p) => Some(&study.parts[*p]),
        BodySource::File(..) => None,
    };
    let id = body.id;
    match nodes {
        StressNodes::Index(k) => {
            if *k >= count {
                return Err(located(
                    study,
                    &path.key("node"),
                    format!(
                        "body '{}' has {count} mesh nodes with stresses (0 to {})",
                        body.name,
                        count.max(1) - 1
                    ),
                ));
            }
            Ok((SensorKind::Stress { body: id, node: *k }, stress_columns()))
        }
        StressNodes::At(x) => {
            let positions: Vec<Vector3<f64>> = match (&body.reduced.mesh, part) {
                (Some(mesh), _) => mesh.nodes.iter().map(|p| Vector3::from(*p)).collect(),
                (None, Some(part)) => part.base.mesh.nodes.iter().map(|p| p.coords).collect(),
                (None, None) => {
                    return Err(located(
                        study,
                        &path.key("node_at"),
                        "the body file has no mesh node positions (reduced without mesh shapes): give `node`",
                    ))
                }
            };
            let size = positions.iter().map(|p| p.norm()).fold(0.0, f64::max);
            let nearest = (0..positions.len().min(count))
                .min_by(|&i, &j| (positions[i] - x).norm().total_cmp(&(positions[j] - x).norm()));
            match nearest {
                // The node tolerance of the part's `node_at` keys: round-off of the mesh
                // coordinates, not a search radius.
                Some(k) if (positions[k] - x).norm() <= 1e-6 * (1.0 + size) => {
                    Ok((SensorKind::Stress { body: id, node: k }, stress_columns()))
                }
                Some(k) => Err(located(
                    study,
                    &path.key("node_at"),
                    format!(
                        "no mesh node of body '{}' at ({}, {}, {}) (part axes); the nearest, node {k} at ({}, {}, {}), is {:.3e} m away",
                        body.name,
                        x.x,
                        x.y,
                        x.z,
                        positions[k].x,
                        positions[k].y,
                        positions[k].z,
                        (positions[k] - x).norm()
                    ),
                )),
                None => Err(located(study, &path.key("node_at"), "the body has no mesh nodes")),
            }
        }
        StressNodes::Set(name) => {
            let Some(part) = part else {
                return Err(located(
                    study,
                    &path.key("set"),
                    "a body read from a file has no node sets: give `node` or `node_at`",
                ));
            };
            let Some(set) = part.base.mesh.node_set(name) else {
                let known: Vec<&str> = part.base.mesh.node_sets.keys().map(String::as_str).collect();
                return Err(located(
                    study,
                    &path.key("set"),
                    format!(
                        "part '{}' has no node set '{name}' (node sets: {})",
                        part.name,
                        known.join(", ")
                    ),
                ));
            };
            let nodes: Vec<usize> = set.iter().map(|n| n.index()).filter(|&k| k < count).collect();
            if nodes.is_empty() {
                return Err(located(
                    study,
                    &path.key("set"),
                    format!("node set '{name}' has no node with stresses"),
                ));
            }
            Ok((
                SensorKind::MaxVonMises { body: id, nodes },
                vec!["von_mises_max [Pa]".into(), "node [-]".into()],
            ))
        }
    }
}

/// The columns of a stress sensor at one node.
fn stress_columns() -> Vec<String> {
    ["xx", "yy", "zz", "xy", "yz", "zx"]
        .iter()
        .map(|c| format!("stress_{c} [Pa]"))
        .chain(["von_mises [Pa]".into(), "max_principal [Pa]".into()])
        .collect()
}

/// Builds the `mbs::Model` of the study's mechanism (module docs).
pub fn build(study: &Study, bodies: ReducedBodies) -> Result<BuiltMechanism, BoxError> {
    let m = &study.mechanism;
    let (reduced, reductions) = bodies;
    // Every point, its position and its name.
    let mut keys: Vec<Key> = Vec::new();
    let mut positions: Vec<Vector3<f64>> = Vec::new();
    for (b, (body, _)) in reduced.iter().enumerate() {
        let place = m.bodies[b].placement;
        for (k, i) in body.interfaces.iter().enumerate() {
            keys.push(Key::Flexible(b, k));
            positions.push((place * Point3::from(Vector3::from(i.position))).coords);
        }
    }
    for (b, r) in m.rigid_bodies.iter().enumerate() {
        for (k, (_, x)) in r.points.iter().enumerate() {
            keys.push(Key::Rigid(b, k));
            positions.push(*x);
        }
    }
    let key_index = |p: &PointRef| -> Option<usize> {
        let key = match p {
            PointRef::Ground => return None,
            PointRef::Flexible { body, interface } => {
                let k = reduced[*body].0.interfaces.iter().position(|i| i.name == *interface)?;
                Key::Flexible(*body, k)
            }
            PointRef::Rigid { body, point } => Key::Rigid(*body, *point),
        };
        keys.iter().position(|k| *k == key)
    };
    let resolve = |p: &PointRef, path: &KeyPath| -> Result<usize, BoxError> {
        key_index(p).ok_or_else(|| {
            located(
                study,
                path,
                format!("point '{}' is not in the reduced body", m.point_name(p)),
            )
        })
    };
    // Fixed joints merge points into one node (mbs::weld_points).
    let mut grounded: Vec<usize> = Vec::new();
    let mut welds: Vec<(usize, usize)> = Vec::new();
    let mut weld_joint: Vec<usize> = Vec::new();
    for (ji, j) in m.joints.iter().enumerate().filter(|(_, j)| j.kind.is_none()) {
        match (&j.parent, &j.child) {
            (PointRef::Ground, PointRef::Ground) => {}
            (PointRef::Ground, p) | (p, PointRef::Ground) => grounded.push(resolve(p, &j.path)?),
            (a, b) => {
                welds.push((resolve(a, &j.path)?, resolve(b, &j.path)?));
                weld_joint.push(ji);
            }
        }
    }
    let point_label = |k: &Key| match k {
        Key::Flexible(b, i) => format!("{}.{}", m.bodies[*b].name, reduced[*b].0.interfaces[*i].name),
        Key::Rigid(b, i) => format!("{}.{}", m.rigid_bodies[*b].name, m.rigid_bodies[*b].points[*i].0),
    };
    let points: Vec<mbs::merge::Point> = keys
        .iter()
        .zip(&positions)
        .map(|(k, x)| mbs::merge::Point {
            name: point_label(k),
            position: *x,
        })
        .collect();
    let mut model = Model::new(study.title.as_deref().unwrap_or("mechanism"));
    let node_of = mbs::weld_points(&mut model, &points, &welds).map_err(|e| {
        let j = &m.joints[weld_joint[e.weld]];
        located(
            study,
            &j.path,
            format!(
                "fixed joint '{}': '{}' and '{}' are {:.3e} m apart; the points of a fixed joint must coincide",
                j.name,
                m.point_name(&j.parent),
                m.point_name(&j.child),
                e.distance
            ),
        )
    })?;
    let node = |p: &PointRef, path: &KeyPath| -> Result<NodeId, BoxError> { Ok(node_of[resolve(p, path)?]) };
    // Every point of every body has a key (above); a missing one is a bug, reported, never
    // a silent attachment to another node.
    let node_of_key = |key: Key| -> Result<NodeId, BoxError> {
        keys.iter()
            .position(|x| *x == key)
            .map(|i| node_of[i])
            .ok_or_else(|| format!("internal error: point {key:?} of the mechanism has no node").into())
    };
    for g in grounded {
        model.add_support(Support::clamp(node_of[g]));
    }
    let mut entities: BTreeMap<mbs::Entity, KeyPath> = BTreeMap::new();
    // Flexible bodies.
    let mut bodies = Vec::new();
    for (b, (body, mesh)) in reduced.iter().enumerate() {
        // One reduced body per part, shared by the bodies made of it, the model and the system.
        let (body, mesh) = (Arc::clone(body), mesh.clone());
        let spec = &m.bodies[b];
        let nodes: Vec<NodeId> = (0..body.interfaces.len())
            .map(|k| node_of_key(Key::Flexible(b, k)))
            .collect::<Result<_, _>>()?;
        let frame = match &spec.frame {
            FrameSpec::CenterOfMass => FrameChoice::CenterOfMass,
            FrameSpec::AuxiliaryNode => FrameChoice::AuxiliaryNode,
            FrameSpec::InterfaceNode(name) => match body.interfaces.iter().position(|i| i.name == *name) {
                Some(k) => FrameChoice::InterfaceNode(k),
                None => {
                    return Err(located(
                        study,
                        &spec.path.key("frame_interface"),
                        format!("the reduced body has no interface '{name}'"),
                    ))
                }
            },
        };
        let mut damping = spec.damping.clone();
        if let Some(z) = spec.modal_ratio {
            damping.modal_ratios = vec![z; body.n_modes];
        }
        model.add_body(Body::Flexible(Box::new(FlexibleBody {
            name: spec.name.clone(),
            reduced: Arc::clone(&body),
            nodes: nodes.clone(),
            placement: spec.placement,
            frame,
            mass: spec.inertia,
            damping,
            planar: spec.planar,
        })));
        let id = mbs::BodyId(model.bodies.len() as u32 - 1);
        entities.insert(mbs::Entity::Body(id), spec.path.clone());
        for &n in &nodes {
            entities
                .entry(mbs::Entity::Node(n))
                .or_insert_with(|| spec.path.clone());
        }
        bodies.push(BodyOut {
            name: spec.name.clone(),
            reduced: body,
            mesh,
            placement: spec.placement,
            frame,
            nodes,
            id,
        });
    }
    // Rigid bodies: the mass data about the first point (nodes have the identity orientation,
    // so the body's axes are the global axes at t = 0), or about a node at the centre of mass
    // for a body without points.
    let mut rigid = Vec::new();
    for (b, r) in m.rigid_bodies.iter().enumerate() {
        let nodes: Vec<NodeId> = (0..r.points.len())
            .map(|k| node_of_key(Key::Rigid(b, k)))
            .collect::<Result<_, _>>()?;
        let (reference, others) = match nodes.split_first() {
            Some((first, rest)) => (*first, rest.to_vec()),
            None => (
                model.add_node(&format!("{}.(center of mass)", r.name), r.center_of_mass),
                Vec::new(),
            ),
        };
        let c = r.center_of_mass - model.nodes[reference.index()].position;
        let id = model.add_rigid_body(RigidBody {
            name: r.name.clone(),
            reference,
            nodes: others.clone(),
            mass: r.mass,
            center_of_mass: c,
            inertia: r.inertia,
        });
        entities.insert(mbs::Entity::Body(id), r.path.clone());
        let mut all = vec![reference];
        all.extend(others);
        for &n in &all {
            entities.entry(mbs::Entity::Node(n)).or_insert_with(|| r.path.clone());
        }
        rigid.push(all);
    }
    for p in &m.point_masses {
        entities.insert(mbs::Entity::PointMass(model.point_masses.len()), p.path.clone());
        model.point_masses.push(PointMass {
            node: node(&p.at, &p.path)?,
            mass: p.mass,
        });
    }
    for s in &m.springs {
        entities.insert(mbs::Entity::Spring(model.springs.len()), s.path.clone());
        model.springs.push(Spring {
            name: s.name.clone(),
            a: node(&s.a, &s.path)?,
            b: match &s.b {
                Some(b) => Some(node(b, &s.path)?),
                None => None,
            },
            ground_point: s.ground_point,
            stiffness: s.stiffness,
            damping: s.damping,
            rest_length: s.rest_length,
        });
    }
    for s in &m.supports {
        let n = node(&s.at, &s.path)?;
        entities.insert(mbs::Entity::Support(model.supports.len()), s.path.clone());
        model.add_support(Support {
            node: n,
            translation: s.translation.clone(),
            rotation: s.rotation.clone(),
        });
    }
    // Joints (fixed ones are merged nodes, above); a joint to the ground gets a clamped node.
    let mut joint_ids: Vec<Option<mbs::JointId>> = Vec::new();
    let mut ground_nodes: Vec<Option<NodeId>> = Vec::new();
    for j in &m.joints {
        let Some(kind) = &j.kind else {
            joint_ids.push(None);
            ground_nodes.push(None);
            continue;
        };
        let child = node(&j.child, &j.path)?;
        let (parent_node, ground) = match &j.parent {
            PointRef::Ground => {
                let g = model.add_node(&format!("ground.{}", j.name), model.nodes[child.index()].position);
                entities.insert(mbs::Entity::Node(g), j.path.clone());
                entities.insert(mbs::Entity::Support(model.supports.len()), j.path.clone());
                model.add_support(Support::clamp(g));
                (g, Some(g))
            }
            p => (node(p, &j.path)?, None),
        };
        let id = model.add_joint(&j.name, parent_node, child, kind.clone());
        entities.insert(mbs::Entity::Joint(id), j.path.clone());
        joint_ids.push(Some(id));
        ground_nodes.push(ground);
    }
    for d in &m.drivers {
        let Some(joint) = joint_ids[d.joint] else {
            return Err(located(study, &d.path, "a fixed joint cannot be driven"));
        };
        entities.insert(mbs::Entity::Driver(model.drivers.len()), d.path.clone());
        model.add_driver(
            &d.name,
            DriverTarget::Joint {
                joint,
                coordinate: d.coordinate,
            },
            d.motion.clone(),
        );
    }
    if let Some((_, g)) = &m.gravity {
        model.gravity = *g;
    }
    let mut loads = Vec::new();
    for l in &m.loads {
        let n = node(&l.at, &l.path)?;
        let mut ids = Vec::new();
        for (kind, value) in &l.values {
            ids.push((*kind, model.loads.len()));
            entities.insert(mbs::Entity::Load(model.loads.len()), l.path.clone());
            model.add_load(Load {
                node: n,
                kind: *kind,
                axes: l.axes,
                value: *value,
                time: l.time.clone(),
            });
        }
        loads.push(NamedLoad {
            name: l.name.clone(),
            path: l.path.clone(),
            target: LoadTarget::Node(ids),
        });
    }
    for l in &m.body_loads {
        loads.push(NamedLoad {
            name: l.name.clone(),
            path: l.path.clone(),
            target: LoadTarget::Body(model.body_loads.len()),
        });
        entities.insert(mbs::Entity::BodyLoad(model.body_loads.len()), l.path.clone());
        model.body_loads.push(body_load(study, l, &bodies[l.body])?);
    }
    // Sensors.
    let mut groups = Vec::new();
    let xyz = |what: &str, unit: &str| -> Vec<String> {
        ["x", "y", "z"].iter().map(|c| format!("{what}_{c} [{unit}]")).collect()
    };
    for s in &m.sensors {
        let kinds: Vec<(String, SensorKind)>;
        let single = |k: SensorKind| vec![(s.name.clone(), k)];
        // A fixed joint has no coordinates (it is a merged node): its unit is never asked for.
        let quantity = |j: usize, c: usize| -> mbs::CoordinateQuantity {
            m.joints[j]
                .kind
                .as_ref()
                .map_or(mbs::CoordinateQuantity::Angle, |k| k.coordinate_quantity(c))
        };
        let columns: Vec<String> = match &s.target {
            SensorTarget::Position(p)
            | SensorTarget::Displacement(p)
            | SensorTarget::Rotation(p)
            | SensorTarget::Velocity(p)
            | SensorTarget::AngularVelocity(p) => {
                // One node, three components: the mbs sensor, the column name and its unit.
                let node = node(p, &s.path)?;
                let (kind, what, unit) = match &s.target {
                    SensorTarget::Position(_) => (SensorKind::NodePosition { node }, "position", "m"),
                    SensorTarget::Displacement(_) => (SensorKind::NodeDisplacement { node }, "displacement", "m"),
                    SensorTarget::Rotation(_) => (SensorKind::NodeRotation { node }, "rotation", "rad"),
                    SensorTarget::Velocity(_) => (SensorKind::NodeVelocity { node }, "velocity", "m/s"),
                    _ => (SensorKind::NodeAngularVelocity { node }, "angular_velocity", "rad/s"),
                };
                kinds = single(kind);
                xyz(what, unit)
            }
            SensorTarget::RelativePosition(p, r) => {
                kinds = single(SensorKind::RelativePosition {
                    node: node(p, &s.path)?,
                    reference: node(r, &s.path)?,
                });
                xyz("relative_position", "m")
            }
            SensorTarget::Deflection { of, chord, normal } => {
                let (a, b) = (node(&chord[0], &s.path)?, node(&chord[1], &s.path)?);
                let (xa, xb) = (model.nodes[a.index()].position, model.nodes[b.index()].position);
                // Coincident chord points define no line: the "deflection" would be a distance
                // to a point. 1e-9 of the coordinates' size is round-off.
                if (xb - xa).norm() <= 1e-9 * xa.norm().max(xb.norm()).max(f64::MIN_POSITIVE) {
                    return Err(located(
                        study,
                        &s.path.key("chord"),
                        format!(
                            "the chord's points '{}' and '{}' coincide at ({:.6}, {:.6}, {:.6}): a deflection is measured from the line through two distinct points",
                            m.point_name(&chord[0]),
                            m.point_name(&chord[1]),
                            xa.x,
                            xa.y,
                            xa.z
                        ),
                    ));
                }
                kinds = single(SensorKind::LineDistance {
                    node: node(of, &s.path)?,
                    a,
                    b,
                    normal: *normal,
                });
                vec!["deflection [m]".into()]
            }
            SensorTarget::JointCoordinate(j, c) | SensorTarget::JointRate(j, c) => {
                let rate = matches!(s.target, SensorTarget::JointRate(..));
                let Some(joint) = joint_ids[*j] else {
                    return Err(located(study, &s.path, "a fixed joint has no coordinate"));
                };
                kinds = single(if rate {
                    SensorKind::JointRate { joint, coordinate: *c }
                } else {
                    SensorKind::JointCoordinate { joint, coordinate: *c }
                });
                vec![format!(
                    "{} {c} [{}]",
                    if rate { "rate" } else { "coordinate" },
                    quantity(*j, *c).unit(rate)
                )]
            }
            SensorTarget::Stress { body, nodes } => {
                let (kind, columns) = stress_sensor(study, &s.path, *body, nodes, &bodies[*body])?;
                kinds = single(kind);
                columns
            }
            SensorTarget::Modal(b) => {
                kinds = single(SensorKind::ModalCoordinates {
                    body: mbs::BodyId(*b as u32),
                });
                (1..=bodies[*b].reduced.n_modes)
                    .map(|k| format!("eta_{k} [-]"))
                    .collect()
            }
            SensorTarget::Reaction(at) => {
                let n = match at {
                    ReactionAt::Point(p) => node(p, &s.path)?,
                    ReactionAt::GroundJoint(j) => match ground_nodes[*j] {
                        Some(g) => g,
                        None => return Err(located(study, &s.path, "the joint has no ground node")),
                    },
                };
                kinds = single(SensorKind::Reaction { node: n });
                ["Fx [N]", "Fy [N]", "Fz [N]", "Mx [N m]", "My [N m]", "Mz [N m]"]
                    .map(String::from)
                    .to_vec()
            }
            SensorTarget::DriverEffort(d) => {
                kinds = single(SensorKind::DriverEffort { driver: *d });
                let dr = &m.drivers[*d];
                vec![format!("effort [{}]", quantity(dr.joint, dr.coordinate).effort_unit())]
            }
            SensorTarget::ActuatorEffort(a) => {
                kinds = single(SensorKind::ActuatorEffort { actuator: *a });
                let ac = &m.actuators[*a];
                let unit = if joint_is_angle(m, ac.joint, ac.coordinate) {
                    "N m"
                } else {
                    "N"
                };
                vec![format!("effort [{unit}]")]
            }
            SensorTarget::Energy => {
                kinds = vec![
                    (format!("{}.kinetic", s.name), SensorKind::KineticEnergy),
                    (format!("{}.strain", s.name), SensorKind::StrainEnergy),
                    (format!("{}.gravity", s.name), SensorKind::GravityPotential),
                ];
                ["kinetic [J]", "strain [J]", "gravity potential [J]"]
                    .map(String::from)
                    .to_vec()
            }
            SensorTarget::Momentum => {
                kinds = vec![
                    (format!("{}.linear", s.name), SensorKind::LinearMomentum),
                    (format!("{}.angular", s.name), SensorKind::AngularMomentum),
                ];
                [
                    "px [kg m/s]",
                    "py [kg m/s]",
                    "pz [kg m/s]",
                    "Lx [kg m^2/s]",
                    "Ly [kg m^2/s]",
                    "Lz [kg m^2/s]",
                ]
                .map(String::from)
                .to_vec()
            }
        };
        let mbs_names = kinds.iter().map(|(n, _)| n.clone()).collect();
        for (n, k) in kinds {
            entities.insert(mbs::Entity::Sensor(model.sensors.len()), s.path.clone());
            model.add_sensor(&n, k);
        }
        groups.push(SensorGroup {
            name: s.name.clone(),
            mbs_names,
            columns,
        });
    }
    for c in &m.initial {
        let first = model.initial.len();
        let (InitialSpec::Joint { path, .. } | InitialSpec::Point { path, .. } | InitialSpec::Body { path, .. }) = c;
        match c {
            InitialSpec::Joint {
                path,
                joint,
                coordinate,
                value,
                rate,
            } => {
                let Some(j) = joint_ids[*joint] else {
                    return Err(located(study, path, "a fixed joint has no coordinate"));
                };
                if let Some(v) = value {
                    model.initial.push(InitialCondition::JointValue {
                        joint: j,
                        coordinate: *coordinate,
                        value: *v,
                    });
                }
                if let Some(r) = rate {
                    model.initial.push(InitialCondition::JointRate {
                        joint: j,
                        coordinate: *coordinate,
                        rate: *r,
                    });
                }
            }
            InitialSpec::Point {
                path,
                at,
                velocity,
                angular_velocity,
            } => {
                let n = node(at, path)?;
                model.initial.push(InitialCondition::NodeVelocity {
                    node: n,
                    velocity: *velocity,
                    angular_velocity: *angular_velocity,
                })
            }
            InitialSpec::Body {
                body,
                velocity,
                angular_velocity,
                point,
                ..
            } => {
                // Flexible bodies come first in the model, then the rigid ones.
                let (id, centre) = match body {
                    BodyRef::Flexible(k) => {
                        let c = Point3::from(Vector3::from(bodies[*k].reduced.inertia.center_of_mass));
                        (*k, (bodies[*k].placement * c).coords)
                    }
                    BodyRef::Rigid(k) => (bodies.len() + k, m.rigid_bodies[*k].center_of_mass),
                };
                model.initial.push(InitialCondition::BodyVelocity {
                    body: mbs::BodyId(id as u32),
                    velocity: *velocity,
                    angular_velocity: *angular_velocity,
                    point: point.unwrap_or(centre),
                });
            }
        }
        for i in first..model.initial.len() {
            entities.insert(mbs::Entity::InitialCondition(i), path.clone());
        }
    }
    let joint_of = |j: usize, path: &KeyPath| -> Result<mbs::JointId, BoxError> {
        joint_ids[j].ok_or_else(|| located(study, path, "a fixed joint has no coordinate"))
    };
    for s in &m.joint_springs {
        entities.insert(mbs::Entity::JointSpring(model.joint_springs.len()), s.path.clone());
        model.joint_springs.push(mbs::JointSpring {
            joint: joint_of(s.joint, &s.path)?,
            coordinate: s.coordinate,
            stiffness: s.stiffness,
            damping: s.damping,
            rest: s.rest,
            preload: s.preload,
        });
    }
    for l in &m.joint_limits {
        entities.insert(mbs::Entity::JointLimit(model.joint_limits.len()), l.path.clone());
        model.joint_limits.push(mbs::JointLimit {
            name: l.name.clone(),
            joint: joint_of(l.joint, &l.path)?,
            coordinate: l.coordinate,
            lower: l.lower,
            upper: l.upper,
            stiffness: l.stiffness,
            damping: l.damping,
        });
    }
    for a in &m.actuators {
        let effort = match &a.effort {
            EffortSpec::Time(f) => mbs::Effort::Time(f.clone()),
            EffortSpec::Pid {
                joint,
                coordinate,
                setpoint,
                kp,
                ki,
                kd,
                max_effort,
            } => mbs::Effort::Pid(mbs::Pid {
                joint: joint_of(*joint, &a.path)?,
                coordinate: *coordinate,
                setpoint: setpoint.clone(),
                kp: *kp,
                ki: *ki,
                kd: *kd,
                max_effort: *max_effort,
            }),
        };
        entities.insert(mbs::Entity::Actuator(model.actuators.len()), a.path.clone());
        model.actuators.push(mbs::JointActuator {
            name: a.name.clone(),
            joint: joint_of(a.joint, &a.path)?,
            coordinate: a.coordinate,
            effort,
        });
    }
    Ok(BuiltMechanism {
        model,
        groups,
        bodies,
        rigid,
        entities,
        reductions,
        loads,
    })
}

impl BuiltMechanism {
    /// `System::new`, with a model error located at the first of its entities
    /// (`mbs::ModelError::entities`) that the study describes.
    pub fn system(&self, study: &Study) -> Result<System, BoxError> {
        System::new(&self.model).map_err(|e| {
            let message = format!("the mechanism cannot be assembled: {}", crate::error::sentence(&e));
            match self.locate(&e.entities()) {
                Some(path) => located(study, path, message),
                None => format!("{}: {message}", study.source.path.display()).into(),
            }
        })
    }

    /// Where the first of `entities` that the study describes is.
    pub fn locate(&self, entities: &[mbs::Entity]) -> Option<&KeyPath> {
        entities.iter().find_map(|e| self.entities.get(e))
    }

    /// A solver failure of an analysis, located at the study's description of the entity it
    /// failed at (`mbs::SolveError::entity`: the body whose floating frame failed), when the
    /// study describes it.
    pub fn stopped(
        &self,
        study: &Study,
        message: String,
        step: Option<usize>,
        source: mbs::SolveError,
    ) -> SolverStopped {
        let location = source
            .entity()
            .and_then(|e| self.locate(&[e]))
            .map(|path| study.at(path));
        SolverStopped {
            message,
            step,
            location,
            source,
        }
    }

    /// Model size for the summary.
    pub fn size(&self, sys: &System) -> serde_json::Value {
        json!({
            "nodes": self.model.nodes.len(),
            "flexible_bodies": self.bodies.len(),
            "rigid_bodies": self.rigid.len(),
            "joints": self.model.joints.len(),
            "drivers": self.model.drivers.len(),
            "unknowns": sys.n_dof(),
            "system_nonzeros": sys.nnz(),
            "modes_kept": self.bodies.iter().map(|b| json!({"body": b.name, "modes": b.reduced.n_modes, "coordinates": b.reduced.n_coordinates()})).collect::<Vec<_>>(),
            "reductions": self.reductions,
        })
    }
}

/// "5 joints (3 fixed)": every joint of the study, the fixed ones (which weld two points
/// into one node and so are no joint of the solver) counted and named as such.
pub fn joint_count(study: &Study) -> String {
    let joints = &study.mechanism.joints;
    let fixed = joints.iter().filter(|j| j.kind.is_none()).count();
    let plural = if joints.len() == 1 { "" } else { "s" };
    if fixed > 0 {
        format!("{} joint{plural} ({fixed} fixed)", joints.len())
    } else {
        format!("{} joint{plural}", joints.len())
    }
}
