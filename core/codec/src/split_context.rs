//! The context of a kd split (paper 003 §3, §5.3; GD02 §4): what the decoder's complex says about
//! where the surface crosses a cell before the cell is split. Encoder and decoder both run
//! [`split_coding`] on the same complex, so they cannot drift: every input is a position or an
//! incidence of the coarse complex (never a vertex id, which differs between the two sides), and
//! all arithmetic is on integers (the same bits on every machine and in any summation order).
//!
//! A split codes "only the low half is non-empty", "only the high one", or "both". Which half is
//! about where the surface passes, "both" about how many points the cell holds. The predictors:
//! - the **centroid** of the vertex's neighbours (GD02): its side of the split plane is the
//!   predicted half, its distance from the plane in half-cells the margin;
//! - the **parallelogram** average over the star (for each triangle `(v, x, y)` of the oriented
//!   star, `x + y − z` for the triangle `(y, x, z)` across its far edge): where it falls against
//!   the centroid's side. The centroid sits inside a curved surface and the parallelogram outside
//!   it; where they agree the half is nearly sure, where they disagree the plane runs between;
//! - the **tangent plane** of the oriented star (the sum of its triangles' normals, oriented by
//!   their corner order): whether its normal points along the split axis (|n_a| ≥ 0.7 |n|: then
//!   the surface crosses the axis once and one half is empty), and if so whether it points
//!   towards the predicted half (the surface bulges outwards, past the centroid);
//! - whether the cell holds a **collapsed** triangle (`v v x` or `v v v`: two of the input's
//!   points fell in this cell, so both halves are likely non-empty);
//! - the **density**: the neighbours' mean distance in half-cells, in octaves (below 2, 2–4, 4–8,
//!   8–16, beyond). It stands for the kd level of §5.3's per-level tables, and unlike the level it
//!   means the same at every precision and on every mesh, so a handful of classes suffice.

use crate::coding::Coding;
use crate::complex::{Complex, Vertex, axis_bits};
use crate::kd_cell::half;
use crate::star_cache::{ENTRIES, RecordBuilder, TRIANGLES};
use crate::symbols::{Family, MAX_LEVELS, context};

/// Margin classes of the centroid: none, then its distance from the split plane in half-cells
/// below 1/8, 1/4, 1/2, 1, 2 and beyond.
const MARGINS: usize = 7;
/// Parallelogram classes: none found, agrees with the centroid's side, disagrees.
const PARALLELOGRAM: usize = 3;
/// Tangent-plane classes: normal not along the split axis (or none), along it towards the
/// predicted half, along it away from it.
const PLANE: usize = 3;
/// Density classes (octaves of the neighbours' distance in half-cells).
const DENSITY: usize = 5;

/// Number of [`Family::Split`] sub-contexts: margin × collapsed × parallelogram.
pub(crate) const SPLIT_SUBS: usize = MARGINS * 2 * PARALLELOGRAM;
/// Values the level slot of a split context takes: tangent plane × (a gap, then density). The
/// adaptive coder starts a new context from the one a slot below (the level above, for other
/// families): here the next sparser density with the same plane, never another plane class.
const SPLIT_LEVELS: usize = (DENSITY + 1) * PLANE;
const _: () = assert!(SPLIT_SUBS == Family::Split.subs() && SPLIT_LEVELS <= MAX_LEVELS);

/// [`crate::complex::axis_bits`] of every kd level a `u8` holds, per axis: a cell's extents
/// read from a table instead of dividing its level by 3 (that division, for each of the ~20
/// cells a split context reads, was ~8 % of its instructions).
const AXIS_BITS: [[u8; 3]; 256] = {
    let mut t = [[0u8; 3]; 256];
    let mut level = 0;
    while level < 256 {
        let mut a = 0;
        while a < 3 {
            t[level][a] = axis_bits(level, a) as u8;
            a += 1;
        }
        level += 1;
    }
    t
};

/// A cell's doubled centre along every axis, `2·corner + extent − 1` (exact integers).
#[inline]
fn doubled(w: &Vertex, bits: u32) -> [i64; 3] {
    let t = &AXIS_BITS[w.level as usize];
    std::array::from_fn(|a| 2 * w.corner[a] as i64 + (1i64 << (bits - t[a] as u32)) - 1)
}

