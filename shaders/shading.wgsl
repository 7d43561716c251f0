// Shading shared by every pass that colours a surface point (the raster passes, crack
// filling, ray casting): the four modes of `tessd_render::Shading`, so a pixel filled by
// object-space crack filling or ray cast gets the colour the raster pass would give it.
// A library: concatenated before the pass that uses it.

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

// The colour of a surface point seen from direction `view` (unit, towards the eye) with
// unit normal `n0` (either side: the side the eye sees is lit), key light `l` (unit), in mode
// `mode` (0 lit, 1 gooch, 2 toon, 3 face-ids) for face id `face_id`.
fn shade(mode: u32, face_id: u32, n0: vec3<f32>, view: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    var n = n0;
    if (dot(n, view) < 0.0) {
        n = -n;
    }
    let diffuse = max(dot(n, l), 0.0);
    let h = normalize(l + view);
    let spec = pow(max(dot(n, h), 0.0), 48.0);

    var color: vec3<f32>;
    switch mode {
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
            color = id_color(face_id);
        }
        default: {
            // Lit: Lambert from a key light, a headlight fill, ambient, Blinn-Phong highlight.
            let fill = 0.25 * max(dot(n, view), 0.0);
            color = BASE * (0.15 + 0.7 * diffuse + fill) + 0.25 * spec;
        }
    }

    return color;
}
