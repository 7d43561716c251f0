//! From the world tolerance ε to a tolerance in the parameter plane (paper 000, section 3.1:
//! "an approximation error expressed in parameter space, computed from ε").
//!
//! A parameter-plane displacement δ = (δu, δv) moves the surface point by
//! `S(p + δ) − S(p) = ∫₀¹ J(p + τδ) δ dτ`, J = [∂S/∂u ∂S/∂v] the 3 × 2 Jacobian, so
//! `|S(p + δ) − S(p)| ≤ σ |δ|` with σ a bound of J's largest singular value (its operator
//! norm, `√λmax(JᵀJ)`) over the face. A trim approximation within `ε_uv = ε / σ` in (u, v)
//! therefore stays within ε in the world. What must not happen is an *under*estimate of σ
//! (an over-estimated ε_uv): that is a place where the parametrisation is locally stretched
//! and no sample sees it.
//!
//! σ is estimated from samples of J, times a safety factor for what lies between them:
//!
//! - a [`GRID`] × [`GRID`] grid over the face's bounds, which is all a smooth analytic
//!   surface (plane, cylinder, cone, sphere, torus) needs;
//! - where the parametrisation is piecewise (a B-spline surface, or an extrusion or
//!   revolution of a B-spline curve), [`PER_SPAN`] parameters in every knot span that meets
//!   the bounds, in each direction with more than one span. Clustered knots make short spans
//!   in which the surface can move many times faster than anywhere the grid looks (a bicubic
//!   patch with knots 0, 0.001, 0.002, 0.5, 1 passes three poles within 0.002 of u); a span
//!   is where J is one polynomial, so a few samples per span follow it, wherever it is.
//!
//! The samples are capped at [`MAX_SAMPLES`] per face ([`SamplePlan`]): the full product of
//! the grid-and-span parameters in u and v when it fits, else the span parameters of one
//! direction along the grid lines of the other, with fewer per span, and past that only the
//! shortest spans (relative to the bounds), the ones clustered knots make.
//!
//! Why samples rather than a bound from the derivative control net: for a polynomial
//! B-spline, the hodograph's poles `p (P[i+1] − P[i]) / (t[i+p+1] − t[i+1])` bound |∂S/∂u|
//! from above (convex hull), and with |∂S/∂v|'s the largest singular value by
//! `√(Mu² + Mv²)` — a guaranteed bound, in the right direction. But it holds for polynomial
//! surfaces only (rational ones, CAD's exact conics and surfaces of revolution among them,
//! need a factor from the spread of the weights on top), the net overstates the derivatives
//! wherever the poles are uneven, and the hypotenuse gives back the factor √2 the singular
//! value removed (see below): ε_uv smaller by √2 on a uniform patch and more on uneven ones,
//! for more pieces and slower builds everywhere, to guard against what sampling per span
//! already sees. Samples are an estimate: a
//! polynomial of degree p on a span can peak between p + 1 samples by its Lebesgue constant
//! (1.63 for a cubic's 4 equispaced samples), so a peak in the middle of a span, on a patch
//! whose derivatives vary at full degree, can exceed [`SAFETY`]; peaks at knots (clustered
//! knots, corners) are sampled, the span ends being samples.
//!
//! (An earlier bound, `√(Mu² + Mv²)` with Mu, Mv the largest |∂S/∂u|, |∂S/∂v|, is also an upper
//! bound of |J δ| / |δ| but never a smaller one, by √2 on a plane or any surface with
//! orthogonal, equally fast directions: a looser tolerance now gives fewer pieces for the
//! same world guarantee.)

use tessd_brep::{Curve, DVec3, Face, Surface};

/// Grid points per direction when bounding the derivatives.
pub const GRID: usize = 17;

/// The factor applied to the sampled maxima for the variation between samples.
pub const SAFETY: f64 = 1.25;

/// The most samples per knot span and direction (the span's two ends, just inside, and
/// evenly between them).
pub const PER_SPAN: usize = 4;

/// The most surface evaluations of one face's estimate (the grid's 289 included).
pub const MAX_SAMPLES: usize = 4096;

/// How far inside its span a span sample at an end is put, relative to the span: the
/// one-sided limit of J there, also at a corner (a knot of full multiplicity), where the two
/// sides differ.
const END_INSET: f64 = 1e-7;

/// The parameter-plane tolerance of one face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTolerance {
    /// The world tolerance it came from.
    pub eps_world: f64,
    /// The bound of |∂S/∂u| over the bounds (safety factor included).
    pub max_du: f64,
    /// The bound of |∂S/∂v| over the bounds (safety factor included).
    pub max_dv: f64,
    /// The bound σ of the Jacobian's largest singular value over the bounds (safety factor
    /// included): `|S(p + δ) − S(p)| ≤ σ |δ|`.
    pub max_stretch: f64,
    /// `ε / σ`: the largest (u, v) distance allowed between a trim and its approximation.
    pub eps_uv: f64,
    /// The surface evaluations the estimate took.
    pub samples: usize,
}

