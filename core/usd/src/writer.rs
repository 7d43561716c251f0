//! The one stage writer; the public entry points are thin wrappers around [`write_root`].

use std::io::Write;

use tessd_mesh::Mesh;

use crate::UsdError;
use crate::names::UniqueNames;
use crate::options::{
    LodSchemaOptions, MeshPrim, MeshPrimOptions, StageOptions, SubdivisionScheme,
};
use crate::usda_out::Out;

/// Writes a stage holding one mesh: the root `Xform` (the `defaultPrim`) with one `Mesh` child.
///
/// # Errors
/// [`UsdError::InvalidMesh`] when `mesh.validate()` fails, [`UsdError::InvalidOption`] /
/// [`UsdError::TooLarge`] for options or sizes USD cannot hold (all checked before anything is
/// written), [`UsdError::Io`] when `w` fails.
pub fn write_mesh_stage(
    w: &mut dyn Write,
    mesh: &Mesh,
    stage: &StageOptions,
    prim: &MeshPrimOptions,
) -> Result<(), UsdError> {
    write_stage(w, stage, &[MeshPrim::new(mesh).with_options(prim.clone())])
}

/// Writes a stage holding several meshes (e.g. several Blender objects) as sibling `Mesh` prims
/// under the root `Xform`, each with its optional transform. Clashing prim names are made
/// unique (`Cube`, `Cube_1`).
///
/// # Errors
/// As [`write_mesh_stage`].
pub fn write_stage(
    w: &mut dyn Write,
    stage: &StageOptions,
    prims: &[MeshPrim<'_>],
) -> Result<(), UsdError> {
    write_root(w, stage, Body::Prims(prims))
}

/// Writes a stage whose root `Xform` has a variant set `LOD` with one variant per level,
/// `LOD0` (= `levels[0]`, the finest, selected by default) to `LOD{n-1}`; each variant holds
/// the `Mesh` prim named by `prim.name`:
///
/// ```text
/// def Xform "Root" (
///     kind = "component"
///     variants = {
///         string LOD = "LOD0"
///     }
///     prepend variantSets = "LOD"
/// )
/// {
///     variantSet "LOD" = {
///         "LOD0" {
///             def Mesh "mesh" { ... }
///         }
///         "LOD1" { ... }
///     }
/// }
/// ```
///
/// # Errors
/// As [`write_mesh_stage`]; [`UsdError::InvalidOption`] when `levels` is empty.
pub fn write_lod_variants(
    w: &mut dyn Write,
    stage: &StageOptions,
    levels: &[&Mesh],
    prim: &MeshPrimOptions,
) -> Result<(), UsdError> {
    write_root(
        w,
        stage,
        Body::Lod {
            levels,
            options: prim,
        },
    )
}

/// Writes a stage with the native `UsdLod` schema (usd-core 26.8+): under the root `Xform`
/// (the `defaultPrim`, kind `component`), an `Xform` named by `prim.name` with `LODRootAPI`
/// applied whose children, in order, are the levels as `Mesh` prims `LOD0` (= `levels[0]`,
/// the finest) to `LOD{n-1}`, and beside it (outside the LOD root, whose children are all LOD
/// items, but inside the `defaultPrim`, so that the relationship survives a reference to the
/// asset) the `LODScreenSizeHeuristic` that `lod:heuristics` targets:
///
/// ```text
/// def Xform "Root" (
///     kind = "component"
/// )
/// {
///     def Xform "mesh" (
///         prepend apiSchemas = ["LODRootAPI"]
///     )
///     {
///         int lod:default:index = 0
///         rel lod:heuristics = </Root/mesh_lodHeuristic>
///
///         def Mesh "LOD0" { ... token visibility = "inherited" }
///         def Mesh "LOD1" { ... token visibility = "invisible" }
///     }
///
///     def LODScreenSizeHeuristic "mesh_lodHeuristic"
///     {
///         float3[] extent = [...]
///         uniform token lod:domain = "imaging"
///         uniform float[] thresholds = [0.25]
///     }
/// }
/// ```
///
/// Only the default level is visible, as the schema recommends for renderers that do not
/// understand it; the heuristic's `extent` is the box of all levels, in the LOD root's
/// coordinates. See [`LodSchemaOptions`] for the default index and the thresholds.
///
/// # Errors
/// As [`write_mesh_stage`]; [`UsdError::InvalidOption`] when `levels` is empty, the default
/// index is out of range, or the thresholds are not `levels.len() - 1` finite, positive,
/// non-increasing numbers.
pub fn write_lod_schema(
    w: &mut dyn Write,
    stage: &StageOptions,
    levels: &[&Mesh],
    prim: &MeshPrimOptions,
    lod: &LodSchemaOptions,
) -> Result<(), UsdError> {
    write_root(
        w,
        stage,
        Body::LodSchema {
            levels,
            options: prim,
            lod,
        },
    )
}

/// What goes under the root prim.
enum Body<'a> {
    Prims(&'a [MeshPrim<'a>]),
    Lod {
        levels: &'a [&'a Mesh],
        options: &'a MeshPrimOptions,
    },
    LodSchema {
        levels: &'a [&'a Mesh],
        options: &'a MeshPrimOptions,
        lod: &'a LodSchemaOptions,
    },
}

