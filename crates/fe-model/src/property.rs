//! Materials and beam sections: values shared by many elements, checked once at
//! construction so that element kernels can trust them.

use crate::error::PropertyError;
use serde::{Deserialize, Serialize};

/// Index into [`crate::FeModel::materials`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct MaterialId(pub u32);

/// Index into [`crate::FeModel::sections`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct SectionId(pub u32);

/// Linear isotropic elastic material.
///
/// Invariant: `E > 0`, `G > 0`, `rho >= 0`, `-1 < nu < 0.5`, and `G = E / (2 (1 + nu))`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IsotropicMaterial {
    name: String,
    E: f64,
    nu: f64,
    G: f64,
    rho: f64,
}

#[allow(non_snake_case)]
impl IsotropicMaterial {
    /// Material from Young's modulus, Poisson's ratio and density.
    pub fn new(name: &str, E: f64, nu: f64, rho: f64) -> Result<Self, PropertyError> {
        let bad = |what: &str, value: f64| PropertyError::Material {
            name: name.to_string(),
            what: what.to_string(),
            value,
        };
        if !(E > 0.0 && E.is_finite()) {
            return Err(bad("Young's modulus E must be positive and finite", E));
        }
        if !(nu > -1.0 && nu < 0.5) {
            return Err(bad("Poisson's ratio nu must lie in (-1, 0.5)", nu));
        }
        if !(rho >= 0.0 && rho.is_finite()) {
            return Err(bad("density rho must be non-negative and finite", rho));
        }
        Ok(Self {
            name: name.to_string(),
            E,
            nu,
            G: E / (2.0 * (1.0 + nu)),
            rho,
        })
    }

    /// Material from Young's and shear moduli (beams often give G, not nu).
    pub fn from_E_G(name: &str, E: f64, G: f64, rho: f64) -> Result<Self, PropertyError> {
        if !(G > 0.0 && G.is_finite()) {
            return Err(PropertyError::Material {
                name: name.to_string(),
                what: "shear modulus G must be positive and finite".into(),
                value: G,
            });
        }
        let nu = E / (2.0 * G) - 1.0;
        Self::new(name, E, nu, rho)
    }

    pub fn name(&self) -> &str {
        &self.name
    }
    pub fn E(&self) -> f64 {
        self.E
    }
    pub fn nu(&self) -> f64 {
        self.nu
    }
    pub fn G(&self) -> f64 {
        self.G
    }
    pub fn rho(&self) -> f64 {
        self.rho
    }
}
