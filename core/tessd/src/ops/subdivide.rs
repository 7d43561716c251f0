//! `subdivide`: uniform refinement (`tessd-subdiv`): the topology phase builds stencil tables
//! once, the apply phase evaluates them on the cage; the refined mesh as a file or arrays.
//!
//! Parameters are described in docs/protocol.md ("subdivide").

use super::common::{
    check_mesh_output, check_stage_options, file_dropped, is_usda, merge_names, stage_options,
    stem, write_mesh_file,
};
use super::library_errors::usd_error;
use super::mesh_arrays::{input_mesh, mesh_to_arrays};
use super::params::paths::output_path;
use super::params::scalars::{as_u64, bool_param};
use serde_json::json;
use std::time::Instant;
use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_mesh::Mesh;
use tessd_subdiv::{Boundary, Refiner, Scheme, SubdivError, SubdivOptions, UvInterpolation};
use tessd_usd::{MeshPrim, MeshPrimOptions, SubdivisionScheme};

/// The largest `levels` accepted (the memory estimate refuses most meshes well before).
pub const MAX_LEVELS: u64 = 10;

/// Maps a refinement error to its protocol code.
pub fn subdiv_error(e: SubdivError) -> OpError {
    let code = match e {
        SubdivError::TooLarge { .. } => ErrorCode::TooLarge,
        SubdivError::InvalidOption(_) => ErrorCode::InvalidRequest,
        _ => ErrorCode::InvalidMesh,
    };
    OpError::new(code, e.to_string())
}

/// Reads `scheme`, `levels`, `boundary`, `uv_interpolation` and `normals`.
///
/// # Errors
/// `invalid_request` naming the parameter.
pub fn parse_options(request: &Request) -> Result<SubdivOptions, OpError> {
    let name = request.str_param("scheme")?.unwrap_or("catmull-clark");
    let scheme = Scheme::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Scheme::ALL.iter().map(|s| s.name()).collect();
        OpError::request(format!(
            "`scheme` must be one of {}, got {name:?}",
            names.join(", ")
        ))
    })?;
    let levels = match request.params.get("levels") {
        None => 1,
        Some(v) => as_u64(v)
            .filter(|n| (1..=MAX_LEVELS).contains(n))
            .ok_or_else(|| {
                OpError::request(format!(
                    "`levels` must be an integer from 1 to {MAX_LEVELS}, got {v}"
                ))
            })?,
    };
    let boundary = match request.str_param("boundary")?.unwrap_or("edge-only") {
        "edge-only" => Boundary::EdgeOnly,
        "edge-and-corner" => Boundary::EdgeAndCorner,
        other => {
            return Err(OpError::request(format!(
                "`boundary` must be \"edge-only\" or \"edge-and-corner\", got {other:?}"
            )));
        }
    };
    let uv_interpolation = match request.str_param("uv_interpolation")? {
        None => UvInterpolation::default(),
        Some(name) => UvInterpolation::from_name(name).ok_or_else(|| {
            let names: Vec<&str> = UvInterpolation::ALL.iter().map(|u| u.name()).collect();
            OpError::request(format!(
                "`uv_interpolation` must be one of {}, got {name:?}",
                names.join(", ")
            ))
        })?,
    };
    Ok(SubdivOptions {
        scheme,
        levels: levels as u32,
        boundary,
        uv_interpolation,
        normals: bool_param(request, "normals")?.unwrap_or(true),
        ..SubdivOptions::default()
    })
}

/// What a `.usda` output holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum UsdOutput {
    /// The refined mesh.
    Refined,
    /// The cage, with `subdivisionScheme` and its rules, for USD consumers to refine.
    Cage,
}

