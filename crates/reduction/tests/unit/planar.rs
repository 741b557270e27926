// Planar reduction (`CbSettings::planar`, `reduction::planar_model`): a beam lying in a plane
// z = z0 of its FE axes, reduced with the out-of-plane dofs of its non-interface nodes
// supported:
// - the same body as the 3D reduction of the beam with those dofs supported by hand;
// - its fixed-interface modes are the in-plane modes of the unsupported 3D reduction (the
//   plane's symmetry decouples the two families), found independently by their mesh shapes;
// - the in-plane / out-of-plane coupling blocks of K_CB and M_CB vanish;
// - solids, nodes off the plane, sections not symmetric about the plane and external
//   matrices are refused, naming the element, node or coupling.

use fe_model::generate::straight_beam;
use fe_model::{
    box_mesh, solid_model, BeamProperties, BeamSection, BeamTheory, CellKind, DofMask, FeModel, IsotropicMaterial,
    MassKind, NodeId,
};
use nalgebra::{Point3, Vector3};
use reduction::{reduce, CbSettings, ModeSelection, ReducedBody, ReductionError, IN_PLANE_DOFS, OUT_OF_PLANE_DOFS};

/// A beam of `n` elements, 0.8 m long, in the plane z = 0.05 along 30 degrees from x, with a
/// 20 x 30 mm rectangular section whose local y axis is `orientation`, interfaces "a" and "b"
/// at its ends.
fn beam(n: usize, orientation: Vector3<f64>) -> (FeModel, Vec<(String, NodeId)>) {
    let mut model = FeModel::default();
    let material = model.add_material(IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap());
    let section = model.add_section(BeamSection::rectangle("rect", 0.02, 0.03, 0.3).unwrap());
    let props = BeamProperties {
        section,
        material,
        orientation,
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    };
    let p0 = Point3::new(0.1, -0.2, 0.05);
    let axis = Vector3::new(30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0);
    let nodes = straight_beam(&mut model, p0, p0 + axis * 0.8, n, &props, None).unwrap();
    (model, vec![("a".into(), nodes[0]), ("b".into(), nodes[n])])
}

fn settings(modes: usize, planar: bool) -> CbSettings {
    CbSettings {
        planar,
        geometric_stiffening: true,
        ..CbSettings::new(ModeSelection::Count(modes))
    }
}

