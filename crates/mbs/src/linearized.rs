//! Linearised analysis about a state: $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ of the
//! assembled system ([`crate::System::matrices`]) and the undamped eigenfrequencies.
//!
//! Not implemented yet beyond the matrices: the eigenvalue solve is the next step (brief §6).
