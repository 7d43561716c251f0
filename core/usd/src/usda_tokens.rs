//! The tokenizer of the `.usda` text format (Sdf's text file format), for [`crate::reader`].
//!
//! Follows the lexical rules of usd-core's `textFileFormat.ll`: `#` comments to the end of the
//! line (the `#usda 1.0` header is one), identifiers with `:` namespaces and `.` suffixes
//! (`primvars:st:indices`, `points.timeSamples`), numbers (`-1.5e-3`, `inf`, `-inf`, `nan`),
//! strings in single, double or triple quotes with C escapes, asset paths (`@a.usda@`,
//! `@@@a@@.usda@@@`), prim paths (`</Root/mesh>`) and the punctuation `( ) [ ] { } = , ; :`.
//! Tokens borrow from the text except strings with escapes; nothing is buffered ahead but one
//! token of look-ahead, so a large array costs no token list.

use std::borrow::Cow;

/// One token.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok<'a> {
    /// An identifier or keyword, with its `:` and `.` parts (`xformOp:translate`).
    Ident(&'a str),
    /// A number as written (`3`, `-0.5`, `1e-7`, `-inf`).
    Number(&'a str),
    /// A quoted string, unescaped.
    Str(Cow<'a, str>),
    /// An asset path, without its `@` delimiters.
    Asset(&'a str),
    /// A prim or property path, without its `<` `>` delimiters.
    Path(&'a str),
    /// One of `( ) [ ] { } = , ; :`.
    Punct(u8),
    /// The end of the text.
    Eof,
}

impl Tok<'_> {
    /// A short description for messages: `'{'`, `identifier "def"`, `end of file`...
    pub(crate) fn describe(&self) -> String {
        match self {
            Tok::Ident(s) => format!("identifier \"{s}\""),
            Tok::Number(s) => format!("number {s}"),
            Tok::Str(s) => format!("string \"{}\"", s.chars().take(40).collect::<String>()),
            Tok::Asset(s) => format!("asset path @{s}@"),
            Tok::Path(s) => format!("path <{s}>"),
            Tok::Punct(c) => format!("'{}'", *c as char),
            Tok::Eof => "the end of the file".to_string(),
        }
    }
}

/// A lexical error: its 1-based line and what is wrong.
pub(crate) type LexError = (usize, String);

/// The tokenizer: `peek` / `next` over the text, counting lines.
pub(crate) struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    /// Line of the next unread byte.
    line: usize,
    /// The look-ahead token and the line it starts on.
    peeked: Option<(Tok<'a>, usize)>,
}

impl<'a> Lexer<'a> {
    /// A tokenizer at the start of `text`.
    pub(crate) fn new(text: &'a str) -> Self {
        Lexer {
            text,
            pos: 0,
            line: 1,
            peeked: None,
        }
    }

    /// The next token without consuming it, and its line.
    pub(crate) fn peek(&mut self) -> Result<(&Tok<'a>, usize), LexError> {
        if self.peeked.is_none() {
            self.peeked = Some(self.lex()?);
        }
        let (t, l) = self.peeked.as_ref().expect("just filled");
        Ok((t, *l))
    }

    /// Consumes and returns the next token and its line.
    pub(crate) fn next_tok(&mut self) -> Result<(Tok<'a>, usize), LexError> {
        match self.peeked.take() {
            Some(t) => Ok(t),
            None => self.lex(),
        }
    }

    fn bytes(&self) -> &'a [u8] {
        self.text.as_bytes()
    }

    fn at(&self, i: usize) -> u8 {
        self.bytes().get(i).copied().unwrap_or(0)
    }

    /// Skips white space and comments.
    fn skip_blank(&mut self) {
        while self.pos < self.text.len() {
            match self.at(self.pos) {
                b'\n' => {
                    self.line += 1;
                    self.pos += 1;
                }
                b' ' | b'\t' | b'\r' => self.pos += 1,
                b'#' => {
                    while self.pos < self.text.len() && self.at(self.pos) != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    fn lex(&mut self) -> Result<(Tok<'a>, usize), LexError> {
        self.skip_blank();
        let line = self.line;
        let start = self.pos;
        let Some(&c) = self.bytes().get(start) else {
            return Ok((Tok::Eof, line));
        };
        let tok = match c {
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b'=' | b',' | b';' | b':' => {
                self.pos += 1;
                Tok::Punct(c)
            }
            b'"' | b'\'' => Tok::Str(self.string(c)?),
            b'@' => Tok::Asset(self.asset()?),
            b'<' => {
                let end = self.text[start..]
                    .find(['>', '\n'])
                    .map(|k| start + k)
                    .filter(|&e| self.at(e) == b'>')
                    .ok_or((
                        line,
                        "unterminated path: no '>' before the end of the line".into(),
                    ))?;
                self.pos = end + 1;
                Tok::Path(&self.text[start + 1..end])
            }
            b'0'..=b'9' | b'.' => Tok::Number(self.number()),
            b'-' | b'+' => {
                if self.text[start + 1..].starts_with("inf") {
                    self.pos += 4;
                    Tok::Number(&self.text[start..self.pos])
                } else if matches!(self.at(start + 1), b'0'..=b'9' | b'.') {
                    Tok::Number(self.number())
                } else {
                    return Err((line, format!("unexpected character '{}'", c as char)));
                }
            }
            c if c.is_ascii_alphabetic() || c == b'_' => Tok::Ident(self.ident()),
            _ => {
                let ch = self.text[start..].chars().next().unwrap_or('?');
                return Err((line, format!("unexpected character {ch:?}")));
            }
        };
        Ok((tok, line))
    }

    fn number(&mut self) -> &'a str {
        let start = self.pos;
        self.pos += 1;
        while let b'0'..=b'9' | b'.' | b'e' | b'E' = self.at(self.pos) {
            let exp = matches!(self.at(self.pos), b'e' | b'E');
            self.pos += 1;
            if exp && matches!(self.at(self.pos), b'+' | b'-') {
                self.pos += 1;
            }
        }
        &self.text[start..self.pos]
    }

    /// `[A-Za-z_][A-Za-z0-9_]*`, with further parts after `:` or `.` (`a:b.c`).
    fn ident(&mut self) -> &'a str {
        let start = self.pos;
        let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
        loop {
            while word(self.at(self.pos)) {
                self.pos += 1;
            }
            let sep = self.at(self.pos);
            let next = self.at(self.pos + 1);
            if (sep == b':' || sep == b'.') && (next.is_ascii_alphabetic() || next == b'_') {
                self.pos += 1;
            } else {
                break;
            }
        }
        &self.text[start..self.pos]
    }

    /// `@path@` or `@@@path@@@`.
    fn asset(&mut self) -> Result<&'a str, LexError> {
        let line = self.line;
        let start = self.pos;
        let (open, close) = if self.text[start..].starts_with("@@@") {
            (3, "@@@")
        } else {
            (1, "@")
        };
        let body = start + open;
        let end = self.text[body..]
            .find(close)
            .map(|k| body + k)
            .filter(|&e| !self.text[body..e].contains('\n'))
            .ok_or((line, "unterminated asset path".to_string()))?;
        self.pos = end + close.len();
        Ok(&self.text[body..end])
    }

    /// A string in `"`, `'`, `"""` or `'''`, unescaped (borrowed when it has no escapes).
    fn string(&mut self, q: u8) -> Result<Cow<'a, str>, LexError> {
        let line = self.line;
        let triple = self.at(self.pos + 1) == q && self.at(self.pos + 2) == q;
        let open = if triple { 3 } else { 1 };
        let body = self.pos + open;
        let mut i = body;
        let mut escaped = false;
        let unterminated = || (line, "unterminated string".to_string());
        let end = loop {
            match *self.bytes().get(i).ok_or_else(unterminated)? {
                b'\\' => {
                    escaped = true;
                    if self.at(i + 1) == b'\n' {
                        self.line += 1;
                    }
                    i += 2;
                }
                b'\n' if !triple => return Err(unterminated()),
                b'\n' => {
                    self.line += 1;
                    i += 1;
                }
                c if c == q && (!triple || (self.at(i + 1) == q && self.at(i + 2) == q)) => {
                    break i;
                }
                _ => i += 1,
            }
        };
        self.pos = end + open;
        let raw = &self.text[body..end];
        Ok(if escaped {
            Cow::Owned(unescape(raw))
        } else {
            Cow::Borrowed(raw)
        })
    }
}

/// C-style escapes: `\n \t \r \\ \" \' \xHH \NNN` (octal); others keep the escaped character.
fn unescape(raw: &str) -> String {
    let mut out = String::with_capacity(raw.len());
    let mut it = raw.chars().peekable();
    while let Some(c) = it.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match it.next() {
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some('r') => out.push('\r'),
            Some('a') => out.push('\u{7}'),
            Some('b') => out.push('\u{8}'),
            Some('f') => out.push('\u{c}'),
            Some('v') => out.push('\u{b}'),
            Some('x') => {
                let mut v = 0u32;
                for _ in 0..2 {
                    match it.peek().and_then(|d| d.to_digit(16)) {
                        Some(d) => {
                            v = v * 16 + d;
                            it.next();
                        }
                        None => break,
                    }
                }
                out.push(char::from_u32(v).unwrap_or('\u{fffd}'));
            }
            Some(d @ '0'..='7') => {
                let mut v = d.to_digit(8).unwrap_or(0);
                for _ in 0..2 {
                    match it.peek().and_then(|d| d.to_digit(8)) {
                        Some(d) => {
                            v = v * 8 + d;
                            it.next();
                        }
                        None => break,
                    }
                }
                out.push(char::from_u32(v).unwrap_or('\u{fffd}'));
            }
            Some(other) => out.push(other),
            None => out.push('\\'),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &str) -> Vec<Tok<'_>> {
        let mut lx = Lexer::new(text);
        let mut v = Vec::new();
        loop {
            match lx.next_tok().unwrap().0 {
                Tok::Eof => return v,
                t => v.push(t),
            }
        }
    }

    #[test]
    fn tokens_of_a_property() {
        assert_eq!(
            all("#usda 1.0\nuniform token[] xformOpOrder = [\"xformOp:translate\"] # c\n"),
            [
                Tok::Ident("uniform"),
                Tok::Ident("token"),
                Tok::Punct(b'['),
                Tok::Punct(b']'),
                Tok::Ident("xformOpOrder"),
                Tok::Punct(b'='),
                Tok::Punct(b'['),
                Tok::Str("xformOp:translate".into()),
                Tok::Punct(b']'),
            ]
        );
        assert_eq!(
            all("points.timeSamples = { 1.5: -inf, -2e-3: 4 }")[..4],
            [
                Tok::Ident("points.timeSamples"),
                Tok::Punct(b'='),
                Tok::Punct(b'{'),
                Tok::Number("1.5"),
            ]
        );
        assert_eq!(all("-inf, -2e-3:")[2], Tok::Number("-2e-3"));
    }

    #[test]
    fn strings_paths_assets() {
        assert_eq!(
            all(r#"'a\'b' "x\n\x41\101" '''m"l
i''' @a.usda@ @@@b@c@@@ </Root/m.prop>"#),
            [
                Tok::Str("a'b".into()),
                Tok::Str("x\nAA".into()),
                Tok::Str("m\"l\ni".into()),
                Tok::Asset("a.usda"),
                Tok::Asset("b@c"),
                Tok::Path("/Root/m.prop"),
            ]
        );
    }

    #[test]
    fn lines_are_counted() {
        let mut lx = Lexer::new("a\n'''x\ny'''\n\n  b");
        assert_eq!(lx.next_tok().unwrap().1, 1);
        assert_eq!(lx.next_tok().unwrap().1, 2);
        assert_eq!(lx.next_tok().unwrap(), (Tok::Ident("b"), 5));
    }

    #[test]
    fn lexical_errors_name_the_line() {
        for (text, line, msg) in [
            ("\n\"abc", 2, "unterminated string"),
            ("\n\n'ab\nc'", 3, "unterminated string"),
            ("'''abc''", 1, "unterminated string"),
            ("x\n@abc", 2, "unterminated asset path"),
            (
                "</a/b",
                1,
                "unterminated path: no '>' before the end of the line",
            ),
            ("\n$", 2, "unexpected character '$'"),
            ("\"a\\", 1, "unterminated string"),
        ] {
            let mut lx = Lexer::new(text);
            let err = loop {
                match lx.next_tok() {
                    Ok((Tok::Eof, _)) => panic!("{text:?} lexed"),
                    Ok(_) => {}
                    Err(e) => break e,
                }
            };
            assert_eq!(err, (line, msg.to_string()), "{text:?}");
        }
    }
}
