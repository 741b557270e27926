//! 6-dof interface nodes on solids, tied to a set of surface nodes by a spider (theory guide §2):
//! RBE2 (the surface follows the interface node rigidly) or RBE3 (the interface node follows
//! the weighted mean motion of the surface and adds no stiffness). Both are sets of
//! [`LinearConstraint`]s, eliminated by [`crate::DofMap`], never penalised.
//!
//! The interface node's six dofs stay **independent** in both kinds: they are the boundary
//! dofs of the Craig-Bampton reduction. No element touches the interface node; its dofs are
//! active because the constraints refer to them.
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\mathbf x_m$, $\mathbf u_m$, $\boldsymbol\theta_m$ | `x_m`, dofs 0..3, 3..6 of the interface node | interface node: position, translation, rotation |
//! | $\mathbf x_s$, $\mathbf u_s$ | `x_s`, dofs 0..3 of a surface node | surface node $s$ |
//! | $\mathbf r_s$ | `r` | $\mathbf x_s - \mathbf x_m$ |
//! | $w_s$ | `weights\[s\]` | RBE3 weight of surface node $s$ |
//! | $\mathbf S_s$ | `S_s` | $[\mathbf I,\ -\tilde{\mathbf r}_s]$ ($3 \times 6$): rigid motion of the interface seen at $s$ |
//! | $\mathbf G$ | `G` | RBE3 map $[\mathbf u_m; \boldsymbol\theta_m] = \mathbf G \mathbf u_{surface}$ ($6 \times 3n$) |
//!
//! # Weights and the default position
//!
//! When the surface nodes cover whole faces of the model's solid elements (a face whose nodes
//! all lie in the set counts, if it is a boundary face: one that a single element has), the
//! interface node defaults to the area centroid
//! $\int \mathbf x\, dA / A$ of those faces, and the RBE3 weights are tributary areas: each
//! face's area shared among its nodes in proportion to the diagonal of the face mass matrix
//! $\int N_i^2 dA$ (HRZ lumping, as for [`crate::element::solid::scalar_mass`]). The consistent
//! $\int N_i\, dA$ would be zero (tri6) or negative (quad8) at the corners of quadratic faces.
//! A face that two elements share lies inside the solid and does not count (a set that takes
//! in a layer of nodes below the surface, as a `near`/`radius` selection does, would
//! otherwise weigh that layer as surface too). A set node on none of the counted faces (inside
//! the solid, or at the fringe of a patch that covers its faces in part) keeps weight zero:
//! the spider follows the surface the whole faces make. A set with no boundary face at all (a
//! section wholly inside the solid) counts its faces once each. Without any whole face the
//! position is the node mean and the weights are equal.

#![allow(non_snake_case)]

use crate::error::FeError;
use crate::mesh::NodeId;
use crate::model::{FeModel, LinearConstraint};
use crate::quadrature;
use nalgebra::{DMatrix, Matrix3, Matrix6, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// How the interface node is tied to its surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SpiderKind {
    /// Rigid spider: every surface node's translation is
    /// $\mathbf u_s = \mathbf u_m + \boldsymbol\theta_m \times \mathbf r_s$ (dependent: the
    /// surface translations). Stiffens the surface.
    Rbe2,
    /// Interpolation spider: the interface node moves with the weighted least-squares rigid fit
    /// of the surface motion; adds no stiffness (dependent: six surface dofs, see
    /// [`add_interface`]).
    Rbe3,
}

/// One interface: its name, its 6-dof node, the spider kind and the surface nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interface {
    pub name: String,
    pub node: NodeId,
    pub kind: SpiderKind,
    pub surface: Vec<NodeId>,
}

/// An interface to add with [`Interfaces::add`]: the arguments of [`add_interface`].
#[derive(Clone, Copy, Debug)]
pub struct InterfaceSpec<'a> {
    pub name: &'a str,
    /// The surface nodes (repeats are ignored).
    pub surface: &'a [NodeId],
    /// Where the interface node goes; `None`: the surface centroid.
    pub at: Option<Point3<f64>>,
    pub kind: SpiderKind,
}

/// The distinct nodes of `nodes`, sorted.
fn surface_set(nodes: &[NodeId]) -> Vec<NodeId> {
    let mut surface = nodes.to_vec();
    surface.sort_unstable();
    surface.dedup();
    surface
}

