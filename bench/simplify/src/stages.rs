//! `stages`: the time of each library stage of every tessd mode, one thread, on generated
//! tori (issue 33's "stage times of each mode, before and after").
//!
//! ```text
//! bench-simplify stages --out FILE.json [--sizes 1,4] [--fraction 0.1] [--repeat 3]
//!                       [--methods a,b,..] [--label TEXT]
//! ```
//!
//! For every torus of `--sizes` (millions of triangles, [`generate::bumpy_torus`], the
//! harness's inputs) and every tessd method, the parameter landing at `--fraction` of the
//! input vertices is searched (untimed, [`params::find_param`]: the same parameter as the
//! harness's); then `--repeat` rounds run every method once each (interleaved, so that a
//! slow spell of the machine spreads over all of them) with a [`StageClock`] on the
//! library's progress callback. The JSON holds, per (torus, method), the call's times and
//! per stage its times and median. The pass runs with one thread: without
//! `RAYON_NUM_THREADS=1` it starts itself again with it.

use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::Command;

use crate::cli::{list, opt, options, parse};
use crate::generate;
use crate::inputs::{cpu_model, stats};
use crate::methods::{self, Input, Method};
use crate::params::find_param;
use crate::timing::{StageClock, median};

/// The stages of one timed call.
type Stages = Vec<(String, f64, u32)>;

/// One method's parameter and its timed calls on one input.
struct Timed {
    method: Method,
    param: f64,
    evals: u32,
    stages: Vec<Stages>,
    totals: Vec<f64>,
    out_vertices: u64,
}

/// The `stages` subcommand.
pub fn stages_cmd(args: &[String]) -> Result<(), String> {
    if std::env::var("RAYON_NUM_THREADS").ok().as_deref() != Some("1") {
        let exe = std::env::current_exe().map_err(|e| e.to_string())?;
        let status = Command::new(exe)
            .arg("stages")
            .args(args)
            .env("RAYON_NUM_THREADS", "1")
            .status()
            .map_err(|e| e.to_string())?;
        return if status.success() {
            Ok(())
        } else {
            Err(format!("stages (one thread): {status}"))
        };
    }
    let (_, opts) = options(args)?;
    let out = PathBuf::from(opt(&opts, "out").ok_or("stages needs --out FILE.json")?);
    let sizes: Vec<f64> = list(opt(&opts, "sizes").unwrap_or("1,4"), "size")?;
    let fraction: f64 = parse(opt(&opts, "fraction").unwrap_or("0.1"), "--fraction")?;
    let repeat: usize = parse(opt(&opts, "repeat").unwrap_or("3"), "--repeat")?;
    let chosen: Vec<Method> = match opt(&opts, "methods") {
        Some(s) => s
            .split(',')
            .map(|m| Method::parse(m).ok_or_else(|| format!("unknown method {m}")))
            .collect::<Result<_, _>>()?,
        None => methods::ALL
            .into_iter()
            .filter(|m| !m.is_meshopt())
            .collect(),
    };
    let unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let mut results: Vec<Value> = Vec::new();
    for &size in &sizes {
        let name = format!("torus_{size}M");
        let mesh = generate::bumpy_torus((size * 1e6).round() as u64);
        let st = stats(&mesh);
        let target = (fraction * st.vertices as f64).round() as u64;
        let input = Input::Mesh(mesh);
        eprintln!(
            "== stages {name}: {} vertices, {} triangles, target {target}",
            st.vertices, st.triangles
        );
        let mut runs: Vec<Timed> = Vec::new();
        for &method in chosen.iter().filter(|m| !m.is_meshopt()) {
            let found = find_param(method, &input, &st, target)?;
            runs.push(Timed {
                method,
                param: found.param,
                evals: found.evals,
                stages: Vec::new(),
                totals: Vec::new(),
                out_vertices: 0,
            });
        }
        for _ in 0..repeat.max(1) {
            for Timed {
                method,
                param,
                stages,
                totals,
                out_vertices,
                ..
            } in &mut runs
            {
                let mut clock = Some(StageClock::start());
                let o = methods::run_observed(*method, &input, *param, &mut |_, stage| {
                    clock.as_mut().expect("clock running").mark(stage);
                    true
                })?;
                let (s, total) = clock.take().expect("clock running").finish();
                *out_vertices = o.counts(&input).0;
                drop(o);
                stages.push(s);
                totals.push(total);
            }
        }
        for Timed {
            method,
            param,
            evals,
            stages,
            totals,
            out_vertices,
        } in runs
        {
            let mut names: Vec<String> = Vec::new();
            for s in stages.iter().flatten() {
                if !names.contains(&s.0) {
                    names.push(s.0.clone());
                }
            }
            let per_stage: Vec<Value> = names
                .iter()
                .map(|n| {
                    let (times, spans): (Vec<f64>, Vec<u32>) = stages
                        .iter()
                        .map(|run| {
                            run.iter()
                                .find(|s| &s.0 == n)
                                .map_or((0.0, 0), |s| (s.1, s.2))
                        })
                        .unzip();
                    json!({
                        "stage": n,
                        "median_s": median(&times),
                        "times_s": times,
                        "spans": spans.iter().copied().max().unwrap_or(0),
                    })
                })
                .collect();
            let t = median(&totals);
            eprintln!(
                "   {:<25} {:>9.1} ms  {}",
                method.name(),
                t * 1e3,
                per_stage
                    .iter()
                    .map(|s| format!(
                        "{} {:.1}",
                        s["stage"].as_str().unwrap_or("?"),
                        s["median_s"].as_f64().unwrap_or(0.0) * 1e3
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            results.push(json!({
                "mesh": name,
                "input_vertices": st.vertices,
                "input_triangles": st.triangles,
                "fraction": fraction,
                "target_vertices": target,
                "method": method.name(),
                "param_name": method.param_name(),
                "param": param,
                "search_evals": evals,
                "out_vertices": out_vertices,
                "times_s": totals,
                "time_s": t,
                "stages": per_stage,
            }));
        }
    }
    let doc = json!({
        "meta": {
            "unix_time": unix,
            "label": opt(&opts, "label").unwrap_or(""),
            "cpu_model": cpu_model(),
            "nproc": std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0),
            "threads": 1,
            "repeat": repeat,
            "fraction": fraction,
            "sizes": sizes,
        },
        "runs": results,
    });
    if let Some(d) = out.parent() {
        std::fs::create_dir_all(d).map_err(|e| e.to_string())?;
    }
    std::fs::write(&out, serde_json::to_string_pretty(&doc).unwrap() + "\n")
        .map_err(|e| format!("{}: {e}", out.display()))
}
