//! The analyses of the mechanism: the validated [`crate::input::validate::mechanism::Mechanism`] becomes an `mbs::Model` (bodies
//! reduced through the cache, points merged by fixed joints into nodes, ground nodes for the
//! joints to the ground), then `mbs::solve_static`, the generalized-α `mbs::Integrator` step
//! by step, or `mbs::spectrum`.
//!
//! Results stream as they are computed: one CSV file per sensor (header with units), flushed
//! after every row, and the deformed meshes of every body (`mechanism_NNNNN.vtu`, listed in
//! `mechanism.pvd`, rewritten after each) at the output times, so an interrupted run keeps
//! them. A solver failure keeps what was written and reports time, step and residual.

#![allow(non_snake_case)]

use crate::error::{BoxError, ResultExt, SolverStopped};
use crate::input::source::KeyPath;
use crate::input::validate::mechanism::{
    joint_is_angle, About, BodyLoadSpec, BodyRef, BodySource, EffortSpec, FrameSpec, InitialSpec, MbsAnalysis,
    PointRef, ReactionAt, SensorTarget, StressNodes,
};
use crate::input::validate::Study;
use crate::output::observer::{Cell, Observer, Progress, SensorGroup, SensorStream, Series, Table};
use crate::output::vtu::{CellRole, PointField, VtuMesh};
use crate::run::{reduce_part, Reduced};
use crate::simulation::{sensor_columns, Simulation};
use mbs::{
    Body, DriverTarget, FlexibleBody, InitialCondition, Load, Model, NodeId, PointMass, RigidBody, SensorKind, Spring,
    Support, System,
};
use nalgebra::{Isometry3, Point3, Vector3};
use reduction::{NodeStresses, ReducedBody};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
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
type ReducedBodies = (Vec<(Arc<ReducedBody>, Option<VtuMesh>)>, Vec<serde_json::Value>);

/// Reduces (or reads from the cache) every flexible body's part, once per part.
fn reduce_bodies(study: &Study, cache: &Path, obs: &mut dyn Observer) -> Result<ReducedBodies, BoxError> {
    let mut done: BTreeMap<usize, Reduced> = BTreeMap::new();
    let mut out = Vec::new();
    let mut reductions = Vec::new();
    for b in &study.mechanism.bodies {
        match &b.source {
            BodySource::Part(p) => {
                if !done.contains_key(p) {
                    let r = reduce_part(study, &study.parts[*p], cache, obs)?;
                    reductions.push(json!({
                        "part": study.parts[*p].name,
                        "fe_dofs": r.free_dofs,
                        "coordinates": r.body.n_coordinates(),
                        "interfaces": r.body.interfaces.len(),
                        "modes_kept": r.body.n_modes,
                        "from_cache": r.from_cache,
                    }));
                    done.insert(*p, r);
                }
                let r = &done[p];
                let mesh = (r.body.mesh.as_ref().map(|m| m.nodes.len()) == Some(r.built.model.node_count()))
                    .then(|| VtuMesh::from_model(&r.built.model, &[]));
                out.push((Arc::clone(&r.body), mesh));
            }
            BodySource::File(_, body) => out.push((Arc::clone(body), None)),
        }
    }
    Ok((out, reductions))
}

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
pub fn build(study: &Study, cache: &Path, obs: &mut dyn Observer) -> Result<BuiltMechanism, BoxError> {
    let m = &study.mechanism;
    let (reduced, reductions) = reduce_bodies(study, cache, obs)?;
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

/// The sensors of the study picked out of the rows of an `mbs::SensorRecord` and sent to
/// the observer; the last sample is kept for the report.
pub struct SensorSampler {
    /// Per group: its columns in a record row.
    columns: Vec<Vec<usize>>,
    /// The abscissa and values of the last sample.
    pub last: Option<(f64, Vec<Vec<f64>>)>,
}

impl SensorSampler {
    /// Starts the sensor stream of `groups` (columns named in `record`), with `x_label` as the
    /// abscissa.
    pub fn start(
        obs: &mut dyn Observer,
        groups: &[SensorGroup],
        record: &mbs::SensorRecord,
        x_label: &str,
        plots: bool,
    ) -> Result<Self, BoxError> {
        let columns = sensor_columns(groups, record)?;
        obs.sensors(&SensorStream { x_label, groups, plots })?;
        Ok(Self { columns, last: None })
    }

    /// Sends the last row of `record` (abscissa `x`).
    pub fn sample(&mut self, obs: &mut dyn Observer, x: f64, record: &mbs::SensorRecord) -> Result<(), BoxError> {
        match record.rows.last() {
            Some(row) => self.sample_row(obs, x, row),
            None => Ok(()),
        }
    }

    /// Sends rows `rows` of `record`, each at its time, all of them even when the user asks
    /// to stop (the folder writes a row, then says so: the first such stop is returned after
    /// the last row).
    pub fn sample_rows(
        &mut self,
        obs: &mut dyn Observer,
        record: &mbs::SensorRecord,
        rows: std::ops::Range<usize>,
    ) -> Result<(), BoxError> {
        let mut stop = None;
        for r in rows {
            match self.sample_row(obs, record.times[r], &record.rows[r]) {
                Ok(()) => {}
                Err(e) if e.is::<crate::interrupt::Interrupted>() => {
                    stop.get_or_insert(e);
                }
                Err(e) => return Err(e),
            }
        }
        stop.map_or(Ok(()), Err)
    }

    /// Sends one row (abscissa `x`).
    fn sample_row(&mut self, obs: &mut dyn Observer, x: f64, row: &[f64]) -> Result<(), BoxError> {
        let values: Vec<Vec<f64>> = self
            .columns
            .iter()
            .map(|cols| cols.iter().map(|&c| row[c]).collect())
            .collect();
        obs.sample(x, &values)?;
        self.last = Some((x, values));
        Ok(())
    }
}

/// The deformed meshes of every body at the output times (module docs), with the stresses of
/// the bodies reduced with stress shapes and the hot spot of each.
pub struct MeshRecovery {
    mesh: VtuMesh,
    /// Per flexible body: its first point (its superelement is the system's).
    flexible: Vec<usize>,
    /// Whether any body has stress shapes.
    stress: bool,
    /// Per rigid body: first point.
    rigid: Vec<usize>,
    /// Per flexible body: the largest von Mises stress seen so far.
    hot: Vec<Option<HotSpot>>,
    /// Per flexible body with stress shapes: the search for the largest von Mises stress over
    /// every node, built at the first output time without a frame.
    maxima: Vec<Option<reduction::VonMisesMaximum>>,
    /// Output times without a frame whose hot spots wait to be found a batch at a time
    /// ([`Self::track`]): the time and each body's CB coordinates (`None` without stress
    /// shapes).
    tracked: Vec<(f64, Vec<Option<Vec<f64>>>)>,
}

/// The largest von Mises stress of one body over the output times: value, FE node (index in
/// the part's mesh), and time (or load factor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HotSpot {
    pub von_mises: f64,
    pub node: usize,
    pub time: f64,
}

