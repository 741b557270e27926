//! Stress recovery: solid stresses at the integration points, extrapolated to the nodes and
//! averaged there; beam section forces and extreme-fibre stresses.
//!
//! # Solids
//!
//! At each point $q$ of the element's stiffness rule the linear stress is
//! $\boldsymbol\sigma_q = \mathbf D\mathbf B_q\mathbf u_e$ ([`super::element::solid::linear_stress`]),
//! the points where the displacement-based stress is most accurate (Barlow points for the
//! hexahedra; Zienkiewicz, Taylor & Zhu, 7th ed., §6.6 and ch. 14). They are carried to the
//! element's nodes by a least-squares fit with the shape functions of the element's linear
//! parent, evaluated at the nodes' reference coordinates (Hinton & Campbell, "Local and global
//! smoothing of discontinuous finite element functions using a least squares method", IJNME 8
//! (1974) 461-480; Cook, Malkus, Plesha & Witt, 4th ed., §7.4):
//! $$\boldsymbol\sigma_a = \sum_q E_{aq}\boldsymbol\sigma_q,\qquad
//! \mathbf E = \mathbf P(\boldsymbol\xi_{nodes})\,(\mathbf P_q^T\mathbf P_q)^{-1}\mathbf P_q^T,$$
//! $\mathbf P_q$ the fit basis at the integration points ($n_q \times n_f$).
//!
//! | kind | stiffness rule | fit basis | extrapolation |
//! |---|---|---|---|
//! | tet4 | 1 point | constant | the element's one stress at its 4 nodes |
//! | tet10 | 4 points | tet4 (linear) | interpolation; mid-edge nodes get the mean of their corners |
//! | hex8 | 2x2x2 Gauss | hex8 (trilinear) | interpolation (the classic $\sqrt3$ extrapolation) |
//! | hex20 | 3x3x3 Gauss | hex8 (trilinear) | least squares over 27 points |
//! | wedge6 | 3 x 2 points | wedge6 | interpolation |
//!
//! Every basis holds the constants, so a uniform stress is carried to the nodes exactly (the
//! patch test, `tests/unit/stress.rs`).
//!
//! **Averaging at the nodes.** A node's stress is the plain (unweighted) mean of the
//! extrapolated values of every solid element that contains it, over all materials: the
//! "averaged nodal stress" of commercial post-processors. Nodes that no solid element
//! contains get none. At a material interface or a re-entrant corner the mean smooths a real
//! jump; the extrapolated element values ([`solid_nodal_stresses`]) keep it.
//!
//! # Beams
//!
//! Section forces $[N, V_y, V_z, T, M_y, M_z]$ in the element's local axes (module
//! [`crate::element::beam2`]) at both ends, as the internal force and moment on the cut face
//! whose outward normal is $+\mathbf e_x$: $\mathbf s(0) = -\mathbf f_1$, $\mathbf s(L) =
//! \mathbf f_2$ with $\mathbf f = \mathbf K_e^{loc}\mathbf u^{loc} - \mathbf f_{load}^{loc}$ the
//! element's end forces (minus the equivalent nodal loads of a load along the element, when
//! given; with them, a cantilever under uniform load gets the exact moments). The axial fibre
//! stress is $\sigma_x(y, z) = N/A + M_y z/I_y - M_z y/I_z$
//! ([`crate::section::BeamSection::fibre_stress_range`]).
//!
//! # Notation
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\boldsymbol\sigma$ | `[f64; 6]` | stress in Voigt order $[xx, yy, zz, xy, yz, zx]$ (tensor components, not engineering strains) |
//! | $\mathbf E$ | `extrapolation` | integration points to nodes ($n \times n_q$) |
//! | $\sigma_{vM}$ | [`von_mises`] | $\sqrt{\tfrac12[(\sigma_1-\sigma_2)^2 + (\sigma_2-\sigma_3)^2 + (\sigma_3-\sigma_1)^2]}$ |
//! | $\sigma_1 \ge \sigma_2 \ge \sigma_3$ | [`principal_stresses`] | eigenvalues of $\boldsymbol\sigma$ |

#![allow(non_snake_case)]

use crate::assembly::element_coordinates;
use crate::element::solid::{displacement_gradient, linear_stress, point_values};
use crate::element::{beam2, hex8, tet4, wedge6, Element, SolidKind};
use crate::error::{ElementError, FeError};
use crate::model::FeModel;
use crate::property::IsotropicMaterial;
use nalgebra::{DMatrix, Matrix3, Point3};
use rayon::prelude::*;
use std::sync::OnceLock;

