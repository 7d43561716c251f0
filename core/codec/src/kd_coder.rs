//! The Gandoin–Devillers coder of one nSP-cell (paper 003 §3 and §5.2b).
//!
//! Geometry: the kd-tree splits every cell in two along x, y, z in turn; each split is coded as
//! "low half non-empty", "high half non-empty" or "both" ([`Family::Split`]). Connectivity: when a
//! cell splits into two non-empty halves, its vertex `v` becomes `v1` (low) and `v2` (high), and
//! every simplex holding `v` is replaced by a non-empty subset of its candidate preimages
//! ([`crate::complex::candidates`]). That subset is the connectivity code, interleaved with the
//! geometry codes. This generalises GD02's edge-collapse and vertex-unification codes to any
//! triangle soup: a triangle whose corners fell into one cell survives as a degenerate triangle
//! (the edge or point it became), so orientation and non-manifold configurations come back exactly.
//!
//! The encoder runs bottom-up (merging the two halves of every cell, level by level, last cell
//! first) and the decoder top-down (splitting, first cell first), so that before each split the
//! decoder holds exactly the complex the encoder held after the matching merge.
//!
//! Predictions (the contexts of [`crate::symbols`]), all computed from what the decoder already
//! has, by one function both sides run (`code_connectivity`, `split_coding`):
//! - a split: the half the vertex's neighbours' centroid lies in, how far it is from the plane,
//!   and whether the cell holds a collapsed triangle (then it likely holds several points);
//! - a triangle holding the vertex once, taken breadth first through shared vertices: the child
//!   its other vertices are already linked to, else the side of the plane they lie on;
//! - a triangle holding both children (`v1 v2 x`, an edge collapse): the links of `x` and the
//!   orientation the neighbouring fine triangles imply;
//! - a triangle made of the vertex alone: whether either child already holds a collapsed edge.

use rustc_hash::FxHashMap;

use crate::ahead::Geometry;
use crate::complex::{Complex, POINT, Simplex, Vertex, axis_bits, candidate_of, candidates};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::symbols::{Family, Symbol, context};

/// The full-precision kd key of a vertex at kd level `level`: its split decisions, first on top.
pub fn kd_key(corner: [u32; 3], level: usize, bits: u32) -> u64 {
    let mut key = 0u64;
    for j in 0..level {
        let axis = j % 3;
        let bit = (corner[axis] >> (bits - 1 - (j / 3) as u32)) & 1;
        key |= (bit as u64) << (63 - j);
    }
    key
}

/// Side of the high half of a split at kd `level`, in grid units.
pub(crate) fn half(level: usize, bits: u32) -> u32 {
    1u32 << (bits - axis_bits(level, level % 3) - 1)
}

/// Whether `w` lies in the high half-space of the split of a cell at `level` with lower corner
/// `corner`.
fn high_side(w: &Vertex, corner: [u32; 3], level: usize, bits: u32) -> bool {
    let a = level % 3;
    w.corner[a] >= corner[a] + half(level, bits)
}

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

/// Swaps the roles of the two children in a mask over the four candidates of a twice-held
/// triangle: (1,1) ↔ (2,2), (1,2) ↔ (2,1).
fn swap_children(mask: u8) -> u8 {
    ((mask & 1) << 3) | ((mask & 8) >> 3) | ((mask & 2) << 1) | ((mask & 4) >> 1)
}

/// How a symbol's value maps to a preimage mask: for the three-valued families, which child is
/// predicted (value 0); for the twice-held triangles, whether the children are swapped.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coding {
    pub(crate) ctx: usize,
    pub(crate) family: Family,
    /// Predicted child is the high one / children swapped.
    pub(crate) flip: bool,
}

impl Coding {
    /// The value coding a split (0 = low half only, 1 = high half only, 2 = both).
    pub(crate) fn split_value(self, split: u8) -> u8 {
        if split == 2 {
            2
        } else {
            u8::from((split == 1) != self.flip)
        }
    }

    /// The split a value codes (the inverse of [`Coding::split_value`]).
    pub(crate) fn split(self, value: u8) -> u8 {
        if value == 2 {
            2
        } else {
            u8::from((value == 1) != self.flip)
        }
    }

