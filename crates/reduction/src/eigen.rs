//! The $m$ lowest eigenpairs of $\mathbf K\boldsymbol\phi = \omega^2\mathbf M\boldsymbol\phi$
//! for sparse symmetric $\mathbf K \succeq 0$ and $\mathbf M \succ 0$, by shift-invert
//! Lanczos on a sparse Cholesky factor (theory guide §3).
//!
//! # Method
//!
//! 1. Factor $\mathbf P(\mathbf K - \sigma\mathbf M)\mathbf P^T = \mathbf L\mathbf L^T$ with
//!    faer's sparse Cholesky (fill-reducing permutation $\mathbf P$ by AMD or, given the dof
//!    positions, nested dissection: `fe_model::ordering`; supernodal or simplicial as faer's
//!    symbolic analysis chooses): [`ShiftInvert::new`], [`ShiftInvert::with_settings`].
//! 2. Find the $m$ largest eigenvalues of the standard symmetric problem for
//!    $$\mathbf C = \mathbf L^{-1}\mathbf P\mathbf M\mathbf P^T\mathbf L^{-T},$$
//!    whose eigenpairs are $\mu_k = 1/(\lambda_k - \sigma)$,
//!    $\mathbf y_k = \mathbf L^T\mathbf P\boldsymbol\phi_k$ (Ericsson & Ruhe 1980, "The
//!    spectral transformation Lanczos method", Math. Comp. 35; Grimes, Lewis & Simon 1994,
//!    SIAM J. Matrix Anal. Appl. 15, §2), by thick-restart Lanczos (the private `Lanczos`).
//!    The factor exists only if $\mathbf K - \sigma\mathbf M \succ 0$, i.e. $\sigma <
//!    \lambda_1$, so every $\mu_k > 0$ and the *largest* $\mu$ are the *lowest* $\lambda$.
//! 3. Back-transform $\boldsymbol\phi_k = \mathbf P^T\mathbf L^{-T}\mathbf y_k$ and do a
//!    Rayleigh-Ritz step on $(\mathbf K, \mathbf M)$ in the span of the $m$ vectors
//!    (`rayleigh_ritz`). It makes $\boldsymbol\Phi^T\mathbf M\boldsymbol\Phi = \mathbf I$
//!    hold to round-off (the Lanczos vectors are orthonormal in the standard inner product
//!    only, and the $\mathbf y_k$ only approximately $\mathbf C$-orthogonal) and gives each
//!    $\lambda_k$ as a Rayleigh quotient of $\mathbf K$ itself, so rigid-body modes come out
//!    with $|\lambda| \approx \varepsilon\lambda_{max}$.
//! 4. Check every pair by its relative residual ([`relative_residual`]) on
//!    $(\mathbf K, \mathbf M)$ themselves, never by the Krylov estimates.
//!
//! ## A factor in single precision
//!
//! [`ShiftInvert::with_settings`] can factor in f32 ([`FactorPrecision`]; automatically only
//! when the double-precision factor would not fit in the available memory): half the bytes,
//! solves accurate to $\kappa\,\varepsilon_{32}$ only. Every solve is then refined in f64 to a
//! double-precision solve's backward error ([`ShiftInvert::solve_refined`]: the constraint
//! modes, the attachment modes and the Lanczos operator alike). The operator $\mathbf C$ below
//! cannot be refined (its two triangular solves are not a solve with $\mathbf K -
//! \sigma\mathbf M$), so with an f32 factor the Lanczos runs on
//! $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$ in the $\mathbf M$ inner product (the private
//! `WholeOperator`; Grimes, Lewis & Simon 1994, §2): the basis is $\mathbf M$-orthonormal,
//! $\mathbf M\mathbf V$ is kept beside it (every inner product a dot product, one sparse product
//! per block step, and the operator's input), the projected matrix
//! $\mathbf V^T\mathbf M(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M\mathbf V$ is symmetric with
//! the same $\mu_k$, and its Ritz vectors are the modes themselves (no back-transformation).
//! Steps 3 and 4 are the same. The double-precision path is unchanged.
//!
//! ## The operator: $\mathbf L^{-1}\mathbf M\mathbf L^{-T}$ rather than $(\mathbf K-\sigma\mathbf M)^{-1}\mathbf M$
//!
//! $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$ is self-adjoint only in the $\mathbf M$ inner
//! product, which a standard symmetric Krylov solver does not use. The split form needs the
//! forward and backward triangular solves separately; faer exposes them
//! ([`faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef::l_solve_with_conj`] and
//! `l_transpose_solve_with_conj` on a supernodal factor,
//! [`faer::sparse::linalg::triangular_solve::solve_lower_triangular_in_place`] and
//! `solve_lower_triangular_transpose_in_place` on a simplicial one), wrapped by
//! `fe_model::SparseCholesky`, which runs the supernodal ones on disjoint subtrees of the
//! elimination tree in parallel. The product with $\mathbf P\mathbf M\mathbf P^T$ permutes
//! the block and multiplies by $\mathbf M$ as given, so one
//! application of $\mathbf C$ costs one forward solve, one backward solve and one sparse
//! product: the same as one solve with $\mathbf K - \sigma\mathbf M$ and one product with
//! $\mathbf M$. Applied to a block of $b$ vectors, it reads the factor and $\mathbf M$ once
//! for all $b$ ([`EigenSettings::block_size`]). Symmetrising with a Cholesky factor of $\mathbf M$ instead would
//! cost a second factorisation of the same fill. The operator implements faer's
//! [`LinOp`], so faer's own Krylov-Schur can be put back in one call once it is fixed (below).
//!
//! ## Why not faer's `partial_self_adjoint_eigen`
//!
//! faer 0.24's Krylov-Schur for self-adjoint operators
//! ([`faer::matrix_free::eigen::partial_self_adjoint_eigen`]) hangs on some inputs (an endless
//! re-orthogonalisation loop; faer issue #262, open). It does so on this module's own
//! random-pencil test (`random_sparse_spd_matches_dense_reference`), with the operator
//! replaced by a dense symmetric matrix too, so it is not our operator. A likely cause: when
//! it compacts the Ritz vectors to lock and to retain, a vector locked after one retained
//! overwrites it, the new basis holds a column twice, the next Ritz vectors are not
//! orthonormal, and the Gram-Schmidt loop, which stops only on a relative criterion, never
//! does. Clustered spectra, where a later Ritz value converges before an earlier one, trigger
//! it. Our `Lanczos` is the same method (Krylov-Schur is thick-restart Lanczos
//! for a symmetric operator: Wu & Simon 2000, SIAM J. Matrix Anal. Appl. 22; Stewart 2001,
//! SIAM J. Matrix Anal. Appl. 23), written without locking, with a bounded classical
//! Gram-Schmidt with one re-orthogonalisation ("twice is enough": Giraud, Langou &
//! Rozložník 2005, Comput. Math. Appl. 50) and a convergence test relative to each Ritz value.
//!
//! ## Dense eigensolvers on scaled matrices
//!
//! The three small dense symmetric eigenproblems (the Lanczos matrix $\mathbf T_k$ at every
//! step, the Rayleigh-Ritz matrix on $(\mathbf K, \mathbf M)$, and $\mathbf C$ itself on the
//! dense path) are solved on a copy scaled to unit largest entry by a power of two
//! (`scaled_self_adjoint_eigen`). faer 0.24's divide and conquer, which it uses from
//! dimension 128, is not scale-invariant, and $\|\mathbf C\| = 1/(\lambda_1 - \sigma)$ is
//! far from 1 in SI units: unscaled, the Ritz vectors of a clamped beam with 100 modes were
//! wrong by $\varepsilon$ absolute while Lanczos reported them converged, and the residual
//! check failed whatever the restarts. With fewer than 64 modes the automatic Krylov
//! dimension stays below 128, where faer's QR algorithm (scale-invariant) runs instead.
//!
//! ## Shift
//!
//! $\sigma = 0$ ([`Shift::Zero`]) needs $\mathbf K \succ 0$ (a supported body). A free body
//! or a mechanism has a singular $\mathbf K$, and with $\sigma = 0$ the factorisation reports
//! [`ReductionError::SingularStiffness`]. A negative shift makes
//! $\mathbf K - \sigma\mathbf M \succ 0$, and the rigid-body modes ($\lambda = 0$) become the
//! dominant $\mu = 1/|\sigma|$. [`Shift::Auto`] takes
//! $\sigma = -10^{-8}\,\mathrm{median}_i(K_{ii}/M_{ii})$; [`AUTO_SHIFT_FRACTION`] says why.
//!
//! ## Tolerance
//!
//! `settings.tolerance` bounds the relative residual of every returned pair
//! ([`relative_residual`]). Lanczos stops when the residual estimate of every wanted Ritz
//! pair, $|\beta_k s_{kj}|$, is below `tolerance` $\cdot$ [`KRYLOV_TOLERANCE_FACTOR`]
//! $\cdot\,|\mu_j|$: relative to each Ritz value, so a wide spread of the wanted spectrum does
//! not loosen the test of the higher modes. The factor 0.1 is a safety margin: for
//! $\mathbf r = \mathbf C\mathbf y - \mu\mathbf y$ and $\boldsymbol\phi = \mathbf
//! P^T\mathbf L^{-T}\mathbf y$, $\mathbf K\boldsymbol\phi - \lambda\mathbf M\boldsymbol\phi
//! = -\mathbf P^T\mathbf L\mathbf r/\mu$, so the residual on $(\mathbf K, \mathbf M)$ differs
//! from the Krylov one by the action of $\mathbf L$. If a pair still fails the check, Lanczos
//! continues from where it stopped with the Krylov tolerance lowered by the shortfall, at
//! most [`MAX_ATTEMPTS`] rounds in all. A residual at or below the round-off floor of its own
//! evaluation ([`residual_floor`]) is accepted whatever the tolerance: the lowest modes of a
//! fine mesh, and rigid-body modes with [`Shift::Auto`], can have a floor above `1e-8`, and
//! their reported residual may then exceed `tolerance`.
//!
//! ## Limits
//!
//! A single-vector Krylov method (`block_size = 1`) sees one vector per distinct eigenvalue in
//! exact arithmetic; a block of $b$ sees up to $b$. Copies beyond $b$ (the six rigid modes of
//! a free body, symmetric structures) are found only because round-off seeds them and
//! shift-invert amplifies them by $\mu_k/\mu_j$ per step, as in ARPACK; near the top of the
//! wanted range that amplification is weak and a copy can be missed, which no residual check
//! can see. It happened with single vectors on the 10k- and 50k-dof Craig-Bampton blocks of
//! `benches/craig_bampton.rs` (pairs of bending modes of the square section; 7-9 % off in the
//! last kept frequencies, found against scipy's `eigsh`), so the automatic block size is never
//! 1: [`SMALL_BLOCK_SIZE`] = 2 below [`BLOCK_MIN_DOFS`], [`AUTO_BLOCK_SIZE`] = 4 from there
//! (`tests/unit/eigen.rs::pairs_at_the_top_of_the_wanted_range_are_found`). An indefinite $\mathbf M$ with a positive diagonal is detected only when it
//! reaches the wanted part of the spectrum (a Ritz value $\mu \le 0$ among the largest in
//! magnitude, or $\boldsymbol\Phi^T\mathbf M\boldsymbol\Phi$ not positive definite).

#![allow(non_snake_case)]

use crate::error::ReductionError;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::matmul::matmul;
use faer::linalg::temp_mat_zeroed;
use faer::mat::AsMatMut;
use faer::matrix_free::LinOp;
use faer::prelude::*;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Side};
use fe_model::{CholeskyError, FillOrdering, Precision, SymbolicFactor};
use rayon::prelude::*;

/// Fraction of the median diagonal ratio $K_{ii}/M_{ii}$ used by [`Shift::Auto`]:
/// $\sigma = -10^{-8}\,\mathrm{median}_i(K_{ii}/M_{ii})$.
///
/// $K_{ii}/M_{ii}$ is the Rayleigh quotient of a unit displacement of one dof, of the order
/// of the highest eigenvalues of the mesh. The lowest flexible eigenvalue is smaller by about
/// $(h/L)^2$ for solids and bars and $(h/L)^4$ for beams in bending ($h$ element size, $L$
/// body size): $10^{-2}$ to $10^{-8}$ for practical meshes. A shift at or below it keeps the
/// separation of the flexible $\mu_k$ about as good as with $\sigma = 0$, and makes the
/// rigid-body $\mu = 1/|\sigma|$ dominate strongly, which is what pulls all copies of the
/// (six-fold) zero eigenvalue out of round-off. The price is the conditioning of
/// $\mathbf K - \sigma\mathbf M$, about $\lambda_{max}/|\sigma| \approx 10^{8}$: harmless for
/// a Cholesky factor in double precision, far from [`SINGULAR_PIVOT_RATIO`], and it puts the
/// residual floor of the rigid modes near $\varepsilon\lambda_{max}/|\sigma| \approx 10^{-8}$
/// ([`residual_floor`]).
pub const AUTO_SHIFT_FRACTION: f64 = 1e-8;

/// A Cholesky pivot $L_{jj}^2$ at or below this fraction of its diagonal entry $A_{jj}$ is
/// taken as a singular matrix: $10^3\varepsilon \approx 2\cdot 10^{-13}$.
///
/// The pivot $L_{jj}^2 = 1/((\mathbf A_{1:j,1:j})^{-1})_{jj}$ (in the order of the factor) is
/// the stiffness of dof $j$ with the dofs eliminated before it free and those after it held.
/// For a singular positive
/// semi-definite matrix it is zero in exact arithmetic and comes out as round-off, a few
/// $\varepsilon A_{jj}$ of either sign (the free-free chain of the tests gives
/// $4\cdot 10^{-16}$); a negative one stops faer's factorisation, a positive one would be
/// accepted and give $\mu \approx 10^{16}$. A stiffness whose pivots fall below
/// $10^3\varepsilon$ is singular to working precision: its lowest eigenvalues cannot be told
/// from round-off anyway.
pub const SINGULAR_PIVOT_RATIO: f64 = 1e3 * f64::EPSILON;

/// Lanczos stops when every wanted Ritz pair of $\mathbf C$ has a residual estimate below
/// `tolerance` times this factor times $|\mu_k|$: a safety factor of 10 between the Krylov
/// target and the check on $(\mathbf K, \mathbf M)$.
pub const KRYLOV_TOLERANCE_FACTOR: f64 = 0.1;

/// At most this many convergence rounds (Lanczos continued with a lower Krylov tolerance
/// after a failed residual check) before [`ReductionError::EigenNotConverged`].
pub const MAX_ATTEMPTS: usize = 3;

/// Largest $n$ solved densely when the Krylov basis would not fit ($n \le p + 1$, $p$ the
/// subspace dimension): the dense path costs $n$ operator applications and an $O(n^3)$
/// eigendecomposition.
pub const DENSE_LIMIT: usize = 2000;