/// A stress tensor in Voigt order $[xx, yy, zz, xy, yz, zx]$.
pub type Voigt = [f64; 6];

/// The symmetric tensor of a Voigt vector.
pub fn tensor(s: &Voigt) -> Matrix3<f64> {
    Matrix3::new(s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2])
}

/// Von Mises equivalent stress
/// $\sqrt{\tfrac12[(\sigma_{xx}-\sigma_{yy})^2 + (\sigma_{yy}-\sigma_{zz})^2 + (\sigma_{zz}-\sigma_{xx})^2]
/// + 3(\sigma_{xy}^2 + \sigma_{yz}^2 + \sigma_{zx}^2)}$.
pub fn von_mises(s: &Voigt) -> f64 {
    let d = (s[0] - s[1]).powi(2) + (s[1] - s[2]).powi(2) + (s[2] - s[0]).powi(2);
    (0.5 * d + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5])).sqrt()
}

/// Principal stresses, largest first: the eigenvalues of the symmetric tensor in closed form
/// (the trigonometric solution of the characteristic cubic \[Smith1961\]; theory guide,
/// results, (10.2)),
/// $\sigma_k = \bar\sigma + 2p\cos\left(\tfrac13\arccos\tfrac{\det\mathbf B}{2} +
/// \tfrac{2\pi j_k}{3}\right)$ with the mean stress $\bar\sigma = \operatorname{tr}\boldsymbol\sigma/3$,
/// $p = \sqrt{\lVert\boldsymbol\sigma - \bar\sigma\mathbf 1\rVert_F^2/6}$ and
/// $\mathbf B = (\boldsymbol\sigma - \bar\sigma\mathbf 1)/p$. No iteration: the stress output
/// evaluates it at every node of a body at every output time. The largest is exact to the
/// round-off of the largest component; at a double root the other two lose up to the square root
/// of the machine epsilon, relative (the arccos argument is clamped to $[-1, 1]$).
pub fn principal_stresses(s: &Voigt) -> [f64; 3] {
    let off = s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
    if off == 0.0 {
        let mut p = [s[0], s[1], s[2]];
        p.sort_by(|a, b| b.total_cmp(a));
        return p;
    }
    let mean = (s[0] + s[1] + s[2]) / 3.0;
    let d = [s[0] - mean, s[1] - mean, s[2] - mean];
    let p = ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + 2.0 * off) / 6.0).sqrt();
    let b = [d[0] / p, d[1] / p, d[2] / p, s[3] / p, s[4] / p, s[5] / p];
    // det B for B = [[b0, b3, b5], [b3, b1, b4], [b5, b4, b2]].
    let det =
        b[0] * (b[1] * b[2] - b[4] * b[4]) - b[3] * (b[3] * b[2] - b[4] * b[5]) + b[5] * (b[3] * b[4] - b[1] * b[5]);
    let phi = (0.5 * det).clamp(-1.0, 1.0).acos() / 3.0;
    let largest = mean + 2.0 * p * phi.cos();
    let smallest = mean + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    [largest, 3.0 * mean - largest - smallest, smallest]
}

fn to_voigt(S: &Matrix3<f64>) -> Voigt {
    [S[(0, 0)], S[(1, 1)], S[(2, 2)], S[(0, 1)], S[(1, 2)], S[(2, 0)]]
}

/// The fit basis of a kind's extrapolation (module docs): its shape functions at `xi`.
fn fit_basis(kind: SolidKind, xi: &[f64; 3]) -> Vec<f64> {
    let parent = |n: usize, f: fn(&[f64; 3], &mut [f64], &mut [[f64; 3]])| {
        let mut N = vec![0.0; n];
        let mut dN = vec![[0.0; 3]; n];
        f(xi, &mut N, &mut dN);
        N
    };
    match kind {
        SolidKind::Tet4 => vec![1.0],
        SolidKind::Tet10 => parent(4, tet4::shape_functions),
        SolidKind::Hex8 | SolidKind::Hex20 => parent(8, hex8::shape_functions),
        SolidKind::Wedge6 => parent(6, wedge6::shape_functions),
    }
}

fn build_extrapolation(kind: SolidKind) -> DMatrix<f64> {
    let rule = kind.stiffness_rule();
    let rows: Vec<Vec<f64>> = rule.points.iter().map(|xi| fit_basis(kind, xi)).collect();
    let nf = rows[0].len();
    let P_q = DMatrix::from_fn(rows.len(), nf, |q, f| rows[q][f]);
    let nodes = kind.reference_nodes();
    let P_n = DMatrix::from_fn(nodes.len(), nf, |a, f| fit_basis(kind, &nodes[a])[f]);
    // The normal matrix is small (at most 8 x 8) and well conditioned: every rule has at least
    // as many points as the basis has functions, placed inside the element.
    let normal = P_q.transpose() * &P_q;
    let inverse = normal
        .try_inverse()
        .expect("the fit basis is unisolvent on the stiffness rule's points");
    P_n * inverse * P_q.transpose()
}

