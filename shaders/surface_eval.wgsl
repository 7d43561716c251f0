// Face basis surfaces on the GPU (issue 21 step 2): S(u, v) with ∂S/∂u and ∂S/∂v for the 8
// surface kinds of `tessd_brep::Surface`, read from the flat pack of
// `tessd_render::surface_pack::SurfacePack` (its module documentation gives the word layouts).
// It is `tessd_brep`'s f64 evaluation (`Surface::eval`, `KnotVector::basis`, `eval_curve`,
// `eval_surface`) transcribed to f32: the same formulas, the same B-spline span search and
// Cox–de Boor recurrence over the same flat (periodic: unrolled) knot vectors. Positions come
// out relative to the pack's scene origin. Ray casting (paper 001 §3.4.2.a, §4.1.2) builds on it.
//
// A library, not a pass: the including shader (the Rust side concatenates the sources)
// declares, at bindings of its choosing:
//   var<storage, read> surf_headers: array<SurfaceHeader>;
//   var<storage, read> surf_words: array<f32>;

// `tessd_render::surface_pack::SurfaceHeader` (32 bytes).
struct SurfaceHeader {
    kind: u32,
    offset: u32,
    flags: u32,
    words: u32,
    // [u0, u1, v0, v1]: the patch rectangle (s, t) ∈ [0, 1]² is normalised over.
    bounds: vec4<f32>,
}

// A surface point with its first partial derivatives.
struct SurfaceSample {
    p: vec3<f32>,
    du: vec3<f32>,
    dv: vec3<f32>,
}

const SURF_PLANE: u32 = 0u;
const SURF_CYLINDER: u32 = 1u;
const SURF_CONE: u32 = 2u;
const SURF_SPHERE: u32 = 3u;
const SURF_TORUS: u32 = 4u;
const SURF_REVOLUTION: u32 = 5u;
const SURF_EXTRUSION: u32 = 6u;
const SURF_BSPLINE: u32 = 7u;
const SURF_CURVE_LINE: u32 = 0u;
const SURF_CURVE_CIRCLE: u32 = 1u;
const SURF_CURVE_ELLIPSE: u32 = 2u;
const SURF_FLAG_REVERSED: u32 = 1u;

// `tessd_brep::bspline::MAX_DEGREE` + 1: the non-zero basis functions at a parameter.
const SURF_MAX_ORDER: u32 = 26u;

fn surf_w(i: u32) -> f32 {
    return surf_words[i];
}

fn surf_u(i: u32) -> u32 {
    return u32(surf_words[i]);
}

fn surf_v3(i: u32) -> vec3<f32> {
    return vec3<f32>(surf_words[i], surf_words[i + 1u], surf_words[i + 2u]);
}

// The non-zero basis functions of a B-spline at a parameter and their derivatives
// (`tessd_brep::bspline::Basis`); `first` is already reduced modulo `poles` when periodic.
struct SurfBasis {
    first: u32,
    values: array<f32, SURF_MAX_ORDER>,
    derivs: array<f32, SURF_MAX_ORDER>,
}

// A flat knot vector in the words: `len` knots from `knots`, degree `p`, `poles` poles, the
// domain [d0, d1] (one period when periodic).
struct SurfKnots {
    knots: u32,
    len: u32,
    p: u32,
    poles: u32,
    periodic: bool,
    d0: f32,
    d1: f32,
}

// Pole index of the k-th non-zero function.
fn surf_pole(kv: SurfKnots, b: SurfBasis, k: u32) -> u32 {
    if kv.periodic {
        return (b.first + k) % max(kv.poles, 1u);
    }
    return b.first + k;
}

