//! F1: sway buckling of a fixed-base portal frame.
//!
//! Two columns of height $h$ clamped at their bases and a beam of span $l = h$ rigidly joined
//! to their tops, one section and material throughout (in-plane bending stiffness $EI$; ten
//! times stiffer out of the plane, so that the frame buckles in its plane), a vertical force
//! $P$ on each column top. For inextensible members the sway mode has
//! $$\frac{x}{\tan x} = -6\,\frac{I_b/l}{I_c/h},\qquad x = h\sqrt{P/EI},$$
//! the published characteristic equation of the fixed-base portal frame (Timoshenko & Gere,
//! *Theory of Elastic Stability*, 2nd ed., 1961, §2.8; the sway equation of the effective-length
//! alignment chart with $G_A = 0$, $G_B = (I_c/h)/(I_b/l)$). With equal members its root is
//! $x = 2.7165$: $P_{cr} = 7.379\,EI/h^2$ per column (effective length $1.157h$; the chart
//! reads 1.16). The model: each member as $N$ Euler-Bernoulli beam superelements (two elements,
//! static modes only), linearised buckling (`mbs::buckling`) about the equilibrium under a
//! tenth of that load.

use crate::models::{add_segment, beam_segment, x_onto, BeamSegment, BeamSpec, BuildError, StraightBeam, Variant};
use crate::{Block, Extent, Grid, Row, Table};
use fe_model::{BeamSection, BeamTheory};
use mbs::{buckling, solve_static, Model, NodeId, StaticSettings, Support, System};
use nalgebra::{Isometry3, Translation3, Vector3};
use reduction::ModeSelection;
use std::error::Error;

type Result<T> = std::result::Result<T, Box<dyn Error>>;

const H: f64 = 1.0;
const E: f64 = 2.1e11;
/// In-plane second moment of area: a 20 mm square.
const I: f64 = 0.02 * 0.02 * 0.02 * 0.02 / 12.0;

/// The root of $x/\tan x = -6$ in $(\pi/2, \pi)$ by bisection on $x\cos x + 6\sin x$.
pub fn sway_root() -> f64 {
    let f = |x: f64| x * x.cos() + 6.0 * x.sin();
    let (mut a, mut b) = (std::f64::consts::FRAC_PI_2, std::f64::consts::PI);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(a) * f(m) <= 0.0 {
            b = m;
        } else {
            a = m;
        }
    }
    0.5 * (a + b)
}

/// $P_{cr}$ per column (N).
pub fn p_critical() -> f64 {
    sway_root().powi(2) * E * I / (H * H)
}

/// The portal frame with `n` superelements per member, clamped at both bases, a downward
/// force `p` on each column top. Returns the model.
pub fn portal_frame(n: usize, p: f64) -> std::result::Result<Model, BuildError> {
    let spec = BeamSpec {
        E,
        nu: 0.3,
        rho: 7850.0,
        // Local y is the frame's normal (orientation z): Iy is the in-plane stiffness.
        section: BeamSection::from_values("portal", 4e-4, I, 10.0 * I, 20.0 * I, 5.0 / 6.0, 5.0 / 6.0).map_err(
            |source| BuildError::Property {
                model: "portal".into(),
                source,
            },
        )?,
        theory: BeamTheory::EulerBernoulli,
    };
    let mut m = Model::new("portal frame");
    let corners = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(0.0, H, 0.0),
        Vector3::new(H, H, 0.0),
        Vector3::new(H, 0.0, 0.0),
    ];
    // Nodes along the three members, corners shared.
    let mut nodes: Vec<NodeId> = vec![m.add_node("base left", corners[0])];
    for k in 0..3 {
        let (a, b) = (corners[k], corners[k + 1]);
        for i in 1..=n {
            nodes.push(m.add_node(&format!("m{k}.{i}"), a + (b - a) * (i as f64 / n as f64)));
        }
    }
    let seg = H / n as f64;
    for k in 0..3 {
        let e = (corners[k + 1] - corners[k]).normalize();
        let q = x_onto(e);
        let name = format!("member{k}");
        let segment = beam_segment(&BeamSegment {
            frame: Variant::REFERENCE.frame,
            ..BeamSegment::new(
                StraightBeam {
                    name: &name,
                    spec: &spec,
                    ends: (Vector3::zeros(), Vector3::new(seg, 0.0, 0.0)),
                    elements: 2,
                    orientation: q.inverse() * Vector3::z(),
                },
                ModeSelection::StaticOnly,
            )
        })?;
        for i in 0..n {
            let at = k * n + i;
            let placement = Isometry3::from_parts(Translation3::from(corners[k] + e * (seg * i as f64)), q);
            add_segment(
                &mut m,
                &segment,
                &format!("member{k}.seg{i}"),
                [nodes[at], nodes[at + 1]],
                placement,
                Variant::REFERENCE,
            );
        }
    }
    m.add_support(Support::clamp(nodes[0]));
    m.add_support(Support::clamp(nodes[3 * n]));
    for top in [nodes[n], nodes[2 * n]] {
        m.add_dead_force(top, Vector3::new(0.0, -p, 0.0));
    }
    Ok(m)
}

