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

use one::Repeats;
use serde_json::{Value, json};
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("run") => run(&args[1..]),
        Some("one") => one_cmd(&args[1..]),
        _ => Err(USAGE.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench-subdiv: {e}");
            ExitCode::FAILURE
        }
    }
}

const USAGE: &str = "usage: bench-subdiv run --cages A.obj,B.obj [--levels 1,2,3,4,5] [--threads 1,2] \
                     [--tools tessd,gpu,osd] [--osd PATH] [--jsonl FILE] [--budget S] \
                     [--min-repeat N] [--max-repeat N] [--osd-budget S] [--osd-max-repeat N]\n       \
                     bench-subdiv one CAGE LEVEL (--threads N | --gpu) [--budget S] \
                     [--min-repeat N] [--max-repeat N]";

/// Positional arguments and `--key value` pairs (`--gpu` takes no value).
type Parsed = (Vec<String>, Vec<(String, String)>);

fn options(args: &[String]) -> Result<Parsed, String> {
    let (mut pos, mut opts) = (Vec::new(), Vec::new());
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if let Some(k) = a.strip_prefix("--") {
            if k == "gpu" {
                opts.push((k.to_string(), String::new()));
                continue;
            }
            let v = it.next().ok_or_else(|| format!("--{k} needs a value"))?;
            opts.push((k.to_string(), v.clone()));
        } else {
            pos.push(a.clone());
        }
    }
    Ok((pos, opts))
}

fn opt<'a>(opts: &'a [(String, String)], key: &str) -> Option<&'a str> {
    opts.iter()
        .rev()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

fn parse<T: std::str::FromStr>(s: &str, what: &str) -> Result<T, String> {
    s.parse().map_err(|_| format!("bad {what}: {s}"))
}

fn list<T: std::str::FromStr>(s: &str, what: &str) -> Result<Vec<T>, String> {
    s.split(',')
        .filter(|x| !x.is_empty())
        .map(|x| parse(x, what))
        .collect()
}

fn repeats(opts: &[(String, String)]) -> Result<Repeats, String> {
    Ok(Repeats {
        budget_s: parse(opt(opts, "budget").unwrap_or("1.0"), "--budget")?,
        min: parse(opt(opts, "min-repeat").unwrap_or("3"), "--min-repeat")?,
        max: parse(opt(opts, "max-repeat").unwrap_or("15"), "--max-repeat")?,
    })
}

// ---------------------------------------------------------------------------------------
// Child: one configuration.

fn one_cmd(args: &[String]) -> Result<(), String> {
    let (pos, opts) = options(args)?;
    let [cage, level] = pos.as_slice() else {
        return Err(USAGE.to_string());
    };
    let level: u32 = parse(level, "level")?;
    let repeats = repeats(&opts)?;
    let rec = if opt(&opts, "gpu").is_some() {
        one::tessd_gpu(Path::new(cage), level, repeats)?
    } else {
        let threads = parse(
            opt(&opts, "threads").ok_or("one needs --threads or --gpu")?,
            "--threads",
        )?;
        one::tessd_cpu(Path::new(cage), level, threads, repeats)?
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

fn run(args: &[String]) -> Result<(), String> {
    let (pos, opts) = options(args)?;
    if !pos.is_empty() {
        return Err(USAGE.to_string());
    }
    let cages: Vec<PathBuf> = opt(&opts, "cages")
        .ok_or("run needs --cages")?
        .split(',')
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
        .collect();
    let levels: Vec<u32> = list(opt(&opts, "levels").unwrap_or("1,2,3,4,5"), "--levels")?;
    let threads: Vec<usize> = list(opt(&opts, "threads").unwrap_or("1,2"), "--threads")?;
    let tools: Vec<String> = list(opt(&opts, "tools").unwrap_or("tessd,gpu,osd"), "--tools")?;
    let osd = PathBuf::from(opt(&opts, "osd").unwrap_or("bench/out/subdiv/osd_bench"));
    let jsonl = PathBuf::from(opt(&opts, "jsonl").unwrap_or("bench/results/subdiv_raw.jsonl"));
    let osd_budget: f64 = parse(opt(&opts, "osd-budget").unwrap_or("4"), "--osd-budget")?;
    let osd_max: u32 = parse(
        opt(&opts, "osd-max-repeat").unwrap_or("9"),
        "--osd-max-repeat",
    )?;
    let repeats = repeats(&opts)?;
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
