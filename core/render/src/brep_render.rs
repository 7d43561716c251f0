//! The B-Rep picture pipeline of paper 001 (figure 4), each step its own pass and module, run
//! here in order with a wall time per step (table 1's rows):
//!
//! 0. basis-surface tessellation of the frame ([`crate::patch_tessellation`]) and triangle
//!    classification ([`crate::triangle_classification`], paper 000 §6);
//! 1. initial rendering with GPU trimming ([`crate::trimmed_surface`], §3.1), gathered into
//!    the per-pixel buffers ([`crate::frame_buffers`]);
//! 2. crack detection ([`crate::crack_detect`], §3.2);
//! 3. then either image-space filling ([`crate::image_fill`], §3.3) or object-space filling
//!    ([`crate::object_fill`], §3.4: depth mask, ray casting from the filled and wireframe
//!    passes, composite);
//!
//! or, instead of all of it, full-scene ray casting ([`crate::ray_cast`]).
//!
//! Each step is submitted on its own and waited for, so that its time is its own (a few
//! hundred microseconds of submission overhead per step, against milliseconds of work).

use crate::bindings::read_words;
use crate::brep_scene::{BrepScene, GpuBrep, brep_group};
use crate::crack_detect::{CrackDetectPass, count_flags, default_d_min};
use crate::frame_buffers::{FrameBuffers, GatherPass};
use crate::image_fill::ImageFillPass;
use crate::object_fill::ObjectFillPass;
use crate::patch_tessellation::{FrameTessellation, PIXEL_ACCURACY, TessellationPass};
use crate::ray_cast::RayCastPass;
use crate::ray_seeds::RaySeeds;
use crate::step_timing::{StepTimings, step};
use crate::targets::Targets;
use crate::triangle_classification::{CellDecision, ClassificationPass};
use crate::trimmed_surface::TrimmedSurfacePass;
use crate::{Camera, Frame, RenderError, RenderSettings, bindings, check_size};
use std::sync::OnceLock;
use std::time::Instant;
use tessd_gpu::{ErrorScopes, GpuContext};

/// How cracks between faces are handled (paper 001 §3.3–3.4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Cracks {
    /// Detected and counted, left as they are.
    None,
    /// Filled from the neighbouring pixels (§3.3): fast, approximate.
    Image,
    /// Filled by ray casting the neighbouring faces at the crack pixels (§3.4): exact.
    #[default]
    Object,
}

impl Cracks {
    /// Every mode, in the CLI's order.
    pub const ALL: [Cracks; 3] = [Cracks::None, Cracks::Image, Cracks::Object];

    /// The mode's name (`none`, `image`, `object`).
    pub fn name(self) -> &'static str {
        match self {
            Cracks::None => "none",
            Cracks::Image => "image",
            Cracks::Object => "object",
        }
    }

    /// The mode named `s`.
    pub fn parse(s: &str) -> Option<Cracks> {
        Cracks::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// What one B-Rep frame did, besides its pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BrepReport {
    /// Per step.
    pub timings: StepTimings,
    /// Crack pixels detected (§3.2; 0 for a ray-cast frame).
    pub cracks_detected: usize,
    /// Of them, filled.
    pub cracks_filled: usize,
    /// Faces tessellated in this frame (the others were outside the view).
    pub faces_drawn: usize,
    /// Grid cells (two triangles each).
    pub cells: u64,
    /// Grid vertices.
    pub grid_vertices: u64,
}

/// The compiled B-Rep passes of a device.
pub struct BrepPasses {
    brep_layout: wgpu::BindGroupLayout,
    tessellate: TessellationPass,
    classify: ClassificationPass,
    surface: TrimmedSurfacePass,
    gather: GatherPass,
    detect: CrackDetectPass,
    image_fill: ImageFillPass,
    object_fill: ObjectFillPass,
    ray_cast: RayCastPass,
}

