//! The `tessd` command line: a thin layer that parses arguments and calls the crates.

mod report;

use anyhow::{Context, Result, bail};
use clap::{CommandFactory, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use report::{print_compare, print_lod, print_simplify, print_stats};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use tessd::ops::common::significant;
use tessd_ipc::arrays::{Arrays, OwnedArray};
use tessd_ipc::job::{CancelToken, JobContext, JobLimits, Progress};
use tessd_ipc::registry::{Request, Response};
use tessd_ipc::server::{Server, ServerOptions};

/// tessd — a local geometry service for CAD and DCC tools.
#[derive(Parser)]
#[command(name = "tessd", version)]
struct Cli {
    /// Worker threads for the parallel passes (simplification, ...), before or after the
    /// command; default: RAYON_NUM_THREADS, else one per core. Simplification gives the same
    /// bytes whatever it is.
    #[arg(long, global = true, value_name = "N")]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the daemon on a local socket.
    Serve {
        /// Socket name (in the per-user folder) or path; default: the per-user socket.
        #[arg(long)]
        socket: Option<String>,
        /// Append the log to this file instead of stderr (lines stamped in RFC 3339 UTC;
        /// level from TESSD_LOG, default info).
        #[arg(long)]
        log: Option<PathBuf>,
        /// Largest request payload in bytes.
        #[arg(long, default_value_t = 4u64 << 30)]
        max_payload: u64,
        /// Most requests running at once, over every client (more are refused, `too_large`).
        #[arg(long, default_value_t = 64)]
        max_jobs: usize,
        /// Most vertices, faces or face corners of one input mesh.
        #[arg(long, default_value_t = 1u64 << 31)]
        max_mesh_elements: u64,
        /// Most bytes one request's estimated working set may need (default: the machine's
        /// physical memory).
        #[arg(long)]
        max_job_memory: Option<u64>,
    },
    /// Run operations from job files.
    Job {
        #[command(subcommand)]
        action: JobAction,
    },
    /// Print a mesh's counts, bounds and topology.
    Stats {
        /// Mesh file (OBJ, PLY, STL, OFF, or a USD stage .usda).
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Convert a mesh between formats (from the extensions).
    Convert {
        /// Input mesh (OBJ, PLY, STL, OFF, or a USD stage .usda).
        input: PathBuf,
        /// Output mesh.
        output: PathBuf,
        #[command(flatten)]
        stage: StageArgs,
    },
    /// Simplify a mesh by vertex clustering (regular grid, quality goal or complexity goal).
    Simplify {
        /// Input mesh (OBJ, PLY, STL, OFF, or a USD stage .usda).
        input: PathBuf,
        /// Output mesh (OBJ, PLY, STL, OFF, or a USD stage for .usda).
        output: PathBuf,
        /// Partition: a regular grid, a quality goal (--max-error) or a complexity goal
        /// (--target-vertices).
        #[arg(long, value_parser = ["grid", "quality", "complexity"])]
        method: String,
        /// Grid: cells along each axis of the bounding box.
        #[arg(long, conflicts_with = "cell_size")]
        cells: Option<u64>,
        /// Grid: side of the cubic cells, in model units or a length with a unit ("2mm", with
        /// --units).
        #[arg(long, value_name = "X|LENGTH", allow_hyphen_values = true)]
        cell_size: Option<String>,
        /// Quality: largest vertex displacement, in model units, a length with a unit ("5mm",
        /// with --units) or a percentage of the largest side of the bounding box ("0.5%").
        #[arg(long, value_name = "X|X%", allow_hyphen_values = true)]
        max_error: Option<String>,
        /// Complexity: vertices to keep, a count or a percentage of the input's ("20%").
        #[arg(long, value_name = "N|N%", allow_hyphen_values = true)]
        target_vertices: Option<String>,
        #[command(flatten)]
        cluster: ClusterArgs,
        /// Also write the partition's cells: wire boxes for .obj, a box mesh otherwise.
        #[arg(long, value_name = "BOXES.obj")]
        partition: Option<PathBuf>,
        #[command(flatten)]
        stage: StageArgs,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Subdivide a cage (uniform refinement; Catmull-Clark matches OpenSubdiv / Blender's
    /// Subdivision Surface modifier with "limit surface" off).
    Subdivide {
        /// Cage mesh (OBJ, PLY, STL, OFF, or a USD stage .usda).
        input: PathBuf,
        /// Output mesh (OBJ, PLY, STL, OFF, or a USD stage for .usda).
        output: PathBuf,
        /// Refinement scheme.
        #[arg(long, default_value = "catmull-clark", value_parser = ["catmull-clark", "loop", "butterfly", "doo-sabin", "sqrt3", "bilinear"])]
        scheme: String,
        /// Refinement levels.
        #[arg(long, default_value_t = 1)]
        levels: u64,
        /// Evaluate the stencils on the GPU.
        #[arg(long)]
        gpu: bool,
        /// Boundary corners: smooth (edge-only) or kept in place (edge-and-corner).
        #[arg(long, default_value = "edge-only", value_parser = ["edge-only", "edge-and-corner"])]
        boundary: String,
        /// UV interpolation, as Blender's "UV Smooth" (corners = "Keep Corners", its default).
        #[arg(long, default_value = "corners", value_parser = ["linear", "corners", "corners-junctions", "corners-junctions-concave", "boundaries", "smooth"])]
        uv_interpolation: String,
        /// Do not give the refined mesh smooth shading normals.
        #[arg(long)]
        no_normals: bool,
        /// For a .usda OUT: write the cage with `subdivisionScheme` set (USD renderers refine
        /// it) instead of the refined mesh.
        #[arg(long)]
        usd_cage: bool,
        /// Animation frames: meshes with the cage's vertices moved (e.g. an OBJ sequence);
        /// OUT (.usda) gets their refined points as time samples 1, 2, ...
        #[arg(long, num_args = 1..)]
        frames: Vec<PathBuf>,
        #[command(flatten)]
        stage: StageArgs,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Build a chain of levels of detail and write them as one USD stage (and optionally one
    /// mesh file per level).
    Lod {
        /// Input mesh (OBJ, PLY, STL, OFF, or a USD stage .usda): LOD0.
        input: PathBuf,
        /// Goals of LOD1, LOD2..., comma-separated, each level coarser than the one before
        /// (a chain that does not get coarser is refused): for --method complexity the vertices
        /// to keep, counts or percentages of the input's, which shrink ("50%,20%,5%"); for
        /// quality the largest error, distances (model units, or "5mm" with --units) or
        /// percentages of the bounding box's largest side, which grow ("0.5%,2%"); for grid the
        /// cells per axis, which shrink ("32,16,8").
        #[arg(
            long,
            value_delimiter = ',',
            required = true,
            allow_hyphen_values = true
        )]
        levels: Vec<String>,
        /// The USD stage to write (.usda).
        #[arg(long, value_name = "LODS.usda")]
        out: Option<PathBuf>,
        /// How the levels' goals are read.
        #[arg(long, default_value = "complexity", value_parser = ["grid", "quality", "complexity"])]
        method: String,
        /// Layout of the stage: a variant set `LOD` (what DCC tools read today) or the native
        /// UsdLod schema of usd-core 26.8+.
        #[arg(long, default_value = "variants", value_parser = ["variants", "usdlod"])]
        lod_schema: String,
        /// Also write one mesh file per level (<stem>_LOD<i>.<format>) into this folder.
        #[arg(long, value_name = "DIR")]
        per_level_dir: Option<PathBuf>,
        /// Format of the per-level files.
        #[arg(long, default_value = "obj", value_parser = ["obj", "ply", "stl", "off", "usda"])]
        per_level_format: String,
        #[command(flatten)]
        cluster: ClusterArgs,
        #[command(flatten)]
        stage: StageArgs,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Compress a mesh losslessly at a quantisation into a progressive .tsc file (paper 003:
    /// Gandoin-Devillers kd-tree codes in an nSP-tree).
    Compress {
        /// Input mesh (OBJ, PLY, STL, OFF, or a USD stage .usda); polygons are fan-triangulated.
        input: PathBuf,
        /// Output .tsc file.
        output: PathBuf,
        /// Bits per coordinate of the quantisation grid (1-20).
        #[arg(long, default_value_t = 12)]
        bits: u32,
        /// nSP-tree subdivisions per axis (2 or 4).
        #[arg(long, default_value_t = 4)]
        cell_split: u32,
        /// Fewest triangles an nSP-cell must hold to be subdivided; its children must also hold
        /// an eighth of it on average (tiny cells cost bits at their borders).
        #[arg(long, default_value_t = tessd_codec::Params::default().min_cell)]
        min_cell: u64,
        /// Precision in bits the root cell reaches before it is subdivided.
        #[arg(long, default_value_t = 7)]
        root_bits: u32,
        /// Bits of geometry coded ahead of the connectivity (paper 003 §6.4, 0-4): a partial
        /// decode draws each vertex at the barycentre of the points it will split into, for a
        /// few more bits per vertex.
        #[arg(long, default_value_t = 0)]
        ahead: u32,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Decode a .tsc file into a mesh, whole or up to a precision.
    Decompress {
        /// Input .tsc file.
        input: PathBuf,
        /// Output mesh (OBJ, PLY, STL, OFF, or a USD stage for .usda).
        output: PathBuf,
        /// Decode only up to this many bits per coordinate (a prefix of the refinement).
        #[arg(long)]
        max_bits: Option<u32>,
        #[command(flatten)]
        stage: StageArgs,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Decode what a camera needs from a .tsc file: each cell refined until its vertices'
    /// error projects within --pixel-error pixels, cells out of view left out.
    ViewDecode {
        /// Input .tsc file.
        input: PathBuf,
        /// Output mesh (OBJ, PLY, STL, OFF, or a USD stage for .usda).
        output: PathBuf,
        /// Eye position, X,Y,Z.
        #[arg(long, allow_hyphen_values = true)]
        eye: String,
        /// The point looked at, X,Y,Z.
        #[arg(long, allow_hyphen_values = true)]
        target: String,
        /// The up direction, X,Y,Z.
        #[arg(long, allow_hyphen_values = true)]
        up: String,
        /// Vertical field of view in degrees.
        #[arg(long, default_value_t = 30.0)]
        fov: f64,
        /// Image size, WIDTHxHEIGHT.
        #[arg(long, default_value = "1280x720")]
        size: String,
        /// Largest projected error of a vertex, in pixels.
        #[arg(long, default_value_t = 1.0)]
        pixel_error: f64,
        #[command(flatten)]
        stage: StageArgs,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Measure the surface distance between two meshes: both one-sided distances, the
    /// symmetric Hausdorff distance and RMS (Metro-style sampling).
    Compare {
        /// First mesh (OBJ, PLY, STL, OFF, or a USD stage .usda).
        a: PathBuf,
        /// Second mesh.
        b: PathBuf,
        /// Face samples per direction (default: 10 per triangle of the larger mesh, 1 M to 20 M).
        #[arg(long)]
        samples: Option<u64>,
        /// Seed of the sample placement.
        #[arg(long)]
        seed: Option<u64>,
        /// Also sample the edges.
        #[arg(long)]
        edges: bool,
        /// Only measure A → B.
        #[arg(long)]
        one_sided: bool,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Tessellate a B-Rep (an exchange document, docs/brep-format.md, or an OpenCASCADE .brep
    /// file): each face's surface to the chordal tolerance, trimmed by its loops, shared edges
    /// discretised once (watertight).
    Tessellate {
        /// B-Rep JSON document (`python -m tessd.brep export`) or OpenCASCADE BREP text
        /// (.brep / .brp: `BRepTools::Write`, FreeCAD's `Shape.exportBrep`).
        input: PathBuf,
        /// Output mesh: a USD stage (.usda, a GeomSubset per face) or OBJ, PLY, STL, OFF.
        output: PathBuf,
        /// Chordal tolerance: a length with a unit (0.1mm, 0.01in, 1cm, 0.001m), a plain
        /// number in the document's units, or a percentage of the part's bounding-box diagonal
        /// (0.05%).
        #[arg(long)]
        tolerance: String,
        /// The largest angle, radians, between neighbouring facets' normals (default 0.5).
        #[arg(long)]
        angle: Option<f64>,
        /// What the f32 positions are relative to: `auto` (default: a rounded centre of the
        /// part, only when f32 would not hold the tolerance at the part's coordinates), `none`,
        /// or `X,Y,Z`. A .usda gets it as the prim's xformOp:translate; OBJ, PLY and OFF are
        /// written absolute in f64.
        #[arg(long)]
        origin: Option<String>,
        /// The length unit of a .brep file's coordinates (mm, cm, m, in; default mm): OpenCASCADE
        /// BREP text carries none. A JSON document names its own.
        #[arg(long)]
        units: Option<String>,
        #[command(flatten)]
        stage: StageArgs,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Open a window on meshes, B-Rep parts and compressed meshes: orbit, subdivide, stream
    /// (Blender's keys; H lists them; --script plays actions).
    View(tessd::view::ViewArgs),
    /// Render a mesh (OBJ, PLY, STL, OFF, USD .usda: a LOD stage's levels side by side) or a
    /// B-Rep (a .json document or an OpenCASCADE .brep file) to a PNG, headless on the GPU (lavapipe without one).
    Render {
        /// Mesh file, `tessd-brep` JSON document or OpenCASCADE .brep file; several mesh files are drawn side by side
        /// (one panel each, one camera fitted to them all: LOD chains, cage and result), as are
        /// the LOD variants of one USD stage.
        #[arg(required = true, num_args = 1..)]
        input: Vec<PathBuf>,
        /// The colour image (.png); with --turntable N, OUT_000.png ... OUT_<N-1>.png.
        output: PathBuf,
        /// Image size, WIDTHxHEIGHT (of each panel when several inputs are drawn).
        #[arg(long, default_value = "1280x720")]
        size: String,
        /// Panels per row when several inputs are drawn (default: one row up to four, else a
        /// square-ish grid).
        #[arg(long, value_name = "N")]
        columns: Option<u64>,
        /// A standard view fitted to the part's bounding box (Z up: front looks along +Y;
        /// with --up-axis Y, Y up: front looks along -Z).
        #[arg(long, value_parser = ["iso", "front", "back", "left", "right", "top", "bottom"], conflicts_with = "eye")]
        view: Option<String>,
        /// Explicit eye position, X,Y,Z (instead of --view).
        #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
        eye: Option<String>,
        /// The point looked at, X,Y,Z (default: the bounding box's centre).
        #[arg(
            long,
            value_name = "X,Y,Z",
            allow_hyphen_values = true,
            requires = "eye"
        )]
        target: Option<String>,
        /// The camera's up direction with --eye, X,Y,Z (default: the --up-axis, or the top
        /// view's up when looking along it).
        #[arg(
            long,
            value_name = "X,Y,Z",
            allow_hyphen_values = true,
            requires = "eye"
        )]
        up: Option<String>,
        /// The world's up axis for the views: Y for scans, glTF and OBJ exports (front then
        /// looks along -Z). Default: a .usda stage's own upAxis, else Z.
        #[arg(long, value_parser = ["Y", "Z"])]
        up_axis: Option<String>,
        /// Vertical field of view, degrees.
        #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
        fov: f64,
        /// B-Rep parts: what to do with cracks between faces (paper 001): `object` fills them
        /// by ray casting the neighbouring faces (exact), `image` from neighbouring pixels
        /// (fast), `none` leaves them (and counts them). Ignored for meshes.
        #[arg(long, default_value = "object", value_parser = ["none", "image", "object"])]
        cracks: String,
        /// B-Rep parts: the world tolerance of the trim approximation, a length with units or
        /// a percentage of the part's box diagonal (default 0.01 %).
        #[arg(long)]
        tolerance: Option<String>,
        /// B-Rep parts: ray cast every pixel against the trimmed surfaces instead of
        /// rasterising their per-frame tessellation (the reference of paper 001 §4.1.2).
        #[arg(long)]
        raycast: bool,
        /// Shading of the colour image.
        #[arg(long, default_value = "lit", value_parser = ["lit", "gooch", "toon", "face-ids"])]
        shading: String,
        /// Overlay the triangle edges (B-Rep parts: the per-frame tessellation grid).
        #[arg(long)]
        edges: bool,
        /// Also write the face ids as a PNG: face index + 1 = R + 256·G + 65536·B, 0 background.
        #[arg(long, value_name = "IDS.png")]
        face_ids: Option<PathBuf>,
        /// Write N frames turning the eye about the up axis through the target.
        #[arg(long, value_name = "N")]
        turntable: Option<u64>,
        /// Print the result (timings per step, adapter, pixel counts) as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Run the main job on built-in sample data, through a real daemon, into ./tessd-demo/.
    Demo {
        /// Output folder.
        #[arg(long, default_value = "tessd-demo")]
        out: PathBuf,
    },
}

/// Settings `simplify` and `lod` share.
#[derive(clap::Args)]
struct ClusterArgs {
    /// Where a cell's vertices merge to.
    #[arg(long, value_parser = ["barycenter", "heaviest", "quadric"])]
    representative: Option<String>,
    /// Vertex weights.
    #[arg(long, value_parser = ["longest_edge", "curvature", "uniform"])]
    weighting: Option<String>,
    /// Fan-triangulate polygons first (grid; the quality and complexity goals always do).
    #[arg(long)]
    triangulate: bool,
    /// Never merge boundary or feature-edge vertices with other vertices.
    #[arg(long)]
    preserve_boundaries: bool,
    /// The unit of the mesh's coordinates (mm, cm, m, in), which a mesh file does not say:
    /// needed for lengths given with a unit ("5mm"), which are converted into it.
    #[arg(long, value_parser = ["mm", "cm", "m", "in"])]
    units: Option<String>,
}

impl ClusterArgs {
    /// Adds these settings to a request's parameters.
    fn add_to(&self, params: &mut serde_json::Value) {
        params["representative"] = serde_json::json!(self.representative);
        params["weighting"] = serde_json::json!(self.weighting);
        params["triangulate"] = serde_json::json!(self.triangulate);
        params["preserve_boundaries"] = serde_json::json!(self.preserve_boundaries);
        params["units"] = serde_json::json!(self.units);
    }
}

/// The USD stage settings of every verb that can write a `.usda`.
#[derive(clap::Args)]
struct StageArgs {
    /// A .usda output's up axis (default: a .usda input's own, else Z).
    #[arg(long, value_parser = ["Y", "Z"])]
    up_axis: Option<String>,
    /// A .usda output's metres per model unit (default: a B-Rep's own units, mm → 0.001; for
    /// a mesh, its --units where the verb takes them, else a .usda input's own, else 1, as
    /// mesh files name none; FreeCAD's millimetres: 0.001).
    #[arg(long, value_name = "M", value_parser = positive_f64)]
    meters_per_unit: Option<f64>,
}

impl StageArgs {
    /// Adds these settings to a request's parameters (`up_axis`, `meters_per_unit`).
    fn add_to(&self, params: &mut serde_json::Value) {
        params["up_axis"] = serde_json::json!(self.up_axis);
        params["meters_per_unit"] = serde_json::json!(self.meters_per_unit);
    }
}

/// A finite number above zero (`--meters-per-unit`).
fn positive_f64(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!(
            "expected a positive number (millimetres: 0.001), got {s:?}"
        )),
    }
}

#[derive(Subcommand)]
enum JobAction {
    /// Run JOB.json: `{"op": ..., "params": {...}}` or `{"jobs": [...]}`.
    Run {
        /// The job file.
        file: PathBuf,
    },
}

/// Mesh-sized buffers on huge pages where the kernel grants them (`tessd_mesh::allocation`).
#[global_allocator]
static ALLOCATOR: tessd_mesh::allocation::LargePages = tessd_mesh::allocation::LargePages;

fn main() {
    // Mesh-sized buffers go back to the system when a job frees them (see the module).
    tessd_mesh::allocation::return_large_buffers_to_system();
    let cli = Cli::parse();
    if !matches!(cli.command, Command::Serve { .. } | Command::Demo { .. }) {
        die_quietly_on_broken_pipe();
    }
    let code = match set_threads(cli.threads).and_then(|()| run(cli)) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("tessd: {}", error_text(&e));
            if e.downcast_ref::<tessd_ipc::socket::BindError>()
                .is_some_and(|b| matches!(b, tessd_ipc::socket::BindError::InUse(_)))
            {
                3
            } else {
                1
            }
        }
    };
    std::process::exit(code);
}

/// Restores SIGPIPE's default action, which Rust's runtime sets to "ignore": a CLI verb whose
/// reader goes away (`tessd stats big.ply | head -1`) then ends quietly, killed by SIGPIPE (the
/// shell shows status 141) like `cat` or `grep`, instead of panicking in `println!`. `serve`
/// keeps ignoring it, so a client that hangs up gives its socket an EPIPE error, not the daemon
/// its death; `demo` too (it talks to its daemon over a socket, and its own lines ignore a
/// closed stdout).
fn die_quietly_on_broken_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// `e` and its causes on one line, `outer: cause: its cause`, each text once: many errors (the
/// `"{path}: {source}"` kind) already print their source, which `{e:#}` would repeat.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let s = cause.to_string();
        if text.is_empty() {
            text = s;
        } else if !text.contains(&s) {
            text.push_str(": ");
            text.push_str(&s);
        }
    }
    text
}

/// Builds the global rayon pool with `threads` workers (`--threads`); without it rayon's default
/// applies (RAYON_NUM_THREADS, else one per core).
fn set_threads(threads: Option<usize>) -> Result<()> {
    let Some(n) = threads else {
        return Ok(());
    };
    if n == 0 {
        bail!("--threads must be at least 1");
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .context("setting up the thread pool")
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Serve {
            socket,
            log,
            max_payload,
            max_jobs,
            max_mesh_elements,
            max_job_memory,
        } => {
            let defaults = JobLimits::default();
            let limits = JobLimits {
                max_mesh_elements,
                max_job_memory: max_job_memory.unwrap_or(defaults.max_job_memory),
            };
            let options = ServerOptions::default()
                .with_limits(tessd_ipc::frame::Limits::default().with_max_payload(max_payload))
                .with_max_jobs(max_jobs)
                .with_job_limits(limits);
            serve(socket.as_deref(), log.as_deref(), options)
        }
        Command::Job {
            action: JobAction::Run { file },
        } => job_run(&file),
        Command::Stats { file, json } => report_or_json(
            run_local("mesh.stats", serde_json::json!({"input": file}))?,
            json,
            |r| print_stats(&file, &r.result),
        ),
        Command::Convert {
            input,
            output,
            stage,
        } => {
            let mut params = serde_json::json!({"input": input, "output": output});
            stage.add_to(&mut params);
            let response = run_local("mesh.convert", params)?;
            println!("{}", report::convert_line(&output, &response.result));
            Ok(())
        }
        Command::Simplify {
            input,
            output,
            method,
            cells,
            cell_size,
            max_error,
            target_vertices,
            cluster,
            partition,
            stage,
            json,
        } => {
            let mut params = serde_json::json!({
                "input": input,
                "output": output,
                "method": method,
                "cells": cells,
                "cell_size": cell_size,
                "max_error": max_error,
                "target_vertices": target_vertices,
                "partition_output": partition,
            });
            cluster.add_to(&mut params);
            stage.add_to(&mut params);
            report_or_json(run_local("simplify", params)?, json, |r| {
                print_simplify(&output, &r.result)
            })
        }
        Command::Subdivide {
            input,
            output,
            scheme,
            levels,
            gpu,
            boundary,
            uv_interpolation,
            no_normals,
            usd_cage,
            frames,
            stage,
            json,
        } => {
            let mut params = serde_json::json!({
                "input": input,
                "output": output,
                "scheme": scheme,
                "levels": levels,
                "gpu": gpu,
                "boundary": boundary,
                "uv_interpolation": uv_interpolation,
                "normals": !no_normals,
                "usd": if usd_cage { "cage" } else { "refined" },
            });
            stage.add_to(&mut params);
            let arrays = if frames.is_empty() {
                Vec::new()
            } else {
                vec![read_frames(&frames)?]
            };
            report_or_json(run_local_with("subdivide", params, &arrays)?, json, |r| {
                let r = &r.result;
                if r["usd"] == "cage" {
                    return println!(
                        "subdivide: the cage ({} faces) marked {} -> {}",
                        r["cage_faces"],
                        r["scheme"],
                        output.display()
                    );
                }
                println!(
                    "subdivide: {} level(s) of {}: {} vertices, {} faces -> {} (topology {:.1} ms, apply {:.1} ms)",
                    r["levels"],
                    r["scheme"],
                    r["vertices"],
                    r["faces"],
                    output.display(),
                    r["topology_ms"].as_f64().unwrap_or(0.0),
                    r["apply_ms"].as_f64().unwrap_or(0.0)
                );
            })
        }
        Command::Lod {
            input,
            levels,
            out,
            method,
            lod_schema,
            per_level_dir,
            per_level_format,
            cluster,
            stage,
            json,
        } => {
            if out.is_none() && per_level_dir.is_none() {
                bail!("give --out LODS.usda and/or --per-level-dir DIR");
            }
            let mut params = serde_json::json!({
                "input": input,
                "levels": levels,
                "output": out,
                "method": method,
                "lod_schema": lod_schema,
                "per_level": per_level_dir,
                "per_level_format": per_level_format,
            });
            cluster.add_to(&mut params);
            stage.add_to(&mut params);
            report_or_json(run_local("lod", params)?, json, |r| {
                print_lod(r);
                for w in r.result["warnings"].as_array().into_iter().flatten() {
                    eprintln!("warning: {}", w.as_str().unwrap_or_default());
                }
            })
        }
        Command::Compress {
            input,
            output,
            bits,
            cell_split,
            min_cell,
            root_bits,
            ahead,
            json,
        } => {
            let params = serde_json::json!({
                "input": input,
                "output": output,
                "bits": bits,
                "cell_split": cell_split,
                "min_cell": min_cell,
                "root_bits": root_bits,
                "ahead": ahead,
            });
            report_or_json(run_local("codec.compress", params)?, json, |r| {
                let r = &r.result;
                println!(
                    "compress: {} vertices, {} triangles at {} bits -> {} ({} bytes, {:.2} bits/vertex, {} nSP-cells) in {:.0} ms",
                    r["input_vertices"],
                    r["input_triangles"],
                    r["bits"],
                    output.display(),
                    r["bytes"],
                    r["bits_per_vertex"].as_f64().unwrap_or(0.0),
                    r["nsp_cells"],
                    r["elapsed_ms"].as_f64().unwrap_or(0.0)
                )
            })
        }
        Command::Decompress {
            input,
            output,
            max_bits,
            stage,
            json,
        } => {
            let mut params =
                serde_json::json!({"input": input, "output": output, "max_bits": max_bits});
            stage.add_to(&mut params);
            report_or_json(run_local("codec.decompress", params)?, json, |r| {
                print_decoded(
                    format!("decompress: {} bits", r.result["bits"]),
                    &r.result,
                    &output,
                )
            })
        }
        Command::ViewDecode {
            input,
            output,
            eye,
            target,
            up,
            fov,
            size,
            pixel_error,
            stage,
            json,
        } => {
            let mut params = serde_json::json!({
                "input": input,
                "output": output,
                "eye": vec3_arg(&eye),
                "target": vec3_arg(&target),
                "up": vec3_arg(&up),
                "fov": fov,
                "size": size,
                "pixel_error": pixel_error,
            });
            stage.add_to(&mut params);
            report_or_json(run_local("codec.view", params)?, json, |r| {
                print_decoded(
                    format!("view-decode: {} cells", r.result["cells"]),
                    &r.result,
                    &output,
                )
            })
        }
        Command::Compare {
            a,
            b,
            samples,
            seed,
            edges,
            one_sided,
            json,
        } => {
            let params = serde_json::json!({
                "a": a,
                "b": b,
                "samples": samples,
                "seed": seed,
                "edges": edges,
                "direction": if one_sided { "a_to_b" } else { "both" },
            });
            report_or_json(run_local("compare", params)?, json, |r| {
                print_compare(&r.result)
            })
        }
        Command::Tessellate {
            input,
            output,
            tolerance,
            angle,
            origin,
            units,
            stage,
            json,
        } => {
            let mut params = serde_json::json!({
                "input": input,
                "output": output,
                "tolerance": tolerance,
                "angle": angle,
                "origin": origin.as_deref().map(origin_param),
                "units": units,
            });
            stage.add_to(&mut params);
            report_or_json(run_local("tessellate", params)?, json, |r| {
                let r = &r.result;
                let units = r["units"].as_str().unwrap_or("");
                let shown = match (r["tolerance_relative"].as_f64(), r["diagonal"].as_f64()) {
                    (Some(rel), Some(d)) => format!(
                        "{} {units}, {} % of the {} {units} diagonal",
                        significant(r["tolerance"].as_f64().unwrap_or(f64::NAN)),
                        significant(rel * 100.0),
                        significant(d)
                    ),
                    _ => format!("{} {units}", r["tolerance"]),
                };
                println!(
                    "tessellate: {} faces, {} triangles (tolerance {shown}) -> {} ({:.1} ms)",
                    r["faces"],
                    r["triangles"],
                    output.display(),
                    r["time_ms"].as_f64().unwrap_or(0.0)
                );
                for w in r["warnings"].as_array().into_iter().flatten() {
                    eprintln!("warning: {}", w.as_str().unwrap_or_default());
                }
            })
        }
        Command::View(args) => tessd::view::run(args.options()?),
        Command::Render {
            input,
            output,
            size,
            columns,
            view,
            eye,
            target,
            up,
            up_axis,
            fov,
            cracks,
            tolerance,
            raycast,
            shading,
            edges,
            face_ids,
            turntable,
            json,
        } => {
            // One input as a path, several as a list (panels side by side).
            let input = match input.as_slice() {
                [one] => serde_json::json!(one),
                many => serde_json::json!(many),
            };
            let params = serde_json::json!({
                "input": input,
                "output": output,
                "size": size,
                "columns": columns,
                "view": view,
                "eye": eye.as_deref().map(vec3_arg),
                "target": target.as_deref().map(vec3_arg),
                "up": up.as_deref().map(vec3_arg),
                "fov": fov,
                "cracks": cracks,
                "tolerance": tolerance,
                "raycast": raycast,
                "shading": shading,
                "edges": edges,
                "face_ids": face_ids,
                "turntable": turntable,
                "up_axis": up_axis,
            });
            report_or_json(run_local("render", params)?, json, |r| {
                let r = &r.result;
                let t = &r["timings_ms"];
                let files = r["files"].as_array().map_or(0, Vec::len);
                let cracks = match r["cracks"]["mode"].as_str() {
                    Some(mode) => format!(
                        ", cracks {}: {} detected, {} filled",
                        mode, r["cracks"]["detected"], r["cracks"]["filled"]
                    ),
                    None => String::new(),
                };
                println!(
                    "render: {}x{} {} view, {} triangles, {} of {} pixels covered{} -> {} ({} file{}; {} {}; draw {:.1} ms, total {:.1} ms)",
                    r["width"],
                    r["height"],
                    r["view"].as_str().unwrap_or(""),
                    r["triangles"],
                    r["covered"],
                    r["pixels"],
                    cracks,
                    output.display(),
                    files,
                    if files == 1 { "" } else { "s" },
                    r["adapter"]["name"].as_str().unwrap_or(""),
                    r["adapter"]["device_type"].as_str().unwrap_or(""),
                    t["draw"].as_f64().unwrap_or(0.0),
                    t["total"].as_f64().unwrap_or(0.0),
                );
            })
        }
        Command::Demo { out } => tessd::demo::run(&out),
    }
}

/// `--origin` as the op's parameter: `auto` and `none` as they are, `X,Y,Z` as a list of
/// three numbers (anything else is passed on as text for the op to refuse, naming it).
fn origin_param(s: &str) -> serde_json::Value {
    let parts: Vec<Option<f64>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match parts.as_slice() {
        [Some(x), Some(y), Some(z)] => serde_json::json!([x, y, z]),
        _ => serde_json::Value::from(s),
    }
}

/// `X,Y,Z` as a list of three numbers (anything else is passed on as text for the op to refuse,
/// naming it).
/// The summary line of a decode: what was decoded, the counts, the file and the bytes read.
fn print_decoded(what: String, r: &serde_json::Value, output: &Path) {
    println!(
        "{what} -> {} vertices, {} triangles -> {} ({} of {} bytes read) in {:.0} ms",
        r["vertices"],
        r["triangles"],
        output.display(),
        r["bytes_read"],
        r["file_bytes"],
        r["elapsed_ms"].as_f64().unwrap_or(0.0)
    )
}

fn vec3_arg(s: &str) -> serde_json::Value {
    origin_param(s)
}

fn serve(socket: Option<&str>, log_file: Option<&Path>, options: ServerOptions) -> Result<()> {
    tessd::logging::init(log_file).context("opening the log file")?;
    let path = tessd_ipc::socket::resolve(socket, true).context("choosing the socket path")?;
    let listener = tessd_ipc::socket::bind(&path)?;
    let server = Server::new(listener, &path, tessd::ops::registry(), options);
    shut_down_on_signals(server.shutdown_handle())?;
    server.serve()?;
    Ok(())
}

/// SIGINT and SIGTERM stop the server as a `shutdown` request does (running requests are
/// cancelled and answered, then the socket is removed), so that a service manager's stop or a
/// terminal's Ctrl-C never leaves a client without its answer.
///
/// A second SIGINT or SIGTERM while that shutdown runs (its grace period can last 10 s) ends
/// the process at once with status 128 + the signal's number (130, 143), the shell's status
/// for a process a signal ended: the caller asked twice, and learns that the shutdown was cut
/// short (requests may have gone unanswered), where a completed one exits 0.
#[cfg(unix)]
fn shut_down_on_signals(handle: tessd_ipc::server::ShutdownHandle) -> Result<()> {
    let mut signals = signal_hook::iterator::Signals::new([
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
    ])
    .context("installing signal handlers")?;
    std::thread::spawn(move || {
        let mut signals = signals.forever();
        if let Some(sig) = signals.next() {
            log::info!("signal {sig} received");
            handle.trigger();
        }
        if let Some(sig) = signals.next() {
            log::warn!("signal {sig} received again during the shutdown: exiting at once");
            log::logger().flush();
            std::process::exit(128 + sig);
        }
    });
    Ok(())
}

/// Windows: the console's Ctrl-C and Ctrl-Break, closing the console window, logging off and
/// shutting down stop the server as SIGTERM does on Unix (running requests are cancelled and
/// answered), through `SetConsoleCtrlHandler`. Windows runs the handler on a thread of its own
/// and, for close, logoff and shutdown, ends the process as soon as the handler returns (it
/// allows about 5 s), so for those the handler does not return: it waits while the server
/// shuts down, and the process ends when `serve` returns and `main` exits. A second event
/// during that shutdown exits at once, as a second signal does on Unix, with 128 + the
/// matching signal's number: 130 for Ctrl-C, 149 for Ctrl-Break (SIGBREAK), 143 for the
/// others (SIGTERM).
#[cfg(windows)]
fn shut_down_on_signals(handle: tessd_ipc::server::ShutdownHandle) -> Result<()> {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicBool, Ordering};
    const CTRL_C_EVENT: u32 = 0;
    const CTRL_BREAK_EVENT: u32 = 1;
    const CTRL_CLOSE_EVENT: u32 = 2;
    const CTRL_LOGOFF_EVENT: u32 = 5;
    const CTRL_SHUTDOWN_EVENT: u32 = 6;
    #[link(name = "kernel32")]
    unsafe extern "system" {
        fn SetConsoleCtrlHandler(
            handler: Option<unsafe extern "system" fn(u32) -> i32>,
            add: i32,
        ) -> i32;
    }
    static HANDLE: OnceLock<tessd_ipc::server::ShutdownHandle> = OnceLock::new();
    static STOPPING: AtomicBool = AtomicBool::new(false);
    unsafe extern "system" fn on_event(event: u32) -> i32 {
        let (name, code) = match event {
            CTRL_C_EVENT => ("Ctrl-C", 130),
            CTRL_BREAK_EVENT => ("Ctrl-Break", 149),
            CTRL_CLOSE_EVENT => ("console close", 143),
            CTRL_LOGOFF_EVENT => ("logoff", 143),
            CTRL_SHUTDOWN_EVENT => ("shutdown", 143),
            _ => return 0,
        };
        if STOPPING.swap(true, Ordering::SeqCst) {
            log::warn!("{name} received again during the shutdown: exiting at once");
            log::logger().flush();
            std::process::exit(code);
        }
        log::info!("{name} received");
        if let Some(handle) = HANDLE.get() {
            handle.trigger();
        }
        if matches!(
            event,
            CTRL_CLOSE_EVENT | CTRL_LOGOFF_EVENT | CTRL_SHUTDOWN_EVENT
        ) {
            // Returning would end the process now; `main` ends it once the server is done.
            loop {
                std::thread::sleep(std::time::Duration::from_secs(60));
            }
        }
        1
    }
    let _ = HANDLE.set(handle);
    // SAFETY: registers a handler with the signature the console API calls; it only touches
    // statics and the shutdown handle, which are thread-safe.
    if unsafe { SetConsoleCtrlHandler(Some(on_event), 1) } == 0 {
        return Err(std::io::Error::last_os_error()).context("installing the console handler");
    }
    Ok(())
}

/// Prints an operation's result: raw JSON with `--json`, else the verb's summary.
fn report_or_json(response: Response, json: bool, summary: impl FnOnce(&Response)) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(&response.result)?);
    } else {
        summary(&response);
    }
    Ok(())
}

