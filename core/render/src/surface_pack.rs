//! Every face's basis surface packed for the GPU (issue 21 step 2): a [`SurfaceHeader`] per
//! face and one flat `f32` word array holding each surface's parameters, read by the WGSL
//! evaluator `shaders/surface_eval.wgsl`, which mirrors `tessd_brep`'s f64 evaluation
//! (`Surface::eval`) in f32. Ray casting (paper 001 §3.4.2.a, §4.1.2) needs S(u, v) and its
//! partial derivatives at arbitrary (u, v), which the tessellated triangles cannot give.
//!
//! Positions (origins, centres, poles) are stored relative to a scene origin, so a part far
//! from the world origin keeps its f32 precision; directions, radii, angles and knots are
//! stored as they are. Integers (degrees, counts, flags, curve kinds) are stored as exact f32
//! values (below 2²⁴), never as bit patterns, so no driver can flush them as denormals.
//!
//! Word layouts, from the header's `offset` (positions `P` are 3 words, relative):
//! - plane: `origin x y`;
//! - cylinder: `origin x y z r`; sphere: the same;
//! - cone: `origin x y z r sin(a) cos(a)`;
//! - torus: `origin x y z R r`;
//! - revolution: `axis_origin axis_dir`, then a curve record;
//! - extrusion: `direction`, then a curve record;
//! - B-spline: `pu pv nu nv periodic_u periodic_v rational len_u len_v u0 u1 v0 v1`, the flat
//!   knots in u (`len_u`), in v (`len_v`), the poles `nu·nv` × 3 (`[i][j]` row-major), and
//!   when rational the weights `nu·nv`.
//!
//! Curve records start with their kind: line `kind origin dir`; circle `kind centre x y r`;
//! ellipse `kind centre x y a b`; B-spline `kind p n periodic rational len t0 t1`, the flat
//! knots, the poles `n` × 3 and, when rational, the weights. Flat knots are
//! `tessd_brep::bspline::KnotVector::flat` (periodic vectors already unrolled), so the shader
//! runs the same span search and Cox–de Boor recurrence as the CPU.

use bytemuck::{Pod, Zeroable};
use tessd_brep::bspline::KnotVector;
use tessd_brep::{Curve3, DVec3, Face, Surface};

/// Surface kind: plane.
pub const PLANE: u32 = 0;
/// Surface kind: cylinder.
pub const CYLINDER: u32 = 1;
/// Surface kind: cone.
pub const CONE: u32 = 2;
/// Surface kind: sphere.
pub const SPHERE: u32 = 3;
/// Surface kind: torus.
pub const TORUS: u32 = 4;
/// Surface kind: surface of revolution of a curve.
pub const REVOLUTION: u32 = 5;
/// Surface kind: extrusion of a curve.
pub const EXTRUSION: u32 = 6;
/// Surface kind: rational tensor-product B-spline.
pub const BSPLINE: u32 = 7;
/// Surface kind: a B-spline (or a swept B-spline curve) whose knots or poles do not validate;
/// the shader evaluates it to zero (point and derivatives), so Newton finds nothing there.
pub const INVALID: u32 = 8;

/// Curve kind of a revolution's meridian or an extrusion's profile: line.
pub const CURVE_LINE: u32 = 0;
/// Curve kind: circle.
pub const CURVE_CIRCLE: u32 = 1;
/// Curve kind: ellipse.
pub const CURVE_ELLIPSE: u32 = 2;
/// Curve kind: rational B-spline.
pub const CURVE_BSPLINE: u32 = 3;

/// Header flag: the face is reversed (its normal is `−∂S/∂u × ∂S/∂v`).
pub const FLAG_REVERSED: u32 = 1;

/// One face's entry, as the shader reads it (`SurfaceHeader` in `surface_eval.wgsl`, 32 bytes,
/// std430: `bounds` is a `vec4<f32>` at offset 16).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SurfaceHeader {
    /// The surface kind ([`PLANE`] … [`BSPLINE`], or [`INVALID`]).
    pub kind: u32,
    /// Index in [`SurfacePack::words`] of the surface's first word.
    pub offset: u32,
    /// Bit 0 ([`FLAG_REVERSED`]): the face is reversed.
    pub flags: u32,
    /// How many words the surface takes.
    pub words: u32,
    /// The face's patch rectangle `[u0, u1, v0, v1]` (`Face::bounds`), over which patch
    /// coordinates (s, t) ∈ [0, 1]² are normalised.
    pub bounds: [f32; 4],
}