/// A part on the device, ready for any number of frames.
pub struct GpuBrepScene {
    /// The CPU side (factors need it every frame).
    pub scene: BrepScene,
    buffers: GpuBrep,
    group: wgpu::BindGroup,
    /// The ray caster's seed boxes and their buffer, made on the first ray cast.
    seeds: OnceLock<(RaySeeds, wgpu::Buffer)>,
}

impl GpuBrepScene {
    /// The ray caster's seeds ([`BrepScene::ray_seeds`]) and their storage buffer, built and
    /// uploaded on the first call.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when the buffer is over the device's limits.
    pub fn ray_seeds(
        &self,
        device: &wgpu::Device,
    ) -> Result<&(RaySeeds, wgpu::Buffer), RenderError> {
        if let Some(s) = self.seeds.get() {
            return Ok(s);
        }
        let seeds = self.scene.ray_seeds();
        let buffer =
            bindings::storage_init(device, "seed boxes", bytemuck::cast_slice(&seeds.boxes))?;
        Ok(self.seeds.get_or_init(|| (seeds, buffer)))
    }

    /// Bytes of the trim structure on the device (paper 000 table 3).
    pub fn trim_bytes(&self) -> usize {
        self.buffers.trim_bytes
    }
}

impl BrepPasses {
    /// Compiles every pass.
    pub fn new(device: &wgpu::Device) -> BrepPasses {
        let stages = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let brep_layout = bindings::brep_layout(device, stages);
        BrepPasses {
            tessellate: TessellationPass::new(device, &brep_layout),
            classify: ClassificationPass::new(device, &brep_layout),
            surface: TrimmedSurfacePass::new(device, &brep_layout),
            gather: GatherPass::new(device),
            detect: CrackDetectPass::new(device),
            image_fill: ImageFillPass::new(device),
            object_fill: ObjectFillPass::new(device, &brep_layout),
            ray_cast: RayCastPass::new(device, &brep_layout),
            brep_layout,
        }
    }

    /// Uploads `scene`.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when a buffer is over the device's limits.
    pub fn upload(&self, gpu: &GpuContext, scene: BrepScene) -> Result<GpuBrepScene, RenderError> {
        let buffers = GpuBrep::upload(&gpu.device, &scene)?;
        let group = brep_group(&gpu.device, &self.brep_layout, &buffers);
        Ok(GpuBrepScene {
            scene,
            buffers,
            group,
            seeds: OnceLock::new(),
        })
    }

