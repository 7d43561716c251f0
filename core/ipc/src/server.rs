//! The local-socket server: one reader thread per connection, one thread per request, replies
//! multiplexed on the connection by request id (docs/protocol.md).
//!
//! The daemon keeps no per-client state beyond the connection, except the [`Holders`]: the
//! host processes that declared they use it (`session.hold`), so that a host that started a
//! shared daemon can tell whether stopping it would pull it from under another program.
//! Operations come from the [`Registry`]; `hello`, `ping`, `cancel`, `shutdown`,
//! `session.hold` and `session.release` are built in because they concern the server itself.

use crate::arrays::{Arrays, OwnedArray};
use crate::envelope::{Envelope, bool_param, holder_pid, parse_envelope};
use crate::error::{ErrorCode, OpError};
use crate::frame::{Frame, FrameError, Limits, PROTOCOL_VERSION, read_frame, write_frame};
use crate::holders::Holders;
use crate::job::{CancelToken, JobContext, JobLimits, Progress};
use crate::json_kind::json_kind;
use crate::registry::{Registry, Request, Response, run_guarded, unknown_op};
use crate::socket_watch::SocketWatch;
use interprocess::local_socket::{Listener, Stream, traits::Listener as _};
use serde_json::{Map, Value, json};
use std::collections::HashMap;
use std::io::{self, BufReader};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::time::{Duration, Instant};

/// Operations the server answers itself.
const BUILTIN_OPS: [&str; 6] = [
    "cancel",
    "hello",
    "ping",
    "session.hold",
    "session.release",
    "shutdown",
];

/// Server settings.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct ServerOptions {
    /// Frame size limits.
    pub limits: Limits,
    /// Most requests one connection may have running at once.
    pub max_in_flight_per_connection: usize,
    /// Most requests the whole daemon runs at once, over every connection.
    pub max_jobs: usize,
    /// What each request may use.
    pub job_limits: JobLimits,
    /// How long `shutdown` waits for running requests before the server returns anyway.
    pub shutdown_grace: Duration,
    /// How often the server checks that its socket path still names the socket it bound
    /// (one `stat`); when it was removed or replaced the server shuts down (at least 10 ms).
    pub socket_check: Duration,
}

impl Default for ServerOptions {
    fn default() -> Self {
        ServerOptions {
            limits: Limits::default(),
            max_in_flight_per_connection: 64,
            max_jobs: 64,
            job_limits: JobLimits::default(),
            shutdown_grace: Duration::from_secs(10),
            socket_check: Duration::from_secs(2),
        }
    }
}

impl ServerOptions {
    /// Sets the frame limits.
    pub fn with_limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }

    /// Sets the most requests the daemon runs at once.
    pub fn with_max_jobs(mut self, max_jobs: usize) -> Self {
        self.max_jobs = max_jobs;
        self
    }

    /// Sets what each request may use.
    pub fn with_job_limits(mut self, limits: JobLimits) -> Self {
        self.job_limits = limits;
        self
    }

    /// Sets how long `shutdown` waits for running requests.
    pub fn with_shutdown_grace(mut self, grace: Duration) -> Self {
        self.shutdown_grace = grace;
        self
    }

    /// Sets how often the socket file is checked (see [`ServerOptions::socket_check`]).
    pub fn with_socket_check(mut self, every: Duration) -> Self {
        self.socket_check = every;
        self
    }
}

struct Shared {
    registry: Registry,
    options: ServerOptions,
    socket: PathBuf,
    stopping: AtomicBool,
    in_flight: AtomicUsize,
    holders: Holders,
    /// Every live connection's running requests, so that shutdown can cancel them all.
    connections: Mutex<Vec<Weak<JobMap>>>,
    /// Unix: the write end of the pipe whose other end the accept loop polls beside the
    /// listener, so that a shutdown wakes it without the socket file (which may be gone).
    #[cfg(unix)]
    wake: std::io::PipeWriter,
}

/// A connection's running requests: request id → its cancel token.
type JobMap = Mutex<HashMap<u64, CancelToken>>;

