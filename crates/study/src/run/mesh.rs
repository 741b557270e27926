//! The deformed meshes of every body of the mechanism at the output times, with the stresses
//! of the bodies reduced with stress shapes and the hot spot of each.

#![allow(non_snake_case)]

use crate::build::{BuiltMechanism, LoadTarget};
use crate::error::{BoxError, ResultExt};
use crate::mesh::{CellRole, VtuMesh};
use crate::output::observer::{Observer, Series};
use crate::output::view::{self, ViewEvent};
use crate::output::vtu::{motion_fields, stress_fields, PointField};
use mbs::{NodeId, System};
use nalgebra::{Point3, Vector3};
use reduction::NodeStresses;
use serde_json::json;

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
    /// The bodies and markers of the results page, sent with the first frame
    /// (`crate::output::view`); `None` once sent.
    view: Option<(Vec<view::Body>, Vec<view::Marker>)>,
    /// The node of each marker.
    marker_nodes: Vec<NodeId>,
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
        let (bodies, markers, marker_nodes) = view_bodies(b, sys);
        Ok(Self {
            mesh,
            flexible,
            stress,
            rigid,
            hot,
            maxima,
            tracked: Vec::new(),
            view: Some((bodies, markers)),
            marker_nodes,
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
        let mut fields = Vec::from(motion_fields(&u, &rot));
        fields.extend([
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
        ]);
        let tensor: Vec<f64> = tensor.iter().flatten().copied().collect();
        if self.has_stress() {
            fields.extend(stress_fields(&tensor, &von_mises, &principal));
        }
        obs.frame(series, t, &self.mesh, &fields)?;
        let frame = self.view_frame(t, b, &kins, &motions);
        self.send_bodies(obs);
        obs.view(&ViewEvent::Pose {
            series,
            key: t,
            frame: &frame,
        });
        Ok(())
    }

    /// The page's bodies and markers, the first time.
    fn send_bodies(&mut self, obs: &mut dyn Observer) {
        if let Some((bodies, markers)) = self.view.take() {
            obs.view(&ViewEvent::Bodies {
                bodies: &bodies,
                markers: &markers,
            });
        }
    }

    /// The poses of the bodies (flexible, then rigid) and the positions of the markers.
    fn view_frame(
        &self,
        key: f64,
        b: &BuiltMechanism,
        kins: &[(superelement::Kinematics, superelement::BodyState)],
        motions: &[mbs::NodeMotion],
    ) -> view::Frame {
        let mut poses: Vec<view::Pose> = kins
            .iter()
            .map(|(kin, _)| view::pose(&kin.frame.r, &kin.frame.R, &kin.q_jj))
            .collect();
        for nodes in &b.rigid {
            let m = &motions[nodes[0].index()];
            poses.push(view::pose(&m.r, &m.R, &[]));
        }
        let markers = self
            .marker_nodes
            .iter()
            .map(|n| {
                let r = motions[n.index()].r;
                [r.x, r.y, r.z]
            })
            .collect();
        view::Frame { key, poses, markers }
    }

    /// Sends the poses at `state` to the results page alone (no mesh frame) as `key` of `series`.
    pub fn view_pose(
        &mut self,
        obs: &mut dyn Observer,
        series: Series,
        key: f64,
        sys: &System,
        state: &mbs::State,
        b: &BuiltMechanism,
    ) -> Result<(), BoxError> {
        let kins = self.kinematics(key, sys, state, b)?;
        let frame = self.view_frame(key, b, &kins, &sys.node_motions(state));
        self.send_bodies(obs);
        obs.view(&ViewEvent::Pose {
            series,
            key,
            frame: &frame,
        });
        Ok(())
    }

    /// Sends the poses at `state` as the configuration the modes of the analysis are about.
    pub fn view_base(
        &mut self,
        obs: &mut dyn Observer,
        sys: &System,
        state: &mbs::State,
        b: &BuiltMechanism,
    ) -> Result<(), BoxError> {
        let kins = self.kinematics(0.0, sys, state, b)?;
        let frame = self.view_frame(0.0, b, &kins, &sys.node_motions(state));
        self.send_bodies(obs);
        obs.view(&ViewEvent::Base(&frame));
        Ok(())
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
                "node_label": body.node_label(h.node),
                "position": position,
                x: h.time,
            }));
            lines.push(format!(
                "hot spot of body '{}': von Mises {:.6e} Pa at {}{} at {x} = {:.6}",
                body.name,
                h.von_mises,
                body.node_name(h.node),
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

/// The bodies of the results page (`crate::output::view`): each flexible body's surface with
/// its mesh shapes and stress shapes (its interfaces joined when it has no mesh shapes), each
/// rigid body's nodes joined; and markers at the joints, supports and point masses, with
/// their nodes.
fn view_bodies(b: &BuiltMechanism, sys: &System) -> (Vec<view::Body>, Vec<view::Marker>, Vec<NodeId>) {
    let mut bodies = Vec::new();
    for body in &b.bodies {
        let se = sys.superelement(body.id);
        let origin = se.map_or(Vector3::zeros(), |se| se.frame_origin());
        let origin = [origin.x, origin.y, origin.z];
        let labels = body.node_labels.clone().unwrap_or_default();
        match &body.reduced.mesh {
            Some(shapes) => {
                let points = &shapes.nodes;
                let mut surface = match &body.mesh {
                    Some(fe) => view::surface(points, &fe.cells, &fe.radius, view::tube_radius(points)),
                    None => view::Surface::default(),
                };
                if surface.node.is_empty() {
                    // Nodes without elements: drawn as points.
                    surface.node = (0..points.len()).collect();
                    surface.offset = vec![[0.0; 3]; points.len()];
                }
                let S = &shapes.shapes;
                let shape = |n: usize, k: usize| std::array::from_fn(|c| S.get(6 * n + c, k));
                let stress_shapes = se.and_then(|se| se.stress_shapes());
                let nodal = stress_shapes.and_then(|s| s.nodal.as_ref().map(|m| (m, &s.solid_node)));
                let value = |n: usize, k: usize| -> [f64; 6] {
                    let (m, _) = nodal.expect("with stress shapes");
                    std::array::from_fn(|c| m.get(6 * n + c, k))
                };
                let solid = |n: usize| nodal.is_some_and(|(_, s)| s.get(n).copied().unwrap_or(false));
                let stress: Option<view::StressOf<'_>> = nodal.map(|_| {
                    (
                        &value as &dyn Fn(usize, usize) -> [f64; 6],
                        &solid as &dyn Fn(usize) -> bool,
                    )
                });
                bodies.push(view::body(
                    &body.name,
                    view::BodyKind::Flexible,
                    points,
                    &surface,
                    origin,
                    labels,
                    S.ncols,
                    shape,
                    stress,
                ));
            }
            None => {
                let points: Vec<[f64; 3]> = body.reduced.interfaces.iter().map(|i| i.position).collect();
                bodies.push(joined(&body.name, view::BodyKind::Flexible, &points, origin));
            }
        }
    }
    for nodes in &b.rigid {
        let n0 = &b.model.nodes[nodes[0].index()];
        let back = n0.orientation.inverse();
        let points: Vec<[f64; 3]> = nodes
            .iter()
            .map(|n| {
                let x = back * (b.model.nodes[n.index()].position - n0.position);
                [x.x, x.y, x.z]
            })
            .collect();
        // The body's name: its nodes are named `body.point`.
        let name = n0.name.split('.').next().unwrap_or(&n0.name);
        bodies.push(joined(name, view::BodyKind::Rigid, &points, [0.0; 3]));
    }
    let mut markers = Vec::new();
    let mut marker_nodes = Vec::new();
    let mut mark = |name: String, kind: &str, node: NodeId| {
        let p = b.model.nodes[node.index()].position;
        markers.push(view::Marker {
            name,
            kind: kind.to_string(),
            body: None,
            position: [p.x, p.y, p.z],
            direction: None,
        });
        marker_nodes.push(node);
    };
    for j in &b.model.joints {
        mark(j.name.clone(), "joint", j.child);
    }
    // A fixed joint between bodies merged their points into one node: still a joint of the study.
    for (name, node) in &b.welds {
        mark(name.clone(), "joint", *node);
    }
    for s in &b.model.supports {
        mark(b.model.nodes[s.node.index()].name.clone(), "ground", s.node);
    }
    for m in &b.model.point_masses {
        mark(m.name.clone(), "mass", m.node);
    }
    (bodies, markers, marker_nodes)
}

