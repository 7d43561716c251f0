//! `tessd compress`, `decompress` and `view-decode` ↔ `ops::codec`: the progressive `.tsc` files.

use super::local_run::{report_or_json, run_local};
use super::shared_args::{StageArgs, vec3_arg};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// `tessd compress`: the mesh, the `.tsc` file and the coder's settings.
#[derive(clap::Args)]
pub struct CompressArgs {
    /// Input mesh (OBJ, PLY, STL, OFF, or a USD stage .usda); polygons are fan-triangulated.
    input: PathBuf,
    /// Output .tsc file.
    output: PathBuf,
    /// Bits per coordinate of the quantisation grid (1-20).
    #[arg(long, default_value_t = 12)]
    bits: u32,
    /// nSP-tree subdivisions per axis (2 or 4).
    #[arg(long, default_value_t = 4)]
    cell_split: u32,
    /// Fewest triangles an nSP-cell must hold to be subdivided; its children must also hold
    /// an eighth of it on average (tiny cells cost bits at their borders).
    #[arg(long, default_value_t = tessd_codec::Params::default().min_cell)]
    min_cell: u64,
    /// Precision in bits the root cell reaches before it is subdivided.
    #[arg(long, default_value_t = 7)]
    root_bits: u32,
    /// Bits of geometry coded ahead of the connectivity (paper 003 §6.4, 0-4): a partial
    /// decode draws each vertex at the barycentre of the points it will split into, for a
    /// few more bits per vertex.
    #[arg(long, default_value_t = 0)]
    ahead: u32,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `tessd compress`: the request from the arguments, then the summary (or `--json`).
pub fn compress(args: CompressArgs) -> Result<()> {
    let CompressArgs {
        input,
        output,
        bits,
        cell_split,
        min_cell,
        root_bits,
        ahead,
        json,
    } = args;
    let params = serde_json::json!({
        "input": input,
        "output": output,
        "bits": bits,
        "cell_split": cell_split,
        "min_cell": min_cell,
        "root_bits": root_bits,
        "ahead": ahead,
    });
    report_or_json(
        run_local::<CompressArgs>("codec.compress", params)?,
        json,
        |r| {
            let r = &r.result;
            println!(
                "compress: {} vertices, {} triangles at {} bits -> {} ({} bytes, {:.2} bits/vertex, {} nSP-cells) in {:.0} ms",
                r["input_vertices"],
                r["input_triangles"],
                r["bits"],
                output.display(),
                r["bytes"],
                r["bits_per_vertex"].as_f64().unwrap_or(0.0),
                r["nsp_cells"],
                r["elapsed_ms"].as_f64().unwrap_or(0.0)
            )
        },
    )
}

/// `tessd decompress`: the `.tsc` file, the mesh and the precision to stop at.
#[derive(clap::Args)]
pub struct DecompressArgs {
    /// Input .tsc file.
    input: PathBuf,
    /// Output mesh (OBJ, PLY, STL, OFF, or a USD stage for .usda).
    output: PathBuf,
    /// Decode only up to this many bits per coordinate (a prefix of the refinement).
    #[arg(long)]
    max_bits: Option<u32>,
    #[command(flatten)]
    stage: StageArgs,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `tessd decompress`: the request from the arguments, then the summary (or `--json`).
pub fn decompress(args: DecompressArgs) -> Result<()> {
    let DecompressArgs {
        input,
        output,
        max_bits,
        stage,
        json,
    } = args;
    let mut params = serde_json::json!({"input": input, "output": output, "max_bits": max_bits});
    stage.add_to(&mut params);
    report_or_json(
        run_local::<DecompressArgs>("codec.decompress", params)?,
        json,
        |r| {
            print_decoded(
                format!("decompress: {} bits", r.result["bits"]),
                &r.result,
                &output,
            )
        },
    )
}

/// `tessd view-decode`: the `.tsc` file, the mesh and the camera it is decoded for.
#[derive(clap::Args)]
pub struct ViewDecodeArgs {
    /// Input .tsc file.
    input: PathBuf,
    /// Output mesh (OBJ, PLY, STL, OFF, or a USD stage for .usda).
    output: PathBuf,
    /// Eye position, X,Y,Z.
    #[arg(long, allow_hyphen_values = true)]
    eye: String,
    /// The point looked at, X,Y,Z.
    #[arg(long, allow_hyphen_values = true)]
    target: String,
    /// The up direction, X,Y,Z.
    #[arg(long, allow_hyphen_values = true)]
    up: String,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 30.0)]
    fov: f64,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    size: String,
    /// Largest projected error of a vertex, in pixels.
    #[arg(long, default_value_t = 1.0)]
    pixel_error: f64,
    #[command(flatten)]
    stage: StageArgs,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `tessd view-decode`: the request from the arguments, then the summary (or `--json`).
pub fn view_decode(args: ViewDecodeArgs) -> Result<()> {
    let ViewDecodeArgs {
        input,
        output,
        eye,
        target,
        up,
        fov,
        size,
        pixel_error,
        stage,
        json,
    } = args;
    let mut params = serde_json::json!({
        "input": input,
        "output": output,
        "eye": vec3_arg(&eye),
        "target": vec3_arg(&target),
        "up": vec3_arg(&up),
        "fov": fov,
        "size": size,
        "pixel_error": pixel_error,
    });
    stage.add_to(&mut params);
    report_or_json(
        run_local::<ViewDecodeArgs>("codec.view", params)?,
        json,
        |r| {
            print_decoded(
                format!("view-decode: {} cells", r.result["cells"]),
                &r.result,
                &output,
            )
        },
    )
}

/// The summary line of a decode: what was decoded, the counts, the file and the bytes read.
fn print_decoded(what: String, r: &serde_json::Value, output: &Path) {
    println!(
        "{what} -> {} vertices, {} triangles -> {} ({} of {} bytes read) in {:.0} ms",
        r["vertices"],
        r["triangles"],
        output.display(),
        r["bytes_read"],
        r["file_bytes"],
        r["elapsed_ms"].as_f64().unwrap_or(0.0)
    )
}
