//! Sensors: each sensor of the study as the `mbs` sensors it is made of and the columns of
//! its group in the outputs.

use super::builder::Builder;
use super::mechanism::{located, BodyOut};
use crate::error::BoxError;
use crate::input::source::KeyPath;
use crate::input::validate::mechanism::{
    joint_is_angle, BodySource, PointRef, ReactionAt, SensorSpec, SensorTarget, StressNodes,
};
use crate::input::validate::Study;
use crate::sensor_group::SensorGroup;
use mbs::SensorKind;
use nalgebra::Vector3;

/// The `mbs` sensors of one sensor of the study, each with its name, and the columns of its
/// group.
type Sensor = (Vec<(String, SensorKind)>, Vec<String>);

/// The three columns `<what>_x [<unit>]`, `_y`, `_z`.
fn xyz(what: &str, unit: &str) -> Vec<String> {
    ["x", "y", "z"].iter().map(|c| format!("{what}_{c} [{unit}]")).collect()
}

impl Builder<'_> {
    /// The sensors, each added to the model as its `mbs` sensors, with its group.
    pub(super) fn sensors(&mut self) -> Result<(), BoxError> {
        let m = &self.study.mechanism;
        for s in &m.sensors {
            let (kinds, mut columns) = self.sensor(s)?;
            let node_labels = file_node_labels(self.study, s);
            if node_labels.is_some() {
                columns.push("node label [-]".into());
            }
            let mbs_names = kinds.iter().map(|(n, _)| n.clone()).collect();
            for (n, k) in kinds {
                self.entities
                    .insert(mbs::Entity::Sensor(self.model.sensors.len()), s.path.clone());
                self.model.add_sensor(&n, k);
            }
            self.groups.push(SensorGroup {
                name: s.name.clone(),
                mbs_names,
                columns,
                node_labels,
            });
        }
        Ok(())
    }

    /// The `mbs` sensors and columns of sensor `s`.
    fn sensor(&self, s: &SensorSpec) -> Result<Sensor, BoxError> {
        let single = |k: SensorKind| vec![(s.name.clone(), k)];
        Ok(match &s.target {
            SensorTarget::Position(p)
            | SensorTarget::Displacement(p)
            | SensorTarget::Rotation(p)
            | SensorTarget::Velocity(p)
            | SensorTarget::AngularVelocity(p) => {
                // One node, three components: the mbs sensor, the column name and its unit.
                let node = self.node(p, &s.path)?;
                let (kind, what, unit) = match &s.target {
                    SensorTarget::Position(_) => (SensorKind::NodePosition { node }, "position", "m"),
                    SensorTarget::Displacement(_) => (SensorKind::NodeDisplacement { node }, "displacement", "m"),
                    SensorTarget::Rotation(_) => (SensorKind::NodeRotation { node }, "rotation", "rad"),
                    SensorTarget::Velocity(_) => (SensorKind::NodeVelocity { node }, "velocity", "m/s"),
                    _ => (SensorKind::NodeAngularVelocity { node }, "angular_velocity", "rad/s"),
                };
                (single(kind), xyz(what, unit))
            }
            SensorTarget::Acceleration(p, axes) | SensorTarget::AngularAcceleration(p, axes) => {
                let node = self.node(p, &s.path)?;
                let axes = *axes;
                let (kind, what, unit) = match &s.target {
                    SensorTarget::Acceleration(..) => {
                        (SensorKind::NodeAcceleration { node, axes }, "acceleration", "m/s^2")
                    }
                    _ => (
                        SensorKind::NodeAngularAcceleration { node, axes },
                        "angular_acceleration",
                        "rad/s^2",
                    ),
                };
                (single(kind), xyz(what, unit))
            }
            SensorTarget::RelativePosition(p, r) => {
                let kind = SensorKind::RelativePosition {
                    node: self.node(p, &s.path)?,
                    reference: self.node(r, &s.path)?,
                };
                (single(kind), xyz("relative_position", "m"))
            }
            SensorTarget::Deflection { of, chord, normal } => (
                single(self.deflection(s, of, chord, normal)?),
                vec!["deflection [m]".into()],
            ),
            SensorTarget::JointCoordinate(j, c) | SensorTarget::JointRate(j, c) => {
                let (kind, column) = self.joint_sensor(s, *j, *c)?;
                (single(kind), vec![column])
            }
            SensorTarget::Stress { body, nodes } => {
                let (kind, columns) = stress_sensor(self.study, &s.path, *body, nodes, &self.bodies[*body])?;
                (single(kind), columns)
            }
            SensorTarget::Modal(b) => {
                let kind = SensorKind::ModalCoordinates {
                    body: mbs::BodyId(*b as u32),
                };
                let columns = (1..=self.bodies[*b].reduced.n_modes)
                    .map(|k| format!("eta_{k} [-]"))
                    .collect();
                (single(kind), columns)
            }
            SensorTarget::Reaction(at) => {
                let n = match at {
                    ReactionAt::Point(p) => self.node(p, &s.path)?,
                    ReactionAt::GroundJoint(j) => match self.ground_nodes[*j] {
                        Some(g) => g,
                        None => return Err(located(self.study, &s.path, "the joint has no ground node")),
                    },
                };
                let columns = ["Fx [N]", "Fy [N]", "Fz [N]", "Mx [N m]", "My [N m]", "Mz [N m]"];
                (
                    single(SensorKind::Reaction { node: n }),
                    columns.map(String::from).to_vec(),
                )
            }
            SensorTarget::DriverEffort(d) => {
                let dr = &self.study.mechanism.drivers[*d];
                let column = format!("effort [{}]", self.quantity(dr.joint, dr.coordinate).effort_unit());
                (single(SensorKind::DriverEffort { driver: *d }), vec![column])
            }
            SensorTarget::ActuatorEffort(a) => {
                let m = &self.study.mechanism;
                let ac = &m.actuators[*a];
                let unit = if joint_is_angle(m, ac.joint, ac.coordinate) {
                    "N m"
                } else {
                    "N"
                };
                (
                    single(SensorKind::ActuatorEffort { actuator: *a }),
                    vec![format!("effort [{unit}]")],
                )
            }
            SensorTarget::Energy => energy(s),
            SensorTarget::EnergyBalance => energy_balance(s),
            SensorTarget::Momentum => momentum(s),
        })
    }

    /// The `mbs` sensor of a `deflection` sensor: the distance of point `of` from the line
    /// through the points of `chord`.
    fn deflection(
        &self,
        s: &SensorSpec,
        of: &PointRef,
        chord: &[PointRef; 2],
        normal: &Option<Vector3<f64>>,
    ) -> Result<SensorKind, BoxError> {
        let m = &self.study.mechanism;
        let (a, b) = (self.node(&chord[0], &s.path)?, self.node(&chord[1], &s.path)?);
        let (xa, xb) = (
            self.model.nodes[a.index()].position,
            self.model.nodes[b.index()].position,
        );
        // Coincident chord points define no line: the "deflection" would be a distance to a
        // point. 1e-9 of the coordinates' size is round-off.
        if (xb - xa).norm() <= 1e-9 * xa.norm().max(xb.norm()).max(f64::MIN_POSITIVE) {
            return Err(located(
                self.study,
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
        Ok(SensorKind::LineDistance {
            node: self.node(of, &s.path)?,
            a,
            b,
            normal: *normal,
        })
    }

    /// The `mbs` sensor and column of a sensor of coordinate `c` of joint `j` (its value, or
    /// its rate).
    fn joint_sensor(&self, s: &SensorSpec, j: usize, c: usize) -> Result<(SensorKind, String), BoxError> {
        let rate = matches!(s.target, SensorTarget::JointRate(..));
        let Some(joint) = self.joint_ids[j] else {
            return Err(located(self.study, &s.path, "a fixed joint has no coordinate"));
        };
        let kind = if rate {
            SensorKind::JointRate { joint, coordinate: c }
        } else {
            SensorKind::JointCoordinate { joint, coordinate: c }
        };
        let quantity = self.quantity(j, c);
        let column = if rate {
            format!("rate {c} [{}]", quantity.rate_unit())
        } else {
            format!("coordinate {c} [{}]", quantity.unit())
        };
        Ok((kind, column))
    }

    /// The quantity of coordinate `c` of joint `j`. A fixed joint has no coordinates (it is a
    /// merged node): its unit is never asked for.
    fn quantity(&self, j: usize, c: usize) -> mbs::CoordinateQuantity {
        self.study.mechanism.joints[j]
            .kind
            .as_ref()
            .map_or(mbs::CoordinateQuantity::Angle, |k| k.coordinate_quantity(c))
    }
}

/// The `mbs` sensors and columns of an `energy` sensor: kinetic, strain and gravity potential.
fn energy(s: &SensorSpec) -> Sensor {
    let kinds = vec![
        (format!("{}.kinetic", s.name), SensorKind::KineticEnergy),
        (format!("{}.strain", s.name), SensorKind::StrainEnergy),
        (format!("{}.gravity", s.name), SensorKind::GravityPotential),
    ];
    let columns = ["kinetic [J]", "strain [J]", "gravity potential [J]"];
    (kinds, columns.map(String::from).to_vec())
}

/// The `mbs` sensor and columns of an `energy-balance` sensor: the work put in, the energies
/// (named as the `energy` sensor's), the dissipated energy and the balance error.
fn energy_balance(s: &SensorSpec) -> Sensor {
    let columns = [
        "work_actuators [J]",
        "work_drivers [J]",
        "work_loads [J]",
        "kinetic [J]",
        "strain [J]",
        "gravity potential [J]",
        "dissipated [J]",
        "balance_error [J]",
    ];
    (
        vec![(s.name.clone(), SensorKind::EnergyBalance)],
        columns.map(String::from).to_vec(),
    )
}

/// The `mbs` sensors and columns of a `momentum` sensor: linear and angular.
fn momentum(s: &SensorSpec) -> Sensor {
    let kinds = vec![
        (format!("{}.linear", s.name), SensorKind::LinearMomentum),
        (format!("{}.angular", s.name), SensorKind::AngularMomentum),
    ];
    let columns = [
        "px [kg m/s]",
        "py [kg m/s]",
        "pz [kg m/s]",
        "Lx [kg m^2/s]",
        "Ly [kg m^2/s]",
        "Lz [kg m^2/s]",
    ];
    (kinds, columns.map(String::from).to_vec())
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
        StressNodes::Label(label) => {
            let Some(part) = part else {
                return Err(located(
                    study,
                    &path.key("label"),
                    format!(
                        "body '{}' is read from a file, whose nodes have no labels: give `node` or `node_at`",
                        body.name
                    ),
                ));
            };
            let tags = &part.base.mesh.node_tags;
            match tags.iter().position(|t| t == label) {
                Some(k) if k < count => Ok((SensorKind::Stress { body: id, node: k }, stress_columns())),
                Some(k) => Err(located(
                    study,
                    &path.key("label"),
                    format!("node {label} (index {k}) of part '{}' has no stresses", part.name),
                )),
                None => Err(located(
                    study,
                    &path.key("label"),
                    format!(
                        "part '{}' has no node {label} (its mesh file numbers {} nodes from {} to {})",
                        part.name,
                        tags.len(),
                        tags.iter().min().copied().unwrap_or(0),
                        tags.iter().max().copied().unwrap_or(0)
                    ),
                )),
            }
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
                        "no mesh node of body '{}' at ({}, {}, {}) (part axes); the nearest, {} at ({}, {}, {}), is {:.3e} m away",
                        body.name,
                        x.x,
                        x.y,
                        x.z,
                        body.node_name(k),
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

/// The mesh file's node numbers for a largest-von-Mises sensor (`set`) of a part read from a
/// mesh file, whose node column is then followed by the node's label; none for generated
/// meshes, whose labels are the index plus one, so their sensor files keep two columns.
fn file_node_labels(study: &Study, s: &SensorSpec) -> Option<Vec<u64>> {
    let SensorTarget::Stress {
        body,
        nodes: StressNodes::Set(_),
    } = &s.target
    else {
        return None;
    };
    let BodySource::Part(p) = study.mechanism.bodies[*body].source else {
        return None;
    };
    let part = &study.parts[p];
    part.mesh_file.as_ref().map(|_| part.base.mesh.node_tags.clone())
}

/// The columns of a stress sensor at one node.
fn stress_columns() -> Vec<String> {
    ["xx", "yy", "zz", "xy", "yz", "zx"]
        .iter()
        .map(|c| format!("stress_{c} [Pa]"))
        .chain(["von_mises [Pa]".into(), "max_principal [Pa]".into()])
        .collect()
}
