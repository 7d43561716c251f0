//! One part, measured in this process: the document's counts, the trim structures of every
//! face at each ε with the classification rate, and the tessellation at each tolerance and
//! rayon pool size. Prints one JSON line per step (see the crate documentation).

use crate::check;
use serde_json::{Value, json};
use std::collections::HashMap;
use std::hint::black_box;
use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;
use tessd_brep::Document;
use tessd_tessellate::{Options, Tessellation, tessellate};
use tessd_trim::TrimStructure;

/// The finest level of section 6's triangle classification a GPU tessellator reaches
/// (tessellation factor 64 = 2^6, section 7).
const K_HARDWARE: u32 = 6;

/// What to measure.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Trim tolerances ε, millimetres.
    pub eps_mm: Vec<f64>,
    /// Points per classification pass.
    pub points: usize,
    /// Timed classification passes.
    pub classify_repeats: usize,
    /// Seconds of timed tessellation runs.
    pub budget_s: f64,
    /// Fewest timed tessellation runs.
    pub min_repeat: usize,
    /// Most timed tessellation runs.
    pub max_repeat: usize,
    /// A warm-up longer than this (seconds) is the only run.
    pub slow_s: f64,
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

/// Prints one record and flushes, so that a child killed later keeps what it finished.
fn emit(rec: &Value) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{rec}");
    let _ = out.flush();
}

/// The message of a caught panic.
fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic".to_string()
    }
}

/// SplitMix64: a small deterministic generator for the classification points.
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Reads and parses a part; a document that does not parse is printed as a `doc` error record
/// (`None`).
fn load(path: &Path) -> Result<Option<(Document, f64, usize)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let t = Instant::now();
    match Document::from_json(&text) {
        Ok(d) => Ok(Some((d, t.elapsed().as_secs_f64() * 1e3, text.len()))),
        Err(e) => {
            emit(&json!({"kind": "doc", "error": e.to_string()}));
            Ok(None)
        }
    }
}

/// Millimetres per document unit.
fn mm_per_unit(doc: &Document) -> f64 {
    doc.units.meters_per_unit() * 1e3
}

/// The `trim` step: the `doc` record, then per ε the `trim` and `classify` records.
///
/// # Errors
/// Only when the file cannot be read.
pub fn trim_step(path: &Path, s: &Settings) -> Result<(), String> {
    let Some((doc, parse_ms, bytes)) = load(path)? else {
        return Ok(());
    };
    doc_record(&doc, parse_ms, bytes);
    for &eps in &s.eps_mm {
        let built = trims(&doc, eps, eps / mm_per_unit(&doc));
        classify_rate(&doc, &built, eps, s);
    }
    Ok(())
}

/// The `tess` step: one `tessellate` record at `tol_mm` in a pool of `threads`.
///
/// # Errors
/// Only when the file cannot be read.
pub fn tess_step(path: &Path, tol_mm: f64, threads: usize, s: &Settings) -> Result<(), String> {
    let Some((doc, _, _)) = load(path)? else {
        return Ok(());
    };
    tessellation(&doc, tol_mm, tol_mm / mm_per_unit(&doc), threads, s);
    Ok(())
}

