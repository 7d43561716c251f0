//! Stanford PLY reading: ASCII, binary little-endian and binary big-endian (writing is
//! `ply_write.rs`).
//!
//! Read: `element vertex` with `x y z` (any scalar type, also the `int8`...`float64` names),
//! optional `nx ny nz` and `s t` / `u v` / `texture_u texture_v` / `texture_s texture_t` (stored
//! as face-varying attributes whose corner indices are the vertex indices); `element face` with
//! `property list <count> <index> vertex_indices` (or `vertex_index`). Every other property,
//! list or scalar, and every other element is skipped. Counts above
//! [`ReadOptions::max_elements`] are refused before anything is allocated, and reservations are
//! bounded by what the rest of the input can hold, so a hostile header cannot make the reader
//! allocate. Data is decoded straight out of the 64 KiB read buffer; triangle files with a
//! `uchar` count and `int`/`uint` indices in little-endian take a dedicated fast path.

use super::ReadOptions;
use super::source::{BUF_SIZE, Source, element_limit, parse_f64, parse_i64, show, tokens};
use crate::{FaceVarying, Mesh, MeshError};
use std::io::Read;

/// Largest header accepted, in bytes.
const MAX_HEADER: u64 = 1 << 20;

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    pub(super) fn parse(name: &[u8]) -> Option<Scalar> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Decodes `b[..self.size()]` (the caller guarantees the length).
    #[inline]
    pub(super) fn decode(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:literal) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(get!(i16, 2)),
            Scalar::U16 => f64::from(get!(u16, 2)),
            Scalar::I32 => f64::from(get!(i32, 4)),
            Scalar::U32 => f64::from(get!(u32, 4)),
            Scalar::F32 => f64::from(get!(f32, 4)),
            Scalar::F64 => get!(f64, 8),
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

