//! One configuration, measured in this process: tessd's topology and apply phases on the CPU
//! with a rayon pool of a given size, or tessd's GPU apply. Each prints one JSON object.

use crate::mem::Baseline;
use serde_json::{Value, json};
use std::path::Path;
use std::time::Instant;
use tessd_gpu::GpuStencils;
use tessd_mesh::Mesh;
use tessd_mesh::io::{ReadOptions, read_path};
use tessd_subdiv::halfedges::Halfedges;
use tessd_subdiv::{Boundary, Faces, Refiner, Scheme, StencilTable, SubdivError, SubdivOptions};

/// How many times to time a phase.
#[derive(Clone, Copy, Debug)]
pub struct Repeats {
    /// Seconds the timed runs of one phase should take in all (after the warm-up).
    pub budget_s: f64,
    /// Fewest timed runs.
    pub min: usize,
    /// Most timed runs.
    pub max: usize,
}

/// Times of one phase: the warm-up and the timed runs, in milliseconds.
pub struct Timing {
    /// The untimed-for-the-median first run.
    pub warmup_ms: f64,
    /// Every timed run, in order.
    pub runs_ms: Vec<f64>,
}

impl Timing {
    /// Median of the timed runs.
    pub fn median_ms(&self) -> f64 {
        median(&self.runs_ms)
    }

    /// JSON fields `<name>_ms`, `<name>_runs_ms`, `<name>_warmup_ms`.
    pub fn insert(&self, rec: &mut Value, name: &str) {
        rec[format!("{name}_ms")] = json!(self.median_ms());
        rec[format!("{name}_runs_ms")] = json!(self.runs_ms);
        rec[format!("{name}_warmup_ms")] = json!(self.warmup_ms);
    }
}

/// Median of `v` (NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => s[n / 2],
        _ => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// Runs `f` once to warm up, then times it `budget / warm-up time` times (clamped to
