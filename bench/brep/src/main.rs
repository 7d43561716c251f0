//! `bench-brep`: paper 000's trim structure (tessd-trim) and tessd's trimmed tessellation
//! (tessd-tessellate) measured on exported B-Rep parts (`tessd-brep` JSON, written by
//! `peer_ocp.py export`).
//!
//! ```text
//! bench-brep run --manifest WORK/parts.json [--jsonl FILE] [--only NAME,..]
//!                [--trim-timeout 120] [--tess-timeout 90] [SETTINGS]
//! bench-brep one PART.json --step trim [SETTINGS]
//! bench-brep one PART.json --step tess --tol MM --pool THREADS [SETTINGS]
//! SETTINGS: [--eps 0.1,0.01] [--tols 0.1,0.01] [--threads 1,2] [--points 1000000]
//!           [--classify-repeats 5] [--budget 2] [--min-repeat 3] [--max-repeat 9] [--slow-s 20]
//! ```
//!
//! `run` is the harness: for every part of the manifest (a JSON array of objects with `name`
//! and `json`; entries with `error` are reported as such) it runs, each in a child process
//! with a wall-clock limit, `one --step trim` and then `one --step tess` for every tolerance
//! (coarse first) and rayon pool size (largest first), and appends the children's JSON lines
//! to the jsonl with `tool` = `"tessd"` and `part` added. A child that crashes or runs past
//! its limit leaves a `child` error line naming the step it was in (the last line of its
//! standard error); a tolerance that ran past the limit stops the finer ones, and a pool size
//! whose single run took over `--slow-s` stops the smaller pools (both recorded as `skipped`).
//!
//! `one` measures one part in this process and prints JSON lines, one per record (`kind`):
//!
//! - `doc`: the document's table-1 counts ([`tessd_brep::Stats`]), units, and whether it is a
//!   closed solid (every edge with a curve used by two trims);
//! - `trim` (one per ε, in mm, converted to document units): `TrimStructure::build` of every
//!   face, one after the other on this thread, each under `catch_unwind`; per face its figures
//!   (quadratics, lines, nodes, deepest leaf, failures, separating lines, packed bytes, k_i,
//!   build time, fit error against the face's (u, v) tolerance) or its error;
//! - `classify` (one per ε): the CPU classification rate, single thread: `--points` random
//!   (u, v) spread evenly over the built faces, uniform in each face's bounds (generated
//!   beforehand), classified with `TrimStructure::classify`; one warm-up pass, then the median
//!   of `--classify-repeats` passes;
//! - `tessellate` (`--step tess`: one tolerance in mm, one rayon pool size):
//!   `tessellate(doc, &Options::new(tol))` with the default angle (0.5 rad), the whole call
//!   timed (validation included) with its CPU time, and the crate's own `stats.time_ms`; one
//!   warm-up run, then budget / warm-up runs clamped to `min..=max` (only the warm-up when it
//!   took more than `--slow-s`); the last mesh is checked for cracks and for its centroid
//!   deviation from the surfaces (see [`check`]).

#![warn(missing_docs)]

mod check;
mod one;

use clap::{Args, Parser};
use serde_json::{Value, json};
use std::fs::OpenOptions;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::{Command, ExitCode, Stdio};
use std::time::{Duration, Instant};

/// Command line.
#[derive(Parser)]
#[command(
    name = "bench-brep",
    about = "trim structures and tessellation of B-Rep parts"
)]
enum Cli {
    /// The harness: every part of the manifest in its own child process.
    Run(RunArgs),
    /// One part in this process; prints JSON lines.
    One(OneArgs),
}

