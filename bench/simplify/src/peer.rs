//! `peer`: a method matched to an output vertex count and timed in this process, for the
//! headline table (`headline.py`), where tessd runs in the daemon and its peer here.
//!
//! ```text
//! bench-simplify peer METHOD INPUT TARGET_VERTICES [--repeat 5] [--budget 40] [--param P]
//! ```
//!
//! Searches the parameter landing at `TARGET_VERTICES` (untimed, [`params::find_param`];
//! `--param` gives it, as found by an earlier call, and skips the search),
//! then times the call `--repeat` times (fewer, but 3 at least, once a further run would
//! pass `--budget` seconds) and prints one JSON line: the parameter, output vertices, times
//! and median.
//! meshoptimizer's `target_index_count` is the parameter, so `simplifySloppy`'s own search
//! for its grid size is inside the timed call.

use serde_json::json;
use std::path::Path;
use std::time::Instant;

use crate::cli::{opt, options, parse};
use crate::inputs::{read, stats};
use crate::methods::{self, Input, Method};
use crate::params::find_param;
use crate::search;
use crate::timing::median;

/// The `peer` subcommand.
pub fn peer_cmd(args: &[String]) -> Result<(), String> {
    let (pos, opts) = options(args)?;
    let [method, input, target] = pos.as_slice() else {
        return Err("usage: bench-simplify peer METHOD INPUT TARGET_VERTICES \
                    [--repeat N] [--budget S] [--param P]"
            .into());
    };
    let method = Method::parse(method).ok_or_else(|| format!("unknown method {method}"))?;
    let target: u64 = parse(target, "target vertices")?;
    let repeat: usize = parse(opt(&opts, "repeat").unwrap_or("5"), "--repeat")?;
    let budget: f64 = parse(opt(&opts, "budget").unwrap_or("40"), "--budget")?;
    let mesh = read(Path::new(input))?;
    let st = stats(&mesh);
    let input = Input::for_method(method, mesh);
    let t_search = Instant::now();
    let found = match opt(&opts, "param") {
        Some(p) => search::Found {
            param: parse(p, "--param")?,
            count: 0,
            evals: 0,
            hit: true,
        },
        None => find_param(method, &input, &st, target)?,
    };
    let search_s = t_search.elapsed().as_secs_f64();
    let (mut times, mut out_vertices) = (Vec::new(), 0);
    let t_all = Instant::now();
    while times.len() < repeat.max(1) {
        if let Some(&prev) = times.last()
            && times.len() >= 3
            && t_all.elapsed().as_secs_f64() + prev > budget
        {
            break;
        }
        let t = Instant::now();
        let o = methods::run(method, &input, found.param)?;
        times.push(t.elapsed().as_secs_f64());
        out_vertices = o.counts(&input).0;
    }
    println!(
        "{}",
        json!({
            "method": method.name(),
            "param_name": method.param_name(),
            "param": found.param,
            "search_evals": found.evals,
            "search_s": search_s,
            "target_vertices": target,
            "out_vertices": out_vertices,
            "hit": (out_vertices as f64 - target as f64).abs() <= search::tolerance(target),
            "input_triangles": st.triangles,
            "times_s": times,
            "time_s": median(&times),
        })
    );
    Ok(())
}
