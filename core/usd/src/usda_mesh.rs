//! One `Mesh` prim spec into a [`tessd_mesh::Mesh`], for [`crate::reader`]: UsdGeomMesh's
//! topology checked (`faceVertexCounts` ≥ 3 adding up to `faceVertexIndices`, indices in range,
//! finite points), points carried to stage space in double precision, normals and UVs from
//! their primvars' interpolation and indices, face `GeomSubset`s as face groups.

use tessd_mesh::{FaceVarying, Mesh};

use crate::UsdError;
use crate::usda_spec::{Item, PrimSpec, Specifier, Value};
use crate::xform_ops::{self, Mat4};

/// Builds the mesh of the `Mesh` prim `p` at `path`, with its world transform (`None`:
/// identity).
///
/// # Errors
/// [`UsdError::Parse`] at the line of the attribute at fault, naming `path` and the attribute
/// (or the GeomSubset); [`UsdError::TooLarge`] for more than 2³² face corners.
pub(crate) fn build(
    p: &PrimSpec,
    path: &str,
    world: Option<&Mat4>,
    source: &str,
) -> Result<Mesh, UsdError> {
    let fail = |line: usize, message: String| UsdError::Parse {
        path: source.to_string(),
        line,
        message,
    };
    let required = |name: &str| {
        numbers(p, name, if name == "points" { 3 } else { 1 }, path, source)?.ok_or_else(|| {
            fail(
                p.line,
                format!("{path}: the Mesh has no {name} (a required attribute)"),
            )
        })
    };
    let (pts, pline) = required("points")?;
    let (counts, cline) = required("faceVertexCounts")?;
    let (idx, iline) = required("faceVertexIndices")?;
    if u32::try_from(idx.len()).is_err() {
        return Err(UsdError::TooLarge(format!(
            "{source}:{iline}: {path}.faceVertexIndices: {} entries do not fit 32-bit indices",
            idx.len()
        )));
    }

    let npts = pts.len() / 3;
    let mut positions = Vec::with_capacity(npts);
    for (i, c) in pts.chunks_exact(3).enumerate() {
        let q = [c[0], c[1], c[2]];
        if q.iter().any(|x| !x.is_finite()) {
            let msg = format!(
                "{path}.points: point {i} is not finite ({}, {}, {})",
                q[0], q[1], q[2]
            );
            return Err(fail(pline, msg));
        }
        let t = world.map_or(q, |m| xform_ops::transform_point(m, q));
        let f = t.map(|x| x as f32);
        if f.iter().any(|x| !x.is_finite()) {
            let msg = format!("{path}.points: point {i} is not finite after the prim's transform");
            return Err(fail(pline, msg));
        }
        positions.push(f);
    }

    let mut face_offsets = Vec::with_capacity(counts.len() + 1);
    face_offsets.push(0u32);
    let mut total = 0u64;
    for (f, &c) in counts.iter().enumerate() {
        if c.fract() != 0.0 {
            let msg = format!("{path}.faceVertexCounts: entry {f} is {c}, not an integer");
            return Err(fail(cline, msg));
        }
        if c < 3.0 {
            let msg = format!(
                "{path}.faceVertexCounts: face {f} has {c} vertices; a face needs at least 3"
            );
            return Err(fail(cline, msg));
        }
        total = total.saturating_add(c as u64);
        if total > idx.len() as u64 {
            let msg = format!(
                "{path}.faceVertexCounts: the counts add up to more than the {} entries of \
                 faceVertexIndices (at face {f}, count {c})",
                idx.len()
            );
            return Err(fail(cline, msg));
        }
        face_offsets.push(total as u32);
    }
    if total != idx.len() as u64 {
        let msg = format!(
            "{path}.faceVertexCounts: the counts add up to {total} but faceVertexIndices has {} \
             entries",
            idx.len()
        );
        return Err(fail(cline, msg));
    }
    let mut face_indices = Vec::with_capacity(idx.len());
    for (k, &v) in idx.iter().enumerate() {
        if !(v.fract() == 0.0 && v >= 0.0 && v < npts as f64) {
            let msg = format!(
                "{path}.faceVertexIndices: entry {k} is {v}, out of range for {npts} points"
            );
            return Err(fail(iline, msg));
        }
        face_indices.push(v as u32);
    }

    let mut mesh = Mesh {
        positions,
        face_offsets,
        face_indices,
        ..Mesh::default()
    };
    let topo = Topology::of(&mesh);
    let uv_name = if p.attr("primvars:st").is_some() {
        Some("primvars:st")
    } else {
        (p.attrs.iter())
            .find(|a| {
                a.name.starts_with("primvars:")
                    && !a.name.ends_with(":indices")
                    && a.type_name.starts_with("texCoord2")
            })
            .map(|a| a.name.as_str())
    };
    mesh.uvs = uv_name.and_then(|n| primvar::<2>(p, n, &topo));
    let normals = match p.attr("primvars:normals") {
        Some(_) => primvar::<3>(p, "primvars:normals", &topo),
        None => primvar::<3>(p, "normals", &topo),
    };
    mesh.normals = match (normals, world) {
        (Some(n), Some(m)) => xform_ops::normal_matrix(m).map(|nm| FaceVarying {
            values: n.values.iter().map(|v| transform_normal(&nm, v)).collect(),
            indices: n.indices,
        }),
        (n, _) => n,
    };
    face_groups(p, path, &mut mesh, source)?;
    mesh.validate()
        .map_err(|e| fail(p.line, format!("{path}: {e}")))?;
    Ok(mesh)
}

