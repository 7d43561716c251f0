//! Meshes in and out of requests: a file path (`params.input`: OBJ, PLY, STL, OFF or a `.usda`
//! stage) or the protocol's mesh arrays
//! (docs/protocol.md, "Mesh arrays": also the generic `point:` / `corner:` / `face:`
//! attributes and `sharp_edges`), and results as arrays or a written file.

use super::library_errors::{mesh_error, usd_error};
use std::path::Path;
use tessd_ipc::arrays::{Arrays, DType, Element, OwnedArray, TakenArray, TypedView};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::Request;
use tessd_mesh::attribute::{check_components, check_name, check_rows};
use tessd_mesh::io::ReadOptions;
use tessd_mesh::{Attribute, Crease, Domain, FaceVarying, Mesh};

fn invalid(message: String) -> OpError {
    OpError::new(ErrorCode::InvalidMesh, message)
}

/// The request's input mesh: read from `params.input` when given, else built from the arrays,
/// which are moved out of the request into the mesh (no copy). Either way it is validated
/// before it is returned; reading a file stops early when the job is cancelled.
///
/// # Errors
/// `invalid_request` when there is neither; `invalid_mesh`, `io`, `too_large`, `unsupported`
/// as the input deserves, naming the element at fault.
pub fn input_mesh(request: &mut Request, ctx: &JobContext) -> Result<Mesh, OpError> {
    let mesh = match request.str_param("input")? {
        Some(path) => read_mesh_file(&request.resolve(path), &read_options(ctx))?,
        None if request.arrays.desc("positions").is_some() => {
            let group_names = match request.params.get("group_names") {
                None => Vec::new(),
                Some(v) => serde_json::from_value::<Vec<String>>(v.clone())
                    .map_err(|_| OpError::request("`group_names` must be a list of strings"))?,
            };
            let mesh = mesh_from_arrays(&mut request.arrays, group_names)?;
            mesh.validate().map_err(mesh_error)?;
            mesh
        }
        None => {
            return Err(OpError::request(
                "no input mesh: give `params.input` (a file path) or the `positions` and `face_indices` arrays",
            ));
        }
    };
    admit_mesh(&mesh, "the input mesh", ctx)?;
    Ok(mesh)
}

/// Reader options for a job: stop when it is cancelled, refuse more elements than the
/// daemon's `--max-mesh-elements` while reading (before the arrays grow).
pub fn read_options(ctx: &JobContext) -> ReadOptions {
    ReadOptions::default()
        .with_cancel(ctx.cancel_token().flag())
        .with_max_elements(ctx.limits().max_mesh_elements)
}

/// Working set of a mesh operation as a multiple of its input mesh's bytes: the largest
/// measured is simplification's (input, clusters and output: at most 1.75× the input extra,
/// bench/results/simplify.md), subdivision estimates its own output; 8 leaves headroom for
/// the reply's copies.
const WORKING_SET_PER_INPUT_BYTE: u64 = 8;

/// Holds a mesh to the job's limits: `--max-mesh-elements` for mesh arrays (files are held
/// while they are read) and `--max-job-memory` for the estimated working set.
///
/// # Errors
/// `too_large`, naming `what`, the count or estimate, and the limit.
pub fn admit_mesh(mesh: &Mesh, what: &str, ctx: &JobContext) -> Result<(), OpError> {
    let max = ctx.limits().max_mesh_elements;
    for (count, name) in [
        (mesh.vertex_count(), "vertices"),
        (mesh.face_count(), "faces"),
        (mesh.face_indices.len(), "face corners"),
    ] {
        if count as u64 > max {
            return Err(OpError::new(
                ErrorCode::TooLarge,
                format!(
                    "{what} has {count} {name}, above the daemon's limit of {max} \
                     (tessd serve --max-mesh-elements)"
                ),
            ));
        }
    }
    let bytes = 12 * mesh.positions.len() as u64
        + 4 * (mesh.face_indices.len() + mesh.face_offsets.len()) as u64;
    ctx.admit_memory(what, bytes.saturating_mul(WORKING_SET_PER_INPUT_BYTE))
}

