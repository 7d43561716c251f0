//! Validation of a document against docs/brep-format.md ("Validation"): the checks, face by
//! face and edge by edge, each refusal one [`ValidationError`] naming the face / loop / trim /
//! pole (or edge) at fault. The refusals are in [`crate::validation_error`], the tolerances in
//! [`crate::tolerances`].

use crate::bspline::KnotVector;
use crate::model::{
    BSplineCurve, BSplineSurface, Curve, Document, FORMAT, Frame, Surface, VERSION,
};
use crate::tolerances::{
    BOUNDS_TOLERANCE, CLOSURE_TOLERANCE, DIRECTION_TOLERANCE, RANGE_TOLERANCE,
};
use crate::validation_error::{Place, ValidationError};
use crate::vector::{Point, Point2};
use std::collections::{HashMap, HashSet};

/// Every error of `doc`, in document order (faces, then edges). Checks that depend on an
/// element already refused (a loop's closure when one of its curves is invalid) are skipped,
/// so each error is a cause, not a consequence.
pub fn validate(doc: &Document) -> Vec<ValidationError> {
    let mut c = Checker::default();
    if doc.format != FORMAT {
        c.push(ValidationError::Format {
            found: serde_json::Value::from(doc.format.clone()).to_string(),
        });
    }
    if doc.version != VERSION {
        c.push(ValidationError::Version {
            found: doc.version.to_string(),
        });
    }
    let edge_ids: HashSet<u64> = doc.edges.iter().flatten().map(|e| e.id).collect();
    let mut face_index: HashMap<u64, usize> = HashMap::new();
    for (index, face) in doc.faces.iter().enumerate() {
        if let Some(&first) = face_index.get(&face.id) {
            c.push(ValidationError::DuplicateFaceId {
                face: face.id,
                first,
                second: index,
            });
        } else {
            face_index.insert(face.id, index);
        }
        c.face(face, &edge_ids);
    }
    let mut seen = HashSet::new();
    for edge in doc.edges.iter().flatten() {
        let at = Place::Edge { edge: edge.id };
        if !seen.insert(edge.id) {
            c.push(ValidationError::DuplicateEdgeId { edge: edge.id });
        }
        if let Some(curve) = &edge.curve
            && c.curve(curve, &at)
        {
            c.range(curve, edge.range, &at);
        }
        c.tolerances(edge, &at);
        for &face in &edge.faces {
            if !face_index.contains_key(&face) {
                c.push(ValidationError::UnknownFace {
                    edge: edge.id,
                    face,
                });
            }
        }
    }
    c.errors
}

#[derive(Default)]
struct Checker {
    errors: Vec<ValidationError>,
}

impl Checker {
    fn push(&mut self, e: ValidationError) {
        self.errors.push(e);
    }

    /// Pushes `e` and returns false when `bad`.
    fn check(&mut self, bad: bool, e: impl FnOnce() -> ValidationError) -> bool {
        if bad {
            self.push(e());
        }
        !bad
    }

    fn finite<V: Finite>(&mut self, v: &V, at: &Place, field: impl Into<String>) -> bool {
        self.check(!v.all_finite(), || ValidationError::NonFinite {
            at: at.clone(),
            field: field.into(),
        })
    }

    fn unit<V: Point>(&mut self, v: &V, at: &Place, field: &'static str) -> bool {
        if !self.finite(v, at, field) {
            return false;
        }
        let length = v.length();
        self.check((length - 1.0).abs() > DIRECTION_TOLERANCE, || {
            ValidationError::NotUnit {
                at: at.clone(),
                field,
                length,
            }
        })
    }

    fn axes<V: Point>(&mut self, x: &V, y: &V, at: &Place) -> bool {
        let ok = self.unit(x, at, "x_dir") & self.unit(y, at, "y_dir");
        if !ok {
            return false;
        }
        let dot = x.dot(*y);
        self.check(dot.abs() > DIRECTION_TOLERANCE, || {
            ValidationError::NotOrthogonal {
                at: at.clone(),
                dot,
            }
        })
    }

    fn frame(&mut self, f: &Frame, at: &Place) -> bool {
        self.finite(&f.origin, at, "origin") & self.axes(&f.x_dir, &f.y_dir, at)
    }

