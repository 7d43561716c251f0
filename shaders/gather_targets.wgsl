// Gather (core/render/src/frame_buffers.rs): copies the raster pass's targets (colour, depth,
// face id, (u, v)) into the per-pixel storage buffers that crack detection and filling (paper
// 001 §3.2–3.4) read and write, turning the depth-buffer value into the distance along the
// view direction (what §3.2's d_min is compared with; the background gets f32::MAX) and
// clearing the crack flags. One invocation per pixel, index y·W + x, row 0 at the top.

struct Gather {
    width: u32,
    height: u32,
    near: f32,
    far: f32,
}

@group(0) @binding(0) var<uniform> g: Gather;
@group(0) @binding(1) var color_in: texture_2d<f32>;
@group(0) @binding(2) var depth_in: texture_depth_2d;
@group(0) @binding(3) var face_in: texture_2d<u32>;
@group(0) @binding(4) var uv_in: texture_2d<f32>;
@group(0) @binding(5) var<storage, read_write> color: array<u32>;
@group(0) @binding(6) var<storage, read_write> depth: array<f32>;
@group(0) @binding(7) var<storage, read_write> face: array<u32>;
@group(0) @binding(8) var<storage, read_write> uv: array<vec2<f32>>;
@group(0) @binding(9) var<storage, read_write> flags: array<u32>;

const BACKGROUND_DEPTH: f32 = 3.4028235e38;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= g.width || gid.y >= g.height {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let i = gid.y * g.width + gid.x;
    color[i] = pack4x8unorm(textureLoad(color_in, p, 0));
    let z = textureLoad(depth_in, p, 0);
    if z >= 1.0 {
        depth[i] = BACKGROUND_DEPTH;
    } else {
        depth[i] = g.far * g.near / (g.far - z * (g.far - g.near));
    }
    face[i] = textureLoad(face_in, p, 0).x;
    uv[i] = textureLoad(uv_in, p, 0).xy;
    flags[i] = 0u;
}
