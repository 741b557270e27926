//! The data of the results page `view.html` (the `viewer` crate): each body's undeformed
//! surface with the shapes and stress shapes of its vertices, gathered once, and per output
//! time (or mode) the bodies' floating frames and elastic coordinates ([`ViewEvent`]); the
//! analyses' sensors; and the [`SceneBuilder`] that collects them for the results folder.
//!
//! # Surfaces
//!
//! Solids show their outer faces: the faces (by their corner nodes) that one element alone
//! has. Shells show their elements. Beams are tubes around their line, eight vertices a ring at
//! each end node; a tube vertex at offset $\mathbf d$ from its node moves with the node's
//! translation and rotation, $\mathbf u + \boldsymbol\theta\times\mathbf d = \mathbf S_t\mathbf q -
//! \tilde{\mathbf d}\mathbf S_r\mathbf q$ ($\tilde{\mathbf d}$ the cross-product matrix of
//! $\mathbf d$; linear in the coordinates, as the node's own shape rows).

use crate::mesh::{CellRole, VtuMesh};
pub use crate::output::observer::ViewEvent;
use crate::output::observer::{Series, Table};
use std::collections::HashMap;
pub use viewer::{Analysis, Body, BodyKind, F32s, Frame, Marker, Mode, Pose, Scene, Sensor, U32s};

/// The surface of a mesh (module docs): vertices (the mesh node of each and its offset from
/// the node, non-zero on tubes), triangles and lines.
#[derive(Clone, Debug, Default)]
pub struct Surface {
    pub node: Vec<usize>,
    pub offset: Vec<[f64; 3]>,
    pub triangles: Vec<u32>,
    pub lines: Vec<u32>,
}

/// The faces of a VTK solid cell by corner positions in its connectivity, anticlockwise seen
/// from outside: those of fe-model's linear elements, whose corner order VTK's linear and
/// quadratic cells share (`output::vtu`).
fn solid_faces(vtk: u8) -> Option<&'static [&'static [usize]]> {
    use fe_model::element::{hex8, tet4, wedge6};
    match vtk {
        10 | 24 => Some(&tet4::FACES),
        12 | 25 => Some(&hex8::FACES),
        13 => Some(&wedge6::FACES),
        _ => None,
    }
}

/// The number of corners of a VTK shell cell (triangles and quadrilaterals, linear or quadratic).
fn shell_corners(vtk: u8) -> Option<usize> {
    match vtk {
        5 | 22 => Some(3),
        9 | 23 => Some(4),
        _ => None,
    }
}

/// Tube vertices a ring.
const RING: usize = 8;

/// The surface of `points` and `cells` (module docs), tubes of radius `radius[k]` around the
/// beam line of cell `k` (`fallback` where it has none).
pub fn surface(points: &[[f64; 3]], cells: &[(u8, Vec<usize>, CellRole)], radius: &[f64], fallback: f64) -> Surface {
    let mut s = Surface::default();
    let mut vertex_of: HashMap<usize, u32> = HashMap::new();
    let mut plain = |s: &mut Surface, node: usize| -> u32 {
        *vertex_of.entry(node).or_insert_with(|| {
            s.node.push(node);
            s.offset.push([0.0; 3]);
            (s.node.len() - 1) as u32
        })
    };
    // Faces of solids, counted by their sorted corners: those of one element are outside.
    let mut faces: HashMap<Vec<usize>, (usize, Vec<usize>)> = HashMap::new();
    let mut order = Vec::new();
    for (k, (vtk, conn, role)) in cells.iter().enumerate() {
        if *role != CellRole::Element {
            continue;
        }
        if let Some(fs) = solid_faces(*vtk) {
            for f in fs {
                let corners: Vec<usize> = f.iter().map(|&k| conn[k]).collect();
                let mut key = corners.clone();
                key.sort_unstable();
                let e = faces.entry(key.clone()).or_insert_with(|| {
                    order.push(key);
                    (0, corners)
                });
                e.0 += 1;
            }
        } else if let Some(n) = shell_corners(*vtk) {
            let v: Vec<u32> = conn[..n].iter().map(|&c| plain(&mut s, c)).collect();
            fan(&mut s.triangles, &v);
        } else if *vtk == 3 && conn.len() == 2 {
            let r = radius.get(k).copied().filter(|r| *r > 0.0).unwrap_or(fallback);
            tube(&mut s, points, conn[0], conn[1], r);
        }
    }
    for key in order {
        let (count, corners) = &faces[&key];
        if *count == 1 {
            let v: Vec<u32> = corners.iter().map(|&c| plain(&mut s, c)).collect();
            fan(&mut s.triangles, &v);
        }
    }
    s
}

