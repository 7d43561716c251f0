//! The GPU trim walk (paper 000 §5: descent of the trim quadtree; §5.1: the implicit test of a
//! quadratic Bézier curve; §5.2–5.3: a two-curve leaf's separating line) as a compute pass
//! over a batch of query points (`shaders/trim_walk.wgsl`).
//!
//! The shader is [`MultiPack::walk`] transcribed, f32 operation for f32 operation and branch
//! for branch, reading the four flat buffers of a [`MultiPack`] from storage buffers. Its
//! answers equal the CPU reference's except, possibly, at points within an ulp of a
//! separating line or a curve, where a driver may fuse a multiply-add that the CPU rounds
//! twice. This pass checks the shader before the surface pass uses the same walk to discard
//! fragments.

use std::time::{Duration, Instant};

use tessd_gpu::{ErrorScopes, GpuContext, GpuError};
use tessd_trim::multi_pack::MultiPack;
use wgpu::util::DeviceExt;

use crate::RenderError;
use crate::bindings::{self, GROUPS_X, dispatch_1d, min_size};

/// The WGSL of the pass.
pub const SHADER: &str = concat!(
    include_str!("../../../shaders/trim_quadtree.wgsl"),
    include_str!("../../../shaders/trim_walk.wgsl")
);

/// Invocations per workgroup (`@workgroup_size` in the shader).
pub const WORKGROUP: u32 = bindings::WORKGROUP;

/// One query as the shader reads it (`Query`, 12 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    face: u32,
    s: f32,
    t: f32,
}

/// Wall times of one [`TrimWalk::run_timed`], measured on the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WalkTimings {
    /// Creating and filling the six buffers.
    pub upload: Duration,
    /// From recording the dispatch until the device reports it done.
    pub dispatch: Duration,
    /// Copying the answers out and mapping them.
    pub readback: Duration,
}

