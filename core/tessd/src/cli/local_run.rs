//! Running one operation in this process, as the CLI verbs do: the same registry and code path
//! as a socket request, with a progress bar on a terminal, errors in the CLI's words, and the
//! result printed as the verb's summary or as JSON.

use super::report;
use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use tessd_ipc::arrays::{Arrays, OwnedArray};
use tessd_ipc::job::{CancelToken, JobContext, Progress};
use tessd_ipc::registry::{Request, Response};

/// Prints an operation's result: raw JSON with `--json`, else the verb's summary.
pub fn report_or_json(
    response: Response,
    json: bool,
    summary: impl FnOnce(&Response),
) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(&response.result)?);
    } else {
        summary(&response);
    }
    Ok(())
}

/// Runs one operation in this process with a progress bar on a terminal — the same registry
/// and code path as a socket request. `A` is the verb's arguments, whose flags the errors name.
pub fn run_local<A: clap::Args>(op: &str, params: serde_json::Value) -> Result<Response> {
    run_local_with::<A>(op, params, &[])
}

/// As [`run_local`], with arrays in the request.
pub fn run_local_with<A: clap::Args>(
    op: &str,
    params: serde_json::Value,
    arrays: &[OwnedArray],
) -> Result<Response> {
    let serde_json::Value::Object(params) = params else {
        unreachable!()
    };
    let cwd = std::env::current_dir()?;
    let request = Request {
        params,
        base_dir: Some(cwd),
        arrays: Arrays::from_owned(arrays),
    };
    // Errors name the CLI's flags (`--cells`), not the protocol's parameters (`cells`).
    let response = with_progress(op, |ctx| {
        tessd::ops::registry()
            .run(op, request, ctx)
            .map_err(|mut e| {
                e.message = report::cli_words(&verb_arguments::<A>(), op, &e.message);
                e
            })
    })?;
    // Every verb that writes a file says what the file could not hold.
    for line in report::dropped_warnings(op, &response) {
        eprintln!("{line}");
    }
    Ok(response)
}

/// The verb's arguments as a clap command, what [`report::cli_words`] reads the flags' names
/// from (its name is not read: `cli_words` knows the verb from the op).
fn verb_arguments<A: clap::Args>() -> clap::Command {
    A::augment_args(clap::Command::new("verb"))
}

/// Runs `f` with a progress bar on stderr when it is a terminal; its error names `label`.
pub fn with_progress(
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

/// `e` and its causes on one line, `outer: cause: its cause`, each text once: many errors (the
/// `"{path}: {source}"` kind) already print their source, which `{e:#}` would repeat.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let s = cause.to_string();
        if text.is_empty() {
            text = s;
        } else if !text.contains(&s) {
            text.push_str(": ");
            text.push_str(&s);
        }
    }
    text
}
