//! Arguments several verbs share (the clustering settings, a USD output's stage settings) and
//! how a few argument texts become request parameters (`X,Y,Z` lists).

/// Settings `simplify` and `lod` share.
#[derive(clap::Args)]
pub struct ClusterArgs {
    /// Where a cell's vertices merge to.
    #[arg(long, value_parser = ["barycenter", "heaviest", "quadric"])]
    representative: Option<String>,
    /// Vertex weights.
    #[arg(long, value_parser = ["longest_edge", "curvature", "uniform"])]
    weighting: Option<String>,
    /// Fan-triangulate polygons first (grid; the quality and complexity goals always do).
    #[arg(long)]
    triangulate: bool,
    /// Never merge boundary or feature-edge vertices with other vertices.
    #[arg(long)]
    preserve_boundaries: bool,
    /// The unit of the mesh's coordinates (mm, cm, m, in), which a mesh file does not say:
    /// needed for lengths given with a unit ("5mm"), which are converted into it.
    #[arg(long, value_parser = ["mm", "cm", "m", "in"])]
    units: Option<String>,
}

impl ClusterArgs {
    /// Adds these settings to a request's parameters.
    pub fn add_to(&self, params: &mut serde_json::Value) {
        params["representative"] = serde_json::json!(self.representative);
        params["weighting"] = serde_json::json!(self.weighting);
        params["triangulate"] = serde_json::json!(self.triangulate);
        params["preserve_boundaries"] = serde_json::json!(self.preserve_boundaries);
        params["units"] = serde_json::json!(self.units);
    }
}

/// The USD stage settings of every verb that can write a `.usda`.
#[derive(clap::Args)]
pub struct StageArgs {
    /// A .usda output's up axis (default: a .usda input's own, else Z).
    #[arg(long, value_parser = ["Y", "Z"])]
    up_axis: Option<String>,
    /// A .usda output's metres per model unit (default: a B-Rep's own units, mm → 0.001; for
    /// a mesh, its --units where the verb takes them, else a .usda input's own, else 1, as
    /// mesh files name none; FreeCAD's millimetres: 0.001).
    #[arg(long, value_name = "M", value_parser = positive_f64)]
    meters_per_unit: Option<f64>,
}

impl StageArgs {
    /// Adds these settings to a request's parameters (`up_axis`, `meters_per_unit`).
    pub fn add_to(&self, params: &mut serde_json::Value) {
        params["up_axis"] = serde_json::json!(self.up_axis);
        params["meters_per_unit"] = serde_json::json!(self.meters_per_unit);
    }
}

/// A finite number above zero (`--meters-per-unit`).
fn positive_f64(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!(
            "expected a positive number (millimetres: 0.001), got {s:?}"
        )),
    }
}

/// `--origin` as the op's parameter: `auto` and `none` as they are, `X,Y,Z` as a list of
/// three numbers (anything else is passed on as text for the op to refuse, naming it).
pub fn origin_param(s: &str) -> serde_json::Value {
    let parts: Vec<Option<f64>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match parts.as_slice() {
        [Some(x), Some(y), Some(z)] => serde_json::json!([x, y, z]),
        _ => serde_json::Value::from(s),
    }
}

/// `X,Y,Z` as a list of three numbers (anything else is passed on as text for the op to refuse,
/// naming it).
pub fn vec3_arg(s: &str) -> serde_json::Value {
    origin_param(s)
}
