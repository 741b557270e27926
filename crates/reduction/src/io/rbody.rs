//! The reduced-body file, `NAME.rbody`: a [`ReducedBody`] saved once and reused by many
//! studies (the role of Adams' MNF or Simpack's SID file, theory guide §1). Reading it back gives a
//! body identical to the one written, bit for bit in every `f64`.
//!
//! # Why one file, half text and half binary
//!
//! - **One file**, not a directory: it is one artifact to copy, cache and delete; [`write()`]
//!   replaces it atomically (temporary file and rename), so a study never sees half a body;
//!   and one set of checksums covers all of it. A directory of JSON and array files can be
//!   copied in part and cannot be replaced in one step.
//! - **A readable JSON metadata block** first: `head -c 4000 beam.rbody` shows the name,
//!   interfaces, frequencies, mass data and the index of the arrays, which is what a person
//!   checks when a study behaves oddly.
//! - **Raw little-endian `f64` arrays** after it: exact by construction, 8 bytes a value
//!   (text would take about 24 and need a correctly rounded parser), and readable from any
//!   language with the offsets in the index (Python:
//!   `numpy.frombuffer(data, '<f8', count=rows*cols, offset=binary_start+offset)
//!   .reshape((rows, cols), order='F')`).
//!
//! The JSON scalars (mass, centre of mass, inertia, positions, frequencies) are exact too:
//! serde_json writes the shortest decimal that rounds back to the same `f64` and this crate
//! enables its `float_roundtrip` feature, so that the reading is correctly rounded.
//!
//! # Layout, format version 3
//!
//! ```text
//! FLEXMBS-RBODY 3\n                         magic and format version: this line never changes shape
//! metadata <bytes> crc32 <8 hex digits>\n   length and CRC-32 of the JSON block
//! <JSON metadata, <bytes> bytes>\n          Metadata: scalars and the array index
//! <arrays>                                  f64 little-endian, column-major, back to back
//! ```
//!
//! The arrays come in this order, each listed in the index with its name, shape, byte offset
//! from the first array, byte count and CRC-32 (IEEE 802.3, the one of zlib and Python's
//! `binascii.crc32`; see [`crc32`]): `K_CB` and `M_CB` ($n \times n$, $n = 6N + m$), `S_t`,
//! `S_r` ($3 \times n$), `S_x` ($9 \times n$), the nine `S_bar[kl]` ($n \times n$, $k, l \in
//! \{x, y, z\}$, entry $3k + l$ of [`InertiaData::S_bar`]), `Phi_com` ($6 \times n$), with
//! geometric stiffness (metadata `geometric_stiffness: true`) the $n$ matrices `G[k]`
//! ($n \times n$, [`ReducedBody::geometric_stiffness`]), with mesh shapes `mesh.nodes`
//! ($3 \times n_{nodes}$) and `mesh.shapes` ($6 n_{nodes} \times n$), with stress shapes
//! (metadata `stress`: the solid node count and the beams with their sections)
//! `stress.nodal` ($6 n_{nodes} \times n$) and `stress.solid_node` ($1 \times n_{nodes}$, 1
//! where a solid element holds the node) when the body has solids, then `stress.beams`
//! ($12 n_{beams} \times n$), and one `load_point[name]` ($6 \times n$) per load point
//! (metadata `load_points`, [`ReducedBody::load_points`]).
//!
//! # Versions
//!
//! The first line is read before anything else, so a build that meets a newer file says
//! which version the file has and which it reads, instead of failing somewhere in the JSON.
//! A change of [`ReducedBody`] or of this layout increments [`FORMAT_VERSION`].
//!
//! - Version 1: the layout above without `G[k]`; its metadata has no `geometric_stiffness`
//!   field. Still read: it gives a body without geometric stiffness, marked with the current
//!   [`FORMAT_VERSION`] (a version-1 file is a version-2 body without `G`, nothing is lost).
//! - Version 2: the optional `G[k]` arrays and the metadata field `geometric_stiffness`.
//!   Still read, as a body without stress shapes or load points.
//! - Version 3: the optional stress shapes, load points and the metadata fields `stress`,
//!   `load_points`, `attachment_modes`.
//!
//! # Errors
//!
//! Reading never panics on a damaged file (`tests/unit/file_format.rs` feeds it every
//! truncation and thousands of random byte changes of a small body's file). Every error is a
//! [`ReductionError::BodyFile`] naming the file, with a [`BodyFileProblem`] that says what is
//! wrong: wrong magic, unsupported version, truncated metadata or array (which array,
//! expected and found bytes), checksum mismatch (which block), malformed JSON (line and
//! column), inconsistent shapes, trailing bytes.