/// What the decoder knows around a vertex, summed in integers (doubled grid units for a
/// complex's vertices; the geometry ahead uses its own fixed-point units).
#[derive(Default, Debug, PartialEq, Eq)]
pub(crate) struct Star {
    /// Neighbour positions counted (a neighbour once per star edge reaching it).
    pub(crate) count: i64,
    /// Σ of their positions.
    pub(crate) sum: [i64; 3],
    /// Σ over those of the largest coordinate distance from the vertex.
    pub(crate) reach: i64,
    /// Σ of the oriented triangles' cross products (relative to the vertex).
    pub(crate) normal: [i128; 3],
    /// Σ of the parallelogram predictions `x + y − z` and how many were found.
    pub(crate) parallelogram: [i64; 3],
    pub(crate) parallelograms: i64,
    /// The cell holds a collapsed triangle (or, ahead, several cells of its level).
    pub(crate) collapsed: bool,
}

impl Star {
    /// Adds a neighbour at `p`, the vertex being at `pv`.
    pub(crate) fn neighbour(&mut self, p: [i64; 3], pv: [i64; 3]) {
        self.count += 1;
        let mut far = 0;
        for a in 0..3 {
            self.sum[a] += p[a];
            far = far.max((p[a] - pv[a]).abs());
        }
        self.reach += far;
    }

    /// Adds a neighbour at `p` counted `w` times, the vertex being at `pv` (`w` calls of
    /// [`Star::neighbour`], in integers).
    #[inline]
    fn neighbours(&mut self, w: i64, p: [i64; 3], pv: [i64; 3]) {
        self.count += w;
        let mut far = 0;
        for a in 0..3 {
            self.sum[a] += w * p[a];
            far = far.max((p[a] - pv[a]).abs());
        }
        self.reach += w * far;
    }

    /// Adds the oriented triangle `(v, x, y)` at `pv`, `px`, `py` to the normal.
    #[inline]
    pub(crate) fn triangle(&mut self, pv: [i64; 3], px: [i64; 3], py: [i64; 3]) {
        // one triangle's cross product fits in 64 bits (coordinates below 2^31: a grid of at
        // most MAX_BITS doubled, or shifted by ahead's fraction bits, which ahead.rs asserts);
        // only the star's sum needs 128
        let e: [i64; 3] = std::array::from_fn(|a| px[a] - pv[a]);
        let f: [i64; 3] = std::array::from_fn(|a| py[a] - pv[a]);
        self.normal[0] += (e[1] * f[2] - e[2] * f[1]) as i128;
        self.normal[1] += (e[2] * f[0] - e[0] * f[2]) as i128;
        self.normal[2] += (e[0] * f[1] - e[1] * f[0]) as i128;
    }

    /// Adds the parallelogram prediction `x + y − z`.
    pub(crate) fn parallelogram(&mut self, px: [i64; 3], py: [i64; 3], pz: [i64; 3]) {
        for a in 0..3 {
            self.parallelogram[a] += px[a] + py[a] - pz[a];
        }
        self.parallelograms += 1;
    }

    /// Whether the parallelograms are worth looking for: the star reaches less than [`FAR`]
    /// half-cells of width `cell`.
    pub(crate) fn near(&self, cell: i64) -> bool {
        self.reach < self.count * cell * FAR
    }
}

/// Calls `f` with the third corner `z` of every triangle `(y, x, z)` across the far edge
/// `x → y` of a star triangle `(v, x, y)` (the edge's other side, in the orientation a
/// consistent surface gives it), `z` being none of `v, x, y`: where the parallelogram
/// `x + y − z` predicts `v`.
pub(crate) fn across(cx: &Complex, v: u32, x: u32, y: u32, mut f: impl FnMut(u32)) {
    across_both(cx, v, x, y, NONE, |_, z| f(z));
}

/// No vertex: a corner is never this id (ids index the complex's vertices).
const NONE: u32 = u32::MAX;