/// The name of the LOD variant set.
const LOD_SET: &str = "LOD";

/// The core writer: checks everything, then streams the layer.
fn write_root(w: &mut dyn Write, stage: &StageOptions, body: Body<'_>) -> Result<(), UsdError> {
    check_stage(stage)?;
    match &body {
        Body::Prims(prims) => {
            for p in prims.iter() {
                check_prim(p.mesh, &p.options, &p.options.name)?;
                if p.transform
                    .iter()
                    .flatten()
                    .flatten()
                    .any(|v| !v.is_finite())
                {
                    return Err(UsdError::InvalidOption(format!(
                        "mesh prim \"{}\": the transform has a non-finite entry",
                        p.options.name
                    )));
                }
                if p.translate.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(UsdError::InvalidOption(format!(
                        "mesh prim \"{}\": the translate has a non-finite entry",
                        p.options.name
                    )));
                }
                for (k, f) in p.point_samples.iter().flat_map(|s| s.iter()).enumerate() {
                    if f.len() != p.mesh.positions.len() {
                        return Err(UsdError::InvalidOption(format!(
                            "mesh prim \"{}\": frame {k} has {} points, the mesh {}",
                            p.options.name,
                            f.len(),
                            p.mesh.positions.len()
                        )));
                    }
                    if let Some(i) = f.iter().position(|q| q.iter().any(|c| !c.is_finite())) {
                        return Err(UsdError::InvalidOption(format!(
                            "mesh prim \"{}\": frame {k}, point {i} is not finite",
                            p.options.name
                        )));
                    }
                }
            }
        }
        Body::Lod { levels, options }
        | Body::LodSchema {
            levels, options, ..
        } => {
            if levels.is_empty() {
                return Err(UsdError::InvalidOption("no LOD levels to write".into()));
            }
            for (i, m) in levels.iter().enumerate() {
                check_prim(m, options, &format!("{} (LOD{i})", options.name))?;
            }
        }
    }
    let thresholds = match &body {
        Body::LodSchema { levels, lod, .. } => Some(lod_thresholds(levels, lod)?),
        _ => None,
    };

    let mut out = Out::new(w);
    let root = crate::sanitize_identifier(&stage.default_prim);
    out.push("#usda 1.0\n(\n");
    out.push_fmt(format_args!("    defaultPrim = \"{root}\"\n"));
    if let Some(doc) = &stage.doc {
        out.push("    doc = ");
        out.push_string_literal(doc);
        out.push("\n");
    }
    let frames = match &body {
        Body::Prims(prims) => prims
            .iter()
            .filter_map(|p| p.point_samples.map(<[_]>::len))
            .max(),
        _ => None,
    };
    if let Some(n) = frames.filter(|&n| n > 0) {
        out.push_fmt(format_args!(
            "    startTimeCode = 1\n    endTimeCode = {n}\n"
        ));
    }
    out.push("    metersPerUnit = ");
    out.push_f64(stage.meters_per_unit);
    out.push_fmt(format_args!(
        "\n    upAxis = \"{}\"\n)\n\n",
        stage.up_axis.token()
    ));

    out.push_fmt(format_args!(
        "def Xform \"{root}\" (\n    kind = \"component\"\n"
    ));
    if let Body::Lod { .. } = body {
        out.push_fmt(format_args!(
            "    variants = {{\n        string {LOD_SET} = \"LOD0\"\n    }}\n    \
             prepend variantSets = \"{LOD_SET}\"\n"
        ));
    }
    out.push(")\n{\n");
    match body {
        Body::Prims(prims) => {
            let mut names = UniqueNames::default();
            for (i, p) in prims.iter().enumerate() {
                if i > 0 {
                    out.push("\n");
                }
                let name = names.claim(&p.options.name, "mesh");
                let extras = PrimExtras {
                    transform: p.transform.as_ref(),
                    translate: p.translate.as_ref(),
                    visibility: None,
                    point_samples: p.point_samples,
                };
                write_mesh(&mut out, 1, p.mesh, &p.options, &name, &extras)?;
            }
        }
        Body::Lod { levels, options } => {
            let name = UniqueNames::default().claim(&options.name, "mesh");
            out.push_fmt(format_args!("    variantSet \"{LOD_SET}\" = {{\n"));
            for (i, m) in levels.iter().enumerate() {
                out.push_fmt(format_args!("        \"LOD{i}\" {{\n"));
                write_mesh(&mut out, 3, m, options, &name, &PrimExtras::default())?;
                out.push("        }\n");
            }
            out.push("    }\n");
        }
        Body::LodSchema {
            levels,
            options,
            lod,
        } => {
            let mut names = UniqueNames::default();
            let lod_root = names.claim(&options.name, "mesh");
            let heuristic = names.claim(&format!("{lod_root}_lodHeuristic"), "lodHeuristic");
            out.push_fmt(format_args!(
                "    def Xform \"{lod_root}\" (\n        prepend apiSchemas = [\"LODRootAPI\"]\n    )\n    \
                 {{\n        int lod:default:index = {}\n        \
                 rel lod:heuristics = </{root}/{heuristic}>\n",
                lod.default_index
            ));
            for (i, m) in levels.iter().enumerate() {
                out.push("\n");
                let extras = PrimExtras {
                    transform: None,
                    translate: None,
                    point_samples: None,
                    visibility: Some(if i == lod.default_index {
                        "inherited"
                    } else {
                        "invisible"
                    }),
                };
                write_mesh(&mut out, 2, m, options, &format!("LOD{i}"), &extras)?;
            }
            out.push_fmt(format_args!(
                "    }}\n\n    def LODScreenSizeHeuristic \"{heuristic}\"\n    {{\n"
            ));
            let all = levels.iter().filter_map(|m| extent(&m.positions));
            if let Some((lo, hi)) = all.reduce(|(a, b), (c, d)| {
                (
                    std::array::from_fn(|k| a[k].min(c[k])),
                    std::array::from_fn(|k| b[k].max(d[k])),
                )
            }) {
                out.push("        float3[] extent = [");
                out.push_tuple(&lo);
                out.push(", ");
                out.push_tuple(&hi);
                out.push("]\n");
            }
            out.push("        uniform token lod:domain = \"imaging\"\n");
            out.push("        uniform float[] thresholds = ");
            out.push_float_array(thresholds.unwrap_or_default().into_iter())?;
            out.push("    }\n");
        }
    }
    out.push("}\n");
    out.finish()
}

