//! One module per group of problems of `benchmarks.md`.

/// A1-A4: linear references (exact or NAFEMS).
pub mod linear;