/// The `doc` record: table-1 counts, validity, and whether the part is a closed solid.
fn doc_record(doc: &Document, parse_ms: f64, json_bytes: usize) {
    // Trims per edge id: a closed solid uses every edge with a curve twice (a seam twice by
    // the same face); degenerate edges (no curve, a pole) are left out.
    let mut uses: HashMap<u64, usize> = HashMap::new();
    for t in doc
        .faces
        .iter()
        .flat_map(|f| &f.loops)
        .flat_map(|l| &l.trims)
    {
        if let Some(e) = t.edge {
            *uses.entry(e).or_default() += 1;
        }
    }
    let edges = doc.edges.as_deref().unwrap_or(&[]);
    let real: Vec<_> = edges.iter().filter(|e| e.curve.is_some()).collect();
    let free = real
        .iter()
        .filter(|e| uses.get(&e.id).copied().unwrap_or(0) == 1)
        .count();
    let closed = !real.is_empty()
        && real
            .iter()
            .all(|e| uses.get(&e.id).copied().unwrap_or(0) == 2);
    let errors = doc.errors();
    emit(&json!({
        "kind": "doc",
        "units": doc.units.name(),
        "mm_per_unit": doc.units.meters_per_unit() * 1e3,
        "source": doc.source,
        "stats": doc.stats(),
        "closed": closed,
        "free_edges": free,
        "validation_errors": errors.len(),
        "first_validation_error": errors.first().map(ToString::to_string),
        "parse_ms": parse_ms,
        "json_bytes": json_bytes,
        "max_loops": doc.faces.iter().map(|f| f.loops.len()).max().unwrap_or(0),
        "max_trims": doc.faces.iter()
            .map(|f| f.loops.iter().map(|l| l.trims.len()).sum::<usize>())
            .max()
            .unwrap_or(0),
    }));
}

/// Builds every face's structure at ε (`eps` in document units), prints the `trim` record and
/// returns the built structures with their face's index.
fn trims(doc: &Document, eps_mm: f64, eps: f64) -> Vec<(usize, TrimStructure)> {
    let mut built = Vec::new();
    let mut faces = Vec::new();
    let mut histogram: Vec<u64> = Vec::new();
    let mut total_ms = 0.0;
    let mut failed = 0;
    for (i, face) in doc.faces.iter().enumerate() {
        eprintln!(
            "trim ε={eps_mm} mm: face {} ({})",
            face.id,
            face.surface.type_name()
        );
        let trims: usize = face.loops.iter().map(|l| l.trims.len()).sum();
        let mut rec = json!({
            "id": face.id,
            "surface": face.surface.type_name(),
            "loops": face.loops.len(),
            "trims": trims,
        });
        let t = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| TrimStructure::build(face, eps)));
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        match result {
            Ok(Ok(ts)) => {
                let st = &ts.stats;
                let build_ms = st.build_time.as_secs_f64() * 1e3;
                total_ms += build_ms;
                for (d, &n) in st.depth_histogram.iter().enumerate() {
                    if histogram.len() <= d {
                        histogram.resize(d + 1, 0);
                    }
                    histogram[d] += u64::from(n);
                }
                rec["quadratics"] = json!(st.quadratics);
                rec["lines"] = json!(st.lines);
                rec["nodes"] = json!(st.nodes);
                rec["leaves"] = json!(
                    st.depth_histogram
                        .iter()
                        .map(|&n| u64::from(n))
                        .sum::<u64>()
                );
                rec["max_depth"] = json!(st.max_depth);
                rec["failures"] = json!(st.failures);
                rec["separating_lines"] = json!(st.separating_lines);
                rec["bytes"] = json!(st.bytes);
                rec["k_i"] = json!(st.k_i);
                if st.k_i.is_none() {
                    // The crate searches k up to its deepest leaf; hardware tessellation
                    // allows factors up to 64 = 2^6 (section 7): try the levels up to 6 too.
                    let k = (0..=K_HARDWARE)
                        .find(|&k| ts.tree.classifiable_at(k) >= tessd_trim::quadtree::K_FRACTION);
                    rec["k_i_to_6"] = json!(k);
                    rec["classifiable_at_6"] = json!(ts.tree.classifiable_at(K_HARDWARE));
                }
                rec["build_ms"] = json!(build_ms);
                rec["fit_error_uv"] = json!(st.max_fit_error_uv);
                rec["eps_uv"] = json!(ts.tolerance.eps_uv);
                rec["fit_over_tol"] = json!(st.max_fit_error_uv / ts.tolerance.eps_uv);
                built.push((i, ts));
            }
            Ok(Err(e)) => {
                failed += 1;
                rec["error"] = json!(e.to_string());
                rec["build_ms"] = json!(wall_ms);
            }
            Err(p) => {
                failed += 1;
                rec["error"] = json!(format!("panic: {}", panic_message(p.as_ref())));
                rec["panicked"] = json!(true);
                rec["build_ms"] = json!(wall_ms);
            }
        }
        faces.push(rec);
    }
    emit(&json!({
        "kind": "trim",
        "eps_mm": eps_mm,
        "eps_doc": eps,
        "faces": faces,
        "failed_faces": failed,
        "depth_histogram": histogram,
        "build_total_ms": total_ms,
    }));
    built
}

