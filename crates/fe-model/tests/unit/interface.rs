//! Interface nodes on solids (RBE2 and RBE3 spiders): the rigid spider moves its surface
//! rigidly; the interpolation spider follows the weighted least-squares rigid fit and adds no
//! stiffness; the interface node's six dofs stay independent; bad surfaces and clashing
//! constraints are refused with the interface's name.

use super::solid::{lowest_frequencies_hz, material};
use fe_model::box_mesh::{box_mesh, solid_model};
use fe_model::interface::{add_interface, add_interface_on_set, InterfaceSpec, Interfaces, SpiderKind};
use fe_model::{solve_static, CellKind, DofMap, DofMask, FeError, FeModel, MassKind, NodalLoad, NodeId};
use nalgebra::{Matrix6, Point3, SMatrix, Vector3, Vector6};

/// A box along x, clamped at x = 0.
fn clamped_box(kind: CellKind, lengths: [f64; 3], divisions: [usize; 3]) -> FeModel {
    let mut model = solid_model(
        box_mesh(kind, lengths, divisions).unwrap(),
        material(),
        MassKind::Consistent,
    )
    .unwrap();
    for n in model.node_set("x0", "clamp").unwrap().to_vec() {
        model.add_support(n, DofMask::ALL);
    }
    model
}

fn translation(u: &[f64; 6]) -> Vector3<f64> {
    Vector3::new(u[0], u[1], u[2])
}

fn rotation(u: &[f64; 6]) -> Vector3<f64> {
    Vector3::new(u[3], u[4], u[5])
}

/// A force and a moment in general directions, so that all six interface dofs move.
fn general_load(node: NodeId) -> NodalLoad {
    NodalLoad {
        node,
        force: Vector3::new(1e6, 2e6, -3e6),
        moment: Vector3::new(1e6, -2e6, 5e5),
    }
}

#[test]
fn rbe2_surface_moves_rigidly_with_the_interface_node() {
    let mut model = clamped_box(CellKind::Hex20, [2.0, 1.0, 1.0], [2, 1, 1]);
    let m = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe2).unwrap();
    // Default position: the area centroid of the face x = 2 (round-off of the face integrals).
    let x_m = model.mesh.nodes[m.index()];
    assert!((x_m - Point3::new(2.0, 0.5, 0.5)).norm() <= 1e-14, "interface at {x_m}");
    // The interface node's six dofs are independent unknowns.
    let dofs = DofMap::new(&model).unwrap();
    assert!(
        (0..6).all(|k| dofs.free_dof(m, k).is_some()),
        "interface dofs are not all free"
    );

    let sol = solve_static(&model, &[general_load(m)]).unwrap();
    let u_m = sol.displacements[m.index()];
    assert!(rotation(&u_m).norm() > 0.0 && translation(&u_m).norm() > 0.0);
    let scale = translation(&u_m).norm() + rotation(&u_m).norm();
    for &s in model.node_set("x1", "test").unwrap() {
        let r = model.mesh.nodes[s.index()] - x_m;
        let rigid = translation(&u_m) + rotation(&u_m).cross(&r);
        let u_s = translation(&sol.displacements[s.index()]);
        // The constraint rows are exact: only the round-off of expanding them remains.
        assert!(
            (u_s - rigid).norm() <= 1e-13 * scale,
            "node {s:?}: {u_s} vs rigid {rigid}"
        );
    }
    // Equilibrium: the clamp takes the applied force (round-off of the solve, whose relative
    // residual solve_static keeps below 1e-8).
    let R: Vector3<f64> = sol.reactions.iter().map(|(_, r)| Vector3::new(r[0], r[1], r[2])).sum();
    let F = general_load(m).force;
    assert!((R + F).norm() <= 1e-7 * F.norm(), "reactions {R} vs load {F}");
}

/// Tributary weights of the nodes of a regular quad4 face grid: a quarter of each adjacent
/// face's area (what HRZ lumping gives for a bilinear rectangle).
fn grid_weights(model: &FeModel, set: &[NodeId], hy: f64, hz: f64) -> Vec<f64> {
    let (ymax, zmax) = (1.0, 1.0);
    set.iter()
        .map(|n| {
            let x = model.mesh.nodes[n.index()];
            // Number of faces touching the node: 1 at a corner, 2 on an edge, 4 inside.
            let on_y = x.y.abs() < 1e-12 || (x.y - ymax).abs() < 1e-12;
            let on_z = x.z.abs() < 1e-12 || (x.z - zmax).abs() < 1e-12;
            let faces = match (on_y, on_z) {
                (true, true) => 1.0,
                (true, false) | (false, true) => 2.0,
                (false, false) => 4.0,
            };
            faces * hy * hz / 4.0
        })
        .collect()
}

