//! GPU apply phase for subdivision stencil tables (paper 002, section 6: one new vertex per
//! thread from a fixed list of old vertices and weights).
//!
//! The topology phase ([`tessd_subdiv::StencilTable`]) runs once per cage topology on the CPU;
//! this crate uploads the resulting chain of tables once ([`GpuStencils::upload`]) and then
//! applies it to any number of vertex-data frames ([`GpuStencils::apply`]), every level in one
//! command submission, reading back only the last level. It runs on wgpu's Vulkan backend, so
//! it also runs without a GPU on Mesa's software Vulkan driver (lavapipe), which is what CI
//! tests against.
//!
//! The kernel (`shaders/stencil_apply.wgsl`) sums each component in f32, in row order, starting
//! from zero: the same order as [`StencilTable::apply`], so the GPU and CPU results agree to
//! rounding (FMA contraction aside).
//!
//! Every input is checked before it reaches the device, and wgpu's own validation and
//! out-of-memory errors are caught with error scopes, so bad input gives a [`GpuError`], never a
//! panic.

#![warn(missing_docs)]

pub mod context;

pub use context::{ErrorScopes, GpuContext, describe};

use std::sync::mpsc;
use std::time::{Duration, Instant};

use tessd_subdiv::StencilTable;
use wgpu::util::DeviceExt;

/// The WGSL kernel: one invocation per refined row.
const SHADER: &str = include_str!("../../../shaders/stencil_apply.wgsl");

/// Invocations per workgroup; must match `@workgroup_size` in the shader.
const WORKGROUP: u32 = 64;

/// Bytes of the per-level uniform (`Params` in the shader).
const PARAMS_SIZE: u64 = 16;

/// How [`GpuError::NoAdapter`]'s message begins, for callers that only see it as text (a
/// protocol error frame).
pub const NO_ADAPTER: &str = "no GPU adapter found";

/// The command that installs the Vulkan loader and Mesa's software Vulkan driver (lavapipe) on
/// Debian and Ubuntu, as [`GpuError::NoAdapter`] names it.
pub const SOFTWARE_DRIVER_INSTALL: &str = "apt-get install mesa-vulkan-drivers libvulkan1";

/// Why a GPU operation failed.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter, not even a software one.
    #[error(
        "{prefix} ({0}); for the software Vulkan driver (lavapipe) install mesa-vulkan-drivers \
         and libvulkan1 ({install})",
        prefix = NO_ADAPTER,
        install = SOFTWARE_DRIVER_INSTALL
    )]
    NoAdapter(String),
    /// The adapter refused to create a device with the limits asked for.
    #[error("GPU device request failed on {adapter}: {source}")]
    DeviceRequest {
        /// The adapter, as [`GpuStencils::adapter_info`] writes it.
        adapter: String,
        /// wgpu's error.
        #[source]
        source: wgpu::RequestDeviceError,
    },
    /// A buffer would exceed what the adapter can allocate or bind.
    #[error("{what} needs {size} bytes, over the adapter's limit of {limit} bytes ({limit_name})")]
    BufferTooLarge {
        /// Which buffer.
        what: &'static str,
        /// Bytes it needs.
        size: u64,
        /// The adapter's limit.
        limit: u64,
        /// Which limit (`max_buffer_size` or `max_storage_buffer_binding_size`).
        limit_name: &'static str,
    },
    /// A level has more rows than one dispatch grid can cover.
    #[error("level {level} has {rows} rows, more than a dispatch grid can cover ({max} rows)")]
    TooManyRows {
        /// Level (0 = first table of the chain).
        level: usize,
        /// Its rows.
        rows: usize,
        /// Most rows a 2-D grid of the adapter can cover.
        max: u64,
    },
    /// `src` does not hold `source_count × stride` floats for the chain's first table.
    #[error("source data has {got} floats, expected {expected} ({rows} rows × stride {stride})")]
    SrcLength {
        /// Floats given.
        got: usize,
        /// Floats expected.
        expected: usize,
        /// Rows of the coarse level.
        rows: usize,
        /// Floats per row.
        stride: usize,
    },
    /// A table is malformed, or a table's sources do not match the previous level's rows.
    #[error("stencil table {level}: {reason}")]
    InvalidTable {
        /// Level (0 = first table of the chain).
        level: usize,
        /// What is wrong.
        reason: String,
    },
    /// The tables were uploaded by another [`GpuStencils`] (another device).
    #[error("the tables were uploaded to another GPU device")]
    ForeignTables,
    /// wgpu reported a validation or out-of-memory error, or mapping the result failed.
    #[error("GPU error: {0}")]
    Wgpu(String),
}

