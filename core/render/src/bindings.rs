//! What every pass's pipeline setup shares: bind-group layout entries, the layout of a B-Rep
//! part's buffers (bind group 1 of the B-Rep passes, `shaders/brep_bindings.wgsl`), uniform
//! buffers, and one-dimensional dispatches larger than a dispatch row.

use bytemuck::Pod;
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

/// A bind group of `buffers` at bindings 0, 1, ... of `layout`.
pub fn bind_buffers(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .enumerate()
        .map(|(k, b)| wgpu::BindGroupEntry {
            binding: k as u32,
            resource: b.as_entire_binding(),
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

/// A compute pipeline of `source`'s `main` with `layouts`.
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
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
