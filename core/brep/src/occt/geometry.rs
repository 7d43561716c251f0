//! Step 3: the geometry sections — `Curve2ds`, `Curves`, `Polygon3D`,
//! `PolygonOnTriangulations`, `Surfaces`, `Triangulations` — read into tables of raw records
//! (the shapes refer to them by number).
//!
//! Records are kept as OCCT builds them when it reads the text (`GeomTools_*Set`), so the later
//! conversion sees the same objects the Python exporters see: directions normalised, a conic's
//! frame rebuilt from its axis and X direction (`gp_Ax2`, `gp_Ax22d`), a plane's Y kept on its
//! side (`gp_Ax3`, direct or not), B-splines and Béziers checked as OCCT's constructors check
//! them and made non-rational when their weights are all equal. Polygons and triangulations are
//! read past (their counts checked), never stored: the document has no use for them.

use super::OcctError;
use super::lexer::Lexer;
use super::locations::normalized;
use crate::model::{BSplineCurve, BSplineSurface};
use crate::vector::Point;
use crate::vector::{Point2, Point3};

/// Records nest (trimmed, offset, extrusion, revolution): deeper than this is refused rather
/// than recursed into.
const MAX_DEPTH: usize = 32;

/// The largest degree OCCT accepts.
const MAX_DEGREE: i64 = 25;

/// A 2D or 3D curve record.
#[derive(Clone, Debug)]
pub(crate) enum RawCurve<P> {
    /// `origin + t·dir`.
    Line {
        /// Origin.
        origin: P,
        /// Unit direction.
        dir: P,
    },
    /// A circle on its frame.
    Circle {
        /// Centre.
        center: P,
        /// X direction.
        x: P,
        /// Y direction.
        y: P,
        /// Radius.
        radius: f64,
    },
    /// An ellipse on its frame.
    Ellipse {
        /// Centre.
        center: P,
        /// Major axis.
        x: P,
        /// Minor axis.
        y: P,
        /// Major radius.
        major: f64,
        /// Minor radius.
        minor: f64,
    },
    /// `origin + t²/(4f)·x + t·y`.
    Parabola {
        /// Apex.
        origin: P,
        /// Axis (towards the focus).
        x: P,
        /// Y direction.
        y: P,
        /// Focal length.
        focal: f64,
    },
    /// `center + a cosh t·x + b sinh t·y`.
    Hyperbola {
        /// Centre.
        center: P,
        /// Major axis.
        x: P,
        /// Minor axis.
        y: P,
        /// Major radius.
        major: f64,
        /// Minor radius.
        minor: f64,
    },
    /// A B-spline (Béziers are read into their identical B-spline).
    Bspline(BSplineCurve<P>),
    /// A trimmed curve: its basis on `[u1, u2]`, same parameter.
    Trimmed {
        /// Start.
        u1: f64,
        /// End.
        u2: f64,
        /// The basis.
        basis: Box<RawCurve<P>>,
    },
    /// An offset curve (no exact exchange-format type).
    Offset,
}

/// A `gp_Ax3`: an origin, the main axis, X, and Y on the side the record chose (`y = ±axis ×
/// x`: a left-handed frame is "indirect").
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ax3 {
    /// Origin.
    pub origin: Point3,
    /// Main direction.
    pub axis: Point3,
    /// X direction.
    pub x: Point3,
    /// Y direction.
    pub y: Point3,
}

/// A surface record.
#[derive(Clone, Debug)]
pub(crate) enum RawSurface {
    /// A plane.
    Plane(Ax3),
    /// A cylinder.
    Cylinder(Ax3, f64),
    /// A cone: reference radius, semi-angle.
    Cone(Ax3, f64, f64),
    /// A sphere.
    Sphere(Ax3, f64),
    /// A torus: major and minor radii.
    Torus(Ax3, f64, f64),
    /// A linear extrusion of a curve.
    Extrusion {
        /// Direction.
        dir: Point3,
        /// The swept curve.
        curve: RawCurve<Point3>,
    },
    /// A surface of revolution.
    Revolution {
        /// A point of the axis.
        origin: Point3,
        /// The axis direction.
        dir: Point3,
        /// The meridian.
        curve: RawCurve<Point3>,
    },
    /// A B-spline surface (Béziers are read into their identical B-spline).
    Bspline(BSplineSurface),
    /// A rectangular trimmed surface: its basis on `[u1, u2] × [v1, v2]`.
    Trimmed {
        /// `[u1, u2, v1, v2]`.
        bounds: [f64; 4],
        /// The basis.
        basis: Box<RawSurface>,
    },
    /// An offset surface (no exact exchange-format type).
    Offset,
}

