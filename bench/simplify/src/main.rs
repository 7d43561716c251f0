//! `bench-simplify`: tessd's simplification side by side with meshoptimizer (and, through
//! `meshlab.py`, MeshLab's vertex clustering) at matched output vertex counts.
//!
//! ```text
//! bench-simplify run [--data DIR] [--work DIR] [--jsonl FILE] [--manifest FILE]
//!                    [--sizes 0.1,1,10] [--scaling-sizes 0.3,3] [--scaling-fraction 0.1]
//!                    [--fractions 0.5,0.1,0.01] [--methods a,b,..] [--meshes a,b,..]
//!                    [--no-shared] [--repeat 3] [--budget 12] [--threads 1]
//!                    [--scaling-threads 2] [--scaling-threads-min-triangles 0]
//!                    [--big] [--big-sizes 50] [--big-fractions 0.1]
//! bench-simplify one METHOD INPUT PARAM --out OUT.ply [--repeat 3] [--budget 12]
//! bench-simplify compare OUTPUT INPUT --samples N
//! bench-simplify gen TRIANGLES OUT.ply
//! bench-simplify arrays INPUT DIR
//! bench-simplify stages --out FILE.json [--sizes 1,4] [--fraction 0.1] [--repeat 3]
//! bench-simplify peer METHOD INPUT TARGET_VERTICES [--repeat 5] [--budget 40]
//! ```
//!
//! `run` is the harness: for every input (the shared meshes of `$TESSD_SHARED_DATA/mesh`
//! and generated bumpy tori of the given sizes, in millions of triangles; the scaling sizes
//! only at the scaling fraction) and every target fraction of the referenced vertices, it finds each method's parameter landing at the
//! target vertex count (untimed, in process), then times the method in a child process
//! (`one`, which also reports peak memory), measures the output against the input with
//! tessd-compare and appends one JSON line per (mesh, method, target) to the jsonl. It also
//! writes a manifest of the inputs (paths, counts, targets, sample count) for `meshlab.py`.
//! `compare` prints the distance of one output to its input as JSON (used by `meshlab.py`, so
//! every error comes from the same tool and options). Timed children run with
//! `RAYON_NUM_THREADS=--threads` (1 by default: throughput per core, like meshoptimizer's).
//!
//! Thread scaling: every tessd method (inputs of at least `--scaling-threads-min-triangles`) is
//! timed again in a child with each of `--scaling-threads` (`RAYON_NUM_THREADS`, default 2;
//! `""` for none) with the parameter found for one thread; the record's `scaling` list holds
//! those times and whether the output is byte-identical to the one-thread output.
//!
//! Big inputs: with `--big` (or `SIMPLIFY_BENCH_50M=1` in the environment) the tori of
//! `--big-sizes` (50 M triangles) are added, at `--big-fractions` only (10 %: one target keeps
//! the run short; runs over the budget are timed once, as everywhere).
//!
//! `arrays` writes a mesh as fan-triangulated raw arrays, `DIR/positions.f32` ([V, 3] f32) and
//! `DIR/faces.u32` ([T, 3] u32), and prints their shapes as JSON (for `e2e_daemon.py`, which
//! sends them to the daemon).
//!
//! `stages` times each library stage of every tessd mode (the spans between the progress
//! callbacks, one thread; see `stages.rs`); `peer` times one method matched to an output
//! vertex count in this process, for `headline.py` (see `peer.rs`).

mod cli;
mod generate;
mod inputs;
mod mem;
mod methods;
mod params;
mod peer;
mod search;
mod stages;
mod timing;

use cli::{list, opt, options, parse};
use inputs::{Stats, cpu_model, read, stats};
use methods::{Input, Method, Triangles};
use serde_json::{Value, json};
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;
use tessd_compare::{CompareOptions, Comparison, SurfaceIndex, bbox_diagonal};
use tessd_mesh::Mesh;
use tessd_mesh::io::write_path;
use timing::median;

/// Mesh-sized buffers on huge pages where the kernel grants them (`tessd_mesh::allocation`).
#[global_allocator]
static ALLOCATOR: tessd_mesh::allocation::LargePages = tessd_mesh::allocation::LargePages;

