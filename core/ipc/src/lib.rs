//! # tessd-ipc — how requests reach the algorithms
//!
//! The wire protocol of docs/protocol.md: [`frame`]s (header + JSON + aligned binary
//! [`arrays`]), the local-socket [`server`] and a blocking [`client`], the [`job`] model
//! (progress and cancellation) shared with [`job_file`]s, the request [`envelope`], the [`holders`] that share one daemon
//! between host programs, and the operation [`registry`] the binary fills. Nothing here knows about meshes: operations are registered from above.
//!
//! ```no_run
//! use tessd_ipc::{registry::{Registry, Response}, server::{Server, ServerOptions}, socket};
//! let mut registry = Registry::new();
//! registry.register("echo", |req: tessd_ipc::registry::Request, _ctx: &tessd_ipc::job::JobContext| {
//!     Ok(Response::json(serde_json::Value::Object(req.params)))
//! });
//! let path = socket::resolve(Some("example"), true).unwrap();
//! let listener = socket::bind(&path).unwrap();
//! Server::new(listener, &path, registry, ServerOptions::default()).serve().unwrap();
//! ```
#![warn(missing_docs)]

pub mod arrays;
pub mod client;
pub mod envelope;
pub mod error;
pub mod frame;
pub mod holders;
pub mod job;
pub mod job_file;
pub mod json_kind;
pub mod registry;
pub mod server;
pub mod socket;
mod socket_watch;

pub use error::{ErrorCode, OpError};
