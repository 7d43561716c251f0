//! The recursive-descent parser of the `.usda` subset [`crate::reader`] reads: a layer's text
//! into a tree of prim specs ([`crate::usda_spec`]), keeping only what meshes need.
//!
//! Grammar (after usd-core's `textFileFormat.yy`; `[ ]` optional, `*` repeated):
//!
//! ```text
//! layer      = "#usda 1.0" [ "(" metadata* ")" ] prim*
//! prim       = ("def" | "over" | "class") [type] "name" [ "(" metadata* ")" ] "{" item* "}"
//! item       = prim | property | "variantSet" "name" "=" "{" variant* "}"
//!            | "reorder" ("nameChildren" | "properties") "=" value
//! variant    = "name" [ "(" metadata* ")" ] "{" item* "}"
//! property   = listop* ["custom"] ["uniform" | "varying" | "config"]
//!              ( "rel" name [ "=" value ] | type ["[]"] name[.timeSamples|.connect|.spline]
//!                [ "=" value ] ) [ "(" metadata* ")" ]
//! metadata   = "doc string" | [listop] key "=" value
//! value      = number | string | ident | asset [path] | path | ( ... ) | [ ... ] | { ... }
//! ```
//!
//! Attributes meshes need (`points`, `faceVertexCounts`, `faceVertexIndices`, normals, UV
//! primvars and their indices, `xformOp:*`, `xformOpOrder`, `visibility`, and a GeomSubset's
//! `elementType`, `familyName`, `indices`) have their values parsed, flattened into `f64`s
//! (single-precision types rounded to `f32` first, as usd-core stores them) or strings; the
//! rest is skipped with balanced brackets. Of `.timeSamples` only the earliest sample is kept.
//! Nesting is limited to [`MAX_DEPTH`] levels, so hostile input cannot overflow the stack, and
//! nothing is allocated beyond what the text holds.
//!
//! Of the metadata, the layer's `upAxis`, `metersPerUnit` and `defaultPrim`, and a prim's
//! `active`, `variants` (selections), `apiSchemas`, `references` and `payload` arcs (their asset
//! and prim paths; layer offsets skipped) are kept; `crate::compose` follows the arcs.

use crate::UsdError;
use crate::usda_spec::{
    ArcKind, ArcSpec, Attr, Item, Layer, PrimSpec, Specifier, Value, VariantSetSpec,
};
use crate::usda_tokens::{Lexer, Tok};

/// Deepest nesting of prims, variants or tuples accepted.
pub(crate) const MAX_DEPTH: usize = 100;

/// What metadata blocks hold that the reader uses.
#[derive(Default)]
struct Meta {
    active: Option<bool>,
    interpolation: Option<String>,
    selections: Vec<(String, String)>,
    api_schemas: Vec<String>,
    arcs: Vec<ArcSpec>,
}

type R<T> = Result<T, UsdError>;

/// Parses a whole layer; `source` names it in errors.
pub(crate) fn parse_layer(text: &str, source: &str) -> R<Layer> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut p = Parser {
        lx: Lexer::new(text),
        source,
        layer: std::sync::Arc::from(source),
        ctx: String::new(),
        depth: 0,
    };
    if !text.starts_with("#usda ") {
        return Err(p.fail(
            1,
            "not a USD ASCII layer: the first line must be \"#usda 1.0\"",
        ));
    }
    let mut layer = Layer::default();
    if p.peek_punct(b'(')? {
        p.layer_metadata(&mut layer)?;
    }
    loop {
        match p.next()? {
            (Tok::Eof, _) => return Ok(layer),
            (Tok::Ident(w), line) if specifier(w).is_some() => {
                layer
                    .prims
                    .push(p.prim(specifier(w).unwrap_or(Specifier::Def), "", line)?);
            }
            (t, line) => {
                return Err(p.fail(
                    line,
                    format!(
                        "expected a prim (def, over or class), found {}",
                        t.describe()
                    ),
                ));
            }
        }
    }
}

fn specifier(w: &str) -> Option<Specifier> {
    match w {
        "def" => Some(Specifier::Def),
        "over" => Some(Specifier::Over),
        "class" => Some(Specifier::Class),
        _ => None,
    }
}

fn is_listop(w: &str) -> bool {
    matches!(w, "prepend" | "append" | "add" | "delete" | "reorder")
}

