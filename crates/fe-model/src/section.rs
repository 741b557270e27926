//! Beam cross-sections, by values or by shape.
//!
//! Local axes: the beam axis is local $x$ (node 1 to node 2); local $y$ and $z$ are the
//! principal axes of the section, with local $y$ fixed by the element's orientation vector.
//! `Iy` is the second moment about local $y$ (bending in the $x$-$z$ plane), `Iz` about local
//! $z$ (bending in the $x$-$y$ plane). Shear areas are `ky * A` (shear along $y$) and `kz * A`.

#![allow(non_snake_case)]

use crate::error::PropertyError;
use serde::{Deserialize, Serialize};

/// A beam cross-section.
///
/// Invariant: `A, Iy, Iz, J > 0` and finite; shear factors `0 < ky, kz <= 1`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamSection {
    name: String,
    A: f64,
    Iy: f64,
    Iz: f64,
    J: f64,
    ky: f64,
    kz: f64,
    /// The outline for fibre stresses; [`SectionShape::Unknown`] for a section given by values
    /// (and in files written before shapes were kept).
    #[serde(default)]
    shape: SectionShape,
}

/// The outline of a section, for the extreme-fibre stresses
/// ([`BeamSection::fibre_stress_range`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum SectionShape {
    /// Given by values: no outline, no fibre stresses.
    #[default]
    Unknown,
    /// Solid rectangle, width `b` along local $y$, height `h` along local $z$.
    Rectangle { b: f64, h: f64 },
    /// Circular tube (`d_inner = 0`: solid circle).
    Tube { d_outer: f64, d_inner: f64 },
}

