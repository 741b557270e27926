//! Fixtures shared by the test modules.

#![allow(non_snake_case, dead_code)]

use fe_model::generate::straight_beam;
use fe_model::{BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind, NodeId};
use nalgebra::{Point3, Vector3};

/// Steel, E = 210 GPa, nu = 0.3, rho = 7850 kg/m^3.
pub fn steel() -> IsotropicMaterial {
    IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap()
}

/// A skewed beam axis, not aligned with any global axis, and its local y and z.
pub fn skewed_axes() -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let x = Vector3::new(1.0, 2.0, 2.0).normalize();
    let y = Vector3::new(0.3, -0.4, 0.1).cross(&x).normalize();
    let z = x.cross(&y);
    (x, y, z)
}

/// A straight beam of `n` elements along the skewed axis from the origin, length `L`,
/// rectangular section `b` (along local y) x `h` (along local z). Returns the model, its
/// nodes and the section.
pub fn skewed_beam(
    L: f64,
    b: f64,
    h: f64,
    n: usize,
    theory: BeamTheory,
    mass: MassKind,
) -> (FeModel, Vec<NodeId>, BeamSection) {
    let (x, y, _) = skewed_axes();
    let mut model = FeModel::default();
    let material = model.add_material(steel());
    let s = BeamSection::rectangle("rect", b, h, 0.3).unwrap();
    let section = model.add_section(s.clone());
    let props = BeamProperties {
        section,
        material,
        orientation: y,
        theory,
        mass,
    };
    let nodes = straight_beam(
        &mut model,
        Point3::origin(),
        Point3::from(x * L),
        n,
        &props,
        Some("beam"),
    )
    .unwrap();
    (model, nodes, s)
}

/// Component of a node's translation (`k0 = 0`) or rotation (`k0 = 3`) along `dir`.
pub fn along(u: &[f64; 6], k0: usize, dir: &Vector3<f64>) -> f64 {
    Vector3::new(u[k0], u[k0 + 1], u[k0 + 2]).dot(dir)
}