fn check_stage(stage: &StageOptions) -> Result<(), UsdError> {
    let m = stage.meters_per_unit;
    if !m.is_finite() || m <= 0.0 {
        return Err(UsdError::InvalidOption(format!(
            "metersPerUnit must be finite and > 0, not {m}"
        )));
    }
    Ok(())
}

/// Largest index USD's `int` can hold.
const MAX_INDEX: usize = i32::MAX as usize;

fn check_prim(mesh: &Mesh, options: &MeshPrimOptions, label: &str) -> Result<(), UsdError> {
    mesh.validate().map_err(|source| UsdError::InvalidMesh {
        prim: label.to_string(),
        source,
    })?;
    let too_large = |what: &str, n: usize| {
        UsdError::TooLarge(format!(
            "mesh prim \"{label}\": {n} {what} do not fit USD's 32-bit int indices"
        ))
    };
    // Each of these is indexed by USD `int`s (faces by GeomSubset indices).
    let indexed = [
        ("vertices", mesh.positions.len()),
        (
            "normals",
            mesh.normals
                .as_ref()
                .filter(|_| options.write_normals)
                .map_or(0, |n| n.values.len()),
        ),
        (
            "UVs",
            mesh.uvs
                .as_ref()
                .filter(|_| options.write_uvs)
                .map_or(0, |t| t.values.len()),
        ),
        ("faces", mesh.face_count()),
    ];
    if let Some((what, n)) = indexed.into_iter().find(|(_, n)| *n > MAX_INDEX + 1) {
        return Err(too_large(what, n));
    }
    let non_triangle = match options.subdivision_scheme {
        Some(SubdivisionScheme::Loop) => mesh.faces().enumerate().find(|(_, f)| f.len() != 3),
        _ => None,
    };
    if let Some((f, face)) = non_triangle {
        return Err(UsdError::InvalidOption(format!(
            "mesh prim \"{label}\": the loop subdivision scheme needs a triangle mesh; face {f} \
             has {} vertices",
            face.len()
        )));
    }
    let uv = crate::sanitize_identifier(&options.uv_primvar_name);
    if options.write_uvs
        && mesh.uvs.is_some()
        && options.write_normals
        && mesh.normals.is_some()
        && uv == "normals"
    {
        return Err(UsdError::InvalidOption(format!(
            "mesh prim \"{label}\": the UV primvar cannot be named \"normals\""
        )));
    }
    Ok(())
}

