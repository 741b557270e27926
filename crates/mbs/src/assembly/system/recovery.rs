//! Results of a state body by body: the floating frame and configuration of a flexible body
//! and its deformed FE mesh (the superelement's mesh recovery, `superelement::recovery`, at
//! the node motions of the state), with the system's own superelements
//! ([`System::superelement`]): nothing is built again to draw a body. The modal coordinates
//! are [`System::modal_coordinates`].

use crate::assembly::system::System;
use crate::error::SolveError;
use crate::model::BodyId;
use crate::state::State;
use nalgebra::Vector3;
use superelement::{BodyState, Kinematics};

impl System {
    /// The superelement kinematics of flexible body `body` at `state` (floating frame solved
    /// from the state's last frame, $\mathbf q^{jj}$, $\mathbf R_j$), with the body state it
    /// was solved for (interface velocities and modal rates included, for mesh velocities);
    /// `Ok(None)` when `body` is not flexible.
    pub fn body_kinematics(&self, state: &State, body: BodyId) -> Result<Option<(Kinematics, BodyState)>, SolveError> {
        let (Some(se), Some(bs)) = (self.superelement(body), self.flexible_body_state(body, state)) else {
            return Ok(None);
        };
        let kin = se.kinematics(&bs).map_err(|source| SolveError::Body {
            body: self.model.bodies[body.index()].name().to_string(),
            id: body,
            at: crate::error::At::Time(state.time),
            step: None,
            source: Box::new(source),
        })?;
        Ok(Some((kin, bs)))
    }

    /// The absolute positions of the FE mesh nodes of flexible body `body` at `state`
    /// (`Ok(None)` when its reduced body carries no mesh shapes, or `body` is not flexible).
    /// The floating frame is solved from the state's last frame.
    pub fn deformed_mesh(&self, state: &State, body: BodyId) -> Result<Option<Vec<Vector3<f64>>>, SolveError> {
        let (Some(se), Some((kin, _))) = (self.superelement(body), self.body_kinematics(state, body)?) else {
            return Ok(None);
        };
        Ok(se.recover_mesh(&kin).map(|m| m.positions))
    }
}
