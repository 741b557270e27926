//! Loads: gravity, the point loads at nodes and the point loads at load points inside
//! flexible bodies, each with the name the study gives it.

use super::builder::Builder;
use super::mechanism::{located, BodyOut, LoadTarget, NamedLoad};
use crate::error::BoxError;
use crate::input::validate::mechanism::BodyLoadSpec;
use crate::input::validate::Study;
use mbs::Load;

impl Builder<'_> {
    /// Gravity and the `[[loads]]` point loads, at nodes and at load points inside bodies.
    pub(super) fn loads(&mut self) -> Result<(), BoxError> {
        let study = self.study;
        let m = &study.mechanism;
        if let Some((_, g)) = &m.gravity {
            self.model.gravity = *g;
        }
        for l in &m.loads {
            let n = self.node(&l.at, &l.path)?;
            let mut ids = Vec::new();
            for (kind, value) in &l.values {
                ids.push((*kind, self.model.loads.len()));
                self.entities
                    .insert(mbs::Entity::Load(self.model.loads.len()), l.path.clone());
                self.model.add_load(Load {
                    node: n,
                    kind: *kind,
                    axes: l.axes,
                    value: *value,
                    time: l.time.clone(),
                });
            }
            self.loads.push(NamedLoad {
                name: l.name.clone(),
                path: l.path.clone(),
                target: LoadTarget::Node(ids),
            });
        }
        for l in &m.body_loads {
            self.loads.push(NamedLoad {
                name: l.name.clone(),
                path: l.path.clone(),
                target: LoadTarget::Body(self.model.body_loads.len()),
            });
            self.entities
                .insert(mbs::Entity::BodyLoad(self.model.body_loads.len()), l.path.clone());
            let load = body_load(study, l, &self.bodies[l.body])?;
            self.model.body_loads.push(load);
        }
        Ok(())
    }
}

/// The `mbs` load of a `[[loads]]` point load at a load point inside a flexible body, its
/// point name resolved against the body's reduced load points.
pub(super) fn body_load(study: &Study, l: &BodyLoadSpec, body: &BodyOut) -> Result<mbs::BodyLoad, BoxError> {
    let Some(point) = body.reduced.load_points.iter().position(|p| p.name == l.point) else {
        let interfaces: Vec<&str> = body.reduced.interfaces.iter().map(|i| i.name.as_str()).collect();
        let points: Vec<&str> = body.reduced.load_points.iter().map(|p| p.name.as_str()).collect();
        return Err(located(
            study,
            &l.path.key("at"),
            format!(
                "body '{}' has no interface or load point '{}' (interfaces: {}; load points: {})",
                body.name,
                l.point,
                interfaces.join(", "),
                if points.is_empty() {
                    "none: add `load_points` to the part's reduction".to_string()
                } else {
                    points.join(", ")
                }
            ),
        ));
    };
    Ok(mbs::BodyLoad {
        body: body.id,
        point,
        force: l.force,
        moment: l.moment,
        axes: l.axes,
        time: l.time.clone(),
    })
}
