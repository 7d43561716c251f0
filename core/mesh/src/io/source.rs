//! The buffered byte reader every format reader goes through.
//!
//! One fixed 64 KiB buffer, refilled in place: binary readers decode records straight out of it
//! (no per-record `read_exact` calls), text readers pull bounded lines from it. It also keeps the
//! bookkeeping the readers need for good errors and safe allocation: the current line number,
//! the number of bytes consumed, the total input length when known, and the cancel flag.

use crate::MeshError;
use std::io::{ErrorKind, Read};
use std::sync::atomic::{AtomicBool, Ordering};

/// Size of the read buffer; also the largest record [`Source::fill`] can expose at once.
pub(crate) const BUF_SIZE: usize = 64 * 1024;

/// Longest text line accepted (a hostile file without newlines must not fill memory).
pub(crate) const MAX_LINE: usize = 16 << 20;

/// Upper bound on speculative `Vec` reservations when the input length is unknown; vectors
/// still grow past it when the data is really there.
const RESERVE_CAP: u64 = 1 << 20;

/// A buffered reader with line counting, input-length knowledge and cancellation.
pub(crate) struct Source<'a, R> {
    inner: R,
    buf: Box<[u8]>,
    pos: usize,
    end: usize,
    eof: bool,
    /// Bytes of the stream before `buf[pos]`.
    consumed: u64,
    /// Lines returned by [`Source::read_line`] so far (so the last one's 1-based number).
    line: u64,
    name: &'a str,
    len: Option<u64>,
    cancel: Option<&'a AtomicBool>,
}

impl<'a, R: Read> Source<'a, R> {
    /// Wraps `inner`; `name` is used in error messages, `len` is the total input size if known.
    pub(crate) fn new(
        inner: R,
        name: &'a str,
        len: Option<u64>,
        cancel: Option<&'a AtomicBool>,
    ) -> Self {
        Source {
            inner,
            buf: vec![0; BUF_SIZE].into_boxed_slice(),
            pos: 0,
            end: 0,
            eof: false,
            consumed: 0,
            line: 0,
            name,
            len,
            cancel,
        }
    }

    /// The input's name for error messages.
    pub(crate) fn name(&self) -> &'a str {
        self.name
    }

    /// Number of the last line returned by [`Source::read_line`] (1-based).
    pub(crate) fn line(&self) -> u64 {
        self.line
    }

    /// Total input length, when known.
    pub(crate) fn len(&self) -> Option<u64> {
        self.len
    }

    /// Bytes left after the current position, when the input length is known.
    pub(crate) fn remaining(&self) -> Option<u64> {
        self.len.map(|l| l.saturating_sub(self.consumed))
    }

    /// Bytes consumed so far.
    pub(crate) fn consumed(&self) -> u64 {
        self.consumed
    }

    /// A `Parse` error at `line` (0 for binary data).
    pub(crate) fn error_at(&self, line: u64, message: impl Into<String>) -> MeshError {
        MeshError::Parse {
            path: self.name.to_string(),
            line,
            message: message.into(),
        }
    }

    /// A `Parse` error at the last line read.
    pub(crate) fn error(&self, message: impl Into<String>) -> MeshError {
        self.error_at(self.line, message)
    }

    /// How many elements to reserve for `count` declared records of at least `min_record`
    /// bytes each: never more than the rest of the input could hold, and at most a modest cap
    /// when its length is unknown (vectors grow if the data is really there).
    pub(crate) fn reserve_hint(&self, count: u64, min_record: u64) -> usize {
        let bound = match self.remaining() {
            Some(rem) => rem / min_record.max(1),
            None => RESERVE_CAP,
        };
        usize::try_from(count.min(bound)).unwrap_or(usize::MAX)
    }

    /// Makes at least `want` (≤ [`BUF_SIZE`]) bytes available unless the input ends first, and
    /// returns everything buffered (shorter than `want` only at the end of the input).
    #[inline]
    pub(crate) fn fill(&mut self, want: usize) -> Result<&[u8], MeshError> {
        if self.end - self.pos < want && !self.eof {
            self.refill(want)?;
        }
        Ok(&self.buf[self.pos..self.end])
    }

    #[cold]
    fn refill(&mut self, want: usize) -> Result<(), MeshError> {
        debug_assert!(want <= BUF_SIZE);
        if self.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(MeshError::Cancelled);
        }
        self.buf.copy_within(self.pos..self.end, 0);
        self.end -= self.pos;
        self.pos = 0;
        while self.end < want.min(BUF_SIZE) && !self.eof {
            match self.inner.read(&mut self.buf[self.end..]) {
                Ok(0) => self.eof = true,
                Ok(n) => self.end += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(source) => {
                    return Err(MeshError::Io {
                        path: self.name.to_string(),
                        source,
                    });
                }
            }
        }
        Ok(())
    }

    /// Marks `n` buffered bytes as used.
    #[inline]
    pub(crate) fn consume(&mut self, n: usize) {
        debug_assert!(n <= self.end - self.pos);
        self.pos += n;
        self.consumed += n as u64;
    }

    /// Skips `n` bytes; returns how many were really there.
    pub(crate) fn skip(&mut self, n: u64) -> Result<u64, MeshError> {
        let mut left = n;
        while left > 0 {
            let avail = self.fill(1)?.len();
            if avail == 0 {
                break;
            }
            let k = avail.min(usize::try_from(left).unwrap_or(usize::MAX));
            self.consume(k);
            left -= k as u64;
        }
        Ok(n - left)
    }

    /// Reads the next line into `out` without its `\n` / `\r\n`; `false` at the end of the
    /// input. A last line without a newline is returned like any other.
    pub(crate) fn read_line(&mut self, out: &mut Vec<u8>) -> Result<bool, MeshError> {
        out.clear();
        let mut any = false;
        loop {
            let avail = self.fill(1)?;
            if avail.is_empty() {
                break;
            }
            any = true;
            if let Some(i) = memchr::memchr(b'\n', avail) {
                out.extend_from_slice(&avail[..i]);
                self.consume(i + 1);
                break;
            }
            let n = avail.len();
            out.extend_from_slice(avail);
            self.consume(n);
            if out.len() > MAX_LINE {
                return Err(self.error_at(self.line + 1, "line too long"));
            }
        }
        if !any {
            return Ok(false);
        }
        if out.len() > MAX_LINE {
            return Err(self.error_at(self.line + 1, "line too long"));
        }
        if out.last() == Some(&b'\r') {
            out.pop();
        }
        self.line += 1;
        Ok(true)
    }
}