impl MeshRecovery {
    pub fn new(b: &BuiltMechanism, sys: &System) -> Result<Self, BoxError> {
        let mut mesh = VtuMesh::default();
        let mut flexible = Vec::new();
        for body in &b.bodies {
            let first = mesh.points.len();
            match (&body.reduced.mesh, &body.mesh) {
                (Some(shapes), Some(fe)) => {
                    for x in &shapes.nodes {
                        let p = body.placement * Point3::from(*x);
                        mesh.points.push([p.x, p.y, p.z]);
                    }
                    for (t, c, r) in &fe.cells {
                        mesh.cells.push((*t, c.iter().map(|i| i + first).collect(), *r));
                    }
                }
                (Some(shapes), None) => {
                    for (i, x) in shapes.nodes.iter().enumerate() {
                        let p = body.placement * Point3::from(*x);
                        mesh.points.push([p.x, p.y, p.z]);
                        mesh.cells.push((1, vec![first + i], CellRole::Element));
                    }
                }
                // No mesh shapes: the interfaces, joined to the first.
                _ => {
                    for (k, i) in body.reduced.interfaces.iter().enumerate() {
                        let p = body.placement * Point3::from(i.position);
                        mesh.points.push([p.x, p.y, p.z]);
                        mesh.cells.push((1, vec![first + k], CellRole::InterfaceNode));
                        if k > 0 {
                            mesh.cells.push((3, vec![first, first + k], CellRole::Element));
                        }
                    }
                }
            }
            flexible.push(first);
        }
        let mut rigid = Vec::new();
        for nodes in &b.rigid {
            let first = mesh.points.len();
            for (k, n) in nodes.iter().enumerate() {
                let p = b.model.nodes[n.index()].position;
                mesh.points.push([p.x, p.y, p.z]);
                mesh.cells.push((1, vec![first + k], CellRole::InterfaceNode));
                if k > 0 {
                    mesh.cells.push((3, vec![first, first + k], CellRole::Element));
                }
            }
            rigid.push(first);
        }
        // Every point in a cell: a point of the body's reduced mesh that no element uses (an
        // interface node of a spider) gets a vertex cell, so ParaView draws and picks it.
        let mut used = vec![false; mesh.points.len()];
        for (_, cell, _) in &mesh.cells {
            for &i in cell {
                used[i] = true;
            }
        }
        for (i, _) in used.iter().enumerate().filter(|(_, u)| !**u) {
            mesh.cells.push((1, vec![i], CellRole::InterfaceNode));
        }
        let hot = vec![None; flexible.len()];
        let stress = b
            .bodies
            .iter()
            .any(|body| sys.superelement(body.id).is_some_and(|se| se.stress_shapes().is_some()));
        let maxima = vec![None; b.bodies.len()];
        Ok(Self {
            mesh,
            flexible,
            stress,
            rigid,
            hot,
            maxima,
            tracked: Vec::new(),
        })
    }

    /// Whether any body has stress shapes (then the frames carry stress fields).
    pub fn has_stress(&self) -> bool {
        self.stress
    }

    /// The kinematics of every flexible body at `state` (`mbs::System::body_kinematics`), with
    /// the body states they were solved for (interface velocities and modal rates included, for
    /// the mesh velocities).
    fn kinematics(
        &self,
        t: f64,
        sys: &System,
        state: &mbs::State,
        b: &BuiltMechanism,
    ) -> Result<Vec<(superelement::Kinematics, superelement::BodyState)>, BoxError> {
        let mut out = Vec::with_capacity(b.bodies.len());
        for body in &b.bodies {
            let kin = sys
                .body_kinematics(state, body.id)
                .context(|| format!("body '{}': floating frame for the mesh at t = {t}", body.name))?
                .ok_or_else(|| format!("internal error: body '{}' is not flexible in the system", body.name))?;
            out.push(kin);
        }
        Ok(out)
    }