impl Element {
    /// Record size when every property is a scalar.
    fn fixed_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0usize, |acc, p| match p.kind {
            Kind::Scalar(t) => acc.checked_add(t.size()),
            Kind::List { .. } => None,
        })
    }

    fn find(&self, names: &[&str]) -> Option<usize> {
        self.props
            .iter()
            .position(|p| names.contains(&p.name.as_str()))
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

fn read_header<R: Read>(src: &mut Source<'_, R>) -> Result<(Encoding, Vec<Element>), MeshError> {
    let mut line = Vec::new();
    if !src.read_line(&mut line)? || line.trim_ascii() != b"ply" {
        return Err(src.error_at(1, "not a PLY file: the first line must be 'ply'"));
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if src.consumed() > MAX_HEADER {
            return Err(src.error(format!("PLY header longer than {MAX_HEADER} bytes")));
        }
        if !src.read_line(&mut line)? {
            return Err(src.error("file ends inside the PLY header (no 'end_header')"));
        }
        let mut t = tokens(&line);
        let Some(keyword) = t.next() else { continue };
        match keyword {
            b"format" => {
                encoding = Some(match t.next().unwrap_or_default() {
                    b"ascii" => Encoding::Ascii,
                    b"binary_little_endian" => Encoding::BinaryLe,
                    b"binary_big_endian" => Encoding::BinaryBe,
                    other => {
                        return Err(MeshError::Unsupported(format!(
                            "{}: unsupported PLY format '{}'",
                            src.name(),
                            show(other)
                        )));
                    }
                });
            }
            b"comment" | b"obj_info" => {}
            b"element" => {
                let (Some(name), Some(count)) = (t.next(), t.next()) else {
                    return Err(src.error("'element' needs a name and a count"));
                };
                let count = parse_i64(count)
                    .and_then(|c| u64::try_from(c).ok())
                    .or_else(|| std::str::from_utf8(count).ok()?.parse::<u64>().ok())
                    .ok_or_else(|| src.error(format!("bad element count '{}'", show(count))))?;
                let name = String::from_utf8_lossy(name).into_owned();
                elements.push(Element {
                    name,
                    count,
                    props: Vec::new(),
                });
            }
            b"property" => {
                let bad_type =
                    |t: &[u8]| src.error(format!("unknown PLY property type '{}'", show(t)));
                let ty = t.next().unwrap_or_default();
                let kind = if ty == b"list" {
                    let (c, i) = (t.next().unwrap_or_default(), t.next().unwrap_or_default());
                    let count = Scalar::parse(c).ok_or_else(|| bad_type(c))?;
                    let item = Scalar::parse(i).ok_or_else(|| bad_type(i))?;
                    if !count.is_int() {
                        return Err(src.error("a PLY list count must have an integer type"));
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(Scalar::parse(ty).ok_or_else(|| bad_type(ty))?)
                };
                let Some(name) = t.next() else {
                    return Err(src.error("'property' needs a name"));
                };
                let name = String::from_utf8_lossy(name).into_owned();
                let Some(element) = elements.last_mut() else {
                    return Err(src.error("'property' before any 'element'"));
                };
                element.props.push(Property { name, kind });
            }
            b"end_header" => break,
            other => {
                return Err(src.error(format!("unexpected PLY header line '{}'", show(other))));
            }
        }
    }
    let encoding = encoding.ok_or_else(|| src.error("PLY header has no 'format' line"))?;
    Ok((encoding, elements))
}

/// The result of decoding one value.
enum Next {
    Value(f64),
    End,
    Bad(String),
}

/// Decodes values of either encoding, with the context needed for error messages.
enum Decoder<'s, 'a, R> {
    Ascii {
        src: &'s mut Source<'a, R>,
        line: Vec<u8>,
        pos: usize,
    },
    Binary {
        src: &'s mut Source<'a, R>,
        big_endian: bool,
    },
}

impl<R: Read> Decoder<'_, '_, R> {
    fn src(&self) -> &Source<'_, R> {
        match self {
            Decoder::Ascii { src, .. } | Decoder::Binary { src, .. } => src,
        }
    }

    /// A parse error for record `i` of `element` (line number for ASCII, none for binary).
    fn error(&self, element: &str, i: u64, what: &str) -> MeshError {
        let line = match self {
            Decoder::Ascii { src, .. } => src.line(),
            Decoder::Binary { .. } => 0,
        };
        self.src().error_at(line, format!("{element} {i}: {what}"))
    }

    fn next(&mut self, ty: Scalar) -> Result<Next, MeshError> {
        match self {
            Decoder::Binary { src, big_endian } => {
                let n = ty.size();
                let b = src.fill(n)?;
                if b.len() < n {
                    return Ok(Next::End);
                }
                let v = ty.decode(b, *big_endian);
                src.consume(n);
                Ok(Next::Value(v))
            }
            Decoder::Ascii { src, line, pos } => loop {
                let rest = &line[*pos..];
                let start = rest.iter().position(|b| !b.is_ascii_whitespace());
                if let Some(s) = start {
                    let len = rest[s..].iter().position(|b| b.is_ascii_whitespace());
                    let len = len.unwrap_or(rest.len() - s);
                    let tok = &rest[s..s + len];
                    *pos += s + len;
                    let v = if ty.is_int() {
                        parse_i64(tok).map(|v| v as f64).or_else(|| parse_f64(tok))
                    } else {
                        parse_f64(tok)
                    };
                    return Ok(v.map_or_else(|| Next::Bad(show(tok)), Next::Value));
                }
                if !src.read_line(line)? {
                    return Ok(Next::End);
                }
                *pos = 0;
            },
        }
    }

    /// The next value of record `i` of `element`, with "file ends" / "bad number" errors.
    #[inline]
    fn value(&mut self, ty: Scalar, element: &str, i: u64) -> Result<f64, MeshError> {
        match self.next(ty)? {
            Next::Value(v) => Ok(v),
            Next::End => Err(self.error(element, i, "file ends")),
            Next::Bad(t) => Err(self.error(element, i, &format!("bad number '{t}'"))),
        }
    }

    /// A list length.
    fn list_len(&mut self, ty: Scalar, element: &str, i: u64) -> Result<u64, MeshError> {
        let n = self.value(ty, element, i)?;
        if n < 0.0 || n.fract() != 0.0 || n > f64::from(u32::MAX) {
            return Err(self.error(element, i, &format!("bad list length {n}")));
        }
        Ok(n as u64)
    }

    /// Skips `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: u64, element: &str, i: u64) -> Result<(), MeshError> {
        if let Decoder::Binary { src, .. } = self {
            let want = n.saturating_mul(ty.size() as u64);
            if src.skip(want)? < want {
                return Err(self.error(element, i, "file ends"));
            }
            return Ok(());
        }
        for _ in 0..n {
            self.value(ty, element, i)?;
        }
        Ok(())
    }

    /// Skips a whole record of `element`.
    fn skip_record(&mut self, element: &Element, i: u64) -> Result<(), MeshError> {
        for p in &element.props {
            match p.kind {
                Kind::Scalar(t) => self.skip(t, 1, &element.name, i)?,
                Kind::List { count, item } => {
                    let n = self.list_len(count, &element.name, i)?;
                    self.skip(item, n, &element.name, i)?;
                }
            }
        }
        Ok(())
    }
}