/// The operation.
///
/// # Errors
/// Bad options (`invalid_request`), bad cages or frames (`invalid_mesh`, naming the element),
/// outputs estimated too large (`too_large`, before allocating), `unsupported` for a cage in
/// USD with a scheme USD cannot name, `io` when writing fails.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let mut options = parse_options(&request)?;
    // the refiner's own estimate of its tables and output, held to the daemon's per-job limit
    options.memory_limit = options.memory_limit.min(ctx.limits().max_job_memory);
    let gpu = bool_param(&request, "gpu")?.unwrap_or(false);
    let output = output_path(&request)?;
    if let Some(path) = output.as_deref() {
        check_mesh_output(path)?;
        // Bad stage options are refused before the work, not when writing.
        check_stage_options(&request)?;
    }
    let usd = match request.str_param("usd")?.unwrap_or("refined") {
        "refined" => UsdOutput::Refined,
        "cage" => UsdOutput::Cage,
        other => {
            return Err(OpError::request(format!(
                "`usd` must be \"refined\" or \"cage\", got {other:?}"
            )));
        }
    };
    let cage = input_mesh(&mut request, ctx)?;
    let frames = read_frames(&request, cage.vertex_count())?;
    if frames.is_some() && output.as_deref().is_some_and(|p| !is_usda(p)) {
        return Err(OpError::request(
            "`frames` need a .usda `output` (points as time samples) or no `output` (arrays)",
        ));
    }
    let name = match request.str_param("name")? {
        Some(n) => n.to_string(),
        None => stem(output.as_deref(), "mesh"),
    };
    if usd == UsdOutput::Cage {
        return write_cage(&request, &cage, &options, output, frames, &name, ctx);
    }
    ctx.progress(0.1, "topology", "")?;
    let t = Instant::now();
    let refiner = Refiner::new(&cage, &options).map_err(subdiv_error)?;
    let topology_ms = t.elapsed().as_secs_f64() * 1e3;
    ctx.progress(0.3, "apply", "")?;
    let mut apply = Apply::new(&refiner, gpu)?;
    let positions = apply.run(&cage.positions)?;
    let mut frame_ms = Vec::new();
    let refined_frames = match &frames {
        None => None,
        Some(frames) => {
            let mut out = Vec::with_capacity(frames.len());
            for (k, f) in frames.iter().enumerate() {
                ctx.progress(
                    0.3 + 0.5 * k as f64 / frames.len() as f64,
                    "apply",
                    &format!("frame {} of {}", k + 1, frames.len()),
                )?;
                let t = Instant::now();
                out.push(apply.run(f)?);
                frame_ms.push(t.elapsed().as_secs_f64() * 1e3);
            }
            Some(out)
        }
    };
    // Normals follow the rest pose only; animated output leaves shading normals to the host.
    let mesh_options = SubdivOptions {
        normals: options.normals && frames.is_none(),
        ..options.clone()
    };
    let mesh = refiner
        .mesh_with(&cage, positions, &mesh_options)
        .map_err(subdiv_error)?;
    let mut result = json!({
        "scheme": options.scheme.name(),
        "levels": options.levels,
        "uv_interpolation": mesh.uvs.as_ref().map(|_| options.uv_interpolation.name()),
        "cage_vertices": cage.vertex_count(),
        "cage_faces": cage.face_count(),
        "vertices": mesh.vertex_count(),
        "faces": mesh.face_count(),
        "topology_ms": topology_ms,
        "apply_ms": apply.first_ms + frame_ms.iter().sum::<f64>(),
        "gpu": apply.device(),
        "dropped_attributes": tessd_subdiv::attributes::dropped(&cage, &options),
    });
    if let Some(f) = &frames {
        result["frames"] = json!(f.len());
        result["apply_ms_per_frame"] = json!(median(&mut frame_ms));
    }
    match output {
        Some(path) => {
            ctx.progress(0.8, "write", "")?;
            write_refined(&request, &mesh, refined_frames.as_deref(), &path, &name)?;
            ctx.progress(1.0, "done", "")?;
            result["output"] = json!(path.display().to_string());
            result["dropped_attributes"] = json!(merge_names(
                tessd_subdiv::attributes::dropped(&cage, &options),
                file_dropped(&mesh, &path)
            ));
            Ok(Response {
                result,
                files: vec![path],
                ..Response::default()
            })
        }
        None => {
            let mut arrays = mesh_to_arrays(mesh);
            if let Some(frames) = refined_frames {
                let (n, v) = (
                    frames.len() as u64,
                    frames.first().map_or(0, Vec::len) as u64,
                );
                let flat: Vec<f32> = frames.into_iter().flatten().flatten().collect();
                arrays.push(OwnedArray::new("frame_positions", vec![n, v, 3], flat));
            }
            Ok(Response {
                result,
                arrays,
                files: Vec::new(),
            })
        }
    }
}