/// Triangles of a convex polygon.
fn fan(triangles: &mut Vec<u32>, v: &[u32]) {
    for k in 1..v.len() - 1 {
        triangles.extend([v[0], v[k], v[k + 1]]);
    }
}

/// A tube of radius `radius` from node `a` to node `b`: a ring of vertices at each end.
fn tube(s: &mut Surface, points: &[[f64; 3]], a: usize, b: usize, radius: f64) {
    let (pa, pb) = (points[a], points[b]);
    let e = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
    let len = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    if !(len > 0.0) {
        return;
    }
    let e = e.map(|x| x / len);
    // A unit vector across the beam, then the third axis.
    let pick = if e[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let n1 = cross(e, pick);
    let l1 = (n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]).sqrt();
    let n1 = n1.map(|x| x / l1);
    let n2 = cross(e, n1);
    let first = s.node.len() as u32;
    for node in [a, b] {
        for k in 0..RING {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / RING as f64;
            let (c, sn) = (phi.cos() * radius, phi.sin() * radius);
            s.node.push(node);
            s.offset.push([0, 1, 2].map(|i| c * n1[i] + sn * n2[i]));
        }
    }
    let r = RING as u32;
    for k in 0..r {
        let (i0, i1) = (first + k, first + (k + 1) % r);
        s.triangles.extend([i0, i1, i1 + r, i0, i1 + r, i0 + r]);
    }
}

/// The tube radius of a beam without a section: a fiftieth of the size of `points`, at least a
/// micrometre.
pub fn tube_radius(points: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let d: f64 = (0..3).map(|c| (hi[c] - lo[c]).max(0.0).powi(2)).sum::<f64>().sqrt();
    (d / 50.0).max(1e-6)
}

/// The rows of a vertex for node six-dof values `w` (translation, rotation): $\mathbf u +
/// \boldsymbol\theta\times\mathbf d$.
pub fn vertex_motion(w: &[f64; 6], d: &[f64; 3]) -> [f64; 3] {
    [
        w[0] + w[4] * d[2] - w[5] * d[1],
        w[1] + w[5] * d[0] - w[3] * d[2],
        w[2] + w[3] * d[1] - w[4] * d[0],
    ]
}

/// The stress shapes of a body's nodes: `value(node, k)` (six components of shape `k`) and
/// whether a node has a stress.
pub type StressOf<'a> = (&'a dyn Fn(usize, usize) -> [f64; 6], &'a dyn Fn(usize) -> bool);

