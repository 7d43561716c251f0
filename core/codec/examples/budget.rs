//! The bit budget of one compression, for working on the codec's contexts and coder: bits per
//! vertex by symbol family, the file's size, and the time of each step, with no daemon.
//!
//! ```text
//! cargo run --release -p tessd-codec --example budget -- MESH [--bits 12] [--min-cell 8000]
//!     [--ahead 0] [--threads N] [--decode]
//! ```
//! `--decode` also decodes the file in memory and checks the counts, and times it.

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
    let mut src = source::open(std::path::Path::new(path)).expect("a readable mesh");
    let mut out = Cursor::new(Vec::new());
    let t = Instant::now();
    let r = compress_source(&mut *src, params, &mut out, &|_| true).expect("compressed");
    let secs = t.elapsed().as_secs_f64();
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
    if args.iter().any(|a| a == "--decode") {
        let bytes = out.into_inner();
        let t = Instant::now();
        let tsc = Tsc::open(&bytes).expect("opens");
        let d = tsc.decode(None).expect("decodes");
        let secs = t.elapsed().as_secs_f64();
        println!(
            "decode: {} corners, {:.3} s ({:.3} M triangles/s)",
            d.corners.len(),
            secs,
            r.input_triangles as f64 / secs / 1e6
        );
    }
}