/// A numeric attribute's values (`arity` per element) and line; `None` when not authored or
/// blocked.
fn numbers<'p>(
    p: &'p PrimSpec,
    name: &str,
    arity: usize,
    path: &str,
    source: &str,
) -> Result<Option<(&'p [f64], usize)>, UsdError> {
    let Some(attr) = p.attr(name) else {
        return Ok(None);
    };
    let message = match attr.value() {
        None => return Ok(None),
        Some(Value::Numbers { nums, arity: a }) if *a == arity || nums.is_empty() => {
            return Ok(Some((nums, attr.line)));
        }
        Some(Value::Numbers { arity: a, .. }) => {
            format!("{path}.{name}: expected {arity} components per element, found {a}")
        }
        Some(_) => format!("{path}.{name}: expected numbers"),
    };
    Err(UsdError::Parse {
        path: source.to_string(),
        line: attr.line,
        message,
    })
}

/// What primvar interpolations are counted over.
struct Topology {
    faces: usize,
    points: usize,
    /// Per corner: (face, vertex).
    corners: Vec<(usize, usize)>,
}

impl Topology {
    fn of(mesh: &Mesh) -> Topology {
        let mut corners = Vec::with_capacity(mesh.face_indices.len());
        for (f, face) in mesh.faces().enumerate() {
            corners.extend(face.iter().map(|&v| (f, v as usize)));
        }
        Topology {
            faces: mesh.face_count(),
            points: mesh.positions.len(),
            corners,
        }
    }
}

