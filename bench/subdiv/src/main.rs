//! `bench-subdiv`: tessd's uniform Catmull–Clark subdivision side by side with OpenSubdiv
//! (through `osd_bench`, the C++ harness next to this crate) on the same cages and levels.
//!
//! ```text
//! bench-subdiv run --cages A.obj,B.obj,.. [--levels 1,2,3,4,5] [--threads 1,2]
//!                  [--tools tessd,gpu,osd] [--osd bench/out/subdiv/osd_bench]
//!                  [--jsonl FILE] [--budget 1.0] [--min-repeat 3] [--max-repeat 15]
//!                  [--osd-budget 4] [--osd-max-repeat 9]
//! bench-subdiv one CAGE LEVEL (--threads N | --gpu) [--budget S] [--min-repeat N] [--max-repeat N]
//! ```
//!
//! `run` is the harness: for every cage and level it runs, each in a fresh child process (so
//! that each configuration's peak memory is its own), `one` with every thread count (tessd on
//! the CPU), `one --gpu` (tessd's GPU apply) and `osd_bench --first-level L --levels L`
//! (OpenSubdiv), and appends one JSON line per configuration to the jsonl (`tool` = `tessd`,
//! `tessd-gpu` or `osd`). The tools of one (cage, level) run back to back, so load from other
//! jobs on the machine hits them alike.
//!
//! `one` measures one configuration in this process and prints one JSON object: tessd's
//! topology phase (`Refiner::new`) and apply phase (`Refiner::apply` of the cage's xyz) in a
//! rayon pool of `--threads` threads, or with `--gpu` the GPU apply. Every timed phase is
//! warmed up once and then run `--budget / warm-up time` times, clamped to
//! `--min-repeat..=--max-repeat`; the median is reported with every run. Memory is the peak
//! resident set over the resident set before the phase (see `mem.rs`).

#![warn(missing_docs)]

mod mem;
mod one;

use clap::{Args, Parser};
use one::Repeats;
use serde_json::{Value, json};
use std::fs::OpenOptions;
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, ExitCode};
use std::time::Instant;

/// Command line.
#[derive(Parser)]
#[command(name = "bench-subdiv", about = "tessd's subdivision beside OpenSubdiv")]
enum Cli {
    /// The harness: every cage × level × tool in its own child process, one JSON line each.
    Run(RunArgs),
    /// One configuration in this process; prints one JSON object.
    One(OneArgs),
}

/// Repeats of every timed phase: `budget / warm-up time`, clamped to `min..=max`.
#[derive(Args, Clone, Copy)]
struct RepeatArgs {
    /// Seconds of runs per phase.
    #[arg(long, default_value_t = 1.0)]
    budget: f64,
    /// Fewest runs.
    #[arg(long = "min-repeat", default_value_t = 3)]
    min_repeat: usize,
    /// Most runs.
    #[arg(long = "max-repeat", default_value_t = 15)]
    max_repeat: usize,
}

impl RepeatArgs {
    fn repeats(self) -> Repeats {
        Repeats {
            budget_s: self.budget,
            min: self.min_repeat,
            max: self.max_repeat,
        }
    }
}

#[derive(Args)]
struct RunArgs {
    /// Cages (OBJ), comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    cages: Vec<PathBuf>,
    /// Levels.
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5")]
    levels: Vec<u32>,
    /// tessd's rayon pool sizes.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    threads: Vec<usize>,
    /// Tools: tessd, gpu, osd.
    #[arg(long, value_delimiter = ',', default_value = "tessd,gpu,osd")]
    tools: Vec<String>,
    /// The OpenSubdiv harness.
    #[arg(long, default_value = "bench/out/subdiv/osd_bench")]
    osd: PathBuf,
    /// Output JSON lines (appended).
    #[arg(long, default_value = "bench/results/subdiv_raw.jsonl")]
    jsonl: PathBuf,
    /// Seconds of runs per OpenSubdiv configuration.
    #[arg(long = "osd-budget", default_value_t = 4.0)]
    osd_budget: f64,
    /// Most OpenSubdiv runs.
    #[arg(long = "osd-max-repeat", default_value_t = 9)]
    osd_max_repeat: u32,
    #[command(flatten)]
    repeat: RepeatArgs,
}

#[derive(Args)]
struct OneArgs {
    /// The cage (OBJ).
    cage: PathBuf,
    /// Levels.
    level: u32,
    /// tessd on the CPU in a pool of this many threads.
    #[arg(long, required_unless_present = "gpu")]
    threads: Option<usize>,
    /// tessd's GPU apply instead.
    #[arg(long)]
    gpu: bool,
    #[command(flatten)]
    repeat: RepeatArgs,
}

fn main() -> ExitCode {
    let result = match Cli::parse() {
        Cli::Run(a) => run(a),
        Cli::One(a) => one_cmd(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench-subdiv: {e}");
            ExitCode::FAILURE
        }
    }
}

// ---------------------------------------------------------------------------------------
// Child: one configuration.