impl BeamSection {
    /// Section from values: area, second moments about local y and z, torsion constant, and
    /// the shear factors for shear along local y and z.
    pub fn from_values(name: &str, A: f64, Iy: f64, Iz: f64, J: f64, ky: f64, kz: f64) -> Result<Self, PropertyError> {
        let bad = |what: &str, value: f64| PropertyError::Section {
            name: name.to_string(),
            what: what.to_string(),
            value,
        };
        for (label, v) in [("area A", A), ("Iy", Iy), ("Iz", Iz), ("torsion constant J", J)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(bad(&format!("{label} must be positive and finite"), v));
            }
        }
        for (label, v) in [("shear factor ky", ky), ("shear factor kz", kz)] {
            if !(v > 0.0 && v <= 1.0) {
                return Err(bad(&format!("{label} must lie in (0, 1]"), v));
            }
        }
        Ok(Self {
            name: name.to_string(),
            A,
            Iy,
            Iz,
            J,
            ky,
            kz,
            shape: SectionShape::Unknown,
        })
    }

    /// Solid rectangle, width `b` along local $y$ and height `h` along local $z$, with
    /// Poisson's ratio `nu` for the shear factor.
    ///
    /// $A = bh$, $I_y = b h^3/12$, $I_z = h b^3/12$. Torsion constant, Saint-Venant's series
    /// (Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed., 1970, torsion of a rectangular
    /// bar), with $a = \max(b,h)$, $t = \min(b,h)$:
    /// $$J = \frac{a t^3}{3}\Big[1 - \frac{192}{\pi^5}\frac{t}{a}\sum_{n=1,3,5,\dots}
    /// \frac{1}{n^5}\tanh\frac{n\pi a}{2t}\Big],$$
    /// summed to round-off ([`rectangle_torsion_constant`]). Roark's approximation
    /// $J \approx a t^3[\tfrac13 - 0.21\tfrac ta(1 - \tfrac{t^4}{12a^4})]$ (Young & Budynas,
    /// *Roark's Formulas for Stress and Strain*, 7th ed., torsion of a solid rectangle) agrees
    /// to about 0.2%. Shear factor $k_y = k_z = 10(1+\nu)/(12+11\nu)$ (G. R. Cowper, "The
    /// shear coefficient in Timoshenko's beam theory", J. Appl. Mech. 33 (1966) 335–340).
    ///
    /// # Errors
    /// [`PropertyError::Section`] if `b` or `h` is not positive and finite, or `nu` is outside
    /// $(-1, 0.5)$.
    pub fn rectangle(name: &str, b: f64, h: f64, nu: f64) -> Result<Self, PropertyError> {
        check_dimension(name, "width b", b)?;
        check_dimension(name, "height h", h)?;
        check_nu(name, nu)?;
        let k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
        let J = rectangle_torsion_constant(b, h);
        let mut section = Self::from_values(name, b * h, b * h.powi(3) / 12.0, h * b.powi(3) / 12.0, J, k, k)?;
        section.shape = SectionShape::Rectangle { b, h };
        Ok(section)
    }

    /// Solid circle of diameter `d`, with Poisson's ratio `nu` for the shear factor.
    ///
    /// $A = \pi d^2/4$, $I_y = I_z = \pi d^4/64$, $J = \pi d^4/32$ (exact for a circle);
    /// shear factor $k = 6(1+\nu)/(7+6\nu)$ (Cowper 1966).
    ///
    /// # Errors
    /// [`PropertyError::Section`] if `d` is not positive and finite, or `nu` is outside
    /// $(-1, 0.5)$.
    pub fn circle(name: &str, d: f64, nu: f64) -> Result<Self, PropertyError> {
        check_dimension(name, "diameter d", d)?;
        Self::tube(name, d, 0.0, nu)
    }

    /// Circular tube with outer and inner diameters `d_outer`, `d_inner` (`d_inner = 0` is a
    /// solid circle), with Poisson's ratio `nu` for the shear factor.
    ///
    /// $A = \pi(d_o^2 - d_i^2)/4$, $I_y = I_z = \pi(d_o^4 - d_i^4)/64$,
    /// $J = \pi(d_o^4 - d_i^4)/32$ (exact for a circular tube); shear factor of the hollow
    /// circle (Cowper 1966), with $m = d_i/d_o$:
    /// $$k = \frac{6(1+\nu)(1+m^2)^2}{(7+6\nu)(1+m^2)^2 + (20+12\nu)m^2}.$$
    ///
    /// # Errors
    /// [`PropertyError::Section`] if `d_outer` is not positive and finite, `d_inner` is
    /// negative or not finite, `d_inner >= d_outer`, or `nu` is outside $(-1, 0.5)$.
    pub fn tube(name: &str, d_outer: f64, d_inner: f64, nu: f64) -> Result<Self, PropertyError> {
        check_dimension(name, "outer diameter", d_outer)?;
        if !(d_inner >= 0.0 && d_inner < d_outer) {
            return Err(PropertyError::Section {
                name: name.to_string(),
                what: format!("inner diameter must lie in [0, outer diameter = {d_outer})"),
                value: d_inner,
            });
        }
        check_nu(name, nu)?;
        let pi = std::f64::consts::PI;
        let m2 = (d_inner / d_outer).powi(2);
        let q = (1.0 + m2).powi(2);
        let k = 6.0 * (1.0 + nu) * q / ((7.0 + 6.0 * nu) * q + (20.0 + 12.0 * nu) * m2);
        let A = pi * (d_outer.powi(2) - d_inner.powi(2)) / 4.0;
        let I = pi * (d_outer.powi(4) - d_inner.powi(4)) / 64.0;
        let mut section = Self::from_values(name, A, I, I, 2.0 * I, k, k)?;
        section.shape = SectionShape::Tube { d_outer, d_inner };
        Ok(section)
    }

    pub fn name(&self) -> &str {
        &self.name
    }
    pub fn A(&self) -> f64 {
        self.A
    }
    pub fn Iy(&self) -> f64 {
        self.Iy
    }
    pub fn Iz(&self) -> f64 {
        self.Iz
    }
    pub fn J(&self) -> f64 {
        self.J
    }
    pub fn ky(&self) -> f64 {
        self.ky
    }
    pub fn kz(&self) -> f64 {
        self.kz
    }
    /// The outline, when the section was given by shape.
    pub fn shape(&self) -> &SectionShape {
        &self.shape
    }

    /// The largest and smallest axial fibre stress $\sigma_x(y, z) = N/A + M_y z/I_y - M_z
    /// y/I_z$ over the section's outline for section forces `s` = $[N, V_y, V_z, T, M_y, M_z]$
    /// (the sign convention of [`crate::element::beam2::beam2_section_forces`]); `None` for a
    /// section given by values. $\sigma_x$ is linear in $(y, z)$: on a rectangle its extremes
    /// lie at the corners, on a circle of radius $r$ they are
    /// $N/A \pm r\sqrt{(M_y/I_y)^2 + (M_z/I_z)^2}$. Shear stresses of $V$ and $T$ are not
    /// included.
    pub fn fibre_stress_range(&self, s: &[f64; 6]) -> Option<[f64; 2]> {
        let n = s[0] / self.A;
        let (ky, kz) = (s[5] / self.Iz, s[4] / self.Iy);
        match self.shape {
            SectionShape::Unknown => None,
            SectionShape::Rectangle { b, h } => {
                let bending = 0.5 * b * ky.abs() + 0.5 * h * kz.abs();
                Some([n + bending, n - bending])
            }
            SectionShape::Tube { d_outer, .. } => {
                let bending = 0.5 * d_outer * (ky * ky + kz * kz).sqrt();
                Some([n + bending, n - bending])
            }
        }
    }

    /// Polar second moment `Iy + Iz`, which sets the torsional rotary inertia.
    pub fn Ip(&self) -> f64 {
        self.Iy + self.Iz
    }
}

