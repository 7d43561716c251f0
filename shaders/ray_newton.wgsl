// Ray–surface intersection by Newton iteration (paper 001 §3.4.2.a: "using the surface and
// the u, v coordinate of the incoming fragment as the starting point for successive Newton
// root finding iterations [FP79]", Faux & Pratt, Computational Geometry for Design and
// Manufacture, 1979), from a (u, v) start, on one face's basis surface.
//
// F(u, v, t) = S(u, v) − (origin + t·dir) = 0 is solved with the 3×3 Jacobian
// [∂S/∂u, ∂S/∂v, −dir] by Cramer's rule. The iteration converges when |F| < tol (world
// units); it gives up when the system is singular (a ray grazing the surface, a degenerate
// parametrisation), when (u, v) wanders more than `RAY_NEWTON_MARGIN` of the patch outside
// the face's patch rectangle, after `RAY_NEWTON_ITERATIONS` steps, or when the root lies
// behind the origin (t ≤ 0). Whether the hit is on the trimmed face is the caller's question
// (the trim walk of paper 000 §5, as §3.4.2.a looks the converged (u, v) up in the trim
// structure).
//
// A library: concatenated after surface_eval.wgsl (whose buffers the including shader
// declares).

// The result of `ray_newton`: `hit` when it converged in front of the origin; then `t` is the
// ray parameter (in units of `dir`), `uv` the native (u, v), `s` the surface there (its
// normal shades the hit without another evaluation); `iterations` the Newton steps taken.
struct RayHit {
    hit: bool,
    t: f32,
    uv: vec2<f32>,
    iterations: u32,
    s: SurfaceSample,
}

// The most Newton steps. From a seed cell's centre (ray_cast.wgsl) quadratic convergence
// reaches f32 precision in 4–6 steps; more only lets a diverging start wander.
const RAY_NEWTON_ITERATIONS: u32 = 12u;

// How far (in patch units, a fraction of the patch's extent) (u, v) may leave the patch
// rectangle during the iteration before the start is abandoned.
const RAY_NEWTON_MARGIN: f32 = 0.05;

// Whether patch point `st` is within the margin of [0, 1]².
fn ray_newton_in_patch(st: vec2<f32>) -> bool {
    return all(st >= vec2<f32>(-RAY_NEWTON_MARGIN)) && all(st <= vec2<f32>(1.0 + RAY_NEWTON_MARGIN));
}

// Newton from `uv0` for the intersection of the ray `origin + t·dir` (relative to the scene
// origin, like the surface) with face `face`'s basis surface; converged when |F| < `tol`.
// A step moves (u, v) by at most `max_step.x` of the patch along u and `max_step.y` along v
// (the whole
// step scaled down, a trust region): from a seed cell's centre the iteration stays near the
// cell instead of jumping to another sheet of a strongly curved surface (a thread's flank),
// and the start is abandoned once (u, v) is more than three such steps from it: a root
// farther away belongs to another seed (the ray caster tries every cell its ray crosses), and
// crawling towards it would only cost time.
// The surface is evaluated at one place in the loop only: every call site of `surface_eval`
// is inlined whole by the shader compilers, and on lavapipe (LLVM) each copy costs seconds of
// pipeline compilation.
fn ray_newton(
    face: u32,
    origin: vec3<f32>,
    dir: vec3<f32>,
    uv0: vec2<f32>,
    tol: f32,
    max_step: vec2<f32>,
) -> RayHit {
    var uv = uv0;
    var t = 0.0;
    let c = -dir;
    for (var i = 0u; i <= RAY_NEWTON_ITERATIONS; i += 1u) {
        let s = surface_eval(face, uv);
        if i == 0u {
            // t of the ray point nearest the start point.
            t = dot(s.p - origin, dir) / dot(dir, dir);
        }
        let f = s.p - (origin + t * dir);
        if length(f) < tol {
            let ok = t > 0.0 && ray_newton_in_patch(uv_to_patch(face, uv));
            return RayHit(ok, t, uv, i, s);
        }
        if i == RAY_NEWTON_ITERATIONS {
            break;
        }
        // J·δ = −F, J = [a b c] with a = S_u, b = S_v, c = −dir: Cramer's rule.
        let a = s.du;
        let b = s.dv;
        let bc = cross(b, c);
        let det = dot(a, bc);
        let scale = length(a) * length(b) * length(c);
        if !(abs(det) > 1e-7 * scale) {
            break;
        }
        let r = -f;
        let d_u = dot(r, bc) / det;
        let d_v = dot(a, cross(r, c)) / det;
        let d_t = dot(a, cross(b, r)) / det;
        let pb = surf_headers[face].bounds;
        let extent = max(abs(vec2<f32>(pb.y - pb.x, pb.w - pb.z)), vec2<f32>(1e-30));
        let reach = max(abs(d_u) / (extent.x * max_step.x), abs(d_v) / (extent.y * max_step.y));
        let k = select(1.0, 1.0 / reach, reach > 1.0);
        uv += k * vec2<f32>(d_u, d_v);
        t += k * d_t;
        let travel = abs(uv - uv0) / (extent * max_step);
        if !ray_newton_in_patch(uv_to_patch(face, uv)) || any(travel > vec2<f32>(3.0)) {
            break;
        }
    }
    var none: RayHit;
    none.hit = false;
    none.t = t;
    none.uv = uv;
    none.iterations = RAY_NEWTON_ITERATIONS;
    return none;
}
