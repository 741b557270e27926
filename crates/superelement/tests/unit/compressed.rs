//! The compressed geometric stiffness (`superelement::compressed`): what a straight beam along
//! a body axis stores, that the entries dropped as round-off are far below the threshold and the
//! smallest entries kept far above it, and that the compressed evaluation equals the dense one
//! and matches central differences.

use faer::Mat;
use nalgebra::{Point3, Vector3};
use reduction::{CbSettings, ModeSelection, ReducedBody};
use superelement::compressed::{clean, coordinate_weights, ROUND_OFF};
use superelement::testing::{compression, fixtures, test_state, without_compression, StateSpec};
use superelement::{Damping, Evaluation, FrameChoice, MassVariant, Superelement};

fn beam(end: Point3<f64>, elements: usize, modes: usize) -> ReducedBody {
    let settings = CbSettings {
        geometric_stiffening: true,
        ..CbSettings::new(ModeSelection::Count(modes))
    };
    fixtures::straight_beam_with(Point3::origin(), end, elements, settings, false).2
}

/// The C2 rod segment of the step benchmark: 0.15 m along x, 4 elements, 2 modes.
fn rod_segment() -> ReducedBody {
    beam(Point3::new(0.15, 0.0, 0.0), 4, 2)
}

fn se(body: &ReducedBody, mass: MassVariant) -> Superelement {
    Superelement::new(body, FrameChoice::CenterOfMass, mass, Damping::rayleigh(0.2, 1e-4)).unwrap()
}

/// The largest weighted entry (module docs of `superelement::compressed`) of `group` relative
/// to the group's largest that is below `limit`, and the smallest at or above it.
fn gap(group: &[Mat<f64>], weight: impl Fn(usize, usize, usize) -> f64, limit: f64) -> (f64, f64) {
    let size = |k: usize, i: usize, j: usize| weight(k, i, j) * group[k][(i, j)].abs();
    let n = group[0].nrows();
    let all = || (0..group.len()).flat_map(move |k| (0..n).flat_map(move |j| (0..n).map(move |i| (k, i, j))));
    let big = all().map(|(k, i, j)| size(k, i, j)).fold(0.0, f64::max);
    let (mut below, mut above) = (0.0_f64, f64::INFINITY);
    for (k, i, j) in all() {
        let r = size(k, i, j) / big;
        if r < limit {
            below = below.max(r);
        } else {
            above = above.min(r);
        }
    }
    (below, above)
}

/// The threshold lies in a wide gap: on straight beams along an axis and skew, short and
/// long, with 2 to 10 modes, what `clean` drops is at least 10x below `ROUND_OFF` (round-off of
/// the reduction) and the smallest entry it keeps at least 100x above it (a real coupling).
#[test]
fn round_off_zeros_are_far_below_the_threshold_and_real_entries_far_above() {
    for end in [
        Point3::new(0.15, 0.0, 0.0),
        Point3::new(0.0, 3.0, 0.0),
        Point3::new(1.0, 0.2, 0.1),
    ] {
        for modes in [2, 4, 10] {
            let body = beam(end, 8, modes);
            let c = coordinate_weights(&body);
            let mut G: Vec<Mat<f64>> = body
                .geometric_stiffness
                .as_ref()
                .unwrap()
                .iter()
                .map(|d| d.to_faer())
                .collect();
            check(&format!("G {end:?} {modes} modes"), &mut G, |k, i, j| {
                c[i] * c[j] * c[k]
            });
        }
    }
}

fn check(what: &str, group: &mut [Mat<f64>], weight: impl Fn(usize, usize, usize) -> f64 + Copy) {
    let (below, above) = gap(group, weight, ROUND_OFF);
    let dropped = clean(&mut group.iter_mut().collect::<Vec<_>>(), weight);
    assert_eq!(dropped, below, "{what}");
    assert!(below < ROUND_OFF / 10.0, "{what}: dropped {below:e}");
    assert!(above > 100.0 * ROUND_OFF, "{what}: kept {above:e}");
}