/// Which precision [`ShiftInvert::with_settings`] factors $\mathbf K - \sigma\mathbf M$ in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FactorPrecision {
    /// Double precision if the factor fits in the available memory
    /// ([`fe_model::available_memory`], with [`MEMORY_FRACTION`] and the caller's reserve),
    /// else single precision if that fits, else [`ReductionError::FactorDoesNotFit`].
    #[default]
    Auto,
    /// Always double precision (refused if it does not fit).
    Double,
    /// Always single precision, with refined solves (refused if it does not fit).
    Single,
}

/// How [`ShiftInvert::with_settings`] factors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FactorSettings {
    /// The precision of the factor.
    pub precision: FactorPrecision,
    /// Bytes the caller will allocate after the factorisation while a double-precision factor
    /// is alive (the constraint modes, the Lanczos basis), counted against the available
    /// memory with the factor.
    pub reserve_bytes: usize,
    /// The same with a single-precision factor (more: its Lanczos keeps $\mathbf M\mathbf V$
    /// beside $\mathbf V$, and its refined solves keep the right-hand sides and residuals).
    pub single_reserve_bytes: usize,
}

impl FactorSettings {
    /// A double-precision factor, no reserve.
    pub const DOUBLE: FactorSettings = FactorSettings {
        precision: FactorPrecision::Double,
        reserve_bytes: 0,
        single_reserve_bytes: 0,
    };

    /// The caller's reserve with a factor in `precision`.
    fn reserve(&self, precision: Precision) -> usize {
        match precision {
            Precision::Double => self.reserve_bytes,
            Precision::Single => self.single_reserve_bytes,
        }
    }
}

/// Fraction of [`fe_model::available_memory`] a factor with its workspace, or with the
/// caller's reserve, may take: the other 10 % are for what the estimate leaves out (the
/// allocator's overhead, small dense matrices, the page cache other programs keep using).
pub const MEMORY_FRACTION: f64 = 0.9;

/// A pivot of the single-precision factor with $L_{jj}^2 \le$ this fraction of its diagonal
/// entry is refused ([`ReductionError::SinglePrecisionBreakdown`]): $10\,\varepsilon_{32}
/// \approx 1.2\cdot 10^{-6}$. Such a pivot is the difference of numbers a million times
/// larger, with at most one correct digit in f32, so the factor's solves have no correct
/// digit in that direction and refinement cannot converge.
pub const SINGLE_PIVOT_RATIO: f64 = 10.0 * f32::EPSILON as f64;

/// At most this many solves with a single-precision factor per refined solve (LAPACK's
/// `dsposv` allows 30). Refinement gains about $-\log_{10}(\kappa\varepsilon_{32})$ digits per
/// step, 3 or more on the meshes measured; a stalled one is stopped earlier, when a
/// correction does not halve the backward error.
pub const MAX_REFINEMENT_STEPS: usize = 30;

/// [`ShiftInvert::solve_refined`] stops refining a column whose backward error is at or below
/// this many $\varepsilon_{64}$: a double-precision Cholesky solve gives a few
/// $\varepsilon_{64}$ (the 50k and 200k hex8 blocks: 4e-16, 2 $\varepsilon_{64}$, as relative
/// residual), and a further step cannot gain on the round-off of the residual's evaluation.
pub const REFINED_FLOOR: f64 = 4.0;

/// The shift $\sigma$ of the spectral transformation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shift {
    /// $\sigma = 0$: for a supported body ($\mathbf K \succ 0$).
    Zero,
    /// A given $\sigma$. It must be below the lowest eigenvalue ($\mathbf K - \sigma\mathbf M$
    /// positive definite); negative for a free body.
    Value(f64),
    /// For a body that may be free: $\sigma = -$[`AUTO_SHIFT_FRACTION`]$\cdot
    /// \mathrm{median}_i(K_{ii}/M_{ii})$. Works for supported bodies too.
    Auto,
}

impl Shift {
    /// The value of $\sigma$ for the pencil $(\mathbf K, \mathbf M)$.
    ///
    /// # Errors
    /// [`ReductionError::InvalidSettings`] for a non-finite value; with [`Shift::Auto`],
    /// [`ReductionError::DimensionMismatch`], [`ReductionError::MassNotPositiveDefinite`] for a
    /// non-positive $M_{ii}$, and [`ReductionError::SingularStiffness`] if no $K_{ii}$ is
    /// positive.
    pub fn resolve(
        &self,
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
    ) -> Result<f64, ReductionError> {
        match *self {
            Shift::Zero => Ok(0.0),
            Shift::Value(sigma) if sigma.is_finite() => Ok(sigma),
            Shift::Value(sigma) => Err(ReductionError::InvalidSettings {
                what: format!("shift must be finite, got {sigma}"),
            }),
            Shift::Auto => {
                check_square_pair(K, M)?;
                let K_diag = diagonal(K);
                let M_diag = diagonal(M);
                check_mass_diagonal(&M_diag)?;
                let mut ratios: Vec<f64> = K_diag
                    .iter()
                    .zip(&M_diag)
                    .filter(|(k, _)| **k > 0.0)
                    .map(|(k, m)| k / m)
                    .collect();
                if ratios.is_empty() {
                    return Err(ReductionError::SingularStiffness {
                        dof: 0,
                        pivot_ratio: 0.0,
                    });
                }
                let mid = ratios.len() / 2;
                let (_, median, _) = ratios.select_nth_unstable_by(mid, f64::total_cmp);
                Ok(-AUTO_SHIFT_FRACTION * *median)
            }
        }
    }
}

/// Settings of [`lowest_modes`] and [`ShiftInvert::lowest_modes`].
#[derive(Debug, Clone, PartialEq)]
pub struct EigenSettings {
    /// Number $m$ of lowest modes wanted, $1 \le m < n$.
    pub n_modes: usize,
    /// Shift $\sigma$ of the spectral transformation (read by [`lowest_modes`] only; a
    /// [`ShiftInvert`] has its shift already).
    pub shift: Shift,
    /// Largest accepted relative residual of a returned pair, [`relative_residual`] (but see
    /// [`residual_floor`]). `1e-8` gives eigenvalues to about $10^{-14}$ relative plus
    /// round-off (the error of a Rayleigh quotient is quadratic in the vector error) and
    /// vectors to about $10^{-8}$.
    pub tolerance: f64,
    /// Maximum number of thick restarts of Lanczos, over all attempts.
    pub max_restarts: usize,
    /// Krylov subspace dimension $p$; `0` for $\max(2m, m + 32)$ with single vectors and
    /// $\max(2m, m + 32, m + 16b)$ with blocks of $b$. Memory is about $n(p + b) + nm$ doubles
    /// besides the factor; each restart cycle costs about $(p - m)/2$ operator applications.
    pub krylov_dim: usize,
    /// Block size $b$ of the Lanczos iteration: $\mathbf C$ is applied to $b$ vectors at once,
    /// so the factor is read once per $b$ vectors; clamped to $p - m$. `0` (the default of
    /// [`EigenSettings::new`]) for automatic: [`AUTO_BLOCK_SIZE`] from [`BLOCK_MIN_DOFS`]
    /// dofs, [`SMALL_BLOCK_SIZE`] below.
    pub block_size: usize,
}

/// The block size of [`EigenSettings::block_size`] `= 0` from [`BLOCK_MIN_DOFS`] dofs.
///
/// A triangular solve with a sparse factor larger than the caches is memory-bound: one
/// right-hand side streams the whole factor for two flops per value; $b$ right-hand sides
/// read it once for $b$ vectors. Measured on the clamped hex8 blocks of `benches/eigen.rs`
/// (one forward and one backward solve, faer's sequential supernodal solves, loaded machine):
/// at 197k dofs (2.85 GB factor) 1, 2, 4, 8 right-hand sides cost 403, 458, 524, 684 ms; at
/// 49k dofs (0.3 GB, read from the 480 MB L3) 60, 74, 103, 110 ms. A block needs more vectors
/// to converge (20 modes at 197k: 71 at $b = 1$, 104 at $b = 4$, 152 at $b = 8$), still far
/// fewer factor reads (26 or 19 against 71). $b = 8$ is not used: on the 50k-dof
/// Craig-Bampton block its 19th pair stalled at a residual of $3\cdot 10^{-8}$ through all
/// [`MAX_ATTEMPTS`] (not understood; $b = 4$ and $b = 1$ reach $10^{-9}$). On the 203 616-dof
/// Craig-Bampton block (2.13 GB factor, the subtree-parallel solves) $b = 8$ needed 168
/// vectors (21 block solves) against 116 (29) and a solve with 8 right-hand sides 1.2 times
/// the CPU time of one with 4; with the longer Gram-Schmidt and $\mathbf M$ products its
/// Lanczos stage took 40.6 s wall and 19.9 CPU-s against 39.0 s and 19.6 CPU-s at $b = 4$
/// (one run each, load 10): no gain.
pub const AUTO_BLOCK_SIZE: usize = 4;

/// From this many dofs [`EigenSettings::block_size`] `= 0` means [`AUTO_BLOCK_SIZE`]. Below,
/// the factor (0.4 GB at 50k dofs) is largely read from cache, a block of 4 costs 1.7 single
/// solves, and the 50k-dof block needs 116 vectors at $b = 4$ against 65: no gain.
pub const BLOCK_MIN_DOFS: usize = 100_000;

/// The block size of [`EigenSettings::block_size`] `= 0` below [`BLOCK_MIN_DOFS`] dofs.
///
/// Not for speed: single vectors miss the second copy of a repeated eigenvalue near the top of
/// the wanted range when round-off does not seed it (module docs, "Limits"), and pairs are
/// common (bodies with a square or round section have pairs of bending modes). The 10k-dof
/// Craig-Bampton block of `benches/craig_bampton.rs` lost two such copies with single vectors;
/// a block of $b$ holds $b$ copies in exact arithmetic.
pub const SMALL_BLOCK_SIZE: usize = 2;

impl EigenSettings {
    /// `n_modes` modes with `shift`, tolerance `1e-8`, at most 100 restarts, automatic Krylov
    /// dimension and block size.
    pub fn new(n_modes: usize, shift: Shift) -> Self {
        Self {
            n_modes,
            shift,
            tolerance: 1e-8,
            max_restarts: 100,
            krylov_dim: 0,
            block_size: 0,
        }
    }
}

/// The result of [`lowest_modes`].
#[derive(Debug, Clone)]
pub struct EigenSolution {
    /// $\lambda_k = \omega_k^2$, ascending.
    pub eigenvalues: Vec<f64>,
    /// $\boldsymbol\Phi$, $n \times m$, column $k$ the mode of `eigenvalues[k]`,
    /// $\mathbf M$-orthonormal: $\boldsymbol\Phi^T\mathbf M\boldsymbol\Phi = \mathbf I$. The
    /// sign of each column makes its largest-magnitude entry positive.
    pub vectors: Mat<f64>,
    /// Relative residual of each pair, [`relative_residual`].
    pub residuals: Vec<f64>,
    /// The shift $\sigma$ that was used.
    pub shift: f64,
    /// Number of applications of the shift-invert operator, counted per vector ($\mathbf C$:
    /// one forward and one backward solve each; with a single-precision factor,
    /// $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$ by refined solves).
    pub operator_applications: usize,
    /// Number of solves with the factor, per vector: equal to `operator_applications` with a
    /// double-precision factor; with a single-precision one, the refinement steps of all the
    /// applications (the first solve included).
    pub factor_solves: usize,
}

/// The $m$ lowest eigenpairs of $\mathbf K\boldsymbol\phi = \lambda\mathbf M\boldsymbol\phi$,
/// $\lambda = \omega^2$ (theory guide §3): [`Shift::resolve`], [`ShiftInvert::new`], then
/// [`ShiftInvert::lowest_modes`].
///
/// `K` and `M` are symmetric with both triangles stored (CSC; unsorted row indices are
/// allowed).
///
/// # Errors
/// See [`ShiftInvert::new`] and [`ShiftInvert::lowest_modes`].
pub fn lowest_modes(
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
    settings: &EigenSettings,
) -> Result<EigenSolution, ReductionError> {
    check_square_pair(K, M)?;
    krylov_dimension(settings, K.nrows())?;
    let sigma = settings.shift.resolve(K, M)?;
    let factor = ShiftInvert::new(K, M, sigma)?;
    factor.lowest_modes(K, M, settings)
}

/// A Cholesky factorisation $\mathbf P(\mathbf K - \sigma\mathbf M)\mathbf P^T = \mathbf
/// L\mathbf L^T$, usable both for solves (constraint modes
/// $\boldsymbol\Psi = -\mathbf K_{ii}^{-1}\mathbf K_{ib}$, theory guide §3) and for the
/// shift-invert eigensolver, so that Craig-Bampton needs one factorisation of
/// $\mathbf K_{ii}$ for both.
#[derive(Debug)]
pub struct ShiftInvert {
    sigma: f64,
    /// $\mathbf P(\mathbf K - \sigma\mathbf M)\mathbf P^T = \mathbf L\mathbf L^T$.
    factor: fe_model::SparseCholesky,
    /// $\|\mathbf K\|_\infty + |\sigma|\,\|\mathbf M\|_\infty \ge \|\mathbf K - \sigma\mathbf
    /// M\|_\infty$, for the backward error of refined solves.
    A_norm: f64,
    /// Largest number of entries in a column of $\mathbf K$ or $\mathbf M$.
    max_column: usize,
    /// Solves with the factor so far (per right-hand side), for [`EigenSolution::factor_solves`].
    solves: std::sync::atomic::AtomicUsize,
}

impl ShiftInvert {
    /// Factor $\mathbf K - \sigma\mathbf M$ (faer sparse Cholesky, AMD ordering, the global
    /// parallelism [`faer::get_global_parallelism`]). Only the lower triangle is read by the
    /// factorisation; both must be stored. With $\sigma = 0$, `M` is only checked, not read.
    /// [`ShiftInvert::with_settings`] chooses the ordering.
    ///
    /// # Errors
    /// - [`ReductionError::DimensionMismatch`]: `K`, `M` not square of the same size.
    /// - [`ReductionError::InvalidSettings`]: $\sigma$ not finite.
    /// - [`ReductionError::NotSymmetric`]: one triangle missing or unsymmetric values.
    /// - [`ReductionError::MassNotPositiveDefinite`]: some $M_{ii} \le 0$.
    /// - [`ReductionError::SingularStiffness`]: $\sigma = 0$ and $\mathbf K$ singular (a pivot
    ///   $\le$ [`SINGULAR_PIVOT_RATIO`] times its diagonal).
    /// - [`ReductionError::ShiftedNotPositiveDefinite`]: $\sigma \neq 0$ and
    ///   $\mathbf K - \sigma\mathbf M$ not positive definite.
    /// - [`ReductionError::Factorization`]: out of memory or index overflow in faer.
    pub fn new(
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        sigma: f64,
    ) -> Result<Self, ReductionError> {
        Self::with_settings(K, M, sigma, None, FillOrdering::Amd, &FactorSettings::DOUBLE)
    }

