//! [`Superelement`]: one AIC-FFR body built from a [`ReducedBody`], and its state
//! [`BodyState`]. The entry points are [`Superelement::solve_frame`],
//! [`Superelement::kinematics`] and [`Superelement::evaluate`].

#![allow(non_snake_case)]

use crate::compressed::{Compressed, COMPRESSED_SHARE};
use crate::error::SuperelementError;
use crate::frame::{FrameProblem, FrameScratch, FrameSettings, FrameSolve};
use crate::local_coordinates::local_coordinates;
use crate::mass::{FfrInertia, MassVariant};
use crate::planar::{angle_of, rotation_z, wrap, Buf, PlanarBody, Solved2, STATE_TOL};
pub use crate::state::BodyState;
use crate::state::{Frame, FrameChoice};
use crate::transform::Kinematics;
use crate::transform::{inverse_with_rcond, phi_j_psi, RCOND_MIN};
use faer::Mat;
use nalgebra::{Matrix3, Vector3};
use reduction::ReducedBody;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Damping of the elastic coordinates, acting on the elastic velocity $\dot{\mathbf q}^{jj} =
/// \mathbf T_j\boldsymbol\Lambda\bar{\mathbf R}^T\dot{\mathbf q}$:
/// $\mathbf D = \alpha\mathbf M_{CB} + \beta\mathbf K_{CB} + \mathrm{diag}_\eta(2\zeta_i\omega_i m_{ii})$.
///
/// $m_{ii}$ is the modal mass of fixed-interface mode $i$ (the $\eta$ diagonal of
/// $\mathbf M_{CB}$; 1 for mass-normalised modes), $\omega_i$ its circular frequency
/// (`ReducedBody::fixed_interface_omega`). Rigid motion is never damped: $\dot{\mathbf q}^{jj}$
/// excludes it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Damping {
    /// Rayleigh mass factor $\alpha$ \[1/s\].
    pub alpha: f64,
    /// Rayleigh stiffness factor $\beta$ \[s\].
    pub beta: f64,
    /// Damping ratio $\zeta_i$ of each fixed-interface mode (empty: none; else one per mode).
    pub modal_ratios: Vec<f64>,
}

impl Damping {
    /// No damping.
    pub fn none() -> Self {
        Self::default()
    }

    /// Rayleigh damping $\alpha\mathbf M_{CB} + \beta\mathbf K_{CB}$.
    pub fn rayleigh(alpha: f64, beta: f64) -> Self {
        Self {
            alpha,
            beta,
            modal_ratios: Vec::new(),
        }
    }
}

/// One AIC-FFR superelement: everything precomputed from a [`ReducedBody`] that does not depend
/// on the state.
#[derive(Clone, Debug)]
pub struct Superelement {
    pub(crate) name: String,
    pub(crate) n_interfaces: usize,
    pub(crate) n_modes: usize,
    pub(crate) n: usize,
    pub(crate) frame_choice: FrameChoice,
    pub(crate) frame_solve: FrameSolve,
    pub(crate) mass_variant: MassVariant,
    /// FE coordinates of the frame origin $P_j$.
    pub(crate) origin: Vector3<f64>,
    /// Undeformed interface positions from $P_j$, body axes.
    pub(crate) x: Vec<Vector3<f64>>,
    /// $\boldsymbol\Phi_j$, $6\times n$ (4.4).
    pub(crate) Phi_j: Mat<f64>,
    pub(crate) K_CB: Mat<f64>,
    pub(crate) M_CB: Mat<f64>,
    /// Damping matrix $\mathbf D$ on $\dot{\mathbf q}^{jj}$ ([`Damping`]).
    pub(crate) D: Mat<f64>,
    pub(crate) damped: bool,
    pub(crate) inertia: FfrInertia,
    /// Body size $L$ for the frame tolerance.
    pub(crate) length: f64,
    pub(crate) frame_settings: FrameSettings,
    /// The reduced body it was built from, shared, not copied: its mesh shapes
    /// ([`Superelement::recover_mesh`]) and the stress of every CB vector
    /// ([`Superelement::recover_stress`]) are the largest data of a body.
    pub(crate) body: Arc<ReducedBody>,
    /// Geometric stiffening $\mathbf G_k$ ([`GeometricStiffness`]); `None`: a linear elastic field.
    pub(crate) geometric: Option<GeometricStiffness>,
    /// The in-plane data of a planar body ([`Self::into_planar`]); `None`: a spatial body.
    pub(crate) planar: Option<Arc<crate::planar::PlanarBody>>,
}