    fn value(self, mask: u8) -> u8 {
        match self.family {
            Family::Twice | Family::Thrice => {
                if self.flip {
                    swap_children(mask) - 1
                } else {
                    mask - 1
                }
            }
            _ => match mask {
                3 => 2,
                m => u8::from((m == 2) != self.flip),
            },
        }
    }

    fn mask(self, value: u8) -> u8 {
        match self.family {
            Family::Twice | Family::Thrice => {
                if self.flip {
                    swap_children(value + 1)
                } else {
                    value + 1
                }
            }
            _ => match value {
                2 => 3,
                v => {
                    if (v == 1) != self.flip {
                        2
                    } else {
                        1
                    }
                }
            },
        }
    }
}

/// The coding of the split decision of vertex `v` (before its split at `level`): predicted half
/// from its neighbours' centroid, sub-context from that prediction's margin and from whether the
/// cell holds a collapsed triangle (then it likely holds several points).
fn split_coding(cx: &mut Complex, v: u32, level: usize, bits: u32) -> Coding {
    let a = level % 3;
    let corner = cx.vertices[v as usize].corner;
    let h = half(level, bits) as f64;
    let mut collapsed = false;
    // the distinct neighbours, on the stack while they are few (the usual case)
    let mut few = [0u32; 48];
    let mut count = 0usize;
    let mut many: Vec<u32> = Vec::new();
    cx.prune(v);
    for &slot in cx.listed(v) {
        let s = cx.simplices[slot as usize].expect("live");
        if s.kind != POINT && s.multiplicity(v) >= 2 {
            collapsed = true;
        }
        for &x in &s.v {
            if x == v || few[..count].contains(&x) {
                continue;
            }
            if count < few.len() {
                few[count] = x;
                count += 1;
            } else {
                many.push(x);
            }
        }
    }
    if !many.is_empty() {
        many.extend_from_slice(&few);
        many.sort_unstable();
        many.dedup();
    }
    let others: &[u32] = if many.is_empty() {
        &few[..count]
    } else {
        &many
    };
    let (margin, high) = if others.is_empty() {
        (0, false)
    } else {
        let sum: f64 = others
            .iter()
            .map(|&x| {
                let w = &cx.vertices[x as usize];
                w.corner[a] as f64 + (w.extent(a, bits) - 1) as f64 / 2.0
            })
            .sum();
        let mean = sum / others.len() as f64;
        let d = ((mean - (corner[a] as f64 + h - 0.5)) / h).abs();
        (margin_context(d), mean > corner[a] as f64 + h - 0.5)
    };
    let family = Family::Split;
    Coding {
        ctx: context(family, usize::from(collapsed) * 7 + margin, level),
        family,
        flip: high,
    }
}

/// The sub-context of a predicted split from the prediction's distance to the split plane, in
/// half-cells: 1 (closest) to 6; 0 is left for "no prediction".
pub(crate) fn margin_context(d: f64) -> usize {
    1 + [0.125, 0.25, 0.5, 1.0, 2.0]
        .iter()
        .filter(|&&m| d >= m)
        .count()
}

/// Where the preimage masks of a split come from: the encoder knows them, the decoder reads them.
trait Masks {
    /// The mask of coarse simplex `c`, coded with `coding`.
    fn mask(&mut self, c: &Simplex, coding: Coding) -> Result<u8, CodecError>;
}

/// Encoder side: masks from the fine complex, symbols appended.
struct Known<'a> {
    masks: FxHashMap<Simplex, u8>,
    out: &'a mut Vec<Symbol>,
}

impl Masks for Known<'_> {
    fn mask(&mut self, c: &Simplex, coding: Coding) -> Result<u8, CodecError> {
        let mask = self.masks[c];
        self.out.push(Symbol::new(coding.ctx, coding.value(mask)));
        Ok(mask)
    }
}

