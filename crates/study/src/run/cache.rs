//! Reduced bodies cached by a hash of what produced them, so that running a study again
//! does not reduce its parts again.
//!
//! The key is a SHA-256 over: a cache-scheme tag, the flexmbs version (the algorithms may
//! change between versions), the reduced-body format version and algorithm revision, the part's name (it is stored
//! in the body), the bytes of its gmsh file if it has one, the whole FE model the reduction
//! runs on (mesh, elements, materials, sections, spiders: serialised as JSON straight into
//! the hasher), the interface nodes and the reduction settings. Anything that can change the
//! body changes the key; a comment or a reordered key in the study file does not. The file is
//! `<cache dir>/<part>-<first 16 hex digits>.rbody`.
//!
//! A cached file is never trusted by its name: beside it, `<file>.key` records the full key
//! and the SHA-256 of the file's bytes ([`record`]), and a body is used only when both match
//! ([`lookup`]) and it passes the reduced-body checks on load; otherwise the part is reduced
//! again. Both files are written to temporary names and renamed, so two runs sharing a cache
//! (two studies, or one study twice) never read a partial file.

use crate::input::part::{Built, Part, Reduction};
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Bumped when what goes into the key changes meaning.
const SCHEME: &str = "flexmbs reduced-body cache, scheme 1";

/// `io::Write` into a hasher, so that serde_json streams the model without a buffer.
struct HashWriter<'a>(&'a mut Sha256);

impl Write for HashWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.update(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The cache key of `part` reduced from `built` with `reduction` (module docs), as hex.
pub fn key(part: &Part, built: &Built, reduction: &Reduction) -> std::io::Result<String> {
    let mut h = Sha256::new();
    let mut field = |label: &str, bytes: &[u8]| {
        // Length-prefixed, so that no two different inputs concatenate to the same bytes.
        h.update(label.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field("scheme", SCHEME.as_bytes());
    field("flexmbs", env!("CARGO_PKG_VERSION").as_bytes());
    field("format", reduction::FORMAT_VERSION.to_string().as_bytes());
    field("algorithms", reduction::ALGORITHM_REVISION.to_string().as_bytes());
    field("part", part.name.as_bytes());
    if let Some(file) = &part.mesh_file {
        field("mesh file", &fe_model::input::read(file)?);
    }
    // f64 Debug output is the shortest decimal that reads back to the same value: exact.
    field(
        "interfaces",
        format!("{:?} {:?}", built.interfaces, built.auxiliary).as_bytes(),
    );
    // The factor's precision is left out: both precisions give the same body (eigenvalues to
    // 1e-10, solves refined to double precision), so a body reduced with one serves the other,
    // and keys of studies without the key stay what they were. The inertia correction and the
    // planar reduction enter only when they are on, for the same reason: a body reduced
    // without them keeps its key.
    let Reduction {
        modes,
        auxiliary_node,
        keep_mesh_shapes,
        geometric_stiffening,
        inertia_correction,
        planar,
        stress_shapes,
        load_points,
        factor: _,
    } = reduction;
    let inertia_correction = if *inertia_correction {
        ", inertia_correction: true"
    } else {
        ""
    };
    let planar = if *planar { ", planar: true" } else { "" };
    field(
        "reduction",
        format!(
            "Reduction {{ modes: {modes:?}, auxiliary_node: {auxiliary_node:?}, keep_mesh_shapes: {keep_mesh_shapes:?}, geometric_stiffening: {geometric_stiffening:?}, stress_shapes: {stress_shapes:?}, load_points: {load_points:?}{inertia_correction}{planar} }}"
        )
        .as_bytes(),
    );
    h.update(b"model");
    serde_json::to_writer(HashWriter(&mut h), &built.model).map_err(std::io::Error::other)?;
    let digest = h.finalize();
    Ok(digest.iter().map(|b| format!("{b:02x}")).collect())
}

/// The cache file of `part` with key `key` in `dir`.
pub fn path(dir: &Path, part: &str, key: &str) -> PathBuf {
    dir.join(format!(
        "{part}-{}.{}",
        &key[..16.min(key.len())],
        reduction::file::EXTENSION
    ))
}

/// The SHA-256 of `bytes`, as hex.
fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// The key file of a cache file.
fn key_path(file: &Path) -> PathBuf {
    let mut name = file.file_name().unwrap_or_default().to_os_string();
    name.push(".key");
    file.with_file_name(name)
}

/// Records that `file` holds the body of `key`: the key and the hash of its bytes.
pub fn record(file: &Path, key: &str) -> std::io::Result<()> {
    let bytes = fe_model::input::read(file)?;
    let text = format!("key {key}\nsha256 {}\n", sha256_hex(&bytes));
    crate::output::summary::write_atomic(&key_path(file), text.as_bytes())
}

/// The bytes of `file` when its key file records `key` and their hash; `None` otherwise (no
/// key file, another key, a changed file).
pub fn lookup(file: &Path, key: &str) -> Option<Vec<u8>> {
    let text = std::fs::read_to_string(key_path(file)).ok()?;
    let bytes = std::fs::read(file).ok()?;
    let expected = format!("key {key}\nsha256 {}\n", sha256_hex(&bytes));
    (text == expected).then_some(bytes)
}