/// The animation frames: the optional array `frames`, f32 of shape [frames, cage vertices, 3].
///
/// # Errors
/// `invalid_request` for a wrong dtype or shape, `invalid_mesh` for another vertex count or a
/// non-finite coordinate (naming the frame and vertex).
fn read_frames(request: &Request, vertices: usize) -> Result<Option<Vec<Vec<[f32; 3]>>>, OpError> {
    let Some(view) = request.arrays.get::<f32>("frames") else {
        return Ok(None);
    };
    let (data, shape) = view.map_err(OpError::request)?;
    if shape.len() != 3 || shape[2] != 3 || shape[0] == 0 {
        return Err(OpError::request(format!(
            "array \"frames\" must have shape [frames ≥ 1, vertices, 3], got {shape:?}"
        )));
    }
    if shape[1] as usize != vertices {
        return Err(subdiv_error(SubdivError::VertexCount {
            what: "each frame of `frames`".to_string(),
            got: shape[1] as usize,
            expected: vertices,
        }));
    }
    let rows: &[[f32; 3]] = bytemuck::cast_slice(data);
    if let Some(i) = rows.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(OpError::new(
            ErrorCode::InvalidMesh,
            format!(
                "frame {}, vertex {}: coordinate is not finite",
                i / vertices,
                i % vertices
            ),
        ));
    }
    Ok(Some(rows.chunks(vertices).map(<[_]>::to_vec).collect()))
}

/// The apply phase on the CPU or, with `gpu`, on the device (tables uploaded once for all
/// frames).
struct Apply<'a> {
    refiner: &'a Refiner,
    gpu: Option<(tessd_gpu::GpuStencils, tessd_gpu::GpuTables)>,
    /// Time of the first application (the cage's positions), ms.
    first_ms: f64,
    runs: usize,
    /// Level buffers reused from frame to frame on the CPU.
    levels: Vec<Vec<f32>>,
}