/// Decoder side: masks read from the stream.
struct Read<'a> {
    reader: &'a mut SymbolReader,
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
fn code_connectivity(
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
    let side = |x: u32| high_side(&cx.vertices[x as usize], corner, level, bits);
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
    // once-held triangles, predicted from the links their other vertices already have and from
    // the sides of the split plane they lie on
    let mut link: FxHashMap<u32, u8> = FxHashMap::default();
    let mut once: Vec<Simplex> = Vec::new();
    for i in bfs {
        let c = sorted[i];
        let (a, b) = others(&c);
        let (la, lb) = (
            link.get(&a).copied().unwrap_or(0),
            link.get(&b).copied().unwrap_or(0),
        );
        let e = la | lb;
        let (sa, sb) = (side(a), side(b));
        // predicted child: the linked one, else the side of the first vertex
        let flip = if e == 1 || e == 2 { e == 2 } else { sa };
        let same = sa == sb;
        let geometry_agrees = sa == flip;
        // both other vertices a whole cell or more away from the split plane
        let far = |x: u32| {
            let w = &cx.vertices[x as usize];
            let ax = level % 3;
            let plane = corner[ax] as u64 + half(level, bits) as u64;
            let (lo_w, hi_w) = (
                w.corner[ax] as u64,
                w.corner[ax] as u64 + w.extent(ax, bits),
            );
            hi_w + half(level, bits) as u64 <= plane || lo_w >= plane + half(level, bits) as u64
        };
        let remote = usize::from(far(a) && far(b));
        let sub = match e {
            0 => usize::from(same) * 2 + remote,
            3 => 4 + usize::from(same) * 2 + remote,
            _ => {
                8 + usize::from(la == lb) * 4 + usize::from(same) * 2 + usize::from(geometry_agrees)
            }
        };
        let family = Family::TriangleOnce;
        let mask = masks.mask(
            &c,
            Coding {
                ctx: context(family, sub, level),
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
        out.push((c, mask));
    }
    // twice-held triangles: the third vertex's links and the orientation of the once-held ones
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
        let sub = [0, 1, 0, 2][lx as usize] * 3 + (ev + 1) as usize;
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
        let sub = usize::from(collapsed_low) * 2 + usize::from(collapsed_high);
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
    Ok(out)
}

/// Encodes one nSP-cell: merges the kd-cells of `cx` from kd level `hi` down to `lo` (§5.2b),
/// with the geometry `advance` kd levels ahead of the connectivity (§6.4; 0 interleaves each
/// split with its connectivity codes).
///
/// `alive` lists the vertices at level `hi` in kd order; on return it lists those at level `lo`.
/// The symbols come back in the decoder's order.
pub fn encode(
    cx: &mut Complex,
    alive: &mut Vec<u32>,
    bits: u32,
    lo: usize,
    hi: usize,
    advance: usize,
) -> Vec<Symbol> {
    let geometry = (advance > 0).then(|| {
        let top = alive
            .iter()
            .map(|&v| cx.vertices[v as usize].corner)
            .collect();
        Geometry::of_cells(top, lo, hi, bits)
    });
    // events are recorded in merge order and emitted reversed: (start, len) into `buffer`;
    // with geometry ahead, the connectivity events of level l end at `level_ends[l - lo]`
    let mut buffer: Vec<Symbol> = Vec::new();
    let mut events: Vec<(u32, u32)> = Vec::new();
    let mut level_ends = vec![0usize; hi - lo];
    // with geometry ahead: the split codes of every level, in kd order
    let mut ahead: Vec<Vec<Symbol>> = vec![Vec::new(); hi - lo];
    let mut conn: Vec<Symbol> = Vec::new();
    for level in (lo..hi).rev() {
        let a = level % 3;
        let h = half(level, bits);
        // group the children of each parent; both are adjacent in kd order
        let mut groups: Vec<(u32, Option<u32>)> = Vec::with_capacity(alive.len());
        let mut i = 0;
        let parent = |cx: &Complex, id: u32| {
            let mut c = cx.vertices[id as usize].corner;
            c[a] &= !h;
            c
        };
        while i < alive.len() {
            let x = alive[i];
            if i + 1 < alive.len() && parent(cx, alive[i + 1]) == parent(cx, x) {
                groups.push((x, Some(alive[i + 1])));
                i += 2;
            } else {
                groups.push((x, None));
                i += 1;
            }
        }
        for &(x, y) in groups.iter().rev() {
            let start = buffer.len() as u32;
            conn.clear();
            let split = match y {
                None => {
                    let vx = &mut cx.vertices[x as usize];
                    let high = vx.corner[a] & h != 0;
                    vx.corner[a] &= !h;
                    vx.level = level as u8;
                    u8::from(high)
                }
                Some(v2) => {
                    merge(cx, x, v2, level, bits, &mut conn);
                    2
                }
            };
            if geometry.is_none() {
                let coding = split_coding(cx, x, level, bits);
                buffer.push(Symbol::new(coding.ctx, coding.split_value(split)));
            }
            buffer.extend_from_slice(&conn);
            events.push((start, buffer.len() as u32 - start));
        }
        *alive = groups.iter().map(|&(x, _)| x).collect();
        level_ends[level - lo] = events.len();
        // the complex now stands where the decoder reads the splits of level `level + A − 1`
        // (of levels lo..lo+A at the start)
        if let Some(g) = &geometry {
            let first = if level == lo { lo } else { level + advance - 1 };
            for depth in first..(level + advance).min(hi) {
                let splits = g.splits(depth);
                ahead[depth - lo] = g
                    .codings(cx, alive, depth, bits)
                    .into_iter()
                    .zip(splits)
                    .map(|(c, &s)| Symbol::new(c.ctx, c.split_value(s)))
                    .collect();
            }
        }
    }
    let mut out = Vec::with_capacity(buffer.len() + ahead.iter().map(Vec::len).sum::<usize>());
    let emit = |out: &mut Vec<Symbol>, events: &[(u32, u32)]| {
        for &(start, len) in events.iter().rev() {
            out.extend_from_slice(&buffer[start as usize..(start + len) as usize]);
        }
    };
    if advance == 0 {
        emit(&mut out, &events);
        return out;
    }
    for symbols in &ahead[..advance.min(hi - lo)] {
        out.extend_from_slice(symbols);
    }
    for level in lo..hi {
        // level l's events lie between level l+1's end and its own (merge order)
        let from = if level + 1 < hi {
            level_ends[level + 1 - lo]
        } else {
            0
        };
        emit(&mut out, &events[from..level_ends[level - lo]]);
        if level + advance < hi {
            out.extend_from_slice(&ahead[level + advance - lo]);
        }
    }
    out
}

/// Merges `v2` (high child) into `v1` (low child) and appends the connectivity codes of the
/// inverse split, in the decoder's order.
fn merge(cx: &mut Complex, v1: u32, v2: u32, level: usize, bits: u32, out: &mut Vec<Symbol>) {
    let mut fine_slots = cx.incident(v1).to_vec();
    fine_slots.extend_from_slice(cx.incident(v2));
    fine_slots.sort_unstable();
    fine_slots.dedup();
    let mut masks: FxHashMap<Simplex, u8> = FxHashMap::default();
    for &slot in &fine_slots {
        let s = cx.simplices[slot as usize].expect("incident() lists live simplices");
        *masks.entry(s.renamed(v2, v1)).or_insert(0) |= 1 << candidate_of(&s, v1, v2);
        cx.remove(slot);
    }
    cx.vertices[v1 as usize].level = level as u8;
    cx.vertices[v2 as usize].level = u8::MAX;
    let coarse: Vec<Simplex> = masks.keys().copied().collect();
    for &c in &coarse {
        cx.add(c);
    }
    let mut known = Known { masks, out };
    code_connectivity(cx, &coarse, v1, v2, level, bits, &mut known)
        .expect("the encoder knows every mask");
}

/// Limits a decoder holds a cell to, so that a corrupt file cannot make it grow without bound.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Most vertices the cell's complex may hold.
    pub vertices: usize,
    /// Most live simplices.
    pub simplices: usize,
}

/// What part of a cell's code one [`decode`] call reads.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    /// Bits per coordinate of the file, `p`.
    pub bits: u32,
    /// kd level the complex is at.
    pub lo: usize,
    /// kd level to stop at.
    pub hi: usize,
    /// The cell's last kd level (its code ends there).
    pub end: usize,
    /// kd levels of geometry ahead of the connectivity (3 × `--ahead`).
    pub advance: usize,
}

