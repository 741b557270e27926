//! MBDyn modal element files (`.fem`): a [`ReducedBody`] written for MBDyn's `modal` joint,
//! and a `.fem` file read back as a [`ReducedBody`].
//!
//! # The format
//!
//! MBDyn's input manual, appendix "Modal Element Data" (FEM file format), and the reader in
//! MBDyn's `struct/modal.cc`: record groups start with a line `** RECORD GROUP <n>`; other
//! lines starting with `**` are comments; values are whitespace-separated.
//!
//! | record | content |
//! |---|---|
//! | 1 | header: one comment line, then `REV NNODES NNORMAL NATTACHED NCONSTRAINT NREJECTED`; $n_x$ = NNORMAL + NATTACHED + NCONSTRAINT - NREJECTED modes |
//! | 2 | the NNODES labels of the exposed FEM nodes |
//! | 3, 4 | initial modal displacements and velocities ($n_x$ each) |
//! | 5, 6, 7 | $x$, $y$, $z$ of the exposed nodes, in the frame of MBDyn's modal node |
//! | 8 | for each mode, one comment line then, for each node, $u_x\ u_y\ u_z\ \theta_x\ \theta_y\ \theta_z$ |
//! | 9, 10 | modal mass $\mathbf X^T\mathbf M\mathbf X$ and stiffness $\mathbf X^T\mathbf K\mathbf X$ ($n_x \times n_x$) |
//! | 11 | diagonal of a lumped mass matrix at the exposed nodes (6 per node) |
//! | 12 | mass $m$; centre of mass $\mathbf c$; inertia $\mathbf J$ about it (3 x 3) |
//! | 13 | modal damping (read and not used) |
//! | 14 | invariant 3: $\int\rho\,\mathbf S\,dV$ ($3 \times n_x$) |
//! | 15 | invariant 4: $\int\rho\,\tilde{\mathbf x}\mathbf S\,dV$ ($3 \times n_x$, $\mathbf x$ from the frame origin) |
//! | 16 | invariant 8: $-\int\rho\,\tilde{\mathbf x}\tilde{\mathbf S}_j\,dV$ ($3 \times 3$ per mode; row $i$ lists mode by mode the row $i$) |
//! | 17 | invariant 5: $\int\rho\,\mathbf S_j \times \mathbf S_k\,dV$ (row $i$: $j$ outer, $k$ inner) |
//! | 18 | invariant 9: $\int\rho\,\tilde{\mathbf S}_j\tilde{\mathbf S}_k\,dV$ (row $i$: $j$, $k$, then the column) |
//!
//! MBDyn refuses any other record number; so do we. `** END OF FILE` ends the data.
//!
//! # What is written ([`to_mbdyn_fem`])
//!
//! MBDyn's modal node carries the body's rigid motion, so the modes must not contain it. The
//! Craig-Bampton coordinates $[\mathbf u_1, \boldsymbol\theta_1, \dots, \boldsymbol\eta]$
//! contain it through the constraint modes; the file holds the Craig-Bampton basis with a
//! *reference interface* $r$ held (its six columns left out): the constraint modes of the
//! other interfaces and the fixed-interface modes, i.e. the deformation seen from a frame
//! attached to interface $r$. These span, with the six rigid motions, the same space as the
//! full basis (rigid motion is a combination of constraint modes), so MBDyn's modal node placed
//! at interface $r$ reproduces the body. Coordinates are written relative to interface $r$ (the
//! frame of the modal node, axes of the FE model); comment lines keep what MBDyn's records do
//! not hold and MBDyn skips: `** FLEXMBS ORIGIN x y z` the offset, `** FLEXMBS BODY name` the
//! name, `** FLEXMBS FIRST MOMENT` and `** FLEXMBS SECOND MOMENT` (3 and 9 values, row by row)
//! the moments $\int\rho\,\mathbf x\,dV$ and $\int\rho\,\mathbf x\mathbf x^T dV$ about the
//! frame origin of the translational field
//! (record 12's $\mathbf J$ holds beam sections' rotary inertia too), and `** FLEXMBS FIELD
//! INVARIANT 3 a k ...` (eight values a line: MBDyn reads comment lines into a buffer of
//! `BUFSIZ` characters) $\int\rho\,\mathbf S\,dV$ of the translational field, which for beams
//! differs from invariant 3 (the consistent mass couples translations and rotations). The exposed nodes
//! are the interfaces, labelled by their names (whitespace replaced by `_`).
//!
//! Record 11 is not written: MBDyn would rebuild invariants from it and add them to the ones
//! given. Records 12 and 14-18 hold the exact mass data, from [`InertiaData`]; record 13 is
//! not written (no damping).
//!
//! # What is read ([`parse_mbdyn_fem`])
//!
//! Any such file: the modes $\mathbf X$ are joined by the six rigid motions of the frame (the
//! modal node), and the basis is brought to Craig-Bampton form on the chosen exposed nodes as
//! interfaces: with $\mathbf B$ the values of the joint basis at the interfaces (6 per node),
//! interface coordinates $\mathbf B^+$, corrected by static condensation in the null space
//! $\mathbf Z$ of $\mathbf B$ ($-\mathbf Z\mathbf K_{zz}^{-1}\mathbf Z^T\mathbf K\mathbf B^+$), and
//! fixed-interface modes from the eigenvectors of $(\mathbf K_{zz}, \mathbf M_{zz})$, each
//! signed so that its largest coefficient on the joint basis is positive. For a file written by
//! [`to_mbdyn_fem`] this is the original body: the same space, interface coordinates and
//! fixed-interface modes (up to the order within repeated frequencies). Mass data come from
//! records 12 and 14-18; without them from record 11 (lumped masses at the exposed nodes, as
//! MBDyn does); missing second-order invariants are zero, as MBDyn takes them (the notes say
//! so). The moments $\int\rho\,\mathbf x$, $\int\rho\,\mathbf x\mathbf x^T$ of the rigid motions and
//! $\int\rho\,\mathbf S\,dV$ of the translational field come from the `FLEXMBS` lines, else
//! from $\mathbf J$ and invariant 3 (exact for solids; for beams the second-order invariants
//! of the rigid motions then include the sections' rotary inertia).
//!
//! The body read passes the physical checks of every body ([`crate::checks`]), and the
//! records as written some of their own: records 9 and 10 symmetric (the body is built from
//! their symmetric parts), record 12's mass, centre of mass and inertia against the nodal
//! masses of record 11 at the node positions of records 5-7
//! ([`crate::checks::record_12_problems`]), its mass and centre of mass against the
//! `FLEXMBS FIRST MOMENT` line ([`crate::checks::stated_moment_problems`]). A file that fails
//! is refused with [`FemError::Checks`]; [`read_mbdyn_fem_unchecked`] reads it for `flexmbs
//! inspect`, with the record checks that could not be made ([`FemBody::not_checked`]).

#![allow(non_snake_case)]

use crate::checks::{BodyCheckError, PhysicsProblem};
use crate::reduced_body::{DenseMatrix, InertiaData, InterfacePoint, ReducedBody, FORMAT_VERSION};
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::path::{Path, PathBuf};

/// A `.fem` file that cannot be written or read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FemError {
    #[error("{path}: cannot {action} the file: {source}")]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// A value missing or not a number, with the record it belongs to.
    #[error("{path}:{line}: RECORD GROUP {record}: expected {expected}, found '{found}'")]
    Malformed {
        path: PathBuf,
        line: usize,
        record: u32,
        expected: String,
        found: String,
    },
    /// Records missing, repeated or unknown; sizes that do not agree.
    #[error("{path}:{line}: {what}")]
    Structure { path: PathBuf, line: usize, what: String },
    /// The body cannot be written (a reference interface that does not exist), or the data
    /// read cannot make a reduced body (interfaces that the modes cannot move independently,
    /// a modal stiffness that is not positive with the interfaces held).
    #[error("{path}: {what}")]
    Body { path: PathBuf, what: String },
    /// The records (9 and 10 symmetric, 12 against the `FLEXMBS` moments) or the body built
    /// from them fail the physical checks ([`crate::checks`]).
    #[error(transparent)]
    Checks(#[from] BodyCheckError),
}

// ------------------------------------------------------------------------------------ helpers

fn dm(m: &DenseMatrix) -> DMatrix<f64> {
    DMatrix::from_column_slice(m.nrows, m.ncols, &m.data)
}

fn dense(m: &DMatrix<f64>) -> DenseMatrix {
    DenseMatrix {
        nrows: m.nrows(),
        ncols: m.ncols(),
        data: m.as_slice().to_vec(),
    }
}