/// `min..=max`). The previous result is dropped before each run, so at most one is alive;
/// the last one is returned.
fn time_repeated<T>(
    repeats: Repeats,
    mut f: impl FnMut() -> Result<T, String>,
) -> Result<(Timing, T), String> {
    let start = Instant::now();
    let mut last = f()?;
    let warmup_ms = start.elapsed().as_secs_f64() * 1e3;
    let n = ((repeats.budget_s * 1e3 / warmup_ms.max(1e-6)).floor() as usize)
        .clamp(repeats.min.max(1), repeats.max.max(repeats.min).max(1));
    let mut runs_ms = Vec::with_capacity(n);
    for _ in 0..n {
        drop(last);
        let t = Instant::now();
        last = f()?;
        runs_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    Ok((Timing { warmup_ms, runs_ms }, last))
}

/// The options every tool gets: Catmull–Clark, `level` levels, OpenSubdiv's default boundary
/// rule (edge-and-corner; the cages are closed anyway).
pub fn options(level: u32) -> SubdivOptions {
    SubdivOptions {
        scheme: Scheme::CatmullClark,
        levels: level,
        boundary: Boundary::EdgeAndCorner,
        ..SubdivOptions::default()
    }
}

/// Reads a cage.
pub fn read_cage(path: &Path) -> Result<Mesh, String> {
    read_path(path, &ReadOptions::default()).map_err(|e| format!("{}: {e}", path.display()))
}

/// Fields common to every record of a cage and level.
fn base_record(tool: &str, cage_path: &Path, cage: &Mesh, level: u32) -> Value {
    json!({
        "tool": tool,
        "cage": cage_path.file_name().map(|n| n.to_string_lossy().into_owned()),
        "level": level,
        "cage_vertices": cage.vertex_count(),
        "cage_faces": cage.face_count(),
    })
}

/// Sizes of a refiner: output counts, stencil terms and the tables' bytes.
fn refiner_fields(rec: &mut Value, refiner: &Refiner) {
    let out_vertices = refiner
        .tables
        .last()
        .map_or(refiner.cage_vertices, StencilTable::len);
    let terms: usize = refiner.tables.iter().map(|t| t.sources.len()).sum();
    let table_bytes: usize = refiner
        .tables
        .iter()
        .map(|t| 4 * (t.offsets.len() + t.sources.len() + t.weights.len()))
        .sum();
    let all_vertices: usize = refiner.tables.iter().map(StencilTable::len).sum();
    rec["out_vertices"] = json!(out_vertices);
    rec["out_faces"] = json!(refiner.faces.len());
    rec["vertices_all_levels"] = json!(all_vertices);
    rec["stencil_terms"] = json!(terms);
    rec["table_bytes"] = json!(table_bytes);
    rec["last_level_terms_per_vertex"] = json!(
        refiner
            .tables
            .last()
            .map_or(0.0, |t| t.sources.len() as f64 / t.len().max(1) as f64)
    );
}

/// `Refiner::new`; a refusal for size (over the 8 GiB default memory limit) is an error
/// starting with `skipped: `.
fn refine(cage: &Mesh, level: u32) -> Result<Refiner, String> {
    match Refiner::new(cage, &options(level)) {
        Ok(r) => Ok(r),
        Err(e @ SubdivError::TooLarge { .. }) => Err(format!("skipped: {e}")),
        Err(e) => Err(e.to_string()),
    }
}

/// The record of a refused configuration, or the error.
fn skipped_or(rec: &mut Value, err: String) -> Result<Value, String> {
    match err.strip_prefix("skipped: ") {
        Some(reason) => {
            rec["skipped"] = json!(reason);
            Ok(rec.take())
        }
        None => Err(err),
    }
}

/// tessd on the CPU with a rayon pool of `threads` threads: the topology phase
/// (`Refiner::new`) and the apply phase (`Refiner::apply` of the cage's xyz, stride 3), each
/// warmed up and timed `repeats` times, and the peak resident memory of each phase.
pub fn tessd_cpu(
    cage_path: &Path,
    level: u32,
    threads: usize,
    repeats: Repeats,
) -> Result<Value, String> {
    let cage = read_cage(cage_path)?;
    let mut rec = base_record("tessd", cage_path, &cage, level);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("rayon pool: {e}"))?;
    let flat: Vec<f32> = cage.positions.as_flattened().to_vec();

    // Topology phase: faces and one stencil table per level.
    let base = Baseline::take();
    let topo = pool.install(|| time_repeated(repeats, || refine(&cage, level)));
    let (topology, refiner) = match topo {
        Ok(x) => x,
        Err(e) => return skipped_or(&mut rec, e),
    };
    let topology_peak_kib = base.peak_over_kib();
    let refiner_kib = base.rss_over_kib();

    // Apply phase: every level on the cage positions, the last level's rows out.
    let before_apply = Baseline::take();
    let (apply, out) = pool.install(|| {
        time_repeated(repeats, || {
            refiner
                .apply(&flat, 3, "the cage")
                .map_err(|e| e.to_string())
        })
    })?;
    let apply_peak_kib = before_apply.peak_over_kib();

    // Apply again into the same level buffers (`Refiner::apply_into`): the steady state of an
    // animation, and what OpenSubdiv's PrimvarRefiner figure measures (a preallocated buffer).
    let mut levels = Vec::new();
    let (apply_reused, _) = pool.install(|| {
        time_repeated(repeats, || {
            refiner
                .apply_into(&flat, 3, "the cage", &mut levels)
                .map(|_| ())
                .map_err(|e| e.to_string())
        })
    })?;

    // Connectivity only (the corner arithmetic of every level, the last level's faces), what
    // OpenSubdiv's RefineUniform does: the topology phase without its stencil tables.
    let faces = Faces {
        offsets: cage.face_offsets.clone(),
        indices: cage.face_indices.clone(),
        vertex_count: cage.positions.len() as u32,
    };
    let (connectivity, _) = pool.install(|| {
        time_repeated(repeats, || {
            let mut h = Halfedges::from_cage(&faces, &[]).map_err(|e| e.to_string())?;
            for _ in 1..level {
                h = h.refine();
            }
            Ok(h.refine_faces())
        })
    })?;

    rec["threads"] = json!(pool.current_num_threads());
    apply_reused.insert(&mut rec, "apply_reused");
    connectivity.insert(&mut rec, "connectivity");
    refiner_fields(&mut rec, &refiner);
    topology.insert(&mut rec, "topology");
    apply.insert(&mut rec, "apply");
    rec["pipeline_ms"] = json!(topology.median_ms() + apply.median_ms());
    rec["checksum"] = json!(out.iter().map(|&x| x as f64).sum::<f64>());
    rec["baseline_rss_kib"] = json!(base.rss_kib);
    rec["topology_peak_kib"] = json!(topology_peak_kib);
    rec["refiner_rss_kib"] = json!(refiner_kib);
    rec["apply_peak_kib"] = json!(apply_peak_kib);
    rec["peak_over_baseline_kib"] = json!(
        topology_peak_kib.max(before_apply.rss_kib.saturating_sub(base.rss_kib) + apply_peak_kib)
    );
    rec["peak_reset_ok"] = json!(base.reset_ok && before_apply.reset_ok);
    Ok(rec)
}

