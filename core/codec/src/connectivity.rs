//! The connectivity codes of one split (paper 003 §3, GD02 generalised to triangle soups): the
//! preimage mask of every coarse simplex holding the split vertex, in an order and with contexts
//! both sides compute from the decoder's state. The encoder knows the masks ([`Known`]), the
//! decoder reads them ([`Read`]).

use std::cell::RefCell;

use crate::coding::{Coding, midpoint_band};
use crate::complex::{Complex, POINT, Simplex};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::kd_cell::half;
use crate::symbols::{Family, Symbol, context, context_banded};

/// Per-thread buffers of [`code_connectivity`], reused from split to split: the stars are small
/// and the splits many, so hash maps and fresh vectors per split cost more than the codes.
/// The other vertices of a star are numbered locally (0, 1, … in order of first appearance) and
/// every per-vertex state lives in small arrays indexed by that number.
#[derive(Default)]
struct Scratch {
    /// Per vertex id of the complex: the generation that last numbered it, and its number.
    stamp: Vec<u32>,
    local: Vec<u32>,
    generation: u32,
    /// Per local number: the vertex id; its rank in corner order; whether it is a pivot; its
    /// links; per child `c`, the fine edges c→x minus x→c of the once-held triangles coded so
    /// far (an unmatched directed edge asks for the triangle on its other side); its centre's
    /// offset from the split plane.
    ids: Vec<u32>,
    rank: Vec<u32>,
    pivot: Vec<bool>,
    link: Vec<u8>,
    balance: Vec<[i32; 2]>,
    /// Per local number: the once-held fine triangles holding it, per child.
    held_by: Vec<[u8; 2]>,
    offset: Vec<i64>,
    /// (corner, local number), sorted to give the ranks.
    by_corner: Vec<([u32; 3], u32)>,
    /// (order key, index into the coarse simplices), sorted: the coding order.
    order: Vec<(u64, u32)>,
    /// The once-held triangles in coding order: local a, local b, index into the coarse list.
    once: Vec<(u32, u32, u32)>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::default();
}

