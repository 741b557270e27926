//! [`NodeMotion`]: a node's state in $\mathbb R^3\times SO(3)$ with its velocities and
//! accelerations (inertial axes; angular velocity and acceleration spatial, $\dot{\mathbf R} =
//! \tilde{\boldsymbol\omega}\mathbf R$).

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Configuration, velocity and acceleration of a node.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodeMotion {
    pub r: Vector3<f64>,
    pub R: UnitQuaternion<f64>,
    pub v: Vector3<f64>,
    pub omega: Vector3<f64>,
    pub a: Vector3<f64>,
    pub alpha: Vector3<f64>,
}
