//! Unit systems of decks: the conversion factor of every quantity, and the mm-t-s twins of
//! the hex20 fixtures read with and without `units`.

use fe_model::mass_properties::center_of_mass;
use fe_model::mesh::import::ImportedModel;
use fe_model::mesh::{abaqus, nastran};
use fe_model::units::{deck_material_warning, implausible_E, implausible_rho, likely_system, Quantity, UnitSystem};
use fe_model::{add_interface, modal_dense, DofMask, FeModel, MassKind, SpiderKind};
use std::path::{Path, PathBuf};

fn fixture(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/import")
        .join(file)
}

/// The factor from each system's unit to SI, for every quantity, written out by hand.
#[test]
fn every_quantity_converts_by_its_own_factor() {
    use Quantity::*;
    let mm_t_s = UnitSystem::MmTonneSecond;
    let mm_kg_ms = UnitSystem::MmKgMillisecond;
    let cases = [
        // quantity, mm-t-s factor and unit, mm-kg-ms factor and unit
        (Length, 1e-3, "mm", 1e-3, "mm"),
        (Area, 1e-6, "mm^2", 1e-6, "mm^2"),
        (SecondMomentOfArea, 1e-12, "mm^4", 1e-12, "mm^4"),
        // N = t mm/s^2 = 1e3 kg 1e-3 m/s^2; kN = kg mm/ms^2 = 1e-3 / 1e-6 N.
        (Force, 1.0, "N", 1e3, "kN"),
        (Moment, 1e-3, "N mm", 1.0, "kN mm"),
        // MPa = N/mm^2; GPa = kN/mm^2.
        (Stress, 1e6, "MPa", 1e9, "GPa"),
        // t/mm^3 = 1e3 kg / 1e-9 m^3; kg/mm^3 = 1 kg / 1e-9 m^3.
        (Density, 1e12, "t/mm^3", 1e9, "kg/mm^3"),
        (Mass, 1e3, "t", 1.0, "kg"),
        (MassMomentOfInertia, 1e-3, "t mm^2", 1e-6, "kg mm^2"),
        // N/mm = 1e3 N/m; kN/mm = 1e6 N/m.
        (Stiffness, 1e3, "N/mm", 1e6, "kN/mm"),
        (RotationalStiffness, 1e-3, "N mm/rad", 1.0, "kN mm/rad"),
        (Time, 1.0, "s", 1e-3, "ms"),
    ];
    assert_eq!(cases.len(), fe_model::units::TABLE.len(), "a case per row of the table");
    for (q, f1, u1, f2, u2) in cases {
        assert_eq!(UnitSystem::Si.to_si(q), 1.0, "{q:?}");
        assert_eq!(mm_t_s.to_si(q), f1, "{q:?} in mm-t-s");
        assert_eq!(mm_t_s.unit(q), u1, "{q:?} in mm-t-s");
        assert_eq!(mm_kg_ms.to_si(q), f2, "{q:?} in mm-kg-ms");
        assert_eq!(mm_kg_ms.unit(q), u2, "{q:?} in mm-kg-ms");
    }
}

#[test]
fn names_parse_back() {
    for s in UnitSystem::ALL {
        assert_eq!(UnitSystem::parse(s.name()), Some(s));
    }
    assert_eq!(UnitSystem::parse("m-kg-s"), Some(UnitSystem::Si));
    assert_eq!(UnitSystem::parse("MM-T-S"), Some(UnitSystem::MmTonneSecond));
    assert_eq!(UnitSystem::parse("mm-g-ms"), None);
}

#[test]
fn the_plausibility_check_names_the_system_the_numbers_fit() {
    // Steel, aluminium in each system, read as SI.
    for (E, rho, system) in [
        (2.1e11, 7850.0, UnitSystem::Si),
        (210000.0, 7.85e-9, UnitSystem::MmTonneSecond),
        (70000.0, 2.7e-9, UnitSystem::MmTonneSecond),
        (210.0, 7.85e-6, UnitSystem::MmKgMillisecond),
    ] {
        assert_eq!(likely_system(E, rho, UnitSystem::Si), Some(system), "{E} {rho}");
    }
    // SI numbers read as mm-t-s: E = 2.1e11 MPa, rho = 7850 t/mm^3.
    let (E, rho) = (2.1e11 * 1e6, 7850.0 * 1e12);
    assert_eq!(likely_system(E, rho, UnitSystem::MmTonneSecond), Some(UnitSystem::Si));
    assert!(implausible_E(E).is_some() && implausible_rho(rho).is_some());
    let w = deck_material_warning("STEEL", "a.inp:7", E, rho, UnitSystem::MmTonneSecond).unwrap();
    for part in [
        "material STEEL (a.inp:7)",
        "210000000000 MPa",
        "heavier than any solid",
        "look like SI units",
    ] {
        assert!(w.contains(part), "'{part}' in: {w}");
    }
    assert!(deck_material_warning("steel", "a.inp:7", 2.1e11, 7850.0, UnitSystem::Si).is_none());
    assert!(implausible_rho(0.0).is_none(), "no mass is not a unit mistake");
}

