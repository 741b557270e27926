//! The residual of one body and its tangent matrices for Newton [S19]:
//! $\mathbf r(\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q}) = \mathbf M\ddot{\mathbf q} + \mathbf Q_v + \mathbf f_{el}
//! + \mathbf f_d - \mathbf f_g$, $\mathbf K_t = \partial\mathbf r/\partial\mathbf q$,
//! $\mathbf C_t = \partial\mathbf r/\partial\dot{\mathbf q}$, $\mathbf M = \partial\mathbf r/\partial\ddot{\mathbf q}$.
//!
//! Naming rule: `evaluate` returns forces and tangents together (they share every
//! intermediate); `*_force`-style pieces live in [`crate::forces`].
//!
//! # Variations
//!
//! $\partial/\partial\mathbf q$ is taken with spatial variations: $\mathbf r_k \leftarrow \mathbf r_k +
//! \delta\mathbf r_k$, $\mathbf R_k \leftarrow \exp(\widetilde{\delta\boldsymbol\pi}_k)\mathbf R_k$,
//! $\boldsymbol\eta \leftarrow \boldsymbol\eta + \delta\boldsymbol\eta$, at fixed spatial velocities
//! $\mathbf v_k, \boldsymbol\omega_k$ and accelerations; the frame is re-solved (its variation is
//! $\mathbf Z_j\boldsymbol\Lambda\bar{\mathbf R}^T\delta\mathbf q$, (3.9)).

#![allow(non_snake_case)]

use crate::body::{BodyState, Superelement};
use crate::error::SuperelementError;
use crate::forces::{Local, Motion};
use crate::frame::Frame;
use crate::mass::MassVariant;
use crate::so3::skew;
use crate::transform::{gemm, rotate_matrix, w_stack, Kinematics};
use faer::{Accum, Mat};
use nalgebra::Vector3;

/// Forces and tangents of one body in absolute interface coordinates, order
/// $[\mathbf r_1, \boldsymbol\pi_1, \dots, \mathbf r_N, \boldsymbol\pi_N, \boldsymbol\eta]$.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// The frame solving (2.6) for this state: store it in the state as the next warm start.
    pub frame: Frame,
    /// Newton iterations of the frame solve.
    pub frame_iterations: usize,
    /// $\mathbf q^{jj}$.
    pub q_jj: Vec<f64>,
    /// $\mathbf r = \mathbf f_{in} + \mathbf f_{el} + \mathbf f_d - \mathbf f_g$ (equals the external
    /// interface forces at a solution).
    pub residual: Vec<f64>,
    /// Inertia force $\mathbf M\ddot{\mathbf q} + \mathbf Q_v$.
    pub f_inertia: Vec<f64>,
    /// Quadratic velocity force $\mathbf Q_v = \mathbf f_{in} - \mathbf M\ddot{\mathbf q}$.
    pub q_v: Vec<f64>,
    /// Elastic force (4.4).
    pub f_elastic: Vec<f64>,
    /// Damping force.
    pub f_damping: Vec<f64>,
    /// Gravity (a load: it enters the residual with a minus sign).
    pub f_gravity: Vec<f64>,
    /// $\mathbf M$.
    pub mass: Mat<f64>,
    /// $\mathbf K_t = \partial\mathbf r/\partial\mathbf q$ (empty when tangents were not asked for).
    pub stiffness: Mat<f64>,
    /// $\mathbf C_t = \partial\mathbf r/\partial\dot{\mathbf q}$ (empty when tangents were not asked for).
    pub damping: Mat<f64>,
}

impl Superelement {
    /// Forces and tangents of the body at `state` with accelerations `acc` ($[\mathbf a_1,
    /// \boldsymbol\alpha_1, \dots, \ddot{\boldsymbol\eta}]$, spatial) under gravity `gravity`.
    /// The frame is solved from `state.frame`.
    pub fn evaluate(&self, state: &BodyState, acc: &[f64], gravity: &Vector3<f64>) -> Result<Evaluation, SuperelementError> {
        self.evaluate_with(state, acc, gravity, true)
    }

