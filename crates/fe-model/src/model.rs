//! [`FeModel`]: a mesh with elements, properties, supports and linear constraints. Plain
//! serde data: this is what passes from the FE stage to the reduction.

use crate::element::{Beam2, BeamTheory, Element, MassKind, Properties};
use crate::error::FeError;
use crate::mesh::{Mesh, NodeId};
use crate::property::{IsotropicMaterial, MaterialId, SectionId};
use crate::section::BeamSection;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Which of a node's six dofs $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$ a support holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DofMask(pub [bool; 6]);

impl DofMask {
    /// All six dofs (a clamp).
    pub const ALL: DofMask = DofMask([true; 6]);
    /// The three translations (a pin).
    pub const TRANSLATIONS: DofMask = DofMask([true, true, true, false, false, false]);
    /// The three rotations.
    pub const ROTATIONS: DofMask = DofMask([false, false, false, true, true, true]);

    /// A mask holding only dof `k` (0..6).
    pub fn single(k: usize) -> DofMask {
        let mut m = [false; 6];
        m[k] = true;
        DofMask(m)
    }
}

/// Dofs of a node held at zero (eliminated from the unknowns, never penalised).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Support {
    pub node: NodeId,
    pub dofs: DofMask,
}

/// A linear multipoint constraint, eliminated from the unknowns:
/// $u_{dep} = \sum_i c_i\, u_i$.
///
/// Each dof is `(node, k)` with `k` in 0..6. The right-hand side dofs must be independent
/// (free or supported), not dependent dofs of another constraint. RBE2 and RBE3 spiders are
/// built as sets of these.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearConstraint {
    /// The spider or rule this constraint belongs to, for messages.
    pub name: String,
    pub dependent: (NodeId, u8),
    pub terms: Vec<(NodeId, u8, f64)>,
}

/// A nodal force and moment in global axes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodalLoad {
    pub node: NodeId,
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
}

impl NodalLoad {
    pub fn force(node: NodeId, force: Vector3<f64>) -> Self {
        Self {
            node,
            force,
            moment: Vector3::zeros(),
        }
    }
    pub fn moment(node: NodeId, moment: Vector3<f64>) -> Self {
        Self {
            node,
            force: Vector3::zeros(),
            moment,
        }
    }
}

/// A finite-element model: geometry, elements, properties, supports and constraints.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FeModel {
    pub mesh: Mesh,
    pub materials: Vec<IsotropicMaterial>,
    pub sections: Vec<BeamSection>,
    pub elements: Vec<Element>,
    pub supports: Vec<Support>,
    pub constraints: Vec<LinearConstraint>,
}

/// The settings shared by the beams a generator creates.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamProperties {
    pub section: SectionId,
    pub material: MaterialId,
    /// A vector in the local $x$-$y$ plane (see [`Beam2::orientation`]).
    pub orientation: Vector3<f64>,
    pub theory: BeamTheory,
    pub mass: MassKind,
}

impl FeModel {
    /// The property tables elements read.
    pub fn properties(&self) -> Properties<'_> {
        Properties {
            materials: &self.materials,
            sections: &self.sections,
        }
    }

    /// Adds a material and returns its id.
    pub fn add_material(&mut self, m: IsotropicMaterial) -> MaterialId {
        self.materials.push(m);
        MaterialId(self.materials.len() as u32 - 1)
    }

    /// Adds a beam section and returns its id.
    pub fn add_section(&mut self, s: BeamSection) -> SectionId {
        self.sections.push(s);
        SectionId(self.sections.len() as u32 - 1)
    }

    /// Adds a node at `x`.
    pub fn add_node(&mut self, x: Point3<f64>) -> NodeId {
        self.mesh.add_node(x)
    }

    /// Adds one beam element between two existing nodes.
    pub fn add_beam(&mut self, n1: NodeId, n2: NodeId, p: &BeamProperties) -> usize {
        self.elements.push(Element::Beam2(Beam2 {
            nodes: [n1, n2],
            section: p.section,
            material: p.material,
            orientation: p.orientation,
            theory: p.theory,
            mass: p.mass,
        }));
        self.elements.len() - 1
    }

    /// Clamps or pins a node.
    pub fn add_support(&mut self, node: NodeId, dofs: DofMask) {
        self.supports.push(Support { node, dofs });
    }

    /// Checks that `node` exists; `context` says who asked, for the message.
    pub fn check_node(&self, node: NodeId, context: &str) -> Result<(), FeError> {
        if node.index() < self.mesh.nodes.len() {
            Ok(())
        } else {
            Err(FeError::UnknownNode {
                context: context.to_string(),
                node,
                count: self.mesh.nodes.len(),
            })
        }
    }

    /// The nodes of a named set, with an error listing the known sets.
    pub fn node_set(&self, name: &str, context: &str) -> Result<&[NodeId], FeError> {
        self.mesh.node_set(name).ok_or_else(|| FeError::UnknownNodeSet {
            context: context.to_string(),
            name: name.to_string(),
            known: self.mesh.node_sets.keys().cloned().collect::<Vec<_>>().join(", "),
        })
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.mesh.nodes.len()
    }
}
