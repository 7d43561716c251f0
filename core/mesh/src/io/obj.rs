//! Wavefront OBJ.
//!
//! Read: `v` (x y z; an optional w or vertex colour after them is ignored), `vt` (`u [v [w]]`),
//! `vn`, `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners, n-gons, negative (relative) indices,
//! `g` and `usemtl` as face groups, `\` line continuations, CRLF, `#` comments. Everything else
//! (`o`, `s`, `mtllib`, `l`, `p`, curves...) is ignored.
//!
//! Decisions:
//! - Texture coordinates (normals) are kept only when *every* face has them on every corner; a
//!   single face without them drops the whole attribute, since the model has no "missing"
//!   value.
//! - Groups: when the file has `usemtl`, groups are materials; otherwise `g` names; otherwise
//!   there are none. Faces before the first group statement go to a group named `default`.
//!   Equal names share one group.
//! - Positive indices may refer to vertices defined later in the file (they are range-checked
//!   at the end, still naming the line); negative ones are relative to the vertices so far.

use super::ReadOptions;
use super::source::{Source, element_limit, parse_f32, parse_i64, show, tokens};
use crate::{FaceVarying, Mesh, MeshError};
use std::collections::HashMap;
use std::io::{Read, Write};

/// Which index of a face corner.
#[derive(Clone, Copy)]
enum Slot {
    Vertex = 0,
    Uv = 1,
    Normal = 2,
}

impl Slot {
    fn noun(self) -> &'static str {
        match self {
            Slot::Vertex => "vertex",
            Slot::Uv => "texture coordinate",
            Slot::Normal => "normal",
        }
    }

    fn plural(self) -> &'static str {
        match self {
            Slot::Vertex => "vertices",
            Slot::Uv => "texture coordinates",
            Slot::Normal => "normals",
        }
    }
}

/// A run of faces sharing the same `usemtl` and `g` (indices into the name tables).
struct Run {
    first_face: usize,
    material: Option<u32>,
    group: Option<u32>,
}

/// Interned names in order of first use.
#[derive(Default)]
struct Names {
    list: Vec<String>,
    index: HashMap<String, u32>,
}

impl Names {
    fn intern(&mut self, name: &str) -> u32 {
        if let Some(&i) = self.index.get(name) {
            return i;
        }
        let i = self.list.len() as u32;
        self.list.push(name.to_string());
        self.index.insert(name.to_string(), i);
        i
    }
}

