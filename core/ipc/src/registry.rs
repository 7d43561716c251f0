//! The operation registry: the daemon knows operations only through it, so a new algorithm
//! adds an [`Operation`] in the binary crate without touching the server.

use crate::arrays::{Arrays, OwnedArray};
use crate::error::OpError;
use crate::job::JobContext;
use serde_json::{Map, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A request as an operation sees it, from the socket or a job file alike.
#[derive(Debug, Default)]
pub struct Request {
    /// The `params` object.
    pub params: Map<String, Value>,
    /// The payload arrays.
    pub arrays: Arrays,
    /// The folder relative paths are resolved against (a job file's folder; `None` over the
    /// socket, where paths are used as given).
    pub base_dir: Option<PathBuf>,
}

impl Request {
    /// Resolves a path parameter against [`Request::base_dir`].
    pub fn resolve(&self, path: &str) -> PathBuf {
        match &self.base_dir {
            Some(base) if Path::new(path).is_relative() => base.join(path),
            _ => PathBuf::from(path),
        }
    }

    /// An optional string parameter.
    ///
    /// # Errors
    /// `invalid_request` when present with another type.
    pub fn str_param(&self, key: &str) -> Result<Option<&str>, OpError> {
        match self.params.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(OpError::request(format!(
                "parameter `{key}` must be a string, got {}",
                crate::json_kind::json_kind(v)
            ))),
        }
    }

    /// An optional number parameter.
    ///
    /// # Errors
    /// `invalid_request` when present with another type or not finite.
    pub fn f64_param(&self, key: &str) -> Result<Option<f64>, OpError> {
        match self.params.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Number(n)) => Ok(n.as_f64()),
            Some(v) => Err(OpError::request(format!(
                "parameter `{key}` must be a number, got {}",
                crate::json_kind::json_kind(v)
            ))),
        }
    }
}

/// An operation's success: a JSON result, arrays and the files it wrote.
#[derive(Debug, Default)]
pub struct Response {
    /// The `result` object.
    pub result: Value,
    /// Arrays returned in the payload.
    pub arrays: Vec<OwnedArray>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl Response {
    /// A response with only a JSON result.
    pub fn json(result: Value) -> Response {
        Response {
            result,
            ..Response::default()
        }
    }
}

/// One protocol operation (`mesh.stats`, `simplify`, ...).
pub trait Operation: Send + Sync {
    /// Runs the request, reporting progress and honouring cancellation through `ctx`.
    ///
    /// # Errors
    /// An [`OpError`] whose message names the offending element.
    fn run(&self, request: Request, ctx: &JobContext) -> Result<Response, OpError>;
}

impl<F> Operation for F
where
    F: Fn(Request, &JobContext) -> Result<Response, OpError> + Send + Sync,
{
    fn run(&self, request: Request, ctx: &JobContext) -> Result<Response, OpError> {
        self(request, ctx)
    }
}

/// Operations by name.
#[derive(Clone, Default)]
pub struct Registry {
    ops: BTreeMap<String, Arc<dyn Operation>>,
    capabilities: Vec<String>,
}

impl Registry {
    /// An empty registry.
    pub fn new() -> Registry {
        Registry::default()
    }

    /// Registers `op` under `name`, replacing any previous one.
    pub fn register(&mut self, name: &str, op: impl Operation + 'static) -> &mut Self {
        self.ops.insert(name.to_string(), Arc::new(op));
        self
    }

    /// Adds a capability string reported by `hello` (e.g. `mesh.read.ply`).
    pub fn add_capability(&mut self, capability: &str) -> &mut Self {
        self.capabilities.push(capability.to_string());
        self
    }

    /// The operation called `name`.
    pub fn get(&self, name: &str) -> Option<Arc<dyn Operation>> {
        self.ops.get(name).cloned()
    }

    /// Registered operation names, sorted.
    pub fn names(&self) -> Vec<String> {
        self.ops.keys().cloned().collect()
    }

    /// Capability strings.
    pub fn capabilities(&self) -> &[String] {
        &self.capabilities
    }

    /// Runs `name` in this process (job files, CLI), on the same path as a socket request,
    /// with panics turned into `internal` errors.
    ///
    /// # Errors
    /// `invalid_request` for an unknown operation, or the operation's error.
    pub fn run(&self, name: &str, request: Request, ctx: &JobContext) -> Result<Response, OpError> {
        let op = self
            .get(name)
            .ok_or_else(|| unknown_op(name, &self.names()))?;
        run_guarded(op.as_ref(), request, ctx)
    }
}

/// The error for an unknown operation, listing the known ones.
pub fn unknown_op(name: &str, known: &[String]) -> OpError {
    OpError::request(format!(
        "unknown operation {name:?}; known operations: {}",
        known.join(", ")
    ))
}

/// Runs an operation, turning a panic (a tessd bug) into an `internal` error so that the
/// daemon keeps serving.
pub(crate) fn run_guarded(
    op: &dyn Operation,
    request: Request,
    ctx: &JobContext,
) -> Result<Response, OpError> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| op.run(request, ctx))).unwrap_or_else(
        |p| {
            let what = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(OpError::new(
                crate::error::ErrorCode::Internal,
                format!("internal error: {what}"),
            ))
        },
    )
}