/// Decodes one nSP-cell: splits the kd-cells of `cx` from kd level `span.lo` up to `span.hi`
/// (§6.2). With geometry ahead (§6.4), `geometry` carries what was read ahead from one call to
/// the next (`None` at the cell's start).
///
/// `alive` lists the vertices at level `lo` in kd order; on return, those at level `hi`.
pub fn decode(
    cx: &mut Complex,
    alive: &mut Vec<u32>,
    span: Span,
    reader: &mut SymbolReader,
    limits: Limits,
    geometry: &mut Option<Geometry>,
) -> Result<(), CodecError> {
    let Span {
        bits,
        lo,
        hi,
        end,
        advance,
    } = span;
    if advance > 0 && geometry.is_none() {
        let mut g = Geometry::start(cx, alive, lo, bits);
        for depth in lo..(lo + advance).min(end) {
            g.read(cx, alive, depth, bits, |ctx| reader.next(ctx))?;
        }
        *geometry = Some(g);
    }
    for level in lo..hi {
        let a = level % 3;
        let h = half(level, bits);
        let mut next = Vec::with_capacity(alive.len() * 2);
        for (i, &v) in alive.iter().enumerate() {
            let split = match geometry {
                Some(g) => *g.splits(level).get(i).ok_or_else(|| {
                    CodecError::corrupt(reader.offset, "the geometry ahead lost a kd-cell")
                })?,
                None => {
                    let coding = split_coding(cx, v, level, bits);
                    coding.split(reader.next(coding.ctx)?)
                }
            };
            let vx = cx.vertices[v as usize];
            let mut high = vx;
            high.corner[a] += h;
            high.level = level as u8 + 1;
            match split {
                0 => {
                    cx.vertices[v as usize].level = level as u8 + 1;
                    next.push(v);
                }
                1 => {
                    cx.vertices[v as usize] = high;
                    next.push(v);
                }
                _ => {
                    if cx.vertices.len() >= limits.vertices {
                        return Err(CodecError::corrupt(
                            reader.offset,
                            format!(
                                "the cell grows past its recorded {} vertices at kd level {level}",
                                limits.vertices
                            ),
                        ));
                    }
                    let v2 = cx.add_vertex(high);
                    split_vertex(cx, v, v2, level, bits, reader)?;
                    next.push(v);
                    next.push(v2);
                    if cx.live > limits.simplices {
                        return Err(CodecError::corrupt(
                            reader.offset,
                            format!(
                                "the cell grows past its recorded {} simplices at kd level {level}",
                                limits.simplices
                            ),
                        ));
                    }
                }
            }
        }
        *alive = next;
        if let Some(g) = geometry {
            g.drop_above(level + 1);
            if level + advance < end {
                g.read(cx, alive, level + advance, bits, |ctx| reader.next(ctx))?;
            }
        }
    }
    Ok(())
}

