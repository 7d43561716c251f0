//! Writes a mesh's `.tsc` file and prints digests of its bytes and of its full decode, so that a
//! change meant to keep the same bytes (data layout, keys, merges, the decoder's assembly) can be
//! checked against the build it started from, and timed stage by stage.
//!
//! ```text
//! cargo run --release -p tessd-codec --example tsc_digest -- MESH OUT.tsc [--bits 12]
//!     [--min-cell 8000] [--ahead 0] [--threads N] [--decode] [--max-bits B] [--ply]
//! ```
//! Prints `bytes <fnv64> <len>`, and with `--decode` (or `--max-bits`, a partial decode)
//! `decoded <fnv64> <corners> <triangles>` plus the compress and decode seconds; with `--ply`,
//! `ply <fnv64> <len>` of `Tsc::write_ply`'s output (the decoder's own triangle order, which a
//! change to the decoder's complex must keep).

use std::io::Cursor;
use std::time::Instant;

use tessd_codec::{Params, Tsc, compress_source, source};

/// This process's user CPU seconds (all threads), from `/proc/self/stat`; 0 where there is none.
fn user_secs() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = &s[s.rfind(')')? + 2..];
            rest.split(' ').nth(11)?.parse::<f64>().ok()
        })
        .map_or(0.0, |ticks| ticks / 100.0)
}

/// FNV-1a over a byte stream: enough to tell two outputs apart, with no dependency.
struct Fnv(u64);

impl Fnv {
    fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (path, out_path) = (&args[0], &args[1]);
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
    let (t, u) = (Instant::now(), user_secs());
    let r = compress_source(&mut *src, params, &mut out, &|_| true).expect("compressed");
    let (secs, user) = (t.elapsed().as_secs_f64(), user_secs() - u);
    let bytes = out.into_inner();
    std::fs::write(out_path, &bytes).expect("written");
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.eat(&bytes);
    println!("bytes {:016x} {}", h.0, bytes.len());
    println!(
        "compress {secs:.3} s, user {user:.2} s, steps ms {:?}",
        r.steps_ms
    );
    let partial = flag("--max-bits").map(|b| b as u32);
    if args.iter().any(|a| a == "--decode") || partial.is_some() {
        let (t, u) = (Instant::now(), user_secs());
        let d = Tsc::open(&bytes)
            .expect("opens")
            .decode(partial)
            .expect("decodes");
        let (secs, user) = (t.elapsed().as_secs_f64(), user_secs() - u);
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        for c in &d.corners {
            c.iter().for_each(|x| h.eat(&x.to_le_bytes()));
        }
        for p in &d.positions {
            p.iter().for_each(|x| h.eat(&x.to_le_bytes()));
        }
        for t in &d.triangles {
            t.iter().for_each(|x| h.eat(&x.to_le_bytes()));
        }
        for x in &d.isolated {
            h.eat(&x.to_le_bytes());
        }
        println!(
            "decoded {:016x} {} {}",
            h.0,
            d.corners.len(),
            d.triangles.len()
        );
        println!("decode {secs:.3} s, user {user:.2} s");
    }
    if args.iter().any(|a| a == "--ply") {
        let mut ply = Vec::new();
        Tsc::open(&bytes)
            .expect("opens")
            .write_ply(&mut ply, &|_| true)
            .expect("written");
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        h.eat(&ply);
        println!("ply {:016x} {}", h.0, ply.len());
    }
}
