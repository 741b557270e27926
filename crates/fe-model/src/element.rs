//! The closed list of element kinds and their dispatch.
//!
//! An element is a pure function of its reference geometry and its properties: it never sees
//! the system, other elements or the dof numbering. Adding a kind is a compile error at every
//! `match` that must handle it.
//!
//! Naming rule: `*_matrices` returns the stiffness $\mathbf K_e$ and mass $\mathbf M_e$ in
//! global axes, local dofs ordered node by node, each node's dofs in the order of
//! [`Element::node_dofs`].

#![allow(non_snake_case)]

pub mod beam2;
pub mod hex20;
pub mod hex8;
pub mod solid;
pub mod tet10;
pub mod tet4;
pub mod wedge6;

pub use solid::{Solid, SolidKind};

use crate::error::ElementError;
use crate::mesh::NodeId;
use crate::property::{IsotropicMaterial, MaterialId, SectionId};
use crate::section::BeamSection;
use nalgebra::{DMatrix, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Dofs of a node that carries rotations: $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$.
pub const DOFS_6: [usize; 6] = [0, 1, 2, 3, 4, 5];
/// Dofs of a solid node: translations only.
pub const DOFS_3: [usize; 3] = [0, 1, 2];

/// Beam bending theory.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum BeamTheory {
    /// No shear deformation; plane sections stay normal to the axis.
    EulerBernoulli,
    /// Shear deformation with the section's shear factors (`ky`, `kz`).
    Timoshenko,
}

/// How an element's mass is distributed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum MassKind {
    /// Consistent mass from the element's shape functions (with rotary inertia for beams).
    Consistent,
    /// Diagonal (lumped) mass.
    Lumped,
}

/// 2-node 3D beam: axial, torsion, bending in two planes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Beam2 {
    pub nodes: [NodeId; 2],
    pub section: SectionId,
    pub material: MaterialId,
    /// Any vector in the local $x$-$y$ plane, not parallel to the axis $\mathbf e_x$ (node 1
    /// to node 2): $\mathbf e_z = \mathbf e_x \times \mathbf v / \lVert \mathbf e_x \times
    /// \mathbf v \rVert$, $\mathbf e_y = \mathbf e_z \times \mathbf e_x$. `Iz` (about
    /// $\mathbf e_z$) resists bending in the $x$-$y$ plane, `Iy` in the $x$-$z$ plane (see
    /// [`crate::section`] and [`beam2`]).
    pub orientation: Vector3<f64>,
    pub theory: BeamTheory,
    pub mass: MassKind,
}

/// One element kind per variant; the list is closed on purpose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Element {
    /// 2 nodes x 6 dofs, theory in [`Beam2::theory`].
    Beam2(Beam2),
    /// 4-node tetrahedron, 3 dofs per node; for contrast only: it locks in bending (theory guide §2).
    Tet4(Solid),
    /// 10-node tetrahedron, 3 dofs per node.
    Tet10(Solid),
    /// 8-node hexahedron, 3 dofs per node.
    Hex8(Solid),
    /// 20-node serendipity hexahedron, 3 dofs per node.
    Hex20(Solid),
    /// 6-node wedge (prism), 3 dofs per node.
    Wedge6(Solid),
}

/// Element stiffness and mass in global axes, dofs ordered node by node.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalMatrices {
    pub K_e: DMatrix<f64>,
    pub M_e: DMatrix<f64>,
}

/// The property tables an element may read.
#[derive(Clone, Copy, Debug)]
pub struct Properties<'a> {
    pub materials: &'a [IsotropicMaterial],
    pub sections: &'a [BeamSection],
}

impl<'a> Properties<'a> {
    pub(crate) fn material(&self, element: usize, id: MaterialId) -> Result<&'a IsotropicMaterial, ElementError> {
        entry(self.materials, element, "material", id.0 as usize)
    }
    pub(crate) fn section(&self, element: usize, id: SectionId) -> Result<&'a BeamSection, ElementError> {
        entry(self.sections, element, "beam section", id.0 as usize)
    }
}

/// Entry `index` of the property table `table` (of `what`s) that element `element` reads.
fn entry<'a, T>(table: &'a [T], element: usize, what: &'static str, index: usize) -> Result<&'a T, ElementError> {
    table.get(index).ok_or(ElementError::MissingProperty {
        element,
        what,
        index,
        count: table.len(),
    })
}