/// The reduced geometric stiffness of a body: $n$ symmetric matrices $\mathbf G_k$ ($n\times n$),
/// the geometric stiffness of the linear stress field of CB coordinate $k$, and the strain energy
/// it gives the body in its floating frame ($\mathbf q = \mathbf q^{jj}$):
///
/// $$U = \tfrac12\mathbf q^T\mathbf K_{CB}\mathbf q + U_3 + U_4,\qquad
/// U_3 = \tfrac12\sum_k q_k\,\mathbf q^T\mathbf G_k\mathbf q,\qquad
/// U_4 = \tfrac12\mathbf b^T\mathbf F\mathbf b,\quad b_m = \tfrac12\mathbf q^T\mathbf G_m\mathbf q,$$
///
/// $\mathbf F = \mathbf K_{CB}^+$ (the crate docs, "Geometric stiffening", derive $U_4$ and say why
/// it is needed). Built from [`ReducedBody::geometric_stiffness`] by [`Superelement::new`], which
/// checks the count ($n$), the shapes ($n\times n$), finiteness and symmetry and stores the
/// symmetric part (so the Hessian is exactly symmetric). The force, tangent and energy terms
/// are in [`crate::forces`] (`GeometricStiffness::gradient_into`, `::energy`).
#[derive(Clone, Debug)]
pub struct GeometricStiffness {
    /// $n$.
    pub(crate) n: usize,
    /// The $\mathbf G_k$ stacked column-major, $(\mathbf G_k)_{ij}$ at $i + nj + n^2k$: as an $n^2\times n$
    /// matrix its column $k$ is $\mathrm{vec}\,\mathbf G_k$, so $\mathrm{vec}\sum_k w_k\mathbf G_k$ is one
    /// matrix-vector product (`forces.rs`).
    pub(crate) stack: Vec<f64>,
    /// The same entries with $j$ and $k$ swapped, $(\mathbf G_k)_{ij}$ at $(i + nk) + n^2j$: as an
    /// $n^2\times n$ matrix times $\mathbf q$ it gives $\mathrm{vec}[\mathbf G_0\mathbf q, \dots,
    /// \mathbf G_{n-1}\mathbf q]$, again a column-major product. Computing that from `stack` needs a
    /// transposed (row-major) operand, which faer multiplies through a packing path: 9k more
    /// instructions per evaluation at $n = 14$, 77k at $n = 72$ (`benches/evaluate.rs`). The price is
    /// a second copy of the $n^3$ entries (8 MB more at $n = 100$).
    pub(crate) stack_t: Vec<f64>,
    /// $\mathbf F = \mathbf K_{CB}^+$, the pseudo-inverse on the complement of the rigid modes.
    pub(crate) F: Mat<f64>,
    /// The nonzero $\mathbf G_k$ with their $k$, by their nonzero entries ([`Compressed`]).
    pub(crate) nonzero: Vec<(usize, Compressed)>,
    /// Use `nonzero` instead of `stack`, `stack_t`: set when the compressed matrices hold at
    /// most [`COMPRESSED_SHARE`] of the $n^3$ entries, where their scalar loops beat the two
    /// dense products (a straight beam along a body axis: 2 of 14 $\mathbf G_k$ nonzero).
    pub(crate) compressed: bool,
}

impl GeometricStiffness {
    /// $\mathbf G_k$ ($k < n$).
    pub fn matrix(&self, k: usize) -> faer::MatRef<'_, f64> {
        let n = self.n;
        faer::MatRef::from_column_major_slice(&self.stack[n * n * k..n * n * (k + 1)], n, n)
    }
    /// $\mathbf F = \mathbf K_{CB}^+$.
    pub fn compliance(&self) -> &Mat<f64> {
        &self.F
    }
}

fn invalid(body: &ReducedBody, what: impl Into<String>) -> SuperelementError {
    SuperelementError::InvalidBody {
        body: body.name.clone(),
        what: what.into(),
    }
}

fn check_dense(
    body: &ReducedBody,
    name: &str,
    m: &reduction::DenseMatrix,
    rows: usize,
    cols: usize,
) -> Result<(), SuperelementError> {
    if m.nrows != rows || m.ncols != cols || m.data.len() != rows * cols {
        return Err(invalid(
            body,
            format!(
                "{name} is {} x {} ({} values), expected {rows} x {cols}",
                m.nrows,
                m.ncols,
                m.data.len()
            ),
        ));
    }
    if let Some(i) = m.data.iter().position(|v| !v.is_finite()) {
        return Err(invalid(
            body,
            format!(
                "{name} has a non-finite entry at ({}, {})",
                i % rows.max(1),
                i / rows.max(1)
            ),
        ));
    }
    Ok(())
}

/// Relative asymmetry $|G_{ij} - G_{ji}|$ accepted in a $\mathbf G_k$, against its largest entry:
/// a projection $\mathbf V^T\mathbf K_\sigma\mathbf V$ in floating point is symmetric to about
/// $n\,\epsilon$; a transposed or wrongly assembled matrix is off by O(1).
const G_SYMMETRY_TOL: f64 = 1e-8;

