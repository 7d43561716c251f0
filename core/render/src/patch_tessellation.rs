//! Basis-surface tessellation per frame (issue 21 point 2; paper 001 §3.1, paper 000 §6–7):
//! every visible face's basis surface as a grid of 2^ku × 2^kv cells over its quadtree's root
//! square, evaluated on the GPU (`shaders/patch_tessellate.wgsl`).
//!
//! **Why a compute pass**: WebGPU has no tessellation stage. Of the two ways the issue offers
//! (a compute pass that writes each patch's (u, v) grid, or instanced grids), the compute pass
//! evaluates each grid vertex once — an instanced grid evaluates the surface in the vertex
//! shader for each of the up to six triangles sharing a vertex — and the raster pass then
//! pulls the vertices by index, so one grid buffer serves the filled pass, the wireframe pass
//! of object-space crack filling, and any camera.
//!
//! **Factors** ([`FrameTessellation::new`], on the CPU, per face and frame): the screen-space
//! bound of Yeo et al. that paper 001 §3.1 asks for — tessellated points within k = 0.5 pixel
//! of the surface — is met with the face's second-derivative bound M (estimated once, see
//! [`crate::brep_scene::FaceInfo::curvature`]): a grid of steps (h_x, h_y) deviates from the
//! surface by at most (M_xx h_x² + 2 M_xy h_x h_y + M_yy h_y²) / 8, which must stay under
//! k pixels' world size at the face's nearest distance from the eye. The factors are then
//! raised to powers of two, at least 2^k_i (paper 000 §6: the grid is aligned to quadtree
//! cells of depth k_i, so triangle classification decides enough cells), at most
//! 2^[`MAX_LEVEL`]. Faces whose box lies outside the view frustum get no grid.

use crate::bindings::{self, dispatch_1d};
use crate::brep_scene::{BrepScene, MAX_LEVEL};
use crate::camera::{Camera, Vec3};
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// The covering accuracy k of paper 001 §3.1, in pixels.
pub const PIXEL_ACCURACY: f64 = 0.5;

/// One face's tessellation in a frame (`PatchFrame` in `shaders/patch_grid.wgsl`, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PatchFrame {
    /// The face (document order).
    pub face: u32,
    /// Cells along the quadtree's x axis (2^ku).
    pub nu: u32,
    /// Cells along y (2^kv).
    pub nv: u32,
    /// The classification depth k_f = min(ku, kv).
    pub level: u32,
    /// The face's first vertex in the frame's grid.
    pub vertex_base: u32,
    /// The face's first cell.
    pub cell_base: u32,
    /// Padding.
    pub pad: [u32; 2],
}

/// A grid vertex as the shaders read it (`GridVertex`, 32 bytes).
pub const GRID_VERTEX_BYTES: u64 = 32;

/// The frame's tessellation: which faces, at which factors.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameTessellation {
    /// The visible faces' records, in document order.
    pub patches: Vec<PatchFrame>,
    /// Grid vertices in all.
    pub vertices: u32,
    /// Grid cells in all (two triangles each).
    pub cells: u32,
}

/// The level (log2 of the factor) for a grid axis whose second derivative is bounded by `m`
/// (world units per quadtree unit²) to stay within `budget` world units, with the mixed
/// term already accounted for by the caller's split of the budget.
fn level_for(m: f64, budget: f64) -> u32 {
    if m.is_nan() || m <= 0.0 {
        return 0;
    }
    // m h² / 8 ≤ budget  ⇔  n = 1/h ≥ sqrt(m / (8 budget)).
    let n = (m / (8.0 * budget)).sqrt();
    if !n.is_finite() {
        return MAX_LEVEL;
    }
    let mut k = 0;
    while ((1u64 << k) as f64) < n && k < MAX_LEVEL {
        k += 1;
    }
    k
}

impl FrameTessellation {
    /// The factors of every face of `scene` for `camera` and a `width × height` image (see
    /// the module documentation), at covering accuracy `accuracy` pixels.
    pub fn new(
        scene: &BrepScene,
        camera: &Camera,
        width: u32,
        height: u32,
        accuracy: f64,
    ) -> FrameTessellation {
        let (forward, right, up) = camera.basis();
        let ty = (0.5 * camera.fov.to_radians()).tan();
        let mut out = FrameTessellation::default();
        let (mut vertices, mut cells) = (0u64, 0u64);
        for (face, info) in scene.faces.iter().enumerate() {
            let corners = info.bounds.corners();
            let rel: Vec<Vec3> = corners.iter().map(|c| *c - camera.eye).collect();
            let depths: Vec<f64> = rel.iter().map(|r| r.dot(forward)).collect();
            let nearest = depths.iter().cloned().fold(f64::INFINITY, f64::min);
            let farthest = depths.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            if info.bounds.min == info.bounds.max || farthest < camera.near || nearest > camera.far
            {
                continue;
            }
            // Outside one side plane of the frustum with all eight corners: culled.
            let tx = ty * width as f64 / height.max(1) as f64;
            let outside = |axis: Vec3, t: f64, sign: f64| {
                rel.iter().all(|r| {
                    let z = r.dot(forward);
                    z > 0.0 && sign * r.dot(axis) > t * z
                })
            };
            if outside(right, tx, 1.0)
                || outside(right, tx, -1.0)
                || outside(up, ty, 1.0)
                || outside(up, ty, -1.0)
            {
                continue;
            }
            let distance = nearest.max(camera.near);
            let tolerance = accuracy * camera.pixel_size(distance, height);
            let [mxx, myy, mxy] = info.curvature;
            // A third of the budget to each term: x, y and the mixed one.
            let mut ku = level_for(mxx, tolerance / 3.0);
            let mut kv = level_for(myy, tolerance / 3.0);
            while mxy * (1.0 / (1u64 << ku) as f64) * (1.0 / (1u64 << kv) as f64) / 4.0
                > tolerance / 3.0
                && (ku < MAX_LEVEL || kv < MAX_LEVEL)
            {
                if ku <= kv && ku < MAX_LEVEL {
                    ku += 1;
                } else {
                    kv += 1;
                }
            }
            if let Some(k) = info.k_i {
                ku = ku.max(k);
                kv = kv.max(k);
            }
            let (nu, nv) = (1u32 << ku, 1u32 << kv);
            out.patches.push(PatchFrame {
                face: face as u32,
                nu,
                nv,
                level: ku.min(kv),
                vertex_base: vertices as u32,
                cell_base: cells as u32,
                pad: [0; 2],
            });
            vertices += (nu as u64 + 1) * (nv as u64 + 1);
            cells += nu as u64 * nv as u64;
        }
        out.vertices = vertices.min(u32::MAX as u64) as u32;
        out.cells = cells.min(u32::MAX as u64 / 6) as u32;
        out
    }
}

