//! The bit budget of one compression, for working on the codec's contexts and coder: bits per
//! vertex by symbol family, the file's size, and the time of each step, with no daemon.
//!
//! ```text
//! cargo run --release -p tessd-codec --example budget -- MESH [--bits 12] [--min-cell 8000]
//!     [--ahead 0] [--threads N] [--decode] [--repeat N]
//! ```
//! `--decode` also decodes the file in memory and checks the counts, and times it.
//! `--repeat N` compresses (and decodes) N times in one process and prints each run's wall and
//! user seconds and their medians, so that a timing needs no shell loop (every run must give the
//! same bytes; the budget printed is the first run's).

use std::io::Cursor;
use std::time::Instant;

use tessd_codec::symbols::ALL;
use tessd_codec::{Params, Tsc, compress_source, source};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .expect("usage: budget MESH [--bits B] [--min-cell N] [--ahead A]");
    let flag = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .map(|i| args[i + 1].parse::<u64>().expect("a number"))
    };
    let mut params = Params::default();
    if let Some(b) = flag("--bits") {
        params.bits = b as u32;
    }
    if let Some(m) = flag("--min-cell") {
        params.min_cell = m;
    }
    if let Some(a) = flag("--ahead") {
        params.ahead = a as u32;
    }
    if let Some(t) = flag("--threads") {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t as usize)
            .build_global()
            .expect("one pool");
    }
    let repeat = flag("--repeat").unwrap_or(1).max(1) as usize;
    let mut src = source::open(std::path::Path::new(path)).expect("a readable mesh");
    let mut out = Cursor::new(Vec::new());
    let mut times = Vec::new();
    let t = Clock::now();
    let r = compress_source(&mut *src, params, &mut out, &|_| true).expect("compressed");
    times.push(t.elapsed());
    let secs = times[0].0;
    let v = r.vertices as f64;
    println!(
        "{path}: {} vertices, {} triangles, {} cells, {} bytes, {:.3} b/v, {:.3} s ({:.3} M triangles/s)",
        r.vertices,
        r.triangles,
        r.nsp_cells,
        r.bytes,
        8.0 * r.bytes as f64 / v,
        secs,
        r.input_triangles as f64 / secs / 1e6
    );
    println!("steps ms (partition, codes, write): {:?}", r.steps_ms);
    for (i, f) in ALL.iter().enumerate() {
        println!(
            "  {:<14} {:>8.3} b/v  {:>10} symbols",
            format!("{f:?}"),
            r.family_bits[i] / v,
            r.family_symbols[i]
        );
    }
    let bytes = out.into_inner();
    let tris = r.input_triangles as f64;
    for _ in 1..repeat {
        let mut again = Cursor::new(Vec::with_capacity(bytes.len()));
        let t = Clock::now();
        compress_source(&mut *src, params, &mut again, &|_| true).expect("compressed");
        times.push(t.elapsed());
        assert!(
            again.into_inner() == bytes,
            "a repeated compression gave other bytes"
        );
    }
    if repeat > 1 {
        report("compress", &times, tris);
    }
    if args.iter().any(|a| a == "--decode") {
        let mut times = Vec::new();
        for _ in 0..repeat {
            let t = Clock::now();
            let tsc = Tsc::open(&bytes).expect("opens");
            let d = tsc.decode(None).expect("decodes");
            times.push(t.elapsed());
            if times.len() == 1 {
                let secs = times[0].0;
                println!(
                    "decode: {} corners, {:.3} s ({:.3} M triangles/s)",
                    d.corners.len(),
                    secs,
                    tris / secs / 1e6
                );
            }
        }
        if repeat > 1 {
            report("decode", &times, tris);
        }
    }
}

/// Wall and user time since a start (user time from `/proc/self/stat`, 10 ms ticks: Linux
/// only, else 0).
struct Clock(Instant, f64);

impl Clock {
    fn now() -> Self {
        Clock(Instant::now(), user_seconds())
    }

    /// (wall, user) seconds since `now`.
    fn elapsed(&self) -> (f64, f64) {
        (self.0.elapsed().as_secs_f64(), user_seconds() - self.1)
    }
}

/// This process's user CPU seconds (all threads).
fn user_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // the fields after the command's closing parenthesis; utime is field 14, the 12th of these
    stat.rsplit_once(')')
        .and_then(|(_, rest)| rest.split_whitespace().nth(11)?.parse::<f64>().ok())
        .map_or(0.0, |ticks| ticks / 100.0)
}

/// Prints every run's times and their medians.
fn report(what: &str, times: &[(f64, f64)], triangles: f64) {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let wall = median(times.iter().map(|t| t.0).collect());
    let user = median(times.iter().map(|t| t.1).collect());
    let runs: Vec<String> = times
        .iter()
        .map(|t| format!("{:.3}/{:.2}", t.0, t.1))
        .collect();
    println!(
        "{what} x{}: median wall {wall:.3} s, user {user:.2} s ({:.3} M triangles/s by user); runs wall/user: {}",
        times.len(),
        triangles / user.max(1e-9) / 1e6,
        runs.join(" ")
    );
}
