//! Symbolic phase of assembly: the sparsity pattern of
//! $\mathbf K = \mathbf T^T \mathbf K_{full} \mathbf T$ and, for each element, where each of
//! its entries goes. Computed once per model; a numeric fill ([`crate::assemble_into`]) only
//! writes values.

use crate::dof::DofMap;
use crate::element::Element;
use crate::model::FeModel;
use faer::sparse::SymbolicSparseColMat;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// How an element's local dofs map to the free dofs it reaches.
#[derive(Clone, Debug)]
pub(crate) enum ElementTransform {
    /// Each local dof is one free dof with coefficient 1, or eliminated (entry `None`):
    /// the reduced matrix is a selection of rows and columns.
    Select(Vec<Option<u32>>),
    /// Some local dof is a combination of free dofs (a spider): $\mathbf T_e$, local x reduced.
    Dense(DMatrix<f64>),
}

/// Where one element's reduced matrix goes.
#[derive(Clone, Debug)]
pub(crate) struct ElementMap {
    /// Free dofs the element reaches, sorted and unique.
    pub dofs: Vec<u32>,
    pub transform: ElementTransform,
    /// Where the element's `dofs.len()`$^2$ slots start in [`SystemPattern`]'s `slots`.
    pub slot_start: usize,
}

/// Sparsity of the assembled matrices (both triangles stored) and the element-to-slot maps.
#[derive(Clone, Debug)]
pub struct SystemPattern {
    pub(crate) symbolic: SymbolicSparseColMat<usize>,
    pub(crate) elements: Vec<ElementMap>,
    /// The slots of all elements, element by element: `slots[slot_start + r + c * nd]` is the
    /// position in the values of entry `(dofs[r], dofs[c])` of an element with `nd` dofs. One
    /// array rather than one per element, so that dropping the pattern gives its memory
    /// back to the system (a large allocation is mapped on its own; a million small ones
    /// stay with the allocator, 1.8 GB of a 1M-dof tet10 body's pattern).
    pub(crate) slots: Vec<usize>,
}

/// The full slots (`6 node + k`) of an element's local dofs, node by node.
pub(crate) fn element_slots(element: &Element) -> Vec<usize> {
    let node_dofs = element.node_dofs();
    element
        .nodes()
        .iter()
        .flat_map(|n| node_dofs.iter().map(move |&k| 6 * n.index() + k))
        .collect()
}

fn element_map(element: &Element, dofs: &DofMap) -> ElementMap {
    let slots = element_slots(element);
    let mut reached: Vec<u32> = slots.iter().flat_map(|&s| dofs.row(s).0.iter().copied()).collect();
    reached.sort_unstable();
    reached.dedup();
    let position = |d: u32| reached.binary_search(&d).expect("reached dof") as u32;
    let simple = slots.iter().all(|&s| {
        let (d, c) = dofs.row(s);
        d.is_empty() || (d.len() == 1 && c[0] == 1.0)
    });
    let transform = if simple {
        ElementTransform::Select(
            slots
                .iter()
                .map(|&s| dofs.row(s).0.first().map(|&d| position(d)))
                .collect(),
        )
    } else {
        let mut T_e = DMatrix::zeros(slots.len(), reached.len());
        for (a, &s) in slots.iter().enumerate() {
            let (d, c) = dofs.row(s);
            for (&dof, &coef) in d.iter().zip(c) {
                T_e[(a, position(dof) as usize)] += coef;
            }
        }
        ElementTransform::Dense(T_e)
    };
    ElementMap {
        dofs: reached,
        transform,
        slot_start: 0,
    }
}

