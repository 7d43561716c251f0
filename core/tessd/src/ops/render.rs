//! `render`: a picture of a mesh or a B-Rep part (`tessd-render`, issue 21): colour, depth,
//! face ids and (u, v) rendered headless on the GPU (lavapipe without one), as PNG files or
//! arrays. Meshes are rasterised as they are; B-Rep documents go through paper 001's pipeline
//! — per-frame tessellation of the basis surfaces, GPU trimming with the trim quadtree (paper
//! 000), crack detection and `cracks` filling (`object` by default) — or, with `raycast`,
//! through full-scene ray casting.
//!
//! Parameters are described in docs/protocol.md ("render").

use super::common::stem;
use super::library_errors::{brep_error, render_error, usd_error};
use super::mesh_arrays::{input_mesh, is_usd_input, read_mesh_file, read_options};
use super::params::brep_input::{is_brep_path, request_brep};
use super::params::camera::{parse_size, vec3_param};
use super::params::lengths::{Tolerance, parse_tolerance};
use super::params::paths::output_path;
use super::params::scalars::{bool_param, u64_param};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_mesh::Mesh;
use tessd_render::camera::{DEFAULT_FOV, UpAxis, Vec3};
use tessd_render::{
    Bounds, BrepReport, BrepScene, Camera, Cracks, Frame, RenderError, RenderSettings, Renderer,
    Scene, Shading, StepTimings, View, panels,
};

/// The most turntable frames.
pub const MAX_FRAMES: u64 = 3600;

/// The most panels side by side.
pub const MAX_PANELS: usize = 64;

/// The process's renderer: opening a device and compiling the shaders costs ~100 ms on a GPU
/// and far more on lavapipe, so the daemon does it once, on the first render. A failure is
/// not kept: a later request tries again.
fn renderer() -> Result<Arc<Renderer>, OpError> {
    static RENDERER: Mutex<Option<Arc<Renderer>>> = Mutex::new(None);
    let mut slot = RENDERER.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(r) = slot.as_ref() {
        return Ok(r.clone());
    }
    let r = Arc::new(Renderer::new().map_err(render_error)?);
    *slot = Some(r.clone());
    Ok(r)
}

/// How the camera is given: a standard view, or an explicit eye (with target and up).
#[derive(Clone, Copy, Debug)]
enum CameraSpec {
    View(View),
    Explicit {
        eye: [f64; 3],
        target: Option<[f64; 3]>,
        up: Option<[f64; 3]>,
    },
}

/// Everything a request asks for, parsed and checked before any work.
struct Params {
    width: u32,
    height: u32,
    /// B-Rep parts: crack handling (paper 001 §3.3–3.4).
    cracks: Cracks,
    /// B-Rep parts: full-scene ray casting instead of the raster pipeline.
    raycast: bool,
    spec: CameraSpec,
    /// `up_axis`: the world's up axis for the standard views, when given (else the stage's,
    /// else Z).
    up_axis: Option<UpAxis>,
    fov: f64,
    settings: RenderSettings,
    frames: u32,
    /// Columns of the panel grid (several meshes); `None`: [`panels::default_columns`].
    columns: Option<usize>,
    output: Option<PathBuf>,
    face_ids: Option<PathBuf>,
}