/// The records of one section, with the line each starts on.
pub(crate) struct Table<T> {
    /// `(record, line)`, numbered from 1 by the text.
    pub items: Vec<(T, u32)>,
}

impl<T> Table<T> {
    /// Record `k` (1-based), if any.
    pub fn get(&self, k: usize) -> Option<&(T, u32)> {
        k.checked_sub(1).and_then(|i| self.items.get(i))
    }

    /// The number of records.
    pub fn len(&self) -> usize {
        self.items.len()
    }
}

/// The geometry sections.
pub(crate) struct Geometry {
    /// `Curve2ds`.
    pub curves2d: Table<RawCurve<Point2>>,
    /// `Curves`.
    pub curves: Table<RawCurve<Point3>>,
    /// `Surfaces`.
    pub surfaces: Table<RawSurface>,
}

impl Geometry {
    /// Reads the six sections in OCCT's order; the polygon and triangulation sections may be
    /// absent (OCCT's reader allows it).
    pub fn read(lx: &mut Lexer, version: u32) -> Result<Geometry, OcctError> {
        let curves2d = read_table(lx, "Curve2ds", |lx| read_curve::<Point2>(lx, 0))?;
        let curves = read_table(lx, "Curves", |lx| read_curve::<Point3>(lx, 0))?;
        skip_section(lx, "Polygon3D", skip_polygon3d)?;
        skip_section(lx, "PolygonOnTriangulations", skip_polygon_on_triangulation)?;
        let surfaces = read_table(lx, "Surfaces", |lx| read_surface(lx, 0))?;
        skip_section(lx, "Triangulations", |lx| skip_triangulation(lx, version))?;
        Ok(Geometry {
            curves2d,
            curves,
            surfaces,
        })
    }
}

fn read_table<T>(
    lx: &mut Lexer,
    section: &'static str,
    mut record: impl FnMut(&mut Lexer) -> Result<T, OcctError>,
) -> Result<Table<T>, OcctError> {
    lx.at(section, None);
    lx.expect(section)?;
    let n = lx.count("the record count", 4)?;
    let mut items = Vec::with_capacity(n);
    for i in 1..=n {
        lx.at(section, Some(i));
        let line = lx.peek().map_or(lx.token_line(), |t| t.line);
        items.push((record(lx)?, line));
    }
    Ok(Table { items })
}

fn skip_section(
    lx: &mut Lexer,
    section: &'static str,
    mut record: impl FnMut(&mut Lexer) -> Result<(), OcctError>,
) -> Result<(), OcctError> {
    lx.at(section, None);
    if lx.peek().map(|t| t.text) != Some(section) {
        return Ok(());
    }
    lx.expect(section)?;
    let n = lx.count("the record count", 4)?;
    for i in 1..=n {
        lx.at(section, Some(i));
        record(lx)?;
    }
    Ok(())
}

/// `k` items of `per` tokens each, checked against the text left (each token takes at least
/// two bytes with its separator) and skipped.
fn skip_items(lx: &mut Lexer, what: &str, k: usize, per: usize) -> Result<(), OcctError> {
    let tokens = k
        .checked_mul(per)
        .ok_or_else(|| lx.error(format!("{what}: count overflows")))?;
    let tokens = lx.check_count(what, tokens as i64, 2)?;
    lx.skip(tokens, what)
}