impl Shared {
    /// Keeps `jobs` (a new connection's requests) for [`Shared::cancel_all`], forgetting the
    /// connections that have ended.
    fn track(&self, jobs: &Arc<JobMap>) {
        let mut connections = lock(&self.connections);
        connections.retain(|c| c.strong_count() > 0);
        connections.push(Arc::downgrade(jobs));
    }

    /// Cancels every running request of every connection; returns how many there were.
    fn cancel_all(&self) -> usize {
        let connections: Vec<Arc<JobMap>> = lock(&self.connections)
            .iter()
            .filter_map(Weak::upgrade)
            .collect();
        let mut n = 0;
        for jobs in connections {
            for token in lock(&jobs).values() {
                token.cancel();
                n += 1;
            }
        }
        n
    }
}

/// Stops a running server from another thread (signal handler, `shutdown` op).
#[derive(Clone)]
pub struct ShutdownHandle(Arc<Shared>);

impl ShutdownHandle {
    /// Stops accepting connections; the server then cancels the running requests, waits for
    /// their answers and returns.
    pub fn trigger(&self) {
        if !self.0.stopping.swap(true, Ordering::SeqCst) {
            log::info!("shutting down");
            // Wake the accept loop. Unix: one byte down the wake pipe (written once, so it can
            // never block), which needs no socket file. Windows: the accept loop blocks in
            // accept(); a connection to the pipe wakes it, and a named pipe cannot be removed
            // from under the daemon, so the connection always arrives.
            #[cfg(unix)]
            {
                use std::io::Write as _;
                if let Err(e) = (&self.0.wake).write_all(&[1]) {
                    log::error!("cannot wake the accept loop: {e}");
                }
            }
            #[cfg(not(unix))]
            let _ = crate::socket::connect(&self.0.socket);
        }
    }
}

/// A server over a bound listener.
pub struct Server {
    shared: Arc<Shared>,
    listener: Listener,
    watch: SocketWatch,
    /// Unix: the read end of [`Shared::wake`].
    #[cfg(unix)]
    woken: std::io::PipeReader,
}

impl Server {
    /// A server answering on `listener` (bound at `socket`, see [`crate::socket::bind`]); call
    /// it right after the bind: it records which file the socket is, to notice when the path
    /// no longer names it.
    ///
    /// # Panics
    /// Unix: when the process cannot create a pipe (out of file descriptors).
    pub fn new(
        mut listener: Listener,
        socket: &Path,
        registry: Registry,
        options: ServerOptions,
    ) -> Self {
        // The socket file is removed on drop by [`SocketWatch::remove_if_ours`], which first
        // checks that it is still this server's: the listener's own removal would take the
        // file of a daemon that replaced it.
        listener.do_not_reclaim_name_on_drop();
        let watch = SocketWatch::new(socket);
        #[cfg(unix)]
        let (woken, wake) = std::io::pipe().expect("creating the shutdown wake pipe");
        let shared = Arc::new(Shared {
            registry,
            options,
            socket: socket.to_path_buf(),
            stopping: AtomicBool::new(false),
            in_flight: AtomicUsize::new(0),
            holders: Holders::new(),
            connections: Mutex::new(Vec::new()),
            #[cfg(unix)]
            wake,
        });
        Server {
            shared,
            listener,
            watch,
            #[cfg(unix)]
            woken,
        }
    }

    /// A handle that stops this server.
    pub fn shutdown_handle(&self) -> ShutdownHandle {
        ShutdownHandle(self.shared.clone())
    }

