//! Step 5: where the f32 positions are measured from. A mesh's positions are f32, whose
//! spacing grows with the distance from the origin: 0.002 mm at 2·10⁴ mm, a fifth of a
//! 0.01 mm tolerance, so a part far from its model's origin loses the precision it was
//! tessellated to. The tessellation is computed in f64; here its f32 positions get an origin
//! they are written relative to, chosen (with [`Origin::Auto`]) only when the f32 spacing at
//! the part's largest coordinate reaches 1 % of the tolerance ([`SPACING_FRACTION`]), so every
//! part that f32 holds well is left untouched, bit for bit.

/// The f32 spacing, as a fraction of the tolerance, from which positions are shifted (and
/// below which they hold the tolerance well enough to be left as they are).
pub const SPACING_FRACTION: f64 = 0.01;

/// Which origin the f32 positions are relative to.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Origin {
    /// The world origin while f32 holds the part to [`SPACING_FRACTION`] of the tolerance;
    /// else the centre of the part's bounding box, rounded to read well ([`auto_origin`]).
    #[default]
    Auto,
    /// Always the world origin (absolute f32 positions, however coarse).
    None,
    /// This point.
    At([f64; 3]),
}

/// The origin chosen and what f32 makes of the positions, absolute and relative to it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Placement {
    /// The origin the f32 positions are relative to ([0, 0, 0] for none).
    pub origin: [f64; 3],
    /// The largest absolute coordinate of the mesh (0 for an empty mesh).
    pub largest: f64,
    /// The f32 spacing at `largest`: the precision absolute f32 positions would have.
    pub spacing: f64,
    /// The largest coordinate relative to `origin`.
    pub largest_relative: f64,
    /// The f32 spacing at `largest_relative`: the precision of the positions written.
    pub spacing_relative: f64,
}

/// The distance between `x` (as f32) and the next f32 away from zero, in f64.
pub fn f32_spacing(x: f64) -> f64 {
    let f = x.abs() as f32;
    if !f.is_finite() {
        return f64::INFINITY;
    }
    f64::from(f32::from_bits(f.to_bits() + 1)) - f64::from(f)
}

/// The axis-aligned box of `points`, or `None` when there are none (or none finite).
pub fn bounds(points: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
}

/// The largest |coordinate| of the box `(lo, hi)` relative to `origin`.
fn largest(lo: [f64; 3], hi: [f64; 3], origin: [f64; 3]) -> f64 {
    (0..3)
        .map(|k| (lo[k] - origin[k]).abs().max((hi[k] - origin[k]).abs()))
        .fold(0.0, f64::max)
}

/// `x` rounded to a multiple of 10^`k`, as the f64 nearest that decimal (so it prints as
/// one: 20000.05, not 20000.050000000003).
fn round_decimal(x: f64, k: i32) -> f64 {
    if k >= 0 {
        let step = 10f64.powi(k);
        (x / step).round() * step
    } else {
        // 10^-k is exact for -k ≤ 22, so n / 10^-k is the correctly rounded decimal.
        let inv = 10f64.powi(-k);
        (x * inv).round() / inv
    }
}

/// The origin [`Origin::Auto`] picks for a box `(lo, hi)` at `tolerance`: `None` when f32
/// holds the box's largest coordinate to [`SPACING_FRACTION`] × `tolerance`; else the box's
/// centre rounded to a multiple of the largest power of ten not above the box's half-extent
/// (or the tolerance, for a box of no extent), so the positions relative to it stay within
/// 1.5 × the half-extent and the origin reads well (20030, not 20025.3172).
pub fn auto_origin(lo: [f64; 3], hi: [f64; 3], tolerance: f64) -> Option<[f64; 3]> {
    if f32_spacing(largest(lo, hi, [0.0; 3])) < SPACING_FRACTION * tolerance {
        return None;
    }
    let half = (0..3).map(|k| 0.5 * (hi[k] - lo[k])).fold(0.0, f64::max);
    let scale = if half > 0.0 { half } else { tolerance };
    let k = scale.log10().floor().clamp(-22.0, 300.0) as i32;
    Some(std::array::from_fn(|i| {
        round_decimal(0.5 * (lo[i] + hi[i]), k)
    }))
}

/// The placement of `points` (the mesh's absolute f64 positions) that `origin` asks for.
pub fn place(points: &[[f64; 3]], tolerance: f64, origin: Origin) -> Placement {
    let Some((lo, hi)) = bounds(points) else {
        let origin = match origin {
            Origin::At(o) => o,
            _ => [0.0; 3],
        };
        return Placement {
            origin,
            ..Placement::default()
        };
    };
    let origin = match origin {
        Origin::Auto => auto_origin(lo, hi, tolerance).unwrap_or([0.0; 3]),
        Origin::None => [0.0; 3],
        Origin::At(o) => o,
    };
    let (abs, rel) = (largest(lo, hi, [0.0; 3]), largest(lo, hi, origin));
    Placement {
        origin,
        largest: abs,
        spacing: f32_spacing(abs),
        largest_relative: rel,
        spacing_relative: f32_spacing(rel),
    }
}

