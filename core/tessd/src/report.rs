//! Human-readable summaries of operation results for the terminal (`--json` prints the raw
//! result instead).

use std::path::Path;
use tessd_ipc::registry::Response;

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
