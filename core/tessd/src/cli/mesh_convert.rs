//! `tessd convert` ↔ `ops::mesh_convert`: a mesh from one format into another.

use super::local_run::run_local;
use super::report::format_name;
use super::shared_args::StageArgs;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// `tessd convert`: the input and output meshes, formats from the extensions.
#[derive(clap::Args)]
pub struct ConvertArgs {
    /// Input mesh (OBJ, PLY, STL, OFF, or a USD stage .usda).
    input: PathBuf,
    /// Output mesh.
    output: PathBuf,
    #[command(flatten)]
    stage: StageArgs,
}

/// Runs `tessd convert`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: ConvertArgs) -> Result<()> {
    let ConvertArgs {
        input,
        output,
        stage,
    } = args;
    let mut params = serde_json::json!({"input": input, "output": output});
    stage.add_to(&mut params);
    let response = run_local::<ConvertArgs>("mesh.convert", params)?;
    println!("{}", convert_line(&output, &response.result));
    Ok(())
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
