//! Byte cursor shared by the MSH 2 and MSH 4 readers: whitespace-separated tokens for the
//! ASCII parts, fixed-size little- or big-endian values for the binary parts, and the
//! construction of located errors.
//!
//! Positions are byte offsets into the input; a [`Location`] (line or byte) is computed from
//! them only when an error is built, so the happy path never counts lines.

use super::{Location, MshError};
use std::path::Path;
use std::str::FromStr;

/// Longest excerpt of offending input quoted in an error message.
const FOUND_MAX_CHARS: usize = 40;

/// Turns byte offsets into [`Location`]s: lines for ASCII files, byte offsets for binary ones
/// (line numbers are meaningless once binary data has been crossed).
#[derive(Clone, Copy)]
pub(super) struct Locator<'a> {
    data: &'a [u8],
    binary: bool,
}

impl Locator<'_> {
    pub(super) fn at(&self, pos: usize) -> Location {
        if self.binary {
            Location::Byte(pos)
        } else {
            let end = pos.min(self.data.len());
            Location::Line(1 + self.data[..end].iter().filter(|&&b| b == b'\n').count())
        }
    }
}

/// Quotes a piece of input for an error message: lossy UTF-8, at most [`FOUND_MAX_CHARS`].
pub(super) fn excerpt(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut out: String = text.chars().take(FOUND_MAX_CHARS).collect();
    if text.chars().count() > FOUND_MAX_CHARS {
        out.push('…');
    }
    out
}

pub(super) struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    path: &'a Path,
    binary: bool,
    big_endian: bool,
    /// The section being read, for error messages (`$Nodes`, ...).
    section: String,
}

impl<'a> Cursor<'a> {
    pub(super) fn new(data: &'a [u8], path: &'a Path) -> Self {
        Cursor {
            data,
            pos: 0,
            path,
            binary: false,
            big_endian: false,
            section: String::new(),
        }
    }

