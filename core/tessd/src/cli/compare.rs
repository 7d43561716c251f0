//! `tessd compare` ↔ `ops::compare`: the surface distance between two meshes.

use super::local_run::{report_or_json, run_local};
use anyhow::Result;
use std::path::PathBuf;

/// `tessd compare`: the two meshes and the sampling.
#[derive(clap::Args)]
pub struct CompareArgs {
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
}

/// Runs `tessd compare`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: CompareArgs) -> Result<()> {
    let CompareArgs {
        a,
        b,
        samples,
        seed,
        edges,
        one_sided,
        json,
    } = args;
    let params = serde_json::json!({
        "a": a,
        "b": b,
        "samples": samples,
        "seed": seed,
        "edges": edges,
        "direction": if one_sided { "a_to_b" } else { "both" },
    });
    report_or_json(run_local::<CompareArgs>("compare", params)?, json, |r| {
        print_compare(&r.result)
    })
}

/// `tessd compare`: both directions, Hausdorff and RMS, absolute and relative.
pub fn print_compare(r: &serde_json::Value) {
    let pct = |v: &serde_json::Value| {
        v.as_f64()
            .map_or_else(|| "-".to_string(), |x| format!("{:.4} %", 100.0 * x))
    };
    for (label, key) in [("A -> B", "a_to_b"), ("B -> A", "b_to_a")] {
        let d = &r[key];
        if d.is_null() {
            continue;
        }
        println!(
            "{label}: max {} ({} of the diagonal), mean {}, rms {} ({}), {} samples",
            d["max"],
            pct(&d["max_relative"]),
            d["mean"],
            d["rms"],
            pct(&d["rms_relative"]),
            d["samples"]
        );
    }
    if !r["hausdorff"].is_null() {
        println!(
            "Hausdorff {} ({} of the diagonal)",
            r["hausdorff"],
            pct(&r["hausdorff_relative"])
        );
        println!(
            "RMS {} ({} of the diagonal)",
            r["rms"],
            pct(&r["rms_relative"])
        );
    }
    println!("bounding-box diagonal {}", r["bbox_diagonal"]);
}