/// What a mesh prim may carry besides the mesh and its options.
#[derive(Default)]
struct PrimExtras<'a> {
    /// `xformOp:transform`.
    transform: Option<&'a [[f64; 4]; 4]>,
    /// `xformOp:translate`, after the transform.
    translate: Option<&'a [f64; 3]>,
    /// The `visibility` token (`"inherited"` / `"invisible"`), when authored.
    visibility: Option<&'static str>,
    /// Animated points (see [`MeshPrim::point_samples`]).
    point_samples: Option<&'a [Vec<[f32; 3]>]>,
}

/// The screen-size thresholds of a `UsdLod` stage: checked when given, else derived from the
/// levels' vertex counts (see [`LodSchemaOptions::screen_size_thresholds`]).
fn lod_thresholds(levels: &[&Mesh], lod: &LodSchemaOptions) -> Result<Vec<f32>, UsdError> {
    let n = levels.len();
    if lod.default_index >= n {
        return Err(UsdError::InvalidOption(format!(
            "the default LOD index {} is out of range for {n} levels",
            lod.default_index
        )));
    }
    match &lod.screen_size_thresholds {
        Some(t) => {
            if t.len() != n - 1 {
                return Err(UsdError::InvalidOption(format!(
                    "{} screen-size thresholds given for {n} LOD levels; {} expected",
                    t.len(),
                    n - 1
                )));
            }
            if let Some(bad) = t.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                return Err(UsdError::InvalidOption(format!(
                    "screen-size thresholds must be finite and > 0, got {bad}"
                )));
            }
            if t.windows(2).any(|w| w[1] > w[0]) {
                return Err(UsdError::InvalidOption(format!(
                    "screen-size thresholds must not increase, got {t:?}"
                )));
            }
            Ok(t.clone())
        }
        None => {
            let v0 = levels[0].positions.len().max(1) as f64;
            let mut last = f32::INFINITY;
            Ok(levels[1..]
                .iter()
                .map(|m| {
                    last = last.min((0.5 * m.positions.len() as f64 / v0) as f32);
                    last
                })
                .collect())
        }
    }
}

