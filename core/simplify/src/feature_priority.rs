//! A surface-error estimate of a cell, for the complexity goal's choice of the cell to split
//! (beyond paper 004, whose section 4 splits the cell with the largest vertex displacement).
//!
//! Displacement sees size, not error: a large flat cell has a large displacement and no surface
//! error, while a cell across a sharp CAD edge or a curved strip has surface error its
//! displacement does not rank. Here each vertex stands for its tangent plane (its
//! area-weighted normal through it, as Lindstrom 2000's quadrics stand for the planes of a
//! cell's faces), and a cell's estimate is the largest distance from its representative (the
//! barycentre the split loop already computes) to its vertices' tangent planes: zero on a flat
//! cell, the sagitta on a curved one, the gap across a crease, half the thickness of two
//! sheets. Border vertices count with their whole displacement ([`vertex_normals`]).
//!
//! With the quadric representative, cells of up to `tangent_key::SMALL_CELL` points are keyed
//! from their tangent planes' quadric point instead of the barycentre (`tangent_key.rs`: the
//! barycentre overrates every cell across a crease, where the quadric point sits on it).
//!
//! Used by the complexity goal only (the quality goal's guarantee is on the displacement and
//! keeps it): the normals of [`vertex_normals`] travel with the vertices through the split
//! (packed in four bytes, [`PackedNormal`]), and the pass of `Adaptive::finish_eval` that
//! measures a cell's largest displacement `d` also takes `s = max plane_distance(rep, q.p,
//! q.n)` (squared, unnormalised: [`plane_distance2`]); the cell's split key becomes [`priority`]`(s, d)` in place of `d`.

use rayon::prelude::*;
use tessd_mesh::Mesh;

/// The share of the displacement added to the surface estimate: it orders the cells the
/// estimate cannot tell apart (flat ones) by size, and keeps every cell that can still be
/// split (distinct vertices) above zero, so the complexity goal can always reach its count.
pub(crate) const DISPLACEMENT_SHARE: f32 = 1.0 / 256.0;

/// The unit area-weighted normal of every vertex (the sum of its faces' area vectors), packed,
/// or none for a vertex on an open border or a non-manifold fan, and for one no face of
/// non-zero area uses: the estimate then takes its whole displacement, since its tangent plane
/// does not say how far the border moves within it. `weights` are the vertices' longest
/// incident edges (`weights.rs`), the scale of the border test.
///
/// A border is found without adjacency: around an interior vertex of a closed fan the edges
/// opposite the vertex form a closed loop, so their vectors sum to zero; on a border they sum
/// to the chord between the fan's two ends.
///
/// One pass over the faces, in parallel (issue 33, point 5): the vertices are cut into
/// ranges, and each range walks the faces in order, adding to its own vertices only, so every
/// vertex's sums are taken in face order — the same bits on any number of cores, and as the
/// serial pass gave. A first pass takes the smallest and largest vertex index of every block
/// of [`SPAN_FACES`] faces ([`face_spans`]), and a range walks only the blocks whose span
/// meets it. Where faces and vertices come in a similar order (scans, generated and exported
/// meshes) a range then reads about its share of the faces, so the ranges can be
/// [`VERTEX_RANGE`] vertices each — many more than cores, their sums in cache; where they do
/// not, there is one range per core, each walking every face.
pub(crate) fn vertex_normals(mesh: &Mesh, weights: &[f32]) -> Vec<PackedNormal> {
    let n = mesh.vertex_count();
    let faces = mesh.face_count();
    let spans = face_spans(mesh);
    let chunk = range_size(&spans, n);
    let mut out = vec![PackedNormal::NONE; n];
    out.par_chunks_mut(chunk).enumerate().for_each(|(i, out)| {
        let (lo, hi) = (i * chunk, i * chunk + out.len());
        let blocks = spans
            .iter()
            .enumerate()
            .filter(|&(_, &(a, b))| (a as usize) < hi && b as usize >= lo)
            .map(|(b, _)| b * SPAN_FACES..((b + 1) * SPAN_FACES).min(faces));
        normals_of_range(mesh, weights, lo, out, blocks);
    });
    out
}

/// Vertices per range of [`vertex_normals`] when the faces' order follows the vertices': the
/// range's sums (24 bytes a vertex) fit in a core's cache.
const VERTEX_RANGE: usize = 1 << 15;

