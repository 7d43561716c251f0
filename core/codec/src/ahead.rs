//! Geometry ahead of connectivity (paper 003 §6.4, `--ahead m`).
//!
//! "le décodeur sera informé des divisions de kd-cells m bits avant que les changements de
//! connectivité n'interviennent effectivement": with an advance of `m` bits the split codes of kd
//! level `k + 3m` come right after the connectivity codes of level `k`, so a vertex shown at
//! level `k` is drawn at the barycentre of its descendants `3m` levels down instead of at its
//! cell's centre — the blocky staircase of a kd-tree at intermediate precisions goes away.
//!
//! A cell's stream is, for `A = 3m` levels of advance over its levels `lo..hi`:
//! `G(lo) … G(lo+A−1)`, then for every level `l`: `C(l)` (the connectivity codes of its splits, in
//! kd order) and `G(l+A)` while `l+A < hi`. Every cell starts with its own first `A` levels of
//! geometry: where the paper stores a child's leading geometry codes in its parent (for the child
//! holding the original kd-cell) and at the head of the other children, here each child carries
//! its own, so that no cell's chunk depends on its siblings' — the parent's last `A` levels of
//! connectivity then see geometry only down to the parent's last level.
//!
//! The split of a cell `c` at level `k` is coded before the connectivity of level `k` is known,
//! so its prediction (`Geometry::coding`) comes from what is: the vertex `u` of the complex
//! holding `c`, its neighbours standing at the barycentres of their descendants at level `k`, and
//! `c` itself; on that star run the predictors of `split_context` (centroid and margin,
//! tangent plane, density; not the parallelograms), with "collapsed" read as "`u` holds more than one
//! level-`k` cell" (then both halves are likely non-empty).

use crate::coding::Coding;
use crate::complex::{Complex, Vertex};
use crate::error::CodecError;
use crate::kd_cell::{half, kd_key};
use crate::split_context::{Star, coding};
use crate::symbols::Family;

/// Fraction bits of the barycentres the split predictions ahead are computed from.
const FRACTION: u32 = 8;
// the star's coordinates (doubled, then FRACTION bits more) stay below 2^31, so that one
// triangle's cross product fits in 64 bits (split_context::Star::triangle)
const _: () = assert!(crate::quantize::MAX_BITS + 1 + FRACTION <= 31);

/// The kd-cells of one level: corners in kd order, their kd keys, prefix sums of their doubled
/// centres, and (once read) how each splits.
#[derive(Clone, Debug, Default)]
struct Level {
    corners: Vec<[u32; 3]>,
    keys: Vec<u64>,
    /// `sums[i]` = Σ over cells `< i` of `2·corner + extent − 1` per axis (exact integers).
    sums: Vec<[u64; 3]>,
    /// 0 = only the low half is non-empty, 1 = only the high one, 2 = both.
    splits: Vec<u8>,
}

impl Level {
    fn new(corners: Vec<[u32; 3]>, depth: usize, bits: u32) -> Self {
        let v = |c: [u32; 3]| Vertex {
            corner: c,
            level: depth as u8,
        };
        let keys = corners.iter().map(|&c| kd_key(c, depth, bits)).collect();
        let mut sums = Vec::with_capacity(corners.len() + 1);
        let mut acc = [0u64; 3];
        sums.push(acc);
        for &c in &corners {
            let x = v(c);
            for (a, s) in acc.iter_mut().enumerate() {
                *s += 2 * c[a] as u64 + x.extent(a, bits) - 1;
            }
            sums.push(acc);
        }
        Level {
            corners,
            keys,
            sums,
            splits: Vec::new(),
        }
    }

    /// The range of cells below the kd-cell `w` (a coarser level's vertex).
    fn below(&self, w: &Vertex, bits: u32) -> std::ops::Range<usize> {
        let d = w.level as usize;
        let first = kd_key(w.corner, d, bits);
        let lo = self.keys.partition_point(|&k| k < first);
        let hi = if d == 0 {
            self.keys.len()
        } else {
            let last = first | (u64::MAX >> d);
            self.keys.partition_point(|&k| k <= last)
        };
        lo..hi
    }