/// A device ready to apply stencil tables: wgpu instance, adapter, device, queue and the
/// compiled kernel. Create it once and reuse it: creating a device costs milliseconds (and far
/// more on lavapipe, which compiles the kernel with LLVM).
pub struct GpuStencils {
    adapter_info: wgpu::AdapterInfo,
    device: wgpu::Device,
    queue: wgpu::Queue,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    limits: wgpu::Limits,
}

/// A chain of stencil tables on the device, made by [`GpuStencils::upload`]. Tables depend only
/// on the cage's topology, so an animation uploads them once and applies them to every frame.
pub struct GpuTables {
    device: wgpu::Device,
    levels: Vec<GpuLevel>,
    source_count: u32,
}

/// One uploaded level.
struct GpuLevel {
    rows: u32,
    offsets: wgpu::Buffer,
    sources: wgpu::Buffer,
    weights: wgpu::Buffer,
}

impl GpuTables {
    /// Levels in the chain.
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// Rows the chain's first table reads (the cage's vertices).
    pub fn source_count(&self) -> usize {
        self.source_count as usize
    }

    /// Rows the chain's last level makes (`source_count` when the chain is empty).
    pub fn output_rows(&self) -> usize {
        self.levels
            .last()
            .map_or(self.source_count as usize, |l| l.rows as usize)
    }
}

impl GpuStencils {
    /// Opens a device: the Vulkan backend (which covers lavapipe, the software driver) plus
    /// whatever other backend this build has, preferring a real GPU but accepting a fallback
    /// (CPU) adapter ([`GpuContext::open`], shared with the renderer). Limits are wgpu's
    /// defaults except the buffer sizes, raised to the adapter's so large meshes fit.
    pub fn new() -> Result<Self, GpuError> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<Self, GpuError> {
        let GpuContext {
            adapter_info,
            device,
            queue,
        } = GpuContext::open_async("tessd-gpu").await?;
        let limits = device.limits();

        let scopes = ErrorScopes::push(&device);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("stencil_apply.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stencil_apply"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(PARAMS_SIZE),
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, true),
                storage(5, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stencil_apply"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("stencil_apply"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        scopes.pop().await?;
        Ok(Self {
            adapter_info,
            device,
            queue,
            layout,
            pipeline,
            limits,
        })
    }

    /// The adapter in use: name, backend and device type (lavapipe shows as `llvmpipe ...`,
    /// `Vulkan`, `Cpu`), and the driver, so logs and test output say where results came from.
    pub fn adapter_info(&self) -> String {
        describe(&self.adapter_info)
    }

    /// The device's limits (buffer sizes, workgroups per dimension).
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }

    /// Uploads a chain of tables (level 1, 2, ...) once; [`apply`](Self::apply) then reuses it
    /// for every frame. Checks that each table is well formed and that each level reads the
    /// rows the previous one makes, since the kernel trusts the indices.
    pub fn upload(&self, tables: &[StencilTable]) -> Result<GpuTables, GpuError> {
        for (level, t) in tables.iter().enumerate() {
            check_table(level, t)?;
            if level > 0 && t.source_count as usize != tables[level - 1].len() {
                return Err(GpuError::InvalidTable {
                    level,
                    reason: format!(
                        "reads {} rows but level {} makes {}",
                        t.source_count,
                        level - 1,
                        tables[level - 1].len()
                    ),
                });
            }
            self.grid(level, t.len())?;
            self.check_binding("offsets", bytes_of_len(t.offsets.len()))?;
            self.check_binding("sources", bytes_of_len(t.sources.len()))?;
            self.check_binding("weights", bytes_of_len(t.weights.len()))?;
        }
        let scopes = ErrorScopes::push(&self.device);
        let levels = tables
            .iter()
            .map(|t| GpuLevel {
                rows: t.len() as u32,
                offsets: self.storage_init("offsets", bytemuck::cast_slice(&t.offsets)),
                sources: self.storage_init("sources", bytemuck::cast_slice(&t.sources)),
                weights: self.storage_init("weights", bytemuck::cast_slice(&t.weights)),
            })
            .collect();
        pollster::block_on(scopes.pop())?;
        Ok(GpuTables {
            device: self.device.clone(),
            levels,
            source_count: tables.first().map_or(0, |t| t.source_count),
        })
    }

    /// Applies the uploaded chain to `src` (`source_count` rows of `stride` floats) and returns
    /// the last level's rows, like [`StencilTable::apply_chain`].
    pub fn apply(
        &self,
        tables: &GpuTables,
        src: &[f32],
        stride: usize,
    ) -> Result<Vec<f32>, GpuError> {
        self.apply_timed(tables, src, stride).map(|(out, _)| out)
    }