/// The extrapolation matrix $\mathbf E$ of a kind ($n_{nodes} \times n_q$, module docs).
pub fn extrapolation(kind: SolidKind) -> &'static DMatrix<f64> {
    static CACHE: [OnceLock<DMatrix<f64>>; 5] = [
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
        OnceLock::new(),
    ];
    let k = SolidKind::ALL.iter().position(|&c| c == kind).expect("a listed kind");
    CACHE[k].get_or_init(|| build_extrapolation(kind))
}

/// The element's stresses extrapolated to its nodes (module docs), in its node order,
/// before averaging, for element displacements `u_e` ($[u_x, u_y, u_z]$ node by node): the
/// stresses at the points of the kind's stiffness rule, extrapolated.
///
/// # Errors
/// As [`crate::element::solid::stiffness`] (inverted element, wrong node count).
pub fn solid_nodal_stresses(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    material: &IsotropicMaterial,
    u_e: &[f64],
) -> Result<Vec<Voigt>, ElementError> {
    if X_e.len() != kind.node_count() || u_e.len() != 3 * kind.node_count() {
        return Err(ElementError::WrongNodeCount {
            element,
            kind: kind.name(),
            expected: kind.node_count(),
            got: X_e.len().min(u_e.len() / 3),
        });
    }
    let at_points = kind
        .stiffness_rule()
        .points
        .iter()
        .enumerate()
        .map(|(q, xi)| {
            let p = point_values(kind, element, q, X_e, xi)?;
            Ok(to_voigt(&linear_stress(material, &displacement_gradient(&p.g, u_e))))
        })
        .collect::<Result<Vec<Voigt>, ElementError>>()?;
    let E = extrapolation(kind);
    Ok((0..E.nrows())
        .map(|a| {
            let mut s = [0.0; 6];
            for (q, sq) in at_points.iter().enumerate() {
                for c in 0..6 {
                    s[c] += E[(a, q)] * sq[c];
                }
            }
            s
        })
        .collect())
}

/// The linear map from a solid element's displacements to its extrapolated nodal stresses:
/// $6n \times 3n$, row $6a + c$ is component $c$ of node $a$ (for many displacement fields at
/// once, as the stress shapes of a reduction).
///
/// # Errors
/// As [`solid_nodal_stresses`].
pub fn solid_stress_operator(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    material: &IsotropicMaterial,
) -> Result<DMatrix<f64>, ElementError> {
    let n = kind.node_count();
    let mut S = DMatrix::zeros(6 * n, 3 * n);
    let mut u_e = vec![0.0; 3 * n];
    // Stress is linear in u_e: one unit field per column.
    for j in 0..3 * n {
        u_e.fill(0.0);
        u_e[j] = 1.0;
        for (a, s) in solid_nodal_stresses(kind, element, X_e, material, &u_e)?
            .iter()
            .enumerate()
        {
            for c in 0..6 {
                S[(6 * a + c, j)] = s[c];
            }
        }
    }
    Ok(S)
}

fn solid_material(model: &FeModel, index: usize) -> Result<Option<(SolidKind, &IsotropicMaterial)>, FeError> {
    let Some((kind, solid)) = model.elements[index].solid() else {
        return Ok(None);
    };
    Ok(Some((kind, model.properties().material(index, solid.material)?)))
}

