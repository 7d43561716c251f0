//! Step 1: the text as whitespace-separated tokens with their line numbers.
//!
//! OCCT reads its BREP text with C++ `>>` extraction, so line breaks only matter in two places
//! (the header line and a face's optional triangulation line, both handled by their readers):
//! everywhere else a record may span lines (B-spline poles do). Every reader goes through this
//! lexer so that each error names the line and the element being read, and so that a count
//! read from the text is checked against what is left of it before anything is allocated.

use super::{OcctError, OcctErrorKind};

/// One token and the line (1-based) it starts on.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Token<'a> {
    /// The token's text (never empty, no whitespace).
    pub text: &'a str,
    /// Its line.
    pub line: u32,
}

/// What is being read, for error messages: `Surfaces[14]`, `TShapes[7]`, `Locations`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ctx {
    /// The section (or element kind).
    pub section: &'static str,
    /// The 1-based record number inside it (the number references use), if any.
    pub index: Option<usize>,
}

impl std::fmt::Display for Ctx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.index {
            Some(i) => write!(f, "{}[{i}]", self.section),
            None => f.write_str(self.section),
        }
    }
}

/// A cursor over the tokens of the text after the header line.
pub(crate) struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    line: u32,
    /// The line of the last token returned (where an error about it is reported).
    last_line: u32,
    /// The continuity code split off an integer (`2CN` → `2`, then `CN`).
    pending: Option<Token<'a>>,
    /// The element being read.
    pub ctx: Ctx,
}

impl<'a> Lexer<'a> {
    /// A lexer over `text[pos..]`, where `pos` is at the start of line `line`.
    pub fn new(text: &'a str, pos: usize, line: u32) -> Lexer<'a> {
        Lexer {
            text,
            pos,
            line,
            last_line: line,
            pending: None,
            ctx: Ctx {
                section: "header",
                index: None,
            },
        }
    }

    /// Sets the element named by errors.
    pub fn at(&mut self, section: &'static str, index: Option<usize>) {
        self.ctx = Ctx { section, index };
    }

    /// A syntax error at the last token's line, naming the current element.
    pub fn error(&self, message: impl std::fmt::Display) -> OcctError {
        self.error_at(self.last_line, message)
    }

    /// A syntax error at `line`, naming the current element.
    pub fn error_at(&self, line: u32, message: impl std::fmt::Display) -> OcctError {
        OcctError {
            kind: OcctErrorKind::Syntax,
            message: format!("line {line}: {}: {message}", self.ctx),
        }
    }

    /// The line of the last token read.
    pub fn token_line(&self) -> u32 {
        self.last_line
    }

    /// Bytes left after the cursor: every count read from the text is checked against this
    /// before it sizes anything (a hostile `Curves 2000000000` fails here, not in `alloc`).
    pub fn remaining(&self) -> usize {
        self.text.len() - self.pos + self.pending.map_or(0, |t| t.text.len() + 1)
    }

    /// The next token, or `None` at the end of the text.
    pub fn next_token(&mut self) -> Option<Token<'a>> {
        if let Some(t) = self.pending.take() {
            self.last_line = t.line;
            return Some(t);
        }
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() && bytes[self.pos].is_ascii_whitespace() {
            if bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < bytes.len() && !bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        self.last_line = self.line;
        // Whitespace is ASCII, so both ends are character boundaries.
        Some(Token {
            text: &self.text[start..self.pos],
            line: self.line,
        })
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Option<Token<'a>> {
        let saved = (self.pos, self.line, self.last_line, self.pending);
        let t = self.next_token();
        (self.pos, self.line, self.last_line, self.pending) = saved;
        t
    }

    /// The next token; `what` names it in the error at the end of the text.
    pub fn token(&mut self, what: &str) -> Result<Token<'a>, OcctError> {
        self.next_token().ok_or_else(|| {
            let line = self.line;
            self.error_at(line, format!("the text ends where {what} was expected"))
        })
    }

    /// The next token, which must be `word`.
    pub fn expect(&mut self, word: &str) -> Result<(), OcctError> {
        let t = self.token(word)?;
        if t.text == word {
            Ok(())
        } else {
            Err(self.error(format!("expected `{word}`, found `{}`", t.text)))
        }
    }

    /// An integer (C++ `int`: 32 bits, as OCCT reads them).
    pub fn int(&mut self, what: &str) -> Result<i64, OcctError> {
        let t = self.token(what)?;
        parse_int(t.text).ok_or_else(|| {
            self.error(format!(
                "expected an integer for {what}, found `{}`",
                t.text
            ))
        })
    }

