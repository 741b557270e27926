//! reduction (docs written later)
#![allow(non_snake_case)]
pub mod craig_bampton;
pub mod diagnostics;
pub mod eigen;
pub mod error;
pub mod file;
pub mod invariants;
pub mod matrix_market;
pub mod modal;
pub mod reduced_body;
pub use eigen::{lowest_modes, EigenSettings, EigenSolution, Shift, ShiftInvert};
pub use craig_bampton::{partition, reduce, CbSettings, ModeSelection, Partition};
pub use craig_bampton::{reduce_external, reduce_external_dofs};
pub use diagnostics::{diagnostics, DiagnosticWarning, Diagnostics, ModeDiagnostics};
pub use file::BodyFileProblem;
pub use matrix_market::{read_matrix_market, write_matrix_market};
pub use error::ReductionError;
pub use modal::modal_sparse;
pub use reduced_body::{DenseMatrix, InertiaData, InterfacePoint, MeshModes, ReducedBody, FORMAT_VERSION};
