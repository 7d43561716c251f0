//! Full-scene ray casting of B-Rep faces (issue 21 step 2; paper 001 §4.1.2, the reference
//! the paper compares its crack filling with): per pixel, Newton on the faces' basis
//! surfaces (`shaders/ray_newton.wgsl`, §3.4.2.a) from seed points, each converged hit
//! trimmed by the same trim structure as the raster path (paper 000 §5,
//! `shaders/trim_quadtree.wgsl`), the nearest kept and shaded into the frame's per-pixel
//! buffers (`crate::frame_buffers` layout). A second, tessellation-free reference for the
//! raster pass and its crack filling.
//!
//! Seeds: the paper bounds its patches by their control polygons' convex hulls; faces here
//! are any of eight surface kinds, so each face's patch is cut into a grid of seed cells (8 ×
//! 8, more along a direction in which the normal turns a lot), each with a world box of
//! sampled surface points inflated by a bound of the surface's bulge between samples. A ray
//! runs Newton from the centre of every cell whose box it crosses, inside every face box it
//! crosses. Built once per scene on the CPU ([`RayCastScene::new`]).

use std::time::{Duration, Instant};

use bytemuck::{Pod, Zeroable};
use tessd_brep::{Document, Face};
use tessd_gpu::{ErrorScopes, GpuContext, GpuError};
use tessd_trim::TrimStructure;
use tessd_trim::multi_pack::MultiPack;
use wgpu::util::DeviceExt;

use crate::camera::{Camera, normalize};
use crate::frame_buffers::FrameBuffers;
use crate::surface_pack::SurfacePack;
use crate::{Frame, RenderError, Shading};

/// The WGSL of the two passes (`cast_rays`, `resolve_hits`) with the libraries they use.
pub const SHADER: &str = concat!(
    include_str!("../../../shaders/surface_eval.wgsl"),
    include_str!("../../../shaders/ray_newton.wgsl"),
    include_str!("../../../shaders/trim_quadtree.wgsl"),
    include_str!("../../../shaders/shading.wgsl"),
    include_str!("../../../shaders/ray_cast.wgsl")
);

/// Invocations per workgroup along x and y (`@workgroup_size(8, 8)`).
const WORKGROUP: u32 = 8;

/// Seed cells along a patch direction: at least this many…
const MIN_CELLS: usize = 8;
/// … at most this many…
const MAX_CELLS: usize = 32;
/// … and one per this much turning of the normal (radians) along the direction.
const TURN_PER_CELL: f64 = std::f64::consts::PI / 8.0;
/// Surface samples per seed cell side when building the cell boxes.
const SAMPLES_PER_CELL: usize = 4;

/// A world box relative to the scene origin (`SeedBox` in `ray_cast.wgsl`, 32 bytes): the
/// scene's face boxes first (`a` = their first cell's index, `b` = cells along s | cells along
/// t << 16), then every face's cells, row by row, s fastest (`a`, `b` unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SeedBox {
    /// Lower corner.
    pub lo: [f32; 3],
    /// Face box: index of its first cell.
    pub a: u32,
    /// Upper corner.
    pub hi: [f32; 3],
    /// Face box: cells along s in the low 16 bits, along t in the high ones.
    pub b: u32,
}

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
    pad: [u32; 2],
}

/// The nearest hit of a pixel (`CastHit`, 16 bytes).
const HIT_BYTES: u64 = 16;

/// A document's faces ready to ray cast: the surfaces ([`SurfacePack`]), the trims
/// ([`MultiPack`]) and the seed boxes, on the device.
pub struct RayCastScene {
    /// The scene origin (the document's bounding-box centre) positions are relative to.
    pub origin: [f64; 3],
    /// The bounding box's diagonal, world units.
    pub diagonal: f64,
    /// Newton's convergence tolerance, world units (10⁻⁵ of the diagonal by default).
    pub tolerance: f64,
    /// Number of faces.
    pub faces: usize,
    /// Seed cells over all faces.
    pub cells: usize,
    /// Faces left out (their trim structure failed to build), with why.
    pub warnings: Vec<String>,
    surf_headers: wgpu::Buffer,
    surf_words: wgpu::Buffer,
    trim: [wgpu::Buffer; 4],
    seeds: wgpu::Buffer,
}