fn clamped_frequencies(imported: &ImportedModel) -> Vec<f64> {
    let mut model: FeModel = imported.to_fe_model(MassKind::Consistent, None).unwrap();
    for s in &imported.supports {
        for &n in &s.nodes {
            model.add_support(n, s.dofs);
        }
    }
    if let Some(clamp) = imported.mesh.node_sets.get("clamp") {
        for &n in clamp {
            model.add_support(n, DofMask::TRANSLATIONS);
        }
    }
    for s in &imported.spiders {
        add_interface(&mut model, &s.name, &s.surface, Some(s.position), s.kind).unwrap();
    }
    if imported.spiders.is_empty() {
        let tip = imported.mesh.node_sets["tip"].clone();
        let c = imported.mesh.nodes[tip[0].index()];
        add_interface(&mut model, "tip", &tip, Some(c), SpiderKind::Rbe2).unwrap();
    }
    modal_dense(&model, 8).unwrap().omega
}

/// The same model from its SI deck and its mm-t-s twin: geometry, mass and frequencies.
fn assert_twins(si: &ImportedModel, mm: &ImportedModel, what: &str) {
    let relative = |a: f64, b: f64| ((a - b) / a).abs();
    for (p, q) in si.mesh.nodes.iter().zip(&mm.mesh.nodes) {
        assert!((p - q).norm() <= 1e-15, "{what}: node at {p} and {q}");
    }
    let (m_si, c_si) = center_of_mass(&si.to_fe_model(MassKind::Consistent, None).unwrap()).unwrap();
    let (m_mm, c_mm) = center_of_mass(&mm.to_fe_model(MassKind::Consistent, None).unwrap()).unwrap();
    assert!(
        relative(m_si, m_mm) < 1e-12 && (c_si - c_mm).norm() < 1e-12,
        "{what}: mass {m_si} {m_mm}"
    );
    let (f_si, f_mm) = (clamped_frequencies(si), clamped_frequencies(mm));
    for (a, b) in f_si.iter().zip(&f_mm) {
        assert!(relative(*a, *b) < 1e-10, "{what}: {f_si:?} and {f_mm:?}");
    }
    assert!(mm.notes.is_empty(), "{what}: {:?}", mm.notes);
}

#[test]
fn an_abaqus_deck_in_mm_t_s_read_with_its_units_is_its_si_twin() {
    let si = abaqus::read(&fixture("hex20.inp"), UnitSystem::Si).unwrap();
    let mm = abaqus::read(&fixture("hex20_mm.inp"), UnitSystem::MmTonneSecond).unwrap();
    assert_twins(&si, &mm, "Abaqus");
    // Read as SI, the deck is 1000 times too light and a warning names the material, the
    // place and the system its numbers fit.
    let wrong = abaqus::read(&fixture("hex20_mm.inp"), UnitSystem::Si).unwrap();
    let (m, _) = center_of_mass(&wrong.to_fe_model(MassKind::Consistent, None).unwrap()).unwrap();
    assert!((m - 0.314).abs() < 1e-9, "{m}");
    let [warning] = wrong.notes.as_slice() else {
        panic!("{:?}", wrong.notes)
    };
    for part in [
        "material steel (",
        "hex20_mm.inp:73)",
        "rho = 0.00000000785 kg/m^3 is lighter than air",
        "look like mm-t-s units",
        "units = \"mm-t-s\"",
    ] {
        assert!(warning.contains(part), "'{part}' in: {warning}");
    }
}

#[test]
fn a_nastran_deck_in_mm_t_s_read_with_its_units_is_its_si_twin() {
    let si = nastran::read(&fixture("hex20.bdf"), UnitSystem::Si).unwrap();
    let mm = nastran::read(&fixture("hex20_mm.bdf"), UnitSystem::MmTonneSecond).unwrap();
    assert_twins(&si, &mm, "Nastran");
    assert!((si.spiders[0].position - mm.spiders[0].position).norm() < 1e-15);
    let wrong = nastran::read(&fixture("hex20_mm.bdf"), UnitSystem::Si).unwrap();
    let warning = wrong.notes.iter().find(|n| n.contains("MAT1_1")).expect("a warning");
    for part in [
        "material MAT1_1 (",
        "hex20_mm.bdf:71)",
        "lighter than air",
        "look like mm-t-s units",
    ] {
        assert!(warning.contains(part), "'{part}' in: {warning}");
    }
}
