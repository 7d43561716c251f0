// Crack pixel detection (core/render/src/crack_detect.rs; paper 001 §3.2, figures 6–8).
// One invocation per pixel, index y·W + x, row 0 at the top. Pixel p is a crack when, for one
// of the four opposite pairs (p_i, p_opp(i)) of its 8-pixel ring, both neighbours lie inside
// the image, both are covered (face ≠ 0), both are closer to the observer than p by at least
// d_min (depth[p] − depth[n] ≥ d_min; a background p has f32::MAX depth), and p's face differs
// from both neighbours' faces (same-face exclusion: a steep perspective slope of one face is no
// crack). Requiring both members of a pair (the "opposite fragment" test) leaves silhouette
// pixels alone. Sets flags[p] |= CRACK and leaves every other bit as it was.

struct CrackDetect {
    width: u32,
    height: u32,
    d_min: f32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: CrackDetect;
@group(0) @binding(1) var<storage, read> depth: array<f32>;
@group(0) @binding(2) var<storage, read> face: array<u32>;
@group(0) @binding(3) var<storage, read_write> flags: array<u32>;

const CRACK: u32 = 1u;

// The first member of each opposite pair; the second is its negation.
const PAIRS = array<vec2<i32>, 4>(
    vec2<i32>(-1, -1),
    vec2<i32>(0, -1),
    vec2<i32>(1, -1),
    vec2<i32>(-1, 0),
);

// Whether neighbour q (in pixels) is inside, covered, closer than p by d_min and of another face.
fn occludes(q: vec2<i32>, p_depth: f32, p_face: u32) -> bool {
    if q.x < 0 || q.y < 0 || q.x >= i32(params.width) || q.y >= i32(params.height) {
        return false;
    }
    let j = u32(q.y) * params.width + u32(q.x);
    let f = face[j];
    return f != 0u && f != p_face && p_depth - depth[j] >= params.d_min;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let i = gid.y * params.width + gid.x;
    let p_depth = depth[i];
    let p_face = face[i];
    var crack = false;
    for (var k = 0u; k < 4u; k++) {
        let o = PAIRS[k];
        if occludes(p + o, p_depth, p_face) && occludes(p - o, p_depth, p_face) {
            crack = true;
        }
    }
    if crack {
        flags[i] = flags[i] | CRACK;
    }
}
