//! Points welded by fixed joints become one node. A fixed joint between two body points has no
//! coordinate: in minimal coordinates the two points *are* one node, shared by both bodies
//! (module docs of the crate: bodies sharing a node are welded). [`weld_points`] merges the
//! points of a model description into the nodes of a [`Model`].

use crate::model::{Model, NodeId};
use nalgebra::Vector3;
use thiserror::Error;

/// Two points of a fixed joint that do not coincide.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("points '{a}' and '{b}' are {distance:.3e} m apart; the points of a fixed joint must coincide")]
pub struct WeldError {
    /// Index of the weld in the list given to [`weld_points`].
    pub weld: usize,
    pub a: String,
    pub b: String,
    pub distance: f64,
}

/// One point of a model description: its name and initial position.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub name: String,
    pub position: Vector3<f64>,
}

/// Welded points coincide to round-off of their placement: a millionth of the model size (the
/// largest distance of a point from the origin, at least a millimetre).
pub fn weld_tolerance(points: &[Point]) -> f64 {
    1e-6 * points.iter().map(|p| p.position.norm()).fold(1e-3, f64::max)
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Adds one node to `model` per class of points joined by `welds` (pairs of point indices) and
/// returns each point's node. A node is named after its points joined by `=` (in point
/// order) and sits at the position of one of them; nodes are added in the order of their
/// first point. Welded points farther apart than [`weld_tolerance`] are refused.
pub fn weld_points(model: &mut Model, points: &[Point], welds: &[(usize, usize)]) -> Result<Vec<NodeId>, WeldError> {
    let tolerance = weld_tolerance(points);
    let mut parent: Vec<usize> = (0..points.len()).collect();
    for (w, &(a, b)) in welds.iter().enumerate() {
        let distance = (points[a].position - points[b].position).norm();
        if distance > tolerance {
            return Err(WeldError {
                weld: w,
                a: points[a].name.clone(),
                b: points[b].name.clone(),
                distance,
            });
        }
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        parent[rb] = ra;
    }
    let mut node_of = vec![NodeId(0); points.len()];
    let mut class_node: std::collections::BTreeMap<usize, NodeId> = std::collections::BTreeMap::new();
    for i in 0..points.len() {
        let r = find(&mut parent, i);
        if let Some(n) = class_node.get(&r) {
            node_of[i] = *n;
            let name = &mut model.nodes[n.index()].name;
            name.push('=');
            name.push_str(&points[i].name);
        } else {
            let n = model.add_node(&points[i].name, points[r].position);
            class_node.insert(r, n);
            node_of[i] = n;
        }
    }
    Ok(node_of)
}