    /// An integer that may have a continuity code glued to it (`2CN`: OCCT writes a seam's
    /// second pcurve number and its continuity without a space); the code becomes the next
    /// token.
    pub fn int_glued(&mut self, what: &str) -> Result<i64, OcctError> {
        let t = self.token(what)?;
        let digits = t
            .text
            .char_indices()
            .find(|&(i, c)| !(c.is_ascii_digit() || (i == 0 && (c == '+' || c == '-'))))
            .map_or(t.text.len(), |(i, _)| i);
        let (number, rest) = t.text.split_at(digits);
        let value = parse_int(number).ok_or_else(|| {
            self.error(format!(
                "expected an integer for {what}, found `{}`",
                t.text
            ))
        })?;
        if !rest.is_empty() {
            self.pending = Some(Token {
                text: rest,
                line: t.line,
            });
        }
        Ok(value)
    }

    /// An integer in `lo..=hi`.
    pub fn int_in(&mut self, what: &str, lo: i64, hi: i64) -> Result<i64, OcctError> {
        let v = self.int(what)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.error(format!("{what} {v} out of range {lo}..{hi}")))
        }
    }

    /// A 0/1 flag.
    pub fn flag(&mut self, what: &str) -> Result<bool, OcctError> {
        Ok(self.int_in(what, 0, 1)? == 1)
    }

    /// A record count, checked against the text left: each record takes at least
    /// `min_bytes` bytes, so a count the text cannot hold is refused before anything is
    /// allocated for it.
    pub fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, OcctError> {
        let n = self.int(what)?;
        self.check_count(what, n, min_bytes)
    }

    /// `n` as a count of items of at least `min_bytes` bytes each (see [`Lexer::count`]).
    pub fn check_count(&self, what: &str, n: i64, min_bytes: usize) -> Result<usize, OcctError> {
        if n < 0 {
            return Err(self.error(format!("negative {what} {n}")));
        }
        let fits = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(min_bytes.max(1)))
            .is_some_and(|bytes| bytes <= self.remaining() + 1);
        if fits {
            Ok(n as usize)
        } else {
            Err(self.error(format!(
                "{what} {n} is more than the rest of the text can hold"
            )))
        }
    }

    /// A finite real number (NaN and infinities are refused: OCCT never writes them for
    /// valid geometry, and they would poison every later computation).
    pub fn real(&mut self, what: &str) -> Result<f64, OcctError> {
        let t = self.token(what)?;
        match t.text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.error(format!("{what} is not a finite number: `{}`", t.text))),
            Err(_) => Err(self.error(format!("expected a number for {what}, found `{}`", t.text))),
        }
    }

    /// `N` reals.
    pub fn reals<const N: usize>(&mut self, what: &str) -> Result<[f64; N], OcctError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.real(what)?;
        }
        Ok(out)
    }

    /// Skips `n` tokens (triangulation and polygon contents, which the document does not
    /// use), failing at the end of the text.
    pub fn skip(&mut self, n: usize, what: &str) -> Result<(), OcctError> {
        for _ in 0..n {
            self.token(what)?;
        }
        Ok(())
    }
}

/// A C++ `int` as OCCT writes it (optional sign, decimal digits, 32 bits).
fn parse_int(s: &str) -> Option<i64> {
    let v: i64 = s.parse().ok()?;
    (i64::from(i32::MIN)..=i64::from(i32::MAX))
        .contains(&v)
        .then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_carry_their_lines_and_glued_continuities_split() {
        let mut lx = Lexer::new("a b\n\n 3  1 2CN 7\n1e-007 -0\n", 0, 1);
        let t = lx.next_token().unwrap();
        assert_eq!((t.text, t.line), ("a", 1));
        lx.next_token();
        assert_eq!(lx.int("x").unwrap(), 3);
        assert_eq!(lx.token_line(), 3);
        assert_eq!(lx.int("x").unwrap(), 1);
        assert_eq!(lx.int_glued("pc2").unwrap(), 2);
        assert_eq!(lx.peek().unwrap().text, "CN");
        assert_eq!(lx.token("c").unwrap().text, "CN");
        assert_eq!(lx.int("x").unwrap(), 7);
        assert_eq!(lx.real("r").unwrap(), 1e-7);
        assert_eq!(lx.real("r").unwrap(), 0.0);
        assert!(lx.next_token().is_none());
        let e = lx.real("tolerance").unwrap_err();
        assert!(
            e.message.starts_with("line 5: header: the text ends"),
            "{e}"
        );
    }

    #[test]
    fn bad_numbers_and_hostile_counts_are_refused() {
        let mut lx = Lexer::new("nan inf 1x 5000000000 99999 1", 0, 1);
        lx.at("Curves", Some(4));
        assert!(lx.real("x").unwrap_err().message.contains("not a finite"));
        assert!(lx.real("x").unwrap_err().message.contains("not a finite"));
        let e = lx.real("radius").unwrap_err();
        assert_eq!(
            e.message,
            "line 1: Curves[4]: expected a number for radius, found `1x`"
        );
        assert!(lx.int("n").is_err());
        assert!(
            lx.count("pole count", 4)
                .unwrap_err()
                .message
                .contains("more than")
        );
        assert_eq!(lx.count("n", 1).unwrap(), 1);
    }
}
