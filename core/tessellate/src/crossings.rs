//! Step 2, continued: boundary polylines that cross. Edges are sampled to the chordal tolerance in 3D,
//! which says nothing about their chords in a face's (u, v): where two trims run close in the
//! parameter plane (the flanks of a thread, a fillet's edge beside a hole), chords of one can
//! cut across the other. A crossing would make the triangulation split both constraints at a
//! new point that the neighbouring faces do not have (an open edge in the welded mesh) and
//! confuse the even-odd inside test. So, before any face is triangulated, the two segments of
//! every crossing are split at their middles, on the shared edge itself when they come from
//! one — every face using that edge gets the new sample, keeping neighbours' boundaries equal —
//! and the faces concerned are looked at again, until no polyline crosses another (or
//! [`ROUNDS`] rounds). Refined polylines converge to their curves, which do not cross.

use crate::Options;
use crate::boundary::{FreeSplits, Polyline, Source, face_loops};
use crate::edges::{EdgeTable, split_edge};
use std::collections::{HashMap, HashSet};
use tessd_brep::{Curve3, DVec2, Document};

/// The most rounds of splitting; polylines still crossing then are left to the triangulation.
pub const ROUNDS: usize = 24;

/// The fewest splits allowed in all (see [`face_loops_uncrossed`]).
pub const MIN_SPLIT_BUDGET: usize = 256;

/// What resolving the crossings did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CrossingStats {
    /// Segments split (shared-edge splits counted once, however many faces use the edge).
    pub splits: usize,
    /// Rounds that found a crossing.
    pub rounds: usize,
    /// Ids of faces whose polylines still cross after the last round.
    pub unresolved: Vec<u64>,
}

/// A polyline segment: `(loop, index of its first point)`.
pub type SegmentRef = (usize, usize);

/// The pairs of segments of `loops` that cross each other at a point interior to both (a
/// sweep over the segments sorted by their smallest u). Segments meeting at an end point do
/// not count.
pub fn crossing_segments(loops: &[Polyline]) -> Vec<[SegmentRef; 2]> {
    crossing_segments_at_most(loops, usize::MAX)
}

/// [`crossing_segments`], stopping at `limit` pairs: polylines that scribble across each other
/// cross in as many pairs as the square of their segments (found by fuzzing: a 3D edge turned
/// 6·10¹⁶ radians round its circle, 16 384 samples, 2 GB of pairs).
pub fn crossing_segments_at_most(loops: &[Polyline], limit: usize) -> Vec<[SegmentRef; 2]> {
    struct Seg {
        at: SegmentRef,
        a: DVec2,
        b: DVec2,
        u: [f64; 2],
        v: [f64; 2],
    }
    let mut segs: Vec<Seg> = Vec::new();
    for (l, lp) in loops.iter().enumerate() {
        for i in 0..lp.len() {
            let (a, b) = (lp[i].uv, lp[(i + 1) % lp.len()].uv);
            segs.push(Seg {
                at: (l, i),
                a,
                b,
                u: [a[0].min(b[0]), a[0].max(b[0])],
                v: [a[1].min(b[1]), a[1].max(b[1])],
            });
        }
    }
    segs.sort_by(|x, y| x.u[0].total_cmp(&y.u[0]));
    let mut out = Vec::new();
    let mut active: Vec<usize> = Vec::new();
    for (k, s) in segs.iter().enumerate() {
        active.retain(|&j| segs[j].u[1] >= s.u[0]);
        for &j in &active {
            let t = &segs[j];
            if t.v[1] >= s.v[0] && s.v[1] >= t.v[0] && cross(s.a, s.b, t.a, t.b) {
                out.push([t.at, s.at]);
                if out.len() >= limit {
                    return out;
                }
            }
        }
        active.push(k);
    }
    out
}

/// The sign of the turn a → b → c (twice the signed area).
fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether segments ab and cd cross at a point interior to both.
fn cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 < 0.0 && o3 * o4 < 0.0
}

