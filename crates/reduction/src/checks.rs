//! The physical checks every reduced body passes before use, whatever its source: a file
//! whose checksums are valid can still hold data no reduction produces (an edited matrix,
//! metadata copied from another body, an MBDyn record 12 with the wrong mass, a node table in
//! millimetres). The superelement would use it silently: wrong frequencies, negative strain
//! energy, wrong kinetic energy. The checks run
//!
//! - on every `.rbody` load ([`crate::io::rbody::read`], [`crate::io::rbody::from_bytes`]);
//! - on every MBDyn `.fem` read ([`crate::io::mbdyn::read_mbdyn_fem`]): the records as
//!   written (records 9 and 10 symmetric, record 12 against the nodal masses of record 11,
//!   see [`record_12_problems`], and against the `FLEXMBS` first moment, see
//!   [`stated_moment_problems`]) and the body built from them;
//! - on matrices from another code (the study's `[bodies.matrices]`, `flexmbs inspect
//!   K.mtx ...`): the node table against $\mathbf K$ ([`node_table_problems`]) and against
//!   the mass of $\mathbf M$ ([`NodeCloud`]) before the reduction
//!   ([`crate::reduce_external_dofs`]), the body after it;
//! - on a body reduced by a study, before it is used or cached;
//! - in `flexmbs inspect`, which prints the [`Measurements`] and the problems.
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
//!
//! # The node table of matrices from another code
//!
//! With the rigid motions $\boldsymbol\phi$ built from the node table about the centroid
//! $\mathbf c$ of its nodes ($\mathbf e_a$ on translation $a$; $\boldsymbol\theta\times(\mathbf
//! x - \mathbf c)$ on the translations and $\boldsymbol\theta$ on the rotations of a node,
//! in the dof order of the dof table), row $i$ of $\mathbf K\boldsymbol\phi$ must vanish:
//! $|(\mathbf K\boldsymbol\phi)_i| \le 10^{-6}\sum_j|K_{ij}\phi_j|$, the sum of the
//! magnitudes that cancel (an exporter's 8 significant digits leave $10^{-8}$ of it). Rows
//! where a translation fails are coupled to dofs the other code removed (supports, springs to
//! ground) and are not asked to pass the rotations; every other row is. A node table in other
//! units than K (millimetres) or with a node at the wrong place (two coincident nodes) strains
//! the rotations everywhere or around that node. A uniform scale of the table of a mesh
//! of solids (three translations per node) is not seen this way (the scaled rotation is
//! still a rigid motion).
//!
//! The mass does see it ([`NodeCloud`]): the mass $m = \mathbf t_a^T\mathbf M\mathbf t_a$
//! of a rigid translation (the largest of the three directions) over the volume $V$ of a box
//! around the nodes with dofs is a lower bound of the material's density, for the body lies
//! in the convex hull of its nodes (of a solid mesh; for beams and shells the box is flat or
//! thin and the bound higher still). Of two boxes the smaller counts: along the axes, and
//! along the principal axes of the nodes (a skewed slender body). $m/V$ below
//! $10^{-2}$ kg/m³ ([`MIN_DENSITY`]) is refused. A node table in millimetres with $\mathbf K$ and
//! $\mathbf M$ in SI makes $V$ $10^9$ times too large: even the densest material
//! (22,600 kg/m³) filling its box gives $2.3\cdot 10^{-5}$, 400 times below the limit
//! (so does a whole model in mm-t-s read as SI). A body in metres is refused only if its
//! material fills less than $10^{-2}/\rho$ of the box: $1.3\cdot 10^{-6}$ for steel,
//! $3\cdot 10^{-4}$ for a 30 kg/m³ foam, far below the sparsest lattice (about $10^{-4}$ of
//! its box in steel).
//!
//! # Record 12 of MBDyn files against their nodal masses
//!
//! Record 12 states the rigid body's mass $m$, centre of mass and inertia about it; the body
//! is built from them (with records 14-18), so the checks above cannot see a wrong record 12
//! (a mass ten times too large makes a consistent, wrong body). Record 11, the diagonal of
//! a lumped mass matrix at the exposed nodes, states the same data as point masses (with
//! their diagonal rotational inertias) at the undeformed node positions of records 5-7
//! ([`record_12_problems`]). Lumping keeps the mass (row sums and diagonal scaling both do)
//! and, for row sums, the first moment exactly ($\sum_i N_i\mathbf x_i = \mathbf x$), so the
//! mass must agree to $10^{-3}$ and each coordinate of the centre to $10^{-3}$ of the body's
//! size (the farthest node with mass from the nodal centre, or the radius of gyration):
//! room for a file printed with four digits. The second moment of point masses differs from
//! the continuum by the mesh's resolution (a bar of $n$ two-node elements, row-sum lumped:
//! $mL^2(1/12 + 1/(6n^2))$ about its centre, $2/n^2$ too large), so each entry of the inertia
//! must agree to $10^{-1}$ of the largest (a mesh of five elements along the body is 8 % off;
//! a wrong inertia, a tensor about the wrong point or a unit slip, is off by far more). A
//! file without record 11 cannot be compared: `flexmbs inspect` says so (for files written
//! by flexmbs, the `FLEXMBS FIRST MOMENT` line still checks mass and centre,
//! [`stated_moment_problems`]). A file with record 12 whose record 11 holds only some of the
//! body's nodes is not one MBDyn reads right either: it builds invariants from record 11
//! when given and adds them to the stated ones ([`crate::io::mbdyn`]).