/// A body drawn as its points, the first joined to the others, moving rigidly with its frame.
fn joined(name: &str, kind: view::BodyKind, points: &[[f64; 3]], origin: [f64; 3]) -> view::Body {
    let surface = view::Surface {
        node: (0..points.len()).collect(),
        offset: vec![[0.0; 3]; points.len()],
        triangles: Vec::new(),
        lines: (1..points.len() as u32).flat_map(|k| [0, k]).collect(),
    };
    view::body(
        name,
        kind,
        points,
        &surface,
        origin,
        Vec::new(),
        0,
        |_, _| [0.0; 6],
        None,
    )
}

/// The results page of the study's mechanism before it runs (`Study.show()` in Python): its
/// bodies at the initial state of the model, one frame, without the sensors. The parts are
/// reduced through the cache of `opts` first.
pub fn model_page(study: &crate::Study, opts: &crate::Options, obs: &mut dyn Observer) -> Result<String, BoxError> {
    if study.mechanism.is_empty() {
        return Err(format!(
            "{}: the study has no mechanism to draw before it runs; run it, and its results page shows the parts' analyses",
            study.source.path.display()
        )
        .into());
    }
    let b = crate::run::reduce::build_mechanism(study, &opts.cache_dir(study), obs)?;
    let sys = b.system(study)?;
    let state = sys.initial_state();
    let title = study
        .title
        .clone()
        .unwrap_or_else(|| study.source.path.display().to_string());
    let mut scene = view::SceneBuilder::new(&title);
    scene.begin("model", "model");
    let mut mw = MeshRecovery::new(&b, &sys)?;
    mw.write(&mut scene, 0.0, &sys, &state, &b)?;
    let mut scene = scene.scene();
    scene.title = format!("{title}: the model before it runs");
    let markers = model_markers(&b, &sys, &state)?;
    for a in &mut scene.analyses {
        for (marker, at) in markers.iter().cloned() {
            a.markers.push(marker);
            a.frames.iter_mut().for_each(|f| f.markers.push(at));
        }
    }
    Ok(viewer::page(&scene))
}

