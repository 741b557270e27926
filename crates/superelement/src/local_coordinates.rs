//! Local interface (Craig-Bampton) coordinates from absolute interface coordinates (theory guide §4):
//! $\mathbf u_k = \mathbf R_j^T(\mathbf r_k - \mathbf r_j) - \mathbf x_k$,
//! $\boldsymbol\theta_k = \log(\mathbf R_j^T\mathbf R_k\mathbf R_{k0}^T)$, and their variation.
//!
//! **Reference orientation.** $\mathbf R_{k0} = \mathbf I$ in body axes: every interface
//! starts aligned with the body (its axes are the FE model's axes). An absolute orientation
//! $\mathbf R_k$ is therefore the rotation of interface $k$ from the FE model's axes, and a
//! rigid motion of the body rotates every $\mathbf R_k$ and the frame alike.
//!
//! **Positions.** $\mathbf x_k$ is the undeformed position of interface $k$ measured from the
//! frame origin $P_j$ in body axes (not from the FE model's origin): the FE position minus
//! the FE position of $P_j$ (the centre of mass, interface $k$, or the auxiliary interface;
//! see [`crate::FrameChoice`]). So $\mathbf r_j$ is where $P_j$ is.

#![allow(non_snake_case)]

use crate::so3;
use crate::state::Frame;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Interface displacement $\mathbf u_k = \mathbf R_j^T(\mathbf r_k - \mathbf r_j) - \mathbf x_k$ (body axes).
///
/// # Derivation
/// Not in the AIC-FFR papers in this form ((5.1) is its inverse). With $\delta\mathbf R_j =
/// \widetilde{\delta\boldsymbol\pi}_j\mathbf R_j$: $\delta\mathbf u_k = \mathbf R_j^T\delta\mathbf r_k -
/// [\mathbf I,\ -\tilde{\mathbf r}_k^{jj}]\,[\mathbf R_j^T\delta\mathbf r_j;\ \mathbf R_j^T\delta\boldsymbol\pi_j]$
/// with $\mathbf r_k^{jj} = \mathbf x_k + \mathbf u_k$: the translation rows of (5.3).
/// Checked by `tests/unit/fd_tangent.rs::local_coordinates_variation`.
pub fn interface_displacement(frame: &Frame, r_k: &Vector3<f64>, x_k: &Vector3<f64>) -> Vector3<f64> {
    frame.R.inverse_transform_vector(&(r_k - frame.r)) - x_k
}

/// Elastic rotation $\boldsymbol\theta_k = \log(\mathbf R_j^T\mathbf R_k\mathbf R_{k0}^T)$, with
/// $\mathbf R_{k0} = \mathbf I$ (module docs).
///
/// # Derivation
/// Not in the AIC-FFR papers. With spatial variations $\delta\mathbf R = \widetilde{\delta\boldsymbol\pi}\mathbf R$,
/// $\delta(\mathbf R_j^T\mathbf R_k) = (\mathbf R_j^T(\delta\boldsymbol\pi_k - \delta\boldsymbol\pi_j))^\sim
/// \mathbf R_j^T\mathbf R_k$, a left perturbation, so
/// $\delta\boldsymbol\theta_k = \mathbf J_l^{-1}(\boldsymbol\theta_k)\,\mathbf R_j^T(\delta\boldsymbol\pi_k - \delta\boldsymbol\pi_j)$
/// ([`so3`] conventions). The AIC-FFR paper's (5.1)/(5.3) use the virtual rotation
/// $\mathbf R_j^T(\delta\boldsymbol\pi_k - \delta\boldsymbol\pi_j)$ in place of $\delta\boldsymbol\theta_k$,
/// which is the $\mathbf J_l^{-1} = \mathbf I$ (small elastic rotation) limit; this crate keeps
/// the factor $\boldsymbol\Lambda$ ([`lambda_blocks`]) so that its tangents are exact.
/// Checked by `tests/unit/fd_tangent.rs::local_coordinates_variation`.
pub fn elastic_rotation(R_j: &UnitQuaternion<f64>, R_k: &UnitQuaternion<f64>) -> Vector3<f64> {
    so3::log(&(R_j.inverse() * R_k))
}

/// The CB coordinates $\mathbf q^{jj} = [\mathbf u_1, \boldsymbol\theta_1, \dots, \mathbf u_N,
/// \boldsymbol\theta_N, \boldsymbol\eta]$ (4.3) for the frame `frame`, written to `q_jj`
/// ($6N + m$ entries; `x` are the undeformed positions from the frame origin).
pub fn local_coordinates(
    frame: &Frame,
    r: &[Vector3<f64>],
    R: &[UnitQuaternion<f64>],
    x: &[Vector3<f64>],
    eta: &[f64],
    q_jj: &mut [f64],
) {
    let N = x.len();
    for k in 0..N {
        let u = interface_displacement(frame, &r[k], &x[k]);
        let th = elastic_rotation(&frame.R, &R[k]);
        q_jj[6 * k..6 * k + 3].copy_from_slice(u.as_slice());
        q_jj[6 * k + 3..6 * k + 6].copy_from_slice(th.as_slice());
    }
    q_jj[6 * N..].copy_from_slice(eta);
}

/// $\boldsymbol\Lambda$: the blocks $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ of the block-diagonal
/// map from virtual rotations to variations of the CB rotation coordinates
/// ($\boldsymbol\Lambda = \mathrm{diag}(\mathbf I, \mathbf J_l^{-1}(\boldsymbol\theta_1), \dots,
/// \mathbf I, \mathbf J_l^{-1}(\boldsymbol\theta_N), \mathbf I_m)$; see [`elastic_rotation`]).
pub fn lambda_blocks(q_jj: &[f64], N: usize) -> Vec<Matrix3<f64>> {
    (0..N).map(|k| so3::left_jacobian_inv(&theta_of(q_jj, k))).collect()
}

/// $\mathbf u_k$ from $\mathbf q^{jj}$.
#[inline]
pub fn u_of(q_jj: &[f64], k: usize) -> Vector3<f64> {
    Vector3::new(q_jj[6 * k], q_jj[6 * k + 1], q_jj[6 * k + 2])
}

/// $\boldsymbol\theta_k$ from $\mathbf q^{jj}$.
#[inline]
pub fn theta_of(q_jj: &[f64], k: usize) -> Vector3<f64> {
    Vector3::new(q_jj[6 * k + 3], q_jj[6 * k + 4], q_jj[6 * k + 5])
}
