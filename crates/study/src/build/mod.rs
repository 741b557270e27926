//! The mechanism of a validated study as an `mbs::Model`, built concern by concern from the
//! bodies the reduction service reduced beforehand ([`ReducedBodies`]):
//!
//! | module | what it holds or adds to the model |
//! |---|---|
//! | [`mechanism`] | the [`BuiltMechanism`] and the [`ReducedBodies`] it is built from |
//! | [`builder`] | the model being built, shared by the concerns below in turn |
//! | [`points`] | the nodes: every point of every body, merged by the fixed joints |
//! | [`bodies`] | flexible and rigid bodies, point masses, springs, supports |
//! | [`joints`] | joints, drivers, joint springs, joint limits, actuators |
//! | [`loads`] | gravity and the named point loads |
//! | [`sensors`] | the `mbs` sensors of each sensor of the study, with its output columns |
//! | [`initial`] | the initial conditions |
//!
//! Beside the model, the [`BuiltMechanism`] keeps what the analyses and outputs need: the
//! sensor groups, each flexible body's reduced body and mesh, the rigid bodies' nodes, the
//! named loads, and where the study describes each entity of the model.

mod bodies;
mod builder;
mod initial;
mod joints;
mod loads;
mod mechanism;
mod points;
mod sensors;

pub use mechanism::{joint_count, BuiltMechanism, LoadTarget, NamedLoad, ReducedBodies};

use crate::error::BoxError;
use crate::input::validate::Study;
use builder::Builder;

/// Builds the `mbs::Model` of the study's mechanism from its reduced bodies (module docs),
/// in the order the model numbers its entities.
pub fn build(study: &Study, bodies: ReducedBodies) -> Result<BuiltMechanism, BoxError> {
    let (reduced, reductions) = bodies;
    let mut b = Builder::new(study, reduced)?;
    b.flexible_bodies()?;
    b.rigid_bodies()?;
    b.point_elements()?;
    b.joints()?;
    b.drivers()?;
    b.loads()?;
    b.sensors()?;
    b.initial_states()?;
    b.joint_forces()?;
    Ok(BuiltMechanism {
        model: b.model,
        groups: b.groups,
        bodies: b.bodies,
        rigid: b.rigid,
        welds: b.welds,
        entities: b.entities,
        reductions,
        loads: b.loads,
    })
}
