//! The multi-face pack (paper 000, section 7), its f32 walk against the f64 classifier
//! (sections 5–5.2) and triangle classification's hand-off (section 6), on the shared B-Rep
//! fixtures and the bottle.

mod common;

use common::Rng;
use std::sync::OnceLock;
use tessd_brep::{Document, Face};
use tessd_trim::TrimStructure;
use tessd_trim::multi_pack::{FACE_HEADER_BYTES, MultiPack};

/// The world tolerance the fixtures are built at (document units).
const EPS: f64 = 0.01;

/// Disagreements between the f32 and f64 walks are allowed this many ε_uv from a curve.
const NEAR: f64 = 2.0;

struct Fixture {
    faces: Vec<Face>,
    trims: Vec<TrimStructure>,
    pack: MultiPack,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let mut faces = Vec::new();
        for text in [
            include_str!("../../brep/tests/data/bspline_face.json"),
            include_str!("../../brep/tests/data/cylinder_with_hole.json"),
            include_str!("data/bottle.json"),
        ] {
            faces.extend(Document::from_json(text).unwrap().faces);
        }
        let trims: Vec<TrimStructure> = faces
            .iter()
            .map(|f| TrimStructure::build(f, EPS).unwrap())
            .collect();
        let mut pack = MultiPack::new();
        for (f, t) in faces.iter().zip(&trims) {
            pack.push(t, f.bounds);
        }
        Fixture { faces, trims, pack }
    })
}

/// The (u, v) distance from `p` to the approximated trim pieces (64 chords per piece).
fn distance_to_pieces(t: &TrimStructure, p: [f64; 2]) -> f64 {
    let mut best = f64::INFINITY;
    for q in t.loops.iter().flatten() {
        let mut a = q.point(0.0);
        for k in 1..=64 {
            let b = q.point(k as f64 / 64.0);
            let d = [b[0] - a[0], b[1] - a[1]];
            let l2 = (d[0] * d[0] + d[1] * d[1]).max(1e-300);
            let s = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0);
            best = best.min((p[0] - a[0] - s * d[0]).hypot(p[1] - a[1] - s * d[1]));
            a = b;
        }
    }
    best
}

#[test]
fn multi_pack_concatenates_and_rebases_face_packs() {
    let fx = fixture();
    let pack = &fx.pack;
    assert_eq!(FACE_HEADER_BYTES, 40);
    assert_eq!(pack.headers.len(), fx.trims.len());
    assert_eq!(pack.header_bytes().len(), 40 * fx.trims.len());
    // Each face's packed size less its 16-byte domain header (moved into the table), plus
    // the table.
    let faces: usize = fx.trims.iter().map(|t| t.packed.bytes() - 16).sum();
    assert_eq!(pack.bytes(), faces + fx.trims.len() * FACE_HEADER_BYTES);
    // Un-rebasing gives back every face's own buffers.
    for (f, t) in fx.trims.iter().enumerate() {
        let (h, p) = (&pack.headers[f], &t.packed);
        let nb = h.node_base as usize;
        let nodes = &pack.nodes[nb..nb + p.nodes.len()];
        for (&w, &orig) in nodes.iter().zip(&p.nodes) {
            let base = match w & 7 {
                0 => h.node_base,
                3..=5 => h.curve_base,
                6 => h.line_base,
                _ => 0,
            };
            assert_eq!(w - (base << 4), orig);
        }
        let cb = h.curve_base as usize * 6;
        assert_eq!(&pack.curves[cb..cb + p.curves.len()], &p.curves[..]);
        let lb = h.line_base as usize * 5;
        for (k, (&w, &orig)) in pack.lines[lb..lb + p.lines.len()]
            .iter()
            .zip(&p.lines)
            .enumerate()
        {
            let base = if k % 5 >= 3 { h.curve_base } else { 0 };
            assert_eq!(w - base, orig);
        }
        assert_eq!(h.depth_limit, t.stats.max_depth);
        assert_eq!(h.k_i, t.stats.k_i.unwrap_or(u32::MAX));
    }
    assert_eq!(
        pack.nodes.len(),
        fx.trims.iter().map(|t| t.packed.nodes.len()).sum::<usize>()
    );
}