/// The markers that the page of a model before it runs adds, with their positions there: each
/// flexible body's interfaces, and the study's point loads as arrows in the direction of their
/// reference vectors (a load at a load point inside a body moves with the body's frame).
fn model_markers(
    b: &BuiltMechanism,
    sys: &System,
    state: &mbs::State,
) -> Result<Vec<(view::Marker, [f64; 3])>, BoxError> {
    let motions = sys.node_motions(state);
    let at_node = |n: NodeId| {
        let r = motions[n.index()].r;
        [r.x, r.y, r.z]
    };
    let mut out = Vec::new();
    for body in &b.bodies {
        for (interface, &node) in body.reduced.interfaces.iter().zip(&body.nodes) {
            let marker = view::Marker {
                name: format!("{}.{}", body.name, interface.name),
                kind: "interface".into(),
                body: None,
                position: at_node(node),
                direction: None,
            };
            out.push((marker, at_node(node)));
        }
    }
    for load in &b.loads {
        let (force, moment, body, position, world) = match &load.target {
            LoadTarget::Node(entries) => {
                let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
                for &(kind, k) in entries {
                    match kind {
                        mbs::LoadKind::Force => f += b.model.loads[k].value,
                        mbs::LoadKind::Moment => m += b.model.loads[k].value,
                    }
                }
                let Some(&(_, k)) = entries.first() else { continue };
                let x = at_node(b.model.loads[k].node);
                (f, m, None, x, x)
            }
            LoadTarget::Body(k) => {
                let l = &b.model.body_loads[*k];
                let Some(j) = b.bodies.iter().position(|body| body.id == l.body) else {
                    continue;
                };
                let p = Vector3::from(b.bodies[j].reduced.load_points[l.point].position);
                let origin = sys
                    .superelement(l.body)
                    .map_or(Vector3::zeros(), |se| se.frame_origin());
                let world = match sys.body_kinematics(state, l.body)? {
                    Some((kin, _)) => kin.frame.r + kin.frame.R * (p - origin),
                    None => p,
                };
                let x = p - origin;
                (l.force, l.moment, Some(j), [x.x, x.y, x.z], [world.x, world.y, world.z])
            }
        };
        let (kind, d) = if force.norm() > 0.0 {
            ("load", force)
        } else {
            ("moment", moment)
        };
        let marker = view::Marker {
            name: load.name.clone(),
            kind: kind.into(),
            body,
            position,
            direction: (d.norm() > 0.0).then(|| [d.x, d.y, d.z]),
        };
        out.push((marker, world));
    }
    Ok(out)
}
