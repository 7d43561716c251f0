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

/// The name a warning gives the format of `file` (from its extension).
fn format_name(file: &Path) -> String {
    let ext = file
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "usda" => "a USD stage".to_string(),
        "tsc" => "the .tsc codec".to_string(),
        "" => "the output".to_string(),
        other => other.to_ascii_uppercase(),
    }
}

/// Whether a file at `file` can hold what the protocol calls `name` (see
/// [`tessd_mesh::io::format_carries`]; a USD stage holds all but sharp edges, a `.tsc` file
/// positions and triangles alone).
fn file_carries(file: &Path, name: &str) -> bool {
    let ext = file
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "usda" => name != "sharp_edges",
        "tsc" => false,
        _ => tessd_mesh::io::Format::from_path(file)
            .is_ok_and(|f| tessd_mesh::io::format_carries(f, name)),
    }
}

/// The warning lines for what an operation's result says it dropped (`dropped_attributes`,
/// and each `lod` level's): one line per attribute and file,
/// `warning: <file>: dropped <attr> (<format> cannot carry it)`, naming the file whose format
/// cannot hold it, or the operation when the files could (a subdivision scheme without
/// face-varying refinement, ...).
pub fn dropped_warnings(op: &str, response: &Response) -> Vec<String> {
    let r = &response.result;
    let mut names: Vec<String> = Vec::new();
    let lists = std::iter::once(&r["dropped_attributes"]).chain(
        r["levels"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|l| &l["dropped_attributes"]),
    );
    for list in lists {
        for n in list
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|n| n.as_str())
        {
            if !names.iter().any(|m| m == n) {
                names.push(n.to_string());
            }
        }
    }
    let mut files: Vec<&Path> = response.files.iter().map(|p| p.as_path()).collect();
    if files.is_empty() {
        files.extend(r["output"].as_str().map(Path::new));
    }
    // Paths as the user gave them: relative to the working folder when inside it.
    let cwd = std::env::current_dir().unwrap_or_default();
    let show = |f: &Path| f.strip_prefix(&cwd).unwrap_or(f).display().to_string();
    let mut lines = Vec::new();
    for name in &names {
        let holders: Vec<&Path> = files
            .iter()
            .copied()
            .filter(|f| !file_carries(f, name))
            .collect();
        if holders.is_empty() {
            let shown = files
                .first()
                .map_or_else(|| "<arrays>".to_string(), |f| show(f));
            lines.push(format!(
                "warning: {shown}: dropped {name} (`{op}` cannot carry it)"
            ));
        }
        for f in holders {
            lines.push(format!(
                "warning: {}: dropped {name} ({} cannot carry it)",
                show(f),
                format_name(f)
            ));
        }
    }
    lines
}

/// The `tessd convert` summary: what the file holds (STL: the triangles written; PLY: the
/// vertices after the seam split, saying how many were added).
pub fn convert_line(output: &Path, r: &serde_json::Value) -> String {
    let w = &r["written"];
    if w["triangulated"].as_bool() == Some(true) {
        let (tris, faces) = (&w["faces"], &r["faces"]);
        return if tris == faces {
            format!("wrote {} ({tris} triangles)", output.display())
        } else {
            format!(
                "wrote {} ({tris} triangles: the {faces} faces fan-triangulated, as STL needs)",
                output.display()
            )
        };
    }
    let vertices = if w.is_null() {
        &r["vertices"]
    } else {
        &w["vertices"]
    };
    let mut line = format!(
        "wrote {} ({vertices} vertices, {} faces)",
        output.display(),
        r["faces"]
    );
    if let Some(n) = w["split_vertices"].as_u64().filter(|&n| n > 0) {
        line += &format!(
            "; {n} vertices added at UV / normal seams ({} holds one UV and normal per vertex)",
            format_name(output)
        );
    }
    line
}

/// The CLI verb that runs protocol operation `op`.
fn verb_of(op: &str) -> &str {
    match op {
        "mesh.convert" => "convert",
        "mesh.stats" => "stats",
        "codec.compress" => "compress",
        "codec.decompress" => "decompress",
        "codec.view" => "view-decode",
        other => other,
    }
}

/// Parameters whose CLI argument has another name than the parameter (the rest are spelt
/// alike: `cell_size` is `--cell-size`).
const RENAMED: &[(&str, &str, &str)] = &[
    ("lod", "output", "out"),
    ("lod", "per_level", "per_level_dir"),
    ("simplify", "partition_output", "partition"),
    ("subdivide", "normals", "no_normals"),
    ("subdivide", "usd", "usd_cage"),
    ("compare", "direction", "one_sided"),
];

/// An operation's error message in the words of the CLI: each backticked protocol parameter
/// (`` `cells` ``, `` `output` ``) becomes the verb's flag (`` `--cells` ``, `` `--out` ``) or
/// positional argument (`` `OUTPUT` ``), found in the verb's own argument definitions (`cli`,
/// the clap command), so a new flag needs no table entry unless its name differs from the
/// parameter's ([`RENAMED`]). Backticked words that are no argument of the verb stay as they
/// are. Daemon clients get the op's own message, with parameter names.
pub fn cli_words(cli: &clap::Command, op: &str, message: &str) -> String {
    let verb = verb_of(op);
    let Some(cmd) = cli.get_subcommands().find(|c| c.get_name() == verb) else {
        return message.to_string();
    };
    let shown = |param: &str| -> Option<String> {
        let id = RENAMED
            .iter()
            .find(|(v, p, _)| *v == verb && *p == param)
            .map_or(param, |r| r.2);
        let arg = cmd.get_arguments().find(|a| a.get_id().as_str() == id)?;
        Some(match arg.get_long() {
            Some(long) => format!("--{long}"),
            None => arg
                .get_value_names()
                .and_then(|n| n.first())
                .map_or_else(|| id.to_ascii_uppercase(), |n| n.to_string()),
        })
    };
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(start) = rest.find('`') {
        let Some(len) = rest[start + 1..].find('`') else {
            break;
        };
        let word = &rest[start + 1..start + 1 + len];
        out.push_str(&rest[..=start]);
        let is_name = !word.is_empty()
            && word
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        match shown(word).filter(|_| is_name) {
            Some(flag) => out.push_str(&flag),
            None => out.push_str(word),
        }
        out.push('`');
        rest = &rest[start + len + 2..];
    }
    out.push_str(rest);
    out
}
