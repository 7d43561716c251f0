//! Object-space crack filling (paper 001 §3.4): step 3, the depth mask
//! (`shaders/object_fill_mask.wgsl`); step 4, ray casting of the neighbouring faces at the
//! crack pixels from the fragments of a filled and a wireframe draw of the frame's grid,
//! with patch mailboxing (`shaders/object_fill.wgsl`); step 5, the composite
//! (`shaders/object_fill_composite.wgsl`). The shaders' headers say how each step departs
//! from the paper and why — chiefly that WGSL's 32-bit atomics leave no room for the paper's
//! depth-and-colour word: the atomic min runs on a depth-and-face key, and a second pass over
//! the winning faces' fragments writes the winners' (u, v), depth and colour.

use crate::camera::Vec3;
use crate::frame_buffers::FrameBuffers;
use crate::newton::NEWTON_TOLERANCE;
use crate::patch_tessellation::GpuTessellation;
use crate::step_timing::{StepTimings, step};
use crate::surface::Params;
use crate::targets::DEPTH_FORMAT;
use crate::{Camera, RenderError, RenderSettings, bindings};
use bytemuck::{Pod, Zeroable};
use tessd_gpu::GpuContext;

/// The WGSL of step 3.
pub const MASK_SHADER: &str = include_str!("../../../shaders/object_fill_mask.wgsl");

/// The WGSL of step 4.
pub const FILL_SHADER: &str = patch_grid_shader!(
    "shading.wgsl",
    "grid_raster.wgsl",
    "ray_newton.wgsl",
    "object_fill.wgsl",
);

/// The WGSL of step 5.
pub const COMPOSITE_SHADER: &str = include_str!("../../../shaders/object_fill_composite.wgsl");

/// `Mask` of step 3 and `Composite` of step 5 (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Frame16 {
    width: u32,
    height: u32,
    near: f32,
    far: f32,
}

/// `Fill` of step 4 (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FillParams {
    eye: [f32; 3],
    width: u32,
    forward: [f32; 3],
    height: u32,
    right: [f32; 3],
    tolerance: f32,
    up: [f32; 3],
    phase: u32,
}

/// The compiled steps 3–5.
pub struct ObjectFillPass {
    mask_layout: wgpu::BindGroupLayout,
    mask: wgpu::RenderPipeline,
    grid_layout: wgpu::BindGroupLayout,
    fill_layout: wgpu::BindGroupLayout,
    /// The filled and the wireframe draw (one fragment shader, the pass chosen by a uniform).
    fill: [wgpu::RenderPipeline; 2],
    composite_layout: wgpu::BindGroupLayout,
    composite: wgpu::ComputePipeline,
}

/// A depth-only render pipeline.
#[allow(clippy::too_many_arguments)]
fn depth_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layouts: &[&wgpu::BindGroupLayout],
    vertex: &str,
    fragment: &str,
    topology: wgpu::PrimitiveTopology,
    depth: (bool, wgpu::CompareFunction),
) -> wgpu::RenderPipeline {
    bindings::render_pipeline(
        device,
        label,
        layouts,
        bindings::RenderStages {
            module,
            vertex: (vertex, &[]),
            fragment,
            topology,
            depth: wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(depth.0),
                depth_compare: Some(depth.1),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            },
            targets: &[],
        },
    )
}