pub(crate) fn read<R: Read>(
    src: &mut Source<'_, R>,
    opts: &ReadOptions,
) -> Result<Mesh, MeshError> {
    let limit = element_limit(opts.max_elements);
    let mut mesh = Mesh::default();
    let mut uv_values: Vec<[f32; 2]> = Vec::new();
    let mut normal_values: Vec<[f32; 3]> = Vec::new();
    let (mut uv_idx, mut normal_idx) = (Vec::<u32>::new(), Vec::<u32>::new());
    let (mut all_uv, mut all_normal) = (true, true);
    // Largest positive index seen per slot, with its line, for the end-of-file range check.
    let mut max_ref = [(0u64, 0u64); 3];
    let (mut materials, mut groups) = (Names::default(), Names::default());
    let (mut material, mut group): (Option<u32>, Option<u32>) = (None, None);
    let mut runs: Vec<Run> = Vec::new();
    let mut corner = [Vec::<u32>::new(), Vec::new(), Vec::new()];
    let mut line = Vec::new();
    let mut more = Vec::new();

    while src.read_line(&mut line)? {
        let lineno = src.line();
        // `\` at the end joins the next line.
        while line.trim_ascii_end().ends_with(b"\\") {
            let keep = line.trim_ascii_end().len() - 1;
            line.truncate(keep);
            line.push(b' ');
            if !src.read_line(&mut more)? {
                break;
            }
            line.extend_from_slice(&more);
            if line.len() > super::source::MAX_LINE {
                return Err(src.error("line too long"));
            }
        }
        // A token starting with `#` ends the line's content.
        let mut toks = tokens(&line).take_while(|t| t[0] != b'#');
        let Some(keyword) = toks.next() else { continue };
        let err = |msg: String| src.error_at(lineno, msg);
        match keyword {
            b"v" | b"vn" => {
                let what = if keyword == b"v" { "v" } else { "vn" };
                let mut p = [0f32; 3];
                for (k, c) in p.iter_mut().enumerate() {
                    let Some(t) = toks.next() else {
                        return Err(err(format!("'{what}' needs 3 coordinates, got {k}")));
                    };
                    *c = parse_f32(t)
                        .ok_or_else(|| err(format!("bad coordinate '{}' in '{what}'", show(t))))?;
                }
                let store = if keyword == b"v" {
                    &mut mesh.positions
                } else {
                    &mut normal_values
                };
                if store.len() as u64 >= limit {
                    return Err(too_large(src.name(), what, limit));
                }
                store.push(p);
            }
            b"vt" => {
                let mut t = [0f32; 2];
                for (k, c) in t.iter_mut().enumerate() {
                    match toks.next() {
                        Some(tok) => {
                            *c = parse_f32(tok).ok_or_else(|| {
                                err(format!("bad coordinate '{}' in 'vt'", show(tok)))
                            })?
                        }
                        None if k == 0 => return Err(err("'vt' needs a u coordinate".into())),
                        None => {}
                    }
                }
                if uv_values.len() as u64 >= limit {
                    return Err(too_large(src.name(), "vt", limit));
                }
                uv_values.push(t);
            }
            b"f" => {
                for c in &mut corner {
                    c.clear();
                }
                let counts = [
                    mesh.positions.len() as u64,
                    uv_values.len() as u64,
                    normal_values.len() as u64,
                ];
                for tok in toks {
                    let mut parts = tok.split(|&b| b == b'/');
                    for slot in [Slot::Vertex, Slot::Uv, Slot::Normal] {
                        match parts.next() {
                            Some(p) if !p.is_empty() => {
                                let i =
                                    resolve(p, slot, counts[slot as usize], lineno, &mut max_ref)
                                        .map_err(&err)?;
                                corner[slot as usize].push(i);
                            }
                            Some(_) if matches!(slot, Slot::Vertex) => {
                                return Err(err(format!("bad face corner '{}'", show(tok))));
                            }
                            _ => {}
                        }
                    }
                    if parts.next().is_some() {
                        return Err(err(format!("bad face corner '{}'", show(tok))));
                    }
                }
                let n = corner[0].len();
                if n < 3 {
                    return Err(err(format!(
                        "face has {n} vertices; a face needs at least 3"
                    )));
                }
                let faces = mesh.face_count();
                if faces as u64 >= limit || (mesh.face_indices.len() + n) as u64 > limit {
                    return Err(too_large(src.name(), "f", limit));
                }
                if runs
                    .last()
                    .is_none_or(|r| r.material != material || r.group != group)
                {
                    runs.push(Run {
                        first_face: faces,
                        material,
                        group,
                    });
                }
                mesh.push_face(&corner[0]);
                keep_attribute(&mut all_uv, &mut uv_idx, &corner[1], n);
                keep_attribute(&mut all_normal, &mut normal_idx, &corner[2], n);
            }
            b"g" | b"usemtl" => {
                let text = memchr::memchr(b'#', &line).map_or(&line[..], |h| &line[..h]);
                let name = rest_of_line(text, keyword.len());
                if keyword == b"g" {
                    group = Some(groups.intern(&name));
                } else {
                    material = Some(materials.intern(&name));
                }
            }
            _ => {}
        }
    }

    let counts = [mesh.positions.len(), uv_values.len(), normal_values.len()];
    for slot in [Slot::Vertex, Slot::Uv, Slot::Normal] {
        let (max, line) = max_ref[slot as usize];
        if max > counts[slot as usize] as u64 {
            return Err(src.error_at(
                line,
                format!(
                    "{} index {max} is out of range; the file has {} {}",
                    slot.noun(),
                    counts[slot as usize],
                    slot.plural()
                ),
            ));
        }
    }
    let has_faces = mesh.face_count() > 0;
    if all_uv && has_faces {
        mesh.uvs = Some(FaceVarying {
            values: uv_values,
            indices: uv_idx,
        });
    }
    if all_normal && has_faces {
        mesh.normals = Some(FaceVarying {
            values: normal_values,
            indices: normal_idx,
        });
    }
    assign_groups(&mut mesh, &runs, &materials, &groups);
    Ok(mesh)
}

fn too_large(name: &str, what: &str, limit: u64) -> MeshError {
    MeshError::TooLarge(format!(
        "{name}: '{what}' records exceed the limit of {limit}"
    ))
}