    /// An edge's optional `tolerance` and `vertex_tolerances`: finite and ≥ 0 (their
    /// length, 2, is the type's).
    fn tolerances(&mut self, edge: &crate::model::Edge, at: &Place) {
        let vt = edge.vertex_tolerances;
        let fields = [
            ("tolerance", edge.tolerance),
            ("vertex_tolerances[0]", vt.map(|v| v[0])),
            ("vertex_tolerances[1]", vt.map(|v| v[1])),
        ];
        for (field, value) in fields {
            let Some(value) = value else { continue };
            if self.finite(&[value, 0.0], at, field) {
                self.check(value < 0.0, || ValidationError::NegativeTolerance {
                    at: at.clone(),
                    field,
                    value,
                });
            }
        }
    }

    fn positive(&mut self, value: f64, at: &Place, field: &'static str) -> bool {
        if !self.finite(&[value, 0.0], at, field) {
            return false;
        }
        self.check(value <= 0.0, || ValidationError::Radius {
            at: at.clone(),
            field,
            value,
        })
    }

    fn knots(
        &mut self,
        degree: usize,
        knots: &[f64],
        mults: &[u32],
        periodic: bool,
        at: &Place,
        direction: &'static str,
    ) -> Option<KnotVector> {
        KnotVector::new(degree, knots, mults, periodic)
            .map_err(|error| {
                self.push(ValidationError::Knots {
                    at: at.clone(),
                    direction,
                    error,
                })
            })
            .ok()
    }

    /// A weight list (or `None`): counts, finite and positive values.
    fn weights(&mut self, weights: Option<&[f64]>, poles: usize, at: &Place, row: Option<usize>) {
        let Some(w) = weights else { return };
        let prefix = row.map_or(String::new(), |i| format!("[{i}]"));
        if !self.check(w.len() != poles, || ValidationError::WeightCount {
            at: at.clone(),
            what: format!("weights{prefix}"),
            got: w.len(),
            expected: poles,
        }) {
            return;
        }
        if let Some((j, &value)) = w
            .iter()
            .enumerate()
            .find(|(_, v)| !(**v > 0.0 && v.is_finite()))
        {
            let pole = match row {
                Some(i) => format!("[{i}][{j}]"),
                None => j.to_string(),
            };
            if value.is_finite() {
                self.push(ValidationError::Weight {
                    at: at.clone(),
                    pole,
                    value,
                });
            } else {
                self.push(ValidationError::NonFinite {
                    at: at.clone(),
                    field: format!("the weight of pole {pole}"),
                });
            }
        }
    }

    fn bspline_curve<P: Point>(&mut self, b: &BSplineCurve<P>, at: &Place) -> bool {
        let Some(kv) = self.knots(b.degree, &b.knots, &b.mults, b.periodic, at, "") else {
            return false;
        };
        let before = self.errors.len();
        if self.check(b.poles.len() != kv.pole_count(), || {
            ValidationError::PoleCount {
                at: at.clone(),
                what: "poles".into(),
                got: b.poles.len(),
                expected: kv.pole_count(),
            }
        }) {
            if let Some(i) = b.poles.iter().position(|p| !p.is_finite()) {
                self.finite(&b.poles[i], at, format!("pole {i}"));
            }
            self.weights(b.weights.as_deref(), b.poles.len(), at, None);
        }
        self.errors.len() == before
    }

    fn bspline_surface(&mut self, b: &BSplineSurface, at: &Place) -> bool {
        let ku = self.knots(b.degree_u, &b.knots_u, &b.mults_u, b.periodic_u, at, "u: ");
        let kv = self.knots(b.degree_v, &b.knots_v, &b.mults_v, b.periodic_v, at, "v: ");
        let (Some(ku), Some(kv)) = (ku, kv) else {
            return false;
        };
        let before = self.errors.len();
        if !self.check(b.poles.len() != ku.pole_count(), || {
            ValidationError::PoleCount {
                at: at.clone(),
                what: "poles (rows in u)".into(),
                got: b.poles.len(),
                expected: ku.pole_count(),
            }
        }) {
            return false;
        }
        for (i, row) in b.poles.iter().enumerate() {
            if !self.check(row.len() != kv.pole_count(), || {
                ValidationError::PoleCount {
                    at: at.clone(),
                    what: format!("poles[{i}] (in v)"),
                    got: row.len(),
                    expected: kv.pole_count(),
                }
            }) {
                return false;
            }
            if let Some(j) = row.iter().position(|p| !p.is_finite()) {
                self.finite(&row[j], at, format!("pole [{i}][{j}]"));
                return false;
            }
        }
        if let Some(w) = &b.weights {
            if !self.check(w.len() != b.poles.len(), || ValidationError::WeightCount {
                at: at.clone(),
                what: "weights (rows in u)".into(),
                got: w.len(),
                expected: b.poles.len(),
            }) {
                return false;
            }
            for (i, row) in w.iter().enumerate() {
                self.weights(Some(row), kv.pole_count(), at, Some(i));
            }
        }
        self.errors.len() == before
    }