fn skip_polygon3d(lx: &mut Lexer) -> Result<(), OcctError> {
    let nodes = lx.count("the node count", 6)?;
    let params = lx.flag("the parameters flag")?;
    lx.real("the deflection")?;
    skip_items(lx, "the nodes", nodes, 3)?;
    if params {
        skip_items(lx, "the parameters", nodes, 1)?;
    }
    Ok(())
}

fn skip_polygon_on_triangulation(lx: &mut Lexer) -> Result<(), OcctError> {
    let nodes = lx.count("the node count", 2)?;
    skip_items(lx, "the node numbers", nodes, 1)?;
    lx.expect("p")?;
    lx.real("the deflection")?;
    if lx.flag("the parameters flag")? {
        skip_items(lx, "the parameters", nodes, 1)?;
    }
    Ok(())
}

fn skip_triangulation(lx: &mut Lexer, version: u32) -> Result<(), OcctError> {
    let nodes = lx.count("the node count", 6)?;
    let triangles = lx.count("the triangle count", 6)?;
    let uv = lx.flag("the UV flag")?;
    // Normals (and their flag) came with version 3.
    let normals = version >= 3 && lx.flag("the normals flag")?;
    lx.real("the deflection")?;
    skip_items(lx, "the nodes", nodes, 3)?;
    if uv {
        skip_items(lx, "the UV nodes", nodes, 2)?;
    }
    skip_items(lx, "the triangles", triangles, 3)?;
    if normals {
        skip_items(lx, "the normals", nodes, 3)?;
    }
    Ok(())
}

/// What differs between 2D and 3D records.
pub(crate) trait Space: Point {
    /// A conic's (X, Y) as OCCT builds its frame: 2D `gp_Ax22d(P, X, Y)` (Y turned ±90° from
    /// X by the sign of X × Y); 3D `gp_Ax2(P, N, X)` (X made normal to N, Y = N × X; the
    /// written Y is read past).
    fn conic_axes(lx: &mut Lexer) -> Result<(Self, Self), OcctError>;

    /// Reads past an offset curve's extra data (3D: its reference direction).
    fn offset_extra(lx: &mut Lexer) -> Result<(), OcctError>;
}

impl Space for Point2 {
    fn conic_axes(lx: &mut Lexer) -> Result<(Self, Self), OcctError> {
        let x: Point2 = dir(lx)?;
        let y: Point2 = dir(lx)?;
        let sense = x[0] * y[1] - x[1] * y[0];
        let y = if sense >= 0.0 {
            Point2::new(-x[1], x[0])
        } else {
            Point2::new(x[1], -x[0])
        };
        Ok((x, y))
    }

    fn offset_extra(_: &mut Lexer) -> Result<(), OcctError> {
        Ok(())
    }
}

impl Space for Point3 {
    fn conic_axes(lx: &mut Lexer) -> Result<(Self, Self), OcctError> {
        let n: Point3 = dir(lx)?;
        let vx: Point3 = dir(lx)?;
        let _: Point3 = dir(lx)?;
        let (x, y) = ax2_axes(n, vx).ok_or_else(|| lx.error("X direction parallel to the axis"))?;
        Ok((x, y))
    }

    fn offset_extra(lx: &mut Lexer) -> Result<(), OcctError> {
        let _: Point3 = dir(lx)?;
        Ok(())
    }
}

/// `gp_Ax2(P, N, Vx)`'s X and Y: X = N × (Vx × N) normalised, Y = N × X.
fn ax2_axes(n: Point3, vx: Point3) -> Option<(Point3, Point3)> {
    let x = n.cross(vx.cross(n));
    if x.length().is_nan() || x.length() <= 1e-300 {
        return None;
    }
    let x = normalized(x);
    Some((x, normalized(n.cross(x))))
}

fn point<P: Point>(lx: &mut Lexer) -> Result<P, OcctError> {
    let mut p = P::ZERO;
    for c in p.coords_mut() {
        *c = lx.real("a coordinate")?;
    }
    Ok(p)
}

fn dir<P: Point>(lx: &mut Lexer) -> Result<P, OcctError> {
    let d: P = point(lx)?;
    if d.length().is_nan() || d.length() <= 1e-300 {
        return Err(lx.error("a null direction"));
    }
    Ok(normalized(d))
}