/// The vertices per range of [`vertex_normals`] for `n` vertices: [`VERTEX_RANGE`] when the
/// ranges would walk at most 1.25 times the face blocks between them, else one range per
/// thread (with `n / 4096 + 1` at most).
fn range_size(spans: &[(u32, u32)], n: usize) -> usize {
    let walked: usize = spans
        .iter()
        .filter(|(a, b)| a <= b)
        .map(|&(a, b)| b as usize / VERTEX_RANGE - a as usize / VERTEX_RANGE + 1)
        .sum();
    if walked <= spans.len() + spans.len() / 4 {
        return VERTEX_RANGE;
    }
    let parts = if crate::blocks::single_thread() {
        1
    } else {
        rayon::current_num_threads().clamp(1, n / 4096 + 1)
    };
    n.div_ceil(parts).max(1)
}

/// Faces per block of [`face_spans`]: small enough that a core skips most of what is not its
/// own, large enough that the spans are a few kilobytes.
const SPAN_FACES: usize = 1024;

/// The smallest and largest vertex index of every block of [`SPAN_FACES`] faces, in parallel
/// (an index pass; `(u32::MAX, 0)` for a block without corners).
fn face_spans(mesh: &Mesh) -> Vec<(u32, u32)> {
    let faces = mesh.face_count();
    (0..faces.div_ceil(SPAN_FACES))
        .into_par_iter()
        .map(|b| {
            let (f0, f1) = (b * SPAN_FACES, ((b + 1) * SPAN_FACES).min(faces));
            let corners = mesh.face_offsets[f0] as usize..mesh.face_offsets[f1] as usize;
            mesh.face_indices[corners]
                .iter()
                .fold((u32::MAX, 0), |(a, b), &v| (a.min(v), b.max(v)))
        })
        .collect()
}

/// [`vertex_normals`] of the vertices `lo..lo + out.len()`, from the faces of `blocks`
/// (increasing ranges of face indices holding every face with a corner in the range).
fn normals_of_range(
    mesh: &Mesh,
    weights: &[f32],
    lo: usize,
    out: &mut [PackedNormal],
    blocks: impl Iterator<Item = std::ops::Range<usize>>,
) {
    let len = out.len();
    // Area vectors, then the opposite edges' vectors, of the range's vertices.
    let mut acc = vec![[[0f32; 3]; 2]; len];
    let whole = lo == 0 && len == mesh.vertex_count();
    match mesh.triangles() {
        Some(tris) => {
            for r in blocks {
                for t in &tris[r] {
                    add_triangle(&mesh.positions, *t, lo, whole, &mut acc);
                }
            }
        }
        None => {
            for r in blocks {
                for f in r {
                    add_face(&mesh.positions, mesh.face(f), lo, whole, &mut acc);
                }
            }
        }
    }
    for ((n, [s, e]), &w) in out.iter_mut().zip(&acc).zip(&weights[lo..lo + len]) {
        let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
        // The opposite edges of a closed fan cancel up to rounding: a few ulps of the
        // longest edge; a border's chord is at least an edge long.
        let border = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() > 1e-3 * w;
        *n = if len > 0.0 && len.is_finite() && !border {
            PackedNormal::pack([s[0] / len, s[1] / len, s[2] / len])
        } else {
            PackedNormal::NONE
        };
    }
}

/// [`add_face`] of a triangle, with the same operations in the same order (the same bits),
/// its corners loaded once.
#[inline(always)]
fn add_triangle(
    positions: &[[f32; 3]],
    t: [u32; 3],
    lo: usize,
    whole: bool,
    acc: &mut [[[f32; 3]; 2]],
) {
    let mine = t.map(|v| (v as usize).wrapping_sub(lo));
    if !whole && mine.iter().all(|&i| i >= acc.len()) {
        return;
    }
    let p = t.map(|v| positions[v as usize]);
    let mut a = [0f32; 3];
    for i in 0..3 {
        let (u, v) = (p[i], p[(i + 1) % 3]);
        a[0] += (u[1] - v[1]) * (u[2] + v[2]);
        a[1] += (u[2] - v[2]) * (u[0] + v[0]);
        a[2] += (u[0] - v[0]) * (u[1] + v[1]);
    }
    for i in 0..3 {
        let Some(s) = acc.get_mut(mine[i]) else {
            continue;
        };
        let (prev, next) = (p[(i + 2) % 3], p[(i + 1) % 3]);
        (0..3).for_each(|k| s[0][k] += a[k]);
        (0..3).for_each(|k| s[1][k] += next[k] - prev[k]);
    }
}

