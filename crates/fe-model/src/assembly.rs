//! Numeric phase of assembly: element matrices computed in parallel (rayon) and added into
//! the values of the pattern's sparse matrices, in parallel by column ranges, every entry in
//! element order ([`assemble_into`]).

use crate::element::LocalMatrices;
use crate::error::{ElementError, FeError};
use crate::model::FeModel;
use crate::pattern::{balanced_ranges, ElementMap, ElementTransform, SystemPattern, COLUMN_RANGES};
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

/// Fills `K_values` and `M_values` (laid out as `pattern`) from the elements of `model`.
///
/// In parallel without copies of the matrices: the element matrices of a block of elements
/// are computed in parallel, then added by column ranges of the pattern in parallel, each
/// range taking the block's elements in order. Every entry is thus the sum of its element
/// contributions in element order, as in a sequential loop: the result is the same bit for
/// bit whatever the number of threads.
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

/// Elements whose matrices are computed before they are added: small enough that they are
/// still in cache when added (hex8: 24 x 24 entries, 4.6 KB for $\mathbf K_e$ and
/// $\mathbf M_e$ each, 2.4 MB a block; blocks of 4096 took 1.3 times the CPU time of 256 at
/// 200k dofs), large enough for both parallel phases (128-256 equally fast).
const ELEMENT_BLOCK: usize = 256;

/// The parallel element loop of [`assemble_into`]: `matrices(e)` gives element `e`'s
/// matrices, each added into the output of the same index (element order per entry, see
/// there). The first failing element in element order is the error.
pub(crate) fn fill_values<const N: usize>(
    model: &FeModel,
    pattern: &SystemPattern,
    outputs: [&mut [f64]; N],
    matrices: impl Fn(usize) -> Result<[DMatrix<f64>; N], ElementError> + Sync,
) -> Result<(), FeError> {
    fill_values_in_blocks(model, pattern, outputs, matrices, ELEMENT_BLOCK, COLUMN_RANGES)
}

/// [`fill_values`] with `block` elements per block and `ranges` column ranges (tests vary
/// them).
fn fill_values_in_blocks<const N: usize>(
    model: &FeModel,
    pattern: &SystemPattern,
    outputs: [&mut [f64]; N],
    matrices: impl Fn(usize) -> Result<[DMatrix<f64>; N], ElementError> + Sync,
    block: usize,
    ranges: usize,
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
    let col_ptr = pattern.symbolic.col_ptr();
    // Column ranges of about equal numbers of stored entries, each with its part of every
    // output (the values are column by column).
    let bounds = balanced_ranges(col_ptr, ranges);
    let mut parts: Vec<(usize, usize, [&mut [f64]; N])> = Vec::with_capacity(bounds.len());
    {
        let mut rests: [&mut [f64]; N] = outputs;
        for w in bounds.windows(2) {
            let len = col_ptr[w[1]] - col_ptr[w[0]];
            let pieces: [&mut [f64]; N] = std::array::from_fn(|i| {
                let (piece, tail) = std::mem::take(&mut rests[i]).split_at_mut(len);
                rests[i] = tail;
                piece
            });
            parts.push((w[0], w[1], pieces));
        }
    }
    parts.par_iter_mut().for_each(|(_, _, outs)| {
        for out in outs.iter_mut() {
            out.fill(0.0);
        }
    });
    let n_elements = model.elements.len();
    let block = block.max(1);
    for first in (0..n_elements).step_by(block) {
        let elements = first..(first + block).min(n_elements);
        // The element matrices in the free dofs they reach, T_e^T A T_e.
        let computed: Vec<Result<[DMatrix<f64>; N], ElementError>> = elements
            .clone()
            .into_par_iter()
            .map(|e| {
                let (map, _) = pattern.element(e);
                Ok(matrices(e)?.map(|A| match &map.transform {
                    ElementTransform::Select(_) => A,
                    ElementTransform::Dense(T_e) => T_e.transpose() * A * T_e,
                }))
            })
            .collect();
        let mut local = Vec::with_capacity(computed.len());
        for m in computed {
            local.push(m?);
        }
        parts.par_iter_mut().for_each(|(c0, c1, outs)| {
            let offset = col_ptr[*c0];
            for (e, A) in elements.clone().zip(&local) {
                let (map, slots) = pattern.element(e);
                let (Some(&first_dof), Some(&last_dof)) = (map.dofs.first(), map.dofs.last()) else {
                    continue;
                };
                if (last_dof as usize) < *c0 || first_dof as usize >= *c1 {
                    continue;
                }
                for (out, A) in outs.iter_mut().zip(A) {
                    scatter_columns((map, slots), A, out, *c0..*c1, offset);
                }
            }
        });
    }
    Ok(())
}