/// Checks [`ReducedBody::geometric_stiffness`] (module docs of [`GeometricStiffness`]).
fn geometric_stiffness(body: &ReducedBody, n: usize) -> Result<Option<GeometricStiffness>, SuperelementError> {
    let Some(list) = &body.geometric_stiffness else {
        return Ok(None);
    };
    if list.len() != n {
        return Err(invalid(
            body,
            format!(
                "geometric_stiffness has {} matrices G_k, expected one per CB coordinate ({n})",
                list.len()
            ),
        ));
    }
    let mut G: Vec<Mat<f64>> = Vec::with_capacity(n);
    for (k, Gk) in list.iter().enumerate() {
        let name = format!("geometric stiffness G[{k}]");
        check_dense(body, &name, Gk, n, n)?;
        let Gk = Gk.to_faer();
        let big = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .map(|(i, j)| Gk[(i, j)].abs())
            .fold(0.0, f64::max);
        for j in 0..n {
            for i in 0..j {
                let (a, b) = (Gk[(i, j)], Gk[(j, i)]);
                if (a - b).abs() > G_SYMMETRY_TOL * big {
                    return Err(invalid(
                        body,
                        format!("{name} is not symmetric: ({i}, {j}) = {a:e} but ({j}, {i}) = {b:e}"),
                    ));
                }
            }
        }
        G.push(Mat::from_fn(n, n, |i, j| 0.5 * (Gk[(i, j)] + Gk[(j, i)])));
    }
    // Without their round-off zeros (`compressed` module docs), if that leaves them sparse
    // enough for the compressed products; else as they are.
    let c = crate::compressed::coordinate_weights(body);
    let mut cleaned = G.clone();
    crate::compressed::clean(&mut cleaned.iter_mut().collect::<Vec<_>>(), |k, i, j| {
        c[i] * c[j] * c[k]
    });
    let nonzero: Vec<(usize, Compressed)> = cleaned
        .iter()
        .enumerate()
        .map(|(k, Gk)| (k, Compressed::new(Gk.as_ref())))
        .filter(|(_, Gk)| !Gk.is_zero())
        .collect();
    let stored: usize = nonzero.iter().map(|(_, G)| G.stored()).sum();
    let compressed = (stored as f64) <= COMPRESSED_SHARE * (n * n * n) as f64;
    if compressed {
        G = cleaned;
    }
    let mut stack = Vec::with_capacity(n * n * n);
    for Gk in &G {
        for j in 0..n {
            stack.extend_from_slice(Gk.col_as_slice(j));
        }
    }
    let mut stack_t = vec![0.0; n * n * n];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                stack_t[i + n * k + n * n * j] = stack[i + n * j + n * n * k];
            }
        }
    }
    let F = rigid_pseudo_inverse(body, n)?;
    Ok(Some(GeometricStiffness {
        n,
        stack,
        stack_t,
        F,
        nonzero,
        compressed,
    }))
}

/// $\mathbf K_{CB}^+$ of a free body: $(\mathbf K_{CB} + \alpha\mathbf P_{rig})^{-1} - \mathbf P_{rig}/\alpha$ with
/// $\mathbf P_{rig} = \boldsymbol\Phi_{rig}(\boldsymbol\Phi_{rig}^T\boldsymbol\Phi_{rig})^{-1}\boldsymbol\Phi_{rig}^T$
/// the projector on the rigid modes (5.2) of the undeformed interface set and $\alpha$ the mean
/// diagonal of $\mathbf K_{CB}$ (the null space of $\mathbf K_{CB}$ is exactly the rigid modes; the
/// Moore-Penrose inverse, checked by `tests/unit/geometric.rs::compliance_is_the_pseudo_inverse_of_k_cb`).
fn rigid_pseudo_inverse(body: &ReducedBody, n: usize) -> Result<Mat<f64>, SuperelementError> {
    use faer::linalg::solvers::DenseSolveCore;
    let x: Vec<Vector3<f64>> = body.interfaces.iter().map(|i| Vector3::from(i.position)).collect();
    let R = crate::transform::phi_rig(&x, body.n_modes);
    let RtR = R.transpose() * &R;
    let RtR_inv = RtR.partial_piv_lu().inverse();
    let P = &R * &RtR_inv * R.transpose();
    let K = body.K_CB.to_faer();
    let alpha = (0..n).map(|i| K[(i, i)].abs()).sum::<f64>() / n as f64;
    let A = Mat::from_fn(n, n, |i, j| K[(i, j)] + alpha * P[(i, j)]);
    let F = A.partial_piv_lu().inverse();
    if F.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Err(invalid(
            body,
            "K_CB has a null space beyond the six rigid motions: the geometric stiffening needs its pseudo-inverse",
        ));
    }
    // (K + alpha P)^-1 = K^+ + P / alpha (P projects on the null space of K).
    Ok(Mat::from_fn(n, n, |i, j| {
        0.5 * (F[(i, j)] + F[(j, i)]) - P[(i, j)] / alpha
    }))
}

impl Superelement {
    /// The same body evaluated as a planar one, in its FE model's xy-plane: 3 coordinates per
    /// interface instead of 6, the out-of-plane rows and columns of every output zero
    /// ([`crate::planar`]). Every method keeps its signature and the $6N + m$ layout; the planar
    /// kernel reads x, y of $\mathbf r_k$, $\mathbf v_k$, the angle about z of $\mathbf R_k$ and
    /// $\omega_z$ (the out-of-plane velocity and acceleration components are not read), and each
    /// evaluation checks that the state lies in the plane.
    ///
    /// # Errors
    /// [`SuperelementError::NotPlanar`], naming the interface, mode or matrix, when the body's
    /// interfaces and frame origin are not in one plane z = const, a reduced matrix ($\mathbf K_{CB}$,
    /// $\mathbf M_{CB}$, $\boldsymbol\Phi_j$, the inertia invariants $\mathbf S_t$, $\mathbf S_r$,
    /// $\mathbf S_x$, the $\mathbf G_k$) couples the in-plane coordinates with the out-of-plane
    /// ones by more than [`crate::planar::COUPLING_TOL`] of its largest entry (a mode out of the
    /// plane, an unsupported internal out-of-plane dof, a beam whose section axes are not the
    /// plane's), the inertia is `Lumped` or the frame is the auxiliary node.
    pub fn into_planar(mut self) -> Result<Self, SuperelementError> {
        if self.planar.is_none() {
            let input = crate::planar::PlanarInput {
                name: &self.name,
                body: &self.body,
                n_interfaces: self.n_interfaces,
                n_modes: self.n_modes,
                n: self.n,
                frame_choice: self.frame_choice,
                mass_variant: self.mass_variant,
                origin: self.origin,
                x: &self.x,
                length: self.length,
                K_CB: &self.K_CB,
                M_CB: &self.M_CB,
                D: &self.D,
                damped: self.damped,
                Phi_j: &self.Phi_j,
                inertia: &self.inertia,
                geometric: self.geometric.as_ref().map(|G| crate::planar::GeometricView {
                    n: G.n,
                    stack: &G.stack,
                    F: &G.F,
                }),
            };
            self.planar = Some(Arc::new(input.build()?));
        }
        Ok(self)
    }

