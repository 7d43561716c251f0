//! Compresses a mesh and prints a digest of `Tsc::write_ply`'s output (the decoder's own
//! triangle order), so that a change to the decoder's complex can be checked for the same PLY
//! bytes against the build it started from.
//!
//! ```text
//! cargo run --release -p tessd-codec --example k_ply_digest -- MESH [--bits 12] [--min-cell N]
//! ```

use std::io::Cursor;

use tessd_codec::{Params, Tsc, compress_source, source};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
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
    let mut src = source::open(std::path::Path::new(&args[0])).expect("a readable mesh");
    let mut out = Cursor::new(Vec::new());
    compress_source(&mut *src, params, &mut out, &|_| true).expect("compressed");
    let bytes = out.into_inner();
    let tsc = Tsc::open(&bytes).expect("opens");
    let mut ply = Vec::new();
    let r = tsc.write_ply(&mut ply, &|_| true).expect("written");
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for &b in &ply {
        h = (h ^ b as u64).wrapping_mul(0x100_0000_01b3);
    }
    println!("ply {h:016x} {} bytes {} triangles", ply.len(), r.triangles);
}