fn parse(request: &Request) -> Result<Params, OpError> {
    let cracks = match request.str_param("cracks")? {
        None => Cracks::Object,
        Some(c) => Cracks::parse(c).ok_or_else(|| {
            OpError::request(format!(
                "`cracks` must be \"none\", \"image\" or \"object\", got {c:?}"
            ))
        })?,
    };
    let raycast = bool_param(request, "raycast")?.unwrap_or(false);
    let (width, height) = parse_size(request.params.get("size"))?;
    let fov = request.f64_param("fov")?.unwrap_or(DEFAULT_FOV);
    if !(fov > 0.0 && fov < 180.0) {
        return Err(OpError::request(format!(
            "`fov` must be a vertical field of view in degrees between 0 and 180, got {fov}"
        )));
    }
    let shading = match request.str_param("shading")? {
        None => Shading::Lit,
        Some(s) => Shading::parse(s).ok_or_else(|| {
            OpError::request(format!(
                "`shading` must be \"lit\", \"gooch\", \"toon\" or \"face-ids\", got {s:?}"
            ))
        })?,
    };
    let edges = bool_param(request, "edges")?.unwrap_or(false);
    let eye = vec3_param(request, "eye")?;
    let target = vec3_param(request, "target")?;
    let up = vec3_param(request, "up")?;
    let view = request.str_param("view")?;
    let spec = match (view, eye) {
        (Some(_), Some(_)) => {
            return Err(OpError::request(
                "give a standard `view` or an explicit `eye` (with `target`, `up`), not both",
            ));
        }
        (_, Some(eye)) => CameraSpec::Explicit { eye, target, up },
        (view, None) => {
            if target.is_some() || up.is_some() {
                return Err(OpError::request(
                    "`target` and `up` go with an explicit `eye`",
                ));
            }
            let view = match view {
                None => View::Iso,
                Some(v) => View::parse(v).ok_or_else(|| {
                    OpError::request(format!(
                        "`view` must be one of iso, front, back, left, right, top, bottom, got {v:?}"
                    ))
                })?,
            };
            CameraSpec::View(view)
        }
    };
    let up_axis = match request.str_param("up_axis")? {
        None => None,
        Some(a) => Some(UpAxis::parse(a).ok_or_else(|| {
            OpError::request(format!("`up_axis` must be \"Y\" or \"Z\", got {a:?}"))
        })?),
    };
    let output = output_path(request)?;
    let face_ids = request.str_param("face_ids")?.map(|p| request.resolve(p));
    for (key, path) in [("output", &output), ("face_ids", &face_ids)] {
        if let Some(p) = path
            && !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))
        {
            return Err(OpError::new(
                ErrorCode::Unsupported,
                format!("`{key}` must be a .png file, got {}", p.display()),
            ));
        }
    }
    let frames = match u64_param(request, "turntable")? {
        None => 1,
        Some(n) if (1..=MAX_FRAMES).contains(&n) => n as u32,
        Some(n) => {
            return Err(OpError::request(format!(
                "`turntable` must be a number of frames from 1 to {MAX_FRAMES}, got {n}"
            )));
        }
    };
    if request
        .params
        .get("turntable")
        .is_some_and(|v| !v.is_null())
        && output.is_none()
    {
        return Err(OpError::request(
            "`turntable` writes files OUT_000.png, ...: it needs `output`",
        ));
    }
    let columns = match u64_param(request, "columns")? {
        None => None,
        Some(n) if (1..=MAX_PANELS as u64).contains(&n) => Some(n as usize),
        Some(n) => {
            return Err(OpError::request(format!(
                "`columns` must be from 1 to {MAX_PANELS}, got {n}"
            )));
        }
    };
    Ok(Params {
        width,
        height,
        columns,
        cracks,
        raycast,
        spec,
        up_axis,
        fov,
        settings: RenderSettings::new(width, height)
            .with_shading(shading)
            .with_edges(edges),
        frames,
        output,
        face_ids,
    })
}

