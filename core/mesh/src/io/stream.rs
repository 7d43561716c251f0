//! Meshes read in passes, never held whole: [`PlyFile`] and [`ObjFile`] walk their file once
//! per pass (vertices, then triangles), so an out-of-core consumer (the codec's partition,
//! paper 003 §5.1) keeps its memory bounded whatever the input's size; [`Slices`] wraps a mesh
//! already in memory behind the same [`MeshSource`] trait.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use super::ply::Scalar;
use crate::MeshError;

/// A mesh read in passes: vertices in order, then triangles (polygons fan-triangulated).
pub trait MeshSource {
    /// Number of vertices.
    fn vertex_count(&self) -> u64;
    /// Calls `f` with every vertex position, in order.
    fn vertices(&mut self, f: &mut dyn FnMut([f32; 3])) -> Result<(), MeshError>;
    /// Calls `f` with every triangle's vertex indices, in order; checks each index against
    /// [`MeshSource::vertex_count`].
    fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), MeshError>;
    /// What the input holds beyond positions and faces, by protocol name (`normals`, `uvs`,
    /// `face_groups`, as [`crate::Mesh::carried_names`] names them): what a consumer of
    /// positions and triangles alone drops. Empty by default.
    fn carried_names(&self) -> Vec<String> {
        Vec::new()
    }
}

/// A mesh in memory.
pub struct Slices<'a> {
    /// Vertex positions.
    pub positions: &'a [[f32; 3]],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
}

impl MeshSource for Slices<'_> {
    fn vertex_count(&self) -> u64 {
        self.positions.len() as u64
    }

    fn vertices(&mut self, f: &mut dyn FnMut([f32; 3])) -> Result<(), MeshError> {
        self.positions.iter().for_each(|&p| f(p));
        Ok(())
    }

    fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), MeshError> {
        let n = self.positions.len() as u64;
        for (i, &t) in self.triangles.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&x| x as u64 >= n) {
                return Err(MeshError::Invalid(format!(
                    "triangle {i} uses vertex {bad}, but there are {n} vertices"
                )));
            }
            f(t);
        }
        Ok(())
    }
}

/// Whether `path` can be streamed (a PLY or OBJ file).
pub fn streamable(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("ply" | "obj")
    )
}

/// Opens a streaming reader for a PLY or OBJ file.
pub fn open(path: &Path) -> Result<Box<dyn MeshSource>, MeshError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("ply") => Ok(Box::new(PlyFile::open(path)?)),
        Some("obj") => Ok(Box::new(ObjFile::open(path)?)),
        _ => Err(MeshError::Unsupported(format!(
            "{}: only PLY and OBJ files are streamed",
            path.display()
        ))),
    }
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> MeshError + '_ {
    move |source| MeshError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn parse_err(path: &Path, message: String) -> MeshError {
    MeshError::Parse {
        path: path.display().to_string(),
        line: 0,
        message,
    }
}

/// What [`PlyFile`]'s walk hands over per record: its index and each property's values.
type RecordFn<'a> = dyn FnMut(u64, &[Vec<f64>]) -> Result<(), MeshError> + 'a;