/// The skew matrix $\tilde{\mathbf a}$, $\tilde{\mathbf a}\mathbf b = \mathbf a \times \mathbf b$.
fn tilde(a: &Vector3<f64>) -> Matrix3<f64> {
    a.cross_matrix()
}

/// [`tilde`] as a dynamic matrix, to multiply `3 x n` blocks.
fn tilde_dyn(a: &Vector3<f64>) -> DMatrix<f64> {
    let t = tilde(a);
    DMatrix::from_fn(3, 3, |i, j| t[(i, j)])
}

/// $\epsilon_{ijk}$.
fn levi_civita(i: usize, j: usize, k: usize) -> f64 {
    match (i, j, k) {
        (0, 1, 2) | (1, 2, 0) | (2, 0, 1) => 1.0,
        (0, 2, 1) | (2, 1, 0) | (1, 0, 2) => -1.0,
        _ => 0.0,
    }
}

/// The mass data of a basis of $n$ columns, all about the frame origin $O$:
/// $\int\rho\,\mathbf S$ (`S_t`, 3 x n), $\int\rho\,\tilde{\mathbf x}\mathbf S$ (`S_rO`),
/// $\mathbf P_j = \int\rho\,\mathbf x\mathbf S_j^T$ (`P[j]`, 3 x 3) and
/// $\mathbf Q_{jk} = \int\rho\,\mathbf S_j\mathbf S_k^T$ (`Q[a][b]`, n x n, entry $(j, k)$ is
/// $Q_{jk}(a, b)$).
struct MassData {
    S_t: DMatrix<f64>,
    S_rO: DMatrix<f64>,
    P: Vec<Matrix3<f64>>,
    Q: Vec<Vec<DMatrix<f64>>>,
}

impl MassData {
    /// The same data for the basis $\mathbf V\mathbf T$ (columns combined by `T`).
    fn transform(&self, T: &DMatrix<f64>) -> MassData {
        let n = T.ncols();
        let P = (0..n)
            .map(|j| (0..self.P.len()).fold(Matrix3::zeros(), |acc, i| acc + self.P[i] * T[(i, j)]))
            .collect();
        MassData {
            S_t: &self.S_t * T,
            S_rO: &self.S_rO * T,
            P,
            Q: self
                .Q
                .iter()
                .map(|row| row.iter().map(|q| T.transpose() * q * T).collect())
                .collect(),
        }
    }
}

// ------------------------------------------------------------------------------------ writing

/// Names usable as MBDyn node labels (no whitespace), unique.
fn labels(body: &ReducedBody) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for (i, p) in body.interfaces.iter().enumerate() {
        let mut l: String = p
            .name
            .chars()
            .map(|c| if c.is_whitespace() { '_' } else { c })
            .collect();
        if l.is_empty() || out.contains(&l) {
            l = format!("{l}_{i}");
        }
        out.push(l);
    }
    out
}

/// The text of the `.fem` file of `body`, with interface `reference` held (module docs).
///
/// # Errors
/// [`FemError::Body`] if `reference` is not an interface of the body.
pub fn to_mbdyn_fem(body: &ReducedBody, reference: usize, origin: &Path) -> Result<String, FemError> {
    use std::fmt::Write;
    let N = body.interfaces.len();
    if reference >= N {
        return Err(FemError::Body {
            path: origin.to_path_buf(),
            what: format!(
                "reference interface {reference} does not exist (the body '{}' has {N})",
                body.name
            ),
        });
    }
    let n = body.n_coordinates();
    let keep: Vec<usize> = (0..n).filter(|&j| j / 6 != reference || j >= 6 * N).collect();
    let x_r = Vector3::from(body.interfaces[reference].position);
    let inertia = &body.inertia;
    let c = Vector3::from(inertia.center_of_mass);
    let c_O = c - x_r;
    let S_t = dm(&inertia.S_t);
    let S_r = dm(&inertia.S_r);
    let S_x = dm(&inertia.S_x);
    let S_bar: Vec<DMatrix<f64>> = inertia.S_bar.iter().map(dm).collect();
    let K = dm(&body.K_CB);
    let M = dm(&body.M_CB);
    // Invariant 4 about the frame origin: S_r is about the centre of mass.
    let S_rO = &S_r + tilde_dyn(&c_O) * &S_t;
    // int rho S_j of the translational field, the field the second-order invariants integrate
    // (for beams not S_t, whose consistent mass couples translations and rotations): the
    // (b, b) entry of Q(T_b, S_j), T_b the rigid translation along b, which in Craig-Bampton
    // coordinates is 1 at every interface's translation b.
    let field_t = |j: usize| Vector3::from_fn(|b, _| (0..N).map(|i| S_bar[3 * b + b][(6 * i + b, j)]).sum());
    // P_j(k, l) = int rho x_k S_jl, x from O (S_x is about the centre of mass).
    let P = |j: usize| Matrix3::from_fn(|k, l| S_x[(3 * k + l, j)] + c_O[k] * field_t(j)[l]);
    let Q = |j: usize, k: usize| Matrix3::from_fn(|a, b| S_bar[3 * a + b][(j, k)]);

    let X2 = second_moment(body, x_r, &P);

    let field3: Vec<Vector3<f64>> = keep.iter().map(|&k| field_t(k)).collect();

    // int rho x about O of the translational field (for beams not m c, which the rotations'
    // inertia coupling enters): P(T_a)(k, a) with T_a the rigid translation along a.
    let first_moment = Vector3::from_fn(|k, _| {
        (0..3)
            .map(|a| (0..N).map(|i| P(6 * i + a)[(k, a)]).sum::<f64>())
            .sum::<f64>()
            / 3.0
    });

    // Writing to a String cannot fail: the writers ignore the results of `writeln!`.
    let mut f = String::new();
    write_flexmbs_lines(&mut f, body, reference, x_r, first_moment, &X2, &field3);
    write_geometry_records(&mut f, body, &keep, x_r);
    write_inertia_records(&mut f, body, x_r, &keep, [&M, &K, &S_t, &S_rO], &P, &Q);
    let _ = writeln!(f, "** END OF FILE");
    Ok(f)
}

/// $\int\rho\,\mathbf x\mathbf x^T$ about the frame origin `x_r` of the translational field,
/// from the moments `P` of the Craig-Bampton coordinates.
fn second_moment(body: &ReducedBody, x_r: Vector3<f64>, P: &dyn Fn(usize) -> Matrix3<f64>) -> Matrix3<f64> {
    // int rho x x^T about O of the translational field, from the rigid rotations written as
    // Craig-Bampton coordinates (rigid motion is exact in the constraint modes):
    // P(theta_alpha)(k, l) = eps_{l alpha j} X2_kj, so X2_kj = 1/2 sum eps_{l alpha j} P(k, l).
    let mut X2 = Matrix3::zeros();
    for al in 0..3 {
        let mut P_rot = Matrix3::zeros();
        for (i, p) in body.interfaces.iter().enumerate() {
            let e_al = Vector3::ith(al, 1.0);
            let u_i = e_al.cross(&(Vector3::from(p.position) - x_r));
            for a in 0..3 {
                P_rot += P(6 * i + a) * u_i[a];
            }
            P_rot += P(6 * i + 3 + al);
        }
        for k in 0..3 {
            for j in 0..3 {
                for l in 0..3 {
                    X2[(k, j)] += 0.5 * levi_civita(l, al, j) * P_rot[(k, l)];
                }
            }
        }
    }
    X2
}

/// A value as the file writes it: the shortest exponent form that reads back exactly.
fn e(v: f64) -> String {
    format!("{v:e}")
}

/// The `** FLEXMBS` comment lines: name, frame origin, first and second moments and the
/// translational field's invariant, which MBDyn skips and [`read_mbdyn_fem`] reads back.
fn write_flexmbs_lines(
    w: &mut String,
    body: &ReducedBody,
    reference: usize,
    x_r: Vector3<f64>,
    first_moment: Vector3<f64>,
    X2: &Matrix3<f64>,
    field3: &[Vector3<f64>],
) {
    use std::fmt::Write;
    let _ = writeln!(w, "** MBDyn MODAL DATA FILE");
    let _ = writeln!(
        w,
        "** written by flexmbs: Craig-Bampton body with interface '{}' held as the modal node's frame",
        body.interfaces[reference].name
    );
    let _ = writeln!(w, "** FLEXMBS BODY {}", body.name.replace(char::is_whitespace, "_"));
    let _ = writeln!(w, "** FLEXMBS ORIGIN {} {} {}", e(x_r.x), e(x_r.y), e(x_r.z));
    let X2_text: Vec<String> = X2.transpose().iter().map(|&v| e(v)).collect();
    let _ = writeln!(
        w,
        "** FLEXMBS FIRST MOMENT {} {} {}",
        e(first_moment.x),
        e(first_moment.y),
        e(first_moment.z)
    );
    let _ = writeln!(w, "** FLEXMBS SECOND MOMENT {}", X2_text.join(" "));
    // int rho S of the translational field, eight values a line (MBDyn reads comment lines
    // into a buffer of BUFSIZ characters).
    for a in 0..3 {
        for (chunk, cols) in field3.chunks(8).enumerate() {
            let values: Vec<String> = cols.iter().map(|v| e(v[a])).collect();
            let _ = writeln!(w, "** FLEXMBS FIELD INVARIANT 3 {a} {} {}", 8 * chunk, values.join(" "));
        }
    }
}