/// The seed cells of one face: cells along s and t and their boxes (relative to `origin`);
/// no cells when the surface does not evaluate to finite points.
pub fn face_seeds(face: &Face, origin: [f64; 3], margin: f64) -> (usize, usize, Vec<SeedBox>) {
    let [u0, u1, v0, v1] = face.bounds;
    let uv = |s: f64, t: f64| (u0 + s * (u1 - u0), v0 + t * (v1 - v0));
    // How far the normal turns along s and along t (the most over a few lines).
    const PROBE: usize = 16;
    let normal = |s: f64, t: f64| {
        let (u, v) = uv(s, t);
        face.surface.eval(u, v).normal()
    };
    let angle = |a: Option<[f64; 3]>, b: Option<[f64; 3]>| match (a, b) {
        (Some(a), Some(b)) => (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
            .clamp(-1.0, 1.0)
            .acos(),
        _ => 0.0,
    };
    let (mut turn_s, mut turn_t) = (0.0f64, 0.0f64);
    for line in 0..=4 {
        let c = line as f64 / 4.0;
        let (mut ts, mut tt) = (0.0, 0.0);
        for k in 0..PROBE {
            let (a, b) = (k as f64 / PROBE as f64, (k + 1) as f64 / PROBE as f64);
            ts += angle(normal(a, c), normal(b, c));
            tt += angle(normal(c, a), normal(c, b));
        }
        turn_s = turn_s.max(ts);
        turn_t = turn_t.max(tt);
    }
    let cells = |turn: f64| ((turn / TURN_PER_CELL).ceil() as usize).clamp(MIN_CELLS, MAX_CELLS);
    let (ns, nt) = (cells(turn_s), cells(turn_t));
    // Samples on a grid SAMPLES_PER_CELL times finer than the cells.
    let (gs, gt) = (ns * SAMPLES_PER_CELL, nt * SAMPLES_PER_CELL);
    let mut p = Vec::with_capacity((gs + 1) * (gt + 1));
    for j in 0..=gt {
        for i in 0..=gs {
            let (u, v) = uv(i as f64 / gs as f64, j as f64 / gt as f64);
            let q = face.surface.point(u, v);
            p.push([0, 1, 2].map(|k| q[k] - origin[k]));
        }
    }
    if p.iter().flatten().any(|x| !x.is_finite()) {
        return (0, 0, Vec::new());
    }
    let at = |i: usize, j: usize| p[j * (gs + 1) + i];
    let second = |a: [f64; 3], m: [f64; 3], b: [f64; 3]| {
        let d = [0, 1, 2].map(|k| a[k] - 2.0 * m[k] + b[k]);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    };
    let mut boxes = Vec::with_capacity(ns * nt);
    for cj in 0..nt {
        for ci in 0..ns {
            let (i0, j0) = (ci * SAMPLES_PER_CELL, cj * SAMPLES_PER_CELL);
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            // The largest second differences along s and t around the cell: the surface
            // strays from the bilinear patch of four samples by about an eighth of their sum.
            let mut bulge = 0.0f64;
            for j in j0..=j0 + SAMPLES_PER_CELL {
                for i in i0..=i0 + SAMPLES_PER_CELL {
                    let q = at(i, j);
                    for k in 0..3 {
                        lo[k] = lo[k].min(q[k]);
                        hi[k] = hi[k].max(q[k]);
                    }
                    let (ia, ib) = (i.saturating_sub(1), (i + 1).min(gs));
                    let (ja, jb) = (j.saturating_sub(1), (j + 1).min(gt));
                    let ds = if ib - ia == 2 {
                        second(at(ia, j), q, at(ib, j))
                    } else {
                        0.0
                    };
                    let dt = if jb - ja == 2 {
                        second(at(i, ja), q, at(i, jb))
                    } else {
                        0.0
                    };
                    bulge = bulge.max(ds + dt);
                }
            }
            // Four times the estimate, for curvature that grows within the cell.
            let pad = 0.5 * bulge + margin;
            boxes.push(SeedBox {
                lo: lo.map(|x| (x - pad) as f32),
                a: 0,
                hi: hi.map(|x| (x + pad) as f32),
                b: 0,
            });
        }
    }
    (ns, nt, boxes)
}

impl RayCastScene {
    /// Packs and uploads `doc`'s faces: the surfaces relative to the document's bounding-box
    /// centre, the trims built by [`TrimStructure::build`] at `eps_world` (world units), the
    /// seed cells. A face whose trim structure fails to build is left out (never hit) and
    /// named in [`warnings`](Self::warnings).
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when a buffer is over the device's limits or wgpu fails.
    pub fn new(
        device: &wgpu::Device,
        doc: &Document,
        eps_world: f64,
    ) -> Result<RayCastScene, RenderError> {
        let bbox = doc.bounding_box();
        let (origin, diagonal) = match bbox {
            Some(b) => (
                [0, 1, 2].map(|k| 0.5 * (b.min[k] + b.max[k])),
                [0, 1, 2]
                    .map(|k| (b.max[k] - b.min[k]).powi(2))
                    .iter()
                    .sum::<f64>()
                    .sqrt(),
            ),
            None => ([0.0; 3], 1.0),
        };
        let diagonal = if diagonal > 0.0 { diagonal } else { 1.0 };
        let tolerance = 1e-5 * diagonal;
        let mut surfaces = SurfacePack::new(origin);
        let mut trims = MultiPack::new();
        let mut warnings = Vec::new();
        let mut face_boxes = Vec::with_capacity(doc.faces.len());
        let mut cell_boxes = Vec::new();
        let first = doc.faces.len() as u32;
        for face in &doc.faces {
            surfaces.push(face);
            let (mut ns, mut nt, mut cells) = face_seeds(face, origin, 1e-6 * diagonal + tolerance);
            match TrimStructure::build(face, eps_world) {
                Ok(trim) => {
                    trims.push(&trim, face.bounds);
                }
                Err(e) => {
                    // Keep the indices aligned: the whole patch as a stand-in, never cast.
                    warnings.push(format!("face {}: {e}; left out", face.id));
                    let mut whole = face.clone();
                    whole.loops.clear();
                    let trim = TrimStructure::build(&whole, eps_world)
                        .map_err(|e| RenderError::Io(format!("face {}: {e}", face.id)))?;
                    trims.push(&trim, face.bounds);
                    (ns, nt, cells) = (0, 0, Vec::new());
                }
            }
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for c in &cells {
                for k in 0..3 {
                    lo[k] = lo[k].min(c.lo[k]);
                    hi[k] = hi[k].max(c.hi[k]);
                }
            }
            face_boxes.push(SeedBox {
                lo,
                a: first + cell_boxes.len() as u32,
                hi,
                b: ns as u32 | (nt as u32) << 16,
            });
            cell_boxes.extend(cells);
        }
        let cells = cell_boxes.len();
        face_boxes.extend(cell_boxes);

        let scopes = ErrorScopes::push(device);
        let limit = device.limits().max_storage_buffer_binding_size;
        let buffer = |label: &'static str, bytes: &[u8]| {
            if bytes.len() as u64 > limit {
                return Err(RenderError::Gpu(GpuError::BufferTooLarge {
                    what: label,
                    size: bytes.len() as u64,
                    limit,
                    limit_name: "max_storage_buffer_binding_size",
                }));
            }
            // An empty array still needs a binding of at least one element.
            let pad = [0u8; 64];
            let contents = if bytes.is_empty() { &pad[..] } else { bytes };
            Ok(
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage: wgpu::BufferUsages::STORAGE,
                }),
            )
        };
        let scene = RayCastScene {
            origin,
            diagonal,
            tolerance,
            faces: doc.faces.len(),
            cells,
            warnings,
            surf_headers: buffer("surface headers", surfaces.header_bytes())?,
            surf_words: buffer("surface words", surfaces.word_bytes())?,
            trim: [
                buffer("trim headers", trims.header_bytes())?,
                buffer("trim nodes", bytemuck::cast_slice(&trims.nodes))?,
                buffer("trim curves", bytemuck::cast_slice(&trims.curves))?,
                buffer("trim lines", bytemuck::cast_slice(&trims.lines))?,
            ],
            seeds: buffer("seed boxes", bytemuck::cast_slice(&face_boxes))?,
        };
        scopes.pop_blocking()?;
        Ok(scene)
    }

    /// With Newton's convergence tolerance set to `tolerance` (world units).
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }
}

