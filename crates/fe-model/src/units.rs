//! Unit systems of imported decks, their conversion to SI, and whether material constants are
//! plausible in SI.
//!
//! flexmbs computes in SI. An Abaqus or Nastran deck is in whatever consistent system its
//! author chose, most often SI or mm-t-s (mm, tonne, second: N, MPa, t/mm³). A deck read in
//! the wrong system is not an error the solver can see: its frequencies are off by a power of
//! ten. So a part declares its deck's system ([`UnitSystem`]), the readers convert every
//! quantity on read with [`UnitSystem::to_si`] (the one table of conversions, [`TABLE`]), and
//! the constants read are checked against what solids have ([`implausible_E`],
//! [`implausible_rho`]), the same check a study's own materials go through.

use std::fmt;

/// A consistent system of units: its length, mass and time units, from which every other
/// unit follows (force = mass length / time², and so on).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UnitSystem {
    /// m, kg, s (N, Pa, kg/m³).
    #[default]
    Si,
    /// mm, t, s (N, MPa, t/mm³): the usual system of Abaqus and Nastran decks.
    MmTonneSecond,
    /// mm, kg, ms (kN, GPa, kg/mm³): the usual system of explicit crash decks.
    MmKgMillisecond,
}

/// A physical quantity a deck may give, by its dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Coordinates, section dimensions.
    Length,
    /// Section areas.
    Area,
    /// Second moments of area and torsion constants.
    SecondMomentOfArea,
    Force,
    /// Moments and torques.
    Moment,
    /// Stresses and moduli ($E$, $G$).
    Stress,
    /// Mass density $\rho$.
    Density,
    /// Point masses.
    Mass,
    /// Rotary inertia of point masses.
    MassMomentOfInertia,
    /// Spring stiffness, force per length.
    Stiffness,
    /// Rotational spring stiffness, moment per radian.
    RotationalStiffness,
    Time,
}

/// The conversion table: each quantity's dimension as powers of (length, mass, time), and its
/// unit in SI, mm-t-s and mm-kg-ms (in the order of [`UnitSystem::ALL`]).
pub const TABLE: &[(Quantity, [i32; 3], [&str; 3])] = &[
    (Quantity::Length, [1, 0, 0], ["m", "mm", "mm"]),
    (Quantity::Area, [2, 0, 0], ["m^2", "mm^2", "mm^2"]),
    (Quantity::SecondMomentOfArea, [4, 0, 0], ["m^4", "mm^4", "mm^4"]),
    (Quantity::Force, [1, 1, -2], ["N", "N", "kN"]),
    (Quantity::Moment, [2, 1, -2], ["N m", "N mm", "kN mm"]),
    (Quantity::Stress, [-1, 1, -2], ["Pa", "MPa", "GPa"]),
    (Quantity::Density, [-3, 1, 0], ["kg/m^3", "t/mm^3", "kg/mm^3"]),
    (Quantity::Mass, [0, 1, 0], ["kg", "t", "kg"]),
    (
        Quantity::MassMomentOfInertia,
        [2, 1, 0],
        ["kg m^2", "t mm^2", "kg mm^2"],
    ),
    (Quantity::Stiffness, [0, 1, -2], ["N/m", "N/mm", "kN/mm"]),
    (
        Quantity::RotationalStiffness,
        [2, 1, -2],
        ["N m/rad", "N mm/rad", "kN mm/rad"],
    ),
    (Quantity::Time, [0, 0, 1], ["s", "s", "ms"]),
];

impl UnitSystem {
    /// Every system, in the order of the unit names of [`TABLE`].
    pub const ALL: [UnitSystem; 3] = [UnitSystem::Si, UnitSystem::MmTonneSecond, UnitSystem::MmKgMillisecond];

    /// The names [`UnitSystem::parse`] accepts, for messages.
    pub const NAMES: &'static str = "\"SI\" (or \"m-kg-s\"), \"mm-t-s\", \"mm-kg-ms\"";

    /// The system's name as a study writes it.
    pub fn name(self) -> &'static str {
        match self {
            UnitSystem::Si => "SI",
            UnitSystem::MmTonneSecond => "mm-t-s",
            UnitSystem::MmKgMillisecond => "mm-kg-ms",
        }
    }

    /// The system called `name` (any case): `SI` or `m-kg-s`, `mm-t-s`, `mm-kg-ms`.
    pub fn parse(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "si" | "m-kg-s" => Some(UnitSystem::Si),
            "mm-t-s" => Some(UnitSystem::MmTonneSecond),
            "mm-kg-ms" => Some(UnitSystem::MmKgMillisecond),
            _ => None,
        }
    }

    /// Powers of ten of the system's length, mass and time units in m, kg, s.
    fn base_exponents(self) -> [i32; 3] {
        match self {
            UnitSystem::Si => [0, 0, 0],
            UnitSystem::MmTonneSecond => [-3, 3, 0],
            UnitSystem::MmKgMillisecond => [-3, 0, -3],
        }
    }

    fn column(self) -> usize {
        match self {
            UnitSystem::Si => 0,
            UnitSystem::MmTonneSecond => 1,
            UnitSystem::MmKgMillisecond => 2,
        }
    }

    /// The factor from this system's unit of `q` to SI: the value in SI is the value given
    /// times this. A power of ten, exact up to the rounding of the literal (`1e-3` is not a
    /// binary fraction).
    pub fn to_si(self, q: Quantity) -> f64 {
        let dimension = row(q).1;
        let n: i32 = dimension.iter().zip(self.base_exponents()).map(|(d, b)| d * b).sum();
        // 10^n exact for |n| <= 22; a negative power is one correctly rounded division.
        if n >= 0 {
            10f64.powi(n)
        } else {
            1.0 / 10f64.powi(-n)
        }
    }

    /// The unit of `q` in this system, as a message writes it (`MPa`, `t/mm^3`).
    pub fn unit(self, q: Quantity) -> &'static str {
        row(q).2[self.column()]
    }
}

