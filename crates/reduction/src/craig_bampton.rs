//! Craig-Bampton reduction of an FE model with interfaces (brief §3).
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

use crate::eigen::{EigenSettings, Shift, ShiftInvert};
use crate::error::ReductionError;
use crate::invariants::inertia_data;
use crate::reduced_body::{DenseMatrix, InterfacePoint, MeshModes, ReducedBody, FORMAT_VERSION};
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::Mat;
use fe_model::{assemble, DofMap, DofStatus, FeModel, NodeId, SystemPattern, DOF_NAMES};
use serde::{Deserialize, Serialize};

/// How many fixed-interface modes to keep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ModeSelection {
    /// Static (constraint) modes only: exact statics for interface loads.
    StaticOnly,
    /// The `m` lowest fixed-interface modes.
    Count(usize),
    /// Every fixed-interface mode below a frequency [Hz].
    CutoffHz(f64),
}

/// Settings of [`reduce`].
#[derive(Clone, Debug, PartialEq)]
pub struct CbSettings {
    pub modes: ModeSelection,
    /// Keep the CB basis on every mesh node (for output and stress recovery).
    pub keep_mesh_shapes: bool,
    /// An interface node placed at the centre of mass, added as the last interface and held
    /// fixed during the reduction (the `auxiliary-node` frame choice, brief §4).
    pub auxiliary_node: Option<NodeId>,
}

impl CbSettings {
    /// Settings keeping `modes`, the mesh shapes, and no auxiliary node.
    pub fn new(modes: ModeSelection) -> Self {
        Self { modes, keep_mesh_shapes: true, auxiliary_node: None }
    }
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
    let n = dofs.n_free();
    let mut position: Vec<Option<Result<usize, usize>>> = vec![None; n];
    let mut boundary = Vec::with_capacity(6 * interfaces.len());
    for (name, node) in interfaces {
        if node.index() >= model.node_count() {
            return Err(ReductionError::Interface {
                name: name.clone(),
                what: format!("node {} does not exist (the model has {} nodes)", node.0, model.node_count()),
            });
        }
        for k in 0..6 {
            match dofs.status(*node, k) {
                DofStatus::Free(d) => {
                    if position[d.index()].is_some() {
                        return Err(ReductionError::Interface {
                            name: name.clone(),
                            what: format!("node {} is used by two interfaces", model.mesh.node_tags[node.index()]),
                        });
                    }
                    position[d.index()] = Some(Ok(boundary.len()));
                    boundary.push(d.index());
                }
                other => {
                    return Err(ReductionError::Interface {
                        name: name.clone(),
                        what: format!(
                            "dof {} of node {} is {} but an interface needs all six dofs free (beam node, or an RBE2/RBE3 interface node of a solid)",
                            DOF_NAMES[k],
                            model.mesh.node_tags[node.index()],
                            match other {
                                DofStatus::Inactive => "inactive (no element or spider uses it)",
                                DofStatus::Supported => "supported",
                                DofStatus::Dependent => "dependent (a spider defines it)",
                                DofStatus::Free(_) => unreachable!(),
                            }
                        ),
                    });
                }
            }
        }
    }
    let mut internal = Vec::with_capacity(n - boundary.len());
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
    Ok(Partition { boundary, internal, position })
}

/// The internal-internal block as a sparse matrix and the internal-boundary block dense.
fn split(A: SparseColMatRef<'_, usize, f64>, p: &Partition) -> Result<(SparseColMat<usize, f64>, Mat<f64>), ReductionError> {
    let (ni, nb) = (p.internal.len(), p.boundary.len());
    let mut triplets = Vec::with_capacity(A.compute_nnz());
    let mut A_ib = Mat::zeros(ni, nb);
    let sym = A.symbolic();
    let values = A.val();
    for col in 0..A.ncols() {
        let range = sym.col_range(col);
        for (&row, &v) in sym.row_idx()[range.clone()].iter().zip(&values[range]) {
            match (p.position[row], p.position[col]) {
                (Err(r), Err(c)) => triplets.push(Triplet::new(r, c, v)),
                (Err(r), Ok(c)) => A_ib[(r, c)] += v,
                _ => {}
            }
        }
    }
    let A_ii = SparseColMat::try_new_from_triplets(ni, ni, &triplets)
        .map_err(|e| ReductionError::Factorization(format!("building the internal block: {e:?}")))?;
    Ok((A_ii, A_ib))
}

