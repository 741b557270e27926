//! reduction (docs written later)
#![allow(non_snake_case)]
pub mod eigen;
pub mod error;
pub use eigen::{lowest_modes, EigenSettings, EigenSolution, Shift, ShiftInvert};
pub use error::ReductionError;