/// Adds one face's area vector and, for each corner, the vector of its opposite edge to the
/// sums of its corners in `lo..lo + acc.len()` (`whole`: every vertex is in the range).
#[inline(always)]
fn add_face<F: AsRef<[u32]> + ?Sized>(
    positions: &[[f32; 3]],
    face: &F,
    lo: usize,
    whole: bool,
    acc: &mut [[[f32; 3]; 2]],
) {
    let face = face.as_ref();
    let mine = |v: u32| (v as usize).wrapping_sub(lo);
    if !whole && !face.iter().any(|&v| mine(v) < acc.len()) {
        return;
    }
    let m = face.len();
    let p = |i: usize| positions[face[i % m] as usize];
    // Newell's area vector (twice the area), exact for triangles.
    let mut a = [0f32; 3];
    for i in 0..m {
        let (u, v) = (p(i), p(i + 1));
        a[0] += (u[1] - v[1]) * (u[2] + v[2]);
        a[1] += (u[2] - v[2]) * (u[0] + v[0]);
        a[2] += (u[0] - v[0]) * (u[1] + v[1]);
    }
    for (i, &v) in face.iter().enumerate() {
        let Some(s) = acc.get_mut(mine(v)) else {
            continue;
        };
        let (prev, next) = (p(i + m - 1), p(i + 1));
        (0..3).for_each(|k| s[0][k] += a[k]);
        (0..3).for_each(|k| s[1][k] += next[k] - prev[k]);
    }
}

/// A unit normal in four bytes — octahedral: the sphere's L1 projection folded onto a square,
/// 16 bits a side, within 1e-4 rad of the normal — or none (a border vertex, see
/// [`vertex_normals`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PackedNormal(u32);

impl PackedNormal {
    /// No normal: the vertex's whole displacement counts.
    pub(crate) const NONE: PackedNormal = PackedNormal(0x8000_8000);

    /// Packs a unit normal (a zero or non-finite one packs as [`PackedNormal::NONE`]).
    pub(crate) fn pack(n: [f32; 3]) -> PackedNormal {
        let l1 = n[0].abs() + n[1].abs() + n[2].abs();
        if !(l1 > 0.0 && l1.is_finite()) {
            return PackedNormal::NONE;
        }
        let (mut x, mut y) = (n[0] / l1, n[1] / l1);
        if n[2] < 0.0 {
            (x, y) = ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum());
        }
        let q = |v: f32| u32::from((v.clamp(-1.0, 1.0) * 32767.0).round() as i16 as u16);
        PackedNormal(q(x) | (q(y) << 16))
    }

    /// The unit normal, or zero for [`PackedNormal::NONE`].
    #[cfg(test)]
    fn unpack(self) -> [f32; 3] {
        let [x, y, z] = self.direction();
        let len = (x * x + y * y + z * z).sqrt();
        if len > 0.0 {
            [x / len, y / len, z / len]
        } else {
            [0.0; 3]
        }
    }

    /// The normal's direction at some length between 1/√3 and 1 (the octahedron's point), or
    /// zero for [`PackedNormal::NONE`]: what a plane distance needs, without a root.
    #[inline]
    pub(crate) fn direction(self) -> [f32; 3] {
        if self == PackedNormal::NONE {
            return [0.0; 3];
        }
        let x = f32::from(self.0 as u16 as i16) / 32767.0;
        let y = f32::from((self.0 >> 16) as u16 as i16) / 32767.0;
        let z = 1.0 - x.abs() - y.abs();
        let (x, y) = if z < 0.0 {
            ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
        } else {
            (x, y)
        };
        [x, y, z]
    }
}

/// The squared distance from a point to the tangent plane of a vertex, from `d` (the point
/// minus the vertex), `dd` = |d|² and `n`, the vertex's normal at any length
/// ([`PackedNormal::direction`]); `dd` itself when `n` is zero (a border vertex, see
/// [`vertex_normals`]). Squared and unnormalised: no root in the split's inner loop.
#[inline]
pub(crate) fn plane_distance2(d: [f32; 3], dd: f32, n: [f32; 3]) -> f32 {
    let nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    let t = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    if nn > 0.0 { t * t / nn } else { dd }
}