/// The lookups of [`across`] for two far edges at once, from one pass over `w`'s list (each
/// triangle across a far edge holds both its ends, so either end's list finds it): the far
/// edge `w → y` (`w` as its x; `f(0, z)`) and the far edge `x → w` (`w` as its y; `f(1, z)`),
/// [`NONE`] for a side not wanted. A star's ring of far edges is then read from every other
/// neighbour's list instead of from every neighbour's.
fn across_both(cx: &Complex, v: u32, w: u32, y: u32, x: u32, mut f: impl FnMut(usize, u32)) {
    // no branch per simplex (a branch per rotation mispredicted ~15 times a split on the
    // torus): each triangle is read from w's first place, and a find is kept by advancing the
    // end of a small buffer. A triangle holding w twice, or y or x twice, has no third corner
    // besides the edge's ends, whichever place is read, so the tests on z reject it; a point
    // (p, p, p) holds no edge between two distinct vertices.
    let mut found = [[0u32; 16]; 2];
    for chunk in cx.listed(w).chunks(16) {
        let mut n = [0usize; 2];
        for &slot in chunk {
            let Some(s) = cx.simplices[slot as usize] else {
                continue;
            };
            let [a, b, c] = s.v;
            let (before, after) = if a == w {
                (c, b)
            } else if b == w {
                (a, c)
            } else {
                (b, a)
            };
            // w → y's other side is (y, w, z): y before w, z after it
            let keep = (before == y) & (after != v) & (after != w) & (after != y);
            found[0][n[0] & 15] = after;
            n[0] += usize::from(keep);
            // x → w's other side is (w, x, z): x after w, z before it
            let keep = (after == x) & (before != v) & (before != x) & (before != w);
            found[1][n[1] & 15] = before;
            n[1] += usize::from(keep);
        }
        for (side, found) in found.iter().enumerate() {
            for &z in &found[..n[side]] {
                f(side, z);
            }
        }
    }
}

// a doubled coordinate stays below 2^(MAX_BITS + 1) ≤ 2^31 (Star::triangle's 64-bit products)
const _: () = assert!(crate::quantize::MAX_BITS < 31);

/// Reach, in half-cells, beyond which the parallelograms are not looked for: there the cell is
/// far smaller than the star, both predictions lie many cells away on fixed sides, and the 2-ring
/// lookups (half the splits at 16 bits) would buy little (bunny 0.05 b/v at 16 bits).
pub(crate) const FAR: i64 = 64;

/// The star of `v` (whose split halves are `h` wide): its neighbours' centroid and reach, its
/// oriented normal, the parallelograms across its far edges, and whether it holds a collapsed
/// triangle. Its ids come from `v`'s cached record ([`crate::star_cache`], made from a walk when
/// there is none), its sums from the current positions.
fn star(cx: &mut Complex, v: u32, bits: u32, h: i64) -> Star {
    let st = star_cached(cx, v, bits, h);
    // the record must be what a walk of the complex finds now (a missed invalidation shows here)
    #[cfg(debug_assertions)]
    assert_eq!(
        st,
        star_walk(cx, v, bits, h, None),
        "the cached star of vertex {v}"
    );
    st
}

/// [`star`] from `v`'s cached record, made (by the walk) when there is none.
fn star_cached(cx: &mut Complex, v: u32, bits: u32, h: i64) -> Star {
    if !cx.star_cache.kept() {
        return star_walk(cx, v, bits, h, None);
    }
    let Some(r) = cx.star_cache.get(v) else {
        let mut b = RecordBuilder::new();
        let st = star_walk(cx, v, bits, h, Some(&mut b));
        cx.star_cache.store(v, b.done());
        return st;
    };
    if r.walk() {
        return star_walk(cx, v, bits, h, None);
    }
    let pv = doubled(&cx.vertices[v as usize], bits);
    let mut p = [[0i64; 3]; ENTRIES];
    let mut st = Star {
        collapsed: r.collapsed(),
        ..Star::default()
    };
    let base = r.base as usize;
    for ((q, &id), &w) in p.iter_mut().zip(&r.ids[..base]).zip(&r.weight) {
        *q = doubled(&cx.vertices[id as usize], bits);
        st.neighbours(w as i64, *q, pv);
    }
    for &[i, j] in &r.tri[..r.tris as usize] {
        st.triangle(pv, p[i as usize], p[j as usize]);
    }
    if !st.near(2 * h) {
        return st;
    }
    let r = if r.far() {
        r
    } else {
        // the parallelograms, wanted for the first time since the record was made
        let mut b = RecordBuilder::far(&r);
        let edges: [(u32, u32); TRIANGLES] =
            std::array::from_fn(|t| (r.ids[r.tri[t][0] as usize], r.ids[r.tri[t][1] as usize]));
        across_edges(cx, v, &edges[..r.tris as usize], |t, z| {
            b.parallelogram(t, z)
        });
        let far = b.done();
        cx.star_cache.store(v, far);
        if far.walk() {
            return star_walk(cx, v, bits, h, None);
        }
        far
    };
    let len = r.len as usize;
    for (q, &id) in p[base..len].iter_mut().zip(&r.ids[base..len]) {
        *q = doubled(&cx.vertices[id as usize], bits);
    }
    for (q, &c) in p[..len].iter().zip(&r.par) {
        let c = c as i64;
        for (sum, x) in st.parallelogram.iter_mut().zip(q) {
            *sum += c * x;
        }
        // each parallelogram adds 1 + 1 − 1 to the coefficients
        st.parallelograms += c;
    }
    st
}