#![allow(non_snake_case)]

pub use crate::error::BodyFileProblem;
use crate::error::ReductionError;
pub use crate::reduced_body::MAGIC;
use crate::reduced_body::{
    BeamStressElement, DenseMatrix, InertiaData, InterfacePoint, LoadPoint, MeshModes, ReducedBody, StressShapes,
    FORMAT_VERSION, OLDEST_READABLE,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file extension [`write()`] callers should use (not enforced).
pub const EXTENSION: &str = "rbody";

/// The JSON metadata block (format versions 1 and 2). Everything that is not a dense array.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Metadata {
    format_version: u32,
    name: String,
    interfaces: Vec<InterfacePoint>,
    n_modes: usize,
    /// Circular frequencies (rad/s) of the fixed-interface modes.
    fixed_interface_omega: Vec<f64>,
    mass: f64,
    center_of_mass: [f64; 3],
    inertia_com: [[f64; 3]; 3],
    auxiliary_interface: Option<usize>,
    /// Number of mesh nodes when mesh shapes are stored.
    mesh_nodes: Option<usize>,
    /// Whether the `G[k]` arrays are stored (version 2; absent, hence false, in version 1).
    #[serde(default)]
    geometric_stiffness: bool,
    /// Stress shapes (version 3; absent before): the `stress.*` arrays.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stress: Option<StressMetadata>,
    /// Load points of static correction (version 3): one `load_point[name]` array each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    load_points: Vec<LoadPointMetadata>,
    /// How many of the modes are attachment modes (version 3).
    #[serde(default, skip_serializing_if = "is_zero")]
    attachment_modes: usize,
    arrays: Vec<ArrayEntry>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// What the metadata says of the stress shapes ([`StressShapes`]).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StressMetadata {
    /// Mesh nodes of the solid stress arrays `stress.nodal` and `stress.solid_node`, when stored.
    nodes: Option<usize>,
    /// The beams of the rows of `stress.beams`.
    beams: Vec<BeamStressElement>,
}

/// A load point without its shape (the array `load_point[name]`).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LoadPointMetadata {
    name: String,
    node: u32,
    position: [f64; 3],
}

/// One array of the binary section.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
struct ArrayEntry {
    name: String,
    rows: usize,
    cols: usize,
    /// Byte offset from the start of the array section.
    offset: u64,
    /// `8 * rows * cols`.
    bytes: u64,
    /// CRC-32 of the bytes, 8 hex digits.
    crc32: String,
}

/// CRC-32 (IEEE 802.3, reflected polynomial `0xEDB88320`, initial value and final xor
/// `0xFFFFFFFF`): the checksum of zlib, gzip and Python's `binascii.crc32`, so a reader in
/// another language can verify a file with its standard library. `crc32(b"123456789") ==
/// 0xCBF43926`, the standard check value.
pub fn crc32(bytes: &[u8]) -> u32 {
    const TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
                k += 1;
            }
            table[i] = c;
            i += 1;
        }
        table
    };
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c = TABLE[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8);
    }
    c ^ 0xFFFF_FFFF
}

const AXES: [char; 3] = ['x', 'y', 'z'];

/// Name, rows and columns of every array, in file order, for a body with `n_interfaces`,
/// `n_modes`, (when stored) `geometric` stiffness and (when mesh shapes are stored)
/// `mesh_nodes`. Checked arithmetic: the counts may come from a damaged file.
fn expected_arrays(
    n_interfaces: usize,
    n_modes: usize,
    geometric: bool,
    mesh_nodes: Option<usize>,
    stress: Option<(Option<usize>, usize)>,
    load_points: &[&str],
) -> Result<Vec<(String, usize, usize)>, String> {
    let n = n_interfaces
        .checked_mul(6)
        .and_then(|b| b.checked_add(n_modes))
        .ok_or_else(|| format!("6 x {n_interfaces} interfaces + {n_modes} modes overflows"))?;
    let mut list = vec![
        ("K_CB".to_string(), n, n),
        ("M_CB".to_string(), n, n),
        ("S_t".to_string(), 3, n),
        ("S_r".to_string(), 3, n),
        ("S_x".to_string(), 9, n),
    ];
    for k in 0..3 {
        for l in 0..3 {
            list.push((format!("S_bar[{}{}]", AXES[k], AXES[l]), n, n));
        }
    }
    list.push(("Phi_com".to_string(), 6, n));
    if geometric {
        list.extend((0..n).map(|k| (format!("G[{k}]"), n, n)));
    }
    if let Some(nodes) = mesh_nodes {
        let slots = nodes
            .checked_mul(6)
            .ok_or_else(|| format!("6 x {nodes} mesh nodes overflows"))?;
        list.push(("mesh.nodes".to_string(), 3, nodes));
        list.push(("mesh.shapes".to_string(), slots, n));
    }
    if let Some((solid_nodes, beams)) = stress {
        if let Some(nodes) = solid_nodes {
            let rows = nodes
                .checked_mul(6)
                .ok_or_else(|| format!("6 x {nodes} stress nodes overflows"))?;
            list.push(("stress.nodal".to_string(), rows, n));
            list.push(("stress.solid_node".to_string(), 1, nodes));
        }
        let rows = beams
            .checked_mul(12)
            .ok_or_else(|| format!("12 x {beams} beams overflows"))?;
        list.push(("stress.beams".to_string(), rows, n));
    }
    list.extend(load_points.iter().map(|name| (format!("load_point[{name}]"), 6, n)));
    Ok(list)
}

