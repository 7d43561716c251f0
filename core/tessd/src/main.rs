//! The `tessd` command line: a thin layer that parses arguments and calls the crates.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use tessd_ipc::job::{CancelToken, JobContext, Progress};
use tessd_ipc::registry::{Request, Response};
use tessd_ipc::server::{Server, ServerOptions};

/// tessd — a local geometry service for CAD and DCC tools.
#[derive(Parser)]
#[command(name = "tessd", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the daemon on a local socket.
    Serve {
        /// Socket name (in the per-user folder) or path; default: the per-user socket.
        #[arg(long)]
        socket: Option<String>,
        /// Also append the log to this file.
        #[arg(long)]
        log: Option<PathBuf>,
        /// Largest request payload in bytes.
        #[arg(long, default_value_t = 4u64 << 30)]
        max_payload: u64,
    },
    /// Run operations from job files.
    Job {
        #[command(subcommand)]
        action: JobAction,
    },
    /// Print a mesh's counts, bounds and topology.
    Stats {
        /// Mesh file (OBJ, PLY, STL, OFF).
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Convert a mesh between formats (from the extensions).
    Convert {
        /// Input mesh.
        input: PathBuf,
        /// Output mesh.
        output: PathBuf,
    },
    /// Run the main job on built-in sample data, through a real daemon, into ./tessd-demo/.
    Demo {
        /// Output folder.
        #[arg(long, default_value = "tessd-demo")]
        out: PathBuf,
    },
}

#[derive(Subcommand)]
enum JobAction {
    /// Run JOB.json: `{"op": ..., "params": {...}}` or `{"jobs": [...]}`.
    Run {
        /// The job file.
        file: PathBuf,
    },
}

fn main() {
    let cli = Cli::parse();
    let code = match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("tessd: {e:#}");
            if e.downcast_ref::<tessd_ipc::socket::BindError>()
                .is_some_and(|b| matches!(b, tessd_ipc::socket::BindError::InUse(_)))
            {
                3
            } else {
                1
            }
        }
    };
    std::process::exit(code);
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Serve {
            socket,
            log,
            max_payload,
        } => serve(socket.as_deref(), log.as_deref(), max_payload),
        Command::Job {
            action: JobAction::Run { file },
        } => job_run(&file),
        Command::Stats { file, json } => {
            let response = run_local("mesh.stats", serde_json::json!({"input": file}))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&response.result)?);
            } else {
                print_stats(&file, &response.result);
            }
            Ok(())
        }
        Command::Convert { input, output } => {
            let response = run_local(
                "mesh.convert",
                serde_json::json!({"input": input, "output": output}),
            )?;
            println!(
                "wrote {} ({} vertices, {} faces)",
                output.display(),
                response.result["vertices"],
                response.result["faces"]
            );
            Ok(())
        }
        Command::Demo { out } => tessd::demo::run(&out),
    }
}

fn serve(socket: Option<&str>, log_file: Option<&Path>, max_payload: u64) -> Result<()> {
    tessd::logging::init(log_file).context("opening the log file")?;
    let path = tessd_ipc::socket::resolve(socket, true).context("choosing the socket path")?;
    let listener = tessd_ipc::socket::bind(&path)?;
    let options = ServerOptions::default()
        .with_limits(tessd_ipc::frame::Limits::default().with_max_payload(max_payload));
    let server = Server::new(listener, &path, tessd::ops::registry(), options);
    let handle = server.shutdown_handle();
    let mut signals = signal_hook::iterator::Signals::new([
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
    ])
    .context("installing signal handlers")?;
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            log::info!("signal {sig} received");
            handle.trigger();
        }
    });
    server.serve()?;
    Ok(())
}

/// Runs one operation in this process with a progress bar on a terminal — the same registry
/// and code path as a socket request.
fn run_local(op: &str, params: serde_json::Value) -> Result<Response> {
    let serde_json::Value::Object(params) = params else {
        unreachable!()
    };
    let cwd = std::env::current_dir()?;
    let request = Request {
        params,
        base_dir: Some(cwd),
        ..Request::default()
    };
    with_progress(op, |ctx| tessd::ops::registry().run(op, request, ctx))
}

fn with_progress(
    label: &str,
    f: impl FnOnce(&JobContext) -> Result<Response, tessd_ipc::OpError>,
) -> Result<Response> {
    let bar = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{prefix} [{bar:30}] {percent:>3}% {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(label.to_string());
        Some(bar)
    } else {
        None
    };
    let sink = |p: Progress| {
        if let Some(bar) = &bar {
            bar.set_position((p.fraction * 1000.0) as u64);
            bar.set_message(format!("{} {}", p.stage, p.message));
        }
    };
    let ctx = JobContext::new(&sink, CancelToken::default());
    let result = f(&ctx);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    result.map_err(|e| anyhow::anyhow!("{label}: {e}"))
}

fn job_run(file: &Path) -> Result<()> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let jobs = tessd_ipc::job_file::parse(&text)
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let base = file
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let registry = tessd::ops::registry();
    let mut failed = 0;
    for (i, job) in jobs.into_iter().enumerate() {
        let label = format!("job {i} ({})", job.op);
        match with_progress(&label, |ctx| {
            tessd_ipc::job_file::run(&registry, job, base, ctx)
        }) {
            Ok(r) => {
                let files: Vec<String> = r.files.iter().map(|p| p.display().to_string()).collect();
                println!(
                    "{}",
                    serde_json::json!({"job": i, "result": r.result, "files": files})
                );
            }
            Err(e) => {
                eprintln!("tessd: {e:#}");
                failed += 1;
            }
        }
    }
    if failed > 0 {
        bail!("{failed} job(s) failed");
    }
    Ok(())
}

fn print_stats(file: &Path, s: &serde_json::Value) {
    println!("{}", file.display());
    for key in [
        "vertices",
        "stored_vertices",
        "unreferenced_vertices",
        "faces",
        "triangles",
        "edges",
        "boundary_edges",
        "boundary_loops",
        "non_manifold_edges",
        "components",
    ] {
        println!("  {key:22} {}", s[key]);
    }
    println!("  {:22} {}", "face sizes", s["face_sizes"]);
    println!("  {:22} {}", "bounds", s["bounds"]);
}