/// The RBE3 interface motion is the weighted least-squares rigid fit of its surface's motion,
/// with tributary-area weights, computed here independently.
#[test]
fn rbe3_interface_follows_the_weighted_least_squares_rigid_fit() {
    // An uneven face grid (2 x 3 quads) so that corner, edge and inner weights all differ.
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 2, 3]);
    let m = add_interface_on_set(
        &mut model,
        "tip",
        "x1",
        Some(Point3::new(2.3, 0.4, 0.7)),
        SpiderKind::Rbe3,
    )
    .unwrap();
    let x_m = model.mesh.nodes[m.index()];
    assert_eq!(x_m, Point3::new(2.3, 0.4, 0.7), "the given position is kept");
    let sol = solve_static(&model, &[general_load(m)]).unwrap();
    let set = model.node_set("x1", "test").unwrap().to_vec();
    let w = grid_weights(&model, &set, 0.5, 1.0 / 3.0);
    let fit = weighted_rigid_fit(&model, &set, &w, x_m, &sol.displacements);
    let u_m = Vector6::from_column_slice(&sol.displacements[m.index()]);
    // Round-off: the elimination solves the same six equations, through a 6 x 6 inverse whose
    // condition number is ~ (extent / spacing)^2 ~ 1e2.
    assert!(
        (u_m - fit).norm() <= 1e-11 * fit.norm(),
        "interface {u_m} vs rigid fit {fit}"
    );
}

/// The weighted least-squares rigid fit $[\mathbf u_m; \boldsymbol\theta_m]$ about `x_m` of the
/// translations of the nodes `set` with weights `w`, computed here independently.
fn weighted_rigid_fit(
    model: &FeModel,
    set: &[NodeId],
    w: &[f64],
    x_m: Point3<f64>,
    displacements: &[[f64; 6]],
) -> Vector6<f64> {
    let mut A = Matrix6::zeros();
    let mut b = Vector6::zeros();
    for (s, w_s) in set.iter().zip(w) {
        let r = model.mesh.nodes[s.index()] - x_m;
        let mut S = SMatrix::<f64, 3, 6>::zeros();
        S.fixed_view_mut::<3, 3>(0, 0).fill_with_identity();
        S.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r.cross_matrix()));
        A += *w_s * S.transpose() * S;
        b += *w_s * S.transpose() * translation(&displacements[s.index()]);
    }
    A.lu().solve(&b).unwrap()
}

