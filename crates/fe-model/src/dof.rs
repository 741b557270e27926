//! Dof numbering: which of each node's six dofs are unknowns, and how the others follow.
//!
//! Every node has six dof slots $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$ (the *full*
//! dofs, index `6 * node + k`). A slot is
//! - **inactive** when no element and no constraint uses it (the rotations of a node that only
//!   solids touch): it is not an unknown and its value is zero;
//! - **supported** when a [`Support`](crate::Support) holds it: eliminated, value zero;
//! - **dependent** when a [`LinearConstraint`](crate::LinearConstraint) defines it from other
//!   dofs: eliminated, value $\sum_i c_i u_i$;
//! - **free** otherwise: an unknown, numbered [`Dof`] in node order.
//!
//! The map is the matrix $\mathbf T$ with $\mathbf u_{full} = \mathbf T \mathbf u_f$, stored by
//! rows (one short row per full dof). Assembly forms $\mathbf T^T \mathbf K_{full} \mathbf T$
//! element by element, so supports and spiders are applied by elimination, never by
//! penalties (theory guide §2).

use crate::error::{FeError, DOF_NAMES};
use crate::mesh::NodeId;
use crate::model::FeModel;
use serde::{Deserialize, Serialize};

/// Index of an independent (free) dof, `0..DofMap::n_free()`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Dof(pub u32);

impl Dof {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What became of one full dof slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DofStatus {
    Inactive,
    Supported,
    Dependent,
    Free(Dof),
}

/// The elimination map $\mathbf u_{full} = \mathbf T \mathbf u_f$ of a model.
///
/// Invariant: each row refers only to free dofs; rows of free dofs are the unit row of their
/// own [`Dof`]; rows of inactive and supported dofs are empty.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DofMap {
    node_tags: Vec<u64>,
    status: Vec<DofStatus>,
    row_ptr: Vec<usize>,
    row_dof: Vec<u32>,
    row_coef: Vec<f64>,
    free_to_full: Vec<u32>,
}

impl DofMap {
    /// Numbers the dofs of `model`: checks that supports and constraints name existing nodes
    /// and that no dependent dof is defined twice, supported, or used on the right-hand side
    /// of another constraint.
    pub fn new(model: &FeModel) -> Result<Self, FeError> {
        let n_nodes = model.node_count();
        let n_full = 6 * n_nodes;
        let mut active = vec![false; n_full];
        for (e, element) in model.elements.iter().enumerate() {
            for &node in element.nodes() {
                // The context is formatted only for an error: once per node of every element
                // would dominate the numbering of a large model.
                if node.index() >= n_nodes {
                    model.check_node(node, &format!("element {e} ({})", element.kind_name()))?;
                }
                for &k in element.node_dofs() {
                    active[6 * node.index() + k] = true;
                }
            }
        }
        for c in &model.constraints {
            let context = || format!("constraint '{}'", c.name);
            if c.dependent.0.index() >= n_nodes {
                model.check_node(c.dependent.0, &context())?;
            }
            // A dof index of 6 or more is reported below, with its constraint.
            if c.dependent.1 < 6 {
                active[6 * c.dependent.0.index() + c.dependent.1 as usize] = true;
            }
            for &(node, k, _) in &c.terms {
                if node.index() >= n_nodes {
                    model.check_node(node, &context())?;
                }
                if k < 6 {
                    active[6 * node.index() + k as usize] = true;
                }
            }
        }
        let mut status: Vec<DofStatus> = active
            .iter()
            .map(|&a| {
                if a {
                    DofStatus::Free(Dof(0))
                } else {
                    DofStatus::Inactive
                }
            })
            .collect();
        for s in &model.supports {
            model.check_node(s.node, "support")?;
            for k in 0..6 {
                // A support on an inactive slot (a solid node's rotation) holds nothing: ignore it.
                if s.dofs.0[k] && active[6 * s.node.index() + k] {
                    status[6 * s.node.index() + k] = DofStatus::Supported;
                }
            }
        }
        let tag = |node: NodeId| {
            model
                .mesh
                .node_tags
                .get(node.index())
                .copied()
                .unwrap_or(node.0 as u64 + 1)
        };
        let constraint_error = |name: &str, node: NodeId, k: usize, why: &str| FeError::Constraint {
            name: name.to_string(),
            node_tag: tag(node),
            dof: DOF_NAMES[k],
            why: why.to_string(),
        };
        let mut defined_by: Vec<Option<usize>> = vec![None; n_full];
        for (ci, c) in model.constraints.iter().enumerate() {
            let (node, k) = (c.dependent.0, c.dependent.1 as usize);
            if k >= 6 {
                return Err(constraint_error(
                    &c.name,
                    node,
                    0,
                    &format!("has dof index {k}, which is not in 0..6"),
                ));
            }
            let slot = 6 * node.index() + k;
            match status[slot] {
                DofStatus::Supported => {
                    return Err(constraint_error(&c.name, node, k, "is both supported and dependent"));
                }
                DofStatus::Dependent => {
                    let other = &model.constraints[defined_by[slot].unwrap_or(ci)].name;
                    return Err(constraint_error(
                        &c.name,
                        node,
                        k,
                        &format!("is already defined by constraint '{other}'"),
                    ));
                }
                _ => {}
            }
            status[slot] = DofStatus::Dependent;
            defined_by[slot] = Some(ci);
        }
        for c in &model.constraints {
            for &(node, k, _) in &c.terms {
                if k >= 6 {
                    return Err(constraint_error(
                        &c.name,
                        node,
                        0,
                        &format!("has dof index {k}, which is not in 0..6"),
                    ));
                }
                if status[6 * node.index() + k as usize] == DofStatus::Dependent {
                    return Err(constraint_error(
                        &c.name,
                        node,
                        k as usize,
                        "is used on the right-hand side but is itself dependent (chained constraints are not supported)",
                    ));
                }
            }
        }
        let mut free_to_full = Vec::new();
        for (slot, st) in status.iter_mut().enumerate() {
            if let DofStatus::Free(d) = st {
                *d = Dof(free_to_full.len() as u32);
                free_to_full.push(slot as u32);
            }
        }
        let mut row_ptr = Vec::with_capacity(n_full + 1);
        let mut row_dof = Vec::with_capacity(free_to_full.len());
        let mut row_coef = Vec::with_capacity(free_to_full.len());
        row_ptr.push(0);
        for slot in 0..n_full {
            match status[slot] {
                DofStatus::Free(d) => {
                    row_dof.push(d.0);
                    row_coef.push(1.0);
                }
                DofStatus::Dependent => {
                    let c = &model.constraints[defined_by[slot].expect("dependent slot has a constraint")];
                    for &(node, k, coef) in &c.terms {
                        // Supported dofs are zero: their terms vanish.
                        if let DofStatus::Free(d) = status[6 * node.index() + k as usize] {
                            row_dof.push(d.0);
                            row_coef.push(coef);
                        }
                    }
                }
                DofStatus::Inactive | DofStatus::Supported => {}
            }
            row_ptr.push(row_dof.len());
        }
        Ok(Self {
            node_tags: model.mesh.node_tags.clone(),
            status,
            row_ptr,
            row_dof,
            row_coef,
            free_to_full,
        })
    }