    /// [`apply`](Self::apply), also returning the wall time of the GPU work: from the
    /// submission (which includes uploading `src`, every level's dispatch and the copy of the
    /// result into a readable buffer) until the device reports it done, measured on the host.
    /// Buffer setup before and the read-back after are not counted.
    ///
    /// All levels go in one command submission: one compute dispatch per level, alternating
    /// between two buffers, so intermediate levels never leave the device.
    pub fn apply_timed(
        &self,
        tables: &GpuTables,
        src: &[f32],
        stride: usize,
    ) -> Result<(Vec<f32>, Duration), GpuError> {
        if tables.device != self.device {
            return Err(GpuError::ForeignTables);
        }
        let rows = tables.source_count as usize;
        let expected = rows.checked_mul(stride).ok_or(GpuError::SrcLength {
            got: src.len(),
            expected: usize::MAX,
            rows,
            stride,
        })?;
        if src.len() != expected {
            return Err(GpuError::SrcLength {
                got: src.len(),
                expected,
                rows,
                stride,
            });
        }
        if tables.levels.is_empty() {
            return Ok((src.to_vec(), Duration::ZERO));
        }
        let out_len = tables.output_rows() * stride;
        if out_len == 0 {
            return Ok((Vec::new(), Duration::ZERO));
        }
        let stride32 = u32::try_from(stride).map_err(|_| GpuError::BufferTooLarge {
            what: "row stride",
            size: stride as u64,
            limit: u32::MAX as u64,
            limit_name: "u32 index",
        })?;

        // Sizes: ping holds src and the even levels' outputs, pong the odd levels'.
        let src_bytes = bytes_of_len(src.len());
        self.check_binding("source data", src_bytes)?;
        let mut ping_size = src_bytes;
        let mut pong_size = 4;
        let mut grids = Vec::with_capacity(tables.levels.len());
        for (level, l) in tables.levels.iter().enumerate() {
            let bytes = (l.rows as u64).saturating_mul(stride as u64 * 4);
            self.check_binding("level output", bytes)?;
            if level % 2 == 0 {
                pong_size = pong_size.max(bytes);
            } else {
                ping_size = ping_size.max(bytes);
            }
            grids.push(self.grid(level, l.rows as usize)?);
        }
        let out_bytes = bytes_of_len(out_len);

        // Per-level uniforms, each at an offset the device can bind.
        let align = (self.limits.min_uniform_buffer_offset_alignment as u64).max(PARAMS_SIZE);
        let mut params = vec![0u8; (align * tables.levels.len() as u64) as usize];
        for (level, (l, &(gx, _))) in tables.levels.iter().zip(&grids).enumerate() {
            let p: [u32; 4] = [l.rows, stride32, gx * WORKGROUP, 0];
            let at = level * align as usize;
            params[at..at + PARAMS_SIZE as usize].copy_from_slice(bytemuck::cast_slice(&p));
        }

        let scopes = ErrorScopes::push(&self.device);
        let params = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("stencil params"),
                contents: &params,
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let storage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let ping = self.buffer("ping", ping_size, storage);
        let pong = self.buffer("pong", pong_size, storage);
        let readback = self.buffer(
            "readback",
            out_bytes,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        self.queue.write_buffer(&ping, 0, bytemuck::cast_slice(src));

        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("stencil apply"),
            });
        let mut in_rows = rows as u64;
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("stencil levels"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            for (level, (l, &(gx, gy))) in tables.levels.iter().zip(&grids).enumerate() {
                let (input, output) = if level % 2 == 0 {
                    (&ping, &pong)
                } else {
                    (&pong, &ping)
                };
                let in_bytes = in_rows * stride as u64 * 4;
                let out_level_bytes = l.rows as u64 * stride as u64 * 4;
                in_rows = l.rows as u64;
                if l.rows == 0 {
                    continue;
                }
                let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("stencil level"),
                    layout: &self.layout,
                    entries: &[
                        entry(0, &params, level as u64 * align, PARAMS_SIZE),
                        whole(1, &l.offsets),
                        whole(2, &l.sources),
                        whole(3, &l.weights),
                        entry(4, input, 0, in_bytes.max(4)),
                        entry(5, output, 0, out_level_bytes),
                    ],
                });
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
        }
        let last = if tables.levels.len() % 2 == 1 {
            &pong
        } else {
            &ping
        };
        encoder.copy_buffer_to_buffer(last, 0, &readback, 0, out_bytes);

        let start = Instant::now();
        let index = self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| GpuError::Wgpu(e.to_string()))?;
        let elapsed = start.elapsed();
        pollster::block_on(scopes.pop())?;

        let (tx, rx) = mpsc::channel();
        readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Wgpu(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Wgpu(format!("mapping the result: {e}")))?
            .map_err(|e| GpuError::Wgpu(format!("mapping the result: {e}")))?;
        let out = {
            let view = readback
                .get_mapped_range(..)
                .map_err(|e| GpuError::Wgpu(format!("reading the result: {e}")))?;
            bytemuck::cast_slice::<u8, f32>(&view[..out_bytes as usize]).to_vec()
        };
        readback.unmap();
        Ok((out, elapsed))
    }

    /// Workgroup grid for a level of `rows` rows on this device.
    fn grid(&self, level: usize, rows: usize) -> Result<(u32, u32), GpuError> {
        let max = self.limits.max_compute_workgroups_per_dimension;
        grid(rows, max).ok_or(GpuError::TooManyRows {
            level,
            rows,
            max: (max as u64).pow(2) * WORKGROUP as u64,
        })
    }

    /// Fails if a storage binding of `size` bytes would exceed the device's limits.
    fn check_binding(&self, what: &'static str, size: u64) -> Result<(), GpuError> {
        if size > self.limits.max_buffer_size {
            return Err(GpuError::BufferTooLarge {
                what,
                size,
                limit: self.limits.max_buffer_size,
                limit_name: "max_buffer_size",
            });
        }
        let binding = self.limits.max_storage_buffer_binding_size;
        if size > binding {
            return Err(GpuError::BufferTooLarge {
                what,
                size,
                limit: binding,
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        Ok(())
    }

    /// A read-only storage buffer holding `data` (at least 4 bytes: empty bindings are invalid).
    fn storage_init(&self, label: &str, data: &[u8]) -> wgpu::Buffer {
        let pad = [0u8; 4];
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if data.is_empty() { &pad } else { data },
                usage: wgpu::BufferUsages::STORAGE,
            })
    }

    fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(4),
            usage,
            mapped_at_creation: false,
        })
    }
}