fn positive(lx: &mut Lexer, what: &str) -> Result<f64, OcctError> {
    let v = lx.real(what)?;
    if v < 0.0 {
        return Err(lx.error(format!("negative {what} {v}")));
    }
    Ok(v)
}

fn read_curve<P: Space>(lx: &mut Lexer, depth: usize) -> Result<RawCurve<P>, OcctError> {
    if depth > MAX_DEPTH {
        return Err(lx.error(format!("curves nested deeper than {MAX_DEPTH}")));
    }
    let line = lx.peek().map_or(lx.token_line(), |t| t.line);
    Ok(match lx.int("the curve type")? {
        1 => RawCurve::Line {
            origin: point(lx)?,
            dir: dir(lx)?,
        },
        2 => {
            let center = point(lx)?;
            let (x, y) = P::conic_axes(lx)?;
            let radius = positive(lx, "radius")?;
            RawCurve::Circle {
                center,
                x,
                y,
                radius,
            }
        }
        3 => {
            let center = point(lx)?;
            let (x, y) = P::conic_axes(lx)?;
            let major = positive(lx, "major radius")?;
            let minor = positive(lx, "minor radius")?;
            RawCurve::Ellipse {
                center,
                x,
                y,
                major,
                minor,
            }
        }
        4 => {
            let origin = point(lx)?;
            let (x, y) = P::conic_axes(lx)?;
            let focal = positive(lx, "focal length")?;
            RawCurve::Parabola {
                origin,
                x,
                y,
                focal,
            }
        }
        5 => {
            let center = point(lx)?;
            let (x, y) = P::conic_axes(lx)?;
            let major = positive(lx, "major radius")?;
            let minor = positive(lx, "minor radius")?;
            RawCurve::Hyperbola {
                center,
                x,
                y,
                major,
                minor,
            }
        }
        6 => {
            let rational = lx.flag("the rational flag")?;
            let degree = lx.int_in("the degree", 1, MAX_DEGREE)? as usize;
            let (poles, weights) = read_poles::<P>(lx, degree + 1, rational)?;
            let mults = vec![degree as u32 + 1; 2];
            bspline_curve(
                lx,
                line,
                degree,
                poles,
                weights,
                vec![0.0, 1.0],
                mults,
                false,
            )?
        }
        7 => {
            let rational = lx.flag("the rational flag")?;
            let periodic = lx.flag("the periodic flag")?;
            let degree = lx.int_in("the degree", 1, MAX_DEGREE)? as usize;
            let n = lx.count("the pole count", 2 * P::DIM)?;
            let k = lx.count("the knot count", 4)?;
            let (poles, weights) = read_poles::<P>(lx, n, rational)?;
            let (knots, mults) = knots(lx, k)?;
            bspline_curve(lx, line, degree, poles, weights, knots, mults, periodic)?
        }
        8 => {
            let u1 = lx.real("the trim start")?;
            let u2 = lx.real("the trim end")?;
            let basis = Box::new(read_curve::<P>(lx, depth + 1)?);
            RawCurve::Trimmed { u1, u2, basis }
        }
        9 => {
            lx.real("the offset distance")?;
            P::offset_extra(lx)?;
            read_curve::<P>(lx, depth + 1)?;
            RawCurve::Offset
        }
        t => return Err(lx.error_at(line, format!("unknown curve type {t}"))),
    })
}

type Poles<P> = (Vec<P>, Option<Vec<f64>>);

fn read_poles<P: Point>(lx: &mut Lexer, n: usize, rational: bool) -> Result<Poles<P>, OcctError> {
    let per = P::DIM + usize::from(rational);
    lx.check_count("the pole count", (n * per) as i64, 2)?;
    let mut poles = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(if rational { n } else { 0 });
    for _ in 0..n {
        poles.push(point::<P>(lx)?);
        if rational {
            weights.push(lx.real("a weight")?);
        }
    }
    Ok((poles, rational.then_some(weights)))
}

