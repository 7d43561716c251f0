//! `tessd simplify` ↔ `ops::simplify`: vertex clustering to a grid, a quality or a complexity goal.

use super::local_run::{report_or_json, run_local};
use super::shared_args::{ClusterArgs, StageArgs};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// `tessd simplify`: the meshes, the partition's goal and the clustering settings.
#[derive(clap::Args)]
pub struct SimplifyArgs {
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
}

/// Runs `tessd simplify`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: SimplifyArgs) -> Result<()> {
    let SimplifyArgs {
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
    } = args;
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
    report_or_json(run_local::<SimplifyArgs>("simplify", params)?, json, |r| {
        print_simplify(&output, &r.result)
    })
}

/// `tessd simplify`: counts before and after, the goal, what elimination removed.
pub fn print_simplify(output: &Path, r: &serde_json::Value) {
    println!(
        "wrote {}: {} -> {} vertices, {} -> {} faces ({} method, {} clusters)",
        output.display(),
        r["input_vertices"],
        r["output_vertices"],
        r["input_faces"],
        r["output_faces"],
        r["method"].as_str().unwrap_or("?"),
        r["clusters"],
    );
    let mut line = format!("  max displacement {}", r["max_displacement"]);
    if let Some(e) = r["surface_error"].as_f64() {
        line += &format!(", surface error {e}");
    }
    if let Some(t) = r["tolerance"].as_f64() {
        line += &format!(" (tolerance {t})");
    }
    if let Some(t) = r["polygon_twist"].as_f64().filter(|&t| t > 0.0) {
        line += &format!(", input polygons twisted by up to {t}");
    }
    if let Some(n) = r["refinement_rounds"].as_u64().filter(|&n| n > 0) {
        line += &format!(", {n} coverage rounds");
    }
    if let Some(t) = r["target_vertices"].as_u64() {
        line += &format!(", target {t} vertices");
    }
    println!("{line}");
    println!(
        "  removed {} degenerate and {} duplicate faces",
        r["degenerate_faces"], r["duplicate_faces"]
    );
    if let Some(p) = r["partition_output"].as_str() {
        println!("  partition: {} cells -> {p}", r["cells"]);
    }
    if let Some(n) = r["note"].as_str() {
        println!("  note: {n}");
    }
}