/// Reads a mesh file, format from the extension: a USD stage (`.usda`; also `.usd`, `.usdc`
/// and `.usdz`, for the reader to say which it cannot read) becomes the meshes it shows by
/// default ([`tessd_usd::UsdStage::composed`]: one face group per mesh prim), anything else
/// goes to [`tessd_mesh::io::read_path`]. The mesh returned is valid.
///
/// # Errors
/// `invalid_mesh` (syntax or a broken mesh prim, naming file, line, prim and attribute; a
/// stage without a visible mesh), `unsupported` (binary crate files, `.usdz`, unknown
/// extensions), `io`, `too_large`, `cancelled` (mesh formats only).
pub fn read_mesh_file(path: &Path, options: &ReadOptions) -> Result<Mesh, OpError> {
    if is_usd_input(path) {
        tessd_usd::read_usda(path)
            .and_then(|stage| stage.composed())
            .map_err(usd_error)
    } else {
        tessd_mesh::io::read_path(path, options).map_err(mesh_error)
    }
}

/// Whether a mesh input goes to the USD reader: `.usda`, `.usd`, `.usdc`, `.usdz`, any case.
pub fn is_usd_input(path: &Path) -> bool {
    path.extension().is_some_and(|e| {
        ["usda", "usd", "usdc", "usdz"]
            .iter()
            .any(|u| e.eq_ignore_ascii_case(u))
    })
}

/// Typed view of a required or optional array, with a message naming it on a dtype mismatch.
fn view<'a, T: Element>(
    arrays: &'a Arrays,
    name: &str,
) -> Result<Option<TypedView<'a, T>>, OpError> {
    arrays.get::<T>(name).transpose().map_err(invalid)
}

/// Array `name` taken out of the request (moved, not copied), if it is there.
fn take<T: Element>(arrays: &mut Arrays, name: &str) -> Result<Option<TakenArray<T>>, OpError> {
    arrays.take::<T>(name).transpose().map_err(invalid)
}

fn check_rows_shape<const N: usize>(name: &str, shape: &[u64]) -> Result<(), OpError> {
    if shape.len() != 2 || shape[1] != N as u64 {
        return Err(invalid(format!(
            "array {name:?} must have shape [n, {N}], got {shape:?}"
        )));
    }
    Ok(())
}

/// `data` as rows of `N` (shape checked), moved when it can be (a `Vec<f32>` of exactly
/// `rows × N` elements, as received), copied once otherwise.
fn into_rows<const N: usize>(
    name: &str,
    data: Vec<f32>,
    shape: &[u64],
) -> Result<Vec<[f32; N]>, OpError> {
    check_rows_shape::<N>(name, shape)?;
    Ok(bytemuck::allocation::try_cast_vec::<f32, [f32; N]>(data)
        .unwrap_or_else(|(_, data)| bytemuck::cast_slice(&data).to_vec()))
}

/// The `positions` array as f32 rows: f32 moved out of the request, f64 converted once.
fn take_positions(arrays: &mut Arrays) -> Result<Vec<[f32; 3]>, OpError> {
    let Some(d) = arrays.desc("positions") else {
        return Err(invalid("the `positions` array is missing".into()));
    };
    match d.dtype {
        DType::F32 => {
            let (p, shape) = take::<f32>(arrays, "positions")?.expect("the array exists");
            into_rows::<3>("positions", p, &shape)
        }
        DType::F64 => {
            let (p, shape) = view::<f64>(arrays, "positions")?.expect("the array exists");
            check_rows_shape::<3>("positions", shape)?;
            Ok(p.chunks_exact(3)
                .map(|r| [r[0] as f32, r[1] as f32, r[2] as f32])
                .collect())
        }
        other => Err(invalid(format!(
            "array \"positions\" has dtype {}; expected f32 or f64",
            other.name()
        ))),
    }
}

/// Face offsets from per-face sizes in one pass (a prefix sum; the checks are folded into it
/// and only a failure walks the sizes again to name the face).
fn offsets_from_sizes(sizes: &[u32], corners: usize) -> Result<Vec<u32>, OpError> {
    let mut offsets = Vec::with_capacity(sizes.len() + 1);
    offsets.push(0u32);
    let (mut total, mut smallest) = (0u64, u32::MAX);
    offsets.extend(sizes.iter().map(|&s| {
        smallest = smallest.min(s);
        total += u64::from(s);
        total as u32
    }));
    if smallest >= 3 && total == corners as u64 && corners <= u32::MAX as usize {
        return Ok(offsets);
    }
    let mut total = 0u64;
    for (f, &s) in sizes.iter().enumerate() {
        if s < 3 {
            return Err(invalid(format!(
                "face {f} has {s} vertices; a face needs at least 3"
            )));
        }
        total += u64::from(s);
        if total > corners as u64 {
            return Err(invalid(format!(
                "face_sizes add up to more than the {corners} face_indices (at face {f})"
            )));
        }
    }
    Err(invalid(if total == corners as u64 {
        format!("{corners} face_indices are more than a mesh can index")
    } else {
        format!("face_sizes add up to {total} but there are {corners} face_indices")
    }))
}

