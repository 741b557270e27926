//! [`ReducedBody`]: everything the superelement needs from a Craig-Bampton reduction, as a
//! versioned file (like Adams' MNF or Simpack's SID): reduced once, reused by many studies.
//!
//! # Coordinates
//!
//! The CB coordinates of a body with $N$ interfaces and $m$ fixed-interface modes are
//! $\mathbf q^{jj} = [\mathbf u_1, \boldsymbol\theta_1, \dots, \mathbf u_N,
//! \boldsymbol\theta_N, \boldsymbol\eta]$, $n = 6N + m$ entries: the interface
//! displacements and rotations (static, constraint modes) followed by the modal amplitudes
//! (dynamic, fixed-interface modes). All vectors are in the FE model's axes, which are the
//! body axes of the undeformed body.
//!
//! # Mass-field invariants
//!
//! With the displacement field of the body $\mathbf u(\mathbf x) = \mathbf S(\mathbf x)
//! \mathbf q^{jj}$ ($\mathbf S = \mathbf N \mathbf V$: the FE shape functions times the CB
//! basis), the floating-frame mass matrix needs volume integrals of $\rho$ times products of
//! $\mathbf x$ and $\mathbf S$ (Shabana, *Dynamics of Multibody Systems*, ch. 5). They are
//! computed from the consistent FE mass matrix: $\int \rho\, \mathbf f^T \mathbf g\, dV =
//! \mathbf f^T \mathbf M \mathbf g$ for fields interpolated by the shape functions.
//! Positions $\mathbf x$ are measured from the centre of mass.

#![allow(non_snake_case)]

use serde::{Deserialize, Serialize};

/// Version of the reduced-body format this build writes (it also reads versions 1 and 2).
/// 2: the optional geometric stiffness arrays. 3: the optional stress shapes
/// ([`ReducedBody::stress`]) and the load points of static correction
/// ([`ReducedBody::load_points`]).
pub const FORMAT_VERSION: u32 = 3;

/// The first bytes of every reduced-body file, followed by a space and the format version.
pub const MAGIC: &str = "FLEXMBS-RBODY";

/// The oldest format version this build reads.
pub(crate) const OLDEST_READABLE: u32 = 1;

/// Revision of the algorithms that compute a [`ReducedBody`], bumped whenever a change can
/// change a body computed from the same input (not only its file format): caches of reduced
/// bodies (the CLI's) key on it. 2: the automatic eigensolver block size is never 1
/// ([`crate::eigen::SMALL_BLOCK_SIZE`]), which finds repeated eigenvalues that single vectors missed.
/// 3: the dense eigensolvers inside Lanczos run on scaled matrices
/// ([`fe_model::scaled_self_adjoint_eigen`]), which made many-mode reductions converge.
pub const ALGORITHM_REVISION: u32 = 3;

/// A dense matrix as plain data (column-major), for files; convert to `faer::Mat` to compute.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DenseMatrix {
    pub nrows: usize,
    pub ncols: usize,
    /// Column-major values, `nrows * ncols` of them.
    pub data: Vec<f64>,
}

impl DenseMatrix {
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            data: vec![0.0; nrows * ncols],
        }
    }

    pub fn from_faer(m: faer::MatRef<'_, f64>) -> Self {
        let mut data = Vec::with_capacity(m.nrows() * m.ncols());
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                data.push(m[(i, j)]);
            }
        }
        Self {
            nrows: m.nrows(),
            ncols: m.ncols(),
            data,
        }
    }

    pub fn to_faer(&self) -> faer::Mat<f64> {
        faer::Mat::from_fn(self.nrows, self.ncols, |i, j| self.data[i + j * self.nrows])
    }

    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i + j * self.nrows]
    }
}

/// One interface of a reduced body: a 6-dof point whose coordinates are CB coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InterfacePoint {
    pub name: String,
    /// The FE node (index into the FE model's nodes) of the interface.
    pub node: u32,
    /// Undeformed position $\mathbf x_k$ in body axes (the FE model's coordinates).
    pub position: [f64; 3],
    /// The node's number in the mesh file the part was read from, when the interface sits on a
    /// node of that file; `None` for generated meshes and for nodes the program added (spider
    /// and auxiliary nodes), which have no number in a file. Absent from files without labels,
    /// so that bodies without labels keep their bytes and older files read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node_label: Option<u64>,
}