/// The `classify` record: single-thread CPU classification rate over random (u, v).
fn classify_rate(doc: &Document, built: &[(usize, TrimStructure)], eps_mm: f64, s: &Settings) {
    if built.is_empty() {
        emit(&json!({"kind": "classify", "eps_mm": eps_mm, "error": "no face built"}));
        return;
    }
    eprintln!("classify ε={eps_mm} mm");
    let per_face = s.points.div_ceil(built.len()).max(1);
    let mut rng = SplitMix(0x7E55_D0B2_E9F0_0C01);
    let points: Vec<Vec<[f64; 2]>> = built
        .iter()
        .map(|(i, _)| {
            let [u0, u1, v0, v1] = doc.faces[*i].bounds;
            (0..per_face)
                .map(|_| {
                    [
                        u0 + (u1 - u0) * rng.next_f64(),
                        v0 + (v1 - v0) * rng.next_f64(),
                    ]
                })
                .collect()
        })
        .collect();
    let total = per_face * built.len();
    let pass = || {
        let t = Instant::now();
        let mut on = 0usize;
        for ((_, ts), pts) in built.iter().zip(&points) {
            for p in pts {
                on += usize::from(ts.classify(black_box(p[0]), black_box(p[1])));
            }
        }
        (t.elapsed().as_secs_f64(), black_box(on))
    };
    let result = catch_unwind(AssertUnwindSafe(|| {
        let (warm_s, on) = pass();
        let runs: Vec<f64> = (0..s.classify_repeats).map(|_| pass().0).collect();
        (warm_s, on, runs)
    }));
    match result {
        Ok((warm_s, on, runs)) => {
            let med = median(&runs);
            emit(&json!({
                "kind": "classify",
                "eps_mm": eps_mm,
                "points": total,
                "faces": built.len(),
                "on_fraction": on as f64 / total as f64,
                "time_ms": med * 1e3,
                "runs_ms": runs.iter().map(|r| r * 1e3).collect::<Vec<_>>(),
                "warmup_ms": warm_s * 1e3,
                "points_per_s": total as f64 / med,
                "ns_per_point": med * 1e9 / total as f64,
            }));
        }
        Err(p) => emit(&json!({"kind": "classify", "eps_mm": eps_mm,
                               "error": format!("panic: {}", panic_message(p.as_ref()))})),
    }
}

/// CPU time of this process (all threads, user + system), milliseconds.
#[cfg(unix)]
fn cpu_ms() -> f64 {
    // SAFETY: getrusage only writes the struct it is given.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) } != 0 {
        return f64::NAN;
    }
    let ms = |t: libc::timeval| t.tv_sec as f64 * 1e3 + t.tv_usec as f64 * 1e-3;
    ms(ru.ru_utime) + ms(ru.ru_stime)
}

/// Not measured off Unix (`getrusage` is POSIX): NaN, as when the call fails.
#[cfg(not(unix))]
fn cpu_ms() -> f64 {
    f64::NAN
}

/// One tessellation, under `catch_unwind`: the result, the call's wall time and CPU time
/// (milliseconds).
fn tess_once(doc: &Document, tol: f64) -> Result<(Tessellation, f64, f64), String> {
    let c = cpu_ms();
    let t = Instant::now();
    match catch_unwind(AssertUnwindSafe(|| tessellate(doc, &Options::new(tol)))) {
        Ok(Ok(out)) => Ok((out, t.elapsed().as_secs_f64() * 1e3, cpu_ms() - c)),
        Ok(Err(e)) => Err(e.to_string()),
        Err(p) => Err(format!("panic: {}", panic_message(p.as_ref()))),
    }
}

