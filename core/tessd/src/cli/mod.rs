//! The verbs of the `tessd` command line, one file per verb or group of verbs, each mirroring
//! its operation under `tessd::ops` (`render.rs` ↔ `ops/render.rs`, `codec.rs` ↔
//! `ops/codec.rs`): the verb's clap arguments, the request it builds, and the summary it
//! prints. Part of the binary, not the library: the library's users (the daemon, job files,
//! the add-on) speak the protocol, and only this binary has flags.

pub mod codec;
pub mod compare;
pub mod job;
pub mod local_run;
pub mod lod;
pub mod mesh_convert;
pub mod mesh_stats;
pub mod render;
pub mod report;
pub mod serve;
pub mod shared_args;
pub mod simplify;
pub mod subdivide;
pub mod tessellate;