/// A far edge `x → y` and its ends' positions.
type FarEdge = ((u32, u32), [[i64; 3]; 2]);

/// [`star`] by a walk of the complex: `v`'s incidence list, and its neighbours' for the
/// parallelograms; what it finds also goes to `record` when given (the parallelograms only if
/// they were looked for).
fn star_walk(
    cx: &Complex,
    v: u32,
    bits: u32,
    h: i64,
    mut record: Option<&mut RecordBuilder>,
) -> Star {
    let pv = doubled(&cx.vertices[v as usize], bits);
    let mut st = Star::default();
    // the far edges of the star's triangles and their ends' positions, on the stack while they
    // are few (the usual case)
    let mut few = [(0u32, 0u32); 16];
    let mut at = [[[0i64; 3]; 2]; 16];
    let mut count = 0;
    let mut many: Vec<FarEdge> = Vec::new();
    for (x, y) in cx.star(v) {
        match (x == v, y == v) {
            (false, false) => {
                let p = [
                    doubled(&cx.vertices[x as usize], bits),
                    doubled(&cx.vertices[y as usize], bits),
                ];
                st.neighbour(p[0], pv);
                st.neighbour(p[1], pv);
                st.triangle(pv, p[0], p[1]);
                // a triangle (v, x, x) has no far edge (and a zero normal)
                if let Some(b) = record.as_mut() {
                    let (i, j) = (b.neighbour(x, 1), b.neighbour(y, 1));
                    if x != y {
                        b.triangle(i, j);
                    }
                }
                if x != y {
                    if count < few.len() {
                        few[count] = (x, y);
                        at[count] = p;
                        count += 1;
                    } else {
                        many.push(((x, y), p));
                    }
                }
            }
            (true, true) => {
                st.collapsed = true;
                if let Some(b) = record.as_mut() {
                    b.collapsed();
                }
            }
            _ => {
                st.collapsed = true;
                let x = if x == v { y } else { x };
                let p = doubled(&cx.vertices[x as usize], bits);
                st.neighbour(p, pv);
                st.neighbour(p, pv);
                if let Some(b) = record.as_mut() {
                    b.collapsed();
                    b.neighbour(x, 2);
                }
            }
        }
    }
    if !st.near(2 * h) {
        return st;
    }
    let mut add = |k: usize, p: [[i64; 3]; 2], z: u32| {
        st.parallelogram(p[0], p[1], doubled(&cx.vertices[z as usize], bits));
        if let Some(b) = record.as_mut() {
            b.parallelogram(k, z);
        }
    };
    if many.is_empty() {
        across_edges(cx, v, &few[..count], |k, z| add(k, at[k], z));
    } else {
        let edges: Vec<(u32, u32)> = few[..count]
            .iter()
            .copied()
            .chain(many.iter().map(|e| e.0))
            .collect();
        let p = |k: usize| if k < count { at[k] } else { many[k - count].1 };
        across_edges(cx, v, &edges, |k, z| add(k, p(k), z));
    }
    if let Some(b) = record {
        b.far_done();
    }
    st
}