/// The CSC structure (`col_ptr`, sorted `row_idx`) of the union of the elements' dense blocks
/// `dofs x dofs`, by a counting sort: every element writes its dofs as rows into each of its
/// dofs' columns (repeats included), then each column is sorted and deduplicated on its own.
/// At 200k dofs this is about 38M entries: a global sort of (column, row) keys took 1.5-3 s
/// of the reduction, twice (the model and the mass data's bare model); columns of at most a
/// few hundred entries sort in cache.
fn column_structure(n: usize, sets: &[&[u32]]) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; n + 1];
    for dofs in sets {
        for &c in dofs.iter() {
            start[c as usize + 1] += dofs.len();
        }
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    // The rows written in parallel by column ranges, each range taking the sets in order
    // (so each column's list is the same as a sequential pass would write).
    let mut rows = vec![0u32; start[n]];
    let spans: Vec<(u32, u32)> = sets
        .par_iter()
        .map(|dofs| dofs.iter().fold((u32::MAX, 0), |(lo, hi), &d| (lo.min(d), hi.max(d))))
        .collect();
    let bounds = balanced_ranges(&start, COLUMN_RANGES);
    let mut parts: Vec<(usize, usize, &mut [u32])> = Vec::with_capacity(bounds.len());
    let mut rest = rows.as_mut_slice();
    for w in bounds.windows(2) {
        let (part, tail) = rest.split_at_mut(start[w[1]] - start[w[0]]);
        parts.push((w[0], w[1], part));
        rest = tail;
    }
    parts.par_iter_mut().for_each(|(c0, c1, part)| {
        let offset = start[*c0];
        let mut fill = start[*c0..*c1].to_vec();
        for (dofs, &(lo, hi)) in sets.iter().zip(&spans) {
            if (hi as usize) < *c0 || lo as usize >= *c1 {
                continue;
            }
            for &c in dofs.iter() {
                if (*c0..*c1).contains(&(c as usize)) {
                    let f = &mut fill[c as usize - *c0];
                    part[*f - offset..*f - offset + dofs.len()].copy_from_slice(dofs);
                    *f += dofs.len();
                }
            }
        }
    });
    // One mutable slice per column, sorted and deduplicated in place in parallel.
    let mut columns: Vec<&mut [u32]> = Vec::with_capacity(n);
    let mut rest = rows.as_mut_slice();
    for j in 0..n {
        let (column, tail) = rest.split_at_mut(start[j + 1] - start[j]);
        columns.push(column);
        rest = tail;
    }
    let unique: Vec<usize> = columns
        .par_iter_mut()
        .map(|column| {
            column.sort_unstable();
            let mut k = 0;
            for i in 0..column.len() {
                if i == 0 || column[i] != column[k - 1] {
                    column[k] = column[i];
                    k += 1;
                }
            }
            k
        })
        .collect();
    let mut col_ptr = vec![0usize; n + 1];
    for j in 0..n {
        col_ptr[j + 1] = col_ptr[j] + unique[j];
    }
    // The row indices, column by column in parallel.
    let mut row_idx = vec![0usize; col_ptr[n]];
    let mut targets: Vec<&mut [usize]> = Vec::with_capacity(n);
    let mut rest = row_idx.as_mut_slice();
    for &k in &unique {
        let (target, tail) = rest.split_at_mut(k);
        targets.push(target);
        rest = tail;
    }
    targets
        .par_iter_mut()
        .zip(columns.par_iter())
        .for_each(|(target, column)| {
            for (t, &r) in target.iter_mut().zip(column.iter()) {
                *t = r as usize;
            }
        });
    (col_ptr, row_idx)
}

/// Column ranges of the parallel fills by columns ([`column_structure`], the assembly's
/// scatter): fixed (no result depends on them), several per thread so that a busy core does
/// not hold the others back.
pub(crate) const COLUMN_RANGES: usize = 32;

/// Bounds $0 = c_0 < c_1 < \dots < c_k = n$ of at most `ranges` column ranges with about
/// equal numbers of entries, for the column pointers `col_ptr` ($n + 1$ of them).
pub(crate) fn balanced_ranges(col_ptr: &[usize], ranges: usize) -> Vec<usize> {
    let n = col_ptr.len() - 1;
    let nnz = col_ptr[n];
    let ranges = ranges.clamp(1, n.max(1));
    let mut bounds = vec![0usize];
    for k in 1..ranges {
        let target = nnz * k / ranges;
        let c = col_ptr.partition_point(|&p| p < target).min(n);
        if c > *bounds.last().expect("starts with 0") {
            bounds.push(c);
        }
    }
    if n > 0 && *bounds.last().expect("starts with 0") < n {
        bounds.push(n);
    }
    bounds
}

