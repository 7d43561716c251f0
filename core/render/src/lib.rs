//! Headless pictures of meshes and B-Rep parts (issue 21, step 1): a wgpu renderer that runs
//! on a real GPU when there is one and on lavapipe (Mesa's software Vulkan driver) otherwise,
//! and reads every target back to the CPU.
//!
//! The pipeline, one module per step: [`scene`] (triangles with face ids and (u, v), from a
//! mesh or a CPU tessellation of a B-Rep), [`camera`] (the pixel-ray convention hosts rely on,
//! standard views fitted to the part), [`surface`] (the raster pass: colour and the metadata
//! buffer of paper 001 §3.1, face id and (u, v), plus depth), [`targets`] (the render targets
//! and their read-back), [`image`] (PNG encoding, including the face-id encoding),
//! [`trim_walk`] (the trim-quadtree walk of paper 000 §5.1–5.3 as a compute pass over query
//! points, checked against its CPU reference).
//!
//! Later steps of issue 21 build on the same targets: GPU trimming (paper 000 §5–7) will
//! discard fragments outside a face's trims in the surface pass, and crack filling (paper 001)
//! will read and write the face-id / (u, v) buffer.
//!
//! ```no_run
//! use tessd_render::{Camera, RenderSettings, Renderer, Scene, View};
//! let mesh = tessd_mesh::io::read_path("bunny.obj".as_ref(), &Default::default()).unwrap();
//! let scene = Scene::from_mesh(&mesh);
//! let renderer = Renderer::new().unwrap();
//! let gpu = renderer.upload(&scene).unwrap();
//! let settings = RenderSettings::new(640, 480);
//! let camera = Camera::fit(View::Iso, &scene.bounds.unwrap(), 30.0, 640.0 / 480.0);
//! let (frame, _) = renderer.render(&gpu, &camera, &settings).unwrap();
//! tessd_render::image::write_png("bunny.png".as_ref(), 640, 480, &frame.color).unwrap();
//! ```

#![warn(missing_docs)]

/// The WGSL of a pass over the frame's grid: `shaders/brep_bindings.wgsl`, `trim_quadtree.wgsl`,
/// `surface_eval.wgsl` and `patch_grid.wgsl`, then the named files of `shaders/`.
macro_rules! patch_grid_shader {
    ($($file:literal),+ $(,)?) => {
        concat!(
            include_str!("../../../shaders/brep_bindings.wgsl"),
            include_str!("../../../shaders/trim_quadtree.wgsl"),
            include_str!("../../../shaders/surface_eval.wgsl"),
            include_str!("../../../shaders/patch_grid.wgsl"),
            $(include_str!(concat!("../../../shaders/", $file)),)+
        )
    };
}

pub mod bindings;
pub mod brep_render;
pub mod brep_scene;
pub mod camera;
pub mod classification_level;
pub mod crack_detect;
pub mod frame_buffers;
pub mod image;
pub mod image_fill;
pub mod newton;
pub mod object_fill;
pub mod panels;
pub mod patch_tessellation;
pub mod present;
pub mod ray_cast;
pub mod ray_seeds;
pub mod scene;
pub mod step_timing;
pub mod surface;
pub mod surface_pack;
pub mod targets;
pub mod triangle_classification;
pub mod trim_walk;
pub mod trimmed_surface;
#[cfg(test)]
mod wgsl_check;

pub use brep_render::{BrepReport, Cracks, GpuBrepScene};
pub use brep_scene::BrepScene;
pub use camera::{Bounds, Camera, UpAxis, View};
pub use scene::Scene;
pub use step_timing::StepTimings;
pub use trim_walk::TrimWalk;

use std::time::{Duration, Instant};
use tessd_gpu::{ErrorScopes, GpuContext, GpuError};
use wgpu::util::DeviceExt;

/// The largest image side accepted, whatever the adapter allows.
pub const MAX_SIDE: u32 = 16384;

/// The most pixels in one image (64 Mi: 8192 × 8192): the targets and their read-back take
/// about 40 bytes per pixel.
pub const MAX_PIXELS: u64 = 1 << 26;

