//! Moving a whole document: every world point (surface frames and axes, curve origins and
//! centres, poles) shifted by one vector, parameters and trims unchanged. Used to place a part
//! far from the origin, where single-precision output loses the tolerance (issue 20, point 5),
//! without changing anything else about it.

use crate::model::{Curve, Curve3, Document, Surface};
use crate::vector::Point3;

impl Document {
    /// The document moved by `d` (model units).
    pub fn translated(&self, d: Point3) -> Document {
        fn curve(c: &mut Curve3, d: Point3) {
            match c {
                Curve::Line { origin, .. } => *origin += d,
                Curve::Circle { center, .. } | Curve::Ellipse { center, .. } => *center += d,
                Curve::Bspline(b) => b.poles.iter_mut().for_each(|p| *p += d),
            }
        }
        let mut doc = self.clone();
        for face in &mut doc.faces {
            match &mut face.surface {
                Surface::Plane { frame }
                | Surface::Cylinder { frame, .. }
                | Surface::Cone { frame, .. }
                | Surface::Sphere { frame, .. }
                | Surface::Torus { frame, .. } => frame.origin += d,
                Surface::Revolution {
                    axis_origin,
                    curve: c,
                    ..
                } => {
                    *axis_origin += d;
                    curve(c, d);
                }
                Surface::Extrusion { curve: c, .. } => curve(c, d),
                Surface::Bspline(b) => {
                    for row in &mut b.poles {
                        row.iter_mut().for_each(|p| *p += d);
                    }
                }
            }
        }
        for edge in doc.edges.iter_mut().flatten() {
            if let Some(c) = &mut edge.curve {
                curve(c, d);
            }
        }
        doc
    }
}
