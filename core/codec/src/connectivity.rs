//! The connectivity codes of one split (paper 003 §3, GD02 generalised to triangle soups): the
//! preimage mask of every coarse simplex holding the split vertex, in an order and with contexts
//! both sides compute from the decoder's state. The encoder knows the masks ([`Known`]), the
//! decoder reads them ([`Read`]).

use rustc_hash::FxHashMap;

use crate::coding::Coding;
use crate::complex::{Complex, POINT, Simplex};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::kd_cell::half;
use crate::symbols::{Family, Symbol, context, context_banded};

/// The order in which the simplices holding `v` are coded: points, then triangles holding `v`
/// once, twice, three times; among those, by the corners of their other vertices in turn order.
fn order_key(cx: &Complex, s: &Simplex, v: u32) -> (u8, u8, [u32; 3], [u32; 3]) {
    let k = s.multiplicity(v) as u8;
    let c = |x: u32| cx.vertices[x as usize].corner;
    if s.kind == POINT || k == 3 {
        return (s.kind, k, [0; 3], [0; 3]);
    }
    if k == 1 {
        let i = s.v.iter().position(|&x| x == v).unwrap();
        (s.kind, k, c(s.v[(i + 1) % 3]), c(s.v[(i + 2) % 3]))
    } else {
        let x = *s.v.iter().find(|&&x| x != v).unwrap();
        (s.kind, k, c(x), [0; 3])
    }
}

/// Orientation evidence for a triangle holding both children and `x`: +1 when the fine
/// triangles around predict `(v1, v2, x)`, −1 for `(v2, v1, x)`, 0 when they do not say.
fn orientation_evidence(once: &[Simplex], v1: u32, v2: u32, x: u32) -> i32 {
    let (mut e12, mut e21) = (0i32, 0i32);
    for t in once.iter().filter(|t| t.v.contains(&x)) {
        for i in 0..3 {
            let (a, b) = (t.v[i], t.v[(i + 1) % 3]);
            if (a == x && b == v2) || (a == v1 && b == x) {
                e12 += 1;
            }
            if (a == x && b == v1) || (a == v2 && b == x) {
                e21 += 1;
            }
        }
    }
    (e12 - e21).signum()
}

