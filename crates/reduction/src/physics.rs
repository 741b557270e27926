//! Physical checks of a [`ReducedBody`]: a file whose checksums are valid can still hold data
//! no reduction produces (an edited matrix, metadata copied from another body). The
//! superelement would use it silently: wrong frequencies, negative strain energy. These
//! checks run on every load ([`crate::io::rbody::read`], [`crate::io::rbody::from_bytes`]) and in
//! `flexmbs inspect`.
//!
//! # What is checked, and why each tolerance is that size
//!
//! With $n = 6N + m$ CB coordinates and $\boldsymbol\Phi_R$ ($n\times 6$) the rigid motions of
//! the interface set about the origin (zero on $\boldsymbol\eta$):
//!
//! - **Finite, symmetric** $\mathbf K_{CB}$ and $\mathbf M_{CB}$: $|A_{ij} - A_{ji}| \le
//!   10^{-8}\sqrt{|A_{ii}A_{jj}|} + 10^{-12}\max|A|$. Both are $\mathbf V^T\mathbf A\mathbf V$ of
//!   a symmetric matrix; the products round at about $10^{-13}$ of the entries' scale.
//! - **Positive modal mass and positive definite** $\mathbf M_{CB}$ (a Cholesky factor
//!   $\mathbf M_{CB} = \mathbf L\mathbf L^T$ exists).
//! - **Positive semi-definite** $\mathbf K_{CB}$ **whose null space is the rigid motions**:
//!   the eigenvalues $\lambda = \omega^2$ of $\mathbf A = \mathbf L^{-1}\mathbf K_{CB}\mathbf L^{-T}$.
//!   A rigid motion $\boldsymbol\Phi_R\mathbf x$ is free when its eigenvalue in the $6\times 6$
//!   problem $\boldsymbol\Phi_R^T\mathbf K\boldsymbol\Phi_R\mathbf x = \mu\,\boldsymbol\Phi_R^T\mathbf M
//!   \boldsymbol\Phi_R\mathbf x$ is below $10^{-8}\lambda_{max}$ (round-off of a rigid motion through
//!   $\mathbf K_{CB}$ is about $10^{-12}\lambda_{max}$; a supported direction costs order one).
//!   A free body has all six; a body supported in its FE model has fewer
//!   ([`crate::DiagnosticWarning::NotFree`]), which is allowed. On the $\mathbf M$-orthogonal
//!   complement of the free rigid motions every eigenvalue must be positive: below
//!   $-10^{-9}\lambda_{max}$ the strain energy is negative (indefinite), within
//!   $10^{-12}\lambda_{max}$ of zero a deformation costs no energy (a mechanism; an elastic
//!   frequency that low, $10^{-6}\omega_{max}$, does not occur in a sound model).
//! - **Metadata against the matrices** (free bodies): $\boldsymbol\Phi_R^T\mathbf M_{CB}\boldsymbol\Phi_R$
//!   is the rigid mass matrix of the FE model exactly (constraint modes reproduce rigid
//!   motion), so mass, centre of mass and inertia about it must match the stored ones to
//!   $10^{-6}$ (of the mass, of the body's size, of the largest inertia): the same quantity
//!   computed two ways agrees to about $10^{-12}$. The fixed-interface modes are $\mathbf K$- and
//!   $\mathbf M$-orthogonal, so $\omega_k^2 = K_{\eta_k\eta_k}/M_{\eta_k\eta_k}$ to $10^{-6}$.
//! - **Interfaces**: distinct names, distinct FE nodes, and no two closer than $10^{-9}$ of the
//!   body's size (two coincident interfaces make the frame equations (theory guide (4.4)) singular).

#![allow(non_snake_case)]