/// The interfaces of a model, in the order they were added.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Interfaces(pub Vec<Interface>);

impl Interfaces {
    /// [`add_interface`] for `spec`, and records the interface. Names must be unique.
    pub fn add(&mut self, model: &mut FeModel, spec: InterfaceSpec<'_>) -> Result<NodeId, FeError> {
        let InterfaceSpec {
            name,
            surface,
            at,
            kind,
        } = spec;
        if self.get(name).is_some() {
            return Err(interface_error(name, "an interface of that name already exists".into()));
        }
        let node = add_interface(model, name, surface, at, kind)?;
        self.0.push(Interface {
            name: name.to_string(),
            node,
            kind,
            surface: surface_set(surface),
        });
        Ok(node)
    }

    /// The interface called `name`.
    pub fn get(&self, name: &str) -> Option<&Interface> {
        self.0.iter().find(|i| i.name == name)
    }

    /// The interface nodes, in order.
    pub fn nodes(&self) -> Vec<NodeId> {
        self.0.iter().map(|i| i.node).collect()
    }
}

fn interface_error(name: &str, why: String) -> FeError {
    FeError::Interface {
        name: name.to_string(),
        why,
    }
}

/// [`add_interface`] on the nodes of a named node set (a gmsh physical surface, or a face set
/// of [`crate::box_mesh::box_mesh`] such as `"x1"`).
pub fn add_interface_on_set(
    model: &mut FeModel,
    name: &str,
    set: &str,
    at: Option<Point3<f64>>,
    kind: SpiderKind,
) -> Result<NodeId, FeError> {
    let nodes = model.node_set(set, &format!("interface '{name}'"))?.to_vec();
    add_interface(model, name, &nodes, at, kind)
}

