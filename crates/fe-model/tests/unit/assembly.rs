//! Dof numbering, elimination and assembly: invariants of the assembled matrices, the
//! constraint elimination, the generators, and the errors of bad input.

use super::common::{skewed_axes, skewed_beam, steel};
use fe_model::generate::{beam_arc, frame, straight_beam, Member};
use fe_model::{
    assemble, solve_static, BeamProperties, BeamSection, BeamTheory, DofMap, DofMask, FeError, FeModel,
    LinearConstraint, MassKind, NodalLoad, NodeId, SystemPattern,
};
use nalgebra::{Point3, Vector3};

fn props(model: &mut FeModel, orientation: Vector3<f64>) -> BeamProperties {
    let material = model.add_material(steel());
    let section = model.add_section(BeamSection::circle("d20", 0.02, 0.3).unwrap());
    BeamProperties {
        section,
        material,
        orientation,
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    }
}

/// A free 3D frame (a tripod with a cross member) in general position.
fn free_frame() -> FeModel {
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::new(0.2, 0.9, -0.3));
    let points = [
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(1.0, 0.1, 0.0),
        Point3::new(0.3, 1.2, 0.2),
        Point3::new(0.4, 0.5, 1.1),
    ];
    let members: Vec<Member> = [(0, 1), (0, 2), (0, 3), (1, 2), (2, 3)]
        .iter()
        .map(|&(from, to)| Member {
            from,
            to,
            elements: 3,
            props: p.clone(),
        })
        .collect();
    frame(&mut model, &points, &members, "tripod").unwrap();
    model
}

fn dense(m: &faer::sparse::SparseColMat<usize, f64>) -> nalgebra::DMatrix<f64> {
    let d = m.to_dense();
    nalgebra::DMatrix::from_fn(d.nrows(), d.ncols(), |i, j| d[(i, j)])
}

/// The rigid motion `u = t + theta x (x - x0)`, rotations `theta`, on the free dofs.
fn rigid_vector(model: &FeModel, dofs: &DofMap, t: Vector3<f64>, theta: Vector3<f64>) -> nalgebra::DVector<f64> {
    let mut r = nalgebra::DVector::zeros(dofs.n_free());
    for (i, x) in model.mesh.nodes.iter().enumerate() {
        let u = t + theta.cross(&x.coords);
        for k in 0..6 {
            if let Some(d) = dofs.free_dof(NodeId(i as u32), k) {
                r[d.index()] = if k < 3 { u[k] } else { theta[k - 3] };
            }
        }
    }
    r
}

#[test]
fn assembled_matrices_are_symmetric_with_six_rigid_modes_and_the_right_mass() {
    let model = free_frame();
    let dofs = DofMap::new(&model).unwrap();
    let pattern = SystemPattern::new(&model, &dofs);
    let a = assemble(&model, &pattern).unwrap();
    let (K, M) = (dense(&a.K), dense(&a.M));
    // Round-off of summing element matrices.
    assert!((&K - K.transpose()).amax() <= 1e-14 * K.amax());
    assert!((&M - M.transpose()).amax() <= 1e-14 * M.amax());
    let mut total_length = 0.0;
    for e in &model.elements {
        let n = e.nodes();
        total_length += (model.mesh.nodes[n[1].index()] - model.mesh.nodes[n[0].index()]).norm();
    }
    let mass = steel().rho() * std::f64::consts::PI * 0.01 * 0.01 * total_length;
    for k in 0..3 {
        let mut t = Vector3::zeros();
        t[k] = 1.0;
        let r = rigid_vector(&model, &dofs, t, Vector3::zeros());
        // Round-off of n element contributions to the quadratic form.
        assert!(
            ((r.transpose() * &M * &r)[0] - mass).abs() < 1e-12 * mass,
            "mass along axis {k}"
        );
        assert!(
            (&K * &r).amax() <= 1e-10 * K.amax(),
            "translation {k} strains the frame"
        );
        let mut th = Vector3::zeros();
        th[k] = 1.0;
        let r = rigid_vector(&model, &dofs, Vector3::zeros(), th);
        // Infinitesimal rotations are exact in the linear element: round-off times the
        // coordinate scale (~1 m).
        assert!((&K * &r).amax() <= 1e-10 * K.amax(), "rotation {k} strains the frame");
    }
}