impl fmt::Display for UnitSystem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

fn row(q: Quantity) -> &'static (Quantity, [i32; 3], [&'static str; 3]) {
    // Every quantity has its row (the unit tests check each).
    TABLE.iter().find(|r| r.0 == q).unwrap_or(&TABLE[0])
}

/// Young's moduli of solids lie above this (soft rubber has about 1 MPa) \[Pa\].
pub const E_SOFTEST: f64 = 1e5;
/// And below this (diamond has about 1.2e12 Pa) \[Pa\].
pub const E_STIFFEST: f64 = 1.5e12;
/// Densities of solids lie above this (air has 1.2 kg/m³) [kg/m³].
pub const RHO_LIGHTEST: f64 = 1.0;
/// And below this (osmium, the densest element, has 22,590 kg/m³) [kg/m³].
pub const RHO_HEAVIEST: f64 = 3e4;

/// A material constant, in SI, that no solid has: most likely given in another unit system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Implausible {
    /// $E$ below [`E_SOFTEST`] (MPa or GPa read as Pa).
    SoftE(f64),
    /// $E$ above [`E_STIFFEST`].
    StiffE(f64),
    /// $\rho$ below [`RHO_LIGHTEST`] (t/mm³ or g/cm³ read as kg/m³).
    LightRho(f64),
    /// $\rho$ above [`RHO_HEAVIEST`].
    HeavyRho(f64),
}

impl Implausible {
    /// The quantity it is about.
    pub fn quantity(self) -> Quantity {
        match self {
            Implausible::SoftE(_) | Implausible::StiffE(_) => Quantity::Stress,
            Implausible::LightRho(_) | Implausible::HeavyRho(_) => Quantity::Density,
        }
    }
}

impl fmt::Display for Implausible {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Implausible::SoftE(E) => write!(f, "E = {E} Pa is softer than any solid"),
            Implausible::StiffE(E) => write!(f, "E = {E} Pa is stiffer than any solid"),
            Implausible::LightRho(rho) => write!(f, "rho = {rho} kg/m^3 is lighter than air"),
            Implausible::HeavyRho(rho) => write!(f, "rho = {rho} kg/m^3 is heavier than any solid"),
        }
    }
}

/// Young's modulus `E` \[Pa\] if no solid has it.
pub fn implausible_E(E: f64) -> Option<Implausible> {
    if E < E_SOFTEST {
        Some(Implausible::SoftE(E))
    } else if E > E_STIFFEST {
        Some(Implausible::StiffE(E))
    } else {
        None
    }
}

/// The density `rho` [kg/m³] if no solid has it (zero is no mass, not a unit mistake).
pub fn implausible_rho(rho: f64) -> Option<Implausible> {
    if rho > 0.0 && rho < RHO_LIGHTEST {
        Some(Implausible::LightRho(rho))
    } else if rho > RHO_HEAVIEST {
        Some(Implausible::HeavyRho(rho))
    } else {
        None
    }
}

/// The unit system in which a material's constants, given as `E` and `rho` in `declared`
/// units, are those of a solid; `None` if none or several are.
pub fn likely_system(E: f64, rho: f64, declared: UnitSystem) -> Option<UnitSystem> {
    let plausible = |s: UnitSystem| {
        let E_si = E * declared.to_si(Quantity::Stress).recip() * s.to_si(Quantity::Stress);
        let rho_si = rho * declared.to_si(Quantity::Density).recip() * s.to_si(Quantity::Density);
        implausible_E(E_si).is_none() && (rho == 0.0 || implausible_rho(rho_si).is_none())
    };
    let mut fits = UnitSystem::ALL.into_iter().filter(|&s| plausible(s));
    match (fits.next(), fits.next()) {
        (Some(s), None) => Some(s),
        _ => None,
    }
}

/// One sentence on a material read from a deck whose constants (`E`, `rho`, converted to SI
/// from `declared` units) no solid has, or `None` if they are plausible: what is wrong, and
/// the unit system the deck's numbers fit. `name` is the material as the deck names it,
/// `place` where it is defined (`deck.inp:12`).
pub fn deck_material_warning(name: &str, place: &str, E: f64, rho: f64, declared: UnitSystem) -> Option<String> {
    let findings: Vec<String> = [implausible_E(E), implausible_rho(rho)]
        .into_iter()
        .flatten()
        .map(|i| {
            let q = i.quantity();
            let given = match q {
                Quantity::Stress => E,
                _ => rho,
            } / declared.to_si(q);
            match declared {
                UnitSystem::Si => i.to_string(),
                _ => format!("{} {} = {i}", given, declared.unit(q)),
            }
        })
        .collect();
    if findings.is_empty() {
        return None;
    }
    let E_given = E / declared.to_si(Quantity::Stress);
    let rho_given = rho / declared.to_si(Quantity::Density);
    let hint = match likely_system(E, rho, declared) {
        Some(s) => format!(
            "; the deck's numbers (E = {E_given} {}, rho = {rho_given} {}) look like {s} units: declare `units = \"{s}\"` in the part's [parts.mesh]",
            s.unit(Quantity::Stress),
            s.unit(Quantity::Density),
        ),
        None => format!("; the part reads the deck in {declared} units (`units` in [parts.mesh]: {})", UnitSystem::NAMES),
    };
    Some(format!("material {name} ({place}): {}{hint}", findings.join(" and ")))
}