    /// Whether [`Self::into_planar`] made this a planar body.
    pub fn is_planar(&self) -> bool {
        self.planar.is_some()
    }

    /// Solves (4.4) $\boldsymbol\Phi_j\mathbf q^{jj}(\mathbf r_j, \mathbf R_j) = \mathbf 0$ for the frame,
    /// starting from `state.frame` (the last step's frame).
    ///
    /// # Derivation
    /// With the local frame variation $\delta\boldsymbol\Xi = [\mathbf R_j^T\delta\mathbf r_j;\
    /// \mathbf R_j^T\delta\boldsymbol\pi_j]$ and the interface coordinates held,
    /// $\delta\mathbf q^{jj} = -\boldsymbol\Lambda\boldsymbol\Phi_{rig}\delta\boldsymbol\Xi$ ((5.3) with the exact
    /// rotation factor, see [`crate::local_coordinates::elastic_rotation`]), so the Jacobian
    /// of $\mathbf g = \boldsymbol\Phi_j\mathbf q^{jj}$ is $-\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig}$
    /// and the Newton step is $\delta\boldsymbol\Xi = (\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig})^{-1}\mathbf g$,
    /// applied as $\mathbf r_j \leftarrow \mathbf r_j + \mathbf R_j\delta\boldsymbol\Xi_t$,
    /// $\mathbf R_j \leftarrow \mathbf R_j\exp(\delta\boldsymbol\Xi_r)$. The eta columns of
    /// $\boldsymbol\Phi_j$ enter $\mathbf g$ with the given $\boldsymbol\eta$. Checked by
    /// `tests/unit/fd_tangent.rs::frame_jacobian` and `tests/unit/frame.rs`.
    ///
    /// For [`FrameChoice::InterfaceNode`] and [`FrameChoice::AuxiliaryNode`] the solution is
    /// explicit, $\mathbf r_j = \mathbf r_k$, $\mathbf R_j = \mathbf R_k$.
    pub fn solve_frame(&self, state: &BodyState) -> Result<(Frame, usize), SuperelementError> {
        if self.is_planar() {
            return self.planar_solve_frame(state);
        }
        let (mut q, mut r_loc, mut Lambda) = (
            vec![0.0; self.n],
            vec![Vector3::zeros(); self.n_interfaces],
            vec![Matrix3::identity(); self.n_interfaces],
        );
        let mut scratch = FrameScratch {
            q: &mut q,
            r_loc: &mut r_loc,
            Lambda: &mut Lambda,
            last_G_inv: None,
        };
        self.solve_frame_in(state, &mut scratch)
    }

    /// [`Self::solve_frame`] with the Newton iterates in `scratch` (no allocation; the hot loop
    /// passes buffers of its workspace).
    pub(crate) fn solve_frame_in(
        &self,
        state: &BodyState,
        scratch: &mut FrameScratch<'_>,
    ) -> Result<(Frame, usize), SuperelementError> {
        self.check_state(state)?;
        let problem = FrameProblem {
            x: &self.x,
            Phi_j: self.Phi_j.as_ref(),
            length: self.length,
            settings: self.frame_settings,
            solve: self.frame_solve,
        };
        crate::frame::solve_frame_in(&problem, state, scratch)
    }

    /// Builds the superelement of `body` with the given frame, inertia variant and damping,
    /// after checking every shape the formulation relies on. It keeps a copy of `body`;
    /// [`Self::shared`] keeps a shared one.
    pub fn new(
        body: &ReducedBody,
        frame_choice: FrameChoice,
        mass_variant: MassVariant,
        damping: Damping,
    ) -> Result<Self, SuperelementError> {
        Self::shared(Arc::new(body.clone()), frame_choice, mass_variant, damping)
    }

