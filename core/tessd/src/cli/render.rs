//! `tessd render` ↔ `ops::render`: meshes or B-Rep parts to a PNG, headless on the GPU.

use super::local_run::{report_or_json, run_local};
use super::shared_args::vec3_arg;
use anyhow::Result;
use std::path::PathBuf;

/// `tessd render`: the inputs, the image, the camera and the B-Rep crack handling.
#[derive(clap::Args)]
pub struct RenderArgs {
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
}

/// Runs `tessd render`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: RenderArgs) -> Result<()> {
    let RenderArgs {
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
    } = args;
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
    report_or_json(run_local::<RenderArgs>("render", params)?, json, |r| {
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
