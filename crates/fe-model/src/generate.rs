//! Beam model generators: straight beams, circular arcs, and frames whose members share
//! nodes. Each generator names its nodes in node sets so loads and supports can refer to
//! them (`"<name>"` all nodes, `"<name>.start"`, `"<name>.end"`).

use crate::error::FeError;
use crate::mesh::NodeId;
use crate::model::{BeamProperties, FeModel};
use nalgebra::{Point3, Rotation3, Unit, Vector3};

fn check_count(generator: &'static str, n: usize) -> Result<(), FeError> {
    if n == 0 {
        return Err(FeError::Generator {
            generator,
            what: "needs at least one element".into(),
        });
    }
    Ok(())
}

fn name_sets(model: &mut FeModel, name: Option<&str>, nodes: &[NodeId]) {
    if let Some(name) = name {
        model.mesh.add_to_node_set(name, nodes.iter().copied());
        model.mesh.add_to_node_set(&format!("{name}.start"), [nodes[0]]);
        model
            .mesh
            .add_to_node_set(&format!("{name}.end"), [nodes[nodes.len() - 1]]);
    }
}

/// `n` beam elements from existing node `a` to existing node `b`, with `n - 1` new interior
/// nodes evenly spaced. Returns the nodes from `a` to `b`.
pub fn beam_between(
    model: &mut FeModel,
    a: NodeId,
    b: NodeId,
    n: usize,
    props: &BeamProperties,
    name: Option<&str>,
) -> Result<Vec<NodeId>, FeError> {
    check_count("beam_between", n)?;
    model.check_node(a, "beam_between")?;
    model.check_node(b, "beam_between")?;
    let (pa, pb) = (model.mesh.nodes[a.index()], model.mesh.nodes[b.index()]);
    let mut nodes = vec![a];
    for i in 1..n {
        let t = i as f64 / n as f64;
        nodes.push(model.add_node(pa + (pb - pa) * t));
    }
    nodes.push(b);
    for w in nodes.windows(2) {
        model.add_beam(w[0], w[1], props);
    }
    name_sets(model, name, &nodes);
    Ok(nodes)
}

/// A straight beam from `p0` to `p1` with `n` elements (creates all its nodes).
pub fn straight_beam(
    model: &mut FeModel,
    p0: Point3<f64>,
    p1: Point3<f64>,
    n: usize,
    props: &BeamProperties,
    name: Option<&str>,
) -> Result<Vec<NodeId>, FeError> {
    check_count("straight_beam", n)?;
    let a = model.add_node(p0);
    let b = model.add_node(p1);
    beam_between(model, a, b, n, props, name)
}

/// A circular arc of `n` straight elements: centre `center`, first node `start`, swept by
/// `angle` (radians, right-handed) about `axis` (the normal of the arc's plane).
///
/// Each element's orientation vector points from its midpoint to the centre, so local $y$
/// is in the plane of the arc (radial) and local $z$ is along the arc's axis: `Iz` is the
/// in-plane bending stiffness and `Iy` the out-of-plane one. `props.orientation` is ignored.
pub fn beam_arc(
    model: &mut FeModel,
    center: Point3<f64>,
    start: Point3<f64>,
    axis: Vector3<f64>,
    angle: f64,
    n: usize,
    props: &BeamProperties,
    name: Option<&str>,
) -> Result<Vec<NodeId>, FeError> {
    check_count("beam_arc", n)?;
    let radius = start - center;
    let Some(axis) = Unit::try_new(axis, 1e-12) else {
        return Err(FeError::Generator {
            generator: "beam_arc",
            what: "the axis has zero length".into(),
        });
    };
    if radius.cross(&axis).norm() <= 1e-12 * radius.norm().max(1.0) {
        return Err(FeError::Generator {
            generator: "beam_arc",
            what: "the start point lies on the axis through the centre (zero radius)".into(),
        });
    }
    if !(angle.is_finite() && angle != 0.0) {
        return Err(FeError::Generator {
            generator: "beam_arc",
            what: format!("the angle must be finite and non-zero (got {angle})"),
        });
    }
    let nodes: Vec<NodeId> = (0..=n)
        .map(|i| {
            let R = Rotation3::from_axis_angle(&axis, angle * i as f64 / n as f64);
            model.add_node(center + R * radius)
        })
        .collect();
    for w in nodes.windows(2) {
        let mid = Point3::from((model.mesh.nodes[w[0].index()].coords + model.mesh.nodes[w[1].index()].coords) * 0.5);
        let p = BeamProperties {
            orientation: center - mid,
            ..props.clone()
        };
        model.add_beam(w[0], w[1], &p);
    }
    name_sets(model, name, &nodes);
    Ok(nodes)
}

/// A member of a frame: from point `from` to point `to` (indices into the frame's points),
/// meshed with `elements` beam elements.
#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    pub from: usize,
    pub to: usize,
    pub elements: usize,
    pub props: BeamProperties,
}

/// A frame: members between shared joint points (rigidly connected: they share the node).
/// Returns the node of each point; point `i` is also the node set `"<name>.p<i>"`, and each
/// member `j` is the node set `"<name>.m<j>"`.
pub fn frame(
    model: &mut FeModel,
    points: &[Point3<f64>],
    members: &[Member],
    name: &str,
) -> Result<Vec<NodeId>, FeError> {
    let joints: Vec<NodeId> = points.iter().map(|p| model.add_node(*p)).collect();
    for (j, m) in members.iter().enumerate() {
        let (Some(&a), Some(&b)) = (joints.get(m.from), joints.get(m.to)) else {
            return Err(FeError::Generator {
                generator: "frame",
                what: format!(
                    "member {j} joins points {} and {}, but the frame has {} points",
                    m.from,
                    m.to,
                    points.len()
                ),
            });
        };
        if a == b {
            return Err(FeError::Generator {
                generator: "frame",
                what: format!("member {j} starts and ends at point {}", m.from),
            });
        }
        beam_between(model, a, b, m.elements, &m.props, Some(&format!("{name}.m{j}")))?;
    }
    for (i, &node) in joints.iter().enumerate() {
        model.mesh.add_to_node_set(&format!("{name}.p{i}"), [node]);
    }
    Ok(joints)
}