#![allow(non_snake_case)]

use crate::reduced_body::ReducedBody;
use faer::sparse::SparseColMatRef;
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::fmt;
use std::path::{Path, PathBuf};

/// A body refused by the physical checks: which body, from which file, and its problems
/// (each naming its entity: matrix entry, interface, node, record).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BodyCheckError {
    /// The body's data ([`examine`], [`stated_moment_problems`]).
    #[error("body '{body}' ({}) fails the physical checks, so it is not used: {}", file.display(), list(problems))]
    Refused {
        body: String,
        file: PathBuf,
        problems: Vec<PhysicsProblem>,
    },
    /// The node table `file` of matrices from another code does not match their stiffness
    /// ([`node_table_problems`]).
    #[error("body '{body}': the node table {} does not match the matrices: {}", file.display(), list(problems))]
    NodeTable {
        body: String,
        file: PathBuf,
        problems: Vec<PhysicsProblem>,
    },
}

fn list(problems: &[PhysicsProblem]) -> String {
    problems.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("; ")
}

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
    /// A rigid `motion` built from the node table is strained by $\mathbf K$: the largest
    /// relative row residual ([`node_table_problems`]) is `relative`, at `node` (0-based index
    /// of the node table); `nodes` nodes fail.
    #[error(
        "the rigid {motion} built from the node table is strained by K at {nodes} node(s), most at node {node} (|K phi| / sum |K||phi| = {relative:.3e} > {NODE_TABLE_RTOL:.0e}): the node table is not the geometry of K (coordinates in other units than m, or nodes at the wrong place)"
    )]
    RigidMotionStrained {
        motion: &'static str,
        node: usize,
        relative: f64,
        nodes: usize,
    },
    /// The mass of $\mathbf M$ over the volume of the box around the node table's nodes
    /// ([`NodeCloud`]) is below [`MIN_DENSITY`]: no material is that light.
    #[error(
        "the mass in M ({mass:.3e} kg) over the volume of the box around the node table's nodes ({volume:.3e} m^3) is {density:.3e} kg/m^3, below {MIN_DENSITY:.0e} kg/m^3 and far below any structural material: the node table is likely in other units than K and M (millimetres make the volume 1e9 times too large)"
    )]
    ImplausibleDensity { mass: f64, volume: f64, density: f64 },
    /// A value the file states (`what`) against the one its other data imply (`by`).
    #[error("the stated {what} {stated:.9e} contradicts {by}, which gives {implied:.9e}")]
    Stated {
        what: String,
        stated: f64,
        implied: f64,
        by: &'static str,
    },
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
/// A row of $\mathbf K\boldsymbol\phi$ against the magnitudes that cancel in it (module docs).
pub const NODE_TABLE_RTOL: f64 = 1e-6;
/// The least mass over the node cloud's box volume \[kg/m^3\] of a body in SI units (module
/// docs).
pub const MIN_DENSITY: f64 = 1e-2;
/// Record 12's mass (of the mass) and centre of mass (of the body's size) against the nodal
/// masses of record 11 (module docs).
pub const NODAL_MASS_RTOL: f64 = 1e-3;
/// Record 12's inertia against the nodal masses of record 11, of the largest entry (module
/// docs).
pub const NODAL_INERTIA_RTOL: f64 = 0.1;