/// Whether an attribute's value is needed for meshes.
fn wanted(name: &str, type_name: &str) -> bool {
    matches!(
        name,
        "points"
            | "faceVertexCounts"
            | "faceVertexIndices"
            | "normals"
            | "xformOpOrder"
            | "visibility"
            | "elementType"
            | "familyName"
            | "indices"
            | "primvars:st"
    ) || name.starts_with("xformOp:")
        || (name.starts_with("primvars:")
            && (name == "primvars:normals"
                || name.ends_with(":indices")
                || type_name.starts_with("texCoord2")))
}

struct Parser<'a> {
    lx: Lexer<'a>,
    source: &'a str,
    /// `source`, shared by the prim specs.
    layer: std::sync::Arc<str>,
    /// The element being read (`/Root/mesh` or `/Root/mesh.points`), for messages.
    ctx: String,
    depth: usize,
}

impl<'a> Parser<'a> {
    fn fail(&self, line: usize, message: impl Into<String>) -> UsdError {
        let message = message.into();
        UsdError::Parse {
            path: self.source.to_string(),
            line,
            message: if self.ctx.is_empty() {
                message
            } else {
                format!("{}: {message}", self.ctx)
            },
        }
    }

    fn next(&mut self) -> R<(Tok<'a>, usize)> {
        self.lx.next_tok().map_err(|(l, m)| self.fail(l, m))
    }

    fn peek(&mut self) -> R<(Tok<'a>, usize)> {
        match self.lx.peek() {
            Ok((t, l)) => Ok((t.clone(), l)),
            Err((l, m)) => Err(self.fail(l, m)),
        }
    }

    fn peek_punct(&mut self, c: u8) -> R<bool> {
        Ok(self.peek()?.0 == Tok::Punct(c))
    }

    fn expect(&mut self, c: u8, what: &str) -> R<usize> {
        match self.next()? {
            (Tok::Punct(p), line) if p == c => Ok(line),
            (t, line) => Err(self.fail(
                line,
                format!("expected '{}' {what}, found {}", c as char, t.describe()),
            )),
        }
    }

