//! A force law of a run ([`mbs::force_law`]) named in the study's terms: it reads joint
//! coordinates by joint name and sets actuators and point loads by their names. A
//! [`ForceLawSource`] (the Python binding's callable, say) says which names it reads and sets;
//! [`law_ports`] resolves them on the built mechanism, and the source makes the law on those
//! ports, which every analysis of the mechanism then evaluates in its Newton iterations.
//!
//! Input names: a joint with one coordinate is read by its name (`elbow`), a joint with
//! several by its name and the coordinate's index (`slider[0]`, `slider[1]`). An output named
//! after an actuator is its effort; after a point load at a node, its force \[N\] (or its
//! moment \[N m\] when the load gives no force), three values in inertial axes, times the
//! load's time function. Loads at load points inside a body and follower loads are refused.

use crate::build::{BuiltMechanism, LoadTarget};
use crate::error::BoxError;
use crate::input::validate::Study;
use mbs::{JointId, LawInput, LawOutput, LawPorts, LawTarget, LoadKind, System};
use std::sync::Arc;

/// What makes a run's force law (module docs).
pub trait ForceLawSource: Send + Sync + std::fmt::Debug {
    /// The names of the actuators and point loads the law sets.
    fn outputs(&self) -> Vec<String>;

    /// The joints whose coordinates the law reads (names as in the module docs, or a joint's
    /// name for all its coordinates); `None`: every joint.
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

/// The ports of `source` on the mechanism `b`: every coordinate of the joints it reads, and
/// the actuators and node loads it sets; a name that is neither is refused with the names
/// there are.
pub fn law_ports(b: &BuiltMechanism, source: &dyn ForceLawSource) -> Result<LawPorts, BoxError> {
    let model = &b.model;
    let mut all = Vec::new();
    for (j, joint) in model.joints.iter().enumerate() {
        let n = joint.kind.n_scalar();
        for c in 0..n {
            all.push((
                joint.name.as_str(),
                LawInput {
                    name: input_name(&joint.name, c, n),
                    joint: JointId(j as u32),
                    coordinate: c,
                },
            ));
        }
    }
    let inputs = match source.reads() {
        None => all.into_iter().map(|(_, i)| i).collect(),
        Some(names) => {
            let mut inputs = Vec::new();
            for name in &names {
                let picked: Vec<LawInput> = all
                    .iter()
                    .filter(|(joint, i)| *joint == name || i.name == *name)
                    .map(|(_, i)| i.clone())
                    .collect();
                if picked.is_empty() {
                    let known: Vec<String> = all.iter().map(|(_, i)| i.name.clone()).collect();
                    return Err(format!(
                        "force law: {}",
                        crate::input::source::unknown_reference("joint coordinate", name, &known)
                    )
                    .into());
                }
                inputs.extend(picked);
            }
            inputs
        }
    };
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

/// The system of `b`, with the force law of `forces` when there is one.
pub fn system(study: &Study, b: &BuiltMechanism, forces: &Forces) -> Result<System, BoxError> {
    let Some(source) = forces else {
        return b.system(study);
    };
    let law = source.law(law_ports(b, source.as_ref())?)?;
    b.system_with(study, |model| System::with_force_law(model, law))
}