fn knots(lx: &mut Lexer, k: usize) -> Result<(Vec<f64>, Vec<u32>), OcctError> {
    let mut knots = Vec::with_capacity(k);
    let mut mults = Vec::with_capacity(k);
    for _ in 0..k {
        knots.push(lx.real("a knot")?);
        mults.push(lx.int_in("a multiplicity", 1, MAX_DEGREE + 1)? as u32);
    }
    Ok((knots, mults))
}

/// Whether weights make a curve rational: OCCT's `Geom_BSplineCurve` drops them when they
/// are all equal (then the curve is polynomial, and the Python exporters write no weights).
fn weights_vary(w: &[f64]) -> bool {
    w.windows(2).any(|p| p[0] != p[1])
}

fn check_weights(lx: &Lexer, line: u32, w: &[f64]) -> Result<(), OcctError> {
    match w.iter().find(|&&x| x.is_nan() || x <= 0.0) {
        Some(x) => Err(lx.error_at(line, format!("weight {x} is not positive"))),
        None => Ok(()),
    }
}

#[allow(clippy::too_many_arguments)]
fn bspline_curve<P: Point>(
    lx: &Lexer,
    line: u32,
    degree: usize,
    poles: Vec<P>,
    weights: Option<Vec<f64>>,
    knots: Vec<f64>,
    mults: Vec<u32>,
    periodic: bool,
) -> Result<RawCurve<P>, OcctError> {
    let kv = crate::bspline::KnotVector::new(degree, &knots, &mults, periodic)
        .map_err(|e| lx.error_at(line, format!("B-spline: {e}")))?;
    if kv.pole_count() != poles.len() {
        return Err(lx.error_at(
            line,
            format!(
                "B-spline: {} poles, the knots give {}",
                poles.len(),
                kv.pole_count()
            ),
        ));
    }
    if let Some(w) = &weights {
        check_weights(lx, line, w)?;
    }
    Ok(RawCurve::Bspline(BSplineCurve {
        degree,
        poles,
        weights: weights.filter(|w| weights_vary(w)),
        knots,
        mults,
        periodic,
        cache: Default::default(),
    }))
}

fn ax3(lx: &mut Lexer) -> Result<Ax3, OcctError> {
    let origin = point(lx)?;
    let axis: Point3 = dir(lx)?;
    let vx: Point3 = dir(lx)?;
    let vy: Point3 = dir(lx)?;
    let (x, y) = ax2_axes(axis, vx).ok_or_else(|| lx.error("X direction parallel to the axis"))?;
    // `gp_Ax3(P, N, X)` is direct; the written Y on the other side makes it indirect.
    let direct = vy.dot(axis.cross(vx)) >= 0.0;
    let y = if direct { y } else { y * -1.0 };
    Ok(Ax3 { origin, axis, x, y })
}