/// Records 1 to 8: header, node list, initial values, node coordinates from the frame
/// origin, and the mode shapes of the kept coordinates `keep`.
fn write_geometry_records(w: &mut String, body: &ReducedBody, keep: &[usize], x_r: Vector3<f64>) {
    use std::fmt::Write;
    let (N, nx) = (body.interfaces.len(), keep.len());
    let _ = writeln!(w, "** RECORD GROUP 1, HEADER");
    let _ = writeln!(
        w,
        "**   REVISION,  NODE,  NORMAL, ATTACHMENT, CONSTRAINT, REJECTED MODES."
    );
    let _ = writeln!(w, "      REV0 {N} {nx} 0 0 0");
    let _ = writeln!(w, "**");
    let _ = writeln!(w, "** RECORD GROUP 2, FINITE ELEMENT NODE LIST");
    let _ = writeln!(w, "{}", labels(body).join(" "));
    let _ = writeln!(w, "**");
    for (record, what) in [(3, "INITIAL MODAL DISPLACEMENTS"), (4, "INITIAL MODAL VELOCITIES")] {
        let _ = writeln!(w, "** RECORD GROUP {record}, {what}");
        let _ = writeln!(w, "{}", vec!["0"; nx].join(" "));
        let _ = writeln!(w, "**");
    }
    for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
        let _ = writeln!(w, "** RECORD GROUP {}, NODAL {axis} COORDINATES", 5 + k);
        for p in &body.interfaces {
            let _ = writeln!(w, "{}", e(p.position[k] - x_r[k]));
        }
        let _ = writeln!(w, "**");
    }
    let _ = writeln!(w, "** RECORD GROUP 8, MODE SHAPES");
    for (m, &j) in keep.iter().enumerate() {
        let _ = writeln!(w, "**    NORMAL MODE SHAPE #  {}", m + 1);
        for i in 0..N {
            // The Craig-Bampton basis at interface i: the identity on its own coordinates.
            let row: Vec<&str> = (0..6).map(|k| if j == 6 * i + k { "1" } else { "0" }).collect();
            let _ = writeln!(w, "{}", row.join(" "));
        }
    }
    let _ = writeln!(w, "**");
}

/// Records 9 to 18: modal mass and stiffness, global inertia and the invariants, with `A`
/// the matrices `M_CB`, `K_CB`, `S_t` and `S_r` about the frame origin.
fn write_inertia_records(
    w: &mut String,
    body: &ReducedBody,
    x_r: Vector3<f64>,
    keep: &[usize],
    A: [&DMatrix<f64>; 4],
    P: &dyn Fn(usize) -> Matrix3<f64>,
    Q: &dyn Fn(usize, usize) -> Matrix3<f64>,
) {
    use std::fmt::Write;
    let [M, K, S_t, S_rO] = A;
    let inertia = &body.inertia;
    let c_O = Vector3::from(inertia.center_of_mass) - x_r;
    let nx = keep.len();
    for (record, what, A) in [(9, "MODAL MASS MATRIX", M), (10, "MODAL STIFFNESS MATRIX", K)] {
        let _ = writeln!(w, "** RECORD GROUP {record}, {what}. COLUMN-MAJOR FORM");
        for &a in keep {
            let row: Vec<String> = keep.iter().map(|&b| e(A[(a, b)])).collect();
            let _ = writeln!(w, "{}", row.join(" "));
        }
        let _ = writeln!(w, "**");
    }
    let _ = writeln!(w, "** RECORD GROUP 12, GLOBAL INERTIA");
    let _ = writeln!(w, "{}", e(inertia.mass));
    let _ = writeln!(w, "{} {} {}", e(c_O.x), e(c_O.y), e(c_O.z));
    for row in &inertia.inertia_com {
        let _ = writeln!(w, "{} {} {}", e(row[0]), e(row[1]), e(row[2]));
    }
    let _ = writeln!(w, "**");
    for (record, what, A) in [(14, "INVARIANT 3", S_t), (15, "INVARIANT 4", S_rO)] {
        let _ = writeln!(w, "** RECORD GROUP {record}, {what}");
        for a in 0..3 {
            let row: Vec<String> = keep.iter().map(|&j| e(A[(a, j)])).collect();
            let _ = writeln!(w, "{}", row.join(" "));
        }
        let _ = writeln!(w, "**");
    }
    // Invariant 8: -int rho x~ S_j~ = tr(P_j) I - P_j^T.
    let _ = writeln!(w, "** RECORD GROUP 16, INVARIANT 8");
    for a in 0..3 {
        let mut row = Vec::with_capacity(3 * nx);
        for &j in keep {
            let Pj = P(j);
            let inv8 = Matrix3::identity() * Pj.trace() - Pj.transpose();
            row.extend((0..3).map(|b| e(inv8[(a, b)])));
        }
        let _ = writeln!(w, "{}", row.join(" "));
    }
    let _ = writeln!(w, "**");
    // Invariant 5: int rho S_j x S_k, from Q_jk(a, b) = int rho S_ja S_kb.
    let _ = writeln!(w, "** RECORD GROUP 17, INVARIANT 5");
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let mut row = Vec::with_capacity(nx * nx);
        for &j in keep {
            for &k in keep {
                let q = Q(j, k);
                row.push(e(q[(b, c)] - q[(c, b)]));
            }
        }
        let _ = writeln!(w, "{}", row.join(" "));
    }
    let _ = writeln!(w, "**");
    // Invariant 9: int rho S_j~ S_k~ = Q_kj - tr(Q_jk) I.
    let _ = writeln!(w, "** RECORD GROUP 18, INVARIANT 9");
    for a in 0..3 {
        let mut row = Vec::with_capacity(3 * nx * nx);
        for &j in keep {
            for &k in keep {
                let inv9 = Q(k, j) - Matrix3::identity() * Q(j, k).trace();
                row.extend((0..3).map(|b| e(inv9[(a, b)])));
            }
        }
        let _ = writeln!(w, "{}", row.join(" "));
    }
    let _ = writeln!(w, "**");
}

/// Writes `body` to `path` as an MBDyn `.fem` file with interface `reference` held.
pub fn write_mbdyn_fem(path: &Path, body: &ReducedBody, reference: usize) -> Result<(), FemError> {
    let text = to_mbdyn_fem(body, reference, path)?;
    std::fs::write(path, text).map_err(|source| FemError::Io {
        path: path.to_path_buf(),
        action: "write",
        source,
    })
}

// ------------------------------------------------------------------------------------ reading

/// The records of a `.fem` file, as read.
#[derive(Default)]
struct Records {
    n_nodes: usize,
    n_modes: usize,
    labels: Vec<String>,
    xyz: [Vec<f64>; 3],
    /// 6 n_nodes x n_modes: mode shapes at the exposed nodes.
    shapes: Option<DMatrix<f64>>,
    M: Option<DMatrix<f64>>,
    K: Option<DMatrix<f64>>,
    lumped: Option<Vec<[f64; 6]>>,
    global: Option<(f64, Vector3<f64>, Matrix3<f64>)>,
    inv3: Option<DMatrix<f64>>,
    inv4: Option<DMatrix<f64>>,
    inv8: Option<Vec<Matrix3<f64>>>,
    inv9: Option<Vec<Vec<Matrix3<f64>>>>,
    name: Option<String>,
    origin: Vector3<f64>,
    /// int rho x x^T about the frame origin (translational field), if the file gives it.
    second_moment: Option<Matrix3<f64>>,
    /// int rho x about the frame origin (translational field), if the file gives it.
    first_moment: Option<Vector3<f64>>,
    /// int rho S of the translational field of each mode, as far as the file gives it.
    field3: Vec<(usize, usize, f64)>,
    seen: Vec<u32>,
}

/// A record as split from the text: its number, its header line, its values with their lines.
type RawRecord<'a> = (u32, usize, Vec<(usize, &'a str)>);

/// Whitespace-separated values of one record, with their lines.
struct Tokens<'a> {
    path: &'a Path,
    record: u32,
    items: Vec<(usize, &'a str)>,
    at: usize,
    /// Line of the record header, for a record that ends too early.
    header_line: usize,
}