/// The arrays of the optional parts of format version 3 (stress shapes, load points), in file
/// order after the mesh shapes, as owned values.
fn version3_arrays(body: &ReducedBody) -> Vec<(String, usize, usize, Vec<f64>)> {
    let mut list = Vec::new();
    if let Some(stress) = &body.stress {
        if let Some(nodal) = &stress.nodal {
            list.push(("stress.nodal".to_string(), nodal.nrows, nodal.ncols, nodal.data.clone()));
            let flags = stress.solid_node.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect();
            list.push(("stress.solid_node".to_string(), 1, stress.solid_node.len(), flags));
        }
        let f = &stress.beam_forces;
        list.push(("stress.beams".to_string(), f.nrows, f.ncols, f.data.clone()));
    }
    for p in &body.load_points {
        list.push((
            format!("load_point[{}]", p.name),
            p.shape.nrows,
            p.shape.ncols,
            p.shape.data.clone(),
        ));
    }
    list
}

/// The metadata's view of a body's stress shapes: solid nodes and beam count.
fn stress_counts(stress: Option<&StressMetadata>) -> Option<(Option<usize>, usize)> {
    stress.map(|s| (s.nodes, s.beams.len()))
}

/// Why an array of `rows` x `cols` must have that shape, for messages.
fn shape_rule(name: &str) -> &'static str {
    match name {
        "K_CB" | "M_CB" => "n x n with n = 6N + m (N interfaces, m modes)",
        "S_t" | "S_r" => "3 x n with n = 6N + m",
        "S_x" => "9 x n with n = 6N + m",
        "Phi_com" => "6 x n with n = 6N + m",
        "mesh.nodes" => "3 x (mesh nodes)",
        "mesh.shapes" => "6 (mesh nodes) x n with n = 6N + m",
        "stress.nodal" => "6 (stress nodes) x n with n = 6N + m",
        "stress.solid_node" => "1 x (stress nodes)",
        "stress.beams" => "12 (beams) x n with n = 6N + m",
        name if name.starts_with("load_point[") => "6 x n with n = 6N + m",
        _ => "n x n with n = 6N + m (N interfaces, m modes)",
    }
}

/// The body's arrays in file order, with their names.
fn body_arrays(body: &ReducedBody) -> Vec<(String, &DenseMatrix)> {
    let mut list = vec![
        ("K_CB".to_string(), &body.K_CB),
        ("M_CB".to_string(), &body.M_CB),
        ("S_t".to_string(), &body.inertia.S_t),
        ("S_r".to_string(), &body.inertia.S_r),
        ("S_x".to_string(), &body.inertia.S_x),
    ];
    for (kl, S) in body.inertia.S_bar.iter().enumerate() {
        list.push((format!("S_bar[{}{}]", AXES[(kl / 3) % 3], AXES[kl % 3]), S));
    }
    list.push(("Phi_com".to_string(), &body.Phi_com));
    for (k, G_k) in body.geometric_stiffness.iter().flatten().enumerate() {
        list.push((format!("G[{k}]"), G_k));
    }
    if let Some(mesh) = &body.mesh {
        list.push(("mesh.shapes".to_string(), &mesh.shapes));
    }
    list
}

