//! STL, ASCII and binary.
//!
//! STL stores every triangle with its own three positions. The reader **welds exactly equal
//! positions** (compared by bit pattern, with −0.0 taken as +0.0) into one vertex, so that
//! topology statistics mean something; it never merges positions that merely lie close. The
//! facet normals of the file are ignored (they are recomputed on writing).
//!
//! Binary or ASCII: a file whose size is exactly 84 + 50·n (n = the count at byte 80) is binary,
//! even when its header starts with `solid` as many exporters write; otherwise a file starting
//! with `solid` whose first 84 bytes are text is ASCII; anything else is binary (and then its
//! size or count is wrong, which is reported). When the input length is unknown, a binary file
//! must end right after its last triangle.
//!
//! Write: binary, faces fan-triangulated, facet normals computed from the triangle.

use super::ReadOptions;
use super::source::{Source, element_limit, parse_f32, show, tokens};
use crate::{Mesh, MeshError};
use std::io::{Read, Write};

pub(crate) fn read<R: Read>(
    src: &mut Source<'_, R>,
    opts: &ReadOptions,
) -> Result<Mesh, MeshError> {
    let limit = element_limit(opts.max_elements);
    let len = src.len();
    let head = src.fill(84)?;
    let starts_solid = head.trim_ascii_start().starts_with(b"solid");
    let textual = head[..head.len().min(84)]
        .iter()
        .all(|&b| (b >= 0x20 && b != 0x7f) || matches!(b, b'\t' | b'\n' | b'\r'));
    let size_says_binary = match (len, head.get(80..84)) {
        (Some(len), Some(c)) => {
            let n = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            len == 84 + 50 * u64::from(n)
        }
        _ => false,
    };
    if size_says_binary || !(starts_solid && textual) {
        read_binary(src, limit)
    } else {
        read_ascii(src, limit)
    }
}

/// Assigns one vertex per distinct position.
///
/// An open-addressing table of 8-byte slots (`hash tag << 32 | vertex + 1`, 0 = empty) with
/// linear probing; keys are not stored but compared against `positions`, which keeps the table
/// at a third of a general hash map's size and most probes to one cache line. In front of it a
/// small direct-mapped cache catches the repeats: STL files list triangles in mesh order, so
/// most corners reuse a position seen a few thousand corners earlier.
struct Welder {
    slots: Vec<u64>,
    len: usize,
    cache: Vec<(Key, u32)>,
    limit: u64,
}

/// The bit pattern of a position, −0.0 taken as +0.0.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Key([u32; 3]);

impl Key {
    #[inline]
    fn of(p: [f32; 3]) -> Key {
        Key(p.map(|c| if c == 0.0 { 0 } else { c.to_bits() }))
    }

    /// A well-mixed 64-bit hash (folded multiplies, as in foldhash).
    #[inline]
    fn hash(&self) -> u64 {
        #[inline]
        fn mix(a: u64, b: u64) -> u64 {
            let m = u128::from(a ^ 0x243f_6a88_85a3_08d3) * u128::from(b ^ 0x1319_8a2e_0370_7344);
            (m >> 64) as u64 ^ m as u64
        }
        let [x, y, z] = self.0;
        mix(
            mix(u64::from(x) << 32 | u64::from(y), 0x9e37_79b9),
            u64::from(z),
        )
    }
}

impl Welder {
    const CACHE: usize = 1 << 14;

    fn new(capacity: usize, limit: u64) -> Welder {
        let slots = (capacity.max(8) * 8 / 7).next_power_of_two();
        Welder {
            slots: vec![0; slots],
            len: 0,
            cache: vec![(Key([0; 3]), u32::MAX); Self::CACHE],
            limit,
        }
    }

    /// The vertex at `p`, added to `positions` when new; `None` when the vertex limit is hit.
    #[inline]
    fn vertex(&mut self, p: [f32; 3], positions: &mut Vec<[f32; 3]>) -> Option<u32> {
        let key = Key::of(p);
        let h = key.hash();
        let c = (h >> 20) as usize & (Self::CACHE - 1);
        let (k, v) = self.cache[c];
        if k == key && v != u32::MAX {
            return Some(v);
        }
        let tag = h & !0xffff_ffff;
        let mask = self.slots.len() - 1;
        let mut i = h as usize & mask;
        let v = loop {
            let s = self.slots[i];
            if s == 0 {
                if positions.len() as u64 >= self.limit {
                    return None;
                }
                let v = positions.len() as u32;
                positions.push(p);
                self.slots[i] = tag | u64::from(v + 1);
                self.len += 1;
                if self.len * 8 > self.slots.len() * 7 {
                    self.grow(positions);
                }
                break v;
            }
            if s & !0xffff_ffff == tag {
                let v = (s as u32) - 1;
                if Key::of(positions[v as usize]) == key {
                    break v;
                }
            }
            i = (i + 1) & mask;
        };
        self.cache[c] = (key, v);
        Some(v)
    }