/// tessd's GPU apply (tessd-gpu, wgpu compute): the tables are built on the CPU (untimed) and
/// uploaded once (timed once); then each apply of the cage's xyz is timed twice over: the whole
/// `apply_timed` call as the host sees it (buffer setup, upload of the positions, every
/// level's dispatch, copy and read-back) and the device part `apply_timed` reports (from the
/// submission until the device is done: upload, dispatches and copy; no buffer setup, no
/// read-back).
pub fn tessd_gpu(cage_path: &Path, level: u32, repeats: Repeats) -> Result<Value, String> {
    let cage = read_cage(cage_path)?;
    let mut rec = base_record("tessd-gpu", cage_path, &cage, level);
    let refiner = match refine(&cage, level) {
        Ok(r) => r,
        Err(e) => return skipped_or(&mut rec, e),
    };
    refiner_fields(&mut rec, &refiner);
    let flat: Vec<f32> = cage.positions.as_flattened().to_vec();
    let cpu = refiner
        .apply(&flat, 3, "the cage")
        .map_err(|e| e.to_string())?;

    let base = Baseline::take();
    let t = Instant::now();
    let gpu = match GpuStencils::new() {
        Ok(g) => g,
        Err(e) => {
            rec["error"] = json!(e.to_string());
            return Ok(rec);
        }
    };
    rec["init_ms"] = json!(t.elapsed().as_secs_f64() * 1e3);
    rec["adapter"] = json!(gpu.adapter_info());
    let t = Instant::now();
    let tables = match gpu.upload(&refiner.tables) {
        Ok(t) => t,
        Err(e) => {
            rec["error"] = json!(e.to_string());
            return Ok(rec);
        }
    };
    rec["upload_ms"] = json!(t.elapsed().as_secs_f64() * 1e3);

    let mut device_ms = Vec::new();
    let timed = time_repeated(repeats, || {
        let (out, device) = gpu
            .apply_timed(&tables, &flat, 3)
            .map_err(|e| e.to_string())?;
        device_ms.push(device.as_secs_f64() * 1e3);
        Ok(out)
    });
    let (apply, out) = match timed {
        Ok(x) => x,
        Err(e) => {
            rec["error"] = json!(e);
            return Ok(rec);
        }
    };
    let device_runs = device_ms.split_off(1); // the first one belongs to the warm-up
    let max_abs = out
        .iter()
        .zip(&cpu)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    apply.insert(&mut rec, "apply");
    rec["device_ms"] = json!(median(&device_runs));
    rec["device_runs_ms"] = json!(device_runs);
    rec["max_abs_vs_cpu"] = json!(if out.len() == cpu.len() {
        json!(max_abs)
    } else {
        json!(format!("length {} vs {}", out.len(), cpu.len()))
    });
    rec["baseline_rss_kib"] = json!(base.rss_kib);
    rec["peak_over_baseline_kib"] = json!(base.peak_over_kib());
    rec["peak_reset_ok"] = json!(base.reset_ok);
    Ok(rec)
}