/// Runs one operation in this process with a progress bar on a terminal — the same registry
/// and code path as a socket request.
fn run_local(op: &str, params: serde_json::Value) -> Result<Response> {
    run_local_with(op, params, &[])
}

/// As [`run_local`], with arrays in the request.
fn run_local_with(op: &str, params: serde_json::Value, arrays: &[OwnedArray]) -> Result<Response> {
    let serde_json::Value::Object(params) = params else {
        unreachable!()
    };
    let cwd = std::env::current_dir()?;
    let request = Request {
        params,
        base_dir: Some(cwd),
        arrays: Arrays::from_owned(arrays),
    };
    // Errors name the CLI's flags (`--cells`), not the protocol's parameters (`cells`).
    let response = with_progress(op, |ctx| {
        tessd::ops::registry()
            .run(op, request, ctx)
            .map_err(|mut e| {
                e.message = report::cli_words(&Cli::command(), op, &e.message);
                e
            })
    })?;
    // Every verb that writes a file says what the file could not hold.
    for line in report::dropped_warnings(op, &response) {
        eprintln!("{line}");
    }
    Ok(response)
}

/// The `frames` array of `subdivide`: the positions of each mesh file, which must all have the
/// same vertex count (the op checks it against the cage).
fn read_frames(paths: &[PathBuf]) -> Result<OwnedArray> {
    let mut flat: Vec<f32> = Vec::new();
    let mut count = None;
    for p in paths {
        let m = tessd::ops::mesh_arrays::read_mesh_file(p, &Default::default())
            .map_err(|e| anyhow::anyhow!("reading frame {}: {}", p.display(), e.message))?;
        if *count.get_or_insert(m.positions.len()) != m.positions.len() {
            bail!(
                "frame {} has {} vertices; the first frame has {}",
                p.display(),
                m.positions.len(),
                count.unwrap_or(0)
            );
        }
        flat.extend(m.positions.iter().flatten());
    }
    let shape = vec![paths.len() as u64, count.unwrap_or(0) as u64, 3];
    Ok(OwnedArray::new("frames", shape, flat))
}

