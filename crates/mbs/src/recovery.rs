//! Results of a state body by body: the modal coordinates $\boldsymbol\eta$ of a flexible body
//! and its deformed FE mesh (the superelement's mesh recovery, `superelement::recovery`, at the
//! node motions of the state), with the system's own superelements ([`System::superelement`]):
//! nothing is built again to draw a body.

use crate::error::SolveError;
use crate::model::BodyId;
use crate::system::{State, System};
use nalgebra::Vector3;
use superelement::Kinematics;

impl System {
    /// $\boldsymbol\eta$ of flexible body `body` at `state`, in the order of its reduced body's
    /// modes; empty for a rigid body, a body without modes or an unknown id.
    pub fn modal_coordinates(&self, state: &State, body: BodyId) -> Vec<f64> {
        self.topo
            .modal_scalars
            .get(body.index())
            .map(|s| s.iter().map(|&i| state.scalars[i]).collect())
            .unwrap_or_default()
    }

    /// The superelement kinematics of flexible body `body` at `state` (floating frame solved
    /// from the state's warm start, $\mathbf q^{jj}$, $\mathbf R_j$); `Ok(None)` when `body` is
    /// not flexible.
    pub fn body_kinematics(&self, state: &State, body: BodyId) -> Result<Option<Kinematics>, SolveError> {
        let (Some(se), Some(bs)) = (self.superelement(body), self.flexible_body_state(body, state)) else {
            return Ok(None);
        };
        se.kinematics(&bs).map(Some).map_err(|source| SolveError::Body {
            body: self.model.bodies[body.index()].name().to_string(),
            t: state.time,
            source,
        })
    }

    /// The absolute positions of the FE mesh nodes of flexible body `body` at `state`
    /// (`Ok(None)` when its reduced body carries no mesh shapes, or `body` is not flexible).
    /// The floating frame is solved from the state's warm start.
    pub fn deformed_mesh(&self, state: &State, body: BodyId) -> Result<Option<Vec<Vector3<f64>>>, SolveError> {
        let (Some(se), Some(kin)) = (self.superelement(body), self.body_kinematics(state, body)?) else {
            return Ok(None);
        };
        Ok(se.recover_mesh(&kin).map(|m| m.positions))
    }
}
