//! Helpers several operations share: typed parameters, USD stage options, writing a mesh to
//! the format its path names.

use super::library_errors::{mesh_error, usd_error};
use super::mesh_arrays::{admit_mesh, read_mesh_file, read_options};
use super::params::lengths::mesh_units;
use std::path::{Path, PathBuf};
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::Request;
use tessd_mesh::Mesh;
use tessd_usd::{MeshPrimOptions, StageOptions, UpAxis};

/// Whether `path` names a USD stage (`.usda`, any case).
pub fn is_usda(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("usda"))
}

/// Refuses an output path whose format tessd cannot write, before any work is done.
///
/// # Errors
/// `unsupported` naming the extension.
pub fn check_mesh_output(path: &Path) -> Result<(), OpError> {
    if is_usda(path) {
        Ok(())
    } else {
        tessd_mesh::io::Format::from_path(path)
            .map(|_| ())
            .map_err(mesh_error)
    }
}

/// The stage options of a request that writes a USD stage. Each of `params.up_axis`
/// (`"Y"`/`"Z"`) and `params.meters_per_unit` that the request gives wins; one it leaves out
/// comes from what the input says, so that a converted, simplified or subdivided model keeps
/// its size and orientation in every USD tool:
/// - `meters_per_unit`: the mesh's unit `params.units` (mm: 0.001), else an input `.usda`
///   stage's own `metersPerUnit`, else 1;
/// - `up_axis`: an input `.usda` stage's own `upAxis`, else Z.
///
/// # Errors
/// `invalid_request` for another axis, a mistyped, non-finite or non-positive value, or an
/// unknown `units`.
pub fn stage_options(request: &Request) -> Result<StageOptions, OpError> {
    let (up, meters_per_unit) = explicit_stage_options(request)?;
    let mesh_unit = mesh_units(request)?.map(tessd_brep::Units::meters_per_unit);
    // Only a missing option sends us to the input stage (parsed again: its layer metadata is
    // not part of the mesh read from it).
    let input_stage = if up.is_none() || (meters_per_unit.is_none() && mesh_unit.is_none()) {
        input_stage_conventions(request)
    } else {
        (None, None)
    };
    Ok(StageOptions::default()
        .with_up_axis(up.or(input_stage.0).unwrap_or(UpAxis::Z))
        .with_meters_per_unit(
            meters_per_unit
                .or(mesh_unit)
                .or(input_stage.1)
                .unwrap_or(1.0),
        ))
}

/// Refuses bad stage options before the work is done, without looking at the input
/// ([`stage_options`] is called again when the stage is written).
///
/// # Errors
/// As [`stage_options`].
pub fn check_stage_options(request: &Request) -> Result<(), OpError> {
    explicit_stage_options(request).map(|_| ())
}

/// As [`stage_options`], with `default_meters_per_unit` when the request names none: a B-Rep's
/// own units (millimetres: 0.001), so that a part keeps its size in every USD tool.
///
/// # Errors
/// As [`stage_options`].
pub fn stage_options_in(
    request: &Request,
    default_meters_per_unit: f64,
) -> Result<StageOptions, OpError> {
    let (up, meters_per_unit) = explicit_stage_options(request)?;
    Ok(StageOptions::default()
        .with_up_axis(up.unwrap_or(UpAxis::Z))
        .with_meters_per_unit(meters_per_unit.unwrap_or(default_meters_per_unit)))
}

/// `params.up_axis` and `params.meters_per_unit` as the request gives them (checked).
fn explicit_stage_options(request: &Request) -> Result<(Option<UpAxis>, Option<f64>), OpError> {
    let up = match request.str_param("up_axis")? {
        None => None,
        Some("Z") | Some("z") => Some(UpAxis::Z),
        Some("Y") | Some("y") => Some(UpAxis::Y),
        Some(other) => {
            return Err(OpError::request(format!(
                "`up_axis` must be \"Y\" or \"Z\", got {other:?}"
            )));
        }
    };
    let meters_per_unit = match request.f64_param("meters_per_unit")? {
        None => None,
        Some(m) if m.is_finite() && m > 0.0 => Some(m),
        Some(m) => {
            return Err(OpError::request(format!(
                "`meters_per_unit` must be a positive number of metres per unit (millimetres: \
                 0.001), got {m}"
            )));
        }
    };
    Ok((up, meters_per_unit))
}