/// A primvar as face-varying values, or `None` when it is absent or inconsistent (wrong
/// arity, a count that does not match its interpolation, an index out of range): optional
/// data is dropped rather than refused.
fn primvar<const N: usize>(
    p: &PrimSpec,
    name: &str,
    topo: &Topology,
) -> Option<FaceVarying<[f32; N]>> {
    let attr = p.attr(name)?;
    let Some(Value::Numbers { nums, arity }) = attr.value() else {
        return None;
    };
    if *arity != N || nums.iter().any(|x| !x.is_finite()) {
        return None;
    }
    // The `normals` attribute defaults to vertex interpolation, primvars to constant.
    let default = if name == "normals" {
        "vertex"
    } else {
        "constant"
    };
    let interpolation = attr.interpolation.as_deref().unwrap_or(default);
    let indices = match p.attr(&format!("{name}:indices")).and_then(|a| a.value()) {
        Some(Value::Numbers { nums, arity: 1 }) => Some(nums.as_slice()),
        _ => None,
    };
    let values: Vec<[f32; N]> = nums
        .chunks_exact(N)
        .map(|c| std::array::from_fn(|k| c[k] as f32))
        .collect();
    let elements = match interpolation {
        "constant" => 1,
        "uniform" => topo.faces,
        "vertex" | "varying" => topo.points,
        "faceVarying" => topo.corners.len(),
        _ => return None,
    };
    let lookup: Vec<u32> = match indices {
        Some(ix) if ix.len() == elements => {
            if ix
                .iter()
                .any(|&i| !(i.fract() == 0.0 && i >= 0.0 && i < values.len() as f64))
            {
                return None;
            }
            ix.iter().map(|&i| i as u32).collect()
        }
        Some(_) => return None,
        None if values.len() == elements => (0..elements as u32).collect(),
        None => return None,
    };
    let corner_indices = (topo.corners.iter().enumerate())
        .map(|(c, &(f, v))| match interpolation {
            "constant" => lookup[0],
            "uniform" => lookup[f],
            "vertex" | "varying" => lookup[v],
            _ => lookup[c],
        })
        .collect();
    Some(FaceVarying {
        values,
        indices: corner_indices,
    })
}

fn transform_normal(nm: &[[f64; 3]; 3], v: &[f32; 3]) -> [f32; 3] {
    let t: [f64; 3] = std::array::from_fn(|c| (0..3).map(|k| f64::from(v[k]) * nm[k][c]).sum());
    let len = t.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len > 0.0 {
        t.map(|x| (x / len) as f32)
    } else {
        [0.0; 3]
    }
}

/// Face groups from the face `GeomSubset` children (the `materialBind` family when there are
/// several families), faces in none getting a group named after the prim; without subsets one
/// group named after the prim.
fn face_groups(p: &PrimSpec, path: &str, mesh: &mut Mesh, source: &str) -> Result<(), UsdError> {
    let nf = mesh.face_count();
    let subsets: Vec<&PrimSpec> = (p.items.iter())
        .filter_map(|i| match i {
            Item::Prim(c)
                if c.specifier == Specifier::Def
                    && c.active
                    && c.type_name == "GeomSubset"
                    && c.token("elementType").unwrap_or("face") == "face" =>
            {
                Some(c)
            }
            _ => None,
        })
        .collect();
    let family = |s: &PrimSpec| s.token("familyName").unwrap_or("").to_string();
    let chosen = if subsets.iter().any(|s| family(s) == "materialBind") {
        "materialBind".to_string()
    } else {
        subsets.first().map(|s| family(s)).unwrap_or_default()
    };
    const NONE: u32 = u32::MAX;
    let mut groups = vec![NONE; nf];
    let mut names = Vec::new();
    for s in subsets.into_iter().filter(|s| family(s) == chosen) {
        let g = names.len() as u32;
        names.push(s.name.clone());
        let spath = format!("{path}/{}", s.name);
        let Some((ix, line)) = numbers(s, "indices", 1, &spath, source)? else {
            continue;
        };
        for (k, &f) in ix.iter().enumerate() {
            if !(f.fract() == 0.0 && f >= 0.0 && f < nf as f64) {
                return Err(UsdError::Parse {
                    path: source.to_string(),
                    line,
                    message: format!(
                        "{spath}.indices: entry {k} is {f}, out of range for {nf} faces"
                    ),
                });
            }
            let slot = &mut groups[f as usize];
            if *slot == NONE {
                *slot = g;
            }
        }
    }
    if names.is_empty() || groups.contains(&NONE) {
        let g = names.len() as u32;
        names.push(p.name.clone());
        groups
            .iter_mut()
            .filter(|x| **x == NONE)
            .for_each(|x| *x = g);
    }
    mesh.face_groups = groups;
    mesh.group_names = names;
    Ok(())
}
