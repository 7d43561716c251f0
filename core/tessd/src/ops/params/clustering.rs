//! The clustering parameters `simplify` and `lod` share: the partition method and its goals
//! (cells per axis, a tolerance, a vertex count), and the settings every level uses
//! (`representative`, `weighting`, `triangulate`, `preserve_boundaries`).

use super::scalars::{Amount, as_u64, bool_param, parse_amount};
use serde_json::Value;
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::Request;
use tessd_simplify::{Count, GridSize, Length, Method, Representative, SimplifyOptions, Weighting};

/// The three partition methods, as named in requests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodKind {
    /// `"grid"`: a regular grid (`cells` or `cell_size`).
    Grid,
    /// `"quality"`: a tolerance (`max_error`).
    Quality,
    /// `"complexity"`: a vertex count (`target_vertices`).
    Complexity,
}

impl MethodKind {
    /// Parses `"grid"`, `"quality"` or `"complexity"`.
    ///
    /// # Errors
    /// `invalid_request` naming the value.
    pub fn parse(s: &str) -> Result<MethodKind, OpError> {
        match s {
            "grid" => Ok(MethodKind::Grid),
            "quality" => Ok(MethodKind::Quality),
            "complexity" => Ok(MethodKind::Complexity),
            other => Err(OpError::request(format!(
                "`method` must be \"grid\", \"quality\" or \"complexity\", got {other:?}"
            ))),
        }
    }

    /// The request name.
    pub fn name(self) -> &'static str {
        match self {
            MethodKind::Grid => "grid",
            MethodKind::Quality => "quality",
            MethodKind::Complexity => "complexity",
        }
    }

    /// The goal of this method from one value: cells per axis (grid), a tolerance (quality:
    /// `"0.5%"` is a percentage of the largest side of the bounding box) or a vertex count
    /// (complexity: `"20%"` of the input's vertices). `what` names the value in messages.
    ///
    /// # Errors
    /// `invalid_request` naming `what` and the value.
    pub fn goal(self, what: &str, v: &Value) -> Result<Method, OpError> {
        match self {
            MethodKind::Grid => {
                let n = match v {
                    Value::String(s) => s.trim().parse::<u64>().ok(),
                    _ => as_u64(v),
                };
                let n = n.filter(|n| (1..=u64::from(u32::MAX)).contains(n));
                n.map(|n| Method::Grid(GridSize::CellsPerAxis(n as u32)))
                    .ok_or_else(|| {
                        OpError::request(format!(
                            "`{what}` must be a positive integer (cells per axis), got {v}"
                        ))
                    })
            }
            MethodKind::Quality => Ok(Method::Quality(match parse_amount(what, v)? {
                Amount::Absolute(x) => Length::Absolute(x),
                Amount::Percent(p) => Length::Relative(p / 100.0),
            })),
            MethodKind::Complexity => match parse_amount(what, v)? {
                Amount::Percent(p) if p < 100.0 => {
                    Ok(Method::Complexity(Count::Relative(p / 100.0)))
                }
                Amount::Percent(p) => Err(OpError::request(format!(
                    "`{what}` must be below 100% of the input's vertices, got {p}%"
                ))),
                Amount::Absolute(x) if x.fract() == 0.0 && x < 2f64.powi(63) => {
                    Ok(Method::Complexity(Count::Absolute(x as u64)))
                }
                Amount::Absolute(_) => Err(OpError::request(format!(
                    "`{what}` must be an integer number of vertices or a percentage such as \
                     \"20%\", got {v}"
                ))),
            },
        }
    }
}

/// The settings every level shares (`representative`, `weighting`, `triangulate`,
/// `preserve_boundaries`), for `method`, with the job's cancel flag.
///
/// # Errors
/// `invalid_request` naming the parameter and its value.
pub fn base_options(
    request: &Request,
    method: Method,
    ctx: &JobContext,
) -> Result<SimplifyOptions, OpError> {
    let representative = match request.str_param("representative")? {
        None | Some("barycenter") => Representative::Barycenter,
        Some("heaviest") => Representative::Heaviest,
        Some("quadric") => Representative::Quadric,
        Some(other) => {
            return Err(OpError::request(format!(
                "`representative` must be \"barycenter\", \"heaviest\" or \"quadric\", got \
                 {other:?}"
            )));
        }
    };
    let weighting = match request.str_param("weighting")? {
        None | Some("longest_edge") => Weighting::LongestEdge,
        Some("curvature") => Weighting::Curvature,
        Some("uniform") => Weighting::Uniform,
        Some(other) => {
            return Err(OpError::request(format!(
                "`weighting` must be \"longest_edge\", \"curvature\" or \"uniform\", got \
                 {other:?}"
            )));
        }
    };
    Ok(SimplifyOptions::new(method)
        .with_representative(representative)
        .with_weighting(weighting)
        .with_triangulate(bool_param(request, "triangulate")?.unwrap_or(false))
        .with_preserve_boundaries(bool_param(request, "preserve_boundaries")?.unwrap_or(false))
        .with_cancel(ctx.cancel_token().flag()))
}