/// Every face's loops (document order) with no two boundary segments crossing, splitting
/// shared edges in `edges` where needed.
///
/// The splits are bounded: at most as many in all as the loops have segments to start with (at
/// least [`MIN_SPLIT_BUDGET`]). Refining polylines whose curves do not cross resolves their
/// crossings with a few splits each; curves that do cross each other (a document whose edge
/// curves disagree with its trims) never stop crossing, and each round would split more
/// segments than the last (found by fuzzing: ×1.6 a round, 83 000 segments after 24 rounds for
/// a 108-segment face). Past the budget the faces still crossing are left `unresolved`.
pub fn face_loops_uncrossed(
    doc: &Document,
    edges: &mut EdgeTable,
    options: &Options,
) -> (Vec<Vec<Polyline>>, CrossingStats) {
    let n = doc.faces.len();
    let mut extra: Vec<FreeSplits> = vec![FreeSplits::new(); n];
    let all: Vec<usize> = (0..n).collect();
    let mut loops: Vec<Vec<Polyline>> = crate::map(&all, |&f| {
        face_loops(&doc.faces[f], edges, &extra[f], options)
    });
    let curves: HashMap<u64, &Curve3> = doc
        .edges
        .iter()
        .flatten()
        .filter_map(|e| e.curve.as_ref().map(|c| (e.id, c)))
        .collect();
    let mut users: HashMap<u64, Vec<usize>> = HashMap::new();
    for (f, face) in doc.faces.iter().enumerate() {
        for id in face
            .loops
            .iter()
            .flat_map(|l| &l.trims)
            .filter_map(|t| t.edge)
        {
            let list = users.entry(id).or_default();
            if list.last() != Some(&f) {
                list.push(f);
            }
        }
    }
    let mut stats = CrossingStats::default();
    let budget = loops
        .iter()
        .flatten()
        .map(Vec::len)
        .sum::<usize>()
        .max(MIN_SPLIT_BUDGET);
    let mut todo = all;
    for round in 0..=ROUNDS {
        // More pairs than the splits left to make would only be dropped.
        let limit = budget.saturating_sub(stats.splits).max(1);
        let found: Vec<Vec<[SegmentRef; 2]>> =
            crate::map(&todo, |&f| crossing_segments_at_most(&loops[f], limit));
        if found.iter().all(Vec::is_empty) {
            break;
        }
        if round == ROUNDS || stats.splits >= budget {
            stats.unresolved = todo
                .iter()
                .zip(&found)
                .filter(|(_, c)| !c.is_empty())
                .map(|(&f, _)| doc.faces[f].id)
                .collect();
            break;
        }
        stats.rounds += 1;
        let mut edge_splits: HashSet<(u64, u64, u64)> = HashSet::new();
        let mut again: HashSet<usize> = HashSet::new();
        for (&f, pairs) in todo.iter().zip(&found) {
            for &(l, i) in pairs.iter().flatten() {
                let Some(seg) = loops[f][l][i].next else {
                    continue;
                };
                let [ta, tb] = seg.t;
                match seg.source {
                    Source::Edge(id) => {
                        let key = (id, ta.min(tb).to_bits(), ta.max(tb).to_bits());
                        if edge_splits.insert(key)
                            && let Some(curve) = curves.get(&id)
                            && split_edge(edges, id, curve, ta, tb)
                        {
                            stats.splits += 1;
                            again.extend(users.get(&id).into_iter().flatten());
                        }
                    }
                    Source::Free(lp, trim) => {
                        let m = 0.5 * (ta + tb);
                        let list = extra[f].entry((lp, trim)).or_default();
                        if m != ta && m != tb && !list.contains(&m) {
                            list.push(m);
                            stats.splits += 1;
                            again.insert(f);
                        }
                    }
                }
            }
        }
        if again.is_empty() {
            break;
        }
        todo = again.into_iter().collect();
        todo.sort_unstable();
        let fresh = crate::map(&todo, |&f| {
            face_loops(&doc.faces[f], edges, &extra[f], options)
        });
        for (&f, l) in todo.iter().zip(fresh) {
            loops[f] = l;
        }
    }
    (loops, stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::BoundaryPoint;
    use tessd_brep::DVec3;

    fn poly(pts: &[[f64; 2]]) -> Polyline {
        pts.iter()
            .map(|&uv| BoundaryPoint {
                uv: uv.into(),
                p: DVec3::new(uv[0], uv[1], 0.0),
                next: None,
            })
            .collect()
    }

    #[test]
    fn finds_crossings_between_and_within_loops_but_not_shared_ends() {
        let square = poly(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        // A triangle poking out through the square's right side.
        let poke = poly(&[[0.5, 0.4], [1.5, 0.5], [0.5, 0.6]]);
        let found = crossing_segments(&[square.clone(), poke]);
        assert_eq!(found.len(), 2, "{found:?}");
        for pair in &found {
            assert!(pair.contains(&(0, 1)), "{found:?}");
        }
        // A hole touching the square at a corner only.
        let touch = poly(&[[0.0, 0.0], [0.3, 0.1], [0.1, 0.3]]);
        assert!(crossing_segments(&[square.clone(), touch]).is_empty());
        // A bow tie crosses itself.
        let bow = poly(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]);
        assert_eq!(crossing_segments(&[bow]), vec![[(0, 0), (0, 2)]]);
        assert!(crossing_segments(&[square]).is_empty());
    }
}
