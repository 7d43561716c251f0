//! The camera: a perspective pinhole whose pixel rays are fixed by issue 21, because hosts
//! (and the later GPU trimming and ray-casting passes) compute rays themselves and must hit
//! the same points the rasteriser shows.
//!
//! The ray of pixel (x, y) of a W × H image (row 0 at the top) leaves the eye along
//! `forward + sx·right + sy·up'`, with
//!
//! ```text
//! sx = (2 (x + 0.5) / W − 1) · tan(fov / 2) · W / H
//! sy = (1 − 2 (y + 0.5) / H) · tan(fov / 2)
//! forward = normalize(target − eye), right = normalize(forward × up), up' = right × forward
//! ```
//!
//! `fov` is the vertical field of view in degrees (default 30). [`Camera::clip_from_world`] is
//! the projection that puts exactly that ray's points on the centre of pixel (x, y) (wgpu's
//! viewport maps NDC y = +1 to row 0), so rasterised and ray-cast images agree pixel for
//! pixel. Everything is computed in f64 and rounded once into the f32 matrix.

use crate::RenderError;

/// 3-vector in f64.
pub type Vec3 = glam::DVec3;

/// The default vertical field of view, degrees.
pub const DEFAULT_FOV: f64 = 30.0;

/// A perspective camera with its clipping planes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (world).
    pub eye: Vec3,
    /// The point looked at (world).
    pub target: Vec3,
    /// The up hint; the image's up is its component orthogonal to the view direction.
    pub up: Vec3,
    /// Vertical field of view, degrees (0 < fov < 180).
    pub fov: f64,
    /// Near plane: distance along `forward` from the eye.
    pub near: f64,
    /// Far plane: distance along `forward` from the eye.
    pub far: f64,
}

/// Standard views of a part, fitted to its bounding box. Z is up; "front" looks along +Y (the
/// eye on the −Y side), as in Blender and FreeCAD. With [`UpAxis::Y`] (scans, glTF, OBJ) the
/// same views turn with the world: Y is up and "front" looks along −Z (the eye on the +Z
/// side), as Blender shows a Y-up file it imports ([`UpAxis::from_z_up`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// From the (+1, −1, +1) direction (front, right, above), Z up.
    Iso,
    /// From −Y looking along +Y, Z up (+X to the right).
    Front,
    /// From +Y looking along −Y, Z up.
    Back,
    /// From −X looking along +X, Z up.
    Left,
    /// From +X looking along −X, Z up.
    Right,
    /// From +Z looking down, +Y up in the image (+X to the right).
    Top,
    /// From −Z looking up, −Y up in the image (+X to the right).
    Bottom,
}

impl View {
    /// Every view, in the CLI's order.
    pub const ALL: [View; 7] = [
        View::Iso,
        View::Front,
        View::Back,
        View::Left,
        View::Right,
        View::Top,
        View::Bottom,
    ];

    /// The view's name (`iso`, `front`, ...).
    pub fn name(self) -> &'static str {
        match self {
            View::Iso => "iso",
            View::Front => "front",
            View::Back => "back",
            View::Left => "left",
            View::Right => "right",
            View::Top => "top",
            View::Bottom => "bottom",
        }
    }

    /// The view named `s`.
    pub fn parse(s: &str) -> Option<View> {
        View::ALL.into_iter().find(|v| v.name() == s)
    }

    /// Direction from the target to the eye, and the up hint.
    fn direction(self) -> (Vec3, Vec3) {
        let z = Vec3::Z;
        match self {
            View::Iso => (Vec3::new(1.0, -1.0, 1.0), z),
            View::Front => (Vec3::NEG_Y, z),
            View::Back => (Vec3::Y, z),
            View::Left => (Vec3::NEG_X, z),
            View::Right => (Vec3::X, z),
            View::Top => (Vec3::Z, Vec3::Y),
            View::Bottom => (Vec3::NEG_Z, Vec3::NEG_Y),
        }
    }
}