/// What the checks measured on a body, for `flexmbs inspect`; `None` where an earlier check
/// failed before the quantity could be computed (module docs for each tolerance).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Measurements {
    /// Largest asymmetry of $\mathbf K_{CB}$ and $\mathbf M_{CB}$: $|A_{ij} - A_{ji}| /
    /// (\sqrt{|A_{ii}A_{jj}|} + 10^{-4}\max|A|)$, passes up to $10^{-8}$.
    pub asymmetry: Option<[f64; 2]>,
    /// Smallest over largest eigenvalue of $\mathbf M_{CB}$ (positive definite: above 0).
    pub mass_eigen_ratio: Option<f64>,
    /// Largest eigenvalue $\lambda_{max} = \omega^2_{max}$ of $\mathbf K_{CB}$ in the
    /// metric of $\mathbf M_{CB}$ \[rad^2/s^2\].
    pub largest_eigenvalue: Option<f64>,
    /// The rigid motions' eigenvalues over $\lambda_{max}$, ascending (free up to $10^{-8}$).
    pub rigid_eigen_ratios: Option<[f64; 6]>,
    /// Lowest eigenvalue over $\lambda_{max}$ on the complement of the free rigid motions
    /// (above $10^{-12}$; below $-10^{-9}$ indefinite).
    pub lowest_elastic_ratio: Option<f64>,
    /// Mass \[kg\], centre of mass \[m\] and inertia about it \[kg m^2\] from the rigid part
    /// of $\mathbf M_{CB}$ (free bodies).
    pub rigid_mass: Option<(f64, [f64; 3], [[f64; 3]; 3])>,
    /// Smallest distance between two interfaces over the largest (above $10^{-9}$).
    pub closest_interfaces: Option<f64>,
}

impl fmt::Display for Measurements {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sci = |v: Option<f64>| v.map(|v| format!("{v:.3e}")).unwrap_or_else(|| "not reached".into());
        if let Some([k, m]) = self.asymmetry {
            writeln!(
                f,
                "  asymmetry of K_CB, M_CB           {k:.3e}, {m:.3e} (limit {SYMMETRY_RTOL:.0e})"
            )?;
        }
        writeln!(
            f,
            "  M_CB eigenvalues, smallest/largest {} (must be > 0)",
            sci(self.mass_eigen_ratio)
        )?;
        writeln!(
            f,
            "  largest omega^2                    {} rad^2/s^2",
            sci(self.largest_eigenvalue)
        )?;
        if let Some(r) = self.rigid_eigen_ratios {
            let free = r.iter().filter(|v| v.abs() <= RIGID_FREE_RTOL).count();
            let list: Vec<String> = r.iter().map(|v| format!("{v:.1e}")).collect();
            writeln!(
                f,
                "  rigid motions / largest omega^2    {} ({free} of 6 free, limit {RIGID_FREE_RTOL:.0e})",
                list.join(" ")
            )?;
        }
        writeln!(
            f,
            "  lowest elastic / largest omega^2   {} (limits -{INDEFINITE_RTOL:.0e}, {MECHANISM_RTOL:.0e})",
            sci(self.lowest_elastic_ratio)
        )?;
        if let Some((m, c, _)) = self.rigid_mass {
            writeln!(
                f,
                "  from M_CB: mass {m:.6e} kg, centre of mass ({:.6e}, {:.6e}, {:.6e}) m (stored values must agree to {METADATA_RTOL:.0e})",
                c[0], c[1], c[2]
            )?;
        }
        match self.closest_interfaces {
            Some(r) => writeln!(
                f,
                "  closest interfaces / body size     {r:.3e} (limit {COINCIDENT_RTOL:.0e})"
            ),
            None => writeln!(f, "  closest interfaces / body size     (fewer than two interfaces)"),
        }
    }
}

/// Every physical problem of `body` (module docs); empty for a sound body. Shapes must be
/// consistent (the file reader checks them first).
pub fn physical_problems(body: &ReducedBody) -> Vec<PhysicsProblem> {
    examine(body).0
}

