//! One self-contained HTML page that animates the results of a flexmbs run: three.js (vendored,
//! `vendor/`) and the data inlined, so the page opens from `file://` with no server and makes
//! no network request.
//!
//! # The data: what the formulation has, not a mesh per frame
//!
//! A flexible body is drawn as its undeformed surface (the outer faces of its solids, its shells,
//! its beams as tubes) with the shapes of the surface vertices, and each frame carries only the
//! body's floating frame and elastic coordinates. A vertex at body coordinates $\mathbf x$
//! (relative to the frame origin) with shape rows $\mathbf S(\mathbf x)$ is at
//!
//! $$\mathbf p = \mathbf r_j + \mathbf R_j(\mathbf x + \mathbf S(\mathbf x)\mathbf q^{jj}),$$
//!
//! the recovery of the superelement crate. A tube vertex at offset $\mathbf d$ from its beam node
//! has the shape rows $\mathbf S_t - \tilde{\mathbf d}\mathbf S_r$ ($\tilde{\mathbf d}$ the cross-product matrix of $\mathbf d$; linear in $\mathbf q$). The
//! stress of a vertex is $\boldsymbol\Sigma(\mathbf x)\mathbf q^{jj}$ (six components, body axes)
//! and its von Mises stress is computed in the page. Rigid bodies and point masses use the same
//! form without shapes. Mode shapes are poses too: the page animates between the pose the
//! modes are about ([`Analysis::base`]) and each mode's pose.
//!
//! Arrays of numbers are base64 float32 (or u32) in the page ([`F32s`], [`U32s`]); poses and
//! times are JSON numbers (f64).

pub mod base64;
mod page;

pub use page::{data_of_page, page};

use serde::{Deserialize, Serialize};

/// Numbers stored as little-endian float32, base64 in JSON.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct F32s(pub Vec<f32>);

/// Indices stored as little-endian u32, base64 in JSON.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct U32s(pub Vec<u32>);

macro_rules! base64_array {
    ($t:ident, $e:ty) => {
        impl Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let bytes: Vec<u8> = self.0.iter().flat_map(|x| x.to_le_bytes()).collect();
                s.serialize_str(&base64::encode(&bytes))
            }
        }
        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let text = String::deserialize(d)?;
                let bytes = base64::decode(&text).map_err(serde::de::Error::custom)?;
                if bytes.len() % 4 != 0 {
                    return Err(serde::de::Error::custom("base64 array: not a whole number of 4-byte values"));
                }
                Ok($t(bytes
                    .chunks_exact(4)
                    .map(|c| <$e>::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect()))
            }
        }
    };
}
base64_array!(F32s, f32);
base64_array!(U32s, u32);

impl F32s {
    /// The values of `x` rounded to float32.
    pub fn from_f64(x: impl IntoIterator<Item = f64>) -> Self {
        Self(x.into_iter().map(|v| v as f32).collect())
    }
}

/// Everything a page shows: the analyses of one run that have something to draw or plot.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// The study's name (the page's title).
    pub title: String,
    pub analyses: Vec<Analysis>,
}

/// One analysis: its bodies, and either frames over time (or load factor) or mode shapes, and
/// its sensors.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Analysis {
    pub name: String,
    /// `dynamic`, `modal`, `buckling`, `static`, `reduce`, `equilibrium`, ...
    pub kind: String,
    pub bodies: Vec<Body>,
    /// Joints, grounds and interface nodes.
    pub markers: Vec<Marker>,
    /// The label of the frames' key: `t [s]`, `load factor [-]`.
    pub key_label: String,
    /// Poses over time (or load factor), in order.
    pub frames: Vec<Frame>,
    /// The pose the modes are about (an identity pose without shapes for a part's modes).
    pub base: Option<Frame>,
    pub modes: Vec<Mode>,
    pub sensors: Vec<Sensor>,
}

/// How a body is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BodyKind {
    #[default]
    Flexible,
    Rigid,
}

/// A body: its undeformed surface in body axes and the shapes of its vertices (module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Body {
    pub name: String,
    pub kind: BodyKind,
    /// The frame origin in the body's reference coordinates (m); vertices are relative to it.
    pub origin: [f64; 3],
    /// Vertex coordinates relative to `origin`, body axes, 3 per vertex (m).
    pub vertices: F32s,
    /// Triangles, 3 vertex indices each.
    pub triangles: U32s,
    /// Segments drawn as lines (a body without a surface: a rigid body's nodes joined), 2 each.
    pub lines: U32s,
    /// The mesh node of each vertex (0-based index in the body's mesh, as in the VTU files).
    pub vertex_node: U32s,
    /// The label of each mesh node in its source file (empty when unknown).
    pub node_labels: Vec<u64>,
    /// Number of shapes (elastic coordinates).
    pub n_shapes: usize,
    /// Shape `k` of vertex `i`, component `c` at `3 n_vertices k + 3 i + c` (m per unit coordinate).
    pub shapes: F32s,
    /// Stress shapes: component `c` (Voigt `xx, yy, zz, xy, yz, zx`) of shape `k` at vertex `i`
    /// at `6 n_vertices k + 6 i + c` (Pa per unit coordinate); empty without stresses.
    pub stress: F32s,
    /// Vertices with a stress (solid nodes), 1 or 0 each; empty: every vertex when `stress` is given.
    pub stressed: U32s,
}

impl Body {
    pub fn n_vertices(&self) -> usize {
        self.vertices.0.len() / 3
    }
}

/// A marker: a small shape at a point, at `position` or where each frame puts it
/// ([`Frame::markers`]), or attached to a body (`body`: body coordinates relative to its origin).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    pub name: String,
    /// `joint`, `ground`, `mass`; on the page of a model before it runs also `interface`,
    /// `load` (a force) and `moment`.
    pub kind: String,
    pub body: Option<usize>,
    pub position: [f64; 3],
    /// A load's direction (world axes), drawn as an arrow onto the point (a moment's: along
    /// its axis); none for the other kinds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
}

/// The pose of every body at one key (time, load factor or mode number).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    pub key: f64,
    pub poses: Vec<Pose>,
    /// The position of each marker of the analysis (m); empty: the markers' own positions.
    #[serde(default)]
    pub markers: Vec<[f64; 3]>,
}

/// A body's floating frame and elastic coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Frame origin (m).
    pub r: [f64; 3],
    /// Frame orientation as a unit quaternion `[x, y, z, w]`.
    pub q: [f64; 4],
    /// Elastic coordinates, one per shape.
    pub eta: Vec<f64>,
}

impl Pose {
    /// The pose at `r` without rotation and with `n` zero coordinates.
    pub fn at(r: [f64; 3], n: usize) -> Self {
        Self {
            r,
            q: [0.0, 0.0, 0.0, 1.0],
            eta: vec![0.0; n],
        }
    }
}

/// One mode: its label (`mode 2`), frequency (Hz) or other value (`load factor 3.2`), and the
/// pose of its shape.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    pub label: String,
    pub frequency: Option<f64>,
    pub pose: Frame,
}

/// A sensor: its columns (`name [unit]`) over the abscissa of its analysis.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sensor {
    pub name: String,
    pub x_label: String,
    pub columns: Vec<String>,
    pub x: F32s,
    /// Column `c` of row `k` at `n_columns k + c`.
    pub values: F32s,
}

impl Analysis {
    /// Whether the analysis has something to show (bodies with frames or modes, or sensors).
    pub fn has_content(&self) -> bool {
        !self.bodies.is_empty() && (!self.frames.is_empty() || !self.modes.is_empty()) || !self.sensors.is_empty()
    }
}
