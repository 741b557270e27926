//! A force law of a run ([`mbs::force_law`]) named in the study's terms: it reads joint
//! coordinates by joint name and position and velocity sensors by their names, and sets
//! actuators and point loads by their names. A [`ForceLawSource`] (the Python binding's
//! callable, say) says which names it reads and sets; [`law_ports`] resolves them on the built
//! mechanism, and the source makes the law on those ports, which every analysis of the
//! mechanism then evaluates in its Newton iterations.
//!
//! Input names: a joint with one coordinate is read by its name (`elbow`), a joint with
//! several by its name and the coordinate's index (`slider[0]`, `slider[1]`). A `position`
//! sensor gives three inputs named as its CSV file and columns are (`tip.position_x`,
//! `tip.position_y`, `tip.position_z`: the node's position along the global axes \[m\], with
//! its velocity as rate), and a `velocity` sensor three (`tipv.velocity_x`, ...: \[m/s\],
//! without a rate); the sensor's name reads all three. Other sensors are refused, located at
//! their `[[sensors]]` entry. An output named after an actuator is its effort; after a point
//! load at a node, its force \[N\] (or its moment \[N m\] when the load gives no force),
//! three values in inertial axes, times the load's time function. Loads at load points inside
//! a body and follower loads are refused.

use crate::build::{BuiltMechanism, LoadTarget};
use crate::error::BoxError;
use crate::input::validate::Study;
use crate::sensor_group::SensorGroup;
use mbs::{JointId, LawInput, LawOutput, LawPorts, LawRead, LawTarget, LoadKind, SensorKind, System};
use std::sync::Arc;

/// What makes a run's force law (module docs).
pub trait ForceLawSource: Send + Sync + std::fmt::Debug {
    /// The names of the actuators and point loads the law sets.
    fn outputs(&self) -> Vec<String>;

    /// The joint coordinates and sensors the law reads (names as in the module docs, or a
    /// joint's or a sensor's name for all its coordinates); `None`: every joint.
    fn reads(&self) -> Option<Vec<String>>;

    /// The law on `ports` (resolved from [`Self::outputs`] and [`Self::reads`]).
    fn law(&self, ports: LawPorts) -> Result<Arc<dyn mbs::ForceLaw>, BoxError>;
}

/// The force law of a run, shared by its analyses (`None`: no law).
pub type Forces = Option<Arc<dyn ForceLawSource>>;

/// The name of coordinate `c` of a joint `name` with `n` coordinates.
fn input_name(name: &str, c: usize, n: usize) -> String {
    if n == 1 {
        name.to_string()
    } else {
        format!("{name}[{c}]")
    }
}

/// The ports of `source` on the mechanism `b` of `study`: the joint coordinates and sensor
/// values it reads (module docs), and the actuators and node loads it sets; a name that is
/// none of these is refused with the names there are.
pub fn law_ports(study: &Study, b: &BuiltMechanism, source: &dyn ForceLawSource) -> Result<LawPorts, BoxError> {
    let inputs = law_inputs(study, b, source.reads())?;
    let model = &b.model;
    let mut outputs = Vec::new();
    for name in source.outputs() {
        let target = if let Some(a) = model.actuators.iter().position(|a| a.name == name) {
            LawTarget::Actuator(a)
        } else if let Some(l) = b.loads.iter().find(|l| l.name == name) {
            match &l.target {
                LoadTarget::Node(loads) => {
                    let pick = |k| loads.iter().find(|(kind, _)| *kind == k).map(|(_, i)| *i);
                    let i = pick(LoadKind::Force)
                        .or_else(|| pick(LoadKind::Moment))
                        .ok_or_else(|| format!("force law: point load '{name}' has neither force nor moment"))?;
                    LawTarget::Load(i)
                }
                LoadTarget::Body(_) => {
                    return Err(format!(
                        "force law: point load '{name}' acts at a load point inside a body; a force law sets \
                         actuators and loads at nodes (set it between steps with set_load)"
                    )
                    .into())
                }
            }
        } else {
            let mut known: Vec<String> = model.actuators.iter().map(|a| a.name.clone()).collect();
            known.extend(b.loads.iter().map(|l| l.name.clone()));
            return Err(format!(
                "force law: {}",
                crate::input::source::unknown_reference("actuator or point load", &name, &known)
            )
            .into());
        };
        outputs.push(LawOutput { name, target });
    }
    Ok(LawPorts { inputs, outputs })
}