/// The sub-context and predicted child (`true` = high) of a once-held triangle `(v, a, b)` from
/// the links `a` and `b` have (bit 0: to the low child, bit 1: to the high one, by triangles
/// decoded before), whether each is a pivot (the third vertex of a coarse `(v, v, x)`: around
/// `v`, the fan of triangles switches from one child to the other at the pivots), and `mid`, the
/// midpoint of `a` and `b` from the split plane in quarters of a child's side (negative below).
///
/// The predicted child is the first single link, else the midpoint's side; the sub-context is the
/// unordered pair of the vertices' states (link relative to the prediction: none, it, the other,
/// both; pivot or not) times six bands of the midpoint's distance on the prediction's side.
fn once_context(a: (u8, bool), b: (u8, bool), mid: i64) -> (usize, bool) {
    let flip = match (a.0, b.0) {
        (1 | 2, _) => a.0 == 2,
        (_, 1 | 2) => b.0 == 2,
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
    let m = if flip { mid } else { -1 - mid };
    let band = match m {
        ..=-5 => 0,
        -4..=-3 => 1,
        -2..=-1 => 2,
        0..=1 => 3,
        2..=3 => 4,
        _ => 5,
    };
    ((x * (x + 1) / 2 + y) * 6 + band, flip)
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
/// coarse complex `cx`: points first, then the triangles holding `v` once in breadth-first order
/// through their shared vertices (so each is predicted from its decoded neighbours), then those
/// holding it twice (orientation from the once-held ones), then three times. Returns every
/// coarse simplex with its preimage mask. Encoder and decoder both run this, so their contexts
/// cannot drift apart.
pub(crate) fn code_connectivity(
    cx: &Complex,
    coarse: &[Simplex],
    v: u32,
    v2: u32,
    level: usize,
    bits: u32,
    masks: &mut impl Masks,
) -> Result<Vec<(Simplex, u8)>, CodecError> {
    let mut sorted: Vec<Simplex> = coarse.to_vec();
    sorted.sort_by_key(|c| order_key(cx, c, v));
    let corner = cx.vertices[v as usize].corner;
    let mut out = Vec::with_capacity(sorted.len());
    // breadth-first order of the once-held triangles
    let once_coarse: Vec<usize> = (0..sorted.len())
        .filter(|&i| sorted[i].kind != POINT && sorted[i].multiplicity(v) == 1)
        .collect();
    let others = |c: &Simplex| {
        let i = c.v.iter().position(|&x| x == v).unwrap();
        (c.v[(i + 1) % 3], c.v[(i + 2) % 3])
    };
    let mut by_vertex: FxHashMap<u32, Vec<usize>> = FxHashMap::default();
    for &i in &once_coarse {
        let (a, b) = others(&sorted[i]);
        by_vertex.entry(a).or_default().push(i);
        if b != a {
            by_vertex.entry(b).or_default().push(i);
        }
    }
    let mut visited = vec![false; sorted.len()];
    let mut bfs: Vec<usize> = Vec::with_capacity(once_coarse.len());
    for &start in &once_coarse {
        if visited[start] {
            continue;
        }
        visited[start] = true;
        let mut head = bfs.len();
        bfs.push(start);
        while head < bfs.len() {
            let (a, b) = others(&sorted[bfs[head]]);
            head += 1;
            for x in [a, b] {
                for &j in &by_vertex[&x] {
                    if !visited[j] {
                        visited[j] = true;
                        bfs.push(j);
                    }
                }
            }
        }
    }
    // points
    for c in sorted.iter().filter(|c| c.kind == POINT) {
        let family = Family::Point;
        let coding = Coding {
            ctx: context(family, 0, level),
            family,
            flip: false,
        };
        out.push((*c, masks.mask(c, coding)?));
    }
    // once-held triangles, predicted from the links their other vertices already have, whether
    // those are pivots, and where their midpoint lies from the split plane
    let pivots: Vec<u32> = sorted
        .iter()
        .filter(|c| c.kind != POINT && c.multiplicity(v) == 2)
        .map(|c| *c.v.iter().find(|&&x| x != v).unwrap())
        .collect();
    let ax = level % 3;
    let plane2 = 2 * (corner[ax] as i64 + half(level, bits) as i64);
    // a vertex's centre from the split plane along its axis, in half grid units
    let offset = |x: u32| {
        let w = &cx.vertices[x as usize];
        2 * w.corner[ax] as i64 + w.extent(ax, bits) as i64 - 1 - plane2
    };
    let band = (level / 3).clamp(4, 7) - 4;
    let mut link: FxHashMap<u32, u8> = FxHashMap::default();
    let mut once: Vec<Simplex> = Vec::new();
    let mut any_both = false;
    for i in bfs {
        let c = sorted[i];
        let (a, b) = others(&c);
        let (la, lb) = (
            link.get(&a).copied().unwrap_or(0),
            link.get(&b).copied().unwrap_or(0),
        );
        // the midpoint of a and b from the plane, in quarters of a child's side
        let mid = (offset(a) + offset(b)).div_euclid(half(level, bits) as i64);
        let (sub, flip) = once_context((la, pivots.contains(&a)), (lb, pivots.contains(&b)), mid);
        let family = Family::TriangleOnce;
        let mask = masks.mask(
            &c,
            Coding {
                ctx: context_banded(family, sub, band),
                family,
                flip,
            },
        )?;
        for x in [a, b] {
            *link.entry(x).or_insert(0) |= mask;
        }
        if mask & 1 != 0 {
            once.push(Simplex::triangle(v, a, b));
        }
        if mask & 2 != 0 {
            once.push(Simplex::triangle(v2, a, b));
        }
        any_both |= mask == 3;
        out.push((c, mask));
    }
    // twice-held triangles: the third vertex's links and the orientation of the once-held ones,
    // whether `(v, v, v)` exists (then the cell held a collapsed triangle) and whether a
    // once-held triangle went to both children
    let vvv = sorted
        .iter()
        .any(|c| c.kind != POINT && c.multiplicity(v) == 3);
    let (mut collapsed_low, mut collapsed_high) = (false, false);
    for c in sorted
        .iter()
        .filter(|c| c.kind != POINT && c.multiplicity(v) == 2)
    {
        let x = *c.v.iter().find(|&&x| x != v).unwrap();
        let lx = link.get(&x).copied().unwrap_or(0);
        let ev = orientation_evidence(&once, v, v2, x);
        let flip = lx == 2 || (lx != 1 && ev < 0);
        let ev = if flip { -ev } else { ev };
        let lx = if lx == 2 { 1 } else { lx.min(3) };
        let sub = ([0, 1, 0, 2][lx as usize] * 3 + (ev + 1) as usize) * 4
            + usize::from(vvv) * 2
            + usize::from(any_both);
        let family = Family::Twice;
        let mask = masks.mask(
            c,
            Coding {
                ctx: context(family, sub, level),
                family,
                flip,
            },
        )?;
        collapsed_low |= mask & 1 != 0;
        collapsed_high |= mask & 8 != 0;
        out.push((*c, mask));
    }
    for c in sorted
        .iter()
        .filter(|c| c.kind != POINT && c.multiplicity(v) == 3)
    {
        let family = Family::Thrice;
        let sub = (usize::from(collapsed_low) * 2 + usize::from(collapsed_high)) * 2
            + usize::from(any_both);
        out.push((
            *c,
            masks.mask(
                c,
                Coding {
                    ctx: context(family, sub, level),
                    family,
                    flip: false,
                },
            )?,
        ));
    }
    #[cfg(test)]
    crate::connectivity_study::record(cx, v, level, bits, &out);
    Ok(out)
}