/// Checks the compressed-row invariants the kernel relies on.
fn check_table(level: usize, t: &StencilTable) -> Result<(), GpuError> {
    let bad = |reason: String| Err(GpuError::InvalidTable { level, reason });
    if t.offsets.is_empty() {
        return bad("offsets is empty (it needs rows + 1 entries)".into());
    }
    if t.offsets[0] != 0 {
        return bad(format!("offsets[0] is {}, not 0", t.offsets[0]));
    }
    if let Some(i) = t.offsets.windows(2).position(|w| w[1] < w[0]) {
        return bad(format!("offsets decrease at row {i}"));
    }
    let terms = *t.offsets.last().unwrap_or(&0) as usize;
    if terms != t.sources.len() || terms != t.weights.len() {
        return bad(format!(
            "offsets end at {terms} but there are {} sources and {} weights",
            t.sources.len(),
            t.weights.len()
        ));
    }
    if let Some(k) = t.sources.iter().position(|&s| s >= t.source_count) {
        return bad(format!(
            "source {} of term {k} is not below source_count {}",
            t.sources[k], t.source_count
        ));
    }
    Ok(())
}

/// Workgroup grid (x, y) covering `rows` rows: 1-D while the workgroups fit in one dimension
/// (`max` per dimension), else 2-D with x full; the shader maps (x, y) back to a row. None when
/// even a `max × max` grid is too small, or rows do not fit the shader's u32 row index.
fn grid(rows: usize, max: u32) -> Option<(u32, u32)> {
    let max = max.max(1) as u64;
    if rows as u64 >= u32::MAX as u64 {
        return None;
    }
    let groups = (rows as u64).div_ceil(WORKGROUP as u64);
    if groups <= max {
        return Some((groups as u32, 1));
    }
    let gy = groups.div_ceil(max);
    (gy <= max).then_some((max as u32, gy as u32))
}

fn bytes_of_len(floats: usize) -> u64 {
    (floats as u64).saturating_mul(4)
}

fn entry(binding: u32, buffer: &wgpu::Buffer, offset: u64, size: u64) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset,
            size: wgpu::BufferSize::new(size),
        }),
    }
}

fn whole(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

#[cfg(test)]
mod tests {
    use super::grid;

    #[test]
    fn grid_goes_2d_past_the_dimension_limit() {
        assert_eq!(grid(0, 65535), Some((0, 1)));
        assert_eq!(grid(1, 65535), Some((1, 1)));
        assert_eq!(grid(64 * 65535, 65535), Some((65535, 1)));
        assert_eq!(grid(64 * 65535 + 1, 65535), Some((65535, 2)));
        assert_eq!(grid(64 * 10 * 3, 10), Some((10, 3)));
        assert_eq!(grid(64 * 10 * 10, 10), Some((10, 10)));
        assert_eq!(grid(64 * 10 * 10 + 1, 10), None);
        assert_eq!(grid(u32::MAX as usize, 65535), None);
    }
}