impl<'a> Tokens<'a> {
    /// The error for `found` at `line` where `expected` was.
    fn malformed(&self, line: usize, expected: String, found: String) -> FemError {
        FemError::Malformed {
            path: self.path.to_path_buf(),
            line,
            record: self.record,
            expected,
            found,
        }
    }

    /// The first 40 characters of the value `t`, for a message.
    fn found(t: &str) -> String {
        t.chars().take(40).collect()
    }

    fn next(&mut self, expected: &str) -> Result<(usize, &'a str), FemError> {
        match self.items.get(self.at) {
            Some(&item) => {
                self.at += 1;
                Ok(item)
            }
            None => Err(self.malformed(
                self.items.last().map_or(self.header_line, |i| i.0),
                expected.to_string(),
                "the end of the record".into(),
            )),
        }
    }

    /// The next value parsed as a `T` that `valid` accepts.
    fn parsed<T: std::str::FromStr>(&mut self, expected: &str, valid: impl Fn(&T) -> bool) -> Result<T, FemError> {
        let (line, t) = self.next(expected)?;
        t.parse::<T>()
            .ok()
            .filter(valid)
            .ok_or_else(|| self.malformed(line, expected.to_string(), Self::found(t)))
    }

    fn real(&mut self, expected: &str) -> Result<f64, FemError> {
        self.parsed(expected, |v: &f64| v.is_finite())
    }

    fn count(&mut self, expected: &str) -> Result<usize, FemError> {
        self.parsed(expected, |&v: &usize| v <= 1_000_000)
    }

    fn matrix(&mut self, rows: usize, cols: usize, expected: &str) -> Result<DMatrix<f64>, FemError> {
        let mut m = DMatrix::zeros(rows, cols);
        for i in 0..rows {
            for j in 0..cols {
                m[(i, j)] = self.real(expected)?;
            }
        }
        Ok(m)
    }

    /// No values may be left over.
    fn done(&self) -> Result<(), FemError> {
        match self.items.get(self.at) {
            None => Ok(()),
            Some(&(line, t)) => Err(self.malformed(
                line,
                "the end of the record (the header's counts give its size)".into(),
                Self::found(t),
            )),
        }
    }
}

/// Reads the `.fem` file at `path` as a reduced body with `interfaces` (labels of exposed
/// nodes; `None`: every exposed node), which passes the physical checks ([`crate::checks`]).
pub fn read_mbdyn_fem(path: &Path, interfaces: Option<&[String]>) -> Result<(ReducedBody, Vec<String>), FemError> {
    checked(read_mbdyn_fem_unchecked(path, interfaces)?, path)
}

/// [`read_mbdyn_fem`] without refusing a body that fails the physical checks: the body, the
/// notes, and the problems of the records as written (for `flexmbs inspect`, which reports
/// them with those of the body).
pub fn read_mbdyn_fem_unchecked(path: &Path, interfaces: Option<&[String]>) -> Result<FemBody, FemError> {
    let bytes = fe_model::input::read(path).map_err(|source| FemError::Io {
        path: path.to_path_buf(),
        action: "read",
        source,
    })?;
    parse_mbdyn_fem_unchecked(&bytes, path, interfaces)
}

/// A body read from a `.fem` file before the checks.
#[derive(Clone, Debug)]
pub struct FemBody {
    pub body: ReducedBody,
    /// What was approximated (records missing, taken as MBDyn takes them).
    pub notes: Vec<String>,
    /// The problems of the records as written: records 9 and 10 symmetric, record 12 against
    /// the nodal masses of record 11 and against the `FLEXMBS` first moment.
    pub problems: Vec<PhysicsProblem>,
    /// The record checks that could not be made, each with the reason (a record 12 without
    /// the record 11 to compare it with), for `flexmbs inspect` to say so.
    pub not_checked: Vec<String>,
}

/// The body and notes of `read`, refused (naming `origin`) when the records or the body fail
/// the physical checks.
fn checked(read: FemBody, origin: &Path) -> Result<(ReducedBody, Vec<String>), FemError> {
    let FemBody {
        body,
        notes,
        mut problems,
        ..
    } = read;
    problems.extend(crate::checks::physical_problems(&body));
    if problems.is_empty() {
        Ok((body, notes))
    } else {
        Err(BodyCheckError::Refused {
            body: body.name.clone(),
            file: origin.to_path_buf(),
            problems,
        }
        .into())
    }
}

/// Parses the text of a `.fem` file into a reduced body (module docs) and the notes on what
/// was approximated; `origin` names the file in errors. The body passes the physical checks.
/// Never panics.
pub fn parse_mbdyn_fem(
    bytes: &[u8],
    origin: &Path,
    interfaces: Option<&[String]>,
) -> Result<(ReducedBody, Vec<String>), FemError> {
    checked(parse_mbdyn_fem_unchecked(bytes, origin, interfaces)?, origin)
}

/// [`parse_mbdyn_fem`] without refusing a body that fails the physical checks (see
/// [`read_mbdyn_fem_unchecked`]).
pub fn parse_mbdyn_fem_unchecked(
    bytes: &[u8],
    origin: &Path,
    interfaces: Option<&[String]>,
) -> Result<FemBody, FemError> {
    let text = String::from_utf8_lossy(bytes);
    let structure = |line: usize, what: String| FemError::Structure {
        path: origin.to_path_buf(),
        line,
        what,
    };
    let (records, mut r) = split_records(&text, origin)?;
    let mut notes = Vec::new();
    for (number, header_line, items) in records {
        if r.seen.contains(&number) {
            return Err(structure(header_line, format!("RECORD GROUP {number} is given twice")));
        }
        if number != 1 && !r.seen.contains(&1) {
            return Err(structure(
                header_line,
                format!("RECORD GROUP {number} comes before RECORD GROUP 1 (the header)"),
            ));
        }
        r.seen.push(number);
        let mut tk = Tokens {
            path: origin,
            record: number,
            items,
            at: 0,
            header_line,
        };
        read_record(&mut r, &mut tk, &mut notes)?;
        tk.done()?;
    }
    for (needed, what) in [
        (1, "header"),
        (2, "node list"),
        (5, "X coordinates"),
        (6, "Y coordinates"),
        (7, "Z coordinates"),
        (8, "mode shapes"),
        (9, "modal mass"),
        (10, "modal stiffness"),
    ] {
        if !r.seen.contains(&needed) {
            return Err(structure(
                text.lines().count(),
                format!("RECORD GROUP {needed} ({what}) is missing"),
            ));
        }
    }
    build_body(r, origin, interfaces, notes)
}

/// The text split into records (number, header line, value tokens with their lines), and the
/// `FLEXMBS` comment lines read into `Records`.
fn split_records<'a>(text: &'a str, origin: &Path) -> Result<(Vec<RawRecord<'a>>, Records), FemError> {
    let structure = |line: usize, what: String| FemError::Structure {
        path: origin.to_path_buf(),
        line,
        what,
    };
    // Split into records: (number, header line, value tokens with lines).
    let mut records: Vec<RawRecord<'_>> = Vec::new();
    let mut r = Records::default();
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let t = line.trim();
        if let Some(rest) = t.strip_prefix("** RECORD GROUP ") {
            let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
            let number: u32 = digits
                .parse()
                .map_err(|_| structure(n, format!("cannot read the record number of '{}'", excerpt(t))))?;
            records.push((number, n, Vec::new()));
        } else if t.starts_with("** END OF FILE") {
            break;
        } else if let Some(rest) = t.strip_prefix("** FLEXMBS ") {
            read_flexmbs_line(&mut r, rest, t, n, origin)?;
        } else if t.starts_with("**") || t.is_empty() {
            continue;
        } else if let Some(last) = records.last_mut() {
            last.2.extend(t.split_whitespace().map(|w| (n, w)));
        } else {
            return Err(structure(
                n,
                format!("data before the first RECORD GROUP: '{}'", excerpt(t)),
            ));
        }
    }
    Ok((records, r))
}

