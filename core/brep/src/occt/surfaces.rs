//! Step 6b: surface records into exchange-format surfaces, placed in the world, as ocp.py's
//! `_surface` writes them.
//!
//! Planes keep their stored frame whatever its handedness (S = O + uX + vY either way).
//! Cylinders, cones, spheres and tori on an indirect `gp_Ax3` cannot keep OCCT's (u, v) in the
//! format's right-handed frame: they are written on (X, −Y) with `mirror` set, and the face
//! then maps u → 2π − u (docs/brep-format.md). Rectangular trimmed surfaces become their basis,
//! revolutions and extrusions keep their exact curve; offset surfaces and revolutions of
//! curves without an exact type are refused (the exporters convert them to NURBS).

use std::f64::consts::{FRAC_PI_2, TAU};

use super::curves::{exact3, natural_range, transformed};
use super::geometry::{Ax3, RawSurface};
use super::locations::Trsf;
use crate::model::{Frame, Surface};

/// A surface ready for the document.
pub(crate) struct Placed {
    /// The surface, in world coordinates.
    pub surface: Surface,
    /// Whether the face's pcurves must be mirrored (u → 2π − u).
    pub mirror: bool,
    /// The parameter range of the record itself when bounded (OCCT's `Geom_Surface::Bounds`,
    /// in OCCT's (u, v)): the domain of a face without wires.
    pub natural: Option<[f64; 4]>,
    /// Whether the record (a trimmed one unwrapped) is a plane: OCCT then projects edges that
    /// store no pcurve on it.
    pub plane: Option<Frame>,
}

/// `raw` placed by `t`, or why the format has no exact type for it.
pub(crate) fn place(raw: &RawSurface, t: &Trsf) -> Result<Placed, String> {
    let frame = |a: &Ax3| {
        let axis = t.dir(a.axis);
        let (x, y) = (t.dir(a.x), t.dir(a.y));
        let mirror = x.cross(y).dot(axis) < 0.0;
        let y = if mirror { y * -1.0 } else { y };
        (
            Frame {
                origin: t.point(a.origin),
                x_dir: x,
                y_dir: y,
            },
            mirror,
        )
    };
    let round = |surface, a: &Ax3, natural| {
        let (frame, mirror) = frame(a);
        let surface = match surface {
            Round::Cylinder(radius) => Surface::Cylinder { frame, radius },
            Round::Cone(radius, semi_angle) => Surface::Cone {
                frame,
                radius,
                semi_angle,
            },
            Round::Sphere(radius) => Surface::Sphere { frame, radius },
            Round::Torus(major_radius, minor_radius) => Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            },
        };
        Placed {
            surface,
            mirror,
            natural,
            plane: None,
        }
    };
    Ok(match raw {
        RawSurface::Trimmed { bounds, basis } => Placed {
            natural: Some(*bounds),
            ..place(basis, t)?
        },
        RawSurface::Plane(a) => {
            let frame = Frame {
                origin: t.point(a.origin),
                x_dir: t.dir(a.x),
                y_dir: t.dir(a.y),
            };
            Placed {
                surface: Surface::Plane { frame },
                mirror: false,
                natural: None,
                plane: Some(frame),
            }
        }
        RawSurface::Cylinder(a, r) => round(Round::Cylinder(*r), a, None),
        RawSurface::Cone(a, r, angle) => round(Round::Cone(*r, *angle), a, None),
        RawSurface::Sphere(a, r) => round(
            Round::Sphere(*r),
            a,
            Some([0.0, TAU, -FRAC_PI_2, FRAC_PI_2]),
        ),
        RawSurface::Torus(a, big, small) => {
            round(Round::Torus(*big, *small), a, Some([0.0, TAU, 0.0, TAU]))
        }
        RawSurface::Extrusion { dir, curve } => {
            let c = exact3(curve)
                .ok_or("a surface of linear extrusion of a curve without an exact type")?;
            Placed {
                surface: Surface::Extrusion {
                    direction: t.dir(*dir),
                    curve: Box::new(transformed(c, t)),
                },
                mirror: false,
                natural: None,
                plane: None,
            }
        }
        RawSurface::Revolution { origin, dir, curve } => {
            let c =
                exact3(curve).ok_or("a surface of revolution of a curve without an exact type")?;
            Placed {
                surface: Surface::Revolution {
                    axis_origin: t.point(*origin),
                    axis_dir: t.dir(*dir),
                    curve: Box::new(transformed(c, t)),
                },
                mirror: false,
                natural: natural_range(curve).map(|[v0, v1]| [0.0, TAU, v0, v1]),
                plane: None,
            }
        }
        RawSurface::Bspline(b) => {
            let mut b = b.clone();
            for row in &mut b.poles {
                row.iter_mut().for_each(|p| *p = t.point(*p));
            }
            let natural = [
                b.knots_u[0],
                b.knots_u[b.knots_u.len() - 1],
                b.knots_v[0],
                b.knots_v[b.knots_v.len() - 1],
            ];
            Placed {
                surface: Surface::Bspline(b),
                mirror: false,
                natural: Some(natural),
                plane: None,
            }
        }
        RawSurface::Offset => return Err("an offset surface".into()),
    })
}

/// The surfaces of revolution about a frame's axis.
enum Round {
    Cylinder(f64),
    Cone(f64, f64),
    Sphere(f64),
    Torus(f64, f64),
}
