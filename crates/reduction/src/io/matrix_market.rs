//! Matrix Market files of sparse matrices, for exchanging $\mathbf K$ and $\mathbf M$ with
//! other FE codes. The reader and the writer are ours: the format is a banner, a size line
//! and one `row column value` line per entry, and reading it ourselves lets every error name
//! the file and the line.
//!
//! The use case: a model from another FE code (node coordinates, $\mathbf K$, $\mathbf M$)
//! is reduced here with [`crate::reduce_external`]; and our matrices can be checked in
//! another code (scipy's `mmread`, MATLAB's `mmread.m`, Julia's `MatrixMarket.jl`).
//!
//! # What is written
//!
//! [`write_matrix_market`] writes `coordinate real general`: every stored entry, both
//! triangles of a symmetric matrix. We do not write the `symmetric` variant: the Matrix
//! Market definition stores the *lower* triangle of a symmetric matrix, and some writers
//! store the upper one, which the definition does not provide for; a general file is read the
//! same way by every reader, at twice the size. Values are printed by Rust's `{}`
//! for `f64`, the shortest decimal that parses back to the same number, so a round trip is
//! exact (`tests/unit/matrix_market.rs`). `{}` prints no exponent, so $10^{-300}$ takes about
//! 300 characters; even the longest `f64` stays within the format's 1024-character lines.
//!
//! # What is read
//!
//! `coordinate real` or `coordinate integer` files, `general` or `symmetric`. A symmetric file
//! stores one triangle (the standard says the lower one; files with the upper one are
//! accepted too); [`read_matrix_market`] returns both triangles. Duplicate entries are summed,
//! as the format's users expect (and as faer's triplet constructor does).
//!
//! The reader trusts nothing the file announces: the size line's entry count is checked
//! against the entries found (storage grows with the lines read, not with the count
//! claimed), and every index against the size.

#![allow(non_snake_case)]

use crate::error::ReductionError;
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use std::collections::HashMap;
use std::path::Path;

/// The Matrix Market text of `A` (`coordinate real general`, every stored entry). Pure: see
/// [`write_matrix_market`] for the file.
pub fn to_matrix_market(A: SparseColMatRef<'_, usize, f64>) -> Vec<u8> {
    use std::fmt::Write as _;
    let mut out = String::from("%%MatrixMarket matrix coordinate real general\n% written by flexmbs\n");
    let _ = writeln!(out, "{} {} {}", A.nrows(), A.ncols(), A.compute_nnz());
    for j in 0..A.ncols() {
        for (&i, &v) in A.row_idx_of_col_raw(j).iter().zip(A.val_of_col(j)) {
            // `{}`: the shortest decimal that parses back to the same f64 (module docs).
            let _ = writeln!(out, "{} {} {v}", i + 1, j + 1);
        }
    }
    out.into_bytes()
}

/// Writes `A` to `path` as `coordinate real general` (module docs: why not `symmetric`).
pub fn write_matrix_market(path: &Path, A: SparseColMatRef<'_, usize, f64>) -> Result<(), ReductionError> {
    std::fs::write(path, to_matrix_market(A)).map_err(|e| ReductionError::MatrixMarket {
        path: path.to_path_buf(),
        line: None,
        what: format!("cannot write it: {e}"),
    })
}

/// Reads a Matrix Market file into a sparse matrix with both triangles stored.
pub fn read_matrix_market(path: &Path) -> Result<SparseColMat<usize, f64>, ReductionError> {
    let bytes = fe_model::input::read(path).map_err(|e| ReductionError::MatrixMarket {
        path: path.to_path_buf(),
        line: None,
        what: format!("cannot read it: {e}"),
    })?;
    parse_matrix_market(&bytes, path)
}

/// Which triangle convention a file uses.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Symmetry {
    General,
    Symmetric,
}

/// Parses the text of a Matrix Market file; `origin` names it in errors. Never panics.
///
/// Every line is checked (by `check`) and its entry kept; the entries become a faer matrix
/// (duplicates summed).
pub fn parse_matrix_market(bytes: &[u8], origin: &Path) -> Result<SparseColMat<usize, f64>, ReductionError> {
    let error = |line: Option<usize>, what: String| ReductionError::MatrixMarket {
        path: origin.to_path_buf(),
        line,
        what,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        error(Some(line), "not text (invalid UTF-8)".into())
    })?;
    let (shape, triplets) = check(text).map_err(|(line, what)| error(line, what))?;
    SparseColMat::try_new_from_triplets(shape.0, shape.1, &triplets)
        .map_err(|e| error(None, format!("cannot build the sparse matrix: {e:?}")))
}

/// An error of [`check`]: the 1-based line at fault, if one is, and why.
type LineError = (Option<usize>, String);

