//! Recovery of the deformed FE mesh from the state: every node at
//! $\mathbf r_j + \mathbf R_j(\mathbf x - \mathbf x_{P_j} + \mathbf S_t\mathbf q^{jj})$ with the CB shapes
//! of `ReducedBody::mesh` (translation slots), and, for nodes with rotation slots (beams,
//! spider nodes), orientation $\mathbf R_j\exp(\mathbf S_r\mathbf q^{jj})$; and the stresses
//! $\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q^{jj}$ from the stress shapes of
//! `ReducedBody::stress` (body axes: the floating frame carries the rigid motion, which adds
//! no stress).

#![allow(non_snake_case)]

use crate::body::{BodyState, Superelement};
use crate::so3;
use crate::transform::Kinematics;
use nalgebra::{UnitQuaternion, Vector3};

/// The deformed mesh of one body.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshState {
    /// Absolute node positions.
    pub positions: Vec<Vector3<f64>>,
    /// Displacements from the FE reference positions, in inertial axes
    /// (positions minus reference coordinates; includes the rigid motion).
    pub displacements: Vec<Vector3<f64>>,
    /// Absolute node orientations (identity rotation slots give $\mathbf R_j$).
    pub orientations: Vec<UnitQuaternion<f64>>,
    /// Elastic displacement of each node in body axes, $\mathbf S_t\mathbf q^{jj}$ (for stress recovery).
    pub elastic: Vec<Vector3<f64>>,
}

/// The stresses of one body, in body axes.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyStress {
    /// Solid stresses at the mesh nodes, Voigt order $[xx, yy, zz, xy, yz, zx]$; `None` at nodes
    /// without a solid element (empty for a body without solids).
    pub nodal: Vec<Option<[f64; 6]>>,
    /// Section forces $[N, V_y, V_z, T, M_y, M_z]$ at both ends of every beam of
    /// `StressShapes::beams`.
    pub beams: Vec<[[f64; 6]; 2]>,
}

impl Superelement {
    /// The stress shapes, when the body was reduced with them.
    pub fn stress_shapes(&self) -> Option<&reduction::StressShapes> {
        self.body.stress.as_ref()
    }

    /// The stresses for elastic coordinates $\mathbf q^{jj}$ (those of a [`Kinematics`]), or
    /// `None` when the body has no stress shapes.
    ///
    /// # Panics
    /// If `q_jj` does not have $n$ entries (a caller's bug).
    pub fn recover_stress(&self, q_jj: &[f64]) -> Option<BodyStress> {
        let shapes = self.body.stress.as_ref()?;
        Some(BodyStress {
            nodal: shapes.nodal_stress(q_jj),
            beams: shapes.beam_section_forces(q_jj),
        })
    }

    /// The deformed mesh for the configuration `kin`, or `None` when the reduced body was
    /// saved without mesh shapes.
    ///
    /// Checked by `tests/unit/recovery.rs` (interface nodes land on the interface positions;
    /// a rigid motion moves the mesh rigidly).
    pub fn recover_mesh(&self, kin: &Kinematics) -> Option<MeshState> {
        let mesh = self.body.mesh.as_ref()?;
        let S = &mesh.shapes;
        let n = self.n;
        let q = &kin.q_jj;
        let mut out = MeshState {
            positions: Vec::with_capacity(mesh.nodes.len()),
            displacements: Vec::with_capacity(mesh.nodes.len()),
            orientations: Vec::with_capacity(mesh.nodes.len()),
            elastic: Vec::with_capacity(mesh.nodes.len()),
        };
        for (i, x) in mesh.nodes.iter().enumerate() {
            let mut w = [0.0; 6];
            for (slot, wk) in w.iter_mut().enumerate() {
                *wk = (0..n).map(|j| S.get(6 * i + slot, j) * q[j]).sum();
            }
            let x = Vector3::from(*x);
            let u = Vector3::new(w[0], w[1], w[2]);
            let p = kin.frame.r + kin.R_j * (x - self.origin + u);
            out.positions.push(p);
            out.displacements.push(p - x);
            out.orientations
                .push(kin.frame.R * so3::exp(&Vector3::new(w[3], w[4], w[5])));
            out.elastic.push(u);
        }
        Some(out)
    }

    /// The velocity of every mesh node for the configuration `kin` of `state` (whose
    /// interface velocities and $\dot{\boldsymbol\eta}$ are used), or `None` without mesh
    /// shapes: $\mathbf v_p = \mathbf v_j + \boldsymbol\omega_j\times(\mathbf p - \mathbf r_j) +
    /// \mathbf R_j\mathbf S(\mathbf x)\dot{\mathbf q}^{jj}$ (the time derivative of theory guide
    /// (10.1), frame velocity from (5.4), elastic velocity from (5.5)).
    ///
    /// Checked by `tests/unit/recovery.rs` against central differences of positions along a
    /// motion.
    pub fn recover_mesh_velocities(&self, kin: &Kinematics, state: &BodyState) -> Option<Vec<Vector3<f64>>> {
        let mesh = self.body.mesh.as_ref()?;
        let S = &mesh.shapes;
        let n = self.n;
        let positions = self.recover_mesh(kin)?.positions;
        let (v_j, omega_j) = self.frame_velocity(kin, state);
        let qd = self.local_velocity(kin, state);
        Some(
            positions
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let mut w = [0.0; 3];
                    for (slot, wk) in w.iter_mut().enumerate() {
                        *wk = (0..n).map(|j| S.get(6 * i + slot, j) * qd[j]).sum();
                    }
                    v_j + omega_j.cross(&(p - kin.frame.r)) + kin.R_j * Vector3::from(w)
                })
                .collect(),
        )
    }
}