impl Element {
    /// The element's nodes, in its own ordering.
    pub fn nodes(&self) -> &[NodeId] {
        match self {
            Element::Beam2(b) => &b.nodes,
            Element::Tet4(s) | Element::Tet10(s) | Element::Hex8(s) | Element::Hex20(s) | Element::Wedge6(s) => {
                &s.nodes
            }
        }
    }

    /// Which of a node's six dofs the element uses (the same for all its nodes).
    pub fn node_dofs(&self) -> &'static [usize] {
        match self {
            Element::Beam2(_) => &DOFS_6,
            Element::Tet4(_) | Element::Tet10(_) | Element::Hex8(_) | Element::Hex20(_) | Element::Wedge6(_) => &DOFS_3,
        }
    }

    /// The kind and data of a solid element, `None` for beams.
    pub fn solid(&self) -> Option<(SolidKind, &Solid)> {
        match self {
            Element::Beam2(_) => None,
            Element::Tet4(s) => Some((SolidKind::Tet4, s)),
            Element::Tet10(s) => Some((SolidKind::Tet10, s)),
            Element::Hex8(s) => Some((SolidKind::Hex8, s)),
            Element::Hex20(s) => Some((SolidKind::Hex20, s)),
            Element::Wedge6(s) => Some((SolidKind::Wedge6, s)),
        }
    }

    /// A solid element of the given kind.
    pub fn new_solid(kind: SolidKind, solid: Solid) -> Element {
        match kind {
            SolidKind::Tet4 => Element::Tet4(solid),
            SolidKind::Tet10 => Element::Tet10(solid),
            SolidKind::Hex8 => Element::Hex8(solid),
            SolidKind::Hex20 => Element::Hex20(solid),
            SolidKind::Wedge6 => Element::Wedge6(solid),
        }
    }

    /// A short name for messages.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Element::Beam2(_) => "beam2",
            Element::Tet4(_) => "tet4",
            Element::Tet10(_) => "tet10",
            Element::Hex8(_) => "hex8",
            Element::Hex20(_) => "hex20",
            Element::Wedge6(_) => "wedge6",
        }
    }

    /// Stiffness and mass in global axes from the reference coordinates `X_e` of the
    /// element's nodes. `index` is the element's position in the model, used in errors.
    pub fn local_matrices(
        &self,
        index: usize,
        X_e: &[Point3<f64>],
        props: &Properties<'_>,
    ) -> Result<LocalMatrices, ElementError> {
        if X_e.len() != self.nodes().len() {
            return Err(ElementError::WrongNodeCount {
                element: index,
                kind: self.kind_name(),
                expected: self.nodes().len(),
                got: X_e.len(),
            });
        }
        let solid_arm = |kind: SolidKind, s: &Solid| {
            let material = props.material(index, s.material)?;
            solid::solid_matrices(kind, index, X_e, material, s.mass)
        };
        match self {
            Element::Beam2(b) => {
                let section = props.section(index, b.section)?;
                let material = props.material(index, b.material)?;
                beam2::beam2_matrices(b, index, [X_e[0], X_e[1]], section, material)
            }
            Element::Tet4(s) => solid_arm(SolidKind::Tet4, s),
            Element::Tet10(s) => solid_arm(SolidKind::Tet10, s),
            Element::Hex8(s) => solid_arm(SolidKind::Hex8, s),
            Element::Hex20(s) => solid_arm(SolidKind::Hex20, s),
            Element::Wedge6(s) => solid_arm(SolidKind::Wedge6, s),
        }
    }

    /// The mass matrix of [`Element::local_matrices`] alone: for solids without computing the
    /// stiffness (most of the cost of an element's matrices); a beam's are cheap and computed
    /// together.
    pub fn mass_matrix(
        &self,
        index: usize,
        X_e: &[Point3<f64>],
        props: &Properties<'_>,
    ) -> Result<DMatrix<f64>, ElementError> {
        match self.solid() {
            Some((kind, s)) if X_e.len() == self.nodes().len() => {
                solid::solid_mass(kind, index, X_e, props.material(index, s.material)?, s.mass)
            }
            _ => Ok(self.local_matrices(index, X_e, props)?.M_e),
        }
    }
}