/// Why a render failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// No device, or wgpu reported an error.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// An image size out of range.
    #[error("{0}")]
    Size(String),
    /// A camera that defines no view.
    #[error("camera: {0}")]
    Camera(String),
    /// PNG encoding or decoding failed.
    #[error("PNG: {0}")]
    Png(String),
    /// A file could not be written.
    #[error("{0}")]
    Io(String),
    /// The caller's progress callback asked to stop.
    #[error("cancelled")]
    Cancelled,
}

impl From<tessd_mesh::MeshError> for RenderError {
    fn from(e: tessd_mesh::MeshError) -> Self {
        RenderError::Io(e.to_string())
    }
}

/// Shading of the colour image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// Per-pixel Lambert from a key light, a headlight fill, ambient and a Blinn-Phong
    /// highlight.
    #[default]
    Lit,
    /// Gooch cool-to-warm technical shading.
    Gooch,
    /// Four-band cel shading with dark rims.
    Toon,
    /// A distinct flat colour per face id.
    FaceIds,
}

impl Shading {
    /// Every mode, in the CLI's order.
    pub const ALL: [Shading; 4] = [
        Shading::Lit,
        Shading::Gooch,
        Shading::Toon,
        Shading::FaceIds,
    ];

    /// The mode's name (`lit`, `gooch`, `toon`, `face-ids`).
    pub fn name(self) -> &'static str {
        match self {
            Shading::Lit => "lit",
            Shading::Gooch => "gooch",
            Shading::Toon => "toon",
            Shading::FaceIds => "face-ids",
        }
    }

    /// The mode named `s`.
    pub fn parse(s: &str) -> Option<Shading> {
        Shading::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// What a mesh's triangles are drawn as (`tessd view`'s `W`). B-Rep parts are always drawn
/// solid; their wireframe is the edge overlay of their per-frame tessellation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DrawMode {
    /// Shaded surfaces.
    #[default]
    Solid = 0,
    /// The triangles' edges only, about a pixel wide, hidden ones included.
    Wireframe = 1,
    /// The vertices only, dots about four pixels across.
    Points = 2,
}

impl DrawMode {
    /// Every mode, in `W`'s cycle order.
    pub const ALL: [DrawMode; 3] = [DrawMode::Solid, DrawMode::Wireframe, DrawMode::Points];

    /// The mode's name (`solid`, `wireframe`, `points`).
    pub fn name(self) -> &'static str {
        match self {
            DrawMode::Solid => "solid",
            DrawMode::Wireframe => "wireframe",
            DrawMode::Points => "points",
        }
    }

    /// The mode named `s`.
    pub fn parse(s: &str) -> Option<DrawMode> {
        DrawMode::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// What to render besides the scene and the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RenderSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Shading of the colour image.
    pub shading: Shading,
    /// Overlay the triangle edges (drawn from barycentric coordinates in the surface pass).
    pub edges: bool,
    /// Surfaces, wireframe or points (meshes only).
    pub mode: DrawMode,
}

impl RenderSettings {
    /// `width × height`, lit, no edges.
    pub fn new(width: u32, height: u32) -> RenderSettings {
        RenderSettings {
            width,
            height,
            shading: Shading::Lit,
            edges: false,
            mode: DrawMode::Solid,
        }
    }

    /// With `shading`.
    pub fn with_shading(mut self, shading: Shading) -> Self {
        self.shading = shading;
        self
    }

    /// With or without the edge overlay.
    pub fn with_edges(mut self, edges: bool) -> Self {
        self.edges = edges;
        self
    }

    /// With `mode`.
    pub fn with_mode(mut self, mode: DrawMode) -> Self {
        self.mode = mode;
        self
    }

    /// Width / height.
    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height.max(1) as f64
    }
}

/// Checks an image size before anything is allocated: each side 1 to `max_side` pixels
/// (at most [`MAX_SIDE`]) and at most [`MAX_PIXELS`] pixels.
///
/// # Errors
/// [`RenderError::Size`] naming the size and the limits.
pub fn check_size(width: u32, height: u32, max_side: u32) -> Result<(), RenderError> {
    let max_side = max_side.min(MAX_SIDE);
    let pixels = width as u64 * height as u64;
    if width == 0 || height == 0 || width > max_side || height > max_side || pixels > MAX_PIXELS {
        return Err(RenderError::Size(format!(
            "image size {width}x{height} is out of range: each side must be 1 to {max_side} pixels \
             and the image at most {MAX_PIXELS} pixels"
        )));
    }
    Ok(())
}