/// The columns `columns` of element `map`'s reduced matrix $\mathbf T_e^T\mathbf A
/// \mathbf T_e$ added at its slots, into `values` holding the pattern's values from position
/// `offset` on, the entries of a column in a fixed order. `A` is the element matrix for a
/// selection and the reduced matrix for a dense transform.
fn scatter_columns(
    (map, slots): (&ElementMap, &[usize]),
    A: &DMatrix<f64>,
    values: &mut [f64],
    columns: std::ops::Range<usize>,
    offset: usize,
) {
    let nd = map.dofs.len();
    let inside = |c: usize| columns.contains(&(map.dofs[c] as usize));
    match &map.transform {
        ElementTransform::Select(position) => {
            for (b, pb) in position.iter().enumerate() {
                let Some(c) = pb else { continue };
                if !inside(*c as usize) {
                    continue;
                }
                for (a, pa) in position.iter().enumerate() {
                    let Some(r) = pa else { continue };
                    values[slots[*r as usize + *c as usize * nd] - offset] += A[(a, b)];
                }
            }
        }
        ElementTransform::Dense(_) => {
            for c in (0..nd).filter(|&c| inside(c)) {
                for r in 0..nd {
                    values[slots[r + c * nd] - offset] += A[(r, c)];
                }
            }
        }
    }
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

/// [`assemble`] taking the pattern, when it is not needed afterwards: its element slots are
/// freed before $\mathbf M$ copies its structure, and $\mathbf K$ takes the structure itself
/// (one copy of the row indices fewer: 16.5M of them at 200k dofs).
pub fn assemble_with_pattern(model: &FeModel, pattern: SystemPattern) -> Result<Assembled, FeError> {
    let mut K = vec![0.0; pattern.nnz()];
    let mut M = vec![0.0; pattern.nnz()];
    assemble_into(model, &pattern, &mut K, &mut M)?;
    let symbolic = pattern.into_symbolic();
    Ok(Assembled {
        M: SparseColMat::new(symbolic.clone(), M),
        K: SparseColMat::new(symbolic, K),
    })
}

/// Assembles $\mathbf M$ alone on the free dofs: [`assemble`] without computing the element
/// stiffnesses ([`element_mass`]) and without the scatter of $\mathbf K$ (the mass data of a
/// reduced body need only $\mathbf M$).
pub fn assemble_mass(model: &FeModel, pattern: &SystemPattern) -> Result<SparseColMat<usize, f64>, FeError> {
    let mut M = vec![0.0; pattern.nnz()];
    fill_values(model, pattern, [&mut M], |e| Ok([element_mass(model, e)?]))?;
    Ok(SparseColMat::new(pattern.symbolic.clone(), M))
}

/// [`assemble_mass`] taking the pattern, whose structure $\mathbf M$ keeps without a copy.
pub fn assemble_mass_with_pattern(
    model: &FeModel,
    pattern: SystemPattern,
) -> Result<SparseColMat<usize, f64>, FeError> {
    let mut M = vec![0.0; pattern.nnz()];
    fill_values(model, &pattern, [&mut M], |e| Ok([element_mass(model, e)?]))?;
    Ok(SparseColMat::new(pattern.into_symbolic(), M))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::straight_beam;
    use crate::{add_interface_on_set, box_mesh, solid_model, BeamProperties, BeamSection, BeamTheory};
    use crate::{CellKind, DofMap, DofMask, IsotropicMaterial, MassKind, NodeId, SpiderKind};
    use nalgebra::Vector3;

    fn steel() -> IsotropicMaterial {
        IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap()
    }

    /// Solid blocks with an RBE2 spider (the dense element transform) and a support, and a
    /// beam: every kind of element map.
    fn models() -> Vec<FeModel> {
        let mut models = Vec::new();
        for kind in [CellKind::Hex8, CellKind::Tet10] {
            let mesh = box_mesh(kind, [0.6, 0.2, 0.2], [6, 2, 2]).unwrap();
            let mut model = solid_model(mesh, steel(), MassKind::Consistent).unwrap();
            // A node at x = 0.6, away from the spider on the face x = 0.
            let far = (0..model.node_count())
                .max_by(|&a, &b| model.mesh.nodes[a].x.total_cmp(&model.mesh.nodes[b].x))
                .unwrap();
            add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
            model.add_support(NodeId(far as u32), DofMask::TRANSLATIONS);
            models.push(model);
        }
        let mut beam = FeModel::default();
        let material = beam.add_material(steel());
        let section = beam.add_section(BeamSection::circle("d20", 0.02, 0.3).unwrap());
        let props = BeamProperties {
            section,
            material,
            orientation: Vector3::new(0.2, 0.9, -0.3),
            theory: BeamTheory::Timoshenko,
            mass: MassKind::Consistent,
        };
        let nodes = straight_beam(
            &mut beam,
            Point3::origin(),
            Point3::new(1.0, 0.3, 0.2),
            12,
            &props,
            None,
        )
        .unwrap();
        beam.add_support(nodes[0], DofMask::ALL);
        models.push(beam);
        models
    }

    /// The sequential definition: element after element, $\mathbf T_e^T\mathbf A\mathbf T_e$
    /// added at the element's slots.
    fn sequential(model: &FeModel, pattern: &SystemPattern) -> [Vec<f64>; 2] {
        let mut out = [vec![0.0; pattern.nnz()], vec![0.0; pattern.nnz()]];
        for e in 0..model.elements.len() {
            let LocalMatrices { K_e, M_e } = element_matrices(model, e).unwrap();
            let (map, slots) = pattern.element(e);
            let nd = map.dofs.len();
            for (values, A) in out.iter_mut().zip([K_e, M_e]) {
                match &map.transform {
                    ElementTransform::Select(position) => {
                        for (b, pb) in position.iter().enumerate() {
                            for (a, pa) in position.iter().enumerate() {
                                if let (Some(r), Some(c)) = (pa, pb) {
                                    values[slots[*r as usize + *c as usize * nd]] += A[(a, b)];
                                }
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
        }
        out
    }

    /// The parallel assembly equals the sequential loop bit for bit on a hex8 and a tet10
    /// block with a spider and a support and on a beam, for several threads, element blocks
    /// and column ranges: each entry is summed in element order whatever the split.
    #[test]
    fn parallel_assembly_equals_the_sequential_loop_bit_for_bit() {
        for model in models() {
            let dofs = DofMap::new(&model).unwrap();
            let pattern = SystemPattern::new(&model, &dofs);
            let expected = sequential(&model, &pattern);
            assert!(pattern
                .elements
                .iter()
                .any(|m| matches!(m.transform, ElementTransform::Select(_))));
            for (threads, block, ranges) in [(1, ELEMENT_BLOCK, COLUMN_RANGES), (3, 5, 7), (4, 1, 1000), (2, 64, 2)] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let (mut K, mut M) = (vec![f64::NAN; pattern.nnz()], vec![f64::NAN; pattern.nnz()]);
                pool.install(|| {
                    fill_values_in_blocks(
                        &model,
                        &pattern,
                        [&mut K, &mut M],
                        |e| {
                            let LocalMatrices { K_e, M_e } = element_matrices(&model, e)?;
                            Ok([K_e, M_e])
                        },
                        block,
                        ranges,
                    )
                })
                .unwrap();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&K),
                    bits(&expected[0]),
                    "K, {threads} threads, blocks of {block}, {ranges} ranges"
                );
                assert_eq!(
                    bits(&M),
                    bits(&expected[1]),
                    "M, {threads} threads, blocks of {block}, {ranges} ranges"
                );
            }
        }
        // The solid models have the dense transform of their spider.
        let solid = &models()[0];
        let pattern = SystemPattern::new(solid, &DofMap::new(solid).unwrap());
        assert!(pattern
            .elements
            .iter()
            .any(|m| matches!(m.transform, ElementTransform::Dense(_))));
    }
}
