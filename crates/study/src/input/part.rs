//! A validated part: its FE model (mesh, elements, properties), its interfaces resolved to
//! nodes, and how to reduce it; and the functions that turn these into the FE model an
//! analysis or a reduction runs on ([`Part::build`], [`Part::build_for_reduction`]).
//!
//! Supports and interfaces are added in a fixed order: supports on mesh nodes, then the
//! interface spiders, then supports on interface nodes. An RBE3 spider must know which
//! surface dofs are supported before it picks its dependent dofs, and a support on an
//! interface node needs that node to exist.

#![allow(non_snake_case)]

use crate::input::source::KeyPath;
use fe_model::mass_properties::center_of_mass;
use fe_model::{DofMask, FeError, FeModel, MassKind, NodalLoad, NodeId, SpiderKind};
use nalgebra::{Point3, Vector3};
use reduction::ModeSelection;
use std::path::PathBuf;

/// Beams carry rotations at every node; solids only translations (interfaces add six dofs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartKind {
    Beam,
    Solid,
}

/// Where an interface attaches.
#[derive(Clone, Debug)]
pub enum InterfaceTarget {
    /// A beam node: the node is the interface.
    BeamNode(NodeId),
    /// A new 6-dof node tied to surface nodes by a spider.
    Spider {
        surface: Vec<NodeId>,
        kind: SpiderKind,
        node_position: Option<Point3<f64>>,
    },
}

#[derive(Clone, Debug)]
pub struct InterfaceSpec {
    pub name: String,
    /// `parts[i].interfaces[k]`, for messages.
    pub path: KeyPath,
    pub target: InterfaceTarget,
}

/// Craig-Bampton settings of a part.
#[derive(Clone, Debug, PartialEq)]
pub struct Reduction {
    pub modes: ModeSelection,
    pub auxiliary_node: bool,
    pub keep_mesh_shapes: bool,
    /// `reduction::CbSettings::geometric_stiffening`.
    pub geometric_stiffening: bool,
    /// `reduction::CbSettings::inertia_correction`.
    pub inertia_correction: bool,
    /// `reduction::CbSettings::planar` (and the default of `planar` for its bodies).
    pub planar: bool,
    /// `reduction::CbSettings::stress_shapes`.
    pub stress_shapes: bool,
    /// `reduction::CbSettings::load_points`: named nodes of the part's mesh.
    pub load_points: Vec<(String, NodeId)>,
    /// `reduction::CbSettings::factor`: the precision of the factor of $\mathbf K_{ii}$.
    pub factor: reduction::FactorPrecision,
}

/// A node of a part as named in a support or load.
#[derive(Clone, Debug, PartialEq)]
pub enum NodeRef {
    /// Interface `k` of the part.
    Interface(usize),
    /// Mesh nodes (a node set, or the node at a position).
    Nodes(Vec<NodeId>),
}

#[derive(Clone, Debug)]
pub struct SupportSpec {
    pub at: NodeRef,
    pub dofs: DofMask,
}

#[derive(Clone, Debug)]
pub struct LoadSpec {
    pub at: NodeRef,
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
}

/// A part of a validated study.
#[derive(Clone, Debug)]
pub struct Part {
    pub name: String,
    pub path: KeyPath,
    pub kind: PartKind,
    /// One line for reports: "20 beam elements (Timoshenko)", "gmsh mesh bar.msh: 96 tet10".
    pub description: String,
    /// The gmsh file it was read from, if any.
    pub mesh_file: Option<PathBuf>,
    /// Mesh, elements and properties; no interfaces, no supports.
    pub base: FeModel,
    pub interfaces: Vec<InterfaceSpec>,
    pub reduction: Option<Reduction>,
}

/// The FE model an analysis runs on, with the node of each interface.
#[derive(Clone, Debug)]
pub struct Built {
    pub model: FeModel,
    pub interfaces: Vec<(String, NodeId)>,
    /// The auxiliary interface node at the centre of mass, when asked for.
    pub auxiliary: Option<NodeId>,
}

