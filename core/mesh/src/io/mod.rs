//! Readers and writers for OBJ, PLY, STL and OFF.
//!
//! Every reader streams its input through one 64 KiB buffer straight into the final vectors of
//! the [`Mesh`] (no intermediate copy of the file or of the faces), never allocates more than
//! the input can hold whatever its header claims, names the line (text) or element (binary) of
//! any error, and calls [`Mesh::validate`] before returning, so every mesh read is valid.
//!
//! What each format carries:
//!
//! | format | read | written |
//! |---|---|---|
//! | OBJ | positions, n-gons, `vt`/`vn` (face-varying), groups (`usemtl`, else `g`) | all of these |
//! | PLY | positions, n-gons, per-vertex `nx ny nz` and `s t`/`u v` | binary LE; normals and UVs as `nx ny nz` / `s t` (a vertex whose corners differ is split, one vertex per value) |
//! | STL | triangles (ASCII or binary), equal positions welded | binary, fan-triangulated |
//! | OFF | positions, n-gons (`OFF`, `COFF`, `NOFF`, `STOFF` headers) | ASCII `OFF` |
//!
//! [`stream`] reads PLY and OBJ files in passes without holding them (positions and
//! fan-triangulated faces only), for consumers that must stay out of core.
//!
//! Creases, sharp edges and generic attributes are carried by none of these formats
//! ([`dropped_by_format`] lists what a write leaves out). Writing goes through [`write_atomic`], so a
//! failed write never leaves a partial file behind.

mod atomic;
mod obj;
mod off;
mod ply;
mod ply_write;
mod source;
mod stl;
pub mod stream;

pub use atomic::{TempOutput, write_atomic};

use crate::{Mesh, MeshError};
use source::Source;
use std::io::{BufRead, BufWriter, Read, Write};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// The end of [`Format::from_path`]'s message for an extension it does not know: the formats
/// this crate reads and writes (a caller that also handles other formats, such as tessd's USD
/// stages, may extend it).
pub const EXPECTED_EXTENSIONS: &str = "expected .obj, .ply, .stl or .off";

/// Mesh file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// STL.
    Stl,
    /// OFF.
    Off,
}

impl Format {
    /// The format for a path's extension (case-insensitive).
    ///
    /// # Errors
    /// [`MeshError::Unsupported`] naming the extension when it is not `obj`, `ply`, `stl` or
    /// `off`, or saying the path has none.
    pub fn from_path(path: &Path) -> Result<Format, MeshError> {
        let Some(ext) = path.extension() else {
            return Err(MeshError::Unsupported(format!(
                "{}: no file extension; {EXPECTED_EXTENSIONS}",
                path.display()
            )));
        };
        let ext = ext.to_string_lossy();
        match ext.to_ascii_lowercase().as_str() {
            "obj" => Ok(Format::Obj),
            "ply" => Ok(Format::Ply),
            "stl" => Ok(Format::Stl),
            "off" => Ok(Format::Off),
            _ => Err(MeshError::Unsupported(format!(
                "unsupported mesh file extension '.{ext}'; {EXPECTED_EXTENSIONS}"
            ))),
        }
    }

    /// The usual lower-case file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Ply => "ply",
            Format::Stl => "stl",
            Format::Off => "off",
        }
    }
}

/// Limits and context for reading untrusted files.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct ReadOptions {
    /// Largest number of vertices, faces or corners accepted (anything above is
    /// [`MeshError::TooLarge`]); the `u32` indices of [`Mesh`] cap it at `u32::MAX` anyway.
    pub max_elements: u64,
    /// Total size of the input in bytes, when known. Binary readers use it to bound what a
    /// header may make them reserve, and the STL reader to tell binary from ASCII files by
    /// size. [`read_path`] sets it from the file's metadata; set it when reading from memory.
    pub input_len: Option<u64>,
    /// When set to `true` (by another thread), reading stops at the next 64 KiB refill with
    /// [`MeshError::Cancelled`]: the daemon's cancellation checkpoint.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            max_elements: 1 << 31,
            input_len: None,
            cancel: None,
        }
    }
}

// Builders, since `#[non_exhaustive]` rules out struct literals in other crates.
impl ReadOptions {
    /// Sets [`ReadOptions::max_elements`].
    pub fn with_max_elements(mut self, max_elements: u64) -> Self {
        self.max_elements = max_elements;
        self
    }

