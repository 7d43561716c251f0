//! The connectivity codes of one split (paper 003 §3, GD02 generalised to triangle soups): the
//! preimage mask of every coarse simplex holding the split vertex, in an order and with contexts
//! both sides compute from the decoder's state. The encoder knows the masks ([`Known`]), the
//! decoder reads them ([`Read`]).

use rustc_hash::FxHashMap;

use crate::coding::Coding;
use crate::complex::{Complex, POINT, Simplex};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::kd_cell::{half, high_side};
use crate::symbols::{Family, Symbol, context};

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

/// Where the preimage masks of a split come from: the encoder knows them, the decoder reads them.
pub(crate) trait Masks {
    /// The mask of coarse simplex `c`, coded with `coding`.
    fn mask(&mut self, c: &Simplex, coding: Coding) -> Result<u8, CodecError>;
}

/// Encoder side: masks from the fine complex, symbols appended.
pub(crate) struct Known<'a> {
    pub(crate) masks: FxHashMap<Simplex, u8>,
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