/// Saint-Venant torsion constant of a solid `b` x `h` rectangle, the series of
/// [`BeamSection::rectangle`].
///
/// # Derivation
/// The series converges like $n^{-5}$, too slowly to sum directly to round-off. Since
/// $\sum_{n\ \mathrm{odd}} n^{-5} = (1 - 2^{-5})\zeta(5)$, we sum the exact odd-$n$ part
/// and subtract the fast-decaying correction $\sum (1 - \tanh x_n)/n^5$,
/// $x_n = n\pi a/(2t) \ge n\pi/2$, whose terms are below $2e^{-n\pi}/n^5$: by $n = 15$ they are
/// under $10^{-25}$.
pub fn rectangle_torsion_constant(b: f64, h: f64) -> f64 {
    const ZETA_5: f64 = 1.036_927_755_143_37; // zeta(5), to f64 precision
    let (a, t) = if b >= h { (b, h) } else { (h, b) };
    let pi = std::f64::consts::PI;
    let mut sum = (1.0 - 1.0 / 32.0) * ZETA_5;
    for n in (1..=15).step_by(2) {
        let n = n as f64;
        let x = n * pi * a / (2.0 * t);
        // 1 - tanh x = 2 / (e^{2x} + 1), without cancellation.
        sum -= 2.0 / ((2.0 * x).exp() + 1.0) / n.powi(5);
    }
    a * t.powi(3) / 3.0 * (1.0 - 192.0 / pi.powi(5) * (t / a) * sum)
}

fn check_dimension(name: &str, what: &str, value: f64) -> Result<(), PropertyError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(PropertyError::Section {
            name: name.to_string(),
            what: format!("{what} must be positive and finite"),
            value,
        })
    }
}

/// The shear factors of Cowper (1966) need a Poisson's ratio in the isotropic range.
fn check_nu(name: &str, nu: f64) -> Result<(), PropertyError> {
    if nu > -1.0 && nu < 0.5 {
        Ok(())
    } else {
        Err(PropertyError::Section {
            name: name.to_string(),
            what: "Poisson's ratio nu must lie in (-1, 0.5)".to_string(),
            value: nu,
        })
    }
}
