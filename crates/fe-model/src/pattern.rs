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

/// The rows of a range of columns in [`column_structure`], one column after another, and
/// each column's (start, length) in them.
type RangeRows = (Vec<u32>, Vec<(usize, usize)>);

/// The CSC structure (`col_ptr`, sorted `row_idx`) of the union of the elements' dense blocks
/// `dofs x dofs`. Column $c$ holds the union of the sets that contain $c$: from the list of
/// those sets (a counting sort of the memberships, in set order), each column gathers their
/// dofs once (a marker per dof skips repeats) and sorts them; a column in the same sets as
/// the one before it (the dofs of one node, for elements that couple all their dofs) has the
/// same rows and takes them without a sort. At 200k dofs the elements' blocks hold about 38M
/// entries with repeats, 16.5M without: a global sort of (column, row) keys took 1.5-3 s of
/// the reduction, a sort of every column with its repeats 0.7 CPU-s.
fn column_structure(n: usize, sets: &[&[u32]]) -> (Vec<usize>, Vec<usize>) {
    // The sets containing each dof, in increasing set order.
    let mut member_start = vec![0usize; n + 1];
    for dofs in sets {
        for &c in dofs.iter() {
            member_start[c as usize + 1] += 1;
        }
    }
    for j in 0..n {
        member_start[j + 1] += member_start[j];
    }
    let mut members = vec![0u32; member_start[n]];
    let mut fill = member_start[..n].to_vec();
    for (s, dofs) in sets.iter().enumerate() {
        for &c in dofs.iter() {
            members[fill[c as usize]] = s as u32;
            fill[c as usize] += 1;
        }
    }
    drop(fill);
    let sets_of = |c: usize| &members[member_start[c]..member_start[c + 1]];
    // Column ranges of about equal numbers of memberships, each in parallel: the rows of its
    // columns one after another, a column in the same sets as the one before it in the range
    // pointing at that one's rows.
    let bounds = balanced_ranges(&member_start, COLUMN_RANGES);
    let ranges: Vec<RangeRows> = bounds
        .par_windows(2)
        .map_init(
            || vec![u32::MAX; n],
            |marker, w| {
                let mut rows: Vec<u32> = Vec::new();
                let mut columns: Vec<(usize, usize)> = Vec::with_capacity(w[1] - w[0]);
                for c in w[0]..w[1] {
                    if c > w[0] && sets_of(c) == sets_of(c - 1) {
                        let previous = *columns.last().expect("a column before");
                        columns.push(previous);
                        continue;
                    }
                    let first = rows.len();
                    for &s in sets_of(c) {
                        for &r in sets[s as usize] {
                            if marker[r as usize] != c as u32 {
                                marker[r as usize] = c as u32;
                                rows.push(r);
                            }
                        }
                    }
                    rows[first..].sort_unstable();
                    columns.push((first, rows.len() - first));
                }
                (rows, columns)
            },
        )
        .collect();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    for (_, columns) in &ranges {
        for &(_, len) in columns {
            col_ptr.push(col_ptr.last().expect("starts with 0") + len);
        }
    }
    // The row indices, range by range in parallel.
    let mut row_idx = vec![0usize; col_ptr[n]];
    let mut targets: Vec<&mut [usize]> = Vec::with_capacity(ranges.len());
    let mut rest = row_idx.as_mut_slice();
    for w in bounds.windows(2) {
        let (target, tail) = rest.split_at_mut(col_ptr[w[1]] - col_ptr[w[0]]);
        targets.push(target);
        rest = tail;
    }
    targets
        .par_iter_mut()
        .zip(ranges.par_iter())
        .for_each(|(target, (rows, columns))| {
            let mut k = 0;
            for &(first, len) in columns {
                for (t, &r) in target[k..k + len].iter_mut().zip(&rows[first..first + len]) {
                    *t = r as usize;
                }
                k += len;
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
/// of `sets` on `n` unknowns, and the whole diagonal (an unknown no set reaches keeps its
/// diagonal entry, so a factorisation sees every pivot): the symbolic phase of
/// any assembly whose elements couple all their unknowns (this crate's elements, the
/// multibody system's bodies and joints).
///
/// # Panics
/// When an unknown of a set is not below `n`, or `n` exceeds `u32::MAX`.
pub fn block_structure(n: usize, sets: &[Vec<usize>]) -> SymbolicSparseColMat<usize> {
    assert!(u32::try_from(n).is_ok(), "block_structure: {n} unknowns exceed u32");
    let mut lists: Vec<Vec<u32>> = sets.iter().map(|s| s.iter().map(|&d| d as u32).collect()).collect();
    lists.extend((0..n as u32).map(|d| vec![d]));
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

    /// The symbolic structure, the element maps and slots freed.
    pub fn into_symbolic(self) -> SymbolicSparseColMat<usize> {
        self.symbolic
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
        // Elements coupling whole "nodes" of three dofs: consecutive columns in the same sets,
        // which share their rows.
        for e in 0..6u32 {
            let first = 3 * (e % 4);
            elements.push(ElementMap {
                dofs: (first..first + 6 + 3 * (e % 2)).collect(),
                transform: ElementTransform::Select(Vec::new()),
                slot_start: 0,
            });
        }
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