    /// Sets [`ReadOptions::input_len`] (e.g. to a byte slice's length).
    pub fn with_input_len(mut self, input_len: u64) -> Self {
        self.input_len = Some(input_len);
        self
    }

    /// Sets [`ReadOptions::cancel`].
    pub fn with_cancel(mut self, cancel: Arc<AtomicBool>) -> Self {
        self.cancel = Some(cancel);
        self
    }
}

/// Reads a mesh file, format from the extension.
///
/// # Errors
/// [`MeshError::Unsupported`] for an unknown extension, [`MeshError::Io`] when the file cannot
/// be read, and whatever [`read`] reports.
pub fn read_path(path: &Path, options: &ReadOptions) -> Result<Mesh, MeshError> {
    let format = Format::from_path(path)?;
    let name = path.display().to_string();
    let io_err = |source| MeshError::Io {
        path: name.clone(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_err)?;
    let meta = file.metadata().map_err(io_err)?;
    let len = if meta.is_file() {
        Some(meta.len())
    } else {
        options.input_len
    };
    read_source(
        Source::new(file, &name, len, options.cancel.as_deref()),
        format,
        options,
    )
}

/// Reads a mesh in `format` from any buffered reader (a file, a socket, `&[u8]` in memory).
///
/// `name_for_errors` names the input in error messages (`"<memory>"`, a request id...). Set
/// [`ReadOptions::input_len`] when the size is known, as for a byte slice.
///
/// # Errors
/// [`MeshError::Parse`] naming the line or element for malformed input, [`MeshError::TooLarge`]
/// when a count exceeds [`ReadOptions::max_elements`], [`MeshError::Unsupported`] for variants
/// of a format that are not read, [`MeshError::Invalid`] when the data parses but breaks an
/// invariant (e.g. a NaN coordinate), [`MeshError::Io`], [`MeshError::Cancelled`].
pub fn read(
    reader: impl BufRead,
    format: Format,
    name_for_errors: &str,
    options: &ReadOptions,
) -> Result<Mesh, MeshError> {
    let src = Source::new(
        reader,
        name_for_errors,
        options.input_len,
        options.cancel.as_deref(),
    );
    read_source(src, format, options)
}

fn read_source<R: Read>(
    mut src: Source<'_, R>,
    format: Format,
    options: &ReadOptions,
) -> Result<Mesh, MeshError> {
    let mesh = match format {
        Format::Obj => obj::read(&mut src, options)?,
        Format::Ply => {
            // The PLY reader range-checks every face as it decodes it.
            let mesh = ply::read(&mut src, options)?;
            mesh.validate_read()?;
            return Ok(mesh);
        }
        Format::Stl => stl::read(&mut src, options)?,
        Format::Off => off::read(&mut src, options)?,
    };
    mesh.validate()?;
    Ok(mesh)
}

/// Writes a mesh file atomically (see [`write_atomic`]), format from the extension.
///
/// # Errors
/// [`MeshError::Unsupported`] for an unknown extension, [`MeshError::Invalid`] when the mesh
/// is not valid, [`MeshError::TooLarge`] when it does not fit the format (STL's `u32` triangle
/// count), [`MeshError::Io`].
pub fn write_path(mesh: &Mesh, path: &Path) -> Result<(), MeshError> {
    let format = Format::from_path(path)?;
    let name = path.display().to_string();
    mesh.validate()?;
    write_atomic(path, |w| write_named(mesh, w, format, &name, None))
}

/// Writes a mesh in `format` to any writer (buffered internally and flushed at the end).
///
/// # Errors
/// As [`write_path`], with I/O errors reported against the name `<output>`.
pub fn write(mesh: &Mesh, w: impl Write, format: Format) -> Result<(), MeshError> {
    mesh.validate()?;
    write_named(mesh, w, format, "<output>", None)
}

/// Writes a mesh file atomically with `positions` (f64, one per vertex of `mesh`) in place of
/// the mesh's f32 ones, for coordinates f32 cannot hold (a part 2·10⁴ mm from its origin has
/// an f32 spacing of 0.002 mm): OBJ and OFF print them in full (the shortest decimal that
/// reads back as the same f64), PLY stores `double` properties; binary STL has f32 only, so
/// they are rounded there.
///
/// # Errors
/// As [`write_path`]; [`MeshError::Invalid`] when `positions` has another count than the
/// mesh's vertices or a non-finite coordinate.
pub fn write_path_f64(mesh: &Mesh, positions: &[[f64; 3]], path: &Path) -> Result<(), MeshError> {
    let format = Format::from_path(path)?;
    let name = path.display().to_string();
    mesh.validate()?;
    check_f64_positions(mesh, positions)?;
    if format == Format::Stl {
        let mut rounded = mesh.clone();
        rounded.positions = positions.iter().map(|p| p.map(|c| c as f32)).collect();
        return write_atomic(path, |w| write_named(&rounded, w, format, &name, None));
    }
    write_atomic(path, |w| {
        write_named(mesh, w, format, &name, Some(positions))
    })
}

fn check_f64_positions(mesh: &Mesh, positions: &[[f64; 3]]) -> Result<(), MeshError> {
    if positions.len() != mesh.positions.len() {
        return Err(MeshError::Invalid(format!(
            "{} f64 positions for a mesh of {} vertices",
            positions.len(),
            mesh.positions.len()
        )));
    }
    if let Some(i) = positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(MeshError::Invalid(format!(
            "f64 position {i} is not finite: {:?}",
            positions[i]
        )));
    }
    Ok(())
}

