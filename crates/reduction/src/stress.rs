//! Stress shapes of a reduced body ([`StressShapes`]): the stress of every CB vector, computed
//! on the FE elements once at reduction time, so that a body's stress at any state is the
//! product $\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q^{jj}$ of the stored shapes with its
//! elastic coordinates (recovery: `superelement::recovery`). Linear in the elastic field,
//! like the reduced body itself (the floating frame carries the large motion).

#![allow(non_snake_case)]

use crate::error::ReductionError;
use crate::reduced_body::{combine, BeamStressElement, DenseMatrix, StressShapes};
use faer::MatRef;
use fe_model::stress::{averaged_nodal_stresses, beam_section_forces};
use fe_model::{Element, FeModel};
use rayon::prelude::*;

/// The stress shapes of the basis `S_full` ($6 n_{nodes} \times n$, every node's six slots):
/// solid stresses at the nodes ([`fe_model::stress::averaged_nodal_stresses`]) and beam section
/// forces at both ends of every beam ([`fe_model::stress::beam_section_forces`]).
///
/// # Errors
/// [`ReductionError::Fe`] or [`ReductionError::InvalidFeModel`] for an element whose geometry or properties cannot give stresses.
pub fn stress_shapes(model: &FeModel, S_full: MatRef<'_, f64>) -> Result<StressShapes, ReductionError> {
    let n = S_full.ncols();
    let basis = DenseMatrix::from_faer(S_full);
    let has_solids = model.elements.iter().any(|e| e.solid().is_some());
    let (nodal, solid_node) = if has_solids {
        let (sigma, count) = averaged_nodal_stresses(model, &basis.data, n)?;
        (
            Some(DenseMatrix {
                nrows: 6 * model.node_count(),
                ncols: n,
                data: sigma,
            }),
            count.iter().map(|&c| c > 0).collect(),
        )
    } else {
        (None, Vec::new())
    };
    let beams: Vec<BeamStressElement> =
        model
            .elements
            .iter()
            .enumerate()
            .filter_map(|(e, element)| match element {
                Element::Beam2(b) => Some((e, b)),
                _ => None,
            })
            .map(|(e, b)| {
                let section = model.sections.get(b.section.0 as usize).cloned().ok_or_else(|| {
                    ReductionError::InvalidFeModel {
                        what: format!("element {e}: beam section {} does not exist", b.section.0),
                    }
                })?;
                Ok(BeamStressElement {
                    element: e as u32,
                    nodes: [b.nodes[0].0, b.nodes[1].0],
                    section,
                })
            })
            .collect::<Result<_, ReductionError>>()?;
    let rows = 12 * beams.len();
    // Column by column in parallel: each CB vector's section forces on every beam.
    let columns: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|k| {
            let mut col = Vec::with_capacity(rows);
            for b in &beams {
                let u_e: Vec<f64> = b
                    .nodes
                    .iter()
                    .flat_map(|&node| (0..6).map(move |s| S_full[(6 * node as usize + s, k)]))
                    .collect();
                let s = beam_section_forces(model, b.element as usize, &u_e, None)?;
                col.extend(s.iter().flatten());
            }
            Ok(col)
        })
        .collect::<Result<_, ReductionError>>()?;
    Ok(StressShapes {
        nodal,
        solid_node,
        beams,
        beam_forces: DenseMatrix {
            nrows: rows,
            ncols: n,
            data: columns.into_iter().flatten().collect(),
        },
    })
}

/// The stresses of a body at its mesh nodes in global axes: the Voigt tensor $[xx, yy, zz, xy,
/// yz, zx]$ (zero where none), von Mises and the largest principal stress \[Pa\]. Beam nodes
/// carry no tensor: their von Mises and largest principal stress are the largest magnitude and
/// the largest value of the extreme-fibre axial stress over the element ends at the node
/// ([`fe_model::BeamSection::fibre_stress_range`]; the shear stresses of the section are not
/// included). Nodes without stress (spider nodes) hold 0.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeStresses {
    pub tensor: Vec<[f64; 6]>,
    pub von_mises: Vec<f64>,
    pub principal: Vec<f64>,
}