fn one_cmd(a: OneArgs) -> Result<(), String> {
    let repeats = a.repeat.repeats();
    let rec = match a.threads {
        _ if a.gpu => one::tessd_gpu(&a.cage, a.level, repeats)?,
        Some(threads) => one::tessd_cpu(&a.cage, a.level, threads, repeats)?,
        None => return Err("one needs --threads or --gpu".to_string()),
    };
    println!("{rec}");
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Harness.

/// One child to run: what it is, and its command line.
struct Job {
    label: String,
    tool: &'static str,
    threads: Option<usize>,
    cage: PathBuf,
    level: u32,
    command: Command,
}

fn run(a: RunArgs) -> Result<(), String> {
    let RunArgs {
        cages,
        levels,
        threads,
        tools,
        osd,
        jsonl,
        osd_budget,
        osd_max_repeat: osd_max,
        repeat,
    } = a;
    let repeats = repeat.repeats();
    let exe = std::env::current_exe().map_err(|e| format!("own path: {e}"))?;
    for cage in &cages {
        if !cage.is_file() {
            return Err(format!("no cage at {}", cage.display()));
        }
    }
    if tools.iter().any(|t| t == "osd") && !osd.is_file() {
        return Err(format!(
            "no osd_bench at {} (bash bench/subdiv/setup_osd.sh builds it)",
            osd.display()
        ));
    }
    if let Some(dir) = jsonl.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }

    let repeat_args = |cmd: &mut Command| {
        cmd.args(["--budget", &repeats.budget_s.to_string()])
            .args(["--min-repeat", &repeats.min.to_string()])
            .args(["--max-repeat", &repeats.max.to_string()]);
    };
    let mut jobs = Vec::new();
    for cage in &cages {
        let name = cage
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        for &level in &levels {
            for tool in &tools {
                match tool.as_str() {
                    "tessd" => {
                        for &t in &threads {
                            let mut cmd = Command::new(&exe);
                            cmd.arg("one").arg(cage).arg(level.to_string());
                            cmd.args(["--threads", &t.to_string()]);
                            repeat_args(&mut cmd);
                            jobs.push(Job {
                                label: format!("tessd {t}t {name} L{level}"),
                                tool: "tessd",
                                threads: Some(t),
                                cage: cage.clone(),
                                level,
                                command: cmd,
                            });
                        }
                    }
                    "gpu" => {
                        let mut cmd = Command::new(&exe);
                        cmd.arg("one").arg(cage).arg(level.to_string()).arg("--gpu");
                        repeat_args(&mut cmd);
                        jobs.push(Job {
                            label: format!("tessd-gpu {name} L{level}"),
                            tool: "tessd-gpu",
                            threads: None,
                            cage: cage.clone(),
                            level,
                            command: cmd,
                        });
                    }
                    "osd" => {
                        let mut cmd = Command::new(&osd);
                        cmd.arg(cage);
                        cmd.args(["--first-level", &level.to_string()]);
                        cmd.args(["--levels", &level.to_string()]);
                        cmd.args(["--repeat", &osd_max.to_string()]);
                        cmd.args(["--budget", &osd_budget.to_string()]);
                        cmd.args(["--boundary", "edge-and-corner"]);
                        jobs.push(Job {
                            label: format!("osd {name} L{level}"),
                            tool: "osd",
                            threads: None,
                            cage: cage.clone(),
                            level,
                            command: cmd,
                        });
                    }
                    other => return Err(format!("unknown tool {other} (tessd, gpu, osd)")),
                }
            }
        }
    }

    let mut out = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&jsonl)
        .map_err(|e| format!("{}: {e}", jsonl.display()))?;
    let total = jobs.len();
    for (i, mut job) in jobs.into_iter().enumerate() {
        let t = Instant::now();
        let result = job.command.output();
        let wall_s = t.elapsed().as_secs_f64();
        let mut rec = match result {
            Ok(o) if o.status.success() => {
                let stdout = String::from_utf8_lossy(&o.stdout);
                match stdout
                    .lines()
                    .rev()
                    .find(|l| !l.trim().is_empty())
                    .map(serde_json::from_str::<Value>)
                {
                    Some(Ok(v)) => v,
                    _ => json!({"error": format!("no JSON in the output: {}", tail(&stdout))}),
                }
            }
            Ok(o) => {
                json!({"error": format!("{}: {}", o.status, tail(&String::from_utf8_lossy(&o.stderr)))})
            }
            Err(e) => json!({"error": format!("could not start: {e}")}),
        };
        rec["tool"] = json!(job.tool);
        rec["cage"] = json!(
            job.cage
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
        );
        rec["cage_path"] = json!(job.cage.display().to_string());
        rec["level"] = json!(job.level);
        if let Some(t) = job.threads {
            rec["threads"] = json!(t);
        }
        rec["child_wall_s"] = json!(wall_s);
        writeln!(out, "{rec}").map_err(|e| format!("{}: {e}", jsonl.display()))?;
        eprintln!(
            "[{:>3}/{total}] {:<36} {}",
            i + 1,
            job.label,
            summary(&rec, wall_s)
        );
    }
    Ok(())
}

/// The last few lines of a child's output, for an error record.
fn tail(s: &str) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(5)..].join(" | ")
}

/// One line of progress for a record.
fn summary(rec: &Value, wall_s: f64) -> String {
    let ms = |k: &str| rec.get(k).and_then(Value::as_f64);
    let f = |k: &str| ms(k).map_or("-".to_string(), |v| format!("{v:.3}"));
    let head = if let Some(e) = rec.get("error") {
        format!("ERROR {e}")
    } else if let Some(s) = rec.get("skipped") {
        format!("skipped: {s}")
    } else {
        match rec["tool"].as_str() {
            Some("osd") => format!(
                "topology {} primvar {} stencils {} + {} ms",
                f("topology_ms"),
                f("primvar_ms"),
                f("stencil_build_ms"),
                f("stencil_eval_ms")
            ),
            Some("tessd-gpu") => format!("apply {} (device {}) ms", f("apply_ms"), f("device_ms")),
            _ => format!("topology {} apply {} ms", f("topology_ms"), f("apply_ms")),
        }
    };
    format!(
        "{head}  out {}  [{wall_s:.1} s]",
        rec.get("out_vertices").map_or("-".into(), Value::to_string)
    )
}
