//! The viewer's camera, moved the way Blender's viewport moves: a turntable orbit about the
//! world's up axis through the target, pans in the view plane, zoom towards the target, the
//! numpad's standard views, and an orthographic look.
//!
//! The renderer draws perspective only, so "orthographic" (`5`) is a long lens: the field of
//! view narrowed to [`ORTHO_FOV`] degrees and the eye moved back so that the plane through
//! the target keeps its size on screen. Parallel lines stay parallel to within a pixel or so.

use tessd_render::{Bounds, Camera, UpAxis, View};

type Vec3 = glam::DVec3;

/// The field of view of the orthographic look, degrees.
pub const ORTHO_FOV: f64 = 0.5;

/// Degrees of orbit per pixel dragged (Blender: about a third of a degree).
pub const ORBIT_PER_PIXEL: f64 = 0.35;

/// The viewer's camera and what it is fitted to.
#[derive(Clone, Debug)]
pub struct Navigation {
    /// The camera as drawn (clipping planes set for the scene).
    pub camera: Camera,
    /// The field of view of the perspective look, degrees.
    pub fov: f64,
    /// Whether the orthographic look is on.
    pub ortho: bool,
    /// The world's up axis (orbits turn about it, views are named after it).
    pub up_axis: UpAxis,
    /// The scene's box.
    pub bounds: Bounds,
}

impl Navigation {
    /// The view `view` of `bounds` for an image of aspect `aspect`.
    pub fn fitted(view: View, up_axis: UpAxis, bounds: Bounds, fov: f64, aspect: f64) -> Self {
        Navigation {
            camera: Camera::fit_up(view, up_axis, &bounds, fov, aspect),
            fov,
            ortho: false,
            up_axis,
            bounds,
        }
    }

    /// An explicit camera (`--eye` or a script's `camera`).
    pub fn set_camera(&mut self, eye: Vec3, target: Vec3, up: Vec3, fov: f64) {
        self.fov = fov;
        self.ortho = false;
        self.camera = Camera::new(eye, target, up, fov).clipped_to(&self.bounds);
    }

    /// The world's up vector.
    fn world_up(&self) -> Vec3 {
        self.up_axis.vector()
    }

    /// Orbits by `dx` degrees about the world's up axis and `dy` degrees about the camera's
    /// right axis (stopping short of the poles, as a turntable does).
    pub fn orbit(&mut self, dx: f64, dy: f64) {
        let up = self.world_up();
        let mut c = self.camera;
        c.up = up;
        c = c.orbit(-dx.to_radians());
        let offset = c.eye - c.target;
        let (_, right, _) = c.basis();
        let elevation = offset
            .normalize()
            .dot(up)
            .clamp(-1.0, 1.0)
            .asin()
            .to_degrees();
        let turn = (elevation + dy).clamp(-89.0, 89.0) - elevation;
        let rotation = glam::DQuat::from_axis_angle(right, -turn.to_radians());
        c.eye = c.target + rotation * offset;
        self.camera = c.clipped_to(&self.bounds);
    }

    /// Pans by `dx`, `dy` pixels of an image `height` pixels high (the target follows).
    pub fn pan(&mut self, dx: f64, dy: f64, height: u32) {
        let c = &mut self.camera;
        let (_, right, up) = c.basis();
        let pixel = c.pixel_size(c.eye.distance(c.target), height);
        let shift = (-right * dx + up * dy) * pixel;
        c.eye += shift;
        c.target += shift;
        self.camera = self.camera.clipped_to(&self.bounds);
    }

    /// Moves the eye towards the target: the distance times `factor` (below 1 closer).
    pub fn zoom(&mut self, factor: f64) {
        let factor = factor.clamp(1e-3, 1e3);
        let c = &mut self.camera;
        c.eye = c.target + (c.eye - c.target) * factor;
        self.camera = self.camera.clipped_to(&self.bounds);
    }

    /// A standard view of the whole scene (numpad 1, 3, 7 and their opposites).
    pub fn view(&mut self, view: View, aspect: f64) {
        let ortho = self.ortho;
        self.ortho = false;
        self.camera = Camera::fit_up(view, self.up_axis, &self.bounds, self.fov, aspect);
        if ortho {
            self.toggle_ortho();
        }
    }