/// `x` to 2 significant digits, as people write it (2e4, 0.002, 20).
fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let step = 10f64.powi(x.abs().log10().floor() as i32 - 1);
    let r = (x / step).round() * step;
    let e = r.abs().log10().floor() as i32;
    let trim = |s: String| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    if (-3..4).contains(&e) {
        let digits = (1 - e).max(0) as usize;
        trim(format!("{r:.digits$}"))
    } else {
        format!("{}e{e}", trim(format!("{:.1}", r / 10f64.powi(e))))
    }
}

impl Placement {
    /// Whether the positions are shifted (the origin is not [0, 0, 0]).
    pub fn shifted(&self) -> bool {
        self.origin != [0.0; 3]
    }

    /// What a host should know about f32 positions placed so, at `tolerance` (`units` names
    /// the length unit): that they are relative to a shifted origin, or that f32 spacing, where
    /// they are written, is [`SPACING_FRACTION`] of the tolerance or more.
    pub fn warnings(&self, tolerance: f64, units: &str) -> Vec<String> {
        let pct = |s: f64| short(100.0 * s / tolerance);
        let coarse = |s: f64| s >= SPACING_FRACTION * tolerance;
        let origin = self.origin.map(|c| format!("{c}")).join(", ");
        let mut out = Vec::new();
        if self.shifted() && coarse(self.spacing) {
            out.push(format!(
                "positions are up to {} {units} from the world origin: f32 spacing {} {units} \
                 there is {} % of the tolerance; they are written relative to the origin \
                 [{origin}] (result `origin`)",
                short(self.largest),
                short(self.spacing),
                pct(self.spacing)
            ));
        } else if self.shifted() {
            out.push(format!(
                "positions are written relative to the origin [{origin}] (result `origin`)"
            ));
        }
        if coarse(self.spacing_relative) {
            let from = if self.shifted() {
                "that origin"
            } else {
                "the world origin"
            };
            out.push(format!(
                "positions are up to {} {units} from {from}: f32 spacing {} {units} there is \
                 {} % of the tolerance; ask for `positions: \"f64\"`{}",
                short(self.largest_relative),
                short(self.spacing_relative),
                pct(self.spacing_relative),
                if self.shifted() {
                    ""
                } else {
                    " or `origin: \"auto\"`"
                }
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacing_of_f32() {
        assert_eq!(f32_spacing(1.0), f64::from(f32::EPSILON));
        assert_eq!(f32_spacing(-1.0), f64::from(f32::EPSILON));
        // 2e4 lies in [2^14, 2^15): spacing 2^-9 ≈ 0.00195.
        assert_eq!(f32_spacing(2e4), 2f64.powi(-9));
        assert!(f32_spacing(0.0) > 0.0);
    }

    #[test]
    fn auto_origin_only_when_f32_is_coarse() {
        // A 50 mm part near the world origin at 0.01 mm: spacing 3.8e-6 < 1e-4, no shift.
        assert_eq!(auto_origin([0.0; 3], [40.0, 30.0, 10.0], 0.01), None);
        // The same part 2e4 mm away: the centre (20020, 15, 5) rounded to a multiple of 10
        // (the half-extent is 20).
        let o = auto_origin([2e4, 0.0, 0.0], [2e4 + 40.0, 30.0, 10.0], 0.01).unwrap();
        assert_eq!(o, [20020.0, 20.0, 10.0]);
        // A 0.1 mm part there: steps of 0.01, printed as decimals.
        let o = auto_origin([2e4, 0.0, 0.0], [2e4 + 0.1, 0.1, 0.1], 1e-4).unwrap();
        assert_eq!(format!("{}", o[0]), "20000.05");
        // A point: the tolerance sets the step.
        let p = [12345.678, 0.0, 0.0];
        assert_eq!(auto_origin(p, p, 0.01).unwrap()[0], 12345.68);
    }

    #[test]
    fn placement_and_warnings() {
        let pts = [[2e4, 0.0, 0.0], [2e4 + 40.0, 30.0, 10.0]];
        let p = place(&pts, 0.01, Origin::Auto);
        assert_eq!(p.origin, [20020.0, 20.0, 10.0]);
        assert_eq!(p.largest, 2e4 + 40.0);
        assert!(p.largest_relative <= 20.0 + 1e-9);
        let w = p.warnings(0.01, "mm");
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(
            w[0],
            "positions are up to 2e4 mm from the world origin: f32 spacing 0.002 mm there is \
             20 % of the tolerance; they are written relative to the origin [20020, 20, 10] \
             (result `origin`)"
        );
        let none = place(&pts, 0.01, Origin::None);
        assert_eq!(none.origin, [0.0; 3]);
        let w = none.warnings(0.01, "mm");
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("from the world origin") && w[0].contains("`origin: \"auto\"`"));
        let near = place(&[[0.0; 3], [40.0, 30.0, 10.0]], 0.01, Origin::Auto);
        assert_eq!(near.origin, [0.0; 3]);
        assert!(near.warnings(0.01, "mm").is_empty());
        assert_eq!(
            place(&[], 0.01, Origin::At([1.0, 2.0, 3.0])).origin,
            [1.0, 2.0, 3.0]
        );
    }
}
