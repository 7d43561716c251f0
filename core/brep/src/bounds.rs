//! The bounding box of a document's geometry, from points ON the part: its shared edges' 3D
//! curves, each face's trims mapped onto its surface, and a grid of surface points inside each
//! face's trims (a dome or a sphere bulges past its boundary). Never from B-spline poles (their
//! hull over-estimates the surface) nor from untrimmed surfaces (a plane's `bounds` may be far
//! larger than its trimmed region). Relative tolerances ("0.05 % of the part") are taken of
//! its diagonal.

use crate::model::{Curve, Document, Face};
use crate::vector::Point;
use crate::vector::{Point2, Point3};

/// Grid intervals per parameter direction over a face's `bounds` (17 × 17 points, those inside
/// the trims kept).
pub const GRID: usize = 16;

/// The fewest segments a curve (edge or trim) is sampled with; more where
/// [`Curve::segments`] asks for more (conics, B-splines).
pub const CURVE_SEGMENTS: usize = 16;

/// An axis-aligned box of space, in the document's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingBox {
    /// The smallest coordinates.
    pub min: Point3,
    /// The largest coordinates.
    pub max: Point3,
}

impl BoundingBox {
    /// The box around one point.
    pub fn at(p: Point3) -> BoundingBox {
        BoundingBox { min: p, max: p }
    }

    /// Grows the box to hold `p`.
    pub fn add(&mut self, p: Point3) {
        // `f64::min` / `max` per coordinate (not glam's `DVec3::min`, a `<` select): the same
        // choice between equal coordinates of opposite zero sign as ever.
        let (lo, hi) = (self.min, self.max);
        self.min = Point3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
        self.max = Point3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
    }

    /// The side lengths.
    pub fn size(&self) -> Point3 {
        self.max - self.min
    }

    /// The length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        self.size().length()
    }
}

/// Grows `b` (or starts it) with `p`; non-finite points (a B-spline the validator would refuse)
/// are left out.
fn grow(b: &mut Option<BoundingBox>, p: Point3) {
    if !p.is_finite() {
        return;
    }
    match b {
        Some(b) => b.add(p),
        None => *b = Some(BoundingBox::at(p)),
    }
}

/// Points along `curve` over `range`, both ends included.
fn samples<P: Point>(curve: &Curve<P>, range: [f64; 2]) -> impl Iterator<Item = P> + '_ {
    let n = curve.segments(range[0], range[1]).max(CURVE_SEGMENTS);
    (0..=n).map(move |i| curve.point(range[0] + (range[1] - range[0]) * (i as f64 / n as f64)))
}

/// Whether `p` is inside the closed polylines `loops` (even-odd: holes are out).
fn inside(loops: &[Vec<Point2>], p: Point2) -> bool {
    let mut odd = false;
    for lp in loops {
        let Some(&last) = lp.last() else { continue };
        let mut a = last;
        for &b in lp {
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    odd = !odd;
                }
            }
            a = b;
        }
    }
    odd
}

/// Calls `add` with points on `face`: its trims on the surface, then the grid points of its
/// `bounds` inside the trims (all of them for a face without loops).
fn face_points(face: &Face, add: &mut impl FnMut(Point3)) {
    let surface = &face.surface;
    let loops: Vec<Vec<Point2>> = face
        .loops
        .iter()
        .map(|l| {
            l.trims
                .iter()
                .flat_map(|t| samples(&t.curve, t.range))
                .collect()
        })
        .collect();
    for &p in loops.iter().flatten() {
        add(surface.point(p.x, p.y));
    }
    let [u0, u1, v0, v1] = face.bounds;
    for i in 0..=GRID {
        let u = u0 + (u1 - u0) * (i as f64 / GRID as f64);
        for j in 0..=GRID {
            let v = v0 + (v1 - v0) * (j as f64 / GRID as f64);
            if face.loops.is_empty() || inside(&loops, Point2::new(u, v)) {
                add(surface.point(u, v));
            }
        }
    }
}