/// A `** FLEXMBS` comment line `t` (line `n`, `rest` after the prefix) into `r`.
fn read_flexmbs_line(r: &mut Records, rest: &str, t: &str, n: usize, origin: &Path) -> Result<(), FemError> {
    let structure = |line: usize, what: String| FemError::Structure {
        path: origin.to_path_buf(),
        line,
        what,
    };
    let words: Vec<&str> = rest.split_whitespace().collect();
    match words.as_slice() {
        ["BODY", name] => r.name = Some(name.to_string()),
        ["FIRST", "MOMENT", values @ ..] => {
            let v: Vec<f64> = values.iter().filter_map(|s| s.parse().ok()).collect();
            if v.len() != 3 || v.iter().any(|c: &f64| !c.is_finite()) {
                return Err(structure(
                    n,
                    format!("cannot read the first moment in '{}'", excerpt(t)),
                ));
            }
            r.first_moment = Some(Vector3::new(v[0], v[1], v[2]));
        }
        ["SECOND", "MOMENT", values @ ..] => {
            let v: Vec<f64> = values.iter().filter_map(|s| s.parse().ok()).collect();
            if v.len() != 9 || v.iter().any(|c: &f64| !c.is_finite()) {
                return Err(structure(
                    n,
                    format!("cannot read the second moment in '{}'", excerpt(t)),
                ));
            }
            r.second_moment = Some(Matrix3::from_row_slice(&v));
        }
        ["FIELD", "INVARIANT", "3", a, first, values @ ..] => {
            let (Ok(a), Ok(first)) = (a.parse::<usize>(), first.parse::<usize>()) else {
                return Err(structure(n, format!("cannot read '{}'", excerpt(t))));
            };
            for (k, v) in values.iter().enumerate() {
                match v.parse::<f64>() {
                    Ok(v) if v.is_finite() && a < 3 => r.field3.push((a, first + k, v)),
                    _ => return Err(structure(n, format!("cannot read '{}'", excerpt(t)))),
                }
            }
        }
        ["ORIGIN", x, y, z] => {
            let v: Vec<f64> = [x, y, z].iter().filter_map(|s| s.parse().ok()).collect();
            if v.len() != 3 || v.iter().any(|c: &f64| !c.is_finite()) {
                return Err(structure(n, format!("cannot read the origin in '{}'", excerpt(t))));
            }
            r.origin = Vector3::new(v[0], v[1], v[2]);
        }
        _ => {}
    }
    Ok(())
}

/// The values of one record into `r` (the header's counts give the sizes of the others).
fn read_record(r: &mut Records, tk: &mut Tokens<'_>, notes: &mut Vec<String>) -> Result<(), FemError> {
    let (number, header_line, path) = (tk.record, tk.header_line, tk.path);
    let structure = |line: usize, what: String| FemError::Structure {
        path: path.to_path_buf(),
        line,
        what,
    };
    let (nn, nm) = (r.n_nodes, r.n_modes);
    match number {
        1 => {
            tk.next("the revision (REV0)")?;
            r.n_nodes = tk.count("the number of nodes")?;
            let normal = tk.count("the number of normal modes")?;
            let attached = tk.count("the number of attached modes")?;
            let constraint = tk.count("the number of constraint modes")?;
            let rejected = tk.count("the number of rejected modes")?;
            if rejected > 0 {
                return Err(structure(
                    header_line,
                    "rejected modes (NREJECTED > 0) are not read".into(),
                ));
            }
            r.n_modes = normal + attached + constraint;
            if r.n_nodes == 0 {
                return Err(structure(header_line, "the file has no nodes".into()));
            }
        }
        2 => {
            for _ in 0..nn {
                r.labels.push(tk.next("a node label")?.1.to_string());
            }
        }
        3 | 4 => {
            for _ in 0..nm {
                if tk.real("an initial modal value")? != 0.0 && number == 3 {
                    notes.push("the initial modal displacements (RECORD GROUP 3) are not used".to_string());
                }
            }
        }
        5..=7 => {
            let axis = (number - 5) as usize;
            for _ in 0..nn {
                let v = tk.real("a node coordinate")?;
                r.xyz[axis].push(v);
            }
        }
        8 => {
            let mut s = DMatrix::zeros(6 * nn, nm);
            for j in 0..nm {
                for i in 0..6 * nn {
                    s[(i, j)] = tk.real("a mode shape value")?;
                }
            }
            r.shapes = Some(s);
        }
        9 => r.M = Some(tk.matrix(nm, nm, "a modal mass value")?),
        10 => r.K = Some(tk.matrix(nm, nm, "a modal stiffness value")?),
        11 => {
            let mut lumped = Vec::with_capacity(nn);
            for _ in 0..nn {
                let mut v = [0.0; 6];
                for x in v.iter_mut() {
                    *x = tk.real("a lumped mass value")?;
                }
                lumped.push(v);
            }
            r.lumped = Some(lumped);
        }
        12 => {
            let m = tk.real("the mass")?;
            let c = Vector3::new(tk.real("x_cg")?, tk.real("y_cg")?, tk.real("z_cg")?);
            let J = tk.matrix(3, 3, "an inertia value")?;
            let J = Matrix3::from_fn(|i, j| J[(i, j)]);
            r.global = Some((m, c, J));
        }
        13 => {
            tk.matrix(nm, nm, "a modal damping value")?;
            notes.push("the modal damping (RECORD GROUP 13) is not used".to_string());
        }
        14 => r.inv3 = Some(tk.matrix(3, nm, "a value of invariant 3")?),
        15 => r.inv4 = Some(tk.matrix(3, nm, "a value of invariant 4")?),
        16 => {
            let mut v = vec![Matrix3::zeros(); nm];
            for a in 0..3 {
                for m in v.iter_mut() {
                    for b in 0..3 {
                        m[(a, b)] = tk.real("a value of invariant 8")?;
                    }
                }
            }
            r.inv8 = Some(v);
        }
        17 => {
            // Invariant 5 is the antisymmetric part of what invariant 9 gives; read to check its size.
            tk.matrix(3, nm * nm, "a value of invariant 5")?;
        }
        18 => {
            let mut v = vec![vec![Matrix3::zeros(); nm]; nm];
            for a in 0..3 {
                for row in v.iter_mut() {
                    for m in row.iter_mut() {
                        for b in 0..3 {
                            m[(a, b)] = tk.real("a value of invariant 9")?;
                        }
                    }
                }
            }
            r.inv9 = Some(v);
        }
        19 => {
            notes.push("the stress stiffening matrices (RECORD GROUP 19) are not used".to_string());
            tk.at = tk.items.len();
        }
        other => {
            return Err(structure(
                header_line,
                format!("RECORD GROUP {other} is not a record of the format (1-19)"),
            ));
        }
    }
    Ok(())
}

fn excerpt(t: &str) -> String {
    t.chars().take(40).collect()
}

/// The reduced body of the records (module docs).
fn build_body(
    r: Records,
    origin: &Path,
    interfaces: Option<&[String]>,
    mut notes: Vec<String>,
) -> Result<FemBody, FemError> {
    let body_error = |what: String| FemError::Body {
        path: origin.to_path_buf(),
        what,
    };
    let (nn, nx) = (r.n_nodes, r.n_modes);
    let y: Vec<Vector3<f64>> = (0..nn)
        .map(|i| Vector3::new(r.xyz[0][i], r.xyz[1][i], r.xyz[2][i]))
        .collect();
    let shapes = r.shapes.clone().unwrap_or_else(|| DMatrix::zeros(6 * nn, nx));
    let M_x = r.M.clone().unwrap_or_else(|| DMatrix::zeros(nx, nx));
    let K_x = r.K.clone().unwrap_or_else(|| DMatrix::zeros(nx, nx));
    let modal = modal_inertia(&r, &y, &shapes, &mut notes, &body_error)?;
    let rigid = RigidMoments::new(&r, &modal);
    // The records as written: the body below is built from their symmetric parts.
    let mut problems: Vec<PhysicsProblem> = [("record 9 (modal mass)", &M_x), ("record 10 (modal stiffness)", &K_x)]
        .into_iter()
        .filter_map(|(name, A)| crate::checks::symmetry_problem(name, A).1)
        .collect();
    problems.extend(crate::checks::stated_moment_problems(
        modal.m,
        &modal.c_O,
        &rigid.J_O,
        r.first_moment.as_ref(),
    ));
    let (nodal_problems, not_checked) = record_12_against_nodal_masses(&r, &y);
    problems.extend(nodal_problems);
    let (M_a, K_a) = joint_matrices(&modal, &rigid, &M_x, &K_x);
    let data = joint_mass_data(&modal, &rigid);

    // Interfaces: the chosen exposed nodes.
    let chosen = chosen_nodes(&r.labels, interfaces, nn, &body_error)?;
    let na = 6 + nx;
    let nb = 6 * chosen.len();
    if nb > na {
        return Err(body_error(format!(
            "{} interfaces need {nb} coordinates, but the rigid motions and {nx} modes give {na}",
            chosen.len()
        )));
    }
    let B = interface_values(&chosen, &y, &shapes, nx);
    let (mut T_b, Z) = interface_null_space(&B, &body_error)?;
    let (omega, V) = fixed_interface_modes(&Z, &K_a, &M_a, &mut T_b, &body_error)?;
    let nz = Z.ncols();
    let mut T = DMatrix::zeros(na, nb + nz);
    T.view_mut((0, 0), (na, nb)).copy_from(&T_b);
    if nz > 0 {
        T.view_mut((0, nb), (na, nz)).copy_from(&(&Z * &V));
    }
    let sym = |A: DMatrix<f64>| (&A + A.transpose()) * 0.5;
    let K_CB = sym(T.transpose() * &K_a * &T);
    let M_CB = sym(T.transpose() * &M_a * &T);
    let (inertia, Phi_com) = reduced_inertia(&data, &T, &modal, &rigid, r.origin, &body_error)?;
    let name = r.name.clone().unwrap_or_else(|| {
        origin
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "mbdyn".into())
    });
    let body = ReducedBody {
        format_version: FORMAT_VERSION,
        name,
        interfaces: chosen
            .iter()
            .map(|&i| InterfacePoint {
                name: r.labels[i].clone(),
                node: i as u32,
                position: (y[i] + r.origin).into(),
                node_label: None,
            })
            .collect(),
        n_modes: nz,
        fixed_interface_omega: omega,
        K_CB: dense(&K_CB),
        M_CB: dense(&M_CB),
        inertia,
        Phi_com: dense(&Phi_com),
        auxiliary_interface: None,
        mesh: None,
        geometric_stiffness: None,
        stress: None,
        load_points: Vec::new(),
        attachment_modes: 0,
    };
    // A file from another code whose record 12 nothing checks: its notes say so, so that a
    // study loading it warns (inspect reports `not_checked` for every file). A file written by
    // flexmbs has its mass and centre checked by the FIRST MOMENT line, and its inertia is a
    // reduction of ours.
    if r.first_moment.is_none() {
        notes.extend(not_checked.iter().cloned());
    }
    Ok(FemBody {
        body,
        notes,
        problems,
        not_checked,
    })
}