    /// [`ShiftInvert::new`] with a chosen fill-reducing ordering (`fe_model::ordering`):
    /// `points[d]` is the position of dof `d` (its node), which nested dissection needs;
    /// [`FillOrdering::Auto`] takes nested dissection for large models with points, AMD
    /// otherwise; and with the precision of the factor chosen by `settings`
    /// ([`FactorPrecision`]): after the symbolic analysis, the peak the factor brings, its
    /// values plus the larger of the factorisation's workspace (faer's, and the f32 copy of
    /// the matrix in single precision; freed when the factorisation returns) and the caller's
    /// reserve in that precision ([`FactorSettings`]), is compared with [`MEMORY_FRACTION`] of
    /// [`fe_model::available_memory`] (measured then, so with $\mathbf K$ and $\mathbf M$
    /// already in memory). Where the available memory cannot be read, nothing is refused and
    /// [`FactorPrecision::Auto`] takes double precision. A single-precision factor is used
    /// through refined solves ([`ShiftInvert::solve_refined`]) and the $\mathbf M$-inner-product
    /// Lanczos (module docs).
    ///
    /// # Errors
    /// Those of [`ShiftInvert::new`]; [`ReductionError::Factorization`] if `points` does not
    /// have one finite entry per row; [`ReductionError::FactorDoesNotFit`] (with an empty
    /// body name, for the caller to fill in);
    /// [`ReductionError::SinglePrecisionBreakdown`] for a pivot of the single-precision factor
    /// that is not positive or below [`SINGLE_PIVOT_RATIO`].
    pub fn with_settings(
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        sigma: f64,
        points: Option<&[[f64; 3]]>,
        ordering: FillOrdering,
        settings: &FactorSettings,
    ) -> Result<Self, ReductionError> {
        check_square_pair(K, M)?;
        if !sigma.is_finite() {
            return Err(ReductionError::InvalidSettings {
                what: format!("shift must be finite, got {sigma}"),
            });
        }
        check_symmetric(K, "K")?;
        check_symmetric(M, "M")?;
        let M_diag = diagonal(M);
        check_mass_diagonal(&M_diag)?;

        // The matrix to factor, lower triangle. With sigma = 0 faer reads the lower triangle
        // of K in place; otherwise K - sigma M is formed once (lower triangle only, half the
        // memory of the full matrix).
        let shifted;
        let A = if sigma == 0.0 {
            K
        } else {
            shifted = lower_shifted(K, M, sigma);
            shifted.as_ref()
        };
        let A_diag = diagonal(A);
        let failed = |e: CholeskyError| ReductionError::Factorization(e.to_string());
        let symbolic = SymbolicFactor::analyse(A.symbolic(), points, ordering).map_err(failed)?;
        let precision = choose_precision(&symbolic, A.val().len(), settings)?;
        let factor = symbolic.factor(A, precision).map_err(|e| match (e, precision) {
            (CholeskyError::NonPositivePivot { dof }, Precision::Single) => single_breakdown(dof, 0.0),
            (CholeskyError::NonPositivePivot { dof }, Precision::Double) => not_positive_definite(dof, 0.0, sigma),
            (other, _) => failed(other),
        })?;
        // A positive pivot can still be round-off (see SINGULAR_PIVOT_RATIO, SINGLE_PIVOT_RATIO).
        let perm_fwd = factor.perm_fwd();
        let (worst_index, worst_ratio) = factor
            .pivots()
            .into_iter()
            .enumerate()
            .map(|(i, l)| (i, l * l / A_diag[perm_fwd[i]]))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 1.0));
        match precision {
            Precision::Double if worst_ratio.is_nan() || worst_ratio <= SINGULAR_PIVOT_RATIO => {
                return Err(not_positive_definite(perm_fwd[worst_index], worst_ratio, sigma));
            }
            Precision::Single if worst_ratio.is_nan() || worst_ratio <= SINGLE_PIVOT_RATIO => {
                return Err(single_breakdown(perm_fwd[worst_index], worst_ratio));
            }
            _ => {}
        }
        let max_column =
            |A: SparseColMatRef<'_, usize, f64>| (0..A.ncols()).map(|j| A.col_range(j).len()).max().unwrap_or(0);
        Ok(Self {
            sigma,
            factor,
            A_norm: norm_inf(K) + sigma.abs() * norm_inf(M),
            max_column: max_column(K).max(max_column(M)),
            solves: std::sync::atomic::AtomicUsize::new(0),
        })
    }

    /// The precision of the factor.
    pub fn precision(&self) -> Precision {
        self.factor.precision()
    }

    /// The fill-reducing ordering used ([`FillOrdering::Amd`] or
    /// [`FillOrdering::NestedDissection`]).
    pub fn ordering(&self) -> FillOrdering {
        self.factor.ordering()
    }

    /// The shift $\sigma$ of this factorisation.
    pub fn shift(&self) -> f64 {
        self.sigma
    }

    /// Dimension $n$.
    pub fn nrows(&self) -> usize {
        self.factor.nrows()
    }

    /// Number of stored values of $\mathbf L$ (supernodal storage includes explicit zeros).
    pub fn factor_len(&self) -> usize {
        self.factor.factor_len()
    }

    /// Subtrees solved in parallel and the fraction of the factor above them
    /// (`fe_model::SparseCholesky::parallel_subtrees`).
    pub fn parallel_subtrees(&self) -> (usize, f64) {
        self.factor.parallel_subtrees()
    }

    /// Floating-point operations of the factorisation ($\sum_j c_j^2$, `fe_model::factor_flops`).
    pub fn factor_flops(&self) -> f64 {
        self.factor.flops()
    }

    /// Solves $(\mathbf K - \sigma\mathbf M)\mathbf X = \mathbf B$ in place, `rhs` holding
    /// $\mathbf B$ on entry and $\mathbf X$ on exit (one column per right-hand side; for the
    /// constraint modes, $\mathbf B = -\mathbf K_{ib}$ with $\sigma = 0$).
    ///
    /// # Panics
    /// If `rhs.nrows()` differs from [`ShiftInvert::nrows`].
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        self.factor.solve_in_place(rhs);
    }

    /// Solves $(\mathbf K - \sigma\mathbf M)\mathbf X = \mathbf B$ in place to the accuracy of
    /// a double-precision solve, whatever the factor's precision. With a double-precision
    /// factor this is [`ShiftInvert::solve_in_place`]. With a single-precision one it is
    /// iterative refinement (Wilkinson; Moler 1967, J. ACM 14; LAPACK's `dsposv`):
    /// $\mathbf X_0 = \hat{\mathbf A}^{-1}\mathbf B$ with the f32 factor, then
    /// $\mathbf R = \mathbf B - (\mathbf K - \sigma\mathbf M)\mathbf X_k$ in f64 with the
    /// matrices themselves and $\mathbf X_{k+1} = \mathbf X_k + \hat{\mathbf A}^{-1}\mathbf R$,
    /// column by column, while a correction at least halves the normwise backward error
    /// $$\eta = \frac{\|\mathbf r\|_\infty}{\|\mathbf A\|_\infty\|\mathbf x\|_\infty +
    /// \|\mathbf b\|_\infty}$$
    /// (Rigal & Gaches 1967, J. ACM 14: the smallest relative change of $\mathbf A$ and
    /// $\mathbf b$ that makes $\mathbf x$ exact) and it is above [`REFINED_FLOOR`]
    /// $\varepsilon_{64}$. That is a double-precision solve's accuracy: a backward-stable
    /// Cholesky solve gives $\eta$ of a few $\varepsilon_{64}$, and the refinement stops only
    /// where the round-off of the residual's own evaluation stops it from falling. Stopping
    /// earlier, at the bound a double solve *guarantees* ($\eta_{64} = \max(\sqrt n,\ c)\,
    /// \varepsilon_{64}$, $c$ the most entries in a column plus 2, the test of LAPACK's
    /// mixed-precision `dsposv`), was not enough: on a 563k-dof tet10 body the Lanczos then
    /// stalled at residuals of $2.5\cdot 10^{-7}$ on $(\mathbf K, \mathbf M)$ for the lowest
    /// modes, whose residual is about $\eta\,\lambda_{max}/\lambda_1$. Each column's $\eta$
    /// falls by about $\kappa(\mathbf A)\,\varepsilon_{32}$ per step; a column that stops
    /// falling above $\eta_{64}$, or is still above it after [`MAX_REFINEMENT_STEPS`] steps,
    /// ends in [`ReductionError::RefinementFailed`] naming `what`, the column, the steps and
    /// $\eta$.
    ///
    /// `K` and `M` must be the matrices that were factored. Returns the number of solves with
    /// the factor (1 for a double-precision factor).
    ///
    /// # Errors
    /// [`ReductionError::RefinementFailed`] (with an empty body name) as above.
    ///
    /// # Panics
    /// If `rhs.nrows()` differs from [`ShiftInvert::nrows`].
    pub fn solve_refined(
        &self,
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        mut rhs: MatMut<'_, f64>,
        what: &dyn Fn() -> String,
    ) -> Result<usize, ReductionError> {
        use std::sync::atomic::Ordering::Relaxed;
        let (n, k) = rhs.shape();
        if self.precision() == Precision::Double {
            self.factor.solve_in_place(rhs);
            self.solves.fetch_add(k, Relaxed);
            return Ok(1);
        }
        let par = faer::get_global_parallelism();
        let B = rhs.to_owned();
        let b_norm: Vec<f64> = (0..k).map(|j| B.col(j).norm_max()).collect();
        let target = (n as f64).sqrt().max(self.max_column as f64 + 2.0) * f64::EPSILON;
        self.factor.solve_in_place(rhs.rb_mut());
        let mut steps = 1;
        let mut previous = vec![f64::INFINITY; k];
        let mut done = vec![false; k];
        loop {
            // R = B - (K - sigma M) X, in f64 with the matrices themselves.
            let mut R = &B - symmetric_times(K, rhs.rb(), par);
            if self.sigma != 0.0 {
                R += symmetric_times(M, rhs.rb(), par) * faer::Scale(self.sigma);
            }
            let eta: Vec<f64> = (0..k)
                .map(|j| R.col(j).norm_max() / (self.A_norm * rhs.rb().col(j).norm_max() + b_norm[j]))
                .collect();
            for j in 0..k {
                if done[j] {
                    continue;
                }
                // Refined while a correction at least halves the backward error, down to the
                // round-off of its own evaluation: then it is what a double solve gives.
                let stalled = !(eta[j] <= 0.5 * previous[j]) || steps >= MAX_REFINEMENT_STEPS;
                if eta[j] <= REFINED_FLOOR * f64::EPSILON || (stalled && eta[j] <= target) {
                    done[j] = true;
                } else if stalled {
                    return Err(ReductionError::RefinementFailed {
                        body: String::new(),
                        what: what(),
                        column: j,
                        steps,
                        backward_error: eta[j],
                        target,
                    });
                }
            }
            if done.iter().all(|&d| d) {
                break;
            }
            for (j, &d) in done.iter().enumerate() {
                if d {
                    R.col_mut(j).fill(0.0);
                }
            }
            self.factor.solve_in_place(R.as_mut());
            rhs += &R;
            previous = eta;
            steps += 1;
        }
        self.solves.fetch_add(k * steps, Relaxed);
        Ok(steps)
    }

    /// The $m$ lowest eigenpairs of $(\mathbf K, \mathbf M)$ from this factorisation of
    /// $\mathbf K - \sigma\mathbf M$ (the [module docs](self) describe the method).
    /// `settings.shift` is not read: the shift is the factor's. `K` and `M` must be the
    /// matrices that were factored; they give the Rayleigh-Ritz step and the residuals.
    ///
    /// # Errors
    /// - [`ReductionError::DimensionMismatch`], [`ReductionError::InvalidModeCount`],
    ///   [`ReductionError::InvalidSettings`] for bad input.
    /// - [`ReductionError::MassNotPositiveDefinite`] if $\mathbf M$ shows indefinite on the
    ///   computed subspace (a wanted Ritz value $\mu \le 0$, or
    ///   $\boldsymbol\Phi^T\mathbf M\boldsymbol\Phi$ not positive definite).
    /// - [`ReductionError::EigenNotConverged`] if Lanczos runs out of restarts, or a residual
    ///   stays above `settings.tolerance` (and its round-off floor) after [`MAX_ATTEMPTS`]
    ///   rounds.
    pub fn lowest_modes(
        &self,
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        settings: &EigenSettings,
    ) -> Result<EigenSolution, ReductionError> {
        self.lowest_modes_with_progress(K, M, settings, &mut |_, _, _| {})
    }

    /// [`ShiftInvert::lowest_modes`], calling `progress(converged, wanted, applications)`
    /// whenever the number of wanted Ritz pairs that meet the Krylov tolerance changes (and
    /// at every restart), for a progress bar.
    ///
    /// # Errors
    /// Those of [`ShiftInvert::lowest_modes`].
    pub fn lowest_modes_with_progress(
        &self,
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        settings: &EigenSettings,
        progress: &mut dyn FnMut(usize, usize, usize),
    ) -> Result<EigenSolution, ReductionError> {
        // One run with the block size of `settings`; a second with single vectors where an
        // automatic block size did not converge.
        with_single_vector_retry(settings, self.nrows(), |settings| {
            let n = self.nrows();
            check_square_pair(K, M)?;
            if K.nrows() != n {
                return Err(ReductionError::DimensionMismatch {
                    what: "K of ShiftInvert::lowest_modes (must be the factored matrix)",
                    expected_rows: n,
                    expected_cols: n,
                    rows: K.nrows(),
                    cols: K.ncols(),
                });
            }
            let p = krylov_dimension(settings, n)?;
            let m = settings.n_modes;
            let b = block_size(settings, n);
            let op = Operator::new(self, M);
            let whole = WholeOperator { factor: self, K, M };
            let krylov = match self.precision() {
                Precision::Double => Krylov::Split(&op),
                Precision::Single => Krylov::Whole(&whole),
            };
            let solves_before = self.solves.load(std::sync::atomic::Ordering::Relaxed);
            let solves = || self.solves.load(std::sync::atomic::Ordering::Relaxed) - solves_before;
            if p + 1 >= n {
                if n > DENSE_LIMIT {
                    return Err(ReductionError::InvalidSettings {
                        what: format!(
                            "the Krylov subspace dimension {p} leaves no room in n = {n}: ask for fewer modes or a \
                             smaller krylov_dim"
                        ),
                    });
                }
                let Y = match krylov {
                    Krylov::Split(op) => dense_operator_eigen(op, m)?,
                    Krylov::Whole(whole) => dense_whole_eigen(whole, m)?,
                };
                let mut sol = self.finish(K, M, Y, settings)?;
                sol.operator_applications = n;
                sol.factor_solves = match krylov {
                    Krylov::Split(_) => n,
                    Krylov::Whole(_) => solves(),
                };
                return Ok(sol);
            }

            progress(0, m, 0);
            // Blocks need room: k > m when the basis is full (p >= m + b), and n > p + b.
            let b = b.min(p - m).min(n - p - 1).max(1);
            let mut lanczos = Lanczos::new(krylov, p, b)?;
            let mut krylov_tolerance = settings.tolerance * KRYLOV_TOLERANCE_FACTOR;
            for attempt in 0..MAX_ATTEMPTS {
                let (mu, Y) = match lanczos.run(m, krylov_tolerance, settings.max_restarts, progress)? {
                    LanczosOutcome::Converged { mu, Y } => (mu, Y),
                    LanczosOutcome::NotConverged { unconverged } => {
                        return Err(ReductionError::EigenNotConverged {
                            requested: m,
                            converged: m - unconverged.len(),
                            failed_modes: unconverged,
                            worst_residual: f64::INFINITY,
                            tolerance: settings.tolerance,
                        })
                    }
                };
                if let Some(bad) = mu.iter().position(|&x| x <= 0.0) {
                    return Err(ReductionError::MassNotPositiveDefinite {
                        dof: None,
                        why: format!(
                            "the shift-invert operator L^-1 M L^-T has the eigenvalue {:.3e} <= 0 among the {m} \
                             largest in magnitude (Ritz value {bad})",
                            mu[bad]
                        ),
                    });
                }
                match self.finish(K, M, Y, settings) {
                    Ok(mut sol) => {
                        sol.operator_applications = lanczos.applications;
                        sol.factor_solves = match krylov {
                            Krylov::Split(_) => lanczos.applications,
                            Krylov::Whole(_) => solves(),
                        };
                        return Ok(sol);
                    }
                    // Continue Lanczos with the Krylov tolerance lowered by the shortfall (at least
                    // tenfold, at most a millionfold): module docs, "Tolerance".
                    Err(ReductionError::EigenNotConverged { worst_residual, .. }) if attempt + 1 < MAX_ATTEMPTS => {
                        krylov_tolerance *= (settings.tolerance / worst_residual).clamp(1e-6, 0.1);
                    }
                    Err(e) => return Err(e),
                }
            }
            unreachable!("the last attempt returns")
        })
    }

    /// Back-transformation $\boldsymbol\Phi = \mathbf P^T\mathbf L^{-T}\mathbf Y$ of the Ritz
    /// vectors `Y` of $\mathbf C$ (permuted order; with a single-precision factor `Y` are the
    /// Ritz vectors of $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$ and $\boldsymbol\Phi =
    /// \mathbf Y$), Rayleigh-Ritz, residual check.
    ///
    /// `Y` is taken by value and overwritten, and the Rayleigh-Ritz step works in place: this
    /// step holds the peak memory of a reduction (the factor, the Lanczos basis and these
    /// $n \times m$ blocks), and three $n \times m$ blocks are alive at most, not seven.
    fn finish(
        &self,
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        Y: Mat<f64>,
        settings: &EigenSettings,
    ) -> Result<EigenSolution, ReductionError> {
        let (n, m) = Y.shape();
        let Phi = match self.precision() {
            Precision::Double => {
                let par = faer::get_global_parallelism();
                let mut Z = Y;
                let mut mem = MemBuffer::new(self.factor.solve_scratch(m, par));
                self.factor.l_transpose_solve(Z.as_mut(), par, MemStack::new(&mut mem));
                let perm_inv = self.factor.perm_inv();
                Mat::<f64>::from_fn(n, m, |i, j| Z[(perm_inv[i], j)])
            }
            Precision::Single => Y,
        };
        let (eigenvalues, vectors, KPhi, MPhi) = rayleigh_ritz(K, M, Phi)?;
        let residuals: Vec<f64> = (0..m)
            .map(|j| relative_residual(KPhi.col(j), MPhi.col(j), eigenvalues[j], self.sigma))
            .collect();
        // A residual at the round-off floor of its own evaluation passes whatever the tolerance.
        let failed_modes: Vec<usize> = (0..m)
            .filter(|&j| {
                let floor = || {
                    residual_floor(
                        K,
                        M,
                        vectors.col(j),
                        KPhi.col(j),
                        MPhi.col(j),
                        eigenvalues[j],
                        self.sigma,
                    )
                };
                !(residuals[j] <= settings.tolerance) && !(residuals[j] <= floor())
            })
            .collect();
        if !failed_modes.is_empty() {
            let worst_residual = failed_modes.iter().map(|&j| residuals[j]).fold(0.0_f64, |a, b| {
                if b.is_nan() {
                    f64::INFINITY
                } else {
                    a.max(b)
                }
            });
            return Err(ReductionError::EigenNotConverged {
                requested: m,
                converged: m - failed_modes.len(),
                failed_modes,
                worst_residual,
                tolerance: settings.tolerance,
            });
        }
        Ok(EigenSolution {
            eigenvalues,
            vectors,
            residuals,
            shift: self.sigma,
            operator_applications: 0,
            factor_solves: 0,
        })
    }
}