/// The lowest critical load per column of the frame with `n` superelements per member, and
/// the next load factor (for the report).
pub fn frame_critical_load(n: usize) -> Result<(f64, f64)> {
    let p = 0.1 * p_critical();
    let model = portal_frame(n, p)?;
    let sys = System::new(&model)?;
    let unloaded = sys.initial_state();
    let sol = solve_static(&sys, unloaded.clone(), &StaticSettings::new(1)).map_err(|e| e.error)?;
    let b = buckling(&sys, &unloaded, &sol.state, 1.0)?;
    let first = *b.load_factors.first().ok_or("no critical load factor")?;
    Ok((first * p, b.load_factors.get(1).copied().unwrap_or(f64::NAN) * p))
}

/// F1 (module docs): the convergence in $N$ and the row of the finest model.
pub fn f1_portal_frame(extent: Extent) -> Result<Vec<Block>> {
    let levels: &[usize] = match extent {
        Extent::Quick => &[4, 8],
        Extent::Full => &[2, 4, 8, 16],
    };
    let pe = p_critical();
    let mut grid = Vec::new();
    let mut last = 0.0;
    for &n in levels {
        let (p1, p2) = frame_critical_load(n)?;
        grid.push(vec![
            n.to_string(),
            format!("{p1:.2}"),
            format!("{:+.3e}", (p1 - pe) / pe),
            format!("{p2:.2}"),
        ]);
        last = p1;
    }
    let n = *levels.last().unwrap_or(&1);
    Ok(vec![
        Block::Heading("F1 Sway buckling of a fixed-base portal frame".into()),
        Block::Text(format!(
            "Columns and beam of 1 m, steel 20 mm square in the plane (ten times stiffer out of it), \
             both bases clamped, a vertical force on each column top. Reference: the published \
             characteristic equation of the fixed-base portal frame, x/tan x = -6 with x = h (P/EI)^(1/2) \
             (Timoshenko & Gere 1961, §2.8; alignment chart, sway frame), P_cr = {:.4} EI/h^2 = {pe:.2} N \
             per column. Each member is N beam superelements with static modes only; linearised \
             buckling about the equilibrium under a tenth of P_cr.",
            sway_root().powi(2)
        )),
        Block::Grid(Grid {
            title: "F1 convergence in the superelements per member".into(),
            note: "A superelement carries its axial force through the rotation of its frame (a chord), \
                   so the chain converges like co-rotational beams, O(1/N^2), from above. The second \
                   load factor is the symmetric (non-sway) mode."
                .into(),
            header: vec![
                "N per member".into(),
                "P_cr [N]".into(),
                "error".into(),
                "second [N]".into(),
            ],
            rows: grid,
        }),
        Block::Table(Table {
            title: format!("F1 portal frame, N = {n} per member"),
            note: format!(
                "Tolerance {}: the chord error of N = {n} (measured in the convergence table), \
                 above the model's 1e-4 from axial shortening, which the reference neglects.",
                if n >= 16 { "0.5 %" } else { "1 %" }
            ),
            rows: vec![Row::new(
                "critical load per column [N]",
                pe,
                last,
                if n >= 16 { 5e-3 } else { 1e-2 },
            )],
        }),
    ])
}