    /// The barycentre of the cells in `r`, in doubled grid units × 2^[`FRACTION`] (rounded
    /// down: the same integers on every machine).
    fn barycentre_fixed(&self, r: std::ops::Range<usize>) -> [i64; 3] {
        let n = (r.end - r.start) as u64;
        std::array::from_fn(|a| {
            (((self.sums[r.end][a] - self.sums[r.start][a]) << FRACTION) / n) as i64
        })
    }

    /// The barycentre of the cells in `r`, in grid units.
    fn barycentre(&self, r: std::ops::Range<usize>) -> [f64; 3] {
        let n = (r.end - r.start) as f64;
        std::array::from_fn(|a| (self.sums[r.end][a] - self.sums[r.start][a]) as f64 / (2.0 * n))
    }

    /// The cells of the next level, from this level's splits.
    fn children(&self, depth: usize, bits: u32) -> Vec<[u32; 3]> {
        let a = depth % 3;
        let h = half(depth, bits);
        let mut out = Vec::with_capacity(self.corners.len() * 5 / 4);
        for (&c, &s) in self.corners.iter().zip(&self.splits) {
            let mut high = c;
            high[a] += h;
            match s {
                0 => out.push(c),
                1 => out.push(high),
                _ => {
                    out.push(c);
                    out.push(high);
                }
            }
        }
        out
    }
}

/// The geometry a cell's decoder knows ahead of its connectivity: the kd-cells of the levels
/// from the complex's level down to the deepest one read.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Level of `levels[0]`.
    first: usize,
    levels: Vec<Level>,
}

impl Geometry {
    /// The geometry of the whole cell, from the full-precision kd-cells `top` at level `hi`
    /// (encoder side): every level from `lo` to `hi`, with its splits.
    pub(crate) fn of_cells(top: Vec<[u32; 3]>, lo: usize, hi: usize, bits: u32) -> Self {
        let mut rev = vec![Level::new(top, hi, bits)];
        for depth in (lo..hi).rev() {
            let below = rev.last().unwrap();
            let a = depth % 3;
            let h = half(depth, bits);
            let mut corners: Vec<[u32; 3]> = Vec::with_capacity(below.corners.len());
            let mut splits: Vec<u8> = Vec::with_capacity(below.corners.len());
            for &c in &below.corners {
                let mut parent = c;
                parent[a] &= !h;
                let side = u8::from(c[a] & h != 0);
                if corners.last() == Some(&parent) {
                    *splits.last_mut().unwrap() = 2;
                } else {
                    corners.push(parent);
                    splits.push(side);
                }
            }
            let mut level = Level::new(corners, depth, bits);
            level.splits = splits;
            rev.push(level);
        }
        rev.reverse();
        Geometry {
            first: lo,
            levels: rev,
        }
    }

    /// The decoder's start: the complex's kd-cells at level `lo`, nothing read yet.
    pub(crate) fn start(cx: &Complex, alive: &[u32], lo: usize, bits: u32) -> Self {
        let corners = alive
            .iter()
            .map(|&v| cx.vertices[v as usize].corner)
            .collect();
        Geometry {
            first: lo,
            levels: vec![Level::new(corners, lo, bits)],
        }
    }

    fn level(&self, depth: usize) -> &Level {
        &self.levels[depth - self.first]
    }

    /// The deepest level whose cells are known.
    pub fn deepest(&self) -> usize {
        self.first + self.levels.len() - 1
    }

    /// How each cell of level `depth` splits (the cells in kd order, as the complex's vertices).
    pub(crate) fn splits(&self, depth: usize) -> &[u8] {
        &self.level(depth).splits
    }

    /// Forgets the levels above `depth` (the complex has passed them).
    pub(crate) fn drop_above(&mut self, depth: usize) {
        let n = depth.saturating_sub(self.first).min(self.levels.len() - 1);
        self.levels.drain(..n);
        self.first += n;
    }

    /// Where vertex `v` (of a complex at or above the deepest level) is drawn: the barycentre of
    /// the deepest known cells below it, in grid units.
    pub fn position(&self, v: &Vertex, bits: u32) -> [f64; 3] {
        let deepest = self.level(self.deepest());
        let r = deepest.below(v, bits);
        if r.is_empty() {
            v.centre(bits)
        } else {
            deepest.barycentre(r)
        }
    }

