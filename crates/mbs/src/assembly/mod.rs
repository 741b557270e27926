//! The model turned into equations: the coordinate maps and the tree of the joints, the
//! elements of the bodies and joint forces, and the [`System`](system::System) that assembles
//! them into residuals and tangents in the independent coordinates.

pub mod body;
pub mod coordinates;
pub mod dense_lu;
pub mod force_law;
pub mod initial;
pub mod joint_forces;
pub mod planar;
pub mod system;
pub mod topology;