/// The entries of a file, 0-based, as faer's triplet constructor takes them.
type Entries = Vec<Triplet<usize, usize, f64>>;

/// Reads and checks the banner, the size line, and every entry (count of fields, numbers,
/// indices in range, count of entries); in a symmetric file, that no entry is given in both
/// triangles. Returns the shape and the entries (0-based; a symmetric file's off-diagonal
/// entries in both triangles), or the 1-based line at fault and why.
fn check(text: &str) -> Result<((usize, usize), Entries), LineError> {
    let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l));
    let (_, banner) = lines.next().ok_or((Some(1), "the file is empty".to_string()))?;
    let words: Vec<String> = banner.split_whitespace().map(|w| w.to_lowercase()).collect();
    let banner_error = |what: &str| {
        (Some(1), format!("{what}; the first line must read '%%MatrixMarket matrix coordinate real general' (or 'integer', or 'symmetric'), found '{banner}'"))
    };
    if words.len() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(banner_error("not a Matrix Market banner"));
    }
    if words[2] != "coordinate" {
        return Err(banner_error(
            "only the sparse 'coordinate' format is read (not dense 'array')",
        ));
    }
    if words[3] != "real" && words[3] != "integer" {
        return Err(banner_error(&format!(
            "'{}' values cannot become a real matrix",
            words[3]
        )));
    }
    let symmetry = match words[4].as_str() {
        "general" => Symmetry::General,
        "symmetric" => Symmetry::Symmetric,
        other => {
            return Err(banner_error(&format!(
                "'{other}' matrices are not read (a stiffness or mass matrix is general or symmetric)"
            )))
        }
    };
    let mut triplets: Entries = Vec::new();
    let mut size: Option<(usize, usize, usize)> = None;
    let mut count = 0usize;
    let mut seen: HashMap<(usize, usize), usize> = HashMap::new();
    for (line, content) in lines {
        let trimmed = content.trim();
        if size.is_none() && (trimmed.is_empty() || trimmed.starts_with('%')) {
            continue;
        }
        let fields: Vec<&str> = trimmed.split_whitespace().collect();
        let Some((rows, cols, entries)) = size else {
            let parsed: Vec<Option<usize>> = fields.iter().map(|f| f.parse().ok()).collect();
            match parsed.as_slice() {
                [Some(r), Some(c), Some(e)] => {
                    if symmetry == Symmetry::Symmetric && r != c {
                        return Err((
                            Some(line),
                            format!("a symmetric matrix must be square, this one is {r} x {c}"),
                        ));
                    }
                    size = Some((*r, *c, *e));
                }
                _ => {
                    return Err((
                        Some(line),
                        format!("expected the size line 'rows columns entries', found '{trimmed}'"),
                    ))
                }
            }
            continue;
        };
        if fields.is_empty() {
            // Blank lines between entries are tolerated, as common readers do.
            continue;
        }
        if count == entries {
            return Err((
                Some(line),
                format!("more entries than the {entries} the size line announces"),
            ));
        }
        let [i, j, v] = fields.as_slice() else {
            return Err((Some(line), format!("an entry is 'row column value', found '{trimmed}'")));
        };
        let index = |f: &str, what: &str, max: usize| match f.parse::<usize>() {
            Ok(k) if (1..=max).contains(&k) => Ok(k - 1),
            _ => Err((Some(line), format!("{what} index '{f}' is not in 1..={max}"))),
        };
        let (i, j) = (index(i, "row", rows)?, index(j, "column", cols)?);
        let value = match v.parse::<f64>() {
            Ok(x) if x.is_finite() => x,
            _ => return Err((Some(line), format!("value '{v}' is not a finite number"))),
        };
        if symmetry == Symmetry::Symmetric && i != j {
            let key = (i.min(j), i.max(j));
            if let Some(previous) = seen.get(&key).copied() {
                return Err((
                    Some(line),
                    format!(
                        "entry ({}, {}) of a symmetric file was already given on line {previous} (as either triangle): a symmetric file stores one triangle",
                        i + 1,
                        j + 1
                    ),
                ));
            }
            seen.insert(key, line);
        }
        triplets.push(Triplet::new(i, j, value));
        if symmetry == Symmetry::Symmetric && i != j {
            triplets.push(Triplet::new(j, i, value));
        }
        count += 1;
    }
    let Some((rows, cols, entries)) = size else {
        return Err((None, "no size line 'rows columns entries' after the banner".into()));
    };
    if count < entries {
        return Err((
            None,
            format!("the size line announces {entries} entries but the file has {count} (truncated?)"),
        ));
    }
    Ok(((rows, cols), triplets))
}