/// A node set that takes in a layer of nodes below the surface (here: every node with x >= 1
/// of a 2-element bar of unit cubes along x) weighs the boundary faces only: the face x = 1
/// that the two cubes share lies inside the solid. By hand, each unit face gives a quarter to
/// each corner: a corner at x = 2 touches the end face and two side faces (3/4), a corner at
/// x = 1 two side faces only (1/2; counting the shared face would give 3/4, i.e. equal
/// weights). The area centroid of the end face (area 1, x = 2) and the four sides (area 1
/// each, x = 1.5) is x = (2 + 4 * 1.5) / 5 = 1.6 (1.5 with the shared face).
#[test]
fn rbe3_weights_count_boundary_faces_only() {
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1]);
    let set: Vec<NodeId> = (0..model.node_count() as u32)
        .map(NodeId)
        .filter(|n| model.mesh.nodes[n.index()].x > 0.5)
        .collect();
    assert_eq!(set.len(), 8);
    let m = add_interface(&mut model, "tip", &set, None, SpiderKind::Rbe3).unwrap();
    let x_m = model.mesh.nodes[m.index()];
    // Round-off of the face integrals (exact Gauss rules on unit squares).
    assert!((x_m - Point3::new(1.6, 0.5, 0.5)).norm() <= 1e-14, "interface at {x_m}");
    let w: Vec<f64> = set
        .iter()
        .map(|n| if model.mesh.nodes[n.index()].x > 1.5 { 0.75 } else { 0.5 })
        .collect();
    let sol = solve_static(&model, &[general_load(m)]).unwrap();
    let fit = weighted_rigid_fit(&model, &set, &w, x_m, &sol.displacements);
    let u_m = Vector6::from_column_slice(&sol.displacements[m.index()]);
    // Round-off, as in the rigid-fit test above; equal weights miss by ~1e-2 relative.
    assert!(
        (u_m - fit).norm() <= 1e-11 * fit.norm(),
        "interface {u_m} vs rigid fit {fit}"
    );

    // A finer mesh of the same bar: nodes inside the solid (on shared faces only) weigh
    // nothing, so the default position is the same area centroid, not the node mean (x = 1.5).
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [4, 2, 2]);
    let set: Vec<NodeId> = (0..model.node_count() as u32)
        .map(NodeId)
        .filter(|n| model.mesh.nodes[n.index()].x > 0.75)
        .collect();
    let m = add_interface(&mut model, "tip", &set, None, SpiderKind::Rbe3).unwrap();
    let x_m = model.mesh.nodes[m.index()];
    // Round-off of summing 20 face integrals.
    assert!((x_m - Point3::new(1.6, 0.5, 0.5)).norm() <= 1e-14, "interface at {x_m}");

    // The nodes within 0.15 m of the centre of the end face of a hex20 bar 1 x 0.2 x 0.2 m
    // (a `near`/`radius` set): the whole end face, nodes inside the solid and nodes on the
    // side faces near the end, whose faces the set covers in part. Only the end face counts:
    // the interface sits at its centre (before, the nodes off the face sent it to the mean of
    // all the nodes, 0.03 m inside the bar, with equal weights).
    let mut model = clamped_box(CellKind::Hex20, [1.0, 0.2, 0.2], [8, 2, 2]);
    let centre = Point3::new(1.0, 0.1, 0.1);
    let set: Vec<NodeId> = (0..model.node_count() as u32)
        .map(NodeId)
        .filter(|n| (model.mesh.nodes[n.index()] - centre).norm() <= 0.15)
        .collect();
    let m = add_interface(&mut model, "end", &set, None, SpiderKind::Rbe3).unwrap();
    let x_m = model.mesh.nodes[m.index()];
    // Round-off of the face integrals (exact Gauss rules on flat quad8 faces).
    assert!((x_m - centre).norm() <= 1e-14, "interface at {x_m}");
}

/// RBE3 adds no stiffness: a free body keeps its frequencies when RBE3 interfaces are added
/// (and its six rigid modes), while RBE2 interfaces stiffen it.
#[test]
fn rbe3_adds_no_stiffness() {
    let free = || {
        solid_model(
            box_mesh(CellKind::Hex20, [1.0, 0.8, 0.6], [2, 2, 2]).unwrap(),
            material(),
            MassKind::Consistent,
        )
        .unwrap()
    };
    // Shift of 1 Hz: K + s M is positive definite for the free body; rigid modes at ~0 Hz.
    let n = 12;
    let f0 = lowest_frequencies_hz(&free(), n);
    let with = |kind: SpiderKind| {
        let mut model = free();
        add_interface_on_set(&mut model, "left", "x0", None, kind).unwrap();
        add_interface_on_set(&mut model, "right", "x1", None, kind).unwrap();
        // A third one off the surface, as for a joint's centre. RBE3 spiders may share nodes
        // (the face z1 shares edges with x0 and x1); two rigid spiders may not, so the RBE2
        // variant takes the inner part of the face only.
        let top: Vec<NodeId> = model
            .node_set("z1", "test")
            .unwrap()
            .iter()
            .copied()
            .filter(|n| {
                kind == SpiderKind::Rbe3 || (model.mesh.nodes[n.index()].x > 0.0 && model.mesh.nodes[n.index()].x < 1.0)
            })
            .collect();
        add_interface(&mut model, "top", &top, Some(Point3::new(0.5, 0.4, 1.0)), kind).unwrap();
        lowest_frequencies_hz(&model, n)
    };
    let f3 = with(SpiderKind::Rbe3);
    let f2 = with(SpiderKind::Rbe2);
    let f_elastic = f0[6];
    for i in 0..6 {
        // Rigid modes: |omega^2| is at the round-off of the shift-invert, ~ eps * cond * s.
        assert!(
            f3[i].abs() <= 1e-4 * f_elastic,
            "RBE3 body: mode {i} at {} Hz is not rigid",
            f3[i]
        );
    }
    for i in 6..n {
        // The constrained space is the same with and without the spiders (they only
        // re-parametrise it): equal to the round-off of two different eliminations.
        assert!(
            (f3[i] / f0[i] - 1.0).abs() <= 1e-8,
            "RBE3 changed mode {i}: {} -> {} Hz",
            f0[i],
            f3[i]
        );
        // RBE2 restrains the faces: never softer (1e-9 for round-off), and stiffer overall.
        assert!(
            f2[i] >= f0[i] * (1.0 - 1e-9),
            "RBE2 softened mode {i}: {} -> {} Hz",
            f0[i],
            f2[i]
        );
    }
    assert!(
        f2[6] > 1.01 * f0[6],
        "RBE2 on two faces should stiffen the first elastic mode"
    );
}