/// Adds a 6-dof interface node at `at` (default: the area centroid of the surface, see the
/// module docs) and the spider constraints tying it to `surface_nodes`. Returns the new node.
///
/// **RBE2**: for every surface node, three constraints
/// $\mathbf u_s = \mathbf u_m + \boldsymbol\theta_m \times \mathbf r_s$, the surface
/// translations dependent.
///
/// **RBE3** (MSC Nastran's RBE3 with the "UM" option, *Quick Reference Guide*, RBE3 entry):
/// the interface motion is the weighted least-squares rigid fit of the surface motion,
/// $\min \sum_s w_s |\mathbf u_s - \mathbf S_s [\mathbf u_m; \boldsymbol\theta_m]|^2$, i.e.
/// $[\mathbf u_m; \boldsymbol\theta_m] = \mathbf G \mathbf u_{surface}$ with
/// $\mathbf G = (\sum_s w_s \mathbf S_s^T \mathbf S_s)^{-1} [w_1 \mathbf S_1^T, \dots, w_n \mathbf S_n^T]$.
/// These six equations are solved for six surface dofs $\mathbf u_d$ (the dependent ones)
/// instead of for the interface dofs, so the interface dofs stay independent:
/// $\mathbf u_d = \mathbf G_d^{-1}([\mathbf u_m; \boldsymbol\theta_m] - \mathbf G_r \mathbf u_r)$.
///
/// # Derivation
/// Not in the AIC-FFR papers. The constraint set $\{[\mathbf u_m; \boldsymbol\theta_m] = \mathbf G
/// \mathbf u_{surface}\}$ is the same whichever six unknowns it is solved for, so the spider
/// still adds no stiffness: a free body with RBE3 interfaces keeps its frequencies (checked by
/// `unit::interface::rbe3_adds_no_stiffness`). The dependent dofs are the columns of $\mathbf G$
/// (with its rotation rows scaled by the RMS radius $\ell$ of the surface, so that all six rows
/// are lengths) picked by column-pivoted Gram-Schmidt (QR with column pivoting, Golub & Van
/// Loan, *Matrix Computations*, 4th ed., §5.4.2): the best-conditioned $\mathbf G_d$ the greedy
/// choice finds. Surface dofs that are supported or already dependent are not candidates.
/// A load $\mathbf f_m$ on the interface node reaches the surface as
/// $\mathbf G^T \mathbf f_m$: uniform for a force on a flat, evenly weighted face.
///
/// # Errors
/// [`FeError::Interface`] naming the interface if the surface is empty, if its nodes
/// coincide or are collinear (the message says which rotation it cannot carry), if an RBE2
/// surface dof is supported or already dependent on another constraint, or if an RBE3 finds no
/// six free surface dofs to make dependent. [`FeError::UnknownNode`] for a surface node the
/// model does not have. Spiders on adjacent faces (sharing nodes) are fine: shared dofs are
/// substituted so that no constraint refers to a dependent dof; two RBE2 spiders, though,
/// cannot share a node.
pub fn add_interface(
    model: &mut FeModel,
    name: &str,
    surface_nodes: &[NodeId],
    at: Option<Point3<f64>>,
    kind: SpiderKind,
) -> Result<NodeId, FeError> {
    let context = format!("interface '{name}'");
    let surface = surface_set(surface_nodes);
    if surface.is_empty() {
        return Err(interface_error(name, "the surface node set is empty".into()));
    }
    for &s in &surface {
        model.check_node(s, &context)?;
    }
    let (centroid, weights) = surface_centroid_and_weights(model, &surface);
    let X: Vec<Point3<f64>> = surface.iter().map(|s| model.mesh.nodes[s.index()]).collect();
    check_carries_six_motions(name, &X, &weights)?;

    // Dofs that cannot be dependent: supported, or dependent on another constraint (by dof
    // slot 6 node + k, so that a spider on every node of a large model stays linear in its size).
    let dofs = DofSlots::new(model);
    let supported = |s: NodeId, k: usize| dofs.supported(s, k);
    let dependent = |s: NodeId, k: usize| dofs.definition(&model.constraints, s, k).is_some();
    for &s in &surface {
        for k in 0..3 {
            let refusal = if kind != SpiderKind::Rbe2 {
                None
            } else if dependent(s, k) {
                Some("is already dependent on another constraint; an RBE2 spider cannot define it again")
            } else if supported(s, k) {
                Some("is supported; an RBE2 spider would make it dependent (support the interface node instead)")
            } else {
                None
            };
            if let Some(why) = refusal {
                return Err(interface_error(
                    name,
                    format!(
                        "surface node {} dof {} {why}",
                        model.mesh.node_tags[s.index()],
                        crate::error::DOF_NAMES[k]
                    ),
                ));
            }
        }
    }

    let x_m = at.unwrap_or(centroid);
    // The node the interface will get; added only once nothing can fail.
    let m = NodeId(model.node_count() as u32);
    let constraints = match kind {
        SpiderKind::Rbe2 => rbe2_constraints(name, m, &x_m, &surface, &X),
        SpiderKind::Rbe3 => {
            let candidate = |s: NodeId, k: usize| !supported(s, k) && !dependent(s, k);
            let definition = |s: NodeId, k: u8| dofs.definition(&model.constraints, s, k as usize);
            rbe3_constraints(name, m, &x_m, &surface, &X, &weights, definition, candidate)?
        }
    };
    // Tagged above the file's numbers: an RBE3 or constraint message naming it by tag must
    // not point at a deck node of the same number.
    let added = model.mesh.add_node_after_tags(x_m);
    debug_assert_eq!(added, m);
    substitute(&mut model.constraints, &constraints);
    model.constraints.extend(constraints);
    Ok(m)
}

/// The supported dofs and the constraint defining each dependent dof of a model, by dof slot
/// $6\,node + k$: one pass over the supports and constraints, then constant-time look-ups.
struct DofSlots {
    supported: Vec<bool>,
    /// Index of the (last) constraint whose dependent dof is the slot, `u32::MAX` for none.
    defined_by: Vec<u32>,
}

impl DofSlots {
    fn new(model: &FeModel) -> Self {
        let slots = 6 * model.node_count();
        let mut supported = vec![false; slots];
        for s in model.supports.iter().filter(|s| s.node.index() < model.node_count()) {
            for k in (0..6).filter(|&k| s.dofs.0[k]) {
                supported[6 * s.node.index() + k] = true;
            }
        }
        let mut defined_by = vec![u32::MAX; slots];
        for (i, c) in model.constraints.iter().enumerate() {
            let slot = 6 * c.dependent.0.index() + c.dependent.1 as usize;
            if let Some(d) = defined_by.get_mut(slot) {
                *d = i as u32;
            }
        }
        Self { supported, defined_by }
    }