thread_local! {
    /// Copies of parts' base models made by [`Part::build`] and [`Part::build_for_reduction`] on
    /// this thread.
    static COPIES: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// How many copies of parts' FE models [`Part::build`] and [`Part::build_for_reduction`] have
/// made on this thread so far: one per static, modal or reduce analysis run; validation ([`Part::check_build`]) makes none. For
/// tests that the work of a check does not grow with copies of a large mesh.
pub fn model_copies() -> usize {
    COPIES.with(|c| c.get())
}

/// Where the auxiliary interface node goes, found on the base model before anything is added.
enum AuxiliaryAt {
    /// The beam node at the centre of mass.
    Node(NodeId),
    /// A new node at the centre of mass, tied by an RBE3 spider to every node of the solids.
    Spider(Point3<f64>),
}

impl Part {
    /// The number of `node` (an index into the base mesh) in the part's mesh file, the deck
    /// label users find it by. `None` for generated meshes (their tags are positions) and for
    /// the nodes the program adds (spider and auxiliary nodes, after the file's nodes).
    pub fn deck_label(&self, node: usize) -> Option<u64> {
        self.mesh_file.as_ref()?;
        self.base.mesh.node_tags.get(node).copied()
    }

    /// The FE model a static or modal analysis runs on: the part with `supports` and the
    /// interfaces. Copies the base model once.
    pub fn build(&self, supports: &[SupportSpec]) -> Result<Built, FeError> {
        self.build_copy(supports, false)
    }

    /// The FE model `reduction` reduces: the part with its interfaces and, when the reduction
    /// asks for one, an auxiliary interface node at the centre of mass (beams: the node there;
    /// solids: an RBE3 spider on every node of the solid elements, which adds no stiffness).
    /// Copies the base model once.
    pub fn build_for_reduction(&self, reduction: &Reduction) -> Result<Built, FeError> {
        self.build_copy(&[], reduction.auxiliary_node)
    }

    /// [`Part::build`] with `supports`, and the auxiliary node with `auxiliary`.
    fn build_copy(&self, supports: &[SupportSpec], auxiliary: bool) -> Result<Built, FeError> {
        COPIES.with(|c| c.set(c.get() + 1));
        let mut model = self.base.clone();
        let (interfaces, auxiliary) = self.build_on(&mut model, supports, auxiliary)?;
        Ok(Built {
            model,
            interfaces,
            auxiliary,
        })
    }

    /// What [`Part::build`] builds, handed to `inspect`, without a copy of the base model: the
    /// supports, spiders and nodes are added to the base itself and removed again, so that
    /// checking a study of a large mesh costs no memory beyond the spiders. The base is the
    /// same after the call, whether the build failed or not.
    pub fn check_build<R>(
        &mut self,
        supports: &[SupportSpec],
        inspect: impl FnOnce(&Built) -> R,
    ) -> Result<R, FeError> {
        self.check_build_on(supports, false, inspect)
    }

    /// What [`Part::build_for_reduction`] builds for the part's own reduction (the auxiliary
    /// node if it asks for one; none without a reduction), handed to `inspect`, without a copy
    /// of the base model, as [`Part::check_build`].
    pub fn check_build_for_reduction<R>(&mut self, inspect: impl FnOnce(&Built) -> R) -> Result<R, FeError> {
        let auxiliary = self.reduction.as_ref().is_some_and(|r| r.auxiliary_node);
        self.check_build_on(&[], auxiliary, inspect)
    }

    /// [`Part::check_build`] with `supports`, and the auxiliary node with `auxiliary`.
    fn check_build_on<R>(
        &mut self,
        supports: &[SupportSpec],
        auxiliary: bool,
        inspect: impl FnOnce(&Built) -> R,
    ) -> Result<R, FeError> {
        let nodes = self.base.node_count();
        let base_supports = self.base.supports.len();
        // A spider may rewrite earlier constraints (shared nodes): keep the base's own.
        let base_constraints = self.base.constraints.clone();
        let mut model = std::mem::take(&mut self.base);
        let result = match self.build_on(&mut model, supports, auxiliary) {
            Ok((interfaces, auxiliary)) => {
                let built = Built {
                    model,
                    interfaces,
                    auxiliary,
                };
                let r = inspect(&built);
                model = built.model;
                Ok(r)
            }
            Err(e) => Err(e),
        };
        model.mesh.nodes.truncate(nodes);
        model.mesh.node_tags.truncate(nodes);
        model.supports.truncate(base_supports);
        model.constraints = base_constraints;
        self.base = model;
        result
    }
    /// Adds `supports`, the interfaces and, with `auxiliary`, the auxiliary node to `model`
    /// (the base model or a copy of it): the interface nodes and the auxiliary node.
    #[allow(clippy::type_complexity)]
    fn build_on(
        &self,
        model: &mut FeModel,
        supports: &[SupportSpec],
        auxiliary: bool,
    ) -> Result<(Vec<(String, NodeId)>, Option<NodeId>), FeError> {
        // The centre of mass is that of the elements: found before any node is added.
        let auxiliary = if auxiliary {
            Some(self.auxiliary_at(model)?)
        } else {
            None
        };
        for s in supports {
            if let NodeRef::Nodes(nodes) = &s.at {
                for &n in nodes {
                    model.add_support(n, s.dofs);
                }
            }
        }
        let mut interfaces = Vec::with_capacity(self.interfaces.len());
        for i in &self.interfaces {
            let node = match &i.target {
                InterfaceTarget::BeamNode(n) => *n,
                InterfaceTarget::Spider {
                    surface,
                    kind,
                    node_position,
                } => fe_model::add_interface(model, &i.name, surface, *node_position, *kind)?,
            };
            interfaces.push((i.name.clone(), node));
        }
        for s in supports {
            if let NodeRef::Interface(k) = s.at {
                model.add_support(interfaces[k].1, s.dofs);
            }
        }
        let auxiliary = match auxiliary {
            None => None,
            Some(AuxiliaryAt::Node(node)) => Some(node),
            Some(AuxiliaryAt::Spider(c)) => {
                // Every node of the solid elements, marked once each: linear in the model size.
                let mut used = vec![false; model.node_count()];
                for e in &model.elements {
                    for n in e.nodes() {
                        if let Some(u) = used.get_mut(n.index()) {
                            *u = true;
                        }
                    }
                }
                let nodes: Vec<NodeId> = (0..used.len()).filter(|&i| used[i]).map(|i| NodeId(i as u32)).collect();
                drop(used);
                Some(fe_model::add_interface(
                    model,
                    "auxiliary",
                    &nodes,
                    Some(c),
                    SpiderKind::Rbe3,
                )?)
            }
        };
        Ok((interfaces, auxiliary))
    }

    /// Where the auxiliary node goes on `base` (the part's elements, no interface added yet).
    fn auxiliary_at(&self, base: &FeModel) -> Result<AuxiliaryAt, FeError> {
        let (mass, c) = center_of_mass(base)?;
        let bad = |why: String| FeError::Interface {
            name: "auxiliary".into(),
            why,
        };
        if !(mass > 0.0) {
            return Err(bad("the part has no mass, so no centre of mass".into()));
        }
        match self.kind {
            PartKind::Beam => {
                let node = base
                    .mesh
                    .nearest_node(&c)
                    .ok_or_else(|| bad("the part has no nodes".into()))?;
                let d = (base.mesh.nodes[node.index()] - c).norm();
                if d > 1e-9 * model_size(base).max(f64::MIN_POSITIVE) {
                    return Err(bad(format!(
                        "no beam node at the centre of mass ({:.6}, {:.6}, {:.6}); the nearest is {:.3e} m away (use an even number of elements on a symmetric beam)",
                        c.x, c.y, c.z, d
                    )));
                }
                Ok(AuxiliaryAt::Node(node))
            }
            PartKind::Solid => Ok(AuxiliaryAt::Spider(c)),
        }
    }

    /// The nodal loads of `loads` on a model built by [`Part::build`]; a load on a set is
    /// refused by the validator, so every `Nodes` here has one node.
    pub fn nodal_loads(built: &Built, loads: &[LoadSpec]) -> Vec<NodalLoad> {
        loads
            .iter()
            .filter_map(|l| {
                let node = match &l.at {
                    NodeRef::Interface(k) => built.interfaces[*k].1,
                    NodeRef::Nodes(n) => *n.first()?,
                };
                Some(NodalLoad {
                    node,
                    force: l.force,
                    moment: l.moment,
                })
            })
            .collect()
    }
}

/// The largest extent of the model's bounding box (1 for an empty model), the length scale
/// for position tolerances.
pub fn model_size(model: &FeModel) -> f64 {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in &model.mesh.nodes {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    let size = (hi - lo).max();
    if size.is_finite() && size > 0.0 {
        size
    } else {
        1.0
    }
}

/// A `MassKind` from the file's choice.
pub fn mass_kind(m: Option<crate::input::schema::MassFile>) -> MassKind {
    match m {
        Some(crate::input::schema::MassFile::Lumped) => MassKind::Lumped,
        _ => MassKind::Consistent,
    }
}