/// `body`'s measurements if it passes every check, else the error naming `file` (where the
/// body comes from) and the problems.
pub fn check_body(body: &ReducedBody, file: &Path) -> Result<Measurements, BodyCheckError> {
    let (problems, measured) = examine(body);
    if problems.is_empty() {
        Ok(measured)
    } else {
        Err(BodyCheckError::Refused {
            body: body.name.clone(),
            file: file.to_path_buf(),
            problems,
        })
    }
}

/// The problems of `body` and what was measured on the way.
pub fn examine(body: &ReducedBody) -> (Vec<PhysicsProblem>, Measurements) {
    let mut measured = Measurements::default();
    let mut out = interface_problems(body, &mut measured);
    let n = body.n_coordinates();
    if body.K_CB.nrows != n || body.K_CB.ncols != n || body.M_CB.nrows != n || body.M_CB.ncols != n || n == 0 {
        return (out, measured);
    }
    let K = DMatrix::from_column_slice(n, n, &body.K_CB.data);
    let M = DMatrix::from_column_slice(n, n, &body.M_CB.data);
    let mut asymmetry = [0.0; 2];
    for (k, (name, A)) in [("K_CB", &K), ("M_CB", &M)].into_iter().enumerate() {
        if let Some((i, j)) = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .find(|&(i, j)| !A[(i, j)].is_finite())
        {
            out.push(PhysicsProblem::NonFinite {
                matrix: name,
                row: i,
                col: j,
            });
            return (out, measured);
        }
        let (ratio, problem) = symmetry_problem(name, A);
        asymmetry[k] = ratio;
        out.extend(problem);
    }
    measured.asymmetry = Some(asymmetry);
    let nb = 6 * body.interfaces.len();
    for k in 0..body.n_modes {
        let v = M[(nb + k, nb + k)];
        if v <= 0.0 {
            out.push(PhysicsProblem::ModalMass { mode: k + 1, value: v });
        }
    }
    if !out.is_empty() {
        return (out, measured);
    }
    let K = (&K + K.transpose()) * 0.5;
    let M = (&M + M.transpose()) * 0.5;
    let mass_eigen = M.clone().symmetric_eigen().eigenvalues;
    let (lo, hi) = mass_eigen
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v.abs())));
    measured.mass_eigen_ratio = Some(lo / hi);
    let Some(chol) = M.clone().cholesky() else {
        out.push(PhysicsProblem::MassIndefinite);
        return (out, measured);
    };
    out.extend(spectrum_problems(body, &K, &M, &chol.l(), &mut measured));
    (out, measured)
}

/// The largest asymmetry ratio of `A` (see [`Measurements::asymmetry`]) and the first entry
/// beyond the tolerance, as a problem of `matrix`.
pub(crate) fn symmetry_problem(matrix: &'static str, A: &DMatrix<f64>) -> (f64, Option<PhysicsProblem>) {
    let amax = A.amax();
    let mut worst = 0.0f64;
    let mut first = None;
    for i in 0..A.nrows() {
        for j in i + 1..A.ncols() {
            let diff = (A[(i, j)] - A[(j, i)]).abs();
            if diff == 0.0 {
                continue;
            }
            let ratio = diff / ((A[(i, i)] * A[(j, j)]).abs().sqrt() + 1e-4 * amax);
            worst = worst.max(ratio);
            if !(ratio <= SYMMETRY_RTOL) && first.is_none() {
                first = Some(PhysicsProblem::NotSymmetric {
                    matrix,
                    row: i,
                    col: j,
                    upper: A[(i, j)],
                    lower: A[(j, i)],
                });
            }
        }
    }
    (worst, first)
}