/// The adapter, for reports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterDescription {
    /// Its name (`llvmpipe (LLVM 15.0.6, 256 bits)` for lavapipe).
    pub name: String,
    /// Backend (`Vulkan`).
    pub backend: String,
    /// Device type (`Cpu`, `DiscreteGpu`, ...).
    pub device_type: String,
    /// Driver and driver info.
    pub driver: String,
}

/// One rendered image on the CPU, rows top to bottom, `width × height` pixels each.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// RGBA8.
    pub color: Vec<u8>,
    /// Distance from the eye along the view direction (camera z) of the surface seen,
    /// `f32::INFINITY` for the background.
    pub depth: Vec<f32>,
    /// Face index + 1 of the surface seen, 0 for the background.
    pub face_id: Vec<u32>,
    /// (u, v) of the surface seen (0 for the background, and for meshes without uvs).
    pub uv: Vec<[f32; 2]>,
}

impl Frame {
    /// Pixels showing the part (face id ≠ 0).
    pub fn covered(&self) -> usize {
        self.face_id.iter().filter(|&&id| id != 0).count()
    }
}

/// Wall times of one render, measured on the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimings {
    /// From recording the pass until the device reports it done.
    pub draw: Duration,
    /// Copying the targets out, mapping and unpadding them.
    pub readback: Duration,
}

/// A scene's triangles on the device, made by [`Renderer::upload`]; render it from any number
/// of cameras (a turntable uploads once).
pub struct GpuScene {
    vertices: wgpu::Buffer,
    vertex_count: u32,
    origin: [f64; 3],
}

/// A device with the compiled passes. Create it once and reuse it: opening a device and
/// compiling the shaders takes a while, far longer on lavapipe (LLVM).
pub struct Renderer {
    gpu: GpuContext,
    surface: surface::SurfacePass,
    /// The B-Rep passes, compiled on the first B-Rep render (a mesh-only process never pays
    /// for them).
    brep: std::sync::OnceLock<brep_render::BrepPasses>,
}

impl Renderer {
    /// Opens a device ([`GpuContext::open`], shared with the stencil apply phase: a real GPU
    /// preferred, lavapipe or any CPU adapter accepted) and compiles the passes.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when there is no adapter or the shaders do not compile.
    pub fn new() -> Result<Renderer, RenderError> {
        Renderer::with_context(GpuContext::open("tessd-render")?)
    }

    /// A renderer on an opened device: the viewer's, opened for its window
    /// ([`GpuContext::open_for_window`]), so that its frames can be presented there.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when the shaders do not compile.
    pub fn with_context(gpu: GpuContext) -> Result<Renderer, RenderError> {
        let scopes = ErrorScopes::push(&gpu.device);
        let surface = surface::SurfacePass::new(&gpu.device);
        scopes.pop_blocking()?;
        Ok(Renderer {
            gpu,
            surface,
            brep: std::sync::OnceLock::new(),
        })
    }

    /// The device and queue (a window presents the frames on them).
    pub fn context(&self) -> &GpuContext {
        &self.gpu
    }

    /// The B-Rep passes, compiled on first use.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when a shader does not compile on this device.
    fn brep_passes(&self) -> Result<&brep_render::BrepPasses, RenderError> {
        if let Some(p) = self.brep.get() {
            return Ok(p);
        }
        let scopes = ErrorScopes::push(&self.gpu.device);
        let passes = brep_render::BrepPasses::new(&self.gpu.device);
        scopes.pop_blocking()?;
        Ok(self.brep.get_or_init(|| passes))
    }

    /// Uploads a B-Rep part prepared by [`BrepScene::new`].
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when a buffer is over the device's limits or a pass does not
    /// compile.
    pub fn upload_brep(&self, scene: BrepScene) -> Result<GpuBrepScene, RenderError> {
        self.brep_passes()?.upload(&self.gpu, scene)
    }