    /// Forces only (no tangents; cheaper, for explicit integrators and energy checks).
    pub fn forces(&self, state: &BodyState, acc: &[f64], gravity: &Vector3<f64>) -> Result<Evaluation, SuperelementError> {
        self.evaluate_with(state, acc, gravity, false)
    }

    fn evaluate_with(
        &self,
        state: &BodyState,
        acc: &[f64],
        gravity: &Vector3<f64>,
        tangents: bool,
    ) -> Result<Evaluation, SuperelementError> {
        if acc.len() != self.n {
            return Err(SuperelementError::InvalidState {
                what: format!("{} accelerations for {} coordinates", acc.len(), self.n),
            });
        }
        let kin = self.kinematics(state)?;
        let qd = state.velocity_vector();
        Ok(self.evaluate_kinematics(&kin, &qd, acc, gravity, tangents))
    }

    /// [`Self::evaluate`] for a configuration already solved ([`Self::kinematics`]).
    ///
    /// # Derivation
    /// Every force is $\bar{\mathbf R}\boldsymbol\rho(\mathbf q^{jj}, \mathbf y, \mathbf a, \mathbf g^L)$
    /// ([`crate::forces`]). A variation $\delta\mathbf q$ moves $\mathbf q^{jj}$ by
    /// $\mathbf B\,\delta\mathbf q^L$ ($\delta\mathbf q^L = \bar{\mathbf R}^T\delta\mathbf q$) and turns the
    /// body axes by $\delta\boldsymbol\Pi = \mathbf Y_r\delta\mathbf q^L$, which changes the body-axis
    /// images of the fixed spatial vectors, $\delta\mathbf y = \mathbf W(\mathbf y)\delta\boldsymbol\Pi$
    /// (likewise $\mathbf a$, $\mathbf g^L$), and rotates the result, $\delta(\bar{\mathbf R}\boldsymbol\rho)
    /// = \bar{\mathbf R}(\delta\boldsymbol\rho - \mathbf W(\boldsymbol\rho)\delta\boldsymbol\Pi)$. Hence
    ///
    /// $$\mathbf K_t = \bar{\mathbf R}\Big[\frac{\partial\boldsymbol\rho}{\partial\mathbf q^{jj}}\mathbf B
    /// + \Big(\frac{\partial\boldsymbol\rho}{\partial\mathbf y}\mathbf W(\mathbf y) + \mathbf M^L\mathbf W(\mathbf a)
    /// + \frac{\partial\boldsymbol\rho}{\partial\mathbf g^L}\tilde{\mathbf g}^L - \mathbf W(\boldsymbol\rho)\Big)\mathbf Y_r\Big]\bar{\mathbf R}^T,$$
    ///
    /// $\mathbf C_t = \bar{\mathbf R}\,\partial\boldsymbol\rho/\partial\mathbf y\,\bar{\mathbf R}^T$,
    /// $\mathbf M = \bar{\mathbf R}\mathbf M^L\bar{\mathbf R}^T$. The term $\mathbf M^L\mathbf W(\mathbf a)\mathbf Y_r$
    /// (with the $\mathbf q^{jj}$-dependence of $\mathbf M^L$ inside $\partial\boldsymbol\rho/\partial\mathbf q^{jj}$)
    /// is $\partial(\mathbf M\ddot{\mathbf q})/\partial\mathbf q$. Checked entry by entry against
    /// central differences by `tests/unit/fd_tangent.rs::tangents_match_fd`.
    pub fn evaluate_kinematics(
        &self,
        kin: &Kinematics,
        qd: &[f64],
        acc: &[f64],
        gravity: &Vector3<f64>,
        tangents: bool,
    ) -> Evaluation {
        let n = self.n;
        let N = self.n_interfaces;
        let mo = Motion::new(kin, qd, acc, gravity, tangents);
        let mut loc = Local::new(n, tangents);
        self.elastic(kin, &mut loc, tangents);
        self.damping_force(kin, &mo, &mut loc, tangents);
        self.gravity(kin, &mo, &mut loc, tangents);
        match self.mass_variant {
            MassVariant::Exact => self.exact_inertia(kin, &mo, &mut loc, tangents),
            MassVariant::Lumped => self.lumped_inertia(kin, &mo, &mut loc, tangents),
        }
        let rho: Vec<f64> = (0..n).map(|i| loc.rho_in[i] + loc.rho_el[i] + loc.rho_d[i] - loc.rho_g[i]).collect();
        let R = &kin.R_j;
        let mut mass = Mat::zeros(n, n);
        rotate_matrix(R, N, &loc.M, &mut mass);
        let f_inertia = kin.rotate(&loc.rho_in, true);
        let mut q_v = f_inertia.clone();
        for j in 0..n {
            for i in 0..n {
                q_v[i] -= mass[(i, j)] * acc[j];
            }
        }
        let (stiffness, damping) = if tangents {
            // K^L = Dq B + (Dy W(y) + M W(a) + Dg g~ - W(rho)) Y_r.
            let mut KL = Mat::zeros(n, n);
            gemm(&mut KL, loc.Dq.as_ref(), kin.B(), 1.0, Accum::Replace);
            let mut H = w_stack(&rho, N);
            for j in 0..3 {
                for i in 0..n {
                    H[(i, j)] = -H[(i, j)];
                }
            }
            gemm(&mut H, loc.Dy.as_ref(), w_stack(&mo.y, N).as_ref(), 1.0, Accum::Add);
            gemm(&mut H, loc.M.as_ref(), w_stack(&mo.a, N).as_ref(), 1.0, Accum::Add);
            let gt = skew(&mo.g);
            let gt = Mat::from_fn(3, 3, |i, j| gt[(i, j)]);
            gemm(&mut H, loc.Dg.as_ref(), gt.as_ref(), 1.0, Accum::Add);
            gemm(&mut KL, H.as_ref(), kin.Y().subrows(3, 3), 1.0, Accum::Add);
            let mut K = Mat::zeros(n, n);
            rotate_matrix(R, N, &KL, &mut K);
            let mut C = Mat::zeros(n, n);
            rotate_matrix(R, N, &loc.Dy, &mut C);
            (K, C)
        } else {
            (Mat::zeros(0, 0), Mat::zeros(0, 0))
        };
        let _ = Vector3::<f64>::zeros();
        Evaluation {
            frame: kin.frame,
            frame_iterations: kin.frame_iterations,
            q_jj: kin.q_jj.clone(),
            residual: kin.rotate(&rho, true),
            f_inertia,
            q_v,
            f_elastic: kin.rotate(&loc.rho_el, true),
            f_damping: kin.rotate(&loc.rho_d, true),
            f_gravity: kin.rotate(&loc.rho_g, true),
            mass,
            stiffness,
            damping,
        }
    }