/// Parses one index of a face corner and turns it 0-based.
fn resolve(
    tok: &[u8],
    slot: Slot,
    count: u64,
    line: u64,
    max_ref: &mut [(u64, u64); 3],
) -> Result<u32, String> {
    let noun = slot.noun();
    let i = parse_i64(tok).ok_or_else(|| format!("bad {noun} index '{}' in 'f'", show(tok)))?;
    let resolved = match i {
        0 => return Err(format!("{noun} index 0 is invalid; OBJ indices start at 1")),
        i if i > 0 => {
            let i = i as u64;
            if i > u64::from(u32::MAX) {
                return Err(format!("{noun} index {i} is out of range"));
            }
            let m = &mut max_ref[slot as usize];
            if i > m.0 {
                *m = (i, line);
            }
            i - 1
        }
        i => {
            let back = i.unsigned_abs();
            if back > count {
                return Err(format!(
                    "{noun} index {i} is out of range; {count} {} are defined before it",
                    slot.plural()
                ));
            }
            count - back
        }
    };
    Ok(resolved as u32)
}

/// Keeps a face-varying attribute only while every face has it on every corner.
fn keep_attribute(all: &mut bool, indices: &mut Vec<u32>, corner: &[u32], n: usize) {
    if !*all {
        return;
    }
    if corner.len() == n {
        indices.extend_from_slice(corner);
    } else {
        *all = false;
        *indices = Vec::new();
    }
}

/// The text after a keyword, trimmed; `default` when empty.
fn rest_of_line(line: &[u8], keyword_len: usize) -> String {
    let start = line
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(0)
        + keyword_len;
    let name = String::from_utf8_lossy(line.get(start..).unwrap_or_default().trim_ascii());
    if name.is_empty() {
        "default".to_string()
    } else {
        name.into_owned()
    }
}

/// Turns the recorded runs into `face_groups`: by material when the file had any `usemtl`, else
/// by `g`; no groups when no face was in one.
fn assign_groups(mesh: &mut Mesh, runs: &[Run], materials: &Names, groups: &Names) {
    let by_material = !materials.list.is_empty();
    let key = |r: &Run| if by_material { r.material } else { r.group };
    let table = if by_material { materials } else { groups };
    if !runs.iter().any(|r| key(r).is_some()) {
        return;
    }
    let mut names = Names::default();
    let faces = mesh.face_count();
    let mut face_groups = Vec::with_capacity(faces);
    for (k, run) in runs.iter().enumerate() {
        let end = runs.get(k + 1).map_or(faces, |r| r.first_face);
        let name = key(run).map_or("default", |i| table.list[i as usize].as_str());
        let id = names.intern(name);
        face_groups.resize(end, id);
    }
    mesh.face_groups = face_groups;
    mesh.group_names = names.list;
}

/// Appends a float that reads back to the same `f32`: plain decimals in the usual range,
/// exponent notation for very small or large magnitudes.
pub(crate) fn push_f32(out: &mut Vec<u8>, x: f32) {
    use std::io::Write as _;
    let a = x.abs();
    // Writing to a Vec cannot fail.
    let _ = if x == 0.0 || (1e-4..1e15).contains(&a) {
        write!(out, "{x}")
    } else {
        write!(out, "{x:e}")
    };
}

/// Appends a decimal integer (the bulk of OBJ and OFF face lines; faster than `write!`).
pub(crate) fn push_u32(out: &mut Vec<u8>, mut v: u32) {
    let mut digits = [0u8; 10];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[i..]);
}

/// Writes `prefix x y ...` lines, one per value.
pub(crate) fn write_values<const N: usize>(
    w: &mut impl Write,
    prefix: &[u8],
    values: &[[f32; N]],
) -> std::io::Result<()> {
    write_rows(w, prefix, values, push_f32)
}

/// Writes `v x y z` lines of f64 positions, each coordinate the shortest decimal that reads
/// back as the same f64 (shared with OFF, whose vertex lines have no prefix).
pub(crate) fn write_f64_values(
    w: &mut impl Write,
    prefix: &[u8],
    values: &[[f64; 3]],
) -> std::io::Result<()> {
    write_rows(w, prefix, values, |line, c| {
        use std::io::Write as _;
        // Writing to a Vec cannot fail.
        let _ = write!(line, "{c}");
    })
}

