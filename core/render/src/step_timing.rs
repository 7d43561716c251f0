//! The timing layer under the B-Rep passes: each step of a frame is recorded, submitted on
//! its own and waited for, so that its wall time is its own (paper 001 table 1's rows). The
//! passes ([`crate::object_fill`]) and their driver ([`crate::brep_render`]) both time their
//! steps here, so that no pass reaches up to the driver for it.

use crate::RenderError;
use std::time::{Duration, Instant};
use tessd_gpu::{GpuContext, GpuError};

/// Wall times of one B-Rep frame by step (paper 001 table 1's rows; zero for steps not run).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTimings {
    /// Factors on the CPU, grid evaluation and triangle classification on the GPU.
    pub tessellation: Duration,
    /// Step 1: the trimmed raster pass and the gather into the per-pixel buffers.
    pub initial: Duration,
    /// Step 2.
    pub crack_detection: Duration,
    /// Image-space filling.
    pub image_fill: Duration,
    /// Step 3: the depth mask.
    pub depth_mask: Duration,
    /// Step 4: ray casting at the crack pixels.
    pub object_fill: Duration,
    /// Step 5: the composite.
    pub composite: Duration,
    /// Full-scene ray casting (instead of steps 1–5).
    pub ray_cast: Duration,
    /// Reading the buffers back.
    pub readback: Duration,
}

impl StepTimings {
    /// The frame's time on the device (everything but the read-back).
    pub fn frame(&self) -> Duration {
        self.tessellation
            + self.initial
            + self.crack_detection
            + self.image_fill
            + self.depth_mask
            + self.object_fill
            + self.composite
            + self.ray_cast
    }
}

/// Records one step with `record`, submits it, waits for the device, and adds the wall time
/// to `time`.
pub(crate) fn step<T>(
    gpu: &GpuContext,
    time: &mut Duration,
    record: impl FnOnce(&mut wgpu::CommandEncoder) -> T,
) -> Result<T, RenderError> {
    let start = Instant::now();
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("step"),
        });
    let out = record(&mut encoder);
    let index = gpu.queue.submit([encoder.finish()]);
    gpu.device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(index),
            timeout: None,
        })
        .map_err(|e| GpuError::Wgpu(e.to_string()))?;
    *time += start.elapsed();
    Ok(out)
}
