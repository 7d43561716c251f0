// Step 5 of paper 001 (§3.4.3; core/render/src/object_fill.rs): crack pixels that step 4 gave
// a winner receive its colour, face, (u, v) and depth; every other pixel keeps step 1's.

struct Composite {
    width: u32,
    height: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> c: Composite;
@group(0) @binding(1) var<storage, read_write> color: array<u32>;
@group(0) @binding(2) var<storage, read_write> depth: array<f32>;
@group(0) @binding(3) var<storage, read_write> face: array<u32>;
@group(0) @binding(4) var<storage, read_write> uv: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> flags: array<u32>;
@group(0) @binding(6) var<storage, read> winner_face: array<u32>;
// (u, v), depth, colour bits (object_fill.wgsl).
@group(0) @binding(7) var<storage, read> winner: array<vec4<f32>>;

const CRACK: u32 = 1u;
const FILLED: u32 = 2u;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= c.width || gid.y >= c.height {
        return;
    }
    let i = gid.y * c.width + gid.x;
    if (flags[i] & CRACK) == 0u || winner_face[i] == 0u {
        return;
    }
    let w = winner[i];
    color[i] = bitcast<u32>(w.w);
    depth[i] = w.z;
    face[i] = winner_face[i];
    uv[i] = w.xy;
    flags[i] |= FILLED;
}