/// The world's up axis, for the standard views.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// +Y up (Stanford scans, glTF, OBJ and most DCC exports).
    Y,
    /// +Z up (CAD, Blender, tessd's own stages): the default.
    #[default]
    Z,
}

impl UpAxis {
    /// `"Y"` or `"Z"`.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }

    /// The axis named `s` (`"Y"`, `"Z"`; USD's `upAxis` spelling).
    pub fn parse(s: &str) -> Option<UpAxis> {
        match s {
            "Y" => Some(UpAxis::Y),
            "Z" => Some(UpAxis::Z),
            _ => None,
        }
    }

    /// The up vector.
    pub fn vector(self) -> Vec3 {
        match self {
            UpAxis::Y => Vec3::Y,
            UpAxis::Z => Vec3::Z,
        }
    }

    /// A direction given in the Z-up convention, in this world: unchanged for Z; for Y the
    /// rotation taking +Z to +Y and −Y (the Z-up front) to +Z: (x, y, z) → (x, z, −y).
    pub fn from_z_up(self, v: Vec3) -> Vec3 {
        match self {
            UpAxis::Z => v,
            UpAxis::Y => Vec3::new(v.x, v.z, -v.y),
        }
    }
}

/// An axis-aligned box in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest coordinates.
    pub min: Vec3,
    /// Largest coordinates.
    pub max: Vec3,
}

impl Bounds {
    /// The centre.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the diagonal: the radius of the sphere around the box.
    pub fn radius(&self) -> f64 {
        0.5 * self.max.distance(self.min)
    }

    /// The smallest box holding both.
    pub fn union(&self, other: &Bounds) -> Bounds {
        Bounds {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::from_array(std::array::from_fn(|k| {
                if i >> k & 1 == 0 {
                    self.min[k]
                } else {
                    self.max[k]
                }
            }))
        })
    }
}

impl Camera {
    /// The camera of `view` fitted to `bounds` for an image of aspect `width / height`: looking
    /// at the box's centre from the view's direction, far enough that the sphere around the box
    /// fits both the vertical and the horizontal field of view.
    pub fn fit(view: View, bounds: &Bounds, fov: f64, aspect: f64) -> Camera {
        Camera::fit_up(view, UpAxis::Z, bounds, fov, aspect)
    }

    /// [`fit`](Self::fit) in a world whose up axis is `up` (the views turned with it).
    pub fn fit_up(view: View, up: UpAxis, bounds: &Bounds, fov: f64, aspect: f64) -> Camera {
        let (dir, hint) = view.direction();
        let (dir, up) = (up.from_z_up(dir), up.from_z_up(hint));
        let half_v = 0.5 * fov.to_radians();
        let half_h = (half_v.tan() * aspect).atan();
        let half = half_v.min(half_h);
        let radius = bounds.radius().max(f64::MIN_POSITIVE);
        let distance = radius / half.sin();
        let target = bounds.center();
        let eye = target + normalize(dir) * distance;
        Camera::new(eye, target, up, fov).clipped_to(bounds)
    }

    /// A camera at `eye` looking at `target`, clipping planes not yet set (see
    /// [`clipped_to`](Self::clipped_to)).
    pub fn new(
        eye: impl Into<Vec3>,
        target: impl Into<Vec3>,
        up: impl Into<Vec3>,
        fov: f64,
    ) -> Camera {
        Camera {
            eye: eye.into(),
            target: target.into(),
            up: up.into(),
            fov,
            near: 0.01,
            far: 100.0,
        }
    }