/// Averaged nodal stresses of every solid element's displacement fields at once: `u` holds
/// `fields` columns of the $6 n_{nodes}$ node slots (column-major, slot $6i + k$ is dof $k$ of
/// node $i$); the result holds, per field, $6 n_{nodes}$ Voigt components (column-major,
/// row $6i + c$), zero at nodes that no solid element contains. The second value counts the
/// solid elements at each node (zero: no stress there).
///
/// Elements are processed in parallel, each thread summing into its own copy.
///
/// # Errors
/// An element with bad geometry or a missing material.
pub fn averaged_nodal_stresses(model: &FeModel, u: &[f64], fields: usize) -> Result<(Vec<f64>, Vec<u32>), FeError> {
    let n_nodes = model.node_count();
    let rows = 6 * n_nodes;
    assert_eq!(u.len(), rows * fields, "u holds 6 slots per node per field");
    let mut count = vec![0u32; n_nodes];
    for element in &model.elements {
        if element.solid().is_some() {
            for node in element.nodes() {
                count[node.index()] += 1;
            }
        }
    }
    let sum = (0..model.elements.len())
        .into_par_iter()
        .try_fold(
            || vec![0.0; rows * fields],
            |mut acc, e| -> Result<Vec<f64>, FeError> {
                let Some((kind, material)) = solid_material(model, e)? else {
                    return Ok(acc);
                };
                let X_e = element_coordinates(model, e)?;
                let S = solid_stress_operator(kind, e, &X_e, material)?;
                let nodes = model.elements[e].nodes();
                let n = nodes.len();
                let mut u_e = DMatrix::zeros(3 * n, fields);
                for f in 0..fields {
                    for (a, node) in nodes.iter().enumerate() {
                        for k in 0..3 {
                            u_e[(3 * a + k, f)] = u[f * rows + 6 * node.index() + k];
                        }
                    }
                }
                let s = S * u_e;
                for f in 0..fields {
                    for (a, node) in nodes.iter().enumerate() {
                        for c in 0..6 {
                            acc[f * rows + 6 * node.index() + c] += s[(6 * a + c, f)];
                        }
                    }
                }
                Ok(acc)
            },
        )
        .try_reduce(
            || vec![0.0; rows * fields],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    *x += y;
                }
                Ok(a)
            },
        )?;
    let mut sigma = sum;
    for f in 0..fields {
        for (i, &c) in count.iter().enumerate() {
            if c > 0 {
                for v in &mut sigma[f * rows + 6 * i..f * rows + 6 * i + 6] {
                    *v /= c as f64;
                }
            }
        }
    }
    Ok((sigma, count))
}

/// Averaged nodal stresses of the displacements `u` of every node (a static solution's):
/// `None` at nodes that no solid element contains.
///
/// # Errors
/// As [`averaged_nodal_stresses`].
pub fn nodal_stresses(model: &FeModel, u: &[[f64; 6]]) -> Result<Vec<Option<Voigt>>, FeError> {
    let flat: Vec<f64> = u.iter().flatten().copied().collect();
    let (sigma, count) = averaged_nodal_stresses(model, &flat, 1)?;
    Ok(count
        .iter()
        .enumerate()
        .map(|(i, &c)| (c > 0).then(|| sigma[6 * i..6 * i + 6].try_into().expect("6 components")))
        .collect())
}

/// Section forces of one beam element at its two ends, local axes (module docs):
/// `[end][N, Vy, Vz, T, My, Mz]`, for the element displacements `u_e` (12 values, global
/// axes) and, when the element carries a load along it, its equivalent nodal loads `load_e`
/// (12 values, global axes, e.g. $\mathbf M_e\mathbf g$ for gravity).
///
/// # Errors
/// As [`beam2::beam2_matrices`], and [`FeError::Element`] if element `index` is not a beam.
pub fn beam_section_forces(
    model: &FeModel,
    index: usize,
    u_e: &[f64],
    load_e: Option<&[f64]>,
) -> Result<[[f64; 6]; 2], FeError> {
    let Element::Beam2(beam) = &model.elements[index] else {
        return Err(FeError::Element(ElementError::WrongNodeCount {
            element: index,
            kind: "beam2 (section forces)",
            expected: 2,
            got: model.elements[index].nodes().len(),
        }));
    };
    let X_e = element_coordinates(model, index)?;
    let props = model.properties();
    let section = props.section(index, beam.section)?;
    let material = props.material(index, beam.material)?;
    Ok(beam2::beam2_section_forces(
        beam,
        index,
        [X_e[0], X_e[1]],
        section,
        material,
        u_e,
        load_e,
    )?)
}

/// The extreme-fibre stresses of beams gathered at their nodes: for each node, the largest
/// magnitude and the largest value over every element end at it (`ends`: node index and the
/// end's `[max, min]` fibre stress, [`crate::section::BeamSection::fibre_stress_range`]);
/// `None` at nodes no end names. The equivalent stress of a beam node for plots, shear
/// stresses of the section not included.
pub fn fibre_extremes_at_nodes(
    n_nodes: usize,
    ends: impl IntoIterator<Item = (usize, [f64; 2])>,
) -> Vec<Option<[f64; 2]>> {
    let mut out: Vec<Option<[f64; 2]>> = vec![None; n_nodes];
    for (node, [max, min]) in ends {
        let magnitude = max.abs().max(min.abs());
        let entry = out[node].get_or_insert([magnitude, max]);
        entry[0] = entry[0].max(magnitude);
        entry[1] = entry[1].max(max);
    }
    out
}
