//! Matrix Market files of sparse matrices, for exchanging $\mathbf K$ and $\mathbf M$ with
//! other FE codes, through the `sprs` crate's reader and writer.
//!
//! The use case: a model from another FE code (node coordinates, $\mathbf K$, $\mathbf M$)
//! is reduced here with [`crate::reduce_external`]; and our matrices can be checked in
//! another code (scipy's `mmread`, MATLAB's `mmread.m`, Julia's `MatrixMarket.jl`).
//!
//! # What is written
//!
//! [`write_matrix_market`] writes `coordinate real general`: every stored entry, both
//! triangles of a symmetric matrix. We do not write the `symmetric` variant: the Matrix
//! Market definition stores the *lower* triangle of a symmetric matrix, and sprs's symmetric
//! writer stores the upper one, which the definition does not provide for; a general file is
//! read the same way by every reader, at twice the size. Values are printed by Rust's `{}`
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
//! sprs's reader trusts the file: it allocates what the size line announces and panics on an
//! index outside the matrix. Before handing the text to sprs we therefore check every line
//! ourselves ([`parse_matrix_market`]), which also lets every error name the file and the
//! line, where sprs says only "Bad matrix market file."

#![allow(non_snake_case)]

use crate::error::ReductionError;
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use std::collections::HashMap;
use std::path::Path;

/// The Matrix Market text of `A` (`coordinate real general`, every stored entry). Pure: see
/// [`write_matrix_market`] for the file.
pub fn to_matrix_market(A: SparseColMatRef<'_, usize, f64>) -> Vec<u8> {
    let mut tri = sprs::TriMat::<f64>::with_capacity((A.nrows(), A.ncols()), A.compute_nnz());
    for j in 0..A.ncols() {
        for (&i, &v) in A.row_idx_of_col_raw(j).iter().zip(A.val_of_col(j)) {
            tri.add_triplet(i, j, v);
        }
    }
    let mut out = Vec::new();
    sprs::io::write_matrix_market_to_bufwrite(&mut out, &tri).expect("writing to a Vec<u8> cannot fail");
    out
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
/// The checks (module docs) run first; sprs then reads the checked text, and its triplets
/// become a faer matrix.
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
    let (shape, clean) = check(text).map_err(|(line, what)| error(line, what))?;
    let tri: sprs::TriMat<f64> = sprs::io::read_matrix_market_from_bufread(&mut clean.as_bytes())
        .map_err(|e| error(None, format!("sprs could not read it after our checks passed: {e}")))?;
    let triplets: Vec<Triplet<usize, usize, f64>> =
        tri.triplet_iter().map(|(&v, (i, j))| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(shape.0, shape.1, &triplets)
        .map_err(|e| error(None, format!("cannot build the sparse matrix: {e:?}")))
}

/// An error of [`check`]: the 1-based line at fault, if one is, and why.
type LineError = (Option<usize>, String);

/// Checks what sprs would trust: the banner, the size line, and every entry (count of fields,
/// numbers, indices in range, count of entries); in a symmetric file, that no entry is given
/// in both triangles. Returns the shape and the text for sprs, or the 1-based line at fault
/// and why.
///
/// The text for sprs is the checked content in the form its reader expects: a canonical
/// banner (`real`, single spaces: sprs compares the banner's bytes, and reads `integer`
/// files only into integer matrices), no comment or blank lines before the size line (its
/// comment loop does not trim, and spins at the end of a file without a size line).
fn check(text: &str) -> Result<((usize, usize), String), LineError> {
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
    let mut clean = format!(
        "%%MatrixMarket matrix coordinate real {}\n",
        if symmetry == Symmetry::General {
            "general"
        } else {
            "symmetric"
        }
    );
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
                    clean.push_str(trimmed);
                    clean.push('\n');
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
            // sprs skips blank lines between entries.
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
        if v.parse::<f64>().map(|x| !x.is_finite()).unwrap_or(true) {
            return Err((Some(line), format!("value '{v}' is not a finite number")));
        }
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
        clean.push_str(trimmed);
        clean.push('\n');
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
    Ok(((rows, cols), clean))
}
