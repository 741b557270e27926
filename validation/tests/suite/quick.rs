//! The quick subset of the validation suite, run by `cargo test`: each benchmark at its
//! `Extent::Quick` levels, every row within the tolerance its table states. The tolerances
//! and their reasons are in the benchmark functions (and repeated in each table's note);
//! the comment on each test names them.

use validation::benchmarks::{dynamics, frame_buckling, linear, nonlinear_statics, transient};
use validation::{failures, Block, Extent};

fn assert_within(blocks: &[Block]) {
    let f = failures(blocks);
    assert!(f.is_empty(), "{}", f.join("\n"));
    assert!(validation::tables(blocks).count() > 0, "no table to check");
}

/// A1 within 0.1 % from 16 elements on (cubic elements converge as h^4; 16 elements give
/// 1e-5 on the first four clamped-free frequencies).
#[test]
fn a1_beam_frequencies() {
    let mut blocks: Vec<Block> = linear::a1_cantilever_frequencies(Extent::Quick)
        .unwrap()
        .into_iter()
        .map(Block::Table)
        .collect();
    blocks.push(Block::Table(
        linear::a1_timoshenko_pinned_pinned(Extent::Quick).unwrap(),
    ));
    assert_within(&blocks);
}

/// A2 to round-off (the cubic beam is exact for end loads) and A3 (CB converges from above,
/// statics exact with static modes).
#[test]
fn a2_a3_statics_and_craig_bampton() {
    assert_within(&[
        Block::Table(linear::a2_cantilever_statics().unwrap()),
        Block::Table(linear::a3_craig_bampton_convergence(Extent::Quick).unwrap()),
    ]);
}

/// A4 (NAFEMS FV32) within 0.5 %: the quick mesh's discretisation error (0.13 % measured).
#[test]
fn a4_fv32() {
    assert_within(&[Block::Table(linear::a4_fv32(Extent::Quick).unwrap())]);
}

/// A5: history within 1 % of the static deflection and the peak within 1 % of the exact
/// modal series (modal truncation of the reduced model and the O(h^2) period error).
#[test]
fn a5_linear_transient() {
    assert_within(&transient::a5_linear_transient(Extent::Quick).unwrap());
}

/// B1 at N = 16: w/L, u/L and the tip rotation within 1e-3 relative (the 1/N^2 chord error
/// of N = 16 is below it; the table's five digits are 2e-5).
#[test]
fn b1_elastica() {
    assert_within(&nonlinear_statics::b1_elastica(Extent::Quick).unwrap());
}

/// B2 at N = 16: the arc within 1e-3 L, and the closed circle at 2 pi to round-off (1e-9).
#[test]
fn b2_roll_up() {
    assert_within(&nonlinear_statics::b2_roll_up(Extent::Quick).unwrap());
}

/// B3 with 8 superelements: each tip coordinate within 1 % (published solutions scatter by
/// 0.5 %).
#[test]
fn b3_bend() {
    assert_within(&nonlinear_statics::b3_bend(Extent::Quick).unwrap());
}

/// C1 bounded: the peak tip deflection below the quasi-static bound (+10 %) and dying out after
/// the spin-up, for 4, 6 and 10 rad/s (coarse model:
/// 2 superelements, h = 10 ms; the refinement study is in the release suite).
#[test]
fn c1_spin_up_bounded() {
    assert_within(&dynamics::c1_spin_up(Extent::Quick).unwrap());
}

/// C4: linear and angular momentum constant to 1e-12 (round-off) with the momentum projection,
/// for every frame choice and inertia variant; energy drift below 1e-3 falling at order 2.
#[test]
fn c4_free_body() {
    assert_within(&dynamics::c4_free_body(Extent::Quick).unwrap());
}

/// S1: the reduced body's stress history (20 modes) within 2 % of the full FE transient's
/// peak (the truncated modes; measured 0.5 % on the peak, 1.5 % over the history).
#[test]
fn s1_transient_stress() {
    assert_within(&validation::benchmarks::stress::s1_transient_stress(Extent::Quick).unwrap());
}

/// F1 at N = 8 superelements per member: the critical load of the portal frame within 1 % of
/// the published characteristic equation (the O(1/N^2) chord error of N = 4 is 2.9 %, so
/// about 0.7 % at N = 8).
#[test]
fn f1_portal_frame_buckling() {
    assert_within(&frame_buckling::f1_portal_frame(Extent::Quick).unwrap());
}
