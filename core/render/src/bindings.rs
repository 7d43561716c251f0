//! What every pass's pipeline setup shares: bind-group layout entries, the layout of a B-Rep
//! part's buffers (bind group 1 of the B-Rep passes, `shaders/brep_bindings.wgsl`), bind
//! groups, uniform buffers, shader modules, compute and render pipelines, compute passes,
//! per-pixel dispatches and one-dimensional dispatches larger than a dispatch row, and the
//! read-back of a buffer.

use crate::RenderError;
use bytemuck::Pod;
use tessd_gpu::GpuError;
use wgpu::util::DeviceExt;

/// A storage-buffer entry at `binding`.
pub fn storage(
    binding: u32,
    read_only: bool,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A uniform-buffer entry at `binding`.
pub fn uniform(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// `entry` (a buffer entry) with a minimum binding size of `bytes`.
pub fn min_size(mut entry: wgpu::BindGroupLayoutEntry, bytes: u64) -> wgpu::BindGroupLayoutEntry {
    if let wgpu::BindingType::Buffer {
        min_binding_size, ..
    } = &mut entry.ty
    {
        *min_binding_size = wgpu::BufferSize::new(bytes);
    }
    entry
}

/// The layout of bind group 1 of the B-Rep passes: the six read-only buffers of
/// [`crate::brep_scene::GpuBrep`] (surface headers and words, trim headers, nodes, curves,
/// lines).
pub fn brep_layout(device: &wgpu::Device, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayout {
    let entries: Vec<_> = (0..6).map(|b| storage(b, true, visibility)).collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("brep buffers"),
        entries: &entries,
    })
}

/// Bind group 0 of the passes that draw the frame's grid: the shading block, the patches,
/// the cells and the grid vertices.
pub(crate) fn grid_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            uniform(0, vf),
            storage(1, true, vf),
            storage(2, true, vf),
            storage(3, true, vf),
        ],
    })
}

/// A bind group of `buffers` at bindings 0, 1, ... of `layout`.
pub fn bind_buffers(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let resources: Vec<_> = buffers.iter().map(|b| b.as_entire_binding()).collect();
    bind_resources(device, label, layout, resources)
}

/// A bind group of `resources` at bindings 0, 1, ... of `layout`.
pub fn bind_resources<'a>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: impl IntoIterator<Item = wgpu::BindingResource<'a>>,
) -> wgpu::BindGroup {
    let entries: Vec<_> = resources
        .into_iter()
        .enumerate()
        .map(|(k, resource)| wgpu::BindGroupEntry {
            binding: k as u32,
            resource,
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A uniform buffer holding `value`.
pub fn uniform_buffer<T: Pod>(device: &wgpu::Device, label: &str, value: &T) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::bytes_of(value),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A shader module of the WGSL `source`.
pub fn shader_module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// A pipeline layout of bind groups `layouts` (group 0, 1, ...).
pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    layouts: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    })
}

/// A compute pipeline of `source`'s `main` with `layouts`.
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
) -> wgpu::ComputePipeline {
    let [pipeline] = compute_pipelines(device, label, source, layouts, ["main"]);
    pipeline
}

/// Compute pipelines of `source`'s entry points `entries` (each labelled with its entry
/// point), sharing one module and the pipeline layout of `layouts`.
pub fn compute_pipelines<const N: usize>(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
    entries: [&str; N],
) -> [wgpu::ComputePipeline; N] {
    let module = shader_module(device, label, source);
    let pipeline_layout = pipeline_layout(device, label, layouts);
    entries.map(|entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(if N == 1 { label } else { entry }),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    })
}