    /// Number of independent dofs.
    pub fn n_free(&self) -> usize {
        self.free_to_full.len()
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.status.len() / 6
    }

    /// Status of dof `k` (0..6) of `node`.
    pub fn status(&self, node: NodeId, k: usize) -> DofStatus {
        self.status[6 * node.index() + k]
    }

    /// The free dof at `(node, k)`, if that slot is free.
    pub fn free_dof(&self, node: NodeId, k: usize) -> Option<Dof> {
        match self.status(node, k) {
            DofStatus::Free(d) => Some(d),
            _ => None,
        }
    }

    /// Row of $\mathbf T$ for full dof `slot = 6 node + k`: free dofs and coefficients.
    pub fn row(&self, slot: usize) -> (&[u32], &[f64]) {
        let (a, b) = (self.row_ptr[slot], self.row_ptr[slot + 1]);
        (&self.row_dof[a..b], &self.row_coef[a..b])
    }

    /// The full slot (`6 node + k`) of a free dof.
    pub fn full_slot(&self, dof: Dof) -> usize {
        self.free_to_full[dof.index()] as usize
    }

    /// `(node tag, dof name)` of a free dof, for messages.
    pub fn describe(&self, dof: Dof) -> (u64, &'static str) {
        let slot = self.full_slot(dof);
        let node = slot / 6;
        (
            self.node_tags.get(node).copied().unwrap_or(node as u64 + 1),
            DOF_NAMES[slot % 6],
        )
    }

    /// $\mathbf u_{full} = \mathbf T \mathbf u_f$, as one `[f64; 6]` per node.
    pub fn expand(&self, u_free: &[f64]) -> Vec<[f64; 6]> {
        assert_eq!(u_free.len(), self.n_free(), "expand: vector length must equal n_free");
        let mut out = vec![[0.0; 6]; self.n_nodes()];
        for (slot, value) in out.iter_mut().flat_map(|u| u.iter_mut()).enumerate() {
            let (dofs, coefs) = self.row(slot);
            *value = dofs.iter().zip(coefs).map(|(&d, &c)| c * u_free[d as usize]).sum();
        }
        out
    }

    /// $\mathbf T^T \mathbf f_{full}$: the free-dof load of a full-dof load. Loads on
    /// dependent dofs are carried to the dofs they depend on; loads on supported dofs go to
    /// the support. A load on an inactive dof is an error naming the node and dof.
    pub fn restrict(&self, f_full: &[[f64; 6]], context: &str) -> Result<Vec<f64>, FeError> {
        let mut f = vec![0.0; self.n_free()];
        for (node, values) in f_full.iter().enumerate() {
            for (k, &value) in values.iter().enumerate() {
                if value == 0.0 {
                    continue;
                }
                let slot = 6 * node + k;
                if self.status[slot] == DofStatus::Inactive {
                    return Err(FeError::InactiveDof {
                        context: context.to_string(),
                        node_tag: self.node_tags.get(node).copied().unwrap_or(node as u64 + 1),
                        dof: DOF_NAMES[k],
                    });
                }
                let (dofs, coefs) = self.row(slot);
                for (&d, &c) in dofs.iter().zip(coefs) {
                    f[d as usize] += c * value;
                }
            }
        }
        Ok(f)
    }
}
