//! The `.usda` text the stage writer ([`crate::writer`]) emits, as text: a buffer handed to
//! the output in chunks (so that a large mesh never becomes one giant `String`), numbers in
//! their shortest round-trip form, arrays, tuples and string literals. Kept apart from the
//! writer, which decides what a stage holds.

use std::fmt::Write as _;
use std::io::{self, Write};

use crate::UsdError;

/// Size at which the text buffer is handed to the writer.
const CHUNK: usize = 1 << 16;

/// Streams text to a writer in chunks of about [`CHUNK`] bytes, so that a large mesh never
/// becomes one giant `String`.
pub(crate) struct Out<'w> {
    w: &'w mut dyn Write,
    buf: String,
}

impl<'w> Out<'w> {
    /// An empty buffer in front of `w`.
    pub(crate) fn new(w: &'w mut dyn Write) -> Self {
        Out {
            w,
            buf: String::with_capacity(CHUNK + 1024),
        }
    }

    /// Appends `s`.
    pub(crate) fn push(&mut self, s: &str) {
        self.buf.push_str(s);
    }

    /// Appends formatted text.
    pub(crate) fn push_fmt(&mut self, args: std::fmt::Arguments<'_>) {
        // Writing to a String cannot fail.
        let _ = self.buf.write_fmt(args);
    }

    /// Hands the buffer to the writer once it is full. Called inside array loops.
    pub(crate) fn spill(&mut self) -> Result<(), UsdError> {
        if self.buf.len() >= CHUNK {
            self.w
                .write_all(self.buf.as_bytes())
                .map_err(UsdError::stream)?;
            self.buf.clear();
        }
        Ok(())
    }

    /// Hands the rest of the buffer to the writer and flushes it.
    pub(crate) fn finish(mut self) -> Result<(), UsdError> {
        let r: io::Result<()> = self
            .w
            .write_all(self.buf.as_bytes())
            .and_then(|_| self.w.flush());
        self.buf.clear();
        r.map_err(UsdError::stream)
    }

    /// Appends `v` ([`push_f32`]).
    pub(crate) fn push_f32(&mut self, v: f32) {
        push_f32(&mut self.buf, v);
    }

    /// Appends `v` ([`push_f64`]).
    pub(crate) fn push_f64(&mut self, v: f64) {
        push_f64(&mut self.buf, v);
    }

    /// `(x, y, z)`.
    pub(crate) fn push_tuple<const N: usize>(&mut self, v: &[f32; N]) {
        self.buf.push('(');
        for (k, c) in v.iter().enumerate() {
            if k > 0 {
                self.buf.push_str(", ");
            }
            self.push_f32(*c);
        }
        self.buf.push(')');
    }

    /// `[a, b, c]` and a newline.
    pub(crate) fn push_int_array(
        &mut self,
        values: impl Iterator<Item = u32>,
    ) -> Result<(), UsdError> {
        self.buf.push('[');
        for (i, v) in values.enumerate() {
            if i > 0 {
                self.buf.push_str(", ");
            }
            self.push_fmt(format_args!("{v}"));
            self.spill()?;
        }
        self.buf.push_str("]\n");
        Ok(())
    }

    /// `[a, b, c]` of floats and a newline.
    pub(crate) fn push_float_array(
        &mut self,
        values: impl Iterator<Item = f32>,
    ) -> Result<(), UsdError> {
        self.buf.push('[');
        for (i, v) in values.enumerate() {
            if i > 0 {
                self.buf.push_str(", ");
            }
            self.push_f32(v);
            self.spill()?;
        }
        self.buf.push_str("]\n");
        Ok(())
    }

    /// `[(x, y, z), ...]` and a newline.
    pub(crate) fn push_tuple_array<const N: usize>(
        &mut self,
        values: &[[f32; N]],
    ) -> Result<(), UsdError> {
        self.push_tuple_array_open(values)?;
        self.buf.push('\n');
        Ok(())
    }

    /// `[a, b, ...]` for rows of one float or more than four (a flat list), `[(a, b), ...]`
    /// for rows of 2 to 4 (tuples); no newline.
    pub(crate) fn push_rows(&mut self, values: &[f32], components: usize) -> Result<(), UsdError> {
        let tuples = (2..=4).contains(&components);
        self.buf.push('[');
        for (i, row) in values.chunks_exact(components.max(1)).enumerate() {
            if i > 0 {
                self.buf.push_str(", ");
            }
            if tuples {
                self.buf.push('(');
            }
            for (k, &v) in row.iter().enumerate() {
                if k > 0 {
                    self.buf.push_str(", ");
                }
                self.push_f32(v);
            }
            if tuples {
                self.buf.push(')');
            }
            self.spill()?;
        }
        self.buf.push(']');
        Ok(())
    }

    /// `[(x, y, z), ...]` without the newline (metadata may follow).
    pub(crate) fn push_tuple_array_open<const N: usize>(
        &mut self,
        values: &[[f32; N]],
    ) -> Result<(), UsdError> {
        self.buf.push('[');
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.buf.push_str(", ");
            }
            self.push_tuple(v);
            self.spill()?;
        }
        self.buf.push(']');
        Ok(())
    }

    /// A double-quoted `.usda` string literal with `\`, `"` and control characters escaped.
    pub(crate) fn push_string_literal(&mut self, s: &str) {
        self.buf.push('"');
        for c in s.chars() {
            match c {
                '"' => self.buf.push_str("\\\""),
                '\\' => self.buf.push_str("\\\\"),
                '\n' => self.buf.push_str("\\n"),
                '\r' => self.buf.push_str("\\r"),
                '\t' => self.buf.push_str("\\t"),
                c if (c as u32) < 0x20 || c as u32 == 0x7f => {
                    self.push_fmt(format_args!("\\x{:02x}", c as u32));
                }
                c => self.buf.push(c),
            }
        }
        self.buf.push('"');
    }
}

/// Shortest round-trip text of a finite float. Plain decimal in `[1e-5, 1e15)` (Rust's `{}`),
/// exponent form outside it (`1e20`, `1.5e-7`) so that no number turns into a 40-digit integer
/// literal; negative zero keeps its sign (`-0.0`). Generic so that `f32` prints with `f32`'s
/// shortest digits, not those of its widening to `f64`.
fn push_float<T>(buf: &mut String, v: T)
where
    T: Copy + Into<f64> + std::fmt::Display + std::fmt::LowerExp,
{
    let x: f64 = v.into();
    debug_assert!(x.is_finite());
    let _ = if x == 0.0 {
        buf.write_str(if x.is_sign_negative() { "-0.0" } else { "0" })
    } else if (1e-5..1e15).contains(&x.abs()) {
        write!(buf, "{v}")
    } else {
        write!(buf, "{v:e}")
    };
}

/// [`push_float`] for `f32`.
pub(crate) fn push_f32(buf: &mut String, v: f32) {
    push_float(buf, v);
}

/// [`push_float`] for `f64`.
pub(crate) fn push_f64(buf: &mut String, v: f64) {
    push_float(buf, v);
}
