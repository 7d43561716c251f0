// A B-Rep part's buffers (core/render/src/brep_scene.rs, `GpuBrep`) as every B-Rep pass binds
// them: bind group 1, the basis surfaces (shaders/surface_eval.wgsl) and the trim structures
// (shaders/trim_quadtree.wgsl). Concatenated before those libraries.

@group(1) @binding(0) var<storage, read> surf_headers: array<SurfaceHeader>;
@group(1) @binding(1) var<storage, read> surf_words: array<f32>;
@group(1) @binding(2) var<storage, read> trim_headers: array<TrimHeader>;
@group(1) @binding(3) var<storage, read> trim_nodes: array<u32>;
@group(1) @binding(4) var<storage, read> trim_curves: array<f32>;
@group(1) @binding(5) var<storage, read> trim_lines: array<u32>;