fn main() -> ExitCode {
    // The daemon's allocation policy, so that the library's figures are the daemon's.
    tessd_mesh::allocation::return_large_buffers_to_system();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("run") => run(&args[1..]),
        Some("one") => one(&args[1..]),
        Some("compare") => compare_cmd(&args[1..]),
        Some("gen") => gen_cmd(&args[1..]),
        Some("arrays") => arrays_cmd(&args[1..]),
        Some("stages") => stages::stages_cmd(&args[1..]),
        Some("peer") => peer::peer_cmd(&args[1..]),
        _ => Err(USAGE.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench-simplify: {e}");
            ExitCode::FAILURE
        }
    }
}

const USAGE: &str = "usage: bench-simplify run [options] | one METHOD INPUT PARAM --out OUT.ply \
                     [--repeat N] [--budget S] | compare OUTPUT INPUT --samples N | gen TRIANGLES OUT.ply | \
                     arrays INPUT DIR | stages --out FILE.json [--sizes 1,4] [--fraction 0.1] \
                     [--repeat 3] | peer METHOD INPUT TARGET_VERTICES [--repeat N] [--budget S]";

// ---------------------------------------------------------------------------------------
// Child: one timed method run with peak memory.

fn one(args: &[String]) -> Result<(), String> {
    let (pos, opts) = options(args)?;
    let [method, input, param] = pos.as_slice() else {
        return Err(USAGE.to_string());
    };
    let method = Method::parse(method).ok_or_else(|| format!("unknown method {method}"))?;
    let param: f64 = parse(param, "parameter")?;
    let out = PathBuf::from(opt(&opts, "out").ok_or("one needs --out")?);
    let repeat: u32 = parse(opt(&opts, "repeat").unwrap_or("3"), "--repeat")?;
    let budget: f64 = parse(opt(&opts, "budget").unwrap_or("12"), "--budget")?;

    let rss_start = mem::status_kib("VmRSS");
    let mesh = read(Path::new(input))?;
    let triangles = mesh.triangle_count() as u64;
    let input_bytes = 12 * mesh.positions.len() as u64 + 12 * triangles;
    let held_bytes = if method.is_meshopt() {
        input_bytes
    } else {
        12 * mesh.positions.len() as u64
            + 4 * (mesh.face_indices.len() + mesh.face_offsets.len()) as u64
    };
    let input = Input::for_method(method, mesh);
    let hwm_load = mem::status_kib("VmHWM");
    let reset_ok = mem::reset_peak();
    let rss_before = mem::status_kib("VmRSS");

    let mut times = Vec::new();
    let mut last = None;
    let t_all = Instant::now();
    while times.len() < repeat.max(1) as usize {
        if let Some(&prev) = times.last()
            && t_all.elapsed().as_secs_f64() + prev > budget
        {
            break;
        }
        drop(last.take()); // free the previous output before the next run
        // Between jobs the daemon, idle, returns freed memory to the system: the same here, so
        // that every run starts from the heap a daemon's job starts from (untimed).
        tessd_mesh::allocation::release_free_memory();
        let t = Instant::now();
        let o = methods::run(method, &input, param)?;
        times.push(t.elapsed().as_secs_f64());
        last = Some(o);
    }
    let hwm_run = mem::status_kib("VmHWM");
    let output = last.expect("one run at least");
    let (out_vertices, out_faces) = output.counts(&input);
    let (max_disp, report_vertices) = match &output {
        methods::Output::Tessd(s) => (
            Some(s.report.max_displacement),
            Some(s.report.output_vertices),
        ),
        methods::Output::Indices(_) => (None, None),
    };
    let out_mesh = output.into_mesh(&input);
    write_path(&out_mesh, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    let rec = json!({
        "method": method.name(),
        "param": param,
        "times_s": times,
        "out_vertices": out_vertices,
        "out_faces": out_faces,
        "out_triangles": out_mesh.triangle_count(),
        "input_triangles": triangles,
        "input_bytes": input_bytes,
        "held_bytes": held_bytes,
        "rss_start_kib": rss_start,
        "hwm_load_kib": hwm_load,
        "rss_before_run_kib": rss_before,
        "hwm_run_kib": hwm_run,
        "peak_reset_ok": reset_ok,
        "max_displacement": max_disp,
        "report_output_vertices": report_vertices,
        "threads": std::env::var("RAYON_NUM_THREADS").ok(),
    });
    println!("{rec}");
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Error measurement.

/// Face samples per direction for an input of this size (Metro's 10 per triangle, clamped);
/// every output of one input is measured with the same count.
fn face_samples(input_triangles: u64) -> u64 {
    (10 * input_triangles).clamp(100_000, 2_000_000)
}

/// Inputs up to this many triangles are also sampled at every vertex (Metro's default);
/// larger ones (the 3 M and 10 M scaling meshes) by face samples only, to keep the run short.
const VERTEX_SAMPLES_MAX_TRIANGLES: u64 = 2_000_000;

fn vertex_samples(input_triangles: u64) -> bool {
    input_triangles <= VERTEX_SAMPLES_MAX_TRIANGLES
}

/// Distances between `out` and `input` (whose index is `input_index`) as JSON fields.
fn measure(out: &Mesh, input: &Mesh, input_index: &SurfaceIndex, samples: u64) -> Value {
    let vertices = vertex_samples(input.triangle_count() as u64);
    let opts = CompareOptions::default()
        .with_samples(samples)
        .with_vertices(vertices);
    let t = Instant::now();
    let result = (|| {
        let out_index = SurfaceIndex::new(out).map_err(|e| e.to_string())?;
        let in_to_out = out_index
            .distance_from(input, &opts)
            .map_err(|e| e.to_string())?;
        let out_to_in = input_index
            .distance_from(out, &opts)
            .map_err(|e| e.to_string())?;
        Ok::<_, String>(Comparison::from_directions(
            out_to_in,
            in_to_out,
            bbox_diagonal(out, input),
        ))
    })();
    match result {
        Ok(c) => json!({
            "hausdorff": c.hausdorff,
            "rms": c.rms,
            "mean": c.mean,
            "out_to_in_max": c.a_to_b.max,
            "in_to_out_max": c.b_to_a.max,
            "out_to_in_rms": c.a_to_b.rms,
            "in_to_out_rms": c.b_to_a.rms,
            "bbox_diagonal": c.bbox_diagonal,
            "hausdorff_rel": c.hausdorff_relative(),
            "rms_rel": if c.bbox_diagonal > 0.0 { c.rms / c.bbox_diagonal } else { 0.0 },
            "face_samples": samples,
            "vertex_samples": vertices,
            "samples_out": c.a_to_b.samples,
            "samples_in": c.b_to_a.samples,
            "compare_s": t.elapsed().as_secs_f64(),
        }),
        Err(e) => json!({ "compare_error": e, "face_samples": samples }),
    }
}

fn compare_cmd(args: &[String]) -> Result<(), String> {
    let (pos, opts) = options(args)?;
    let [out, input] = pos.as_slice() else {
        return Err(USAGE.to_string());
    };
    let (out, input) = (read(Path::new(out))?, read(Path::new(input))?);
    let samples = match opt(&opts, "samples") {
        Some(s) => parse(s, "--samples")?,
        None => face_samples(input.triangle_count() as u64),
    };
    let index = SurfaceIndex::new(&input).map_err(|e| e.to_string())?;
    let mut v = measure(&out, &input, &index, samples);
    v["out_vertices"] = json!(methods::referenced(&out.face_indices, out.positions.len()));
    v["out_faces"] = json!(out.face_count());
    println!("{v}");
    Ok(())
}

fn gen_cmd(args: &[String]) -> Result<(), String> {
    let [t, out] = args else {
        return Err(USAGE.to_string());
    };
    let m = generate::bumpy_torus(parse::<f64>(t, "triangles")? as u64);
    write_path(&m, Path::new(out)).map_err(|e| e.to_string())
}

fn arrays_cmd(args: &[String]) -> Result<(), String> {
    let [input, dir] = args else {
        return Err(USAGE.to_string());
    };
    let mesh = read(Path::new(input))?;
    let dir = Path::new(dir);
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let tris = Triangles::from_mesh(&mesh);
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("positions.f32", bytemuck::cast_slice(&tris.positions))?;
    write("faces.u32", bytemuck::cast_slice(&tris.indices))?;
    println!(
        "{}",
        json!({"vertices": tris.positions.len(), "triangles": tris.indices.len() / 3})
    );
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Harness.

struct Config {
    work: PathBuf,
    jsonl: PathBuf,
    fractions: Vec<f64>,
    methods: Vec<Method>,
    repeat: u32,
    budget: f64,
    threads: String,
    /// Further thread counts timed for the tessd methods (thread scaling).
    scaling_threads: Vec<String>,
    /// Inputs below this many triangles get no thread-scaling runs.
    scaling_threads_min_triangles: u64,
}

fn run(args: &[String]) -> Result<(), String> {
    let (_, opts) = options(args)?;
    let data = match opt(&opts, "data") {
        Some(d) => PathBuf::from(d),
        None => std::env::var_os("TESSD_SHARED_DATA")
            .map(|d| PathBuf::from(d).join("mesh"))
            .unwrap_or_else(|| PathBuf::from("/work/shared/data/mesh")),
    };
    let cfg = Config {
        work: PathBuf::from(opt(&opts, "work").unwrap_or("/tmp/tessd-bench-simplify")),
        jsonl: PathBuf::from(opt(&opts, "jsonl").unwrap_or("bench/results/simplify_raw.jsonl")),
        fractions: list(
            opt(&opts, "fractions").unwrap_or("0.5,0.1,0.01"),
            "fraction",
        )?,
        methods: match opt(&opts, "methods") {
            Some(s) => s
                .split(',')
                .map(|m| Method::parse(m).ok_or_else(|| format!("unknown method {m}")))
                .collect::<Result<_, _>>()?,
            None => methods::ALL.to_vec(),
        },
        repeat: parse(opt(&opts, "repeat").unwrap_or("3"), "--repeat")?,
        budget: parse(opt(&opts, "budget").unwrap_or("12"), "--budget")?,
        threads: opt(&opts, "threads").unwrap_or("1").to_string(),
        scaling_threads: opt(&opts, "scaling-threads")
            .unwrap_or("2")
            .split(',')
            .filter(|x| !x.is_empty())
            .map(|x| parse::<u32>(x, "--scaling-threads").map(|n| n.to_string()))
            .collect::<Result<_, _>>()?,
        scaling_threads_min_triangles: parse::<f64>(
            opt(&opts, "scaling-threads-min-triangles").unwrap_or("0"),
            "--scaling-threads-min-triangles",
        )? as u64,
    };
    let manifest_path =
        PathBuf::from(opt(&opts, "manifest").unwrap_or("bench/results/simplify_inputs.json"));
    let sizes: Vec<f64> = list(opt(&opts, "sizes").unwrap_or("0.1,1,10"), "size")?;
    let scaling_sizes: Vec<f64> = list(
        opt(&opts, "scaling-sizes").unwrap_or("0.3,3"),
        "scaling size",
    )?;
    let scaling_fraction: f64 = parse(
        opt(&opts, "scaling-fraction").unwrap_or("0.1"),
        "--scaling-fraction",
    )?;
    let big =
        opt(&opts, "big").is_some() || std::env::var("SIMPLIFY_BENCH_50M").is_ok_and(|v| v == "1");
    let big_sizes: Vec<f64> = if big {
        list(opt(&opts, "big-sizes").unwrap_or("50"), "big size")?
    } else {
        Vec::new()
    };
    let big_fractions: Vec<f64> =
        list(opt(&opts, "big-fractions").unwrap_or("0.1"), "big fraction")?;
    let only: Option<Vec<String>> =
        opt(&opts, "meshes").map(|s| s.split(',').map(String::from).collect());
    for d in ["inputs", "outputs"] {
        std::fs::create_dir_all(cfg.work.join(d)).map_err(|e| e.to_string())?;
    }

    // Inputs: shared files, then generated tori.
    // (name, path, triangles to generate, fractions)
    let mut inputs: Vec<(String, PathBuf, Option<u64>, Vec<f64>)> = Vec::new();
    if opt(&opts, "no-shared").is_none() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&data)
            .map_err(|e| format!("{}: {e}", data.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension().is_some_and(|e| {
                    ["obj", "ply", "off", "stl"]
                        .contains(&e.to_string_lossy().to_lowercase().as_str())
                })
            })
            .collect();
        files.sort();
        for p in files {
            let name = p.file_stem().unwrap().to_string_lossy().to_string();
            inputs.push((name, p, None, cfg.fractions.clone()));
        }
    }
    let mut generated: Vec<(f64, Vec<f64>)> = sizes
        .iter()
        .map(|&s| (s, cfg.fractions.clone()))
        .chain(scaling_sizes.iter().map(|&s| (s, vec![scaling_fraction])))
        .chain(big_sizes.iter().map(|&s| (s, big_fractions.clone())))
        .collect();
    generated.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (s, fractions) in generated {
        let name = format!("torus_{s}M");
        let path = cfg.work.join("inputs").join(format!("{name}.ply"));
        inputs.push((name, path, Some((s * 1e6).round() as u64), fractions));
    }
    if let Some(only) = &only {
        inputs.retain(|(n, ..)| only.contains(n));
    }

    let t_run = Instant::now();
    let unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let mut manifest = json!({
        "meta": {
            "unix_time": unix,
            "nproc": std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0),
            "cpu_model": cpu_model(),
            "timing_threads": cfg.threads,
            "scaling_threads": cfg.scaling_threads,
            "scaling_threads_min_triangles": cfg.scaling_threads_min_triangles,
            "big_sizes": big_sizes,
            "big_fractions": if big { json!(big_fractions) } else { json!([]) },
            "fractions": cfg.fractions,
            "repeat": cfg.repeat,
            "budget_s": cfg.budget,
            "work": cfg.work,
        },
        "meshes": [],
    });
    for (name, path, generate, fractions) in &inputs {
        let t_mesh = Instant::now();
        let mesh = match generate {
            Some(t) => {
                let m = generate::bumpy_torus(*t);
                write_path(&m, path).map_err(|e| e.to_string())?;
                m
            }
            None => match read(path) {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("skipping {name}: {e}");
                    continue;
                }
            },
        };
        let st = stats(&mesh);
        let samples = face_samples(st.triangles);
        eprintln!(
            "== {name}: {} vertices, {} triangles ({} faces), {} face samples",
            st.vertices,
            st.triangles,
            mesh.face_count(),
            samples
        );
        let targets: Vec<Value> = fractions
            .iter()
            .map(|f| json!({"fraction": f, "target": (f * st.vertices as f64).round() as u64}))
            .collect();
        manifest["meshes"].as_array_mut().unwrap().push(json!({
            "mesh": name,
            "path": path,
            "generated": generate.is_some(),
            "input_vertices": st.vertices,
            "positions": mesh.positions.len(),
            "input_faces": mesh.face_count(),
            "input_triangles": st.triangles,
            "input_bytes": st.input_bytes,
            "bbox_diagonal": st.diagonal,
            "size": st.size,
            "area": st.area,
            "face_samples": samples,
            "vertex_samples": vertex_samples(st.triangles),
            "targets": targets,
        }));
        write_json(&manifest_path, &manifest)?;
        let input_index = match SurfaceIndex::new(&mesh) {
            Ok(i) => i,
            Err(e) => {
                eprintln!("skipping {name}: {e}");
                continue;
            }
        };
        let tessd_input = Input::Mesh(mesh);
        let Input::Mesh(mesh) = &tessd_input else {
            unreachable!()
        };
        let mut tri_input: Option<Input> = None;
        for &fraction in fractions {
            let target = (fraction * st.vertices as f64).round() as u64;
            for &method in &cfg.methods {
                let base = json!({
                    "mesh": name,
                    "generated": generate.is_some(),
                    "method": method.name(),
                    "family": if method.is_meshopt() { "meshopt" } else { "tessd" },
                    "fraction": fraction,
                    "target_vertices": target,
                    "input_vertices": st.vertices,
                    "input_triangles": st.triangles,
                    "input_faces": mesh.face_count(),
                    "input_bytes": st.input_bytes,
                    "param_name": method.param_name(),
                });
                if target < 4 || target >= st.vertices {
                    let mut rec = base;
                    rec["skipped"] = json!(format!(
                        "target of {target} vertices is outside 4..{}",
                        st.vertices
                    ));
                    append(&cfg.jsonl, &rec)?;
                    continue;
                }
                if method.is_meshopt() && tri_input.is_none() {
                    tri_input = Some(Input::Triangles(Triangles::from_mesh(mesh)));
                }
                let input = if method.is_meshopt() {
                    tri_input.as_ref().unwrap()
                } else {
                    &tessd_input
                };
                let rec = bench_one(
                    &cfg,
                    name,
                    path,
                    method,
                    input,
                    mesh,
                    &st,
                    target,
                    &input_index,
                    samples,
                    base,
                );
                let rec = match rec {
                    Ok(r) => r,
                    Err((mut base, e)) => {
                        eprintln!("   {} {target}: FAILED {e}", method.name());
                        base["error"] = json!(e);
                        base
                    }
                };
                append(&cfg.jsonl, &rec)?;
            }
        }
        eprintln!("   {name} done in {:.1} s", t_mesh.elapsed().as_secs_f64());
    }
    manifest["meta"]["harness_s"] = json!(t_run.elapsed().as_secs_f64());
    write_json(&manifest_path, &manifest)?;
    eprintln!("harness done in {:.1} s", t_run.elapsed().as_secs_f64());
    Ok(())
}

