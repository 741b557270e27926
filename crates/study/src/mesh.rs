//! The mesh of a part or a body as VTK cells: points, cells in VTK's node order and what each
//! cell stands for. Plain data that `build` (a body's mesh) and `run` (the meshes of a part's
//! results) make and `output::vtu` writes; it uses nothing of the crate, so that `build`
//! needs nothing of `output`. The node orders are described in `output::vtu`.

use fe_model::{CellKind, Element, FeModel, NodeId};

/// `VTK[k] = ours[HEX20_TO_VTK[k]]`. Corners agree; VTK lists the mid-edge nodes of the bottom
/// face (01, 12, 23, 30), then the top face (45, 56, 67, 74), then the vertical edges (04, 15,
/// 26, 37); gmsh lists them by lowest corner: 01, 03, 04, 12, 15, 23, 26, 37, 45, 47, 56, 67.
pub const HEX20_TO_VTK: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15];

/// `VTK[k] = ours[TET10_TO_VTK[k]]`: VTK's node 8 is on edge 1-3 and 9 on edge 2-3; gmsh's 8
/// is on edge 3-2 and 9 on edge 3-1.
pub const TET10_TO_VTK: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

const IDENTITY: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19];

/// The VTK cell type of a kind, and the permutation from our node order to VTK's.
pub fn vtk_cell(kind: CellKind) -> (u8, &'static [usize]) {
    match kind {
        CellKind::Line2 => (3, &IDENTITY[..2]),
        CellKind::Tri3 => (5, &IDENTITY[..3]),
        CellKind::Quad4 => (9, &IDENTITY[..4]),
        CellKind::Tet4 => (10, &IDENTITY[..4]),
        CellKind::Hex8 => (12, &IDENTITY[..8]),
        CellKind::Wedge6 => (13, &IDENTITY[..6]),
        CellKind::Tri6 => (22, &IDENTITY[..6]),
        CellKind::Quad8 => (23, &IDENTITY[..8]),
        CellKind::Tet10 => (24, &TET10_TO_VTK),
        CellKind::Hex20 => (25, &HEX20_TO_VTK),
    }
}

/// What a VTU cell stands for, written as the cell field `kind` so that ParaView's Threshold
/// can show elements, spiders and interface nodes apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellRole {
    Element = 0,
    SpiderLeg = 1,
    InterfaceNode = 2,
}

/// The radius of the tube that draws a beam of section `s`: a round section's outer radius,
/// else that of the circle of its area.
fn section_radius(s: &fe_model::BeamSection) -> f64 {
    match s.shape() {
        fe_model::SectionShape::Tube { d_outer, .. } => d_outer / 2.0,
        _ => (s.A() / std::f64::consts::PI).sqrt(),
    }
}

/// Points and cells in VTK order.
#[derive(Clone, Debug, Default)]
pub struct VtuMesh {
    pub points: Vec<[f64; 3]>,
    /// VTK type, connectivity in VTK order, role.
    pub cells: Vec<(u8, Vec<usize>, CellRole)>,
    /// The radius of each beam cell's section, cell by cell (0 for other cells; a circle of
    /// the section's area when it is not round), for drawing beams as tubes; may be shorter
    /// than `cells` (cells past its end have none).
    pub radius: Vec<f64>,
}

impl VtuMesh {
    /// The elements of `model` (beams as lines, solids as their kind), and for each
    /// interface `(node, surface nodes)` a vertex and one line per spider leg.
    pub fn from_model(model: &FeModel, interfaces: &[(NodeId, Vec<NodeId>)]) -> Self {
        let points = model.mesh.nodes.iter().map(|p| [p.x, p.y, p.z]).collect();
        let mut cells = Vec::with_capacity(model.elements.len());
        let mut radius = Vec::with_capacity(model.elements.len());
        for e in &model.elements {
            radius.push(match e {
                Element::Beam2(b) => model.sections.get(b.section.0 as usize).map_or(0.0, section_radius),
                _ => 0.0,
            });
            let kind = match e {
                Element::Beam2(_) => CellKind::Line2,
                other => match other.solid() {
                    Some((k, _)) => k.cell_kind(),
                    None => {
                        radius.pop();
                        continue;
                    }
                },
            };
            cells.push(Self::cell(kind, e.nodes()));
        }
        for (node, surface) in interfaces {
            cells.push((1, vec![node.index()], CellRole::InterfaceNode));
            for s in surface {
                cells.push((3, vec![node.index(), s.index()], CellRole::SpiderLeg));
            }
        }
        Self { points, cells, radius }
    }

    /// One cell of `kind` with nodes in our order.
    pub fn cell(kind: CellKind, nodes: &[NodeId]) -> (u8, Vec<usize>, CellRole) {
        let (vtk, perm) = vtk_cell(kind);
        (vtk, perm.iter().map(|&k| nodes[k].index()).collect(), CellRole::Element)
    }
}