#[test]
fn assembly_does_not_depend_on_element_order() {
    let model = free_frame();
    let mut reversed = model.clone();
    reversed.elements.reverse();
    let get = |m: &FeModel| {
        let dofs = DofMap::new(m).unwrap();
        let a = assemble(m, &SystemPattern::new(m, &dofs)).unwrap();
        (dense(&a.K), dense(&a.M))
    };
    let (K1, M1) = get(&model);
    let (K2, M2) = get(&reversed);
    // Only the order of floating-point sums differs.
    assert!((&K1 - &K2).amax() <= 1e-14 * K1.amax());
    assert!((&M1 - &M2).amax() <= 1e-14 * M1.amax());
}

/// Two beams joined end to end by six equality constraints behave as one beam: the
/// constraint elimination is exact.
#[test]
fn constraints_are_eliminated_exactly() {
    let (x, _, z) = skewed_axes();
    let (L, P) = (1.2, 100.0);
    let (mut whole, nodes, _) = skewed_beam(L, 0.02, 0.03, 6, BeamTheory::Timoshenko, MassKind::Consistent);
    whole.add_support(nodes[0], DofMask::ALL);
    let reference = solve_static(&whole, &[NodalLoad::force(nodes[6], z * P)])
        .unwrap()
        .displacements[nodes[6].index()];

    let mut split = FeModel::default();
    let material = split.add_material(steel());
    let section = split.add_section(BeamSection::rectangle("rect", 0.02, 0.03, 0.3).unwrap());
    let (_, y, _) = skewed_axes();
    let p = BeamProperties {
        section,
        material,
        orientation: y,
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    };
    let first = straight_beam(&mut split, Point3::origin(), Point3::from(x * (L / 2.0)), 3, &p, None).unwrap();
    let second = straight_beam(
        &mut split,
        Point3::from(x * (L / 2.0)),
        Point3::from(x * L),
        3,
        &p,
        None,
    )
    .unwrap();
    for k in 0..6u8 {
        split.constraints.push(LinearConstraint {
            name: "weld".into(),
            dependent: (second[0], k),
            terms: vec![(first[3], k, 1.0)],
        });
    }
    split.add_support(first[0], DofMask::ALL);
    let u = solve_static(&split, &[NodalLoad::force(second[3], z * P)])
        .unwrap()
        .displacements[second[3].index()];
    for k in 0..6 {
        // Same equations, different numbering: round-off only.
        assert!(
            (u[k] - reference[k]).abs() <= 1e-10 * reference.iter().fold(0.0f64, |m, v| m.max(v.abs())),
            "dof {k}"
        );
    }
}

#[test]
fn arc_generator_places_nodes_on_the_circle_and_frames_share_nodes() {
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::z());
    let nodes = beam_arc(
        &mut model,
        Point3::new(0.0, 100.0, 0.0),
        Point3::origin(),
        Vector3::z(),
        std::f64::consts::FRAC_PI_4,
        8,
        &p,
        Some("bend"),
    )
    .unwrap();
    assert_eq!(nodes.len(), 9);
    for n in &nodes {
        // Rotation by nalgebra: round-off of the radius (100).
        assert!(((model.mesh.nodes[n.index()] - Point3::new(0.0, 100.0, 0.0)).norm() - 100.0).abs() < 1e-12);
    }
    let end = model.mesh.nodes[nodes[8].index()];
    let expect = Point3::new(
        100.0 * (std::f64::consts::FRAC_PI_4).sin(),
        100.0 * (1.0 - std::f64::consts::FRAC_PI_4.cos()),
        0.0,
    );
    assert!((end - expect).norm() < 1e-12, "arc end {end} vs {expect}");
    assert_eq!(model.mesh.node_set("bend.end").unwrap(), &[nodes[8]]);

    let model = free_frame();
    // 4 joints + 5 members x 2 interior nodes: members share the joint nodes.
    assert_eq!(model.node_count(), 4 + 5 * 2);
    assert_eq!(model.elements.len(), 15);
}