/// Checks that a body's counts and shapes agree before it is written.
fn check_writable(body: &ReducedBody) -> Result<(), String> {
    if body.format_version != FORMAT_VERSION {
        return Err(format!(
            "it says format version {}, but this build writes version {FORMAT_VERSION} only",
            body.format_version
        ));
    }
    if body.fixed_interface_omega.len() != body.n_modes {
        return Err(format!(
            "{} frequencies for {} modes",
            body.fixed_interface_omega.len(),
            body.n_modes
        ));
    }
    if body.inertia.S_bar.len() != 9 {
        return Err(format!("S_bar holds {} matrices, not 9", body.inertia.S_bar.len()));
    }
    if let Some(aux) = body.auxiliary_interface {
        if aux >= body.interfaces.len() {
            return Err(format!(
                "auxiliary interface {aux} but only {} interfaces",
                body.interfaces.len()
            ));
        }
    }
    if let Some(G) = &body.geometric_stiffness {
        let n = body.n_coordinates();
        if G.len() != n {
            return Err(format!(
                "geometric stiffness holds {} matrices for n = {n} CB coordinates",
                G.len()
            ));
        }
    }
    if body.attachment_modes > body.n_modes {
        return Err(format!(
            "{} attachment modes but only {} modes",
            body.attachment_modes, body.n_modes
        ));
    }
    let names: Vec<&str> = body.load_points.iter().map(|p| p.name.as_str()).collect();
    let expected = expected_arrays(
        body.interfaces.len(),
        body.n_modes,
        body.geometric_stiffness.is_some(),
        body.mesh.as_ref().map(|m| m.nodes.len()),
        body.stress
            .as_ref()
            .map(|s| (s.nodal.as_ref().map(|_| s.solid_node.len()), s.beams.len())),
        &names,
    )?;
    let expected: Vec<_> = expected
        .into_iter()
        .filter(|(name, _, _)| name != "mesh.nodes")
        .collect();
    let extra = version3_arrays(body);
    let mut all: Vec<(String, usize, usize, usize)> = body_arrays(body)
        .into_iter()
        .map(|(name, A)| (name, A.nrows, A.ncols, A.data.len()))
        .collect();
    all.extend(extra.iter().map(|(name, r, c, d)| (name.clone(), *r, *c, d.len())));
    if all.len() != expected.len() {
        return Err(format!(
            "{} arrays where the counts ask for {}",
            all.len(),
            expected.len()
        ));
    }
    for ((name, rows, cols), (_, nrows, ncols, len)) in expected.iter().zip(all) {
        if nrows != *rows || ncols != *cols {
            return Err(format!(
                "{name} is {nrows} x {ncols} but must be {} = {rows} x {cols}",
                shape_rule(name)
            ));
        }
        if len != rows * cols {
            return Err(format!("{name} is {rows} x {cols} but holds {len} values"));
        }
    }
    // JSON has no NaN or infinity: refuse them here rather than write a file that cannot be
    // read back.
    let mut scalars: Vec<(String, f64)> = vec![("mass".into(), body.inertia.mass)];
    scalars.extend(
        body.inertia
            .center_of_mass
            .iter()
            .enumerate()
            .map(|(i, &v)| (format!("center_of_mass[{i}]"), v)),
    );
    for (i, row) in body.inertia.inertia_com.iter().enumerate() {
        scalars.extend(
            row.iter()
                .enumerate()
                .map(|(j, &v)| (format!("inertia_com[{i}][{j}]"), v)),
        );
    }
    scalars.extend(
        body.fixed_interface_omega
            .iter()
            .enumerate()
            .map(|(i, &v)| (format!("fixed_interface_omega[{i}]"), v)),
    );
    for p in &body.interfaces {
        scalars.extend(
            p.position
                .iter()
                .map(|&v| (format!("position of interface '{}'", p.name), v)),
        );
    }
    if let Some((what, v)) = scalars.iter().find(|(_, v)| !v.is_finite()) {
        return Err(format!("{what} is {v}, which JSON cannot hold"));
    }
    Ok(())
}