/// Where the wanted vertex properties are: `slots[k]` is the property index feeding value `k`
/// (x y z, nx ny nz, u v).
struct VertexLayout {
    slots: Vec<Option<u8>>,
    normals: bool,
    uvs: bool,
}

impl VertexLayout {
    fn new(element: &Element, name: &str) -> Result<VertexLayout, MeshError> {
        let scalar = |i: usize| matches!(element.props[i].kind, Kind::Scalar(_));
        let find = |names: &[&str]| element.find(names).filter(|&i| scalar(i));
        let mut slots = vec![None; element.props.len()];
        for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
            let Some(i) = find(&[axis]) else {
                return Err(MeshError::Parse {
                    path: name.to_string(),
                    line: 0,
                    message: format!("PLY vertex element has no scalar '{axis}' property"),
                });
            };
            slots[i] = Some(k as u8);
        }
        let normal = [find(&["nx"]), find(&["ny"]), find(&["nz"])];
        let normals = normal.iter().all(Option::is_some);
        if normals {
            for (k, i) in normal.into_iter().flatten().enumerate() {
                slots[i] = Some(3 + k as u8);
            }
        }
        let u = find(&["s", "u", "texture_u", "texture_s"]);
        let v = find(&["t", "v", "texture_v", "texture_t"]);
        let uvs = u.is_some() && v.is_some();
        if let (Some(u), Some(v)) = (u, v) {
            slots[u] = Some(6);
            slots[v] = Some(7);
        }
        Ok(VertexLayout {
            slots,
            normals,
            uvs,
        })
    }
}

/// Per-vertex attributes being read.
#[derive(Default)]
struct VertexAttrs {
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
}

fn push_vertex(mesh: &mut Mesh, attrs: &mut VertexAttrs, layout: &VertexLayout, s: &[f64; 8]) {
    mesh.positions.push([s[0] as f32, s[1] as f32, s[2] as f32]);
    if layout.normals {
        attrs.normals.push([s[3] as f32, s[4] as f32, s[5] as f32]);
    }
    if layout.uvs {
        attrs.uvs.push([s[6] as f32, s[7] as f32]);
    }
}