impl StressShapes {
    /// The number of mesh nodes the shapes cover (solid nodes, beam nodes).
    pub fn node_count(&self) -> usize {
        self.solid_node.len().max(
            self.beams
                .iter()
                .flat_map(|b| b.nodes)
                .max()
                .map_or(0, |m| m as usize + 1),
        )
    }

    /// [`NodeStresses`] for CB coordinates `q` ($\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q$ in
    /// body axes), turned into global axes by `R` ($\mathbf R\boldsymbol\sigma\mathbf R^T$).
    /// One matrix-vector product for every node's tensor; von Mises and the principal stresses
    /// are invariant under the rotation and are taken from the body-axes tensor.
    ///
    /// # Panics
    /// If `q` does not have one value per column (a caller's bug).
    pub fn node_stresses(&self, q: &[f64], R: &nalgebra::Matrix3<f64>) -> NodeStresses {
        let n_nodes = self.node_count();
        let mut out = NodeStresses {
            tensor: vec![[0.0; 6]; n_nodes],
            von_mises: vec![0.0; n_nodes],
            principal: vec![0.0; n_nodes],
        };
        self.for_each_solid_node(q, |i, s| {
            let g = R * fe_model::stress::tensor(s) * R.transpose();
            out.tensor[i] = [g[(0, 0)], g[(1, 1)], g[(2, 2)], g[(0, 1)], g[(1, 2)], g[(2, 0)]];
            out.von_mises[i] = fe_model::von_mises(s);
            out.principal[i] = fe_model::principal_stresses(s)[0];
        });
        for (i, x) in self.beam_extremes(q, n_nodes).iter().enumerate() {
            if let Some([magnitude, largest]) = x {
                out.von_mises[i] = *magnitude;
                out.principal[i] = *largest;
            }
        }
        out
    }

    /// The von Mises stress of every mesh node for CB coordinates `q`, as
    /// [`NodeStresses::von_mises`] of [`Self::node_stresses`] but without the rotation to global
    /// axes (von Mises is invariant under it) and without principal stresses: the cheap path of
    /// a largest-von-Mises output at every step.
    ///
    /// # Panics
    /// If `q` does not have one value per column (a caller's bug).
    pub fn von_mises(&self, q: &[f64]) -> Vec<f64> {
        let n_nodes = self.node_count();
        let mut vm = vec![0.0; n_nodes];
        self.for_each_solid_node(q, |i, s| vm[i] = fe_model::von_mises(s));
        for (i, x) in self.beam_extremes(q, n_nodes).iter().enumerate() {
            if let Some([magnitude, _]) = x {
                vm[i] = *magnitude;
            }
        }
        vm
    }

    /// Calls `f(i, sigma_i)` with the body-axes stress of every solid node `i` below the node
    /// count ($\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q$, one matrix-vector product).
    fn for_each_solid_node(&self, q: &[f64], mut f: impl FnMut(usize, &[f64; 6])) {
        let Some(S) = &self.nodal else {
            return;
        };
        let sigma = combine(S, q);
        for ((i, s), _) in sigma
            .chunks_exact(6)
            .enumerate()
            .zip(&self.solid_node)
            .filter(|(_, &solid)| solid)
        {
            f(i, s.try_into().expect("6 components"));
        }
    }

    /// The largest magnitude and the largest value of the beams' extreme-fibre axial stress at
    /// every node below `n_nodes` (`None` at nodes without a beam end).
    fn beam_extremes(&self, q: &[f64], n_nodes: usize) -> Vec<Option<[f64; 2]>> {
        if self.beams.is_empty() {
            return Vec::new();
        }
        let forces = self.beam_section_forces(q);
        let ends = self.beams.iter().zip(&forces).flat_map(|(b, forces)| {
            forces.iter().enumerate().filter_map(move |(end, f)| {
                let node = b.nodes[end] as usize;
                let range = b.section.fibre_stress_range(f)?;
                (node < n_nodes).then_some((node, range))
            })
        });
        fe_model::stress::fibre_extremes_at_nodes(n_nodes, ends)
    }
}