fn push_f64s(out: &mut Vec<u8>, values: impl Iterator<Item = f64>) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// The file's bytes for `body`. `destination` only names the file in errors (pass any label
/// when the bytes go elsewhere).
///
/// # Errors
/// [`BodyFileProblem::Unwritable`] when the body's own counts and shapes disagree or a JSON
/// scalar is not finite.
pub fn to_bytes(body: &ReducedBody, destination: &Path) -> Result<Vec<u8>, ReductionError> {
    let error = |problem| ReductionError::BodyFile {
        path: destination.to_path_buf(),
        problem,
    };
    check_writable(body).map_err(|what| error(BodyFileProblem::Unwritable { what }))?;
    let mut arrays: Vec<(String, usize, usize, Vec<u8>)> = Vec::new();
    let mut add = |name: String, rows: usize, cols: usize, values: &mut dyn Iterator<Item = f64>| {
        let mut bytes = Vec::with_capacity(8 * rows * cols);
        push_f64s(&mut bytes, values);
        arrays.push((name, rows, cols, bytes));
    };
    let mut list = body_arrays(body);
    let shapes = body.mesh.as_ref().map(|_| list.pop().expect("mesh.shapes is last"));
    for (name, A) in list {
        add(name, A.nrows, A.ncols, &mut A.data.iter().copied());
    }
    if let (Some(mesh), Some((name, S))) = (&body.mesh, shapes) {
        add(
            "mesh.nodes".into(),
            3,
            mesh.nodes.len(),
            &mut mesh.nodes.iter().flat_map(|x| x.iter().copied()),
        );
        add(name, S.nrows, S.ncols, &mut S.data.iter().copied());
    }
    for (name, rows, cols, data) in version3_arrays(body) {
        add(name, rows, cols, &mut data.into_iter());
    }
    let mut offset = 0u64;
    let index = arrays
        .iter()
        .map(|(name, rows, cols, bytes)| {
            let entry = ArrayEntry {
                name: name.clone(),
                rows: *rows,
                cols: *cols,
                offset,
                bytes: bytes.len() as u64,
                crc32: format!("{:08x}", crc32(bytes)),
            };
            offset += bytes.len() as u64;
            entry
        })
        .collect();
    let metadata = Metadata {
        format_version: FORMAT_VERSION,
        name: body.name.clone(),
        interfaces: body.interfaces.clone(),
        n_modes: body.n_modes,
        fixed_interface_omega: body.fixed_interface_omega.clone(),
        mass: body.inertia.mass,
        center_of_mass: body.inertia.center_of_mass,
        inertia_com: body.inertia.inertia_com,
        auxiliary_interface: body.auxiliary_interface,
        mesh_nodes: body.mesh.as_ref().map(|m| m.nodes.len()),
        geometric_stiffness: body.geometric_stiffness.is_some(),
        stress: body.stress.as_ref().map(|s| StressMetadata {
            nodes: s.nodal.as_ref().map(|_| s.solid_node.len()),
            beams: s.beams.clone(),
        }),
        load_points: body
            .load_points
            .iter()
            .map(|p| LoadPointMetadata {
                name: p.name.clone(),
                node: p.node,
                position: p.position,
            })
            .collect(),
        attachment_modes: body.attachment_modes,
        arrays: index,
    };
    let json = serde_json::to_vec_pretty(&metadata).map_err(|e| {
        error(BodyFileProblem::Unwritable {
            what: format!("JSON encoding failed: {e}"),
        })
    })?;
    let mut out = Vec::with_capacity(json.len() + offset as usize + 64);
    out.extend_from_slice(format!("{MAGIC} {FORMAT_VERSION}\n").as_bytes());
    out.extend_from_slice(format!("metadata {} crc32 {:08x}\n", json.len(), crc32(&json)).as_bytes());
    out.extend_from_slice(&json);
    out.push(b'\n');
    for (_, _, _, bytes) in &arrays {
        out.extend_from_slice(bytes);
    }
    Ok(out)
}

/// Writes `body` to `path` (conventionally `NAME.rbody`), replacing any existing file
/// atomically: the bytes go to a temporary file in the same directory, which is then
/// renamed, so a reader sees the old file or the new one, never a partial one.
pub fn write(body: &ReducedBody, path: &Path) -> Result<(), ReductionError> {
    let bytes = to_bytes(body, path)?;
    let io = |action: &'static str, e: std::io::Error| ReductionError::BodyFile {
        path: path.to_path_buf(),
        problem: BodyFileProblem::Io {
            action,
            message: e.to_string(),
        },
    };
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "body".into());
    // Unique per process and per call, so that concurrent writers (two runs sharing a cache,
    // two threads of one) never share a temporary file.
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_file_name(format!(".{file_name}.tmp-{}-{n}", std::process::id()));
    // A failed write (a full disk) leaves no partial temporary behind.
    std::fs::write(&tmp, &bytes).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io("write", e)
    })?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io("replace", e)
    })
}

/// Reads a reduced-body file written by [`write()`] and checks its physics
/// ([`crate::checks`]).
pub fn read(path: &Path) -> Result<ReducedBody, ReductionError> {
    checked(read_unchecked(path)?, path)
}

/// Parses the bytes of a reduced-body file and checks its physics ([`crate::checks`]);
/// `origin` names it in errors. Never panics.
pub fn from_bytes(bytes: &[u8], origin: &Path) -> Result<ReducedBody, ReductionError> {
    checked(from_bytes_unchecked(bytes, origin)?, origin)
}