    /// [`Self::new`] with the reduced body shared with the caller (a model holding it too).
    pub fn shared(
        shared: Arc<ReducedBody>,
        frame_choice: FrameChoice,
        mass_variant: MassVariant,
        damping: Damping,
    ) -> Result<Self, SuperelementError> {
        let body: &ReducedBody = &shared;
        let N = body.interfaces.len();
        let m = body.n_modes;
        let n = body.n_coordinates();
        if N == 0 {
            return Err(invalid(body, "a superelement needs at least one interface"));
        }
        check_dense(body, "K_CB", &body.K_CB, n, n)?;
        check_dense(body, "M_CB", &body.M_CB, n, n)?;
        check_dense(body, "Phi_com", &body.Phi_com, 6, n)?;
        let inertia = &body.inertia;
        check_dense(body, "S_t", &inertia.S_t, 3, n)?;
        check_dense(body, "S_r", &inertia.S_r, 3, n)?;
        check_dense(body, "S_x", &inertia.S_x, 9, n)?;
        if inertia.S_bar.len() != 9 {
            return Err(invalid(
                body,
                format!("S_bar has {} matrices, expected 9", inertia.S_bar.len()),
            ));
        }
        for (i, S) in inertia.S_bar.iter().enumerate() {
            check_dense(body, &format!("S_bar[{i}]"), S, n, n)?;
        }
        if !(inertia.mass > 0.0 && inertia.mass.is_finite()) {
            return Err(invalid(
                body,
                format!("the mass must be positive and finite, got {}", inertia.mass),
            ));
        }
        if body.fixed_interface_omega.len() != m {
            return Err(invalid(
                body,
                format!(
                    "{} fixed-interface frequencies for {m} modes",
                    body.fixed_interface_omega.len()
                ),
            ));
        }
        for (name, v) in [("alpha", damping.alpha), ("beta", damping.beta)] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(invalid(
                    body,
                    format!("damping {name} must be finite and >= 0, got {v}"),
                ));
            }
        }
        if !damping.modal_ratios.is_empty() && damping.modal_ratios.len() != m {
            return Err(invalid(
                body,
                format!(
                    "{} modal damping ratios for {m} fixed-interface modes",
                    damping.modal_ratios.len()
                ),
            ));
        }
        if let Some(z) = damping.modal_ratios.iter().find(|z| !(**z >= 0.0 && z.is_finite())) {
            return Err(invalid(
                body,
                format!("modal damping ratios must be finite and >= 0, got {z}"),
            ));
        }
        let positions: Vec<Vector3<f64>> = body.interfaces.iter().map(|i| Vector3::from(i.position)).collect();
        let com = Vector3::from(inertia.center_of_mass);
        let bad_choice = |what: String| SuperelementError::InvalidFrameChoice {
            body: body.name.clone(),
            choice: frame_choice.to_string(),
            what,
        };
        let (origin, frame_solve, Phi_j) = match frame_choice {
            FrameChoice::CenterOfMass => (com, FrameSolve::Newton, body.Phi_com.to_faer()),
            FrameChoice::InterfaceNode(k) => {
                if k >= N {
                    return Err(bad_choice(format!("the body has {N} interfaces (0-based index {k})")));
                }
                (positions[k], FrameSolve::AtInterface(k), selection(n, k))
            }
            FrameChoice::AuxiliaryNode => {
                let k = body
                    .auxiliary_interface
                    .ok_or_else(|| bad_choice("the body was reduced without an auxiliary interface".into()))?;
                if k >= N {
                    return Err(bad_choice(format!("auxiliary interface {k} of {N}")));
                }
                (positions[k], FrameSolve::AtInterface(k), selection(n, k))
            }
        };
        let geometric = geometric_stiffness(body, n)?;
        for lp in &body.load_points {
            check_dense(body, &format!("the shape of load point '{}'", lp.name), &lp.shape, 6, n)?;
            if !lp.position.iter().all(|x| x.is_finite()) {
                return Err(invalid(
                    body,
                    format!("load point '{}' has a non-finite position", lp.name),
                ));
            }
        }
        let x: Vec<Vector3<f64>> = positions.iter().map(|p| p - origin).collect();
        let K_CB = body.K_CB.to_faer();
        let M_CB = body.M_CB.to_faer();
        let mut D = Mat::from_fn(n, n, |i, j| damping.alpha * M_CB[(i, j)] + damping.beta * K_CB[(i, j)]);
        for (i, z) in damping.modal_ratios.iter().enumerate() {
            let c = 6 * N + i;
            D[(c, c)] += 2.0 * z * body.fixed_interface_omega[i] * M_CB[(c, c)];
        }
        let damped = damping.alpha > 0.0 || damping.beta > 0.0 || damping.modal_ratios.iter().any(|z| *z > 0.0);
        let ffr = FfrInertia::new(inertia, &origin, &M_CB);
        // Body size: farthest interface from the frame origin, or the radius of gyration for a
        // body whose only interface sits at the frame.
        let Ic = Matrix3::from_fn(|i, j| inertia.inertia_com[i][j]);
        let gyration = (Ic.trace() / (2.0 * inertia.mass)).max(0.0).sqrt();
        let length = x
            .iter()
            .map(|v| v.norm())
            .fold(gyration, f64::max)
            .max(f64::MIN_POSITIVE);
        // (5.4) must be solvable for the undeformed body.
        let G = phi_j_psi(Phi_j.as_ref(), &x, &vec![Matrix3::identity(); N]);
        match inverse_with_rcond(&G) {
            Some((_, rcond)) if rcond >= RCOND_MIN => {}
            other => {
                return Err(bad_choice(format!(
                    "Phi_j Phi_rig of the undeformed body is singular (rcond {:.3e})",
                    other.map(|o| o.1).unwrap_or(0.0)
                )))
            }
        }
        Ok(Self {
            name: body.name.clone(),
            n_interfaces: N,
            n_modes: m,
            n,
            frame_choice,
            frame_solve,
            mass_variant,
            origin,
            x,
            Phi_j,
            K_CB,
            M_CB,
            D,
            damped,
            inertia: ffr,
            length,
            frame_settings: FrameSettings::default(),
            body: Arc::clone(&shared),
            geometric,
            planar: None,
        })
    }

    /// The reduced body the superelement was built from (shared with the model that holds it).
    pub fn reduced_body(&self) -> &Arc<ReducedBody> {
        &self.body
    }

    /// Replaces the settings of the frame solve.
    pub fn with_frame_settings(mut self, settings: FrameSettings) -> Self {
        self.frame_settings = settings;
        self
    }

    /// Body name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Number of interfaces $N$.
    pub fn n_interfaces(&self) -> usize {
        self.n_interfaces
    }
    /// Number of fixed-interface modes $m$.
    pub fn n_modes(&self) -> usize {
        self.n_modes
    }
    /// Number of coordinates of the superelement, $6N + m$ (also the length of $\mathbf q^{jj}$).
    pub fn n_coordinates(&self) -> usize {
        self.n
    }
    /// The frame choice.
    pub fn frame_choice(&self) -> FrameChoice {
        self.frame_choice
    }
    /// The inertia variant.
    pub fn mass_variant(&self) -> MassVariant {
        self.mass_variant
    }
    /// Undeformed interface positions $\mathbf x_k$ from the frame origin, body axes.
    pub fn interface_positions(&self) -> &[Vector3<f64>] {
        &self.x
    }
    /// FE coordinates of the frame origin $P_j$.
    pub fn frame_origin(&self) -> Vector3<f64> {
        self.origin
    }
    /// Undeformed centre of mass from the frame origin, body axes.
    pub fn center_of_mass(&self) -> Vector3<f64> {
        self.inertia.d
    }
    /// Total mass.
    pub fn mass(&self) -> f64 {
        self.inertia.mass
    }
    /// $\boldsymbol\Phi_j$ (4.4).
    pub fn phi_j(&self) -> &Mat<f64> {
        &self.Phi_j
    }
    /// $\mathbf K_{CB}$.
    pub fn k_cb(&self) -> &Mat<f64> {
        &self.K_CB
    }
    /// $\mathbf M_{CB}$.
    pub fn m_cb(&self) -> &Mat<f64> {
        &self.M_CB
    }
    /// The geometric stiffness $\mathbf G_k$, when the body has one ([`GeometricStiffness`]).
    pub fn geometric_stiffness(&self) -> Option<&GeometricStiffness> {
        self.geometric.as_ref()
    }
    /// The FFR inertia invariants about the frame origin.
    pub fn ffr_inertia(&self) -> &FfrInertia {
        &self.inertia
    }

    /// The undeformed body placed rigidly at `frame`, at rest: $\mathbf r_k = \mathbf r_j +
    /// \mathbf R_j\mathbf x_k$, $\mathbf R_k = \mathbf R_j$, $\boldsymbol\eta = \mathbf 0$.
    pub fn undeformed_state(&self, frame: Frame) -> BodyState {
        self.rigid_state(frame, Vector3::zeros(), Vector3::zeros())
    }

    /// The undeformed body at `frame` moving rigidly with the frame-origin velocity `v_j` and
    /// angular velocity `omega`: $\mathbf v_k = \mathbf v_j + \boldsymbol\omega\times\mathbf R_j\mathbf x_k$.
    pub fn rigid_state(&self, frame: Frame, v_j: Vector3<f64>, omega: Vector3<f64>) -> BodyState {
        let N = self.n_interfaces;
        let arm: Vec<Vector3<f64>> = self.x.iter().map(|x| frame.R * x).collect();
        BodyState {
            r: arm.iter().map(|a| frame.r + a).collect(),
            R: vec![frame.R; N],
            v: arm.iter().map(|a| v_j + omega.cross(a)).collect(),
            omega: vec![omega; N],
            eta: vec![0.0; self.n_modes],
            eta_dot: vec![0.0; self.n_modes],
            frame,
        }
    }

    pub(crate) fn check_state(&self, s: &BodyState) -> Result<(), SuperelementError> {
        let N = self.n_interfaces;
        let m = self.n_modes;
        let bad = |what: String| Err(SuperelementError::InvalidState { what });
        if s.r.len() != N || s.R.len() != N || s.v.len() != N || s.omega.len() != N {
            return bad(format!(
                "body '{}' has {N} interfaces; the state has {} positions, {} orientations, {} velocities, {} angular velocities",
                self.name,
                s.r.len(),
                s.R.len(),
                s.v.len(),
                s.omega.len()
            ));
        }
        if s.eta.len() != m || s.eta_dot.len() != m {
            return bad(format!(
                "body '{}' has {m} modes; the state has {} modal coordinates and {} rates",
                self.name,
                s.eta.len(),
                s.eta_dot.len()
            ));
        }
        let finite =
            s.r.iter()
                .chain(&s.v)
                .chain(&s.omega)
                .all(|v| v.iter().all(|x| x.is_finite()))
                && s.R.iter().all(|q| q.coords.iter().all(|x| x.is_finite()))
                && s.eta.iter().chain(&s.eta_dot).all(|x| x.is_finite())
                && s.frame.r.iter().all(|x| x.is_finite())
                && s.frame.R.coords.iter().all(|x| x.is_finite());
        if !finite {
            return bad("the state has a non-finite entry".into());
        }
        Ok(())
    }

    /// Solves the frame (4.4) and builds the configuration-level matrices (5.2)-(5.6).
    ///
    /// For a planar body the frame is the planar one and the matrices those of the spatial
    /// body at that configuration (complete, in the $6N + m$ layout).
    pub fn kinematics(&self, state: &BodyState) -> Result<Kinematics, SuperelementError> {
        let (frame, iterations) = self.solve_frame(state)?;
        self.kinematics_at(state, frame, iterations)
    }

    /// Like [`Self::kinematics`] for a given frame (not solved; for tests of the local maps).
    pub fn kinematics_at(
        &self,
        state: &BodyState,
        frame: Frame,
        iterations: usize,
    ) -> Result<Kinematics, SuperelementError> {
        let mut q = vec![0.0; self.n];
        local_coordinates(&frame, &state.r, &state.R, &self.x, &state.eta, &mut q);
        Kinematics::new(frame, iterations, q, &self.x, self.Phi_j.as_ref())
    }

    /// Velocity of the frame (5.4) in inertial axes: $(\dot{\mathbf r}_j, \boldsymbol\omega_j) =
    /// \mathrm{diag}(\mathbf R_j,\mathbf R_j)\,\mathbf Z_j\boldsymbol\Lambda\bar{\mathbf R}^T\dot{\mathbf q}$.
    pub fn frame_velocity(&self, kin: &Kinematics, state: &BodyState) -> (Vector3<f64>, Vector3<f64>) {
        if self.is_planar() {
            // The planar frame velocity (x, y and the rate about z); a singular configuration
            // cannot come from a successful evaluation: its velocity is reported as NaN.
            let xi = self
                .planar_velocities(kin, state)
                .map(|(xi, _)| xi)
                .unwrap_or([f64::NAN; 3]);
            return (kin.R_j * Vector3::new(xi[0], xi[1], 0.0), Vector3::new(0.0, 0.0, xi[2]));
        }
        let y = kin.to_body(&state.velocity_vector());
        let Y = kin.Y();
        let xi: Vec<f64> = (0..6).map(|a| (0..self.n).map(|j| Y[(a, j)] * y[j]).sum()).collect();
        (
            kin.R_j * Vector3::new(xi[0], xi[1], xi[2]),
            kin.R_j * Vector3::new(xi[3], xi[4], xi[5]),
        )
    }

    /// Elastic velocity $\dot{\mathbf q}^{jj} = \mathbf T_j\boldsymbol\Lambda\bar{\mathbf R}^T\dot{\mathbf q}$ (5.5).
    /// Any kinematics of the state will do: after a forces-only evaluation, which leaves
    /// $\mathbf B$ out, a completed copy is formed.
    pub fn local_velocity(&self, kin: &Kinematics, state: &BodyState) -> Vec<f64> {
        if self.is_planar() {
            let mut out = vec![0.0; self.n];
            match self.planar_velocities(kin, state) {
                Ok((_, zeta)) => {
                    for (&g, z) in self.planar_body().index.iter().zip(zeta) {
                        out[g] = z;
                    }
                }
                Err(_) => out.fill(f64::NAN),
            }
            return out;
        }
        let y = kin.to_body(&state.velocity_vector());
        let completed;
        let B = match kin.B() {
            Some(B) => B,
            None => {
                let mut k = kin.clone();
                k.complete();
                completed = k;
                completed.B_rows()
            }
        };
        (0..self.n)
            .map(|i| (0..self.n).map(|j| B[(i, j)] * y[j]).sum())
            .collect()
    }
}