/// Splits `v` into itself (low half) and `v2` (high half), reading one connectivity code per
/// simplex holding `v`.
fn split_vertex(
    cx: &mut Complex,
    v: u32,
    v2: u32,
    level: usize,
    bits: u32,
    reader: &mut SymbolReader,
) -> Result<(), CodecError> {
    let slots = cx.incident(v).to_vec();
    let coarse: Vec<Simplex> = slots
        .iter()
        .map(|&s| cx.simplices[s as usize].expect("live"))
        .collect();
    let decoded = code_connectivity(cx, &coarse, v, v2, level, bits, &mut Read { reader })?;
    for &s in &slots {
        cx.remove(s);
    }
    cx.vertices[v as usize].level = level as u8 + 1;
    for (c, mask) in decoded {
        for (i, f) in candidates(&c, v, v2).into_iter().enumerate() {
            if mask & (1 << i) != 0 {
                cx.add(f);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_and_masks_round_trip_in_every_family() {
        for family in crate::symbols::ALL {
            let masks: Vec<u8> = if family.alphabet() == 3 {
                vec![1, 2, 3]
            } else {
                (1..16).collect()
            };
            for flip in [false, true] {
                let coding = Coding {
                    ctx: context(family, 0, 0),
                    family,
                    flip,
                };
                for &m in &masks {
                    let value = coding.value(m);
                    assert!((value as usize) < family.alphabet());
                    assert_eq!(coding.mask(value), m, "{family:?} flip {flip}");
                }
            }
        }
    }
}