/// The compiled pass: pipeline and bind group layout, made once per device.
pub struct TrimWalk {
    device: wgpu::Device,
    queue: wgpu::Queue,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

/// A bind group layout entry for storage buffer `binding` of at least `min` bytes.
fn storage(binding: u32, read_only: bool, min: u64) -> wgpu::BindGroupLayoutEntry {
    min_size(
        bindings::storage(binding, read_only, wgpu::ShaderStages::COMPUTE),
        min,
    )
}

fn gpu_error(e: impl std::fmt::Display) -> RenderError {
    RenderError::Gpu(GpuError::Wgpu(e.to_string()))
}

impl TrimWalk {
    /// Compiles the shader and builds the pipeline on `gpu`'s device.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when the shader or the pipeline fails to build.
    pub fn new(gpu: &GpuContext) -> Result<TrimWalk, RenderError> {
        let device = &gpu.device;
        let scopes = ErrorScopes::push(device);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("trim_walk"),
            entries: &[
                storage(0, true, tessd_trim::multi_pack::FACE_HEADER_BYTES as u64),
                storage(1, true, 4),
                storage(2, true, 4),
                storage(3, true, 4),
                storage(4, true, size_of::<Query>() as u64),
                storage(5, false, 4),
            ],
        });
        let pipeline = bindings::compute_pipeline(device, "trim_walk", SHADER, &[&layout]);
        scopes.pop_blocking()?;
        Ok(TrimWalk {
            device: device.clone(),
            queue: gpu.queue.clone(),
            layout,
            pipeline,
        })
    }

    /// Whether each query point `(face, s, t)` — patch coordinates of face `face` of `pack` —
    /// is on its face: [`MultiPack::walk`] on the device. A face index beyond the pack
    /// answers `false`.
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when a buffer is over the device's limits or wgpu fails.
    pub fn run(
        &self,
        pack: &MultiPack,
        queries: &[(u32, f32, f32)],
    ) -> Result<Vec<bool>, RenderError> {
        self.run_timed(pack, queries).map(|(on, _)| on)
    }

    /// [`run`](Self::run), with the wall times of its phases.
    ///
    /// # Errors
    /// As [`run`](Self::run).
    pub fn run_timed(
        &self,
        pack: &MultiPack,
        queries: &[(u32, f32, f32)],
    ) -> Result<(Vec<bool>, WalkTimings), RenderError> {
        if queries.is_empty() {
            return Ok((Vec::new(), WalkTimings::default()));
        }
        let device = &self.device;
        let n = queries.len();
        let rows = (n as u64).div_ceil(u64::from(WORKGROUP) * u64::from(GROUPS_X));
        let limits = device.limits();
        if rows > u64::from(limits.max_compute_workgroups_per_dimension)
            || u32::try_from(n).is_err()
        {
            return Err(RenderError::Size(format!(
                "{n} trim-walk queries are more than one dispatch takes"
            )));
        }
        let start = Instant::now();
        let scopes = ErrorScopes::push(device);
        let queries: Vec<Query> = queries
            .iter()
            .map(|&(face, s, t)| Query { face, s, t })
            .collect();
        let pad = [0u8; tessd_trim::multi_pack::FACE_HEADER_BYTES];
        let buffer = |label: &'static str, bytes: &[u8], usage: wgpu::BufferUsages| {
            let limit = limits.max_storage_buffer_binding_size;
            if bytes.len() as u64 > limit {
                return Err(RenderError::Gpu(GpuError::BufferTooLarge {
                    what: label,
                    size: bytes.len() as u64,
                    limit,
                    limit_name: "max_storage_buffer_binding_size",
                }));
            }
            // An empty array still needs a binding of at least one element.
            let contents = if bytes.is_empty() { &pad[..] } else { bytes };
            Ok(
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage,
                }),
            )
        };
        let read = wgpu::BufferUsages::STORAGE;
        let buffers = [
            buffer("trim headers", pack.header_bytes(), read)?,
            buffer("trim nodes", bytemuck::cast_slice(&pack.nodes), read)?,
            buffer("trim curves", bytemuck::cast_slice(&pack.curves), read)?,
            buffer("trim lines", bytemuck::cast_slice(&pack.lines), read)?,
            buffer("trim queries", bytemuck::cast_slice(&queries), read)?,
        ];
        let result_bytes = 4 * n as u64;
        let results = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("trim results"),
            size: result_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let [headers, nodes, curves, lines, query_buffer] = &buffers;
        let bind = bindings::bind_buffers(
            device,
            "trim_walk",
            &self.layout,
            &[headers, nodes, curves, lines, query_buffer, &results],
        );
        let upload = start.elapsed();

        let start = Instant::now();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("trim_walk"),
        });
        let (x, y, _) = dispatch_1d(n as u32);
        bindings::compute_pass(
            &mut encoder,
            "trim_walk",
            &self.pipeline,
            &[&bind],
            (x, y, 1),
        );
        let index = self.queue.submit([encoder.finish()]);
        device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(gpu_error)?;
        let dispatch = start.elapsed();

        let start = Instant::now();
        let words = bindings::read_words(device, &self.queue, &results)?;
        scopes.pop_blocking()?;
        let on = words.iter().map(|&w| w != 0).collect();
        let readback = start.elapsed();
        Ok((
            on,
            WalkTimings {
                upload,
                dispatch,
                readback,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use crate::wgsl_check::{struct_size, validated};

    /// The WGSL parses and validates without a device, and its `TrimHeader` and `Query`
    /// structs have the sizes of the Rust ones (40 and 12 bytes).
    #[test]
    fn shader_validates_with_naga() {
        let module = validated(super::SHADER);
        assert_eq!(
            struct_size(&module, "TrimHeader"),
            tessd_trim::multi_pack::FACE_HEADER_BYTES
        );
        assert_eq!(struct_size(&module, "Query"), size_of::<super::Query>());
        assert_eq!(size_of::<super::Query>(), 12);
    }
}
