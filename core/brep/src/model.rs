//! The document as serde reads it (docs/brep-format.md): faces with their surface and trim
//! loops, shared edges, and the surface / curve types, tagged on `type`. The types are plain
//! data mirroring the JSON one to one, so what the exporter writes is what the evaluators use;
//! invariants are checked by [`crate::validate`], not by the types. Points and vectors are
//! glam's [`glam::DVec2`] / [`glam::DVec3`] ([`Point2`], [`Point3`], in [`crate::vector`]), which glam's `serde`
//! feature reads and writes as the plain `[u, v]` / `[x, y, z]` arrays of the format.

use crate::bspline::KnotVector;
use crate::knot_cache::KnotCache;
use crate::vector::{Point2, Point3};
use serde::{Deserialize, Serialize};

/// The value of the document's `format` field.
pub const FORMAT: &str = "tessd-brep";

/// The format version this crate reads and writes.
pub const VERSION: u64 = 1;

/// A whole exchange document: a list of faces and, when the source has topology, the edges
/// they share.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Document {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`] for documents this crate accepts.
    pub version: u64,
    /// The length unit of every world coordinate.
    pub units: Units,
    /// Free text naming where the faces came from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The faces.
    pub faces: Vec<Face>,
    /// The shared edges; `None` for sources without topology (unsewn surfaces).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edges: Option<Vec<Edge>>,
}

/// The length unit of world coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Units {
    /// Millimetres.
    #[serde(rename = "mm")]
    Millimetres,
    /// Centimetres.
    #[serde(rename = "cm")]
    Centimetres,
    /// Metres.
    #[serde(rename = "m")]
    Metres,
    /// Inches.
    #[serde(rename = "in")]
    Inches,
}

impl Units {
    /// Every unit, in the order of their names in messages ("mm", "cm", "m", "in").
    pub const ALL: [Units; 4] = [
        Units::Millimetres,
        Units::Centimetres,
        Units::Metres,
        Units::Inches,
    ];

    /// The unit of a name as written in documents and parameters (`"mm"`, `"cm"`, `"m"`,
    /// `"in"`), `None` for any other.
    pub fn from_name(name: &str) -> Option<Units> {
        Units::ALL.into_iter().find(|u| u.name() == name)
    }

    /// The name as written in the document.
    pub fn name(self) -> &'static str {
        match self {
            Units::Millimetres => "mm",
            Units::Centimetres => "cm",
            Units::Metres => "m",
            Units::Inches => "in",
        }
    }

    /// Metres per unit (USD's `metersPerUnit`).
    pub fn meters_per_unit(self) -> f64 {
        match self {
            Units::Millimetres => 0.001,
            Units::Centimetres => 0.01,
            Units::Metres => 1.0,
            Units::Inches => 0.0254,
        }
    }
}

/// A trimmed face: a region of its surface's parameter plane bounded by loops.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Face {
    /// Unique among the faces (the source's face index), so errors and results can name it.
    pub id: u64,
    /// Whether the face's normal is the surface's `∂S/∂u × ∂S/∂v` negated.
    #[serde(default)]
    pub reversed: bool,
    /// The underlying (basis) surface.
    pub surface: Surface,
    /// The parameter range `[u0, u1, v0, v1]` every trim lies in.
    pub bounds: [f64; 4],
    /// The outer loop first (counter-clockwise), then the holes (clockwise); empty means the
    /// whole `bounds` rectangle.
    #[serde(default)]
    pub loops: Vec<Loop>,
}

/// A closed chain of trims in the parameter plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Loop {
    /// The trims in order, each starting where the previous ends (JSON field `edges`, as OCP
    /// calls a wire's members).
    #[serde(rename = "edges")]
    pub trims: Vec<Trim>,
}

/// One piece of a loop: a 2D curve walked over a parameter range.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trim {
    /// The curve in (u, v).
    pub curve: Curve2,
    /// `[t0, t1]`; `t0 > t1` walks the curve backwards.
    pub range: [f64; 2],
    /// The shared edge this trim lies on, if the source has topology.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge: Option<u64>,
}