impl Scratch {
    /// Numbers the other vertices of the star of `v` and ranks them by corner.
    fn number(&mut self, cx: &Complex, coarse: &[Simplex], v: u32) {
        if self.stamp.len() < cx.vertices.len() {
            self.stamp.resize(cx.vertices.len(), 0);
            self.local.resize(cx.vertices.len(), 0);
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        self.ids.clear();
        for c in coarse {
            for &x in &c.v {
                if x != v && self.stamp[x as usize] != self.generation {
                    self.stamp[x as usize] = self.generation;
                    self.local[x as usize] = self.ids.len() as u32;
                    self.ids.push(x);
                }
            }
        }
        let n = self.ids.len();
        self.by_corner.clear();
        self.by_corner.extend(
            self.ids
                .iter()
                .enumerate()
                .map(|(l, &x)| (cx.vertices[x as usize].corner, l as u32)),
        );
        // corners are distinct among live kd-cells (they do not overlap), so ranks never tie
        self.by_corner.sort_unstable();
        self.rank.resize(n, 0);
        for (r, &(_, l)) in self.by_corner.iter().enumerate() {
            self.rank[l as usize] = r as u32;
        }
        self.pivot.clear();
        self.pivot.resize(n, false);
        self.link.clear();
        self.link.resize(n, 0);
        self.balance.clear();
        self.balance.resize(n, [0, 0]);
        self.held_by.clear();
        self.held_by.resize(n, [0, 0]);
    }

    fn of(&self, x: u32) -> u32 {
        self.local[x as usize]
    }
}

/// The sub-context and predicted child (`true` = high) of a once-held triangle `(v, a, b)` from
/// the links `a` and `b` have (bit 0: to the low child, bit 1: to the high one, by triangles
/// decoded before), whether each is a pivot (the third vertex of a coarse `(v, v, x)`: around
/// `v`, the fan of triangles switches from one child to the other at the pivots), and `mid`, the
/// midpoint of `a` and `b` from the split plane in quarters of a child's side (negative below).
///
/// The predicted child is the single link (of the vertex that is not a pivot where two single
/// links disagree), else the midpoint's side; the sub-context is the
/// unordered pair of the vertices' states (link relative to the prediction: none, it, the other,
/// both; pivot or not) times six bands of the midpoint's distance on the prediction's side times
/// how many more unmatched fine edges of `a` and `b` the triangle would close on the predicted
/// child than on the other (−2..=2; `balance` holds, for `a` then `b`, c→x minus x→c per child).
fn once_context(a: (u8, bool), b: (u8, bool), mid: i64, balance: [[i32; 2]; 2]) -> (usize, bool) {
    let flip = match (a, b) {
        // single links that disagree: the fan switches children at a pivot, so the link of
        // the vertex that is not one holds across the triangle; else the midpoint decides
        ((1 | 2, pa), (1 | 2, pb)) if a.0 != b.0 => match (pa, pb) {
            (true, false) => b.0 == 2,
            (false, true) => a.0 == 2,
            _ => mid >= 0,
        },
        ((1 | 2, _), _) => a.0 == 2,
        (_, (1 | 2, _)) => b.0 == 2,
        _ => mid >= 0,
    };
    let state = |(l, pivot): (u8, bool)| {
        let rel = match l {
            0 => 0,
            3 => 3,
            l => 1 + usize::from((l == 2) != flip),
        };
        rel * 2 + usize::from(pivot)
    };
    let (x, y) = (state(a), state(b));
    let (x, y) = (x.max(y), x.min(y));
    let band = midpoint_band(mid, flip);
    // the fine triangle (c, a, b) holds c→a and b→c: it closes an unmatched a→c or c→b and
    // doubles an unmatched c→a or b→c; the predicted child's score against the other's
    let [da, db] = balance;
    let score = |k: usize| {
        i32::from(da[k] < 0) + i32::from(db[k] > 0) - i32::from(da[k] > 0) - i32::from(db[k] < 0)
    };
    let (p, o) = if flip { (1, 0) } else { (0, 1) };
    let closes = ((score(p) - score(o)).clamp(-2, 2) + 2) as usize;
    (((x * (x + 1) / 2 + y) * 6 + band) * 5 + closes, flip)
}

/// Where the preimage masks of a split come from: the encoder knows them, the decoder reads them.
pub(crate) trait Masks {
    /// The mask of coarse simplex `c`, coded with `coding`.
    fn mask(&mut self, c: &Simplex, coding: Coding) -> Result<u8, CodecError>;
}

/// Encoder side: masks from the fine complex, symbols appended.
pub(crate) struct Known<'a> {
    pub(crate) masks: crate::complex::MaskList,
    pub(crate) out: &'a mut Vec<Symbol>,
}

impl Masks for Known<'_> {
    fn mask(&mut self, c: &Simplex, coding: Coding) -> Result<u8, CodecError> {
        let mask = self.masks[c];
        self.out.push(Symbol::new(coding.ctx, coding.value(mask)));
        Ok(mask)
    }
}

/// Decoder side: masks read from the stream.
pub(crate) struct Read<'a> {
    pub(crate) reader: &'a mut SymbolReader,
}

impl Masks for Read<'_> {
    fn mask(&mut self, _c: &Simplex, coding: Coding) -> Result<u8, CodecError> {
        Ok(coding.mask(self.reader.next(coding.ctx)?))
    }
}