/// Rayleigh-Ritz for $(\mathbf K, \mathbf M)$ on the span of the columns of `Phi`:
/// with $\mathbf B = \boldsymbol\Phi^T\mathbf M\boldsymbol\Phi = \mathbf R\mathbf R^T$
/// (dense Cholesky) and $\mathbf R^{-1}\boldsymbol\Phi^T\mathbf K\boldsymbol\Phi\mathbf R^{-T}
/// = \mathbf S\boldsymbol\Lambda\mathbf S^T$, the Ritz vectors are
/// $\boldsymbol\Phi\mathbf R^{-T}\mathbf S$ (Parlett, "The Symmetric Eigenvalue Problem",
/// SIAM 1998, §11.4 and §15.1). Returns $\boldsymbol\Lambda$ ascending, the vectors (each with
/// its largest-magnitude entry positive), and their products with $\mathbf K$ and $\mathbf M$.
/// `Phi` becomes the vectors, and the products are rotated in place (`times_in_place`): no
/// $n \times m$ block beyond the three.
#[allow(clippy::type_complexity)]
fn rayleigh_ritz(
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
    Phi: Mat<f64>,
) -> Result<(Vec<f64>, Mat<f64>, Mat<f64>, Mat<f64>), ReductionError> {
    let (n, m) = Phi.shape();
    let par = faer::get_global_parallelism();
    let mut KPhi = symmetric_times(K, Phi.as_ref(), par);
    let mut MPhi = symmetric_times(M, Phi.as_ref(), par);
    let symmetrise = |A: Mat<f64>| Mat::<f64>::from_fn(m, m, |i, j| 0.5 * (A[(i, j)] + A[(j, i)]));
    let A = symmetrise(Phi.transpose() * &KPhi);
    let B = symmetrise(Phi.transpose() * &MPhi);
    let (eigenvalues, mut T) = symmetric_definite_eigen(
        A,
        B.as_ref(),
        "Phi^T M Phi of the computed modes is not positive definite",
        "the Ritz problem",
    )?;
    // The sign convention on the columns of Phi T.
    let mut vectors = Phi;
    times_in_place(vectors.as_mut(), T.as_ref(), par);
    for j in 0..m {
        let col = vectors.col(j);
        let mut largest = 0.0_f64;
        for i in 0..n {
            if col[i].abs() > largest.abs() {
                largest = col[i];
            }
        }
        if largest < 0.0 {
            T.col_mut(j).iter_mut().for_each(|t| *t = -*t);
            vectors.col_mut(j).iter_mut().for_each(|v| *v = -*v);
        }
    }
    times_in_place(KPhi.as_mut(), T.as_ref(), par);
    times_in_place(MPhi.as_mut(), T.as_ref(), par);
    Ok((eigenvalues, vectors, KPhi, MPhi))
}

/// $\mathbf A_{:,0:q} \leftarrow \mathbf A\mathbf S$ for $\mathbf A$ $n \times k$ and
/// $\mathbf S$ $k \times q$, $q \le k$, in place by blocks of [`GS_ROWS`] rows (in parallel
/// with `par`), each through a small copy: neither an $n \times q$ result nor the packed copy of
/// $\mathbf A$ that faer's parallel product keeps for its threads (an $n \times k$ buffer that
/// stays allocated: 130 MB of resident memory after the thick restart of the 203 616-dof
/// Craig-Bampton block).
fn times_in_place(A: MatMut<'_, f64>, S: MatRef<'_, f64>, par: Par) {
    let q = S.ncols();
    assert!(S.nrows() == A.ncols() && q <= A.ncols());
    let block = |rows: MatMut<'_, f64>| {
        let mut product = Mat::<f64>::zeros(rows.nrows(), q);
        matmul(product.as_mut(), Accum::Replace, rows.rb(), S, 1.0, Par::Seq);
        rows.get_mut(.., 0..q).copy_from(&product);
    };
    match par {
        Par::Rayon(_) => A.par_row_chunks_mut(GS_ROWS).for_each(block),
        Par::Seq => {
            let mut A = A;
            let n = A.nrows();
            for i in (0..n).step_by(GS_ROWS) {
                block(A.rb_mut().subrows_mut(i, GS_ROWS.min(n - i)));
            }
        }
    }
}

/// $\mathbf A\mathbf S$ by blocks of [`GS_ROWS`] rows, as [`times_in_place`] (no packed copy
/// of $\mathbf A$ kept by faer's parallel product).
fn times(A: MatRef<'_, f64>, S: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(A.nrows(), S.ncols());
    let block = |(mut out, rows): (MatMut<'_, f64>, MatRef<'_, f64>)| {
        matmul(out.rb_mut(), Accum::Replace, rows, S, 1.0, Par::Seq);
    };
    match par {
        Par::Rayon(_) => out
            .as_mut()
            .par_row_chunks_mut(GS_ROWS)
            .zip(A.par_row_chunks(GS_ROWS))
            .for_each(block),
        Par::Seq => {
            let n = A.nrows();
            for i in (0..n).step_by(GS_ROWS) {
                let rows = GS_ROWS.min(n - i);
                block((out.as_mut().subrows_mut(i, rows), A.subrows(i, rows)));
            }
        }
    }
    out
}

/// Relative residual of an eigenpair,
/// $$r = \frac{\|\mathbf K\boldsymbol\phi - \lambda\mathbf M\boldsymbol\phi\|_2}
/// {\max(\|\mathbf K\boldsymbol\phi\|_2,\ |\lambda - \sigma|\,\|\mathbf M\boldsymbol\phi\|_2)}.$$
///
/// For $\sigma = 0$ this is the usual $\|\mathbf K\boldsymbol\phi - \lambda\mathbf
/// M\boldsymbol\phi\| / \|\mathbf K\boldsymbol\phi\|$ with the guard
/// $|\lambda|\,\|\mathbf M\boldsymbol\phi\|$. For a rigid-body mode ($\lambda \approx 0$,
/// $\mathbf K\boldsymbol\phi \approx 0$) that guard is itself round-off and the ratio would be
/// $O(1)$ for any vector. The numerator is also the residual of the shifted pencil,
/// $(\mathbf K - \sigma\mathbf M)\boldsymbol\phi - (\lambda - \sigma)\mathbf M\boldsymbol\phi$,
/// whose natural scale is $|\lambda - \sigma|\,\|\mathbf M\boldsymbol\phi\|$: a rigid mode is
/// measured against the inertia forces at the shift, which is the accuracy shift-invert
/// delivers ($\mu = 1/(\lambda - \sigma)$, relative).
pub fn relative_residual(KPhi: ColRef<'_, f64>, MPhi: ColRef<'_, f64>, lambda: f64, sigma: f64) -> f64 {
    let r = (KPhi - MPhi * lambda).norm_l2();
    let scale = KPhi.norm_l2().max((lambda - sigma).abs() * MPhi.norm_l2());
    r / scale
}

/// Round-off floor of [`relative_residual`]: the worst-case error of evaluating
/// $\mathbf K\boldsymbol\phi - \lambda\mathbf M\boldsymbol\phi$ in floating point,
/// $\gamma_c\,\|\,|\mathbf K||\boldsymbol\phi| + |\lambda|\,|\mathbf M||\boldsymbol\phi|\,\|_2$
/// with $\gamma_c = c\varepsilon/(1 - c\varepsilon)$ and $c$ = 2 + the most entries in a
/// column (Higham, "Accuracy and Stability of Numerical Algorithms", SIAM 2002, §3.1 and
/// §3.5), over the scale of [`relative_residual`].
///
/// It is about $\varepsilon\lambda_{max}/\lambda_k$ for a flexible mode and
/// $\varepsilon\lambda_{max}/|\sigma|$ for a rigid one, and can exceed a tolerance of `1e-8`
/// (the lowest mode of a fine mesh or a slender beam, the rigid modes with [`Shift::Auto`]):
/// no pair can be verified below it, so a residual at or below the floor is accepted.
pub fn residual_floor(
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
    phi: ColRef<'_, f64>,
    Kphi: ColRef<'_, f64>,
    Mphi: ColRef<'_, f64>,
    lambda: f64,
    sigma: f64,
) -> f64 {
    let n = phi.nrows();
    let max_col = |A: SparseColMatRef<'_, usize, f64>| (0..A.ncols()).map(|j| A.col_range(j).len()).max().unwrap_or(0);
    let c = (2 + max_col(K).max(max_col(M))) as f64;
    let gamma = c * f64::EPSILON / (1.0 - c * f64::EPSILON);
    // (|A| |phi|)_i from column i: A is symmetric, so its column is its row.
    let abs_product = |A: SparseColMatRef<'_, usize, f64>, i: usize| -> f64 {
        A.col_range(i)
            .map(|p| A.val()[p].abs() * phi[A.row_idx()[p]].abs())
            .sum()
    };
    let bound = (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let b = abs_product(K, i) + lambda.abs() * abs_product(M, i);
            b * b
        })
        .sum::<f64>()
        .sqrt();
    let scale = Kphi.norm_l2().max((lambda - sigma).abs() * Mphi.norm_l2());
    gamma * bound / scale
}