/// A body for the page: `surface` of the nodes `points` (coordinates of the body's frame
/// axes, `origin` subtracted), `n_shapes` shapes with node values `shape(node, k)`, and stress
/// shapes `stress(node, k)` at the nodes where `stressed(node)`.
#[allow(clippy::too_many_arguments)]
pub fn body(
    name: &str,
    kind: BodyKind,
    points: &[[f64; 3]],
    surface: &Surface,
    origin: [f64; 3],
    node_labels: Vec<u64>,
    n_shapes: usize,
    shape: impl Fn(usize, usize) -> [f64; 6],
    stress: Option<StressOf<'_>>,
) -> Body {
    let nv = surface.node.len();
    let mut vertices = Vec::with_capacity(3 * nv);
    for (n, d) in surface.node.iter().zip(&surface.offset) {
        let p = points[*n];
        vertices.extend((0..3).map(|c| (p[c] + d[c] - origin[c]) as f32));
    }
    let mut shapes = Vec::with_capacity(3 * nv * n_shapes);
    for k in 0..n_shapes {
        for (n, d) in surface.node.iter().zip(&surface.offset) {
            shapes.extend(vertex_motion(&shape(*n, k), d).map(|x| x as f32));
        }
    }
    let (mut sigma, mut stressed) = (Vec::new(), Vec::new());
    if let Some((value, is_stressed)) = stress {
        // Tube vertices carry no stress (beam stresses are section forces, not a field).
        stressed = surface
            .node
            .iter()
            .zip(&surface.offset)
            .map(|(n, d)| u32::from(*d == [0.0; 3] && is_stressed(*n)))
            .collect();
        for k in 0..n_shapes {
            for (i, n) in surface.node.iter().enumerate() {
                let s = if stressed[i] == 1 { value(*n, k) } else { [0.0; 6] };
                sigma.extend(s.map(|x| x as f32));
            }
        }
    }
    Body {
        name: name.to_string(),
        kind,
        origin,
        vertices: F32s(vertices),
        triangles: U32s(surface.triangles.clone()),
        lines: U32s(surface.lines.clone()),
        vertex_node: U32s(surface.node.iter().map(|&n| n as u32).collect()),
        node_labels,
        n_shapes,
        shapes: F32s(shapes),
        stress: F32s(sigma),
        stressed: U32s(stressed),
    }
}

/// A pose from a position and a rotation.
pub fn pose(r: &nalgebra::Vector3<f64>, q: &nalgebra::UnitQuaternion<f64>, eta: &[f64]) -> Pose {
    Pose {
        r: [r.x, r.y, r.z],
        q: [q.i, q.j, q.k, q.w],
        eta: eta.to_vec(),
    }
}

/// Collects the page's data over a run (the results folder holds one).
#[derive(Default)]
pub struct SceneBuilder {
    pub scene: Scene,
    /// The current analysis: the values of its tables that label modes.
    mode_values: Vec<(String, Vec<f64>)>,
    /// The sensor stream of the current analysis: names and columns per group.
    sensors: Vec<Sensor>,
    x_label: String,
    /// The surface of the current analysis's part.
    part_surface: Option<Surface>,
    /// The current analysis (its index in the scene).
    current: Option<usize>,
}

impl SceneBuilder {
    pub fn new(title: &str) -> Self {
        Self {
            scene: Scene {
                title: title.to_string(),
                analyses: Vec::new(),
            },
            ..Default::default()
        }
    }

    /// The scene of an earlier run (its page's data), for the analyses `names` of the study:
    /// what this run does not run again is kept.
    pub fn keep(&mut self, earlier: Scene, names: &[String]) {
        self.scene.analyses = earlier
            .analyses
            .into_iter()
            .filter(|a| names.contains(&a.name))
            .collect();
    }

    fn current(&mut self) -> Option<&mut Analysis> {
        self.current.and_then(|k| self.scene.analyses.get_mut(k))
    }

    /// Analysis `name` starts: it replaces its results of an earlier run.
    pub fn begin(&mut self, name: &str, kind: &str) {
        self.finish_sensors();
        self.mode_values.clear();
        self.part_surface = None;
        let k = match self.scene.analyses.iter().position(|a| a.name == name) {
            Some(k) => k,
            None => {
                self.scene.analyses.push(Analysis::default());
                self.scene.analyses.len() - 1
            }
        };
        self.current = Some(k);
        self.scene.analyses[k] = Analysis {
            name: name.to_string(),
            kind: kind.to_string(),
            key_label: if kind == "equilibrium" {
                "load factor [-]".into()
            } else {
                "t [s]".into()
            },
            ..Default::default()
        };
    }