/// The connectivity codes of the split of `v` (low child, keeps the id) and `v2` (§3), over the
/// coarse complex `cx`: the triangles holding `v` once, their midpoints farthest from the split
/// plane first (so that those near it are predicted by the links the others gave their
/// vertices), then those holding it twice (orientation from the once-held ones; the third
/// vertex linked to one child first), then three times, then the isolated point (which needs
/// the children no triangle holds); otherwise in the order of the corners of their other
/// vertices in turn order. Writes every coarse simplex
/// with its preimage mask into `out` (cleared first: a caller splitting many vertices reuses one
/// buffer). Encoder and decoder both run this, so their contexts cannot drift
/// apart; every order and context comes from corners and decoded masks, never from vertex ids
/// (the two sides number vertices differently).
pub(crate) fn code_connectivity(
    cx: &Complex,
    coarse: &[Simplex],
    (v, v2): (u32, u32),
    level: usize,
    bits: u32,
    masks: &mut impl Masks,
    out: &mut Vec<(Simplex, u8)>,
) -> Result<(), CodecError> {
    out.clear();
    SCRATCH.with(|s| {
        code_with(
            &mut s.borrow_mut(),
            cx,
            coarse,
            (v, v2),
            level,
            bits,
            masks,
            out,
        )
    })
}