/// The distance from `x` to the tangent plane of the vertex at `p` with normal `n`; to `p`
/// itself when `n` is zero.
#[cfg(test)]
fn plane_distance(x: [f32; 3], p: [f32; 3], n: [f32; 3]) -> f32 {
    let d = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
    plane_distance2(d, d[0] * d[0] + d[1] * d[1] + d[2] * d[2], n).sqrt()
}

/// The split priority of a cell whose largest distance to its vertices' tangent planes is
/// `surface` and largest vertex displacement `displacement`.
#[inline]
pub(crate) fn priority(surface: f32, displacement: f32) -> f32 {
    surface + DISPLACEMENT_SHARE * displacement
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cell's estimate: the largest distance from the barycentre to the tangent planes.
    fn estimate(points: &[([f32; 3], [f32; 3])]) -> f32 {
        let mut c = [0f32; 3];
        for (p, _) in points {
            (0..3).for_each(|k| c[k] += p[k] / points.len() as f32);
        }
        points
            .iter()
            .map(|&(p, n)| plane_distance(c, p, n))
            .fold(0.0, f32::max)
    }

    #[test]
    fn flat_cells_have_no_error_and_creases_are_found() {
        let up = [0.0, 0.0, 1.0];
        let flat: Vec<_> = (0..9)
            .map(|i| ([(i % 3) as f32, (i / 3) as f32, 2.0], up))
            .collect();
        assert!(estimate(&flat) < 1e-6);
        // A roof: two slopes meeting at x = 0 (a 90° crease); the barycentre lies 2 below the
        // ridge, √2 off both slopes, though its displacement to the eaves is larger.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let mut roof = Vec::new();
        for i in 1..4 {
            let x = i as f32;
            roof.push(([-x, 0.0, -x], [-s, 0.0, s]));
            roof.push(([x, 0.0, -x], [s, 0.0, s]));
        }
        assert!(
            (estimate(&roof) - 2f32.sqrt()).abs() < 1e-5,
            "{}",
            estimate(&roof)
        );
        // Two parallel sheets 1 apart: half the gap.
        let mut sheets = Vec::new();
        for i in 0..4 {
            sheets.push(([i as f32, 0.0, 0.0], up));
            sheets.push(([i as f32, 1.0, 1.0], up));
        }
        assert!((estimate(&sheets) - 0.5).abs() < 1e-5);
        assert_eq!(priority(0.0, 256.0), 1.0);
    }

    #[test]
    fn normals_of_a_closed_and_an_open_mesh() {
        // A closed tetrahedron, faces outwards.
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            ..Mesh::default()
        };
        for f in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            m.push_face(&f);
        }
        let w = crate::weights::vertex_weights(&m, crate::options::Weighting::LongestEdge);
        let n: Vec<[f32; 3]> = vertex_normals(&m, &w).iter().map(|n| n.unpack()).collect();
        assert_eq!(n[1], [1.0, 0.0, 0.0]);
        let s = -(1.0f32 / 3.0).sqrt();
        assert!(n[0].iter().all(|&x| (x - s).abs() < 1e-4), "{:?}", n[0]);
        // Without its slanted face, vertices 1–3 are on the open border (whole displacement);
        // vertex 0's fan is still closed.
        m.face_offsets.pop();
        m.face_indices.truncate(9);
        let open: Vec<[f32; 3]> = vertex_normals(&m, &w).iter().map(|n| n.unpack()).collect();
        assert_eq!(open[0], n[0]);
        assert_eq!(open[1..], [[0.0; 3]; 3]);
        assert_eq!(plane_distance([3.0, 4.0, 0.0], [0.0; 3], [0.0; 3]), 5.0);
    }

    /// A bumpy `n` × `n` grid of quads split in two, the faces of row 3 left whole (polygons),
    /// with its vertices in row order or shuffled (the faces then span the whole index range).
    fn bumpy_grid(n: u32, shuffled: bool) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..n {
            for i in 0..n {
                let z = ((i * 7 + j * 13) % 5) as f32 * 0.1;
                m.positions.push([i as f32, j as f32, z]);
            }
        }
        let id = |v: u32| if shuffled { (v * 7919) % (n * n) } else { v };
        if shuffled {
            let old = m.positions.clone();
            (0..n * n).for_each(|v| m.positions[id(v) as usize] = old[v as usize]);
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let v = j * n + i;
                let [a, b, c, d] = [v, v + 1, v + n + 1, v + n].map(id);
                if j == 3 {
                    m.push_face(&[a, b, c, d]);
                } else {
                    m.push_face(&[a, b, c]);
                    m.push_face(&[a, c, d]);
                }
            }
        }
        m
    }

    /// The serial pass: every face in order, every vertex in range.
    fn serial_normals(m: &Mesh, w: &[f32]) -> Vec<PackedNormal> {
        let mut out = vec![PackedNormal::NONE; m.vertex_count()];
        normals_of_range(m, w, 0, &mut out, std::iter::once(0..m.face_count()));
        out
    }

    #[test]
    fn normals_do_not_depend_on_the_ranges() {
        // Every split of the vertices into ranges gives the bits of the whole.
        let m = bumpy_grid(30, false);
        let w = crate::weights::vertex_weights(&m, crate::options::Weighting::LongestEdge);
        let whole = serial_normals(&m, &w);
        assert!(whole.iter().filter(|&&n| n != PackedNormal::NONE).count() > 700);
        for chunk in [1, 7, 128, 899] {
            let mut parts = vec![PackedNormal::NONE; 900];
            for (i, out) in parts.chunks_mut(chunk).enumerate() {
                normals_of_range(&m, &w, i * chunk, out, std::iter::once(0..m.face_count()));
            }
            assert_eq!(parts, whole, "ranges of {chunk}");
        }
        assert_eq!(vertex_normals(&m, &w), whole);
    }

    #[test]
    fn normals_are_the_serial_bits_on_any_number_of_threads() {
        // 300 × 300 vertices: 174 blocks of faces, so a core skips the blocks outside its
        // range; shuffled, every block spans every range and no block may be skipped.
        for shuffled in [false, true] {
            let m = bumpy_grid(300, shuffled);
            let w = crate::weights::vertex_weights(&m, crate::options::Weighting::LongestEdge);
            let serial = serial_normals(&m, &w);
            let spans = face_spans(&m);
            assert!(spans.len() > 100);
            let narrow = spans.iter().filter(|(a, b)| b - a < 5000).count();
            assert_eq!(narrow > 100, !shuffled, "{narrow} narrow spans");
            for threads in [1, 2, 7] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let n = pool.install(|| vertex_normals(&m, &w));
                assert!(n == serial, "{threads} threads, shuffled {shuffled}");
            }
        }
    }

    /// `cargo test --release -p tessd-simplify --lib normals_time -- --ignored --nocapture`:
    /// the pass on a 4 M-triangle grid (2 M vertices) at 1 and 2 threads, and its face spans
    /// alone, medians of 7 (the pass before the spans, which every core walked whole, is
    /// dd33ec6's, timed beside this one in 006afdc4's message).
    #[test]
    #[ignore]
    fn normals_time() {
        let m = bumpy_grid(1415, false);
        let w = crate::weights::vertex_weights(&m, crate::options::Weighting::LongestEdge);
        let serial = serial_normals(&m, &w);
        let median_ms = |f: &dyn Fn()| {
            let mut t: Vec<f64> = (0..7)
                .map(|_| {
                    let t = std::time::Instant::now();
                    f();
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            t.sort_by(f64::total_cmp);
            t[3]
        };
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let ms = median_ms(&|| assert!(pool.install(|| vertex_normals(&m, &w)) == serial));
            println!("{threads} threads, {} faces: {ms:.1} ms", m.face_count());
        }
        let spans = median_ms(&|| {
            std::hint::black_box(face_spans(&m));
        });
        println!("face spans alone: {spans:.1} ms");
    }

    #[test]
    fn packed_normals_round_trip_within_1e_4() {
        let mut worst = 0f32;
        for i in 0..200 {
            // A spiral over the whole sphere, poles and octant seams included.
            let z = 1.0 - 2.0 * i as f32 / 199.0;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = i as f32 * 2.399_963;
            let n = [r * a.cos(), r * a.sin(), z];
            let u = PackedNormal::pack(n).unpack();
            let d = ((n[0] - u[0]).powi(2) + (n[1] - u[1]).powi(2) + (n[2] - u[2]).powi(2)).sqrt();
            worst = worst.max(d);
        }
        assert!(worst < 1e-4, "{worst}");
        assert_eq!(PackedNormal::pack([0.0; 3]), PackedNormal::NONE);
        assert_eq!(PackedNormal::NONE.unpack(), [0.0; 3]);
        assert_eq!(
            PackedNormal::pack([0.0, 0.0, -1.0]).unpack(),
            [0.0, 0.0, -1.0]
        );
    }
}