impl FrameTessellation {
    /// Every face of `scene` at 2^k × 2^k cells, whatever the view (for tests and
    /// diagnostics of triangle classification at a given level).
    pub fn uniform(scene: &BrepScene, k: u32) -> FrameTessellation {
        let n = 1u32 << k.min(MAX_LEVEL);
        let mut out = FrameTessellation::default();
        for face in 0..scene.faces.len() as u32 {
            out.patches.push(PatchFrame {
                face,
                nu: n,
                nv: n,
                level: k.min(MAX_LEVEL),
                vertex_base: out.vertices,
                cell_base: out.cells,
                pad: [0; 2],
            });
            out.vertices += (n + 1) * (n + 1);
            out.cells += n * n;
        }
        out
    }
}

/// The uniform block of the grid and classification passes (`TessParams`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct TessParams {
    pub patch_count: u32,
    pub vertex_count: u32,
    pub cell_count: u32,
    pub row: u32,
}

/// The WGSL of the grid pass.
pub const SHADER: &str = patch_grid_shader!("patch_tessellate.wgsl");

/// A frame's tessellation on the device.
pub struct GpuTessellation {
    /// The [`PatchFrame`]s.
    pub patches: wgpu::Buffer,
    /// The grid vertices.
    pub grid: wgpu::Buffer,
    /// The cell records (filled by triangle classification).
    pub cells: wgpu::Buffer,
    /// Cells in all.
    pub cell_count: u32,
    /// Vertices in all.
    pub vertex_count: u32,
}

/// A one-dimensional pass over the frame's grid (`source`'s `main`): bind group 0 holds the
/// [`TessParams`] block, the patches (read) and one buffer it writes, group 1 the part's
/// buffers. The grid and the classification passes are two of these.
pub(crate) struct GridPass {
    label: &'static str,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl GridPass {
    /// Compiles `source` with `brep` as the layout of bind group 1.
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &'static str,
        source: &str,
        brep: &wgpu::BindGroupLayout,
    ) -> GridPass {
        let c = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &[
                bindings::uniform(0, c),
                bindings::storage(1, true, c),
                bindings::storage(2, false, c),
            ],
        });
        let pipeline = bindings::compute_pipeline(device, label, source, &[&layout, brep]);
        GridPass {
            label,
            layout,
            pipeline,
        }
    }

    /// Records one invocation per element of `count` (grid vertices or cells) of `frame`,
    /// reading the patch records and writing the output of `[patches, out]`; nothing when
    /// `count` is 0.
    pub(crate) fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        brep_group: &wgpu::BindGroup,
        frame: &FrameTessellation,
        count: u32,
        [patches, out]: [&wgpu::Buffer; 2],
    ) {
        if count == 0 {
            return;
        }
        let (x, y, row) = dispatch_1d(count);
        let params = TessParams {
            patch_count: frame.patches.len() as u32,
            vertex_count: frame.vertices,
            cell_count: frame.cells,
            row,
        };
        let uniform = bindings::uniform_buffer(device, self.label, &params);
        let group =
            bindings::bind_buffers(device, self.label, &self.layout, &[&uniform, patches, out]);
        bindings::compute_pass(
            encoder,
            self.label,
            &self.pipeline,
            &[&group, brep_group],
            (x, y, 1),
        );
    }
}

/// The compiled grid pass.
pub struct TessellationPass {
    pass: GridPass,
}

impl TessellationPass {
    /// Compiles the shader; `brep` is the layout of bind group 1.
    pub fn new(device: &wgpu::Device, brep: &wgpu::BindGroupLayout) -> TessellationPass {
        TessellationPass {
            pass: GridPass::new(device, "patch_tessellate", SHADER, brep),
        }
    }

    /// Creates the frame's buffers and records the grid evaluation.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        brep_group: &wgpu::BindGroup,
        frame: &FrameTessellation,
    ) -> GpuTessellation {
        let empty = [PatchFrame::default()];
        let patches = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("patch frames"),
            contents: bytemuck::cast_slice(if frame.patches.is_empty() {
                &empty
            } else {
                &frame.patches
            }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let grid = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("patch grid"),
            size: (frame.vertices as u64 * GRID_VERTEX_BYTES).max(GRID_VERTEX_BYTES),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let cells = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("patch cells"),
            size: (frame.cells as u64 * 24).max(24),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        self.pass.encode(
            device,
            encoder,
            brep_group,
            frame,
            frame.vertices,
            [&patches, &grid],
        );
        GpuTessellation {
            patches,
            grid,
            cells,
            cell_count: frame.cells,
            vertex_count: frame.vertices,
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