#[test]
fn collinear_coincident_or_empty_surfaces_are_refused() {
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1]);
    // The nodes along the edge y = 0, z = 0: collinear along x.
    let edge: Vec<NodeId> = (0..model.node_count() as u32)
        .map(NodeId)
        .filter(|n| {
            let x = model.mesh.nodes[n.index()];
            x.y == 0.0 && x.z == 0.0
        })
        .collect();
    assert_eq!(edge.len(), 3);
    for kind in [SpiderKind::Rbe2, SpiderKind::Rbe3] {
        let err = add_interface(&mut model, "edge", &edge, None, kind).unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(err, FeError::Interface { ref name, .. } if name == "edge"),
            "{err:?}"
        );
        assert!(
            msg.contains("collinear") && msg.contains("rotation about the x axis"),
            "{msg}"
        );
    }
    // A diagonal line names its direction.
    let diagonal: Vec<NodeId> = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0)]
        .iter()
        .map(|p| model.mesh.nearest_node(p).unwrap())
        .collect();
    let msg = add_interface(&mut model, "diag", &diagonal, None, SpiderKind::Rbe3)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("interface 'diag'") && msg.contains("axis [0.5774, 0.5774, 0.5774]")
            || msg.contains("axis [-0.5774, -0.5774, -0.5774]"),
        "{msg}"
    );
    let msg = add_interface(&mut model, "one", &edge[..1], None, SpiderKind::Rbe2)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("interface 'one'") && msg.contains("coincide"), "{msg}");
    let msg = add_interface(&mut model, "none", &[], None, SpiderKind::Rbe2)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("interface 'none'") && msg.contains("empty"), "{msg}");
    // Nothing was added by the failed calls.
    assert!(model.constraints.is_empty());
    assert_eq!(model.node_count(), 3 * 2 * 2);
}

#[test]
fn spiders_on_supported_or_dependent_dofs_are_refused() {
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1]);
    // RBE2 on the clamped face would make supported dofs dependent.
    let msg = add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("interface 'root'") && msg.contains("supported"), "{msg}");
    // RBE3 never makes supported dofs dependent; on a fully clamped face none is left.
    let msg = add_interface_on_set(&mut model, "root3", "x0", None, SpiderKind::Rbe3)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("interface 'root3'") && msg.contains("supported"), "{msg}");
    // A second spider on the surface of an RBE3 clashes with its dependent dofs.
    add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe3).unwrap();
    let msg = add_interface_on_set(&mut model, "tip2", "x1", None, SpiderKind::Rbe2)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("interface 'tip2'") && msg.contains("already dependent"),
        "{msg}"
    );
    // The model with the one RBE3 spider is well posed.
    DofMap::new(&model).unwrap();
}

#[test]
fn interfaces_registry_keeps_names_unique() {
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1]);
    let mut interfaces = Interfaces::default();
    let surface = model.node_set("x1", "test").unwrap().to_vec();
    let a = interfaces
        .add(
            &mut model,
            InterfaceSpec {
                name: "tip",
                surface: &surface,
                at: None,
                kind: SpiderKind::Rbe3,
            },
        )
        .unwrap();
    let err = interfaces
        .add(
            &mut model,
            InterfaceSpec {
                name: "tip",
                surface: &surface,
                at: None,
                kind: SpiderKind::Rbe2,
            },
        )
        .unwrap_err();
    assert!(
        err.to_string().contains("interface 'tip'") && err.to_string().contains("already exists"),
        "{err}"
    );
    assert_eq!(interfaces.nodes(), vec![a]);
    let tip = interfaces.get("tip").unwrap();
    assert_eq!((tip.kind, tip.surface.len()), (SpiderKind::Rbe3, 4));
}