#[test]
fn bad_input_gives_errors_that_name_the_entity() {
    // Zero-length element.
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::y());
    let a = model.add_node(Point3::new(1.0, 2.0, 3.0));
    let b = model.add_node(Point3::new(2.0, 2.0, 3.0));
    let c = model.add_node(Point3::new(2.0, 2.0, 3.0));
    model.add_beam(a, b, &p);
    model.add_beam(b, c, &p);
    model.add_support(a, DofMask::ALL);
    let e = solve_static(&model, &[]).unwrap_err().to_string();
    assert!(e.contains("element 1") && e.contains("zero length"), "{e}");

    // Orientation vector parallel to the axis.
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::x() * 2.0);
    straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 2, &p, None).unwrap();
    let e = solve_static(&model, &[]).unwrap_err().to_string();
    assert!(e.contains("element 0") && e.contains("parallel"), "{e}");

    // Unknown node in a support and in a load.
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::y());
    let nodes = straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 2, &p, None).unwrap();
    let mut bad = model.clone();
    bad.add_support(NodeId(99), DofMask::ALL);
    let e = solve_static(&bad, &[]).unwrap_err().to_string();
    assert!(e.contains("support") && e.contains("NodeId(99)"), "{e}");
    model.add_support(nodes[0], DofMask::ALL);
    let e = solve_static(&model, &[NodalLoad::force(NodeId(42), Vector3::x())])
        .unwrap_err()
        .to_string();
    assert!(e.contains("load 0") && e.contains("NodeId(42)"), "{e}");

    // A mechanism: only the translations of the first node are held, so the beam spins
    // freely about the first node.
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::y());
    let nodes = straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 2, &p, None).unwrap();
    model.add_support(nodes[0], DofMask::TRANSLATIONS);
    let e = solve_static(&model, &[NodalLoad::force(nodes[2], Vector3::y())]).unwrap_err();
    assert!(
        matches!(e, FeError::Mechanism { .. } | FeError::LinearAlgebra(_)),
        "{e}"
    );
    assert!(e.to_string().contains("singular"), "{e}");

    // Non-positive section values.
    let e = BeamSection::from_values("bad", -1.0, 1.0, 1.0, 1.0, 0.8, 0.8)
        .unwrap_err()
        .to_string();
    assert!(e.contains("'bad'") && e.contains("area"), "{e}");
    let e = fe_model::IsotropicMaterial::new("rubber?", 1e6, 0.5, 1000.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("'rubber?'") && e.contains("Poisson"), "{e}");

    // A constraint whose dependent dof is also supported.
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::y());
    let nodes = straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 2, &p, None).unwrap();
    model.add_support(nodes[0], DofMask::ALL);
    model.constraints.push(LinearConstraint {
        name: "tie".into(),
        dependent: (nodes[0], 1),
        terms: vec![(nodes[2], 1, 1.0)],
    });
    let e = DofMap::new(&model).unwrap_err().to_string();
    assert!(
        e.contains("'tie'") && e.contains("uy") && e.contains("supported"),
        "{e}"
    );

    // Generators refuse zero elements.
    let mut model = FeModel::default();
    let p = props(&mut model, Vector3::y());
    let e = straight_beam(&mut model, Point3::origin(), Point3::new(1.0, 0.0, 0.0), 0, &p, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("at least one element"), "{e}");
}

#[test]
fn box_mesh_refuses_bad_sizes_with_an_error() {
    use fe_model::{box_mesh, CellKind};
    let e = box_mesh(CellKind::Hex8, [1.0, 0.0, 1.0], [1, 1, 1])
        .unwrap_err()
        .to_string();
    assert!(e.contains("box_mesh") && e.contains("positive"), "{e}");
    let e = box_mesh(CellKind::Hex20, [1.0, 1.0, 1.0], [1, 0, 1])
        .unwrap_err()
        .to_string();
    assert!(e.contains("division"), "{e}");
    let e = box_mesh(CellKind::Line2, [1.0, 1.0, 1.0], [1, 1, 1])
        .unwrap_err()
        .to_string();
    assert!(e.contains("solid"), "{e}");
}

/// `assemble_mass` (element masses alone, without the stiffness) gives exactly the mass
/// matrix of `assemble`, for beams and for each solid kind with an RBE2 spider (the dense
/// element transform): the same element masses added in the same order, so bit for bit.
#[test]
fn mass_alone_equals_the_mass_of_the_full_assembly() {
    use fe_model::assembly::assemble_mass;
    use fe_model::{add_interface_on_set, box_mesh, solid_model, CellKind, SpiderKind};
    let mut models = vec![free_frame()];
    for kind in [
        CellKind::Tet4,
        CellKind::Tet10,
        CellKind::Hex8,
        CellKind::Hex20,
        CellKind::Wedge6,
    ] {
        let mesh = box_mesh(kind, [0.4, 0.1, 0.1], [4, 1, 1]).unwrap();
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let mut model = solid_model(mesh.clone(), steel(), mass).unwrap();
            add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
            models.push(model);
        }
    }
    for model in models {
        let dofs = DofMap::new(&model).unwrap();
        let pattern = SystemPattern::new(&model, &dofs);
        let full = assemble(&model, &pattern).unwrap();
        let alone = assemble_mass(&model, &pattern).unwrap();
        assert_eq!(full.M.val(), alone.val(), "{} elements", model.elements.len());
    }
}