/// Record 12 against the rigid-body mass data of the nodal masses of record 11 at the
/// undeformed node positions ([`crate::checks::record_12_problems`]); without record 11, the
/// reason the comparison was not made.
fn record_12_against_nodal_masses(r: &Records, y: &[Vector3<f64>]) -> (Vec<PhysicsProblem>, Vec<String>) {
    let Some((m, c_O, J)) = r.global else {
        // The mass data are record 11's own: nothing to compare.
        return (Vec::new(), Vec::new());
    };
    let Some(lumped) = &r.lumped else {
        let partly = if r.first_moment.is_some() {
            "its mass and centre of mass are checked against the FLEXMBS FIRST MOMENT line only, its inertia not at all"
        } else {
            "its mass, centre of mass and inertia are not checked"
        };
        return (
            Vec::new(),
            vec![format!(
                "record 12 (rigid-body inertia) was not compared with nodal masses: the file has no record 11; {partly}"
            )],
        );
    };
    let nodal = lumped_rigid(lumped, y);
    // The body's size: the farthest node with mass from the nodal centre of mass, or the
    // radius of gyration.
    let size = lumped
        .iter()
        .zip(y)
        .filter(|(l, _)| l[0] != 0.0)
        .map(|(_, y)| (y - nodal.1).norm())
        .fold(
            (nodal.2.trace().abs() / nodal.0.abs().max(f64::MIN_POSITIVE)).sqrt(),
            f64::max,
        );
    (
        crate::checks::record_12_problems((m, &c_O, &J), (nodal.0, &nodal.1, &nodal.2), size),
        Vec::new(),
    )
}

/// Mass data about the frame origin $O$ summed from the lumped masses at the exposed nodes
/// (record 11), as MBDyn does without records 12 and 14-18.
struct LumpedData {
    /// $(m, \mathbf c_O, \mathbf J_{com})$, as record 12 gives them.
    global: (f64, Vector3<f64>, Matrix3<f64>),
    inv3: DMatrix<f64>,
    inv4: DMatrix<f64>,
    P: Vec<Matrix3<f64>>,
    Q: Vec<Vec<Matrix3<f64>>>,
}

/// $(m, \mathbf c_O, \mathbf J_{com})$ of the nodal masses of record 11 at the undeformed
/// node positions `y` (from the frame origin $O$): point masses with their diagonal rotational
/// inertias.
fn lumped_rigid(lumped: &[[f64; 6]], y: &[Vector3<f64>]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let mut m = 0.0;
    let mut first = Vector3::zeros();
    let mut J_O = Matrix3::zeros();
    for (l, y) in lumped.iter().zip(y) {
        m += l[0];
        first += y * l[0];
        J_O += Matrix3::from_diagonal(&Vector3::new(l[3], l[4], l[5])) - tilde(y) * tilde(y) * l[0];
    }
    let c_O = first / m.max(f64::MIN_POSITIVE);
    (m, c_O, J_O + tilde(&c_O) * tilde(&c_O) * m)
}

fn lumped_data(lumped: &[[f64; 6]], y: &[Vector3<f64>], shapes: &DMatrix<f64>, nx: usize) -> LumpedData {
    let mut inv3 = DMatrix::zeros(3, nx);
    let mut inv4 = DMatrix::zeros(3, nx);
    let mut P = vec![Matrix3::zeros(); nx];
    let mut Q = vec![vec![Matrix3::zeros(); nx]; nx];
    for (i, l) in lumped.iter().enumerate() {
        let (mi, Ji) = (l[0], Matrix3::from_diagonal(&Vector3::new(l[3], l[4], l[5])));
        let phi_t = |j: usize| Vector3::new(shapes[(6 * i, j)], shapes[(6 * i + 1, j)], shapes[(6 * i + 2, j)]);
        let phi_r = |j: usize| Vector3::new(shapes[(6 * i + 3, j)], shapes[(6 * i + 4, j)], shapes[(6 * i + 5, j)]);
        for j in 0..nx {
            let t = phi_t(j);
            let v4 = tilde(&y[i]) * t * mi + Ji * phi_r(j);
            for a in 0..3 {
                inv3[(a, j)] += mi * t[a];
                inv4[(a, j)] += v4[a];
            }
            P[j] += y[i] * t.transpose() * mi;
            for k in 0..nx {
                Q[j][k] += t * phi_t(k).transpose() * mi;
            }
        }
    }
    LumpedData {
        global: lumped_rigid(lumped, y),
        inv3,
        inv4,
        P,
        Q,
    }
}

/// The body's mass and the modes' mass data about the frame origin $O$, from records 12 and
/// 14-18, or from the lumped masses of record 11; what is missing is zero (with a note).
struct ModalInertia {
    m: f64,
    /// Centre of mass from $O$.
    c_O: Vector3<f64>,
    J_com: Matrix3<f64>,
    /// Invariants 3 and 4 ($3 \times n_x$).
    inv3: DMatrix<f64>,
    inv4: DMatrix<f64>,
    /// $\mathbf P_j = \int\rho\,\mathbf x\mathbf S_j^T$ and $\mathbf Q_{jk} = \int\rho\,\mathbf S_j\mathbf S_k^T$ of the modes.
    P: Vec<Matrix3<f64>>,
    Q: Vec<Vec<Matrix3<f64>>>,
    /// $\int\rho\,\mathbf S$ of the translational field ($3 \times n_x$).
    field3: DMatrix<f64>,
}