    fn supported(&self, node: NodeId, k: usize) -> bool {
        self.supported.get(6 * node.index() + k).copied().unwrap_or(false)
    }

    /// The terms of the constraint that defines dof `k` of `node`, if one does.
    fn definition<'c>(&self, constraints: &'c [LinearConstraint], node: NodeId, k: usize) -> Option<&'c Definition> {
        let i = *self.defined_by.get(6 * node.index() + k)?;
        constraints.get(i as usize).map(|c| &c.terms)
    }
}

/// Keeps every constraint's right-hand side independent when spiders share surface nodes
/// (adjacent faces share their edge): a dof that a `new` constraint defines is replaced by its
/// definition wherever an `existing` constraint uses it. The `new` rows refer to independent
/// dofs only (RBE2: the interface node; RBE3: see [`rbe3_constraints`]), so no chain remains
/// for [`crate::DofMap`] to refuse, and the constrained motions are unchanged.
fn substitute(existing: &mut [LinearConstraint], new: &[LinearConstraint]) {
    let fresh: BTreeMap<(NodeId, u8), &Definition> = new.iter().map(|c| (c.dependent, &c.terms)).collect();
    for c in existing.iter_mut() {
        if !c.terms.iter().any(|t| fresh.contains_key(&(t.0, t.1))) {
            continue;
        }
        // Sum coefficients per dof, in first-seen order, so that the rows stay short.
        let mut order: Vec<(NodeId, u8)> = Vec::new();
        let mut sum: BTreeMap<(NodeId, u8), f64> = BTreeMap::new();
        let mut add = |key: (NodeId, u8), v: f64| {
            if !sum.contains_key(&key) {
                order.push(key);
            }
            *sum.entry(key).or_insert(0.0) += v;
        };
        for &(node, k, v) in &c.terms {
            match fresh.get(&(node, k)) {
                Some(def) => def.iter().for_each(|&(n2, k2, v2)| add((n2, k2), v * v2)),
                None => add((node, k), v),
            }
        }
        c.terms = order
            .into_iter()
            .map(|key| (key.0, key.1, sum[&key]))
            .filter(|t| t.2 != 0.0)
            .collect();
    }
}

/// RBE2 rows: $u_{s,i} = u_{m,i} + (\boldsymbol\theta_m \times \mathbf r_s)_i$.
fn rbe2_constraints(
    name: &str,
    m: NodeId,
    x_m: &Point3<f64>,
    surface: &[NodeId],
    X: &[Point3<f64>],
) -> Vec<LinearConstraint> {
    let mut out = Vec::with_capacity(3 * surface.len());
    for (&s, x_s) in surface.iter().zip(X) {
        let r = x_s - x_m;
        // theta x r = (ty rz - tz ry, tz rx - tx rz, tx ry - ty rx).
        let rows: [[(u8, f64); 2]; 3] = [[(4, r.z), (5, -r.y)], [(5, r.x), (3, -r.z)], [(3, r.y), (4, -r.x)]];
        for (i, row) in rows.iter().enumerate() {
            let mut terms = vec![(m, i as u8, 1.0)];
            terms.extend(row.iter().filter(|(_, c)| *c != 0.0).map(|&(k, c)| (m, k, c)));
            out.push(LinearConstraint {
                name: name.to_string(),
                dependent: (s, i as u8),
                terms,
            });
        }
    }
    out
}

/// $\mathbf S_s = [\mathbf I, -\tilde{\mathbf r}_s]$: $\mathbf u_m + \boldsymbol\theta_m \times
/// \mathbf r_s = \mathbf S_s [\mathbf u_m; \boldsymbol\theta_m]$ (the translation rows of
/// [`crate::rigid::rigid_motion_block`]).
fn rigid_map(r: &Vector3<f64>) -> nalgebra::SMatrix<f64, 3, 6> {
    crate::rigid::rigid_motion_block(r).fixed_rows::<3>(0).into_owned()
}

/// A linear definition of a dependent dof: its terms $(node, dof, c)$.
type Definition = Vec<(NodeId, u8, f64)>;