impl ObjectFillPass {
    /// Compiles the three steps; `brep` is the layout of bind group 1.
    pub fn new(device: &wgpu::Device, brep: &wgpu::BindGroupLayout) -> ObjectFillPass {
        let f = wgpu::ShaderStages::FRAGMENT;
        let module = |label, source: &str| bindings::shader_module(device, label, source);
        let mask_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("object_fill_mask"),
            entries: &[
                bindings::uniform(0, f),
                bindings::storage(1, true, f),
                bindings::storage(2, true, f),
                bindings::storage(3, false, f),
                bindings::storage(4, false, f),
                bindings::storage(5, false, f),
            ],
        });
        let mask_module = module("object_fill_mask.wgsl", MASK_SHADER);
        let mask = depth_pipeline(
            device,
            "object_fill_mask",
            &mask_module,
            &[&mask_layout],
            "vs_main",
            "fs_main",
            wgpu::PrimitiveTopology::TriangleList,
            (true, wgpu::CompareFunction::Always),
        );
        let grid_layout = bindings::grid_layout(device, "object_fill grid");
        let fill_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("object_fill"),
            entries: &[
                bindings::uniform(0, f),
                bindings::storage(1, true, f),
                bindings::storage(2, false, f),
                bindings::storage(3, false, f),
                bindings::storage(4, false, f),
                bindings::storage(5, false, f),
            ],
        });
        let early = device
            .features()
            .contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST);
        let fill_source = if early {
            FILL_SHADER.replace(
                "\n@fragment\nfn fs_fill",
                "\n@fragment @early_depth_test(force)\nfn fs_fill",
            )
        } else {
            FILL_SHADER.to_string()
        };
        let fill_module = module("object_fill.wgsl", &fill_source);
        let test = (false, wgpu::CompareFunction::LessEqual);
        let tri = wgpu::PrimitiveTopology::TriangleList;
        let line = wgpu::PrimitiveTopology::LineList;
        let layouts = [&grid_layout, brep, &fill_layout];
        let make = |vs, topology| {
            depth_pipeline(
                device,
                vs,
                &fill_module,
                &layouts,
                vs,
                "fs_fill",
                topology,
                test,
            )
        };
        let fill = [make("vs_filled", tri), make("vs_lines", line)];
        let c = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![bindings::uniform(0, c)];
        entries.extend((1..6).map(|b| bindings::storage(b, false, c)));
        entries.extend((6..8).map(|b| bindings::storage(b, true, c)));
        let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("object_fill_composite"),
            entries: &entries,
        });
        let composite = bindings::compute_pipeline(
            device,
            "object_fill_composite",
            COMPOSITE_SHADER,
            &[&composite_layout],
        );
        ObjectFillPass {
            mask_layout,
            mask,
            grid_layout,
            fill_layout,
            fill,
            composite_layout,
            composite,
        }
    }

    /// Runs steps 3–5 on `buffers` (after crack detection), adding their times to `t`;
    /// `scale` is the part's box diagonal (Newton's tolerance is relative to it).
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when wgpu fails.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        gpu: &GpuContext,
        brep_group: &wgpu::BindGroup,
        tess: &GpuTessellation,
        buffers: &FrameBuffers,
        origin: [f64; 3],
        scale: f64,
        camera: &Camera,
        settings: &RenderSettings,
        t: &mut StepTimings,
    ) -> Result<(), RenderError> {
        let device = &gpu.device;
        let (width, height) = (buffers.width, buffers.height);
        let n = (width as u64 * height as u64).max(1);
        let scratch = |label, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: n * bytes,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let zmin = scratch("fill zmin", 4);
        let mailbox = scratch("fill mailbox", 4);
        let winner_face = scratch("fill winner face", 4);
        let winner = scratch("fill winner", 16);
        let mask_texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth mask"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let mask_view = mask_texture.create_view(&Default::default());
        let depth_pass = |e: &'_ mut wgpu::CommandEncoder, label, clear: bool| {
            e.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &mask_view,
                    depth_ops: Some(wgpu::Operations {
                        load: if clear {
                            wgpu::LoadOp::Clear(0.0)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime()
        };

        // Step 3.
        let frame = Frame16 {
            width,
            height,
            near: camera.near as f32,
            far: camera.far as f32,
        };
        let mask_uniform = bindings::uniform_buffer(device, "mask params", &frame);
        let mask_group = bindings::bind_buffers(
            device,
            "object_fill_mask",
            &self.mask_layout,
            &[
                &mask_uniform,
                &buffers.depth,
                &buffers.flags,
                &zmin,
                &mailbox,
                &winner_face,
            ],
        );
        step(gpu, &mut t.depth_mask, |e| {
            let mut pass = depth_pass(e, "object_fill_mask", true);
            pass.set_pipeline(&self.mask);
            pass.set_bind_group(0, &mask_group, &[]);
            pass.draw(0..3, 0..1);
        })?;

        // Step 4: pass A (filled, wireframe), then pass B (filled, wireframe).
        let params = Params::new(camera, origin, width, height, settings);
        let params_uniform = bindings::uniform_buffer(device, "object_fill params", &params);
        let grid_group = bindings::bind_buffers(
            device,
            "object_fill grid",
            &self.grid_layout,
            &[&params_uniform, &tess.patches, &tess.cells, &tess.grid],
        );
        let (forward, right, up) = camera.basis();
        let ty = (0.5 * camera.fov.to_radians()).tan();
        let tx = ty * width as f64 / height.max(1) as f64;
        let f32s = |v: Vec3, s: f64| (v * s).as_vec3().to_array();
        let fill = FillParams {
            eye: [0, 1, 2].map(|k| (camera.eye[k] - origin[k]) as f32),
            width,
            forward: f32s(forward, 1.0),
            height,
            right: f32s(right, tx),
            tolerance: (NEWTON_TOLERANCE * scale) as f32,
            up: f32s(up, ty),
            phase: 0,
        };
        let fill_groups = [0, 1].map(|phase| {
            let uniform =
                bindings::uniform_buffer(device, "fill params", &FillParams { phase, ..fill });
            bindings::bind_buffers(
                device,
                "object_fill",
                &self.fill_layout,
                &[
                    &uniform,
                    &buffers.flags,
                    &zmin,
                    &mailbox,
                    &winner_face,
                    &winner,
                ],
            )
        });
        let cells = tess.cell_count;
        step(gpu, &mut t.object_fill, |e| {
            for (group, label) in fill_groups.iter().zip(["object_fill A", "object_fill B"]) {
                let mut pass = depth_pass(e, label, false);
                pass.set_bind_group(0, &grid_group, &[]);
                pass.set_bind_group(1, brep_group, &[]);
                pass.set_bind_group(2, group, &[]);
                if cells > 0 {
                    pass.set_pipeline(&self.fill[0]);
                    pass.draw(0..cells * 6, 0..1);
                    pass.set_pipeline(&self.fill[1]);
                    pass.draw(0..cells * 10, 0..1);
                }
            }
        })?;

        // Step 5.
        let composite_uniform = bindings::uniform_buffer(device, "composite params", &frame);
        let composite_group = bindings::bind_buffers(
            device,
            "object_fill_composite",
            &self.composite_layout,
            &[
                &composite_uniform,
                &buffers.color,
                &buffers.depth,
                &buffers.face,
                &buffers.uv,
                &buffers.flags,
                &winner_face,
                &winner,
            ],
        );
        step(gpu, &mut t.composite, |e| {
            bindings::compute_pass(
                e,
                "object_fill_composite",
                &self.composite,
                &[&composite_group],
                bindings::dispatch_pixels(width, height),
            );
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::wgsl_check::{struct_size, validated};

    #[test]
    fn shaders_validate_with_naga() {
        let m = validated(super::MASK_SHADER);
        assert_eq!(struct_size(&m, "Mask"), size_of::<super::Frame16>());
        let m = validated(super::FILL_SHADER);
        assert_eq!(struct_size(&m, "Fill"), size_of::<super::FillParams>());
        let m = validated(super::COMPOSITE_SHADER);
        assert_eq!(struct_size(&m, "Composite"), size_of::<super::Frame16>());
    }
}
