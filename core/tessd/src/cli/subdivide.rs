//! `tessd subdivide` ↔ `ops::subdivide`: uniform refinement of a cage (and of its frames).

use super::local_run::{report_or_json, run_local_with};
use super::shared_args::StageArgs;
use anyhow::{Result, bail};
use std::path::PathBuf;
use tessd_ipc::arrays::OwnedArray;

/// `tessd subdivide`: the cage, the scheme and its options, and the animation frames.
#[derive(clap::Args)]
pub struct SubdivideArgs {
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
}

/// Runs `tessd subdivide`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: SubdivideArgs) -> Result<()> {
    let SubdivideArgs {
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
    } = args;
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
    report_or_json(
        run_local_with::<SubdivideArgs>("subdivide", params, &arrays)?,
        json,
        |r| {
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
        },
    )
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