/// $\mathbf C = \mathbf L^{-1}\mathbf P\mathbf M\mathbf P^T\mathbf L^{-T}$ as a faer
/// [`LinOp`] (symmetric, so `conj_apply` is `apply`).
///
/// The product with $\mathbf P\mathbf M\mathbf P^T$ permutes the block to the order of
/// $\mathbf M$, multiplies and permutes back ($2nb$ copies, nothing next to the solves),
/// rather than holding a permuted copy of $\mathbf M$: at 200k dofs that copy was 264 MB
/// of the Lanczos stage's peak, and the product in the mesh's own order is as fast (the
/// nodes of a generated or meshed body are numbered with their neighbours close).
struct Operator<'a> {
    factor: &'a ShiftInvert,
    M: SparseColMatRef<'a, usize, f64>,
}

impl<'a> Operator<'a> {
    fn new(factor: &'a ShiftInvert, M: SparseColMatRef<'a, usize, f64>) -> Self {
        Self { factor, M }
    }
}

impl std::fmt::Debug for Operator<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Operator").field("n", &self.factor.nrows()).finish()
    }
}

impl LinOp<f64> for Operator<'_> {
    fn apply_scratch(&self, rhs_ncols: usize, par: Par) -> StackReq {
        self.factor.factor.solve_scratch(rhs_ncols, par)
    }

    fn nrows(&self) -> usize {
        self.factor.nrows()
    }

    fn ncols(&self) -> usize {
        self.factor.nrows()
    }

    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        let (n, k) = rhs.shape();
        let (mut z, stack) = temp_mat_zeroed::<f64, _, _>(n, k, stack);
        let mut z = z.as_mat_mut();
        z.copy_from(rhs);
        // z = L^{-T} y
        self.factor.factor.l_transpose_solve(z.rb_mut(), par, stack);
        // out = (P M P^T) z, reading M once for all k columns.
        let fwd = self.factor.factor.perm_fwd();
        let mut z_orig = Mat::<f64>::zeros(n, k);
        for c in 0..k {
            let (zc, mut oc) = (z.rb().col(c), z_orig.col_mut(c));
            for (i, &row) in fwd.iter().enumerate() {
                oc[row] = zc[i];
            }
        }
        let Mz = symmetric_times(self.M, z_orig.as_ref(), par);
        drop(z_orig);
        let mut out = out;
        for c in 0..k {
            let (mc, mut oc) = (Mz.col(c), out.rb_mut().col_mut(c));
            for (i, &row) in fwd.iter().enumerate() {
                oc[i] = mc[row];
            }
        }
        // out = L^{-1} out
        self.factor.factor.l_solve(out, par, stack);
    }

    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack)
    }
}

/// $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$ by whole refined solves
/// ([`ShiftInvert::solve_refined`]), self-adjoint in the $\mathbf M$ inner product: the
/// operator of the Lanczos with a single-precision factor (module docs). It is applied to
/// $\mathbf M\mathbf V$, which the $\mathbf M$-inner-product Lanczos keeps.
struct WholeOperator<'a> {
    factor: &'a ShiftInvert,
    K: SparseColMatRef<'a, usize, f64>,
    M: SparseColMatRef<'a, usize, f64>,
}

impl WholeOperator<'_> {
    /// `x` $\leftarrow (\mathbf K - \sigma\mathbf M)^{-1}$`x` for `x` $= \mathbf M\mathbf v$;
    /// `first` is the index of the first vector among all applications, for the error.
    fn solve(&self, x: MatMut<'_, f64>, first: usize) -> Result<(), ReductionError> {
        let k = x.ncols();
        self.factor
            .solve_refined(self.K, self.M, x, &|| {
                format!(
                    "the Lanczos operator (K - sigma M)^-1 M, vectors {first} to {}",
                    first + k - 1
                )
            })
            .map(|_| ())
    }
}

/// The operator of [`Lanczos`] and its inner product.
#[derive(Clone, Copy)]
enum Krylov<'a> {
    /// $\mathbf C = \mathbf L^{-1}\mathbf P\mathbf M\mathbf P^T\mathbf L^{-T}$, Euclidean inner
    /// product (double-precision factor).
    Split(&'a Operator<'a>),
    /// $(\mathbf K - \sigma\mathbf M)^{-1}\mathbf M$, $\mathbf M$ inner product
    /// (single-precision factor).
    Whole(&'a WholeOperator<'a>),
}

impl Krylov<'_> {
    fn nrows(&self) -> usize {
        match self {
            Krylov::Split(op) => op.nrows(),
            Krylov::Whole(op) => op.factor.nrows(),
        }
    }
}

/// The dense path of [`WholeOperator`]: $\mathbf S = \mathbf M(\mathbf K - \sigma\mathbf
/// M)^{-1}\mathbf M$ from $n$ refined solves, the symmetric-definite problem $\mathbf S\mathbf
/// y = \mu\mathbf M\mathbf y$ through the dense Cholesky factor of $\mathbf M$, and the $m$
/// largest $\mu$: their vectors (descending $\mu$) approximate the modes themselves.
fn dense_whole_eigen(op: &WholeOperator<'_>, m: usize) -> Result<Mat<f64>, ReductionError> {
    let n = op.factor.nrows();
    let par = faer::get_global_parallelism();
    let M = symmetric_times(op.M, Mat::<f64>::identity(n, n).as_ref(), par);
    let mut Z = M.clone();
    op.solve(Z.as_mut(), 0)?;
    let S = &M * &Z;
    let S = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (S[(i, j)] + S[(j, i)]));
    let (values, Y) = symmetric_definite_eigen(
        S,
        M.as_ref(),
        "its dense Cholesky factorisation failed",
        "the shift-invert operator",
    )?;
    largest(&values, Y.as_ref(), m)
}

/// The dense symmetric-definite eigenproblem $\mathbf A\mathbf x = \lambda\mathbf B\mathbf x$
/// ($\mathbf A$, $\mathbf B$ symmetric): with $\mathbf B = \mathbf R\mathbf R^T$ and
/// $\mathbf R^{-1}\mathbf A\mathbf R^{-T} = \mathbf S\boldsymbol\Lambda\mathbf S^T$, the
/// eigenvalues ascending and the $\mathbf B$-orthonormal vectors $\mathbf R^{-T}\mathbf S$.
/// `not_definite` says why a failed Cholesky factorisation of $\mathbf B$ means an indefinite
/// mass; `what` names the problem for the dense eigensolver's error.
fn symmetric_definite_eigen(
    A: Mat<f64>,
    B: MatRef<'_, f64>,
    not_definite: &str,
    what: &str,
) -> Result<(Vec<f64>, Mat<f64>), ReductionError> {
    let par = faer::get_global_parallelism();
    let llt = B
        .llt(Side::Lower)
        .map_err(|_| ReductionError::MassNotPositiveDefinite {
            dof: None,
            why: not_definite.into(),
        })?;
    let R = llt.L();
    // G = R^{-1} A R^{-T}
    let mut G = A;
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(R, G.as_mut(), par);
    let mut G = G.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(R, G.as_mut(), par);
    let n = G.nrows();
    let G = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (G[(i, j)] + G[(j, i)]));
    let (values, mut T) = scaled_self_adjoint_eigen(G.as_ref(), what)?;
    // T = R^{-T} S
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(R.transpose(), T.as_mut(), par);
    Ok((values, T))
}

/// The error for a failed or singular factorisation of $\mathbf K - \sigma\mathbf M$ at
/// (original) `dof`.
fn not_positive_definite(dof: usize, pivot_ratio: f64, sigma: f64) -> ReductionError {
    if sigma == 0.0 {
        ReductionError::SingularStiffness { dof, pivot_ratio }
    } else {
        ReductionError::ShiftedNotPositiveDefinite {
            shift: sigma,
            dof,
            pivot_ratio,
            hint: if sigma > 0.0 {
                "the shift is above the lowest eigenvalue; lower it"
            } else {
                "K or M is indefinite, or the shift is too close to zero for a free body"
            },
        }
    }
}

/// The error for a pivot of a single-precision factor at (original) `dof` that is not
/// positive (`pivot_ratio` 0) or below [`SINGLE_PIVOT_RATIO`].
fn single_breakdown(dof: usize, pivot_ratio: f64) -> ReductionError {
    ReductionError::SinglePrecisionBreakdown {
        body: String::new(),
        at: format!("dof {dof}"),
        pivot_ratio,
    }
}