/// One property of a PLY element: a scalar, or a list (count type, item type).
#[derive(Clone, Debug)]
struct Property {
    name: String,
    scalar: Scalar,
    list: Option<Scalar>,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum PlyFormat {
    Ascii,
    Little,
    Big,
}

/// A PLY file (ASCII or binary, either byte order) read in passes without holding it.
#[derive(Debug)]
pub struct PlyFile {
    path: PathBuf,
    format: PlyFormat,
    elements: Vec<Element>,
    body: u64,
    vertices: u64,
}

impl PlyFile {
    /// Reads the header.
    pub fn open(path: &Path) -> Result<Self, MeshError> {
        let mut r = BufReader::new(File::open(path).map_err(io_err(path))?);
        let mut line = String::new();
        let mut body = 0u64;
        let mut format = None;
        let mut elements: Vec<Element> = Vec::new();
        let mut first = true;
        loop {
            line.clear();
            let n = r.read_line(&mut line).map_err(io_err(path))?;
            if n == 0 {
                return Err(parse_err(path, "the PLY header has no end_header".into()));
            }
            body += n as u64;
            let t: Vec<&str> = line.split_whitespace().collect();
            if first {
                if t.first() != Some(&"ply") {
                    return Err(parse_err(
                        path,
                        "not a PLY file (no \"ply\" on the first line)".into(),
                    ));
                }
                first = false;
                continue;
            }
            match t.as_slice() {
                ["format", f, _] => {
                    format = Some(match *f {
                        "ascii" => PlyFormat::Ascii,
                        "binary_little_endian" => PlyFormat::Little,
                        "binary_big_endian" => PlyFormat::Big,
                        other => {
                            return Err(parse_err(path, format!("unknown PLY format {other:?}")));
                        }
                    })
                }
                ["element", name, count] => elements.push(Element {
                    name: name.to_string(),
                    count: count.parse().map_err(|_| {
                        parse_err(path, format!("element {name} has count {count:?}"))
                    })?,
                    properties: Vec::new(),
                }),
                ["property", "list", c, i, name] => {
                    let (Some(c), Some(i)) =
                        (Scalar::parse(c.as_bytes()), Scalar::parse(i.as_bytes()))
                    else {
                        return Err(parse_err(
                            path,
                            format!("property list {name} has an unknown type"),
                        ));
                    };
                    let e = elements
                        .last_mut()
                        .ok_or_else(|| parse_err(path, "a property before any element".into()))?;
                    e.properties.push(Property {
                        name: name.to_string(),
                        scalar: i,
                        list: Some(c),
                    });
                }
                ["property", ty, name] => {
                    let s = Scalar::parse(ty.as_bytes()).ok_or_else(|| {
                        parse_err(path, format!("property {name} has unknown type {ty}"))
                    })?;
                    let e = elements
                        .last_mut()
                        .ok_or_else(|| parse_err(path, "a property before any element".into()))?;
                    e.properties.push(Property {
                        name: name.to_string(),
                        scalar: s,
                        list: None,
                    });
                }
                ["end_header"] => break,
                _ => {}
            }
        }
        let format =
            format.ok_or_else(|| parse_err(path, "the PLY header has no format line".into()))?;
        let vertices = elements
            .iter()
            .find(|e| e.name == "vertex")
            .map_or(0, |e| e.count);
        // Every record takes bytes (at least a line break in ASCII, its scalars and list counts
        // in binary), so a count the file cannot hold is refused here, not walked: fuzzing
        // found an element of 4·10¹² records, which the passes would have read for hours.
        let left = std::fs::metadata(path)
            .map_err(io_err(path))?
            .len()
            .saturating_sub(body);
        for e in &elements {
            let least: u64 = match format {
                PlyFormat::Ascii => 1,
                _ => e
                    .properties
                    .iter()
                    .map(|p| p.list.unwrap_or(p.scalar).size() as u64)
                    .sum(),
            };
            if least > 0 && e.count > left / least {
                return Err(parse_err(
                    path,
                    format!(
                        "element {} declares {} records of at least {least} bytes, but {left} \
                         bytes follow the header",
                        e.name, e.count
                    ),
                ));
            }
        }
        let ply = PlyFile {
            path: path.to_path_buf(),
            format,
            elements,
            body,
            vertices,
        };
        if let Some(v) = ply.elements.iter().find(|e| e.name == "vertex") {
            for axis in ["x", "y", "z"] {
                if !v
                    .properties
                    .iter()
                    .any(|p| p.name == axis && p.list.is_none())
                {
                    return Err(parse_err(
                        path,
                        format!("the vertex element has no scalar {axis}"),
                    ));
                }
            }
        }
        Ok(ply)
    }