/// Builds a mesh from the protocol's arrays (not yet validated), moving the large ones out of
/// `arrays` (positions, face indices, face-varying values and indices, face groups) instead of
/// copying them.
///
/// # Errors
/// `invalid_mesh` naming the array at fault.
pub fn mesh_from_arrays(arrays: &mut Arrays, group_names: Vec<String>) -> Result<Mesh, OpError> {
    let positions = take_positions(arrays)?;
    let (indices, ishape) = take::<u32>(arrays, "face_indices")?
        .ok_or_else(|| invalid("the `face_indices` array is missing".into()))?;
    let face_offsets: Vec<u32> = match (ishape.len(), view::<u32>(arrays, "face_sizes")?) {
        (1, Some((sizes, _))) => offsets_from_sizes(sizes, indices.len())?,
        (1, None) => {
            return Err(invalid(
                "1-D `face_indices` needs a `face_sizes` array".into(),
            ));
        }
        (2, _) => {
            let n = ishape[1] as u32;
            if n < 3 {
                return Err(invalid(format!(
                    "face_indices of shape {ishape:?}: faces need at least 3 vertices"
                )));
            }
            (0..=ishape[0] as u32).map(|f| f * n).collect()
        }
        _ => {
            return Err(invalid(format!(
                "`face_indices` must be 1-D or 2-D, got shape {ishape:?}"
            )));
        }
    };
    let corners = indices.len();
    let normals = face_varying::<3>(arrays, "normals", "normal_indices", corners)?;
    let uvs = face_varying::<2>(arrays, "uvs", "uv_indices", corners)?;
    let creases = match view::<u32>(arrays, "crease_edges")? {
        None => Vec::new(),
        Some((edges, shape)) => {
            if shape.len() != 2 || shape[1] != 2 {
                return Err(invalid(format!(
                    "`crease_edges` must have shape [n, 2], got {shape:?}"
                )));
            }
            let (values, _) = view::<f32>(arrays, "crease_values")?
                .ok_or_else(|| invalid("`crease_edges` needs a `crease_values` array".into()))?;
            if values.len() * 2 != edges.len() {
                return Err(invalid(format!(
                    "{} crease values given for {} crease edges",
                    values.len(),
                    edges.len() / 2
                )));
            }
            edges
                .chunks_exact(2)
                .zip(values)
                .map(|(e, &value)| Crease {
                    a: e[0],
                    b: e[1],
                    value,
                })
                .collect()
        }
    };
    let face_groups = take::<u32>(arrays, "face_groups")?
        .map(|(g, _)| g)
        .unwrap_or_default();
    // Groups without (enough) names get `group<i>`, so hosts may send bare group indices.
    let mut group_names = group_names;
    if let Some(&top) = face_groups.iter().max() {
        let needed = top as usize + 1;
        if group_names.len() < needed && needed <= face_groups.len() {
            group_names.extend((group_names.len()..needed).map(|i| format!("group{i}")));
        }
    }
    let counts = [
        (Domain::Point, positions.len()),
        (Domain::Corner, corners),
        (Domain::Face, face_offsets.len() - 1),
    ];
    let attributes = attributes_from_arrays(arrays, &counts)?;
    let sharp_edges = match view::<u32>(arrays, "sharp_edges")? {
        None => Vec::new(),
        Some((edges, shape)) => {
            if shape.len() != 2 || shape[1] != 2 {
                return Err(invalid(format!(
                    "array \"sharp_edges\" must have shape [n, 2], got {shape:?}"
                )));
            }
            bytemuck::cast_slice::<u32, [u32; 2]>(edges).to_vec()
        }
    };
    Ok(Mesh {
        positions,
        face_offsets,
        face_indices: indices,
        normals,
        uvs,
        creases,
        face_groups,
        group_names,
        attributes,
        sharp_edges,
    })
}

