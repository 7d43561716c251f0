//! `tessd tessellate` ↔ `ops::tessellate`: a B-Rep to a watertight mesh within a chordal tolerance.

use super::local_run::{report_or_json, run_local};
use super::shared_args::{StageArgs, origin_param};
use anyhow::Result;
use std::path::PathBuf;
use tessd::ops::common::significant;

/// `tessd tessellate`: the B-Rep, the output mesh, the tolerance and the origin.
#[derive(clap::Args)]
pub struct TessellateArgs {
    /// B-Rep JSON document (`python -m tessd.brep export`) or OpenCASCADE BREP text
    /// (.brep / .brp: `BRepTools::Write`, FreeCAD's `Shape.exportBrep`).
    input: PathBuf,
    /// Output mesh: a USD stage (.usda, a GeomSubset per face) or OBJ, PLY, STL, OFF.
    output: PathBuf,
    /// Chordal tolerance: a length with a unit (0.1mm, 0.01in, 1cm, 0.001m), a plain
    /// number in the document's units, or a percentage of the part's bounding-box diagonal
    /// (0.05%).
    #[arg(long)]
    tolerance: String,
    /// The largest angle, radians, between neighbouring facets' normals (default 0.5).
    #[arg(long)]
    angle: Option<f64>,
    /// What the f32 positions are relative to: `auto` (default: a rounded centre of the
    /// part, only when f32 would not hold the tolerance at the part's coordinates), `none`,
    /// or `X,Y,Z`. A .usda gets it as the prim's xformOp:translate; OBJ, PLY and OFF are
    /// written absolute in f64.
    #[arg(long)]
    origin: Option<String>,
    /// The length unit of a .brep file's coordinates (mm, cm, m, in; default mm): OpenCASCADE
    /// BREP text carries none. A JSON document names its own.
    #[arg(long)]
    units: Option<String>,
    #[command(flatten)]
    stage: StageArgs,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `tessd tessellate`: the request from the arguments, then the summary (or `--json`).
pub fn run(args: TessellateArgs) -> Result<()> {
    let TessellateArgs {
        input,
        output,
        tolerance,
        angle,
        origin,
        units,
        stage,
        json,
    } = args;
    let mut params = serde_json::json!({
        "input": input,
        "output": output,
        "tolerance": tolerance,
        "angle": angle,
        "origin": origin.as_deref().map(origin_param),
        "units": units,
    });
    stage.add_to(&mut params);
    report_or_json(
        run_local::<TessellateArgs>("tessellate", params)?,
        json,
        |r| {
            let r = &r.result;
            let units = r["units"].as_str().unwrap_or("");
            let shown = match (r["tolerance_relative"].as_f64(), r["diagonal"].as_f64()) {
                (Some(rel), Some(d)) => format!(
                    "{} {units}, {} % of the {} {units} diagonal",
                    significant(r["tolerance"].as_f64().unwrap_or(f64::NAN)),
                    significant(rel * 100.0),
                    significant(d)
                ),
                _ => format!("{} {units}", r["tolerance"]),
            };
            println!(
                "tessellate: {} faces, {} triangles (tolerance {shown}) -> {} ({:.1} ms)",
                r["faces"],
                r["triangles"],
                output.display(),
                r["time_ms"].as_f64().unwrap_or(0.0)
            );
            for w in r["warnings"].as_array().into_iter().flatten() {
                eprintln!("warning: {}", w.as_str().unwrap_or_default());
            }
        },
    )
}
