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

use crate::part::{Built, Part, Reduction};
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
        field("mesh file", &std::fs::read(file)?);
    }
    // f64 Debug output is the shortest decimal that reads back to the same value: exact.
    field(
        "interfaces",
        format!("{:?} {:?}", built.interfaces, built.auxiliary).as_bytes(),
    );
    field("reduction", format!("{reduction:?}").as_bytes());
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