fn read_vertices<R: Read>(
    dec: &mut Decoder<'_, '_, R>,
    element: &Element,
    layout: &VertexLayout,
    mesh: &mut Mesh,
    attrs: &mut VertexAttrs,
) -> Result<(), MeshError> {
    let name = element.name.as_str();
    let mut s = [0f64; 8];
    if let (Decoder::Binary { src, big_endian }, Some(size)) = (&mut *dec, element.fixed_size())
        && size <= BUF_SIZE
    {
        // Fixed-size records: decode the wanted fields straight out of the buffer.
        let be = *big_endian;
        let mut fields = Vec::new();
        let mut offset = 0;
        for (p, slot) in element.props.iter().zip(&layout.slots) {
            let Kind::Scalar(t) = p.kind else {
                unreachable!("fixed_size has only scalars")
            };
            if let Some(k) = slot {
                fields.push((offset, t, usize::from(*k)));
            }
            offset += t.size();
        }
        // Whole records at a time out of each buffer fill; `x y z` only, little-endian float
        // (what most writers produce), is a straight copy of each record.
        let xyz_f32 = !be
            && size == 12
            && fields
                == [
                    (0, Scalar::F32, 0),
                    (4, Scalar::F32, 1),
                    (8, Scalar::F32, 2),
                ];
        let mut i = 0;
        while i < element.count {
            let b = src.fill(size)?;
            if b.len() < size {
                return Err(src.error_at(0, format!("{name} {i}: file ends")));
            }
            let k = (b.len() / size).min(usize::try_from(element.count - i).unwrap_or(usize::MAX));
            let records = &b[..k * size];
            if xyz_f32 {
                mesh.positions.extend(records.chunks_exact(12).map(|r| {
                    let f = |o: usize| f32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]);
                    [f(0), f(4), f(8)]
                }));
            } else {
                for r in records.chunks_exact(size) {
                    for &(off, t, k) in &fields {
                        s[k] = t.decode(&r[off..], be);
                    }
                    push_vertex(mesh, attrs, layout, &s);
                }
            }
            src.consume(k * size);
            i += k as u64;
        }
        return Ok(());
    }
    for i in 0..element.count {
        for (p, slot) in element.props.iter().zip(&layout.slots) {
            match p.kind {
                Kind::Scalar(t) => {
                    let v = dec.value(t, name, i)?;
                    if let Some(k) = slot {
                        s[usize::from(*k)] = v;
                    }
                }
                Kind::List { count, item } => {
                    let n = dec.list_len(count, name, i)?;
                    dec.skip(item, n, name, i)?;
                }
            }
        }
        push_vertex(mesh, attrs, layout, &s);
    }
    Ok(())
}

/// Face-reading context.
struct FaceCtx {
    /// Declared vertex count (indices must be below it).
    vertices: u64,
    /// Property index of the vertex index list.
    list: usize,
    /// Corner limit.
    limit: u64,
}

impl FaceCtx {
    /// Checks a face of `n` corners; the error continues "face 12".
    fn check_size(&self, mesh: &Mesh, n: u64) -> Result<(), String> {
        if n < 3 {
            return Err(format!(" has {n} vertices; a face needs at least 3"));
        }
        if mesh.face_indices.len() as u64 + n > self.limit {
            return Err(format!(": face corners exceed the limit of {}", self.limit));
        }
        Ok(())
    }

    fn out_of_range(&self, v: impl std::fmt::Display) -> String {
        format!(
            "vertex index {v} is out of range; the file has {} vertices",
            self.vertices
        )
    }
}