/// The CSC structure (rows sorted) of the union of the dense blocks $\text{set}\times\text{set}$
/// of `sets` on `n` unknowns, with the whole diagonal when `diagonal`: the symbolic phase of
/// any assembly whose elements couple all their unknowns (this crate's elements, the
/// multibody system's bodies and joints).
///
/// # Panics
/// When an unknown of a set is not below `n`, or `n` exceeds `u32::MAX`.
pub fn block_structure(n: usize, sets: &[Vec<usize>], diagonal: bool) -> SymbolicSparseColMat<usize> {
    assert!(u32::try_from(n).is_ok(), "block_structure: {n} unknowns exceed u32");
    let mut lists: Vec<Vec<u32>> = sets.iter().map(|s| s.iter().map(|&d| d as u32).collect()).collect();
    if diagonal {
        lists.extend((0..n as u32).map(|d| vec![d]));
    }
    let slices: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
    let (col_ptr, row_idx) = column_structure(n, &slices);
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

impl SystemPattern {
    /// Builds the pattern of `model` under the elimination `dofs`.
    pub fn new(model: &FeModel, dofs: &DofMap) -> Self {
        let n = dofs.n_free();
        let mut elements: Vec<ElementMap> = model.elements.par_iter().map(|e| element_map(e, dofs)).collect();
        let sets: Vec<&[u32]> = elements.iter().map(|m| m.dofs.as_slice()).collect();
        let (col_ptr, row_idx) = column_structure(n, &sets);
        let mut total = 0;
        for m in &mut elements {
            m.slot_start = total;
            total += m.dofs.len() * m.dofs.len();
        }
        let mut slots = vec![0usize; total];
        let mut pieces: Vec<&mut [usize]> = Vec::with_capacity(elements.len());
        let mut rest = slots.as_mut_slice();
        for m in &elements {
            let (piece, tail) = rest.split_at_mut(m.dofs.len() * m.dofs.len());
            pieces.push(piece);
            rest = tail;
        }
        elements.par_iter().zip(pieces.par_iter_mut()).for_each(|(m, piece)| {
            // The element's dofs and each column's rows are both sorted: one merge per column.
            let mut k = 0;
            for &c in &m.dofs {
                let mut p = col_ptr[c as usize];
                for &r in &m.dofs {
                    while row_idx[p] < r as usize {
                        p += 1;
                    }
                    debug_assert_eq!(row_idx[p], r as usize, "entry in pattern");
                    piece[k] = p;
                    k += 1;
                }
            }
        });
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Self {
            symbolic,
            elements,
            slots,
        }
    }

    /// Element `e`'s map and its slots ([`SystemPattern::slots`]).
    pub(crate) fn element(&self, e: usize) -> (&ElementMap, &[usize]) {
        let map = &self.elements[e];
        let nd = map.dofs.len();
        (map, &self.slots[map.slot_start..map.slot_start + nd * nd])
    }

    /// Number of rows (and columns): the free dofs.
    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries (both triangles).
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// The symbolic structure, shared by K and M.
    pub fn symbolic(&self) -> &SymbolicSparseColMat<usize> {
        &self.symbolic
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// The counting sort against the set of (column, row) pairs the elements touch, with
    /// overlapping elements, repeated pairs, empty columns and an element without dofs.
    #[test]
    fn column_structure_is_the_union_of_the_element_blocks() {
        let n = 50;
        let mut elements: Vec<ElementMap> = (0..40u32)
            .map(|e| {
                let mut dofs: Vec<u32> = (0..1 + e % 7).map(|k| (e * 7 + k * 11) % 45).collect();
                dofs.sort_unstable();
                dofs.dedup();
                ElementMap {
                    dofs,
                    transform: ElementTransform::Select(Vec::new()),
                    slot_start: 0,
                }
            })
            .collect();
        elements.push(ElementMap {
            dofs: Vec::new(),
            transform: ElementTransform::Select(Vec::new()),
            slot_start: 0,
        });
        let expected: BTreeSet<(usize, usize)> = elements
            .iter()
            .flat_map(|m| {
                m.dofs
                    .iter()
                    .flat_map(|&c| m.dofs.iter().map(move |&r| (c as usize, r as usize)))
            })
            .collect();
        let sets: Vec<&[u32]> = elements.iter().map(|m| m.dofs.as_slice()).collect();
        let (col_ptr, row_idx) = column_structure(n, &sets);
        assert_eq!(col_ptr.len(), n + 1);
        let got: Vec<(usize, usize)> = (0..n)
            .flat_map(|c| row_idx[col_ptr[c]..col_ptr[c + 1]].iter().map(move |&r| (c, r)))
            .collect();
        // Sorted within each column and free of repeats: equal to the ordered set.
        assert_eq!(got, expected.into_iter().collect::<Vec<_>>());
        assert!((45..n).all(|c| col_ptr[c] == col_ptr[c + 1]), "columns 45.. are empty");
    }
}