    fn curve<P: Point>(&mut self, curve: &Curve<P>, at: &Place) -> bool {
        match curve {
            Curve::Line { origin, dir } => {
                self.finite(origin, at, "origin") & self.unit(dir, at, "dir")
            }
            Curve::Circle {
                center,
                x_dir,
                y_dir,
                radius,
            } => {
                self.finite(center, at, "center")
                    & self.axes(x_dir, y_dir, at)
                    & self.positive(*radius, at, "radius")
            }
            Curve::Ellipse {
                center,
                x_dir,
                y_dir,
                major_radius,
                minor_radius,
            } => {
                self.finite(center, at, "center")
                    & self.axes(x_dir, y_dir, at)
                    & self.positive(*major_radius, at, "major_radius")
                    & self.positive(*minor_radius, at, "minor_radius")
            }
            Curve::Bspline(b) => self.bspline_curve(b, at),
        }
    }

    /// A curve's range: finite, not empty, within a non-periodic B-spline's knots.
    fn range<P: Point>(&mut self, curve: &Curve<P>, range: [f64; 2], at: &Place) -> bool {
        if !self.finite(&range, at, "range") {
            return false;
        }
        if !self.check(range[0] == range[1], || ValidationError::EmptyRange {
            at: at.clone(),
            t: range[0],
        }) {
            return false;
        }
        if let Curve::Bspline(b) = curve
            && !b.periodic
        {
            let domain = [b.knots[0], b.knots[b.knots.len() - 1]];
            let tol = RANGE_TOLERANCE * (domain[1] - domain[0]);
            let (lo, hi) = (range[0].min(range[1]), range[0].max(range[1]));
            return self.check(lo < domain[0] - tol || hi > domain[1] + tol, || {
                ValidationError::RangeOutsideKnots {
                    at: at.clone(),
                    range,
                    domain,
                }
            });
        }
        true
    }