impl<'a> Apply<'a> {
    fn new(refiner: &'a Refiner, gpu: bool) -> Result<Apply<'a>, OpError> {
        let gpu = if gpu {
            let device = tessd_gpu::GpuStencils::new().map_err(gpu_error)?;
            let tables = device.upload(&refiner.tables).map_err(gpu_error)?;
            Some((device, tables))
        } else {
            None
        };
        Ok(Apply {
            refiner,
            gpu,
            first_ms: 0.0,
            runs: 0,
            levels: Vec::new(),
        })
    }

    fn run(&mut self, positions: &[[f32; 3]]) -> Result<Vec<[f32; 3]>, OpError> {
        let t = Instant::now();
        let out = match &self.gpu {
            Some((device, tables)) => {
                let flat = device
                    .apply(tables, positions.as_flattened(), 3)
                    .map_err(gpu_error)?;
                flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
            }
            None => self
                .refiner
                .apply_into(positions.as_flattened(), 3, "the cage", &mut self.levels)
                .map_err(subdiv_error)?
                .as_chunks::<3>()
                .0
                .to_vec(),
        };
        if self.runs == 0 {
            self.first_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        self.runs += 1;
        Ok(out)
    }

    /// The adapter's description, when on the GPU.
    fn device(&self) -> Option<String> {
        self.gpu.as_ref().map(|(d, _)| d.adapter_info())
    }
}

fn gpu_error(e: tessd_gpu::GpuError) -> OpError {
    OpError::new(ErrorCode::Unsupported, format!("GPU apply: {e}"))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

/// Writes the refined mesh; with frames (a `.usda` output, checked before), its points as
/// time samples.
fn write_refined(
    request: &Request,
    mesh: &Mesh,
    frames: Option<&[Vec<[f32; 3]>]>,
    path: &std::path::Path,
    name: &str,
) -> Result<(), OpError> {
    match frames {
        None => write_mesh_file(request, mesh, path, name),
        Some(frames) => {
            let stage = stage_options(request)?;
            let prim = MeshPrim::new(mesh)
                .with_options(MeshPrimOptions::default().with_name(name))
                .with_point_samples(frames);
            tessd_usd::write_usda_file(path, |w| tessd_usd::write_stage(w, &stage, &[prim]))
                .map_err(usd_error)
        }
    }
}

/// `usd: "cage"`: checks the cage refines (one level: named errors for bad cages), then
/// writes it to the `.usda` output with `subdivisionScheme`, `interpolateBoundary` and
/// `faceVaryingLinearInterpolation` set from the options, frames as time samples.
fn write_cage(
    request: &Request,
    cage: &Mesh,
    options: &SubdivOptions,
    output: Option<std::path::PathBuf>,
    frames: Option<Vec<Vec<[f32; 3]>>>,
    name: &str,
    ctx: &JobContext,
) -> Result<Response, OpError> {
    let Some(path) = output.filter(|p| is_usda(p)) else {
        return Err(OpError::request("`usd: \"cage\"` needs a .usda `output`"));
    };
    let scheme = match options.scheme {
        Scheme::CatmullClark => SubdivisionScheme::CatmullClark,
        Scheme::Loop => SubdivisionScheme::Loop,
        Scheme::Bilinear => SubdivisionScheme::Bilinear,
        other => {
            return Err(OpError::new(
                ErrorCode::Unsupported,
                format!(
                    "USD has no subdivisionScheme for {}; write the refined mesh instead (usd: \"refined\")",
                    other.name()
                ),
            ));
        }
    };
    ctx.progress(0.2, "check", "")?;
    Refiner::new(
        cage,
        &SubdivOptions {
            levels: 1,
            ..options.clone()
        },
    )
    .map_err(subdiv_error)?;
    let boundary = match options.boundary {
        Boundary::EdgeOnly => "edgeOnly",
        Boundary::EdgeAndCorner => "edgeAndCorner",
    };
    let fvar = match options.uv_interpolation {
        UvInterpolation::Linear => "all",
        UvInterpolation::Corners => "cornersOnly",
        UvInterpolation::CornersJunctions => "cornersPlus1",
        UvInterpolation::CornersJunctionsConcave => "cornersPlus2",
        UvInterpolation::Boundaries => "boundaries",
        UvInterpolation::Smooth => "none",
    };
    ctx.progress(0.6, "write", "")?;
    let stage = stage_options(request)?;
    let mut prim = MeshPrim::new(cage).with_options(
        MeshPrimOptions::default()
            .with_name(name)
            .with_subdivision_scheme(Some(scheme))
            .with_cage_rules(boundary, fvar),
    );
    if let Some(f) = frames.as_deref() {
        prim = prim.with_point_samples(f);
    }
    tessd_usd::write_usda_file(&path, |w| tessd_usd::write_stage(w, &stage, &[prim]))
        .map_err(usd_error)?;
    ctx.progress(1.0, "done", "")?;
    let mut result = json!({
        "scheme": options.scheme.name(),
        "levels": options.levels,
        "usd": "cage",
        "cage_vertices": cage.vertex_count(),
        "cage_faces": cage.face_count(),
        "output": path.display().to_string(),
        "dropped_attributes": file_dropped(cage, &path),
    });
    if let Some(f) = &frames {
        result["frames"] = json!(f.len());
    }
    Ok(Response {
        result,
        files: vec![path],
        ..Response::default()
    })
}
