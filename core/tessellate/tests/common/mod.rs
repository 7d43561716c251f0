//! Checks shared by the tessellation tests, written independently of the crate's internals.

#![allow(dead_code)]

use std::collections::HashMap;
use tessd_brep::{Document, Face};
use tessd_tessellate::{Options, Tessellation};

/// Reads a fixture from tests/data.
pub fn load(name: &str) -> Document {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let doc = Document::from_json(&text).unwrap();
    doc.validate().unwrap();
    doc
}

/// Tessellates with `tolerance` and the default angle.
pub fn run(doc: &Document, tolerance: f64) -> Tessellation {
    tessd_tessellate::tessellate(doc, &Options::new(tolerance)).unwrap()
}

/// Triangles per welded edge (a pair of welded vertex indices).
type EdgeUses = HashMap<(u32, u32), i64>;

/// Welds vertices of equal position and counts the triangles using each edge (after dropping
/// triangles collapsed by the weld), with the welded positions.
fn edge_uses(t: &Tessellation) -> (EdgeUses, Vec<[f32; 3]>) {
    let mesh = &t.mesh;
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut pos = Vec::new();
    let welded: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = p.map(f32::to_bits);
            *ids.entry(key).or_insert_with(|| {
                pos.push(*p);
                (pos.len() - 1) as u32
            })
        })
        .collect();
    let mut count: HashMap<(u32, u32), i64> = HashMap::new();
    for f in mesh.faces() {
        assert_eq!(f.len(), 3);
        let w = [
            welded[f[0] as usize],
            welded[f[1] as usize],
            welded[f[2] as usize],
        ];
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    (count, pos)
}

/// The welded edges whose number of triangles `keep` accepts.
fn edges_where(t: &Tessellation, keep: impl Fn(i64) -> bool) -> Vec<([f32; 3], [f32; 3])> {
    let (count, pos) = edge_uses(t);
    count
        .into_iter()
        .filter(|&(_, n)| keep(n))
        .map(|((a, b), _)| (pos[a as usize], pos[b as usize]))
        .collect()
}

/// The edges used by one triangle only (cracks, on a closed solid).
pub fn open_edges(t: &Tessellation) -> Vec<([f32; 3], [f32; 3])> {
    edges_where(t, |n| n == 1)
}

/// The edges used by more than two triangles (folds).
pub fn nonmanifold_edges(t: &Tessellation) -> Vec<([f32; 3], [f32; 3])> {
    edges_where(t, |n| n > 2)
}

/// The total area of the mesh's triangles (in f64).
pub fn area(t: &Tessellation) -> f64 {
    group_areas(t).iter().sum()
}

/// The area of each face group.
pub fn group_areas(t: &Tessellation) -> Vec<f64> {
    let mesh = &t.mesh;
    let mut out = vec![0.0; mesh.group_names.len()];
    for (i, f) in mesh.faces().enumerate() {
        let p = |k: usize| mesh.positions[f[k] as usize].map(f64::from);
        let (a, b, c) = (p(0), p(1), p(2));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        out[mesh.face_groups[i] as usize] += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    }
    out
}

/// Dense (u, v) polylines of a face's loops, sampled straight from the trim curves.
pub fn dense_loops(face: &Face) -> Vec<Vec<[f64; 2]>> {
    face.loops
        .iter()
        .map(|lp| {
            let mut pts = Vec::new();
            for trim in &lp.trims {
                let [t0, t1] = trim.range;
                let n = 400;
                for k in 0..n {
                    let t = t0 + (t1 - t0) * k as f64 / n as f64;
                    pts.push(trim.curve.point(t).to_array());
                }
            }
            pts
        })
        .collect()
}

/// Even-odd point in polygons.
pub fn inside(loops: &[Vec<[f64; 2]>], p: [f64; 2]) -> bool {
    let mut odd = false;
    for lp in loops {
        for k in 0..lp.len() {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if x > p[0] {
                    odd = !odd;
                }
            }
        }
    }
    odd
}

/// How many triangles have their (u, v) centroid clearly outside their face's loops.
pub fn outside_triangles(doc: &Document, t: &Tessellation) -> usize {
    let loops: Vec<Vec<Vec<[f64; 2]>>> = doc.faces.iter().map(dense_loops).collect();
    let mut bad = 0;
    for (i, f) in t.mesh.faces().enumerate() {
        let g = t.mesh.face_groups[i] as usize;
        if loops[g].is_empty() {
            continue;
        }
        let c = [0, 1].map(|d| f.iter().map(|&v| t.uvs[v as usize][d]).sum::<f64>() / 3.0);
        if !inside(&loops[g], c) {
            // A triangle on the chord of a concave trim may have its centroid just across
            // the exact curve: only centroids clearly outside count.
            let pts: Vec<[f64; 2]> = loops[g].iter().flatten().copied().collect();
            let (lo, hi) = pts
                .iter()
                .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
                    (
                        [lo[0].min(p[0]), lo[1].min(p[1])],
                        [hi[0].max(p[0]), hi[1].max(p[1])],
                    )
                });
            let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
            let near = pts
                .iter()
                .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
                .fold(f64::MAX, f64::min);
            if near > 1e-3 * diag {
                bad += 1;
            }
        }
    }
    bad
}
