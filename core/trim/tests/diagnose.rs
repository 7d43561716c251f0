//! A diagnostic for depth-13 failures (paper 000, section 8, table 4) on exported documents:
//! `TESSD_TRIM_JSON=a.json,b.json cargo test --release -p tessd-trim --test diagnose --
//! --ignored --nocapture` builds every face at ε = 0.1 and 0.01 mm and prints, per failing
//! face, each failed leaf: its (u, v) box, depth, the curves crossing it (loop, trim, piece,
//! control points) and why the leaf rule failed. `TESSD_TRIM_FACES=13,14` restricts the faces.

mod common;

use common::{exact_inside, sampled_loops};
use tessd_brep::{Document, Face};
use tessd_trim::approximate::approximate_trim;
use tessd_trim::{NodeKind, Quadratic, TrimStructure};

/// Where curve `c` of the structure came from: (loop, trim, piece) found by matching its
/// middle control point against each trim's own approximation (`None` for bridging segments).
fn origin(face: &Face, t: &TrimStructure, c: usize) -> String {
    let mut k = 0;
    for (li, lp) in t.loops.iter().enumerate() {
        if c < k + lp.len() {
            let q = &lp[c - k];
            let Some(floop) = face.loops.get(li) else {
                return format!("loop {li} (bounds), piece {}", c - k);
            };
            for (ti, trim) in floop.trims.iter().enumerate() {
                if let Ok(a) = approximate_trim(trim, t.tolerance.eps_uv) {
                    for (pi, p) in a.pieces.iter().enumerate() {
                        if p.p[1] == q.p[1] || p.p[2] == q.p[2] {
                            return format!(
                                "loop {li} piece {} = trim {ti} ({}) piece {pi}/{}",
                                c - k,
                                trim.curve.type_name(),
                                a.pieces.len()
                            );
                        }
                    }
                }
            }
            return format!("loop {li} piece {} (bridge)", c - k);
        }
        k += lp.len();
    }
    "?".into()
}

fn d2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The smallest distance between two curves' parts, sampled, and where.
fn closest(a: &Quadratic, ra: [f64; 2], b: &Quadratic, rb: [f64; 2]) -> (f64, [f64; 2]) {
    let n = 400;
    let mut best = (f64::INFINITY, [0.0, 0.0]);
    for i in 0..=n {
        let p = a.point(ra[0] + (ra[1] - ra[0]) * i as f64 / n as f64);
        for j in 0..=n {
            let q = b.point(rb[0] + (rb[1] - rb[0]) * j as f64 / n as f64);
            let d = d2(p, q);
            if d < best.0 {
                best = (d, p);
            }
        }
    }
    best
}

