// Image-space crack filling (core/render/src/image_fill.rs; paper 001 §3.3). One invocation per
// pixel, index y·W + x, row 0 at the top. For a pixel flagged CRACK, the usable neighbours are
// those of its 8-pixel ring that are inside the image, covered (face ≠ 0) and not flagged CRACK.
// B_p (here a face id: one face = one patch) is the face covering the most usable neighbours;
// ties go to the nearest mean depth, then to the smallest id. The pixel gets the average colour
// and the mean depth of B_p's neighbours, B_p's id, the (u, v) of the nearest of them (the first
// in ring order on equal depths), and FILLED. A crack pixel without a usable neighbour is left
// as it is.
//
// Only non-CRACK pixels are read (colour, depth, face, uv) and only CRACK pixels are written, so
// invocations never race on those buffers; the flags, read to find CRACK neighbours while crack
// pixels gain FILLED, are accessed atomically.

struct ImageFill {
    width: u32,
    height: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: ImageFill;
@group(0) @binding(1) var<storage, read_write> color: array<u32>;
@group(0) @binding(2) var<storage, read_write> depth: array<f32>;
@group(0) @binding(3) var<storage, read_write> face: array<u32>;
@group(0) @binding(4) var<storage, read_write> uv: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> flags: array<atomic<u32>>;

const CRACK: u32 = 1u;
const FILLED: u32 = 2u;

const RING = array<vec2<i32>, 8>(
    vec2<i32>(-1, -1),
    vec2<i32>(0, -1),
    vec2<i32>(1, -1),
    vec2<i32>(-1, 0),
    vec2<i32>(1, 0),
    vec2<i32>(-1, 1),
    vec2<i32>(0, 1),
    vec2<i32>(1, 1),
);

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let i = gid.y * params.width + gid.x;
    if (atomicLoad(&flags[i]) & CRACK) == 0u {
        return;
    }
    let p = vec2<i32>(gid.xy);

    // The usable neighbours: index and face (face 0 = unusable).
    var index: array<u32, 8>;
    var ids: array<u32, 8>;
    var depths: array<f32, 8>;
    for (var k = 0u; k < 8u; k++) {
        ids[k] = 0u;
        let q = p + RING[k];
        if q.x < 0 || q.y < 0 || q.x >= i32(params.width) || q.y >= i32(params.height) {
            continue;
        }
        let j = u32(q.y) * params.width + u32(q.x);
        if (atomicLoad(&flags[j]) & CRACK) != 0u {
            continue;
        }
        index[k] = j;
        ids[k] = face[j];
        depths[k] = depth[j];
    }

    // B_p: most neighbours, then nearest mean depth, then smallest id.
    var best_id = 0u;
    var best_count = 0u;
    var best_mean = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let id = ids[k];
        if id == 0u {
            continue;
        }
        var count = 0u;
        var sum = 0.0;
        for (var m = 0u; m < 8u; m++) {
            if ids[m] == id {
                count += 1u;
                sum += depths[m];
            }
        }
        let mean = sum / f32(count);
        let better = best_id == 0u || count > best_count
            || (count == best_count && (mean < best_mean || (mean == best_mean && id < best_id)));
        if better {
            best_id = id;
            best_count = count;
            best_mean = mean;
        }
    }
    if best_id == 0u {
        return;
    }

    // Average colour of B_p's neighbours; (u, v) of the nearest of them.
    var rgba = vec4<f32>(0.0);
    var nearest = 0u;
    var nearest_depth = 0.0;
    var found = false;
    for (var k = 0u; k < 8u; k++) {
        if ids[k] != best_id {
            continue;
        }
        rgba += unpack4x8unorm(color[index[k]]);
        if !found || depths[k] < nearest_depth {
            found = true;
            nearest = index[k];
            nearest_depth = depths[k];
        }
    }
    color[i] = pack4x8unorm(rgba / f32(best_count));
    depth[i] = best_mean;
    face[i] = best_id;
    uv[i] = uv[nearest];
    atomicOr(&flags[i], FILLED);
}
