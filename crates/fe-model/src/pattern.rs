//! Symbolic phase of assembly (style R9): the sparsity pattern of
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
    /// `slots[r + c * dofs.len()]` is the position in the values of entry `(dofs[r], dofs[c])`.
    pub slots: Vec<usize>,
}

/// Sparsity of the assembled matrices (both triangles stored) and the element-to-slot maps.
#[derive(Clone, Debug)]
pub struct SystemPattern {
    pub(crate) symbolic: SymbolicSparseColMat<usize>,
    pub(crate) elements: Vec<ElementMap>,
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
        slots: Vec::new(),
    }
}

impl SystemPattern {
    /// Builds the pattern of `model` under the elimination `dofs`.
    pub fn new(model: &FeModel, dofs: &DofMap) -> Self {
        let n = dofs.n_free();
        let mut elements: Vec<ElementMap> = model.elements.par_iter().map(|e| element_map(e, dofs)).collect();
        // Every (row, col) pair an element touches, as one u64 key = col * n + row, so a
        // parallel sort gives the CSC structure directly.
        let mut keys: Vec<u64> = elements
            .par_iter()
            .flat_map_iter(|m| {
                let d = &m.dofs;
                d.iter()
                    .flat_map(move |&c| d.iter().map(move |&r| c as u64 * n as u64 + r as u64))
            })
            .collect();
        keys.par_sort_unstable();
        keys.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::with_capacity(keys.len());
        for &key in &keys {
            col_ptr[(key / n as u64) as usize + 1] += 1;
            row_idx.push((key % n as u64) as usize);
        }
        drop(keys);
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        elements.par_iter_mut().for_each(|m| {
            let nd = m.dofs.len();
            let mut slots = Vec::with_capacity(nd * nd);
            for &c in &m.dofs {
                let (a, b) = (col_ptr[c as usize], col_ptr[c as usize + 1]);
                let column = &row_idx[a..b];
                for &r in &m.dofs {
                    slots.push(a + column.binary_search(&(r as usize)).expect("entry in pattern"));
                }
            }
            m.slots = slots;
        });
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Self { symbolic, elements }
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