/// The rod segment along x stores two nonzero G_k (the axial constraint modes of its two ends;
/// bending, torsion, shear and the bending modes carry no axial force), about 100 of the n^3 =
/// 2744 entries. A skew beam has six (the end translations); a solid block has no zero G_k and
/// keeps the dense path.
#[test]
fn a_straight_beam_stores_its_geometric_stiffness_compressed() {
    let c = compression(&se(&rod_segment(), MassVariant::Exact));
    assert_eq!(c.geometric, Some(true), "{c:?}");
    // Coordinates: [u_1, theta_1, u_2, theta_2, eta]; u_x of the ends are 0 and 6.
    assert_eq!(c.nonzero_G, vec![0, 6]);
    assert!(c.stored * 20 < 14 * 14 * 14, "{c:?}");
    let skew = compression(&se(&beam(Point3::new(1.0, 0.2, 0.1), 4, 2), MassVariant::Exact));
    assert_eq!(skew.nonzero_G, vec![0, 1, 2, 6, 7, 8], "{skew:?}");
    let settings = CbSettings {
        geometric_stiffening: true,
        ..CbSettings::new(ModeSelection::Count(2))
    };
    let block = fixtures::solid_block_with(settings).2;
    assert_eq!(compression(&se(&block, MassVariant::Exact)).geometric, Some(false));
}

/// The compressed evaluation equals the dense one on a deformed, rotated, moving state with
/// gravity and damping, both inertia variants, with and without tangents. Tolerance: the two
/// differ only in the order of the additions (at most n = 14 terms a sum, each below the
/// matrix's largest entry), so 1e-12 of the largest entry of each output, 50x n epsilon.
#[test]
fn the_compressed_evaluation_equals_the_dense_one() {
    let body = rod_segment();
    for mass in [MassVariant::Exact, MassVariant::Lumped] {
        let fast = se(&body, mass);
        let dense = without_compression(&fast);
        assert_eq!(compression(&dense).geometric, Some(false));
        for (i, angle) in [30.0, 120.0].iter().enumerate() {
            let (state, acc) = test_state(&fast, &StateSpec::moving(*angle, 5 + i as u64));
            let g = Vector3::new(0.0, -9.81, 2.0);
            let a = fast.evaluate(&state, &acc, &g).unwrap();
            let b = dense.evaluate(&state, &acc, &g).unwrap();
            let close = |what: &str, x: &[f64], y: &[f64]| {
                let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                let diff = x.iter().zip(y).fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()));
                assert!(
                    diff <= 1e-12 * scale,
                    "{mass:?} {angle}: {what} differs by {diff:e} (scale {scale:e})"
                );
            };
            let flat = |e: &Evaluation| {
                [&e.mass, &e.stiffness, &e.damping].map(|m| {
                    m.col_iter()
                        .flat_map(|c| c.iter().copied().collect::<Vec<_>>())
                        .collect::<Vec<f64>>()
                })
            };
            close("residual", &a.residual, &b.residual);
            let (fa, fb) = (
                fast.forces(&state, &acc, &g).unwrap(),
                dense.forces(&state, &acc, &g).unwrap(),
            );
            close("residual, forces only", &fa.residual, &fb.residual);
            close("elastic force", &a.f_elastic, &b.f_elastic);
            close("inertia force", &a.f_inertia, &b.f_inertia);
            let (fa, fb) = (flat(&a), flat(&b));
            for (k, what) in ["M", "K_t", "C_t"].iter().enumerate() {
                close(what, &fa[k], &fb[k]);
            }
            let (kin_a, kin_b) = (fast.kinematics(&state).unwrap(), dense.kinematics(&state).unwrap());
            let (ua, ub) = (fast.strain_energy(&kin_a), dense.strain_energy(&kin_b));
            assert!(
                (ua - ub).abs() <= 1e-12 * ub.abs(),
                "{mass:?} {angle}: energy {ua} against {ub}"
            );
        }
    }
}

/// K_t, C_t and M of the compressed rod segment against central differences (the helper and
/// tolerance of `fd_tangent.rs`): the compressed path is checked on its own, not only through
/// its equality with the dense one.
#[test]
fn compressed_tangents_match_fd() {
    let body = rod_segment();
    for mass in [MassVariant::Exact, MassVariant::Lumped] {
        let s = se(&body, mass);
        for (i, angle) in [30.0, 170.0].iter().enumerate() {
            let (state, acc) = test_state(&s, &StateSpec::moving(*angle, 9 + i as u64));
            super::fd_tangent::check_tangents(
                &s,
                &state,
                &acc,
                &Vector3::new(0.0, -9.81, 2.0),
                &format!("rod segment {mass:?} {angle} deg"),
            );
        }
    }
}