/// Spiders on adjacent faces share the nodes of the common edge: an RBE3 whose surface holds
/// dofs an RBE2 defines, and an RBE3 whose dependent dofs another RBE3 uses, are both resolved
/// by substitution, and the results still obey each spider.
#[test]
fn spiders_on_adjacent_faces_share_their_edge() {
    let mut model = clamped_box(CellKind::Hex20, [2.0, 1.0, 1.0], [2, 1, 1]);
    let tip = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe2).unwrap();
    let top = add_interface_on_set(&mut model, "top", "z1", None, SpiderKind::Rbe3).unwrap();
    let side = add_interface_on_set(&mut model, "side", "y1", None, SpiderKind::Rbe3).unwrap();
    let sol = solve_static(&model, &[general_load(top), general_load(side)]).unwrap();
    let u_m = sol.displacements[tip.index()];
    let x_m = model.mesh.nodes[tip.index()];
    let scale = translation(&u_m).norm() + rotation(&u_m).norm();
    for &s in model.node_set("x1", "test").unwrap() {
        let rigid = translation(&u_m) + rotation(&u_m).cross(&(model.mesh.nodes[s.index()] - x_m));
        // Exact constraint rows, expanded: round-off only.
        assert!((translation(&sol.displacements[s.index()]) - rigid).norm() <= 1e-12 * scale);
    }
}

/// Reactions at a support on an RBE2 interface node balance the load: the force reaches the
/// support through the spider's constraints, not through an element.
#[test]
fn reactions_at_a_spider_support_balance_the_load() {
    let mesh = box_mesh(CellKind::Hex8, [2.0, 0.5, 0.5], [4, 1, 1]).unwrap();
    let mut model = solid_model(mesh, material(), MassKind::Consistent).unwrap();
    let clamp = add_interface_on_set(&mut model, "clamp", "x0", None, SpiderKind::Rbe2).unwrap();
    let tip = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe3).unwrap();
    model.add_support(clamp, DofMask::ALL);
    let F = Vector3::new(3.0, -2.0, 5.0) * 1e3;
    let s = fe_model::solve_static(&model, &[fe_model::NodalLoad::force(tip, F)]).unwrap();
    assert_eq!(s.reactions.len(), 1);
    let (node, r) = s.reactions[0];
    assert_eq!(node, clamp);
    let x_clamp = model.mesh.nodes[clamp.index()].coords;
    let x_tip = model.mesh.nodes[tip.index()].coords;
    let moment = (x_tip - x_clamp).cross(&F);
    for k in 0..3 {
        // Equilibrium of the whole body: round-off of the solve, relative to the load.
        assert!((r[k] + F[k]).abs() < 1e-8 * F.norm(), "force {k}: {r:?}");
        assert!((r[3 + k] + moment[k]).abs() < 1e-8 * moment.norm(), "moment {k}: {r:?}");
    }
}

/// A deck numbered out of order (its first node is 13 of 12): the spider nodes are tagged above
/// every number of the deck, so a message naming a node by its tag never points at the
/// deck's node 13. A mesh numbered 1, 2, ..., n tags them by position, as before.
#[test]
fn spider_nodes_are_tagged_above_the_decks_numbers() {
    let mut model = clamped_box(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1]);
    assert_eq!(model.node_count(), 12);
    let at = |x: f64| -> Vec<NodeId> {
        (0..12u32)
            .map(NodeId)
            .filter(|n| (model.mesh.nodes[n.index()].x - x).abs() < 0.1)
            .collect()
    };
    let (tip, mid) = (at(2.0), at(1.0));
    let mut generated = model.clone();
    let m = add_interface(&mut generated, "tip", &tip, None, SpiderKind::Rbe2).unwrap();
    assert_eq!(generated.mesh.node_tags[m.index()], 13);
    model.mesh.node_tags = std::iter::once(13).chain(1..=11).collect();
    let m = add_interface(&mut model, "tip", &tip, None, SpiderKind::Rbe2).unwrap();
    let n = add_interface(&mut model, "mid", &mid, None, SpiderKind::Rbe2).unwrap();
    assert_eq!(
        (model.mesh.node_tags[m.index()], model.mesh.node_tags[n.index()]),
        (14, 15)
    );
    // Messages print the tag: the spider node's dofs are named by 14, not the deck's node 13.
    let dofs = DofMap::new(&model).unwrap();
    let first = (0..dofs.n_free() as u32)
        .map(fe_model::Dof)
        .find(|&d| dofs.full_slot(d) / 6 == m.index())
        .unwrap();
    assert_eq!(dofs.describe(first), (14, "ux"));
}
