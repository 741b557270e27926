//! A force and moment at a load point inside the body (a node of the FE model that is not an
//! interface, reduced with its attachment modes: `reduction::LoadPoint`), as a generalised
//! force on the body's absolute interface coordinates and modal coordinates.
//!
//! # Derivation
//!
//! Theory guide, point loads inside a body, (6.11)-(6.12).
//!
//! The load point sits at $\mathbf p = \mathbf r_j + \mathbf R_j\mathbf s$, $\mathbf s =
//! \mathbf d_p + \mathbf S_u\mathbf q^{jj}$ ($\mathbf d_p$ its undeformed position from the frame
//! origin, $\mathbf S_u$, $\mathbf S_r$ the translation and rotation rows of its CB shape
//! $\mathbf S_p$, body axes), and turns by $\delta\boldsymbol\Pi + \mathbf S_r\delta\mathbf q^{jj}$
//! (body axes; the elastic rotation is the linear one of the CB shapes). A force $\mathbf f$ and
//! moment $\mathbf m$ there, $\mathbf f^L$, $\mathbf m^L$ in body axes, do the virtual work
//! $\mathbf Q^T[\delta\mathbf r_j^L;\ \delta\boldsymbol\Pi;\ \delta\mathbf q^{jj}]$ with
//! $$\mathbf Q = [\mathbf f^L;\ \mathbf s\times\mathbf f^L + \mathbf m^L;\ \mathbf S_u^T\mathbf f^L +
//! \mathbf S_r^T\mathbf m^L],$$
//! the reduced load vector $\mathbf S_p^T[\mathbf f^L; \mathbf m^L]$ in its last block: exactly the
//! gravity force of [`crate::forces`] with the body's mass moved to one point. Transformed by
//! $\mathbf P$ ((5.6) in body axes) its residual share is $\boldsymbol\rho = -\mathbf P^T\mathbf Q$,
//! in inertial axes $\bar{\mathbf R}\boldsymbol\rho$.
//!
//! * Dead load ($\mathbf f$, $\mathbf m$ fixed in inertial axes): $\mathbf f^L = \mathbf R_j^T\mathbf f$.
//! * Follower load ($\mathbf f^L$, $\mathbf m^L$ fixed in body axes): it turns with the floating
//!   frame.
//!
//! Tangent, as in [`crate::tangent`] with no velocity or acceleration terms:
//! $$\mathbf K^L = \frac{\partial\boldsymbol\rho}{\partial\mathbf q^{jj}}\mathbf B + \Big(
//! \frac{\partial\boldsymbol\rho}{\partial\mathbf f^L}\tilde{\mathbf f}^L + \frac{\partial\boldsymbol\rho}{\partial\mathbf m^L}
//! \tilde{\mathbf m}^L - \mathbf W(\boldsymbol\rho)\Big)\mathbf Y_r,$$
//! the middle terms for a dead load only, with $\partial\boldsymbol\rho/\partial\mathbf q^{jj} =
//! -\partial(\mathbf P^T\mathbf Q)/\partial\mathbf q^{jj}|_{\mathbf Q} + \mathbf Y_r^T\tilde{\mathbf f}^L\mathbf S_u$
//! (from $\partial(\mathbf s\times\mathbf f^L)/\partial\mathbf q^{jj} = -\tilde{\mathbf f}^L\mathbf S_u$),
//! $\partial\boldsymbol\rho/\partial\mathbf f^L = -\mathbf P^T[\mathbf I;\ \tilde{\mathbf s};\ \mathbf S_u^T]$,
//! $\partial\boldsymbol\rho/\partial\mathbf m^L = -\mathbf P^T[\mathbf 0;\ \mathbf I;\ \mathbf S_r^T]$.
//! Checked against central differences by `tests/unit/point_load.rs`.
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\mathbf d_p$ | `d` | undeformed load point from the frame origin, body axes |
//! | $\mathbf S_u$, $\mathbf S_r$ | `shape` rows 0-2, 3-5 | CB shape of the load point |
//! | $\mathbf f^L$, $\mathbf m^L$ | `fl`, `ml` | force and moment in body axes |
//! | $\mathbf Q$ | `Q` | generalised load in FFR coordinates |
//! | $\boldsymbol\rho$ | `rho` | residual share, body axes |