    /// Every body's stresses from its kinematics, updating the hot spots at time `t`.
    fn stresses(
        &mut self,
        t: f64,
        sys: &System,
        b: &BuiltMechanism,
        kins: &[(superelement::Kinematics, superelement::BodyState)],
    ) -> Vec<Option<NodeStresses>> {
        let mut out = Vec::with_capacity(kins.len());
        for (k, (body, (kin, _))) in b.bodies.iter().zip(kins).enumerate() {
            let Some(se) = sys.superelement(body.id) else {
                out.push(None);
                continue;
            };
            let st = se.stress_shapes().map(|s| s.node_stresses(&kin.q_jj, &kin.R_j));
            if let Some(st) = &st {
                if let Some((node, &vm)) = st.von_mises.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) {
                    self.update_hot_spot(k, node, vm, t);
                }
            }
            out.push(st);
        }
        out
    }

    /// Body `k`'s hot spot becomes (`node`, `vm`, `t`) when `vm` is above it.
    fn update_hot_spot(&mut self, k: usize, node: usize, vm: f64, t: f64) {
        if self.hot[k].is_none_or(|h| vm > h.von_mises) {
            self.hot[k] = Some(HotSpot {
                von_mises: vm,
                node,
                time: t,
            });
        }
    }

    /// Updates the hot spots at an output time without writing a frame: the largest von
    /// Mises stress of each body over every node (`reduction::VonMisesMaximum::maxima`, the
    /// same maximum as every node's, at a fraction of its cost), found for a batch of output
    /// times at once: the state waits until a batch is full, a frame is written or the
    /// summary is made.
    pub fn track(&mut self, t: f64, sys: &System, state: &mbs::State, b: &BuiltMechanism) -> Result<(), BoxError> {
        if !self.has_stress() {
            return Ok(());
        }
        let kins = self.kinematics(t, sys, state, b)?;
        let qs = b
            .bodies
            .iter()
            .zip(&kins)
            .map(|(body, (kin, _))| {
                let shapes = sys.superelement(body.id).and_then(|se| se.stress_shapes());
                shapes.map(|_| kin.q_jj.clone())
            })
            .collect();
        self.tracked.push((t, qs));
        if self.tracked.len() >= mbs::PendingRows::BATCH {
            self.update_tracked(sys, b);
        }
        Ok(())
    }

    /// The hot spots of the output times waiting in [`Self::track`], in time order.
    fn update_tracked(&mut self, sys: &System, b: &BuiltMechanism) {
        let tracked = std::mem::take(&mut self.tracked);
        if tracked.is_empty() {
            return;
        }
        for (k, body) in b.bodies.iter().enumerate() {
            let Some(shapes) = sys.superelement(body.id).and_then(|se| se.stress_shapes()) else {
                continue;
            };
            let states: Vec<&[f64]> = tracked.iter().filter_map(|(_, qs)| qs[k].as_deref()).collect();
            let search = self.maxima[k].get_or_insert_with(|| {
                let every: Vec<usize> = (0..shapes.node_count()).collect();
                reduction::VonMisesMaximum::new(shapes, &every)
            });
            let (found, _) = search.maxima(shapes, &states);
            for ((t, _), maximum) in tracked.iter().zip(found) {
                if let Some((node, vm)) = maximum {
                    self.update_hot_spot(k, node, vm, *t);
                }
            }
        }
    }

    /// Sends the deformed meshes at `state` to the observer as a frame of
    /// [`Series::Mechanism`] at `t`, with the point fields `displacement` (from t = 0, m),
    /// `rotation` (rotation vector from t = 0, rad), `velocity` (m/s) and `body` (the index of
    /// the body the point belongs to: flexible bodies first, then rigid bodies, in study
    /// order), and the stress fields when a body has stress shapes.
    pub fn write(
        &mut self,
        obs: &mut dyn Observer,
        t: f64,
        sys: &System,
        state: &mbs::State,
        b: &BuiltMechanism,
    ) -> Result<(), BoxError> {
        self.write_series(obs, Series::Mechanism, t, sys, state, b)
    }

    /// [`Self::write`] as a frame of `series` with key `t` (buckling modes: the mode number).
    #[allow(clippy::too_many_arguments)]
    pub fn write_series(
        &mut self,
        obs: &mut dyn Observer,
        series: Series,
        t: f64,
        sys: &System,
        state: &mbs::State,
        b: &BuiltMechanism,
    ) -> Result<(), BoxError> {
        let motions = sys.node_motions(state);
        let n_points = self.mesh.points.len();
        let mut u = vec![[0.0; 3]; n_points];
        let mut rot = vec![[0.0; 3]; n_points];
        let mut vel = vec![[0.0; 3]; n_points];
        let mut body_of = vec![0.0; n_points];
        let vec3 = |v: Vector3<f64>| [v.x, v.y, v.z];
        let kins = self.kinematics(t, sys, state, b)?;
        // The earlier output times first: of equal maxima, the hot spot keeps the first time.
        self.update_tracked(sys, b);
        let stresses = if self.has_stress() {
            self.stresses(t, sys, b, &kins)
        } else {
            Vec::new()
        };
        let mut tensor = vec![[0.0; 6]; n_points];
        let mut von_mises = vec![0.0; n_points];
        let mut principal = vec![0.0; n_points];
        // The first point of every body, flexible then rigid, and the end of the last.
        let ends: Vec<usize> = self
            .flexible
            .iter()
            .chain(&self.rigid)
            .copied()
            .skip(1)
            .chain(std::iter::once(n_points))
            .collect();
        for (k, (body, &first)) in b.bodies.iter().zip(&self.flexible).enumerate() {
            let (kin, bs) = &kins[k];
            let recovered = sys
                .superelement(body.id)
                .and_then(|se| Some((se.recover_mesh(kin)?, se.recover_mesh_velocities(kin, bs)?)));
            match recovered {
                Some((ms, vs)) => {
                    for (i, p) in ms.positions.iter().enumerate() {
                        let x = &self.mesh.points[first + i];
                        u[first + i] = [p.x - x[0], p.y - x[1], p.z - x[2]];
                        let turned = ms.orientations[i] * body.placement.rotation.inverse();
                        rot[first + i] = vec3(turned.scaled_axis());
                        vel[first + i] = vec3(vs[i]);
                    }
                    // Stresses live on the mesh nodes, drawn only with the mesh shapes.
                    if let Some(Some(st)) = stresses.get(k) {
                        let n = ms.positions.len().min(st.tensor.len());
                        tensor[first..first + n].copy_from_slice(&st.tensor[..n]);
                        von_mises[first..first + n].copy_from_slice(&st.von_mises[..n]);
                        principal[first..first + n].copy_from_slice(&st.principal[..n]);
                    }
                }
                _ => {
                    for (j, n) in body.nodes.iter().enumerate() {
                        let m = &motions[n.index()];
                        let x = &self.mesh.points[first + j];
                        u[first + j] = [m.r.x - x[0], m.r.y - x[1], m.r.z - x[2]];
                        rot[first + j] = vec3(m.R.scaled_axis());
                        vel[first + j] = vec3(m.v);
                    }
                }
            }
            body_of[first..ends[k]].fill(k as f64);
        }
        for (j, (nodes, first)) in b.rigid.iter().zip(&self.rigid).enumerate() {
            for (k, n) in nodes.iter().enumerate() {
                let m = &motions[n.index()];
                let x = &self.mesh.points[first + k];
                u[first + k] = [m.r.x - x[0], m.r.y - x[1], m.r.z - x[2]];
                rot[first + k] = vec3(m.R.scaled_axis());
                vel[first + k] = vec3(m.v);
            }
            let index = b.bodies.len() + j;
            body_of[*first..ends[index]].fill(index as f64);
        }
        let flat = |f: &[[f64; 3]]| -> Vec<f64> { f.iter().flatten().copied().collect() };
        let (u, rot, vel) = (flat(&u), flat(&rot), flat(&vel));
        let mut fields = vec![
            PointField {
                name: "displacement",
                components: 3,
                values: &u,
            },
            PointField {
                name: "rotation",
                components: 3,
                values: &rot,
            },
            PointField {
                name: "velocity",
                components: 3,
                values: &vel,
            },
            PointField {
                name: "body",
                components: 1,
                values: &body_of,
            },
        ];
        let tensor: Vec<f64> = tensor.iter().flatten().copied().collect();
        if self.has_stress() {
            fields.push(PointField {
                name: "stress",
                components: 6,
                values: &tensor,
            });
            fields.push(PointField {
                name: "von_mises",
                components: 1,
                values: &von_mises,
            });
            fields.push(PointField {
                name: "max_principal",
                components: 1,
                values: &principal,
            });
        }
        obs.frame(series, t, &self.mesh, &fields)
    }

    /// The hot spots as summary entries and report lines, `x` naming the time axis (the
    /// output times still waiting in [`Self::track`] included).
    pub fn hot_spot_summary(&mut self, sys: &System, b: &BuiltMechanism, x: &str) -> (serde_json::Value, Vec<String>) {
        self.update_tracked(sys, b);
        let mut entries = Vec::new();
        let mut lines = Vec::new();
        for (body, hot) in b.bodies.iter().zip(&self.hot) {
            let Some(h) = hot else { continue };
            let position = body.reduced.mesh.as_ref().map(|m| m.nodes[h.node]);
            entries.push(json!({
                "body": body.name,
                "von_mises_Pa": h.von_mises,
                "node": h.node,
                "position": position,
                x: h.time,
            }));
            lines.push(format!(
                "hot spot of body '{}': von Mises {:.6e} Pa at FE node index {}{} at {x} = {:.6}",
                body.name,
                h.von_mises,
                h.node,
                position.map_or(String::new(), |p| format!(
                    " ({:.4e}, {:.4e}, {:.4e}) m",
                    p[0], p[1], p[2]
                )),
                h.time
            ));
        }
        (serde_json::Value::Array(entries), lines)
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

/// What a multibody analysis produced, for the summary.
pub struct MbsOutcome {
    pub free_dofs: usize,
    pub report: Vec<String>,
    pub results: serde_json::Value,
    /// A solver failure after partial results were written.
    pub failure: Option<SolverStopped>,
    /// The final state (equilibrium, dynamic), for analyses that `start` from it.
    pub final_state: Option<mbs::State>,
}

/// Runs one analysis of the mechanism, every result to `obs`.
/// `start`: the final state of the analysis named in its `start` key.
pub fn run_analysis(
    study: &Study,
    analysis: &MbsAnalysis,
    b: &BuiltMechanism,
    start: Option<&mbs::State>,
    obs: &mut dyn Observer,
) -> Result<MbsOutcome, BoxError> {
    let sys = Arc::new(b.system(study)?);
    let n = sys.n_dof();
    let mut out = MbsOutcome {
        free_dofs: n,
        report: vec![format!(
            "mechanism: {} nodes, {} flexible and {} rigid bodies, {}, {n} unknowns",
            b.model.nodes.len(),
            b.bodies.len(),
            b.rigid.len(),
            joint_count(study)
        )],
        results: json!({}),
        failure: None,
        final_state: None,
    };
    let output = &study.mechanism.output;
    let t0 = Instant::now();
    match analysis {
        MbsAnalysis::Equilibrium {
            steps,
            tolerance,
            max_iterations,
            time,
            arc_length,
        } => {
            let method = if *arc_length {
                // The first arc spans about 1/steps of the load (the scaled norm weighs the load
                // factor by 1); the path may take up to 50 times as many steps to pass limit points.
                let mut s = mbs::ArcLengthSettings::new(1.0 / *steps as f64, 1.0, (50 * *steps).max(1000));
                s.tolerance = *tolerance;
                s.max_iterations = *max_iterations;
                s.time = *time;
                mbs::StaticMethod::ArcLength(s)
            } else {
                let mut s = mbs::StaticSettings::new(*steps);
                s.tolerance = *tolerance;
                s.max_iterations = *max_iterations;
                s.time = *time;
                mbs::StaticMethod::LoadStepping(s)
            };
            let first = match start {
                Some(s) => sys.at_rest(s, *time),
                None => sys.initial_state(),
            };
            let (sol, failure) = match mbs::solve_static_with(&sys, first, &method) {
                Ok(s) => (s, None),
                Err(inc) => (inc.partial, Some(inc.error)),
            };
            let mut files = SensorSampler::start(obs, &b.groups, &sol.sensors, "load factor [-]", output.plots)?;
            let mut rec = sys.sensor_record();
            for (t, row) in sol.sensors.times.iter().zip(&sol.sensors.rows) {
                rec.times.push(*t);
                rec.rows.push(row.clone());
                files.sample(obs, *t, &rec)?;
            }
            let mut mw = MeshRecovery::new(b, &sys)?;
            mw.write(obs, 1.0, &sys, &sol.state, b)?;
            let (hot_spots, hot_lines) = mw.hot_spot_summary(&sys, b, "load_factor");
            out.report.extend(hot_lines);
            let iterations: usize = sol.steps.iter().map(|s| s.residuals.len().saturating_sub(1)).sum();
            out.report.push(format!(
                "{} load steps, {iterations} Newton iterations, {} rejected attempts; last relative residual {:.2e}",
                sol.steps.len(),
                sol.rejected.len(),
                sol.steps
                    .last()
                    .and_then(|s| s.residuals.last())
                    .copied()
                    .unwrap_or(f64::NAN)
            ));
            report_last(&mut out.report, b, &files);
            out.results = json!({
                "model": b.size(&sys),
                "load_steps": sol.steps.len(),
                "newton_iterations": iterations,
                "rejected_steps": sol.rejected.len(),
                "load_factor_reached": sol.sensors.times.last().copied().unwrap_or(0.0),
                "seconds_solving": t0.elapsed().as_secs_f64(),
                "hot_spots": hot_spots,
            });
            obs.sensors_end()?;
            if failure.is_none() {
                out.final_state = Some(sol.state.clone());
            }
            out.failure = failure.map(|e| {
                let message = "equilibrium stopped; the converged load steps are written".into();
                b.stopped(study, message, Some(sol.steps.len() + 1), e)
            });
        }
        MbsAnalysis::Dynamic {
            t_end,
            dt,
            newton,
            dt_min,
            adaptive,
            ..
        } => {
            let first = dynamic_start(&sys, start);
            let t_start = first.time();
            if *t_end <= t_start {
                return Err(format!(
                    "t_end = {t_end} s is not after the start at t = {t_start} s (the state of the analysis named in `start`)"
                )
                .into());
            }
            let mut integ = Simulation::with_start(study, Arc::clone(&sys), b, analysis, first)?;
            let mut rec = sys.sensor_record();
            integ.record(&mut rec)?;
            let mut files = SensorSampler::start(obs, &b.groups, &rec, "t [s]", output.plots)?;
            files.sample(obs, t_start, &rec)?;
            let mut mw = MeshRecovery::new(b, &sys)?;
            if output.vtu_every.is_some() {
                mw.write(obs, t_start, &sys, integ.state(), b)?;
            }
            let stepping = match adaptive {
                None => mbs::Stepping::Fixed { min_step: *dt_min },
                Some(ad) => mbs::Stepping::Adaptive(ad.clone()),
            };
            // Fixed steps: the last one is shortened to end exactly at t_end (mbs::fixed_steps,
            // as Integrator::run_to steps).
            let (_, last_step) = mbs::fixed_steps(t_start, *t_end, *dt);
            // Why the callback stopped the run: a sensor that is not finite
            // (mbs::SolveError::NonFiniteSensor, a solver stop) or a file that cannot be written.
            enum Halt {
                Sensor(mbs::SolveError, usize),
                Output(BoxError),
            }
            impl<E: Into<BoxError>> From<E> for Halt {
                fn from(e: E) -> Self {
                    Halt::Output(e.into())
                }
            }
            let mut last_written = t_start;
            // Rows whose largest-von-Mises values are found a batch at a time (the rows reach
            // the files in order, a batch at a time, at most PendingRows::WAIT late).
            let mut pending = mbs::PendingRows::default();
            // Completes the waiting rows (all of them with `flush`) and writes every row the
            // record gained; a sensor that is not finite: the rows before it are written, the
            // run is not complete. Only the last row is kept, to keep the record small.
            // `record`: the integrator whose current state is recorded first (else the waiting
            // rows are completed alone).
            let mut write_rows = |record: Option<&mbs::Integrator>,
                                  pending: &mut mbs::PendingRows,
                                  rec: &mut mbs::SensorRecord,
                                  files: &mut SensorSampler,
                                  obs: &mut dyn Observer,
                                  k: usize|
             -> Result<(), Halt> {
                let before = rec.rows.len();
                let recorded = match record {
                    Some(integ) => integ.record_deferred(pending, rec),
                    None => sys.complete_rows(pending, rec),
                };
                let good = if recorded.is_err() {
                    rec.rows.len().saturating_sub(1).max(before)
                } else {
                    rec.rows.len()
                };
                files.sample_rows(obs, rec, before..good)?;
                if good > before {
                    last_written = rec.times[good - 1];
                }
                recorded.map_err(|e| {
                    let step = match &e {
                        mbs::SolveError::NonFiniteSensor { step, .. } => *step,
                        _ => k,
                    };
                    Halt::Sensor(e, step)
                })?;
                if rec.rows.len() > 1 {
                    rec.rows.drain(..rec.rows.len() - 1);
                    rec.times.drain(..rec.times.len() - 1);
                }
                Ok(())
            };
            let run = integ.run_to(&stepping, |done, integ| -> Result<(), Halt> {
                let (k, t) = (done.k, done.time);
                let vtu_now = output.vtu_every.is_some_and(|v| k % v == 0 || done.last);
                if crate::interrupt::requested() && !pending.is_empty() {
                    // A stop asked for: the waiting rows are written first.
                    write_rows(None, &mut pending, &mut rec, &mut files, obs, k)?;
                }
                if k % output.every == 0 || done.last {
                    write_rows(Some(integ), &mut pending, &mut rec, &mut files, obs, k)?;
                    if !vtu_now {
                        mw.track(t, &sys, integ.state(), b)?;
                    }
                }
                if vtu_now {
                    mw.write(obs, t, &sys, integ.state(), b)?;
                }
                let (done, total) = match done.planned {
                    Some(n) => (k as u64, n as u64),
                    None => ((1000.0 * (t - t_start) / (t_end - t_start)) as u64, 1000),
                };
                obs.progress(&Progress::Steps {
                    what: "time integration".into(),
                    done,
                    total,
                });
                Ok(())
            });
            // The rows still waiting: a run that ended or failed writes them; a stop asked for
            // wrote them (above); a file that cannot be written stops here.
            let run = match run {
                Ok((totals, failure)) => {
                    match write_rows(None, &mut pending, &mut rec, &mut files, obs, totals.steps) {
                        Ok(()) => Ok((totals, failure)),
                        // The solver's own failure stays the run's.
                        Err(_) if failure.is_some() => Ok((totals, failure)),
                        Err(error) => Err(Box::new(mbs::Interrupted { error, totals })),
                    }
                }
                Err(stop) => {
                    let unwritable = matches!(&stop.error, Halt::Output(e) if !e.is::<crate::interrupt::Interrupted>());
                    if !unwritable {
                        let _ = write_rows(None, &mut pending, &mut rec, &mut files, obs, stop.totals.steps);
                    }
                    Err(stop)
                }
            };
            let (totals, failure) = match run {
                Ok((totals, None)) => (totals, None),
                Ok((totals, Some(e))) => {
                    let message = format!(
                        "time integration stopped; results up to t = {:.6} s (step {}) are written",
                        integ.state().time(),
                        totals.steps
                    );
                    let failure = b.stopped(study, message, Some(totals.steps + 1), e);
                    (totals, Some(failure))
                }
                Err(stop) => match stop.error {
                    Halt::Output(e) => return Err(e),
                    Halt::Sensor(e, k) => {
                        let message =
                            format!("time integration stopped; results up to t = {last_written:.6} s are written");
                        let failure = b.stopped(study, message, Some(k), e);
                        (stop.totals, Some(failure))
                    }
                },
            };
            out.failure = failure;
            obs.progress(&Progress::Finished);
            let mbs::StepTotals {
                steps,
                planned,
                iterations,
                jacobians,
                max_iterations: max_iter,
                retries,
                rejected,
                smallest_step: h_min,
                largest_step: h_max,
            } = totals;
            let n_steps = planned.unwrap_or(0);
            let t_reached = integ.state().time();
            match adaptive {
                None => out.report.push(format!(
                    "{steps} of {n_steps} steps of {dt} s{} from t = {t_start} to {t_reached:.6} s, {iterations} Newton iterations ({:.2} per step, at most {max_iter})",
                    if last_step < *dt * (1.0 - 1e-9) {
                        format!(" (the last shortened to {last_step:.6e} s to end at t_end)")
                    } else {
                        String::new()
                    },
                    iterations as f64 / steps.max(1) as f64
                )),
                Some(ad) => out.report.push(format!(
                    "{steps} adaptive steps from t = {t_start} to {t_reached:.6} s (error tolerance {:.1e}; steps {h_min:.3e} to {h_max:.3e} s), {rejected} rejected and retried, {iterations} Newton iterations",
                    ad.tolerance
                )),
            }
            if adaptive.is_none() {
                out.report.push(if retries.is_empty() {
                    "no step needed retrying (fixed step)".to_string()
                } else {
                    let smallest = retries.iter().map(|r| r.smallest_step).fold(f64::INFINITY, f64::min);
                    let first = &retries[0];
                    format!(
                        "{} failed step(s) retried with halved steps (smallest {smallest:.3e} s, dt_min {dt_min:.3e} s); the first at t = {:.6} s: {}",
                        retries.len(),
                        first.time,
                        first.cause
                    )
                });
            }
            if *newton == mbs::NewtonStrategy::Modified {
                out.report.push(format!(
                    "modified Newton: {jacobians} iteration matrices factorised ({:.2} per step)",
                    jacobians as f64 / steps.max(1) as f64
                ));
            }
            report_last(&mut out.report, b, &files);
            let (hot_spots, hot_lines) = mw.hot_spot_summary(&sys, b, "t");
            out.report.extend(hot_lines);
            out.results = json!({
                "model": b.size(&sys),
                "hot_spots": hot_spots,
                "steps": steps,
                "steps_planned": planned,
                "t_start": t_start,
                "t_reached": t_reached,
                "newton_iterations": iterations,
                "max_iterations_per_step": max_iter,
                "newton": match newton {
                    mbs::NewtonStrategy::Full => "full",
                    mbs::NewtonStrategy::Modified => "modified",
                },
                "jacobians": jacobians,
                "adaptive": adaptive.is_some(),
                "smallest_step": if h_min.is_finite() { json!(h_min) } else { json!(null) },
                "largest_step": h_max,
                "rejected_steps": rejected,
                "retried_steps": retries.len(),
                "retries": retries.iter().map(|r| json!({
                    "time": r.time,
                    "step": r.step,
                    "smallest_step": r.smallest_step,
                    "substeps": r.substeps,
                    "cause": r.cause.to_string(),
                })).collect::<Vec<_>>(),
                "seconds_solving": t0.elapsed().as_secs_f64(),
            });
            obs.sensors_end()?;
            if out.failure.is_none() {
                out.final_state = Some(integ.state().clone());
            }
        }
        MbsAnalysis::Linearized { modes, about } => {
            let state = match (start, about) {
                (Some(s), _) => s.clone(),
                (None, About::Initial) => sys.initial_state(),
                (None, About::Equilibrium) => {
                    mbs::solve_static(&sys, sys.initial_state(), &mbs::StaticSettings::new(1))
                        .map_err(|e| format!("the equilibrium to linearise about: {}", e.error))?
                        .state
                }
                (None, About::Time { t, dt }) => {
                    let settings = mbs::DynamicSettings::new(*dt, *t, mbs::DynamicSettings::DEFAULT_RHO_INF);
                    mbs::solve_dynamic(&sys, sys.initial_state(), &settings)
                        .map_err(|e| format!("the dynamic run up to t = {t} s to linearise about: {}", e.error))?
                        .final_state
                }
            };
            let s = mbs::spectrum(&sys, &state)?;
            let mut csv = Table::new("frequencies", &["mode", "frequency [Hz]", "omega [rad/s]"]);
            let shown: Vec<f64> = s.omega.iter().take(*modes).copied().collect();
            for (k, w) in shown.iter().enumerate() {
                csv.row(vec![
                    Cell::from(k + 1),
                    Cell::Num(w / (2.0 * std::f64::consts::PI)),
                    Cell::Num(*w),
                ]);
            }
            obs.table(&csv)?;
            let mut csv = Table::new(
                "state_space",
                &["eigenvalue", "real [1/s]", "imaginary [rad/s]", "damped frequency [Hz]"],
            );
            for (k, (re, im)) in s.state_space.iter().enumerate() {
                csv.row(vec![
                    Cell::from(k + 1),
                    Cell::Num(*re),
                    Cell::Num(*im),
                    Cell::Num(im / (2.0 * std::f64::consts::PI)),
                ]);
            }
            obs.table(&csv)?;
            // Which bodies and nodes carry each mode's energy (mbs::mode_energies).
            let energies = mbs::mode_energies(&sys, &state)?;
            let mut csv = Table::new(
                "modes",
                &[
                    "mode",
                    "frequency [Hz]",
                    "damping ratio [-]",
                    "rigid body [-]",
                    "carried by",
                    "growth rate [1/s]",
                ],
            );
            for (k, e) in energies.iter().take(*modes).enumerate() {
                csv.row(vec![
                    Cell::from(k + 1),
                    Cell::Num(e.frequency_hz),
                    e.damping_ratio.map_or(Cell::Empty, Cell::Num),
                    Cell::from(usize::from(e.rigid_body)),
                    Cell::from(e.label.clone()),
                    e.growth_rate.map_or(Cell::Empty, Cell::Num),
                ]);
            }
            obs.table(&csv)?;
            // A growing eigenvalue: the state is not a stable one, whatever the frequencies say.
            let growing = s.growing();
            let fastest = growing.iter().map(|g| g.0).fold(0.0, f64::max);
            if !growing.is_empty() {
                let unstable: Vec<String> = energies
                    .iter()
                    .enumerate()
                    .filter(|(_, e)| e.unstable)
                    .map(|(k, _)| (k + 1).to_string())
                    .collect();
                let line = format!(
                    "UNSTABLE: {} state-space eigenvalue(s) with a positive real part (the fastest grows at {fastest:.4e} 1/s: amplitude doubled every {:.4e} s){}; the state linearised about is not a stable equilibrium or steady motion",
                    growing.len(),
                    std::f64::consts::LN_2 / fastest,
                    if unstable.is_empty() {
                        String::new()
                    } else {
                        format!(", modes {}", unstable.join(", "))
                    }
                );
                obs.progress(&Progress::Warning(format!("linearized analysis: {line}")));
                out.report.insert(0, line);
            }
            for (k, e) in energies.iter().take(*modes).enumerate() {
                out.report
                    .push(format!("mode {}: {:.6e} Hz, {}", k + 1, e.frequency_hz, e.label));
            }
            let hz: Vec<f64> = shown.iter().map(|w| w / (2.0 * std::f64::consts::PI)).collect();
            out.report.push(format!(
                "lowest {} frequencies [Hz]: {}",
                hz.len(),
                hz.iter().map(|f| format!("{f:.6e}")).collect::<Vec<_>>().join(", ")
            ));
            let labels: Vec<&str> = energies.iter().take(*modes).map(|e| e.label.as_str()).collect();
            out.results = json!({
                "model": b.size(&sys),
                "frequencies_hz": hz,
                "mode_labels": labels,
                "stable": growing.is_empty(),
                "growing_eigenvalues": growing.iter().map(|g| json!([g.0, g.1])).collect::<Vec<_>>(),
                "largest_growth_rate": if growing.is_empty() { json!(null) } else { json!(fastest) },
                "about": if start.is_some() { "start".to_string() } else { format!("{about:?}") },
            });
        }
        MbsAnalysis::Buckling {
            modes,
            steps,
            tolerance,
            max_iterations,
        } => run_buckling(
            study,
            &sys,
            b,
            start,
            [*modes, *steps, *max_iterations],
            *tolerance,
            obs,
            &mut out,
        )?,
    }
    Ok(out)
}

/// The first state of a `dynamic` analysis: the initial state, or the final state of the
/// analysis named in `start` (from an equilibrium: at rest in its configuration at its time).
pub fn dynamic_start(sys: &System, start: Option<&mbs::State>) -> mbs::State {
    match start {
        Some(s) if s.velocity().iter().all(|v| *v == 0.0) => sys.at_rest(s, s.time()),
        Some(s) => s.clone(),
        None => sys.initial_state(),
    }
}

/// The `buckling` analysis (`mbs::buckling` about the equilibrium under the full load, or the
/// state of `start`), with the stability of that equilibrium (`mbs::stability`): the load
/// factors as a table, each mode drawn on the loaded configuration for ParaView.
fn run_buckling(
    study: &Study,
    sys: &System,
    b: &BuiltMechanism,
    start: Option<&mbs::State>,
    [modes, steps, max_iterations]: [usize; 3],
    tolerance: f64,
    obs: &mut dyn Observer,
    out: &mut MbsOutcome,
) -> Result<(), BoxError> {
    let unloaded = sys.initial_state();
    let loaded = match start {
        Some(s) => s.clone(),
        None => {
            let mut settings = mbs::StaticSettings::new(steps);
            settings.tolerance = tolerance;
            settings.max_iterations = max_iterations;
            match mbs::solve_static(sys, unloaded.clone(), &settings) {
                Ok(sol) => sol.state,
                Err(inc) => {
                    let reached = inc.partial.steps.last().map_or(0.0, |s| s.lambda);
                    out.report.push(format!(
                        "no equilibrium under the full load: load stepping stopped at load factor {reached:.6}"
                    ));
                    out.results = json!({
                        "model": b.size(sys),
                        "past_critical_point": true,
                        "load_factor_reached": reached,
                    });
                    let message = format!(
                        "the structure is past a limit point: no equilibrium beyond load factor {reached:.6}; an 'equilibrium' analysis with method = \"arc-length\" follows the path through it"
                    );
                    out.failure = Some(b.stopped(study, message, Some(inc.partial.steps.len() + 1), inc.error));
                    return Ok(());
                }
            }
        }
    };
    let stability = mbs::stability(sys, &loaded, 1.0)?;
    let bk = mbs::buckling(sys, &unloaded, &loaded, 1.0)?;
    let mut table = Table::new("load_factors", &["mode", "critical load factor [-]"]);
    for (k, f) in bk.load_factors.iter().take(modes).enumerate() {
        table.row(vec![Cell::from(k + 1), Cell::Num(*f)]);
    }
    obs.table(&table)?;
    // Each mode on the loaded configuration, its largest displacement a tenth of the model.
    let mut mw = MeshRecovery::new(b, sys)?;
    let base = sys.node_motions(&loaded);
    let size = {
        let n = base.len().max(1) as f64;
        let c = base.iter().map(|m| m.r).sum::<Vector3<f64>>() / n;
        base.iter().map(|m| (m.r - c).norm()).fold(1e-3, f64::max)
    };
    for k in 0..bk.load_factors.len().min(modes) {
        let phi: Vec<f64> = (0..sys.n_dof()).map(|i| bk.modes[(i, k)]).collect();
        let probe = sys.retract(&loaded, &phi.iter().map(|x| x * 1e-6).collect::<Vec<_>>());
        let moved = sys
            .node_motions(&probe)
            .iter()
            .zip(&base)
            .map(|(a, b)| (a.r - b.r).norm())
            .fold(0.0, f64::max)
            / 1e-6;
        let scale = if moved > 0.0 { 0.1 * size / moved } else { 0.0 };
        let mut state = sys.retract(&loaded, &phi.iter().map(|x| x * scale).collect::<Vec<_>>());
        sys.reset_frames(&mut state);
        mw.write_series(obs, Series::Modes, (k + 1) as f64, sys, &state, b)?;
    }
    let first = bk.load_factors.iter().copied().find(|f| *f > 0.0);
    let past = stability.past_critical_point() || first.is_some_and(|f| f < 1.0);
    out.report.push(format!(
        "critical load factors: {}",
        bk.load_factors
            .iter()
            .take(modes)
            .map(|f| format!("{f:.6e}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    if past {
        out.report.push(format!(
            "the structure is past a critical point under the full load: {} negative eigenvalue(s) of the tangent stiffness{}",
            stability.negative,
            first.map_or(String::new(), |f| format!(", lowest positive critical load factor {f:.6}"))
        ));
    }
    out.results = json!({
        "model": b.size(sys),
        "load_factors": bk.load_factors.iter().take(modes).collect::<Vec<_>>(),
        "past_critical_point": past,
        "negative_eigenvalues": stability.negative,
    });
    Ok(())
}

/// The last value of every sensor, for the report.
fn report_last(report: &mut Vec<String>, b: &BuiltMechanism, files: &SensorSampler) {
    let Some((x, rows)) = &files.last else {
        return;
    };
    for (g, row) in b.groups.iter().zip(rows) {
        let values: Vec<String> = g
            .columns
            .iter()
            .zip(row)
            .map(|(c, v)| format!("{c} = {v:.6e}"))
            .collect();
        report.push(format!("sensor '{}' at {x:.6}: {}", g.name, values.join(", ")));
    }
}