fn modal_inertia(
    r: &Records,
    y: &[Vector3<f64>],
    shapes: &DMatrix<f64>,
    notes: &mut Vec<String>,
    body_error: &dyn Fn(String) -> FemError,
) -> Result<ModalInertia, FemError> {
    let nx = r.n_modes;
    // Mass data about the frame origin O: from records 12, 14-18, or from the lumped masses.
    let lumped_data = r.lumped.as_ref().map(|lumped| lumped_data(lumped, y, shapes, nx));
    let (m, c_O, J_com) = match (&r.global, &lumped_data) {
        (Some(g), _) => *g,
        (None, Some(d)) => d.global,
        (None, None) => {
            return Err(body_error(
                "the file has no inertia: neither RECORD GROUP 12 (global inertia) nor 11 (lumped masses)".into(),
            ))
        }
    };
    if !(m > 0.0) {
        return Err(body_error(format!("the mass is {m:e}; a body needs a positive mass")));
    }
    let inv3 = r.inv3.clone().or_else(|| lumped_data.as_ref().map(|d| d.inv3.clone()));
    let inv4 = r.inv4.clone().or_else(|| lumped_data.as_ref().map(|d| d.inv4.clone()));
    let P = match (&r.inv8, &lumped_data) {
        // P_j^T = tr(P_j) I - Inv8_j, with tr(P_j) = tr(Inv8_j) / 2.
        (Some(inv8), _) => inv8
            .iter()
            .map(|v| (Matrix3::identity() * (v.trace() / 2.0) - v).transpose())
            .collect(),
        (None, Some(d)) => d.P.clone(),
        (None, None) => vec![Matrix3::zeros(); nx],
    };
    let Q = match (&r.inv9, &lumped_data) {
        // Inv9_jk = Q_kj - tr(Q_jk) I: Q_kj = Inv9_jk - tr(Inv9_jk) / 2 I.
        (Some(inv9), _) => (0..nx)
            .map(|j| {
                (0..nx)
                    .map(|k| inv9[k][j] - Matrix3::identity() * (inv9[k][j].trace() / 2.0))
                    .collect()
            })
            .collect(),
        (None, Some(d)) => d.Q.clone(),
        (None, None) => vec![vec![Matrix3::zeros(); nx]; nx],
    };
    if inv3.is_none() || inv4.is_none() {
        notes.push("invariants 3 and 4 (RECORD GROUPS 14, 15) are missing: taken as zero, as MBDyn does (right for free-free normal modes)".into());
    }
    if r.inv8.is_none() && lumped_data.is_none() {
        notes.push("invariant 8 (RECORD GROUP 16) is missing: taken as zero, as MBDyn does".into());
    }
    if r.inv9.is_none() && lumped_data.is_none() {
        notes.push("invariant 9 (RECORD GROUP 18) is missing: taken as zero, as MBDyn does".into());
    }
    let inv3 = inv3.unwrap_or_else(|| DMatrix::zeros(3, nx));
    let inv4 = inv4.unwrap_or_else(|| DMatrix::zeros(3, nx));
    // int rho S of the translational field: the FLEXMBS lines, else invariant 3.
    let mut field3 = inv3.clone();
    for &(a, k, v) in &r.field3 {
        if k < nx {
            field3[(a, k)] = v;
        }
    }
    Ok(ModalInertia {
        m,
        c_O,
        J_com,
        inv3,
        inv4,
        P,
        Q,
        field3,
    })
}

/// The rigid body's moments about the frame origin $O$: $\mathbf J_O$, and of the
/// translational field $\int\rho\,\mathbf x$ (`X1`) and $\int\rho\,\mathbf x\mathbf x^T$ (`X2`).
struct RigidMoments {
    J_O: Matrix3<f64>,
    X1: Vector3<f64>,
    X2: Matrix3<f64>,
}

impl RigidMoments {
    fn new(r: &Records, modal: &ModalInertia) -> RigidMoments {
        let (m, c_O) = (modal.m, modal.c_O);
        let J_O = modal.J_com - tilde(&c_O) * tilde(&c_O) * m;
        // int rho x x^T about O (translational field): from the file, or from J_O (which includes
        // any rotary inertia of beam sections).
        let X2 = r
            .second_moment
            .unwrap_or_else(|| Matrix3::identity() * (J_O.trace() / 2.0) - J_O);
        let X1 = r.first_moment.unwrap_or(c_O * m);
        RigidMoments { J_O, X1, X2 }
    }
}

/// Mass and stiffness of the joint basis [rigid motions of the frame (t, theta about O),
/// modes]: $n_a = 6 + n_x$ columns.
fn joint_matrices(
    modal: &ModalInertia,
    rigid: &RigidMoments,
    M_x: &DMatrix<f64>,
    K_x: &DMatrix<f64>,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let (m, c_O, J_O) = (modal.m, modal.c_O, rigid.J_O);
    let (inv3, inv4) = (&modal.inv3, &modal.inv4);
    let nx = M_x.nrows();
    let na = 6 + nx;
    let mut M_a = DMatrix::zeros(na, na);
    let mut K_a = DMatrix::zeros(na, na);
    for a in 0..3 {
        M_a[(a, a)] = m;
        for b in 0..3 {
            M_a[(a, 3 + b)] = -m * tilde(&c_O)[(a, b)];
            M_a[(3 + a, b)] = m * tilde(&c_O)[(a, b)];
            M_a[(3 + a, 3 + b)] = J_O[(a, b)];
        }
        for j in 0..nx {
            M_a[(a, 6 + j)] = inv3[(a, j)];
            M_a[(6 + j, a)] = inv3[(a, j)];
            M_a[(3 + a, 6 + j)] = inv4[(a, j)];
            M_a[(6 + j, 3 + a)] = inv4[(a, j)];
        }
    }
    M_a.view_mut((6, 6), (nx, nx)).copy_from(M_x);
    K_a.view_mut((6, 6), (nx, nx)).copy_from(K_x);
    (M_a, K_a)
}

/// The [`MassData`] of the joint basis (see [`joint_matrices`]).
fn joint_mass_data(modal: &ModalInertia, rigid: &RigidMoments) -> MassData {
    let (m, c_O) = (modal.m, modal.c_O);
    let (J_O, X1, X2) = (rigid.J_O, rigid.X1, rigid.X2);
    let (inv3, inv4, P, field3) = (&modal.inv3, &modal.inv4, &modal.P, &modal.field3);
    let nx = P.len();
    let na = 6 + nx;
    let mut S_t = DMatrix::zeros(3, na);
    let mut S_rO = DMatrix::zeros(3, na);
    let mut Pa = vec![Matrix3::zeros(); na];
    for a in 0..3 {
        S_t[(a, a)] = m;
        for b in 0..3 {
            S_t[(a, 3 + b)] = -m * tilde(&c_O)[(a, b)];
            S_rO[(a, b)] = m * tilde(&c_O)[(a, b)];
            S_rO[(a, 3 + b)] = J_O[(a, b)];
        }
        for j in 0..nx {
            S_t[(a, 6 + j)] = inv3[(a, j)];
            S_rO[(a, 6 + j)] = inv4[(a, j)];
        }
    }
    // P for the rigid columns: t_alpha: m c e_alpha^T; theta_alpha: P(k, l) = eps_{l alpha j} X2_kj.
    for al in 0..3 {
        Pa[al] = Matrix3::from_fn(|k, l| if l == al { X1[k] } else { 0.0 });
        Pa[3 + al] = Matrix3::from_fn(|k, l| (0..3).map(|j| levi_civita(l, al, j) * X2[(k, j)]).sum());
    }
    Pa[6..].copy_from_slice(P);
    // Q(c1, c2)(a, b) = int rho S_c1,a S_c2,b.
    let field_rigid = |col: usize| -> Box<dyn Fn(usize, usize) -> f64> {
        // Returns, for a rigid column and component a, the coefficient of x_j (j < 3) or of 1 (j = 3).
        if col < 3 {
            Box::new(move |a, j| if j == 3 && a == col { 1.0 } else { 0.0 })
        } else {
            let al = col - 3;
            Box::new(move |a, j| if j < 3 { levi_civita(a, al, j) } else { 0.0 })
        }
    };
    let mut Qa = vec![vec![DMatrix::zeros(na, na); 3]; 3];
    // Moments of the field "1" and "x_j": m, m c, X2.
    let moment = |i: usize, j: usize| -> f64 {
        match (i, j) {
            (3, 3) => m,
            (3, j) | (j, 3) => X1[j],
            (i, j) => X2[(i, j)],
        }
    };
    for c1 in 0..6 {
        let f1 = field_rigid(c1);
        for c2 in 0..6 {
            let f2 = field_rigid(c2);
            for a in 0..3 {
                for b in 0..3 {
                    let mut v = 0.0;
                    for i in 0..4 {
                        for j in 0..4 {
                            let (p, q) = (f1(a, i), f2(b, j));
                            if p != 0.0 && q != 0.0 {
                                v += p * q * moment(i, j);
                            }
                        }
                    }
                    Qa[a][b][(c1, c2)] = v;
                }
            }
        }
        // Rigid column c1 with mode k: int rho S_c1,a S_kb = sum_i f1(a, i) * (moment of x_i with S_kb).
        for k in 0..nx {
            for a in 0..3 {
                for b in 0..3 {
                    let mut v = 0.0;
                    for i in 0..4 {
                        let p = f1(a, i);
                        if p != 0.0 {
                            v += p * if i == 3 { field3[(b, k)] } else { P[k][(i, b)] };
                        }
                    }
                    Qa[a][b][(c1, 6 + k)] = v;
                    Qa[b][a][(6 + k, c1)] = v;
                }
            }
        }
    }
    for j in 0..nx {
        for k in 0..nx {
            for a in 0..3 {
                for b in 0..3 {
                    Qa[a][b][(6 + j, 6 + k)] = modal.Q[j][k][(a, b)];
                }
            }
        }
    }
    MassData {
        S_t,
        S_rO,
        P: Pa,
        Q: Qa,
    }
}