/// Reduces `model` with the given interfaces (name, node) by Craig-Bampton.
///
/// Interfaces are beam nodes or the 6-dof nodes of RBE2/RBE3 spiders on solids; their six
/// dofs must be free. The FE model's own supports are kept (a body clamped in the FE model
/// stays clamped).
pub fn reduce(
    model: &FeModel,
    name: &str,
    interfaces: &[(String, NodeId)],
    settings: &CbSettings,
) -> Result<ReducedBody, ReductionError> {
    let mut interfaces: Vec<(String, NodeId)> = interfaces.to_vec();
    let auxiliary_interface = settings.auxiliary_node.map(|node| {
        interfaces.push(("auxiliary".to_string(), node));
        interfaces.len() - 1
    });
    if interfaces.is_empty() {
        return Err(ReductionError::Interface { name: name.into(), what: "a reduced body needs at least one interface".into() });
    }
    let dofs = DofMap::new(model).map_err(ReductionError::from_fe)?;
    let pattern = SystemPattern::new(model, &dofs);
    let a = assemble(model, &pattern).map_err(ReductionError::from_fe)?;
    let p = partition(model, &dofs, &interfaces)?;
    let (nb, ni, n_free) = (p.boundary.len(), p.internal.len(), dofs.n_free());

    // One factorisation of K_ii for the constraint modes and the fixed-interface modes.
    let (K_ii, K_ib) = split(a.K.as_ref(), &p)?;
    let (M_ii, _) = split(a.M.as_ref(), &p)?;
    let (Psi, Phi_i, omega) = if ni == 0 {
        (Mat::zeros(0, nb), Mat::zeros(0, 0), Vec::new())
    } else {
        let factor = ShiftInvert::new(K_ii.as_ref(), M_ii.as_ref(), 0.0).map_err(|e| match e {
            ReductionError::SingularStiffness { dof, .. } => {
                let (tag, k) = dofs.describe(fe_model::Dof(p.internal[dof] as u32));
                ReductionError::Interface {
                    name: name.into(),
                    what: format!(
                        "with the interfaces held, the body can still move without straining near node {tag} dof {k}: add an interface or a support there"
                    ),
                }
            }
            other => other,
        })?;
        // (brief §3) Psi = -K_ii^{-1} K_ib: 6N solves with the one factor.
        let mut Psi = -&K_ib;
        factor.solve_in_place(Psi.as_mut());
        let (Phi_i, omega) = fixed_interface_modes(&factor, K_ii.as_ref(), M_ii.as_ref(), settings.modes, ni)?;
        (Psi, Phi_i, omega)
    };
    let m = omega.len();
    let n = nb + m;
    // V on the free dofs, in the free-dof order of the FE model.
    let mut V = Mat::<f64>::zeros(n_free, n);
    for (b, &d) in p.boundary.iter().enumerate() {
        V[(d, b)] = 1.0;
    }
    for (i, &d) in p.internal.iter().enumerate() {
        for c in 0..nb {
            V[(d, c)] = Psi[(i, c)];
        }
        for c in 0..m {
            V[(d, nb + c)] = Phi_i[(i, c)];
        }
    }
    let KV = &a.K * &V;
    let MV = &a.M * &V;
    let K_CB = symmetrize(V.transpose() * &KV);
    let M_CB = symmetrize(V.transpose() * &MV);

    let positions: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    // The CB basis on every node's six slots: S_full = T V (dependent slots follow their spider).
    let mut S_full = Mat::<f64>::zeros(6 * model.node_count(), n);
    for slot in 0..6 * model.node_count() {
        let (d, c) = dofs.row(slot);
        for (&dof, &coef) in d.iter().zip(c) {
            for col in 0..n {
                S_full[(slot, col)] += coef * V[(dof as usize, col)];
            }
        }
    }
    let (inertia, Phi_com) = inertia_data(model, &S_full)?;
    if let Some(aux) = auxiliary_interface {
        let x = positions[interfaces[aux].1.index()];
        let c = inertia.center_of_mass;
        let size = model.mesh.nodes.iter().map(|p| p.coords.norm()).fold(0.0f64, f64::max).max(1e-300);
        let d = ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) + (x[2] - c[2]).powi(2)).sqrt();
        // The auxiliary frame is defined at the centre of mass; a node off it by more than a
        // millionth of the body's size was placed wrongly.
        if d > 1e-6 * size {
            return Err(ReductionError::Interface {
                name: "auxiliary".into(),
                what: format!("the auxiliary node is {d:.3e} from the centre of mass {c:?}; place it at the centre of mass"),
            });
        }
    }
    Ok(ReducedBody {
        format_version: FORMAT_VERSION,
        name: name.to_string(),
        interfaces: interfaces
            .iter()
            .map(|(name, node)| InterfacePoint { name: name.clone(), node: node.0, position: positions[node.index()] })
            .collect(),
        n_modes: m,
        fixed_interface_omega: omega,
        K_CB: DenseMatrix::from_faer(K_CB.as_ref()),
        M_CB: DenseMatrix::from_faer(M_CB.as_ref()),
        inertia,
        Phi_com: DenseMatrix::from_faer(Phi_com.as_ref()),
        auxiliary_interface,
        mesh: settings.keep_mesh_shapes.then(|| MeshModes { nodes: positions, shapes: DenseMatrix::from_faer(S_full.as_ref()) }),
    })
}

