//! What one analysis produced, part or mechanism alike.

use crate::error::SolverStopped;

/// What one analysis produced, for the summary.
pub struct Outcome {
    pub free_dofs: usize,
    pub report: Vec<String>,
    pub results: serde_json::Value,
    /// A solver that stopped after writing part of its results.
    pub failure: Option<SolverStopped>,
    /// The final state (equilibrium, dynamic), for analyses that `start` from it.
    pub final_state: Option<mbs::State>,
}