    /// The view from the other side (numpad 9): the eye mirrored through the target.
    pub fn opposite(&mut self) {
        let c = &mut self.camera;
        c.eye = c.target - (c.eye - c.target);
        self.camera = self.camera.clipped_to(&self.bounds);
    }

    /// Frames the whole scene from the current direction (Home).
    pub fn frame_all(&mut self, aspect: f64) {
        let c = self.camera;
        let dir = (c.eye - c.target).normalize_or(Vec3::Z);
        let half_v = 0.5 * c.fov.to_radians();
        let half = half_v.min((half_v.tan() * aspect).atan());
        let distance = self.bounds.radius().max(f64::MIN_POSITIVE) / half.sin();
        let target = self.bounds.center();
        self.camera =
            Camera::new(target + dir * distance, target, c.up, c.fov).clipped_to(&self.bounds);
    }

    /// Switches between the perspective and the orthographic look (numpad 5), keeping the
    /// plane through the target the same size on screen.
    pub fn toggle_ortho(&mut self) {
        let c = self.camera;
        let (from, to) = if self.ortho {
            (ORTHO_FOV, self.fov)
        } else {
            (c.fov, ORTHO_FOV)
        };
        if !self.ortho {
            self.fov = c.fov;
        }
        let d = c.eye.distance(c.target);
        let height = 2.0 * d * (0.5 * from.to_radians()).tan();
        let d2 = 0.5 * height / (0.5 * to.to_radians()).tan();
        let dir = (c.eye - c.target).normalize_or(Vec3::Z);
        self.ortho = !self.ortho;
        self.camera = Camera::new(c.target + dir * d2, c.target, c.up, to).clipped_to(&self.bounds);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Navigation {
        let b = Bounds {
            min: Vec3::splat(-1.0),
            max: Vec3::ONE,
        };
        Navigation::fitted(View::Front, UpAxis::Z, b, 30.0, 1.0)
    }

    #[test]
    fn orbiting_keeps_the_distance_and_stops_at_the_pole() {
        let mut n = unit();
        let d = n.camera.eye.distance(n.camera.target);
        n.orbit(90.0, 0.0);
        assert!((n.camera.eye.distance(n.camera.target) - d).abs() < 1e-9);
        // front looks along +Y; a quarter turn puts the eye on the x axis
        assert!(n.camera.eye.y.abs() < 1e-9 && n.camera.eye.x.abs() > 1.0);
        n.orbit(0.0, 200.0);
        let elevation = (n.camera.eye - n.camera.target)
            .normalize()
            .z
            .asin()
            .to_degrees();
        assert!((elevation - 89.0).abs() < 1e-6, "{elevation}");
        n.camera.check().unwrap();
    }

    #[test]
    fn ortho_keeps_the_target_plane_and_comes_back() {
        let mut n = unit();
        let before = n.camera;
        let size = |c: &Camera| c.pixel_size(c.eye.distance(c.target), 100);
        n.toggle_ortho();
        assert!((n.camera.fov - ORTHO_FOV).abs() < 1e-12);
        assert!((size(&n.camera) / size(&before) - 1.0).abs() < 1e-9);
        n.toggle_ortho();
        assert!((n.camera.eye - before.eye).length() < 1e-9);
        assert_eq!(n.camera.fov, before.fov);
    }

    #[test]
    fn pan_zoom_and_opposite_move_as_asked() {
        let mut n = unit();
        let d = n.camera.eye.distance(n.camera.target);
        n.zoom(0.5);
        assert!((n.camera.eye.distance(n.camera.target) - 0.5 * d).abs() < 1e-9);
        let t = n.camera.target;
        n.pan(10.0, 0.0, 100);
        assert!(n.camera.target.distance(t) > 0.0);
        let e = n.camera.eye - n.camera.target;
        n.opposite();
        assert!(((n.camera.eye - n.camera.target) + e).length() < 1e-9);
    }
}