fn read_faces<R: Read>(
    dec: &mut Decoder<'_, '_, R>,
    element: &Element,
    ctx: &FaceCtx,
    mesh: &mut Mesh,
) -> Result<(), MeshError> {
    let name = element.name.as_str();
    // `Some(signed)` for the fast path: little-endian, one property `list uchar int|uint`.
    let fast = match (&*dec, element.props.as_slice()) {
        (
            Decoder::Binary {
                big_endian: false, ..
            },
            [only],
        ) => match only.kind {
            Kind::List {
                count: Scalar::U8,
                item: item @ (Scalar::I32 | Scalar::U32),
            } => Some(item == Scalar::I32),
            _ => None,
        },
        _ => None,
    };
    if let (Some(signed), Decoder::Binary { src, .. }) = (fast, &mut *dec) {
        // The common binary triangle file: `list uchar int|uint`, little-endian.
        let nv = u32::try_from(ctx.vertices).unwrap_or(u32::MAX);
        // Indices at or above `bound` are out of range (negative ones too, when signed).
        let bound = if signed { nv.min(1 << 31) } else { nv };
        let out_of_range = |v: u32| {
            let shown = if signed {
                i64::from(v as i32)
            } else {
                i64::from(v)
            };
            ctx.out_of_range(shown)
        };
        let mut i = 0;
        while i < element.count {
            let b = src.fill(1 + 255 * 4)?;
            // Triangles in bulk: the run of whole 13-byte records starting with 3 in the buffer,
            // range-checked by a max-reduction (the record at fault is found only on failure).
            let room = (ctx.limit.saturating_sub(mesh.face_indices.len() as u64) / 3)
                .min(element.count - i);
            let k_max = (b.len() / 13).min(usize::try_from(room).unwrap_or(usize::MAX));
            let k = b[..k_max * 13]
                .chunks_exact(13)
                .position(|r| r[0] != 3)
                .unwrap_or(k_max);
            if k > 0 {
                let base = mesh.face_indices.len();
                let mut top = 0u32;
                mesh.face_indices
                    .extend(b[..k * 13].chunks_exact(13).flat_map(|r| {
                        let v = |o: usize| u32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]);
                        let t = [v(1), v(5), v(9)];
                        top = top.max(t[0]).max(t[1]).max(t[2]);
                        t
                    }));
                if top >= bound {
                    let c = mesh.face_indices[base..]
                        .iter()
                        .position(|&v| v >= bound)
                        .expect("an index is at or above the bound");
                    let v = mesh.face_indices[base + c];
                    let f = i + (c / 3) as u64;
                    return Err(src.error_at(0, format!("{name} {f}: {}", out_of_range(v))));
                }
                let end = mesh.face_offsets.last().copied().unwrap_or(0);
                mesh.face_offsets
                    .extend((1..=k as u32).map(|j| end + 3 * j));
                src.consume(k * 13);
                i += k as u64;
                continue;
            }
            // Any other face (or a triangle across the buffer's end): one record.
            let Some(&n) = b.first() else {
                return Err(src.error_at(0, format!("{name} {i}: file ends")));
            };
            let need = 1 + 4 * usize::from(n);
            if b.len() < need {
                return Err(src.error_at(0, format!("{name} {i}: file ends")));
            }
            if let Err(e) = ctx.check_size(mesh, u64::from(n)) {
                return Err(src.error_at(0, format!("{name} {i}{e}")));
            }
            for c in b[1..need].chunks_exact(4) {
                let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                if v >= bound {
                    return Err(src.error_at(0, format!("{name} {i}: {}", out_of_range(v))));
                }
                mesh.face_indices.push(v);
            }
            src.consume(need);
            mesh.face_offsets.push(mesh.face_indices.len() as u32);
            i += 1;
        }
        return Ok(());
    }
    for i in 0..element.count {
        for (p, prop) in element.props.iter().enumerate() {
            match prop.kind {
                Kind::Scalar(t) => dec.skip(t, 1, name, i)?,
                Kind::List { count, item } if p == ctx.list => {
                    let n = dec.list_len(count, name, i)?;
                    if let Err(e) = ctx.check_size(mesh, n) {
                        let line = match dec {
                            Decoder::Ascii { src, .. } => src.line(),
                            Decoder::Binary { .. } => 0,
                        };
                        return Err(dec.src().error_at(line, format!("{name} {i}{e}")));
                    }
                    for _ in 0..n {
                        let v = dec.value(item, name, i)?;
                        if !(v >= 0.0 && v.fract() == 0.0 && v < ctx.vertices as f64) {
                            return Err(dec.error(name, i, &ctx.out_of_range(v)));
                        }
                        mesh.face_indices.push(v as u32);
                    }
                }
                Kind::List { count, item } => {
                    let n = dec.list_len(count, name, i)?;
                    dec.skip(item, n, name, i)?;
                }
            }
        }
        mesh.face_offsets.push(mesh.face_indices.len() as u32);
    }
    Ok(())
}

