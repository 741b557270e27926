//! Results of a state body by body: the modal coordinates $\boldsymbol\eta$ of a flexible body
//! and its deformed FE mesh (the superelement's mesh recovery, `superelement::recovery`, at the
//! node motions of the state). The system's own superelements are used: nothing is built
//! again to draw a body.

use crate::error::SolveError;
use crate::model::BodyId;
use crate::system::{State, System};
use nalgebra::Vector3;

impl System {
    /// Index in `self.flexible` of the flexible element of `body`.
    fn flexible_index(&self, body: BodyId) -> Option<usize> {
        self.flexible.iter().position(|f| f.body == body.index())
    }

    /// $\boldsymbol\eta$ of flexible body `body` at `state`, in the order of its reduced body's
    /// modes; empty for a rigid body, a body without modes or an unknown id.
    pub fn modal_coordinates(&self, state: &State, body: BodyId) -> Vec<f64> {
        self.topo
            .modal_scalars
            .get(body.index())
            .map(|s| s.iter().map(|&i| state.scalars[i]).collect())
            .unwrap_or_default()
    }

    /// The absolute positions of the FE mesh nodes of flexible body `body` at `state`
    /// (`Ok(None)` when its reduced body carries no mesh shapes, or `body` is not flexible).
    /// The floating frame is solved from the state's warm start.
    pub fn deformed_mesh(&self, state: &State, body: BodyId) -> Result<Option<Vec<Vector3<f64>>>, SolveError> {
        let Some(i) = self.flexible_index(body) else {
            return Ok(None);
        };
        let f = &self.flexible[i];
        let motions = self.node_motions(state);
        let eta = self.modal_coordinates(state, body);
        let eta_dot = vec![0.0; eta.len()];
        let bs = f.body_state(&motions, &eta, &eta_dot, state.frames[i]);
        let kin = f.se.kinematics(&bs).map_err(|source| SolveError::Body {
            body: self.model.bodies[body.index()].name().to_string(),
            t: state.time,
            source,
        })?;
        Ok(f.se.recover_mesh(&kin).map(|m| m.positions))
    }
}