fn with_progress(
    label: &str,
    f: impl FnOnce(&JobContext) -> Result<Response, tessd_ipc::OpError>,
) -> Result<Response> {
    let bar = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{prefix} [{bar:30}] {percent:>3}% {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(label.to_string());
        Some(bar)
    } else {
        None
    };
    let sink = |p: Progress| {
        if let Some(bar) = &bar {
            bar.set_position((p.fraction * 1000.0) as u64);
            bar.set_message(format!("{} {}", p.stage, p.message));
        }
    };
    let ctx = JobContext::new(&sink, CancelToken::default());
    let result = f(&ctx);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    result.map_err(|e| anyhow::anyhow!("{label}: {e}"))
}

fn job_run(file: &Path) -> Result<()> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let jobs = tessd_ipc::job_file::parse(&text)
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let base = file
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let registry = tessd::ops::registry();
    let mut failed = 0;
    for (i, job) in jobs.into_iter().enumerate() {
        let label = format!("job {i} ({})", job.op);
        match with_progress(&label, |ctx| {
            tessd_ipc::job_file::run(&registry, job, base, ctx)
        }) {
            Ok(r) => {
                let files: Vec<String> = r.files.iter().map(|p| p.display().to_string()).collect();
                println!(
                    "{}",
                    serde_json::json!({"job": i, "result": r.result, "files": files})
                );
            }
            Err(e) => {
                eprintln!("tessd: {}", error_text(&e));
                failed += 1;
            }
        }
    }
    if failed > 0 {
        bail!("{failed} job(s) failed");
    }
    Ok(())
}