/// RBE3 rows by the "UM" elimination (see [`add_interface`]). `definition` gives the terms of
/// the existing constraint that defines a dof, if any: a surface dof that one of them defines
/// is replaced by its definition before the dependent dofs are chosen, so the new rows refer to
/// independent dofs only. Linear in the number of surface nodes and their definitions' terms.
#[allow(clippy::too_many_arguments)]
fn rbe3_constraints<'d>(
    name: &str,
    m: NodeId,
    x_m: &Point3<f64>,
    surface: &[NodeId],
    X: &[Point3<f64>],
    weights: &[f64],
    definition: impl Fn(NodeId, u8) -> Option<&'d Definition>,
    candidate: impl Fn(NodeId, usize) -> bool,
) -> Result<Vec<LinearConstraint>, FeError> {
    let mut A = Matrix6::zeros();
    for (x_s, &w) in X.iter().zip(weights) {
        let S = rigid_map(&(x_s - x_m));
        A += w * S.transpose() * S;
    }
    let A_inv = A
        .try_inverse()
        .ok_or_else(|| interface_error(name, "the RBE3 normal matrix is singular".into()))?;
    // Columns of G over independent dofs: [u_m; theta_m] = G u_cols, in first-seen order;
    // `column_of` maps a dof slot (6 node + k) to its column.
    let mut columns: Vec<(NodeId, u8)> = Vec::new();
    let mut column_of: Vec<u32> = Vec::new();
    let mut g_columns: Vec<nalgebra::Vector6<f64>> = Vec::new();
    let mut add = |key: (NodeId, u8), g: nalgebra::Vector6<f64>| {
        let slot = 6 * key.0.index() + key.1 as usize;
        if slot >= column_of.len() {
            column_of.resize(slot + 1, u32::MAX);
        }
        if column_of[slot] == u32::MAX {
            column_of[slot] = columns.len() as u32;
            columns.push(key);
            g_columns.push(nalgebra::Vector6::zeros());
        }
        g_columns[column_of[slot] as usize] += g;
    };
    for ((&s, x_s), &w) in surface.iter().zip(X).zip(weights) {
        let G_s = w * A_inv * rigid_map(&(x_s - x_m)).transpose();
        for k in 0..3u8 {
            let g = G_s.column(k as usize).into_owned();
            match definition(s, k) {
                Some(def) => def.iter().for_each(|&(n2, k2, c)| add((n2, k2), c * g)),
                None => add((s, k), g),
            }
        }
    }
    let nc = columns.len();
    let G = DMatrix::from_iterator(6, nc, g_columns.iter().flat_map(|g| g.iter().copied()));
    drop(g_columns);
    // Choose six columns by column-pivoted Gram-Schmidt on G with the rotation rows scaled to
    // lengths (they act on translations / length otherwise, and pivoting would be unit-biased).
    // Candidates: this surface's own translations that are free.
    let w_sum: f64 = weights.iter().sum();
    let ell = (X
        .iter()
        .zip(weights)
        .map(|(x, w)| w * (x - x_m).norm_squared())
        .sum::<f64>()
        / w_sum)
        .sqrt()
        .max(f64::MIN_POSITIVE);
    // `surface` is sorted: membership by binary search, once per column.
    let is_candidate: Vec<bool> = columns
        .iter()
        .map(|&(node, k)| k < 3 && surface.binary_search(&node).is_ok() && candidate(node, k as usize))
        .collect();
    let mut Q = G.clone();
    for r in 3..6 {
        Q.row_mut(r).scale_mut(ell);
    }
    let mut chosen: Vec<usize> = Vec::with_capacity(6);
    let initial = (0..nc).map(|c| Q.column(c).norm()).fold(0.0, f64::max);
    for _ in 0..6 {
        let best = (0..nc)
            .filter(|&c| !chosen.contains(&c) && is_candidate[c])
            .map(|c| (c, Q.column(c).norm()))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        // 1e-10: far above the round-off left in a column after orthogonalisation against
        // the others (~1e-16 relative), far below any pivot of a usable surface.
        let Some((c, norm)) = best.filter(|&(_, norm)| norm > 1e-10 * initial) else {
            return Err(interface_error(
                name,
                "no six free surface dofs can carry the interface motion (too many surface dofs are supported or already dependent)".into(),
            ));
        };
        let q = Q.column(c) / norm;
        for j in 0..nc {
            let p = q.dot(&Q.column(j));
            Q.column_mut(j).axpy(-p, &q, 1.0);
        }
        chosen.push(c);
    }
    let mut G_d = Matrix6::zeros();
    for (i, &c) in chosen.iter().enumerate() {
        G_d.set_column(i, &G.fixed_view::<6, 1>(0, c));
    }
    let G_d_inv = G_d
        .try_inverse()
        .ok_or_else(|| interface_error(name, "the chosen RBE3 dependent dofs are singular".into()))?;
    // u_d = G_d^{-1} [u_m; theta_m] - G_d^{-1} G_r u_r.
    let H = G_d_inv * &G;
    let mut out = Vec::with_capacity(6);
    for (i, &c) in chosen.iter().enumerate() {
        let mut terms = Vec::with_capacity(nc);
        for k in 0..6 {
            if G_d_inv[(i, k)] != 0.0 {
                terms.push((m, k as u8, G_d_inv[(i, k)]));
            }
        }
        for j in (0..nc).filter(|j| !chosen.contains(j)) {
            if H[(i, j)] != 0.0 {
                terms.push((columns[j].0, columns[j].1, -H[(i, j)]));
            }
        }
        out.push(LinearConstraint {
            name: name.to_string(),
            dependent: columns[c],
            terms,
        });
    }
    Ok(out)
}

