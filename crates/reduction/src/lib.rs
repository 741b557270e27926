//! reduction (docs written later)
#![allow(non_snake_case)]
pub mod craig_bampton;
pub mod eigen;
pub mod error;
pub mod invariants;
pub mod reduced_body;
pub use eigen::{lowest_modes, EigenSettings, EigenSolution, Shift, ShiftInvert};
pub use craig_bampton::{partition, reduce, CbSettings, ModeSelection, Partition};
pub use error::ReductionError;
pub use reduced_body::{DenseMatrix, InertiaData, InterfacePoint, MeshModes, ReducedBody, FORMAT_VERSION};
