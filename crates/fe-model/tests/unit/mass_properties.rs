//! `center_of_mass` against closed forms: a solid box (every solid kind, consistent and lumped
//! mass, off the origin) and a round beam along a skew axis (a cylinder).

use fe_model::generate::straight_beam;
use fe_model::{
    box_mesh, center_of_mass, solid_model, BeamProperties, BeamSection, BeamTheory, CellKind, FeModel,
    IsotropicMaterial, MassKind,
};
use nalgebra::{Point3, Vector3};

/// A box a x b x c of density rho has mass rho a b c and its centre at the middle: every
/// solid kind integrates a constant density exactly, so the sums of its mass matrix give both
/// to round-off (1e-12 relative: sums of a few hundred entries of size 1e-3 of the total).
#[test]
fn box_mass_and_centre_are_exact() {
    let (a, b, c, rho) = (0.4, 0.1, 0.05, 7850.0);
    let shift = Vector3::new(1.0, -2.0, 0.5);
    for kind in [
        CellKind::Hex8,
        CellKind::Hex20,
        CellKind::Tet4,
        CellKind::Tet10,
        CellKind::Wedge6,
    ] {
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let mut mesh = box_mesh(kind, [a, b, c], [4, 2, 1]).unwrap();
            for x in mesh.nodes.iter_mut() {
                *x += shift;
            }
            let steel = IsotropicMaterial::new("steel", 210e9, 0.3, rho).unwrap();
            let model = solid_model(mesh, steel, mass).unwrap();
            let (m, com) = center_of_mass(&model).unwrap();
            let exact = rho * a * b * c;
            assert!(
                (m - exact).abs() < 1e-12 * exact,
                "{kind:?} {mass:?}: mass {m} vs {exact}"
            );
            let centre = Point3::new(a / 2.0, b / 2.0, c / 2.0) + shift;
            assert!(
                (com - centre).norm() < 1e-12 * a,
                "{kind:?} {mass:?}: centre {com} vs {centre}"
            );
        }
    }
}

/// A round bar of diameter d and length L is a cylinder: mass rho pi d^2/4 L, centre at the
/// middle of its axis, whatever the axis and the element count (exact for straight elements).
#[test]
fn cylinder_mass_and_centre_are_exact() {
    let (d, rho) = (0.03, 2700.0);
    let (p0, p1) = (Point3::new(0.2, 0.1, -0.3), Point3::new(1.1, 0.7, 0.4));
    let mut model = FeModel::default();
    let material = model.add_material(IsotropicMaterial::new("aluminium", 70e9, 0.33, rho).unwrap());
    let section = model.add_section(BeamSection::circle("bar", d, 0.33).unwrap());
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::z(),
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    };
    straight_beam(&mut model, p0, p1, 7, &props, None).unwrap();
    let (m, com) = center_of_mass(&model).unwrap();
    let L = (p1 - p0).norm();
    let exact = rho * std::f64::consts::PI * d * d / 4.0 * L;
    // Round-off of seven element lengths and products: 1e-12 relative.
    assert!((m - exact).abs() < 1e-12 * exact, "mass {m} vs {exact}");
    assert!(
        (com - Point3::from((p0.coords + p1.coords) / 2.0)).norm() < 1e-12 * L,
        "centre {com}"
    );
}

/// A model without mass elements has mass zero (the caller refuses it) and no NaN.
#[test]
fn empty_model_has_no_mass() {
    let (m, com) = center_of_mass(&FeModel::default()).unwrap();
    assert_eq!(m, 0.0);
    assert!(com.coords.iter().all(|x| x.is_finite()));
}