fn skip_element<R: Read>(dec: &mut Decoder<'_, '_, R>, element: &Element) -> Result<(), MeshError> {
    if element.props.is_empty() {
        // Records of nothing: do not spin through a hostile count.
        return Ok(());
    }
    if let (Decoder::Binary { src, .. }, Some(size)) = (&mut *dec, element.fixed_size()) {
        let want = element.count.saturating_mul(size as u64);
        let got = src.skip(want)?;
        if got < want {
            let i = got / (size as u64).max(1);
            return Err(src.error_at(0, format!("{} {i}: file ends", element.name)));
        }
        return Ok(());
    }
    for i in 0..element.count {
        dec.skip_record(element, i)?;
    }
    Ok(())
}

/// Smallest possible size of one record, to bound reservations (ASCII: a digit and a space
/// per value).
fn min_record(element: &Element, encoding: Encoding, index_list: Option<usize>) -> u64 {
    element
        .props
        .iter()
        .enumerate()
        .map(|(p, prop)| {
            let items: usize = if Some(p) == index_list { 3 } else { 0 };
            match (encoding, prop.kind) {
                (Encoding::Ascii, Kind::Scalar(_)) => 2,
                (Encoding::Ascii, Kind::List { .. }) => 2 + 2 * items as u64,
                (_, Kind::Scalar(t)) => t.size() as u64,
                (_, Kind::List { count, item }) => (count.size() + items * item.size()) as u64,
            }
        })
        .sum()
}