// `KnotVector::basis`: the span s with flat[s] ≤ t < flat[s+1] (the parameter wrapped into
// the period when periodic, end spans extended outside a non-periodic domain), then
// Cox–de Boor for the values and the degree-(p−1) functions for the derivatives.
fn surf_basis(kv: SurfKnots, t0: f32) -> SurfBasis {
    let p = kv.p;
    var t = t0;
    if kv.periodic {
        let len = kv.d1 - kv.d0;
        let x = t - kv.d0;
        var r = x - len * floor(x / len);
        if r >= len {
            r -= len;
        }
        t = kv.d0 + max(r, 0.0);
    }
    // partition_point(k ≤ t) by bisection.
    var lo = 0u;
    var hi = kv.len;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if surf_w(kv.knots + mid) <= t {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    var s = select(0u, lo - 1u, lo > 0u);
    s = clamp(s, p, kv.len - p - 2u);
    while s > p && surf_w(kv.knots + s) >= surf_w(kv.knots + s + 1u) {
        s -= 1u;
    }

    var b: SurfBasis;
    var prev: array<f32, SURF_MAX_ORDER>;
    var left: array<f32, SURF_MAX_ORDER>;
    var right: array<f32, SURF_MAX_ORDER>;
    b.values[0] = 1.0;
    for (var j = 1u; j <= p; j += 1u) {
        if j == p {
            for (var r = 0u; r < p; r += 1u) {
                prev[r] = b.values[r];
            }
        }
        left[j] = t - surf_w(kv.knots + s + 1u - j);
        right[j] = surf_w(kv.knots + s + j) - t;
        var saved = 0.0;
        for (var r = 0u; r < j; r += 1u) {
            let temp = b.values[r] / (right[r + 1u] + left[j - r]);
            b.values[r] = saved + right[r + 1u] * temp;
            saved = left[j - r] * temp;
        }
        b.values[j] = saved;
    }
    // N'_{i,p} = p (N_{i,p−1} / (k[i+p] − k[i]) − N_{i+1,p−1} / (k[i+p+1] − k[i+1])).
    let first = s - p;
    for (var r = 0u; r <= p; r += 1u) {
        let i = kv.knots + first + r;
        var v = 0.0;
        if r >= 1u {
            let den = surf_w(i + p) - surf_w(i);
            if den > 0.0 {
                v += prev[r - 1u] / den;
            }
        }
        if r < p {
            let den = surf_w(i + p + 1u) - surf_w(i + 1u);
            if den > 0.0 {
                v -= prev[r] / den;
            }
        }
        b.derivs[r] = f32(p) * v;
    }
    b.first = first;
    if kv.periodic {
        b.first = first % max(kv.poles, 1u);
    }
    return b;
}

// A curve point and its derivative.
struct SurfCurveSample {
    p: vec3<f32>,
    d: vec3<f32>,
}

// The curve record at word `c` at parameter t (`Curve::eval`, `eval_curve`).
fn surf_curve(c: u32, t: f32) -> SurfCurveSample {
    let kind = surf_u(c);
    let ct = cos(t);
    let st = sin(t);
    if kind == SURF_CURVE_LINE {
        let d = surf_v3(c + 4u);
        return SurfCurveSample(surf_v3(c + 1u) + t * d, d);
    }
    if kind == SURF_CURVE_CIRCLE || kind == SURF_CURVE_ELLIPSE {
        let x = surf_v3(c + 4u);
        let y = surf_v3(c + 7u);
        let a = surf_w(c + 10u);
        let b = select(a, surf_w(c + 11u), kind == SURF_CURVE_ELLIPSE);
        return SurfCurveSample(surf_v3(c + 1u) + a * ct * x + b * st * y, -a * st * x + b * ct * y);
    }
    // B-spline: kind p n periodic rational len t0 t1, knots, poles, weights.
    let n = surf_u(c + 2u);
    let len = surf_u(c + 5u);
    let kv = SurfKnots(c + 8u, len, surf_u(c + 1u), n, surf_u(c + 3u) != 0u, surf_w(c + 6u), surf_w(c + 7u));
    let rational = surf_u(c + 4u) != 0u;
    let poles = c + 8u + len;
    let weights = poles + 3u * n;
    let b = surf_basis(kv, t);
    var a = vec3<f32>(0.0);
    var da = vec3<f32>(0.0);
    var w = 0.0;
    var dw = 0.0;
    for (var k = 0u; k <= kv.p; k += 1u) {
        let i = surf_pole(kv, b, k);
        let wi = select(1.0, surf_w(weights + i), rational);
        let pi = surf_v3(poles + 3u * i);
        a += pi * (b.values[k] * wi);
        da += pi * (b.derivs[k] * wi);
        w += b.values[k] * wi;
        dw += b.derivs[k] * wi;
    }
    let cp = a / w;
    return SurfCurveSample(cp, (da - cp * dw) / w);
}

// The rational tensor-product B-spline at word `o` (`eval_surface`).
fn surf_bspline(o: u32, uv: vec2<f32>) -> SurfaceSample {
    let nu = surf_u(o + 2u);
    let nv = surf_u(o + 3u);
    let len_u = surf_u(o + 7u);
    let len_v = surf_u(o + 8u);
    let ku = SurfKnots(o + 13u, len_u, surf_u(o), nu, surf_u(o + 4u) != 0u, surf_w(o + 9u), surf_w(o + 10u));
    let kv = SurfKnots(o + 13u + len_u, len_v, surf_u(o + 1u), nv, surf_u(o + 5u) != 0u, surf_w(o + 11u), surf_w(o + 12u));
    let rational = surf_u(o + 6u) != 0u;
    let poles = o + 13u + len_u + len_v;
    let weights = poles + 3u * nu * nv;
    let bu = surf_basis(ku, uv.x);
    let bv = surf_basis(kv, uv.y);
    var a = vec3<f32>(0.0);
    var au = vec3<f32>(0.0);
    var av = vec3<f32>(0.0);
    var w = 0.0;
    var wu = 0.0;
    var wv = 0.0;
    for (var ki = 0u; ki <= ku.p; ki += 1u) {
        let i = surf_pole(ku, bu, ki);
        for (var kj = 0u; kj <= kv.p; kj += 1u) {
            let j = surf_pole(kv, bv, kj);
            let ij = i * nv + j;
            let wij = select(1.0, surf_w(weights + ij), rational);
            let p = surf_v3(poles + 3u * ij);
            let n = bu.values[ki] * bv.values[kj] * wij;
            let n_u = bu.derivs[ki] * bv.values[kj] * wij;
            let n_v = bu.values[ki] * bv.derivs[kj] * wij;
            a += p * n;
            au += p * n_u;
            av += p * n_v;
            w += n;
            wu += n_u;
            wv += n_v;
        }
    }
    let s = a / w;
    return SurfaceSample(s, (au - s * wu) / w, (av - s * wv) / w);
}

// S(u, v), ∂S/∂u, ∂S/∂v of face `face`'s basis surface at native (u, v) (not patch (s, t)),
// relative to the scene origin. Zero for a surface packed as invalid.
fn surface_eval(face: u32, uv: vec2<f32>) -> SurfaceSample {
    let h = surf_headers[face];
    let o = h.offset;
    let u = uv.x;
    let v = uv.y;
    switch h.kind {
        case 0u: {
            let x = surf_v3(o + 3u);
            let y = surf_v3(o + 6u);
            return SurfaceSample(surf_v3(o) + u * x + v * y, x, y);
        }
        case 1u, 2u, 3u, 4u: {
            // The rotational quadrics: e(u) = cos u·x + sin u·y swept about z.
            let org = surf_v3(o);
            let x = surf_v3(o + 3u);
            let y = surf_v3(o + 6u);
            let z = surf_v3(o + 9u);
            let e = cos(u) * x + sin(u) * y;
            let de = -sin(u) * x + cos(u) * y;
            let r = surf_w(o + 12u);
            if h.kind == SURF_CYLINDER {
                return SurfaceSample(org + r * e + v * z, r * de, z);
            }
            if h.kind == SURF_CONE {
                let sa = surf_w(o + 13u);
                let ca = surf_w(o + 14u);
                let rv = r + v * sa;
                return SurfaceSample(org + rv * e + (v * ca) * z, rv * de, sa * e + ca * z);
            }
            let cv = cos(v);
            let sv = sin(v);
            if h.kind == SURF_SPHERE {
                return SurfaceSample(org + (r * cv) * e + (r * sv) * z, (r * cv) * de, (-r * sv) * e + (r * cv) * z);
            }
            let minor = surf_w(o + 13u);
            let rv = r + minor * cv;
            return SurfaceSample(org + rv * e + (minor * sv) * z, rv * de, (-minor * sv) * e + (minor * cv) * z);
        }
        case 5u: {
            // Rodrigues: R(u)q = q cos u + (a × q) sin u + a (a·q)(1 − cos u).
            let ao = surf_v3(o);
            let a = surf_v3(o + 3u);
            let c = surf_curve(o + 6u, v);
            let q = c.p - ao;
            let cu = cos(u);
            let su = sin(u);
            let aq = dot(a, q);
            let p = ao + cu * q + su * cross(a, q) + (aq * (1.0 - cu)) * a;
            let du = -su * q + cu * cross(a, q) + (aq * su) * a;
            let dv = cu * c.d + su * cross(a, c.d) + (dot(a, c.d) * (1.0 - cu)) * a;
            return SurfaceSample(p, du, dv);
        }
        case 6u: {
            let d = surf_v3(o);
            let c = surf_curve(o + 3u, u);
            return SurfaceSample(c.p + v * d, c.d, d);
        }
        case 7u: {
            return surf_bspline(o, uv);
        }
        default: {
            // An invalid surface: no point, no derivatives (Newton finds it singular).
            return SurfaceSample(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
        }
    }
}

// The face's unit normal at a sample: ∂S/∂u × ∂S/∂v normalised, negated for a reversed face.
// Where the cross product vanishes (a sphere's pole, a cone's apex, a collapsed B-spline
// edge) the fallback is, for a sphere, the outward radial direction (as `Surface::normal`),
// otherwise the direction of the derivative that survives crossed with any axis it is not
// parallel to — some unit vector, since shading only needs one there.
fn surface_normal(face: u32, s: SurfaceSample) -> vec3<f32> {
    let h = surf_headers[face];
    var n = cross(s.du, s.dv);
    let len = length(n);
    let scale = length(s.du) * length(s.dv);
    if !(len > 1e-7 * scale && len > 0.0) {
        if h.kind == SURF_SPHERE {
            n = s.p - surf_v3(h.offset);
        } else {
            var d = s.du;
            if dot(s.dv, s.dv) > dot(d, d) {
                d = s.dv;
            }
            var axis = vec3<f32>(1.0, 0.0, 0.0);
            if abs(d.x) > abs(d.y) || abs(d.x) > abs(d.z) {
                axis = vec3<f32>(0.0, 1.0, 0.0);
            }
            n = cross(d, axis);
            if dot(n, n) == 0.0 {
                n = vec3<f32>(0.0, 0.0, 1.0);
            }
        }
    }
    n = normalize(n);
    if (h.flags & SURF_FLAG_REVERSED) != 0u {
        n = -n;
    }
    return n;
}

// Patch (s, t) ∈ [0, 1]² of `face` to native (u, v): u = u0 + s·(u1 − u0), v = v0 + t·(v1 − v0).
fn patch_to_uv(face: u32, st: vec2<f32>) -> vec2<f32> {
    let b = surf_headers[face].bounds;
    return vec2<f32>(b.x + st.x * (b.y - b.x), b.z + st.y * (b.w - b.z));
}

// Native (u, v) of `face` to patch (s, t) (0 along a direction of zero extent).
fn uv_to_patch(face: u32, uv: vec2<f32>) -> vec2<f32> {
    let b = surf_headers[face].bounds;
    let eu = b.y - b.x;
    let ev = b.w - b.z;
    return vec2<f32>(select(0.0, (uv.x - b.x) / eu, eu != 0.0), select(0.0, (uv.y - b.z) / ev, ev != 0.0));
}