/// Splits a line into whitespace-separated tokens.
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// Parses a decimal float token (also `nan` / `inf`, which validation then rejects).
pub(crate) fn parse_f32(tok: &[u8]) -> Option<f32> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a decimal float token as `f64`.
pub(crate) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Parses a decimal integer token (optional sign, digits only).
///
/// Face indices are most of an OBJ or OFF file, so the usual short case is done on the bytes
/// directly; long tokens go through `str::parse` for its overflow handling.
#[inline]
pub(crate) fn parse_i64(tok: &[u8]) -> Option<i64> {
    let (negative, digits) = match tok.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, tok),
    };
    if digits.is_empty() || digits.len() > 18 {
        return std::str::from_utf8(tok).ok()?.parse().ok();
    }
    let mut v: i64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v * 10 + i64::from(d);
    }
    Some(if negative { -v } else { v })
}

/// A token for an error message: lossy UTF-8, cut to a readable length.
pub(crate) fn show(tok: &[u8]) -> String {
    const MAX: usize = 40;
    let s = String::from_utf8_lossy(&tok[..tok.len().min(MAX)]).into_owned();
    if tok.len() > MAX { s + "…" } else { s }
}

/// The largest element count the mesh model can index (`u32` indices) within the caller's limit.
pub(crate) fn element_limit(max_elements: u64) -> u64 {
    max_elements.min(u64::from(u32::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_crlf_and_keep_last_partial_line() {
        let data = b"a b\r\n\nlast";
        let mut s = Source::new(&data[..], "t", None, None);
        let mut l = Vec::new();
        assert!(s.read_line(&mut l).unwrap());
        assert_eq!(l, b"a b");
        assert!(s.read_line(&mut l).unwrap());
        assert_eq!(l, b"");
        assert!(s.read_line(&mut l).unwrap());
        assert_eq!((l.as_slice(), s.line()), (&b"last"[..], 3));
        assert!(!s.read_line(&mut l).unwrap());
    }

    #[test]
    fn fill_crosses_buffer_boundaries() {
        let data: Vec<u8> = (0..200_000u32).map(|i| i as u8).collect();
        let mut s = Source::new(&data[..], "t", Some(data.len() as u64), None);
        let mut total = 0;
        loop {
            let b = s.fill(13).unwrap();
            if b.len() < 13 {
                assert_eq!(b.len(), data.len() % 13);
                break;
            }
            assert_eq!(b[0], data[total]);
            s.consume(13);
            total += 13;
        }
        assert_eq!(s.skip(1000).unwrap(), (data.len() % 13) as u64);
    }

    #[test]
    fn integers() {
        for t in [
            "0",
            "-0",
            "+12",
            "-9223372036854775808",
            "9223372036854775807",
            "000000000000000000001",
        ] {
            assert_eq!(parse_i64(t.as_bytes()), t.parse().ok(), "{t}");
        }
        for t in [
            "",
            "-",
            "+",
            "1a",
            "1.0",
            "--1",
            "9223372036854775808",
            " 1",
        ] {
            assert_eq!(parse_i64(t.as_bytes()), None, "{t}");
        }
    }

    #[test]
    fn cancel_flag_stops_reading() {
        let flag = AtomicBool::new(true);
        let data = [0u8; 10];
        let mut s = Source::new(&data[..], "t", None, Some(&flag));
        assert!(matches!(s.fill(1), Err(MeshError::Cancelled)));
    }
}
