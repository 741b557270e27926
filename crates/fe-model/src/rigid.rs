//! Rigid motions of points that carry six dofs (three translations, three small rotations):
//! the one source of the rigid-mode matrices of interface sets, spiders and reduced bodies.
//!
//! | symbol | meaning | code |
//! |---|---|---|
//! | $\mathbf t,\ \boldsymbol\theta$ | translation of the reference point, small rotation | columns 0-2, 3-5 |
//! | $\mathbf r$ | a point's offset from the reference point | `r` |
//! | $\tilde{\mathbf r}$ | the cross-product matrix, $\tilde{\mathbf r}\mathbf a = \mathbf r\times\mathbf a$ | |

#![allow(non_snake_case)]

use nalgebra::{DMatrix, Matrix6, Vector3};

/// $\begin{bmatrix}\mathbf I & -\tilde{\mathbf r}\\ \mathbf 0 & \mathbf I\end{bmatrix}$: the six
/// dofs of a point at offset $\mathbf r$ from the reference point under the rigid motion
/// $[\mathbf t; \boldsymbol\theta]$, which moves it by $\mathbf t + \boldsymbol\theta\times\mathbf r$
/// and turns it by $\boldsymbol\theta$ (theory guide, rigid modes of the interface set (5.2)).
/// Its first three rows are the spider map $\mathbf S = [\mathbf I, -\tilde{\mathbf r}]$ of a
/// point without rotations.
pub fn rigid_motion_block(r: &Vector3<f64>) -> Matrix6<f64> {
    let mut B = Matrix6::identity();
    B.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r.cross_matrix()));
    B
}

/// The rigid modes of a set of six-dof points about `c`: $(6N + m) \times 6$, block row $k$
/// the [`rigid_motion_block`] of point $k$ at $\mathbf x_k - \mathbf c$, then `extra_rows` zero
/// rows (the modal coordinates of a reduced body, which rigid motions do not move).
pub fn rigid_modes(points: &[Vector3<f64>], c: &Vector3<f64>, extra_rows: usize) -> DMatrix<f64> {
    let mut P = DMatrix::zeros(6 * points.len() + extra_rows, 6);
    for (k, x) in points.iter().enumerate() {
        P.fixed_view_mut::<6, 6>(6 * k, 0)
            .copy_from(&rigid_motion_block(&(x - c)));
    }
    P
}
