//! `tessd stats` ↔ `ops::mesh_stats`: a mesh's counts, bounds and topology.

use super::local_run::{report_or_json, run_local};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// `tessd stats`: the mesh file to describe.
#[derive(clap::Args)]
pub struct StatsArgs {
    /// Mesh file (OBJ, PLY, STL, OFF, or a USD stage .usda).
    file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `tessd stats`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: StatsArgs) -> Result<()> {
    let StatsArgs { file, json } = args;
    report_or_json(
        run_local::<StatsArgs>("mesh.stats", serde_json::json!({"input": file}))?,
        json,
        |r| print_stats(&file, &r.result),
    )
}

/// `tessd stats`: counts, bounds and topology.
pub fn print_stats(file: &Path, s: &serde_json::Value) {
    println!("{}", file.display());
    for key in [
        "vertices",
        "stored_vertices",
        "unreferenced_vertices",
        "faces",
        "triangles",
        "edges",
        "boundary_edges",
        "boundary_loops",
        "non_manifold_edges",
        "components",
    ] {
        println!("  {key:22} {}", s[key]);
    }
    println!("  {:22} {}", "face sizes", s["face_sizes"]);
    println!("  {:22} {}", "bounds", s["bounds"]);
}
