//! Units of the joint coordinates: which scalar coordinate of a [`JointKind`] is an angle
//! (radians) and which a length (metres), for sensor headers and driver efforts.

use crate::model::JointKind;

/// What a scalar joint coordinate measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoordinateQuantity {
    /// A rotation angle $\theta$ \[rad\]; its effort is a moment \[N m\].
    Angle,
    /// A translation $s$ \[m\]; its effort is a force \[N\].
    Length,
}

impl CoordinateQuantity {
    /// The SI unit of the coordinate.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Angle => "rad",
            Self::Length => "m",
        }
    }

    /// The SI unit of the coordinate's time derivative.
    pub fn rate_unit(self) -> &'static str {
        match self {
            Self::Angle => "rad/s",
            Self::Length => "m/s",
        }
    }

    /// The SI unit of the generalised force that does work on the coordinate.
    pub fn effort_unit(self) -> &'static str {
        match self {
            Self::Angle => "N m",
            Self::Length => "N",
        }
    }
}

impl JointKind {
    /// What scalar coordinate `coordinate` (0-based, as in [`JointKind`]'s docs) measures:
    /// $s$ of prismatic joints, the first of cylindrical and the first two of planar joints are
    /// lengths, every other coordinate an angle.
    pub fn coordinate_quantity(&self, coordinate: usize) -> CoordinateQuantity {
        let length = match self {
            JointKind::Prismatic { .. } => true,
            JointKind::Cylindrical { .. } => coordinate == 0,
            JointKind::Planar { .. } => coordinate < 2,
            JointKind::Spherical | JointKind::Revolute { .. } | JointKind::Universal { .. } => false,
        };
        if length {
            CoordinateQuantity::Length
        } else {
            CoordinateQuantity::Angle
        }
    }
}
