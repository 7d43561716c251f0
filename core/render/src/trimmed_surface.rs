//! Step 1 of paper 001 (§3.1): the initial rendering of a B-Rep part from the frame's
//! basis-surface tessellation ([`crate::patch_tessellation`]) with direct GPU trimming
//! (paper 000 §5: each fragment walks the face's trim quadtree from the node triangle
//! classification handed down, §6, stopping at a node under the pixel's footprint, §5.3, and
//! off-face fragments are discarded), into the same targets as the mesh pass: colour, depth
//! and the metadata buffer (face id, (u, v)) (`shaders/trimmed_surface.wgsl`).
//!
//! Back faces are kept (no culling): a tessellation triangle can face away while part of the
//! surface it stands for faces the eye (paper 001 figure 11), and the fragment's normal comes
//! from the surface, not the triangle.

use crate::camera::Camera;
use crate::patch_tessellation::GpuTessellation;
use crate::surface::{Params, TargetViews, color_targets, depth_state};
use crate::targets::Targets;
use crate::{RenderSettings, bindings};

/// The WGSL of the pass.
pub const SHADER: &str =
    patch_grid_shader!("shading.wgsl", "grid_raster.wgsl", "trimmed_surface.wgsl");

/// The compiled pass.
pub struct TrimmedSurfacePass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

impl TrimmedSurfacePass {
    /// Compiles the shader; `brep` is the layout of bind group 1.
    pub fn new(device: &wgpu::Device, brep: &wgpu::BindGroupLayout) -> TrimmedSurfacePass {
        let module = bindings::shader_module(device, "trimmed_surface.wgsl", SHADER);
        let layout = bindings::grid_layout(device, "trimmed_surface");
        let pipeline = bindings::render_pipeline(
            device,
            "trimmed_surface",
            &[&layout, brep],
            bindings::RenderStages {
                module: &module,
                vertex: ("vs_main", &[]),
                fragment: "fs_main",
                topology: wgpu::PrimitiveTopology::TriangleList,
                depth: depth_state(),
                targets: &color_targets(),
            },
        );
        TrimmedSurfacePass { layout, pipeline }
    }

    /// The bind group 0 of a frame: its shading block and its tessellation.
    pub(crate) fn frame_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        tess: &GpuTessellation,
        camera: &Camera,
        origin: [f64; 3],
        targets: &Targets,
        settings: &RenderSettings,
    ) -> wgpu::BindGroup {
        let params = Params::new(camera, origin, targets.width, targets.height, settings);
        let uniform = bindings::uniform_buffer(device, "trimmed_surface params", &params);
        bindings::bind_buffers(
            device,
            "trimmed_surface",
            layout,
            &[&uniform, &tess.patches, &tess.cells, &tess.grid],
        )
    }

    /// Records the pass: clears the targets and draws every cell of `tess`.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        brep_group: &wgpu::BindGroup,
        tess: &GpuTessellation,
        origin: [f64; 3],
        camera: &Camera,
        settings: &RenderSettings,
    ) {
        let group = Self::frame_group(
            device,
            &self.layout,
            tess,
            camera,
            origin,
            targets,
            settings,
        );
        let views = TargetViews::new(targets);
        let mut pass = views.clear_pass(encoder, "trimmed_surface");
        if tess.cell_count > 0 {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.set_bind_group(1, brep_group, &[]);
            pass.draw(0..tess.cell_count * 6, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    /// The WGSL parses and validates without a device.
    #[test]
    fn shader_validates_with_naga() {
        crate::wgsl_check::validated(super::SHADER);
    }
}