/// What `one` measures (shared by `run`, which passes them on).
#[derive(Args, Clone)]
struct Settings {
    /// Trim approximation tolerances ε, millimetres.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.01")]
    eps: Vec<f64>,
    /// Tessellation tolerances, millimetres.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.01")]
    tols: Vec<f64>,
    /// Rayon pool sizes for the tessellation.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    threads: Vec<usize>,
    /// Points classified per pass (spread over the faces).
    #[arg(long, default_value_t = 1_000_000)]
    points: usize,
    /// Timed classification passes.
    #[arg(long = "classify-repeats", default_value_t = 5)]
    classify_repeats: usize,
    /// Seconds of timed tessellation runs per configuration.
    #[arg(long, default_value_t = 2.0)]
    budget: f64,
    /// Fewest timed tessellation runs.
    #[arg(long = "min-repeat", default_value_t = 3)]
    min_repeat: usize,
    /// Most timed tessellation runs.
    #[arg(long = "max-repeat", default_value_t = 9)]
    max_repeat: usize,
    /// A warm-up tessellation longer than this (seconds) is the only run.
    #[arg(long = "slow-s", default_value_t = 20.0)]
    slow_s: f64,
}

impl Settings {
    fn to_args(&self) -> Vec<String> {
        let list = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(",");
        let threads = self
            .threads
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(",");
        vec![
            format!("--eps={}", list(&self.eps)),
            format!("--tols={}", list(&self.tols)),
            format!("--threads={threads}"),
            format!("--points={}", self.points),
            format!("--classify-repeats={}", self.classify_repeats),
            format!("--budget={}", self.budget),
            format!("--min-repeat={}", self.min_repeat),
            format!("--max-repeat={}", self.max_repeat),
            format!("--slow-s={}", self.slow_s),
        ]
    }
}

#[derive(Args)]
struct RunArgs {
    /// The manifest written by `peer_ocp.py export`.
    #[arg(long)]
    manifest: PathBuf,
    /// Output JSON lines (appended).
    #[arg(long, default_value = "bench/results/brep_raw.jsonl")]
    jsonl: PathBuf,
    /// Wall-clock limit of a part's trim child (every ε and the classification), seconds.
    #[arg(long = "trim-timeout", default_value_t = 120.0)]
    trim_timeout: f64,
    /// Wall-clock limit of one tessellation child (one tolerance and pool size), seconds.
    #[arg(long = "tess-timeout", default_value_t = 90.0)]
    tess_timeout: f64,
    /// Only these parts (names, comma-separated).
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
    #[command(flatten)]
    settings: Settings,
}

#[derive(Args)]
struct OneArgs {
    /// The part's tessd-brep JSON.
    part: PathBuf,
    /// `trim` (the doc, trim and classify records) or `tess` (one tessellate record).
    #[arg(long, default_value = "trim")]
    step: String,
    /// The tessellation tolerance (mm) of `--step tess`.
    #[arg(long, default_value_t = 0.1)]
    tol: f64,
    /// The rayon pool size of `--step tess`.
    #[arg(long = "pool", default_value_t = 1)]
    pool: usize,
    #[command(flatten)]
    settings: Settings,
}

fn main() -> ExitCode {
    let result = match Cli::parse() {
        Cli::Run(a) => run(a),
        Cli::One(a) => {
            let settings: one::Settings = a.settings.into();
            match a.step.as_str() {
                "trim" => one::trim_step(&a.part, &settings),
                "tess" => one::tess_step(&a.part, a.tol, a.pool, &settings),
                other => Err(format!("unknown step {other} (trim, tess)")),
            }
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench-brep: {e}");
            ExitCode::FAILURE
        }
    }
}

impl From<Settings> for one::Settings {
    fn from(s: Settings) -> one::Settings {
        one::Settings {
            eps_mm: s.eps,
            points: s.points,
            classify_repeats: s.classify_repeats.max(1),
            budget_s: s.budget,
            min_repeat: s.min_repeat.max(1),
            max_repeat: s.max_repeat.max(s.min_repeat).max(1),
            slow_s: s.slow_s,
        }
    }
}

/// What a finished (or killed) child left.
struct ChildOutput {
    stdout: String,
    stderr: String,
    status: Option<std::process::ExitStatus>,
    timed_out: bool,
}

