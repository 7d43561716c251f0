//! Triangle classification (paper 000 §6; `shaders/triangle_classify.wgsl`): once per grid
//! cell of the frame's tessellation, before rasterisation, the quadtree node at depth
//! k_f = min(ku, kv) that holds the cell. A cell wholly off the face is dropped by the raster
//! pass's vertex shader (the paper's geometry-shader culling), a cell wholly on needs no
//! per-fragment walk, and any other cell hands its node to its fragments, whose walk resumes
//! there instead of at the root. The factors are at least 2^k_i (see
//! [`crate::patch_tessellation`]), the level at which section 6 finds at least 40 % of the
//! domain decided — by this pass's own rule, read on the CPU by
//! [`crate::classification_level`].

use crate::patch_tessellation::{FrameTessellation, GpuTessellation, GridPass};

/// What the pass decided for one grid cell (a `CellRecord` of `patch_grid.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellDecision {
    /// The patch's index in the frame's [`FrameTessellation::patches`].
    pub patch: u32,
    /// The cell's column (along the quadtree's x axis).
    pub column: u32,
    /// Its row.
    pub row: u32,
    /// The quadtree node handed to the cell's fragments.
    pub node: u32,
    /// That node's depth.
    pub depth: u32,
    /// `Some(on)` when the cell is wholly on or off the face, `None` when its fragments walk.
    pub whole: Option<bool>,
}

impl CellDecision {
    /// Decodes the pass's 24-byte cell records.
    pub fn decode(words: &[u32]) -> Vec<CellDecision> {
        words
            .chunks_exact(6)
            .map(|w| CellDecision {
                patch: w[0],
                column: w[1] & 0xffff,
                row: w[1] >> 16,
                node: w[2],
                depth: w[3] & 0xff,
                whole: match w[3] >> 8 {
                    1 => Some(false),
                    2 => Some(true),
                    _ => None,
                },
            })
            .collect()
    }
}

/// The WGSL of the pass.
pub const SHADER: &str = patch_grid_shader!("triangle_classify.wgsl");

/// The compiled pass.
pub struct ClassificationPass {
    pass: GridPass,
}

impl ClassificationPass {
    /// Compiles the shader; `brep` is the layout of bind group 1.
    pub fn new(device: &wgpu::Device, brep: &wgpu::BindGroupLayout) -> ClassificationPass {
        ClassificationPass {
            pass: GridPass::new(device, "triangle_classify", SHADER, brep),
        }
    }

    /// Records the classification of every cell of `tess` into its cell records.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        brep_group: &wgpu::BindGroup,
        frame: &FrameTessellation,
        tess: &GpuTessellation,
    ) {
        self.pass.encode(
            device,
            encoder,
            brep_group,
            frame,
            frame.cells,
            [&tess.patches, &tess.cells],
        );
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
