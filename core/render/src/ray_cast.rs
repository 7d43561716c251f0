//! Full-scene ray casting of B-Rep faces (issue 21 step 2; paper 001 §4.1.2, the reference
//! the paper compares its crack filling with): per pixel, Newton on the faces' basis
//! surfaces (`shaders/ray_newton.wgsl`, §3.4.2.a) from seed points, each converged hit
//! trimmed by the same trim structure as the raster path (paper 000 §5,
//! `shaders/trim_quadtree.wgsl`), the nearest kept and shaded into the frame's per-pixel
//! buffers (`crate::frame_buffers` layout). A second, tessellation-free reference for the
//! raster pass and its crack filling.
//!
//! Seeds: the seed boxes of [`crate::ray_seeds`], built once per scene on the CPU and uploaded
//! with it ([`GpuBrepScene::ray_seeds`](crate::GpuBrepScene::ray_seeds)).
//!
//! Bindings: group 0 is the pass's own (parameters, seed boxes, the per-pixel hits, the
//! frame's buffers), group 1 the part's shared buffers ([`crate::bindings::brep_layout`],
//! `shaders/brep_bindings.wgsl`). Run by [`crate::brep_render::BrepPasses::ray_cast`].

use crate::camera::Vec3;
use bytemuck::{Pod, Zeroable};
use std::time::{Duration, Instant};
use tessd_gpu::{GpuContext, GpuError};
use wgpu::util::DeviceExt;

use crate::RenderError;
use crate::RenderSettings;
use crate::bindings::{self, PIXEL_TILE, storage, uniform};
use crate::brep_scene::BrepScene;
use crate::camera::Camera;
use crate::frame_buffers::FrameBuffers;
use crate::newton::NEWTON_TOLERANCE;
use crate::ray_seeds::{RaySeeds, SeedBox};

/// The WGSL of the two passes (`cast_rays`, `resolve_hits`) with the libraries they use.
pub const SHADER: &str = concat!(
    include_str!("../../../shaders/brep_bindings.wgsl"),
    include_str!("../../../shaders/surface_eval.wgsl"),
    include_str!("../../../shaders/ray_newton.wgsl"),
    include_str!("../../../shaders/trim_quadtree.wgsl"),
    include_str!("../../../shaders/shading.wgsl"),
    include_str!("../../../shaders/ray_cast.wgsl")
);

/// The uniform block (`RayParams` in the shader, 96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    eye: [f32; 3],
    tol: f32,
    forward: [f32; 3],
    width: u32,
    right: [f32; 3],
    height: u32,
    up: [f32; 3],
    faces: u32,
    light: [f32; 3],
    shading: u32,
    tan_x: f32,
    tan_y: f32,
    /// The first pixel row and column of the region being searched (the search runs in
    /// regions of the image, one slice at a time).
    row0: u32,
    col0: u32,
}

/// The loop iterations one search dispatch may spend per invocation: lavapipe ends an
/// invocation's loop nest after 65 535 (see `shaders/ray_cast.wgsl`); a margin is kept.
pub const LOOP_BUDGET: u32 = 60_000;

/// About how long one submission of the search should keep the device busy: the caller's
/// progress and cancel are heard between submissions.
pub const SLICE: Duration = Duration::from_millis(25);

/// Bytes between two batch records in the batch uniform buffer (wgpu's dynamic-offset
/// alignment).
const BATCH_STRIDE: u64 = 256;

/// `Batch` in the shader (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Batch {
    begin: u32,
    end: u32,
    first: u32,
    pad: u32,
}

/// The nearest hit of a pixel (`CastHit`, 16 bytes).
const HIT_BYTES: u64 = 16;

/// The compiled passes: made once per device.
pub struct RayCastPass {
    layout: wgpu::BindGroupLayout,
    cast: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
}

