//! `lod`: a chain of levels of detail from one mesh in one call (`tessd_simplify::lod::lod_chain`
//! prepares the mesh once for all levels), written as one USD stage — a variant set `LOD` or
//! the native `UsdLod` schema — and optionally one mesh file per level; the levels come back
//! as `lod<i>.*` arrays without file outputs, or with them when `return_arrays` is set (the
//! chain is computed once for both).
//!
//! The parameters are described in docs/protocol.md ("lod").

use super::common::{file_dropped, is_usda, merge_names, stage_options, stem, write_mesh_file};
use super::library_errors::{simplify_error, usd_error};
use super::mesh_arrays::{input_mesh, mesh_to_prefixed_arrays};
use super::params::clustering::{MethodKind, base_options};
use super::params::lengths::lengths_in_model_units;
use super::params::paths::output_path;
use super::params::scalars::{as_u64, bool_param};
use super::simplify::{remove_all, report_json};
use serde_json::{Value, json};
use std::path::PathBuf;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_mesh::Mesh;
use tessd_simplify::{GridSize, Method};
use tessd_usd::{LodSchemaOptions, MeshPrimOptions};

/// Most levels one request may ask for.
const MAX_LEVELS: usize = 32;

/// How the levels are laid out in the USD stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Schema {
    /// A variant set `LOD` (`LOD0`..), what DCC tools read today.
    Variants,
    /// The `UsdLod` schema of usd-core 26.8+.
    UsdLod,
}

/// The `levels` parameter: a list, or a comma-separated string (`"50%,20%,5%"`).
fn level_values(request: &Request) -> Result<Vec<Value>, OpError> {
    let values = match request.params.get("levels") {
        Some(Value::Array(items)) => items.clone(),
        Some(Value::String(s)) => s
            .split(',')
            .map(|p| Value::String(p.trim().to_string()))
            .collect(),
        None | Some(Value::Null) => {
            return Err(OpError::request(
                "`levels` is required: the goals of LOD1, LOD2... (e.g. [\"50%\", \"20%\", \"5%\"])",
            ));
        }
        Some(v) => {
            return Err(OpError::request(format!(
                "`levels` must be a list of goals, got {v}"
            )));
        }
    };
    if values.is_empty() || values.len() > MAX_LEVELS {
        return Err(OpError::request(format!(
            "`levels` must hold 1 to {MAX_LEVELS} goals, got {}",
            values.len()
        )));
    }
    Ok(values)
}