/// The planar glue ([`crate::planar`]): reading a planar state, the planar frame, the planar
/// parts of 3D-layout vectors.
impl Superelement {
    pub(crate) fn planar_body(&self) -> &PlanarBody {
        self.planar.as_deref().expect("a planar body")
    }

    /// Checks that `state` lies in the plane (NotPlanar naming the interface) and reads the
    /// positions into `r` and the angles into `phi`.
    pub(crate) fn read_planar(
        &self,
        state: &BodyState,
        r: &mut [[f64; 2]],
        phi: &mut [f64],
    ) -> Result<f64, SuperelementError> {
        self.check_state(state)?;
        let z0 = state.r[0].z;
        let mut r_max: f64 = 0.0;
        for k in 0..self.n_interfaces {
            let R = &state.R[k];
            let name = &self.body.interfaces[k].name;
            // The tilt out of the plane, 2 |(q_x, q_y)| of the quaternion, by its square.
            let tilt2 = 4.0 * (R.coords[0] * R.coords[0] + R.coords[1] * R.coords[1]);
            if !(tilt2 <= STATE_TOL * STATE_TOL) {
                let tilt = tilt2.sqrt();
                return Err(self.not_planar(format!(
                    "the orientation of interface '{name}' is tilted {tilt:.3e} rad out of the xy-plane"
                )));
            }
            let dz = state.r[k].z - z0;
            if !(dz.abs() <= STATE_TOL * self.length + 64.0 * f64::EPSILON * state.r[k].z.abs()) {
                return Err(self.not_planar(format!(
                    "interface '{name}' is {dz:.3e} m out of the plane z = {z0} of the first interface"
                )));
            }
            r[k] = [state.r[k].x, state.r[k].y];
            phi[k] = angle_of(R);
            r_max = r_max.max(state.r[k].norm());
        }
        Ok(r_max)
    }