    /// Renders a B-Rep part with GPU trimming and crack handling `cracks` (paper 001).
    ///
    /// # Errors
    /// As [`brep_render::BrepPasses::render`].
    pub fn render_brep(
        &self,
        part: &GpuBrepScene,
        camera: &Camera,
        settings: &RenderSettings,
        cracks: Cracks,
    ) -> Result<(Frame, BrepReport), RenderError> {
        self.brep_passes()?
            .render(&self.gpu, part, camera, settings, cracks)
    }

    /// Triangle classification's decision per grid cell of `frame` over `part` (see
    /// [`brep_render::BrepPasses::classify_cells`]).
    ///
    /// # Errors
    /// As [`brep_render::BrepPasses::classify_cells`].
    pub fn classify_cells(
        &self,
        part: &GpuBrepScene,
        frame: &patch_tessellation::FrameTessellation,
    ) -> Result<Vec<triangle_classification::CellDecision>, RenderError> {
        self.brep_passes()?.classify_cells(&self.gpu, part, frame)
    }

    /// Ray casts a B-Rep part (the full-scene reference of paper 001 §4.1.2).
    ///
    /// # Errors
    /// As [`brep_render::BrepPasses::ray_cast`].
    pub fn ray_cast_brep(
        &self,
        part: &GpuBrepScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<(Frame, BrepReport), RenderError> {
        self.ray_cast_brep_with_progress(part, camera, settings, &mut |_| true)
    }

    /// [`ray_cast_brep`](Self::ray_cast_brep) telling `progress` the fraction done after
    /// each slice of about [`ray_cast::SLICE`] of device time; answering `false` stops it.
    ///
    /// # Errors
    /// As [`brep_render::BrepPasses::ray_cast`]: [`RenderError::Cancelled`] when `progress`
    /// answers `false`.
    pub fn ray_cast_brep_with_progress(
        &self,
        part: &GpuBrepScene,
        camera: &Camera,
        settings: &RenderSettings,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<(Frame, BrepReport), RenderError> {
        self.brep_passes()?
            .ray_cast(&self.gpu, part, camera, settings, progress)
    }

    /// The adapter as one line: name, backend, device type, driver.
    pub fn adapter_info(&self) -> String {
        self.gpu.describe()
    }

    /// The adapter's name, backend, device type and driver, each on its own.
    pub fn adapter(&self) -> AdapterDescription {
        let i = &self.gpu.adapter_info;
        AdapterDescription {
            name: i.name.clone(),
            backend: format!("{:?}", i.backend),
            device_type: format!("{:?}", i.device_type),
            driver: format!("{} {}", i.driver, i.driver_info).trim().to_string(),
        }
    }

    /// The largest image side this device takes (the smaller of its 2D texture limit and
    /// [`MAX_SIDE`]).
    pub fn max_side(&self) -> u32 {
        self.gpu
            .device
            .limits()
            .max_texture_dimension_2d
            .min(MAX_SIDE)
    }

    /// Uploads a scene's triangles.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when the buffer is over the device's limits or wgpu fails.
    pub fn upload(&self, scene: &Scene) -> Result<GpuScene, RenderError> {
        let bytes: &[u8] = bytemuck::cast_slice(&scene.vertices);
        let limit = self.gpu.device.limits().max_buffer_size;
        if bytes.len() as u64 > limit || scene.vertices.len() > u32::MAX as usize {
            return Err(GpuError::BufferTooLarge {
                what: "vertex buffer",
                size: bytes.len() as u64,
                limit,
                limit_name: "max_buffer_size",
            }
            .into());
        }
        let scopes = ErrorScopes::push(&self.gpu.device);
        let pad = [0u8; 4];
        let vertices = self
            .gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("render vertices"),
                contents: if bytes.is_empty() { &pad } else { bytes },
                usage: wgpu::BufferUsages::VERTEX,
            });
        scopes.pop_blocking()?;
        Ok(GpuScene {
            vertices,
            vertex_count: scene.vertices.len() as u32,
            origin: scene.origin.to_array(),
        })
    }