/// A shared edge: its 3D curve and the faces it bounds, so tessellation can discretise it once
/// for all of them and neighbouring faces meet without cracks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// Unique among the edges.
    pub id: u64,
    /// The 3D curve; `None` for degenerate edges (a sphere's poles).
    #[serde(default)]
    pub curve: Option<Curve3>,
    /// `[t0, t1]` on the curve.
    pub range: [f64; 2],
    /// The ids of the faces the edge bounds.
    #[serde(default)]
    pub faces: Vec<u64>,
    /// The edge's tolerance (OCP `BRep_Tool::Tolerance(edge)`: how far its pcurves on their
    /// surfaces may stray from the 3D curve), world units, ≥ 0; `None` when not written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// The tolerances of the edge's vertices at `range[0]` and at `range[1]` (OCP
    /// `BRep_Tool::Tolerance(vertex)`: the radius of the ball every edge end meeting there lies
    /// in), world units, ≥ 0; `None` when not written. Tessellation merges edge ends within
    /// them (capped, see `tessd-tessellate`'s `edges` module), closing the small holes real
    /// files leave where edges meet.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex_tolerances: Option<[f64; 2]>,
}

/// A right-handed orthonormal frame (OCP's `gp_Ax3` with a direct orientation is written with
/// `z_dir = x_dir × y_dir`; an indirect one simply has its `y_dir` negated).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// The origin.
    pub origin: Point3,
    /// The first axis (unit).
    pub x_dir: Point3,
    /// The second axis (unit, orthogonal to `x_dir`).
    pub y_dir: Point3,
}

impl Frame {
    /// `x_dir × y_dir`.
    pub fn z_dir(&self) -> Point3 {
        self.x_dir.cross(self.y_dir)
    }
}

/// The basis surface of a face; the parametrisations are OCP's (`Geom_*Surface`), so OCP's
/// pcurves need no conversion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Surface {
    /// `origin + u·x + v·y`.
    Plane {
        /// The frame.
        #[serde(flatten)]
        frame: Frame,
    },
    /// `origin + r(cos u·x + sin u·y) + v·z`.
    Cylinder {
        /// The frame.
        #[serde(flatten)]
        frame: Frame,
        /// The radius (> 0).
        radius: f64,
    },
    /// `origin + (r + v sin a)(cos u·x + sin u·y) + v cos a·z`.
    Cone {
        /// The frame.
        #[serde(flatten)]
        frame: Frame,
        /// The radius at v = 0 (≥ 0).
        radius: f64,
        /// The half angle at the apex, radians, 0 < |a| < π/2.
        semi_angle: f64,
    },
    /// `origin + r cos v (cos u·x + sin u·y) + r sin v·z`.
    Sphere {
        /// The frame.
        #[serde(flatten)]
        frame: Frame,
        /// The radius (> 0).
        radius: f64,
    },
    /// `origin + (R + r cos v)(cos u·x + sin u·y) + r sin v·z`.
    Torus {
        /// The frame.
        #[serde(flatten)]
        frame: Frame,
        /// R (> 0).
        major_radius: f64,
        /// r (> 0).
        minor_radius: f64,
    },
    /// The curve at parameter v rotated by angle u about the axis.
    Revolution {
        /// A point of the axis.
        axis_origin: Point3,
        /// The axis direction (unit); u turns counter-clockwise about it.
        axis_dir: Point3,
        /// The meridian.
        curve: Box<Curve3>,
    },
    /// `C(u) + v·direction`.
    Extrusion {
        /// The direction (unit).
        direction: Point3,
        /// The swept curve.
        curve: Box<Curve3>,
    },
    /// A rational tensor-product B-spline (OCP `Geom_BSplineSurface` conventions).
    Bspline(BSplineSurface),
}

impl Surface {
    /// The `type` name as written in the document.
    pub fn type_name(&self) -> &'static str {
        match self {
            Surface::Plane { .. } => "plane",
            Surface::Cylinder { .. } => "cylinder",
            Surface::Cone { .. } => "cone",
            Surface::Sphere { .. } => "sphere",
            Surface::Torus { .. } => "torus",
            Surface::Revolution { .. } => "revolution",
            Surface::Extrusion { .. } => "extrusion",
            Surface::Bspline(_) => "bspline",
        }
    }

    /// Every surface `type` name, in the document's order.
    pub const TYPE_NAMES: [&'static str; 8] = [
        "plane",
        "cylinder",
        "cone",
        "sphere",
        "torus",
        "revolution",
        "extrusion",
        "bspline",
    ];
}