use crate::reduced_body::ReducedBody;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// One physical inconsistency of a reduced body (module docs), with the message that names it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PhysicsProblem {
    /// An entry of `matrix` (`K_CB` or `M_CB`) is not finite.
    #[error("{matrix}[{row}, {col}] is not finite")]
    NonFinite {
        matrix: &'static str,
        row: usize,
        col: usize,
    },
    /// `matrix` is not symmetric at (`row`, `col`).
    #[error("{matrix} is not symmetric: entry ({row}, {col}) is {upper:.6e}, entry ({col}, {row}) is {lower:.6e}")]
    NotSymmetric {
        matrix: &'static str,
        row: usize,
        col: usize,
        upper: f64,
        lower: f64,
    },
    /// The generalised mass of fixed-interface mode `mode` (1-based) is not positive.
    #[error("fixed-interface mode {mode} has generalised mass {value:.6e}: a mass must be positive")]
    ModalMass { mode: usize, value: f64 },
    /// $\mathbf M_{CB}$ has no Cholesky factor: some motion has no or negative kinetic energy.
    #[error("M_CB is not positive definite: some motion of the body has no or negative kinetic energy")]
    MassIndefinite,
    /// $\mathbf K_{CB}$ has a negative eigenvalue $\omega^2$ on the elastic motions.
    #[error(
        "K_CB is indefinite: an elastic motion has omega^2 = {eigenvalue:.6e} rad^2/s^2 (largest {largest:.6e}), i.e. negative strain energy"
    )]
    StiffnessIndefinite { eigenvalue: f64, largest: f64 },
    /// A deformation that is not a rigid motion costs no strain energy.
    #[error(
        "K_CB has {count} zero-energy deformation(s) besides the rigid motions (eigenvalue below 1e-12 x {largest:.6e} rad^2/s^2): a mechanism"
    )]
    Mechanism { count: usize, largest: f64 },
    /// Stored metadata (`what`: mass, a centre-of-mass or inertia entry) against the value
    /// $\boldsymbol\Phi_R^T\mathbf M_{CB}\boldsymbol\Phi_R$ implies.
    #[error("the stored {what} {stored:.9e} contradicts M_CB, whose rigid-body part gives {from_matrices:.9e}")]
    Metadata {
        what: String,
        stored: f64,
        from_matrices: f64,
    },
    /// A stored fixed-interface frequency against $\sqrt{K_{\eta\eta}/M_{\eta\eta}}$.
    #[error(
        "fixed-interface mode {mode}: the stored frequency {stored:.9e} rad/s contradicts K_CB and M_CB, which give {from_matrices:.9e} rad/s"
    )]
    Frequency {
        mode: usize,
        stored: f64,
        from_matrices: f64,
    },
    /// Two interfaces share a name.
    #[error("two interfaces are named '{name}'")]
    DuplicateName { name: String },
    /// Two interfaces at the same point (or on the same FE node).
    #[error(
        "interfaces '{a}' and '{b}' coincide (distance {distance:.3e} m): the frame of the body is not fixed by them"
    )]
    Coincident { a: String, b: String, distance: f64 },
}

/// Symmetry tolerance (module docs).
const SYMMETRY_RTOL: f64 = 1e-8;
/// A rigid motion is free below this fraction of the largest eigenvalue (module docs).
const RIGID_FREE_RTOL: f64 = 1e-8;
/// Below $-$ this fraction of the largest eigenvalue: indefinite (module docs).
const INDEFINITE_RTOL: f64 = 1e-9;
/// Within this fraction of zero: a mechanism (module docs).
const MECHANISM_RTOL: f64 = 1e-12;
/// Metadata and frequencies against the matrices (module docs).
const METADATA_RTOL: f64 = 1e-6;
/// Coincident interfaces, as a fraction of the body's size.
const COINCIDENT_RTOL: f64 = 1e-9;