    /// Renders `scene` from `camera` and reads every target back.
    ///
    /// # Errors
    /// [`RenderError::Size`] for a size out of range ([`check_size`] with this device's
    /// limit), [`RenderError::Camera`] for a camera that defines no view,
    /// [`RenderError::Gpu`] when wgpu fails.
    pub fn render(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<(Frame, FrameTimings), RenderError> {
        let (width, height) = (settings.width, settings.height);
        check_size(width, height, self.max_side())?;
        camera.check()?;
        if !(camera.near > 0.0 && camera.far > camera.near && camera.far.is_finite()) {
            return Err(RenderError::Camera(format!(
                "near {} and far {} planes must satisfy 0 < near < far",
                camera.near, camera.far
            )));
        }
        let device = &self.gpu.device;
        let start = Instant::now();
        let scopes = ErrorScopes::push(device);
        let targets = targets::Targets::new(device, width, height);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("render"),
        });
        self.surface.encode(
            device,
            &mut encoder,
            &targets,
            &scene.vertices,
            scene.vertex_count,
            scene.origin,
            camera,
            settings,
        );
        let index = self.gpu.queue.submit([encoder.finish()]);
        device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| GpuError::Wgpu(e.to_string()))?;
        scopes.pop_blocking()?;
        let draw = start.elapsed();

        let start = Instant::now();
        let raw = targets.read(device, &self.gpu.queue)?;
        let depth = raw
            .depth
            .iter()
            .map(|&z| {
                if z >= 1.0 {
                    f32::INFINITY
                } else {
                    camera.linear_depth(z)
                }
            })
            .collect();
        let frame = Frame {
            width,
            height,
            color: raw.color,
            depth,
            face_id: raw.face_id,
            uv: raw.uv,
        };
        let readback = start.elapsed();
        Ok((frame, FrameTimings { draw, readback }))
    }
}

/// The chordal tolerance at which to tessellate a B-Rep part of box `bounds` for `camera` and
/// an image `height` pixels high: half the world size of one pixel at the part's nearest
/// distance along the view direction (at least a tenth of the centre's distance, so an eye
/// inside the box does not ask for an endless mesh), and at least 10⁻⁵ of the box's diagonal.
/// Finer than a pixel, the facets of the CPU tessellation stay invisible until GPU trimming
/// (issue 21 step 2) evaluates the surfaces per pixel.
pub fn pixel_tolerance(camera: &Camera, bounds: &Bounds, height: u32) -> f64 {
    let (forward, _, _) = camera.basis();
    let center = (bounds.center() - camera.eye).dot(forward);
    let nearest = bounds
        .corners()
        .iter()
        .map(|c| (*c - camera.eye).dot(forward))
        .fold(f64::INFINITY, f64::min);
    let distance = nearest.max(0.1 * center.abs()).max(f64::MIN_POSITIVE);
    let tolerance = 0.5 * camera.pixel_size(distance, height);
    tolerance.max(2e-5 * bounds.radius())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked() {
        assert!(check_size(1, 1, 8192).is_ok());
        assert!(check_size(8192, 8192, 8192).is_ok());
        let e = check_size(0, 0, 8192).unwrap_err().to_string();
        assert!(e.contains("0x0"), "{e}");
        let e = check_size(100_000, 100_000, 8192).unwrap_err().to_string();
        assert!(e.contains("100000x100000"), "{e}");
        assert!(check_size(8193, 10, 8192).is_err());
        assert!(check_size(16384, 16384, 16384).is_err()); // over MAX_PIXELS
    }

    #[test]
    fn tolerance_follows_the_pixel_footprint() {
        let b = Bounds {
            min: camera::Vec3::splat(-1.0),
            max: camera::Vec3::ONE,
        };
        let c = Camera::fit(View::Front, &b, 30.0, 1.0);
        let t720 = pixel_tolerance(&c, &b, 720);
        let t360 = pixel_tolerance(&c, &b, 360);
        assert!((t360 / t720 - 2.0).abs() < 1e-9);
        // Half a pixel at the box's near face, which is 1 unit in front of the centre.
        let near = c.eye.distance(b.center()) - 1.0;
        assert!((t720 - 0.5 * c.pixel_size(near, 720)).abs() < 1e-12);
    }
}