    /// The codings of the splits of level `depth`'s cells, each predicted from the vertex of
    /// `cx` holding it (`alive`, in kd order, all at one coarser or equal level).
    pub(crate) fn codings(
        &self,
        cx: &Complex,
        alive: &[u32],
        depth: usize,
        bits: u32,
    ) -> Vec<Coding> {
        let level = self.level(depth);
        let mut j = 0;
        let mut out = Vec::with_capacity(level.corners.len());
        for (i, &c) in level.corners.iter().enumerate() {
            let key = level.keys[i];
            // the vertex holding c: the alive vertices cover the cells in kd order
            while j + 1 < alive.len() && !holds(&cx.vertices[alive[j] as usize], key, bits) {
                j += 1;
            }
            out.push(self.coding(cx, alive[j], c, depth, bits));
        }
        out
    }

    /// The coding of the split of the level-`depth` cell at `corner`, held by vertex `u`: the
    /// predictors of [`crate::split_context`] but the parallelograms on `u`'s star, each
    /// neighbour standing at the barycentre of its descendants at level `depth` (in fixed point:
    /// integers on both sides, whatever order they list the star in), the cell itself at its
    /// centre, and "collapsed" meaning that `u` holds several cells of the level.
    fn coding(&self, cx: &Complex, u: u32, corner: [u32; 3], depth: usize, bits: u32) -> Coding {
        let level = self.level(depth);
        let a = depth % 3;
        let h = half(depth, bits) as i64;
        let cell = Vertex {
            corner,
            level: depth as u8,
        };
        let pv: [i64; 3] = std::array::from_fn(|k| {
            (2 * corner[k] as i64 + cell.extent(k, bits) as i64 - 1) << FRACTION
        });
        // the neighbours' barycentres, each looked up once (two binary searches)
        let mut seen: Vec<(u32, Option<[i64; 3]>)> = Vec::with_capacity(16);
        let mut at = |x: u32| -> Option<[i64; 3]> {
            if let Some(&(_, p)) = seen.iter().find(|&&(y, _)| y == x) {
                return p;
            }
            let r = level.below(&cx.vertices[x as usize], bits);
            let p = (!r.is_empty()).then(|| level.barycentre_fixed(r));
            seen.push((x, p));
            p
        };
        let mut st = Star {
            collapsed: level.below(&cx.vertices[u as usize], bits).len() > 1,
            ..Star::default()
        };
        for (x, y) in cx.star(u) {
            match (x == u, y == u) {
                (false, false) => {
                    let (px, py) = (at(x), at(y));
                    for p in [px, py].into_iter().flatten() {
                        st.neighbour(p, pv);
                    }
                    if let (Some(px), Some(py)) = (px, py) {
                        st.triangle(pv, px, py);
                    }
                }
                (true, true) => {}
                _ => {
                    if let Some(p) = at(if x == u { y } else { x }) {
                        st.neighbour(p, pv);
                        st.neighbour(p, pv);
                    }
                }
            }
        }
        // no parallelograms here: each would cost two more binary searches of the level's keys
        // (1.1 M torus, 12 bits, --ahead 1, compress + decode: 13.8 -> 20.4 s user) for 0.27 b/v
        // on the bunny
        let width = (2 * h) << FRACTION;
        let plane = (2 * corner[a] as i64 + 2 * h - 1) << FRACTION;
        coding(&st, Family::Ahead, a, plane, width)
    }

    /// Reads the splits of level `depth` and adds the next level's cells (decoder side).
    pub(crate) fn read(
        &mut self,
        cx: &Complex,
        alive: &[u32],
        depth: usize,
        bits: u32,
        mut next: impl FnMut(usize) -> Result<u8, CodecError>,
    ) -> Result<(), CodecError> {
        let codings = self.codings(cx, alive, depth, bits);
        let mut splits = Vec::with_capacity(codings.len());
        for coding in codings {
            splits.push(coding.split(next(coding.ctx)?));
        }
        let i = depth - self.first;
        self.levels[i].splits = splits;
        let corners = self.levels[i].children(depth, bits);
        self.levels.push(Level::new(corners, depth + 1, bits));
        Ok(())
    }
}

/// Whether kd-cell `w` holds the cell with kd key `key`.
fn holds(w: &Vertex, key: u64, bits: u32) -> bool {
    let d = w.level as usize;
    d == 0 || (key ^ kd_key(w.corner, d, bits)) >> (64 - d) == 0
}
