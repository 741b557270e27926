//! Craig-Bampton reduction of an FE model with interfaces (theory guide §3).
//!
//! The free dofs of the FE model are split into the boundary set $b$ (the six dofs of every
//! interface node, interface by interface) and the internal set $i$ (all others). The CB
//! basis is
//! $$\mathbf V = \begin{bmatrix}\mathbf I & \mathbf 0\\ \boldsymbol\Psi & \boldsymbol\Phi_i\end{bmatrix},
//! \qquad \boldsymbol\Psi = -\mathbf K_{ii}^{-1}\mathbf K_{ib},\qquad
//! \mathbf K_{ii}\boldsymbol\Phi_i = \mathbf M_{ii}\boldsymbol\Phi_i\boldsymbol\Omega^2,$$
//! with one sparse Cholesky factorisation of $\mathbf K_{ii}$ serving both the constraint
//! modes and the shift-invert eigensolver ([`ShiftInvert`]).
//! $\mathbf K_{CB} = \mathbf V^T\mathbf K\mathbf V$, $\mathbf M_{CB} = \mathbf V^T\mathbf M\mathbf V$.

use crate::attachment::static_correction;
use crate::eigen::{symmetric_times, EigenSettings, FactorPrecision, FactorSettings, Shift, ShiftInvert};
use crate::error::ReductionError;
use crate::geometric::reduced_geometric_stiffness;
use crate::invariants::{gather_rows, inertia_data, inertia_data_from_mass, select_entries};
use crate::reduced_body::{
    DenseMatrix, InertiaData, InterfacePoint, LoadPoint, MeshModes, ReducedBody, StressShapes, FORMAT_VERSION,
};
use crate::stress::stress_shapes;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Mat, MatRef};
use fe_model::{
    assemble_with_pattern, dof_points, DofMap, DofStatus, FeModel, FillOrdering, NodeId, SystemPattern, DOF_NAMES,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How many fixed-interface modes to keep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ModeSelection {
    /// Static (constraint) modes only: exact statics for interface loads.
    StaticOnly,
    /// The `m` lowest fixed-interface modes.
    Count(usize),
    /// Every fixed-interface mode below a frequency (Hz).
    CutoffHz(f64),
}

/// Settings of [`reduce`].
#[derive(Clone, Debug, PartialEq)]
pub struct CbSettings {
    pub modes: ModeSelection,
    /// Keep the CB basis on every mesh node (for output and stress recovery).
    pub keep_mesh_shapes: bool,
    /// An interface node placed at the centre of mass, added as the last interface and held
    /// fixed during the reduction (the `auxiliary-node` frame choice, theory guide §4).
    pub auxiliary_node: Option<NodeId>,
    /// Compute [`ReducedBody::geometric_stiffness`] (geometric stiffening: the stiffness the
    /// stress of each CB coordinate adds to every other), for bodies whose axial loads change
    /// their bending stiffness. Off by default.
    pub geometric_stiffening: bool,
    /// Compute [`ReducedBody::stress`], the stress of every CB vector (solid nodal stresses,
    /// beam section forces), for stress recovery. Off by default.
    pub stress_shapes: bool,
    /// Named load points (name, FE node) where loads act inside the body: each gets attachment
    /// modes (static correction, [`crate::attachment`]) appended to the modes, and a
    /// [`crate::LoadPoint`] in the body.
    pub load_points: Vec<(String, NodeId)>,
    /// Static correction for the interfaces' inertia: append to the modes the static
    /// response of the interior to the inertia of each constraint mode,
    /// $\mathbf K_{ii}^{-1}(\mathbf M_{ii}\boldsymbol\Psi + \mathbf M_{ib})$ ([`crate::attachment`],
    /// theory guide (3.10)), so that the quasi-static stress of the body's own inertia under
    /// any acceleration of its interfaces (the axial force along a connecting rod) is in the
    /// span whatever the number of modes. Up to $6N$ more coordinates; with geometric
    /// stiffening it makes the result converge monotonically in the modes. Off by default.
    pub inertia_correction: bool,
    /// The precision of the factor of $\mathbf K_{ii}$ ([`FactorPrecision`]): automatic
    /// (double precision when it fits in the available memory) by default.
    pub factor: FactorPrecision,
    /// Reduce a planar part: a beam model lying in one plane $z = z_0$ of its FE axes, whose
    /// out-of-plane dofs $u_z, \theta_x, \theta_y$ are supported on every node that is not an
    /// interface ([`planar_model`]), so that every fixed-interface mode (and every static
    /// correction vector) moves in the xy-plane. The interfaces keep their six dofs; by the
    /// plane's symmetry the in-plane and out-of-plane blocks of $\mathbf K_{CB}$, $\mathbf M_{CB}$
    /// do not couple, which the reduction checks ([`ReductionError::NotPlanar`]). For bodies
    /// evaluated in the plane (`superelement::Superelement::into_planar`). Off by default.
    pub planar: bool,
}

impl CbSettings {
    /// Settings keeping `modes`, the mesh shapes, and no auxiliary node.
    pub fn new(modes: ModeSelection) -> Self {
        Self {
            modes,
            keep_mesh_shapes: true,
            auxiliary_node: None,
            geometric_stiffening: false,
            stress_shapes: false,
            load_points: Vec::new(),
            inertia_correction: false,
            factor: FactorPrecision::Auto,
            planar: false,
        }
    }
}

/// The in-plane dofs $u_x, u_y, \theta_z$ of an interface, in the order of its six.
pub const IN_PLANE_DOFS: [usize; 3] = [0, 1, 5];
/// The out-of-plane dofs $u_z, \theta_x, \theta_y$ of a node.
pub const OUT_OF_PLANE_DOFS: [usize; 3] = [2, 3, 4];

/// The FE model of a planar part ([`CbSettings::planar`]): `model` with the out-of-plane dofs
/// $u_z, \theta_x, \theta_y$ supported on every node that is not in `interfaces` (dofs a
/// spider defines are left to it). `name` names the body in errors.
///
/// # Errors
/// [`ReductionError::NotPlanar`] when the model has an element that is not a beam (a solid
/// has no planar reduction here) or its nodes do not lie in one plane $z = z_0$ (to
/// $10^{-9}$ of the model's size), naming the element or node.
pub fn planar_model(model: &FeModel, name: &str, interfaces: &[NodeId]) -> Result<FeModel, ReductionError> {
    let not_planar = |what: String| ReductionError::NotPlanar {
        body: name.into(),
        what,
    };
    if let Some(e) = model
        .elements
        .iter()
        .position(|e| !matches!(e, fe_model::Element::Beam2(_)))
    {
        return Err(not_planar(format!(
            "element {} is not a beam: a planar reduction needs a beam model in its xy-plane",
            e + 1
        )));
    }
    let nodes = &model.mesh.nodes;
    let tag = |node: usize| model.mesh.node_tags.get(node).copied().unwrap_or(node as u64 + 1);
    if let Some(first) = nodes.first() {
        let size = nodes
            .iter()
            .map(|x| (x - first).norm())
            .fold(0.0f64, f64::max)
            .max(1e-300);
        if let Some(k) = nodes.iter().position(|x| !((x.z - first.z).abs() <= 1e-9 * size)) {
            return Err(not_planar(format!(
                "node {} is at z = {} but node {} at z = {}: a planar part lies in one plane z = const of its FE axes",
                tag(k),
                nodes[k].z,
                tag(0),
                first.z
            )));
        }
    }
    let dependent: std::collections::HashSet<(u32, usize)> = model
        .constraints
        .iter()
        .map(|c| (c.dependent.0 .0, c.dependent.1 as usize))
        .collect();
    let mut planar = model.clone();
    for node in 0..nodes.len() {
        let id = NodeId(node as u32);
        if interfaces.contains(&id) {
            continue;
        }
        let mut mask = [false; 6];
        for k in OUT_OF_PLANE_DOFS {
            mask[k] = !dependent.contains(&(node as u32, k));
        }
        planar.add_support(id, fe_model::DofMask(mask));
    }
    Ok(planar)
}

/// Checks that the in-plane dofs of the interfaces (and the modes) do not couple to the
/// out-of-plane ones in $\mathbf K_{CB}$ and $\mathbf M_{CB}$ (to $10^{-9}$ of the geometric
/// mean of the two diagonal entries): the check of a planar reduction.
fn check_planar(name: &str, interfaces: &[(String, usize)], K: &Mat<f64>, M: &Mat<f64>) -> Result<(), ReductionError> {
    let nb = 6 * interfaces.len();
    let out: Vec<usize> = (0..nb).filter(|r| OUT_OF_PLANE_DOFS.contains(&(r % 6))).collect();
    let inside: Vec<usize> = (0..K.ncols()).filter(|c| !out.contains(c)).collect();
    for (what, A) in [("K_CB", K), ("M_CB", M)] {
        for &r in &out {
            for &c in &inside {
                let scale = (A[(r, r)].abs() * A[(c, c)].abs()).sqrt();
                if !(A[(r, c)].abs() <= 1e-9 * scale) {
                    let coordinate = |i: usize| {
                        if i < nb {
                            format!("dof {} of interface '{}'", DOF_NAMES[i % 6], interfaces[i / 6].0)
                        } else {
                            format!("mode {}", i - nb + 1)
                        }
                    };
                    return Err(ReductionError::NotPlanar {
                        body: name.into(),
                        what: format!(
                            "{what} couples {} to {} ({:.3e} of their diagonal entries): the beams' sections are not symmetric about the plane (a principal axis along z)",
                            coordinate(r),
                            coordinate(c),
                            A[(r, c)].abs() / scale
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

/// A stage of [`reduce_with_progress`], reported as it starts (or, for
/// [`Stage::Factorised`] and [`Stage::EigenIteration`], as it progresses).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Stage {
    /// Assembling $\mathbf K$ and $\mathbf M$ on the free dofs.
    Assembling,
    /// Ordering and factoring $\mathbf K_{ii}$ ($n_i$ = `internal_dofs`).
    Factorising { internal_dofs: usize },
    /// $\mathbf K_{ii}$ factored: stored values of $\mathbf L$, the floating-point operations
    /// the factorisation took ($\sum_j c_j^2$) and the ordering used.
    Factorised {
        factor_len: usize,
        flops: f64,
        ordering: FillOrdering,
        /// The precision of the factor's values ([`CbSettings::factor`]).
        precision: fe_model::Precision,
    },
    /// The constraint modes $\boldsymbol\Psi$: `count` solves with the factor.
    ConstraintModes { count: usize },
    /// Lanczos: `converged` of the `wanted` fixed-interface modes meet the Krylov tolerance,
    /// after `applications` operator applications.
    EigenIteration {
        converged: usize,
        wanted: usize,
        applications: usize,
    },
    /// The solves are done: the constraint modes took `constraint_steps` solves with the factor
    /// (per column; more than 1 with a single-precision factor, whose solves are refined), the
    /// fixed-interface modes `applications` applications of the shift-invert operator and
    /// `factor_solves` solves with the factor (per vector).
    Solved {
        constraint_steps: usize,
        applications: usize,
        factor_solves: usize,
    },
    /// The basis $\mathbf V$ and the projections $\mathbf K_{CB}$, $\mathbf M_{CB}$.
    Projecting,
    /// Mass data, inertia invariants and the rigid fit $\boldsymbol\Phi_{com}$.
    Invariants,
    /// The reduced geometric stiffness matrices $\mathbf G_k$ (with
    /// [`CbSettings::geometric_stiffening`]).
    GeometricStiffness,
}

/// The boundary/internal split of the free dofs.
#[derive(Clone, Debug)]
pub struct Partition {
    /// Free-dof index of each boundary dof, interface by interface, six each.
    pub boundary: Vec<usize>,
    /// Free-dof index of each internal dof.
    pub internal: Vec<usize>,
    /// For each free dof: `Ok(b)` boundary position or `Err(i)` internal position.
    pub position: Vec<Result<usize, usize>>,
}

/// Splits the free dofs of `dofs` into boundary (the interface nodes' six dofs) and internal.
pub fn partition(model: &FeModel, dofs: &DofMap, interfaces: &[(String, NodeId)]) -> Result<Partition, ReductionError> {
    let tag = |node: usize| model.mesh.node_tags.get(node).copied().unwrap_or(node as u64 + 1);
    let interfaces: Vec<(String, usize)> = interfaces.iter().map(|(n, node)| (n.clone(), node.index())).collect();
    partition_by(
        dofs.n_free(),
        model.node_count(),
        &interfaces,
        &|node| format!("node {}", tag(node)),
        &|node, k| match dofs.status(NodeId(node as u32), k) {
            DofStatus::Free(d) => Ok(d.index()),
            DofStatus::Inactive => Err("inactive (no element or spider uses it)"),
            DofStatus::Supported => Err("supported"),
            DofStatus::Dependent => Err("dependent (a spider defines it)"),
        },
    )
}

/// The partition for any model: `slot(node, k)` is the free dof of dof `k` of `node`, or why
/// that slot has none; `label(node)` names a node in messages (its tag for an FE model, its
/// index for external matrices).
fn partition_by(
    n_free: usize,
    n_nodes: usize,
    interfaces: &[(String, usize)],
    label: &dyn Fn(usize) -> String,
    slot: &dyn Fn(usize, usize) -> Result<usize, &'static str>,
) -> Result<Partition, ReductionError> {
    let mut position: Vec<Option<Result<usize, usize>>> = vec![None; n_free];
    let mut boundary = Vec::with_capacity(6 * interfaces.len());
    for (name, node) in interfaces {
        if *node >= n_nodes {
            return Err(ReductionError::Interface {
                name: name.clone(),
                what: format!("node {node} does not exist (the model has {n_nodes} nodes)"),
            });
        }
        for k in 0..6 {
            match slot(*node, k) {
                Ok(d) => {
                    if position[d].is_some() {
                        return Err(ReductionError::Interface {
                            name: name.clone(),
                            what: format!("{} is used by two interfaces", label(*node)),
                        });
                    }
                    position[d] = Some(Ok(boundary.len()));
                    boundary.push(d);
                }
                Err(why) => {
                    return Err(ReductionError::Interface {
                        name: name.clone(),
                        what: format!(
                            "dof {} of {} is {why} but an interface needs all six dofs free (beam node, or an RBE2/RBE3 interface node of a solid)",
                            DOF_NAMES[k],
                            label(*node),
                        ),
                    });
                }
            }
        }
    }
    let mut internal = Vec::with_capacity(n_free - boundary.len());
    let position = position
        .into_iter()
        .enumerate()
        .map(|(d, p)| {
            p.unwrap_or_else(|| {
                internal.push(d);
                Err(internal.len() - 1)
            })
        })
        .collect();
    Ok(Partition {
        boundary,
        internal,
        position,
    })
}

/// The free-dof matrices split by a [`Partition`]: the internal blocks sparse (both
/// triangles), the internal-boundary and boundary blocks dense. It is all that [`project`]
/// needs, so that [`reduce`] frees $\mathbf K$ and $\mathbf M$ of the free dofs (and their
/// assembly pattern) before the factorisation of $\mathbf K_{ii}$, whose peak memory they
/// would add to. $\mathbf M_{ii}$ keeps only its nonzero entries (a solid's mass assembled on
/// the pattern of $\mathbf K$ is two thirds exact zeros), or shares the row indices of
/// $\mathbf K_{ii}$ when it has the same pattern without zeros.
struct Blocks {
    /// The pattern of $\mathbf K_{ii}$ and its values.
    pattern_ii: SymbolicSparseColMat<usize>,
    K_ii: Vec<f64>,
    /// The pattern of $\mathbf M_{ii}$ where it is not that of $\mathbf K_{ii}$.
    M_pattern_ii: Option<SymbolicSparseColMat<usize>>,
    M_ii: Vec<f64>,
    /// $n_i \times n_b$.
    K_ib: Mat<f64>,
    M_ib: Mat<f64>,
    /// $n_b \times n_b$.
    K_bb: Mat<f64>,
    M_bb: Mat<f64>,
}

impl Blocks {
    fn new(
        K: SparseColMatRef<'_, usize, f64>,
        M: SparseColMatRef<'_, usize, f64>,
        p: &Partition,
    ) -> Result<Self, ReductionError> {
        let (pattern_ii, K_ii, K_ib, K_bb) = split(K, p, true, false)?;
        // M assembled on K's pattern keeps a solid's exact zeros (its mass couples only equal
        // components: two thirds of the stored entries), which would take memory beside the
        // factor and be read by every Lanczos operator application: they are left out
        // (which changes no sum), unless there are none, when M_ii shares K_ii's row indices.
        let shared = K.symbolic().col_ptr() == M.symbolic().col_ptr()
            && K.symbolic().col_nnz().is_none()
            && M.symbolic().col_nnz().is_none()
            && K.symbolic().row_idx() == M.symbolic().row_idx()
            && internal_entries(M, p, true) == internal_entries(M, p, false);
        let (M_pattern_ii, M_ii, M_ib, M_bb) = split(M, p, !shared, true)?;
        Ok(Self {
            pattern_ii: pattern_ii.expect("the pattern of K_ii"),
            K_ii,
            M_pattern_ii,
            M_ii,
            K_ib,
            M_ib,
            K_bb,
            M_bb,
        })
    }

    fn K_ii(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.pattern_ii.as_ref(), &self.K_ii)
    }

    fn M_ii(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(
            self.M_pattern_ii.as_ref().unwrap_or(&self.pattern_ii).as_ref(),
            &self.M_ii,
        )
    }
}

/// The internal-internal block as a sparse matrix (its pattern only if `with_pattern`), the
/// internal-boundary and the boundary-boundary blocks dense.
///
/// Internal positions increase with the free-dof index, so each column of $\mathbf A_{ii}$
/// is column `internal[c]` of $\mathbf A$ filtered, in the same row order: no sort. With
/// `drop_zeros`, stored zeros are left out of $\mathbf A_{ii}$.
#[allow(clippy::type_complexity)]
fn split(
    A: SparseColMatRef<'_, usize, f64>,
    p: &Partition,
    with_pattern: bool,
    drop_zeros: bool,
) -> Result<(Option<SymbolicSparseColMat<usize>>, Vec<f64>, Mat<f64>, Mat<f64>), ReductionError> {
    let (ni, nb) = (p.internal.len(), p.boundary.len());
    let mut A_ib = Mat::zeros(ni, nb);
    let mut A_bb = Mat::zeros(nb, nb);
    for (c, &col) in p.boundary.iter().enumerate() {
        for (&row, &v) in A.row_idx_of_col_raw(col).iter().zip(A.val_of_col(col)) {
            match p.position[row] {
                Err(r) => A_ib[(r, c)] += v,
                Ok(r) => A_bb[(r, c)] += v,
            }
        }
    }
    // Column by column in parallel (`select_entries`); rows stay in A's order: sorted (and
    // unique) when A's are, as for assembled matrices and those read by `read_matrix_market`.
    let A_ii = select_entries(A, ni, &p.internal, |row, v| match p.position[row] {
        Err(r) if !(drop_zeros && v == 0.0) => Some(r),
        _ => None,
    });
    let (symbolic, values) = A_ii.into_parts();
    let pattern = with_pattern.then_some(symbolic);
    Ok((pattern, values, A_ib, A_bb))
}

/// The stored entries of $\mathbf A_{ii}$ (without the stored zeros if `drop_zeros`).
fn internal_entries(A: SparseColMatRef<'_, usize, f64>, p: &Partition, drop_zeros: bool) -> usize {
    p.internal
        .par_iter()
        .map(|&col| {
            A.row_idx_of_col_raw(col)
                .iter()
                .zip(A.val_of_col(col))
                .filter(|&(&row, &v)| p.position[row].is_err() && !(drop_zeros && v == 0.0))
                .count()
        })
        .sum()
}

/// $\mathbf V^T\mathbf A\mathbf V$ for the CB basis $\mathbf V = \begin{bmatrix}\mathbf I &
/// \mathbf 0\\ \boldsymbol\Psi & \boldsymbol\Phi_i\end{bmatrix}$ (boundary rows first,
/// $\mathbf V_i = [\boldsymbol\Psi\ \boldsymbol\Phi_i]$) from the blocks of $\mathbf A$:
/// $\mathbf V_i^T(\mathbf A_{ib}\mathbf E + \mathbf A_{ii}\mathbf V_i)$ plus, in the first
/// $n_b$ rows, $\mathbf A_{bb}\mathbf E + \mathbf A_{ib}^T\mathbf V_i$, with $\mathbf E =
/// [\mathbf I\ \mathbf 0]$. Not symmetrised.
fn project_blocks(
    A_ii: SparseColMatRef<'_, usize, f64>,
    A_ib: &Mat<f64>,
    A_bb: &Mat<f64>,
    V_i: MatRef<'_, f64>,
    par: faer::Par,
) -> Mat<f64> {
    let nb = A_bb.nrows();
    let n = V_i.ncols();
    let mut AV_i = crate::eigen::symmetric_times(A_ii, V_i, par);
    for c in 0..nb {
        for (a, &v) in AV_i.col_mut(c).iter_mut().zip(A_ib.col(c).iter()) {
            *a += v;
        }
    }
    let mut P = crate::eigen::gram(V_i, AV_i.as_ref(), par);
    let top = crate::eigen::gram(A_ib.as_ref(), V_i, par);
    for c in 0..n {
        for r in 0..nb {
            P[(r, c)] += top[(r, c)] + if c < nb { A_bb[(r, c)] } else { 0.0 };
        }
    }
    P
}

/// The CB basis on the free dofs and the reduced matrices: what [`reduce`] and
/// [`reduce_external`] share.
struct Projection {
    /// $\mathbf V$, free dofs x $n$.
    V: Mat<f64>,
    /// Circular frequencies of the kept fixed-interface modes.
    omega: Vec<f64>,
    K_CB: Mat<f64>,
    M_CB: Mat<f64>,
    /// How many of the modes (the last) are static correction vectors.
    n_attachment: usize,
}

/// The core of the reduction, independent of where $\mathbf K$ and $\mathbf M$ came from:
/// constraint modes and fixed-interface modes from one factorisation of $\mathbf K_{ii}$,
/// the basis $\mathbf V$ and the projections (module docs). `describe(d)` names free dof `d`
/// in messages.
/// The free-dof matrices, split, and how to order and name their dofs, for [`project`].
struct FreeSystem<'a> {
    blocks: Blocks,
    /// Position of each free dof (its node), for nested dissection.
    points: &'a [[f64; 3]],
    ordering: FillOrdering,
    /// Names free dof `d` in messages.
    describe: &'a dyn Fn(usize) -> String,
}

impl<'a> FreeSystem<'a> {
    fn new(
        blocks: Blocks,
        points: &'a [[f64; 3]],
        ordering: FillOrdering,
        describe: &'a dyn Fn(usize) -> String,
    ) -> Self {
        FreeSystem {
            blocks,
            points,
            ordering,
            describe,
        }
    }
}

/// The nodes of `settings.load_points` as [`load_point_dofs`] reads them.
fn settings_load_points(settings: &CbSettings) -> NamedNodes {
    settings
        .load_points
        .iter()
        .map(|(n, node)| (n.clone(), node.index()))
        .collect()
}

fn project(
    system: FreeSystem<'_>,
    p: &Partition,
    settings: &CbSettings,
    load_dofs: &[usize],
    name: &str,
    progress: &mut dyn FnMut(Stage),
) -> Result<Projection, ReductionError> {
    let (modes, inertia_correction) = (settings.modes, settings.inertia_correction);
    let FreeSystem {
        blocks,
        points,
        ordering,
        describe,
    } = system;
    let precision = settings.factor;
    let (K_ii, M_ii) = (blocks.K_ii(), blocks.M_ii());
    let Blocks {
        K_ib, M_ib, K_bb, M_bb, ..
    } = &blocks;
    let (nb, ni, n_free) = (p.boundary.len(), p.internal.len(), p.position.len());
    // Static correction: one load per load-point dof, one per constraint mode with the
    // inertia correction.
    let n_loads = load_dofs.len() + if inertia_correction { nb } else { 0 };
    // Before any factorisation: a count the interior cannot give is the user's to change.
    if let ModeSelection::Count(m) = modes {
        if m > 0 && m >= ni {
            return Err(ReductionError::TooManyModes {
                body: name.into(),
                requested: m,
                interior: ni,
            });
        }
    }
    // One factorisation of K_ii for the constraint modes and the fixed-interface modes.
    let (Psi, Phi_i, omega, n_attachment) = if ni == 0 {
        (Mat::zeros(0, nb), Mat::zeros(0, 0), Vec::new(), 0)
    } else {
        progress(Stage::Factorising { internal_dofs: ni });
        let points_i: Vec<[f64; 3]> = p.internal.iter().map(|&d| points[d]).collect();
        let settings = FactorSettings {
            precision,
            reserve_bytes: reserve_bytes(ni, nb, modes, n_loads, fe_model::Precision::Double),
            single_reserve_bytes: reserve_bytes(ni, nb, modes, n_loads, fe_model::Precision::Single),
        };
        let name_errors = |e: ReductionError| {
            match e {
            ReductionError::SingularStiffness { dof, .. } => ReductionError::Interface {
                name: name.into(),
                what: format!(
                    "with the interfaces held, the body can still move without straining near {}: add an interface or a support there",
                    describe(p.internal[dof])
                ),
            },
            ReductionError::SinglePrecisionBreakdown { at, pivot_ratio, .. } => {
                let at = match at.strip_prefix("dof ").and_then(|d| d.parse::<usize>().ok()) {
                    Some(dof) => describe(p.internal[dof]),
                    None => at,
                };
                ReductionError::SinglePrecisionBreakdown {
                    body: format!("part '{name}'"),
                    at,
                    pivot_ratio,
                }
            }
            other => other.with_body(&format!("part '{name}'")),
        }
        };
        let factor =
            ShiftInvert::with_settings(K_ii, M_ii, 0.0, Some(&points_i), ordering, &settings).map_err(name_errors)?;
        drop(points_i);
        progress(Stage::Factorised {
            factor_len: factor.factor_len(),
            flops: factor.factor_flops(),
            ordering: factor.ordering(),
            precision: factor.precision(),
        });
        // (theory guide §3) Psi = -K_ii^{-1} K_ib: 6N solves with the one factor, refined to
        // a double-precision solve's accuracy when the factor is in single precision.
        progress(Stage::ConstraintModes { count: nb });
        let mut Psi = -K_ib;
        let constraint_steps = factor
            .solve_refined(K_ii, M_ii, Psi.as_mut(), &|| "the constraint modes".into())
            .map_err(name_errors)?;
        let (mut Phi_i, mut omega, (applications, factor_solves)) =
            fixed_interface_modes(&factor, K_ii, M_ii, modes, ni, progress).map_err(name_errors)?;
        progress(Stage::Solved {
            constraint_steps,
            applications,
            factor_solves,
        });
        // F = [unit loads on the load-point dofs, M_ii Psi + M_ib] (theory guide (6.10), (3.10)).
        let mut F = Mat::<f64>::zeros(ni, n_loads);
        for (j, &d) in load_dofs.iter().enumerate() {
            F[(d, j)] = 1.0;
        }
        if inertia_correction {
            let inertia = symmetric_times(M_ii, Psi.as_ref(), faer::get_global_parallelism()) + M_ib;
            F.subcols_mut(load_dofs.len(), nb).copy_from(&inertia);
        }
        let (X, omega_x) = static_correction(&factor, K_ii, M_ii, &Phi_i, F).map_err(name_errors)?;
        let n_attachment = X.ncols();
        if n_attachment > 0 {
            let m = Phi_i.ncols();
            Phi_i = Mat::from_fn(
                ni,
                m + n_attachment,
                |i, j| {
                    if j < m {
                        Phi_i[(i, j)]
                    } else {
                        X[(i, j - m)]
                    }
                },
            );
            omega.extend(omega_x);
        }
        (Psi, Phi_i, omega, n_attachment)
    };
    progress(Stage::Projecting);
    let m = omega.len();
    let n = nb + m;
    // V_i = [Psi Phi_i], the internal rows of V; the projections from the blocks.
    let V_i = gather_rows(ni, n, |i, c| if c < nb { Psi[(i, c)] } else { Phi_i[(i, c - nb)] });
    drop((Psi, Phi_i));
    let par = faer::get_global_parallelism();
    let K_CB = symmetrize(project_blocks(K_ii, K_ib, K_bb, V_i.as_ref(), par));
    let M_CB = symmetrize(project_blocks(M_ii, M_ib, M_bb, V_i.as_ref(), par));
    drop(blocks);
    // V on the free dofs, in the free-dof order of the model, column by column (the matrices
    // are column-major).
    let V = gather_rows(n_free, n, |d, c| match p.position[d] {
        Ok(b) => {
            if b == c {
                1.0
            } else {
                0.0
            }
        }
        Err(i) => V_i[(i, c)],
    });
    Ok(Projection {
        V,
        omega,
        K_CB,
        M_CB,
        n_attachment,
    })
}

/// Bytes allocated while the factor of $\mathbf K_{ii}$ ($n_i$ rows) in `precision` is alive,
/// for [`FactorSettings`]: the most $n_i$-vectors of the three stages held at once. The
/// constraint modes $\boldsymbol\Psi$ ($n_b$ columns) and the solve's permuted copy; with a
/// single-precision factor also the right-hand sides, the residuals, the sparse product's
/// row-major copies and result, and the f32 copy of the solve. Then $\boldsymbol\Psi$ and the
/// eigensolver's vectors ([`crate::eigen::eigen_vectors`]). Then $\boldsymbol\Psi$, the $m$
/// modes and the `n_loads` static correction vectors (load-point dofs, constraint modes'
/// inertia) with their refined solve and products. A cut-off frequency counts as 20 modes (its first request asks for 8, then
/// doubles).
fn reserve_bytes(ni: usize, nb: usize, modes: ModeSelection, n_loads: usize, precision: fe_model::Precision) -> usize {
    let m = match modes {
        ModeSelection::StaticOnly => 0,
        ModeSelection::Count(m) => m,
        ModeSelection::CutoffHz(_) => 20,
    };
    // Columns a refined solve of k right-hand sides holds beside them.
    let solve = |k: usize| match precision {
        fe_model::Precision::Double => k,
        fe_model::Precision::Single => 5 * k + k.div_ceil(2),
    };
    let eigen = if m == 0 {
        0
    } else {
        crate::eigen::eigen_vectors(&EigenSettings::new(m, Shift::Zero), ni, precision)
    };
    let columns = (nb + solve(nb))
        .max(nb + eigen)
        .max(nb + m + n_loads + solve(n_loads).max(2 * n_loads));
    8 * ni * columns
}

/// The last step shared by [`reduce`] and [`reduce_external`]: checks the auxiliary node
/// against the centre of mass and packs the [`ReducedBody`].
struct BodyParts<'a> {
    name: &'a str,
    interfaces: &'a [(String, usize)],
    nodes: Vec<[f64; 3]>,
    projection: Projection,
    S_full: Mat<f64>,
    /// The inertia invariants and the centre-of-mass shapes $\boldsymbol\Phi_{com}$, computed
    /// together from $\mathbf M$ and the full shapes.
    inertia: (InertiaData, Mat<f64>),
    auxiliary_interface: Option<usize>,
    keep_mesh_shapes: bool,
    geometric_stiffness: Option<Vec<DenseMatrix>>,
    stress: Option<StressShapes>,
    load_points: &'a [(String, usize)],
}

fn finish(parts: BodyParts<'_>) -> Result<ReducedBody, ReductionError> {
    let BodyParts {
        name,
        interfaces,
        nodes,
        projection,
        S_full,
        inertia: (inertia, Phi_com),
        auxiliary_interface,
        keep_mesh_shapes,
        geometric_stiffness,
        stress,
        load_points,
    } = parts;
    if let Some(aux) = auxiliary_interface {
        let x = nodes[interfaces[aux].1];
        let c = inertia.center_of_mass;
        let size = nodes
            .iter()
            .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
            .fold(0.0f64, f64::max)
            .max(1e-300);
        let d = ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) + (x[2] - c[2]).powi(2)).sqrt();
        // The auxiliary frame is defined at the centre of mass; a node off it by more than a
        // millionth of the body's size was placed wrongly.
        if d > 1e-6 * size {
            return Err(ReductionError::Interface {
                name: "auxiliary".into(),
                what: format!(
                    "the auxiliary node is {d:.3e} from the centre of mass {c:?}; place it at the centre of mass"
                ),
            });
        }
    }
    let load_points = load_points
        .iter()
        .map(|(name, node)| LoadPoint {
            name: name.clone(),
            node: *node as u32,
            position: nodes[*node],
            shape: DenseMatrix::from_faer(S_full.subrows(6 * node, 6)),
        })
        .collect();
    let Projection {
        omega,
        K_CB,
        M_CB,
        n_attachment,
        ..
    } = projection;
    Ok(ReducedBody {
        format_version: FORMAT_VERSION,
        name: name.to_string(),
        interfaces: interfaces
            .iter()
            .map(|(name, node)| InterfacePoint {
                name: name.clone(),
                node: *node as u32,
                position: nodes[*node],
                node_label: None,
            })
            .collect(),
        n_modes: omega.len(),
        fixed_interface_omega: omega,
        K_CB: DenseMatrix::from_faer(K_CB.as_ref()),
        M_CB: DenseMatrix::from_faer(M_CB.as_ref()),
        inertia,
        Phi_com: DenseMatrix::from_faer(Phi_com.as_ref()),
        auxiliary_interface,
        mesh: keep_mesh_shapes.then(|| MeshModes {
            nodes,
            shapes: DenseMatrix::from_faer(S_full.as_ref()),
        }),
        geometric_stiffness,
        stress,
        load_points,
        attachment_modes: n_attachment,
    })
}

/// The internal positions of the load points' dofs: every free dof of each point's node
/// (translations of a solid node; all six of a beam node), for [`static_correction`].
/// `slot(node, k)` is the free dof of slot `k` of `node`, `None` for a slot without one
/// (inactive, supported or dependent: a dependent slot follows its spider's node).
fn load_point_dofs(
    load_points: &[(String, usize)],
    n_nodes: usize,
    p: &Partition,
    slot: &dyn Fn(usize, usize) -> Option<usize>,
) -> Result<Vec<usize>, ReductionError> {
    let mut out = Vec::new();
    for (name, node) in load_points {
        let bad = |what: String| ReductionError::InvalidSettings {
            what: format!("load point '{name}': {what}"),
        };
        if *node >= n_nodes {
            return Err(bad(format!(
                "node {node} does not exist (the model has {n_nodes} nodes)"
            )));
        }
        let before = out.len();
        for k in 0..6 {
            if let Some(d) = slot(*node, k) {
                match p.position[d] {
                    Err(i) => {
                        if out.contains(&i) {
                            return Err(bad("its node is already another load point".into()));
                        }
                        out.push(i)
                    }
                    Ok(_) => {
                        return Err(bad(
                            "its node is an interface; loads there need no static correction".into()
                        ))
                    }
                }
            }
        }
        if out.len() == before {
            return Err(bad("its node has no free dof (supported, or moved by a spider)".into()));
        }
    }
    Ok(out)
}

/// Interfaces as (name, node index).
type NamedNodes = Vec<(String, usize)>;

/// The interface list with the auxiliary node appended (named `auxiliary`), and its index.
fn with_auxiliary(
    name: &str,
    interfaces: &[(String, usize)],
    auxiliary_node: Option<NodeId>,
) -> Result<(NamedNodes, Option<usize>), ReductionError> {
    let mut interfaces = interfaces.to_vec();
    let auxiliary_interface = auxiliary_node.map(|node| {
        interfaces.push(("auxiliary".to_string(), node.index()));
        interfaces.len() - 1
    });
    if interfaces.is_empty() {
        return Err(ReductionError::Interface {
            name: name.into(),
            what: "a reduced body needs at least one interface".into(),
        });
    }
    Ok((interfaces, auxiliary_interface))
}

/// Reduces `model` with the given interfaces (name, node) by Craig-Bampton.
///
/// Interfaces are beam nodes or the 6-dof nodes of RBE2/RBE3 spiders on solids; their six
/// dofs must be free. The FE model's own supports are kept (a body clamped in the FE model
/// stays clamped). The factorisation of $\mathbf K_{ii}$ uses [`FillOrdering::Auto`]
/// (nested dissection on the node positions for large models).
pub fn reduce(
    model: &FeModel,
    name: &str,
    interfaces: &[(String, NodeId)],
    settings: &CbSettings,
) -> Result<ReducedBody, ReductionError> {
    reduce_with_progress(model, name, interfaces, settings, FillOrdering::Auto, &mut |_| {})
}

/// [`reduce`] with a chosen fill-reducing `ordering` for $\mathbf K_{ii}$, calling
/// `progress` as each [`Stage`] starts (for a progress bar, or to time the stages).
pub fn reduce_with_progress(
    model: &FeModel,
    name: &str,
    interfaces: &[(String, NodeId)],
    settings: &CbSettings,
    ordering: FillOrdering,
    progress: &mut dyn FnMut(Stage),
) -> Result<ReducedBody, ReductionError> {
    let interfaces: Vec<(String, usize)> = interfaces.iter().map(|(n, node)| (n.clone(), node.index())).collect();
    let (interfaces, auxiliary_interface) = with_auxiliary(name, &interfaces, settings.auxiliary_node)?;
    let planar;
    let model = if settings.planar {
        let nodes: Vec<NodeId> = interfaces.iter().map(|(_, i)| NodeId(*i as u32)).collect();
        planar = planar_model(model, name, &nodes)?;
        &planar
    } else {
        model
    };
    progress(Stage::Assembling);
    let dofs = DofMap::new(model)?;
    let a = assemble_with_pattern(model, SystemPattern::new(model, &dofs))?;
    let node_ids: Vec<(String, NodeId)> = interfaces.iter().map(|(n, i)| (n.clone(), NodeId(*i as u32))).collect();
    let p = partition(model, &dofs, &node_ids)?;
    let describe = |d: usize| {
        let (tag, k) = dofs.describe(fe_model::Dof(d as u32));
        format!("node {tag} dof {k}")
    };
    let points = dof_points(model, &dofs);
    // Only the blocks from here on: K and M of the free dofs are freed before the
    // factorisation.
    let blocks = Blocks::new(a.K.as_ref(), a.M.as_ref(), &p)?;
    drop(a);
    let system = FreeSystem::new(blocks, &points, ordering, &describe);
    let load_points = settings_load_points(settings);
    let load_dofs = load_point_dofs(&load_points, model.node_count(), &p, &|node, k| {
        dofs.free_dof(NodeId(node as u32), k).map(|d| d.index())
    })?;
    let projection = project(system, &p, settings, &load_dofs, name, progress)?;
    if settings.planar {
        check_planar(name, &interfaces, &projection.K_CB, &projection.M_CB)?;
    }
    let n = projection.V.ncols();
    // The CB basis on every node's six slots: S_full = T V (dependent slots follow their spider).
    let S_full = gather_rows(6 * model.node_count(), n, |slot, col| {
        let (d, c) = dofs.row(slot);
        d.iter()
            .zip(c)
            .map(|(&dof, &coef)| coef * projection.V[(dof as usize, col)])
            .sum()
    });
    progress(Stage::Invariants);
    let inertia = inertia_data(model, &S_full)?;
    let geometric_stiffness = if settings.geometric_stiffening {
        progress(Stage::GeometricStiffness);
        Some(reduced_geometric_stiffness(model, S_full.as_ref())?)
    } else {
        None
    };
    let stress = if settings.stress_shapes {
        Some(stress_shapes(model, S_full.as_ref())?)
    } else {
        None
    };
    finish(BodyParts {
        name,
        interfaces: &interfaces,
        nodes: model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect(),
        projection,
        S_full,
        inertia,
        auxiliary_interface,
        keep_mesh_shapes: settings.keep_mesh_shapes,
        geometric_stiffness,
        stress,
        load_points: &load_points,
    })
}

/// Reduces a model given as matrices, from another FE code: node coordinates, $\mathbf K$
/// and $\mathbf M$ with `dofs_per_node` (3 or 6) dofs for every node, in node order
/// (row $d$ is dof $d \bmod$ `dofs_per_node` of node $\lfloor d/$`dofs_per_node`$\rfloor$,
/// dofs ordered $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$). Interfaces are `(name,
/// node index)`; each needs six dofs, so with `dofs_per_node = 3` (a solid mesh) use
/// [`reduce_external_dofs`], where the interface nodes (of RBE2/RBE3 spiders already
/// eliminated by the other code) carry six dofs and the others three.
///
/// Same result as [`reduce`] for the same matrices (`tests/unit/matrix_market.rs` checks it
/// to round-off), except for the mass data; see [`reduce_external_dofs`].
pub fn reduce_external(
    nodes: &[[f64; 3]],
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
    dofs_per_node: usize,
    name: &str,
    interfaces: &[(String, usize)],
    settings: &CbSettings,
) -> Result<ReducedBody, ReductionError> {
    if dofs_per_node != 3 && dofs_per_node != 6 {
        return Err(ReductionError::ExternalModel {
            what: format!("dofs_per_node must be 3 (solids) or 6 (beams, shells), got {dofs_per_node}"),
        });
    }
    if K.nrows() != nodes.len() * dofs_per_node {
        return Err(ReductionError::ExternalModel {
            what: format!(
                "K has {} rows but {} nodes x {dofs_per_node} dofs per node make {}",
                K.nrows(),
                nodes.len(),
                nodes.len() * dofs_per_node
            ),
        });
    }
    let dofs: Vec<(usize, usize)> = (0..K.nrows()).map(|d| (d / dofs_per_node, d % dofs_per_node)).collect();
    reduce_external_dofs(nodes, K, M, &dofs, name, interfaces, settings)
}

/// [`reduce_external`] with an explicit dof list: row $d$ of $\mathbf K$ and $\mathbf M$ is
/// dof `dofs[d].1` (0..6, $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$) of node
/// `dofs[d].0`. Nodes may carry any subset of their six dofs (three for solid nodes, six for
/// interface nodes, none for a node whose dofs the other code eliminated).
///
/// # Mass data
/// [`reduce`] computes the mass, centre of mass, inertia tensor and invariants from the mass
/// matrix of the body *without* supports or spiders (`invariants` module docs). Here only the
/// given $\mathbf M$ exists, so they are computed from it, on the given dofs:
/// - supports eliminated by the other code take their mass with them (a clamped node's mass
///   is missing from the total); spiders eliminated by elimination keep it exactly for the
///   rigid-body data (mass, centre, inertia, $\int\rho\mathbf S$, $\int\rho\tilde{\mathbf x}
///   \mathbf S$), because a rigid motion of the independent dofs is a rigid motion of the
///   dependent ones (RBE2 and RBE3 both reproduce rigid motion);
/// - the second-order invariants place scalar fields in the translation slots of the given
///   dofs only, so with spiders eliminated the mass of the dependent surface nodes, lumped
///   into the interface node's six dofs, is seen at the interface node: an approximation
///   where [`reduce`] is exact for solids;
/// - the mesh shapes ([`MeshModes`]) hold zeros in the slots the matrices do not have.
///
/// # Errors
/// [`ReductionError::ExternalModel`] for inconsistent sizes, a dof listed twice, a node index
/// out of range or a non-symmetric matrix (with the offending entry);
/// [`ReductionError::Interface`] for an interface node without its six dofs;
/// [`ReductionError::ExternalModel`] with [`CbSettings::geometric_stiffening`] (it needs the
/// elements); and every error of [`reduce`]'s eigen solution.
pub fn reduce_external_dofs(
    nodes: &[[f64; 3]],
    K: SparseColMatRef<'_, usize, f64>,
    M: SparseColMatRef<'_, usize, f64>,
    dofs: &[(usize, usize)],
    name: &str,
    interfaces: &[(String, usize)],
    settings: &CbSettings,
) -> Result<ReducedBody, ReductionError> {
    if settings.planar {
        return Err(ReductionError::ExternalModel {
            what: "a planar reduction needs the FE model's elements and nodes (use `reduce`)".into(),
        });
    }
    if settings.geometric_stiffening || settings.stress_shapes {
        // G_k and the stress shapes need the stress of each mode, hence the elements:
        // matrices alone do not have it.
        return Err(ReductionError::ExternalModel {
            what: "geometric stiffening and stress shapes need the FE model's elements (use `reduce`); matrices from another code do not carry them".into(),
        });
    }
    let n_free = dofs.len();
    for (what, A) in [("K", K), ("M", M)] {
        if A.nrows() != n_free || A.ncols() != n_free {
            return Err(ReductionError::ExternalModel {
                what: format!(
                    "{what} is {} x {} but the dof list has {n_free} dofs",
                    A.nrows(),
                    A.ncols()
                ),
            });
        }
        check_symmetric_entries(A, what)?;
    }
    if let Some(bad) = nodes.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
        return Err(ReductionError::ExternalModel {
            what: format!("node {bad} has a non-finite coordinate {:?}", nodes[bad]),
        });
    }
    let mut slot_dof: Vec<Option<usize>> = vec![None; 6 * nodes.len()];
    for (d, &(node, k)) in dofs.iter().enumerate() {
        if node >= nodes.len() || k >= 6 {
            return Err(ReductionError::ExternalModel {
                what: format!(
                    "dof {d} is dof {k} of node {node}, but there are {} nodes and 6 dofs per node",
                    nodes.len()
                ),
            });
        }
        if let Some(other) = slot_dof[6 * node + k].replace(d) {
            return Err(ReductionError::ExternalModel {
                what: format!("dofs {other} and {d} are both dof {} of node {node}", DOF_NAMES[k]),
            });
        }
    }
    let (interfaces, auxiliary_interface) = with_auxiliary(name, interfaces, settings.auxiliary_node)?;
    let p = partition_by(
        n_free,
        nodes.len(),
        &interfaces,
        &|node| format!("node {node} (index)"),
        &|node, k| slot_dof[6 * node + k].ok_or("not in the matrices"),
    )?;
    let describe = |d: usize| format!("node {} (index) dof {}", dofs[d].0, DOF_NAMES[dofs[d].1]);
    let points: Vec<[f64; 3]> = dofs.iter().map(|&(node, _)| nodes[node]).collect();
    let system = FreeSystem::new(Blocks::new(K, M, &p)?, &points, FillOrdering::Auto, &describe);
    let load_points = settings_load_points(settings);
    let load_dofs = load_point_dofs(&load_points, nodes.len(), &p, &|node, k| slot_dof[6 * node + k])?;
    let projection = project(system, &p, settings, &load_dofs, name, &mut |_| {})?;
    let n = projection.V.ncols();
    let mut S_full = Mat::<f64>::zeros(6 * nodes.len(), n);
    for col in 0..n {
        for (d, &(node, k)) in dofs.iter().enumerate() {
            S_full[(6 * node + k, col)] = projection.V[(d, col)];
        }
    }
    let slots: Vec<usize> = dofs.iter().map(|&(node, k)| 6 * node + k).collect();
    let inertia = inertia_data_from_mass(M, &slots, nodes, &S_full)?;
    finish(BodyParts {
        name,
        interfaces: &interfaces,
        nodes: nodes.to_vec(),
        projection,
        S_full,
        inertia,
        auxiliary_interface,
        keep_mesh_shapes: settings.keep_mesh_shapes,
        geometric_stiffness: None,
        stress: None,
        load_points: &load_points,
    })
}

/// Refuses a matrix whose entries $(i, j)$ and $(j, i)$ differ, naming the first such pair.
///
/// Tolerance $10^{-10} \max|A|$: an assembled matrix is symmetric to a few ulps of its
/// largest entries (each entry is a sum of element contributions added in the same order for
/// both triangles, up to the order of a few terms), and a file written by another code
/// prints $a_{ij}$ and $a_{ji}$ with the same digits, so a real asymmetry or a missing
/// triangle stands out by many orders of magnitude.
fn check_symmetric_entries(A: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), ReductionError> {
    // Summed per position: a matrix built from triplets may list a position twice.
    let mut value: std::collections::HashMap<(usize, usize), f64> = std::collections::HashMap::new();
    let mut max = 0.0f64;
    for j in 0..A.ncols() {
        for (&i, &v) in A.row_idx_of_col_raw(j).iter().zip(A.val_of_col(j)) {
            *value.entry((i, j)).or_default() += v;
            max = max.max(v.abs());
        }
    }
    if !max.is_finite() {
        return Err(ReductionError::ExternalModel {
            what: format!("{what} has a non-finite entry"),
        });
    }
    let tol = 1e-10 * max;
    // Column by column, so that the first offending entry is reported, whatever the hashing.
    for j in 0..A.ncols() {
        for &i in A.row_idx_of_col_raw(j) {
            let v = value[&(i, j)];
            let w = value.get(&(j, i)).copied();
            if (v - w.unwrap_or(0.0)).abs() > tol {
                let mirror = match w {
                    Some(w) => format!("({j}, {i}) is {w:e}"),
                    None => format!("({j}, {i}) is not stored"),
                };
                return Err(ReductionError::ExternalModel {
                    what: format!(
                        "{what} is not symmetric: entry ({i}, {j}) is {v:e} but {mirror} (0-based; both triangles must be stored, and equal to within {tol:.1e})"
                    ),
                });
            }
        }
    }
    Ok(())
}

/// $\frac12(\mathbf A + \mathbf A^T)$: the projections are symmetric up to round-off; make
/// them exactly so for the eigen- and Cholesky solvers downstream.
fn symmetrize(A: Mat<f64>) -> Mat<f64> {
    Mat::from_fn(A.nrows(), A.ncols(), |i, j| 0.5 * (A[(i, j)] + A[(j, i)]))
}

/// The fixed-interface modes by count or cut-off frequency, with their circular frequencies and
/// the operator applications and solves with the factor they took (over all requests).
#[allow(clippy::type_complexity)]
fn fixed_interface_modes(
    factor: &ShiftInvert,
    K_ii: SparseColMatRef<'_, usize, f64>,
    M_ii: SparseColMatRef<'_, usize, f64>,
    selection: ModeSelection,
    ni: usize,
    progress: &mut dyn FnMut(Stage),
) -> Result<(Mat<f64>, Vec<f64>, (usize, usize)), ReductionError> {
    let mut counts = (0, 0);
    let mut solve = |m: usize| {
        let s = factor.lowest_modes_with_progress(
            K_ii,
            M_ii,
            &EigenSettings::new(m, Shift::Zero),
            &mut |converged, wanted, applications| {
                progress(Stage::EigenIteration {
                    converged,
                    wanted,
                    applications,
                })
            },
        )?;
        counts.0 += s.operator_applications;
        counts.1 += s.factor_solves;
        Ok::<_, ReductionError>(s)
    };
    let to_omega = |lambda: &[f64]| lambda.iter().map(|l| l.max(0.0).sqrt()).collect::<Vec<f64>>();
    match selection {
        ModeSelection::StaticOnly | ModeSelection::Count(0) => Ok((Mat::zeros(ni, 0), Vec::new(), (0, 0))),
        ModeSelection::Count(m) => {
            if m >= ni {
                return Err(ReductionError::InvalidModeCount { requested: m, n: ni });
            }
            let s = solve(m)?;
            Ok((s.vectors, to_omega(&s.eigenvalues), counts))
        }
        ModeSelection::CutoffHz(f) => {
            if !(f > 0.0 && f.is_finite()) {
                return Err(ReductionError::InvalidSettings {
                    what: format!("cut-off frequency must be positive, got {f} Hz"),
                });
            }
            let cutoff = 2.0 * std::f64::consts::PI * f;
            // Ask for more modes until one lies above the cut-off (or the model runs out).
            let mut m = 8.min(ni.saturating_sub(1));
            loop {
                if m == 0 {
                    return Ok((Mat::zeros(ni, 0), Vec::new(), counts));
                }
                let s = solve(m)?;
                let omega = to_omega(&s.eigenvalues);
                let keep = omega.iter().take_while(|&&w| w <= cutoff).count();
                if keep < m || m + 1 >= ni {
                    return Ok((s.vectors.subcols(0, keep).to_owned(), omega[..keep].to_vec(), counts));
                }
                m = (2 * m).min(ni - 1);
            }
        }
    }
}