/// The `point:<name>`, `corner:<name>` and `face:<name>` arrays (f32, [rows] or [rows, C]),
/// in the order they were sent. Dtype, name, components and the row count (`counts`: rows
/// expected per domain) are checked from the array's table before its data is copied, so a
/// hostile shape never sizes an allocation; values are checked by [`Mesh::validate`].
///
/// # Errors
/// `invalid_mesh` naming the array.
fn attributes_from_arrays(
    arrays: &Arrays,
    counts: &[(Domain, usize); 3],
) -> Result<Vec<Attribute>, OpError> {
    let mut out = Vec::new();
    for desc in arrays.descs() {
        let Some((domain, name)) = Domain::split_label(&desc.name) else {
            continue;
        };
        let label = desc.name.as_str();
        check_name(label, name).map_err(mesh_error)?;
        let (data, shape) = view::<f32>(arrays, label)?.expect("the array is in the table");
        let (rows, components, flat) = match *shape {
            [rows] => (rows, 1, true),
            [rows, c] => (rows, c, false),
            _ => {
                return Err(invalid(format!(
                    "array {label:?} must have shape [rows] or [rows, components], got {shape:?}"
                )));
            }
        };
        check_components(label, usize::try_from(components).unwrap_or(usize::MAX))
            .map_err(mesh_error)?;
        let expected = counts
            .iter()
            .find(|c| c.0 == domain)
            .expect("every domain")
            .1;
        check_rows(label, domain, rows as usize, expected).map_err(mesh_error)?;
        let mut attribute = Attribute::new(name, domain, components as usize, data.to_vec());
        attribute.flat = flat;
        out.push(attribute);
    }
    Ok(out)
}

fn face_varying<const N: usize>(
    arrays: &mut Arrays,
    values: &str,
    indices: &str,
    corners: usize,
) -> Result<Option<FaceVarying<[f32; N]>>, OpError> {
    let Some((data, shape)) = take::<f32>(arrays, values)? else {
        return Ok(None);
    };
    let values_rows = into_rows::<N>(values, data, &shape)?;
    let idx = match take::<u32>(arrays, indices)? {
        Some((i, _)) => i,
        None if values_rows.len() == corners => (0..corners as u32).collect(),
        None => {
            return Err(invalid(format!(
                "{} {values} given without `{indices}` for {corners} face corners",
                values_rows.len()
            )));
        }
    };
    Ok(Some(FaceVarying {
        values: values_rows,
        indices: idx,
    }))
}

/// The mesh as protocol arrays (1-D `face_indices` with `face_sizes`), moving its buffers.
pub fn mesh_to_arrays(mesh: Mesh) -> Vec<OwnedArray> {
    mesh_to_prefixed_arrays(mesh, "")
}

/// [`mesh_to_arrays`] with every array name prefixed (`"lod1."` gives `lod1.positions`...),
/// for results that hold several meshes.
pub fn mesh_to_prefixed_arrays(mesh: Mesh, prefix: &str) -> Vec<OwnedArray> {
    let named = |name: &str| format!("{prefix}{name}");
    let sizes: Vec<u32> = mesh.face_offsets.windows(2).map(|w| w[1] - w[0]).collect();
    let mut out = vec![
        OwnedArray::rows(&named("positions"), mesh.positions),
        OwnedArray::new(
            &named("face_indices"),
            vec![mesh.face_indices.len() as u64],
            mesh.face_indices,
        ),
        OwnedArray::new(&named("face_sizes"), vec![sizes.len() as u64], sizes),
    ];
    if let Some(n) = mesh.normals {
        out.push(OwnedArray::new(
            &named("normal_indices"),
            vec![n.indices.len() as u64],
            n.indices,
        ));
        out.push(OwnedArray::rows(&named("normals"), n.values));
    }
    if let Some(t) = mesh.uvs {
        out.push(OwnedArray::new(
            &named("uv_indices"),
            vec![t.indices.len() as u64],
            t.indices,
        ));
        out.push(OwnedArray::rows(&named("uvs"), t.values));
    }
    if !mesh.creases.is_empty() {
        let edges: Vec<[u32; 2]> = mesh.creases.iter().map(|c| [c.a, c.b]).collect();
        let values: Vec<f32> = mesh.creases.iter().map(|c| c.value).collect();
        out.push(OwnedArray::rows(&named("crease_edges"), edges));
        out.push(OwnedArray::new(
            &named("crease_values"),
            vec![values.len() as u64],
            values,
        ));
    }
    if !mesh.face_groups.is_empty() {
        out.push(OwnedArray::new(
            &named("face_groups"),
            vec![mesh.face_groups.len() as u64],
            mesh.face_groups,
        ));
    }
    if !mesh.sharp_edges.is_empty() {
        out.push(OwnedArray::rows(&named("sharp_edges"), mesh.sharp_edges));
    }
    for a in mesh.attributes {
        let rows = a.rows() as u64;
        let shape = if a.flat && a.components == 1 {
            vec![rows]
        } else {
            vec![rows, a.components as u64]
        };
        out.push(OwnedArray::new(&named(&a.label()), shape, a.values));
    }
    out
}