    fn surface(&mut self, s: &Surface, face: u64) -> bool {
        let at = Place::Surface { face };
        match s {
            Surface::Plane { frame } => self.frame(frame, &at),
            Surface::Cylinder { frame, radius } | Surface::Sphere { frame, radius } => {
                self.frame(frame, &at) & self.positive(*radius, &at, "radius")
            }
            Surface::Cone {
                frame,
                radius,
                semi_angle,
            } => {
                let mut ok = self.frame(frame, &at);
                ok &= self.finite(&[*radius, *semi_angle], &at, "radius / semi_angle")
                    && self.check(*radius < 0.0, || ValidationError::ConeRadius {
                        at: at.clone(),
                        value: *radius,
                    })
                    && self.check(
                        semi_angle.abs() <= 1e-12
                            || semi_angle.abs() >= std::f64::consts::FRAC_PI_2 - 1e-12,
                        || ValidationError::SemiAngle {
                            at: at.clone(),
                            value: *semi_angle,
                        },
                    );
                ok
            }
            Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            } => {
                self.frame(frame, &at)
                    & self.positive(*major_radius, &at, "major_radius")
                    & self.positive(*minor_radius, &at, "minor_radius")
            }
            Surface::Revolution {
                axis_origin,
                axis_dir,
                curve,
            } => {
                self.finite(axis_origin, &at, "axis_origin")
                    & self.unit(axis_dir, &at, "axis_dir")
                    & self.curve(curve.as_ref(), &Place::SurfaceCurve { face })
            }
            Surface::Extrusion { direction, curve } => {
                self.unit(direction, &at, "direction")
                    & self.curve(curve.as_ref(), &Place::SurfaceCurve { face })
            }
            Surface::Bspline(b) => self.bspline_surface(b, &at),
        }
    }

    fn face(&mut self, face: &crate::model::Face, edge_ids: &HashSet<u64>) {
        let id = face.id;
        self.surface(&face.surface, id);
        let b = face.bounds;
        let bounds_ok = if !b.iter().all(|x| x.is_finite()) {
            self.push(ValidationError::NonFinite {
                at: Place::Face { face: id },
                field: "bounds".into(),
            });
            false
        } else {
            self.check(!(b[0] < b[1] && b[2] < b[3]), || ValidationError::Bounds {
                face: id,
                bounds: b,
            })
        };
        let size = ((b[1] - b[0]).powi(2) + (b[3] - b[2]).powi(2)).sqrt();
        for (l, lp) in face.loops.iter().enumerate() {
            if !self.check(lp.trims.is_empty(), || ValidationError::EmptyLoop {
                face: id,
                loop_index: l,
            }) {
                continue;
            }
            let mut loop_ok = bounds_ok;
            for (t, trim) in lp.trims.iter().enumerate() {
                let at = Place::Trim {
                    face: id,
                    loop_index: l,
                    trim: t,
                };
                let ok = self.curve(&trim.curve, &at) && self.range(&trim.curve, trim.range, &at);
                loop_ok &= ok;
                if let Some(edge) = trim.edge
                    && !edge_ids.contains(&edge)
                {
                    self.push(ValidationError::UnknownEdge {
                        face: id,
                        loop_index: l,
                        trim: t,
                        edge,
                    });
                }
            }
            if loop_ok {
                self.loop_geometry(face, l, size);
            }
        }
    }

    /// Bounds, closure and orientation of loop `l`, whose trims are valid.
    fn loop_geometry(&mut self, face: &crate::model::Face, l: usize, size: f64) {
        let id = face.id;
        let b = face.bounds;
        let trims = &face.loops[l].trims;
        let slack = BOUNDS_TOLERANCE * size;
        let mut polyline: Vec<Point2> = Vec::new();
        for (t, trim) in trims.iter().enumerate() {
            let [t0, t1] = trim.range;
            let n = trim.curve.segments(t0, t1);
            for k in 0..=n {
                let s = t0 + (t1 - t0) * (k as f64 / n as f64);
                let p = trim.curve.point(s);
                let outside = p[0] < b[0] - slack
                    || p[0] > b[1] + slack
                    || p[1] < b[2] - slack
                    || p[1] > b[3] + slack;
                if outside {
                    self.push(ValidationError::OutsideBounds {
                        face: id,
                        loop_index: l,
                        trim: t,
                        t: s,
                        point: p,
                        bounds: b,
                    });
                    return;
                }
                if k < n {
                    polyline.push(p);
                }
            }
        }
        let tolerance = CLOSURE_TOLERANCE * size;
        let mut closed = true;
        for (t, trim) in trims.iter().enumerate() {
            let next = (t + 1) % trims.len();
            let end = trim.curve.point(trim.range[1]);
            let start = trims[next].curve.point(trims[next].range[0]);
            let gap = (end - start).length();
            if gap > tolerance {
                self.push(ValidationError::OpenLoop {
                    face: id,
                    loop_index: l,
                    trim: t,
                    next,
                    gap,
                    tolerance,
                });
                closed = false;
            }
        }
        if !closed {
            return;
        }
        let area = signed_area(&polyline);
        if l == 0 {
            self.check(area <= 0.0, || ValidationError::OuterClockwise {
                face: id,
                area,
            });
        } else {
            self.check(area >= 0.0, || ValidationError::HoleCounterClockwise {
                face: id,
                loop_index: l,
                area,
            });
        }
    }
}

/// What [`Checker::finite`] checks: a point (glam's `is_finite`) or a few plain numbers
/// (a range, a radius).
trait Finite {
    fn all_finite(&self) -> bool;
}

impl<P: Point> Finite for P {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}

impl<const N: usize> Finite for [f64; N] {
    fn all_finite(&self) -> bool {
        self.iter().all(|c| c.is_finite())
    }
}

/// The signed area of a closed polygon (shoelace; positive when counter-clockwise).
pub fn signed_area(points: &[Point2]) -> f64 {
    let Some(&o) = points.first() else {
        return 0.0;
    };
    // Relative to the first point, so large parameter offsets do not cost precision.
    let mut twice = 0.0;
    for w in 0..points.len() {
        let a = points[w] - o;
        let b = points[(w + 1) % points.len()] - o;
        twice += a[0] * b[1] - a[1] * b[0];
    }
    twice / 2.0
}
