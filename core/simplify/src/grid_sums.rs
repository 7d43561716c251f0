//! The grid's per-cluster sums and its representatives: passes S and C of the grid's fused
//! passes (issue 33). No member lists: every vertex adds itself into its cluster's slots as
//! the vertices stream by (`grid_cells.rs` calls [`contribution`] in the pass that numbers the
//! cells), and the representatives are read off the slots.
//!
//! For the weighted barycentre (Belblidia & Perrin, section 2, "fusion des sommets") the sums
//! are integers, so that they are the same bits in any order and every core can add into the
//! same slots: each vertex's place inside its cell (0 to 1 along each axis; the cell is the
//! same for the whole cluster) in 23-bit fixed point, times its weight scaled by a power of
//! two that takes the mesh's largest weight to 2³⁷–2³⁸. A product is below 2⁶², split into
//! its low 32 bits and the rest, each summed in a u64: exact for up to 2³² vertices a
//! cluster. The barycentre lies within about 2⁻²⁴ of a cell side of the exact one (a few
//! ulps of the f32 result, where the order of f64 sums used to decide the last bits); a
//! weight below 2⁻³⁸ of the largest counts as that much. The heaviest vertex (its position
//! is the heaviest representative) is a maximum of (weight, −index): the first met among
//! equals.

use crate::blocks;
use crate::grid_frame::Grid;
use crate::options::Representative;
use crate::partition::UNUSED;
use crate::quadric::Quadric;
use crate::representative;
use rayon::prelude::*;
use std::sync::atomic::AtomicU32;
use std::sync::atomic::Ordering::Relaxed;
use tessd_mesh::Mesh;

/// u64 slots a cluster's sums take (x low, x high, y low, y high, z low, z high, weight; one
/// spare to fill the cache line).
pub(crate) const SLOTS: usize = 8;

/// Fixed-point steps per cell side.
const UNIT: f64 = (1u64 << 23) as f64;

/// Per-cluster sums, as the cell pass leaves them.
pub(crate) struct Sums {
    /// Heaviest vertex of each cluster: `weight bits << 32 | !index`.
    pub heavy: Vec<u64>,
    /// [`SLOTS`] a cluster: the fixed-point sums.
    pub sums: Vec<u64>,
    /// When asked for (the quadric representative): the box of each cluster's vertices, six
    /// [`ordered`] bits a cluster, low corner then high corner (minima and maxima: the same
    /// whichever core takes them first).
    pub boxes: Vec<u32>,
}

/// A cluster's box before its first vertex, in [`ordered`] bits.
pub(crate) const EMPTY_BOX: [u32; 6] = [u32::MAX, u32::MAX, u32::MAX, 0, 0, 0];

/// The weight scale: a power of two (exact) that takes the largest of `weights` to
/// 2³⁷–2³⁸.
pub(crate) fn weight_scale(weights: &[f32]) -> f64 {
    let top = blocks::map(weights.len(), |r| {
        weights[r]
            .iter()
            .fold(0f32, |m, &w| if w > m { w } else { m })
    })
    .into_iter()
    .fold(0f32, f32::max);
    let e = i64::from((top.to_bits() >> 23) & 0xff);
    f64::from_bits(((1023 + 37 + 127 - e).clamp(1, 2046) as u64) << 52)
}

/// Key of vertex `v` of weight `w` for the heaviest: the largest weight, then the smallest
/// index.
#[inline]
pub(crate) fn heavy_key(v: usize, w: f32) -> u64 {
    u64::from(w.to_bits()) << 32 | u64::from(!(v as u32))
}

/// What a vertex of weight `w` at `u` inside its cell adds to its cluster's [`SLOTS`].
#[inline]
pub(crate) fn contribution(u: [f64; 3], w: f32, scale: f64) -> [u64; 7] {
    // Rounded by adding a half and truncating through i64 (`f64::round` and f64 → u64 are
    // library calls or branches on the baseline x86-64 target). A referenced vertex counts at
    // least one step, so that every cluster's weight is positive.
    // SAFETY (both conversions): finite values in 0..2³⁸ (a weight is at most the largest,
    // scaled below 2³⁸; a place is clamped to 0..2 steps of 2²³).
    let wq = (unsafe { (f64::from(w) * scale + 0.5).to_int_unchecked::<i64>() }).max(1) as u64;
    let mut out = [0u64; 7];
    for k in 0..3 {
        let x = u[k].clamp(0.0, 2.0) * UNIT + 0.5;
        let uq = unsafe { x.to_int_unchecked::<i64>() } as u64;
        let term = wq * uq;
        out[2 * k] = term & 0xffff_ffff;
        out[2 * k + 1] = term >> 32;
    }
    out[6] = wq;
    out
}

/// `x`'s bits turned so that unsigned order is float order.
#[inline]
pub(crate) fn ordered(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 1 << 31 != 0 { !b } else { b | 1 << 31 }
}

/// [`ordered`]'s inverse.
fn unordered(o: u32) -> f32 {
    f32::from_bits(if o & 1 << 31 != 0 { o & !(1 << 31) } else { !o })
}