    /// Doubles the table, re-filing every vertex.
    #[cold]
    fn grow(&mut self, positions: &[[f32; 3]]) {
        let mut slots = vec![0u64; self.slots.len() * 2];
        let mask = slots.len() - 1;
        for (v, p) in positions.iter().enumerate() {
            let h = Key::of(*p).hash();
            let mut i = h as usize & mask;
            while slots[i] != 0 {
                i = (i + 1) & mask;
            }
            slots[i] = (h & !0xffff_ffff) | (v as u64 + 1);
        }
        self.slots = slots;
    }
}

fn read_binary<R: Read>(src: &mut Source<'_, R>, limit: u64) -> Result<Mesh, MeshError> {
    let name = src.name();
    let head = src.fill(84)?;
    let Some(&[a, b, c, d]) = head.get(80..84) else {
        let got = head.len();
        return Err(src.error_at(
            0,
            format!("not an STL file: {got} bytes, shorter than a binary STL header"),
        ));
    };
    let n = u64::from(u32::from_le_bytes([a, b, c, d]));
    src.consume(84);
    if let Some(len) = src.len() {
        let expected = 84 + 50 * n;
        if len != expected {
            return Err(src.error_at(
                0,
                format!(
                    "binary STL header declares {n} triangles ({expected} bytes) but the file has \
                     {len} bytes"
                ),
            ));
        }
    }
    if n > limit || 3 * n > limit {
        return Err(MeshError::TooLarge(format!(
            "{}: binary STL declares {n} triangles; the limit is {}",
            src.name(),
            limit / 3
        )));
    }
    let faces = src.reserve_hint(n, 50);
    let mut mesh = Mesh::default();
    mesh.face_offsets.reserve_exact(faces);
    mesh.face_indices.reserve_exact(3 * faces);
    // A closed triangle mesh has about half as many vertices as triangles; open ones a little
    // more. Reserving 5/8 avoids a rehash of the map in the usual cases.
    let vertices = faces / 2 + faces / 8 + 3;
    mesh.positions.reserve(vertices);
    let mut welder = Welder::new(vertices, limit);
    for i in 0..n {
        let b = src.fill(50)?;
        if b.len() < 50 {
            return Err(src.error_at(0, format!("triangle {i}: file ends")));
        }
        let mut corners = [[0f32; 3]; 3];
        for (c, bytes) in corners.iter_mut().flatten().zip(b[12..48].chunks_exact(4)) {
            *c = f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        }
        src.consume(50);
        for p in corners {
            let v = welder
                .vertex(p, &mut mesh.positions)
                .ok_or_else(|| too_many(name, limit))?;
            mesh.face_indices.push(v);
        }
        mesh.face_offsets.push(mesh.face_indices.len() as u32);
    }
    if src.len().is_none() && !src.fill(1)?.is_empty() {
        return Err(src.error_at(0, format!("binary STL has data after its {n} triangles")));
    }
    Ok(mesh)
}

fn too_many(name: &str, limit: u64) -> MeshError {
    MeshError::TooLarge(format!(
        "{name}: STL has more than {limit} distinct vertices"
    ))
}

fn read_ascii<R: Read>(src: &mut Source<'_, R>, limit: u64) -> Result<Mesh, MeshError> {
    let mut mesh = Mesh::default();
    let mut welder = Welder::new(1024, limit);
    let mut line = Vec::new();
    let mut facet: Option<Vec<u32>> = None;
    let mut seen_solid = false;
    while src.read_line(&mut line)? {
        let mut t = tokens(&line);
        let Some(keyword) = t.next() else { continue };
        if !seen_solid {
            if keyword != b"solid" {
                return Err(src.error("not an ASCII STL: expected 'solid'"));
            }
            seen_solid = true;
            continue;
        }
        match keyword {
            b"facet" => {
                if facet.is_some() {
                    return Err(src.error("'facet' inside a facet (missing 'endfacet')"));
                }
                facet = Some(Vec::with_capacity(3));
            }
            b"vertex" => {
                let Some(corners) = facet.as_mut() else {
                    return Err(src.error("'vertex' outside a facet"));
                };
                let mut p = [0f32; 3];
                for (k, c) in p.iter_mut().enumerate() {
                    let tok = t.next().ok_or_else(|| {
                        src.error(format!("'vertex' needs 3 coordinates, got {k}"))
                    })?;
                    *c = parse_f32(tok).ok_or_else(|| {
                        src.error(format!("bad coordinate '{}' in 'vertex'", show(tok)))
                    })?;
                }
                let v = welder
                    .vertex(p, &mut mesh.positions)
                    .ok_or_else(|| too_many(src.name(), limit))?;
                corners.push(v);
            }
            b"endfacet" => {
                let Some(corners) = facet.take() else {
                    return Err(src.error("'endfacet' without 'facet'"));
                };
                if corners.len() < 3 {
                    return Err(src.error(format!(
                        "facet has {} vertices; a facet needs at least 3",
                        corners.len()
                    )));
                }
                if mesh.face_count() as u64 >= limit
                    || (mesh.face_indices.len() + corners.len()) as u64 > limit
                {
                    return Err(MeshError::TooLarge(format!(
                        "{}: STL facets exceed the limit of {limit}",
                        src.name()
                    )));
                }
                mesh.push_face(&corners);
            }
            b"outer" | b"endloop" | b"endsolid" | b"solid" => {}
            other => {
                return Err(src.error(format!("unexpected '{}' in an ASCII STL", show(other))));
            }
        }
    }
    if facet.is_some() {
        return Err(src.error("file ends inside a facet"));
    }
    Ok(mesh)
}

