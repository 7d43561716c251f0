// The surface pass of tessd-render (core/render/src/surface.rs): rasterises triangles into
// the colour target and the metadata targets of paper 001 §3.1 (per pixel the face id and the
// surface's (u, v); depth in the depth target), shading in one of four modes, with an optional
// overlay of the triangle edges drawn from barycentric coordinates (no second pass, so the
// lines can never z-fight with the surface).
//
// Keep `Params` in step with `Params` in surface.rs (96 bytes).

struct Params {
    // Clip space from positions relative to the scene origin; x, y put each pixel's ray of the
    // camera convention (camera.rs) on the pixel's centre.
    clip_from_world: mat4x4<f32>,
    // The eye, relative to the scene origin.
    eye: vec3<f32>,
    // 0 lit, 1 gooch, 2 toon, 3 face-ids.
    shading: u32,
    // Unit vector towards the key light (world).
    light: vec3<f32>,
    // Bit 0: overlay triangle edges. Bits 1-2: the draw mode, 0 solid, 1 wireframe (only
    // the pixels within a pixel of an edge), 2 points (only those within two pixels of a
    // corner): `tessd view`'s `W`.
    edges: u32,
};

@group(0) @binding(0) var<uniform> params: Params;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) face_id: u32,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) bary: vec2<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) face_id: u32,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) bary: vec3<f32>,
};

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) face_id: u32,
    @location(2) uv: vec2<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = params.clip_from_world * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.face_id = v.face_id;
    out.normal = v.normal;
    out.uv = v.uv;
    out.bary = vec3<f32>(v.bary, 1.0 - v.bary.x - v.bary.y);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    // Derivatives first, in uniform control flow.
    let flat_n = cross(dpdx(in.world), dpdy(in.world));
    let bary_w = fwidth(in.bary);

    let view = normalize(params.eye - in.world);
    var n = in.normal;
    if (dot(n, n) < 0.25) {
        n = flat_n;
    }
    n = normalize(n);
    var color = shade(params.shading, in.face_id, n, view, params.light);

    let mode = params.edges >> 1u;
    if (params.edges != 0u) {
        // Distance to the nearest triangle edge, in pixels: a line about one pixel wide.
        // Faded out on triangles only a few pixels across (a scan's dense mesh would turn
        // solid dark), where the lines would carry no information.
        let d = in.bary / max(bary_w, vec3<f32>(1e-12));
        let e = min(d.x, min(d.y, d.z));
        if (mode == 1u && e > 1.0) {
            discard;
        }
        // A corner is where the two other coordinates vanish.
        let corner = min(max(d.y, d.z), min(max(d.x, d.z), max(d.x, d.y)));
        if (mode == 2u && corner > 2.0) {
            discard;
        }
        if ((params.edges & 1u) != 0u && mode == 0u) {
            let small = max(bary_w.x, max(bary_w.y, bary_w.z));
            let a = (1.0 - smoothstep(0.5, 1.5, e)) * (1.0 - smoothstep(0.15, 0.4, small));
            color = mix(color, vec3<f32>(0.08, 0.08, 0.1), 0.85 * a);
        }
    }

    var out: FragmentOut;
    out.color = vec4<f32>(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
    out.face_id = in.face_id;
    out.uv = in.uv;
    return out;
}
