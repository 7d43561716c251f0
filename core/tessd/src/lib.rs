//! # tessd — the daemon and command line
//!
//! The top of the pipeline: [`ops`] adapts requests to the library crates
//! (`tessd-mesh`, `tessd-usd`, ...) and fills the registry that both `tessd serve` and
//! `tessd job run` use; [`demo`] runs the main job on the bundled sample; [`logging`] sends
//! the daemon's log to stderr and optionally a file.
#![warn(missing_docs)]

pub mod demo;
pub mod logging;
pub mod ops;
pub mod view;