fn write_named(
    mesh: &Mesh,
    w: impl Write,
    format: Format,
    name: &str,
    f64_positions: Option<&[[f64; 3]]>,
) -> Result<(), MeshError> {
    let io_err = |source| MeshError::Io {
        path: name.to_string(),
        source,
    };
    let mut w = BufWriter::with_capacity(source::BUF_SIZE, w);
    match format {
        Format::Obj => obj::write(mesh, &mut w, f64_positions).map_err(io_err)?,
        Format::Ply => ply_write::write(mesh, &mut w, f64_positions).map_err(io_err)?,
        Format::Stl => stl::write(mesh, &mut w, name)?,
        Format::Off => off::write(mesh, &mut w, f64_positions).map_err(io_err)?,
    }
    w.flush().map_err(io_err)
}

/// What writing `mesh` as `format` leaves out, by protocol name (see
/// [`Mesh::carried_names`]): no format here holds creases, sharp edges or generic attributes;
/// OBJ keeps normals, UVs and face groups; PLY keeps normals and UVs (per vertex: a vertex
/// with several is split, see [`written_counts`]); STL and OFF keep positions and faces alone.
pub fn dropped_by_format(mesh: &Mesh, format: Format) -> Vec<String> {
    let kept = |name: &str| format_carries(format, name);
    mesh.carried_names()
        .into_iter()
        .filter(|n| !kept(n))
        .collect()
}

/// Whether a file of `format` holds what the protocol calls `name` (`normals`, `uvs`,
/// `crease_edges`, `face_groups`, `sharp_edges`, a generic attribute's label): OBJ holds
/// normals, UVs and face groups, PLY normals and UVs, STL and OFF none of them.
pub fn format_carries(format: Format, name: &str) -> bool {
    matches!(
        (format, name),
        (Format::Obj, "normals" | "uvs" | "face_groups") | (Format::Ply, "normals" | "uvs")
    )
}

/// What a file of `format` written from a mesh holds, as a reader counts it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct WrittenCounts {
    /// Vertices in the file (PLY: after the seam split; STL: the mesh's, which a reader
    /// welds back from the triangles' corners).
    pub vertices: usize,
    /// Faces in the file: the mesh's polygons, or for STL the triangles of their fan
    /// triangulation.
    pub faces: usize,
    /// Whether the faces are the fan triangulation's triangles (STL).
    pub triangulated: bool,
    /// Vertices PLY added by splitting a vertex whose corners carry several UVs or normals
    /// (one vertex per distinct pair, as exporters do); 0 for the other formats.
    pub split_vertices: usize,
}

/// The counts a file of `format` holds when [`write_path`] writes `mesh` there.
pub fn written_counts(mesh: &Mesh, format: Format) -> WrittenCounts {
    let split_vertices = match format {
        Format::Ply => split_at_seams(mesh).map_or(0, |s| s.source.len()),
        _ => 0,
    };
    let triangulated = format == Format::Stl;
    WrittenCounts {
        vertices: mesh.vertex_count() + split_vertices,
        faces: if triangulated {
            mesh.triangle_count()
        } else {
            mesh.face_count()
        },
        triangulated,
        split_vertices,
    }
}