/// Checks that the surface points carry all six rigid motions: not all coincident, not
/// collinear. With the weighted centroid $\mathbf c$ and $\mathbf r_s = \mathbf x_s - \mathbf c$,
/// the "inertia" $\mathbf J = \sum_s w_s (|\mathbf r_s|^2 \mathbf I - \mathbf r_s \mathbf r_s^T)$
/// is singular exactly when the points lie on a line (null vector: the line's direction, the
/// axis the spider cannot turn about) or coincide ($\mathbf J = 0$).
fn check_carries_six_motions(name: &str, X: &[Point3<f64>], weights: &[f64]) -> Result<(), FeError> {
    let w_sum: f64 = weights.iter().sum();
    let c = X
        .iter()
        .zip(weights)
        .fold(Vector3::zeros(), |acc, (x, w)| acc + *w * x.coords)
        / w_sum;
    let mut J = Matrix3::zeros();
    let mut size: f64 = 0.0;
    for (x, &w) in X.iter().zip(weights) {
        let r = x.coords - c;
        J += w * (r.norm_squared() * Matrix3::identity() - r * r.transpose());
        size = size.max(x.coords.norm());
    }
    let eig = nalgebra::SymmetricEigen::new(J);
    let (i_min, lambda_min) = eig.eigenvalues.argmin();
    let lambda_max = eig.eigenvalues.max();
    // Coincident: J vanishes to round-off of the coordinates (|x| ~ size).
    if lambda_max <= 1e-20 * w_sum * size * size || X.len() == 1 {
        return Err(interface_error(
            name,
            format!(
                "its {} surface node(s) coincide: it cannot carry rotations about any axis (it needs at least 3 non-collinear nodes)",
                X.len()
            ),
        ));
    }
    // Collinear: relative 1e-8 means an offset from the line below 1e-4 of the set's extent.
    if lambda_min <= 1e-8 * lambda_max {
        let axis = eig.eigenvectors.column(i_min).into_owned();
        return Err(interface_error(
            name,
            format!(
                "its {} surface nodes are collinear: it cannot carry a rotation about {} (it needs at least 3 non-collinear nodes)",
                X.len(),
                axis_name(&axis)
            ),
        ));
    }
    Ok(())
}

/// "the x axis" for a global axis, else the direction's components.
fn axis_name(d: &Vector3<f64>) -> String {
    for (k, label) in ["x", "y", "z"].iter().enumerate() {
        if d[k].abs() >= 1.0 - 1e-9 {
            return format!("the {label} axis");
        }
    }
    format!("the axis [{:.4}, {:.4}, {:.4}]", d.x, d.y, d.z)
}