/// Patch-edge points (s or t ∈ {0, 1}) lie on the face's bounds, where trims often run
/// along or touch the bounds tangentially: there a separating line or a curve's tangent can
/// coincide with the edge, and the f32 and f64 rounding of a point *on* it pick different
/// curves. Those disagreements are counted apart; far from the curves they must lie on the
/// f64 leaf's separating line.
#[test]
fn f32_walk_matches_f64_classification_away_from_curves() {
    let fx = fixture();
    let (mut points, mut disagree, mut far) = (0usize, 0usize, 0usize);
    let (mut edge_points, mut edge_disagree, mut edge_far) = (0usize, 0usize, 0usize);
    let mut worst = 0.0f64;
    for (f, (face, t)) in fx.faces.iter().zip(&fx.trims).enumerate() {
        let [u0, u1, v0, v1] = face.bounds;
        let d = t.tree.domain;
        let mut rng = Rng(face.id * 7 + 3);
        let grid = (0..=32u32).flat_map(|i| (0..=32u32).map(move |j| (i, j)));
        let mut samples: Vec<[f32; 2]> = grid
            .map(|(i, j)| [i as f32 / 32.0, j as f32 / 32.0])
            .collect();
        samples.extend((0..2000).map(|_| [rng.next() as f32, rng.next() as f32]));
        for [s, st] in samples {
            let (u, v) = (
                u0 + f64::from(s) * (u1 - u0),
                v0 + f64::from(st) * (v1 - v0),
            );
            let edge = s == 0.0 || s == 1.0 || st == 0.0 || st == 1.0;
            if edge {
                edge_points += 1;
            } else {
                points += 1;
            }
            let reference = t.classify_at(u, v, [0.0, 0.0]);
            if fx.pack.walk(f, s, st) == reference.on {
                continue;
            }
            let dist = distance_to_pieces(t, [u, v]) / t.tolerance.eps_uv;
            if !edge {
                disagree += 1;
                worst = worst.max(dist);
                if dist > NEAR {
                    far += 1;
                    eprintln!(
                        "face {}: ({s}, {st}) disagrees {dist:.2} ε_uv away",
                        face.id
                    );
                }
                continue;
            }
            edge_disagree += 1;
            if dist > NEAR {
                edge_far += 1;
                let node = &t.tree.nodes[reference.node as usize];
                assert_ne!(node.line, u32::MAX, "face {}: ({s}, {st})", face.id);
                let l = t.tree.lines[node.line as usize].map(f64::from);
                let (x, y) = ((u - d[0]) / (d[1] - d[0]), (v - d[2]) / (d[3] - d[2]));
                assert!(
                    (l[0] * x + l[1] * y + l[2]).abs() < 1e-6,
                    "face {}",
                    face.id
                );
            }
        }
    }
    eprintln!(
        "f32 walk vs f64 classify on {} faces: {points} interior points, {disagree} \
         disagreements, all within {worst:.1e} ε_uv of a curve ({far} farther than {NEAR} \
         ε_uv); {edge_points} patch-edge points, {edge_disagree} disagreements, {edge_far} \
         of them farther than {NEAR} ε_uv (on a separating line along the edge)",
        fx.faces.len()
    );
    assert!(points > 0);
    assert_eq!(far, 0);
}

#[test]
fn cell_handoff_resumes_the_walk() {
    let fx = fixture();
    let (mut cells, mut points, mut whole, mut deep) = (0usize, 0usize, 0usize, 0usize);
    for (f, h) in fx.pack.headers.iter().enumerate() {
        let mut rng = Rng(f as u64 + 11);
        for k in 0..=8u32 {
            let n = 1u32 << k;
            let size = 1.0 / n as f32;
            for _ in 0..8 {
                let i = (rng.next() * n as f64) as u32;
                let j = (rng.next() * n as f64) as u32;
                let origin = [i as f32 * size, j as f32 * size];
                let c = fx.pack.classify_cell(f, origin, size);
                cells += 1;
                assert!(c.depth <= h.depth_limit);
                deep += usize::from(c.depth > 0);
                whole += usize::from(c.whole.is_some());
                // The node's cell holds the mapped cell.
                let side = 0.5f32.powi(c.depth as i32);
                let lo = fx.pack.to_tree(f, origin[0], origin[1]);
                let hi = fx.pack.to_tree(f, origin[0] + size, origin[1] + size);
                if c.depth > 0 {
                    for a in 0..2 {
                        assert!(lo[a] >= c.origin[a] && hi[a] < c.origin[a] + side);
                    }
                }
                for _ in 0..32 {
                    let s = origin[0] + size * rng.next() as f32;
                    let t = origin[1] + size * rng.next() as f32;
                    let root = fx.pack.walk(f, s, t);
                    assert_eq!(fx.pack.walk_from(f, &c, s, t), root, "face {f} {c:?}");
                    if let Some(on) = c.whole {
                        assert_eq!(on, root);
                    }
                    points += 1;
                }
            }
        }
    }
    eprintln!(
        "hand-off: {cells} cells ({deep} below the root, {whole} whole), {points} points \
         resumed alike"
    );
}