/// A mesh's vertices split so that its normals and UVs are per vertex, as PLY stores them.
pub(crate) struct SeamSplit {
    /// For each added vertex (numbered after the mesh's own), the vertex it copies.
    pub source: Vec<u32>,
    /// The faces' corners on the split vertices.
    pub face_indices: Vec<u32>,
    /// One normal per split vertex (mesh vertices first), when the mesh has normals.
    pub normals: Option<Vec<[f32; 3]>>,
    /// One UV per split vertex, when the mesh has UVs.
    pub uvs: Option<Vec<[f32; 2]>>,
}

/// Splits every vertex whose corners carry different UVs or normals into one vertex per
/// distinct (UV, normal) pair: the first pair a vertex meets keeps its index, the others get
/// new vertices after the mesh's. `None` when nothing needs splitting (no face-varying values,
/// or one value per vertex already).
pub(crate) fn split_at_seams(mesh: &Mesh) -> Option<SeamSplit> {
    if mesh.normals.is_none() && mesh.uvs.is_none() {
        return None;
    }
    let uv_ok = mesh
        .uvs
        .as_ref()
        .is_none_or(|t| per_vertex(mesh, t).is_some());
    let n_ok = mesh
        .normals
        .as_ref()
        .is_none_or(|n| per_vertex(mesh, n).is_some());
    if uv_ok && n_ok {
        return None;
    }
    // The key of a corner: its UV and normal bits (-0.0 read as 0.0, as `==` does).
    let bits = |x: f32| (x + 0.0).to_bits();
    let key = |c: usize| -> [u32; 5] {
        let mut k = [0u32; 5];
        if let Some(t) = &mesh.uvs {
            let v = t.values[t.indices[c] as usize];
            k[0] = bits(v[0]);
            k[1] = bits(v[1]);
        }
        if let Some(n) = &mesh.normals {
            let v = n.values[n.indices[c] as usize];
            k[2] = bits(v[0]);
            k[3] = bits(v[1]);
            k[4] = bits(v[2]);
        }
        k
    };
    let n = mesh.positions.len();
    let mut first: Vec<Option<[u32; 5]>> = vec![None; n];
    let mut extra: std::collections::HashMap<(u32, [u32; 5]), u32> = Default::default();
    let mut source: Vec<u32> = Vec::new();
    let mut corner_of: Vec<usize> = vec![usize::MAX; n];
    let mut extra_corner: Vec<usize> = Vec::new();
    let mut face_indices = Vec::with_capacity(mesh.face_indices.len());
    for (c, &v) in mesh.face_indices.iter().enumerate() {
        let k = key(c);
        let slot = &mut first[v as usize];
        let out = match slot {
            None => {
                *slot = Some(k);
                corner_of[v as usize] = c;
                v
            }
            Some(f) if *f == k => v,
            Some(_) => *extra.entry((v, k)).or_insert_with(|| {
                source.push(v);
                extra_corner.push(c);
                (n + source.len() - 1) as u32
            }),
        };
        face_indices.push(out);
    }
    // Each split vertex's values from one of its corners (unused vertices get zeros).
    let corners: Vec<usize> = corner_of.into_iter().chain(extra_corner).collect();
    let gather = |f: &dyn Fn(usize) -> [f32; 3]| -> Vec<[f32; 3]> {
        corners
            .iter()
            .map(|&c| if c == usize::MAX { [0.0; 3] } else { f(c) })
            .collect()
    };
    let normals = mesh
        .normals
        .as_ref()
        .map(|a| gather(&|c| a.values[a.indices[c] as usize]));
    let uvs = mesh.uvs.as_ref().map(|a| {
        gather(&|c| {
            let t = a.values[a.indices[c] as usize];
            [t[0], t[1], 0.0]
        })
        .into_iter()
        .map(|t| [t[0], t[1]])
        .collect()
    });
    Some(SeamSplit {
        source,
        face_indices,
        normals,
        uvs,
    })
}

