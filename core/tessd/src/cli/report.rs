//! What an operation says, in the CLI's terms: its errors with the verb's flags for the
//! protocol's parameters, and a warning per attribute an output file could not hold.

use std::path::Path;
use tessd_ipc::registry::Response;

/// The name a warning gives the format of `file` (from its extension).
pub fn format_name(file: &Path) -> String {
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
/// positional argument (`` `OUTPUT` ``), found in the verb's own argument definitions (`cmd`,
/// the verb's clap command), so a new flag needs no table entry unless its name differs from the
/// parameter's ([`RENAMED`]). Backticked words that are no argument of the verb stay as they
/// are. Daemon clients get the op's own message, with parameter names.
pub fn cli_words(cmd: &clap::Command, op: &str, message: &str) -> String {
    let verb = verb_of(op);
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