/// The vertex and fragment stages, primitive topology, depth test and colour targets of a
/// [`render_pipeline`].
pub struct RenderStages<'a> {
    /// The shader module of both stages.
    pub module: &'a wgpu::ShaderModule,
    /// The vertex entry point and the vertex buffers it reads.
    pub vertex: (&'a str, &'a [Option<wgpu::VertexBufferLayout<'a>>]),
    /// The fragment entry point.
    pub fragment: &'a str,
    /// What the vertices draw.
    pub topology: wgpu::PrimitiveTopology,
    /// The depth test.
    pub depth: wgpu::DepthStencilState,
    /// The colour targets.
    pub targets: &'a [Option<wgpu::ColorTargetState>],
}

/// A render pipeline of `stages` with bind groups `layouts`, without multisampling and
/// without culling (a pass that draws the frame's grid or CAD and scanned meshes cannot rely
/// on closed, consistently wound triangles).
pub fn render_pipeline(
    device: &wgpu::Device,
    label: &str,
    layouts: &[&wgpu::BindGroupLayout],
    stages: RenderStages,
) -> wgpu::RenderPipeline {
    let pipeline_layout = pipeline_layout(device, label, layouts);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: stages.module,
            entry_point: Some(stages.vertex.0),
            compilation_options: Default::default(),
            buffers: stages.vertex.1,
        },
        primitive: wgpu::PrimitiveState {
            topology: stages.topology,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(stages.depth),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: stages.module,
            entry_point: Some(stages.fragment),
            compilation_options: Default::default(),
            targets: stages.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Records a compute pass of `pipeline` with `groups` bound at 0, 1, ... and one dispatch of
/// `(x, y, z)` workgroups.
pub fn compute_pass(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    groups: &[&wgpu::BindGroup],
    (x, y, z): (u32, u32, u32),
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    for (k, group) in groups.iter().enumerate() {
        pass.set_bind_group(k as u32, *group, &[]);
    }
    pass.dispatch_workgroups(x, y, z);
}

/// Invocations per workgroup along x and y of the per-pixel passes (`@workgroup_size(8, 8)`).
pub const PIXEL_TILE: u32 = 8;

/// The dispatch `(x, y, 1)` in workgroups covering a `width × height` image with one
/// invocation per pixel.
pub fn dispatch_pixels(width: u32, height: u32) -> (u32, u32, u32) {
    (width.div_ceil(PIXEL_TILE), height.div_ceil(PIXEL_TILE), 1)
}

/// Invocations per workgroup of the one-dimensional passes (`@workgroup_size(64)`).
pub const WORKGROUP: u32 = 64;

/// Workgroups along x per dispatch row; larger counts use more rows (y).
pub const GROUPS_X: u32 = 32768;

/// The dispatch `(x, y)` in workgroups covering `n` invocations, and the invocations per row
/// (what a shader multiplies `global_invocation_id.y` by).
pub fn dispatch_1d(n: u32) -> (u32, u32, u32) {
    let groups = n.div_ceil(WORKGROUP).max(1);
    let x = groups.min(GROUPS_X);
    (x, groups.div_ceil(x), x * WORKGROUP)
}

/// Copies `buffer` (made with `COPY_SRC`) to a mappable buffer once the work submitted so far
/// is done, and returns its contents as 32-bit words.
///
/// # Errors
/// [`RenderError::Gpu`] when the device fails or the mapping does.
pub fn read_words(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u32>, RenderError> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("read back"),
    });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    let failed = |e: String| RenderError::Gpu(GpuError::Wgpu(format!("reading back: {e}")));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| failed(e.to_string()))?;
    rx.recv()
        .map_err(|e| failed(e.to_string()))?
        .map_err(|e| failed(e.to_string()))?;
    let words = {
        let view = staging
            .get_mapped_range(..)
            .map_err(|e| failed(e.to_string()))?;
        bytemuck::cast_slice::<u8, u32>(&view).to_vec()
    };
    staging.unmap();
    Ok(words)
}

/// A storage buffer holding `bytes`, refused when over the device's binding limit; an empty
/// array still gets 64 bytes, as a binding needs at least one element.
///
/// # Errors
/// [`RenderError::Gpu`] ([`GpuError::BufferTooLarge`]) naming `label`.
pub fn storage_init(
    device: &wgpu::Device,
    label: &'static str,
    bytes: &[u8],
) -> Result<wgpu::Buffer, RenderError> {
    let limit = device.limits().max_storage_buffer_binding_size;
    if bytes.len() as u64 > limit {
        return Err(GpuError::BufferTooLarge {
            what: label,
            size: bytes.len() as u64,
            limit,
            limit_name: "max_storage_buffer_binding_size",
        }
        .into());
    }
    let pad = [0u8; 64];
    Ok(
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: if bytes.is_empty() { &pad } else { bytes },
            usage: wgpu::BufferUsages::STORAGE,
        }),
    )
}
