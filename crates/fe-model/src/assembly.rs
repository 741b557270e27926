//! Numeric phase of assembly: element matrices computed in parallel (rayon) and
//! added into the values of the pattern's sparse matrices.

use crate::element::LocalMatrices;
use crate::error::{ElementError, FeError};
use crate::model::FeModel;
use crate::pattern::{ElementMap, ElementTransform, SystemPattern};
use faer::sparse::SparseColMat;
use nalgebra::{DMatrix, Point3};
use rayon::prelude::*;

/// Assembled stiffness and mass on the free dofs, both triangles stored.
#[derive(Clone, Debug)]
pub struct Assembled {
    pub K: SparseColMat<usize, f64>,
    pub M: SparseColMat<usize, f64>,
}

/// Reference coordinates of element `index`'s nodes (a missing node is an element error).
pub(crate) fn element_coordinates(model: &FeModel, index: usize) -> Result<Vec<Point3<f64>>, ElementError> {
    model.elements[index]
        .nodes()
        .iter()
        .map(|node| {
            model
                .mesh
                .nodes
                .get(node.index())
                .copied()
                .ok_or(ElementError::MissingNode {
                    element: index,
                    node: node.0,
                    count: model.mesh.nodes.len(),
                })
        })
        .collect()
}

/// Stiffness and mass of element `index` in global axes.
pub fn element_matrices(model: &FeModel, index: usize) -> Result<LocalMatrices, ElementError> {
    let X_e = element_coordinates(model, index)?;
    model.elements[index].local_matrices(index, &X_e, &model.properties())
}

/// Mass matrix of element `index` in global axes ([`crate::Element::mass_matrix`]).
pub fn element_mass(model: &FeModel, index: usize) -> Result<DMatrix<f64>, ElementError> {
    let X_e = element_coordinates(model, index)?;
    model.elements[index].mass_matrix(index, &X_e, &model.properties())
}

/// $\mathbf T_e^T \mathbf A \mathbf T_e$ added at the element's slots (also the geometric
/// stiffness's assembly, `geometric.rs`).
pub(crate) fn scatter((map, slots): (&ElementMap, &[usize]), A: &DMatrix<f64>, values: &mut [f64]) {
    let nd = map.dofs.len();
    match &map.transform {
        ElementTransform::Select(position) => {
            for (b, pb) in position.iter().enumerate() {
                let Some(c) = pb else { continue };
                for (a, pa) in position.iter().enumerate() {
                    let Some(r) = pa else { continue };
                    values[slots[*r as usize + *c as usize * nd]] += A[(a, b)];
                }
            }
        }
        ElementTransform::Dense(T_e) => {
            let reduced = T_e.transpose() * A * T_e;
            for c in 0..nd {
                for r in 0..nd {
                    values[slots[r + c * nd]] += reduced[(r, c)];
                }
            }
        }
    }
}

/// Fills `K_values` and `M_values` (laid out as `pattern`) from the elements of `model`.
///
/// Work is split into one contiguous range of elements per rayon thread; each range adds
/// into its own buffer and the buffers are summed, so the result does not depend on timing
/// beyond the order of that final sum.
pub fn assemble_into(
    model: &FeModel,
    pattern: &SystemPattern,
    K_values: &mut [f64],
    M_values: &mut [f64],
) -> Result<(), FeError> {
    fill_values(model, pattern, [K_values, M_values], |e| {
        let LocalMatrices { K_e, M_e } = element_matrices(model, e)?;
        Ok([K_e, M_e])
    })
}

/// The parallel element loop of [`assemble_into`]: `matrices(e)` gives element `e`'s
/// matrices, each added into the output of the same index.
fn fill_values<const N: usize>(
    model: &FeModel,
    pattern: &SystemPattern,
    outputs: [&mut [f64]; N],
    matrices: impl Fn(usize) -> Result<[DMatrix<f64>; N], ElementError> + Sync,
) -> Result<(), FeError> {
    let nnz = pattern.nnz();
    for out in &outputs {
        assert_eq!(out.len(), nnz, "assembled values must have the pattern's length");
    }
    assert_eq!(
        pattern.elements.len(),
        model.elements.len(),
        "pattern built for another model"
    );
    let n_elements = model.elements.len();
    let n_chunks = rayon::current_num_threads().clamp(1, n_elements.max(1));
    let chunk = n_elements.div_ceil(n_chunks).max(1);
    let fill = |range: std::ops::Range<usize>, outs: &mut [&mut [f64]]| -> Result<(), FeError> {
        for e in range {
            for (out, A) in outs.iter_mut().zip(matrices(e)?) {
                scatter(pattern.element(e), &A, out);
            }
        }
        Ok(())
    };
    let mut outputs = outputs;
    for out in outputs.iter_mut() {
        out.fill(0.0);
    }
    let others: Vec<Result<Vec<Vec<f64>>, FeError>> = (1..n_chunks)
        .into_par_iter()
        .map(|t| {
            let mut bufs: Vec<Vec<f64>> = (0..N).map(|_| vec![0.0; nnz]).collect();
            let mut outs: Vec<&mut [f64]> = bufs.iter_mut().map(|b| b.as_mut_slice()).collect();
            fill(t * chunk..((t + 1) * chunk).min(n_elements), &mut outs)?;
            Ok(bufs)
        })
        .collect();
    fill(0..chunk.min(n_elements), &mut outputs)?;
    for other in others {
        for (out, buf) in outputs.iter_mut().zip(other?) {
            out.par_iter_mut().zip(buf.par_iter()).for_each(|(a, b)| *a += b);
        }
    }
    Ok(())
}

/// Assembles $\mathbf K$ and $\mathbf M$ on the free dofs (allocating form of
/// [`assemble_into`]).
pub fn assemble(model: &FeModel, pattern: &SystemPattern) -> Result<Assembled, FeError> {
    let mut K = vec![0.0; pattern.nnz()];
    let mut M = vec![0.0; pattern.nnz()];
    assemble_into(model, pattern, &mut K, &mut M)?;
    Ok(Assembled {
        K: SparseColMat::new(pattern.symbolic.clone(), K),
        M: SparseColMat::new(pattern.symbolic.clone(), M),
    })
}

/// Assembles $\mathbf M$ alone on the free dofs: [`assemble`] without computing the element
/// stiffnesses ([`element_mass`]) and without the scatter and the per-thread buffers of
/// $\mathbf K$ (the mass data of a reduced body need only $\mathbf M$).
pub fn assemble_mass(model: &FeModel, pattern: &SystemPattern) -> Result<SparseColMat<usize, f64>, FeError> {
    let mut M = vec![0.0; pattern.nnz()];
    fill_values(model, pattern, [&mut M], |e| Ok([element_mass(model, e)?]))?;
    Ok(SparseColMat::new(pattern.symbolic.clone(), M))
}