/// Writes a binary STL of the fan triangulation.
pub(crate) fn write(mesh: &Mesh, w: &mut impl Write, name: &str) -> Result<(), MeshError> {
    let triangles = mesh.triangle_count();
    let count = u32::try_from(triangles).map_err(|_| {
        MeshError::TooLarge(format!(
            "{name}: {triangles} triangles do not fit a binary STL (at most {})",
            u32::MAX
        ))
    })?;
    let io_err = |source| MeshError::Io {
        path: name.to_string(),
        source,
    };
    // Must not start with "solid", or other readers may take the file for ASCII.
    let mut header = [b' '; 80];
    let text = b"binary STL written by tessd-mesh";
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header).map_err(io_err)?;
    w.write_all(&count.to_le_bytes()).map_err(io_err)?;
    let mut record = [0u8; 50];
    for face in mesh.faces() {
        for k in 1..face.len() - 1 {
            let p = [face[0], face[k], face[k + 1]].map(|v| mesh.positions[v as usize]);
            let n = facet_normal(&p);
            for (slot, v) in std::iter::once(&n).chain(&p).enumerate() {
                for (c, x) in v.iter().enumerate() {
                    let o = slot * 12 + c * 4;
                    record[o..o + 4].copy_from_slice(&x.to_le_bytes());
                }
            }
            w.write_all(&record).map_err(io_err)?;
        }
    }
    Ok(())
}

/// The unit normal of a triangle, or zero for a degenerate one.
fn facet_normal(p: &[[f32; 3]; 3]) -> [f32; 3] {
    let d = |a: [f32; 3], b: [f32; 3]| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let (u, v) = (d(p[0], p[1]), d(p[0], p[2]));
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        n.map(|c| c / len)
    } else {
        [0.0; 3]
    }
}

#[cfg(test)]
mod tests {
    use crate::io::{Format, ReadOptions, read};
    use crate::{Mesh, MeshError};

    fn parse(bytes: &[u8], known_len: bool) -> Result<Mesh, MeshError> {
        let o = ReadOptions {
            input_len: known_len.then_some(bytes.len() as u64),
            ..ReadOptions::default()
        };
        read(bytes, Format::Stl, "t.stl", &o)
    }

    #[test]
    fn welder_grows_and_keeps_indices() {
        let mut w = super::Welder::new(8, u64::from(u32::MAX));
        let mut positions = Vec::new();
        let p = |i: u32| [i as f32, (i % 7) as f32, -(i as f32) * 0.5];
        for round in 0..3 {
            for i in 0..20_000u32 {
                assert_eq!(w.vertex(p(i), &mut positions), Some(i), "round {round}");
            }
        }
        assert_eq!(positions.len(), 20_000);
        assert_eq!(w.vertex([-0.0, 0.0, 0.0], &mut positions), Some(0));
        let mut w = super::Welder::new(8, 2);
        let mut positions = Vec::new();
        assert_eq!(w.vertex(p(1), &mut positions), Some(0));
        assert_eq!(w.vertex(p(2), &mut positions), Some(1));
        assert_eq!(w.vertex(p(3), &mut positions), None);
    }

    #[test]
    fn ascii_welds_equal_positions() {
        let text = "solid cube\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n\
                    vertex 1 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n outer loop\n\
                    vertex -0 0 0\n vertex 1 1 0\n vertex 0 1 0\n endloop\n endfacet\nendsolid cube\n";
        for known in [true, false] {
            let m = parse(text.as_bytes(), known).unwrap();
            assert_eq!((m.vertex_count(), m.face_count()), (4, 2));
            assert_eq!(m.face(1), &[0, 2, 3]);
        }
    }

    #[test]
    fn binary_with_solid_header_is_detected_by_size() {
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2, 3]);
        let mut out = Vec::new();
        crate::io::write(&m, &mut out, Format::Stl).unwrap();
        assert_eq!(out.len(), 84 + 100);
        out[..80].copy_from_slice(&[b's'; 80]);
        out[..6].copy_from_slice(b"solid ");
        for known in [true, false] {
            let back = parse(&out, known).unwrap();
            assert_eq!(back.positions, m.positions);
            assert_eq!(back.face_indices, [0, 1, 2, 0, 2, 3]);
        }
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let e = parse(b"solid x\nfacet normal 0 0 1\nvertex 0 0 q\n", true).unwrap_err();
        assert_eq!(e.to_string(), "t.stl:3: bad coordinate 'q' in 'vertex'");
        let e = parse(
            b"solid x\nfacet\nvertex 0 0 0\nvertex 1 0 0\nendfacet\n",
            true,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.stl:5: facet has 2 vertices; a facet needs at least 3"
        );
    }
}
