// Step 3 of paper 001 (§3.4.1; core/render/src/object_fill.rs): the depth mask, drawn as one
// full-screen triangle that writes each pixel's mask depth, and the per-pixel state of step 4
// initialised on the way. The mask of pixel p is the largest step-1 depth among the crack
// pixels of p's 1-ring (p included): a step-4 fragment at p can only fill a crack pixel q in
// that ring with a surface nearer than what q shows, so anything deeper is culled by the depth
// test. Where the ring holds no crack the mask is 0 and every fragment is culled — stricter
// than the paper's "the maximum of the pixel's own depth and its neighbouring cracks' depths",
// which lets fragments in front of a crack-free pixel through only for them to find no crack.
// Also: the atomic key of step 4 starts at the pixel's step-1 depth (a crack showing a far
// face keeps it unless ray casting finds something nearer), and the mailbox and the winner
// slot are emptied.

struct Mask {
    width: u32,
    height: u32,
    near: f32,
    far: f32,
}

@group(0) @binding(0) var<uniform> m: Mask;
@group(0) @binding(1) var<storage, read> depth: array<f32>;
@group(0) @binding(2) var<storage, read> flags: array<u32>;
@group(0) @binding(3) var<storage, read_write> zmin: array<u32>;
@group(0) @binding(4) var<storage, read_write> mailbox: array<u32>;
@group(0) @binding(5) var<storage, read_write> winner_face: array<u32>;

const CRACK: u32 = 1u;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let x = f32((vi << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(vi & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

// The depth-buffer value of distance `d` along the view direction (the projection of
// camera.rs: a + b / d with a = f / (f − n), b = −f n / (f − n)), clamped to [0, 1].
fn ndc_depth(d: f32) -> f32 {
    let a = m.far / (m.far - m.near);
    return clamp(a * (1.0 - m.near / d), 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @builtin(frag_depth) f32 {
    let p = vec2<i32>(frag.xy);
    let i = u32(p.y) * m.width + u32(p.x);
    // Step 1's surface as the key to beat: its depth, tag 4095 (see object_fill.wgsl).
    zmin[i] = (bitcast<u32>(depth[i]) & ~0xfffu) | 0xfffu;
    mailbox[i] = 0u;
    winner_face[i] = 0u;
    var mask = 0.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = p + vec2<i32>(dx, dy);
            if q.x < 0 || q.y < 0 || q.x >= i32(m.width) || q.y >= i32(m.height) {
                continue;
            }
            let j = u32(q.y) * m.width + u32(q.x);
            if (flags[j] & CRACK) != 0u {
                mask = max(mask, ndc_depth(depth[j]));
            }
        }
    }
    return mask;
}
