// Full-model modal analysis through the sparse path (`reduction::modal_sparse`): A1 beam
// frequencies against the analytic values and against the dense path.

use fe_model::generate::straight_beam;
use fe_model::{modal_dense, BeamProperties, BeamSection, BeamTheory, DofMask, FeModel, IsotropicMaterial, MassKind};
use nalgebra::{Point3, Vector3};
use reduction::{modal_sparse, Shift};

fn beam(n: usize, clamped: bool) -> (FeModel, BeamSection) {
    let mut model = FeModel::default();
    let material = model.add_material(IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap());
    let s = BeamSection::rectangle("r", 0.003, 0.002, 0.3).unwrap();
    let section = model.add_section(s.clone());
    let axis = Vector3::new(2.0, -1.0, 0.5).normalize();
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::z().cross(&axis),
        theory: BeamTheory::EulerBernoulli,
        mass: MassKind::Consistent,
    };
    let nodes = straight_beam(&mut model, Point3::origin(), Point3::from(axis), n, &props, None).unwrap();
    if clamped {
        model.add_support(nodes[0], DofMask::ALL);
    }
    (model, s)
}

/// A1 clamped-free through the sparse path: the first bending frequency of each plane
/// within 0.1 % with 40 elements, and the same spectrum as the dense path.
#[test]
fn a1_cantilever_through_the_sparse_path() {
    let (model, s) = beam(40, true);
    let (modes, residuals) = modal_sparse(&model, 12, Shift::Zero).unwrap();
    // The relative residual of the lowest mode of a slender beam cannot fall below the
    // round-off floor eps * lambda_max / lambda_1 (about 1e-8 here: the eigensolver accepts
    // pairs at that floor, see eigen::residual_floor); 1e-6 would flag a wrong pair.
    assert!(residuals.iter().all(|r| *r < 1e-6), "residuals {residuals:?}");
    let (E, rho, L) = (210e9, 7850.0, 1.0f64);
    let beta = 1.87510407f64;
    for I in [s.Iy(), s.Iz()] {
        let exact = beta * beta * (E * I / (rho * s.A() * L.powi(4))).sqrt();
        // One of the computed frequencies is this plane's first bending frequency. 0.1 % is
        // the required accuracy; 40 cubic elements are at about 1e-7.
        let best = modes
            .omega
            .iter()
            .map(|w| ((w - exact) / exact).abs())
            .fold(f64::INFINITY, f64::min);
        assert!(
            best < 1e-3,
            "no frequency within 0.1 % of {exact} rad/s: {:?}",
            modes.omega
        );
    }
    let dense = modal_dense(&model, 12).unwrap();
    for (a, b) in modes.omega.iter().zip(&dense.omega) {
        // Both solves are accurate to round-off relative to the mode (shift-invert in both).
        assert!((a - b).abs() < 1e-8 * b, "sparse {a} vs dense {b}");
    }
}

/// A free body: six rigid modes near zero, then the A1 free-free frequencies.
#[test]
fn a1_free_free_through_the_sparse_path_with_a_negative_shift() {
    let (model, s) = beam(40, false);
    let (modes, _) = modal_sparse(&model, 10, Shift::Auto).unwrap();
    let (E, rho, L) = (210e9, 7850.0, 1.0f64);
    let first = 4.73004074f64.powi(2) * (E * s.Iz().min(s.Iy()) / (rho * s.A() * L.powi(4))).sqrt();
    for w in &modes.omega[..6] {
        // Rigid modes: round-off of the factorised shifted pencil, far below the first
        // elastic frequency.
        assert!(w.abs() < 1e-4 * first, "rigid mode at {w} rad/s");
    }
    assert!(
        ((modes.omega[6] - first) / first).abs() < 1e-3,
        "first elastic {} vs {first}",
        modes.omega[6]
    );
}