/// The exposed nodes that become interfaces: those labelled `interfaces`, else all.
fn chosen_nodes(
    labels: &[String],
    interfaces: Option<&[String]>,
    nn: usize,
    body_error: &dyn Fn(String) -> FemError,
) -> Result<Vec<usize>, FemError> {
    match interfaces {
        None => Ok((0..nn).collect()),
        Some(names) => names
            .iter()
            .map(|name| {
                labels.iter().position(|l| l == name).ok_or_else(|| {
                    body_error(format!(
                        "no exposed node is labelled '{name}' (labels: {})",
                        labels.join(", ")
                    ))
                })
            })
            .collect(),
    }
}

/// $\mathbf B$: the interface values ($6 N \times n_a$) of the joint basis.
fn interface_values(chosen: &[usize], y: &[Vector3<f64>], shapes: &DMatrix<f64>, nx: usize) -> DMatrix<f64> {
    let nb = 6 * chosen.len();
    let mut B = DMatrix::zeros(nb, 6 + nx);
    for (q, &i) in chosen.iter().enumerate() {
        for a in 0..3 {
            B[(6 * q + a, a)] = 1.0;
            B[(6 * q + 3 + a, 3 + a)] = 1.0;
            for b in 0..3 {
                B[(6 * q + a, 3 + b)] = -tilde(&y[i])[(a, b)];
            }
        }
        for j in 0..nx {
            for d in 0..6 {
                B[(6 * q + d, 6 + j)] = shapes[(6 * i + d, j)];
            }
        }
    }
    B
}

/// $\mathbf B^+ = \mathbf B^T(\mathbf B\mathbf B^T)^{-1}$ and an orthonormal basis $\mathbf Z$ of
/// the null space of $\mathbf B$; an error unless $\mathbf B$ has full row rank.
fn interface_null_space(
    B: &DMatrix<f64>,
    body_error: &dyn Fn(String) -> FemError,
) -> Result<(DMatrix<f64>, DMatrix<f64>), FemError> {
    let (nb, na) = B.shape();
    // B has full row rank unless two interfaces cannot move independently with these modes.
    let singular_values = B.transpose().singular_values();
    let s_max = singular_values.max();
    let rank = singular_values.iter().filter(|&&s| s > 1e-10 * s_max).count();
    if rank < nb {
        return Err(body_error(format!(
            "the interfaces cannot move independently with these modes (rank {rank} of {nb}): choose fewer interfaces or a file with more modes"
        )));
    }
    let Bt = B.transpose();
    let BBt_inv = (B * &Bt)
        .try_inverse()
        .ok_or_else(|| body_error("the interface values are singular".into()))?;
    // The null space Z of B: the projector's columns, orthonormalised (Gram-Schmidt, twice).
    let proj = DMatrix::<f64>::identity(na, na) - &Bt * &BBt_inv * B;
    let mut Z_cols: Vec<nalgebra::DVector<f64>> = Vec::new();
    for e in 0..na {
        if Z_cols.len() == na - nb {
            break;
        }
        let mut v = proj.column(e).into_owned();
        for _ in 0..2 {
            for z in &Z_cols {
                let d = z.dot(&v);
                v -= z * d;
            }
        }
        let norm = v.norm();
        if norm > 1e-8 {
            Z_cols.push(v / norm);
        }
    }
    let nz = na - nb;
    if Z_cols.len() != nz {
        return Err(body_error(
            "cannot complete the null space of the interface values".into(),
        ));
    }
    let Z = if nz == 0 {
        DMatrix::zeros(na, 0)
    } else {
        DMatrix::from_columns(&Z_cols)
    };
    Ok((&Bt * &BBt_inv, Z))
}

/// The fixed-interface modes in the null space `Z` (coefficients `V`, mass-normalised, each
/// signed so that its largest coefficient on the joint basis is positive) and their
/// frequencies; condenses `T_b` statically onto them (zero generalised force on `Z`).
fn fixed_interface_modes(
    Z: &DMatrix<f64>,
    K_a: &DMatrix<f64>,
    M_a: &DMatrix<f64>,
    T_b: &mut DMatrix<f64>,
    body_error: &dyn Fn(String) -> FemError,
) -> Result<(Vec<f64>, DMatrix<f64>), FemError> {
    let nz = Z.ncols();
    let K_zz = Z.transpose() * K_a * Z;
    let M_zz = Z.transpose() * M_a * Z;
    if nz == 0 {
        return Ok((Vec::new(), DMatrix::zeros(0, 0)));
    }
    let chol = K_zz.clone().cholesky().ok_or_else(|| {
        body_error("with the interfaces held, the modal stiffness is not positive definite: the body can still move without straining (choose other interfaces)".into())
    })?;
    // Static condensation: interface coordinates with zero generalised force on Z.
    *T_b -= Z * chol.solve(&(Z.transpose() * K_a * &*T_b));
    let L = M_zz
        .clone()
        .cholesky()
        .ok_or_else(|| body_error("with the interfaces held, the modal mass is not positive definite".into()))?;
    // K_zz v = w^2 M_zz v: with M = L L^T, (L^-1 K L^-T) u = w^2 u, v = L^-T u.
    let Linv = L
        .l()
        .try_inverse()
        .ok_or_else(|| body_error("the modal mass cannot be inverted".into()))?;
    let A = &Linv * &K_zz * Linv.transpose();
    let A = (&A + A.transpose()) * 0.5;
    let eig = nalgebra::SymmetricEigen::new(A);
    let mut order: Vec<usize> = (0..nz).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let mut V = DMatrix::zeros(nz, nz);
    let mut omega = Vec::with_capacity(nz);
    for (k, &o) in order.iter().enumerate() {
        let v = Linv.transpose() * eig.eigenvectors.column(o);
        // Sign: the largest coefficient on the joint basis positive.
        let full = Z * &v;
        let big = full
            .iter()
            .copied()
            .fold(0.0f64, |acc, x| if x.abs() > acc.abs() { x } else { acc });
        let v = if big < 0.0 { -v } else { v };
        V.set_column(k, &v);
        omega.push(eig.eigenvalues[o].max(0.0).sqrt());
    }
    Ok((omega, V))
}

/// The inertia data and $\boldsymbol\Phi_{com}$ of the Craig-Bampton basis $\mathbf T$ (columns
/// of the joint basis), the centre of mass moved by the frame origin `origin`.
fn reduced_inertia(
    data: &MassData,
    T: &DMatrix<f64>,
    modal: &ModalInertia,
    rigid: &RigidMoments,
    origin: Vector3<f64>,
    body_error: &dyn Fn(String) -> FemError,
) -> Result<(InertiaData, DMatrix<f64>), FemError> {
    let (m, c_O, J_com, X1) = (modal.m, modal.c_O, modal.J_com, rigid.X1);
    let nx = modal.P.len();
    let na = 6 + nx;
    let d = data.transform(T);
    let n = T.ncols();
    let S_r = &d.S_rO - tilde_dyn(&c_O) * &d.S_t;
    // int rho S of the translational field for the joint basis: m e_a, e_a x X1, the modes'.
    let mut field_a = DMatrix::zeros(3, na);
    for a in 0..3 {
        field_a[(a, a)] = m;
        let rot = Vector3::ith(a, 1.0).cross(&X1);
        for b in 0..3 {
            field_a[(b, 3 + a)] = rot[b];
        }
    }
    field_a.view_mut((0, 6), (3, nx)).copy_from(&modal.field3);
    let field_new = &field_a * T;
    let S_x = DMatrix::from_fn(9, n, |row, j| {
        let (k, l) = (row / 3, row % 3);
        d.P[j][(k, l)] - c_O[k] * field_new[(l, j)]
    });
    let S_bar: Vec<DenseMatrix> = (0..9).map(|ab| dense(&d.Q[ab / 3][ab % 3])).collect();
    let J_inv = J_com
        .try_inverse()
        .ok_or_else(|| body_error("the inertia tensor (RECORD GROUP 12) is singular".into()))?;
    let Phi_com = DMatrix::from_fn(6, n, |i, j| {
        if i < 3 {
            d.S_t[(i, j)] / m
        } else {
            (0..3).map(|k| J_inv[(i - 3, k)] * S_r[(k, j)]).sum()
        }
    });
    let c = c_O + origin;
    let inertia = InertiaData {
        mass: m,
        center_of_mass: c.into(),
        inertia_com: [
            [J_com[(0, 0)], J_com[(0, 1)], J_com[(0, 2)]],
            [J_com[(1, 0)], J_com[(1, 1)], J_com[(1, 2)]],
            [J_com[(2, 0)], J_com[(2, 1)], J_com[(2, 2)]],
        ],
        S_t: dense(&d.S_t),
        S_r: dense(&S_r),
        S_x: dense(&S_x),
        S_bar,
    };
    Ok((inertia, Phi_com))
}