    /// A table of the current analysis: frequencies and load factors label its modes.
    pub fn table(&mut self, t: &Table) {
        let wanted = ["frequency [Hz]", "critical load factor [-]"];
        if let Some(k) = t.columns.iter().position(|c| wanted.contains(&c.as_str())) {
            self.mode_values.push((t.columns[k].clone(), t.column(k)));
        }
    }

    pub fn sensors(&mut self, x_label: &str, groups: &[crate::output::observer::SensorGroup]) {
        self.finish_sensors();
        self.x_label = x_label.to_string();
        self.sensors = groups
            .iter()
            .map(|g| Sensor {
                name: g.name.clone(),
                x_label: x_label.to_string(),
                columns: g.columns.clone(),
                ..Default::default()
            })
            .collect();
    }

    pub fn sample(&mut self, x: f64, values: &[Vec<f64>]) {
        for (s, v) in self.sensors.iter_mut().zip(values) {
            s.x.0.push(x as f32);
            s.values.0.extend(v.iter().map(|&x| x as f32));
        }
    }

    /// The sensors of the stream into the current analysis.
    pub fn finish_sensors(&mut self) {
        let sensors = std::mem::take(&mut self.sensors);
        let x_label = self.x_label.clone();
        if let Some(a) = self.current() {
            if !x_label.is_empty() && !x_label.starts_with('t') {
                a.key_label = x_label.clone();
            }
            a.sensors.extend(sensors);
        }
    }

    /// The label and frequency of mode `key` (1-based) of the current analysis.
    fn mode_label(&self, series: Series, key: f64) -> (String, Option<f64>) {
        let k = key as usize;
        let what = match series {
            Series::Shapes => "shape",
            Series::Static => "static displacement",
            _ => "mode",
        };
        if series == Series::Static {
            return (what.into(), None);
        }
        let value = |name: &str| {
            self.mode_values
                .iter()
                .find(|(c, _)| c == name)
                .and_then(|(_, v)| v.get(k.wrapping_sub(1)).copied())
                .filter(|v| v.is_finite())
        };
        match value("critical load factor [-]") {
            Some(f) => (format!("{what} {k}: load factor {f:.6}"), None),
            None => (format!("{what} {k}"), value("frequency [Hz]")),
        }
    }

    pub fn event(&mut self, e: &ViewEvent<'_>) {
        match e {
            ViewEvent::Bodies { bodies, markers } => {
                if let Some(a) = self.current() {
                    a.bodies = bodies.to_vec();
                    a.markers = markers.to_vec();
                }
            }
            ViewEvent::Base(frame) => {
                if let Some(a) = self.current() {
                    a.base = Some((*frame).clone());
                }
            }
            ViewEvent::Pose { series, key, frame } => {
                let label = self.mode_label(*series, *key);
                let Some(a) = self.current() else { return };
                match series {
                    Series::Mechanism => a.frames.push((*frame).clone()),
                    _ => a.modes.push(Mode {
                        label: label.0,
                        frequency: label.1,
                        pose: (*frame).clone(),
                    }),
                }
            }
            ViewEvent::PartField {
                series,
                key,
                mesh,
                labels,
                values,
                stress,
            } => self.part_field(*series, *key, (*mesh, *labels), values, *stress),
        }
    }

