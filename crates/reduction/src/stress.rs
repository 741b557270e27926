//! Stress shapes of a reduced body ([`StressShapes`]): the stress of every CB vector, computed
//! on the FE elements once at reduction time, so that a body's stress at any state is the
//! product $\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q^{jj}$ of the stored shapes with its
//! elastic coordinates (recovery: `superelement::recovery`). Linear in the elastic field,
//! like the reduced body itself (the floating frame carries the large motion).

#![allow(non_snake_case)]

use crate::error::ReductionError;
use crate::reduced_body::{BeamStressElement, DenseMatrix, StressShapes};
use faer::MatRef;
use fe_model::stress::{averaged_nodal_stresses, beam_section_forces};
use fe_model::{Element, FeModel};
use rayon::prelude::*;

/// The stress shapes of the basis `S_full` ($6 n_{nodes} \times n$, every node's six slots):
/// solid stresses at the nodes ([`fe_model::stress::averaged_nodal_stresses`]) and beam section
/// forces at both ends of every beam ([`fe_model::stress::beam_section_forces`]).
///
/// # Errors
/// [`ReductionError::Fe`] for an element whose geometry or properties cannot give stresses.
pub fn stress_shapes(model: &FeModel, S_full: MatRef<'_, f64>) -> Result<StressShapes, ReductionError> {
    let n = S_full.ncols();
    let basis = DenseMatrix::from_faer(S_full);
    let has_solids = model.elements.iter().any(|e| e.solid().is_some());
    let (nodal, solid_node) = if has_solids {
        let (sigma, count) = averaged_nodal_stresses(model, &basis.data, n).map_err(ReductionError::from_fe)?;
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
    let beams: Vec<BeamStressElement> = model
        .elements
        .iter()
        .enumerate()
        .filter_map(|(e, element)| match element {
            Element::Beam2(b) => Some((e, b)),
            _ => None,
        })
        .map(|(e, b)| {
            let section = model.sections.get(b.section.0 as usize).cloned().ok_or_else(|| {
                ReductionError::Fe(format!("element {e}: beam section {} does not exist", b.section.0))
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
                let s = beam_section_forces(model, b.element as usize, &u_e, None).map_err(ReductionError::from_fe)?;
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
