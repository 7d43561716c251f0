//! The out-of-core partition alone (paper 003 §5.1), timed pass by pass: how long each pass over
//! the file's vertices and triangles took, and the whole partition, with no coding after it.
//!
//! ```text
//! cargo run --release -p tessd-codec --example partition_passes -- MESH [--bits 16] [--raw]
//! ```
//! `--raw` times three bare passes over the triangles instead (the reader alone, nothing done
//! with them): what a partition pass costs at least.

use std::time::Instant;

use tessd_codec::Params;
use tessd_codec::source::{self, MeshSource};
use tessd_mesh::MeshError;

/// A source that times its passes.
struct Timed {
    src: Box<dyn MeshSource>,
    passes: Vec<(&'static str, f64)>,
}

impl Timed {
    fn pass<R>(&mut self, what: &'static str, run: impl FnOnce(&mut dyn MeshSource) -> R) -> R {
        let t = Instant::now();
        let r = run(&mut *self.src);
        self.passes.push((what, t.elapsed().as_secs_f64()));
        r
    }
}

impl MeshSource for Timed {
    fn vertex_count(&self) -> u64 {
        self.src.vertex_count()
    }

    fn vertices(&mut self, f: &mut dyn FnMut([f32; 3])) -> Result<(), MeshError> {
        self.pass("vertices", |s| s.vertices(f))
    }

    fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), MeshError> {
        self.pass("triangles", |s| s.triangles(f))
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .expect("usage: partition_passes MESH [--bits B] [--raw]");
    let bits = args
        .iter()
        .position(|a| a == "--bits")
        .map_or(16, |i| args[i + 1].parse().expect("a number"));
    let mut src = Timed {
        src: source::open(std::path::Path::new(path)).expect("a readable mesh"),
        passes: Vec::new(),
    };
    if args.iter().any(|a| a == "--raw") {
        for _ in 0..3 {
            let mut sum = 0u64;
            src.triangles(&mut |t| sum = sum.wrapping_add(t[0] as u64))
                .expect("read");
            println!("raw triangle pass {:.3} s", src.passes.last().unwrap().1);
        }
        return;
    }
    let params = Params {
        bits,
        ..Params::default()
    };
    let t = Instant::now();
    let part = tessd_codec::partition::build(&mut src, params, &|_| true).expect("partitioned");
    let secs = t.elapsed().as_secs_f64();
    for (what, s) in &src.passes {
        println!("{what} pass {s:.3} s");
    }
    println!(
        "partition {secs:.3} s: {} passes, {} cells, {} points",
        src.passes.len(),
        part.nodes.len(),
        part.points.len()
    );
}