/// Calls `f(k, z)` for every `z` that [`across`] finds across the far edge `edges[k]` of `v`'s
/// star. Up to 16 edges, every far edge is read once, two at a time where they meet: an edge
/// x → y with the edge ending at x (x's list serves both) or the one starting at y (y's list).
/// On a fan of k triangles that is about k/2 list passes instead of k. The edges are found by
/// their ends' low bits; where two ends share them one is not found and its edge is read alone.
fn across_edges(cx: &Complex, v: u32, edges: &[(u32, u32)], mut f: impl FnMut(usize, u32)) {
    if edges.len() > 16 {
        for (k, &(x, y)) in edges.iter().enumerate() {
            across(cx, v, x, y, |z| f(k, z));
        }
        return;
    }
    let (mut x_at, mut y_at) = ([NONE; 32], [NONE; 32]);
    let (mut x_edge, mut y_edge) = ([0u8; 32], [0u8; 32]);
    for (k, &(x, y)) in edges.iter().enumerate() {
        x_at[x as usize & 31] = x;
        x_edge[x as usize & 31] = k as u8;
        y_at[y as usize & 31] = y;
        y_edge[y as usize & 31] = k as u8;
    }
    // the edges not read yet, taken lowest first (a loop per list pass, not per edge)
    let mut open = (1u32 << edges.len()) - 1;
    while open != 0 {
        let i = open.trailing_zeros() as usize;
        open &= open - 1;
        let (x, y) = edges[i];
        let into_x = y_edge[x as usize & 31] as usize;
        let from_y = x_edge[y as usize & 31] as usize;
        let pair_x = (y_at[x as usize & 31] == x) & (open >> into_x & 1 != 0);
        let pair_y = !pair_x & (x_at[y as usize & 31] == y) & (open >> from_y & 1 != 0);
        // (the vertex whose list is read, its edge as x, its edge as y or none)
        let (w, out, inn) = if pair_x {
            (x, i, into_x)
        } else if pair_y {
            (y, from_y, i)
        } else {
            (x, i, usize::MAX)
        };
        let xw = if inn == usize::MAX {
            NONE
        } else {
            edges[inn].0
        };
        open &= !(1u32 << out) & !(1u32 << (inn & 31));
        across_both(cx, v, w, edges[out].1, xw, |side, z| {
            f(if side == 0 { out } else { inn }, z)
        });
    }
}

/// Whether `n` points along axis `a` (|n_a| ≥ 0.7 |n|), in integers: the components are first
/// shifted down to 30 bits so that the squares cannot overflow.
fn along(n: [i128; 3], a: usize) -> bool {
    let top = n.iter().map(|c| c.unsigned_abs()).max().unwrap_or(0);
    if top == 0 {
        return false;
    }
    let shift = (128 - top.leading_zeros()).saturating_sub(30);
    let m: [i128; 3] = std::array::from_fn(|k| n[k] >> shift);
    let norm: i128 = m.iter().map(|c| c * c).sum();
    100 * m[a] * m[a] >= 49 * norm
}

/// The coding of the split decision of vertex `v` (before its split at `level`), from the
/// predictors of the module doc.
pub(crate) fn split_coding(cx: &mut Complex, v: u32, level: usize, bits: u32) -> Coding {
    let a = level % 3;
    let corner = cx.vertices[v as usize].corner;
    let h = half(level, bits) as i64;
    let st = star(cx, v, bits, h);
    // the split plane in doubled units: corner + h − 1/2; a half-cell is 2h
    let plane = 2 * corner[a] as i64 + 2 * h - 1;
    coding(&st, Family::Split, a, plane, 2 * h)
}