fn read_surface(lx: &mut Lexer, depth: usize) -> Result<RawSurface, OcctError> {
    if depth > MAX_DEPTH {
        return Err(lx.error(format!("surfaces nested deeper than {MAX_DEPTH}")));
    }
    let line = lx.peek().map_or(lx.token_line(), |t| t.line);
    Ok(match lx.int("the surface type")? {
        1 => RawSurface::Plane(ax3(lx)?),
        2 => RawSurface::Cylinder(ax3(lx)?, positive(lx, "radius")?),
        3 => RawSurface::Cone(
            ax3(lx)?,
            positive(lx, "radius")?,
            lx.real("the semi-angle")?,
        ),
        4 => RawSurface::Sphere(ax3(lx)?, positive(lx, "radius")?),
        5 => RawSurface::Torus(
            ax3(lx)?,
            positive(lx, "major radius")?,
            positive(lx, "minor radius")?,
        ),
        6 => RawSurface::Extrusion {
            dir: dir(lx)?,
            curve: read_curve(lx, depth + 1)?,
        },
        7 => RawSurface::Revolution {
            origin: point(lx)?,
            dir: dir(lx)?,
            curve: read_curve(lx, depth + 1)?,
        },
        8 => {
            let ur = lx.flag("the u rational flag")?;
            let vr = lx.flag("the v rational flag")?;
            let du = lx.int_in("the u degree", 1, MAX_DEGREE)? as usize;
            let dv = lx.int_in("the v degree", 1, MAX_DEGREE)? as usize;
            let (poles, weights) = pole_grid(lx, du + 1, dv + 1, ur || vr)?;
            let mu = vec![du as u32 + 1; 2];
            let mv = vec![dv as u32 + 1; 2];
            let uv = ([0.0, 1.0].to_vec(), mu, [0.0, 1.0].to_vec(), mv);
            bspline_surface(lx, line, [du, dv], poles, weights, uv, [false; 2])?
        }
        9 => {
            let ur = lx.flag("the u rational flag")?;
            let vr = lx.flag("the v rational flag")?;
            let up = lx.flag("the u periodic flag")?;
            let vp = lx.flag("the v periodic flag")?;
            let du = lx.int_in("the u degree", 1, MAX_DEGREE)? as usize;
            let dv = lx.int_in("the v degree", 1, MAX_DEGREE)? as usize;
            let nu = lx.count("the u pole count", 2)?;
            let nv = lx.count("the v pole count", 2)?;
            let ku = lx.count("the u knot count", 4)?;
            let kv = lx.count("the v knot count", 4)?;
            let (poles, weights) = pole_grid(lx, nu, nv, ur || vr)?;
            let (knots_u, mults_u) = knots(lx, ku)?;
            let (knots_v, mults_v) = knots(lx, kv)?;
            let uv = (knots_u, mults_u, knots_v, mults_v);
            bspline_surface(lx, line, [du, dv], poles, weights, uv, [up, vp])?
        }
        10 => {
            let bounds = lx.reals::<4>("a trim bound")?;
            RawSurface::Trimmed {
                bounds,
                basis: Box::new(read_surface(lx, depth + 1)?),
            }
        }
        11 => {
            lx.real("the offset distance")?;
            read_surface(lx, depth + 1)?;
            RawSurface::Offset
        }
        t => return Err(lx.error_at(line, format!("unknown surface type {t}"))),
    })
}

type Grid = (Vec<Vec<Point3>>, Option<Vec<Vec<f64>>>);

fn pole_grid(lx: &mut Lexer, nu: usize, nv: usize, rational: bool) -> Result<Grid, OcctError> {
    let per = 3 + usize::from(rational);
    let tokens = nu
        .checked_mul(nv)
        .and_then(|n| n.checked_mul(per))
        .ok_or_else(|| lx.error("the pole count overflows"))?;
    lx.check_count("the pole count", tokens as i64, 2)?;
    let mut poles = Vec::with_capacity(nu);
    let mut weights = Vec::with_capacity(if rational { nu } else { 0 });
    for _ in 0..nu {
        let (row, w) = read_poles::<Point3>(lx, nv, rational)?;
        poles.push(row);
        if let Some(w) = w {
            weights.push(w);
        }
    }
    Ok((poles, rational.then_some(weights)))
}

/// Whether a surface's weights make it rational (`Geom_BSplineSurface`: two neighbours
/// differing by more than the float spacing at their size).
fn grid_weights_vary(w: &[Vec<f64>]) -> bool {
    let differ = |a: f64, b: f64| (a - b).abs() > ulp(a);
    let along_v = w
        .iter()
        .any(|row| row.windows(2).any(|p| differ(p[0], p[1])));
    let along_u = w
        .windows(2)
        .any(|rows| rows[0].iter().zip(&rows[1]).any(|(&a, &b)| differ(a, b)));
    along_u || along_v
}

/// The distance from `|x|` to the next larger float (OCCT's `Epsilon`).
fn ulp(x: f64) -> f64 {
    let a = x.abs();
    f64::from_bits(a.to_bits() + 1) - a
}

type KnotsUv = (Vec<f64>, Vec<u32>, Vec<f64>, Vec<u32>);

