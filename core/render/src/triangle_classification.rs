//! Triangle classification (paper 000 §6; `shaders/triangle_classify.wgsl`): once per grid
//! cell of the frame's tessellation, before rasterisation, the quadtree node at depth
//! k_f = min(ku, kv) that holds the cell. A cell wholly off the face is dropped by the raster
//! pass's vertex shader (the paper's geometry-shader culling), a cell wholly on needs no
//! per-fragment walk, and any other cell hands its node to its fragments, whose walk resumes
//! there instead of at the root. The factors are at least 2^k_i (see
//! [`crate::patch_tessellation`]), the level at which section 6 finds at least 40 % of the
//! domain decided — by this pass's own rule ([`classification_level`]).

use crate::patch_tessellation::{FrameTessellation, GpuTessellation, GridPass};
use tessd_trim::multi_pack::MultiPack;
use tessd_trim::pack::NODE_INDEX_BITS;
use tessd_trim::quadtree::K_FRACTION;

/// The level k_i of paper 000 §6 as this renderer's triangulation has it: the smallest k ≤
/// `max_level` at which at least [`K_FRACTION`] of face `face`'s quadtree square lies in grid
/// cells (2^k × 2^k over the square) that the classification pass decides whole, or `None`
/// when no level up to `max_level` gets there. Section 6 asks this of the triangles the
/// renderer really draws; the quadtree's own estimate ([`tessd_trim::Quadtree::k_i`]) splits
/// cells along a diagonal and decides quadratic leaves by their convex region, which
/// `triangle_classify.wgsl` does not — so it is recomputed here with the shader's rule: the
/// node reached by a cell's centre, no deeper than k, decides the cell when it is an on / off
/// leaf, or a line leaf with the cell's four corners on one side.
pub fn classification_level(pack: &MultiPack, face: usize, max_level: u32) -> Option<u32> {
    (0..=max_level).find(|&k| decided_share(pack, face, k) >= K_FRACTION)
}

/// The share of face `face`'s quadtree square in level-`k` cells the pass decides whole.
pub fn decided_share(pack: &MultiPack, face: usize, k: u32) -> f64 {
    let h = &pack.headers[face];
    // (node, depth, cell origin); the side is 2^-depth.
    let mut stack = vec![(h.node_base, 0u32, [0.0f64; 2])];
    let mut share = 0.0;
    while let Some((node, depth, o)) = stack.pop() {
        let word = pack.nodes[node as usize];
        let side = 0.5f64.powi(depth as i32);
        let kind = word & 7;
        if kind == 0 && depth < k && depth < h.depth_limit {
            let first = word >> (32 - NODE_INDEX_BITS);
            let half = 0.5 * side;
            for c in 0..4u32 {
                let d = [f64::from(c & 1) * half, f64::from(c >> 1) * half];
                stack.push((first + c, depth + 1, [o[0] + d[0], o[1] + d[1]]));
            }
            continue;
        }
        share += match kind {
            1 | 2 => side * side,
            3 => {
                // The node's level-k cells with their four corners on one side of the line.
                let n = 1u32 << k.saturating_sub(depth);
                let step = side / f64::from(n);
                let index = word >> (32 - NODE_INDEX_BITS);
                let on = |i: u32, j: u32| {
                    let (x, y) = (o[0] + f64::from(i) * step, o[1] + f64::from(j) * step);
                    pack.curve(index, 0, x as f32, y as f32)
                };
                let mut whole = 0u32;
                for j in 0..n {
                    for i in 0..n {
                        let c = [on(i, j), on(i + 1, j), on(i, j + 1), on(i + 1, j + 1)];
                        whole += u32::from(c.iter().all(|&x| x) || c.iter().all(|&x| !x));
                    }
                }
                f64::from(whole) * step * step
            }
            _ => 0.0,
        };
    }
    share
}

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