/// The compiled passes: made once per device.
pub struct RayCastPass {
    cast_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    cast: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
}

fn entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    entry(binding, wgpu::BufferBindingType::Storage { read_only })
}

fn bind<'a>(binding: u32, buffer: &'a wgpu::Buffer) -> wgpu::BindGroupEntry<'a> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

impl RayCastPass {
    /// Compiles the shader and builds both pipelines (wgpu reports failures through the
    /// device's error scopes).
    pub fn new(device: &wgpu::Device) -> RayCastPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ray_cast.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let uniform = entry(0, wgpu::BufferBindingType::Uniform);
        let cast_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ray_cast cast"),
            entries: &[
                uniform,
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, true),
                storage(5, true),
                storage(6, true),
                storage(7, true),
                storage(8, false),
            ],
        });
        let resolve_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ray_cast resolve"),
            entries: &[
                uniform,
                storage(1, true),
                storage(2, true),
                storage(8, false),
                storage(9, false),
                storage(10, false),
                storage(11, false),
                storage(12, false),
            ],
        });
        let pipeline = |layout: &wgpu::BindGroupLayout, entry: &str| {
            let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pl),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let cast = pipeline(&cast_layout, "cast_rays");
        let resolve = pipeline(&resolve_layout, "resolve_hits");
        RayCastPass {
            cast_layout,
            resolve_layout,
            cast,
            resolve,
        }
    }

    /// Records both passes: every pixel of a `width × height` image of `scene` seen from
    /// `camera` written to the four per-pixel buffers (`color` RGBA8 packed, `depth` camera z
    /// or `f32::MAX`, `face` index + 1 or 0, `uv` native (u, v); index y·W + x, row 0 at the
    /// top), shaded in mode `shading` with the raster pass's key light.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &RayCastScene,
        camera: &Camera,
        shading: Shading,
        width: u32,
        height: u32,
        color: &wgpu::Buffer,
        depth: &wgpu::Buffer,
        face: &wgpu::Buffer,
        uv: &wgpu::Buffer,
    ) {
        let (forward, right, up) = camera.basis();
        // The raster pass's key light (surface.rs): above and to the left of the viewer.
        let light =
            normalize([0, 1, 2].map(|k| 0.55 * up[k] - 0.35 * right[k] - 0.75 * forward[k]));
        let tan_y = (0.5 * camera.fov.to_radians()).tan();
        let f32s = |v: [f64; 3]| v.map(|x| x as f32);
        let params = Params {
            eye: f32s([0, 1, 2].map(|k| camera.eye[k] - scene.origin[k])),
            tol: scene.tolerance as f32,
            forward: f32s(forward),
            width,
            right: f32s(right),
            height,
            up: f32s(up),
            faces: scene.faces as u32,
            light: f32s(light),
            shading: match shading {
                Shading::Lit => 0,
                Shading::Gooch => 1,
                Shading::Toon => 2,
                Shading::FaceIds => 3,
            },
            tan_x: (tan_y * width as f64 / height.max(1) as f64) as f32,
            tan_y: tan_y as f32,
            pad: [0; 2],
        };
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray_cast params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let hits = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray_cast hits"),
            size: (width as u64 * height as u64 * HIT_BYTES).max(HIT_BYTES),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let [t0, t1, t2, t3] = &scene.trim;
        let cast_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ray_cast cast"),
            layout: &self.cast_layout,
            entries: &[
                bind(0, &uniform),
                bind(1, &scene.surf_headers),
                bind(2, &scene.surf_words),
                bind(3, t0),
                bind(4, t1),
                bind(5, t2),
                bind(6, t3),
                bind(7, &scene.seeds),
                bind(8, &hits),
            ],
        });
        let resolve_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ray_cast resolve"),
            layout: &self.resolve_layout,
            entries: &[
                bind(0, &uniform),
                bind(1, &scene.surf_headers),
                bind(2, &scene.surf_words),
                bind(8, &hits),
                bind(9, color),
                bind(10, depth),
                bind(11, face),
                bind(12, uv),
            ],
        });
        let groups = (width.div_ceil(WORKGROUP), height.div_ceil(WORKGROUP));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("ray_cast"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.cast);
        pass.set_bind_group(0, &cast_bind, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        pass.set_pipeline(&self.resolve);
        pass.set_bind_group(0, &resolve_bind, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }

    /// Renders `scene` from `camera` into fresh [`FrameBuffers`] and reads them back; also
    /// returns the wall time from recording to the device reporting the passes done.
    ///
    /// # Errors
    /// [`RenderError::Size`] for an empty image, [`RenderError::Camera`] for a camera that
    /// defines no view, [`RenderError::Gpu`] when wgpu fails.
    pub fn render(
        &self,
        gpu: &GpuContext,
        scene: &RayCastScene,
        camera: &Camera,
        shading: Shading,
        width: u32,
        height: u32,
    ) -> Result<(Frame, Duration), RenderError> {
        crate::check_size(width, height, crate::MAX_SIDE)?;
        camera.check()?;
        let device = &gpu.device;
        let start = Instant::now();
        let scopes = ErrorScopes::push(device);
        let buffers = FrameBuffers::new(device, width, height);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("ray_cast"),
        });
        self.encode(
            device,
            &mut encoder,
            scene,
            camera,
            shading,
            width,
            height,
            &buffers.color,
            &buffers.depth,
            &buffers.face,
            &buffers.uv,
        );
        let index = gpu.queue.submit([encoder.finish()]);
        device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| GpuError::Wgpu(e.to_string()))?;
        scopes.pop_blocking()?;
        let elapsed = start.elapsed();
        let (frame, _) = buffers.read(device, &gpu.queue)?;
        Ok((frame, elapsed))
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
        assert_eq!(struct_size(&module, "SeedBox"), size_of::<super::SeedBox>());
        assert_eq!(struct_size(&module, "CastHit") as u64, super::HIT_BYTES);
        assert_eq!(
            struct_size(&module, "SurfaceHeader"),
            crate::surface_pack::SURFACE_HEADER_BYTES
        );
    }
}