    pub(super) fn locator(&self) -> Locator<'a> {
        Locator {
            data: self.data,
            binary: self.binary,
        }
    }

    pub(super) fn path(&self) -> &'a Path {
        self.path
    }

    pub(super) fn pos(&self) -> usize {
        self.pos
    }

    pub(super) fn at(&self, pos: usize) -> Location {
        self.locator().at(pos)
    }

    pub(super) fn set_binary(&mut self, binary: bool) {
        self.binary = binary;
    }

    pub(super) fn set_big_endian(&mut self, big_endian: bool) {
        self.big_endian = big_endian;
    }

    pub(super) fn set_section(&mut self, section: &str) {
        self.section.clear();
        self.section.push_str(section);
    }

    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    // ---------------------------------------------------------------- errors

    pub(super) fn truncated(&self, pos: usize, expected: &str, found: String) -> MshError {
        MshError::Truncated {
            path: self.path.to_path_buf(),
            at: self.at(pos),
            section: self.section.clone(),
            expected: expected.to_string(),
            found,
        }
    }

    fn truncated_at_eof(&self, expected: &str) -> MshError {
        self.truncated(self.data.len(), expected, "end of file".to_string())
    }

    pub(super) fn header_mismatch(&self, pos: usize, what: &str, header: u64, found: u64) -> MshError {
        MshError::HeaderMismatch {
            path: self.path.to_path_buf(),
            at: self.at(pos),
            section: self.section.clone(),
            what: what.to_string(),
            header,
            found,
        }
    }

    pub(super) fn malformed(&self, pos: usize, expected: &str, found: String) -> MshError {
        MshError::Malformed {
            path: self.path.to_path_buf(),
            at: self.at(pos),
            section: self.section.clone(),
            expected: expected.to_string(),
            found,
        }
    }

    fn malformed_number(&self, pos: usize, expected: &str, found: String) -> MshError {
        MshError::MalformedNumber {
            path: self.path.to_path_buf(),
            at: self.at(pos),
            section: self.section.clone(),
            expected: expected.to_string(),
            found,
        }
    }

    // ---------------------------------------------------------------- ASCII

    fn skip_whitespace(&mut self) {
        while let Some(b) = self.data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
    }

    /// The next whitespace-separated token and its start, or `None` at the end of the input.
    pub(super) fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_whitespace();
        let start = self.pos;
        while let Some(b) = self.data.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.data[start..self.pos]))
    }

    /// Moves past the end of the current line (after its `\n`, or to the end of the input).
    pub(super) fn skip_line(&mut self) {
        match self.data[self.pos.min(self.data.len())..]
            .iter()
            .position(|&b| b == b'\n')
        {
            Some(offset) => self.pos += offset + 1,
            None => self.pos = self.data.len(),
        }
    }

    /// The rest of the current line without its line ending, and its start; the cursor moves
    /// past the line.
    pub(super) fn rest_of_line(&mut self) -> (usize, &'a [u8]) {
        let start = self.pos.min(self.data.len());
        self.skip_line();
        let mut line = &self.data[start..self.pos.max(start)];
        while let [head @ .., b'\n' | b'\r'] = line {
            line = head;
        }
        (start, line)
    }

    /// A number token with its start. A `$` token (a section marker) where data is expected
    /// means the section holds fewer records than its header announced: reported as truncated.
    pub(super) fn number_at<T: FromStr>(&mut self, expected: &str) -> Result<(T, usize), MshError> {
        let Some((start, token)) = self.token() else {
            return Err(self.truncated_at_eof(expected));
        };
        if token.first() == Some(&b'$') {
            return Err(self.truncated(start, expected, excerpt(token)));
        }
        std::str::from_utf8(token)
            .ok()
            .and_then(|text| text.parse::<T>().ok())
            .map(|value| (value, start))
            .ok_or_else(|| self.malformed_number(start, expected, excerpt(token)))
    }

    pub(super) fn number<T: FromStr>(&mut self, expected: &str) -> Result<T, MshError> {
        self.number_at(expected).map(|(value, _)| value)
    }

    /// A finite floating-point token (a coordinate).
    pub(super) fn coordinate(&mut self, expected: &str) -> Result<f64, MshError> {
        let (value, start) = self.number_at::<f64>(expected)?;
        if value.is_finite() {
            Ok(value)
        } else {
            Err(self.malformed_number(start, expected, value.to_string()))
        }
    }

    /// The token that closes a section, such as `$EndNodes`.
    pub(super) fn expect_end(&mut self, marker: &str) -> Result<(), MshError> {
        match self.token() {
            None => Err(self.truncated_at_eof(marker)),
            Some((_, token)) if token == marker.as_bytes() => Ok(()),
            Some((start, token)) => Err(self.malformed(start, marker, format!("'{}'", excerpt(token)))),
        }
    }

    /// The next section marker (a token starting with `$`) and its start, skipping any line
    /// that does not start with `$` as gmsh itself does; `None` at the end of the input.
    pub(super) fn next_section(&mut self) -> Option<(usize, &'a [u8])> {
        loop {
            self.skip_whitespace();
            match self.data.get(self.pos) {
                None => return None,
                Some(b'$') => return self.token(),
                Some(_) => self.skip_line(),
            }
        }
    }

    /// Skips an unknown section `$Name` (whose marker has been read) up to and including its
    /// `$EndName`. Searching for the marker works for binary sections too.
    pub(super) fn skip_section(&mut self, name: &[u8]) -> Result<(), MshError> {
        let mut end = b"$End".to_vec();
        end.extend_from_slice(name.strip_prefix(b"$").unwrap_or(name));
        let rest = &self.data[self.pos.min(self.data.len())..];
        match rest.windows(end.len()).position(|window| window == end.as_slice()) {
            Some(offset) => {
                self.pos += offset + end.len();
                Ok(())
            }
            None => Err(self.truncated_at_eof(&String::from_utf8_lossy(&end))),
        }
    }

    /// A capacity for `count` records of at least `min_bytes` each, capped by what the rest of
    /// the input can hold, so a corrupt count cannot trigger a huge allocation.
    pub(super) fn capacity(&self, count: u64, min_bytes: usize) -> usize {
        let fit = self.remaining() / min_bytes.max(1);
        usize::try_from(count).unwrap_or(usize::MAX).min(fit)
    }

    // ---------------------------------------------------------------- binary

    /// Checks that `count` records of `record_bytes` each fit in the rest of the input, before
    /// a binary block is read or allocated.
    pub(super) fn ensure_binary(&self, count: u64, record_bytes: usize, expected: &str) -> Result<(), MshError> {
        let needed = usize::try_from(count)
            .ok()
            .and_then(|count| count.checked_mul(record_bytes));
        match needed {
            Some(needed) if needed <= self.remaining() => Ok(()),
            _ => Err(self.truncated_at_eof(&format!("{count} × {expected}"))),
        }
    }

    fn take<const N: usize>(&mut self, expected: &str) -> Result<[u8; N], MshError> {
        let bytes = self
            .data
            .get(self.pos..)
            .and_then(|rest| rest.get(..N))
            .and_then(|bytes| <[u8; N]>::try_from(bytes).ok())
            .ok_or_else(|| self.truncated_at_eof(expected))?;
        self.pos += N;
        Ok(bytes)
    }

    /// A raw 4-byte value, for the endianness check of the binary header.
    pub(super) fn raw4(&mut self, expected: &str) -> Result<[u8; 4], MshError> {
        self.take::<4>(expected)
    }

    /// A C `int` (4 bytes).
    pub(super) fn int(&mut self, expected: &str) -> Result<i32, MshError> {
        let bytes = self.take::<4>(expected)?;
        Ok(if self.big_endian {
            i32::from_be_bytes(bytes)
        } else {
            i32::from_le_bytes(bytes)
        })
    }

    /// A non-negative C `int` as a count or tag.
    pub(super) fn int_unsigned(&mut self, expected: &str) -> Result<u64, MshError> {
        let start = self.pos;
        let value = self.int(expected)?;
        u64::try_from(value).map_err(|_| self.malformed_number(start, expected, value.to_string()))
    }

    /// A `size_t` (8 bytes: the header's data size, checked when the format is read).
    pub(super) fn size(&mut self, expected: &str) -> Result<u64, MshError> {
        let bytes = self.take::<8>(expected)?;
        Ok(if self.big_endian {
            u64::from_be_bytes(bytes)
        } else {
            u64::from_le_bytes(bytes)
        })
    }

    /// A `double` that must be finite (a coordinate).
    pub(super) fn binary_coordinate(&mut self, expected: &str) -> Result<f64, MshError> {
        let start = self.pos;
        let value = self.binary_double(expected)?;
        if value.is_finite() {
            Ok(value)
        } else {
            Err(self.malformed_number(start, expected, value.to_string()))
        }
    }

    /// A `double`, any value (bounding boxes we do not use).
    pub(super) fn binary_double(&mut self, expected: &str) -> Result<f64, MshError> {
        let bytes = self.take::<8>(expected)?;
        Ok(if self.big_endian {
            f64::from_be_bytes(bytes)
        } else {
            f64::from_le_bytes(bytes)
        })
    }

    /// Skips `count` binary values of `bytes` each (checked against the remaining input).
    pub(super) fn skip_binary(&mut self, count: u64, bytes: usize, expected: &str) -> Result<(), MshError> {
        self.ensure_binary(count, bytes, expected)?;
        // `ensure_binary` proved count * bytes <= remaining, so this neither overflows nor
        // runs past the end.
        self.pos += count as usize * bytes;
        Ok(())
    }
}