    /// Kinetic energy $\tfrac12\dot{\mathbf q}^T\mathbf M\dot{\mathbf q}$ of the chosen inertia variant.
    pub fn kinetic_energy(&self, state: &BodyState) -> Result<f64, SuperelementError> {
        let kin = self.kinematics(state)?;
        let qd = state.velocity_vector();
        let ev = self.evaluate_kinematics(&kin, &qd, &vec![0.0; self.n], &Vector3::zeros(), false);
        let mut T = 0.0;
        for j in 0..self.n {
            for i in 0..self.n {
                T += 0.5 * qd[i] * ev.mass[(i, j)] * qd[j];
            }
        }
        Ok(T)
    }

    /// Strain energy $\tfrac12\mathbf q^{jjT}\mathbf K_{CB}\mathbf q^{jj}$.
    pub fn strain_energy(&self, kin: &Kinematics) -> f64 {
        let mut f = vec![0.0; self.n];
        crate::mass::matvec(&self.K_CB, &kin.q_jj, &mut f);
        0.5 * f.iter().zip(&kin.q_jj).map(|(a, b)| a * b).sum::<f64>()
    }

    /// Gravity potential $-\mathbf g\cdot(m\mathbf r_j + \mathbf R_j\mathbf s)$, $\mathbf s = m\mathbf d + \mathbf S_t\mathbf q^{jj}$.
    pub fn gravity_potential(&self, kin: &Kinematics, gravity: &Vector3<f64>) -> f64 {
        let I = &self.inertia;
        let s: Vector3<f64> = I.d * I.mass + crate::mass::mul3(&I.S_t, &kin.q_jj);
        -gravity.dot(&(kin.frame.r * I.mass + kin.R_j * s))
    }
}