/// The (u, v) tolerance of `face` for the world tolerance `eps_world`, σ sampled on the grid
/// and in every knot span ([`SamplePlan::of`]). Where the derivatives are not finite or
/// vanish everywhere (a degenerate surface) the derivative bound is taken as 1, and the
/// result is kept above 1e-9 of the bounds' size so fitting terminates.
pub fn uv_tolerance(face: &Face, eps_world: f64) -> UvTolerance {
    estimate(face, eps_world, &SamplePlan::of(face))
}

/// The estimate on the [`GRID`] × [`GRID`] grid alone, blind to knot spans: what
/// [`uv_tolerance`] was before spans were sampled, kept to compare with (it over-estimates
/// ε_uv on B-splines with clustered knots).
pub fn grid_uv_tolerance(face: &Face, eps_world: f64) -> UvTolerance {
    estimate(face, eps_world, &SamplePlan::grid(face))
}

fn estimate(face: &Face, eps_world: f64, plan: &SamplePlan) -> UvTolerance {
    let [u0, u1, v0, v1] = face.bounds;
    let mut mu: f64 = 0.0;
    let mut mv: f64 = 0.0;
    let mut ms: f64 = 0.0;
    let mut samples = 0;
    plan.for_each(|u, v| {
        samples += 1;
        let sp = face.surface.eval(u, v);
        let (a, b) = (sp.du.length(), sp.dv.length());
        if a.is_finite() {
            mu = mu.max(a);
        }
        if b.is_finite() {
            mv = mv.max(b);
        }
        let s = largest_singular_value(sp.du, sp.dv);
        if s.is_finite() {
            ms = ms.max(s);
        }
    });
    let (mu, mv, ms) = (mu * SAFETY, mv * SAFETY, ms * SAFETY);
    let m = if ms > 0.0 && ms.is_finite() { ms } else { 1.0 };
    let size = (u1 - u0).hypot(v1 - v0);
    UvTolerance {
        eps_world,
        max_du: mu,
        max_dv: mv,
        max_stretch: ms,
        eps_uv: (eps_world / m).max(size * 1e-9),
        samples,
    }
}

/// Where J is sampled: parameters in u and v, each the grid's (`grid_*`) or the knot spans'
/// (`span_*`), and how they are combined.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplePlan {
    /// The grid's u parameters.
    pub grid_u: Vec<f64>,
    /// The grid's v parameters.
    pub grid_v: Vec<f64>,
    /// The span samples in u.
    pub span_u: Vec<f64>,
    /// The span samples in v.
    pub span_v: Vec<f64>,
    /// Every (u, v) of (grid ∪ span) in u × (grid ∪ span) in v when true; else the span
    /// parameters of each direction along the other's grid lines, and the grid.
    pub product: bool,
}

impl SamplePlan {
    /// The grid alone.
    pub fn grid(face: &Face) -> SamplePlan {
        let [u0, u1, v0, v1] = face.bounds;
        let line = |a: f64, b: f64| -> Vec<f64> {
            (0..GRID)
                .map(|i| a + (b - a) * i as f64 / (GRID - 1) as f64)
                .collect()
        };
        SamplePlan {
            grid_u: line(u0, u1),
            grid_v: line(v0, v1),
            span_u: Vec::new(),
            span_v: Vec::new(),
            product: true,
        }
    }

    /// The grid and the knot spans of `face`'s surface within its bounds, within
    /// [`MAX_SAMPLES`]: the product with [`PER_SPAN`] (then 3) samples per span if it fits,
    /// else the lines with 4, 3 or 2 per span, else the lines through the two ends of the
    /// shortest spans (relative to the bounds' side), as many as fit.
    pub fn of(face: &Face) -> SamplePlan {
        let mut plan = SamplePlan::grid(face);
        let [u0, u1, v0, v1] = face.bounds;
        let (ku, kv) = knot_lines(&face.surface);
        let su = spans(ku, u0, u1);
        let sv = spans(kv, v0, v1);
        if su.is_empty() && sv.is_empty() {
            return plan;
        }
        let g = GRID;
        let layouts = [(true, 4), (true, 3), (false, 4), (false, 3), (false, 2)];
        for (product, k) in layouts {
            let k = k.min(PER_SPAN);
            let (nu, nv) = (su.len() * k, sv.len() * k);
            let count = if product {
                (g + nu) * (g + nv)
            } else {
                g * g + g * (nu + nv)
            };
            if count <= MAX_SAMPLES {
                plan.span_u = samples_in(&su, k);
                plan.span_v = samples_in(&sv, k);
                plan.product = product;
                return plan;
            }
        }
        // The shortest spans first, relative to their side, two samples each, along lines.
        let room = (MAX_SAMPLES - g * g) / (2 * g);
        let mut all: Vec<(f64, bool, [f64; 2])> = su
            .iter()
            .map(|&s| ((s[1] - s[0]) / (u1 - u0), true, s))
            .chain(sv.iter().map(|&s| ((s[1] - s[0]) / (v1 - v0), false, s)))
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        all.truncate(room);
        let pick = |in_u: bool| -> Vec<[f64; 2]> {
            all.iter().filter(|s| s.1 == in_u).map(|s| s.2).collect()
        };
        plan.span_u = samples_in(&pick(true), 2);
        plan.span_v = samples_in(&pick(false), 2);
        plan.product = false;
        plan
    }