/// $\|\mathbf A\|_\infty$, the largest absolute row sum (the column sums of a symmetric matrix).
fn norm_inf(A: SparseColMatRef<'_, usize, f64>) -> f64 {
    (0..A.ncols())
        .map(|j| A.col_range(j).map(|p| A.val()[p].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// The precision of the factor for `settings` (see [`ShiftInvert::with_settings`]), from the
/// symbolic analysis of a matrix with `stored` stored entries.
fn choose_precision(
    symbolic: &SymbolicFactor,
    stored: usize,
    settings: &FactorSettings,
) -> Result<Precision, ReductionError> {
    // The workspace is freed before the caller allocates its reserve: the peak is the factor
    // plus the larger of the two.
    let needed =
        |p: Precision| symbolic.factor_len() * p.bytes() + symbolic.workspace_bytes(p, stored).max(settings.reserve(p));
    let Some(available) = fe_model::available_memory() else {
        return Ok(match settings.precision {
            FactorPrecision::Single => Precision::Single,
            FactorPrecision::Auto | FactorPrecision::Double => Precision::Double,
        });
    };
    let budget = MEMORY_FRACTION * available as f64;
    let fits = |p: Precision| needed(p) as f64 <= budget;
    let refuse = |p: Precision, hint: &'static str| {
        let gb = |bytes: f64| bytes / 1e9;
        ReductionError::FactorDoesNotFit {
            body: String::new(),
            precision: p.name(),
            factor_values: symbolic.factor_len() / 1_000_000,
            factor_gb: gb((symbolic.factor_len() * p.bytes()) as f64),
            needed_gb: gb(needed(p) as f64),
            available_gb: gb(budget),
            hint,
        }
    };
    const SMALLER: &str = "coarsen the mesh, or reduce on a machine with more memory";
    match settings.precision {
        FactorPrecision::Double if fits(Precision::Double) => Ok(Precision::Double),
        FactorPrecision::Double => Err(refuse(
            Precision::Double,
            "set factor = \"auto\" or \"single\" to factor in single precision with refined solves",
        )),
        FactorPrecision::Single if fits(Precision::Single) => Ok(Precision::Single),
        FactorPrecision::Single => Err(refuse(Precision::Single, SMALLER)),
        FactorPrecision::Auto if fits(Precision::Double) => Ok(Precision::Double),
        FactorPrecision::Auto if fits(Precision::Single) => Ok(Precision::Single),
        FactorPrecision::Auto => Err(refuse(Precision::Single, SMALLER)),
    }
}

/// $\mathbf A\mathbf X$ for a sparse symmetric $\mathbf A$ stored with both triangles (CSC;
/// unsorted or repeated row indices allowed): a gather, row by row in parallel, $(\mathbf
/// A\mathbf X)_{i\cdot} = \sum_p a_p\,\mathbf X_{r_p\cdot}$ over column $i$ (which is row
/// $i$), on a row-major copy of $\mathbf X$ so that the $k$ values of a row sit side by side:
/// $\mathbf A$ is read once for all $k$ columns, and each thread writes its own rows. faer's
/// sparse-dense product scatters column by column, on one thread.
pub(crate) fn symmetric_times(A: SparseColMatRef<'_, usize, f64>, X: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let (n, k) = X.shape();
    assert_eq!(
        A.ncols(),
        n,
        "symmetric_times: A is {} x {}, X has {n} rows",
        A.nrows(),
        A.ncols()
    );
    let (row_idx, val) = (A.row_idx(), A.val());
    if k == 1 {
        // One column (single-vector Lanczos): no row-major copy.
        let x: Vec<f64> = X.col(0).iter().copied().collect();
        let row = |i: usize| -> f64 { A.col_range(i).map(|p| val[p] * x[row_idx[p]]).sum() };
        let mut out = vec![0.0; n];
        match par {
            Par::Rayon(_) => out
                .par_iter_mut()
                .with_min_len(4096)
                .enumerate()
                .for_each(|(i, o)| *o = row(i)),
            Par::Seq => out.iter_mut().enumerate().for_each(|(i, o)| *o = row(i)),
        }
        return Mat::from_fn(n, 1, |i, _| out[i]);
    }
    // Row-major copies in blocks of rows (a block of both layouts stays in cache; a
    // column-by-column transpose misses it at every entry), in parallel with `par`.
    let parallel = matches!(par, Par::Rayon(_));
    let mut x_rows = vec![0.0; n * k];
    if k > 0 {
        let to_rows = |(b, rows): (usize, &mut [f64])| {
            let (i0, len) = (b * TRANSPOSE_ROWS, rows.len() / k);
            for c in 0..k {
                for (r, &x) in X.col(c).subrows(i0, len).iter().enumerate() {
                    rows[r * k + c] = x;
                }
            }
        };
        if parallel {
            x_rows.par_chunks_mut(TRANSPOSE_ROWS * k).enumerate().for_each(to_rows);
        } else {
            x_rows.chunks_mut(TRANSPOSE_ROWS * k).enumerate().for_each(to_rows);
        }
    }
    let mut out_rows = vec![0.0; n * k];
    let row = |i: usize, o: &mut [f64]| {
        for p in A.col_range(i) {
            let (v, xr) = (val[p], &x_rows[row_idx[p] * k..][..k]);
            for (o, x) in o.iter_mut().zip(xr) {
                *o += v * x;
            }
        }
    };
    let mut out = Mat::<f64>::zeros(n, k);
    if k > 0 {
        let from_rows = |(rows, mut block): (&[f64], MatMut<'_, f64>)| {
            for c in 0..k {
                for (r, o) in block.rb_mut().col_mut(c).iter_mut().enumerate() {
                    *o = rows[r * k + c];
                }
            }
        };
        if parallel {
            out_rows
                .par_chunks_mut(k)
                .with_min_len(4096)
                .enumerate()
                .for_each(|(i, o)| row(i, o));
            out_rows
                .par_chunks(TRANSPOSE_ROWS * k)
                .zip(out.par_row_chunks_mut(TRANSPOSE_ROWS))
                .for_each(from_rows);
        } else {
            out_rows.chunks_mut(k).enumerate().for_each(|(i, o)| row(i, o));
            for (b, rows) in out_rows.chunks(TRANSPOSE_ROWS * k).enumerate() {
                from_rows((rows, out.as_mut().subrows_mut(b * TRANSPOSE_ROWS, rows.len() / k)));
            }
        }
    }
    out
}

/// Applies `op` with a freshly allocated workspace.
fn apply_alloc(op: &Operator<'_>, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par) {
    let mut mem = MemBuffer::new(op.apply_scratch(rhs.ncols(), par));
    op.apply(out, rhs, par, MemStack::new(&mut mem));
}

/// After re-orthogonalisation, a new Lanczos vector below this fraction of $\|\mathbf C
/// \mathbf v_j\|$ is round-off: the Krylov space is invariant (to working precision) and
/// Lanczos continues with a random direction ($\beta_j = 0$). $10^3\varepsilon$: the noise of
/// two Gram-Schmidt passes against at most a few hundred vectors.
const BREAKDOWN_RATIO: f64 = 1e3 * f64::EPSILON;

/// What [`Lanczos::run`] ends with.
enum LanczosOutcome {
    /// The `m` largest Ritz values $\mu$ (descending magnitude) and their Ritz vectors.
    Converged { mu: Vec<f64>, Y: Mat<f64> },
    /// Restarts exhausted; the wanted Ritz pairs (0-based, descending $|\mu|$) not converged.
    NotConverged { unconverged: Vec<usize> },
}

/// Ritz values of the projected matrix, descending in magnitude, with their eigenvectors.
struct Ritz {
    theta: Vec<f64>,
    S: Mat<f64>,
}

/// Thick-restart block Lanczos for the $m$ largest-magnitude eigenpairs of the symmetric
/// [`Operator`] (Wu & Simon 2000, "Thick-restart Lanczos method for large symmetric
/// eigenvalue problems", SIAM J. Matrix Anal. Appl. 22, §2-3; the symmetric case of Stewart's
/// Krylov-Schur, 2001; blocks as in Grimes, Lewis & Simon 1994, §3).
///
/// The Krylov decomposition $\mathbf C\mathbf V_k = \mathbf V_k\mathbf T_k +
/// \mathbf W\mathbf B\mathbf E_k^T$ is extended one block of $b$ vectors at a time:
/// $\mathbf C$ applied to the last block (one forward and one backward solve with $b$
/// right-hand sides: the factor is read once for $b$ vectors; `EigenSettings::block_size`
/// says when that pays), orthogonalised against all previous vectors by classical
/// Gram-Schmidt done twice, and orthonormalised within the block (QR, $\mathbf B = \mathbf R$).
/// After each step, $\mathbf T_k = \mathbf S\boldsymbol\Theta\mathbf S^T$ gives the Ritz pairs
/// and their residual estimates $\|\mathbf B\,\mathbf s_{k-b+1:k,j}\|$; a pair converges when
/// its estimate is below `tolerance` $\cdot|\theta_j|$ (relative, as ARPACK's). A full basis
/// ($k + b > p$) is restarted: keep the `keep` largest Ritz vectors,
/// $\mathbf V_{keep} \leftarrow \mathbf V_k\mathbf S_{keep}$, then the next block, with
/// $\mathbf T$ diagonal $\boldsymbol\Theta_{keep}$ bordered by the arrow
/// $\mathbf B\mathbf S_{k-b+1:k,1:keep}$. With $b = 1$ this is the single-vector method. No
/// locking: converged vectors keep being refined, which costs little and avoids the
/// bookkeeping that breaks faer's version (module docs).
struct Lanczos<'a> {
    op: Krylov<'a>,
    par: Par,
    p: usize,
    /// Block size $b$.
    b: usize,
    /// $n \times (p + b)$ basis, orthonormal in the operator's inner product.
    V: Mat<f64>,
    /// $\mathbf M\mathbf V$ with [`Krylov::Whole`] (the $\mathbf M$ inner products are dot
    /// products with it, and the operator's input); $0 \times 0$ with [`Krylov::Split`].
    MV: Mat<f64>,
    /// $p \times p$ projected matrix (arrowhead plus block tridiagonal).
    T: Mat<f64>,
    /// Coupling $\mathbf B$ ($b \times b$, upper triangular) of the next block after the last step.
    B: Mat<f64>,
    /// Size of the current decomposition: columns `0..k` of `V` and `T` are valid, columns
    /// `k..k + b` of `V` are the next block.
    k: usize,
    restarts: usize,
    applications: usize,
    last_ritz: Option<Ritz>,
    mem: MemBuffer,
    rng: u64,
}

impl<'a> Lanczos<'a> {
    /// Basis of dimension `p` with blocks of `b`, started from $\mathbf C$ applied to a fixed
    /// pseudo-random block (as ARPACK does for shift-invert: it removes the components that
    /// $\mathbf C$ damps, so the start lies in the range of the operator).
    fn new(op: Krylov<'a>, p: usize, b: usize) -> Result<Self, ReductionError> {
        let n = op.nrows();
        let par = faer::get_global_parallelism();
        let scratch = match op {
            Krylov::Split(op) => op.apply_scratch(b, par),
            Krylov::Whole(_) => StackReq::EMPTY,
        };
        let mem = MemBuffer::try_new(scratch)
            .map_err(|_| ReductionError::Factorization("out of memory for the solve workspace".into()))?;
        let mut this = Self {
            op,
            par,
            p,
            b,
            V: Mat::zeros(n, p + b),
            MV: match op {
                Krylov::Split(_) => Mat::zeros(0, 0),
                Krylov::Whole(_) => Mat::zeros(n, p + b),
            },
            T: Mat::zeros(p, p),
            B: Mat::zeros(b, b),
            k: 0,
            restarts: 0,
            applications: 0,
            last_ritz: None,
            mem,
            rng: 0x9E37_79B9_7F4A_7C15,
        };
        let start = Mat::<f64>::from_fn(n, b, |_, _| uniform(&mut this.rng));
        match op {
            Krylov::Split(op) => op.apply(
                this.V.get_mut(.., 0..b),
                start.as_ref(),
                par,
                MemStack::new(&mut this.mem),
            ),
            Krylov::Whole(op) => {
                let Mstart = symmetric_times(op.M, start.as_ref(), par);
                this.V.get_mut(.., 0..b).copy_from(&Mstart);
                op.solve(this.V.get_mut(.., 0..b), 0)?;
            }
        }
        this.applications += b;
        let norm = this.V.get(.., 0..b).norm_l2();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(ReductionError::Factorization(format!(
                "the shift-invert operator gave a block of norm {norm}"
            )));
        }
        let (mut head, _) = this.V.as_mut().split_at_col_mut(b);
        let empty = MatRef::from_column_major_slice(&[], n, 0);
        match op {
            Krylov::Split(_) => {
                let _ = orthonormalise_block(head.rb_mut(), empty, None, &mut this.rng, par);
            }
            Krylov::Whole(op) => {
                let (mut mhead, _) = this.MV.as_mut().split_at_col_mut(b);
                let mass = MassProduct {
                    M: op.M,
                    MV: empty,
                    MW: mhead.rb_mut(),
                };
                let _ = orthonormalise_block(head.rb_mut(), empty, Some(mass), &mut this.rng, par);
            }
        }
        Ok(this)
    }

    /// Runs block Lanczos steps (and thick restarts) until the `m` largest Ritz pairs meet
    /// `tolerance` (relative), checked after every step, or until `max_restarts` restarts
    /// have been done in all. Can be called again with a lower tolerance: it continues from
    /// the current basis.
    fn run(
        &mut self,
        m: usize,
        tolerance: f64,
        max_restarts: usize,
        progress: &mut dyn FnMut(usize, usize, usize),
    ) -> Result<LanczosOutcome, ReductionError> {
        let keep = (m + (self.p - m) / 2).min(self.p - self.b);
        let mut reported = usize::MAX;
        loop {
            if self.k + self.b > self.p {
                // A run that returned converged on a full basis did not keep its Ritz pairs.
                let ritz = match self.last_ritz.take() {
                    Some(ritz) => ritz,
                    None => self.ritz()?,
                };
                if self.restarts >= max_restarts {
                    let unconverged = (0..m).filter(|&j| !self.converged(&ritz, j, tolerance)).collect();
                    self.last_ritz = Some(ritz);
                    return Ok(LanczosOutcome::NotConverged { unconverged });
                }
                self.restart(&ritz, keep);
                progress(reported.min(m), m, self.applications);
            }
            self.step()?;
            if self.k > m {
                // A k x k dense eigenproblem per step: negligible next to the solves.
                let ritz = self.ritz()?;
                let converged = (0..m).filter(|&j| self.converged(&ritz, j, tolerance)).count();
                if converged != reported {
                    reported = converged;
                    progress(converged, m, self.applications);
                }
                if converged == m {
                    let Y = times(self.V.get(.., 0..self.k), ritz.S.get(.., 0..m), self.par);
                    let mu = ritz.theta[..m].to_vec();
                    return Ok(LanczosOutcome::Converged { mu, Y });
                }
                if self.k + self.b > self.p {
                    self.last_ritz = Some(ritz);
                }
            }
        }
    }

    /// Residual estimate $\|\mathbf B\mathbf s_{k-b+1:k,j}\|$ of Ritz pair `j` against
    /// `tolerance` relative to $|\theta_j|$.
    fn converged(&self, ritz: &Ritz, j: usize, tolerance: f64) -> bool {
        let (k, b) = (self.k, self.b);
        let s = ritz.S.get(k - b..k, j..j + 1);
        (&self.B * s).norm_l2() <= tolerance * ritz.theta[j].abs()
    }

    /// One block step: $\mathbf W = \mathbf C\mathbf V_{k:k+b}$, orthogonalised against
    /// $\mathbf v_0 \dots \mathbf v_{k+b-1}$ and within itself, becomes the next block.
    fn step(&mut self) -> Result<(), ReductionError> {
        let (par, j, b) = (self.par, self.k, self.b);
        let (done, mut next) = self.V.as_mut().split_at_col_mut(j + b);
        let done = done.rb();
        let mut W = next.rb_mut().get_mut(.., 0..b);
        match self.op {
            Krylov::Split(op) => op.apply(W.rb_mut(), done.get(.., j..j + b), par, MemStack::new(&mut self.mem)),
            Krylov::Whole(op) => {
                W.copy_from(self.MV.get(.., j..j + b));
                op.solve(W.rb_mut(), self.applications)?;
            }
        }
        self.applications += b;
        let norm0 = W.norm_l2();
        if !norm0.is_finite() {
            return Err(ReductionError::Factorization(format!(
                "the shift-invert operator gave a block of norm {norm0}"
            )));
        }
        let (h, R) = match self.op {
            Krylov::Split(_) => orthonormalise_block(W.rb_mut(), done, None, &mut self.rng, par),
            Krylov::Whole(op) => {
                let (Mdone, mut Mnext) = self.MV.as_mut().split_at_col_mut(j + b);
                let MW = Mnext.rb_mut().get_mut(.., 0..b);
                let mass = MassProduct {
                    M: op.M,
                    MV: Mdone.rb(),
                    MW,
                };
                orthonormalise_block(W.rb_mut(), done, Some(mass), &mut self.rng, par)
            }
        };
        // T_{0..j+b, j..j+b} = V^T C V_blk (the projection), kept symmetric.
        let rows = (j + b).min(self.p);
        for c in 0..b {
            if j + c >= self.p {
                break;
            }
            for r in 0..rows {
                self.T[(r, j + c)] = h[(r, c)];
                self.T[(j + c, r)] = h[(r, c)];
            }
        }
        // The diagonal block symmetrised: round-off makes V_blk^T C V_blk slightly asymmetric.
        for c in 0..b.min(self.p - j) {
            for r in 0..c {
                let v = 0.5 * (h[(j + r, c)] + h[(j + c, r)]);
                self.T[(j + r, j + c)] = v;
                self.T[(j + c, j + r)] = v;
            }
        }
        // The coupling to the next block, B = R (upper triangular).
        for c in 0..b {
            for r in 0..b {
                if j + b + r < self.p && j + c < self.p {
                    self.T[(j + b + r, j + c)] = R[(r, c)];
                    self.T[(j + c, j + b + r)] = R[(r, c)];
                }
            }
        }
        self.B = R;
        self.k = j + b;
        Ok(())
    }

    /// Ritz pairs of the current projected matrix $\mathbf T_k$, descending in magnitude.
    fn ritz(&self) -> Result<Ritz, ReductionError> {
        let k = self.k;
        let (values, U) = scaled_self_adjoint_eigen(self.T.get(0..k, 0..k), "the Lanczos matrix")?;
        let mut order: Vec<usize> = (0..k).collect();
        order.sort_by(|&a, &b| values[b].abs().total_cmp(&values[a].abs()));
        Ok(Ritz {
            theta: order.iter().map(|&j| values[j]).collect(),
            S: Mat::from_fn(k, k, |i, j| U[(i, order[j])]),
        })
    }

    /// Thick restart from a full basis: keep the `keep` largest Ritz vectors and the next
    /// block.
    fn restart(&mut self, ritz: &Ritz, keep: usize) {
        let (k, b) = (self.k, self.b);
        times_in_place(self.V.get_mut(.., 0..k), ritz.S.get(.., 0..keep), self.par);
        let next = self.V.get(.., k..k + b).to_owned();
        self.V.get_mut(.., keep..keep + b).copy_from(&next);
        if let Krylov::Whole(_) = self.op {
            times_in_place(self.MV.get_mut(.., 0..k), ritz.S.get(.., 0..keep), self.par);
            let next = self.MV.get(.., k..k + b).to_owned();
            self.MV.get_mut(.., keep..keep + b).copy_from(&next);
        }
        // Arrow: B S_{k-b..k, 0..keep}.
        let arrow = &self.B * ritz.S.get(k - b..k, 0..keep);
        self.T.fill(0.0);
        for i in 0..keep {
            self.T[(i, i)] = ritz.theta[i];
            for r in 0..b {
                self.T[(keep + r, i)] = arrow[(r, i)];
                self.T[(i, keep + r)] = arrow[(r, i)];
            }
        }
        self.k = keep;
        self.restarts += 1;
    }
}

/// The $\mathbf M$ inner product for [`orthonormalise_block`]: $\mathbf M$, $\mathbf M\mathbf V$
/// of the basis, and where $\mathbf M\mathbf W$ of the result goes.
struct MassProduct<'a> {
    M: SparseColMatRef<'a, usize, f64>,
    MV: MatRef<'a, f64>,
    MW: MatMut<'a, f64>,
}