/// Writes `def Mesh "name" { ... }` at indentation level `ind`.
fn write_mesh(
    out: &mut Out<'_>,
    ind: usize,
    mesh: &Mesh,
    options: &MeshPrimOptions,
    name: &str,
    extras: &PrimExtras<'_>,
) -> Result<(), UsdError> {
    let pad = "    ".repeat(ind);
    let pad1 = "    ".repeat(ind + 1);
    out.push_fmt(format_args!("{pad}def Mesh \"{name}\"\n{pad}{{\n"));

    // Extent of all points, as UsdGeomPointBased::ComputeExtent computes it.
    if let Some((lo, hi)) = extent(&mesh.positions) {
        out.push_fmt(format_args!("{pad1}float3[] extent = ["));
        out.push_tuple(&lo);
        out.push(", ");
        out.push_tuple(&hi);
        out.push("]\n");
    }
    out.push_fmt(format_args!("{pad1}int[] faceVertexCounts = "));
    out.push_int_array(mesh.face_offsets.windows(2).map(|w| w[1] - w[0]))?;
    out.push_fmt(format_args!("{pad1}int[] faceVertexIndices = "));
    out.push_int_array(mesh.face_indices.iter().copied())?;
    out.push_fmt(format_args!(
        "{pad1}uniform bool doubleSided = {}\n{pad1}uniform token orientation = \"rightHanded\"\n",
        options.double_sided
    ));
    out.push_fmt(format_args!("{pad1}point3f[] points = "));
    out.push_tuple_array(&mesh.positions)?;
    if let Some(frames) = extras.point_samples {
        out.push_fmt(format_args!("{pad1}float3[] extent.timeSamples = {{\n"));
        for (k, f) in frames.iter().enumerate() {
            if let Some((lo, hi)) = extent(f) {
                out.push_fmt(format_args!("{pad1}    {}: [", k + 1));
                out.push_tuple(&lo);
                out.push(", ");
                out.push_tuple(&hi);
                out.push("],\n");
            }
        }
        out.push_fmt(format_args!(
            "{pad1}}}\n{pad1}point3f[] points.timeSamples = {{\n"
        ));
        for (k, f) in frames.iter().enumerate() {
            out.push_fmt(format_args!("{pad1}    {}: ", k + 1));
            out.push_tuple_array_open(f)?;
            out.push(",\n");
        }
        out.push_fmt(format_args!("{pad1}}}\n"));
    }

    if let Some(n) = mesh.normals.as_ref().filter(|_| options.write_normals) {
        out.push_fmt(format_args!("{pad1}normal3f[] primvars:normals = "));
        out.push_tuple_array_open(&n.values)?;
        out.push_fmt(format_args!(
            " (\n{pad1}    interpolation = \"faceVarying\"\n{pad1})\n"
        ));
        out.push_fmt(format_args!("{pad1}int[] primvars:normals:indices = "));
        out.push_int_array(n.indices.iter().copied())?;
    }
    if let Some(t) = mesh.uvs.as_ref().filter(|_| options.write_uvs) {
        let uv = crate::sanitize_identifier(&options.uv_primvar_name);
        out.push_fmt(format_args!("{pad1}texCoord2f[] primvars:{uv} = "));
        out.push_tuple_array_open(&t.values)?;
        out.push_fmt(format_args!(
            " (\n{pad1}    interpolation = \"faceVarying\"\n{pad1})\n"
        ));
        out.push_fmt(format_args!("{pad1}int[] primvars:{uv}:indices = "));
        out.push_int_array(t.indices.iter().copied())?;
    }
    for p in crate::primvars::attribute_primvars(mesh, options) {
        out.push_fmt(format_args!("{pad1}{} primvars:{} = ", p.type_name, p.name));
        out.push_rows(&p.attribute.values, p.attribute.components)?;
        out.push_fmt(format_args!(" (\n"));
        if let Some(n) = p.element_size {
            out.push_fmt(format_args!("{pad1}    elementSize = {n}\n"));
        }
        out.push_fmt(format_args!(
            "{pad1}    interpolation = \"{}\"\n{pad1})\n",
            p.interpolation
        ));
    }
    if !mesh.creases.is_empty() {
        // One crease per edge: lengths of 2, one sharpness each.
        out.push_fmt(format_args!("{pad1}int[] creaseIndices = "));
        out.push_int_array(mesh.creases.iter().flat_map(|c| [c.a, c.b]))?;
        out.push_fmt(format_args!("{pad1}int[] creaseLengths = "));
        out.push_int_array(mesh.creases.iter().map(|_| 2))?;
        out.push_fmt(format_args!("{pad1}float[] creaseSharpnesses = "));
        out.push_float_array(mesh.creases.iter().map(|c| c.value))?;
    }
    let scheme = options
        .subdivision_scheme
        .map_or("none", SubdivisionScheme::token);
    out.push_fmt(format_args!(
        "{pad1}uniform token subdivisionScheme = \"{scheme}\"\n"
    ));
    if options.subdivision_scheme.is_some() {
        if let Some(t) = options.interpolate_boundary {
            out.push_fmt(format_args!("{pad1}token interpolateBoundary = \"{t}\"\n"));
        }
        if let Some(t) = options.face_varying_linear_interpolation {
            out.push_fmt(format_args!(
                "{pad1}token faceVaryingLinearInterpolation = \"{t}\"\n"
            ));
        }
    }
    if !mesh.face_groups.is_empty() {
        // `face_groups` gives every face exactly one group, so the subsets partition the faces.
        out.push_fmt(format_args!(
            "{pad1}uniform token subsetFamily:materialBind:familyType = \"partition\"\n"
        ));
    }
    if let Some(v) = extras.visibility {
        out.push_fmt(format_args!("{pad1}token visibility = \"{v}\"\n"));
    }
    if let Some(m) = extras.transform {
        out.push_fmt(format_args!("{pad1}matrix4d xformOp:transform = ( "));
        for (r, row) in m.iter().enumerate() {
            if r > 0 {
                out.push(", ");
            }
            out.push("(");
            for (c, v) in row.iter().enumerate() {
                if c > 0 {
                    out.push(", ");
                }
                out.push_f64(*v);
            }
            out.push(")");
        }
        out.push(" )\n");
    }
    if let Some(t) = extras.translate {
        out.push_fmt(format_args!("{pad1}double3 xformOp:translate = ("));
        for (k, v) in t.iter().enumerate() {
            if k > 0 {
                out.push(", ");
            }
            out.push_f64(*v);
        }
        out.push(")\n");
    }
    let ops: Vec<&str> = [
        extras.transform.map(|_| "\"xformOp:transform\""),
        extras.translate.map(|_| "\"xformOp:translate\""),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !ops.is_empty() {
        out.push_fmt(format_args!(
            "{pad1}uniform token[] xformOpOrder = [{}]\n",
            ops.join(", ")
        ));
    }
    if !mesh.face_groups.is_empty() {
        write_subsets(out, &pad1, mesh)?;
    }
    out.push_fmt(format_args!("{pad}}}\n"));
    Ok(())
}

/// One `GeomSubset` per non-empty face group, in group order.
fn write_subsets(out: &mut Out<'_>, pad: &str, mesh: &Mesh) -> Result<(), UsdError> {
    // Counting sort of the faces by group: `order[start[g]..start[g + 1]]` are group g's faces.
    let ng = mesh.group_names.len();
    let mut start = vec![0usize; ng + 1];
    for &g in &mesh.face_groups {
        start[g as usize + 1] += 1;
    }
    for g in 0..ng {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut order = vec![0u32; mesh.face_groups.len()];
    for (f, &g) in mesh.face_groups.iter().enumerate() {
        order[fill[g as usize]] = f as u32;
        fill[g as usize] += 1;
    }
    let mut names = UniqueNames::default();
    for (g, group_name) in mesh.group_names.iter().enumerate() {
        let faces = &order[start[g]..start[g + 1]];
        if faces.is_empty() {
            continue;
        }
        let name = names.claim(group_name, "group");
        out.push_fmt(format_args!(
            "\n{pad}def GeomSubset \"{name}\"\n{pad}{{\n\
             {pad}    uniform token elementType = \"face\"\n\
             {pad}    uniform token familyName = \"materialBind\"\n\
             {pad}    int[] indices = "
        ));
        out.push_int_array(faces.iter().copied())?;
        out.push_fmt(format_args!("{pad}}}\n"));
    }
    Ok(())
}

fn extent(points: &[[f32; 3]]) -> Option<([f32; 3], [f32; 3])> {
    let first = *points.first()?;
    let (mut lo, mut hi) = (first, first);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    Some((lo, hi))
}
