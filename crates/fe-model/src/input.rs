//! Reading input files (meshes, study files, reduced bodies, matrices): regular files only.
//! A named pipe (FIFO) blocks the reader until some other program writes into it, and a
//! device or a folder is no input file either; they are refused with an error that names the
//! path and what it is, before the file is opened.

use std::io;
use std::path::Path;

/// Refuses `path` unless it is a regular file (symbolic links are followed).
pub fn check_regular(path: &Path) -> io::Result<()> {
    let kind = std::fs::metadata(path)?.file_type();
    if kind.is_file() {
        return Ok(());
    }
    let what = if kind.is_dir() { "a folder" } else { special_kind(&kind) };
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{} is {what}, not a regular file: input files must be regular files",
            path.display()
        ),
    ))
}

#[cfg(unix)]
fn special_kind(kind: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_fifo() {
        "a named pipe (FIFO)"
    } else if kind.is_socket() {
        "a socket"
    } else if kind.is_block_device() || kind.is_char_device() {
        "a device"
    } else {
        "not a regular file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "a special file"
}

/// The bytes of the regular file at `path` ([`check_regular`], then `std::fs::read`).
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    check_regular(path)?;
    std::fs::read(path)
}

/// The text of the regular file at `path` ([`check_regular`], then `std::fs::read_to_string`).
pub fn read_to_string(path: &Path) -> io::Result<String> {
    check_regular(path)?;
    std::fs::read_to_string(path)
}