/// Area centroid and tributary-area weights of the surface (module docs), or the node mean
/// and equal weights when the surface does not cover whole element faces.
fn surface_centroid_and_weights(model: &FeModel, surface: &[NodeId]) -> (Point3<f64>, Vec<f64>) {
    let mean = surface
        .iter()
        .fold(Vector3::zeros(), |acc, s| acc + model.mesh.nodes[s.index()].coords)
        / surface.len() as f64;
    let equal = (Point3::from(mean), vec![1.0; surface.len()]);
    // Position of each node in `surface` (`u32::MAX`: not in it), by node index.
    let mut position = vec![u32::MAX; model.node_count()];
    for (i, s) in surface.iter().enumerate() {
        if let Some(p) = position.get_mut(s.index()) {
            *p = i as u32;
        }
    }
    let in_surface = |n: NodeId| position.get(n.index()).is_some_and(|&p| p != u32::MAX);
    // Faces of solid elements whose nodes all lie in the surface: sorted by their sorted
    // nodes, a face shared by two elements (an interior face) is adjacent to its twin.
    // Linear in the number of faces but for the sort, so that a spider on every node of a
    // model of millions of cells stays cheap.
    let mut found: Vec<FaceRef> = Vec::new();
    for (e, element) in model.elements.iter().enumerate() {
        let Some((kind, solid)) = element.solid() else { continue };
        for (f, face) in kind.faces().iter().enumerate() {
            if face.len() <= MAX_FACE_NODES && face.iter().all(|&a| in_surface(solid.nodes[a])) {
                let mut key = [u32::MAX; MAX_FACE_NODES];
                for (k, &a) in key.iter_mut().zip(face.iter()) {
                    *k = solid.nodes[a].0;
                }
                key[..face.len()].sort_unstable();
                found.push(FaceRef {
                    key,
                    len: face.len() as u8,
                    element: e as u32,
                    face: f as u8,
                });
            }
        }
    }
    found.sort_unstable_by(|a, b| a.key().cmp(b.key()).then(a.element.cmp(&b.element)));
    let (boundary, interior) = split_shared_faces(found);
    // Set nodes on none of these faces (inside the solid, or on a face the set covers in
    // part) keep weight zero.
    let found = if boundary.is_empty() { interior } else { boundary };
    if found.is_empty() {
        return equal;
    }
    let mut weights = vec![0.0; surface.len()];
    let mut area = 0.0;
    let mut moment = Vector3::zeros();
    let mut nodes: Vec<NodeId> = Vec::with_capacity(MAX_FACE_NODES);
    let mut X: Vec<Point3<f64>> = Vec::with_capacity(MAX_FACE_NODES);
    for f in &found {
        // The face's nodes in the order of the element it was first met in.
        let Some((kind, solid)) = model.elements[f.element as usize].solid() else {
            continue;
        };
        nodes.clear();
        nodes.extend(kind.faces()[f.face as usize].iter().map(|&a| solid.nodes[a]));
        X.clear();
        X.extend(nodes.iter().map(|n| model.mesh.nodes[n.index()]));
        let (a, first, diag) = face_integrals(&X);
        area += a;
        moment += first;
        let d_sum: f64 = diag.iter().sum();
        for (n, d) in nodes.iter().zip(diag) {
            weights[position[n.index()] as usize] += a * d / d_sum;
        }
    }
    if weights.iter().any(|&w| !(w >= 0.0 && w.is_finite())) || !(area > 0.0) {
        return equal;
    }
    (Point3::from(moment / area), weights)
}

/// `sorted` (faces sorted by key) split into the faces only one element has (boundary faces,
/// which carry the surface's area) and those two elements share (interior faces, once each,
/// as met first), which lie inside the solid and count only for a section that has no
/// boundary face at all.
fn split_shared_faces(sorted: Vec<FaceRef>) -> (Vec<FaceRef>, Vec<FaceRef>) {
    let mut boundary = Vec::with_capacity(sorted.len());
    let mut interior = Vec::new();
    let mut faces = sorted.into_iter().peekable();
    while let Some(first) = faces.next() {
        let mut shared = false;
        while faces.next_if(|twin| twin.key() == first.key()).is_some() {
            shared = true;
        }
        if shared {
            interior.push(first);
        } else {
            boundary.push(first);
        }
    }
    (boundary, interior)
}

/// The most nodes a solid face has (quad8).
const MAX_FACE_NODES: usize = 8;

/// A face of a solid element found on a surface: its nodes sorted (padded with `u32::MAX`),
/// the element and the face's index among the element kind's faces.
struct FaceRef {
    key: [u32; MAX_FACE_NODES],
    len: u8,
    element: u32,
    face: u8,
}

impl FaceRef {
    fn key(&self) -> &[u32] {
        &self.key[..self.len as usize]
    }
}