/// `body` if [`crate::checks::physical_problems`] finds nothing, else the error naming them.
fn checked(body: ReducedBody, origin: &Path) -> Result<ReducedBody, ReductionError> {
    let problems = crate::checks::physical_problems(&body);
    if problems.is_empty() {
        Ok(body)
    } else {
        Err(ReductionError::BodyFile {
            path: PathBuf::from(origin),
            problem: BodyFileProblem::Physics { problems },
        })
    }
}

/// [`from_bytes`] without the physical checks: for `inspect`, which reports them.
pub fn from_bytes_unchecked(bytes: &[u8], origin: &Path) -> Result<ReducedBody, ReductionError> {
    parse(bytes).map_err(|problem| ReductionError::BodyFile {
        path: PathBuf::from(origin),
        problem,
    })
}

/// [`read`] without the physical checks (see [`from_bytes_unchecked`]).
pub fn read_unchecked(path: &Path) -> Result<ReducedBody, ReductionError> {
    let bytes = fe_model::input::read(path).map_err(|e| ReductionError::BodyFile {
        path: path.to_path_buf(),
        problem: BodyFileProblem::Io {
            action: "read",
            message: e.to_string(),
        },
    })?;
    from_bytes_unchecked(&bytes, path)
}

/// The next line (without its `\n`) from `start`, looking at most `limit` bytes ahead: header
/// lines are short, and a damaged file must not make us scan megabytes of binary for a
/// newline.
fn header_line(bytes: &[u8], start: usize, limit: usize) -> Option<(&[u8], usize)> {
    let window = &bytes[start.min(bytes.len())..bytes.len().min(start.saturating_add(limit))];
    let end = window.iter().position(|&b| b == b'\n')?;
    Some((&window[..end], start + end + 1))
}

/// A whole number in the one form [`to_bytes`] writes it (no sign, no leading zero): the
/// header lines are outside the checksums, so only their canonical form is accepted, and every
/// change to them is detected.
fn canonical_number(text: &str) -> Option<u64> {
    let value: u64 = text.parse().ok()?;
    (value.to_string() == text).then_some(value)
}

/// A CRC-32 as [`to_bytes`] writes it: exactly 8 lower-case hex digits.
fn canonical_crc(text: &str) -> Option<u32> {
    let ok = text.len() == 8 && text.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b));
    ok.then(|| u32::from_str_radix(text, 16).ok()).flatten()
}

/// A short printable rendering of raw bytes, for messages.
fn printable(bytes: &[u8]) -> String {
    String::from_utf8_lossy(&bytes[..bytes.len().min(24)]).into_owned()
}

fn parse(bytes: &[u8]) -> Result<ReducedBody, BodyFileProblem> {
    let (version, next) = read_version(bytes)?;
    let (meta, json_end) = read_metadata(bytes, next)?;
    check_metadata(&meta, version)?;
    let (expected, values) = read_arrays(&meta, &bytes[json_end + 1..])?;
    Ok(assemble(meta, &expected, values))
}

/// Line 1: magic and version, read before anything else (module docs, "Versions"); the
/// version and where line 2 starts.
fn read_version(bytes: &[u8]) -> Result<(u64, usize), BodyFileProblem> {
    let magic = format!("{MAGIC} ");
    if !bytes.starts_with(magic.as_bytes()) {
        return Err(BodyFileProblem::WrongMagic {
            found: printable(bytes),
        });
    }
    let (line1, next) = header_line(bytes, 0, 64).ok_or_else(|| BodyFileProblem::Header {
        line: 1,
        what: "no end of line within 64 bytes after the magic".into(),
    })?;
    let version_text = std::str::from_utf8(&line1[magic.len()..]).unwrap_or("");
    let version = canonical_number(version_text).ok_or_else(|| BodyFileProblem::Header {
        line: 1,
        what: format!(
            "'{}' is not a format version (a whole number)",
            printable(&line1[magic.len()..])
        ),
    })?;
    if !(OLDEST_READABLE as u64..=FORMAT_VERSION as u64).contains(&version) {
        return Err(BodyFileProblem::UnsupportedVersion {
            found: version,
            supported: FORMAT_VERSION,
        });
    }

    Ok((version, next))
}