/// What a level's goal amounts to on `mesh`, in the unit the chain must move along: cells per
/// axis (grid), the tolerance in model units (quality: a percentage of the largest side of the
/// referenced vertices' bounding box), the vertices to keep (complexity: a percentage of the
/// referenced vertices, rounded as the simplifier rounds it).
fn resolved_goals(methods: &[Method], mesh: &Mesh) -> Vec<f64> {
    let mut referenced = vec![false; mesh.positions.len()];
    for &i in &mesh.face_indices {
        if let Some(r) = referenced.get_mut(i as usize) {
            *r = true;
        }
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut vertices = 0u64;
    for (p, _) in mesh.positions.iter().zip(&referenced).filter(|(_, r)| **r) {
        vertices += 1;
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (0..3)
        .map(|k| f64::from(hi[k] - lo[k]))
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    methods
        .iter()
        .map(|m| match *m {
            Method::Grid(GridSize::CellsPerAxis(n)) => f64::from(n),
            Method::Grid(GridSize::CellSize(side)) => side,
            Method::Quality(length) => length.resolve(size),
            Method::Complexity(count) => count.resolve(vertices) as f64,
        })
        .collect()
}

/// A level as the request gave it (`"50%"`, `20000`).
fn shown(v: &Value) -> String {
    match v {
        Value::String(s) => s.trim().to_string(),
        other => other.to_string(),
    }
}

/// Refuses a chain whose levels do not get coarser from one to the next: for quality the
/// levels are tolerances and must grow, for complexity vertex counts and for grid cells per
/// axis, which must shrink. Percentages are resolved against `mesh` first, so that `"1%"` and
/// `0.2` compare as the distances they are. The message names `levels`, says how the method
/// reads them and offers the levels in an order that works.
///
/// # Errors
/// `invalid_request` naming `levels`, the two levels at fault and the method.
fn check_coarsening(
    kind: MethodKind,
    values: &[Value],
    methods: &[Method],
    mesh: &Mesh,
) -> Result<(), OpError> {
    let goals = resolved_goals(methods, mesh);
    // The goal grows from one level to the next for quality, shrinks for the others.
    let grows = kind == MethodKind::Quality;
    let coarser = |a: f64, b: f64| if grows { b > a } else { b < a };
    let Some(i) = (1..goals.len()).find(|&i| !coarser(goals[i - 1], goals[i])) else {
        return Ok(());
    };
    let (reads, must, unit) = match kind {
        MethodKind::Quality => (
            "the largest error a vertex may move (a distance, or a percentage of the bounding \
             box's largest side), which must grow",
            "above",
            "",
        ),
        MethodKind::Complexity => (
            "the vertices to keep (a count, or a percentage of the input's vertices), which \
             must shrink",
            "below",
            " vertices",
        ),
        MethodKind::Grid => ("the cells per axis, which must shrink", "below", ""),
    };
    let level = |j: usize| {
        let given = shown(&values[j]);
        let resolved = goals[j];
        let exact = given.parse::<f64>().is_ok_and(|g| g == resolved);
        if exact {
            format!("LOD{}'s {given}{unit}", j + 1)
        } else {
            format!(
                "LOD{}'s {given} ({}{unit})",
                j + 1,
                super::common::significant(resolved)
            )
        }
    };
    // The same levels, coarsening, each goal once.
    let mut order: Vec<usize> = (0..goals.len()).collect();
    order.sort_by(|&a, &b| {
        let o = goals[a].total_cmp(&goals[b]);
        if grows { o } else { o.reverse() }
    });
    order.dedup_by(|b, a| goals[*a] == goals[*b]);
    let suggestion = order
        .iter()
        .map(|&j| shown(&values[j]))
        .collect::<Vec<_>>()
        .join(",");
    Err(OpError::request(format!(
        "`levels` must get coarser from each level to the next: with method {} a level is {}, \
         but {} is not {must} {}; did you mean {suggestion}?",
        kind.name(),
        reads,
        level(i),
        level(i - 1),
    )))
}

/// The folder for one file per level: `per_level` = `true` (the output's folder) or a folder.
fn per_level_dir(request: &Request, output: Option<&PathBuf>) -> Result<Option<PathBuf>, OpError> {
    match request.params.get("per_level") {
        None | Some(Value::Null) | Some(Value::Bool(false)) => Ok(None),
        Some(Value::Bool(true)) => match output {
            Some(o) => Ok(Some(
                o.parent()
                    .filter(|p| !p.as_os_str().is_empty())
                    .map_or_else(|| request.resolve("."), PathBuf::from),
            )),
            None => Err(OpError::request(
                "`per_level: true` writes beside `output`, which is missing; give `per_level` a \
                 folder instead",
            )),
        },
        Some(Value::String(dir)) if !dir.is_empty() => Ok(Some(request.resolve(dir))),
        Some(v) => Err(OpError::request(format!(
            "`per_level` must be true, false or a folder path, got {v}"
        ))),
    }
}

/// The extension of the per-level files (`per_level_format`, default `obj`).
fn per_level_format(request: &Request) -> Result<String, OpError> {
    let ext = request
        .str_param("per_level_format")?
        .unwrap_or("obj")
        .trim_start_matches('.')
        .to_ascii_lowercase();
    let probe = PathBuf::from(format!("level.{ext}"));
    if !is_usda(&probe) && tessd_mesh::io::Format::from_path(&probe).is_err() {
        return Err(OpError::new(
            ErrorCode::Unsupported,
            format!("`per_level_format` must be one of obj, ply, stl, off, usda; got {ext:?}"),
        ));
    }
    Ok(ext)
}

/// The operation.
///
/// # Errors
/// `invalid_request` for missing or invalid settings (naming the parameter and value),
/// `unsupported` for an output that is not `.usda` or an unknown per-level format,
/// `invalid_mesh`, `io`, `cancelled`.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let kind = match request.str_param("method")? {
        Some(m) => MethodKind::parse(m)?,
        None => MethodKind::Complexity,
    };
    for key in ["cells", "cell_size", "max_error", "target_vertices"] {
        if request.params.get(key).is_some_and(|v| !v.is_null()) {
            return Err(OpError::request(format!(
                "`lod` takes its goals from `levels`, not `{key}`"
            )));
        }
    }
    if kind == MethodKind::Quality {
        lengths_in_model_units(&mut request, &["levels"])?;
    }
    let values = level_values(&request)?;
    let methods = values
        .iter()
        .enumerate()
        .map(|(i, v)| kind.goal(&format!("levels[{i}]"), v))
        .collect::<Result<Vec<_>, _>>()?;
    let options = base_options(&request, methods[0], ctx)?;
    let schema = match request.str_param("lod_schema")? {
        None | Some("variants") => Schema::Variants,
        Some("usdlod") => Schema::UsdLod,
        Some(other) => {
            return Err(OpError::request(format!(
                "`lod_schema` must be \"variants\" or \"usdlod\", got {other:?}"
            )));
        }
    };
    let default_index = match request.params.get("default_level") {
        None | Some(Value::Null) => 0,
        Some(v) => as_u64(v)
            .filter(|&i| i as usize <= methods.len())
            .ok_or_else(|| {
                OpError::request(format!(
                    "`default_level` must be an integer from 0 to {}, got {v}",
                    methods.len()
                ))
            })? as usize,
    };
    if default_index != 0 && schema == Schema::Variants {
        return Err(OpError::request(
            "`default_level` applies to `lod_schema: \"usdlod\"`; the variant set always selects LOD0",
        ));
    }
    let output = output_path(&request)?;
    if let Some(o) = output.as_deref().filter(|o| !is_usda(o)) {
        return Err(OpError::new(
            ErrorCode::Unsupported,
            format!(
                "`output` of `lod` must be a .usda stage, got {}",
                o.display()
            ),
        ));
    }
    let per_level = per_level_dir(&request, output.as_ref())?;
    let return_arrays = bool_param(&request, "return_arrays")?.unwrap_or(false);
    let format = per_level_format(&request)?;
    let stage = stage_options(&request)?;
    let input_path = request.str_param("input")?.map(|p| request.resolve(p));
    let name = match request.str_param("name")? {
        Some(n) => n.to_string(),
        None => stem(input_path.as_deref(), "mesh"),
    };

    let mesh = input_mesh(&mut request, ctx)?;
    check_coarsening(kind, &values, &methods, &mesh)?;
    ctx.progress(0.05, "simplify", "")?;
    let mut progress = |f: f64, stage: &str| ctx.progress(0.05 + 0.8 * f, stage, "").is_ok();
    let chain = tessd_simplify::lod::lod_chain(&mesh, &methods, &options, &mut progress)
        .map_err(|e| simplify_error(e, "levels"))?;
    ctx.progress(0.85, "write", "")?;

    let levels: Vec<Value> = chain
        .iter()
        .zip(&values)
        .enumerate()
        .map(|(i, (s, goal))| {
            let mut r = report_json(&s.report);
            r["level"] = json!(i + 1);
            r["goal"] = goal.clone();
            r
        })
        .collect();
    // The goals get coarser (checked above), but what they give need not: grid cells are not
    // nested, and a tolerance may keep every vertex. Each level that keeps no fewer vertices
    // than the one before is named.
    let mut previous = chain[0].report.input_vertices;
    let mut warnings: Vec<String> = Vec::new();
    for (i, (s, goal)) in chain.iter().zip(&values).enumerate() {
        let kept = s.report.output_vertices;
        if kept >= previous {
            warnings.push(format!(
                "LOD{} (goal {}) has {kept} vertices, not fewer than LOD{i}'s {previous}: it is \
                 no coarser than the level before it",
                i + 1,
                shown(goal)
            ));
        }
        previous = kept;
    }
    let mut result = json!({
        "method": kind.name(),
        "lod_schema": match schema {
            Schema::Variants => "variants",
            Schema::UsdLod => "usdlod",
        },
        "input_vertices": chain[0].report.input_vertices,
        "input_faces": chain[0].report.input_faces,
        "lod0": {"points": mesh.positions.len(), "faces": mesh.face_count()},
        "levels": levels,
        "warnings": warnings,
    });

    let meshes: Vec<&Mesh> = std::iter::once(&mesh)
        .chain(chain.iter().map(|s| &s.mesh))
        .collect();
    let mut files: Vec<PathBuf> = Vec::new();
    // What the files cannot hold (the levels themselves carry everything: see each level's
    // report); every level holds what LOD0 holds.
    let mut dropped: Vec<String> = Vec::new();
    if let Some(path) = &output {
        dropped = merge_names(dropped, file_dropped(&mesh, path));
        let prim = MeshPrimOptions::default().with_name(name.clone());
        let lod = LodSchemaOptions::default().with_default_index(default_index);
        tessd_usd::write_usda_file(path, |w| match schema {
            Schema::Variants => tessd_usd::write_lod_variants(w, &stage, &meshes, &prim),
            Schema::UsdLod => tessd_usd::write_lod_schema(w, &stage, &meshes, &prim, &lod),
        })
        .map_err(usd_error)?;
        result["output"] = json!(path.display().to_string());
        files.push(path.clone());
    }
    if let Some(dir) = &per_level {
        let base = stem(output.as_deref(), &name);
        let written = std::fs::create_dir_all(dir)
            .map_err(|e| OpError::new(ErrorCode::Io, format!("{}: {e}", dir.display())))
            .and_then(|()| {
                let mut paths = Vec::new();
                for (i, m) in meshes.iter().enumerate() {
                    let path = dir.join(format!("{base}_LOD{i}.{format}"));
                    if let Err(e) = write_mesh_file(&request, m, &path, &format!("{name}_LOD{i}")) {
                        remove_all(&paths);
                        return Err(e);
                    }
                    dropped = merge_names(std::mem::take(&mut dropped), file_dropped(m, &path));
                    paths.push(path);
                }
                Ok(paths)
            });
        match written {
            Ok(paths) => {
                result["per_level_files"] = json!(
                    paths
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                );
                files.extend(paths);
            }
            Err(e) => {
                remove_all(&files);
                return Err(e);
            }
        }
    }
    result["dropped_attributes"] = json!(dropped);
    let mut arrays = Vec::new();
    if return_arrays || (output.is_none() && per_level.is_none()) {
        for (i, s) in chain.into_iter().enumerate() {
            arrays.extend(mesh_to_prefixed_arrays(s.mesh, &format!("lod{}.", i + 1)));
        }
    }
    // The files are written: a cancel arriving now is too late to undo them.
    let _ = ctx.progress(1.0, "done", "");
    Ok(Response {
        result,
        arrays,
        files,
    })
}
