//! The analyses on a [`crate::System`]: statics by load stepping and by arc length, the
//! stability of a static state, linearised spectra and buckling, and time integration.

pub mod arc_length;
pub mod dynamic;
pub mod linearized;
pub mod stability;
pub mod static_solver;