    pub(crate) fn not_planar(&self, what: String) -> SuperelementError {
        SuperelementError::NotPlanar {
            body: self.name.clone(),
            what,
        }
    }

    /// Solves the planar frame (4.4) from the warm start (the frame of `warm`, its angle
    /// `warm_angle`): positions `r`, angles `phi`, modal coordinates `eta`; `b` holds the Newton
    /// iterates. Returns the frame, the iterations and, after a Newton solve, $(\sin, \cos)$ of
    /// the frame angle.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn planar_frame(
        &self,
        r: &[[f64; 2]],
        phi: &[f64],
        eta: &[f64],
        r_max: f64,
        warm: &Frame,
        warm_angle: f64,
        b: &mut Buf<f64>,
    ) -> Result<Solved2, SuperelementError> {
        let pb = self.planar_body();
        match self.frame_solve {
            FrameSolve::AtInterface(k) => Ok(((r[k], phi[k]), 0, None)),
            FrameSolve::Newton => {
                let x0 = pb.x[0];
                let guess = || {
                    let (s, c) = phi[0].sin_cos();
                    (
                        [r[0][0] - (c * x0[0] - s * x0[1]), r[0][1] - (s * x0[0] + c * x0[1])],
                        phi[0],
                    )
                };
                let warm = ([warm.r.x, warm.r.y], warm_angle);
                let far = phi.iter().any(|p| wrap(p - warm.1).abs() > 1.0);
                let (L, settings) = (self.length, self.frame_settings);
                let solved = if far {
                    pb.newton(r, phi, eta, r_max, guess(), L, settings, b)
                } else {
                    pb.newton(r, phi, eta, r_max, warm, L, settings, b)
                        .or_else(|e| pb.newton(r, phi, eta, r_max, guess(), L, settings, b).map_err(|_| e))
                };
                solved.map(|(frame, it, sc)| (frame, it, Some(sc)))
            }
        }
    }

    /// The 3D frame of a planar one.
    pub(crate) fn frame_3d(&self, frame: ([f64; 2], f64), z: f64) -> Frame {
        Frame::new(Vector3::new(frame.0[0], frame.0[1], z), rotation_z(frame.1))
    }

    /// Planar [`Superelement::solve_frame`].
    pub(crate) fn planar_solve_frame(&self, state: &BodyState) -> Result<(Frame, usize), SuperelementError> {
        let pb = self.planar_body();
        let mut r = vec![[0.0; 2]; pb.N];
        let mut phi = vec![0.0; pb.N];
        let r_max = self.read_planar(state, &mut r, &mut phi)?;
        let mut b = Buf::<f64>::new(pb.N, pb.n, 0);
        let warm_angle = angle_of(&state.frame.R);
        let (frame, it, _) = self.planar_frame(&r, &phi, &state.eta, r_max, &state.frame, warm_angle, &mut b)?;
        Ok((self.frame_3d(frame, state.r[0].z - self.x[0].z), it))
    }

    /// The planar local coordinates of a 3D-layout $\mathbf q^{jj}$.
    pub(crate) fn planar_q(&self, q3: &[f64]) -> Vec<f64> {
        self.planar_body().index.iter().map(|&g| q3[g]).collect()
    }

    /// $\bar{\mathbf R}^T\dot{\mathbf q}$ (planar) of a 3D-layout velocity vector, for the frame
    /// angle of `frame`.
    pub(crate) fn planar_y(&self, frame: &Frame, qd3: &[f64]) -> Vec<f64> {
        let pb = self.planar_body();
        let (s, c) = angle_of(&frame.R).sin_cos();
        let mut y: Vec<f64> = pb.index.iter().map(|&g| qd3[g]).collect();
        for k in 0..pb.N {
            let (vx, vy) = (y[3 * k], y[3 * k + 1]);
            y[3 * k] = c * vx + s * vy;
            y[3 * k + 1] = c * vy - s * vx;
        }
        y
    }

    /// Frame velocity (x, y, rate about z) and elastic velocity (planar) at the configuration
    /// `kin` for the state's velocities.
    pub(crate) fn planar_velocities(
        &self,
        kin: &Kinematics,
        state: &BodyState,
    ) -> Result<([f64; 3], Vec<f64>), SuperelementError> {
        let q = self.planar_q(&kin.q_jj);
        let y = self.planar_y(&kin.frame, &state.velocity_vector());
        self.planar_body().velocities(&q, &y)
    }
}

/// $\boldsymbol\Phi_j$ of a frame at interface $k$: the 6 rows selecting $\mathbf q_k^{jj}$.
fn selection(n: usize, k: usize) -> Mat<f64> {
    Mat::from_fn(6, n, |i, j| if j == 6 * k + i { 1.0 } else { 0.0 })
}