    /// A part's field becomes one more shape of its body (the body made at the first).
    fn part_field(
        &mut self,
        series: Series,
        key: f64,
        (mesh, labels): (&VtuMesh, &[u64]),
        values: &[[f64; 6]],
        stress: Option<&[[f64; 6]]>,
    ) {
        let label = self.mode_label(series, key);
        if self.part_surface.is_none() {
            self.part_surface = Some(surface(
                &mesh.points,
                &mesh.cells,
                &mesh.radius,
                tube_radius(&mesh.points),
            ));
        }
        let s = self.part_surface.clone().unwrap_or_default();
        let Some(a) = self.current() else { return };
        if a.bodies.is_empty() {
            let mut b = body(
                &a.name,
                BodyKind::Flexible,
                &mesh.points,
                &s,
                [0.0; 3],
                labels.to_vec(),
                0,
                |_, _| [0.0; 6],
                None,
            );
            b.name = "part".into();
            a.bodies.push(b);
            a.base = Some(Frame {
                key: 0.0,
                poses: vec![Pose::at([0.0; 3], 0)],
                markers: Vec::new(),
            });
        }
        let b = &mut a.bodies[0];
        let k = b.n_shapes;
        for (n, d) in s.node.iter().zip(&s.offset) {
            b.shapes.0.extend(vertex_motion(&values[*n], d).map(|x| x as f32));
        }
        if let Some(st) = stress {
            // Stress only at the solid nodes: a node whose tensor is zero in every field has none.
            for (n, d) in s.node.iter().zip(&s.offset) {
                let v = if *d == [0.0; 3] { st[*n] } else { [0.0; 6] };
                b.stress.0.extend(v.map(|x| x as f32));
            }
            if b.stressed.0.is_empty() {
                b.stressed.0 = s.offset.iter().map(|d| u32::from(*d == [0.0; 3])).collect();
            }
        }
        b.n_shapes = k + 1;
        if let Some(base) = &mut a.base {
            base.poses[0].eta.push(0.0);
        }
        for m in &mut a.modes {
            m.pose.poses[0].eta.push(0.0);
        }
        let mut eta = vec![0.0; k + 1];
        eta[k] = 1.0;
        a.modes.push(Mode {
            label: label.0,
            frequency: label.1,
            pose: Frame {
                key,
                poses: vec![Pose {
                    r: [0.0; 3],
                    q: [0.0, 0.0, 0.0, 1.0],
                    eta,
                }],
                markers: Vec::new(),
            },
        });
    }

    /// The scene of the analyses that have something to show (a sensor stream still going
    /// on with its rows so far).
    pub fn scene(&self) -> Scene {
        let mut scene = self.scene.clone();
        if let Some(a) = self.current.and_then(|k| scene.analyses.get_mut(k)) {
            a.sensors.extend(self.sensors.iter().cloned());
        }
        scene.analyses.retain(|a| a.has_content());
        scene
    }
}

/// A scene builder receives the page's events of a run made without a results folder.
impl crate::output::observer::Observer for SceneBuilder {
    fn begin(&mut self, a: &crate::output::observer::AnalysisInfo) -> Result<(), crate::error::BoxError> {
        SceneBuilder::begin(self, &a.name, &a.kind);
        Ok(())
    }
    fn table(&mut self, t: &Table) -> Result<(), crate::error::BoxError> {
        SceneBuilder::table(self, t);
        Ok(())
    }
    fn view(&mut self, event: &ViewEvent<'_>) {
        self.event(event);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two hexahedra sharing a face: the ten outer quadrilaterals (20 triangles), not the
    /// shared one; every vertex a corner node, none a mid-edge node of the quadratic one.
    #[test]
    fn the_surface_of_solids_is_their_unshared_faces() {
        let mut points = Vec::new();
        for x in [0.0, 1.0, 2.0] {
            for (y, z) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                points.push([x, y, z]);
            }
        }
        // VTK hexahedron: face x = a (0..4) then x = b (4..8), same order around.
        let hex = |a: usize, b: usize| {
            (
                12u8,
                vec![
                    4 * a,
                    4 * a + 3,
                    4 * a + 2,
                    4 * a + 1,
                    4 * b,
                    4 * b + 3,
                    4 * b + 2,
                    4 * b + 1,
                ],
                CellRole::Element,
            )
        };
        let mut cells = vec![hex(0, 1), hex(1, 2)];
        // A spider leg is not drawn.
        cells.push((3, vec![0, 11], CellRole::SpiderLeg));
        let s = surface(&points, &cells, &[], 0.1);
        assert_eq!(s.triangles.len(), 3 * 20);
        assert_eq!(s.node.len(), 12, "every node of the two bricks is on their surface");
        assert!(s.offset.iter().all(|d| *d == [0.0; 3]));
        // No triangle lies in the shared face x = 1.
        for t in s.triangles.chunks(3) {
            let xs: Vec<f64> = t.iter().map(|&v| points[s.node[v as usize]][0]).collect();
            assert!(!xs.iter().all(|&x| x == 1.0), "{xs:?}");
        }
    }