/// Area $A$, first moment $\int \mathbf x\, dA$, and the face mass diagonal $\int N_i^2 dA$ of
/// one face (tri3, quad4, tri6 or quad8, by node count; orderings of
/// [`crate::element::SolidKind::faces`]).
fn face_integrals(X: &[Point3<f64>]) -> (f64, Vector3<f64>, Vec<f64>) {
    let n = X.len();
    // Built once: a spider on every node of a large model integrates millions of faces.
    static TRIANGLE: OnceLock<quadrature::Rule<2>> = OnceLock::new();
    static QUADRILATERAL: OnceLock<quadrature::Rule<2>> = OnceLock::new();
    let rule: &quadrature::Rule<2> = match n {
        // Degree 5 / 3x3 Gauss: exact for N_i^2 on flat faces (degree 4), ample for the rest.
        3 | 6 => TRIANGLE.get_or_init(|| quadrature::triangle(5)),
        _ => QUADRILATERAL.get_or_init(|| quadrature::quadrilateral(3)),
    };
    let mut area = 0.0;
    let mut first = Vector3::zeros();
    let mut diag = vec![0.0; n];
    let mut N = vec![0.0; n];
    let mut dN = vec![[0.0; 2]; n];
    for (p, w) in rule.points.iter().zip(&rule.weights) {
        face_shape(n, p, &mut N, &mut dN);
        let mut x = Vector3::zeros();
        let mut xs = Vector3::zeros();
        let mut xt = Vector3::zeros();
        for i in 0..n {
            x += N[i] * X[i].coords;
            xs += dN[i][0] * X[i].coords;
            xt += dN[i][1] * X[i].coords;
        }
        let dA = w * xs.cross(&xt).norm();
        area += dA;
        first += dA * x;
        for i in 0..n {
            diag[i] += dA * N[i] * N[i];
        }
    }
    (area, first, diag)
}

/// Shape functions of the face kinds: tri3/tri6 on the reference triangle, quad4/quad8 on
/// $[-1, 1]^2$ (corners anticlockwise, then edge nodes of edges (0,1), (1,2), ...).
fn face_shape(n: usize, p: &[f64; 2], N: &mut [f64], dN: &mut [[f64; 2]]) {
    let (s, t) = (p[0], p[1]);
    match n {
        3 | 6 => {
            let L = [1.0 - s - t, s, t];
            let dL = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
            if n == 3 {
                N[..3].copy_from_slice(&L);
                dN[..3].copy_from_slice(&dL);
            } else {
                for i in 0..3 {
                    N[i] = L[i] * (2.0 * L[i] - 1.0);
                    dN[i] = [(4.0 * L[i] - 1.0) * dL[i][0], (4.0 * L[i] - 1.0) * dL[i][1]];
                }
                for (e, (a, b)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
                    N[3 + e] = 4.0 * L[a] * L[b];
                    dN[3 + e] = [
                        4.0 * (L[b] * dL[a][0] + L[a] * dL[b][0]),
                        4.0 * (L[b] * dL[a][1] + L[a] * dL[b][1]),
                    ];
                }
            }
        }
        _ => {
            let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
            for (i, c) in corners.iter().enumerate() {
                let (a, b) = (1.0 + c[0] * s, 1.0 + c[1] * t);
                if n == 4 {
                    N[i] = 0.25 * a * b;
                    dN[i] = [0.25 * c[0] * b, 0.25 * a * c[1]];
                } else {
                    let q = c[0] * s + c[1] * t - 1.0;
                    N[i] = 0.25 * a * b * q;
                    dN[i] = [0.25 * c[0] * b * (q + a), 0.25 * c[1] * a * (q + b)];
                }
            }
            if n == 8 {
                // Edge nodes 4: (0,-1), 5: (1,0), 6: (0,1), 7: (-1,0).
                for (i, c) in [[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]].iter().enumerate() {
                    if c[0] == 0.0 {
                        let b = 1.0 + c[1] * t;
                        N[4 + i] = 0.5 * (1.0 - s * s) * b;
                        dN[4 + i] = [-s * b, 0.5 * (1.0 - s * s) * c[1]];
                    } else {
                        let a = 1.0 + c[0] * s;
                        N[4 + i] = 0.5 * a * (1.0 - t * t);
                        dN[4 + i] = [0.5 * c[0] * (1.0 - t * t), -t * a];
                    }
                }
            }
        }
    }
}