#![allow(non_snake_case)]

use crate::body::Superelement;
use crate::error::SuperelementError;
use crate::forces::w_into;
use crate::so3::skew;
use crate::transform::{gemm, rotate_matrix, Kinematics};
use faer::{Accum, Mat};
use nalgebra::Vector3;

/// A force and moment at load point `point` (index into the reduced body's load points).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLoad {
    pub point: usize,
    /// Force \[N\] and moment \[N m\]: inertial axes for a dead load, body (FE model) axes
    /// for a follower.
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
    /// Whether the load turns with the body's floating frame.
    pub follower: bool,
}

/// The residual share of a point load and its tangent, with the buffers they are computed in
/// (sized once for a body: [`Superelement::point_load_workspace`]).
#[derive(Clone, Debug)]
pub struct PointLoadWorkspace {
    /// Residual share $\bar{\mathbf R}\boldsymbol\rho$ (minus the generalised load).
    pub residual: Vec<f64>,
    /// Its derivative $\partial(\bar{\mathbf R}\boldsymbol\rho)/\partial\mathbf q$ (spatial variations).
    pub stiffness: Mat<f64>,
    Q: Vec<f64>,
    rho: Vec<f64>,
    phi: Vec<f64>,
    Dq: Mat<f64>,
    KL: Mat<f64>,
    H: Mat<f64>,
    G: Mat<f64>,
    three_n: Mat<f64>,
}

impl Superelement {
    /// The load points of the reduced body (name, FE node, position, CB shape).
    pub fn load_points(&self) -> &[reduction::LoadPoint] {
        &self.body.load_points
    }

    /// Buffers for [`Self::point_load_into`].
    pub fn point_load_workspace(&self) -> PointLoadWorkspace {
        let n = self.n;
        PointLoadWorkspace {
            residual: vec![0.0; n],
            stiffness: Mat::zeros(n, n),
            Q: vec![0.0; 6 + n],
            rho: vec![0.0; n],
            phi: vec![0.0; n],
            Dq: Mat::zeros(n, n),
            KL: Mat::zeros(n, n),
            H: Mat::zeros(n, 3),
            G: Mat::zeros(6 + n, 3),
            three_n: Mat::zeros(3, n),
        }
    }

    /// The residual share of `load` (module docs) at the configuration `kin` into `ws.residual`
    /// and its derivative into `ws.stiffness`. Several loads on one body: call once per load and
    /// add.
    ///
    /// # Errors
    /// [`SuperelementError::InvalidState`] if the body has no load point `load.point`.
    pub fn point_load_into(
        &self,
        kin: &Kinematics,
        load: &PointLoad,
        ws: &mut PointLoadWorkspace,
    ) -> Result<(), SuperelementError> {
        self.point_load_level(kin, load, true, ws)
    }

    /// [`Self::point_load_into`] without the derivative: `ws.residual` only (`ws.stiffness` is
    /// not written), what a Newton iteration that reuses its iteration matrix reads.
    ///
    /// # Errors
    /// [`SuperelementError::InvalidState`] if the body has no load point `load.point`.
    pub fn point_load_residual_into(
        &self,
        kin: &Kinematics,
        load: &PointLoad,
        ws: &mut PointLoadWorkspace,
    ) -> Result<(), SuperelementError> {
        self.point_load_level(kin, load, false, ws)
    }