/// The coding of a split along axis `a` from the star's sums, the split plane and a half-cell's
/// width in the star's units: the centroid's side is the predicted half (value 0); the
/// sub-context is margin × collapsed × parallelogram, and the level slot of the context carries
/// tangent plane × density (§5.3's per-level tables, by what the level stood for). Shared with
/// the geometry ahead ([`crate::ahead`]), whose star is made of its cells' barycentres.
pub(crate) fn coding(st: &Star, family: Family, a: usize, plane: i64, cell: i64) -> Coding {
    let (margin, high) = if st.count == 0 {
        (0, false)
    } else {
        let off = st.sum[a] - st.count * plane;
        let d = 8 * off.unsigned_abs();
        let unit = (cell * st.count) as u64;
        let m = 1 + [1u64, 2, 4, 8, 16]
            .iter()
            .filter(|&&k| d >= k * unit)
            .count();
        (m, off > 0)
    };
    let parallelogram = if st.parallelograms == 0 {
        0
    } else {
        let up = st.parallelogram[a] - st.parallelograms * plane > 0;
        1 + usize::from(up != high)
    };
    let plane_class = if along(st.normal, a) {
        1 + usize::from((st.normal[a] > 0) != high)
    } else {
        0
    };
    // octaves of the mean reach in half-cells
    let density = if st.count == 0 {
        0
    } else {
        [2i64, 4, 8, 16]
            .iter()
            .filter(|&&k| st.reach >= st.count * cell * k)
            .count()
    };
    let sub = (margin * 2 + usize::from(st.collapsed)) * PARALLELOGRAM + parallelogram;
    Coding {
        ctx: context(family, sub, plane_class * (DENSITY + 1) + 1 + density),
        family,
        flip: high,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::Simplex;

    /// A fan of four triangles around `v` in the plane z = 8 (oriented counter-clockwise seen
    /// from +z), each with the triangle across its far edge, all cells at full precision.
    fn fan(lift: u32) -> (Complex, u32) {
        let mut cx = Complex::default();
        let mut at = |x: u32, y: u32, z: u32| {
            cx.add_vertex(Vertex {
                corner: [x, y, z],
                level: 12,
            })
        };
        let v = at(8, 8, 8 + lift);
        let ring = [at(12, 8, 8), at(8, 12, 8), at(4, 8, 8), at(8, 4, 8)];
        // the outer vertices across the far edges: a flat square grid
        let outer = [at(12, 12, 8), at(4, 12, 8), at(4, 4, 8), at(12, 4, 8)];
        for i in 0..4 {
            let (x, y) = (ring[i], ring[(i + 1) % 4]);
            cx.add(Simplex::triangle(v, x, y));
            cx.add(Simplex::triangle(y, x, outer[i]));
        }
        (cx, v)
    }

    #[test]
    fn a_flat_fan_has_a_normal_along_z_and_parallelograms_through_its_plane() {
        let (mut cx, v) = fan(0);
        let st = star(&mut cx, v, 4, 1);
        assert_eq!(st.count, 8, "two corners per star triangle");
        assert!(!st.collapsed);
        assert!(along(st.normal, 2) && !along(st.normal, 0) && !along(st.normal, 1));
        assert!(st.normal[2] > 0, "counter-clockwise from +z");
        assert_eq!(st.parallelograms, 4);
        // x + y − z over the fan: each lands on v's own cell centre (doubled: 2·8 + 1 − 1)
        assert_eq!(st.parallelogram, [4 * 16, 4 * 16, 4 * 16]);
        assert_eq!(st.sum, [8 * 16, 8 * 16, 8 * 16]);
    }

    #[test]
    fn a_collapsed_triangle_marks_the_cell() {
        let (mut cx, v) = fan(0);
        let w = cx.add_vertex(Vertex {
            corner: [0, 0, 0],
            level: 12,
        });
        cx.add(Simplex::triangle(v, v, w));
        let st = star(&mut cx, v, 4, 1);
        assert!(st.collapsed);
        assert_eq!(
            st.count, 10,
            "the collapsed triangle's other corner counts twice"
        );
    }

    #[test]
    fn across_finds_every_third_corner_of_the_edge_and_nothing_degenerate() {
        // x → y is a far edge of v's star; y → x is held by two triangles (a non-manifold
        // edge) besides degenerate and foreign ones, and x's list is long enough to be read
        // in several chunks
        let mut cx = Complex::default();
        let ids: Vec<u32> = (0..40u32)
            .map(|i| {
                cx.add_vertex(Vertex {
                    corner: [i, 0, 0],
                    level: 12,
                })
            })
            .collect();
        let (v, x, y, z1, z2) = (ids[0], ids[1], ids[2], ids[3], ids[4]);
        cx.add(Simplex::triangle(v, x, y));
        for k in 5..30 {
            cx.add(Simplex::triangle(x, ids[k], ids[k + 1]));
        }
        cx.add(Simplex::triangle(y, x, z1));
        cx.add(Simplex::triangle(y, x, x));
        cx.add(Simplex::triangle(x, x, y));
        cx.add(Simplex::triangle(y, x, v));
        cx.add(Simplex::triangle(x, y, z1));
        cx.add(Simplex::point(x));
        cx.add(Simplex::triangle(z2, y, x));
        cx.add(Simplex::triangle(x, x, x));
        assert!(cx.listed(x).len() > 32);
        let mut got = Vec::new();
        across(&cx, v, x, y, |z| got.push(z));
        assert_eq!(got, vec![z1, z2], "in slot order, each once");
        // the same edge looked up from y's list, as the far edge ending there
        let mut from_y = Vec::new();
        across_both(&cx, v, y, NONE, x, |side, z| {
            assert_eq!(side, 1);
            from_y.push(z)
        });
        from_y.sort();
        assert_eq!(from_y, vec![z1, z2]);
    }

    #[test]
    fn the_paired_lookups_sum_what_one_lookup_per_far_edge_sums() {
        // a 7 × 7 grid of two triangles a square, some squares doubled by the other diagonal
        // (non-manifold edges), a flipped copy of a triangle, and degenerate triangles
        let mut cx = Complex::default();
        let id: Vec<u32> = (0..49u32)
            .map(|i| {
                cx.add_vertex(Vertex {
                    corner: [4 * (i % 7), 4 * (i / 7), (i * 5) % 3],
                    level: 12,
                })
            })
            .collect();
        let at = |i: u32, j: u32| id[(j * 7 + i) as usize];
        let mut all = Vec::new();
        for j in 0..6 {
            for i in 0..6 {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                all.push(Simplex::triangle(a, b, c));
                all.push(Simplex::triangle(a, c, d));
                if (i + j) % 4 == 0 {
                    all.push(Simplex::triangle(a, b, d));
                    all.push(Simplex::triangle(a, d, c));
                }
                if (i * j) % 5 == 1 {
                    all.push(Simplex::triangle(a, a, c));
                    all.push(Simplex::triangle(b, c, c));
                }
            }
        }
        all.push(Simplex::triangle(at(3, 3), at(3, 2), at(2, 2)));
        all.sort();
        all.dedup();
        for s in all {
            cx.add(s);
        }
        let mut pairs = 0;
        for &v in &id {
            let st = star(&mut cx, v, 4, 1);
            let (mut sum, mut n) = ([0i64; 3], 0);
            for (x, y) in cx.star(v).collect::<Vec<_>>() {
                if x == v || y == v || x == y {
                    continue;
                }
                let (px, py) = (
                    doubled(&cx.vertices[x as usize], 4),
                    doubled(&cx.vertices[y as usize], 4),
                );
                across(&cx, v, x, y, |z| {
                    let pz = doubled(&cx.vertices[z as usize], 4);
                    for a in 0..3 {
                        sum[a] += px[a] + py[a] - pz[a];
                    }
                    n += 1;
                });
            }
            assert_eq!(
                (st.parallelogram, st.parallelograms),
                (sum, n),
                "vertex {v}"
            );
            pairs += n;
        }
        assert!(pairs > 100);
    }

    /// Every vertex's star from the cache against a walk of the complex, at a spread of cell
    /// sizes (so that the parallelograms are sometimes wanted, sometimes not); fills the cache.
    fn check_all_stars(cx: &mut Complex, bits: u32, step: usize) {
        for v in 0..cx.vertices.len() as u32 {
            for h in [1i64 << 12, 1, 1 << 6] {
                let cached = star_cached(cx, v, bits, h);
                assert_eq!(
                    cached,
                    star_walk(cx, v, bits, h, None),
                    "vertex {v} (h {h}) after step {step}"
                );
            }
        }
    }

    #[test]
    fn cached_stars_equal_walked_ones_through_random_splits_merges_and_renumberings() {
        use crate::complex::{MaskList, Weld, candidates};
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rand = move |n: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % n as u64) as usize
        };
        let bits = 16;
        for round in 0..6 {
            let mut cx = Complex::default();
            let n = 12 + 6 * round;
            for _ in 0..n {
                let corner = [0, 0, 0].map(|_| rand(1 << 16) as u32);
                cx.add_vertex(Vertex {
                    corner,
                    level: rand(40) as u8,
                });
            }
            // a grid-like fan plus random, degenerate and non-manifold triangles; a hub whose
            // star does not fit a record
            let mut all: Vec<Simplex> = Vec::new();
            for i in 0..n as u32 - 2 {
                all.push(Simplex::triangle(i, i + 1, i + 2));
                all.push(Simplex::triangle(i + 2, i + 1, (i + 5) % n as u32));
            }
            for _ in 0..2 * n {
                let t = [0; 3].map(|_| rand(n) as u32);
                all.push(Simplex::triangle(t[0], t[1], t[2]));
            }
            for i in 1..n as u32 - 1 {
                if round % 2 == 0 {
                    all.push(Simplex::triangle(0, i, i + 1));
                }
            }
            all.push(Simplex::point(3));
            all.push(Simplex::triangle(4, 4, 4));
            all.sort();
            all.dedup();
            for s in all {
                cx.add(s);
            }
            let (mut masks, mut work) = (MaskList::default(), Weld::default());
            for step in 0..60 {
                check_all_stars(&mut cx, bits, step);
                if step % 17 == 5 {
                    // records turned off (all dropped) for a step, then made again
                    cx.star_cache.set_kept(false);
                    check_all_stars(&mut cx, bits, step);
                    assert!(cx.star_cache.is_empty());
                    cx.star_cache.set_kept(true);
                }
                let used = cx.used_vertices();
                match rand(5) {
                    0 | 1 => {
                        // a decoder's split with random preimage masks
                        let v = used[rand(used.len())];
                        let mut high = cx.vertices[v as usize];
                        high.level = high.level.saturating_add(1);
                        let v2 = cx.add_vertex(high);
                        let slots = cx.listed(v).to_vec();
                        let decoded: Vec<(Simplex, u8)> = slots
                            .iter()
                            .map(|&t| {
                                let c = cx.simplices[t as usize].unwrap();
                                let k = candidates(&c, v, v2).len();
                                (c, 1 + rand((1 << k) - 1) as u8)
                            })
                            .collect();
                        cx.split(v, v2, &slots, &decoded, &mut work);
                    }
                    2 => {
                        // an encoder's merge
                        if used.len() > 4 {
                            let v1 = used[rand(used.len())];
                            let v2 = used[rand(used.len())];
                            if v1 != v2 {
                                cx.weld(v1, v2, &mut masks, &mut work);
                                cx.forget(v2);
                            }
                        }
                    }
                    3 => {
                        // a triangle added or removed by another caller
                        if rand(2) == 0 {
                            let t = [0; 3].map(|_| used[rand(used.len())]);
                            let s = Simplex::triangle(t[0], t[1], t[2]);
                            if !cx.live_simplices().any(|x| x == s) {
                                cx.add(s);
                            }
                        } else {
                            let live: Vec<u32> = (0..cx.simplices.len() as u32)
                                .filter(|&t| cx.simplices[t as usize].is_some())
                                .collect();
                            cx.remove(live[rand(live.len())]);
                        }
                    }
                    _ => {
                        // renumbered in a random order
                        let mut alive = used.clone();
                        for i in (1..alive.len()).rev() {
                            alive.swap(i, rand(i + 1));
                        }
                        cx.reorder(&mut alive);
                    }
                }
            }
            check_all_stars(&mut cx, bits, 60);
        }
    }

    #[test]
    fn the_axis_table_is_axis_bits() {
        for (level, row) in AXIS_BITS.iter().enumerate() {
            for (a, &b) in row.iter().enumerate() {
                assert_eq!(b as u32, axis_bits(level, a));
            }
        }
        let w = Vertex {
            corner: [5, 6, 7],
            level: 4,
        };
        // level 4 on a 4-bit grid: 2 bits along x, 1 along y and z
        assert_eq!(
            doubled(&w, 4),
            [2 * 5 + 4 - 1, 2 * 6 + 8 - 1, 2 * 7 + 8 - 1]
        );
    }

    #[test]
    fn the_plane_test_survives_huge_normals() {
        let big = 1i128 << 100;
        assert!(along([big, big / 4, -big / 4], 0));
        assert!(!along([big, big, big], 0));
        assert!(!along([0, 0, 0], 1));
    }

    #[test]
    fn the_split_of_a_lifted_vertex_is_predicted_below_it() {
        // v's cell at level 11 (z from 10 to 11) lies above the fan's plane z = 8: the centroid
        // and the parallelograms lie below its split plane (axis z, 11 % 3 = 2), so the
        // predicted half is the low one, and the normal points away from it (towards +z)
        let (mut cx, v) = fan(2);
        cx.vertices[v as usize].level = 11;
        let c = split_coding(&mut cx, v, 11, 4);
        assert!(!c.flip);
        let (sub, slot) = (c.ctx / MAX_LEVELS, c.ctx % MAX_LEVELS);
        assert_eq!(
            sub % PARALLELOGRAM,
            1,
            "the parallelograms agree with the centroid"
        );
        assert_eq!(
            slot / (DENSITY + 1),
            2,
            "the normal points away from the predicted half"
        );
    }
}