    /// Serves until shut down — by [`ShutdownHandle::trigger`], or by itself when its socket
    /// path no longer names the socket it bound (removed or replaced; checked every
    /// [`ServerOptions::socket_check`]) — then cancels the running requests and waits (up to
    /// the grace period) for each to answer (`cancelled`, or its result when it was past its
    /// last checkpoint).
    /// The socket file is removed when the server is dropped, if it is still this server's.
    ///
    /// # Errors
    /// Only when accepting fails persistently; per-client failures never end the server.
    pub fn serve(mut self) -> io::Result<()> {
        log::info!("tessd listening on {}", self.shared.socket.display());
        let accepted = self.accept_until_stopped();
        // A trigger from now on (a signal) has nothing to wake.
        self.shared.stopping.store(true, Ordering::SeqCst);
        accepted?;
        // Running requests are cancelled, and each answers `cancelled` at its next checkpoint
        // before its count drops; a request that a connection admitted after the first pass
        // is caught by the next one.
        let cancelled = self.shared.cancel_all();
        if cancelled > 0 {
            log::info!("cancelling {cancelled} running request(s)");
        }
        let deadline = Instant::now() + self.shared.options.shutdown_grace;
        while self.shared.in_flight.load(Ordering::SeqCst) > 0 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
            self.shared.cancel_all();
        }
        let left = self.shared.in_flight.load(Ordering::SeqCst);
        if left > 0 {
            log::warn!("stopped with {left} request(s) still running past the grace period");
        } else {
            log::info!("stopped");
        }
        Ok(())
    }

    /// Unix: accepts connections until a shutdown is triggered or the socket is lost. The
    /// listener is nonblocking and polled together with the wake pipe; the poll's timeout
    /// paces the socket check, so an idle daemon wakes once per check and at no other time.
    #[cfg(unix)]
    fn accept_until_stopped(&mut self) -> io::Result<()> {
        use interprocess::local_socket::ListenerNonblockingMode;
        use std::os::fd::{AsFd as _, AsRawFd as _};
        // Streams stay blocking: only accept() returns at once when nobody is waiting.
        self.listener
            .set_nonblocking(ListenerNonblockingMode::Accept)?;
        let Listener::UdSocket(uds) = &self.listener;
        let listener_fd = uds.as_fd().as_raw_fd();
        let wake_fd = self.woken.as_raw_fd();
        let every = self
            .shared
            .options
            .socket_check
            .max(Duration::from_millis(10));
        let mut next_check = Instant::now() + every;
        let mut failures = 0u32;
        loop {
            let wait = next_check.saturating_duration_since(Instant::now());
            // rounded up, so that the loop never spins on a timeout of 0 ms before the check
            let wait_ms = i32::try_from(wait.as_micros().div_ceil(1000)).unwrap_or(i32::MAX);
            let mut fds = [
                libc::pollfd {
                    fd: listener_fd,
                    events: libc::POLLIN,
                    revents: 0,
                },
                libc::pollfd {
                    fd: wake_fd,
                    events: libc::POLLIN,
                    revents: 0,
                },
            ];
            // SAFETY: `fds` is a valid array of two pollfd for the duration of the call, and
            // both descriptors stay open while `self` lives.
            let ready = unsafe { libc::poll(fds.as_mut_ptr(), 2, wait_ms) };
            if ready < 0 {
                let e = io::Error::last_os_error();
                if e.kind() != io::ErrorKind::Interrupted {
                    failures += 1;
                    log::warn!("poll failed: {e}");
                    if failures > 100 {
                        return Err(e);
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                continue;
            }
            if self.shared.stopping.load(Ordering::SeqCst) {
                return Ok(());
            }
            if Instant::now() >= next_check {
                if let Some(why) = self.watch.lost() {
                    log::warn!("{why}: no client can reach this daemon any more; stopping");
                    self.shared.stopping.store(true, Ordering::SeqCst);
                    return Ok(());
                }
                next_check = Instant::now() + every;
            }
            if fds[0].revents == 0 {
                continue;
            }
            // Every connection waiting now, then back to the poll.
            loop {
                match self.listener.accept() {
                    Ok(stream) => {
                        failures = 0;
                        // BSD and macOS hand the listener's O_NONBLOCK on to the accepted
                        // socket (Linux does not); the connection's reader needs it blocking.
                        #[cfg(not(any(target_os = "linux", target_os = "android")))]
                        if let Err(e) = interprocess::local_socket::traits::Stream::set_nonblocking(
                            &stream, false,
                        ) {
                            log::warn!("cannot make a connection blocking: {e}");
                            continue;
                        }
                        self.spawn_connection(stream);
                    }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        failures += 1;
                        log::warn!("accept failed: {e}");
                        if failures > 100 {
                            return Err(e);
                        }
                        std::thread::sleep(Duration::from_millis(10));
                        break;
                    }
                }
            }
        }
    }

    /// Windows: accepts connections until a shutdown is triggered; the trigger wakes the
    /// blocking accept() by connecting. The named pipe cannot be removed or taken over while
    /// this server holds an instance of it, so there is no socket to watch.
    #[cfg(not(unix))]
    fn accept_until_stopped(&mut self) -> io::Result<()> {
        use interprocess::local_socket::traits::ListenerExt as _;
        let mut failures = 0u32;
        for conn in self.listener.incoming() {
            if self.shared.stopping.load(Ordering::SeqCst) {
                break;
            }
            match conn {
                Ok(stream) => {
                    failures = 0;
                    self.spawn_connection(stream);
                }
                Err(e) => {
                    failures += 1;
                    log::warn!("accept failed: {e}");
                    if failures > 100 {
                        return Err(e);
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
            }
        }
        Ok(())
    }

    /// Serves `stream` on a thread of its own.
    fn spawn_connection(&self, stream: Stream) {
        let shared = self.shared.clone();
        let spawned = std::thread::Builder::new()
            .name("tessd-conn".into())
            .spawn(move || Connection::new(stream, shared).run());
        if let Err(e) = spawned {
            log::error!("cannot start a connection thread: {e}");
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.watch.remove_if_ours();
    }
}

/// One client connection: reads frames, runs requests, writes replies.
struct Connection {
    stream: Arc<Stream>,
    write_lock: Arc<Mutex<()>>,
    jobs: Arc<Mutex<HashMap<u64, CancelToken>>>,
    shared: Arc<Shared>,
}

impl Connection {
    fn new(stream: Stream, shared: Arc<Shared>) -> Connection {
        let jobs = Arc::new(Mutex::new(HashMap::new()));
        shared.track(&jobs);
        Connection {
            stream: Arc::new(stream),
            write_lock: Arc::new(Mutex::new(())),
            jobs,
            shared,
        }
    }

    fn run(self) {
        let mut reader = BufReader::with_capacity(64 << 10, &*self.stream);
        loop {
            match read_frame(&mut reader, &self.shared.options.limits) {
                Ok(frame) => self.dispatch(frame),
                Err(FrameError::Closed) => break,
                Err(FrameError::Io(e)) => {
                    log::debug!("connection read failed: {e}");
                    break;
                }
                Err(e) => {
                    // The byte stream is out of step: answer once, then close.
                    log::info!("closing connection after a bad frame: {e}");
                    self.reply(&Value::Null, Err(OpError::new(code_of(&e), e.to_string())));
                    break;
                }
            }
        }
        // Closing the connection cancels everything still running on it.
        for token in lock(&self.jobs).values() {
            token.cancel();
        }
    }

    fn dispatch(&self, frame: Frame) {
        let Frame { mut json, arrays } = frame;
        let raw_id = json.get("id").cloned().unwrap_or(Value::Null);
        let parsed = parse_envelope(&mut json);
        let Envelope { id, op, params } = match parsed {
            Ok(p) => p,
            Err(e) => return self.reply(&raw_id, Err(e)),
        };
        // Every request, built-in or not, must have an id no running request uses: a client
        // routes replies by id, and one id must get exactly one final frame.
        if lock(&self.jobs).contains_key(&id) {
            let message = format!("request id {id} is already running");
            return self.reply(&raw_id, Err(OpError::request(message)));
        }
        match op.as_str() {
            "hello" => self.reply(&raw_id, Ok(Response::json(self.hello()))),
            "ping" => {
                let echo = params.get("echo").cloned().unwrap_or(Value::Null);
                self.reply(
                    &raw_id,
                    Ok(Response::json(json!({"pong": true, "echo": echo}))),
                )
            }
            "cancel" => {
                let result = match params.get("id").and_then(Value::as_u64) {
                    Some(target) => {
                        let token = lock(&self.jobs).get(&target).cloned();
                        token.as_ref().map(CancelToken::cancel);
                        Ok(Response::json(json!({"cancelled": token.is_some()})))
                    }
                    None => Err(OpError::request(
                        "cancel needs `params.id`, the request to stop",
                    )),
                };
                self.reply(&raw_id, result)
            }
            "shutdown" => match bool_param(&params, "if_unheld") {
                Err(e) => self.reply(&raw_id, Err(e)),
                Ok(if_unheld) => {
                    // Counting and deciding under one call keeps "stop unless someone holds
                    // it" free of the race a separate `hello` then `shutdown` would have.
                    let holders = self.shared.holders.count();
                    if if_unheld && holders > 0 {
                        let result = json!({"ok": false, "stopping": false, "holders": holders});
                        self.reply(&raw_id, Ok(Response::json(result)));
                    } else {
                        // A plain `shutdown` answers as it always did, for older clients.
                        let result = if if_unheld {
                            json!({"ok": true, "stopping": true, "holders": holders})
                        } else {
                            json!({"ok": true})
                        };
                        self.reply(&raw_id, Ok(Response::json(result)));
                        ShutdownHandle(self.shared.clone()).trigger();
                    }
                }
            },
            "session.hold" => {
                let result = holder_pid(&params, "session.hold").and_then(|pid| {
                    let host = match params.get("host") {
                        None | Some(Value::Null) => "",
                        Some(Value::String(s)) => s.as_str(),
                        Some(v) => {
                            return Err(OpError::request(format!(
                                "parameter `host` must be a string (the holding program, e.g. \
                                 \"blender\"), got {}",
                                json_kind(v)
                            )));
                        }
                    };
                    let n = self.shared.holders.hold(pid, host);
                    log::info!("held by {host} (pid {pid}); {n} holder(s)");
                    Ok(Response::json(json!({"holders": n})))
                });
                self.reply(&raw_id, result)
            }
            "session.release" => {
                let result = holder_pid(&params, "session.release").map(|pid| {
                    let n = self.shared.holders.release(pid);
                    log::info!("released by pid {pid}; {n} holder(s) left");
                    Response::json(json!({"holders": n}))
                });
                self.reply(&raw_id, result)
            }
            _ => self.start_job(id, raw_id, op, params, arrays),
        }
    }

    fn hello(&self) -> Value {
        json!({
            "server": "tessd",
            "version": env!("CARGO_PKG_VERSION"),
            "protocol": PROTOCOL_VERSION,
            "ops": self.known_ops(),
            "capabilities": self.shared.registry.capabilities(),
            "pid": std::process::id(),
            "holders": self.shared.holders.count(),
            "held_by": self.shared.holders.describe(),
        })
    }

    /// The registered operations and the built-in ones, sorted.
    fn known_ops(&self) -> Vec<String> {
        let mut ops = self.shared.registry.names();
        ops.extend(BUILTIN_OPS.map(String::from));
        ops.sort();
        ops
    }

    fn start_job(
        &self,
        id: u64,
        raw_id: Value,
        op: String,
        params: Map<String, Value>,
        arrays: Arrays,
    ) {
        let Some(operation) = self.shared.registry.get(&op) else {
            return self.reply(&raw_id, Err(unknown_op(&op, &self.known_ops())));
        };
        let token = CancelToken::default();
        {
            let mut jobs = lock(&self.jobs);
            let refusal = if jobs.contains_key(&id) {
                Some(OpError::request(format!(
                    "request id {id} is already running"
                )))
            } else if jobs.len() >= self.shared.options.max_in_flight_per_connection {
                Some(OpError::new(
                    ErrorCode::TooLarge,
                    format!(
                        "this connection already runs {} requests, the most allowed",
                        self.shared.options.max_in_flight_per_connection
                    ),
                ))
            } else {
                // the daemon-wide count is taken and checked in one step, so that concurrent
                // connections cannot together pass the limit
                let max_jobs = self.shared.options.max_jobs;
                let admitted =
                    self.shared
                        .in_flight
                        .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                            (n < max_jobs).then_some(n + 1)
                        });
                admitted.is_err().then(|| {
                    OpError::new(
                        ErrorCode::TooLarge,
                        format!(
                            "the daemon already runs {max_jobs} requests, the most allowed \
                             (tessd serve --max-jobs); retry when one finishes"
                        ),
                    )
                })
            };
            if let Some(e) = refusal {
                drop(jobs);
                return self.reply(&raw_id, Err(e));
            }
            jobs.insert(id, token.clone());
        }
        let this = Connection {
            stream: self.stream.clone(),
            write_lock: self.write_lock.clone(),
            jobs: self.jobs.clone(),
            shared: self.shared.clone(),
        };
        let spawned = std::thread::Builder::new()
            .name(format!("tessd-{op}"))
            .spawn(move || {
                let started = Instant::now();
                let sink = |p: Progress| {
                    let msg = json!({"id": id, "type": "progress", "progress": {
                    "fraction": p.fraction, "stage": p.stage, "message": p.message}});
                    this.send(msg, &[]);
                };
                let ctx = JobContext::new(&sink, token).with_limits(this.shared.options.job_limits);
                let request = Request {
                    params,
                    arrays,
                    base_dir: None,
                };
                let result = run_guarded(operation.as_ref(), request, &ctx);
                match &result {
                    Ok(_) => log::debug!("{op} #{id} done in {:?}", started.elapsed()),
                    Err(e) => log::info!("{op} #{id} failed: {e}"),
                }
                lock(&this.jobs).remove(&id);
                this.reply_timed(&Value::from(id), result, Some(started.elapsed()));
                if this.shared.in_flight.fetch_sub(1, Ordering::SeqCst) == 1 {
                    // Idle: what the jobs freed goes back to the system.
                    tessd_mesh::allocation::release_free_memory();
                }
            });
        if let Err(e) = spawned {
            lock(&self.jobs).remove(&id);
            self.shared.in_flight.fetch_sub(1, Ordering::SeqCst);
            self.reply(
                &raw_id,
                Err(OpError::new(
                    ErrorCode::Internal,
                    format!("cannot start job: {e}"),
                )),
            );
        }
    }

    /// Sends the final frame of a request.
    fn reply(&self, id: &Value, result: Result<Response, OpError>) {
        self.reply_timed(id, result, None);
    }

    /// Sends the final frame of a request; an operation's `ok` frame carries `elapsed_ms`, the
    /// time the daemon spent on it (so hosts can tell work from transfer).
    fn reply_timed(
        &self,
        id: &Value,
        result: Result<Response, OpError>,
        elapsed: Option<Duration>,
    ) {
        match result {
            Ok(r) => {
                let files: Vec<Value> = r
                    .files
                    .iter()
                    .map(|p| Value::from(p.display().to_string()))
                    .collect();
                let mut msg = json!({"id": id, "type": "ok", "result": r.result, "files": files, "arrays": []});
                if let Some(t) = elapsed {
                    msg["elapsed_ms"] = json!(t.as_secs_f64() * 1e3);
                }
                self.send(msg, &r.arrays);
            }
            Err(e) => {
                let msg = json!({"id": id, "type": "error",
                                 "error": {"code": e.code.as_str(), "message": e.message}});
                self.send(msg, &[]);
            }
        }
    }

    fn send(&self, msg: Value, arrays: &[OwnedArray]) {
        let Value::Object(map) = msg else {
            unreachable!("replies are objects")
        };
        let _guard = lock(&self.write_lock);
        if let Err(e) = write_frame(&mut &*self.stream, map, arrays) {
            log::debug!("reply not delivered: {e}");
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn code_of(e: &FrameError) -> ErrorCode {
    match e.code() {
        "too_large" => ErrorCode::TooLarge,
        _ => ErrorCode::InvalidFrame,
    }
}