/// Classical Gram-Schmidt of the block `W` against the orthonormal columns of `V`, done twice
/// ("twice is enough": Giraud, Langou & Rozložník 2005), then orthonormalised within itself
/// column by column, twice ($\mathbf W = \mathbf Q\mathbf R$, `W` overwritten by
/// $\mathbf Q$). Returns the coefficients $\mathbf V^T\mathbf W$ (summed over all passes) and
/// $\mathbf R$.
///
/// In the Euclidean inner product (`mass = None`) or in the $\mathbf M$ inner product
/// ([`MassProduct`]: `V` $\mathbf M$-orthonormal): then $\mathbf M\mathbf w$ is carried along
/// so that every inner product is a dot product, the coefficients are $\mathbf V^T\mathbf
/// M\mathbf W$, and `MW` receives $\mathbf M\mathbf W$ of the result, recomputed (one sparse
/// product) so that the stored $\mathbf M\mathbf V$ does not drift.
///
/// A column that vanishes to round-off against the others (below [`BREAKDOWN_RATIO`] of the
/// block's norm: the Krylov space is invariant to working precision) is replaced by a random
/// direction orthogonal to everything, decoupled ($R_{cc} = 0$), as single-vector Lanczos
/// restarts after a breakdown.
fn orthonormalise_block(
    mut W: MatMut<'_, f64>,
    V: MatRef<'_, f64>,
    mass: Option<MassProduct<'_>>,
    rng: &mut u64,
    par: Par,
) -> (Mat<f64>, Mat<f64>) {
    let (n, b) = W.shape();
    // The products with the basis take the coefficients from M V (from V itself, Euclidean).
    let (M, MV, MW) = match mass {
        Some(MassProduct { M, MV, MW }) => (Some(M), MV, Some(MW)),
        None => (None, V, None),
    };
    let mut h = Mat::<f64>::zeros(V.ncols(), b);
    let euclidean_norm0 = W.norm_l2();
    for _pass in 0..2 {
        h += project_out_with(W.rb_mut(), MV, V, par);
    }
    let mut MWt = M.map(|M| symmetric_times(M, W.rb(), par));
    let dot = |x: ColRef<'_, f64>, y: ColRef<'_, f64>| x.transpose() * y;
    let norm0 = match &MWt {
        // The block's M-norm before the projection: Pythagoras over the coefficients and the rest.
        Some(MWt) => (h.squared_norm_l2() + (0..b).map(|c| dot(W.rb().col(c), MWt.col(c))).sum::<f64>())
            .max(0.0)
            .sqrt(),
        None => euclidean_norm0,
    };
    // The norm of column w, with mw = M w in the M inner product.
    let norm_of = |w: MatRef<'_, f64>, mw: Option<MatRef<'_, f64>>| match mw {
        Some(mw) => dot(w.col(0), mw.col(0)).max(0.0).sqrt(),
        None => w.norm_l2(),
    };
    // Then column by column within the block (b is a few columns: cheap next to the above).
    let mut R = Mat::<f64>::zeros(b, b);
    for c in 0..b {
        let (left, mut right) = W.rb_mut().split_at_col_mut(c);
        let left = left.rb();
        let mut w = right.rb_mut().get_mut(.., 0..1);
        let (Mleft, mut mw) = match MWt.as_mut() {
            Some(MWt) => {
                let (Mleft, Mright) = MWt.as_mut().split_at_col_mut(c);
                (Mleft.into_const(), Some(Mright.get_mut(.., 0..1)))
            }
            None => (left, None),
        };
        // w -= left g with g from Mleft, and mw -= Mleft g along with it.
        let project_left = |w: MatMut<'_, f64>, mw: &mut Option<MatMut<'_, f64>>| {
            let g = project_out_with(w, Mleft, left, par);
            if let Some(mw) = mw {
                matmul(mw.rb_mut(), Accum::Add, Mleft, g.as_ref(), -1.0, Par::Seq);
            }
            g
        };
        let norm_in = norm_of(w.rb(), mw.as_ref().map(|m| m.rb()));
        for _pass in 0..2 {
            let g = project_left(w.rb_mut(), &mut mw);
            for i in 0..c {
                R[(i, c)] += g[(i, 0)];
            }
        }
        let mut norm = norm_of(w.rb(), mw.as_ref().map(|m| m.rb()));
        // A column nearly in the span of the earlier ones (a converging block) has lost digits:
        // the round-off of the passes above, relative to what is left, is no longer
        // orthogonal to V. One more pass against V and the block restores it (Daniel, Gragg,
        // Kaufman & Stewart 1976, Math. Comp. 30: reorthogonalise when the norm falls below
        // 1/sqrt(2) of its value before).
        if norm < std::f64::consts::FRAC_1_SQRT_2 * norm_in {
            let g = project_out_with(w.rb_mut(), MV, V, par);
            for i in 0..V.ncols() {
                h[(i, c)] += g[(i, 0)];
            }
            if let (Some(M), Some(mw)) = (M, mw.as_mut()) {
                mw.copy_from(symmetric_times(M, w.rb(), par));
            }
            let g = project_left(w.rb_mut(), &mut mw);
            for i in 0..c {
                R[(i, c)] += g[(i, 0)];
            }
            norm = norm_of(w.rb(), mw.as_ref().map(|m| m.rb()));
        }
        if norm > BREAKDOWN_RATIO * norm0 && norm.is_finite() {
            R[(c, c)] = norm;
        } else {
            // Invariant subspace: a random direction, orthogonal to V and the block so far.
            for i in 0..n {
                w[(i, 0)] = uniform(rng);
            }
            for _pass in 0..2 {
                project_out_with(w.rb_mut(), MV, V, par);
                project_out_with(w.rb_mut(), Mleft, left, par);
            }
            if let (Some(M), Some(mw)) = (M, mw.as_mut()) {
                mw.copy_from(symmetric_times(M, w.rb(), par));
            }
            norm = norm_of(w.rb(), mw.as_ref().map(|m| m.rb()));
        }
        w.col_mut(0).iter_mut().for_each(|x| *x /= norm);
        if let Some(mw) = mw.as_mut() {
            mw.rb_mut().col_mut(0).iter_mut().for_each(|x| *x /= norm);
        }
    }
    if let (Some(M), Some(mut MW)) = (M, MW) {
        MW.copy_from(symmetric_times(M, W.rb(), par));
    }
    (h, R)
}

/// One classical Gram-Schmidt pass: $\mathbf W \leftarrow \mathbf W - \mathbf Q\mathbf G$
/// with $\mathbf G = \mathbf P^T\mathbf W$; returns $\mathbf G$. With $\mathbf P = \mathbf Q$
/// (orthonormal columns) a pass in the Euclidean inner product, with $\mathbf P = \mathbf
/// M\mathbf Q$ ($\mathbf Q$ $\mathbf M$-orthonormal) one in the $\mathbf M$ inner product.
///
/// By blocks of [`GS_ROWS`] rows, each a sequential product on data that fits in a core's
/// cache, summed: $\mathbf Q$ ($n \times$ up to a few hundred) is read once per product.
/// A parallel dense product on the whole of $\mathbf Q$ packs (copies) it first, which for
/// this tall, thin shape costs more memory traffic than the product itself.
fn project_out_with(mut W: MatMut<'_, f64>, P: MatRef<'_, f64>, Q: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let (q, b) = (Q.ncols(), W.ncols());
    if q == 0 {
        return Mat::<f64>::zeros(q, b);
    }
    let G = gram(P, W.rb(), par);
    match par {
        Par::Rayon(_) => W
            .par_row_chunks_mut(GS_ROWS)
            .zip(Q.par_row_chunks(GS_ROWS))
            .for_each(|(Wc, Qc)| matmul(Wc, Accum::Add, Qc, G.as_ref(), -1.0, Par::Seq)),
        Par::Seq => matmul(W.rb_mut(), Accum::Add, Q, G.as_ref(), -1.0, Par::Seq),
    }
    G
}

/// $\mathbf P^T\mathbf W$ for tall, thin `P` and `W` (the same rows, a few hundred columns
/// at most): by blocks of [`GS_ROWS`] rows, each a sequential product on data that fits in a
/// core's cache, the blocks in parallel with `par`. A parallel dense product on the whole
/// packs (copies) both first, which for this shape costs more memory traffic than the
/// product itself. The partial products are added in the order of the blocks, so the result
/// is the same for any number of threads and for `Par::Seq`.
pub(crate) fn gram(P: MatRef<'_, f64>, W: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let (q, b) = (P.ncols(), W.ncols());
    let partial = |(Pc, Wc): (MatRef<'_, f64>, MatRef<'_, f64>)| {
        let mut g = Mat::<f64>::zeros(q, b);
        matmul(g.as_mut(), Accum::Replace, Pc.transpose(), Wc, 1.0, Par::Seq);
        g
    };
    let partials: Vec<Mat<f64>> = match par {
        Par::Rayon(_) => P
            .par_row_chunks(GS_ROWS)
            .zip(W.par_row_chunks(GS_ROWS))
            .map(partial)
            .collect(),
        Par::Seq => (0..P.nrows())
            .step_by(GS_ROWS)
            .map(|i| {
                let rows = GS_ROWS.min(P.nrows() - i);
                partial((P.subrows(i, rows), W.subrows(i, rows)))
            })
            .collect(),
    };
    partials.into_iter().fold(Mat::<f64>::zeros(q, b), |a, c| a + c)
}

/// Rows per block of the layout changes in [`symmetric_times`]: 256 rows of 96 columns,
/// 196 KB in each layout.
const TRANSPOSE_ROWS: usize = 256;

/// Rows per block of [`project_out_with`] and [`gram`]: 1024 rows of a 200-column basis are
/// 1.6 MB; [`gram`] keeps one partial product per block (the 96 x 96 of the invariants'
/// fields: 74 KB a block, 14 MB at 200k rows).
pub(crate) const GS_ROWS: usize = 1024;

/// Small problems: the dense $\mathbf C$ from $n$ applications, its dense
/// eigendecomposition, the $m$ largest $\mu$ (descending).
fn dense_operator_eigen(op: &Operator<'_>, m: usize) -> Result<Mat<f64>, ReductionError> {
    let n = op.nrows();
    let par = faer::get_global_parallelism();
    let mut C = Mat::<f64>::zeros(n, n);
    apply_alloc(op, C.as_mut(), Mat::<f64>::identity(n, n).as_ref(), par);
    let C = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (C[(i, j)] + C[(j, i)]));
    let (values, U) = scaled_self_adjoint_eigen(C.as_ref(), "the shift-invert operator")?;
    largest(&values, U.as_ref(), m)
}

/// The vectors of the `m` largest of the ascending `values` (the columns of `U`), descending,
/// refused if one of them is not positive (an indefinite $\mathbf M$). For an indefinite
/// $\mathbf M$, a large negative $\mu$ is not picked here; the Rayleigh-Ritz step may still
/// see it.
fn largest(values: &[f64], U: MatRef<'_, f64>, m: usize) -> Result<Mat<f64>, ReductionError> {
    let n = values.len();
    let mu: Vec<f64> = (0..m).map(|k| values[n - 1 - k]).collect();
    if let Some(bad) = mu.iter().position(|&x| x <= 0.0) {
        return Err(ReductionError::MassNotPositiveDefinite {
            dof: None,
            why: format!("the shift-invert operator has the eigenvalue {:.3e} <= 0", mu[bad]),
        });
    }
    Ok(Mat::<f64>::from_fn(U.nrows(), m, |i, k| U[(i, n - 1 - k)]))
}

/// [`fe_model::scaled_self_adjoint_eigen`] (faer's dense symmetric eigensolver on the matrix
/// scaled to unit size: faer's divide and conquer is not scale-invariant, and the Lanczos matrix
/// has norm $\mu_1$, far from 1; see there and the module docs) with the error named for `what`.
fn scaled_self_adjoint_eigen(A: MatRef<'_, f64>, what: &str) -> Result<(Vec<f64>, Mat<f64>), ReductionError> {
    fe_model::scaled_self_adjoint_eigen(A)
        .map_err(|e| ReductionError::Factorization(format!("dense eigensolver of {what}: {e}")))
}

/// Uniform pseudo-random number in $[-1, 1)$ (SplitMix64): the start vector is fixed, so
/// results are reproducible.
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

fn check_square_pair(
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
) -> Result<(), ReductionError> {
    let n = K.nrows();
    if K.ncols() != n {
        return Err(ReductionError::DimensionMismatch {
            what: "K must be square",
            expected_rows: n,
            expected_cols: n,
            rows: K.nrows(),
            cols: K.ncols(),
        });
    }
    if M.nrows() != n || M.ncols() != n {
        return Err(ReductionError::DimensionMismatch {
            what: "M must have the shape of K",
            expected_rows: n,
            expected_cols: n,
            rows: M.nrows(),
            cols: M.ncols(),
        });
    }
    Ok(())
}

/// Runs `solve` with `settings`; when the block size was the automatic choice (`block_size = 0`
/// on `n` >= [`BLOCK_MIN_DOFS`] dofs) and the run did not converge, runs it again with single
/// vectors. The automatic block size is a speed choice, not the user's: a block run that stalls
/// (blocks of 8 did on a 50k-dof body, [`AUTO_BLOCK_SIZE`]) is repeated with the robust
/// iteration before giving up. A block size the user chose is never changed.
fn with_single_vector_retry(
    settings: &EigenSettings,
    n: usize,
    mut solve: impl FnMut(&EigenSettings) -> Result<EigenSolution, ReductionError>,
) -> Result<EigenSolution, ReductionError> {
    let automatic_block = settings.block_size == 0 && block_size(settings, n) > 1;
    match solve(settings) {
        Err(ReductionError::EigenNotConverged { .. }) if automatic_block => solve(&EigenSettings {
            block_size: 1,
            ..settings.clone()
        }),
        result => result,
    }
}

/// The block size $b$ for a problem of size `n` (before clamping to the Krylov dimension):
/// [`EigenSettings::block_size`], or for `0` [`AUTO_BLOCK_SIZE`] from [`BLOCK_MIN_DOFS`] dofs.
fn block_size(settings: &EigenSettings, n: usize) -> usize {
    match settings.block_size {
        0 if n >= BLOCK_MIN_DOFS => AUTO_BLOCK_SIZE,
        0 => SMALL_BLOCK_SIZE,
        b => b,
    }
}

/// The most $n$-vectors (f64) [`ShiftInvert::lowest_modes_with_progress`] holds at once for
/// `settings` on a pencil of size `n` with a factor in `precision`: the basis $\mathbf V$
/// ($p + b$ columns; with a single-precision factor $\mathbf M\mathbf V$ too; the thick
/// restart rotates it in place) and the last step's $5m$ columns ($\boldsymbol\Phi$,
/// $\mathbf K\boldsymbol\Phi$, and while $\mathbf M\boldsymbol\Phi$ is computed the
/// row-major copies of its operand and result: the Ritz vectors $\mathbf Y$ become
/// $\boldsymbol\Phi$ and the Rayleigh-Ritz step rotates in place). Settings that
/// [`krylov_dimension`] refuses count 0 (they fail before allocating).
pub(crate) fn eigen_vectors(settings: &EigenSettings, n: usize, precision: Precision) -> usize {
    let Ok(p) = krylov_dimension(settings, n) else {
        return 0;
    };
    let m = settings.n_modes;
    if p + 1 >= n {
        // The dense path: the operator or mass as n x n matrices, their symmetrised copies
        // and eigenvectors.
        return 6 * n + 5 * m;
    }
    let b = block_size(settings, n).min(p - m).min(n - p - 1).max(1);
    let copies = match precision {
        Precision::Double => 1,
        Precision::Single => 2,
    };
    copies * (p + b) + 5 * m
}