/// The largest |A_rc| / sqrt(|A_rr A_cc|) between an out-of-plane interface dof r and an
/// in-plane coordinate c (interface dof or mode).
fn coupling(body: &ReducedBody, A: &reduction::DenseMatrix) -> f64 {
    let nb = 6 * body.interfaces.len();
    let n = A.nrows;
    let mut worst = 0.0f64;
    for r in (0..nb).filter(|r| OUT_OF_PLANE_DOFS.contains(&(r % 6))) {
        for c in (0..n).filter(|c| *c >= nb || IN_PLANE_DOFS.contains(&(c % 6))) {
            worst = worst.max(A.get(r, c).abs() / (A.get(r, r) * A.get(c, c)).abs().sqrt());
        }
    }
    worst
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn a_planar_reduction_is_the_beam_with_its_out_of_plane_dofs_supported() {
    let (model, interfaces) = beam(12, Vector3::z());
    let planar = reduce(&model, "beam", &interfaces, &settings(4, true)).unwrap();
    // By hand: uz, rx, ry of every interior node supported, reduced as a 3D body.
    let mut held = model.clone();
    for node in (0..model.node_count() as u32).map(NodeId) {
        if interfaces.iter().all(|(_, i)| *i != node) {
            held.add_support(node, DofMask([false, false, true, true, true, false]));
        }
    }
    let by_hand = reduce(&held, "beam", &interfaces, &settings(4, false)).unwrap();
    assert_eq!(planar.n_coordinates(), 12 + 4);
    for (a, b) in planar.fixed_interface_omega.iter().zip(&by_hand.fixed_interface_omega) {
        // The same supported model reduced twice, the same eigenproblem: equal to the
        // eigensolver's convergence, well within 1e-10.
        assert!(relative(*a, *b) < 1e-10, "{a} against {b}");
    }
    let scale = (0..16).map(|i| by_hand.K_CB.get(i, i).abs()).fold(0.0, f64::max);
    for (x, y) in planar.K_CB.data.iter().zip(&by_hand.K_CB.data) {
        // Equal matrices from the same factor; round-off of the projections, far below 1e-10.
        assert!((x - y).abs() <= 1e-10 * scale, "K_CB {x} against {y}");
    }
    // The mass data do not see the supports (they are the unsupported body's).
    assert_eq!(planar.inertia.mass, by_hand.inertia.mass);
}

#[test]
fn a_planar_reduction_keeps_the_in_plane_modes_of_the_3d_beam_and_decouples_the_plane() {
    let (model, interfaces) = beam(12, Vector3::z());
    let m = 4;
    let planar = reduce(&model, "beam", &interfaces, &settings(m, true)).unwrap();
    // The unsupported 3D beam with enough modes to hold the first m in-plane ones: each mode
    // is in-plane or out-of-plane (its mesh shape has no component in the other family).
    let full = reduce(&model, "beam", &interfaces, &settings(3 * m, false)).unwrap();
    let shapes = &full.mesh.as_ref().unwrap().shapes;
    let nb = 12;
    let mut in_plane = Vec::new();
    for (j, omega) in full.fixed_interface_omega.iter().enumerate() {
        let norm = |dofs: [usize; 3]| {
            (0..shapes.nrows)
                .filter(|r| dofs.contains(&(r % 6)))
                .map(|r| shapes.get(r, nb + j).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let (inside, out) = (norm(IN_PLANE_DOFS), norm(OUT_OF_PLANE_DOFS));
        // The 3D beam's modes are in-plane or out-of-plane by the plane's symmetry, up to the
        // eigensolver's convergence in a degenerate pair: 1e-9 of the mode's norm.
        assert!(inside.min(out) < 1e-9 * inside.max(out), "mode {j} mixes the families: {inside} {out}");
        if inside > out {
            in_plane.push(*omega);
        }
    }
    assert!(in_plane.len() >= m, "{in_plane:?}");
    for (a, b) in planar.fixed_interface_omega.iter().zip(&in_plane) {
        // As above: the planar and the 3D eigenproblems share their in-plane eigenvalues, to the
        // eigensolver's convergence, 1e-10.
        assert!(relative(*a, *b) < 1e-10, "{a} against the 3D in-plane {b}");
    }
    // All modes of the planar body are in-plane.
    let shapes = &planar.mesh.as_ref().unwrap().shapes;
    for j in 0..m {
        for r in (0..shapes.nrows).filter(|r| OUT_OF_PLANE_DOFS.contains(&(r % 6))) {
            assert_eq!(shapes.get(r, nb + j), 0.0, "mode {j} row {r}");
        }
    }
    let (k, mm) = (coupling(&planar, &planar.K_CB), coupling(&planar, &planar.M_CB));
    // The symmetry makes the coupling blocks exactly zero; 1e-12 allows round-off only.
    assert!(k < 1e-12 && mm < 1e-12, "K_CB {k:.3e}, M_CB {mm:.3e}");
    // The geometric stiffness is computed on the planar basis too.
    assert_eq!(planar.geometric_stiffness.as_ref().unwrap().len(), 12 + m);
}

#[test]
fn what_cannot_be_reduced_planar_is_refused_by_name() {
    // A section turned about the beam's axis: its principal axes are not along z.
    let (model, interfaces) = beam(6, Vector3::new(0.0, 0.3, 1.0));
    let e = reduce(&model, "oblique", &interfaces, &settings(2, true)).unwrap_err();
    assert!(matches!(e, ReductionError::NotPlanar { .. }), "{e}");
    let e = e.to_string();
    assert!(e.contains("'oblique'") && e.contains("couples"), "{e}");

    // A node off the plane.
    let (mut model, interfaces) = beam(6, Vector3::z());
    model.mesh.nodes[3].z += 1e-3;
    let e = reduce(&model, "bent", &interfaces, &settings(2, true)).unwrap_err().to_string();
    assert!(e.contains("'bent'") && e.contains("node 4"), "{e}");

    // A solid.
    let mesh = box_mesh(CellKind::Hex8, [0.3, 0.02, 0.02], [3, 1, 1]).unwrap();
    let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
    let solid = solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let e = reduce(&solid, "block", &[("a".into(), NodeId(0))], &settings(2, true))
        .unwrap_err()
        .to_string();
    assert!(e.contains("'block'") && e.contains("element 1 is not a beam"), "{e}");
}
