//! The file formats of a reduced body and of its finite-element input, each in its own
//! module; none of them is used by the reduction itself, only by the callers around it.
//!
//! - [`rbody`]: the reduced-body file `NAME.rbody`, a [`ReducedBody`](crate::ReducedBody)
//!   saved once and read back bit for bit.
//! - [`matrix_market`]: sparse `K` and `M` of an external FE code in Matrix Market
//!   coordinate format.
//! - [`mbdyn`]: MBDyn's modal-element `.fem` file, written from and read into a
//!   [`ReducedBody`](crate::ReducedBody).
pub mod matrix_market;
pub mod mbdyn;
pub mod rbody;