/// Rigid-body inertia and the mass-field invariants of the modes (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InertiaData {
    /// Total mass $m = \int \rho\, dV$.
    pub mass: f64,
    /// Centre of mass of the undeformed body, FE coordinates.
    pub center_of_mass: [f64; 3],
    /// Inertia tensor about the centre of mass, $\int \rho (\mathbf x^T \mathbf x \mathbf 1 -
    /// \mathbf x \mathbf x^T) dV$ (with the sections' rotary inertia for beams), row-major.
    pub inertia_com: [[f64; 3]; 3],
    /// $3 \times n$: $\int \rho\, \mathbf S\, dV$ (translational participation).
    pub S_t: DenseMatrix,
    /// $3 \times n$: $\int \rho\, \tilde{\mathbf x} \mathbf S\, dV$ about the centre of mass,
    /// rotary inertia of beam sections included (rotational participation).
    pub S_r: DenseMatrix,
    /// $9 \times n$: row $3k + l$ is $\int \rho\, x_k \mathbf S_l\, dV$ ($\mathbf S_l$: row $l$
    /// of $\mathbf S$), $\mathbf x$ from the centre of mass.
    pub S_x: DenseMatrix,
    /// Nine $n \times n$ matrices: entry $3k + l$ is $\bar{\mathbf S}_{kl} = \int \rho\,
    /// \mathbf S_k^T \mathbf S_l\, dV$ (translational field only; the rotary inertia of beam
    /// sections enters $\mathbf M_{CB}$ but not these second-order terms).
    pub S_bar: Vec<DenseMatrix>,
}

/// Mode shapes on every FE node, for output and recovery of the deformed mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshModes {
    /// Reference coordinates of the FE nodes.
    pub nodes: Vec<[f64; 3]>,
    /// $6 n_{nodes} \times n$: the CB basis on every node's six dof slots (zero where a slot
    /// is inactive or supported).
    pub shapes: DenseMatrix,
}

/// The stress of every CB vector (column $k$: the stress field of $\mathbf V\mathbf e_k$),
/// so that a body's stresses are $\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q^{jj}$ for
/// elastic coordinates $\mathbf q^{jj}$ ([`fe_model::stress`] for the recovery on the
/// elements: solid stresses extrapolated from the integration points and averaged at the
/// nodes; beam section forces at the element ends).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StressShapes {
    /// $6 n_{nodes} \times n$ (row $6i + c$: Voigt component $c$, order $[xx, yy, zz, xy, yz,
    /// zx]$, of mesh node $i$), body axes; `None` when the body has no solid elements. Zero at
    /// nodes no solid element contains ([`StressShapes::solid_node`]).
    pub nodal: Option<DenseMatrix>,
    /// Whether each mesh node carries a solid stress (empty when `nodal` is `None`).
    pub solid_node: Vec<bool>,
    /// The beam elements, in the order of the rows of `beam_forces`.
    pub beams: Vec<BeamStressElement>,
    /// $12 n_{beams} \times n$: section forces $[N, V_y, V_z, T, M_y, M_z]$ (element axes) at
    /// end 1 (rows $12b..12b+6$) and end 2 ($12b+6..12b+12$) of beam $b$.
    pub beam_forces: DenseMatrix,
}

impl StressShapes {
    /// Solid stresses at the mesh nodes for CB coordinates `q` ($n$ values):
    /// $\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q$, `None` at nodes without a solid
    /// element and for a body without solids. Column by column (axpy on contiguous columns).
    ///
    /// # Panics
    /// If `q` does not have one value per column (a caller's bug).
    pub fn nodal_stress(&self, q: &[f64]) -> Vec<Option<[f64; 6]>> {
        let Some(S) = &self.nodal else {
            return Vec::new();
        };
        let sigma = combine(S, q);
        self.solid_node
            .iter()
            .enumerate()
            .map(|(i, &solid)| solid.then(|| sigma[6 * i..6 * i + 6].try_into().expect("6 components")))
            .collect()
    }

    /// Section forces $[N, V_y, V_z, T, M_y, M_z]$ at both ends of every beam of
    /// [`StressShapes::beams`] for CB coordinates `q`.
    ///
    /// # Panics
    /// If `q` does not have one value per column (a caller's bug).
    pub fn beam_section_forces(&self, q: &[f64]) -> Vec<[[f64; 6]; 2]> {
        let f = combine(&self.beam_forces, q);
        f.chunks_exact(12)
            .map(|c| {
                let mut s = [[0.0; 6]; 2];
                s[0].copy_from_slice(&c[..6]);
                s[1].copy_from_slice(&c[6..]);
                s
            })
            .collect()
    }
}