impl Face {
    /// The bounding box of points on the trimmed face (see the module's notes); `None` when
    /// none evaluates to a finite point.
    pub fn bounding_box(&self) -> Option<BoundingBox> {
        let mut b = None;
        face_points(self, &mut |p| grow(&mut b, p));
        b
    }
}

impl Document {
    /// The bounding box of points on the part: every shared edge's 3D curve, and every face's
    /// trims and interior (see the module's notes); `None` for a document without faces or
    /// edges, or none that evaluates to a finite point. Sampling, it may fall short of the
    /// exact box by the sagitta of a sampling step (a grid step of a face's `bounds`, 1/16),
    /// never exceed it.
    pub fn bounding_box(&self) -> Option<BoundingBox> {
        let mut b = None;
        for edge in self.edges.iter().flatten() {
            if let Some(curve) = &edge.curve {
                for p in samples(curve, edge.range) {
                    grow(&mut b, p);
                }
            }
        }
        for face in &self.faces {
            face_points(face, &mut |p| grow(&mut b, p));
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(faces: &str) -> Document {
        let doc = Document::from_json(&format!(
            r#"{{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [{faces}]}}"#
        ))
        .unwrap();
        doc.validate().unwrap();
        doc
    }

    fn close(a: Point3, b: Point3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn a_face_without_loops_is_its_bounds() {
        let d = doc(
            r#"{"id": 0, "surface": {"type": "plane", "origin": [1, 2, 3],
            "x_dir": [1, 0, 0], "y_dir": [0, 0, 1]}, "bounds": [0, 2, -1, 1]}"#,
        );
        let b = d.bounding_box().unwrap();
        assert!(
            close(b.min, Point3::new(1.0, 2.0, 2.0)) && close(b.max, Point3::new(3.0, 2.0, 4.0)),
            "{b:?}"
        );
        assert!((b.diagonal() - 8f64.sqrt()).abs() < 1e-12);
        assert_eq!(d.faces[0].bounding_box(), Some(b));
    }

    #[test]
    fn trims_not_bounds() {
        // A triangle in the corner of a much larger parameter range.
        let line = |o: [f64; 2], d: [f64; 2], len: f64| {
            format!(
                r#"{{"curve": {{"type": "line", "origin": {o:?}, "dir": {d:?}}}, "range": [0, {len}]}}"#
            )
        };
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let edges = [
            line([0.0, 0.0], [1.0, 0.0], 1.0),
            line([1.0, 0.0], [-s, s], 2f64.sqrt()),
            line([0.0, 1.0], [0.0, -1.0], 1.0),
        ]
        .join(",");
        let d = doc(&format!(
            r#"{{"id": 0, "surface": {{"type": "plane", "origin": [0, 0, 0],
            "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]}}, "bounds": [0, 10, 0, 10],
            "loops": [{{"edges": [{edges}]}}]}}"#
        ));
        let b = d.bounding_box().unwrap();
        assert!(
            close(b.min, Point3::ZERO) && close(b.max, Point3::new(1.0, 1.0, 0.0)),
            "{b:?}"
        );
    }

    #[test]
    fn a_sphere_bulges_past_its_seam() {
        // A whole sphere: its only boundary is the seam (a half meridian), its box the grid's.
        let d = doc(
            r#"{"id": 0, "surface": {"type": "sphere", "origin": [0, 0, 0],
            "x_dir": [1, 0, 0], "y_dir": [0, 1, 0], "radius": 2},
            "bounds": [0, 6.283185307179586, -1.5707963267948966, 1.5707963267948966]}"#,
        );
        let b = d.bounding_box().unwrap();
        assert!(
            close(b.min, Point3::splat(-2.0)) && close(b.max, Point3::splat(2.0)),
            "{b:?}"
        );
    }

    #[test]
    fn nothing_to_measure() {
        assert_eq!(doc("").bounding_box(), None);
    }
}