/// The cameras of the frames: the view fitted to `bounds` (in a world whose up axis is
/// `axis`) or the explicit eye, turned about the up axis through the target for a turntable.
fn cameras(p: &Params, axis: UpAxis, bounds: &Bounds) -> Result<Vec<Camera>, OpError> {
    let aspect = p.settings.aspect();
    let base = match p.spec {
        CameraSpec::View(v) => Camera::fit_up(v, axis, bounds, p.fov, aspect),
        CameraSpec::Explicit { eye, target, up } => {
            let eye = Vec3::from(eye);
            let target = target.map_or_else(|| bounds.center(), Vec3::from);
            let up = up.map_or_else(
                || {
                    // The up axis, unless the view is along it (then the top view's up).
                    let d = tessd_render::camera::normalize(target - eye);
                    if d.dot(axis.vector()).abs() > 0.999 {
                        axis.from_z_up(Vec3::Y)
                    } else {
                        axis.vector()
                    }
                },
                Vec3::from,
            );
            Camera::new(eye, target, up, p.fov)
        }
    };
    base.check().map_err(render_error)?;
    Ok((0..p.frames)
        .map(|i| {
            let angle = std::f64::consts::TAU * i as f64 / p.frames as f64;
            base.orbit(angle).clipped_to(bounds)
        })
        .collect())
}

/// Everything `render` does with a request before it reads the input or opens the GPU: parses
/// and checks the parameters, then places the frames' cameras (the standard view fitted to
/// `bounds`, or the explicit eye; one per turntable frame) around a part inside `bounds`. The
/// fuzzer's entry to the op's parameters (fuzz/fuzz_targets/render_params.rs).
///
/// # Errors
/// As [`run`] for bad parameters: `invalid_request` naming the parameter and the value,
/// `unsupported` for outputs that are not `.png`.
pub fn plan_cameras(request: &Request, bounds: &Bounds) -> Result<Vec<Camera>, OpError> {
    let p = parse(request)?;
    cameras(&p, p.up_axis.unwrap_or_default(), bounds)
}

/// One mesh panel: its label (file stem, or LOD variant), triangles on the device and count.
struct MeshPanel {
    label: String,
    gpu: tessd_render::GpuScene,
    triangles: usize,
}

/// What is drawn: meshes (one panel each, tiled side by side when several), or a B-Rep part.
enum Part {
    Meshes(Vec<MeshPanel>),
    Brep(Box<tessd_render::GpuBrepScene>),
}

/// The panels of a mesh render, and the up axis their USD stages author.
type Panels = (Vec<(String, Mesh)>, Option<UpAxis>);

/// The meshes of a mesh render, labelled: `input` as a list of files gives one panel per file
/// (a LOD chain, a cage beside its subdivided surface); one USD stage one panel per level of
/// its LOD chain (the variants of its first variant set that holds meshes, else the levels of
/// its first `UsdLod` root: both `tessd lod` schemas), else one; any other file or the mesh
/// arrays one panel. With them, the `upAxis` of the (first) USD stage that authors one.
fn mesh_panels(request: &mut Request, ctx: &JobContext) -> Result<Panels, OpError> {
    let label = |path: &Path| stem(Some(path), "mesh");
    match request.params.get("input") {
        Some(Value::Array(items)) => {
            if items.is_empty() || items.len() > MAX_PANELS {
                return Err(OpError::request(format!(
                    "`input` as a list names 1 to {MAX_PANELS} mesh files, got {}",
                    items.len()
                )));
            }
            let options = read_options(ctx);
            let mut out = Vec::with_capacity(items.len());
            let mut axis = None;
            for (i, item) in items.iter().enumerate() {
                let path = item.as_str().map(|p| request.resolve(p)).ok_or_else(|| {
                    OpError::request(format!("`input[{i}]` must be a file path, got {item}"))
                })?;
                if is_brep_path(&path) {
                    return Err(OpError::new(
                        ErrorCode::Unsupported,
                        format!(
                            "`input[{i}]` ({}) is a B-Rep document: panels side by side are                              meshes; render a B-Rep part on its own",
                            path.display()
                        ),
                    ));
                }
                ctx.checkpoint()?;
                let what = format!("`input[{i}]`");
                let mesh = if is_usd_input(&path) {
                    let stage = tessd_usd::read_usda(&path).map_err(usd_error);
                    let stage = stage.map_err(|e| prefixed(&what, e))?;
                    axis = axis.or(stage_axis(&stage));
                    stage.composed().map_err(usd_error)
                } else {
                    read_mesh_file(&path, &options)
                };
                out.push((label(&path), mesh.map_err(|e| prefixed(&what, e))?));
            }
            Ok((out, axis))
        }
        Some(Value::String(p)) if is_usd_input(Path::new(p)) => {
            let path = request.resolve(p);
            let stage = tessd_usd::read_usda(&path).map_err(usd_error)?;
            let panels = stage.variant_panels().map_err(usd_error)?;
            if panels.len() > MAX_PANELS {
                return Err(OpError::request(format!(
                    "{}: {} variants, more than the {MAX_PANELS} panels a render draws",
                    path.display(),
                    panels.len()
                )));
            }
            // Each prim's mesh is validated as the reader builds it; merging keeps it valid.
            Ok((panels, stage_axis(&stage)))
        }
        _ => {
            let name = request
                .str_param("input")?
                .map_or_else(|| "arrays".to_string(), |p| label(Path::new(p)));
            Ok((vec![(name, input_mesh(request, ctx)?)], None))
        }
    }
}