/// The representative of each cluster of `cluster_of` (a partition of `grid`) from its sums
/// (pass C); the quadric representative takes every cluster's quadric from `quadrics` (the
/// face pass summed them, `grid_quadrics.rs`) or, without them, sums them first, a chunk of
/// clusters at a time.
pub(crate) fn grid_representatives(
    mesh: &Mesh,
    cluster_of: &[u32],
    sums: Sums,
    grid: &Grid,
    rep: Representative,
    quadrics: Option<Vec<Quadric>>,
) -> Vec<[f32; 3]> {
    let positions = &mesh.positions;
    let n = sums.heavy.len();
    let heaviest = |c: usize| !(sums.heavy[c] as u32) as usize;
    if rep == Representative::Heaviest {
        return (0..n)
            .into_par_iter()
            .map(|c| positions[heaviest(c)])
            .collect();
    }
    let side = grid.side();
    let barycentre = |c: usize| -> [f64; 3] {
        let s = &sums.sums[c * SLOTS..(c + 1) * SLOTS];
        let w = s[6] as f64 * UNIT;
        let corner = grid.corner(grid.locate(&positions[heaviest(c)]).0);
        std::array::from_fn(|k| {
            // High part times 2³² plus low part, each rounded once, in a fixed order.
            let x = s[2 * k + 1] as f64 * (1u64 << 32) as f64 + s[2 * k] as f64;
            corner[k] + x / w * side[k]
        })
    };
    if rep != Representative::Quadric {
        return (0..n)
            .into_par_iter()
            .map(|c| barycentre(c).map(|x| x as f32))
            .collect();
    }
    // The barycentres first (the minimiser's start and fallback; in f32, which is what the
    // fallback gives anyway), so that the sums and the heaviest are freed before the
    // quadrics are held: the peak stays under twice the input at half its vertices.
    let mut reps: Vec<[f32; 3]> = (0..n)
        .into_par_iter()
        .map(|c| barycentre(c).map(|x| x as f32))
        .collect();
    let taken = sums.boxes;
    drop(sums.sums);
    drop(sums.heavy);
    // The box of each cluster's vertices (the minimiser's bound): taken in the cell pass
    // where the clusters are few, else now that the sums are freed.
    let boxes = if taken.len() == 6 * n {
        taken
    } else {
        cluster_boxes(positions, cluster_of, n)
    };
    let mut solve = |first: usize, quadrics: &[Quadric]| {
        let out = &mut reps[first..first + quadrics.len()];
        // Each barycentre turns into its cluster's representative in place.
        out.par_iter_mut().enumerate().for_each(|(i, x)| {
            let c = first + i;
            let b = &boxes[6 * c..6 * c + 6];
            let lo = std::array::from_fn(|k| unordered(b[k]));
            let hi = std::array::from_fn(|k| unordered(b[3 + k]));
            *x = representative::quadric_point(&quadrics[i], [lo, hi], x.map(f64::from));
        });
    };
    match quadrics {
        Some(q) => solve(0, &q),
        None => representative::for_each_quadric_chunk(
            mesh,
            cluster_of,
            n,
            representative::GRID_SHARE,
            solve,
        ),
    }
    reps
}

/// The box of each of the `n` clusters of `cluster_of`'s vertices: six [`ordered`] bits a
/// cluster, low corner then high corner (minima and maxima: the same whichever core takes
/// them first).
pub(crate) fn cluster_boxes(positions: &[[f32; 3]], cluster_of: &[u32], n: usize) -> Vec<u32> {
    let boxes: Vec<AtomicU32> = (0..6 * n)
        .map(|k| AtomicU32::new(EMPTY_BOX[k % 6]))
        .collect();
    let single = blocks::single_thread();
    blocks::ranges(cluster_of.len()).for_each(|r| {
        for v in r {
            let c = cluster_of[v];
            if c == UNUSED {
                continue;
            }
            let b = &boxes[6 * c as usize..6 * c as usize + 6];
            for k in 0..3 {
                let o = ordered(positions[v][k]);
                if single {
                    b[k].store(b[k].load(Relaxed).min(o), Relaxed);
                    b[3 + k].store(b[3 + k].load(Relaxed).max(o), Relaxed);
                } else {
                    b[k].fetch_min(o, Relaxed);
                    b[3 + k].fetch_max(o, Relaxed);
                }
            }
        }
    });
    boxes.into_iter().map(AtomicU32::into_inner).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordered_bits_keep_float_order() {
        let xs = [-3.5f32, -0.0, 0.0, 1e-30, 2.0, 7.25];
        for w in xs.windows(2) {
            assert!(ordered(w[0]) <= ordered(w[1]));
        }
        for x in xs {
            assert_eq!(unordered(ordered(x)).to_bits(), x.to_bits());
        }
    }

    #[test]
    fn fixed_point_sums_give_the_weighted_mean() {
        // Two vertices of weights 1 and 3 at 0.2 and 0.6 of a cell: mean 0.5.
        let scale = weight_scale(&[1.0, 3.0]);
        let a = contribution([0.2, 0.0, 1.0], 1.0, scale);
        let b = contribution([0.6, 0.5, 1.0], 3.0, scale);
        let s: Vec<u64> = (0..7).map(|k| a[k] + b[k]).collect();
        let mean = |k: usize| {
            (s[2 * k + 1] as f64 * 2f64.powi(32) + s[2 * k] as f64) / (s[6] as f64 * UNIT)
        };
        assert!((mean(0) - 0.5).abs() < 1e-7, "{}", mean(0));
        assert!((mean(1) - 0.375).abs() < 1e-7);
        assert!((mean(2) - 1.0).abs() < 1e-7);
    }
}