impl RayCastPass {
    /// Compiles the shader and builds both pipelines, group 1 being `brep_layout` (wgpu
    /// reports failures through the device's error scopes).
    pub fn new(device: &wgpu::Device, brep_layout: &wgpu::BindGroupLayout) -> RayCastPass {
        let c = wgpu::ShaderStages::COMPUTE;
        // Params, seed boxes, hits, then the frame's colour, depth, face and (u, v), and the
        // batch (a dynamic offset into the batch records).
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ray_cast"),
            entries: &[
                uniform(0, c),
                storage(1, true, c),
                storage(2, false, c),
                storage(3, false, c),
                storage(4, false, c),
                storage(5, false, c),
                storage(6, false, c),
                storage(8, true, c),
                wgpu::BindGroupLayoutEntry {
                    binding: 7,
                    visibility: c,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(size_of::<Batch>() as u64),
                    },
                    count: None,
                },
            ],
        });
        let [cast, resolve] = bindings::compute_pipelines(
            device,
            "ray_cast",
            SHADER,
            &[&layout, brep_layout],
            ["cast_rays", "resolve_hits"],
        );
        RayCastPass {
            layout,
            cast,
            resolve,
        }
    }

    /// Runs both passes: every pixel of `out` (its `width × height`) of the part `scene`
    /// (on the device as `brep`, bound as `brep_group`) seen from `camera` written to the
    /// frame's colour (RGBA8 packed), depth (camera z, or the background depth), face (its
    /// index plus one, or 0) and (u, v) (native) buffers; index y·W + x, row 0 at the top.
    /// Shaded in `settings.shading` with the raster pass's key light; Newton's tolerance is
    /// [`NEWTON_TOLERANCE`] of the part's box diagonal (as object filling). The crack flags
    /// are left as they are.
    ///
    /// The search is submitted in slices of about [`SLICE`] of device time each: regions of
    /// the image in reading order (part of a row of [`PIXEL_TILE`]-pixel tiles, or whole tile
    /// rows), each through all its batches before the next; the region's size and the batches
    /// per submission are sized from what each batch cost per tile in the same tile columns
    /// of the rows above (measured as it goes). After each submission `progress` gets the fraction of the search done; when it
    /// answers `false` nothing more is submitted and the pass ends with
    /// [`RenderError::Cancelled`]. A slice is at least one batch over one tile.
    ///
    /// # Errors
    /// [`RenderError::Cancelled`]; [`RenderError::Gpu`] when waiting for the device fails.
    #[allow(clippy::too_many_arguments)]
    pub fn cast(
        &self,
        gpu: &GpuContext,
        brep_group: &wgpu::BindGroup,
        (seeds, seed_buffer): (&RaySeeds, &wgpu::Buffer),
        scene: &BrepScene,
        camera: &Camera,
        settings: &RenderSettings,
        out: &FrameBuffers,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<(), RenderError> {
        let device = &gpu.device;
        let (width, height) = (out.width, out.height);
        let (forward, right, up) = camera.basis();
        let lit = crate::surface::Params::new(camera, scene.origin, width, height, settings);
        let tan_y = (0.5 * camera.fov.to_radians()).tan();
        let f32s = |v: Vec3| v.as_vec3().to_array();
        let params = Params {
            eye: f32s(camera.eye - Vec3::from(scene.origin)),
            tol: (NEWTON_TOLERANCE * 2.0 * scene.bounds.radius()) as f32,
            forward: f32s(forward),
            width,
            right: f32s(right),
            height,
            up: f32s(up),
            faces: scene.faces.len() as u32,
            light: lit.light,
            shading: lit.shading,
            tan_x: (tan_y * width as f64 / height.max(1) as f64) as f32,
            tan_y: tan_y as f32,
            row0: 0,
            col0: 0,
        };
        let mut params = params;
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray_cast params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let hits = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray_cast hits"),
            size: (width as u64 * height as u64 * HIT_BYTES).max(HIT_BYTES),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        // Work items: the faces nearest first, each face's cells in chunks whose worst-case
        // loop cost fits the budget; then batches of consecutive items within the budget
        // (analytic faces go by the dozen, a thread's cells by the ten). At least one batch,
        // which starts every pixel from no hit.
        let eye = [0, 1, 2].map(|k| camera.eye[k] - scene.origin[k]);
        let nearest = |b: &SeedBox| {
            (0..8)
                .map(|i| {
                    (0..3)
                        .map(|k| {
                            let c = if i >> k & 1 == 0 { b.lo[k] } else { b.hi[k] };
                            (c as f64 - eye[k]) * forward[k]
                        })
                        .sum::<f64>()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let faces = scene.faces.len();
        let mut by_depth: Vec<(f64, usize)> = (0..faces)
            .filter(|&f| seeds.boxes[f].b != 0)
            .map(|f| (nearest(&seeds.boxes[f]), f))
            .collect();
        by_depth.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut items: Vec<[u32; 4]> = Vec::new();
        let mut costs: Vec<u32> = Vec::new();
        for &(_, f) in &by_depth {
            let fb = &seeds.boxes[f];
            let count = (fb.b & 0xffff) * (fb.b >> 16);
            let per_cell = seeds.cell_costs[f].saturating_add(1);
            let chunk = (LOOP_BUDGET / per_cell).max(1);
            let mut first = 0;
            while first < count {
                let n = chunk.min(count - first);
                items.push([f as u32, fb.a + first, n, 0]);
                costs.push(1 + n * per_cell);
                first += n;
            }
        }
        let mut batches = vec![Batch {
            begin: 0,
            end: 0,
            first: 1,
            pad: 0,
        }];
        let mut spent = 0u32;
        for (k, &cost) in costs.iter().enumerate() {
            let last = batches.last_mut().expect("one batch at least");
            if last.end > last.begin && spent.saturating_add(cost) > LOOP_BUDGET {
                batches.push(Batch {
                    begin: k as u32,
                    end: k as u32 + 1,
                    first: 0,
                    pad: 0,
                });
                spent = cost;
            } else {
                last.end = k as u32 + 1;
                spent = spent.saturating_add(cost);
            }
        }
        let items_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray_cast items"),
            contents: bytemuck::cast_slice(if items.is_empty() {
                &[[0u32; 4]][..]
            } else {
                &items
            }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let mut records = vec![0u8; batches.len() * BATCH_STRIDE as usize];
        for (k, b) in batches.iter().enumerate() {
            let at = k * BATCH_STRIDE as usize;
            records[at..at + size_of::<Batch>()].copy_from_slice(bytemuck::bytes_of(b));
        }
        let batch_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray_cast batches"),
            contents: &records,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        // Bindings 0–6, then the batch (7, one record at a dynamic offset) and the items (8).
        let batch = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &batch_buffer,
            offset: 0,
            size: wgpu::BufferSize::new(size_of::<Batch>() as u64),
        });
        let resources = [
            &uniform,
            seed_buffer,
            &hits,
            &out.color,
            &out.depth,
            &out.face,
            &out.uv,
        ]
        .map(|b| b.as_entire_binding())
        .into_iter()
        .chain([batch, items_buffer.as_entire_binding()]);
        let group = bindings::bind_resources(device, "ray_cast", &self.layout, resources);
        let groups = bindings::dispatch_pixels(width, height);
        // One submission: `record` in a compute pass, then a wait for the device.
        let submit = |record: &mut dyn FnMut(&mut wgpu::ComputePass<'_>)| {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("ray_cast"),
            });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("ray_cast"),
                    timestamp_writes: None,
                });
                pass.set_bind_group(1, brep_group, &[]);
                record(&mut pass);
            }
            let index = gpu.queue.submit([encoder.finish()]);
            gpu.device
                .poll(wgpu::PollType::Wait {
                    submission_index: Some(index),
                    timeout: None,
                })
                .map_err(|e| GpuError::Wgpu(e.to_string()))
        };
        let (tiles_x, tiles_y) = (groups.0, groups.1);
        let nb = batches.len();
        let slice = SLICE.as_secs_f64();
        let tx = tiles_x as usize;
        // Seconds per tile of each batch in each tile column, as last measured (the rows
        // above predict the next: a part's silhouette changes little from one tile row to the
        // next, while the nearest faces' batches, first, cost far more than the rest);
        // `None` before a column is measured.
        let mut cost: Vec<Option<f64>> = vec![None; nb * tx];
        let total = tiles_x as u64 * tiles_y as u64;
        let (mut row, mut col) = (0u32, 0u32);
        // The last region's tiles: an unmeasured stretch grows at most twice as large.
        let mut last = 2u32;
        while row < tiles_y {
            // The region: from `col`, as many columns as the dearest batch of each can do in a
            // slice; whole tile rows when a whole row fits.
            let dearest = |c: usize| {
                (0..nb)
                    .filter_map(|b| cost[b * tx + c])
                    .fold(None, |a: Option<f64>, x| Some(a.map_or(x, |a| a.max(x))))
            };
            let (mut cols, mut spent) = (0u32, 0.0);
            let mut unknown = 0u32;
            while col + cols < tiles_x {
                let c = dearest((col + cols) as usize);
                if c.is_none() {
                    unknown += 1;
                }
                let next = spent + c.unwrap_or(0.0);
                if cols > 0 && (next > slice || unknown > 2 * last) {
                    break;
                }
                spent = next;
                cols += 1;
            }
            let rows = if col == 0 && cols == tiles_x && unknown == 0 {
                ((slice / spent.max(1e-12)) as u32).clamp(1, tiles_y - row)
            } else {
                1
            };
            last = cols * rows;
            let span = col as usize..(col + cols) as usize;
            // Batch `b`'s predicted seconds over the region (`None`: unknown somewhere).
            let predict = |cost: &[Option<f64>], b: usize| {
                span.clone()
                    .map(|c| cost[b * tx + c])
                    .sum::<Option<f64>>()
                    .map(|s| s * rows as f64)
            };
            params.row0 = row * PIXEL_TILE;
            params.col0 = col * PIXEL_TILE;
            gpu.queue
                .write_buffer(&uniform, 0, bytemuck::bytes_of(&params));
            let mut b = 0;
            while b < nb {
                // As many batches as fit a slice by their predictions (one at least; one
                // without a prediction goes alone).
                let (mut count, mut spent) = (0, 0.0);
                while b + count < nb {
                    match predict(&cost, b + count) {
                        Some(t) if count == 0 || spent + t <= slice => {
                            spent += t;
                            count += 1;
                        }
                        None if count == 0 => {
                            count = 1;
                            break;
                        }
                        _ => break,
                    }
                }
                let start = Instant::now();
                submit(&mut |pass| {
                    pass.set_pipeline(&self.cast);
                    for k in b..b + count {
                        pass.set_bind_group(0, &group, &[(k as u64 * BATCH_STRIDE) as u32]);
                        pass.dispatch_workgroups(cols, rows, 1);
                    }
                })?;
                // The time shared over the batches and columns in proportion to what was
                // predicted (evenly where nothing was).
                let took = start.elapsed().as_secs_f64();
                let mut weights = Vec::with_capacity(count * span.len());
                for k in b..b + count {
                    for c in span.clone() {
                        weights.push(cost[k * tx + c].unwrap_or(0.0));
                    }
                }
                let sum: f64 = weights.iter().sum();
                let even = sum <= 0.0 || weights.contains(&0.0);
                let cells = weights.len() as f64;
                let mut w = weights.into_iter();
                for k in b..b + count {
                    for c in span.clone() {
                        let share = match (even, w.next()) {
                            (false, Some(x)) => took * x / sum,
                            _ => took / cells,
                        };
                        cost[k * tx + c] = Some(share / rows as f64);
                    }
                }
                b += count;
                let done = (row as u64 * tiles_x as u64 + col as u64) as f64
                    + (cols * rows) as f64 * b as f64 / nb as f64;
                if !progress(done / total as f64) {
                    return Err(RenderError::Cancelled);
                }
            }
            col += cols;
            if col >= tiles_x {
                col = 0;
                row += rows;
            }
        }
        submit(&mut |pass| {
            pass.set_bind_group(0, &group, &[0]);
            pass.set_pipeline(&self.resolve);
            pass.dispatch_workgroups(tiles_x, tiles_y, 1);
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::wgsl_check::{struct_size, validated};

    /// The WGSL validates without a device and its structs have the Rust sizes.
    #[test]
    fn shader_validates_with_naga() {
        let module = validated(super::SHADER);
        assert_eq!(
            struct_size(&module, "RayParams"),
            size_of::<super::Params>()
        );
        assert_eq!(size_of::<super::Params>(), 96);
        assert_eq!(
            struct_size(&module, "SeedBox"),
            size_of::<crate::ray_seeds::SeedBox>()
        );
        assert_eq!(struct_size(&module, "CastHit") as u64, super::HIT_BYTES);
        assert_eq!(
            struct_size(&module, "SurfaceHeader"),
            crate::surface_pack::SURFACE_HEADER_BYTES
        );
    }
}
