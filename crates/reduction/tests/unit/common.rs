// Fixtures shared by the unit tests: the straight beam models several areas reduce.

use fe_model::generate::straight_beam;
use fe_model::{BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind, NodeId};
use nalgebra::{Point3, Vector3};

/// Steel: E = 210 GPa, nu = 0.3, rho = 7850 kg/m^3.
pub fn steel() -> IsotropicMaterial {
    IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap()
}

/// Circular section d = 20 mm.
pub fn d20() -> BeamSection {
    BeamSection::circle("d20", 0.02, 0.3).unwrap()
}

/// A straight beam of `material` and `section` from `a` to `b`, `n` elements with `theory`,
/// `mass` and the orientation vector `orientation`: the model and its nodes in order.
pub fn beam_model(
    material: IsotropicMaterial,
    section: BeamSection,
    (theory, mass): (BeamTheory, MassKind),
    orientation: Vector3<f64>,
    (a, b): (Point3<f64>, Point3<f64>),
    n: usize,
) -> (FeModel, Vec<NodeId>) {
    let mut model = FeModel::default();
    let material = model.add_material(material);
    let section = model.add_section(section);
    let props = BeamProperties {
        section,
        material,
        orientation,
        theory,
        mass,
    };
    let nodes = straight_beam(&mut model, a, b, n, &props, None).unwrap();
    (model, nodes)
}

/// A free 1 m steel Timoshenko beam of `section` along the skewed axis (1, 0.5, -0.3) from
/// (0.1, 0.2, 0.3), `n` elements with `mass`: the model and its nodes in order.
pub fn skew_steel_beam(n: usize, section: BeamSection, mass: MassKind) -> (FeModel, Vec<NodeId>) {
    let axis = Vector3::new(1.0, 0.5, -0.3).normalize();
    let p0 = Point3::new(0.1, 0.2, 0.3);
    beam_model(
        steel(),
        section,
        (BeamTheory::Timoshenko, mass),
        Vector3::z().cross(&axis),
        (p0, p0 + axis),
        n,
    )
}