/// Every physical problem of `body` (module docs); empty for a sound body. Shapes must be
/// consistent (the file reader checks them first).
pub fn physical_problems(body: &ReducedBody) -> Vec<PhysicsProblem> {
    let mut out = interface_problems(body);
    let n = body.n_coordinates();
    if body.K_CB.nrows != n || body.K_CB.ncols != n || body.M_CB.nrows != n || body.M_CB.ncols != n || n == 0 {
        return out;
    }
    let K = DMatrix::from_column_slice(n, n, &body.K_CB.data);
    let M = DMatrix::from_column_slice(n, n, &body.M_CB.data);
    for (name, A) in [("K_CB", &K), ("M_CB", &M)] {
        if let Some((i, j)) = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .find(|&(i, j)| !A[(i, j)].is_finite())
        {
            out.push(PhysicsProblem::NonFinite {
                matrix: name,
                row: i,
                col: j,
            });
            return out;
        }
        let amax = A.amax();
        'rows: for i in 0..n {
            for j in i + 1..n {
                let tol = SYMMETRY_RTOL * (A[(i, i)] * A[(j, j)]).abs().sqrt() + 1e-12 * amax;
                if (A[(i, j)] - A[(j, i)]).abs() > tol {
                    out.push(PhysicsProblem::NotSymmetric {
                        matrix: name,
                        row: i,
                        col: j,
                        upper: A[(i, j)],
                        lower: A[(j, i)],
                    });
                    break 'rows;
                }
            }
        }
    }
    let nb = 6 * body.interfaces.len();
    for k in 0..body.n_modes {
        let v = M[(nb + k, nb + k)];
        if v <= 0.0 {
            out.push(PhysicsProblem::ModalMass { mode: k + 1, value: v });
        }
    }
    if !out.is_empty() {
        return out;
    }
    let K = (&K + K.transpose()) * 0.5;
    let M = (&M + M.transpose()) * 0.5;
    let Some(chol) = M.clone().cholesky() else {
        out.push(PhysicsProblem::MassIndefinite);
        return out;
    };
    // A = L^-1 K L^-T.
    let L = chol.l();
    let Linv = match L.clone().try_inverse() {
        Some(x) => x,
        None => {
            out.push(PhysicsProblem::MassIndefinite);
            return out;
        }
    };
    let A = &Linv * &K * Linv.transpose();
    let A = (&A + A.transpose()) * 0.5;
    let lambda = A.clone().symmetric_eigen().eigenvalues;
    let largest = lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if largest == 0.0 {
        out.push(PhysicsProblem::Mechanism { count: n, largest });
        return out;
    }

    // Free rigid motions: the 6x6 problem in the rigid subspace, solved in the A metric.
    let P = rigid_modes(body);
    let Y = L.transpose() * &P; // rigid motions in the coordinates of A
    let (Yq, _) = Y.clone().qr().unpack();
    let Ar = Yq.transpose() * &A * &Yq;
    let er = ((&Ar + Ar.transpose()) * 0.5).symmetric_eigen();
    let free: Vec<usize> = (0..6)
        .filter(|&j| er.eigenvalues[j].abs() <= RIGID_FREE_RTOL * largest)
        .collect();
    let Z0 = DMatrix::from_fn(n, free.len(), |i, c| {
        (0..6).map(|k| Yq[(i, k)] * er.eigenvectors[(k, free[c])]).sum::<f64>()
    });
    // A on the complement of the free rigid motions: project them out and give them the
    // eigenvalue `largest` (so they are neither counted as zero nor negative), leaving the
    // complement's eigenvalues unchanged.
    let r = free.len();
    let Pc = DMatrix::identity(n, n) - &Z0 * Z0.transpose();
    let complement = &Pc * &A * &Pc + &Z0 * Z0.transpose() * largest;
    let ec = ((&complement + complement.transpose()) * 0.5).symmetric_eigen();
    let lowest = ec.eigenvalues.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    if lowest < -INDEFINITE_RTOL * largest {
        out.push(PhysicsProblem::StiffnessIndefinite {
            eigenvalue: lowest,
            largest,
        });
    } else {
        let count = ec
            .eigenvalues
            .iter()
            .filter(|v| v.abs() <= MECHANISM_RTOL * largest)
            .count();
        if count > 0 {
            out.push(PhysicsProblem::Mechanism { count, largest });
        }
    }

    // Fixed-interface frequencies.
    for (k, &stored) in body.fixed_interface_omega.iter().enumerate() {
        let i = nb + k;
        let w2 = K[(i, i)] / M[(i, i)];
        let from = w2.max(0.0).sqrt();
        if !((stored - from).abs() <= METADATA_RTOL * from.max(stored.abs())) {
            out.push(PhysicsProblem::Frequency {
                mode: k + 1,
                stored,
                from_matrices: from,
            });
        }
    }

    // Mass metadata, for a free body.
    if r == 6 {
        out.extend(metadata_problems(body, &(P.transpose() * &M * &P)));
    }
    out
}