/// Size of [`SurfaceHeader`] in bytes.
pub const SURFACE_HEADER_BYTES: usize = size_of::<SurfaceHeader>();

/// The faces' surfaces in the flat form `surface_eval.wgsl` reads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfacePack {
    /// One per face, in push order.
    pub headers: Vec<SurfaceHeader>,
    /// Every surface's words (see the module documentation).
    pub words: Vec<f32>,
    /// The scene origin positions are relative to.
    pub origin: [f64; 3],
}

impl SurfacePack {
    /// An empty pack whose positions will be stored relative to `origin`.
    pub fn new(origin: [f64; 3]) -> SurfacePack {
        SurfacePack {
            headers: Vec::new(),
            words: Vec::new(),
            origin,
        }
    }

    /// Appends `face`'s basis surface; returns its index (the push order, so pushing a
    /// document's faces in order makes it the document's face index).
    pub fn push(&mut self, face: &Face) -> usize {
        let offset = self.words.len();
        let kind = self.encode_surface(&face.surface).unwrap_or_else(|| {
            self.words.truncate(offset);
            INVALID
        });
        let b = face.bounds;
        self.headers.push(SurfaceHeader {
            kind,
            offset: offset as u32,
            flags: if face.reversed { FLAG_REVERSED } else { 0 },
            words: (self.words.len() - offset) as u32,
            bounds: [b[0] as f32, b[1] as f32, b[2] as f32, b[3] as f32],
        });
        self.headers.len() - 1
    }