/// $\mathbf A\mathbf q$ for a column-major `A`.
pub(crate) fn combine(A: &DenseMatrix, q: &[f64]) -> Vec<f64> {
    assert_eq!(q.len(), A.ncols, "one coordinate per column");
    let mut out = vec![0.0; A.nrows];
    for (j, &qj) in q.iter().enumerate() {
        if qj != 0.0 {
            for (o, a) in out.iter_mut().zip(&A.data[j * A.nrows..(j + 1) * A.nrows]) {
                *o += a * qj;
            }
        }
    }
    out
}

/// A beam element of a body with stress shapes: its FE index and nodes, and its section
/// (for the extreme-fibre stresses, [`fe_model::BeamSection::fibre_stress_range`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamStressElement {
    pub element: u32,
    pub nodes: [u32; 2],
    pub section: fe_model::BeamSection,
}

/// A named point where loads act inside the body, with the static correction that makes the
/// quasi-static response to them exact: the reduction appends attachment modes for its dofs
/// (module [`crate::attachment`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoadPoint {
    pub name: String,
    /// The FE node (index into the FE model's nodes).
    pub node: u32,
    /// Undeformed position in body axes.
    pub position: [f64; 3],
    /// $6 \times n$: the CB basis at the node's six dof slots (zero rows for the slots a
    /// solid node does not have), so that a force $\mathbf f$ and moment $\mathbf m$ (body
    /// axes) at the point do the virtual work $\delta\mathbf q^T\mathbf S_p^T[\mathbf f;
    /// \mathbf m]$.
    pub shape: DenseMatrix,
}

/// A Craig-Bampton reduced body: the data the AIC-FFR superelement reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReducedBody {
    pub format_version: u32,
    pub name: String,
    /// Interfaces in the order of the CB coordinates.
    pub interfaces: Vec<InterfacePoint>,
    /// Number $m$ of fixed-interface (dynamic) modes.
    pub n_modes: usize,
    /// Circular frequencies \[rad/s\] of the kept fixed-interface modes, ascending.
    pub fixed_interface_omega: Vec<f64>,
    /// $\mathbf K_{CB} = \mathbf V^T \mathbf K \mathbf V$, $n \times n$.
    pub K_CB: DenseMatrix,
    /// $\mathbf M_{CB} = \mathbf V^T \mathbf M \mathbf V$, $n \times n$.
    pub M_CB: DenseMatrix,
    pub inertia: InertiaData,
    /// $6 \times n$: the CB modes evaluated at the centre of mass by the mass-weighted rigid
    /// fit $(\boldsymbol\Phi_R^T \mathbf M \boldsymbol\Phi_R)^{-1} \boldsymbol\Phi_R^T \mathbf M
    /// \mathbf V$ (theory guide §4), rows: translation, then rotation.
    pub Phi_com: DenseMatrix,
    /// Index of the auxiliary interface at the centre of mass, when the body was reduced with
    /// one (the third frame choice).
    pub auxiliary_interface: Option<usize>,
    /// Mode shapes on the mesh, when kept.
    pub mesh: Option<MeshModes>,
    /// Geometric stiffening (optional): $n$ matrices
    /// $\mathbf G_k = \mathbf V^T\mathbf K_G(\boldsymbol\sigma(\mathbf V\mathbf e_k))\mathbf V$
    /// ($n \times n$, symmetric), the reduced geometric stiffness of the stress field of CB
    /// coordinate $k$ ([`crate::geometric`]), so the strain energy gains the cubic term
    /// $U_3 = \tfrac12 \sum_k q_k\, \mathbf q^T \mathbf G_k \mathbf q$ (the second-order part of
    /// the Green-Lagrange strain under the linear stress). `None`: linear elastic field.
    #[serde(default)]
    pub geometric_stiffness: Option<Vec<DenseMatrix>>,
    /// The stress of every CB vector, when kept (optional, like the mesh shapes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stress: Option<StressShapes>,
    /// Load points with static correction; the last [`ReducedBody::attachment_modes`] of the
    /// `n_modes` modes are their attachment modes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub load_points: Vec<LoadPoint>,
    /// How many of the `n_modes` modes (the last ones) are static correction vectors (the
    /// attachment modes of the load points, and with [`CbSettings::inertia_correction`](crate::CbSettings)
    /// those of the constraint modes' inertia) rather than fixed-interface eigenmodes; their
    /// entries of `fixed_interface_omega` are their Rayleigh frequencies.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub attachment_modes: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl ReducedBody {
    /// Number of CB coordinates $n = 6N + m$.
    pub fn n_coordinates(&self) -> usize {
        6 * self.interfaces.len() + self.n_modes
    }
}