/// The rigid motions of the interface set about the origin, $n\times 6$ (zero on the modes):
/// a translation $\mathbf t$ and a small rotation $\boldsymbol\theta$ move interface $k$ by
/// $\mathbf t + \boldsymbol\theta\times\mathbf x_k$ and turn it by $\boldsymbol\theta$.
fn rigid_modes(body: &ReducedBody) -> DMatrix<f64> {
    let x: Vec<Vector3<f64>> = body.interfaces.iter().map(|p| Vector3::from(p.position)).collect();
    fe_model::rigid::rigid_modes(&x, &Vector3::zeros(), body.n_modes)
}

/// Mass, centre of mass and inertia from the rigid mass matrix `Mr` $= \boldsymbol\Phi_R^T
/// \mathbf M_{CB}\boldsymbol\Phi_R$ (about the origin: $[m\mathbf 1, -m\tilde{\mathbf c};\
/// m\tilde{\mathbf c}, \mathbf J_O]$) against the stored ones.
fn metadata_problems(body: &ReducedBody, Mr: &DMatrix<f64>) -> Vec<PhysicsProblem> {
    let mut out = Vec::new();
    let i = &body.inertia;
    let m = (Mr[(0, 0)] + Mr[(1, 1)] + Mr[(2, 2)]) / 3.0;
    let mut check = |what: String, stored: f64, from: f64, scale: f64| {
        if !((stored - from).abs() <= METADATA_RTOL * scale) {
            out.push(PhysicsProblem::Metadata {
                what,
                stored,
                from_matrices: from,
            });
        }
    };
    check("mass".into(), i.mass, m, m.abs().max(i.mass.abs()));
    if !(m > 0.0) {
        return out;
    }
    // B = -m c~: c_x = -B[2,1]/m, c_y = -B[0,2]/m, c_z = -B[1,0]/m.
    let B = Mr.view((0, 3), (3, 3));
    let c = Vector3::new(-B[(2, 1)] / m, -B[(0, 2)] / m, -B[(1, 0)] / m);
    let J_O = Matrix3::from_fn(|a, b| Mr[(3 + a, 3 + b)]);
    let J_c = J_O - m * (Matrix3::identity() * c.norm_squared() - c * c.transpose());
    // The body's size: its radius of gyration and the interfaces' distance from the centre.
    let size = body
        .interfaces
        .iter()
        .map(|p| (Vector3::from(p.position) - c).norm())
        .fold((J_c.trace() / m).abs().sqrt(), f64::max);
    for a in 0..3 {
        check(
            format!("centre of mass [{}]", ["x", "y", "z"][a]),
            i.center_of_mass[a],
            c[a],
            size,
        );
    }
    let jmax = J_c.amax().max(1e-300);
    for a in 0..3 {
        for b in 0..3 {
            check(
                format!(
                    "inertia about the centre of mass [{}{}]",
                    ["x", "y", "z"][a],
                    ["x", "y", "z"][b]
                ),
                i.inertia_com[a][b],
                J_c[(a, b)],
                jmax,
            );
        }
    }
    out
}

/// Duplicate names, shared FE nodes and coincident positions.
fn interface_problems(body: &ReducedBody) -> Vec<PhysicsProblem> {
    let mut out = Vec::new();
    let mut names: Vec<&str> = body.interfaces.iter().map(|p| p.name.as_str()).collect();
    names.sort_unstable();
    for w in names.windows(2) {
        if w[0] == w[1] && !out.contains(&PhysicsProblem::DuplicateName { name: w[0].into() }) {
            out.push(PhysicsProblem::DuplicateName { name: w[0].into() });
        }
    }
    let pos: Vec<Vector3<f64>> = body.interfaces.iter().map(|p| Vector3::from(p.position)).collect();
    let size = pos
        .iter()
        .flat_map(|a| pos.iter().map(move |b| (a - b).norm()))
        .fold(0.0f64, f64::max);
    for a in 0..pos.len() {
        for b in a + 1..pos.len() {
            let d = (pos[a] - pos[b]).norm();
            let same_node = body.interfaces[a].node == body.interfaces[b].node;
            if same_node || d <= COINCIDENT_RTOL * size || !(d > 0.0) {
                out.push(PhysicsProblem::Coincident {
                    a: body.interfaces[a].name.clone(),
                    b: body.interfaces[b].name.clone(),
                    distance: d,
                });
            }
        }
    }
    out
}