    /// Walks every element record; `f(element index, record index, values)` receives each
    /// property's values (one for a scalar, the items for a list).
    fn walk(&self, want: &str, f: &mut RecordFn<'_>) -> Result<(), MeshError> {
        let path = &self.path;
        let mut file = File::open(path).map_err(io_err(path))?;
        std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(self.body))
            .map_err(io_err(path))?;
        let mut r = BufReader::with_capacity(1 << 20, file);
        let big = self.format == PlyFormat::Big;
        let mut values: Vec<Vec<f64>> = Vec::new();
        let mut line = String::new();
        let mut buf = [0u8; 8];
        for e in &self.elements {
            let here = e.name == want;
            if e.properties.is_empty() && self.format != PlyFormat::Ascii {
                // Binary records without properties take no bytes: nothing to read or hand over
                // (the vertex and face elements the passes want always have properties).
                continue;
            }
            if !here
                && self.format != PlyFormat::Ascii
                && e.properties.iter().all(|p| p.list.is_none())
            {
                // fixed-size binary records this pass does not want (the vertices, in a pass
                // over the faces): one seek, not a read per scalar (the open checked that the
                // file can hold them; a short file fails on the wanted element's first read)
                let size: u64 = e.properties.iter().map(|p| p.scalar.size() as u64).sum();
                r.seek_relative((e.count * size) as i64)
                    .map_err(io_err(path))?;
                continue;
            }
            values.resize(e.properties.len(), Vec::new());
            for k in 0..e.count {
                let eof = || parse_err(path, format!("the file ends inside {} {k}", e.name));
                if self.format == PlyFormat::Ascii {
                    line.clear();
                    if r.read_line(&mut line).map_err(io_err(path))? == 0 {
                        return Err(eof());
                    }
                    if !here {
                        continue;
                    }
                    let mut tokens = line.split_whitespace();
                    let mut next = || -> Result<f64, MeshError> {
                        tokens.next().and_then(|t| t.parse().ok()).ok_or_else(|| {
                            parse_err(
                                path,
                                format!("{} {k}: a value is missing or not a number", e.name),
                            )
                        })
                    };
                    for (p, v) in e.properties.iter().zip(values.iter_mut()) {
                        v.clear();
                        let n = if p.list.is_some() {
                            next()? as usize
                        } else {
                            1
                        };
                        for _ in 0..n {
                            v.push(next()?);
                        }
                    }
                } else {
                    for (p, v) in e.properties.iter().zip(values.iter_mut()) {
                        v.clear();
                        let n = match p.list {
                            Some(c) => {
                                r.read_exact(&mut buf[..c.size()]).map_err(|_| eof())?;
                                let n = c.decode(&buf, big);
                                if !(0.0..=1e6).contains(&n) {
                                    return Err(parse_err(
                                        path,
                                        format!("{} {k}: a list of {n} items", e.name),
                                    ));
                                }
                                n as usize
                            }
                            None => 1,
                        };
                        for _ in 0..n {
                            r.read_exact(&mut buf[..p.scalar.size()])
                                .map_err(|_| eof())?;
                            if here {
                                v.push(p.scalar.decode(&buf, big));
                            }
                        }
                    }
                }
                if here {
                    f(k, &values)?;
                }
            }
            if here {
                return Ok(());
            }
        }
        Ok(())
    }
}

impl MeshSource for PlyFile {
    fn vertex_count(&self) -> u64 {
        self.vertices
    }

    fn carried_names(&self) -> Vec<String> {
        // The vertex properties the in-memory PLY reader turns into normals and UVs.
        let has = |names: &[&str]| {
            self.elements.iter().any(|e| {
                e.name == "vertex"
                    && e.properties
                        .iter()
                        .any(|p| p.list.is_none() && names.contains(&p.name.as_str()))
            })
        };
        let mut out = Vec::new();
        if has(&["nx"]) {
            out.push("normals".to_string());
        }
        if has(&["s", "u", "texture_u", "texture_s"]) {
            out.push("uvs".to_string());
        }
        out
    }

    fn vertices(&mut self, f: &mut dyn FnMut([f32; 3])) -> Result<(), MeshError> {
        let v = self.elements.iter().find(|e| e.name == "vertex").cloned();
        let Some(v) = v else { return Ok(()) };
        let at: Vec<usize> = ["x", "y", "z"]
            .iter()
            .map(|a| v.properties.iter().position(|p| p.name == *a).unwrap())
            .collect();
        self.walk("vertex", &mut |_, vals| {
            f([
                vals[at[0]][0] as f32,
                vals[at[1]][0] as f32,
                vals[at[2]][0] as f32,
            ]);
            Ok(())
        })
    }

    fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), MeshError> {
        let Some(face) = self.elements.iter().find(|e| e.name == "face").cloned() else {
            return Ok(());
        };
        let Some(list) = face.properties.iter().position(|p| {
            p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
        }) else {
            return Err(parse_err(
                &self.path,
                "the face element has no vertex_indices list".into(),
            ));
        };
        let n = self.vertices;
        let path = self.path.clone();
        self.walk("face", &mut |k, vals| {
            let idx = &vals[list];
            for &x in idx {
                if !(x >= 0.0 && x < n as f64) {
                    return Err(parse_err(
                        &path,
                        format!("face {k} uses vertex {x}, but there are {n} vertices"),
                    ));
                }
            }
            for i in 1..idx.len().saturating_sub(1) {
                f([idx[0] as u32, idx[i] as u32, idx[i + 1] as u32]);
            }
            Ok(())
        })
    }
}

