// Apply phase of subdivision stencil tables (core/subdiv/src/stencil.rs, run by core/gpu).
//
// One invocation makes one refined row: dst[row] = Σ weights[k] · src[sources[k]] for k in
// offsets[row]..offsets[row + 1], rows being `stride` floats. Each component is summed in f32
// starting from 0 and adding the terms in row order, the same order as the CPU
// `StencilTable::apply`, so both agree to rounding.
//
// The grid may be 2-D (when rows / 64 exceeds max_compute_workgroups_per_dimension): the row
// is then gid.y * row_pitch + gid.x, with row_pitch = workgroups in x * 64.

struct Params {
    // Rows of the refined level (invocations past it do nothing).
    rows: u32,
    // Floats per row.
    stride: u32,
    // Invocations per grid row in x (workgroups in x * 64).
    row_pitch: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> offsets: array<u32>;
@group(0) @binding(2) var<storage, read> sources: array<u32>;
@group(0) @binding(3) var<storage, read> weights: array<f32>;
@group(0) @binding(4) var<storage, read> src: array<f32>;
@group(0) @binding(5) var<storage, read_write> dst: array<f32>;

// Components summed per pass over the row's terms: a private accumulator block, so the
// terms (source index and weight) are read once per block instead of once per component.
const BLOCK: u32 = 8u;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let row = gid.y * params.row_pitch + gid.x;
    if (row >= params.rows) {
        return;
    }
    let stride = params.stride;
    let begin = offsets[row];
    let end = offsets[row + 1u];
    let out = row * stride;

    for (var c0 = 0u; c0 < stride; c0 += BLOCK) {
        let n = min(BLOCK, stride - c0);
        var acc: array<f32, 8>;
        for (var j = 0u; j < BLOCK; j++) {
            acc[j] = 0.0;
        }
        for (var k = begin; k < end; k++) {
            let w = weights[k];
            let base = sources[k] * stride + c0;
            for (var j = 0u; j < n; j++) {
                acc[j] = acc[j] + w * src[base + j];
            }
        }
        for (var j = 0u; j < n; j++) {
            dst[out + c0 + j] = acc[j];
        }
    }
}
