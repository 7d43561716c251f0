//! OFF (Object File Format, ASCII).
//!
//! Read: an optional `OFF` header (also `COFF`, `NOFF`, `CNOFF`, `STOFF` and combinations;
//! the counts may follow on the same line), a `vertices faces [edges]` line, one vertex per line
//! (`x y z`, then `nx ny nz` for `N`, then `s t` for `ST` without `C`; colours ignored), one
//! face per line (`n i1 ... in`, trailing colour values ignored). `#` starts a comment. The
//! higher-dimensional `4OFF` / `nOFF` variants and binary OFF are not supported.
//!
//! Write: plain ASCII `OFF` (positions and faces only).

use super::ReadOptions;
use super::obj::{push_u32, write_values};
use super::source::{Source, element_limit, parse_f32, parse_i64, show, tokens};
use crate::{FaceVarying, Mesh, MeshError};
use std::io::{Read, Write};

/// Reads the next line with content (comments stripped); `false` at the end of the input.
fn content_line<R: Read>(src: &mut Source<'_, R>, line: &mut Vec<u8>) -> Result<bool, MeshError> {
    while src.read_line(line)? {
        if let Some(hash) = line.iter().position(|&b| b == b'#') {
            line.truncate(hash);
        }
        if !line.trim_ascii().is_empty() {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Which optional per-vertex values the header announces.
#[derive(Default)]
struct Header {
    normals: bool,
    colors: bool,
    texture: bool,
}

/// Parses `[ST][C][N]OFF`; `None` when `tok` is not such a keyword.
fn parse_keyword(tok: &[u8]) -> Option<Result<Header, String>> {
    let mut rest = tok.strip_suffix(b"OFF")?;
    let mut h = Header::default();
    if let Some(r) = rest.strip_prefix(b"ST") {
        (h.texture, rest) = (true, r);
    }
    if let Some(r) = rest.strip_prefix(b"C") {
        (h.colors, rest) = (true, r);
    }
    if let Some(r) = rest.strip_prefix(b"N") {
        (h.normals, rest) = (true, r);
    }
    Some(match rest {
        b"" => Ok(h),
        b"4" | b"n" | b"4n" => Err(format!(
            "'{}' (higher-dimensional OFF) is not supported",
            show(tok)
        )),
        _ => return None,
    })
}

pub(crate) fn read<R: Read>(
    src: &mut Source<'_, R>,
    opts: &ReadOptions,
) -> Result<Mesh, MeshError> {
    let limit = element_limit(opts.max_elements);
    let mut line = Vec::new();
    if !content_line(src, &mut line)? {
        return Err(src.error_at(1, "empty file: expected an OFF header"));
    }
    let first = tokens(&line).next().unwrap_or_default();
    let (header, skip) = match parse_keyword(first) {
        Some(Ok(h)) => (h, 1),
        Some(Err(msg)) => return Err(MeshError::Unsupported(format!("{}: {msg}", src.name()))),
        None if parse_i64(first).is_some() => (Header::default(), 0),
        None => {
            return Err(src.error(format!(
                "not an OFF file: expected 'OFF', got '{}'",
                show(first)
            )));
        }
    };
    let mut counts: Vec<Vec<u8>> = tokens(&line).skip(skip).map(<[u8]>::to_vec).collect();
    if counts
        .first()
        .is_some_and(|t| t.eq_ignore_ascii_case(b"BINARY"))
    {
        return Err(MeshError::Unsupported(format!(
            "{}: binary OFF is not supported",
            src.name()
        )));
    }
    if counts.len() < 2 {
        if !content_line(src, &mut line)? {
            return Err(src.error("file ends before the OFF counts line"));
        }
        counts = tokens(&line).map(<[u8]>::to_vec).collect();
    }
    let count = |k: usize, what: &str| -> Result<u64, MeshError> {
        let tok = counts
            .get(k)
            .ok_or_else(|| src.error(format!("OFF counts line has no {what} count")))?;
        parse_i64(tok)
            .and_then(|c| u64::try_from(c).ok())
            .ok_or_else(|| src.error(format!("bad {what} count '{}'", show(tok))))
    };
    let (nv, nf) = (count(0, "vertex")?, count(1, "face")?);
    for (n, what) in [(nv, "vertices"), (nf, "faces")] {
        if n > limit {
            return Err(MeshError::TooLarge(format!(
                "{}: OFF header declares {n} {what}; the limit is {limit}",
                src.name()
            )));
        }
    }

    let mut mesh = Mesh::default();
    let n_hint = src.reserve_hint(nv, 6);
    mesh.positions.reserve_exact(n_hint);
    let mut normals = Vec::with_capacity(if header.normals { n_hint } else { 0 });
    let uvs_on = header.texture && !header.colors;
    let mut uvs = Vec::with_capacity(if uvs_on { n_hint } else { 0 });
    let wanted = 3 + if header.normals { 3 } else { 0 } + if uvs_on { 2 } else { 0 };
    let mut values = [0f32; 8];
    for i in 0..nv {
        if !content_line(src, &mut line)? {
            return Err(src.error(format!("vertex {i}: file ends")));
        }
        let mut t = tokens(&line);
        for (k, v) in values[..wanted].iter_mut().enumerate() {
            let tok = t.next().ok_or_else(|| {
                src.error(format!("vertex {i}: expected {wanted} values, got {k}"))
            })?;
            *v = parse_f32(tok)
                .ok_or_else(|| src.error(format!("vertex {i}: bad coordinate '{}'", show(tok))))?;
        }
        mesh.positions.push([values[0], values[1], values[2]]);
        if header.normals {
            normals.push([values[3], values[4], values[5]]);
        }
        if uvs_on {
            let o = if header.normals { 6 } else { 3 };
            uvs.push([values[o], values[o + 1]]);
        }
    }

    let f_hint = src.reserve_hint(nf, 8);
    mesh.face_offsets.reserve_exact(f_hint);
    mesh.face_indices.reserve(f_hint.saturating_mul(3));
    for i in 0..nf {
        if !content_line(src, &mut line)? {
            return Err(src.error(format!("face {i}: file ends")));
        }
        let mut t = tokens(&line);
        let tok = t.next().unwrap_or_default();
        let n = parse_i64(tok)
            .ok_or_else(|| src.error(format!("face {i}: bad vertex count '{}'", show(tok))))?;
        if n < 3 {
            return Err(src.error(format!(
                "face {i} has {n} vertices; a face needs at least 3"
            )));
        }
        if mesh.face_indices.len() as u64 + n as u64 > limit {
            return Err(MeshError::TooLarge(format!(
                "{}: OFF face corners exceed the limit of {limit}",
                src.name()
            )));
        }
        for k in 0..n {
            let tok = t.next().ok_or_else(|| {
                src.error(format!("face {i}: expected {n} vertex indices, got {k}"))
            })?;
            let v = parse_i64(tok)
                .ok_or_else(|| src.error(format!("face {i}: bad vertex index '{}'", show(tok))))?;
            if v < 0 || v as u64 >= nv {
                return Err(src.error(format!(
                    "face {i}: vertex index {v} is out of range; the file has {nv} vertices"
                )));
            }
            mesh.face_indices.push(v as u32);
        }
        mesh.face_offsets.push(mesh.face_indices.len() as u32);
    }
    if header.normals {
        mesh.normals = Some(FaceVarying {
            values: normals,
            indices: mesh.face_indices.clone(),
        });
    }
    if uvs_on {
        mesh.uvs = Some(FaceVarying {
            values: uvs,
            indices: mesh.face_indices.clone(),
        });
    }
    Ok(mesh)
}

/// Writes `mesh` as OFF; with `f64_positions`, those as its vertex lines.
pub(crate) fn write(
    mesh: &Mesh,
    w: &mut impl Write,
    f64_positions: Option<&[[f64; 3]]>,
) -> std::io::Result<()> {
    writeln!(w, "OFF\n{} {} 0", mesh.vertex_count(), mesh.face_count())?;
    match f64_positions {
        Some(p) => super::obj::write_f64_values(w, b"", p)?,
        None => write_values(w, b"", &mesh.positions)?,
    }
    let mut line = Vec::with_capacity(128);
    for face in mesh.faces() {
        line.clear();
        push_u32(&mut line, face.len() as u32);
        for &v in face {
            line.push(b' ');
            push_u32(&mut line, v);
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::io::{Format, ReadOptions, read};
    use crate::{Mesh, MeshError};

    fn parse(text: &str) -> Result<Mesh, MeshError> {
        read(
            text.as_bytes(),
            Format::Off,
            "t.off",
            &ReadOptions::default(),
        )
    }

    #[test]
    fn variants_comments_and_colours() {
        let m = parse(
            "# c\nCOFF 4 1 0\n0 0 0 255 0 0 255\n1 0 0 1 1 1 1\n1 1 0 1 1 1 1\n\n\
                       0 1 0 1 1 1 1 # corner\n4 0 1 2 3 255 0 0\n",
        )
        .unwrap();
        assert_eq!((m.vertex_count(), m.face(0)), (4, &[0u32, 1, 2, 3][..]));
        let m = parse("NOFF\n3 1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(m.normals.unwrap().values, [[0.0, 0.0, 1.0]; 3]);
        let m = parse("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 2 1 0\n").unwrap();
        assert_eq!(m.face(0), &[2, 1, 0]);
    }

    #[test]
    fn errors() {
        let e = parse("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.off:6: face 0: vertex index 3 is out of range; the file has 3 vertices"
        );
        let e = parse("OFF\n3 1 0\n0 0 0\n1 0 0\n").unwrap_err();
        assert_eq!(e.to_string(), "t.off:4: vertex 2: file ends");
        assert!(matches!(
            parse("4OFF\n1 0 0\n"),
            Err(MeshError::Unsupported(_))
        ));
    }
}