    fn ident(&mut self, what: &str) -> R<&'a str> {
        match self.next()? {
            (Tok::Ident(w), _) => Ok(w),
            (t, line) => Err(self.fail(line, format!("expected {what}, found {}", t.describe()))),
        }
    }

    fn enter(&mut self, line: usize) -> R<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.fail(line, format!("nested deeper than {MAX_DEPTH} levels")));
        }
        Ok(())
    }

    fn layer_metadata(&mut self, layer: &mut Layer) -> R<()> {
        let open = self.expect(b'(', "")?;
        loop {
            let (t, line) = self.next()?;
            let key = match t {
                Tok::Punct(b')') => return Ok(()),
                Tok::Punct(b';') | Tok::Str(_) => continue,
                Tok::Ident(k) if is_listop(k) => self.ident("a metadata name")?,
                Tok::Ident(k) => k,
                Tok::Eof => return Err(self.unclosed(line, "the layer metadata", open)),
                t => {
                    let msg = format!(
                        "in the layer metadata: expected a name, found {}",
                        t.describe()
                    );
                    return Err(self.fail(line, msg));
                }
            };
            self.expect(b'=', &format!("after the layer metadata {key}"))?;
            match (key, self.peek()?) {
                ("upAxis", (Tok::Str(s), _)) => {
                    layer.up_axis = Some(s.into_owned());
                    self.next()?;
                }
                ("metersPerUnit", (Tok::Number(n), line)) => {
                    layer.meters_per_unit = Some(self.number(n, false, line)?);
                    self.next()?;
                }
                ("defaultPrim", (Tok::Str(s), _)) => {
                    layer.default_prim = Some(s.into_owned());
                    self.next()?;
                }
                _ => self.skip_value()?,
            }
        }
    }

    fn unclosed(&self, line: usize, what: &str, open: usize) -> UsdError {
        self.fail(
            line,
            format!("unexpected end of file in {what} (opened at line {open})"),
        )
    }

    /// A prim, its specifier already read.
    fn prim(&mut self, specifier: Specifier, parent: &str, line: usize) -> R<PrimSpec> {
        self.enter(line)?;
        let type_name = match self.peek()?.0 {
            Tok::Ident(t) => {
                self.next()?;
                t.to_string()
            }
            _ => String::new(),
        };
        let name = match self.next()? {
            (Tok::Str(s), _) => s.into_owned(),
            (t, l) => {
                let msg = format!(
                    "expected the prim's name (a quoted string), found {}",
                    t.describe()
                );
                return Err(self.fail(l, msg));
            }
        };
        let path = format!("{parent}/{name}");
        let saved = std::mem::replace(&mut self.ctx, path.clone());
        let mut prim = PrimSpec {
            specifier,
            type_name,
            name,
            line,
            active: true,
            selections: Vec::new(),
            api_schemas: Vec::new(),
            arcs: Vec::new(),
            layer: self.layer.clone(),
            attrs: Vec::new(),
            items: Vec::new(),
        };
        if self.peek_punct(b'(')? {
            let meta = self.metadata("the prim's metadata")?;
            prim.active = meta.active.unwrap_or(true);
            prim.selections = meta.selections;
            prim.api_schemas = meta.api_schemas;
            // References are stronger than payloads (LIVRPS).
            prim.arcs = meta.arcs;
            prim.arcs.sort_by_key(|a| a.kind == ArcKind::Payload);
        }
        let open = self.expect(b'{', "to open the prim's body")?;
        let mut items = Vec::new();
        self.body(
            &path,
            open,
            Some(&mut prim.attrs),
            &mut items,
            &mut prim.selections,
        )?;
        prim.items = items;
        self.ctx = saved;
        self.depth -= 1;
        Ok(prim)
    }

    /// Items up to the closing `}` (consumed). `attrs` is `None` in variants, whose properties
    /// are skipped.
    fn body(
        &mut self,
        path: &str,
        open: usize,
        mut attrs: Option<&mut Vec<Attr>>,
        items: &mut Vec<Item>,
        selections: &mut Vec<(String, String)>,
    ) -> R<()> {
        loop {
            let (t, line) = self.next()?;
            match t {
                Tok::Punct(b'}') => return Ok(()),
                Tok::Punct(b';') => {}
                Tok::Ident(w) if specifier(w).is_some() => {
                    let spec = specifier(w).unwrap_or(Specifier::Def);
                    items.push(Item::Prim(self.prim(spec, path, line)?));
                }
                Tok::Ident("variantSet") => {
                    items.push(Item::VariantSet(self.variant_set(path, line, selections)?));
                }
                Tok::Ident("reorder")
                    if matches!(self.peek()?.0, Tok::Ident("nameChildren" | "properties")) =>
                {
                    self.next()?;
                    self.expect(b'=', "after reorder")?;
                    self.skip_value()?;
                }
                Tok::Ident(w) => self.property(w, line, path, attrs.as_deref_mut())?,
                Tok::Eof => return Err(self.unclosed(line, "the prim's body", open)),
                t => {
                    let msg = format!(
                        "expected a property, prim or variantSet, found {}",
                        t.describe()
                    );
                    return Err(self.fail(line, msg));
                }
            }
        }
    }

    fn variant_set(
        &mut self,
        path: &str,
        line: usize,
        selections: &mut Vec<(String, String)>,
    ) -> R<VariantSetSpec> {
        self.enter(line)?;
        let name = match self.next()? {
            (Tok::Str(s), _) => s.into_owned(),
            (t, l) => {
                let msg = format!(
                    "expected the variant set's name (a quoted string), found {}",
                    t.describe()
                );
                return Err(self.fail(l, msg));
            }
        };
        self.expect(b'=', &format!("after variantSet \"{name}\""))?;
        let open = self.expect(b'{', &format!("to open variantSet \"{name}\""))?;
        let mut set = VariantSetSpec {
            name,
            variants: Vec::new(),
        };
        loop {
            let (t, l) = self.next()?;
            match t {
                Tok::Punct(b'}') => break,
                Tok::Str(v) => {
                    let v = v.into_owned();
                    let saved =
                        std::mem::replace(&mut self.ctx, format!("{path}{{{}={v}}}", set.name));
                    if self.peek_punct(b'(')? {
                        selections.extend(self.metadata("the variant's metadata")?.selections);
                    }
                    let vopen = self.expect(b'{', "to open the variant")?;
                    let mut items = Vec::new();
                    self.enter(l)?;
                    self.body(path, vopen, None, &mut items, selections)?;
                    self.depth -= 1;
                    self.ctx = saved;
                    set.variants.push((v, items));
                }
                Tok::Eof => {
                    let what = format!("variantSet \"{}\"", set.name);
                    return Err(self.unclosed(l, &what, open));
                }
                t => {
                    let msg = format!(
                        "expected a variant name (a quoted string) in variantSet \"{}\", found {}",
                        set.name,
                        t.describe()
                    );
                    return Err(self.fail(l, msg));
                }
            }
        }
        self.depth -= 1;
        Ok(set)
    }

    /// A property, its first word already read.
    fn property(
        &mut self,
        first: &'a str,
        line: usize,
        path: &str,
        attrs: Option<&mut Vec<Attr>>,
    ) -> R<()> {
        let mut w = first;
        while is_listop(w) || matches!(w, "custom" | "uniform" | "varying" | "config") {
            w = self.ident("a property type")?;
        }
        if w == "rel" {
            let name = self.ident("the relationship's name")?;
            let saved = std::mem::replace(&mut self.ctx, format!("{path}.{name}"));
            if self.peek_punct(b'=')? {
                self.next()?;
                self.skip_value()?;
            }
            if self.peek_punct(b'(')? {
                self.metadata("the relationship's metadata")?;
            }
            self.ctx = saved;
            return Ok(());
        }
        let type_name = w;
        if self.peek_punct(b'[')? {
            self.next()?;
            self.expect(b']', &format!("after the type {type_name}["))?;
        }
        let full = self.ident(&format!("the attribute's name after its type {type_name}"))?;
        let (name, suffix) = match full.rsplit_once('.') {
            Some((n, s @ ("timeSamples" | "connect" | "spline" | "default"))) => (n, s),
            _ => (full, ""),
        };
        let saved = std::mem::replace(&mut self.ctx, format!("{path}.{name}"));
        let keep = attrs.is_some()
            && wanted(name, type_name)
            && matches!(suffix, "" | "default" | "timeSamples");
        let single = is_single(type_name);
        let mut default = None;
        let mut sample = None;
        if self.peek_punct(b'=')? {
            self.next()?;
            match (keep, suffix) {
                (true, "timeSamples") => sample = self.time_samples(single)?,
                (true, _) => default = Some(self.value(single)?),
                (false, _) => self.skip_value()?,
            }
        }
        let mut interpolation = None;
        if self.peek_punct(b'(')? {
            interpolation = self.metadata("the attribute's metadata")?.interpolation;
        }
        self.ctx = saved;
        if let (true, Some(attrs)) = (keep, attrs) {
            let attr = match attrs.iter().position(|a| a.name == name) {
                Some(i) => &mut attrs[i],
                None => {
                    attrs.push(Attr {
                        name: name.to_string(),
                        type_name: type_name.to_string(),
                        line,
                        default: None,
                        sample: None,
                        interpolation: None,
                    });
                    attrs.last_mut().expect("just pushed")
                }
            };
            attr.default = default.or(attr.default.take());
            attr.sample = sample.or(attr.sample.take());
            attr.interpolation = interpolation.or(attr.interpolation.take());
        }
        Ok(())
    }

    /// `{ time: value, ... }`: the earliest sample.
    fn time_samples(&mut self, single: bool) -> R<Option<(f64, Value)>> {
        let open = self.expect(b'{', "to open the time samples")?;
        let mut best: Option<(f64, Value)> = None;
        loop {
            match self.next()? {
                (Tok::Punct(b'}'), _) => return Ok(best),
                (Tok::Punct(b','), _) => {}
                (Tok::Number(n), line) => {
                    let time = self.number(n, false, line)?;
                    self.expect(b':', "after the time sample's time")?;
                    let v = self.value(single)?;
                    if best.as_ref().is_none_or(|(t, _)| time < *t) {
                        best = Some((time, v));
                    }
                }
                (Tok::Eof, line) => return Err(self.unclosed(line, "the time samples", open)),
                (t, line) => {
                    let msg = format!(
                        "expected a time sample (time: value), found {}",
                        t.describe()
                    );
                    return Err(self.fail(line, msg));
                }
            }
        }
    }

    /// `( ... )` metadata: the entries the reader uses; the rest is skipped.
    fn metadata(&mut self, what: &str) -> R<Meta> {
        let open = self.expect(b'(', "")?;
        let mut meta = Meta::default();
        loop {
            let (t, line) = self.next()?;
            let mut op = "";
            let key = match t {
                Tok::Punct(b')') => return Ok(meta),
                Tok::Punct(b';') | Tok::Str(_) => continue,
                Tok::Ident(k) if is_listop(k) => {
                    op = k;
                    self.ident("a metadata name")?
                }
                Tok::Ident(k) => k,
                Tok::Eof => return Err(self.unclosed(line, what, open)),
                t => {
                    let msg = format!("in {what}: expected a name, found {}", t.describe());
                    return Err(self.fail(line, msg));
                }
            };
            self.expect(b'=', &format!("after the metadata {key}"))?;
            match (key, self.peek()?.0) {
                ("active", Tok::Ident(b @ ("true" | "false"))) => {
                    meta.active = Some(b == "true");
                    self.next()?;
                }
                ("active", Tok::Number(n)) => {
                    meta.active = Some(n != "0");
                    self.next()?;
                }
                ("interpolation", Tok::Str(s)) => {
                    meta.interpolation = Some(s.into_owned());
                    self.next()?;
                }
                ("variants", Tok::Punct(b'{')) => self.selections(&mut meta.selections)?,
                ("references" | "payload", _) if op != "delete" => {
                    let kind = if key == "payload" {
                        ArcKind::Payload
                    } else {
                        ArcKind::Reference
                    };
                    // A plain (explicit) list replaces; list ops add to it.
                    if op.is_empty() {
                        meta.arcs.retain(|a| a.kind != kind);
                    }
                    self.arcs(kind, &mut meta.arcs)?;
                }
                ("apiSchemas", Tok::Punct(b'[')) if op != "delete" => {
                    let (_, l) = self.next()?;
                    match self.list(false, l)? {
                        Value::Strings(s) => meta.api_schemas.extend(s),
                        Value::Numbers { nums, .. } if nums.is_empty() => {}
                        _ => return Err(self.fail(l, "apiSchemas: expected a list of names")),
                    }
                }
                _ => self.skip_value()?,
            }
        }
    }

    /// The value of `references` or `payload`: `None`, one arc, or `[arc, ...]`.
    fn arcs(&mut self, kind: ArcKind, out: &mut Vec<ArcSpec>) -> R<()> {
        match self.peek()? {
            (Tok::Ident("None"), _) => {
                self.next()?;
                Ok(())
            }
            (Tok::Punct(b'['), open) => {
                self.next()?;
                loop {
                    match self.peek()?.0 {
                        Tok::Punct(b']') => {
                            self.next()?;
                            return Ok(());
                        }
                        Tok::Punct(b',') => {
                            self.next()?;
                        }
                        Tok::Eof => {
                            let (_, l) = self.next()?;
                            return Err(self.unclosed(l, kind.key(), open));
                        }
                        _ => self.arc(kind, out)?,
                    }
                }
            }
            _ => self.arc(kind, out),
        }
    }

    /// One arc: `@asset@`, `@asset@</prim>` or `</prim>`, then an optional `( ... )` (layer
    /// offset, custom data), skipped.
    fn arc(&mut self, kind: ArcKind, out: &mut Vec<ArcSpec>) -> R<()> {
        let (t, line) = self.next()?;
        let (asset, prim) = match t {
            Tok::Asset(a) => {
                let prim = match self.peek()?.0 {
                    Tok::Path(p) => {
                        self.next()?;
                        Some(p.to_string())
                    }
                    _ => None,
                };
                (Some(a.to_string()), prim)
            }
            Tok::Path(p) => (None, Some(p.to_string())),
            t => {
                let msg = format!(
                    "{}: expected an asset path (@file.usda@) or a prim path (</Prim>), found {}",
                    kind.key(),
                    t.describe()
                );
                return Err(self.fail(line, msg));
            }
        };
        if self.peek_punct(b'(')? {
            let (_, l) = self.next()?;
            self.skip_balanced(b'(', l)?;
        }
        out.push(ArcSpec {
            kind,
            asset,
            prim,
            line,
        });
        Ok(())
    }

    /// `{ string LOD = "LOD0" ... }`.
    fn selections(&mut self, out: &mut Vec<(String, String)>) -> R<()> {
        let open = self.expect(b'{', "")?;
        loop {
            let (t, line) = self.next()?;
            match t {
                Tok::Punct(b'}') => return Ok(()),
                Tok::Punct(b';') | Tok::Punct(b',') => {}
                Tok::Ident(_) => {
                    let set = match self.next()? {
                        (Tok::Ident(s), _) => s.to_string(),
                        (Tok::Str(s), _) => s.into_owned(),
                        (t, l) => {
                            let msg =
                                format!("expected a variant set name, found {}", t.describe());
                            return Err(self.fail(l, msg));
                        }
                    };
                    self.expect(b'=', &format!("after the variant selection {set}"))?;
                    match self.next()? {
                        (Tok::Str(v), _) => out.push((set, v.into_owned())),
                        (t, l) => {
                            let msg = format!(
                                "expected the selected variant of {set} (a string), found {}",
                                t.describe()
                            );
                            return Err(self.fail(l, msg));
                        }
                    }
                }
                Tok::Eof => return Err(self.unclosed(line, "the variant selections", open)),
                t => {
                    let msg = format!(
                        "expected a variant selection (string SET = \"VARIANT\"), found {}",
                        t.describe()
                    );
                    return Err(self.fail(line, msg));
                }
            }
        }
    }

    /// Any value, skipped: balanced brackets, an asset path with its prim path and layer
    /// offset, or one token.
    fn skip_value(&mut self) -> R<()> {
        let (t, line) = self.next()?;
        match t {
            Tok::Punct(c @ (b'(' | b'[' | b'{')) => self.skip_balanced(c, line),
            Tok::Asset(_) | Tok::Path(_) => {
                // A reference's prim path, then its layer offset.
                if let Tok::Path(_) = self.peek()?.0 {
                    self.next()?;
                }
                if self.peek_punct(b'(')? {
                    let (_, l) = self.next()?;
                    self.skip_balanced(b'(', l)?;
                }
                Ok(())
            }
            Tok::Number(_) | Tok::Str(_) | Tok::Ident(_) => Ok(()),
            Tok::Eof => Err(self.fail(line, "unexpected end of file: expected a value")),
            t => Err(self.fail(line, format!("expected a value, found {}", t.describe()))),
        }
    }

    /// Skips to the bracket closing `open` (already read), whatever is inside.
    fn skip_balanced(&mut self, open: u8, line: usize) -> R<()> {
        let closer = |c: u8| match c {
            b'(' => b')',
            b'[' => b']',
            _ => b'}',
        };
        let mut stack = vec![(closer(open), line)];
        while let Some(&(want, from)) = stack.last() {
            match self.next()? {
                (Tok::Punct(c @ (b'(' | b'[' | b'{')), l) => stack.push((closer(c), l)),
                (Tok::Punct(c @ (b')' | b']' | b'}')), l) => {
                    if c != want {
                        let msg = format!(
                            "expected '{}' (to close line {from}), found '{}'",
                            want as char, c as char
                        );
                        return Err(self.fail(l, msg));
                    }
                    stack.pop();
                }
                (Tok::Eof, l) => {
                    let msg = format!(
                        "unexpected end of file: the bracket opened at line {from} is not closed"
                    );
                    return Err(self.fail(l, msg));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// A value of a wanted attribute: numbers (scalars, tuples, lists of them), strings, or
    /// `None`; other kinds are skipped as [`Value::Blocked`].
    fn value(&mut self, single: bool) -> R<Value> {
        let (t, line) = self.peek()?;
        match t {
            Tok::Punct(b'[') => {
                self.next()?;
                self.list(single, line)
            }
            Tok::Punct(b'(') => {
                self.next()?;
                let mut nums = Vec::new();
                let arity = self.tuple(single, &mut nums, 1)?;
                Ok(Value::Numbers { nums, arity })
            }
            Tok::Number(n) | Tok::Ident(n @ ("inf" | "nan")) => {
                self.next()?;
                Ok(Value::Numbers {
                    nums: vec![self.number(n, single, line)?],
                    arity: 1,
                })
            }
            Tok::Str(s) => {
                self.next()?;
                Ok(Value::Strings(vec![s.into_owned()]))
            }
            _ => {
                self.skip_value()?;
                Ok(Value::Blocked)
            }
        }
    }

    /// `[a, b, ...]` after the `[`: numbers or tuples of one arity, or strings.
    fn list(&mut self, single: bool, open: usize) -> R<Value> {
        let mut nums = Vec::new();
        let mut strings = Vec::new();
        let mut arity = None;
        let mut count = 0usize;
        loop {
            let (t, line) = self.next()?;
            let a = match t {
                Tok::Punct(b']') => break,
                Tok::Punct(b'(') => self.tuple(single, &mut nums, 1)?,
                Tok::Number(n) | Tok::Ident(n @ ("inf" | "nan")) => {
                    nums.push(self.number(n, single, line)?);
                    1
                }
                Tok::Str(s) => {
                    strings.push(s.into_owned());
                    0
                }
                Tok::Eof => {
                    let msg = format!("unexpected end of file in the list opened at line {open}");
                    return Err(self.fail(line, msg));
                }
                t => {
                    let msg = format!(
                        "expected a number, tuple or string in the list, found {}",
                        t.describe()
                    );
                    return Err(self.fail(line, msg));
                }
            };
            if *arity.get_or_insert(a) != a {
                let msg = format!(
                    "element {count} has {a} components; the list's first element has {}",
                    arity.unwrap_or(0)
                );
                return Err(self.fail(line, msg));
            }
            count += 1;
            match self.next()? {
                (Tok::Punct(b','), _) => {}
                (Tok::Punct(b']'), _) => break,
                (t, l) => {
                    let msg = format!(
                        "expected ',' or ']' after element {}, found {}",
                        count - 1,
                        t.describe()
                    );
                    return Err(self.fail(l, msg));
                }
            }
        }
        Ok(match arity {
            Some(0) => Value::Strings(strings),
            a => Value::Numbers {
                nums,
                arity: a.unwrap_or(1),
            },
        })
    }

    /// `( ... )` after the `(`: its numbers (nested tuples flattened) appended to `nums`;
    /// returns how many.
    fn tuple(&mut self, single: bool, nums: &mut Vec<f64>, depth: usize) -> R<usize> {
        let mut n = 0;
        loop {
            let (t, line) = self.next()?;
            match t {
                Tok::Punct(b')') if n == 0 => return Ok(0),
                Tok::Punct(b'(') if depth < 4 => n += self.tuple(single, nums, depth + 1)?,
                Tok::Number(s) | Tok::Ident(s @ ("inf" | "nan")) => {
                    nums.push(self.number(s, single, line)?);
                    n += 1;
                }
                Tok::Eof => return Err(self.fail(line, "unexpected end of file in a tuple")),
                t => {
                    let msg = format!("expected a number in the tuple, found {}", t.describe());
                    return Err(self.fail(line, msg));
                }
            }
            match self.next()? {
                (Tok::Punct(b','), _) if self.peek_punct(b')')? => {
                    self.next()?;
                    return Ok(n);
                }
                (Tok::Punct(b','), _) => {}
                (Tok::Punct(b')'), _) => return Ok(n),
                (t, l) => {
                    let msg = format!("expected ',' or ')' in the tuple, found {}", t.describe());
                    return Err(self.fail(l, msg));
                }
            }
        }
    }

    /// A number token's value; `single` rounds it to `f32` as usd-core does for `float` types.
    fn number(&self, s: &str, single: bool, line: usize) -> R<f64> {
        let v = match s {
            "inf" | "+inf" => Some(f64::INFINITY),
            "-inf" => Some(f64::NEG_INFINITY),
            "nan" => Some(f64::NAN),
            _ if single => s.parse::<f32>().ok().map(f64::from),
            _ => s.parse::<f64>().ok(),
        };
        v.ok_or_else(|| self.fail(line, format!("bad number {s:?}")))
    }
}

/// Whether values of this type are single (or half) precision.
fn is_single(type_name: &str) -> bool {
    type_name.starts_with("float")
        || type_name.starts_with("half")
        || ((type_name.ends_with('f') || type_name.ends_with('h'))
            && !type_name.starts_with("matrix"))
}

#[cfg(test)]
#[path = "usda_parse_tests.rs"]
mod tests;
