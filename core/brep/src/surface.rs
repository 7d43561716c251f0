//! Surface evaluation for every surface type: the point, the partial derivatives ∂S/∂u and
//! ∂S/∂v, and the unit normal, in OCP's parametrisations (docs/brep-format.md, "Surfaces");
//! a face's normal is the surface's turned over when the face is `reversed`.

use crate::bspline::{KnotVector, eval_surface, eval_surface_point, surface_fits};
use crate::model::{BSplineSurface, Face, Frame, Surface};
use crate::vector::{Point3, combine};

/// A surface point with its first partial derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// S(u, v).
    pub point: Point3,
    /// ∂S/∂u.
    pub du: Point3,
    /// ∂S/∂v.
    pub dv: Point3,
}

impl SurfacePoint {
    /// `∂S/∂u × ∂S/∂v` normalised, or `None` where the parametrisation degenerates (a sphere's
    /// pole, a cone's apex) and the cross product vanishes.
    pub fn normal(&self) -> Option<Point3> {
        let n = self.du.cross(self.dv);
        let len = n.length();
        let scale = self.du.length() * self.dv.length();
        (len > 1e-12 * scale && len.is_finite()).then(|| n * (1.0 / len))
    }
}

/// `cos u·x + sin u·y` and its derivative in u, the circle every rotational surface sweeps.
fn radial(frame: &Frame, u: f64) -> (Point3, Point3) {
    let (c, s) = (u.cos(), u.sin());
    (
        combine(&[(c, frame.x_dir), (s, frame.y_dir)]),
        combine(&[(-s, frame.x_dir), (c, frame.y_dir)]),
    )
}

impl BSplineSurface {
    /// `(S, ∂S/∂u, ∂S/∂v)`, or `None` for a surface [`crate::validate`] refuses.
    pub fn eval(&self, u: f64, v: f64) -> Option<SurfacePoint> {
        let (ku, kv) = self.knot_vectors()?;
        let (point, du, dv) = eval_surface(ku, kv, &self.poles, self.weights.as_deref(), u, v);
        Some(SurfacePoint { point, du, dv })
    }

    /// `S(u, v)` alone (no derivatives), or `None` for a surface [`crate::validate`] refuses.
    pub fn point(&self, u: f64, v: f64) -> Option<Point3> {
        let (ku, kv) = self.knot_vectors()?;
        Some(eval_surface_point(
            ku,
            kv,
            &self.poles,
            self.weights.as_deref(),
            u,
            v,
        ))
    }

    /// The checked knot vectors, `None` when they or the poles break the rules.
    fn knot_vectors(&self) -> Option<&(KnotVector, KnotVector)> {
        self.cache.get_or_init(|| {
            let ku = KnotVector::new(self.degree_u, &self.knots_u, &self.mults_u, self.periodic_u)
                .ok()?;
            let kv = KnotVector::new(self.degree_v, &self.knots_v, &self.mults_v, self.periodic_v)
                .ok()?;
            surface_fits(&ku, &kv, &self.poles, self.weights.as_deref()).then_some((ku, kv))
        })
    }
}

impl Surface {
    /// S(u, v) with its partial derivatives; NaN coordinates for a B-spline (or a swept
    /// B-spline curve) that does not validate.
    pub fn eval(&self, u: f64, v: f64) -> SurfacePoint {
        match self {
            Surface::Plane { frame } => SurfacePoint {
                point: combine(&[(1.0, frame.origin), (u, frame.x_dir), (v, frame.y_dir)]),
                du: frame.x_dir,
                dv: frame.y_dir,
            },
            Surface::Cylinder { frame, radius } => {
                let (e, de) = radial(frame, u);
                let z = frame.z_dir();
                SurfacePoint {
                    point: combine(&[(1.0, frame.origin), (*radius, e), (v, z)]),
                    du: de * *radius,
                    dv: z,
                }
            }
            Surface::Cone {
                frame,
                radius,
                semi_angle,
            } => {
                let (e, de) = radial(frame, u);
                let z = frame.z_dir();
                let (sa, ca) = (semi_angle.sin(), semi_angle.cos());
                let r = radius + v * sa;
                SurfacePoint {
                    point: combine(&[(1.0, frame.origin), (r, e), (v * ca, z)]),
                    du: de * r,
                    dv: combine(&[(sa, e), (ca, z)]),
                }
            }
            Surface::Sphere { frame, radius } => {
                let (e, de) = radial(frame, u);
                let z = frame.z_dir();
                let (cv, sv) = (v.cos(), v.sin());
                SurfacePoint {
                    point: combine(&[(1.0, frame.origin), (radius * cv, e), (radius * sv, z)]),
                    du: de * (radius * cv),
                    dv: combine(&[(-radius * sv, e), (radius * cv, z)]),
                }
            }
            Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            } => {
                let (e, de) = radial(frame, u);
                let z = frame.z_dir();
                let (cv, sv) = (v.cos(), v.sin());
                let r = major_radius + minor_radius * cv;
                SurfacePoint {
                    point: combine(&[(1.0, frame.origin), (r, e), (minor_radius * sv, z)]),
                    du: de * r,
                    dv: combine(&[(-minor_radius * sv, e), (minor_radius * cv, z)]),
                }
            }
            Surface::Revolution {
                axis_origin,
                axis_dir,
                curve,
            } => {
                // Rodrigues: R(u)q = q cos u + (a × q) sin u + a (a·q)(1 − cos u).
                let (c, dc) = curve.eval(v);
                let a = *axis_dir;
                let rotate = |q: Point3| {
                    combine(&[
                        (u.cos(), q),
                        (u.sin(), a.cross(q)),
                        (a.dot(q) * (1.0 - u.cos()), a),
                    ])
                };
                let q = c - *axis_origin;
                SurfacePoint {
                    point: *axis_origin + rotate(q),
                    du: combine(&[
                        (-u.sin(), q),
                        (u.cos(), a.cross(q)),
                        (a.dot(q) * u.sin(), a),
                    ]),
                    dv: rotate(dc),
                }
            }
            Surface::Extrusion { direction, curve } => {
                let (c, dc) = curve.eval(u);
                SurfacePoint {
                    point: c + *direction * v,
                    du: dc,
                    dv: *direction,
                }
            }
            Surface::Bspline(b) => b.eval(u, v).unwrap_or(SurfacePoint {
                point: Point3::NAN,
                du: Point3::NAN,
                dv: Point3::NAN,
            }),
        }
    }

    /// S(u, v).
    pub fn point(&self, u: f64, v: f64) -> Point3 {
        match self {
            Surface::Bspline(b) => b.point(u, v).unwrap_or(Point3::NAN),
            _ => self.eval(u, v).point,
        }
    }

    /// The unit normal `∂S/∂u × ∂S/∂v`; at a sphere's poles, where that vanishes, the
    /// outward radial direction; `None` at other degenerate points (a cone's apex).
    pub fn normal(&self, u: f64, v: f64) -> Option<Point3> {
        let sp = self.eval(u, v);
        sp.normal().or_else(|| match self {
            Surface::Sphere { frame, radius } => Some((sp.point - frame.origin) * (1.0 / radius)),
            _ => None,
        })
    }
}

impl Face {
    /// The face's outward unit normal at (u, v): the surface's, negated when `reversed`.
    pub fn normal(&self, u: f64, v: f64) -> Option<Point3> {
        let n = self.surface.normal(u, v)?;
        Some(if self.reversed { n * -1.0 } else { n })
    }
}