/// The inputs of the names `reads` (module docs; `None`: every joint coordinate): a joint's
/// coordinates, a sensor's inputs ([`sensor_inputs`]) or one of them. A name that is none of
/// these is refused with the names there are.
fn law_inputs(study: &Study, b: &BuiltMechanism, reads: Option<Vec<String>>) -> Result<Vec<LawInput>, BoxError> {
    let model = &b.model;
    let mut joints = Vec::new();
    for (j, joint) in model.joints.iter().enumerate() {
        let n = joint.kind.n_scalar();
        for c in 0..n {
            let name = input_name(&joint.name, c, n);
            joints.push((joint.name.as_str(), LawInput::coordinate(name, JointId(j as u32), c)));
        }
    }
    let Some(names) = reads else {
        return Ok(joints.into_iter().map(|(_, i)| i).collect());
    };
    let mut inputs = Vec::new();
    for name in &names {
        let picked: Vec<LawInput> = joints
            .iter()
            .filter(|(joint, i)| *joint == name || i.name == *name)
            .map(|(_, i)| i.clone())
            .collect();
        if !picked.is_empty() {
            inputs.extend(picked);
            continue;
        }
        // A sensor's name, or a sensor's name and a column's (the sensor's name may hold dots).
        let sensor = b
            .groups
            .iter()
            .find(|g| g.name == *name)
            .map(|g| (g, None))
            .or_else(|| {
                let (sensor, column) = name.rsplit_once('.')?;
                b.groups.iter().find(|g| g.name == sensor).map(|g| (g, Some(column)))
            });
        if let Some((g, column)) = sensor {
            let all = sensor_inputs(study, b, g)?;
            let found: Vec<LawInput> = all
                .iter()
                .filter(|i| column.is_none() || i.name == *name)
                .cloned()
                .collect();
            if found.is_empty() {
                let known: Vec<String> = all.into_iter().map(|i| i.name).collect();
                return Err(format!(
                    "force law: {}",
                    crate::input::source::unknown_reference("sensor column", name, &known)
                )
                .into());
            }
            inputs.extend(found);
            continue;
        }
        let mut known: Vec<String> = joints.iter().map(|(_, i)| i.name.clone()).collect();
        for g in &b.groups {
            known.extend(sensor_inputs(study, b, g).into_iter().flatten().map(|i| i.name));
        }
        return Err(format!(
            "force law: {}",
            crate::input::source::unknown_reference("joint coordinate or position/velocity sensor", name, &known)
        )
        .into());
    }
    Ok(inputs)
}

/// The inputs sensor `g` gives a force law: a position sensor's three coordinates, named as
/// its CSV file and columns are (`tip.position_y`), with the velocity as rate, or a velocity
/// sensor's three components, without a rate; another sensor is refused, located at its
/// `[[sensors]]` entry.
fn sensor_inputs(study: &Study, b: &BuiltMechanism, g: &SensorGroup) -> Result<Vec<LawInput>, BoxError> {
    let index = g
        .mbs_names
        .first()
        .and_then(|n| b.model.sensors.iter().position(|s| s.name == *n));
    let read = |axis| match index.map(|k| &b.model.sensors[k].kind) {
        Some(SensorKind::NodePosition { node }) => Some(LawRead::NodePosition { node: *node, axis }),
        Some(SensorKind::NodeVelocity { node }) => Some(LawRead::NodeVelocity { node: *node, axis }),
        _ => None,
    };
    if read(0).is_none() || g.columns.len() < 3 {
        let message = format!(
            "force law: sensor '{}' is not a position or velocity sensor: a force law reads joint \
             coordinates and the position or velocity of a point",
            g.name
        );
        let path = index.and_then(|k| b.entities.get(&mbs::Entity::Sensor(k)));
        return Err(match path {
            Some(path) => format!("{}: {path}: {message}", study.location(path)),
            None => message,
        }
        .into());
    }
    Ok((0..3)
        .filter_map(|axis| {
            let column = g.columns[axis]
                .split_once(" [")
                .map_or(g.columns[axis].as_str(), |(c, _)| c);
            Some(LawInput {
                name: format!("{}.{column}", g.name),
                reads: read(axis)?,
            })
        })
        .collect())
}

/// The system of `b`, with the force law of `forces` when there is one.
pub fn system(study: &Study, b: &BuiltMechanism, forces: &Forces) -> Result<System, BoxError> {
    let Some(source) = forces else {
        return b.system(study);
    };
    let law = source.law(law_ports(study, b, source.as_ref())?)?;
    b.system_with(study, |model| System::with_force_law(model, law))
}