    /// A beam's tube: rings of vertices around its nodes at the radius, whose mean is the
    /// node, and whose shape rows are the node's translation plus its rotation times the
    /// offset, as a small rotation moves a point of the section.
    #[test]
    fn a_tube_vertex_moves_with_its_node_translation_and_rotation() {
        let points = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let s = surface(&points, &[(3, vec![0, 1], CellRole::Element)], &[0.05], 1.0);
        assert_eq!(s.node.len(), 2 * RING);
        assert_eq!(s.triangles.len(), 3 * 2 * RING);
        for (n, d) in s.node.iter().zip(&s.offset) {
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            assert!((r - 0.05).abs() < 1e-15 && d[0].abs() < 1e-15, "{n}: {d:?}");
        }
        let mean: f64 = s.offset[..RING].iter().map(|d| d[1] + d[2]).sum();
        assert!(mean.abs() < 1e-15);
        // A small rotation theta about x, y, z and a translation: the section point moves by
        // (exp([theta]) - I) d + u to first order.
        let w = [1e-3, -2e-3, 5e-4, 1e-6, -3e-6, 2e-6];
        let d = s.offset[3];
        let moved = vertex_motion(&w, &d);
        let theta = nalgebra::Vector3::new(w[3], w[4], w[5]);
        let exact = nalgebra::Rotation3::new(theta) * nalgebra::Vector3::from(d) - nalgebra::Vector3::from(d)
            + nalgebra::Vector3::new(w[0], w[1], w[2]);
        for c in 0..3 {
            assert!((moved[c] - exact[c]).abs() < 1e-12, "{moved:?} {exact:?}");
        }
    }

    /// A part's fields become the shapes of its one body, each mode's pose its unit
    /// coordinate, labelled with the frequencies of the analysis's table.
    #[test]
    fn a_part_field_is_a_shape_of_its_body() {
        let mut b = SceneBuilder::new("t");
        b.begin("modes", "modal");
        let mut t = Table::new("frequencies", &["mode", "frequency [Hz]"]);
        t.row(vec![1usize.into(), 12.5.into()]);
        t.row(vec![2usize.into(), 40.0.into()]);
        b.table(&t);
        let mesh = VtuMesh {
            points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            cells: vec![(10, vec![0, 1, 2, 3], CellRole::Element)],
            radius: Vec::new(),
        };
        for k in 0..2 {
            let values: Vec<[f64; 6]> = (0..4).map(|n| [0.0, 0.0, (n + k) as f64, 0.0, 0.0, 0.0]).collect();
            b.event(&ViewEvent::PartField {
                series: Series::Modes,
                key: (k + 1) as f64,
                mesh: &mesh,
                labels: &[11, 12, 13, 14],
                values: &values,
                stress: None,
            });
        }
        let scene = b.scene();
        let a = &scene.analyses[0];
        assert_eq!(a.bodies[0].n_shapes, 2);
        assert_eq!(a.bodies[0].shapes.0.len(), 2 * 3 * 4);
        assert_eq!(a.modes[1].frequency, Some(40.0));
        assert_eq!(a.modes[1].label, "mode 2");
        assert_eq!(a.modes[0].pose.poses[0].eta, [1.0, 0.0]);
        assert_eq!(a.modes[1].pose.poses[0].eta, [0.0, 1.0]);
        assert_eq!(a.base.as_ref().unwrap().poses[0].eta, [0.0, 0.0]);
        // Vertex of node 3 in shape 2 (k = 1): z displacement 4.
        let v = a.bodies[0].vertex_node.0.iter().position(|&n| n == 3).unwrap();
        assert_eq!(a.bodies[0].shapes.0[3 * 4 + 3 * v + 2], 4.0);
        assert_eq!(a.bodies[0].node_labels, [11, 12, 13, 14]);
    }
}
