//! Errors of the superelement. Each says what failed, with the numbers a user needs to act.

use thiserror::Error;

/// Everything that can go wrong building or evaluating a superelement.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SuperelementError {
    /// The reduced body is inconsistent (a matrix of the wrong shape, a non-finite or
    /// non-positive mass, a damping list of the wrong length, ...).
    #[error("invalid reduced body '{body}': {what}")]
    InvalidBody { body: String, what: String },
    /// The frame choice does not fit the body (an interface index out of range, an auxiliary
    /// frame on a body reduced without an auxiliary interface).
    #[error("frame choice {choice} does not fit body '{body}': {what}")]
    InvalidFrameChoice { body: String, choice: String, what: String },
    /// The state does not fit the body (wrong number of interfaces or modal coordinates,
    /// non-finite values).
    #[error("invalid state: {what}")]
    InvalidState { what: String },
    /// Newton on $\boldsymbol\Phi_j\mathbf q^{jj} = \mathbf 0$ (4.4) did not reach the
    /// tolerance. `residual` is $\max(|\mathbf g_t|/L, |\mathbf g_r|)$ of the last iterate
    /// ($L$: body size). Usually the warm start (the previous frame) is far from the new state:
    /// take a smaller step, or start from the frame of a nearby state.
    #[error(
        "the body's floating frame could not be found (no convergence in {iterations} iterations, \
         residual {residual:.3e} > {tolerance:.3e}): the body is deformed further than one linear \
         elastic body can follow, or the step from the last state is too large; take a smaller \
         time step or more load steps, split the member into more bodies, or check the loads \
         and units (theory guide, section 4.4)"
    )]
    FrameNotConverged {
        iterations: usize,
        residual: f64,
        tolerance: f64,
    },
    /// $\boldsymbol\Phi_j\boldsymbol\Phi_{rig}$ (5.4) is singular: the frame cannot see all
    /// six rigid motions of the (deformed) interface set. `rcond` is the ratio of the smallest
    /// to the largest singular value.
    #[error(
        "the body's floating frame is undetermined (condition {rcond:.3e}): its deformed interfaces \
         no longer fix its six rigid motions, so it is deformed further than one linear elastic \
         body can follow; split the member into more bodies, or check the loads and units \
         (theory guide, section 4.4)"
    )]
    SingularFrame { rcond: f64 },
    /// The body cannot be evaluated as a planar one ([`crate::Superelement::into_planar`]):
    /// its reduced matrices couple the FE model's xy-plane to the out-of-plane motion, or a
    /// state left the plane. `what` names the interface, mode or coupling.
    #[error("body '{body}' is not planar: {what}")]
    NotPlanar { body: String, what: String },
}
