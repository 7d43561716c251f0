//! The parameter of a method that lands at a target output vertex count (untimed search).

use std::time::{Duration, Instant};

use crate::inputs::Stats;
use crate::methods::{self, Input, Method};
use crate::search;

/// The parameter of `method` on `input` (whose figures are `st`) giving `target` output
/// vertices: the complexity goal takes the count itself; the others are searched
/// ([`search::find`]) from a first guess of the cell size, tolerance or index count. The
/// search gives up after 2 minutes (more above 10 M triangles).
///
/// # Errors
/// The method's error, or the search's deadline.
pub fn find_param(
    method: Method,
    input: &Input,
    st: &Stats,
    target: u64,
) -> Result<search::Found, String> {
    let (p0, slope, range, integer) = match method {
        Method::Complexity(_) => {
            return Ok(search::Found {
                param: target as f64,
                count: 0,
                evals: 0,
                hit: true,
            });
        }
        Method::Grid(_) => (
            (1.5 * st.area / target as f64).sqrt(),
            -2.0,
            (st.size * 1e-6, st.size * 2.0),
            false,
        ),
        Method::Quality(_) => (
            0.4 * (st.area / target as f64).sqrt(),
            -2.0,
            (st.size * 1e-7, st.size),
            false,
        ),
        Method::Sloppy | Method::Qem => {
            let r = st.triangles as f64 / st.vertices as f64;
            (
                3.0 * r * target as f64,
                1.0,
                (3.0, 3.0 * st.triangles as f64),
                true,
            )
        }
    };
    let t_search = Instant::now();
    let deadline = Duration::from_secs_f64(120.0 * (st.triangles as f64 / 1e7).max(1.0));
    search::find(target, p0, slope, range, integer, 40, |p| {
        if t_search.elapsed() > deadline {
            return Err("search deadline".into());
        }
        Ok(methods::run(method, input, p)?.counts(input).0)
    })
}