/// A stage's authored `upAxis` (`None` when absent or neither Y nor Z).
fn stage_axis(stage: &tessd_usd::UsdStage) -> Option<UpAxis> {
    stage.up_axis.as_deref().and_then(UpAxis::parse)
}

/// `error` with its message prefixed by `what`.
fn prefixed(what: &str, mut error: OpError) -> OpError {
    error.message = format!("{what}: {}", error.message);
    error
}

/// The B-Rep frames' time per step of paper 001 table 1, summed over the frames, ms.
pub fn step_timings(reports: &[BrepReport]) -> Value {
    let mut t = StepTimings::default();
    for r in reports {
        let s = &r.timings;
        t.tessellation += s.tessellation;
        t.initial += s.initial;
        t.crack_detection += s.crack_detection;
        t.image_fill += s.image_fill;
        t.depth_mask += s.depth_mask;
        t.object_fill += s.object_fill;
        t.composite += s.composite;
        t.ray_cast += s.ray_cast;
        t.readback += s.readback;
    }
    json!({
        "tessellation": ms(t.tessellation),
        "initial_render": ms(t.initial),
        "crack_detection": ms(t.crack_detection),
        "image_fill": ms(t.image_fill),
        "depth_mask": ms(t.depth_mask),
        "object_fill": ms(t.object_fill),
        "composite": ms(t.composite),
        "ray_cast": ms(t.ray_cast),
        "readback": ms(t.readback),
        "frame": ms(t.frame()),
    })
}

/// `OUT.png` for one frame, `OUT_007.png` for frame 7 of a turntable.
fn frame_path(path: &Path, frame: u32, frames: u32) -> PathBuf {
    if frames == 1 {
        return path.to_path_buf();
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}_{frame:03}.png"))
}

/// Removes already written files when a later one fails (best effort).
struct Written(Vec<PathBuf>);