/// Per-vertex values for a face-varying attribute, when every corner of a vertex uses the same
/// value (what PLY and OFF can store); vertices no face uses get `T::default()`.
fn per_vertex<T: Copy + Default + PartialEq>(
    mesh: &Mesh,
    attr: &crate::FaceVarying<T>,
) -> Option<Vec<T>> {
    let mut out = vec![T::default(); mesh.positions.len()];
    let mut seen = vec![false; mesh.positions.len()];
    for (&v, &a) in mesh.face_indices.iter().zip(&attr.indices) {
        let value = attr.values[a as usize];
        let (v, first) = (v as usize, !seen[v as usize]);
        if first {
            out[v] = value;
            seen[v] = true;
        } else if out[v] != value {
            return None;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_extension() {
        assert_eq!(
            Format::from_path(Path::new("a/B.PlY")).unwrap(),
            Format::Ply
        );
        assert_eq!(Format::from_path(Path::new("x.obj")).unwrap(), Format::Obj);
        let e = Format::from_path(Path::new("x.fbx")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "unsupported mesh file extension '.fbx'; expected .obj, .ply, .stl or .off"
        );
        assert!(matches!(
            Format::from_path(Path::new("noext")),
            Err(MeshError::Unsupported(_))
        ));
    }

    #[test]
    fn read_from_memory() {
        let m = read(
            &b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"[..],
            Format::Obj,
            "m",
            &Default::default(),
        )
        .unwrap();
        assert_eq!((m.vertex_count(), m.face_count()), (3, 1));
    }
}

#[cfg(test)]
mod f64_positions {
    use super::*;

    /// A triangle 2·10⁴ units out, whose f64 corners f32 cannot hold (spacing 0.002 there).
    fn far() -> (Mesh, Vec<[f64; 3]>) {
        let exact = vec![
            [20000.0001, 0.0, 0.0],
            [20001.0003, 0.0, 0.0],
            [20000.0001, 1.0000007, 0.0],
        ];
        let mesh = Mesh {
            positions: exact.iter().map(|p| p.map(|c| c as f32)).collect(),
            face_offsets: vec![0, 3],
            face_indices: vec![0, 1, 2],
            ..Mesh::default()
        };
        (mesh, exact)
    }

    /// Reads the f64 coordinates of a written file back: OBJ and OFF as text, PLY's doubles.
    fn read_back(path: &Path, format: Format) -> Vec<[f64; 3]> {
        let bytes = std::fs::read(path).unwrap();
        match format {
            Format::Obj | Format::Off => {
                let text = String::from_utf8(bytes).unwrap();
                let lines: Vec<&str> = match format {
                    Format::Obj => text.lines().filter_map(|l| l.strip_prefix("v ")).collect(),
                    _ => text.lines().skip(2).take(3).collect(),
                };
                lines
                    .iter()
                    .map(|l| {
                        let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                        [v[0], v[1], v[2]]
                    })
                    .collect()
            }
            _ => {
                let text = String::from_utf8_lossy(&bytes);
                assert!(text.contains("property double x\nproperty double y\nproperty double z\n"));
                let start = text.find("end_header\n").unwrap() + "end_header\n".len();
                (0..3)
                    .map(|v| {
                        std::array::from_fn(|k| {
                            let o = start + 8 * (3 * v + k);
                            f64::from_le_bytes(bytes[o..o + 8].try_into().unwrap())
                        })
                    })
                    .collect()
            }
        }
    }

    #[test]
    fn text_and_ply_keep_every_f64_bit() {
        let (mesh, exact) = far();
        let dir = tempfile::tempdir().unwrap();
        for format in [Format::Obj, Format::Off, Format::Ply] {
            let path = dir.path().join(format!("far.{}", format.extension()));
            write_path_f64(&mesh, &exact, &path).unwrap();
            assert_eq!(read_back(&path, format), exact, "{format:?}");
            // The readers (f32) still read the file, near the f32 positions.
            let back = read_path(&path, &ReadOptions::default()).unwrap();
            assert_eq!(back.positions, mesh.positions, "{format:?}");
        }
        // f32 files of the same mesh are unchanged by the new entry point's existence.
        let path = dir.path().join("plain.ply");
        write_path(&mesh, &path).unwrap();
        assert!(
            String::from_utf8_lossy(&std::fs::read(&path).unwrap()).contains("property float x")
        );
    }

    #[test]
    fn stl_rounds_and_bad_positions_are_refused() {
        let (mesh, exact) = far();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("far.stl");
        write_path_f64(&mesh, &exact, &path).unwrap();
        let back = read_path(&path, &ReadOptions::default()).unwrap();
        assert_eq!(back.positions, mesh.positions);
        let e = write_path_f64(&mesh, &exact[..2], &dir.path().join("x.obj")).unwrap_err();
        assert!(matches!(e, MeshError::Invalid(_)), "{e}");
        let mut nan = exact.clone();
        nan[1][2] = f64::NAN;
        let e = write_path_f64(&mesh, &nan, &dir.path().join("x.obj")).unwrap_err();
        assert!(e.to_string().contains("position 1"), "{e}");
    }
}
