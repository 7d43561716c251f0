//! `tessd lod` ↔ `ops::lod`: a chain of levels of detail as one USD stage and/or one file per level.

use super::local_run::{report_or_json, run_local};
use super::shared_args::{ClusterArgs, StageArgs};
use anyhow::{Result, bail};
use std::path::PathBuf;
use tessd_ipc::registry::Response;

/// `tessd lod`: the input (LOD0), the levels' goals and where the chain is written.
#[derive(clap::Args)]
pub struct LodArgs {
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
}

/// Runs `tessd lod`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: LodArgs) -> Result<()> {
    let LodArgs {
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
    } = args;
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
    report_or_json(run_local::<LodArgs>("lod", params)?, json, |r| {
        print_lod(r);
        for w in r.result["warnings"].as_array().into_iter().flatten() {
            eprintln!("warning: {}", w.as_str().unwrap_or_default());
        }
    })
}

/// `tessd lod`: one line per level.
pub fn print_lod(response: &Response) {
    let r = &response.result;
    println!(
        "LOD0: {} vertices, {} faces (the input)",
        r["lod0"]["points"], r["lod0"]["faces"]
    );
    for level in r["levels"].as_array().into_iter().flatten() {
        let goal = match &level["goal"] {
            serde_json::Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        println!(
            "LOD{}: {} vertices, {} faces (goal {goal}, max displacement {}, surface error {})",
            level["level"],
            level["output_vertices"],
            level["output_faces"],
            level["max_displacement"],
            level["surface_error"]
        );
        if let Some(n) = level["note"].as_str() {
            println!("  note: {n}");
        }
    }
    for f in &response.files {
        println!("wrote {}", f.display());
    }
}
