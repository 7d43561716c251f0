//! Crack pixel detection (paper 001 §3.2, figures 6–8) as a compute pass over
//! [`FrameBuffers`] (`shaders/crack_detect.wgsl`).
//!
//! A pixel p is flagged [`CRACK`] when, for one of the four opposite pairs (p_i, p_opp(i)) of
//! its 8-pixel ring, both neighbours
//! - lie inside the image,
//! - are covered (face id ≠ 0),
//! - are closer to the observer than p by at least `d_min` (`depth[p] − depth[n] ≥ d_min`; a
//!   background p has [`BACKGROUND_DEPTH`](crate::frame_buffers::BACKGROUND_DEPTH), so a hole
//!   onto the background qualifies), and
//! - have a face id different from p's (the same-face exclusion of §3.2: a pixel deeper than
//!   neighbours of its own face is a steep perspective slope of that face, not a crack).
//!
//! Requiring both members of an opposite pair (the paper's "opposite fragment" test, figure 8)
//! is what leaves silhouette and occlusion-contour pixels alone: there only one side of p is
//! nearer. Here one face is one patch (each face's basis surface is evaluated directly), so the
//! paper's B-Rep face id is our face id. The detection is conservative, as in the paper: every
//! crack is flagged, and a few non-crack pixels (e.g. a thin slot narrower than two pixels seen
//! head-on) may be flagged too.
//!
//! The pass only sets the [`CRACK`] bit; it neither clears flags nor touches other buffers.

use crate::bindings::{self, storage, uniform};
use crate::frame_buffers::{CRACK, FILLED, FrameBuffers};
use bytemuck::{Pod, Zeroable};

/// The uniform block of the detection shader (`CrackDetect`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CrackDetectParams {
    width: u32,
    height: u32,
    d_min: f32,
    _pad: u32,
}

/// The WGSL of the detection pass.
pub const CRACK_DETECT_SHADER: &str = include_str!("../../../shaders/crack_detect.wgsl");

/// The `d_min` of §3.2 for a part whose bounding box has diagonal `bounds_diagonal` (world
/// units): `10⁻³ ×` the diagonal.
///
/// The paper defines `d_min` as the shortest distance a ray can travel between two
/// front-facing hits on the model (figure 7): any smaller depth step between p and both of its
/// opposite neighbours cannot come from the model itself. That minimum is hard to compute, so
/// the paper sets it to 1 mm for its (mechanical, decimetre-to-metre sized) models. A fixed
/// length does not suit parts of any size and unit, so we take the same order of magnitude
/// relative to the part, 1/1000 of its diagonal:
/// - small enough to be below the wall thicknesses and step heights of ordinary parts, so every
///   crack that opens onto a farther surface or the background is flagged;
/// - large enough to be well above the depth differences between neighbouring pixels of
///   different faces meeting along a shared edge (at most the tessellation tolerance plus the
///   depth change across one pixel at moderate slopes), so shared edges are not flagged.
///
/// A non-finite or non-positive diagonal gives `f32::MIN_POSITIVE` (any depth step counts).
pub fn default_d_min(bounds_diagonal: f64) -> f32 {
    let d = (1e-3 * bounds_diagonal) as f32;
    if d.is_finite() && d > 0.0 {
        d
    } else {
        f32::MIN_POSITIVE
    }
}

/// The number of pixels flagged [`CRACK`] and the number flagged [`FILLED`] in `flags` (as
/// [`FrameBuffers::read`] returns them).
pub fn count_flags(flags: &[u32]) -> (usize, usize) {
    flags.iter().fold((0, 0), |(cracks, filled), &f| {
        (
            cracks + usize::from(f & CRACK != 0),
            filled + usize::from(f & FILLED != 0),
        )
    })
}

/// The crack detection pass of §3.2 (see the module documentation).
pub struct CrackDetectPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl CrackDetectPass {
    /// Compiles the shader.
    pub fn new(device: &wgpu::Device) -> CrackDetectPass {
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("crack_detect"),
            entries: &[
                uniform(0, c),
                storage(1, true, c),
                storage(2, true, c),
                storage(3, false, c),
            ],
        });
        let pipeline =
            bindings::compute_pipeline(device, "crack_detect", CRACK_DETECT_SHADER, &[&layout]);
        CrackDetectPass { layout, pipeline }
    }

    /// Records the detection over `buffers` with threshold `d_min` (world units along the view
    /// direction; see [`default_d_min`]): sets the [`CRACK`] bit of every crack pixel.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &FrameBuffers,
        d_min: f32,
    ) {
        let params = CrackDetectParams {
            width: buffers.width,
            height: buffers.height,
            d_min,
            _pad: 0,
        };
        let uniform = bindings::uniform_buffer(device, "crack_detect params", &params);
        let group = bindings::bind_buffers(
            device,
            "crack_detect",
            &self.layout,
            &[&uniform, &buffers.depth, &buffers.face, &buffers.flags],
        );
        bindings::compute_pass(
            encoder,
            "crack_detect",
            &self.pipeline,
            &[&group],
            bindings::dispatch_pixels(buffers.width, buffers.height),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crack_detect_shader_validates_with_naga() {
        let module = crate::wgsl_check::validated(CRACK_DETECT_SHADER);
        assert_eq!(
            crate::wgsl_check::struct_size(&module, "CrackDetect"),
            size_of::<CrackDetectParams>()
        );
    }

    #[test]
    fn default_d_min_is_a_thousandth_of_the_diagonal() {
        assert_eq!(default_d_min(1000.0), 1.0);
        assert!((default_d_min(0.5) - 5e-4).abs() < 1e-9);
        assert_eq!(default_d_min(0.0), f32::MIN_POSITIVE);
        assert_eq!(default_d_min(f64::NAN), f32::MIN_POSITIVE);
    }

    #[test]
    fn count_flags_counts_each_bit() {
        assert_eq!(count_flags(&[]), (0, 0));
        assert_eq!(count_flags(&[0, CRACK, CRACK | FILLED, FILLED, 4]), (2, 2));
    }
}
