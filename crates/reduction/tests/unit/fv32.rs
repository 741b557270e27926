// NAFEMS FV32 (validation problem A4): the cantilevered tapered membrane, in-plane modes of a
// hex20 solid mesh through the sparse path.

use fe_model::{box_mesh, solid_model, CellKind, DofMask, IsotropicMaterial, MassKind, NodeId};
use reduction::{modal_sparse, Shift};

/// The trapezoid (0,0)-(10,2)-(10,3)-(0,5), 0.05 m thick, meshed `nx` x `ny` x 1 with hex20,
/// clamped along x = 0. The out-of-plane displacement is held at the mid-plane nodes only:
/// that removes the plate's bending modes, while the faces still contract freely, so the
/// in-plane modes are those of plane stress (which is what FV32 asks for).
fn fv32_model(nx: usize, ny: usize) -> fe_model::FeModel {
    let (t, L) = (0.05, 10.0);
    let mut mesh = box_mesh(CellKind::Hex20, [L, 5.0, t], [nx, ny, 1]).unwrap();
    for p in mesh.nodes.iter_mut() {
        let width = 5.0 - 0.4 * p.x;
        p.y = 2.5 + (p.y - 2.5) * width / 5.0;
    }
    let clamp: Vec<NodeId> = mesh.node_set("x0").unwrap().to_vec();
    let mid: Vec<NodeId> = (0..mesh.nodes.len() as u32)
        .map(NodeId)
        .filter(|n| (mesh.nodes[n.index()].z - t / 2.0).abs() < 1e-9)
        .collect();
    let steel = IsotropicMaterial::new("FV32 steel", 200e9, 0.3, 8000.0).unwrap();
    let mut model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
    for n in clamp {
        model.add_support(n, DofMask::TRANSLATIONS);
    }
    for n in mid {
        model.add_support(n, DofMask::single(2));
    }
    model
}

#[test]
fn fv32_in_plane_frequencies_within_half_a_percent() {
    let reference = [44.623, 130.03, 162.70, 246.05, 379.90, 391.44];
    let model = fv32_model(16, 8);
    let (modes, _) = modal_sparse(&model, 10, Shift::Zero).unwrap();
    // One hex20 layer with the mid-plane held still has out-of-plane modes (w zero at the
    // vertical edges, not at the in-plane mid-edge nodes): keep the modes whose out-of-plane
    // motion is small against the in-plane motion (in-plane modes have only the Poisson
    // thickness change, ~1e-3 of it).
    let f: Vec<f64> = modes
        .frequencies_hz()
        .into_iter()
        .zip(&modes.shapes)
        .filter(|(_, shape)| {
            let (in_plane, out) = shape
                .iter()
                .fold((0.0, 0.0), |(a, b), u| (a + u[0] * u[0] + u[1] * u[1], b + u[2] * u[2]));
            out < 1e-2 * in_plane
        })
        .map(|(f, _)| f)
        .collect();
    assert!(f.len() >= 6, "only {} in-plane modes among the 10 lowest", f.len());
    for (i, (&ours, &r)) in f.iter().zip(&reference).enumerate() {
        let e = ((ours - r) / r).abs();
        println!("FV32 mode {}: {ours:.3} Hz vs {r} Hz ({e:.2e})", i + 1);
        // 0.5 % is the target; the NAFEMS reference values are given to 5 digits.
        assert!(e < 5e-3, "FV32 mode {}: {ours} Hz vs {r} Hz", i + 1);
    }
}