pub(crate) fn read<R: Read>(
    src: &mut Source<'_, R>,
    opts: &ReadOptions,
) -> Result<Mesh, MeshError> {
    let limit = element_limit(opts.max_elements);
    let (encoding, elements) = read_header(src)?;
    let vertex_el = elements.iter().position(|e| e.name == "vertex");
    let face_el = elements.iter().position(|e| e.name == "face");
    for e in [vertex_el, face_el]
        .into_iter()
        .flatten()
        .map(|i| &elements[i])
    {
        if e.count > limit {
            return Err(MeshError::TooLarge(format!(
                "{}: PLY header declares {} {} elements; the limit is {limit}",
                src.name(),
                e.count,
                e.name
            )));
        }
    }
    let layout = vertex_el
        .map(|i| VertexLayout::new(&elements[i], src.name()))
        .transpose()?;
    let face_list = match face_el {
        Some(f) => {
            let el = &elements[f];
            let list = el
                .find(&["vertex_indices", "vertex_index"])
                .filter(|&p| matches!(el.props[p].kind, Kind::List { item, .. } if item.is_int()));
            Some(list.ok_or_else(|| {
                src.error_at(0, "PLY face element has no integer 'vertex_indices' list")
            })?)
        }
        None => None,
    };

    let mut mesh = Mesh::default();
    let mut attrs = VertexAttrs::default();
    if let (Some(v), Some(layout)) = (vertex_el, &layout) {
        let el = &elements[v];
        let n = src.reserve_hint(el.count, min_record(el, encoding, None));
        mesh.positions.reserve_exact(n);
        if layout.normals {
            attrs.normals.reserve_exact(n);
        }
        if layout.uvs {
            attrs.uvs.reserve_exact(n);
        }
    }
    let vertices = vertex_el.map_or(0, |v| elements[v].count);
    let mut dec = match encoding {
        Encoding::Ascii => Decoder::Ascii {
            src,
            line: Vec::new(),
            pos: 0,
        },
        Encoding::BinaryLe => Decoder::Binary {
            src,
            big_endian: false,
        },
        Encoding::BinaryBe => Decoder::Binary {
            src,
            big_endian: true,
        },
    };
    for (e, element) in elements.iter().enumerate() {
        if Some(e) == vertex_el
            && let Some(layout) = &layout
        {
            read_vertices(&mut dec, element, layout, &mut mesh, &mut attrs)?;
        } else if Some(e) == face_el
            && let Some(list) = face_list
        {
            let src = dec.src();
            let faces = src.reserve_hint(element.count, min_record(element, encoding, Some(list)));
            // Corners: bounded by the bytes left when known (exact for a triangle file).
            let corners = match (src.remaining(), element.props[list].kind, encoding) {
                (
                    Some(rem),
                    Kind::List { count, item },
                    Encoding::BinaryLe | Encoding::BinaryBe,
                ) => {
                    let lists = element.count.saturating_mul(count.size() as u64);
                    (rem.saturating_sub(lists) / item.size() as u64).min(faces as u64 * 4)
                }
                _ => faces as u64 * 3,
            };
            mesh.face_offsets.reserve_exact(faces);
            mesh.face_indices
                .reserve_exact(usize::try_from(corners).unwrap_or(0));
            let ctx = FaceCtx {
                vertices,
                list,
                limit,
            };
            read_faces(&mut dec, element, &ctx, &mut mesh)?;
        } else {
            skip_element(&mut dec, element)?;
        }
    }
    if layout.as_ref().is_some_and(|l| l.normals) {
        mesh.normals = Some(FaceVarying {
            values: attrs.normals,
            indices: mesh.face_indices.clone(),
        });
    }
    if layout.as_ref().is_some_and(|l| l.uvs) {
        mesh.uvs = Some(FaceVarying {
            values: attrs.uvs,
            indices: mesh.face_indices.clone(),
        });
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use crate::io::{Format, ReadOptions, read};
    use crate::{Mesh, MeshError};

    fn parse(bytes: &[u8]) -> Result<Mesh, MeshError> {
        let o = ReadOptions::default().with_input_len(bytes.len() as u64);
        read(bytes, Format::Ply, "t.ply", &o)
    }

    #[test]
    fn ascii_with_skipped_properties_lists_and_elements() {
        let text = "ply\nformat ascii 1.0\ncomment hi\nobj_info x\nelement vertex 4\n\
            property double x\nproperty list uchar int junk\nproperty float y\nproperty float z\n\
            property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n\
            element face 1\nproperty uchar flags\nproperty list uint8 int32 vertex_index\nproperty float q\n\
            element edge 1\nproperty int vertex1\nproperty list uchar float w\nend_header\n\
            0 2 7 7 0 0 0 0 1 0.5 0.25\n1 0 0 0 0 0 1 0 0\n1 0 1 0 0 0 1 0 0\n0 0 1 0 0 0 1 0 0\n\
            9 4 0 1 2 3 0.5\n3 2 1.5 2.5\n";
        let m = parse(text.as_bytes()).unwrap();
        assert_eq!(
            m.positions,
            [[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(m.face(0), &[0, 1, 2, 3]);
        assert_eq!(m.normals.as_ref().unwrap().values[0], [0.0, 0.0, 1.0]);
        assert_eq!(m.uvs.as_ref().unwrap().values[0], [0.5, 0.25]);
        assert_eq!(m.uvs.as_ref().unwrap().indices, [0, 1, 2, 3]);
    }

    #[test]
    fn header_errors() {
        let e = parse(b"ply\nformat binary_middle_endian 1.0\nend_header\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.ply: unsupported PLY format 'binary_middle_endian'"
        );
        let e = parse(b"plx\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.ply:1: not a PLY file: the first line must be 'ply'"
        );
        let e =
            parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n")
                .unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.ply: PLY vertex element has no scalar 'y' property"
        );
    }
}
