//! `tessd serve`: the daemon on a local socket, stopped by signals as by a `shutdown` request.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use tessd_ipc::job::JobLimits;
use tessd_ipc::server::{Server, ServerOptions};

/// `tessd serve`: the socket, the log and the limits of the daemon.
#[derive(clap::Args)]
pub struct ServeArgs {
    /// Socket name (in the per-user folder) or path; default: the per-user socket.
    #[arg(long)]
    socket: Option<String>,
    /// Append the log to this file instead of stderr (lines stamped in RFC 3339 UTC;
    /// level from TESSD_LOG, default info).
    #[arg(long)]
    log: Option<PathBuf>,
    /// Largest request payload in bytes.
    #[arg(long, default_value_t = 4u64 << 30)]
    max_payload: u64,
    /// Most requests running at once, over every client (more are refused, `too_large`).
    #[arg(long, default_value_t = 64)]
    max_jobs: usize,
    /// Most vertices, faces or face corners of one input mesh.
    #[arg(long, default_value_t = 1u64 << 31)]
    max_mesh_elements: u64,
    /// Most bytes one request's estimated working set may need (default: the machine's
    /// physical memory).
    #[arg(long)]
    max_job_memory: Option<u64>,
}

/// Runs `tessd serve`: the daemon with these limits until a signal or a `shutdown` request.
pub fn run(args: ServeArgs) -> Result<()> {
    let ServeArgs {
        socket,
        log,
        max_payload,
        max_jobs,
        max_mesh_elements,
        max_job_memory,
    } = args;
    let defaults = JobLimits::default();
    let limits = JobLimits {
        max_mesh_elements,
        max_job_memory: max_job_memory.unwrap_or(defaults.max_job_memory),
    };
    let options = ServerOptions::default()
        .with_limits(tessd_ipc::frame::Limits::default().with_max_payload(max_payload))
        .with_max_jobs(max_jobs)
        .with_job_limits(limits);
    serve(socket.as_deref(), log.as_deref(), options)
}

fn serve(socket: Option<&str>, log_file: Option<&Path>, options: ServerOptions) -> Result<()> {
    tessd::logging::init(log_file).context("opening the log file")?;
    let path = tessd_ipc::socket::resolve(socket, true).context("choosing the socket path")?;
    let listener = tessd_ipc::socket::bind(&path)?;
    let server = Server::new(listener, &path, tessd::ops::registry(), options);
    shut_down_on_signals(server.shutdown_handle())?;
    server.serve()?;
    Ok(())
}

/// SIGINT and SIGTERM stop the server as a `shutdown` request does (running requests are
/// cancelled and answered, then the socket is removed), so that a service manager's stop or a
/// terminal's Ctrl-C never leaves a client without its answer.
///
/// A second SIGINT or SIGTERM while that shutdown runs (its grace period can last 10 s) ends
/// the process at once with status 128 + the signal's number (130, 143), the shell's status
/// for a process a signal ended: the caller asked twice, and learns that the shutdown was cut
/// short (requests may have gone unanswered), where a completed one exits 0.
#[cfg(unix)]
fn shut_down_on_signals(handle: tessd_ipc::server::ShutdownHandle) -> Result<()> {
    let mut signals = signal_hook::iterator::Signals::new([
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
    ])
    .context("installing signal handlers")?;
    std::thread::spawn(move || {
        let mut signals = signals.forever();
        if let Some(sig) = signals.next() {
            log::info!("signal {sig} received");
            handle.trigger();
        }
        if let Some(sig) = signals.next() {
            log::warn!("signal {sig} received again during the shutdown: exiting at once");
            log::logger().flush();
            std::process::exit(128 + sig);
        }
    });
    Ok(())
}

/// Windows: the console's Ctrl-C and Ctrl-Break, closing the console window, logging off and
/// shutting down stop the server as SIGTERM does on Unix (running requests are cancelled and
/// answered), through `SetConsoleCtrlHandler`. Windows runs the handler on a thread of its own
/// and, for close, logoff and shutdown, ends the process as soon as the handler returns (it
/// allows about 5 s), so for those the handler does not return: it waits while the server
/// shuts down, and the process ends when `serve` returns and `main` exits. A second event
/// during that shutdown exits at once, as a second signal does on Unix, with 128 + the
/// matching signal's number: 130 for Ctrl-C, 149 for Ctrl-Break (SIGBREAK), 143 for the
/// others (SIGTERM).
#[cfg(windows)]
fn shut_down_on_signals(handle: tessd_ipc::server::ShutdownHandle) -> Result<()> {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicBool, Ordering};
    const CTRL_C_EVENT: u32 = 0;
    const CTRL_BREAK_EVENT: u32 = 1;
    const CTRL_CLOSE_EVENT: u32 = 2;
    const CTRL_LOGOFF_EVENT: u32 = 5;
    const CTRL_SHUTDOWN_EVENT: u32 = 6;
    #[link(name = "kernel32")]
    unsafe extern "system" {
        fn SetConsoleCtrlHandler(
            handler: Option<unsafe extern "system" fn(u32) -> i32>,
            add: i32,
        ) -> i32;
    }
    static HANDLE: OnceLock<tessd_ipc::server::ShutdownHandle> = OnceLock::new();
    static STOPPING: AtomicBool = AtomicBool::new(false);
    unsafe extern "system" fn on_event(event: u32) -> i32 {
        let (name, code) = match event {
            CTRL_C_EVENT => ("Ctrl-C", 130),
            CTRL_BREAK_EVENT => ("Ctrl-Break", 149),
            CTRL_CLOSE_EVENT => ("console close", 143),
            CTRL_LOGOFF_EVENT => ("logoff", 143),
            CTRL_SHUTDOWN_EVENT => ("shutdown", 143),
            _ => return 0,
        };
        if STOPPING.swap(true, Ordering::SeqCst) {
            log::warn!("{name} received again during the shutdown: exiting at once");
            log::logger().flush();
            std::process::exit(code);
        }
        log::info!("{name} received");
        if let Some(handle) = HANDLE.get() {
            handle.trigger();
        }
        if matches!(
            event,
            CTRL_CLOSE_EVENT | CTRL_LOGOFF_EVENT | CTRL_SHUTDOWN_EVENT
        ) {
            // Returning would end the process now; `main` ends it once the server is done.
            loop {
                std::thread::sleep(std::time::Duration::from_secs(60));
            }
        }
        1
    }
    let _ = HANDLE.set(handle);
    // SAFETY: registers a handler with the signature the console API calls; it only touches
    // statics and the shutdown handle, which are thread-safe.
    if unsafe { SetConsoleCtrlHandler(Some(on_event), 1) } == 0 {
        return Err(std::io::Error::last_os_error()).context("installing the console handler");
    }
    Ok(())
}