/// Runs `cmd`, killing it after `limit`; both streams are drained by threads meanwhile.
fn run_limited(mut cmd: Command, limit: Duration) -> std::io::Result<ChildOutput> {
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn()?;
    let drain = |r: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut s = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut s);
            }
            String::from_utf8_lossy(&s).into_owned()
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|r| Box::new(r) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|r| Box::new(r) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break Some(s);
        }
        if start.elapsed() > limit {
            timed_out = true;
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Ok(ChildOutput {
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
        status,
        timed_out,
    })
}

/// The harness's output file and progress.
struct Sink {
    out: std::fs::File,
    path: PathBuf,
}

impl Sink {
    fn write(&mut self, rec: &Value) -> Result<(), String> {
        writeln!(self.out, "{rec}").map_err(|e| format!("{}: {e}", self.path.display()))
    }
}

/// How a child ended, for the harness's decisions.
struct Outcome {
    /// Its records, as written.
    records: Vec<Value>,
    /// Killed at the limit.
    timed_out: bool,
    /// One line per record, for the progress line.
    progress: Vec<String>,
}

/// Runs one child and writes its records (plus an error record if it did not finish).
fn child(
    sink: &mut Sink,
    cmd: Command,
    limit: f64,
    name: &str,
    context: Value,
) -> Result<Outcome, String> {
    let res = run_limited(cmd, Duration::from_secs_f64(limit))
        .map_err(|e| format!("could not start a child: {e}"))?;
    let mut records = Vec::new();
    let mut progress = Vec::new();
    for line in res.stdout.lines().filter(|l| !l.trim().is_empty()) {
        let mut rec: Value = match serde_json::from_str(line) {
            Ok(v) => v,
            Err(e) => json!({"kind": "garbled", "error": format!("{e}: {line:.200}")}),
        };
        rec["tool"] = json!("tessd");
        rec["part"] = json!(name);
        progress.push(summary(&rec));
        sink.write(&rec)?;
        records.push(rec);
    }
    if !res.status.is_some_and(|s| s.success()) {
        let last = res
            .stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("")
            .to_string();
        let why = if res.timed_out {
            format!("killed after the {limit} s limit")
        } else {
            res.status
                .map_or("no status".to_string(), |s| s.to_string())
        };
        let mut rec = json!({"tool": "tessd", "part": name, "kind": "child", "error": why,
                             "timed_out": res.timed_out, "last_step": last,
                             "lines_before": records.len()});
        if let (Some(r), Some(c)) = (rec.as_object_mut(), context.as_object()) {
            for (k, v) in c {
                r.insert(k.clone(), v.clone());
            }
        }
        sink.write(&rec)?;
        progress.push(format!("ERROR {why} in: {last}"));
    }
    Ok(Outcome {
        records,
        timed_out: res.timed_out,
        progress,
    })
}