impl Drop for Written {
    fn drop(&mut self) {
        for p in &self.0 {
            let _ = std::fs::remove_file(p);
        }
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn point(v: Vec3) -> Value {
    json!(v.to_array())
}

/// The inputs gathered for drawing: the part on the device, its cameras, and the time each
/// step took (`prepare`: a B-Rep's trim structures; `device`: opening the renderer).
struct Gathered {
    part: Part,
    cams: Vec<Camera>,
    prepare_ms: f64,
    device_ms: f64,
    upload_ms: f64,
}

/// The frames drawn: the files written, and what the result reports of them.
struct Rendered {
    files: Vec<PathBuf>,
    /// Pixels covered, per frame.
    covered: Vec<usize>,
    /// B-Rep parts: each frame's pipeline report.
    steps: Vec<BrepReport>,
    draw: Duration,
    readback: Duration,
    encode: Duration,
    /// The last frame, returned as arrays when no file is asked for.
    last: Option<Frame>,
}

/// The operation, in its steps: parse the request, gather the inputs (planning the cameras
/// on their bounds), render and write each frame, then describe it all.
///
/// # Errors
/// `invalid_request` for bad parameters (naming them and the value), `unsupported` for
/// outputs that are not `.png`; as `brep.load` and the mesh ops for the input; `internal`
/// when the GPU fails; `cancelled`.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    let total = Instant::now();
    ctx.progress(0.0, "read", "")?;
    let p = parse(&request)?;
    let mut result = json!({});
    let gathered = if is_brep_request(&request) {
        gather_brep(&mut request, &p, ctx, &mut result)?
    } else {
        gather_meshes(&mut request, &p, ctx, &mut result)?
    };
    let renderer = renderer()?;
    let rendered = render_frames(&renderer, &p, &gathered, ctx)?;
    describe(&mut result, &renderer, &p, &gathered, &rendered);
    result["timings_ms"]["total"] = json!(ms(total.elapsed()));
    ctx.progress(1.0, "done", "")?;
    Ok(Response {
        result,
        arrays: frame_arrays(&p, rendered.last),
        files: rendered.files,
    })
}

/// Whether the input is a B-Rep document (`brep`, or an `input` naming a B-Rep file) rather
/// than a mesh.
fn is_brep_request(request: &Request) -> bool {
    request.params.get("brep").is_some_and(|v| !v.is_null())
        || request
            .params
            .get("input")
            .and_then(Value::as_str)
            .is_some_and(|s| is_brep_path(Path::new(s)))
}

/// Gathers a B-Rep part: the document, its cameras, its trim structures (to the `tolerance`)
/// and their upload to the device.
fn gather_brep(
    request: &mut Request,
    p: &Params,
    ctx: &JobContext,
    result: &mut Value,
) -> Result<Gathered, OpError> {
    let t = Instant::now();
    let asked_tolerance = request
        .params
        .get("tolerance")
        .cloned()
        .filter(|v| !v.is_null());
    let doc = request_brep(request)?;
    doc.validate().map_err(brep_error)?;
    let b = doc
        .bounding_box()
        .ok_or_else(|| OpError::request("the document has no faces to render"))?;
    let bounds = Bounds {
        min: b.min,
        max: b.max,
    };
    let axis = p.up_axis.unwrap_or_default();
    result["up_axis"] = json!(axis.name());
    let cams = cameras(p, axis, &bounds)?;
    let trim_tolerance = match &asked_tolerance {
        Some(v) => Some(match parse_tolerance(v, doc.units)? {
            Tolerance::Length(x) => x,
            Tolerance::Percent(pc) => pc / 100.0 * 2.0 * bounds.radius(),
        }),
        None => None,
    };
    let read_ms = ms(t.elapsed());
    ctx.progress(0.05, "prepare", "trim structures")?;
    let t = Instant::now();
    let scene = BrepScene::new(&doc, trim_tolerance).map_err(render_error)?;
    ctx.checkpoint()?;
    result["tolerance"] = json!(scene.trim_tolerance);
    result["units"] = json!(doc.units.name());
    result["faces"] = json!(doc.faces.len());
    if !scene.skipped.is_empty() {
        result["warnings"] = json!(scene.skipped);
    }
    result["timings_ms"] = json!({"read": read_ms});
    let prepare_ms = ms(t.elapsed());
    ctx.progress(0.4, "upload", "")?;
    let t = Instant::now();
    let renderer = renderer()?;
    let device_ms = ms(t.elapsed());
    let t = Instant::now();
    let gpu = renderer.upload_brep(scene).map_err(render_error)?;
    result["trim_bytes"] = json!(gpu.trim_bytes());
    Ok(Gathered {
        part: Part::Brep(Box::new(gpu)),
        cams,
        prepare_ms,
        device_ms,
        upload_ms: ms(t.elapsed()),
    })
}

/// Gathers the mesh panels: the meshes, one camera fitted to them all (the panels compare at
/// one scale), and their upload to the device.
fn gather_meshes(
    request: &mut Request,
    p: &Params,
    ctx: &JobContext,
    result: &mut Value,
) -> Result<Gathered, OpError> {
    let t = Instant::now();
    if p.raycast {
        return Err(OpError::new(
            ErrorCode::Unsupported,
            "`raycast` ray casts the exact surfaces of a B-Rep document; a mesh is \
             rasterised as it is",
        ));
    }
    let (meshes, stage_axis) = mesh_panels(request, ctx)?;
    ctx.checkpoint()?;
    // The request's axis, else the stage's own, else Z.
    let axis = p.up_axis.or(stage_axis).unwrap_or_default();
    result["up_axis"] = json!(axis.name());
    let mut scenes = Vec::with_capacity(meshes.len());
    let mut bounds: Option<Bounds> = None;
    for (label, mesh) in &meshes {
        let scene = Scene::from_mesh(mesh);
        let b = scene.bounds.ok_or_else(|| {
            OpError::new(
                ErrorCode::InvalidMesh,
                format!("the mesh {label:?} has no faces to render"),
            )
        })?;
        bounds = Some(bounds.map_or(b, |a| a.union(&b)));
        scenes.push((label.clone(), scene));
    }
    drop(meshes);
    let bounds = bounds.ok_or_else(|| OpError::request("no mesh to render"))?;
    let cams = cameras(p, axis, &bounds)?;
    result["faces"] = json!(scenes.iter().map(|(_, s)| s.max_id).max().unwrap_or(0));
    result["timings_ms"] = json!({"read": ms(t.elapsed())});
    ctx.progress(0.4, "upload", "")?;
    let t = Instant::now();
    let renderer = renderer()?;
    let device_ms = ms(t.elapsed());
    let t = Instant::now();
    let mut panels = Vec::with_capacity(scenes.len());
    for (label, scene) in scenes {
        panels.push(MeshPanel {
            label,
            gpu: renderer.upload(&scene).map_err(render_error)?,
            triangles: scene.triangles(),
        });
    }
    Ok(Gathered {
        part: Part::Meshes(panels),
        cams,
        prepare_ms: 0.0,
        device_ms,
        upload_ms: ms(t.elapsed()),
    })
}

/// The panels drawn side by side and the columns of their grid.
fn panel_grid(p: &Params, part: &Part) -> (usize, usize) {
    let panel_count = match part {
        Part::Meshes(m) => m.len(),
        Part::Brep(_) => 1,
    };
    let columns = p
        .columns
        .unwrap_or_else(|| panels::default_columns(panel_count))
        .min(panel_count);
    (panel_count, columns)
}

/// Renders each camera's frame and writes its PNGs (colour, face ids); the files written so
/// far are removed when a later step fails.
fn render_frames(
    renderer: &Renderer,
    p: &Params,
    g: &Gathered,
    ctx: &JobContext,
) -> Result<Rendered, OpError> {
    let cams = &g.cams;
    let mut written = Written(Vec::new());
    let (mut draw, mut readback, mut encode) = (Duration::ZERO, Duration::ZERO, Duration::ZERO);
    let mut covered = Vec::with_capacity(cams.len());
    let mut steps = Vec::with_capacity(cams.len());
    let mut last: Option<Frame> = None;
    let (_, columns) = panel_grid(p, &g.part);
    for (i, camera) in cams.iter().enumerate() {
        ctx.checkpoint()?;
        let frame = match &g.part {
            Part::Meshes(meshes) => {
                let mut frames = Vec::with_capacity(meshes.len());
                for m in meshes {
                    ctx.checkpoint()?;
                    let (frame, timings) = renderer
                        .render(&m.gpu, camera, &p.settings)
                        .map_err(render_error)?;
                    draw += timings.draw;
                    readback += timings.readback;
                    frames.push(frame);
                }
                if frames.len() == 1 {
                    frames.swap_remove(0)
                } else {
                    panels::tile(&frames, columns)
                }
            }
            Part::Brep(gpu) => {
                let (frame, report) = if p.raycast {
                    ray_cast_frame(renderer, gpu, camera, p, i, cams.len(), ctx)?
                } else {
                    renderer.render_brep(gpu, camera, &p.settings, p.cracks)
                }
                .map_err(render_error)?;
                draw += report.timings.frame();
                readback += report.timings.readback;
                steps.push(report);
                frame
            }
        };
        covered.push(frame.covered());
        let t = Instant::now();
        write_frame(p, &frame, i as u32, &mut written, ctx)?;
        encode += t.elapsed();
        let _ = ctx.progress(
            0.5 + 0.5 * (i + 1) as f64 / cams.len() as f64,
            "render",
            &format!("frame {} of {}", i + 1, cams.len()),
        );
        last = Some(frame);
    }
    Ok(Rendered {
        files: std::mem::take(&mut written.0),
        covered,
        steps,
        draw,
        readback,
        encode,
        last,
    })
}

/// Ray casts frame `i` of `frames` (`raycast`), reporting progress and honouring a cancel
/// between the ray caster's slices; the outer `Err` is the job's cancellation, the inner
/// result the renderer's.
fn ray_cast_frame(
    renderer: &Renderer,
    gpu: &tessd_render::GpuBrepScene,
    camera: &Camera,
    p: &Params,
    i: usize,
    frames: usize,
    ctx: &JobContext,
) -> Result<Result<(Frame, BrepReport), RenderError>, OpError> {
    // Progress and cancel between the ray caster's slices (~25 ms each).
    let mut stop = None;
    let mut tell = |done: f64| {
        let at = 0.5 + 0.5 * (i as f64 + done) / frames as f64;
        let msg = format!(
            "frame {} of {frames}: ray cast {:.0} %",
            i + 1,
            100.0 * done
        );
        match ctx.progress(at.min(1.0), "render", &msg) {
            Ok(()) => true,
            Err(e) => {
                stop = Some(e);
                false
            }
        }
    };
    let cast = renderer.ray_cast_brep_with_progress(gpu, camera, &p.settings, &mut tell);
    if let (Err(RenderError::Cancelled), Some(e)) = (&cast, stop) {
        return Err(e);
    }
    Ok(cast)
}

/// Writes frame `i`'s PNGs: the colour image to `output`, the face ids to `face_ids`.
fn write_frame(
    p: &Params,
    frame: &Frame,
    i: u32,
    written: &mut Written,
    ctx: &JobContext,
) -> Result<(), OpError> {
    for (path, ids) in [(&p.output, false), (&p.face_ids, true)] {
        let Some(path) = path else { continue };
        let path = frame_path(path, i, p.frames);
        ctx.checkpoint()?;
        let encoded;
        let rgba = if ids {
            encoded = tessd_render::image::face_ids_to_rgba(&frame.face_id);
            &encoded
        } else {
            &frame.color
        };
        tessd_render::image::write_png(&path, frame.width, frame.height, rgba)
            .map_err(render_error)?;
        written.0.push(path);
    }
    Ok(())
}

/// The result: the image's size, the adapter, the view and camera, what was drawn (panels or
/// the B-Rep pipeline's grid and cracks), the pixels covered, the files and the timings
/// (`total` is added by [`run`]).
fn describe(result: &mut Value, renderer: &Renderer, p: &Params, g: &Gathered, r: &Rendered) {
    let steps = &r.steps;
    let first = &g.cams[0];
    let a = renderer.adapter();
    let read_ms = result["timings_ms"]["read"].as_f64().unwrap_or(0.0);
    let (panel_count, columns) = panel_grid(p, &g.part);
    let rows = panel_count.div_ceil(columns) as u32;
    result["width"] = json!(p.width * columns as u32);
    result["height"] = json!(p.height * rows);
    result["frames"] = json!(p.frames);
    result["adapter"] = json!({
        "name": a.name, "backend": a.backend, "device_type": a.device_type, "driver": a.driver,
    });
    result["view"] = json!(match p.spec {
        CameraSpec::View(v) => v.name(),
        CameraSpec::Explicit { .. } => "explicit",
    });
    result["camera"] = json!({
        "eye": point(first.eye), "target": point(first.target), "up": point(first.up),
        "fov": first.fov, "near": first.near, "far": first.far,
    });
    result["shading"] = json!(p.settings.shading.name());
    result["edges"] = json!(p.settings.edges);
    match &g.part {
        Part::Meshes(meshes) => {
            result["triangles"] = json!(meshes.iter().map(|m| m.triangles).sum::<usize>());
            if meshes.len() > 1 {
                result["panels"] = json!(
                    meshes
                        .iter()
                        .enumerate()
                        .map(|(i, m)| {
                            let (x, y) = panels::panel_origin(i, columns, p.width, p.height);
                            json!({"label": m.label, "triangles": m.triangles,
                                   "x": x, "y": y, "width": p.width, "height": p.height})
                        })
                        .collect::<Vec<_>>()
                );
                result["columns"] = json!(columns);
                result["rows"] = json!(rows);
            }
        }
        Part::Brep(_) => {
            let first = steps.first().copied().unwrap_or_default();
            // The frame's own tessellation: two triangles per grid cell.
            result["triangles"] = json!(2 * first.cells);
            result["grid"] = json!({
                "faces_drawn": first.faces_drawn,
                "cells": first.cells,
                "vertices": first.grid_vertices,
            });
            result["method"] = json!(if p.raycast { "raycast" } else { "raster" });
            if !p.raycast {
                let detected: usize = steps.iter().map(|r| r.cracks_detected).sum();
                let filled: usize = steps.iter().map(|r| r.cracks_filled).sum();
                result["cracks"] = json!({
                    "mode": p.cracks.name(),
                    "detected": detected,
                    "filled": filled,
                });
                if p.frames > 1 {
                    result["cracks"]["detected_per_frame"] =
                        json!(steps.iter().map(|r| r.cracks_detected).collect::<Vec<_>>());
                }
            }
        }
    }
    result["pixels"] = json!(p.width as u64 * columns as u64 * p.height as u64 * rows as u64);
    result["covered"] = json!(r.covered[0]);
    if p.frames > 1 {
        result["covered_per_frame"] = json!(r.covered);
    }
    result["output"] = json!(p.output.as_ref().map(|o| o.display().to_string()));
    result["files"] = json!(
        r.files
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
    );
    result["timings_ms"] = json!({
        "read": read_ms,
        "prepare": g.prepare_ms,
        "tessellate": ms(steps.iter().map(|r| r.timings.tessellation).sum()),
        "device": g.device_ms,
        "upload": g.upload_ms,
        "draw": ms(r.draw),
        "readback": ms(r.readback),
        "encode": ms(r.encode),
    });
    if matches!(g.part, Part::Brep(_)) {
        result["timings_ms"]["steps"] = step_timings(steps);
    }
}

/// The last frame as arrays (`color`, `depth`, `face_id`, `uv`), when no file was asked for.
fn frame_arrays(p: &Params, last: Option<Frame>) -> Vec<OwnedArray> {
    match (&p.output, last) {
        (None, Some(f)) => {
            let (h, w) = (f.height as u64, f.width as u64);
            let uv: Vec<f32> = f.uv.iter().flatten().copied().collect();
            vec![
                OwnedArray::new("color", vec![h, w, 4], f.color),
                OwnedArray::new("depth", vec![h, w], f.depth),
                OwnedArray::new("face_id", vec![h, w], f.face_id),
                OwnedArray::new("uv", vec![h, w, 2], uv),
            ]
        }
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_names() {
        let p = Path::new("/tmp/out.png");
        assert_eq!(frame_path(p, 0, 1), p);
        assert_eq!(frame_path(p, 7, 12), Path::new("/tmp/out_007.png"));
    }
}