/// Checks `settings` for a problem of size `n` and returns the Krylov dimension $p$.
fn krylov_dimension(settings: &EigenSettings, n: usize) -> Result<usize, ReductionError> {
    let m = settings.n_modes;
    if m == 0 || m >= n {
        return Err(ReductionError::InvalidModeCount { requested: m, n });
    }
    if !(settings.tolerance.is_finite() && settings.tolerance > 0.0) {
        return Err(ReductionError::InvalidSettings {
            what: format!("tolerance must be positive and finite, got {}", settings.tolerance),
        });
    }
    match settings.krylov_dim {
        0 => {
            // Blocks: room for 16 block steps beyond the wanted m.
            let b = block_size(settings, n);
            let single = (2 * m).max(m + 32);
            Ok(if b > 1 { single.max(m + 16 * b) } else { single })
        }
        p if p > m => Ok(p),
        p => Err(ReductionError::InvalidSettings {
            what: format!("krylov_dim = {p} must exceed n_modes = {m} (or be 0 for automatic)"),
        }),
    }
}

fn check_mass_diagonal(M_diag: &[f64]) -> Result<(), ReductionError> {
    if let Some(dof) = M_diag.iter().position(|&d| !(d > 0.0 && d.is_finite())) {
        return Err(ReductionError::MassNotPositiveDefinite {
            dof: Some(dof),
            why: format!("diagonal entry {:.3e} is not positive", M_diag[dof]),
        });
    }
    Ok(())
}

/// Diagonal of a CSC matrix (duplicates summed).
fn diagonal(A: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    let mut d = vec![0.0; A.nrows()];
    for j in 0..A.ncols() {
        for p in A.col_range(j) {
            if A.row_idx()[p] == j {
                d[j] += A.val()[p];
            }
        }
    }
    d
}

/// Checks that the strict lower and upper triangles hold the same values, by comparing a
/// position-weighted sum of each (one pass, no transpose). A matrix stored with one triangle
/// only fails it; explicit zeros in one triangle do not matter.
///
/// The tolerance has two parts. The summation: at most `count` $\cdot\,\varepsilon\sum|w a|$
/// for two recursive sums of `count` terms (Higham, "Accuracy and Stability of Numerical
/// Algorithms", 2002, §4.2). The assembly: each $a_{ij}$ and $a_{ji}$ is a sum of element
/// entries, rotated to global axes, whose round-off is relative to the element's largest
/// entries, about $\sqrt{|a_{ii}a_{jj}|}$, not to $a_{ij}$ itself; an entry that is zero in
/// exact arithmetic (a coupling that cancels in a beam on a skewed axis) holds only that
/// round-off. So each pair may differ by [`SYMMETRY_ROUNDOFF`] $\cdot\,\varepsilon
/// \sqrt{|a_{ii}a_{jj}|}$. Judging by the off-diagonal entries alone failed on a beam of two
/// elements, whose internal block holds one node and nothing but such couplings.
fn check_symmetric(A: SparseColMatRef<'_, usize, f64>, name: &'static str) -> Result<(), ReductionError> {
    // Weight of the unordered pair {i, j}: a deterministic value in [1, 2).
    let weight = |i: usize, j: usize| {
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        let h = (a as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (b as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        1.0 + (h >> 11) as f64 / (1u64 << 53) as f64
    };
    let d = diagonal(A);
    let (mut lower, mut upper, mut abs, mut assembly, mut count) = (0.0, 0.0, 0.0, 0.0, 0usize);
    for j in 0..A.ncols() {
        for p in A.col_range(j) {
            let i = A.row_idx()[p];
            let v = A.val()[p];
            if i == j {
                continue;
            }
            let w = weight(i, j);
            if i > j {
                lower += w * v;
            } else {
                upper += w * v;
            }
            abs += (w * v).abs();
            assembly += w * (d[i] * d[j]).abs().sqrt();
            count += 1;
        }
    }
    let tol = (count.max(1) as f64) * f64::EPSILON * abs + SYMMETRY_ROUNDOFF * f64::EPSILON * assembly;
    if (lower - upper).abs() > tol || lower.is_nan() || upper.is_nan() {
        return Err(ReductionError::NotSymmetric {
            matrix: name,
            lower,
            upper,
        });
    }
    Ok(())
}

/// Round-off allowed between $a_{ij}$ and $a_{ji}$ by `check_symmetric`, in units of
/// $\varepsilon\sqrt{|a_{ii}a_{jj}|}$: 64 covers the rotation to global axes ($3\times 3$
/// products, twice) and the sum over the elements sharing the pair (a few tens at most),
/// while a missing triangle or a real asymmetry is of the order of the entries themselves.
const SYMMETRY_ROUNDOFF: f64 = 64.0;

/// The lower triangle of $\mathbf K - \sigma\mathbf M$ (union of the patterns).
fn lower_shifted(
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
    sigma: f64,
) -> SparseColMat<usize, f64> {
    let n = K.nrows();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    // slot[i]: position of row i in the column being built, usize::MAX if absent.
    let mut slot = vec![usize::MAX; n];
    col_ptr.push(0);
    for j in 0..n {
        let start = row_idx.len();
        let mut add = |i: usize, v: f64| {
            if i < j {
                return;
            }
            if slot[i] == usize::MAX {
                slot[i] = row_idx.len();
                row_idx.push(i);
                values.push(v);
            } else {
                values[slot[i]] += v;
            }
        };
        for p in K.col_range(j) {
            add(K.row_idx()[p], K.val()[p]);
        }
        for p in M.col_range(j) {
            add(M.row_idx()[p], -sigma * M.val()[p]);
        }
        for &i in &row_idx[start..] {
            slot[i] = usize::MAX;
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic = SymbolicSparseColMat::new_unsorted_checked(n, n, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// The retry rule of `lowest_modes_with_progress`: an automatic block run that does not
    /// converge is repeated once with single vectors; a block size the user chose and other
    /// errors are not retried. (A real stall needs a 50k-dof body
    /// and blocks of 8, far too slow for a test: the solver is replaced by a recorder that
    /// stalls with blocks and converges with single vectors, on the real small problem below.)
    #[test]
    fn automatic_block_stall_retries_with_single_vectors() {
        let n = 200;
        let K = SparseColMat::<usize, f64>::try_new_from_triplets(
            n,
            n,
            &(0..n).map(|i| Triplet::new(i, i, (i + 1) as f64)).collect::<Vec<_>>(),
        )
        .unwrap();
        let M = SparseColMat::<usize, f64>::try_new_from_triplets(
            n,
            n,
            &(0..n).map(|i| Triplet::new(i, i, 1.0)).collect::<Vec<_>>(),
        )
        .unwrap();
        let stall = || ReductionError::EigenNotConverged {
            requested: 3,
            converged: 2,
            failed_modes: vec![2],
            worst_residual: 3e-8,
            tolerance: 1e-10,
        };
        // Stalls whenever the effective block size is above 1, else solves for real.
        let run = |calls: &mut Vec<usize>, s: &EigenSettings, n_claimed: usize| {
            calls.push(block_size(s, n_claimed));
            if block_size(s, n_claimed) > 1 {
                Err(stall())
            } else {
                lowest_modes(K.as_ref(), M.as_ref(), &EigenSettings::new(3, Shift::Zero))
            }
        };
        // Automatic on a (claimed) large problem: one block run, then single vectors.
        let mut calls = Vec::new();
        let sol = with_single_vector_retry(&EigenSettings::new(3, Shift::Zero), BLOCK_MIN_DOFS, |s| {
            run(&mut calls, s, BLOCK_MIN_DOFS)
        })
        .expect("the single-vector retry converges");
        assert_eq!(calls, [AUTO_BLOCK_SIZE, 1]);
        // The eigenvalues 1, 2, 3 of the diagonal pencil: a Ritz value's error is about the
        // square of its residual (1e-8 requested), so 1e-9 shows the retry's result is real.
        for (k, lambda) in sol.eigenvalues.iter().enumerate() {
            assert!((lambda - (k + 1) as f64).abs() < 1e-9, "eigenvalue {k}: {lambda}");
        }
        // The user's block size: no retry, the stall is reported.
        let mut calls = Vec::new();
        let user = EigenSettings {
            block_size: 4,
            ..EigenSettings::new(3, Shift::Zero)
        };
        let err = with_single_vector_retry(&user, BLOCK_MIN_DOFS, |s| run(&mut calls, s, BLOCK_MIN_DOFS));
        assert!(matches!(err, Err(ReductionError::EigenNotConverged { .. })), "{err:?}");
        assert_eq!(calls, [4]);
        // Automatic below BLOCK_MIN_DOFS: blocks of SMALL_BLOCK_SIZE, retried the same way.
        let mut calls = Vec::new();
        with_single_vector_retry(&EigenSettings::new(3, Shift::Zero), n, |s| run(&mut calls, s, n))
            .expect("single vectors");
        assert_eq!(calls, [SMALL_BLOCK_SIZE, 1]);
        // Other errors are not retried.
        let mut calls = 0;
        let err = with_single_vector_retry(&EigenSettings::new(3, Shift::Zero), BLOCK_MIN_DOFS, |_| {
            calls += 1;
            Err(ReductionError::InvalidSettings { what: "test".into() })
        });
        assert!(matches!(err, Err(ReductionError::InvalidSettings { .. })), "{err:?}");
        assert_eq!(calls, 1);
    }

    /// `scaled_self_adjoint_eigen` on a symmetric matrix of norm $10^{-6}$ (and $10^{12}$) with eigenvalues
    /// graded down to $10^{-14}$ (as the Lanczos matrix of a clamped beam, dimension 200 so
    /// that faer takes divide and conquer): every pair has a residual of round-off relative to
    /// $\|\mathbf A\|$. faer's unscaled EVD does not (its deflation tolerance is absolute):
    /// FIXME(faer) if that assertion fails, faer scales now and the wrapper can go.
    #[test]
    fn scaled_eigen_is_backward_stable_at_small_and_large_norm() {
        let n = 200;
        let mut rng = 7u64;
        let X = Mat::<f64>::from_fn(n, n, |_, _| uniform(&mut rng));
        let Q = X.qr().compute_Q();
        let theta: Vec<f64> = (0..n).map(|i| 1e-6 / ((i + 1) as f64).powi(4)).collect();
        let A = &Q * Mat::<f64>::from_fn(n, n, |i, j| if i == j { theta[i] } else { 0.0 }) * Q.transpose();
        let A = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (A[(i, j)] + A[(j, i)]));
        let worst = |A: &Mat<f64>, values: &[f64], U: MatRef<'_, f64>| {
            (0..n)
                .map(|j| (A * U.col(j) - U.col(j) * values[j]).norm_l2())
                .fold(0.0_f64, f64::max)
        };
        // The same matrix at norm 1e-6 and 1e12 (a power of two apart from 1e-6: exact).
        let mut tol = 0.0;
        for factor in [1.0, 2f64.powi(60)] {
            let A = &A * faer::Scale(factor);
            let (values, U) = scaled_self_adjoint_eigen(A.as_ref(), "test").unwrap();
            // Backward stable: residuals of a few n eps ||A||.
            tol = 4.0 * n as f64 * f64::EPSILON * A.norm_max();
            let ours = worst(&A, &values, U.as_ref());
            assert!(
                ours <= tol,
                "norm {:.1e}: worst residual {ours:.3e} > {tol:.3e}",
                A.norm_max()
            );
        }
        let tol = tol / 2f64.powi(60);
        let evd = A.self_adjoint_eigen(Side::Lower).unwrap();
        let values: Vec<f64> = (0..n).map(|k| evd.S()[k]).collect();
        let faer_unscaled = worst(&A, &values, evd.U());
        assert!(
            faer_unscaled > 1e3 * tol,
            "faer's unscaled EVD is now accurate ({faer_unscaled:.3e}): scaled_self_adjoint_eigen can go"
        );
    }

    /// The products by blocks of rows of the thick restart and the Rayleigh-Ritz step against
    /// faer's product: in place (`times_in_place`, the first `q` columns overwritten, the
    /// others kept) and into a new matrix (`times`), with a last block shorter than
    /// `GS_ROWS`, in parallel and in sequence. Only the order of the block products'
    /// additions may differ from faer's: round-off.
    #[test]
    fn products_by_rows_match_faer_product() {
        let n = 3 * GS_ROWS + 17;
        let A = Mat::<f64>::from_fn(n, 9, |i, j| ((i * 31 + j * 17) % 23) as f64 / 7.0 - 1.5);
        for q in [0, 1, 5, 9] {
            let S = Mat::<f64>::from_fn(9, q, |i, j| ((i * 5 + j * 3) % 11) as f64 - 5.0);
            let reference = &A * &S;
            let tol = 1e-13 * reference.norm_max().max(1.0);
            for par in [Par::Seq, Par::rayon(2)] {
                let mut B = A.clone();
                times_in_place(B.as_mut(), S.as_ref(), par);
                assert!((B.get(.., 0..q) - &reference).norm_max() <= tol, "q = {q}, {par:?}");
                assert_eq!(
                    B.get(.., q..),
                    A.get(.., q..),
                    "q = {q}, {par:?}: columns beyond q changed"
                );
                let C = times(A.as_ref(), S.as_ref(), par);
                assert!((&C - &reference).norm_max() <= tol, "q = {q}, {par:?}");
            }
        }
    }

    /// The gather product against faer's sparse-dense product, on a symmetric matrix with
    /// unsorted and repeated entries, for 0, 1 and 5 columns, in parallel and in sequence.
    #[test]
    fn symmetric_times_matches_faer_product() {
        let n = 9000;
        let mut triplets = Vec::new();
        for i in 0..n {
            triplets.push(Triplet::new(i, i, 4.0 + (i % 7) as f64));
            for d in [1, 37, 1000] {
                if i + d < n {
                    let v = -1.0 / (1 + (i * d) % 5) as f64;
                    // Repeated entries are summed by both products.
                    for (r, c) in [(i, i + d), (i + d, i)] {
                        triplets.push(Triplet::new(r, c, 0.5 * v));
                        triplets.push(Triplet::new(r, c, 0.5 * v));
                    }
                }
            }
        }
        let A = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).unwrap();
        for k in [0, 1, 5] {
            let X = Mat::<f64>::from_fn(n, k, |i, j| ((i * 13 + j * 7) % 19) as f64 - 9.0);
            let reference = &A * &X;
            for par in [Par::Seq, Par::rayon(2)] {
                let AX = symmetric_times(A.as_ref(), X.as_ref(), par);
                let err = (&AX - &reference).norm_max();
                assert!(
                    err <= 1e-12 * reference.norm_max().max(1.0),
                    "k = {k}, {par:?}: {err:.2e}"
                );
            }
        }
    }
}