/// The `tessellate` record of one tolerance (`tol` in document units) and pool size.
fn tessellation(doc: &Document, tol_mm: f64, tol: f64, threads: usize, s: &Settings) {
    eprintln!("tessellate tol={tol_mm} mm, {threads} threads");
    let mut rec = json!({"kind": "tessellate", "tol_mm": tol_mm, "tol_doc": tol,
                         "threads": threads, "angle": Options::DEFAULT_ANGLE});
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(p) => p,
        Err(e) => {
            rec["error"] = json!(format!("rayon pool: {e}"));
            emit(&rec);
            return;
        }
    };
    let result = pool.install(|| -> Result<_, String> {
        let (mut last, warm_ms, warm_cpu) = tess_once(doc, tol)?;
        let mut runs = Vec::new();
        let mut inner = Vec::new();
        let mut cpu = Vec::new();
        if warm_ms < s.slow_s * 1e3 {
            let n = ((s.budget_s * 1e3 / warm_ms.max(1e-3)).floor() as usize)
                .clamp(s.min_repeat, s.max_repeat);
            for _ in 0..n {
                drop(last);
                let (out, ms, c) = tess_once(doc, tol)?;
                runs.push(ms);
                cpu.push(c);
                inner.push(out.stats.time_ms);
                last = out;
            }
        }
        Ok((last, warm_ms, runs, inner, cpu, warm_cpu))
    });
    match result {
        Ok((out, warm_ms, runs, inner, cpu, warm_cpu)) => {
            let only_warm = runs.is_empty();
            let (runs, inner, cpu) = if only_warm {
                (vec![warm_ms], vec![out.stats.time_ms], vec![warm_cpu])
            } else {
                (runs, inner, cpu)
            };
            let st = &out.stats;
            let c = check::cracks(&out);
            let d = check::deviation(doc, &out, tol);
            rec["cpu_ms"] = json!(median(&cpu));
            rec["deviation_max"] = json!(d.max);
            rec["deviation_p99"] = json!(d.p99);
            rec["deviation_over_tol"] = json!(d.over);
            rec["deviation_worst_face"] = json!(d.worst_face);
            rec["deviation_worst_uvs"] = json!(d.worst_uvs);
            rec["time_ms"] = json!(median(&runs));
            rec["runs_ms"] = json!(runs);
            rec["warmup_ms"] = json!(warm_ms);
            rec["only_warmup"] = json!(only_warm);
            rec["inner_time_ms"] = json!(median(&inner));
            rec["triangles"] = json!(st.triangles);
            rec["vertices"] = json!(st.vertices);
            rec["edges"] = json!(st.edges);
            rec["refined_points"] = json!(st.refined_points);
            rec["empty_faces"] = json!(st.empty_faces);
            rec["welded_vertices"] = json!(c.welded_vertices);
            rec["open_edges"] = json!(c.open_edges);
            rec["nonmanifold_edges"] = json!(c.nonmanifold_edges);
            rec["collapsed_triangles"] = json!(c.collapsed_triangles);
            rec["open_edge_examples"] = json!(c.examples);
            rec["nonmanifold_examples"] = json!(
                c.nonmanifold_examples
                    .iter()
                    .map(|(e, g)| json!({"edge": e, "faces": g
                        .iter()
                        .map(|&k| doc.faces[k as usize].id)
                        .collect::<Vec<_>>()}))
                    .collect::<Vec<_>>()
            );
            rec["mesh_valid"] = json!(out.mesh.validate().err().map(|e| e.to_string()));
        }
        Err(e) => rec["error"] = json!(e),
    }
    emit(&rec);
}