/// The eigenvalue checks of `K` in the metric of `M` $= \mathbf L\mathbf L^T$ (both
/// symmetric), the frequencies and, for a free body, the mass data (module docs).
fn spectrum_problems(
    body: &ReducedBody,
    K: &DMatrix<f64>,
    M: &DMatrix<f64>,
    L: &DMatrix<f64>,
    measured: &mut Measurements,
) -> Vec<PhysicsProblem> {
    let mut out = Vec::new();
    let n = K.nrows();
    let nb = 6 * body.interfaces.len();
    // A = L^-1 K L^-T.
    let Some(Linv) = L.clone().try_inverse() else {
        out.push(PhysicsProblem::MassIndefinite);
        return out;
    };
    let A = &Linv * K * Linv.transpose();
    let A = (&A + A.transpose()) * 0.5;
    let lambda = A.clone().symmetric_eigen().eigenvalues;
    let largest = lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    measured.largest_eigenvalue = Some(largest);
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
    let mut ratios: Vec<f64> = er.eigenvalues.iter().map(|v| v / largest).collect();
    ratios.sort_by(f64::total_cmp);
    measured.rigid_eigen_ratios = ratios.try_into().ok();
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
    measured.lowest_elastic_ratio = Some(lowest / largest);
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
        out.extend(metadata_problems(body, &(P.transpose() * M * &P), measured));
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
fn metadata_problems(body: &ReducedBody, Mr: &DMatrix<f64>, measured: &mut Measurements) -> Vec<PhysicsProblem> {
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
    measured.rigid_mass = Some((m, c.into(), J_c.transpose().into()));
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
fn interface_problems(body: &ReducedBody, measured: &mut Measurements) -> Vec<PhysicsProblem> {
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
            let ratio = if size > 0.0 { d / size } else { 0.0 };
            measured.closest_interfaces = Some(measured.closest_interfaces.map_or(ratio, |r| r.min(ratio)));
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

/// The rigid motions built from a node table against the stiffness of matrices from another
/// code (module docs): `K` with row $d$ dof `dofs[d].1` ($[u_x, u_y, u_z, \theta_x,
/// \theta_y, \theta_z]$) of node `dofs[d].0` (an index into `nodes`, checked by the caller).
/// One [`PhysicsProblem::RigidMotionStrained`] per strained rotation.
pub fn node_table_problems(
    nodes: &[[f64; 3]],
    K: SparseColMatRef<'_, usize, f64>,
    dofs: &[(usize, usize)],
) -> Vec<PhysicsProblem> {
    let n = dofs.len();
    if n == 0 || K.nrows() != n || K.ncols() != n {
        return Vec::new();
    }
    // The centroid of the nodes with dofs: rotations about it keep phi of the body's size.
    let x = nodes_with_dofs(nodes, dofs);
    let c = x.iter().fold(Vector3::zeros(), |s, x| s + x) / x.len().max(1) as f64;
    // phi[d][k]: rigid motion k (translations x, y, z, rotations about x, y, z) at dof d.
    let phi: Vec<[f64; 6]> = dofs
        .iter()
        .map(|&(node, k)| {
            let block = fe_model::rigid::rigid_motion_block(&(Vector3::from(nodes[node]) - c));
            std::array::from_fn(|j| block[(k, j)])
        })
        .collect();
    // K phi and the magnitudes that cancel in it, row by row.
    let mut residual = vec![[0.0f64; 6]; n];
    let mut scale = vec![[0.0f64; 6]; n];
    for j in 0..n {
        for (&i, &v) in K.row_idx_of_col_raw(j).iter().zip(K.val_of_col(j)) {
            for k in 0..6 {
                residual[i][k] += v * phi[j][k];
                scale[i][k] += (v * phi[j][k]).abs();
            }
        }
    }
    let relative = |i: usize, k: usize| {
        if residual[i][k] == 0.0 {
            0.0
        } else {
            residual[i][k].abs() / scale[i][k]
        }
    };
    let mut out = Vec::new();
    for (k, motion) in [
        (3, "rotation about x"),
        (4, "rotation about y"),
        (5, "rotation about z"),
    ] {
        let mut failing = vec![false; nodes.len()];
        let mut worst = (0.0f64, 0usize);
        for i in 0..n {
            // Rows coupled to dofs the other code removed fail the translations too: excused.
            if (0..3).any(|t| !(relative(i, t) <= NODE_TABLE_RTOL)) {
                continue;
            }
            let r = relative(i, k);
            if !(r <= NODE_TABLE_RTOL) {
                failing[dofs[i].0] = true;
                if !(r <= worst.0) {
                    worst = (r, dofs[i].0);
                }
            }
        }
        let nodes_failing = failing.iter().filter(|&&f| f).count();
        if nodes_failing > 0 {
            out.push(PhysicsProblem::RigidMotionStrained {
                motion,
                node: worst.1,
                relative: worst.0,
                nodes: nodes_failing,
            });
        }
    }
    out
}

/// Record 12 of an MBDyn file (mass `m`, centre of mass `c_O` from the frame origin $O$, and
/// inertia `J_O` about $O$, for the body's size) against the first moment about $O$ the file
/// also states (`first` $= \int\rho\,\mathbf x$, the `FLEXMBS FIRST MOMENT` line):
/// $\int\rho\,\mathbf x = m\mathbf c_O$ to $10^{-6}$ (the mass when $|\mathbf c_O|$ is at
/// least $10^{-3}$ of the body's size, then each coordinate of the centre, to $10^{-6}$ of
/// the size). The second moment is not compared with $\mathbf J_O$: for beams the two differ
/// by more than the sections' rotary inertia (the translational field of a consistent beam
/// mass is not the exact one).
pub fn stated_moment_problems(
    m: f64,
    c_O: &Vector3<f64>,
    J_O: &Matrix3<f64>,
    first: Option<&Vector3<f64>>,
) -> Vec<PhysicsProblem> {
    let mut out = Vec::new();
    if !(m > 0.0) {
        return out;
    }
    let size = c_O.norm() + (J_O.trace().abs() / m).sqrt();
    if let Some(X1) = first {
        if c_O.norm() >= 1e-3 * size {
            let implied = X1.dot(c_O) / c_O.norm_squared();
            if !((implied - m).abs() <= METADATA_RTOL * m) {
                out.push(PhysicsProblem::Stated {
                    what: "record 12 mass".into(),
                    stated: m,
                    implied,
                    by: "the first moment (FLEXMBS FIRST MOMENT) over the record 12 centre of mass",
                });
            }
        }
        for a in 0..3 {
            if !((X1[a] / m - c_O[a]).abs() <= METADATA_RTOL * size) {
                out.push(PhysicsProblem::Stated {
                    what: format!(
                        "record 12 centre of mass [{}] from the frame origin",
                        ["x", "y", "z"][a]
                    ),
                    stated: c_O[a],
                    implied: X1[a] / m,
                    by: "the first moment (FLEXMBS FIRST MOMENT) over the record 12 mass",
                });
            }
        }
    }
    out
}

/// Record 12 of an MBDyn file as `stated` (mass $m$, centre of mass $\mathbf c_O$ from the
/// frame origin, inertia $\mathbf J$ about the centre of mass) against the same data of the
/// file's nodal masses (`nodal`: record 11's point masses and diagonal rotational inertias at
/// the undeformed node positions), `size` the body's size (module docs): the mass to
/// [`NODAL_MASS_RTOL`] of the nodal mass, each coordinate of the centre to [`NODAL_MASS_RTOL`]
/// of `size`, each entry of the inertia to [`NODAL_INERTIA_RTOL`] of the nodal inertia's
/// largest entry. One [`PhysicsProblem::Stated`] per value outside.
pub fn record_12_problems(
    stated: (f64, &Vector3<f64>, &Matrix3<f64>),
    nodal: (f64, &Vector3<f64>, &Matrix3<f64>),
    size: f64,
) -> Vec<PhysicsProblem> {
    const BY: &str = "the nodal masses of record 11 at the node positions of records 5-7";
    let mut out = Vec::new();
    let mut check = |what: String, stated: f64, implied: f64, tolerance: f64| {
        if !((stated - implied).abs() <= tolerance) {
            out.push(PhysicsProblem::Stated {
                what,
                stated,
                implied,
                by: BY,
            });
        }
    };
    let axes = ["x", "y", "z"];
    check(
        "record 12 mass".into(),
        stated.0,
        nodal.0,
        NODAL_MASS_RTOL * nodal.0.abs(),
    );
    for a in 0..3 {
        check(
            format!("record 12 centre of mass [{}] from the frame origin", axes[a]),
            stated.1[a],
            nodal.1[a],
            NODAL_MASS_RTOL * size,
        );
    }
    let jmax = nodal.2.amax();
    for a in 0..3 {
        for b in a..3 {
            check(
                format!("record 12 inertia about the centre of mass [{}{}]", axes[a], axes[b]),
                stated.2[(a, b)],
                nodal.2[(a, b)],
                NODAL_INERTIA_RTOL * jmax,
            );
        }
    }
    out
}

/// The node table of matrices from another code against their mass (module docs): the mass
/// of a rigid translation through $\mathbf M$ over the volume of the smaller of two boxes
/// around the nodes that have dofs (along the axes, and along the principal axes of the
/// cloud), a lower bound of the material's density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeCloud {
    /// $\mathbf t_a^T\mathbf M\mathbf t_a$, the largest of the three directions $a$ \[kg\].
    pub mass: f64,
    /// The sides of the box \[m\].
    pub sides: [f64; 3],
    /// `mass` over the box's volume \[kg/m^3\]; infinite for a straight or flat cloud (a
    /// beam or a plate, whose volume the nodes do not span).
    pub density_bound: f64,
}

impl NodeCloud {
    /// The cloud of `nodes` with `M` (row $d$ dof `dofs[d].1` of node `dofs[d].0`, an index
    /// into `nodes` checked by the caller).
    pub fn new(nodes: &[[f64; 3]], M: SparseColMatRef<'_, usize, f64>, dofs: &[(usize, usize)]) -> NodeCloud {
        let mut mass = [0.0f64; 3];
        for j in 0..M.ncols().min(dofs.len()) {
            for (&i, &v) in M.row_idx_of_col_raw(j).iter().zip(M.val_of_col(j)) {
                let (a, b) = (dofs.get(i).map_or(6, |d| d.1), dofs[j].1);
                if a == b && a < 3 {
                    mass[a] += v;
                }
            }
        }
        let sides = smaller_box(&nodes_with_dofs(nodes, dofs));
        let mass = mass.iter().fold(0.0f64, |m, &v| m.max(v));
        let volume = sides.iter().product::<f64>();
        NodeCloud {
            mass,
            sides,
            density_bound: if volume > 0.0 { mass / volume } else { f64::INFINITY },
        }
    }

    /// [`PhysicsProblem::ImplausibleDensity`] when the density bound is below [`MIN_DENSITY`].
    pub fn problem(&self) -> Option<PhysicsProblem> {
        (self.density_bound < MIN_DENSITY).then(|| PhysicsProblem::ImplausibleDensity {
            mass: self.mass,
            volume: self.sides.iter().product(),
            density: self.density_bound,
        })
    }
}

impl fmt::Display for NodeCloud {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [a, b, c] = self.sides;
        writeln!(
            f,
            "  node table: box {a:.3e} x {b:.3e} x {c:.3e} m, mass in M {:.6e} kg, mass / box volume {:.3e} kg/m^3 (limit {MIN_DENSITY:.0e})",
            self.mass, self.density_bound
        )
    }
}

/// The positions of the nodes of a node table that carry dofs (`dofs[d].0`: the node of row
/// $d$), in the table's order: the nodes the matrices' checks measure.
fn nodes_with_dofs(nodes: &[[f64; 3]], dofs: &[(usize, usize)]) -> Vec<Vector3<f64>> {
    let mut used = vec![false; nodes.len()];
    for &(node, _) in dofs {
        used[node] = true;
    }
    nodes
        .iter()
        .zip(&used)
        .filter(|(_, &u)| u)
        .map(|(x, _)| Vector3::from(*x))
        .collect()
}

/// The sides of the smaller of two boxes around `x`: along the axes, and along the principal
/// axes of the points (which fits a skewed slender body).
fn smaller_box(x: &[Vector3<f64>]) -> [f64; 3] {
    if x.is_empty() {
        return [0.0; 3];
    }
    let c = x.iter().sum::<Vector3<f64>>() / x.len() as f64;
    let spread = x
        .iter()
        .fold(Matrix3::zeros(), |s, p| s + (p - c) * (p - c).transpose());
    // Non-finite coordinates (refused by every reader) would keep the eigensolver iterating.
    let principal = if spread.iter().all(|v| v.is_finite()) {
        spread.symmetric_eigen().eigenvectors
    } else {
        Matrix3::identity()
    };
    let sides = |axes: &Matrix3<f64>| -> [f64; 3] {
        std::array::from_fn(|k| {
            let along = x.iter().map(|p| axes.column(k).dot(&(p - c)));
            let (lo, hi) = along.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
            hi - lo
        })
    };
    let (aligned, turned) = (sides(&Matrix3::identity()), sides(&principal));
    if turned.iter().product::<f64>() < aligned.iter().product::<f64>() {
        turned
    } else {
        aligned
    }
}
