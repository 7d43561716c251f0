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

use crate::bindings::{self, storage, uniform};
use crate::frame_buffers::FrameBuffers;
use bytemuck::{Pod, Zeroable};

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
        let c = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![uniform(0, c)];
        entries.extend((1..6).map(|binding| storage(binding, false, c)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("image_fill"),
            entries: &entries,
        });
        let pipeline =
            bindings::compute_pipeline(device, "image_fill", IMAGE_FILL_SHADER, &[&layout]);
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
        let uniform = bindings::uniform_buffer(device, "image_fill params", &params);
        let group = bindings::bind_buffers(
            device,
            "image_fill",
            &self.layout,
            &[
                &uniform,
                &buffers.color,
                &buffers.depth,
                &buffers.face,
                &buffers.uv,
                &buffers.flags,
            ],
        );
        bindings::compute_pass(
            encoder,
            "image_fill",
            &self.pipeline,
            &[&group],
            bindings::dispatch_pixels(buffers.width, buffers.height),
        );
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
