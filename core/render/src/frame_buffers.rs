//! The per-pixel storage buffers every pass after the raster pass works on (paper 001,
//! figure 4: the colour, depth and metadata buffers, and the crack flags of §3.2): crack
//! detection and both crack fillings read and write them, the full-scene ray caster writes
//! them directly, and [`FrameBuffers::read`] turns them into a [`Frame`].
//!
//! Layout (one element per pixel, index `y·W + x`, row 0 at the top), shared by every WGSL
//! pass that binds them:
//! - `color: array<u32>`: RGBA8 as `pack4x8unorm` packs it (R in the low byte);
//! - `depth: array<f32>`: distance along the view direction (camera z), [`BACKGROUND_DEPTH`]
//!   for the background;
//! - `face: array<u32>`: face index + 1, 0 for the background;
//! - `uv: array<vec2<f32>>`: the surface's native (u, v);
//! - `flags: array<u32>`: [`CRACK`] set by crack detection, [`FILLED`] by a filling.
//!
//! The raster pass renders into textures (depth testing needs a depth attachment);
//! [`GatherPass`] copies them into the buffers (`shaders/gather_targets.wgsl`). Buffers
//! rather than storage textures: WGSL atomics (object-space filling's atomic min, §3.4.2)
//! exist only on buffers, and a buffer reads back without row padding.

use crate::bindings;
use crate::camera::Camera;
use crate::targets::Targets;
use crate::{Frame, RenderError};
use bytemuck::{Pod, Zeroable};
use std::sync::mpsc;
use tessd_gpu::{ErrorScopes, GpuError};
use wgpu::util::DeviceExt;

/// The depth of a background pixel in the buffers (f32::MAX: finite, so comparisons and
/// differences stay ordinary); [`Frame::depth`] has `f32::INFINITY` there.
pub const BACKGROUND_DEPTH: f32 = f32::MAX;

/// Flag bit: the pixel was detected as a crack (paper 001 §3.2).
pub const CRACK: u32 = 1;
/// Flag bit: a crack pixel that a filling (§3.3 or §3.4) gave a surface.
pub const FILLED: u32 = 2;

/// The per-pixel buffers of one image size (see the module documentation).
pub struct FrameBuffers {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Packed RGBA8.
    pub color: wgpu::Buffer,
    /// Camera-z distance.
    pub depth: wgpu::Buffer,
    /// Face index + 1.
    pub face: wgpu::Buffer,
    /// Native (u, v).
    pub uv: wgpu::Buffer,
    /// Crack flags.
    pub flags: wgpu::Buffer,
}

const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

impl FrameBuffers {
    /// Zeroed buffers for `width × height` pixels.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> FrameBuffers {
        let n = width as u64 * height as u64;
        let make = |label, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (n * bytes).max(4),
                usage: USAGE,
                mapped_at_creation: false,
            })
        };
        FrameBuffers {
            width,
            height,
            color: make("frame color", 4),
            depth: make("frame depth", 4),
            face: make("frame face", 4),
            uv: make("frame uv", 8),
            flags: make("frame flags", 4),
        }
    }

    /// Buffers holding `frame` (infinite depths become [`BACKGROUND_DEPTH`]) and `flags`
    /// (zero when `None`): how tests feed a pass a picture made on the CPU.
    pub fn upload(device: &wgpu::Device, frame: &Frame, flags: Option<&[u32]>) -> FrameBuffers {
        let n = frame.width as usize * frame.height as usize;
        let make = |label, contents: &[u8]| {
            let pad = [0u8; 4];
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if contents.is_empty() { &pad } else { contents },
                usage: USAGE,
            })
        };
        let depth: Vec<f32> = frame
            .depth
            .iter()
            .map(|&d| if d.is_finite() { d } else { BACKGROUND_DEPTH })
            .collect();
        let zero = vec![0u32; n];
        FrameBuffers {
            width: frame.width,
            height: frame.height,
            color: make("frame color", &frame.color),
            depth: make("frame depth", bytemuck::cast_slice(&depth)),
            face: make("frame face", bytemuck::cast_slice(&frame.face_id)),
            uv: make("frame uv", bytemuck::cast_slice(&frame.uv)),
            flags: make("frame flags", bytemuck::cast_slice(flags.unwrap_or(&zero))),
        }
    }

    /// Reads every buffer back: the frame ([`BACKGROUND_DEPTH`] becomes `f32::INFINITY`) and
    /// the flags.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when mapping fails.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(Frame, Vec<u32>), RenderError> {
        let scopes = ErrorScopes::push(device);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read back frame buffers"),
        });
        let sources = [&self.color, &self.depth, &self.face, &self.uv, &self.flags];
        let staging: Vec<wgpu::Buffer> = sources
            .iter()
            .map(|src| {
                let b = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("frame readback"),
                    size: src.size(),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                encoder.copy_buffer_to_buffer(src, 0, &b, 0, src.size());
                b
            })
            .collect();
        queue.submit([encoder.finish()]);
        let (tx, rx) = mpsc::channel();
        for (i, b) in staging.iter().enumerate() {
            let tx = tx.clone();
            b.map_async(wgpu::MapMode::Read, .., move |r| {
                let _ = tx.send((i, r));
            });
        }
        drop(tx);
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Wgpu(e.to_string()))?;
        scopes.pop_blocking()?;
        for (i, r) in rx.iter() {
            r.map_err(|e| GpuError::Wgpu(format!("mapping frame buffer {i}: {e}")))?;
        }
        let n = self.width as usize * self.height as usize;
        let mut words: Vec<Vec<u32>> = Vec::with_capacity(staging.len());
        for b in &staging {
            let view = b
                .get_mapped_range(..)
                .map_err(|e| GpuError::Wgpu(format!("reading back: {e}")))?;
            // Copied word by word: a mapped range need not be 4-byte aligned for bytemuck.
            let w: Vec<u32> = view
                .chunks_exact(4)
                .map(|c| u32::from_ne_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            drop(view);
            b.unmap();
            words.push(w);
        }
        let mut it = words.into_iter();
        let mut next = |len: usize| {
            let mut w = it.next().unwrap_or_default();
            w.truncate(len);
            w
        };
        let color: Vec<u8> = next(n).iter().flat_map(|w| w.to_ne_bytes()).collect();
        let depth = next(n)
            .into_iter()
            .map(|b| {
                let d = f32::from_bits(b);
                if d >= BACKGROUND_DEPTH {
                    f32::INFINITY
                } else {
                    d
                }
            })
            .collect();
        let face_id = next(n);
        let uv = next(2 * n)
            .chunks_exact(2)
            .map(|p| [f32::from_bits(p[0]), f32::from_bits(p[1])])
            .collect();
        let flags = next(n);
        let frame = Frame {
            width: self.width,
            height: self.height,
            color,
            depth,
            face_id,
            uv,
        };
        Ok((frame, flags))
    }
}