#[test]
#[ignore]
fn diagnose_failures() {
    let Ok(paths) = std::env::var("TESSD_TRIM_JSON") else {
        eprintln!("set TESSD_TRIM_JSON");
        return;
    };
    let only: Option<Vec<u64>> = std::env::var("TESSD_TRIM_FACES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect());
    let verbose = std::env::var("TESSD_TRIM_QUIET").is_err();
    for path in paths.split(',') {
        let doc = Document::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        for eps in [0.1, 0.01] {
            let (mut faces, mut leaves, mut nodes, mut bytes) = (0, 0, 0, 0);
            let mut time = std::time::Duration::ZERO;
            let mut failing = Vec::new();
            for face in &doc.faces {
                if only.as_ref().is_some_and(|o| !o.contains(&face.id)) {
                    continue;
                }
                let t = TrimStructure::build(face, eps).unwrap();
                nodes += t.stats.nodes;
                bytes += t.stats.bytes;
                time += t.stats.build_time;
                if std::env::var("TESSD_TRIM_TIMES").is_ok() {
                    eprintln!(
                        "TIME ε {eps} face {}: {:?}, {} quadratics, {} nodes",
                        face.id, t.stats.build_time, t.stats.quadratics, t.stats.nodes
                    );
                }
                if t.stats.failures == 0 {
                    continue;
                }
                faces += 1;
                leaves += t.stats.failures;
                failing.push(face.id);
                if !verbose {
                    continue;
                }
                let d = t.tree.domain;
                let (w, h) = (d[1] - d[0], d[3] - d[2]);
                eprintln!(
                    "== {path} ε {eps}: face {} ({}), {} loops, eps_uv {:.3e}, {} failed",
                    face.id,
                    face.surface.type_name(),
                    face.loops.len(),
                    t.tolerance.eps_uv,
                    t.stats.failures
                );
                for n in t.tree.nodes.iter().filter(|n| n.kind == NodeKind::Failed) {
                    let s = n.size();
                    let rect = n.clip_rect();
                    let box_uv = [
                        d[0] + w * n.origin[0],
                        d[0] + w * (n.origin[0] + s),
                        d[2] + h * n.origin[1],
                        d[2] + h * (n.origin[1] + s),
                    ];
                    let crossing: Vec<(usize, [f64; 2])> = t
                        .tree
                        .curves
                        .iter()
                        .enumerate()
                        .filter_map(|(c, q)| q.clip(rect).map(|r| (c, r)))
                        .collect();
                    eprintln!(
                        "  leaf depth {} box u [{:.9}, {:.9}] v [{:.9}, {:.9}], {} curves",
                        n.depth,
                        box_uv[0],
                        box_uv[1],
                        box_uv[2],
                        box_uv[3],
                        crossing.len()
                    );
                    let den = |p: [f64; 2]| [d[0] + w * p[0], d[2] + h * p[1]];
                    for &(c, r) in &crossing {
                        let q = &t.tree.curves[c];
                        eprintln!(
                            "    curve {c} [{}] {} t [{:.6}, {:.6}] p {:?}",
                            origin(face, &t, c),
                            if q.line { "line" } else { "quad" },
                            r[0],
                            r[1],
                            q.p.map(den)
                        );
                    }
                    for i in 0..crossing.len() {
                        for j in i + 1..crossing.len() {
                            let (a, ra) = crossing[i];
                            let (b, rb) = crossing[j];
                            let (qa, qb) = (&t.tree.curves[a], &t.tree.curves[b]);
                            let shared = [
                                (0, 0, d2(qa.p[0], qb.p[0])),
                                (0, 2, d2(qa.p[0], qb.p[2])),
                                (2, 0, d2(qa.p[2], qb.p[0])),
                                (2, 2, d2(qa.p[2], qb.p[2])),
                            ]
                            .into_iter()
                            .filter(|x| x.2 < 1e-12)
                            .map(|x| format!("p{}=p{}", x.0, x.1))
                            .collect::<Vec<_>>();
                            let (dist, at) = closest(qa, ra, qb, rb);
                            eprintln!(
                                "    pair {a}-{b}: shared ends {shared:?}, closest {:.3e} \
                                 (cell {:.3e}) at {:?}",
                                dist,
                                s,
                                den(at)
                            );
                        }
                    }
                }
            }
            eprintln!(
                "SUMMARY {path} ε {eps}: failing faces {faces} {failing:?}, failed leaves \
                 {leaves}, nodes {nodes}, bytes {bytes}, build {time:?}"
            );
        }
    }
}

fn unit(d: [f64; 2]) -> [f64; 2] {
    let l = d[0].hypot(d[1]);
    [d[0] / l, d[1] / l]
}

fn angle(a: [f64; 2], b: [f64; 2]) -> f64 {
    let (a, b) = (unit(a), unit(b));
    (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1])
}