/// The `upAxis` and `metersPerUnit` an input `.usda` stage (`params.input`) authors, each
/// `None` when it authors none, the input is no stage, or it cannot be read (reading the
/// input itself reports that).
fn input_stage_conventions(request: &Request) -> (Option<UpAxis>, Option<f64>) {
    let Ok(Some(input)) = request.str_param("input") else {
        return (None, None);
    };
    let path = request.resolve(input);
    if !super::mesh_arrays::is_usd_input(&path) {
        return (None, None);
    }
    let Ok(stage) = tessd_usd::read_usda(&path) else {
        return (None, None);
    };
    let up = match stage.up_axis.as_deref() {
        Some("Y") => Some(UpAxis::Y),
        Some("Z") => Some(UpAxis::Z),
        _ => None,
    };
    let meters_per_unit = stage.meters_per_unit.filter(|m| m.is_finite() && *m > 0.0);
    (up, meters_per_unit)
}

/// The file stem of `path`, or `fallback`.
pub fn stem(path: Option<&Path>, fallback: &str) -> String {
    path.and_then(Path::file_stem)
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| fallback.to_string())
}

/// Writes `mesh` to `path` atomically: a USD stage for `.usda` (stage options from the
/// request, the mesh prim named `name`), else the mesh format of the extension.
///
/// # Errors
/// `unsupported`, `io`, `invalid_mesh`, `invalid_request` as the writers say.
pub fn write_mesh_file(
    request: &Request,
    mesh: &Mesh,
    path: &Path,
    name: &str,
) -> Result<(), OpError> {
    if is_usda(path) {
        let stage = stage_options(request)?;
        let prim = MeshPrimOptions::default().with_name(name);
        tessd_usd::write_usda_file(path, |w| {
            tessd_usd::write_mesh_stage(w, mesh, &stage, &prim)
        })
        .map_err(usd_error)
    } else {
        tessd_mesh::io::write_path(mesh, path).map_err(mesh_error)
    }
}

/// What writing `mesh` to `path` with [`write_mesh_file`] leaves out, by protocol name (the
/// results' `dropped_attributes`): for a USD stage, sharp edges; for OBJ / PLY / STL / OFF,
/// what the format cannot hold ([`tessd_mesh::io::dropped_by_format`]).
pub fn file_dropped(mesh: &Mesh, path: &Path) -> Vec<String> {
    if is_usda(path) {
        tessd_usd::dropped_by_usd(mesh, &MeshPrimOptions::default())
    } else {
        tessd_mesh::io::Format::from_path(path)
            .map(|f| tessd_mesh::io::dropped_by_format(mesh, f))
            .unwrap_or_default()
    }
}

/// `a` followed by the names of `b` it does not hold yet.
pub fn merge_names(mut a: Vec<String>, b: Vec<String>) -> Vec<String> {
    for name in b {
        if !a.contains(&name) {
            a.push(name);
        }
    }
    a
}

/// Reads the mesh file named by the string parameter `key` (resolved against the request's
/// folder; a `.usda` stage as [`read_mesh_file`] reads it), stopping early when the job is
/// cancelled.
///
/// # Errors
/// `invalid_request` when the parameter is missing; as the reader says otherwise.
pub fn read_mesh_param(
    request: &Request,
    key: &str,
    ctx: &JobContext,
) -> Result<(Mesh, PathBuf), OpError> {
    let path = request
        .str_param(key)?
        .map(|p| request.resolve(p))
        .ok_or_else(|| OpError::request(format!("`{key}` (a mesh file path) is required")))?;
    let mesh = read_mesh_file(&path, &read_options(ctx))?;
    admit_mesh(&mesh, &format!("`{key}`"), ctx)?;
    Ok((mesh, path))
}

/// `x` to 4 significant digits without trailing zeros (`0.01234`, `24.6`, `0.05`): lengths and
/// goals in messages and summaries.
pub fn significant(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return x.to_string();
    }
    let decimals = (3 - x.abs().log10().floor() as i64).clamp(0, 17) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}
