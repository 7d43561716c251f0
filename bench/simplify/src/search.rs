//! Finding the parameter of a method that lands at a target output vertex count.
//!
//! The count is a monotone-ish power of the parameter (about `cell size^-2` for grids and
//! tolerances on a surface, about linear in a target index count), so the search works on
//! `ln parameter` vs `ln count`: a step along an assumed slope until the target is bracketed,
//! then secant steps kept inside the bracket (at least 10 % from either end, so the bracket
//! always shrinks). Counts are steps, so a target can fall between two neighbouring counts;
//! the closest count found is returned either way.

/// The outcome of a search.
#[derive(Clone, Copy, Debug)]
pub struct Found {
    /// The parameter giving `count`.
    pub param: f64,
    /// The closest count found.
    pub count: u64,
    /// Evaluations made.
    pub evals: u32,
    /// Whether `count` is within the tolerance of the target.
    pub hit: bool,
}

/// The accepted distance from `target`: 1 % (at least half a vertex, i.e. exact below 50).
pub fn tolerance(target: u64) -> f64 {
    (0.01 * target as f64).max(0.5)
}

/// Searches `param` in `[lo, hi]`, starting at `p0`, with `slope` the assumed
/// `d ln count / d ln param` (its sign says whether the count grows with the parameter);
/// `integer` parameters are rounded. `f` returns the count for a parameter.
///
/// # Errors
/// The first error of `f`.
#[allow(clippy::too_many_arguments)]
pub fn find(
    target: u64,
    p0: f64,
    slope: f64,
    (lo, hi): (f64, f64),
    integer: bool,
    max_evals: u32,
    mut f: impl FnMut(f64) -> Result<u64, String>,
) -> Result<Found, String> {
    let tol = tolerance(target);
    let lt = (target as f64).ln();
    let inc = slope > 0.0;
    let norm = |p: f64| {
        let p = p.clamp(lo, hi);
        if integer { p.round().max(1.0) } else { p }
    };
    let ln_count = |c: u64| (c as f64).max(0.5).ln();
    let mut best: Option<Found> = None;
    // Bracket: `a` below the target parameter, `b` above (as (ln p, ln count)).
    let mut a: Option<(f64, f64)> = None;
    let mut b: Option<(f64, f64)> = None;
    let mut tried: Vec<f64> = Vec::new();
    let mut last: Option<(f64, f64)> = None;
    let mut prev: Option<(f64, f64)>;
    let mut p = norm(p0);
    let mut evals = 0;
    loop {
        let c = f(p)?;
        evals += 1;
        tried.push(p);
        let err = (c as f64 - target as f64).abs();
        if best.is_none_or(|b| err < (b.count as f64 - target as f64).abs()) {
            best = Some(Found {
                param: p,
                count: c,
                evals,
                hit: err <= tol,
            });
        }
        if err <= tol || evals >= max_evals {
            break;
        }
        let pt = (p.ln(), ln_count(c));
        // Too few vertices: move towards more (larger p if increasing).
        let need_larger = (c < target) == inc;
        if need_larger {
            a = Some(pt);
        } else {
            b = Some(pt);
        }
        prev = last;
        last = Some(pt);
        let x = match (a, b) {
            (Some(a), Some(b)) => {
                let w = b.0 - a.0;
                let x = if (b.1 - a.1).abs() > 1e-12 {
                    a.0 + (lt - a.1) * w / (b.1 - a.1)
                } else {
                    a.0 + 0.5 * w
                };
                x.clamp(a.0 + 0.1 * w, b.0 - 0.1 * w)
            }
            _ => {
                // Slope from the last two points when it has the expected sign.
                let k = match (prev, last) {
                    (Some(q), Some(l)) if (l.0 - q.0).abs() > 1e-12 => {
                        let k = (l.1 - q.1) / (l.0 - q.0);
                        if k * slope > 0.0 { k } else { slope }
                    }
                    _ => slope,
                };
                let step = ((lt - pt.1) / k).clamp(-16f64.ln(), 16f64.ln());
                let step = if need_larger {
                    step.max(0.01)
                } else {
                    step.min(-0.01)
                };
                pt.0 + step
            }
        };
        let mut np = norm(x.exp());
        if integer && tried.contains(&np) {
            np = norm(if need_larger { np + 1.0 } else { np - 1.0 });
        }
        let inside = match (a, b) {
            (Some(a), Some(b)) => np.ln() > a.0 && np.ln() < b.0,
            _ => true,
        };
        let width_ok = match (a, b) {
            (Some(a), Some(b)) => b.0 - a.0 > 1e-9,
            _ => true,
        };
        if tried.contains(&np) || !inside || !width_ok {
            break; // the target falls between two neighbouring counts
        }
        p = np;
    }
    let mut found = best.expect("at least one evaluation");
    found.evals = evals;
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_power_law_and_steps() {
        // count = 1e6 / p^2, continuous.
        let r = find(1234, 0.5, -2.0, (1e-6, 1e3), false, 40, |p| {
            Ok((1e6 / (p * p)) as u64)
        })
        .unwrap();
        assert!(r.hit, "{r:?}");
        // Integer, increasing, coarse steps of 10: 1234 is unreachable, closest is 1230.
        let r = find(1234, 100.0, 1.0, (1.0, 1e6), true, 60, |p| {
            Ok((p as u64 / 10) * 10)
        })
        .unwrap();
        assert!(r.hit, "{r:?}");
        let r = find(1234, 100.0, 1.0, (1.0, 1e6), true, 60, |p| {
            Ok((p as u64 / 100) * 100)
        })
        .unwrap();
        assert_eq!(r.count, 1200, "{r:?}");
        assert!(!r.hit);
    }
}