/// A B-spline surface: poles `[nu][nv]`, distinct knots with multiplicities in each direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BSplineSurface {
    /// Degree in u (≥ 1).
    pub degree_u: usize,
    /// Degree in v (≥ 1).
    pub degree_v: usize,
    /// The control points, `poles[i][j]` for u-index i and v-index j.
    pub poles: Vec<Vec<Point3>>,
    /// The weights `[nu][nv]` (all > 0), or `None` for a polynomial surface.
    #[serde(default)]
    pub weights: Option<Vec<Vec<f64>>>,
    /// Distinct knots in u, strictly increasing.
    pub knots_u: Vec<f64>,
    /// Their multiplicities.
    pub mults_u: Vec<u32>,
    /// Distinct knots in v, strictly increasing.
    pub knots_v: Vec<f64>,
    /// Their multiplicities.
    pub mults_v: Vec<u32>,
    /// Whether the surface is periodic in u (poles wrap around).
    #[serde(default)]
    pub periodic_u: bool,
    /// Whether the surface is periodic in v.
    #[serde(default)]
    pub periodic_v: bool,
    /// The knot vectors built on first evaluation (not part of the format).
    #[serde(skip)]
    pub cache: KnotCache,
}

/// A curve of the parameter plane (a trim's pcurve).
pub type Curve2 = Curve<Point2>;

/// A curve of space (an edge, a revolution's meridian, an extrusion's profile).
pub type Curve3 = Curve<Point3>;

/// A curve with 2 or 3 coordinates per point; the same types in both dimensions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
#[serde(bound(
    serialize = "P: Serialize",
    deserialize = "P: Deserialize<'de> + crate::vector::Point"
))]
pub enum Curve<P> {
    /// `origin + t·dir`.
    Line {
        /// A point of the line (t = 0).
        origin: P,
        /// The direction (unit).
        dir: P,
    },
    /// `center + r(cos t·x + sin t·y)`.
    Circle {
        /// The centre.
        center: P,
        /// The direction of t = 0 (unit).
        x_dir: P,
        /// The direction of t = π/2 (unit, orthogonal to `x_dir`); in 2D, `x_dir` turned +90°
        /// for a counter-clockwise circle, −90° for a clockwise one.
        y_dir: P,
        /// The radius (> 0).
        radius: f64,
    },
    /// `center + a cos t·x + b sin t·y`.
    Ellipse {
        /// The centre.
        center: P,
        /// The major axis (unit).
        x_dir: P,
        /// The minor axis (unit, orthogonal to `x_dir`).
        y_dir: P,
        /// a (> 0).
        major_radius: f64,
        /// b (> 0).
        minor_radius: f64,
    },
    /// A rational B-spline (OCP `Geom(2d)_BSplineCurve` conventions).
    Bspline(BSplineCurve<P>),
}

impl<P> Curve<P> {
    /// The `type` name as written in the document.
    pub fn type_name(&self) -> &'static str {
        match self {
            Curve::Line { .. } => "line",
            Curve::Circle { .. } => "circle",
            Curve::Ellipse { .. } => "ellipse",
            Curve::Bspline(_) => "bspline",
        }
    }

    /// Every curve `type` name, in the document's order.
    pub const TYPE_NAMES: [&'static str; 4] = ["line", "circle", "ellipse", "bspline"];
}

/// A B-spline curve: poles, distinct knots with multiplicities.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "P: Serialize",
    deserialize = "P: Deserialize<'de> + crate::vector::Point"
))]
pub struct BSplineCurve<P> {
    /// The degree (≥ 1).
    pub degree: usize,
    /// The control points.
    pub poles: Vec<P>,
    /// One weight per pole (all > 0), or `None` for a polynomial curve.
    #[serde(default)]
    pub weights: Option<Vec<f64>>,
    /// Distinct knots, strictly increasing.
    pub knots: Vec<f64>,
    /// Their multiplicities.
    pub mults: Vec<u32>,
    /// Whether the curve is periodic (poles wrap around; first and last multiplicities equal).
    #[serde(default)]
    pub periodic: bool,
    /// The knot vector built on first evaluation (not part of the format).
    #[serde(skip)]
    pub cache: KnotCache<KnotVector>,
}