    /// Runs the grid and triangle-classification passes of `frame` over `part` and reads
    /// back what classification decided per cell (tests and diagnostics of paper 000 §6).
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when wgpu fails.
    pub fn classify_cells(
        &self,
        gpu: &GpuContext,
        part: &GpuBrepScene,
        frame: &FrameTessellation,
    ) -> Result<Vec<CellDecision>, RenderError> {
        let device = &gpu.device;
        let scopes = ErrorScopes::push(device);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("classify cells"),
        });
        let tess = self
            .tessellate
            .encode(device, &mut encoder, &part.group, frame);
        self.classify
            .encode(device, &mut encoder, &part.group, frame, &tess);
        gpu.queue.submit([encoder.finish()]);
        let words = read_words(device, &gpu.queue, &tess.cells)?;
        scopes.pop_blocking()?;
        let mut cells = CellDecision::decode(&words);
        cells.truncate(frame.cells as usize);
        Ok(cells)
    }

    /// Renders `part` from `camera`: tessellation, steps 1–2, then the filling `cracks` asks
    /// for, and reads the frame back.
    ///
    /// # Errors
    /// [`RenderError::Size`] / [`RenderError::Camera`] for a bad size or camera,
    /// [`RenderError::Gpu`] when wgpu fails.
    pub fn render(
        &self,
        gpu: &GpuContext,
        part: &GpuBrepScene,
        camera: &Camera,
        settings: &RenderSettings,
        cracks: Cracks,
    ) -> Result<(Frame, BrepReport), RenderError> {
        let (width, height) = (settings.width, settings.height);
        check_frame(gpu, camera, width, height)?;
        let device = &gpu.device;
        let scene = &part.scene;
        let mut report = BrepReport::default();
        let t = &mut report.timings;
        let scopes = ErrorScopes::push(device);

        let tess_frame = FrameTessellation::new(scene, camera, width, height, PIXEL_ACCURACY);
        report.faces_drawn = tess_frame.patches.len();
        report.cells = tess_frame.cells as u64;
        report.grid_vertices = tess_frame.vertices as u64;
        let tess = step(gpu, &mut t.tessellation, |e| {
            let tess = self.tessellate.encode(device, e, &part.group, &tess_frame);
            self.classify
                .encode(device, e, &part.group, &tess_frame, &tess);
            tess
        })?;

        let targets = Targets::new(device, width, height);
        let buffers = FrameBuffers::new(device, width, height);
        step(gpu, &mut t.initial, |e| {
            self.surface.encode(
                device,
                e,
                &targets,
                &part.group,
                &tess,
                scene.origin,
                camera,
                settings,
            );
            self.gather.encode(device, e, &targets, camera, &buffers);
        })?;

        let d_min = default_d_min(2.0 * scene.bounds.radius());
        step(gpu, &mut t.crack_detection, |e| {
            self.detect.encode(device, e, &buffers, d_min)
        })?;
        match cracks {
            Cracks::None => {}
            Cracks::Image => {
                step(gpu, &mut t.image_fill, |e| {
                    self.image_fill.encode(device, e, &buffers)
                })?;
            }
            Cracks::Object => {
                self.object_fill.run(
                    gpu,
                    &part.group,
                    &tess,
                    &buffers,
                    scene.origin,
                    2.0 * scene.bounds.radius(),
                    camera,
                    settings,
                    t,
                )?;
            }
        }
        scopes.pop_blocking()?;

        let start = Instant::now();
        let (frame, flags) = buffers.read(device, &gpu.queue)?;
        t.readback = start.elapsed();
        let (detected, filled) = count_flags(&flags);
        report.cracks_detected = detected;
        report.cracks_filled = filled;
        Ok((frame, report))
    }

    /// Full-scene ray casting of `part` from `camera` (the comparison of paper 001 §4.1.2),
    /// submitted in slices (see [`RayCastPass::cast`]): `progress` gets the fraction done
    /// after each and stops the pass by answering `false`.
    ///
    /// # Errors
    /// As [`render`](Self::render); [`RenderError::Cancelled`] when `progress` answers
    /// `false`.
    pub fn ray_cast(
        &self,
        gpu: &GpuContext,
        part: &GpuBrepScene,
        camera: &Camera,
        settings: &RenderSettings,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<(Frame, BrepReport), RenderError> {
        let (width, height) = (settings.width, settings.height);
        check_frame(gpu, camera, width, height)?;
        let device = &gpu.device;
        let mut report = BrepReport::default();
        let scopes = ErrorScopes::push(device);
        let buffers = FrameBuffers::new(device, width, height);
        let (seeds, seed_buffer) = part.ray_seeds(device)?;
        let start = Instant::now();
        let cast = self.ray_cast.cast(
            gpu,
            &part.group,
            (seeds, seed_buffer),
            &part.scene,
            camera,
            settings,
            &buffers,
            progress,
        );
        report.timings.ray_cast += start.elapsed();
        // The device's own errors first: they explain a failed wait.
        scopes.pop_blocking()?;
        cast?;
        let start = Instant::now();
        let (frame, _) = buffers.read(device, &gpu.queue)?;
        report.timings.readback = start.elapsed();
        report.faces_drawn = part.scene.faces.len();
        Ok((frame, report))
    }
}

/// The checks every frame makes before allocating.
fn check_frame(
    gpu: &GpuContext,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<(), RenderError> {
    let max_side = gpu.device.limits().max_texture_dimension_2d;
    check_size(width, height, max_side)?;
    camera.check()?;
    if !(camera.near > 0.0 && camera.far > camera.near && camera.far.is_finite()) {
        return Err(RenderError::Camera(format!(
            "near {} and far {} planes must satisfy 0 < near < far",
            camera.near, camera.far
        )));
    }
    Ok(())
}