/// A Wavefront OBJ file read in passes (`v` and `f` lines; negative indices counted back from
/// the vertices read so far; texture and normal indices ignored).
#[derive(Debug)]
pub struct ObjFile {
    path: PathBuf,
    vertices: u64,
    has_normals: bool,
    has_uvs: bool,
    has_groups: bool,
}

impl ObjFile {
    /// Counts the vertices.
    pub fn open(path: &Path) -> Result<Self, MeshError> {
        let mut obj = ObjFile {
            path: path.to_path_buf(),
            vertices: 0,
            has_normals: false,
            has_uvs: false,
            has_groups: false,
        };
        let (mut n, mut normals, mut uvs, mut groups) = (0, false, false, false);
        let keyword = |line: &str, k: &str| {
            line.strip_prefix(k)
                .is_some_and(|rest| rest.starts_with([' ', '\t']))
        };
        obj.lines(&mut |_, line| {
            if keyword(line, "v") {
                n += 1;
            } else if keyword(line, "vn") {
                normals = true;
            } else if keyword(line, "vt") {
                uvs = true;
            } else if keyword(line, "usemtl") || keyword(line, "g") {
                groups = true;
            }
            Ok(())
        })?;
        obj.vertices = n;
        (obj.has_normals, obj.has_uvs, obj.has_groups) = (normals, uvs, groups);
        Ok(obj)
    }

    fn lines(
        &self,
        f: &mut dyn FnMut(u64, &str) -> Result<(), MeshError>,
    ) -> Result<(), MeshError> {
        let path = &self.path;
        let r = BufReader::with_capacity(1 << 20, File::open(path).map_err(io_err(path))?);
        for (i, line) in r.lines().enumerate() {
            let line = line.map_err(io_err(path))?;
            f(i as u64 + 1, line.trim_start())?;
        }
        Ok(())
    }
}

impl MeshSource for ObjFile {
    fn vertex_count(&self) -> u64 {
        self.vertices
    }

    fn carried_names(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.has_normals {
            out.push("normals".to_string());
        }
        if self.has_uvs {
            out.push("uvs".to_string());
        }
        if self.has_groups {
            out.push("face_groups".to_string());
        }
        out
    }

    fn vertices(&mut self, f: &mut dyn FnMut([f32; 3])) -> Result<(), MeshError> {
        let path = self.path.clone();
        self.lines(&mut |no, line| {
            if let Some(rest) = line.strip_prefix("v ").or_else(|| line.strip_prefix("v\t")) {
                let mut t = rest.split_whitespace().map(|x| x.parse::<f32>());
                let mut c = [0f32; 3];
                for x in &mut c {
                    *x = match t.next() {
                        Some(Ok(v)) => v,
                        _ => {
                            return Err(parse_err(
                                &path,
                                format!("line {no}: a vertex needs three numbers"),
                            ));
                        }
                    };
                }
                f(c);
            }
            Ok(())
        })
    }

    fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), MeshError> {
        let path = self.path.clone();
        let total = self.vertices as i64;
        let mut seen = 0i64;
        let mut idx: Vec<u32> = Vec::new();
        self.lines(&mut |no, line| {
            if line.starts_with("v ") || line.starts_with("v\t") {
                seen += 1;
            } else if let Some(rest) = line.strip_prefix("f ").or_else(|| line.strip_prefix("f\t"))
            {
                idx.clear();
                for tok in rest.split_whitespace() {
                    let v: i64 = tok
                        .split('/')
                        .next()
                        .and_then(|x| x.parse().ok())
                        .ok_or_else(|| {
                            parse_err(&path, format!("line {no}: bad face corner {tok:?}"))
                        })?;
                    let i = if v < 0 { seen + v } else { v - 1 };
                    if i < 0 || i >= total {
                        return Err(parse_err(
                            &path,
                            format!("line {no}: face corner {tok} is outside the {total} vertices"),
                        ));
                    }
                    idx.push(i as u32);
                }
                for i in 1..idx.len().saturating_sub(1) {
                    f([idx[0], idx[i], idx[i + 1]]);
                }
            }
            Ok(())
        })
    }
}