fn run(a: RunArgs) -> Result<(), String> {
    let text = std::fs::read_to_string(&a.manifest)
        .map_err(|e| format!("{}: {e}", a.manifest.display()))?;
    let manifest: Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", a.manifest.display()))?;
    let parts = manifest
        .as_array()
        .ok_or_else(|| format!("{}: not a JSON array", a.manifest.display()))?;
    let exe = std::env::current_exe().map_err(|e| format!("own path: {e}"))?;
    if let Some(dir) = a.jsonl.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let out = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&a.jsonl)
        .map_err(|e| format!("{}: {e}", a.jsonl.display()))?;
    let mut sink = Sink {
        out,
        path: a.jsonl.clone(),
    };
    // Coarse tolerances first (a part too slow at one is not tried finer); the largest pool
    // first (a part too slow with it is not tried with fewer threads).
    let mut tols = a.settings.tols.clone();
    tols.sort_by(|x, y| y.total_cmp(x));
    let mut pools = a.settings.threads.clone();
    pools.sort_unstable_by(|x, y| y.cmp(x));
    pools.dedup();
    let total = parts.len();
    for (i, p) in parts.iter().enumerate() {
        let name = p["name"].as_str().unwrap_or("?").to_string();
        if !a.only.is_empty() && !a.only.contains(&name) {
            continue;
        }
        let started = Instant::now();
        if let Some(e) = p.get("error") {
            sink.write(&json!({"tool": "tessd", "part": name, "kind": "export", "error": e}))?;
            eprintln!("[{:>2}/{total}] {name:<34} export failed: {e}", i + 1);
            continue;
        }
        let Some(path) = p["json"].as_str() else {
            sink.write(&json!({"tool": "tessd", "part": name, "kind": "export",
                               "error": "no json in the manifest"}))?;
            continue;
        };
        let mut progress = Vec::new();
        let mut cmd = Command::new(&exe);
        cmd.arg("one")
            .arg(path)
            .arg("--step=trim")
            .args(a.settings.to_args());
        let o = child(
            &mut sink,
            cmd,
            a.trim_timeout,
            &name,
            json!({"step": "trim"}),
        )?;
        progress.extend(o.progress);
        let mut stop: Option<String> = None;
        for &tol in &tols {
            for (k, &pool) in pools.iter().enumerate() {
                if let Some(why) = &stop {
                    sink.write(&json!({"tool": "tessd", "part": name, "kind": "tessellate",
                                       "tol_mm": tol, "threads": pool, "skipped": why}))?;
                    continue;
                }
                let mut cmd = Command::new(&exe);
                cmd.arg("one")
                    .arg(path)
                    .arg("--step=tess")
                    .arg(format!("--tol={tol}"))
                    .arg(format!("--pool={pool}"))
                    .args(a.settings.to_args());
                let o = child(
                    &mut sink,
                    cmd,
                    a.tess_timeout,
                    &name,
                    json!({"step": "tessellate", "tol_mm": tol, "threads": pool}),
                )?;
                progress.extend(o.progress);
                if o.timed_out {
                    stop = Some(format!(
                        "not run: tol {tol} mm with {pool} threads ran past the {} s limit",
                        a.tess_timeout
                    ));
                    continue;
                }
                let slow = o
                    .records
                    .iter()
                    .any(|r| r["only_warmup"].as_bool() == Some(true));
                if slow && k + 1 < pools.len() {
                    for &rest in &pools[k + 1..] {
                        sink.write(&json!({"tool": "tessd", "part": name, "kind": "tessellate",
                            "tol_mm": tol, "threads": rest,
                            "skipped": format!("not run: {pool} threads took over {} s", a.settings.slow_s)}))?;
                    }
                    break;
                }
            }
        }
        eprintln!(
            "[{:>2}/{total}] {name:<34} {:.1} s  {}",
            i + 1,
            started.elapsed().as_secs_f64(),
            progress.join(" | ")
        );
    }
    Ok(())
}

/// A few words about a record, for the progress line.
fn summary(rec: &Value) -> String {
    let f = |k: &str| rec.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN);
    match rec["kind"].as_str() {
        Some("doc") => format!("{} faces", rec["stats"]["faces"]),
        Some("trim") => format!(
            "trim ε={} {:.0} ms{}",
            rec["eps_mm"],
            f("build_total_ms"),
            match rec["failed_faces"].as_u64() {
                Some(0) | None => String::new(),
                Some(n) => format!(" ({n} faces failed)"),
            }
        ),
        Some("classify") => format!(
            "classify ε={} {:.2e} pt/s",
            rec["eps_mm"],
            f("points_per_s")
        ),
        Some("tessellate") => match rec.get("error") {
            Some(e) => format!("tess {}t tol={} ERROR {e}", rec["threads"], rec["tol_mm"]),
            None => format!(
                "tess {}t tol={} {:.1} ms {} tri",
                rec["threads"],
                rec["tol_mm"],
                f("time_ms"),
                rec["triangles"]
            ),
        },
        _ => rec
            .get("error")
            .map_or_else(|| "?".to_string(), |e| format!("ERROR {e}")),
    }
}