    /// The headers as bytes, for a storage buffer.
    pub fn header_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.headers)
    }

    /// The words as bytes, for a storage buffer.
    pub fn word_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.words)
    }

    fn scalar(&mut self, x: f64) {
        self.words.push(x as f32);
    }

    fn count(&mut self, n: usize) {
        self.words.push(n as f32);
    }

    fn vector(&mut self, v: DVec3) {
        self.words.extend(v.to_array().map(|x| x as f32));
    }

    fn position(&mut self, p: DVec3) {
        let o = self.origin;
        self.words.extend([0, 1, 2].map(|k| (p[k] - o[k]) as f32));
    }

    fn frame(&mut self, f: &tessd_brep::model::Frame, with_z: bool) {
        self.position(f.origin);
        self.vector(f.x_dir);
        self.vector(f.y_dir);
        if with_z {
            self.vector(f.z_dir());
        }
    }

    /// Writes the surface's words; its kind, or `None` for an invalid B-spline.
    fn encode_surface(&mut self, surface: &Surface) -> Option<u32> {
        Some(match surface {
            Surface::Plane { frame } => {
                self.frame(frame, false);
                PLANE
            }
            Surface::Cylinder { frame, radius } => {
                self.frame(frame, true);
                self.scalar(*radius);
                CYLINDER
            }
            Surface::Cone {
                frame,
                radius,
                semi_angle,
            } => {
                self.frame(frame, true);
                self.scalar(*radius);
                self.scalar(semi_angle.sin());
                self.scalar(semi_angle.cos());
                CONE
            }
            Surface::Sphere { frame, radius } => {
                self.frame(frame, true);
                self.scalar(*radius);
                SPHERE
            }
            Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            } => {
                self.frame(frame, true);
                self.scalar(*major_radius);
                self.scalar(*minor_radius);
                TORUS
            }
            Surface::Revolution {
                axis_origin,
                axis_dir,
                curve,
            } => {
                self.position(*axis_origin);
                self.vector(*axis_dir);
                self.encode_curve(curve)?;
                REVOLUTION
            }
            Surface::Extrusion { direction, curve } => {
                self.vector(*direction);
                self.encode_curve(curve)?;
                EXTRUSION
            }
            Surface::Bspline(b) => {
                let ku = KnotVector::new(b.degree_u, &b.knots_u, &b.mults_u, b.periodic_u).ok()?;
                let kv = KnotVector::new(b.degree_v, &b.knots_v, &b.mults_v, b.periodic_v).ok()?;
                let (nu, nv) = (ku.pole_count(), kv.pole_count());
                let weights = b.weights.as_ref();
                if b.poles.len() != nu
                    || b.poles.iter().any(|r| r.len() != nv)
                    || weights.is_some_and(|w| w.len() != nu || w.iter().any(|r| r.len() != nv))
                {
                    return None;
                }
                self.count(b.degree_u);
                self.count(b.degree_v);
                self.count(nu);
                self.count(nv);
                self.count(b.periodic_u as usize);
                self.count(b.periodic_v as usize);
                self.count(weights.is_some() as usize);
                self.count(ku.flat().len());
                self.count(kv.flat().len());
                for d in [ku.domain(), kv.domain()] {
                    self.scalar(d[0]);
                    self.scalar(d[1]);
                }
                for k in ku.flat().iter().chain(kv.flat()) {
                    self.scalar(*k);
                }
                for p in b.poles.iter().flatten() {
                    self.position(*p);
                }
                for w in weights.into_iter().flatten().flatten() {
                    self.scalar(*w);
                }
                BSPLINE
            }
        })
    }

    /// Writes a curve record; `None` for an invalid B-spline curve.
    fn encode_curve(&mut self, curve: &Curve3) -> Option<()> {
        match curve {
            Curve3::Line { origin, dir } => {
                self.count(CURVE_LINE as usize);
                self.position(*origin);
                self.vector(*dir);
            }
            Curve3::Circle {
                center,
                x_dir,
                y_dir,
                radius,
            } => {
                self.count(CURVE_CIRCLE as usize);
                self.position(*center);
                self.vector(*x_dir);
                self.vector(*y_dir);
                self.scalar(*radius);
            }
            Curve3::Ellipse {
                center,
                x_dir,
                y_dir,
                major_radius,
                minor_radius,
            } => {
                self.count(CURVE_ELLIPSE as usize);
                self.position(*center);
                self.vector(*x_dir);
                self.vector(*y_dir);
                self.scalar(*major_radius);
                self.scalar(*minor_radius);
            }
            Curve3::Bspline(b) => {
                let kv = b.knot_vector().ok()?;
                let n = kv.pole_count();
                if b.poles.len() != n || b.weights.as_ref().is_some_and(|w| w.len() != n) {
                    return None;
                }
                self.count(CURVE_BSPLINE as usize);
                self.count(b.degree);
                self.count(n);
                self.count(b.periodic as usize);
                self.count(b.weights.is_some() as usize);
                self.count(kv.flat().len());
                self.scalar(kv.domain()[0]);
                self.scalar(kv.domain()[1]);
                for k in kv.flat() {
                    self.scalar(*k);
                }
                for p in &b.poles {
                    self.position(*p);
                }
                for w in b.weights.iter().flatten() {
                    self.scalar(*w);
                }
            }
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_check::{struct_size, validated};

    /// The evaluator library, with the buffers an including shader declares and an entry
    /// point using every function, validates; its `SurfaceHeader` has the Rust size.
    #[test]
    fn surface_eval_validates_with_naga() {
        let source = concat!(
            include_str!("../../../shaders/surface_eval.wgsl"),
            "@group(0) @binding(0) var<storage, read> surf_headers: array<SurfaceHeader>;\n",
            "@group(0) @binding(1) var<storage, read> surf_words: array<f32>;\n",
            "@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;\n",
            "@compute @workgroup_size(1) fn main() {\n",
            "  let uv = patch_to_uv(0u, uv_to_patch(0u, vec2<f32>(0.5)));\n",
            "  let s = surface_eval(0u, uv);\n",
            "  out[0] = vec4<f32>(s.p + s.du + s.dv + surface_normal(0u, s), 0.0);\n",
            "}\n"
        );
        let module = validated(source);
        assert_eq!(struct_size(&module, "SurfaceHeader"), SURFACE_HEADER_BYTES);
        assert_eq!(SURFACE_HEADER_BYTES % 16, 0);
    }

    /// Positions are relative to the origin; the header records kind, flags and bounds.
    #[test]
    fn plane_is_packed_relative_to_the_origin() {
        let doc = tessd_brep::Document::from_json(include_str!(
            "../../brep/tests/data/cylinder_with_hole.json"
        ))
        .unwrap();
        let mut pack = SurfacePack::new([1.0, 2.0, 3.0]);
        for f in &doc.faces {
            pack.push(f);
        }
        for (h, f) in pack.headers.iter().zip(&doc.faces) {
            assert_ne!(h.kind, INVALID);
            assert_eq!(h.flags & FLAG_REVERSED != 0, f.reversed);
            if let Surface::Plane { frame } = &f.surface {
                assert_eq!(h.kind, PLANE);
                let o = &pack.words[h.offset as usize..h.offset as usize + 3];
                let expected = [0, 1, 2].map(|k| (frame.origin[k] - pack.origin[k]) as f32);
                assert_eq!(o, expected);
            }
        }
    }
}