#[allow(clippy::too_many_arguments)]
fn code_with(
    s: &mut Scratch,
    cx: &Complex,
    coarse: &[Simplex],
    (v, v2): (u32, u32),
    level: usize,
    bits: u32,
    masks: &mut impl Masks,
    out: &mut Vec<(Simplex, u8)>,
) -> Result<(), CodecError> {
    s.number(cx, coarse, v);
    // the coding order: kind, multiplicity, then the ranks of the other vertices in turn order
    s.order.clear();
    let mut vvv = false;
    for (i, c) in coarse.iter().enumerate() {
        let k = c.multiplicity(v) as u64;
        let head = ((c.kind as u64) << 2 | k) << 48;
        let key = if c.kind == POINT || k == 3 {
            vvv |= c.kind != POINT;
            head
        } else if k == 1 {
            let (a, b) = c.after(v);
            head | (s.rank[s.of(a) as usize] as u64) << 24 | s.rank[s.of(b) as usize] as u64
        } else {
            let x = *c.v.iter().find(|&&x| x != v).unwrap();
            let l = s.of(x) as usize;
            s.pivot[l] = true;
            head | (s.rank[s.of(x) as usize] as u64) << 24
        };
        s.order.push((key, i as u32));
    }
    s.order.sort_unstable();
    debug_assert!(s.order.windows(2).all(|w| w[0].0 != w[1].0));
    // once-held triangles, predicted from the links their other vertices already have, whether
    // those are pivots, and where their midpoint lies from the split plane
    let corner = cx.vertices[v as usize].corner;
    let ax = level % 3;
    let h = half(level, bits) as i64;
    let plane2 = 2 * (corner[ax] as i64 + h);
    // a vertex's centre from the split plane along the axis, in half grid units
    s.offset.clear();
    s.offset.extend(s.ids.iter().map(|&x| {
        let w = &cx.vertices[x as usize];
        2 * w.corner[ax] as i64 + w.extent(ax, bits) as i64 - 1 - plane2
    }));
    // the once-held triangles, their midpoints farthest from the plane first: those the
    // geometry predicts surely come first and link their vertices, so that the ones near the
    // plane, coded last, are predicted by the links (on the bunny at 12 bits 2.59 -> 2.23 b/v
    // against a breadth-first walk through the shared vertices; fandisk 2.51 -> 2.17)
    s.once.clear();
    for &(key, i) in &s.order {
        let c = &coarse[i as usize];
        if c.kind != POINT && key >> 48 & 3 == 1 {
            let (a, b) = c.after(v);
            s.once.push((s.of(a), s.of(b), i));
        }
    }
    let (offset, rank) = (&s.offset, &s.rank);
    // ties by the ranks (corners), never by `i`: the two sides list a star in different orders
    s.once.sort_unstable_by_key(|&(a, b, _)| {
        let (a, b) = (a as usize, b as usize);
        (-(offset[a] + offset[b]).abs(), rank[a], rank[b])
    });
    let band = (level / 3).clamp(4, 7) - 4;
    // which children hold a once-held fine triangle already
    let mut held = [false; 2];
    for j in 0..s.once.len() {
        let (a, b, i) = s.once[j];
        let c = coarse[i as usize];
        let (a, b) = (a as usize, b as usize);
        // the midpoint of a and b from the plane, in quarters of a child's side
        let mid = (s.offset[a] + s.offset[b]).div_euclid(h);
        let (sub, flip) = once_context(
            (s.link[a], s.pivot[a]),
            (s.link[b], s.pivot[b]),
            mid,
            [s.balance[a], s.balance[b]],
        );
        let (p, o) = if flip { (1, 0) } else { (0, 1) };
        let sub = sub * 4 + usize::from(held[p]) * 2 + usize::from(held[o]);
        let family = Family::TriangleOnce;
        let mask = masks.mask(
            &c,
            Coding {
                ctx: context_banded(family, sub, band),
                family,
                flip,
            },
        )?;
        s.link[a] |= mask;
        s.link[b] |= mask;
        // the fine triangle (c, a, b) has the edges c→a and b→c
        for (k, held) in held.iter_mut().enumerate() {
            if mask & (1 << k) != 0 {
                *held = true;
                s.held_by[a][k] = s.held_by[a][k].saturating_add(1);
                s.held_by[b][k] = s.held_by[b][k].saturating_add(1);
                s.balance[a][k] += 1;
                s.balance[b][k] -= 1;
            }
        }
        out.push((c, mask));
    }
    // twice-held triangles: the third vertex's links and the orientation of the once-held ones,
    // whether `(v, v, v)` exists (then the cell held a collapsed triangle); first those whose
    // third vertex is linked to one child (nearly always `(c, c, x)`: they tell which children
    // hold collapsed edges), then those linked to both, which that tells most about (on the
    // bunny at 12 bits 1.28 -> 1.15 b/v, fandisk 1.35 -> 1.24)
    let mut bridged = false;
    // the collapsed edges (c, c, x) decoded so far, per child
    let mut collapsed = [0usize; 2];
    for both in [false, true] {
        for &(key, i) in &s.order {
            let c = &coarse[i as usize];
            if c.kind == POINT || key >> 48 & 3 != 2 {
                continue;
            }
            let x = *c.v.iter().find(|&&x| x != v).unwrap();
            let l = s.of(x) as usize;
            let lx = s.link[l];
            if (lx == 3) != both {
                continue;
            }
            // orientation evidence: an unmatched v1→x or x→v2 predicts (v1, v2, x), an
            // unmatched x→v1 or v2→x predicts (v2, v1, x)
            let ev = (s.balance[l][0] - s.balance[l][1]).signum();
            let flip = lx == 2 || (lx != 1 && ev < 0);
            let ev = if flip { -ev } else { ev };
            let lx = if lx == 2 { 1 } else { lx.min(3) };
            // x linked to both children: whether (c, c, ·) came before, for the predicted child
            // c and the other (then its cell holds several vertices: more collapsed triangles)
            // and how many once-held fine triangles of each child hold x (0, 1, 2+)
            let (seen, around) = if lx == 3 {
                let [low, high] = collapsed.map(|n| n > 0);
                let (p, o) = if flip { (high, low) } else { (low, high) };
                let [n1, n2] = s.held_by[l].map(|n| n.min(2) as usize);
                let (np, no) = if flip { (n2, n1) } else { (n1, n2) };
                (usize::from(p) * 2 + usize::from(o), np * 3 + no)
            } else {
                (0, 0)
            };
            let sub =
                ((([0, 1, 0, 2][lx as usize] * 3 + (ev + 1) as usize) * 2 + usize::from(vvv)) * 4
                    + seen)
                    * 9
                    + around;
            let family = Family::Twice;
            let mask = masks.mask(
                c,
                Coding {
                    ctx: context(family, sub, level),
                    family,
                    flip,
                },
            )?;
            collapsed[0] += usize::from(mask & 1 != 0);
            collapsed[1] += usize::from(mask & 8 != 0);
            // (v1, v1, x), (v1, v2, x), (v2, v1, x) hold the low child, all but the first the
            // high one
            held[0] |= mask & 7 != 0;
            held[1] |= mask & 14 != 0;
            bridged |= mask & 6 != 0;
            out.push((*c, mask));
        }
    }
    // the triangle made of the vertex alone: how many collapsed edges `(c, c, x)` each child
    // holds (0, 1, 2, 3+: a child holding several is likely to hold a whole fine triangle too;
    // the count took the bunny's thrice codes from 0.66 to 0.34 b/v and fandisk's from 0.73 to
    // 0.43 against "any"), and whether a fine `(v1, v2, x)` or `(v2, v1, x)` bridges them
    for &(key, i) in &s.order {
        let c = &coarse[i as usize];
        if c.kind == POINT || key >> 48 & 3 != 3 {
            continue;
        }
        let family = Family::Thrice;
        let sub = (collapsed[0].min(3) * 4 + collapsed[1].min(3)) * 2 + usize::from(bridged);
        let coding = Coding {
            ctx: context_banded(family, sub, band),
            family,
            flip: false,
        };
        let mask = masks.mask(c, coding)?;
        // (v1, v1, v1) holds the low child, (v2, v2, v2) the high one, the others both
        held[0] |= mask & 13 != 0;
        held[1] |= mask & 14 != 0;
        out.push((*c, mask));
    }
    // isolated points last: both children exist, so a child no triangle holds needs the point
    // (both uncovered: the point is alone in the star and goes to both)
    for &(_, i) in &s.order {
        let c = &coarse[i as usize];
        if c.kind != POINT {
            continue;
        }
        let family = Family::Point;
        let coding = Coding {
            ctx: context(
                family,
                usize::from(held[0]) * 2 + usize::from(held[1]),
                level,
            ),
            family,
            flip: held[0] && !held[1],
        };
        out.push((*c, masks.mask(c, coding)?));
    }
    #[cfg(test)]
    crate::connectivity_study::record(cx, v, level, bits, out);
    let _ = v2;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::Vertex;

    #[test]
    fn once_contexts_do_not_depend_on_which_child_is_low() {
        // swapping the children swaps link bits 1 and 2, mirrors the midpoint (floor quarters:
        // m ↔ −1 − m) and swaps each vertex's balance; the sub-context must stay and the
        // predicted child swap, so that both halves of a split share their statistics
        let swap = |l: u8| ((l & 1) << 1) | ((l & 2) >> 1);
        let mut subs = std::collections::HashSet::new();
        for la in 0..4u8 {
            for lb in 0..4u8 {
                for (pa, pb) in [(false, false), (true, false), (false, true), (true, true)] {
                    for mid in -9..9i64 {
                        for d in 0..81 {
                            let t = |k: i32| (d / 3i32.pow(k as u32)) % 3 - 1;
                            let balance = [[t(0), t(1)], [t(2), t(3)]];
                            let (sub, flip) = once_context((la, pa), (lb, pb), mid, balance);
                            let mirrored = [[t(1), t(0)], [t(3), t(2)]];
                            let (sub2, flip2) =
                                once_context((swap(la), pa), (swap(lb), pb), -1 - mid, mirrored);
                            assert_eq!((sub, flip), (sub2, !flip2), "{la} {lb} {mid} {balance:?}");
                            assert!(sub * 4 + 3 < Family::TriangleOnce.subs());
                            subs.insert(sub);
                        }
                    }
                }
            }
        }
        // (540 of the 1 080 are reachable: "the other child" needs both links single, and
        // then the pivot, if one alone is, holds it)
        assert_eq!(subs.len(), 540);
    }

    /// Masks from the corners of a simplex's vertices (so both numberings get the same ones),
    /// with every coding recorded.
    struct ByCorner {
        corners: Vec<[u32; 3]>,
        log: Vec<(usize, bool, u8)>,
    }

    impl Masks for ByCorner {
        fn mask(&mut self, c: &Simplex, coding: Coding) -> Result<u8, CodecError> {
            // the corners in their smallest rotation: the ids' rotation differs between sides
            let t = c.v.map(|x| self.corners[x as usize]);
            let t = *[t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]]
                .iter()
                .min()
                .unwrap();
            let mut h = 0x9e37_79b9u32;
            for k in t {
                for &k in &k {
                    h = (h ^ k).wrapping_mul(0x0100_0193);
                }
            }
            let mask = match coding.family {
                Family::Twice | Family::Thrice => 1 + (h >> 7) as u8 % 15,
                _ => 1 + (h >> 7) as u8 % 3,
            };
            self.log.push((coding.ctx, coding.flip, coding.value(mask)));
            Ok(mask)
        }
    }

    #[test]
    fn codes_depend_on_corners_not_on_vertex_numbers() {
        // the encoder and the decoder number vertices differently and list a star in different
        // orders: the codes must be the same
        let (bits, level) = (6, 6);
        let centre = [16u32, 16, 16];
        let mut corners = vec![centre];
        for dx in [0u32, 16, 32] {
            for dy in [0u32, 16, 32] {
                for dz in [0u32, 16, 32] {
                    if [dx, dy, dz] != [16, 16, 16] {
                        corners.push([dx, dy, dz]);
                    }
                }
            }
        }
        // the star of vertex 0 (by position in `corners`): a ring, a few more, collapsed ones
        let mut star: Vec<[usize; 3]> = Vec::new();
        for i in 1..corners.len() {
            star.push([0, i, 1 + i % (corners.len() - 1)]);
            if i % 4 == 0 {
                star.push([0, 0, i]);
            }
        }
        star.push([0, 0, 0]);
        let run = |order: &dyn Fn(usize) -> usize, reverse: bool| {
            let n = corners.len();
            let mut cx = Complex::default();
            let mut id = vec![0u32; n];
            for k in 0..n {
                let i = order(k);
                id[i] = cx.add_vertex(Vertex {
                    corner: corners[i],
                    level: level as u8,
                });
            }
            let mut coarse: Vec<Simplex> = star
                .iter()
                .map(|t| Simplex::triangle(id[t[0]], id[t[1]], id[t[2]]))
                .collect();
            coarse.push(Simplex::point(id[0]));
            if reverse {
                coarse.reverse();
            }
            let mut high = corners[0];
            high[0] += 8;
            let v2 = cx.add_vertex(Vertex {
                corner: high,
                level: level as u8 + 1,
            });
            let mut masks = ByCorner {
                corners: cx.vertices.iter().map(|w| w.corner).collect(),
                log: Vec::new(),
            };
            let mut out = Vec::new();
            code_connectivity(&cx, &coarse, (id[0], v2), level, bits, &mut masks, &mut out)
                .expect("codes");
            let by_corner: Vec<([[u32; 3]; 3], u8)> = out
                .iter()
                .map(|(c, m)| (c.v.map(|x| masks.corners[x as usize]), *m))
                .collect();
            (masks.log, by_corner)
        };
        let n = corners.len();
        let (log_a, out_a) = run(&|k| k, false);
        let (log_b, out_b) = run(&|k| n - 1 - k, true);
        assert_eq!(log_a.len(), star.len() + 1);
        assert_eq!(log_a, log_b);
        // the same simplices (up to rotation, which differs with the ids) with the same masks
        let norm = |v: &[([[u32; 3]; 3], u8)]| {
            let mut v: Vec<([[u32; 3]; 3], u8)> = v
                .iter()
                .map(|&(t, m)| {
                    (
                        *[t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]]
                            .iter()
                            .min()
                            .unwrap(),
                        m,
                    )
                })
                .collect();
            v.sort_unstable();
            v
        };
        assert_eq!(norm(&out_a), norm(&out_b));
    }
}