/// Per trim of the chosen faces: the angle between the exact and approximated end tangents,
/// and between consecutive trims' exact tangents.
#[test]
#[ignore]
fn diagnose_tangents() {
    let Ok(paths) = std::env::var("TESSD_TRIM_JSON") else {
        return;
    };
    let only: Vec<u64> = std::env::var("TESSD_TRIM_FACES")
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_default();
    for path in paths.split(',') {
        let doc = Document::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        for face in doc.faces.iter().filter(|f| only.contains(&f.id)) {
            for eps in [0.1, 0.01] {
                let tol = tessd_trim::tolerance::uv_tolerance(face, eps);
                eprintln!("face {} eps {eps}", face.id);
                for (li, lp) in face.loops.iter().enumerate() {
                    let n = lp.trims.len();
                    for (ti, trim) in lp.trims.iter().enumerate() {
                        let [t0, t1] = trim.range;
                        let sg = (t1 - t0).signum();
                        let d0 = trim.curve.eval(t0).1.map(|x| x * sg);
                        let d1 = trim.curve.eval(t1).1.map(|x| x * sg);
                        let a = approximate_trim(trim, tol.eps_uv).unwrap();
                        let f = a.pieces[0];
                        let l = a.pieces[a.pieces.len() - 1];
                        let s0 = if f.line {
                            [f.p[2][0] - f.p[0][0], f.p[2][1] - f.p[0][1]]
                        } else {
                            [f.p[1][0] - f.p[0][0], f.p[1][1] - f.p[0][1]]
                        };
                        let s1 = if l.line {
                            [l.p[2][0] - l.p[0][0], l.p[2][1] - l.p[0][1]]
                        } else {
                            [l.p[2][0] - l.p[1][0], l.p[2][1] - l.p[1][1]]
                        };
                        let next = &lp.trims[(ti + 1) % n];
                        let [u0, u1] = next.range;
                        let nd = next.curve.eval(u0).1.map(|x| x * (u1 - u0).signum());
                        eprintln!(
                            "  loop {li} trim {ti} {} pieces {} err {:.2e}: start err {:.2e} end err {:.2e}; exact turn to next {:.4e}",
                            trim.curve.type_name(),
                            a.pieces.len(),
                            a.max_error,
                            angle(d0.into(), s0),
                            angle(d1.into(), s1),
                            angle(d1.into(), nd.into())
                        );
                    }
                }
            }
        }
    }
}

/// Classification of every face against even-odd on its exact trims (2048 samples each):
/// random points of the bounds and points around every trim vertex; prints the points that
/// disagree farther than the (u, v) tolerance from the trims.
#[test]
#[ignore]
fn diagnose_classification() {
    let Ok(paths) = std::env::var("TESSD_TRIM_JSON") else {
        return;
    };
    for path in paths.split(',') {
        let doc = Document::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        for eps in [0.1, 0.01] {
            let (mut n, mut wrong, mut faces) = (0usize, 0usize, 0usize);
            for face in &doc.faces {
                let t = TrimStructure::build(face, eps).unwrap();
                let polys = sampled_loops(face, 2048);
                let [u0, u1, v0, v1] = face.bounds;
                let size = (u1 - u0).hypot(v1 - v0);
                let mut pts = Vec::new();
                let mut x = face.id.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
                let mut rnd = || {
                    x ^= x >> 12;
                    x ^= x << 25;
                    x ^= x >> 27;
                    (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
                };
                for _ in 0..4000 {
                    pts.push([u0 + (u1 - u0) * rnd(), v0 + (v1 - v0) * rnd()]);
                }
                for l in &face.loops {
                    for tr in &l.trims {
                        let c = tr.curve.point(tr.range[0]);
                        for r in [3.0 * t.tolerance.eps_uv, 1e-3 * size, 1e-2 * size] {
                            for _ in 0..40 {
                                let a = std::f64::consts::TAU * rnd();
                                let rr = r * rnd().sqrt();
                                pts.push([c[0] + rr * a.cos(), c[1] + rr * a.sin()]);
                            }
                        }
                    }
                }
                let mut bad = 0;
                for p in pts {
                    let (inside, d) = exact_inside(&polys, p, face.loops.is_empty());
                    n += 1;
                    if t.classify(p[0], p[1]) != inside && d > t.tolerance.eps_uv + 1e-9 * size {
                        bad += 1;
                        if bad <= 3 {
                            eprintln!(
                                "  {path} ε {eps} face {}: {p:?} classified {} (distance {d:.3e}, eps_uv {:.3e})",
                                face.id, !inside, t.tolerance.eps_uv
                            );
                        }
                    }
                }
                wrong += bad;
                faces += usize::from(bad > 0);
            }
            eprintln!(
                "CLASSIFY {path} ε {eps}: {wrong} of {n} points wrong beyond eps_uv, in {faces} faces"
            );
        }
    }
}
