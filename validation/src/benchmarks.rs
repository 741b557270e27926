//! One module per group of problems of the validation guide (`docs/validation.md`).

/// C1-C4: dynamics.
pub mod dynamics;
/// F1: sway buckling of a portal frame against its published characteristic equation.
pub mod frame_buckling;
/// A1-A4: linear references (exact or NAFEMS).
pub mod linear;
/// B1-B3: geometrically nonlinear statics.
pub mod nonlinear_statics;
/// A5: linear transient against the exact modal series.
pub mod transient;
/// The AIC-FFR paper's comparison: frame choices x inertia variants, beam rod against solid rod.
pub mod variants;