/// Line 2 (`metadata <bytes> crc32 <hex>`, starting at `next`) and the JSON block it
/// announces: the metadata and where the block ends (at its newline).
fn read_metadata(bytes: &[u8], next: usize) -> Result<(Metadata, usize), BodyFileProblem> {
    let line2_error = |what: String| BodyFileProblem::Header { line: 2, what };
    let (line2, json_start) =
        header_line(bytes, next, 128).ok_or_else(|| line2_error("no end of line within 128 bytes".into()))?;
    let line2 = std::str::from_utf8(line2).map_err(|_| line2_error(format!("not text: {:?}", printable(line2))))?;
    let words: Vec<&str> = line2.split(' ').collect();
    let (json_len, json_crc) = match words.as_slice() {
        ["metadata", len, "crc32", crc] => (
            canonical_number(len).ok_or_else(|| line2_error(format!("'{len}' is not a byte count")))?,
            canonical_crc(crc).ok_or_else(|| line2_error(format!("'{crc}' is not 8 lower-case hex digits")))?,
        ),
        _ => {
            return Err(line2_error(format!(
                "expected 'metadata <bytes> crc32 <8 hex digits>', found '{line2}'"
            )))
        }
    };
    let available = (bytes.len() - json_start) as u64;
    // The JSON block and the newline after it.
    if json_len >= available {
        return Err(BodyFileProblem::TruncatedMetadata {
            expected: json_len.saturating_add(1),
            found: available,
        });
    }
    let json_end = json_start + json_len as usize;
    let json = &bytes[json_start..json_end];
    let computed = crc32(json);
    if computed != json_crc {
        return Err(BodyFileProblem::Checksum {
            block: "metadata".into(),
            stored: json_crc,
            computed,
        });
    }
    if bytes[json_end] != b'\n' {
        return Err(BodyFileProblem::Header {
            line: 3,
            what: format!(
                "the metadata block must end with a newline, found byte {:#04x}",
                bytes[json_end]
            ),
        });
    }
    let meta: Metadata = serde_json::from_slice(json).map_err(|e| BodyFileProblem::Json {
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    Ok((meta, json_end))
}

/// The metadata's counts agree with each other and with the file's `version`.
fn check_metadata(meta: &Metadata, version: u64) -> Result<(), BodyFileProblem> {
    let shape = |what: String| BodyFileProblem::Shape { what };
    if meta.format_version as u64 != version {
        return Err(shape(format!(
            "the metadata says format version {} but the first line says {version}",
            meta.format_version
        )));
    }
    if version == 1 && meta.geometric_stiffness {
        return Err(shape(
            "the metadata says geometric_stiffness, which format version 1 does not have".into(),
        ));
    }
    if version < 3 && (meta.stress.is_some() || !meta.load_points.is_empty() || meta.attachment_modes > 0) {
        return Err(shape(format!(
            "the metadata has stress shapes, load points or attachment modes, which format version {version} does not have"
        )));
    }
    if meta.attachment_modes > meta.n_modes {
        return Err(shape(format!(
            "attachment_modes = {} but n_modes = {}",
            meta.attachment_modes, meta.n_modes
        )));
    }
    if meta.fixed_interface_omega.len() != meta.n_modes {
        return Err(shape(format!(
            "{} fixed-interface frequencies for n_modes = {}",
            meta.fixed_interface_omega.len(),
            meta.n_modes
        )));
    }
    if let Some(aux) = meta.auxiliary_interface {
        if aux >= meta.interfaces.len() {
            return Err(shape(format!(
                "auxiliary_interface = {aux} but there are {} interfaces",
                meta.interfaces.len()
            )));
        }
    }
    Ok(())
}

/// The array index checked against the arrays the metadata implies, and the arrays read
/// from `binary` (what follows the metadata block), each against its checksum.
#[allow(clippy::type_complexity)]
fn read_arrays(
    meta: &Metadata,
    binary: &[u8],
) -> Result<(Vec<(String, usize, usize)>, Vec<Vec<f64>>), BodyFileProblem> {
    let shape = |what: String| BodyFileProblem::Shape { what };
    // The index: names, shapes and offsets as the format prescribes, checked before any
    // allocation so that damaged counts cannot ask for absurd memory.
    let names: Vec<&str> = meta.load_points.iter().map(|p| p.name.as_str()).collect();
    let expected = expected_arrays(
        meta.interfaces.len(),
        meta.n_modes,
        meta.geometric_stiffness,
        meta.mesh_nodes,
        stress_counts(meta.stress.as_ref()),
        &names,
    )
    .map_err(shape)?;
    if meta.arrays.len() != expected.len() {
        return Err(shape(format!(
            "the index lists {} arrays; a body with {} interfaces, {} modes, {} and {} holds {}",
            meta.arrays.len(),
            meta.interfaces.len(),
            meta.n_modes,
            if meta.geometric_stiffness {
                "geometric stiffness"
            } else {
                "no geometric stiffness"
            },
            if meta.mesh_nodes.is_some() {
                "mesh shapes"
            } else {
                "no mesh shapes"
            },
            expected.len()
        )));
    }
    let mut offset = 0u64;
    let mut values: Vec<Vec<f64>> = Vec::with_capacity(expected.len());
    for (k, (entry, (name, rows, cols))) in meta.arrays.iter().zip(&expected).enumerate() {
        if &entry.name != name {
            return Err(shape(format!(
                "array {k} of the index is '{}' where '{name}' belongs",
                entry.name
            )));
        }
        if (entry.rows, entry.cols) != (*rows, *cols) {
            return Err(shape(format!(
                "{name} is {} x {} but must be {} = {rows} x {cols}",
                entry.rows,
                entry.cols,
                shape_rule(name)
            )));
        }
        let needed = (*rows as u64)
            .checked_mul(*cols as u64)
            .and_then(|c| c.checked_mul(8))
            .ok_or_else(|| shape(format!("{name}: {rows} x {cols} values overflow a byte count")))?;
        if entry.bytes != needed {
            return Err(shape(format!(
                "{name}: the index says {} bytes, {rows} x {cols} values take {needed}",
                entry.bytes
            )));
        }
        if entry.offset != offset {
            return Err(shape(format!(
                "{name} is at offset {} but the arrays before it end at {offset}",
                entry.offset
            )));
        }
        let stored = canonical_crc(&entry.crc32).ok_or_else(|| {
            shape(format!(
                "{name}: crc32 '{}' is not 8 lower-case hex digits",
                entry.crc32
            ))
        })?;
        let found = (binary.len() as u64).saturating_sub(offset);
        if found < needed {
            return Err(BodyFileProblem::TruncatedArray {
                array: name.clone(),
                offset,
                expected: needed,
                found,
            });
        }
        let chunk = &binary[offset as usize..(offset + needed) as usize];
        let computed = crc32(chunk);
        if computed != stored {
            return Err(BodyFileProblem::Checksum {
                block: name.clone(),
                stored,
                computed,
            });
        }
        values.push(
            chunk
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("chunks of 8")))
                .collect(),
        );
        offset += needed;
    }
    if binary.len() as u64 > offset {
        return Err(BodyFileProblem::TrailingBytes {
            count: binary.len() as u64 - offset,
            expected: offset,
        });
    }
    Ok((expected, values))
}