    fn point_load_level(
        &self,
        kin: &Kinematics,
        load: &PointLoad,
        tangents: bool,
        ws: &mut PointLoadWorkspace,
    ) -> Result<(), SuperelementError> {
        if self.is_planar() {
            return Err(self.not_planar(format!(
                "point loads (load point {}) have no planar evaluation",
                load.point
            )));
        }
        let lp = self
            .body
            .load_points
            .get(load.point)
            .ok_or_else(|| SuperelementError::InvalidState {
                what: format!(
                    "load point {} of body '{}', which has {}",
                    load.point,
                    self.name,
                    self.body.load_points.len()
                ),
            })?;
        let n = self.n;
        let N = self.n_interfaces;
        let S = &lp.shape;
        let (fl, ml) = if load.follower {
            (load.force, load.moment)
        } else {
            (kin.R_j.transpose() * load.force, kin.R_j.transpose() * load.moment)
        };
        let mut s = Vector3::from(lp.position) - self.origin;
        for (j, q) in kin.q_jj.iter().enumerate() {
            for i in 0..3 {
                s[i] += S.get(i, j) * q;
            }
        }
        let Q = &mut ws.Q;
        let sf = s.cross(&fl) + ml;
        for i in 0..3 {
            Q[i] = fl[i];
            Q[3 + i] = sf[i];
        }
        for j in 0..n {
            Q[6 + j] = (0..3).map(|i| S.get(i, j) * fl[i] + S.get(3 + i, j) * ml[i]).sum();
        }
        kin.pt_vec(Q, &mut ws.rho);
        ws.rho.iter_mut().for_each(|r| *r = -*r);
        kin.to_inertial_into(&ws.rho, &mut ws.residual);
        if !tangents {
            return Ok(());
        }
        // d rho / d q_jj = -D(P^T)[Q] + Y_r^T f~ S_u.
        let P = kin.P.as_ref();
        ws.Dq.fill(0.0);
        for q in ws.Q.iter_mut() {
            *q = -*q;
        }
        kin.add_d_pt(&ws.Q, &mut ws.phi, &mut ws.Dq, 1.0);
        let ft = skew(&fl);
        for j in 0..n {
            let v = ft * Vector3::new(S.get(0, j), S.get(1, j), S.get(2, j));
            for i in 0..3 {
                ws.three_n[(i, j)] = v[i];
            }
        }
        gemm(
            &mut ws.Dq,
            P.subrows(3, 3).transpose(),
            ws.three_n.as_ref(),
            1.0,
            Accum::Add,
        );
        // K^L = Dq B + (Df f~ + Dm m~ - W(rho)) Y_r.
        gemm(&mut ws.KL, ws.Dq.as_ref(), kin.B_rows(), 1.0, Accum::Replace);
        w_into(&ws.rho, N, &mut ws.H);
        for j in 0..3 {
            for h in ws.H.col_as_slice_mut(j) {
                *h = -*h;
            }
        }
        if !load.follower {
            // Df = -P^T [I; s~; S_u^T], Dm = -P^T [0; I; S_r^T], each times its skew matrix.
            let st = skew(&s);
            let mt = skew(&ml);
            let G = &mut ws.G;
            for c in 0..3 {
                for i in 0..3 {
                    let e = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
                    // Column c of [I; s~] f~ + [0; I] m~.
                    G[(i, c)] = ft[(i, c)];
                    G[(3 + i, c)] = (0..3).map(|k| st[(i, k)] * ft[(k, c)] + e(i, k) * mt[(k, c)]).sum();
                }
                for j in 0..n {
                    G[(6 + j, c)] = (0..3)
                        .map(|k| S.get(k, j) * ft[(k, c)] + S.get(3 + k, j) * mt[(k, c)])
                        .sum();
                }
            }
            gemm(&mut ws.H, P.transpose(), ws.G.as_ref(), -1.0, Accum::Add);
        }
        gemm(&mut ws.KL, ws.H.as_ref(), kin.Y().subrows(3, 3), 1.0, Accum::Add);
        rotate_matrix(&kin.R_j, N, &ws.KL, &mut ws.stiffness);
        Ok(())
    }
}