    /// The number of (u, v) samples.
    pub fn len(&self) -> usize {
        let mut n = 0;
        self.for_each(|_, _| n += 1);
        n
    }

    /// Whether there is no sample (never: the grid is always there).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Calls `f` on every sample.
    pub fn for_each(&self, mut f: impl FnMut(f64, f64)) {
        if self.product {
            for &u in self.grid_u.iter().chain(&self.span_u) {
                for &v in self.grid_v.iter().chain(&self.span_v) {
                    f(u, v);
                }
            }
            return;
        }
        for &u in self.grid_u.iter().chain(&self.span_u) {
            for &v in &self.grid_v {
                f(u, v);
            }
        }
        for &v in &self.span_v {
            for &u in &self.grid_u {
                f(u, v);
            }
        }
    }
}

/// The distinct knots of a piecewise parametrisation in u and in v, and whether each is
/// periodic (`None`: one piece, smooth throughout).
type KnotLine<'a> = Option<(&'a [f64], bool)>;

fn knot_lines(surface: &Surface) -> (KnotLine<'_>, KnotLine<'_>) {
    match surface {
        Surface::Bspline(b) => (
            Some((b.knots_u.as_slice(), b.periodic_u)),
            Some((b.knots_v.as_slice(), b.periodic_v)),
        ),
        Surface::Extrusion { curve, .. } => (curve_knots(curve), None),
        Surface::Revolution { curve, .. } => (None, curve_knots(curve)),
        _ => (None, None),
    }
}

fn curve_knots(curve: &Curve<DVec3>) -> KnotLine<'_> {
    match curve {
        Curve::Bspline(b) => Some((b.knots.as_slice(), b.periodic)),
        _ => None,
    }
}

/// The knot spans `[a, b]` that meet `[lo, hi]`, clipped to it; empty when the range lies in
/// a single span (nothing the grid does not already see). Periodic knots repeat with the
/// period (at most 64 periods are unrolled: bounds are a period or so in practice).
fn spans(knots: KnotLine<'_>, lo: f64, hi: f64) -> Vec<[f64; 2]> {
    let Some((knots, periodic)) = knots else {
        return Vec::new();
    };
    let (Some(&first), Some(&last)) = (knots.first(), knots.last()) else {
        return Vec::new();
    };
    let period = last - first;
    let inside = |k: f64| k > lo && k < hi && k.is_finite();
    let mut cuts: Vec<f64> = if periodic && period > 0.0 && period.is_finite() {
        let n0 = ((lo - first) / period).floor().max(-1e6) as i64;
        let n1 = ((hi - first) / period).ceil().min(1e6) as i64;
        let n1 = n1.min(n0 + 64);
        (n0..=n1)
            .flat_map(|n| knots.iter().map(move |&k| k + n as f64 * period))
            .filter(|&k| inside(k))
            .collect()
    } else {
        knots.iter().copied().filter(|&k| inside(k)).collect()
    };
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    if cuts.is_empty() {
        return Vec::new();
    }
    let mut ends = vec![lo];
    ends.extend(cuts);
    ends.push(hi);
    ends.windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| [w[0], w[1]])
        .collect()
}

/// `k` parameters in each span: its ends (just inside, [`END_INSET`]) and evenly between
/// them; the middle for `k` = 1.
fn samples_in(spans: &[[f64; 2]], k: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(spans.len() * k);
    for &[a, b] in spans {
        if k == 1 {
            out.push(0.5 * (a + b));
            continue;
        }
        for i in 0..k {
            let f = (i as f64 / (k - 1) as f64).clamp(END_INSET, 1.0 - END_INSET);
            out.push(a + (b - a) * f);
        }
    }
    out
}

/// The largest singular value of the 3 × 2 matrix [a b]: `√λmax` of the Gram matrix
/// `[[a·a, a·b], [a·b, b·b]]`, `λmax = (E + G) / 2 + √(((E − G) / 2)² + F²)`. Rounded up
/// by a few ulps, so that it never falls below |a| or |b| by rounding.
pub fn largest_singular_value(a: DVec3, b: DVec3) -> f64 {
    let (e, f, g) = (a.dot(a), a.dot(b), b.dot(b));
    let half = 0.5 * (e - g);
    let lambda = 0.5 * (e + g) + half.hypot(f);
    lambda.sqrt() * (1.0 + 8.0 * f64::EPSILON)
}
