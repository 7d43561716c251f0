//! `tessd job run`: operations from a job file, one JSON line per job.

use super::local_run::{error_text, with_progress};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// `tessd job`: what to do with job files.
#[derive(clap::Args)]
pub struct JobArgs {
    #[command(subcommand)]
    action: JobAction,
}

/// The `job` subcommands.
#[derive(clap::Subcommand)]
enum JobAction {
    /// Run JOB.json: `{"op": ..., "params": {...}}` or `{"jobs": [...]}`.
    Run {
        /// The job file.
        file: PathBuf,
    },
}

/// Runs `tessd job ACTION`.
pub fn run(args: JobArgs) -> Result<()> {
    match args.action {
        JobAction::Run { file } => job_run(&file),
    }
}

/// Runs every job of `file` in order, paths relative to its folder; fails when any failed.
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
                eprintln!("tessd: {}", error_text(&e));
                failed += 1;
            }
        }
    }
    if failed > 0 {
        bail!("{failed} job(s) failed");
    }
    Ok(())
}