/// Writes one `prefix c0 c1 ...` line per row, each coordinate formatted by `push`.
fn write_rows<T: Copy, const N: usize>(
    w: &mut impl Write,
    prefix: &[u8],
    values: &[[T; N]],
    push: impl Fn(&mut Vec<u8>, T),
) -> std::io::Result<()> {
    let mut line = Vec::with_capacity(128);
    for v in values {
        line.clear();
        line.extend_from_slice(prefix);
        for (k, &c) in v.iter().enumerate() {
            if k > 0 || !prefix.is_empty() {
                line.push(b' ');
            }
            push(&mut line, c);
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    Ok(())
}

/// Writes `mesh` as OBJ; with `f64_positions`, those as its `v` lines.
pub(crate) fn write(
    mesh: &Mesh,
    w: &mut impl Write,
    f64_positions: Option<&[[f64; 3]]>,
) -> std::io::Result<()> {
    writeln!(w, "# written by tessd-mesh")?;
    writeln!(
        w,
        "# {} vertices, {} faces",
        mesh.vertex_count(),
        mesh.face_count()
    )?;
    match f64_positions {
        Some(p) => write_f64_values(w, b"v", p)?,
        None => write_values(w, b"v", &mesh.positions)?,
    }
    if let Some(uv) = &mesh.uvs {
        write_values(w, b"vt", &uv.values)?;
    }
    if let Some(n) = &mesh.normals {
        write_values(w, b"vn", &n.values)?;
    }
    let uv = mesh.uvs.as_ref().map(|a| a.indices.as_slice());
    let nr = mesh.normals.as_ref().map(|a| a.indices.as_slice());
    let mut current_group = None;
    let mut line = Vec::with_capacity(128);
    for (f, win) in mesh.face_offsets.windows(2).enumerate() {
        if let Some(&g) = mesh.face_groups.get(f)
            && current_group != Some(g)
        {
            current_group = Some(g);
            let name: String = mesh.group_names[g as usize]
                .chars()
                .map(|c| {
                    if matches!(c, '\n' | '\r' | '#') {
                        '_'
                    } else {
                        c
                    }
                })
                .collect();
            let name = if name.trim().is_empty() {
                "default"
            } else {
                name.as_str()
            };
            writeln!(w, "usemtl {name}")?;
        }
        line.clear();
        line.push(b'f');
        for c in win[0] as usize..win[1] as usize {
            line.push(b' ');
            push_u32(&mut line, mesh.face_indices[c] + 1);
            if uv.is_some() || nr.is_some() {
                line.push(b'/');
            }
            if let Some(t) = uv {
                push_u32(&mut line, t[c] + 1);
            }
            if let Some(n) = nr {
                line.push(b'/');
                push_u32(&mut line, n[c] + 1);
            }
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
            Format::Obj,
            "t.obj",
            &ReadOptions::default(),
        )
    }

    #[test]
    fn corner_forms_negative_indices_and_continuations() {
        let m = parse(
            "v 0 0 0 1\r\nv 1 0 0 0.5 0.5 0.5\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1\nvt 1 1 0\nvt 0 1\n\
             vn 0 0 1\nf -4/1/1 -3/2/1 \\\n -2/3/1 -1/4/1\n",
        )
        .unwrap();
        assert_eq!(m.face(0), &[0, 1, 2, 3]);
        let uv = m.uvs.unwrap();
        assert_eq!(uv.values[1], [1.0, 0.0]);
        assert_eq!(uv.indices, [0, 1, 2, 3]);
        assert_eq!(m.normals.unwrap().indices, [0, 0, 0, 0]);
    }

    #[test]
    fn partial_attributes_are_dropped() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 3 2 1\n").unwrap();
        assert!(m.uvs.is_none() && m.normals.is_none());
    }

    #[test]
    fn groups_prefer_usemtl_and_default_comes_first() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng a\nusemtl red\nf 1 2 3\ng b\nf 1 2 3\n\
                    usemtl blue\nf 1 2 3\nusemtl red\nf 1 2 3\n";
        let m = parse(text).unwrap();
        assert_eq!(m.group_names, ["default", "red", "blue"]);
        assert_eq!(m.face_groups, [0, 1, 1, 2, 1]);
        let m = parse(&text.replace("usemtl", "o")).unwrap();
        assert_eq!(m.group_names, ["default", "a", "b"]);
        assert_eq!(m.face_groups, [0, 1, 2, 2, 2]);
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert!(m.face_groups.is_empty() && m.group_names.is_empty());
    }

    #[test]
    fn forward_references_are_allowed() {
        let m = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(m.face(0), &[0, 1, 2]);
    }

    #[test]
    fn written_obj_reads_back_identically() {
        let mut text = String::from("v 0.1 -2.5e-7 3e20\nv 1 0 0\nv 1 1 0\nv 0 1 0\n");
        text += "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ng top\nf 1/1/1 2/2/1 3/3/1 4/2/1\n";
        let m = parse(&text).unwrap();
        let mut out = Vec::new();
        crate::io::write(&m, &mut out, Format::Obj).unwrap();
        let back = read(&out[..], Format::Obj, "b", &ReadOptions::default()).unwrap();
        assert_eq!(back, m);
    }
}
