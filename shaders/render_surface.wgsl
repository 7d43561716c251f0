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
    // 1: overlay triangle edges.
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

// A well-mixed 32-bit hash, so neighbouring ids get unrelated colours.
fn hash(x0: u32) -> u32 {
    var x = x0;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

fn hsv(h: f32, s: f32, v: f32) -> vec3<f32> {
    let k = vec3<f32>(1.0, 2.0 / 3.0, 1.0 / 3.0);
    let p = abs(fract(vec3<f32>(h) + k) * 6.0 - 3.0);
    return v * mix(vec3<f32>(1.0), clamp(p - 1.0, vec3<f32>(0.0), vec3<f32>(1.0)), s);
}

// A distinct colour per face id: hue from the hash, saturation and value in bands.
fn id_color(id: u32) -> vec3<f32> {
    let h = hash(id);
    let hue = f32(h & 0xffffu) / 65536.0;
    let s = 0.45 + 0.4 * f32((h >> 16u) & 3u) / 3.0;
    let v = 0.7 + 0.25 * f32((h >> 18u) & 3u) / 3.0;
    return hsv(hue, s, v);
}

const BASE: vec3<f32> = vec3<f32>(0.72, 0.76, 0.82);

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
    // Two-sided: the side the eye sees.
    if (dot(n, view) < 0.0) {
        n = -n;
    }
    let l = params.light;
    let diffuse = max(dot(n, l), 0.0);
    let h = normalize(l + view);
    let spec = pow(max(dot(n, h), 0.0), 48.0);

    var color: vec3<f32>;
    switch params.shading {
        case 1u: {
            // Gooch: cool to warm with the light (squared, so that surfaces turned from the
            // key light read cool rather than all warm), a white highlight.
            let cool = vec3<f32>(0.05, 0.15, 0.55) + 0.25 * BASE;
            let warm = vec3<f32>(0.5, 0.42, 0.05) + 0.45 * BASE;
            let t = 0.5 * (1.0 + dot(n, l));
            color = mix(cool, warm, t * t) + 0.3 * spec;
        }
        case 2u: {
            // Toon: four bands, dark rims at grazing angles.
            var band = 0.3;
            if (diffuse > 0.85) {
                band = 1.0;
            } else if (diffuse > 0.45) {
                band = 0.75;
            } else if (diffuse > 0.15) {
                band = 0.5;
            }
            color = BASE * band;
            if (spec > 0.6) {
                color = vec3<f32>(1.0);
            }
            if (dot(n, view) < 0.22) {
                color = vec3<f32>(0.08);
            }
        }
        case 3u: {
            color = id_color(in.face_id);
        }
        default: {
            // Lit: Lambert from a key light, a headlight fill, ambient, Blinn-Phong highlight.
            let fill = 0.25 * max(dot(n, view), 0.0);
            color = BASE * (0.15 + 0.7 * diffuse + fill) + 0.25 * spec;
        }
    }

    if (params.edges != 0u) {
        // Distance to the nearest triangle edge, in pixels: a line about one pixel wide.
        // Faded out on triangles only a few pixels across (a scan's dense mesh would turn
        // solid dark), where the lines would carry no information.
        let d = in.bary / max(bary_w, vec3<f32>(1e-12));
        let e = min(d.x, min(d.y, d.z));
        let small = max(bary_w.x, max(bary_w.y, bary_w.z));
        let a = (1.0 - smoothstep(0.5, 1.5, e)) * (1.0 - smoothstep(0.15, 0.4, small));
        color = mix(color, vec3<f32>(0.08, 0.08, 0.1), 0.85 * a);
    }

    var out: FragmentOut;
    out.color = vec4<f32>(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
    out.face_id = in.face_id;
    out.uv = in.uv;
    return out;
}