/// The uniform block of the gather shader (`Gather`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GatherParams {
    width: u32,
    height: u32,
    near: f32,
    far: f32,
}

/// The WGSL of the gather pass.
pub const GATHER_SHADER: &str = include_str!("../../../shaders/gather_targets.wgsl");

/// Copies the raster targets into [`FrameBuffers`] (see the module documentation).
pub struct GatherPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl GatherPass {
    /// Compiles the shader.
    pub fn new(device: &wgpu::Device) -> GatherPass {
        let c = wgpu::ShaderStages::COMPUTE;
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: c,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let unfiltered = wgpu::TextureSampleType::Float { filterable: false };
        let mut entries = vec![
            bindings::uniform(0, c),
            texture(1, unfiltered),
            texture(2, wgpu::TextureSampleType::Depth),
            texture(3, wgpu::TextureSampleType::Uint),
            texture(4, unfiltered),
        ];
        entries.extend((5..10).map(|binding| bindings::storage(binding, false, c)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gather_targets"),
            entries: &entries,
        });
        let pipeline =
            bindings::compute_pipeline(device, "gather_targets", GATHER_SHADER, &[&layout]);
        GatherPass { layout, pipeline }
    }

    /// Records the copy of `targets` into `out` (same size), depth linearised with
    /// `camera`'s planes.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        camera: &Camera,
        out: &FrameBuffers,
    ) {
        let params = GatherParams {
            width: out.width,
            height: out.height,
            near: camera.near as f32,
            far: camera.far as f32,
        };
        let uniform = bindings::uniform_buffer(device, "gather params", &params);
        let view = |t: &wgpu::Texture, aspect| {
            t.create_view(&wgpu::TextureViewDescriptor {
                aspect,
                ..Default::default()
            })
        };
        let views = [
            view(&targets.color, wgpu::TextureAspect::All),
            view(&targets.depth, wgpu::TextureAspect::DepthOnly),
            view(&targets.face_id, wgpu::TextureAspect::All),
            view(&targets.uv, wgpu::TextureAspect::All),
        ];
        let resources = std::iter::once(uniform.as_entire_binding())
            .chain(views.iter().map(wgpu::BindingResource::TextureView))
            .chain(
                [&out.color, &out.depth, &out.face, &out.uv, &out.flags]
                    .map(|b| b.as_entire_binding()),
            );
        let group = bindings::bind_resources(device, "gather_targets", &self.layout, resources);
        bindings::compute_pass(
            encoder,
            "gather_targets",
            &self.pipeline,
            &[&group],
            bindings::dispatch_pixels(out.width, out.height),
        );
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn gather_shader_validates_with_naga() {
        let module = crate::wgsl_check::validated(super::GATHER_SHADER);
        assert_eq!(
            crate::wgsl_check::struct_size(&module, "Gather"),
            size_of::<super::GatherParams>()
        );
    }
}