fn bspline_surface(
    lx: &Lexer,
    line: u32,
    [du, dv]: [usize; 2],
    poles: Vec<Vec<Point3>>,
    weights: Option<Vec<Vec<f64>>>,
    (knots_u, mults_u, knots_v, mults_v): KnotsUv,
    [up, vp]: [bool; 2],
) -> Result<RawSurface, OcctError> {
    let ku = crate::bspline::KnotVector::new(du, &knots_u, &mults_u, up)
        .map_err(|e| lx.error_at(line, format!("B-spline surface, u: {e}")))?;
    let kv = crate::bspline::KnotVector::new(dv, &knots_v, &mults_v, vp)
        .map_err(|e| lx.error_at(line, format!("B-spline surface, v: {e}")))?;
    let (nu, nv) = (poles.len(), poles.first().map_or(0, Vec::len));
    if (ku.pole_count(), kv.pole_count()) != (nu, nv) {
        return Err(lx.error_at(
            line,
            format!(
                "B-spline surface: {nu}×{nv} poles, the knots give {}×{}",
                ku.pole_count(),
                kv.pole_count()
            ),
        ));
    }
    if let Some(w) = &weights {
        for row in w {
            check_weights(lx, line, row)?;
        }
    }
    Ok(RawSurface::Bspline(BSplineSurface {
        degree_u: du,
        degree_v: dv,
        poles,
        weights: weights.filter(|w| grid_weights_vary(w)),
        knots_u,
        mults_u,
        knots_v,
        mults_v,
        periodic_u: up,
        periodic_v: vp,
        cache: Default::default(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry(text: &str) -> Result<Geometry, OcctError> {
        Geometry::read(&mut Lexer::new(text, 0, 1), 1)
    }

    #[test]
    fn records_are_read_as_occt_builds_them() {
        let g = geometry(
            "Curve2ds 2\n2 1 2 1 0 -0 -1 3\n8 -4 5\n1 1 2 1 0\nCurves 1\n\
             7 1 0 1 3 3 0 1 0 4 1 -2 0 4 2 3 0 4\n0 2 1 1 2 2\n\
             Polygon3D 0\nPolygonOnTriangulations 0\nSurfaces 2\n\
             1 0 0 3 0 0 1 1 0 0 0 -1 0\n2 0 0 0 0 0 1 1 0 0 0 1 0 4\nTriangulations 0\n",
        )
        .unwrap();
        // A clockwise 2D circle keeps its sense; Y is rebuilt from X.
        match &g.curves2d.items[0].0 {
            RawCurve::Circle { x, y, radius, .. } => {
                assert_eq!(
                    (*x, *y, *radius),
                    (Point2::new(1.0, 0.0), Point2::new(0.0, -1.0), 3.0)
                );
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            g.curves2d.items[1].0,
            RawCurve::Trimmed { u1: -4.0, .. }
        ));
        assert_eq!(g.curves2d.items[1].1, 3);
        // Equal weights: not rational.
        match &g.curves.items[0].0 {
            RawCurve::Bspline(b) => assert!(b.weights.is_none() && b.poles.len() == 3),
            other => panic!("{other:?}"),
        }
        match &g.surfaces.items[0].0 {
            RawSurface::Plane(a) => assert_eq!(a.y, Point3::new(0.0, -1.0, 0.0)),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn bad_records_name_their_line() {
        let e = geometry(
            "Curve2ds 0\nCurves 0\nPolygon3D 0\nPolygonOnTriangulations 0\nSurfaces 1\n12 0 0\n",
        )
        .err()
        .unwrap();
        assert_eq!(e.message, "line 6: Surfaces[1]: unknown surface type 12");
        let e = geometry("Curve2ds 1\n7 0 0 2 5 2 0 0 1 1 2 2 3 3 4 4 0 3 1 3\n")
            .err()
            .unwrap();
        assert!(
            e.message
                .contains("Curve2ds[1]: B-spline: 5 poles, the knots give 3"),
            "{e}"
        );
        let e = geometry("Curve2ds 1\n7 0 0 2 2000000000 2 0 0\n")
            .err()
            .unwrap();
        assert!(e.message.contains("more than the rest"), "{e}");
    }
}
