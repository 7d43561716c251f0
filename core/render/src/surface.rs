//! The surface pass: one draw of the scene's triangles into [`Targets`], depth-tested, writing
//! the shaded colour, the face id and the (u, v) of the nearest surface at each pixel centre
//! (`shaders/render_surface.wgsl`). No multisampling: the metadata must be the value of one
//! surface point, the one on the pixel's ray, not a blend.

use crate::camera::Camera;
use crate::scene::Vertex;
use crate::targets::{COLOR_FORMAT, DEPTH_FORMAT, FACE_ID_FORMAT, Targets, UV_FORMAT};
use crate::{RenderSettings, Shading, bindings};
use bytemuck::{Pod, Zeroable};

/// The WGSL of the pass.
pub const SHADER: &str = concat!(
    include_str!("../../../shaders/shading.wgsl"),
    include_str!("../../../shaders/render_surface.wgsl")
);

/// The background: a light grey (RGB 224).
pub const BACKGROUND: [u8; 4] = [224, 224, 224, 255];

/// The uniform block (`Params` in the shader, 96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct Params {
    clip_from_world: [[f32; 4]; 4],
    eye: [f32; 3],
    pub(crate) shading: u32,
    pub(crate) light: [f32; 3],
    edges: u32,
}

impl Params {
    /// The block for `camera` (positions relative to `origin`), a `width × height` image and
    /// `settings`; the key light sits above and to the left of the viewer, a little behind
    /// the camera. Shared by every pass that shades ([`crate::trimmed_surface`] too).
    pub(crate) fn new(
        camera: &Camera,
        origin: [f64; 3],
        width: u32,
        height: u32,
        settings: &RenderSettings,
    ) -> Params {
        let (forward, right, up) = camera.basis();
        let light = crate::camera::normalize(up * 0.55 - right * 0.35 - forward * 0.75);
        Params {
            clip_from_world: camera.clip_from_world(origin.into(), width, height),
            eye: [0, 1, 2].map(|k| (camera.eye[k] - origin[k]) as f32),
            shading: match settings.shading {
                Shading::Lit => 0,
                Shading::Gooch => 1,
                Shading::Toon => 2,
                Shading::FaceIds => 3,
            },
            light: light.as_vec3().to_array(),
            edges: settings.edges as u32 | (settings.mode as u32) << 1,
        }
    }
}

/// The compiled pass: pipeline and bind group layout, made once per device.
pub struct SurfacePass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

impl SurfacePass {
    /// Compiles the shader and builds the pipeline.
    pub fn new(device: &wgpu::Device) -> SurfacePass {
        let module = bindings::shader_module(device, "render_surface.wgsl", SHADER);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("render_surface"),
            entries: &[bindings::min_size(
                bindings::uniform(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                size_of::<Params>() as u64,
            )],
        });
        let attributes = wgpu::vertex_attr_array![
            0 => Float32x3,
            1 => Uint32,
            2 => Float32x3,
            3 => Float32x2,
            4 => Float32x2,
        ];
        // CAD and scanned meshes are not reliably closed or consistently wound: no culling.
        let pipeline = bindings::render_pipeline(
            device,
            "render_surface",
            &[&layout],
            bindings::RenderStages {
                module: &module,
                vertex: (
                    "vs_main",
                    &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &attributes,
                    })],
                ),
                fragment: "fs_main",
                topology: wgpu::PrimitiveTopology::TriangleList,
                depth: depth_state(),
                targets: &color_targets(),
            },
        );
        SurfacePass { layout, pipeline }
    }

    /// Records the pass: clears the targets (background grey, face id 0, (u, v) 0, depth 1)
    /// and draws `vertex_count` vertices of `vertices` (positions relative to `origin`).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        vertices: &wgpu::Buffer,
        vertex_count: u32,
        origin: [f64; 3],
        camera: &Camera,
        settings: &RenderSettings,
    ) {
        let params = Params::new(camera, origin, targets.width, targets.height, settings);
        let uniform = bindings::uniform_buffer(device, "render_surface params", &params);
        let bind = bindings::bind_buffers(device, "render_surface", &self.layout, &[&uniform]);
        let views = TargetViews::new(targets);
        let mut pass = views.clear_pass(encoder, "render_surface");
        if vertex_count > 0 {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.draw(0..vertex_count, 0..1);
        }
    }
}

/// Views of the four targets, for a pass that draws into them.
pub(crate) struct TargetViews {
    color: wgpu::TextureView,
    face_id: wgpu::TextureView,
    uv: wgpu::TextureView,
    depth: wgpu::TextureView,
}

impl TargetViews {
    /// Views of `targets`.
    pub(crate) fn new(targets: &Targets) -> TargetViews {
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        TargetViews {
            color: view(&targets.color),
            face_id: view(&targets.face_id),
            uv: view(&targets.uv),
            depth: view(&targets.depth),
        }
    }

    /// A render pass that clears the targets (background grey, face id 0, (u, v) 0, depth 1).
    pub(crate) fn clear_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
    ) -> wgpu::RenderPass<'e> {
        let bg = BACKGROUND.map(|c| c as f64 / 255.0);
        let attach = |view, clear| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[
                attach(
                    &self.color,
                    wgpu::Color {
                        r: bg[0],
                        g: bg[1],
                        b: bg[2],
                        a: 1.0,
                    },
                ),
                attach(&self.face_id, wgpu::Color::TRANSPARENT),
                attach(&self.uv, wgpu::Color::TRANSPARENT),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

/// The colour, face-id and (u, v) targets of the surface passes, unblended.
pub(crate) fn color_targets() -> [Option<wgpu::ColorTargetState>; 3] {
    [COLOR_FORMAT, FACE_ID_FORMAT, UV_FORMAT].map(|format| {
        Some(wgpu::ColorTargetState {
            format,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })
    })
}

/// The depth state of the surface passes: test `Less`, write.
pub(crate) fn depth_state() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

#[cfg(test)]
mod tests {
    use crate::wgsl_check::{struct_size, validated};

    /// The WGSL parses and validates without a device, and its `Params` block is 96 bytes.
    #[test]
    fn shader_validates_with_naga() {
        let module = validated(super::SHADER);
        assert_eq!(struct_size(&module, "Params"), 96);
    }

    #[test]
    fn params_match_the_shader_block() {
        assert_eq!(size_of::<super::Params>(), 96);
        assert_eq!(size_of::<crate::scene::Vertex>(), 44);
    }
}