fn write_json(path: &Path, v: &Value) -> Result<(), String> {
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).map_err(|e| e.to_string())?;
    }
    std::fs::write(path, serde_json::to_string_pretty(v).unwrap() + "\n")
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn append(path: &Path, v: &Value) -> Result<(), String> {
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).map_err(|e| e.to_string())?;
    }
    let mut f = OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    writeln!(f, "{v}").map_err(|e| e.to_string())
}

/// Search, timed child run, error measurement of one (mesh, method, target).
#[allow(clippy::too_many_arguments)]
fn bench_one(
    cfg: &Config,
    name: &str,
    path: &Path,
    method: Method,
    input: &Input,
    mesh: &Mesh,
    st: &Stats,
    target: u64,
    input_index: &SurfaceIndex,
    samples: u64,
    mut rec: Value,
) -> Result<Value, (Value, String)> {
    // 1. The parameter (untimed).
    let t_search = Instant::now();
    let found = match params::find_param(method, input, st, target) {
        Ok(f) => f,
        Err(e) => return Err((rec, format!("search: {e}"))),
    };
    let search_s = t_search.elapsed().as_secs_f64();
    rec["param"] = json!(found.param);
    rec["search_evals"] = json!(found.evals);
    rec["search_s"] = json!(search_s);
    if !matches!(method, Method::Complexity(_)) {
        rec["search_count"] = json!(found.count);
        rec["search_hit"] = json!(found.hit);
    }
    if let Method::Grid(_) = method {
        rec["cells_per_axis"] = json!(st.size / found.param);
    }

    // 2. Timed run in a child process.
    let pct = format!("{}", (rec["fraction"].as_f64().unwrap() * 100.0));
    let out = cfg
        .work
        .join("outputs")
        .join(format!("{name}__{}__{pct}.ply", method.name()));
    let c = time_child(cfg, method, path, found.param, &out, &cfg.threads)
        .map_err(|e| (rec.clone(), e))?;
    let times = child_times(&c);
    let t = median(&times);
    let out_vertices = c["out_vertices"].as_u64().unwrap_or(0);
    let kib = |k: &str| c[k].as_u64().unwrap_or(0);
    let extra = (kib("hwm_run_kib").saturating_sub(kib("rss_before_run_kib"))) * 1024;
    for k in [
        "times_s",
        "out_vertices",
        "out_faces",
        "out_triangles",
        "held_bytes",
        "rss_start_kib",
        "hwm_load_kib",
        "rss_before_run_kib",
        "hwm_run_kib",
        "peak_reset_ok",
        "max_displacement",
        "report_output_vertices",
        "threads",
    ] {
        rec[k] = c[k].clone();
    }
    rec["time_s"] = json!(t);
    rec["repeats"] = json!(times.len());
    rec["mtris_per_s"] = json!(st.triangles as f64 / t / 1e6);
    rec["extra_peak_bytes"] = json!(extra);
    rec["mem_ratio"] = json!(extra as f64 / st.input_bytes as f64);
    rec["process_hwm_kib"] = json!(kib("hwm_load_kib").max(kib("hwm_run_kib")));
    rec["deviation"] = json!((out_vertices as f64 - target as f64) / target as f64);
    rec["hit"] = json!((out_vertices as f64 - target as f64).abs() <= search::tolerance(target));
    rec["output_path"] = json!(out);

    // 2b. Thread scaling: the same parameter with more threads; the output must not change.
    let scaling = !method.is_meshopt() && st.triangles >= cfg.scaling_threads_min_triangles;
    let mut scaling_recs = Vec::new();
    for threads in cfg.scaling_threads.iter().filter(|_| scaling) {
        let out_n = cfg
            .work
            .join("outputs")
            .join(format!("{name}__{}__{pct}__{threads}t.ply", method.name()));
        let r = match time_child(cfg, method, path, found.param, &out_n, threads) {
            Ok(cn) => {
                let tn = child_times(&cn);
                let med = median(&tn);
                let vn = cn["out_vertices"].as_u64().unwrap_or(0);
                let identical = same_bytes(&out, &out_n);
                let extra_n = (cn["hwm_run_kib"].as_u64().unwrap_or(0))
                    .saturating_sub(cn["rss_before_run_kib"].as_u64().unwrap_or(0))
                    * 1024;
                json!({
                    "threads": threads,
                    "times_s": tn,
                    "time_s": med,
                    "repeats": tn.len(),
                    "speedup": t / med,
                    "mtris_per_s": st.triangles as f64 / med / 1e6,
                    "out_vertices": vn,
                    "same_count": vn == out_vertices,
                    "identical": identical,
                    "extra_peak_bytes": extra_n,
                    "mem_ratio": extra_n as f64 / st.input_bytes as f64,
                })
            }
            Err(e) => json!({ "threads": threads, "error": e }),
        };
        let _ = std::fs::remove_file(&out_n);
        scaling_recs.push(r);
    }
    if scaling {
        rec["scaling"] = json!(scaling_recs);
    }

    // 3. Error against the input.
    let out_mesh = read(&out).map_err(|e| (rec.clone(), e))?;
    let m = measure(&out_mesh, mesh, input_index, samples);
    for (k, v) in m.as_object().unwrap() {
        rec[k] = v.clone();
    }
    let scaling_note: String = scaling_recs
        .iter()
        .map(|r| match r["time_s"].as_f64() {
            Some(tn) => format!(
                " | {}t {:.2} ms {:.2}x{}",
                r["threads"].as_str().unwrap_or("?"),
                tn * 1e3,
                t / tn,
                if r["identical"] == json!(true) {
                    ""
                } else if r["same_count"] == json!(true) {
                    " (count same, bytes DIFFER)"
                } else {
                    " (OUTPUT DIFFERS)"
                }
            ),
            None => format!(" | {}t FAILED", r["threads"].as_str().unwrap_or("?")),
        })
        .collect();
    eprintln!(
        "   {:<25} {:>5}% target {:>8} got {:>8} ({} evals, {:.1} s search) {:>9.2} ms x{} {:>7.1} Mtri/s mem {:.2}x  H {:.3e} RMS {:.3e}{}",
        method.name(),
        pct,
        target,
        out_vertices,
        found.evals,
        search_s,
        t * 1e3,
        times.len(),
        st.triangles as f64 / t / 1e6,
        extra as f64 / st.input_bytes as f64,
        rec["hausdorff"].as_f64().unwrap_or(f64::NAN),
        rec["rms"].as_f64().unwrap_or(f64::NAN),
        scaling_note,
    );
    Ok(rec)
}

/// One timed child run (`one`) of `method` with `param` on `path` under
/// `RAYON_NUM_THREADS=threads`, writing `out`; its JSON line.
fn time_child(
    cfg: &Config,
    method: Method,
    path: &Path,
    param: f64,
    out: &Path,
    threads: &str,
) -> Result<Value, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let child = Command::new(exe)
        .arg("one")
        .arg(method.name())
        .arg(path)
        .arg(format!("{param}"))
        .arg("--out")
        .arg(out)
        .arg("--repeat")
        .arg(cfg.repeat.to_string())
        .arg("--budget")
        .arg(cfg.budget.to_string())
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .map_err(|e| e.to_string())?;
    if !child.status.success() {
        let e = String::from_utf8_lossy(&child.stderr).to_string();
        return Err(format!("child ({threads} threads): {e}"));
    }
    serde_json::from_slice(&child.stdout).map_err(|e| e.to_string())
}

/// The run times of a child's JSON line.
fn child_times(c: &Value) -> Vec<f64> {
    c["times_s"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

/// Whether two files hold the same bytes (false when either cannot be read). Outputs are at
/// most a few hundred MB, read whole.
fn same_bytes(a: &Path, b: &Path) -> bool {
    match (std::fs::read(a), std::fs::read(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
