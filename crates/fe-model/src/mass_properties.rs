//! Mass properties of an FE model computed from its elements: the mass and centre of mass
//! of the same mass distribution the assembled mass matrix holds (so a check of a reduced
//! body's centre of mass against it agrees to round-off).

#![allow(non_snake_case)]

use crate::element::solid::scalar_mass;
use crate::{Element, FeError, FeModel};
use nalgebra::{Point3, Vector3};

/// Mass and centre of mass of the elements of `model`, from the same mass distribution the
/// mass matrix holds (the reduction checks an auxiliary node against its own centre of mass
/// to a millionth of the body's size, so an approximation would not do). Elements without a
/// material or section are skipped; a model without mass gives mass 0 and the origin.
///
/// # Errors
/// [`FeError::Element`] when a solid's geometry gives no mass matrix (an inverted cell).
///
/// # Derivation
/// Beams: $\rho A L$ at the element midpoint, exact for a straight prismatic element with
/// consistent or lumped (half to each node) mass. Solids: with the scalar mass matrix
/// $m_{ab} = \int\rho N_a N_b\,dV$ and $\sum_a N_a = 1$,
/// $\int\rho\,dV = \sum_{ab} m_{ab}$ and $\int\rho\,\mathbf x\,dV = \sum_b \mathbf x_b \sum_a m_{ab}$
/// (isoparametric: $\mathbf x = \sum_b N_b\mathbf x_b$); for HRZ-lumped mass the same sums
/// over the diagonal, which is what the reduction's lumped mass matrix gives.
pub fn center_of_mass(model: &FeModel) -> Result<(f64, Point3<f64>), FeError> {
    let mut mass = 0.0;
    let mut first = Vector3::zeros();
    for (e, element) in model.elements.iter().enumerate() {
        match element {
            Element::Beam2(b) => {
                let x1 = model.mesh.nodes[b.nodes[0].index()];
                let x2 = model.mesh.nodes[b.nodes[1].index()];
                let (Some(section), Some(material)) = (
                    model.sections.get(b.section.0 as usize),
                    model.materials.get(b.material.0 as usize),
                ) else {
                    continue;
                };
                let m = material.rho() * section.A() * (x2 - x1).norm();
                mass += m;
                first += (x1.coords + x2.coords) * (0.5 * m);
            }
            _ => {
                let Some((kind, solid)) = element.solid() else {
                    continue;
                };
                let Some(material) = model.materials.get(solid.material.0 as usize) else {
                    continue;
                };
                let X_e: Vec<Point3<f64>> = solid.nodes.iter().map(|n| model.mesh.nodes[n.index()]).collect();
                let m_ab = scalar_mass(kind, e, &X_e, material.rho(), solid.mass)?;
                for b in 0..X_e.len() {
                    let col: f64 = m_ab.column(b).sum();
                    mass += col;
                    first += X_e[b].coords * col;
                }
            }
        }
    }
    Ok((mass, Point3::from(first / mass.max(f64::MIN_POSITIVE))))
}