    /// Checks that the camera defines a view: finite values, eye ≠ target, up not parallel to
    /// the view direction, 0 < fov < 180.
    ///
    /// # Errors
    /// [`RenderError::Camera`] naming what is wrong.
    pub fn check(&self) -> Result<(), RenderError> {
        if ![self.eye, self.target, self.up]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(RenderError::Camera(format!(
                "eye {:?}, target {:?} and up {:?} must be finite",
                self.eye.to_array(),
                self.target.to_array(),
                self.up.to_array()
            )));
        }
        if !(self.fov > 0.0 && self.fov < 180.0) {
            return Err(RenderError::Camera(format!(
                "fov must be between 0 and 180 degrees, got {}",
                self.fov
            )));
        }
        let d = self.target - self.eye;
        if d.length() == 0.0 {
            return Err(RenderError::Camera(format!(
                "eye and target are the same point {:?}",
                self.eye.to_array()
            )));
        }
        let f = normalize(d);
        let u = self.up;
        if u.length() == 0.0 || f.cross(normalize(u)).length() < 1e-9 {
            return Err(RenderError::Camera(format!(
                "up {:?} is parallel to the view direction {:?} (or zero)",
                self.up.to_array(),
                f.to_array()
            )));
        }
        Ok(())
    }

    /// This camera with near and far planes around `bounds`: the box's extent along the view
    /// direction, widened by 1 % (and the near plane kept at least 1/10 000 of the far one, so
    /// an eye inside the box still gets a usable depth range). The near plane is always below
    /// the far one: from an eye so far away that the box's depth is below f64's resolution there
    /// (found by fuzzing: an eye 1.8·10²⁰ from a unit box gave near = far, a projection
    /// with no depth range), near is far · (1 − 10⁻⁶).
    pub fn clipped_to(mut self, bounds: &Bounds) -> Camera {
        let (f, _, _) = self.basis();
        let ds = bounds.corners().map(|c| (c - self.eye).dot(f));
        let dmin = ds.iter().copied().fold(f64::INFINITY, f64::min);
        let dmax = ds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let span = (dmax - dmin).max(bounds.radius()).max(1e-30);
        let far = (dmax + 0.01 * span).max(1e-30);
        let near = (dmin - 0.01 * span).max(far * 1e-4).min(far * (1.0 - 1e-6));
        self.near = near;
        self.far = far;
        self
    }

    /// `forward`, `right`, `up'` of the convention (module docs).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = normalize(self.target - self.eye);
        let right = normalize(forward.cross(self.up));
        let up = right.cross(forward);
        (forward, right, up)
    }

    /// The (unnormalised) direction of the ray of pixel (x, y) in a `width × height` image:
    /// `forward + sx·right + sy·up'`.
    pub fn ray(&self, x: u32, y: u32, width: u32, height: u32) -> Vec3 {
        let (f, r, u) = self.basis();
        let t = (0.5 * self.fov.to_radians()).tan();
        let (w, h) = (width as f64, height as f64);
        let sx = (2.0 * (x as f64 + 0.5) / w - 1.0) * t * w / h;
        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h) * t;
        f + (r * sx + u * sy)
    }

    /// The clip-space transform (column-major, as WGSL's `mat4x4<f32>`) of points given
    /// relative to `origin`: x and y so that the ray of each pixel centre lands on it, w = the
    /// distance along `forward`, depth 0 at `near` and 1 at `far`.
    pub fn clip_from_world(&self, origin: Vec3, width: u32, height: u32) -> [[f32; 4]; 4] {
        let (f, r, u) = self.basis();
        let ty = (0.5 * self.fov.to_radians()).tan();
        let tx = ty * width as f64 / height as f64;
        let (n, fa) = (self.near, self.far);
        let a = fa / (fa - n);
        let b = -fa * n / (fa - n);
        // Rows of the 4 × 4 matrix acting on (q − e, 1), e the eye relative to the origin.
        let e = self.eye - origin;
        let rows: [(Vec3, f64); 4] = [
            (r * (1.0 / tx), 0.0),
            (u * (1.0 / ty), 0.0),
            (f * a, b),
            (f, 0.0),
        ];
        let mut m = [[0f32; 4]; 4];
        for (i, (row, c)) in rows.iter().enumerate() {
            for k in 0..3 {
                m[k][i] = row[k] as f32;
            }
            m[3][i] = (c - row.dot(e)) as f32;
        }
        m
    }

    /// The distance along `forward` of a depth-buffer value `z` (0 at `near`, 1 at `far`), the
    /// inverse of [`clip_from_world`](Self::clip_from_world)'s depth.
    pub fn linear_depth(&self, z: f32) -> f32 {
        let (n, f) = (self.near, self.far);
        (f * n / (f - z as f64 * (f - n))) as f32
    }

    /// The world size of one pixel at distance `distance` along the view direction, for an
    /// image `height` pixels high: how fine geometry must be to look exact there.
    pub fn pixel_size(&self, distance: f64, height: u32) -> f64 {
        2.0 * distance * (0.5 * self.fov.to_radians()).tan() / height.max(1) as f64
    }

    /// This camera with the eye turned by `angle` radians about the axis along `up` through
    /// the target (right-handed: positive turns counter-clockwise seen from above).
    pub fn orbit(&self, angle: f64) -> Camera {
        let k = normalize(self.up);
        let v = self.eye - self.target;
        let (s, c) = angle.sin_cos();
        // Rodrigues: v cos + (k × v) sin + k (k·v)(1 − cos).
        let rotated = (v * c + k.cross(v) * s) + k * (k.dot(v) * (1.0 - c));
        Camera {
            eye: self.target + rotated,
            ..*self
        }
    }
}