/// The body of the checked metadata and arrays.
fn assemble(meta: Metadata, expected: &[(String, usize, usize)], values: Vec<Vec<f64>>) -> ReducedBody {
    // In file order (`expected_arrays`), each array taken once.
    let mut arrays = values
        .into_iter()
        .zip(expected)
        .map(|(data, (_, rows, cols))| DenseMatrix {
            nrows: *rows,
            ncols: *cols,
            data,
        });
    let mut next_matrix = || arrays.next().expect("one value list per expected array");
    let K_CB = next_matrix();
    let M_CB = next_matrix();
    let S_t = next_matrix();
    let S_r = next_matrix();
    let S_x = next_matrix();
    let S_bar = (0..9).map(|_| next_matrix()).collect();
    let Phi_com = next_matrix();
    let n = K_CB.nrows;
    let geometric_stiffness = meta
        .geometric_stiffness
        .then(|| (0..n).map(|_| next_matrix()).collect());
    let mesh = meta.mesh_nodes.map(|_| {
        let nodes = next_matrix().data.chunks_exact(3).map(|x| [x[0], x[1], x[2]]).collect();
        MeshModes {
            nodes,
            shapes: next_matrix(),
        }
    });
    let stress = meta.stress.map(|s| {
        let (nodal, solid_node) = match s.nodes {
            Some(_) => (
                Some(next_matrix()),
                next_matrix().data.iter().map(|&f| f != 0.0).collect(),
            ),
            None => (None, Vec::new()),
        };
        StressShapes {
            nodal,
            solid_node,
            beams: s.beams,
            beam_forces: next_matrix(),
        }
    });
    let load_points = meta
        .load_points
        .into_iter()
        .map(|p| LoadPoint {
            name: p.name,
            node: p.node,
            position: p.position,
            shape: next_matrix(),
        })
        .collect();
    ReducedBody {
        // A version-1 file reads as a current body without geometric stiffness (module docs).
        format_version: FORMAT_VERSION,
        name: meta.name,
        interfaces: meta.interfaces,
        n_modes: meta.n_modes,
        fixed_interface_omega: meta.fixed_interface_omega,
        K_CB,
        M_CB,
        inertia: InertiaData {
            mass: meta.mass,
            center_of_mass: meta.center_of_mass,
            inertia_com: meta.inertia_com,
            S_t,
            S_r,
            S_x,
            S_bar,
        },
        Phi_com,
        auxiliary_interface: meta.auxiliary_interface,
        mesh,
        geometric_stiffness,
        stress,
        load_points,
        attachment_modes: meta.attachment_modes,
    }
}
