//! Errors of the reduction stage. Each says what failed, where (matrix, dof, mode) and what to
//! do about it.

use crate::reduced_body::{MAGIC, OLDEST_READABLE};
use thiserror::Error;

/// Errors of the sparse eigensolver and the shift-invert factorisation.
///
/// Dof indices are those of the matrices as given (the fill-reducing permutation of the
/// Cholesky factor is undone before an index is reported).
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ReductionError {
    /// Two matrices that must have the same shape, or a matrix that must be square, do not.
    #[error("{what}: expected a {expected_rows} x {expected_cols} matrix, got {rows} x {cols}")]
    DimensionMismatch {
        what: &'static str,
        expected_rows: usize,
        expected_cols: usize,
        rows: usize,
        cols: usize,
    },
    /// The number of requested modes must satisfy $1 \le m < n$.
    #[error("{requested} modes requested from a problem with {n} dofs (need 1 <= n_modes < {n})")]
    InvalidModeCount { requested: usize, n: usize },
    /// A setting is outside its range (a tolerance that is not positive, a shift that is not
    /// finite, ...).
    #[error("invalid eigensolver setting: {what}")]
    InvalidSettings { what: String },
    /// A matrix is not stored with both triangles, or is not symmetric. The solver needs full
    /// symmetric CSC storage: the Cholesky factor reads the lower triangle, the products with
    /// $\mathbf K$ and $\mathbf M$ read both.
    #[error("{matrix} is not symmetric with both triangles stored: the weighted sums of its strict lower and strict upper triangles are {lower:.6e} and {upper:.6e}")]
    NotSymmetric {
        matrix: &'static str,
        lower: f64,
        upper: f64,
    },
    /// The stiffness matrix is singular (a free body or a mechanism) and the shift is zero,
    /// so $\mathbf K$ itself has no Cholesky factor. `pivot_ratio` is the pivot over the
    /// diagonal entry of that dof ($\le 0$ when the factorisation stopped there).
    #[error("the stiffness matrix is singular at dof {dof} (pivot / diagonal = {pivot_ratio:.3e}): the body is free or a mechanism; use a negative shift (Shift::Auto or Shift::Value(sigma < 0)) to compute its rigid-body modes, or add supports")]
    SingularStiffness { dof: usize, pivot_ratio: f64 },
    /// $\mathbf K - \sigma\mathbf M$ has no Cholesky factor for a non-zero shift. For
    /// $\sigma > 0$ the shift lies above the lowest eigenvalue (Sylvester's law of inertia);
    /// for $\sigma < 0$, $\mathbf K$ or $\mathbf M$ is indefinite, or the shift is so small
    /// that $\mathbf K - \sigma\mathbf M$ is singular to working precision.
    #[error("K - sigma M with sigma = {shift:.6e} is not positive definite at dof {dof} (pivot / diagonal = {pivot_ratio:.3e}): {hint}")]
    ShiftedNotPositiveDefinite {
        shift: f64,
        dof: usize,
        pivot_ratio: f64,
        hint: &'static str,
    },
    /// The mass matrix is not positive definite: a dof without mass (a non-positive diagonal
    /// entry), or an indefinite matrix found by the eigensolver (`dof` is then `None`).
    #[error("the mass matrix is not positive definite{}: {why}", dof.map(|d| format!(" at dof {d}")).unwrap_or_default())]
    MassNotPositiveDefinite { dof: Option<usize>, why: String },
    /// The eigensolver did not deliver the requested eigenpairs: either Lanczos ran out of
    /// `max_restarts` with only `converged` pairs converged (`worst_residual` is then
    /// infinite), or the residual check of the returned pairs failed. `failed_modes` are
    /// 0-based, in ascending order of eigenvalue.
    #[error("eigensolver did not converge: {converged} of {requested} modes converged; modes {failed_modes:?} fail the residual check (worst relative residual {worst_residual:.3e} > {tolerance:.3e}); raise max_restarts or krylov_dim, or loosen the tolerance")]
    EigenNotConverged {
        requested: usize,
        converged: usize,
        failed_modes: Vec<usize>,
        worst_residual: f64,
        tolerance: f64,
    },
    /// The Cholesky factor of `K - sigma M` (with its workspace, or the vectors the reduction
    /// allocates after it) needs more memory than is available (`fe_model::available_memory`),
    /// in the precision the `factor` setting allows: refused before any value is computed.
    #[error("{body}: the Cholesky factor of K_ii does not fit in memory in {precision} precision: {factor_values} M values, {factor_gb:.1} GB of factor, {needed_gb:.1} GB at the peak with its workspace or the reduction's vectors, against {available_gb:.1} GB available; {hint}")]
    FactorDoesNotFit {
        body: String,
        precision: &'static str,
        factor_values: usize,
        factor_gb: f64,
        needed_gb: f64,
        available_gb: f64,
        hint: &'static str,
    },
    /// The single-precision factor broke down (a pivot not positive, or below
    /// `eigen::SINGLE_PIVOT_RATIO` of its diagonal entry) at `at`: the matrix is singular or
    /// too poorly conditioned for a factor with about 7 significant digits.
    #[error("{body}: the single-precision factor of K_ii breaks down at {at} (pivot / diagonal = {pivot_ratio:.3e}): the stiffness is singular there or too poorly conditioned for single precision; set factor = \"double\"")]
    SinglePrecisionBreakdown { body: String, at: String, pivot_ratio: f64 },
    /// Iterative refinement with the single-precision factor did not reach a double-precision
    /// solve's accuracy (`eigen::ShiftInvert::solve_refined`): the residual stopped falling,
    /// or [`crate::eigen::MAX_REFINEMENT_STEPS`] corrections did not suffice.
    #[error("{body}: iterative refinement with the single-precision factor fails in {what}, right-hand side {column}: backward error {backward_error:.3e} after {steps} corrections (needed {target:.3e}); the matrix (K_ii in a Craig-Bampton reduction, K - sigma M with a shift) is too poorly conditioned for a single-precision factor: set factor = \"double\"")]
    RefinementFailed {
        body: String,
        what: String,
        column: usize,
        steps: usize,
        backward_error: f64,
        target: f64,
    },
    /// The sparse factorisation failed for a reason other than the matrix (out of memory,
    /// index overflow).
    #[error("sparse factorisation failed: {0}")]
    Factorization(String),
    /// An interface of a body cannot serve as a Craig-Bampton boundary (missing node, a dof
    /// that is not free, the body still free with all interfaces held, ...).
    #[error("interface '{name}': {what}")]
    Interface { name: String, what: String },
    /// More fixed-interface modes asked of body `body` than its interior (the free dofs not on
    /// an interface) can give: the eigensolver needs fewer modes than dofs, so at most
    /// `interior - 1`.
    #[error("{requested} fixed-interface modes requested of '{body}', but its interior (the free dofs not on an interface) has {interior} dofs, so at most {} modes", interior.saturating_sub(1))]
    TooManyModes {
        body: String,
        requested: usize,
        interior: usize,
    },
    /// A planar reduction (`CbSettings::planar`) of body `body` is impossible: an element
    /// that is not a beam, a node off the plane of the others, or a coupling of the in-plane
    /// and out-of-plane coordinates (named).
    #[error("body '{body}' cannot be reduced as a planar part: {what}")]
    NotPlanar { body: String, what: String },
    /// The FE model could not be numbered or assembled: the FE stage's error is the source.
    #[error("FE model")]
    Fe(#[from] fe_model::FeError),
    /// The FE model holds data the reduction cannot use (a beam without its section, a
    /// non-finite geometric stiffness entry): which, and why.
    #[error("FE model: {what}")]
    InvalidFeModel { what: String },
    /// Matrices and node coordinates from another FE code are inconsistent (sizes, dof list,
    /// an unsymmetric entry); see `craig_bampton::reduce_external`.
    #[error("external model: {what}")]
    ExternalModel { what: String },
    /// A reduced-body file (`file` module) could not be written or read back: which file, and
    /// what is wrong with it.
    #[error("reduced-body file {}: {problem}", path.display())]
    BodyFile {
        path: std::path::PathBuf,
        problem: BodyFileProblem,
    },
    /// A Matrix Market file (`matrix_market` module) could not be written or read: which
    /// file, the 1-based line when one is to blame, and what is wrong.
    #[error("Matrix Market file {}{}: {what}", path.display(), line.map(|l| format!(", line {l}")).unwrap_or_default())]
    MatrixMarket {
        path: std::path::PathBuf,
        line: Option<usize>,
        what: String,
    },
}

/// What is wrong with a reduced-body file; the file itself is named by
/// [`ReductionError::BodyFile`].
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum BodyFileProblem {
    /// The file system refused (`action` is "read", "write", ...).
    #[error("cannot {action} it: {message}")]
    Io { action: &'static str, message: String },
    /// The file does not start with [`crate::io::rbody::MAGIC`].
    #[error("not a reduced-body file: it starts with {found:?}, where a reduced-body file starts with \"{MAGIC} \"")]
    WrongMagic { found: String },
    /// The format version on the first line is not the one this build reads.
    #[error("{}", version_message(*found, *supported))]
    UnsupportedVersion { found: u64, supported: u32 },
    /// A header line (1 or 2) is not what the format prescribes.
    #[error("header line {line}: {what}")]
    Header { line: usize, what: String },
    /// The file ends inside the JSON metadata block.
    #[error(
        "the metadata block is truncated: the header announces {expected} bytes, the file has {found} after the header"
    )]
    TruncatedMetadata { expected: u64, found: u64 },
    /// A stored CRC-32 does not match the bytes: the file was changed or damaged after it was
    /// written. `block` is `metadata` or the array's name.
    #[error("checksum mismatch in {block}: stored crc32 {stored:08x}, computed {computed:08x} (the file was changed or damaged after it was written)")]
    Checksum { block: String, stored: u32, computed: u32 },
    /// The metadata block is not the JSON of the file's format version; `line` and `column` are
    /// serde_json's, counted in the JSON block (its line 1 is line 3 of the file).
    #[error("malformed metadata JSON at line {line}, column {column} of the block (file line {}): {message}", line + 2)]
    Json {
        line: usize,
        column: usize,
        message: String,
    },
    /// The file ends inside an array.
    #[error("array {array} is truncated: it needs {expected} bytes from byte {offset} of the array section, the file has {found}")]
    TruncatedArray {
        array: String,
        offset: u64,
        expected: u64,
        found: u64,
    },
    /// Bytes after the last array.
    #[error("{count} unexpected bytes after the last array (the index accounts for {expected} bytes of arrays)")]
    TrailingBytes { count: u64, expected: u64 },
    /// Shapes or counts that contradict each other (an array that is not $n \times n$, a
    /// frequency list whose length is not the mode count, an index in the wrong order, ...).
    #[error("inconsistent data: {what}")]
    Shape { what: String },
    /// The body cannot be written (a non-finite scalar, which JSON cannot hold, or a body
    /// whose own shapes are inconsistent).
    #[error("the body cannot be written: {what}")]
    Unwritable { what: String },
    /// The file is intact but its data are physically wrong ([`crate::checks`]): no reduction
    /// produces them.
    #[error("physically inconsistent data (no reduction produces these; reduce the body again): {}", problems.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("; "))]
    Physics {
        problems: Vec<crate::checks::PhysicsProblem>,
    },
}

impl ReductionError {
    /// The error with `name` as the body in the variants that carry one and were made
    /// without it ([`ReductionError::FactorDoesNotFit`],
    /// [`ReductionError::SinglePrecisionBreakdown`], [`ReductionError::RefinementFailed`], as
    /// `eigen::ShiftInvert` makes them); other errors unchanged.
    pub fn with_body(mut self, name: &str) -> Self {
        if let ReductionError::FactorDoesNotFit { body, .. }
        | ReductionError::SinglePrecisionBreakdown { body, .. }
        | ReductionError::RefinementFailed { body, .. } = &mut self
        {
            if body.is_empty() {
                *body = name.to_string();
            }
        }
        self
    }
}

fn version_message(found: u64, supported: u32) -> String {
    if found > supported as u64 {
        format!("format version {found} is newer than this build, which reads versions {OLDEST_READABLE} to {supported}: read it with a newer flexmbs, or reduce the body again with this one")
    } else {
        format!(
            "format version {found} is not supported: this build reads versions {OLDEST_READABLE} to {supported}; reduce the body again"
        )
    }
}
