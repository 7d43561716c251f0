//! Image-space crack filling (paper 001 §3.3) as a compute pass over [`FrameBuffers`]
//! (`shaders/image_fill.wgsl`), run after [`CrackDetectPass`](crate::crack_detect::CrackDetectPass).
//!
//! For each pixel p flagged [`CRACK`](crate::frame_buffers::CRACK), the usable neighbours are
//! those of its 8-pixel ring that are inside the image, covered (face id ≠ 0) and not flagged
//! CRACK themselves. The paper's patch B_p is the one covering the most of them; here one face
//! is one patch, so B_p is a face id. Ties (which the paper leaves open) are broken
//! deterministically: the nearest mean depth of the face's neighbours, then the smallest id.
//! p then receives
//! - the average colour of B_p's neighbours (the paper's rule),
//! - their mean depth, B_p's id, and the (u, v) of the nearest of them (first in ring order
//!   on equal depths), so later passes see a consistent surface sample,
//! - the [`FILLED`](crate::frame_buffers::FILLED) flag.
//!
//! A crack pixel without a usable neighbour is left unchanged (and not FILLED). Only non-crack
//! pixels are read and only crack pixels written, so one dispatch has no read/write hazard
//! between invocations; in particular a crack pixel is never filled from another crack pixel
//! filled in the same pass.

use crate::frame_buffers::FrameBuffers;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// The uniform block of the fill shader (`ImageFill`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ImageFillParams {
    width: u32,
    height: u32,
    _pad0: u32,
    _pad1: u32,
}

/// The WGSL of the image-space fill pass.
pub const IMAGE_FILL_SHADER: &str = include_str!("../../../shaders/image_fill.wgsl");

/// The image-space crack filling pass of §3.3 (see the module documentation).
pub struct ImageFillPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl ImageFillPass {
    /// Compiles the shader.
    pub fn new(device: &wgpu::Device) -> ImageFillPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("image_fill.wgsl"),
            source: wgpu::ShaderSource::Wgsl(IMAGE_FILL_SHADER.into()),
        });
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }];
        entries.extend((1..6).map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("image_fill"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("image_fill"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("image_fill"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        ImageFillPass { layout, pipeline }
    }

    /// Records the filling of every crack pixel of `buffers` (colour, depth, face, (u, v) and
    /// the FILLED bit; see the module documentation).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &FrameBuffers,
    ) {
        let params = ImageFillParams {
            width: buffers.width,
            height: buffers.height,
            _pad0: 0,
            _pad1: 0,
        };
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("image_fill params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }];
        for (k, b) in [
            &buffers.color,
            &buffers.depth,
            &buffers.face,
            &buffers.uv,
            &buffers.flags,
        ]
        .into_iter()
        .enumerate()
        {
            entries.push(wgpu::BindGroupEntry {
                binding: 1 + k as u32,
                resource: b.as_entire_binding(),
            });
        }
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("image_fill"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("image_fill"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(buffers.width.div_ceil(8), buffers.height.div_ceil(8), 1);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn image_fill_shader_validates_with_naga() {
        let module = crate::wgsl_check::validated(super::IMAGE_FILL_SHADER);
        assert_eq!(
            crate::wgsl_check::struct_size(&module, "ImageFill"),
            size_of::<super::ImageFillParams>()
        );
    }
}