/// a / |a| (a itself when zero: a degenerate view is reported by [`Camera::check`], not
/// turned into NaNs, as glam's `normalize` would).
pub fn normalize(a: Vec3) -> Vec3 {
    let n = a.length();
    if n > 0.0 { a * (1.0 / n) } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Bounds {
        Bounds {
            min: Vec3::splat(-1.0),
            max: Vec3::ONE,
        }
    }

    /// Projects `p` with the matrix and returns pixel coordinates.
    fn project(c: &Camera, p: Vec3, w: u32, h: u32) -> (f64, f64, f64) {
        let m = c.clip_from_world(Vec3::ZERO, w, h);
        let clip: [f64; 4] = std::array::from_fn(|i| {
            (0..3).map(|k| m[k][i] as f64 * p[k]).sum::<f64>() + m[3][i] as f64
        });
        let (nx, ny, nz) = (clip[0] / clip[3], clip[1] / clip[3], clip[2] / clip[3]);
        ((nx + 1.0) / 2.0 * w as f64, (1.0 - ny) / 2.0 * h as f64, nz)
    }

    #[test]
    fn rays_land_on_their_pixel_centres() {
        let c = Camera::fit(View::Iso, &unit_box(), 30.0, 160.0 / 120.0);
        for (x, y) in [(0, 0), (159, 119), (80, 60), (17, 93)] {
            let d = c.ray(x, y, 160, 120);
            let p = c.eye + d * 5.0;
            let (px, py, _) = project(&c, p, 160, 120);
            assert!((px - (x as f64 + 0.5)).abs() < 1e-4, "{px} vs {x}");
            assert!((py - (y as f64 + 0.5)).abs() < 1e-4, "{py} vs {y}");
        }
    }

    #[test]
    fn depth_round_trips_and_spans_the_box() {
        let c = Camera::fit(View::Front, &unit_box(), 30.0, 1.0);
        for d in [c.near, 0.5 * (c.near + c.far), c.far] {
            let p = c.eye + c.basis().0 * d;
            let (_, _, z) = project(&c, p, 10, 10);
            assert!((c.linear_depth(z as f32) as f64 - d).abs() < 1e-4 * d);
        }
        let corners = unit_box().corners();
        for p in corners {
            let (_, _, z) = project(&c, p, 10, 10);
            assert!(z > 0.0 && z < 1.0, "{z}");
        }
    }

    #[test]
    fn views_look_where_documented() {
        let b = unit_box();
        let front = Camera::fit(View::Front, &b, 30.0, 1.0);
        assert!(front.eye[1] < -1.0 && front.basis().1[0] > 0.99);
        let top = Camera::fit(View::Top, &b, 30.0, 1.0);
        assert!(top.eye[2] > 1.0 && top.basis().1[0] > 0.99);
        let bottom = Camera::fit(View::Bottom, &b, 30.0, 1.0);
        assert!(bottom.eye[2] < -1.0 && bottom.basis().1[0] > 0.99);
        let iso = Camera::fit(View::Iso, &b, 30.0, 1.0);
        assert!(iso.eye[0] > 1.0 && iso.eye[1] < -1.0 && iso.eye[2] > 1.0);
        // Fitted: every corner inside the image.
        for v in View::ALL {
            let c = Camera::fit(v, &b, 30.0, 2.0);
            for p in b.corners() {
                let (x, y, _) = project(&c, p, 200, 100);
                assert!(
                    (0.0..=200.0).contains(&x) && (0.0..=100.0).contains(&y),
                    "{v:?}"
                );
            }
        }
    }

    #[test]
    fn y_up_views_turn_with_the_world() {
        let b = unit_box();
        let front = Camera::fit_up(View::Front, UpAxis::Y, &b, 30.0, 1.0);
        let (_, right, up) = front.basis();
        // From +Z looking along −Z, +Y up in the image, +X to the right.
        assert!(front.eye[2] > 1.0 && right[0] > 0.99 && up[1] > 0.99);
        let top = Camera::fit_up(View::Top, UpAxis::Y, &b, 30.0, 1.0);
        let (_, right, up) = top.basis();
        assert!(top.eye[1] > 1.0 && right[0] > 0.99 && up[2] < -0.99);
        let iso = Camera::fit_up(View::Iso, UpAxis::Y, &b, 30.0, 1.0);
        assert!(iso.eye[0] > 1.0 && iso.eye[1] > 1.0 && iso.eye[2] > 1.0);
        assert!(iso.basis().2[1] > 0.5);
        for v in View::ALL {
            assert_eq!(
                Camera::fit_up(v, UpAxis::Z, &b, 30.0, 2.0),
                Camera::fit(v, &b, 30.0, 2.0)
            );
        }
    }

    #[test]
    fn orbit_keeps_distance_and_height() {
        let c = Camera::fit(View::Iso, &unit_box(), 30.0, 1.0);
        let o = c.orbit(std::f64::consts::FRAC_PI_2);
        assert!((o.eye.distance(o.target) - c.eye.distance(c.target)).abs() < 1e-9);
        assert!((o.eye[2] - c.eye[2]).abs() < 1e-9);
        // A quarter turn counter-clockwise about +Z: (x, y) → (−y, x).
        assert!((o.eye[0] + c.eye[1]).abs() < 1e-9 && (o.eye[1] - c.eye[0]).abs() < 1e-9);
    }

    #[test]
    fn bad_cameras_are_refused() {
        let up = [0.0, 0.0, 1.0];
        let same = Camera::new([0.0; 3], [0.0; 3], up, 30.0).check();
        // The message names the points as the request wrote them, not as glam's Debug does.
        assert_eq!(
            same.unwrap_err().to_string(),
            "camera: eye and target are the same point [0.0, 0.0, 0.0]"
        );
        assert!(
            Camera::new([0.0; 3], [0.0, 0.0, 1.0], up, 30.0)
                .check()
                .is_err()
        );
        assert!(
            Camera::new([0.0; 3], [1.0, 0.0, 0.0], up, 180.0)
                .check()
                .is_err()
        );
        assert!(
            Camera::new([0.0; 3], [1.0, 0.0, 0.0], up, 30.0)
                .check()
                .is_ok()
        );
    }
}