/// $\frac12(\mathbf A + \mathbf A^T)$: the projections are symmetric up to round-off; make
/// them exactly so for the eigen- and Cholesky solvers downstream.
fn symmetrize(A: Mat<f64>) -> Mat<f64> {
    Mat::from_fn(A.nrows(), A.ncols(), |i, j| 0.5 * (A[(i, j)] + A[(j, i)]))
}

/// The fixed-interface modes by count or cut-off frequency, with their circular frequencies.
fn fixed_interface_modes(
    factor: &ShiftInvert,
    K_ii: SparseColMatRef<'_, usize, f64>,
    M_ii: SparseColMatRef<'_, usize, f64>,
    selection: ModeSelection,
    ni: usize,
) -> Result<(Mat<f64>, Vec<f64>), ReductionError> {
    let solve = |m: usize| factor.lowest_modes(K_ii, M_ii, &EigenSettings::new(m, Shift::Zero));
    let to_omega = |lambda: &[f64]| lambda.iter().map(|l| l.max(0.0).sqrt()).collect::<Vec<f64>>();
    match selection {
        ModeSelection::StaticOnly => Ok((Mat::zeros(ni, 0), Vec::new())),
        ModeSelection::Count(0) => Ok((Mat::zeros(ni, 0), Vec::new())),
        ModeSelection::Count(m) => {
            if m >= ni {
                return Err(ReductionError::InvalidModeCount { requested: m, n: ni });
            }
            let s = solve(m)?;
            Ok((s.vectors, to_omega(&s.eigenvalues)))
        }
        ModeSelection::CutoffHz(f) => {
            if !(f > 0.0 && f.is_finite()) {
                return Err(ReductionError::InvalidSettings { what: format!("cut-off frequency must be positive, got {f} Hz") });
            }
            let cutoff = 2.0 * std::f64::consts::PI * f;
            // Ask for more modes until one lies above the cut-off (or the model runs out).
            let mut m = 8.min(ni.saturating_sub(1));
            loop {
                if m == 0 {
                    return Ok((Mat::zeros(ni, 0), Vec::new()));
                }
                let s = solve(m)?;
                let omega = to_omega(&s.eigenvalues);
                let keep = omega.iter().take_while(|&&w| w <= cutoff).count();
                if keep < m || m + 1 >= ni {
                    return Ok((s.vectors.subcols(0, keep).to_owned(), omega[..keep].to_vec()));
                }
                m = (2 * m).min(ni - 1);
            }
        }
    }
}
