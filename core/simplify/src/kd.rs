//! The vocabulary of the adaptive partitions' k-d splitting (Belblidia & Perrin, section 5,
//! figure 6: a cell is cut in two across the largest side of its points' box): 16-byte points,
//! the points' box, where it is cut, and the split pass, which moves a cell's points to either
//! side of the cut and gathers the two halves' boxes, nothing else (issue 33, design point 3;
//! its branch-free variant for small cells did not pay, see [`partition`]).
//! Weights and normals are read by vertex index only in the exact passes of the goals
//! (`adaptive_partition.rs`).

use crate::partition::Cell;

/// A referenced vertex as the partitions move it: position and vertex index (16 bytes).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Point {
    /// Position.
    pub p: [f32; 3],
    /// Vertex index.
    pub id: u32,
}

/// The box of a set of points (the "inner box" of section 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    /// Lower corner.
    pub lo: [f32; 3],
    /// Upper corner.
    pub hi: [f32; 3],
}

impl Bounds {
    /// No point yet.
    pub const EMPTY: Bounds = Bounds {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };

    /// Grows the box to hold `p`.
    #[inline]
    pub fn add(&mut self, p: &[f32; 3]) {
        for (k, &x) in p.iter().enumerate() {
            self.lo[k] = self.lo[k].min(x);
            self.hi[k] = self.hi[k].max(x);
        }
    }

    /// Grows the box to hold `o`.
    #[inline]
    pub fn merge(&mut self, o: &Bounds) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(o.lo[k]);
            self.hi[k] = self.hi[k].max(o.hi[k]);
        }
    }

    /// The box of `points`.
    pub fn of(points: &[Point]) -> Bounds {
        let mut b = Bounds::EMPTY;
        points.iter().for_each(|q| b.add(&q.p));
        b
    }

    /// The cut of section 5: the middle of the largest side (the last of equal sides), or
    /// `None` when the points coincide.
    pub fn cut(&self) -> Option<Cut> {
        let (lo, hi) = (self.lo, self.hi);
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .expect("three axes");
        (hi[axis] > lo[axis]).then(|| Cut {
            axis,
            at: 0.5 * (lo[axis] + hi[axis]),
        })
    }

    /// The squared diagonal, summed in f32 exactly as a displacement is
    /// (`Adaptive::extremes`): a representative inside the box moves no point farther, to the
    /// bit, since every rounding step is monotone.
    #[inline]
    pub fn diagonal2(&self) -> f32 {
        let s = [
            self.hi[0] - self.lo[0],
            self.hi[1] - self.lo[1],
            self.hi[2] - self.lo[2],
        ];
        s[0] * s[0] + s[1] * s[1] + s[2] * s[2]
    }

    /// Half the largest side, exactly (in f64): a representative inside the box is at least
    /// this far from a point at one end of that side.
    #[inline]
    pub fn half_largest_side(&self) -> f64 {
        (0..3)
            .map(|k| 0.5 * (f64::from(self.hi[k]) - f64::from(self.lo[k])))
            .fold(0.0, f64::max)
    }
}

/// Where a split cut its cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cut {
    /// The axis across which the cell is cut.
    pub axis: usize,
    /// The coordinate of the cut: points below go to the first half.
    pub at: f32,
}

impl Cut {
    /// The two halves of `cell`.
    pub fn cells(&self, cell: &Cell) -> (Cell, Cell) {
        let (mut l, mut r) = (*cell, *cell);
        l.max[self.axis] = self.at;
        r.min[self.axis] = self.at;
        (l, r)
    }
}

/// Splits `verts` (non-empty, not all at one position along `cut.axis`) at `cut`: moves the
/// points below the cut to the front and returns how many they are, the two halves' boxes
/// and the cut taken. `aux` (as long as `verts`) is what travels beside the points (the
/// complexity goal's weights and normals, nothing for the quality goal): it is moved the same
/// way. When the midpoint rounds onto an end of the box (no point on one side), the points
/// are split at the median instead, as before.
pub(crate) fn split_points<A: Copy>(
    verts: &mut [Point],
    aux: &mut [A],
    cut: Cut,
) -> (usize, Bounds, Bounds, Cut) {
    let (axis, at) = (cut.axis, cut.at);
    let (mut mid, mut lb, mut rb) = partition(verts, aux, axis, at);
    let mut cut = cut;
    if mid == 0 || mid == verts.len() {
        mid = verts.len() / 2;
        let mut pairs: Vec<(Point, A)> = verts.iter().copied().zip(aux.iter().copied()).collect();
        pairs.select_nth_unstable_by(mid, |a, b| a.0.p[axis].total_cmp(&b.0.p[axis]));
        for ((q, a), (pq, pa)) in verts.iter_mut().zip(aux.iter_mut()).zip(pairs) {
            (*q, *a) = (pq, pa);
        }
        cut.at = verts[mid].p[axis];
        (lb, rb) = (Bounds::of(&verts[..mid]), Bounds::of(&verts[mid..]));
    }
    (mid, lb, rb, cut)
}

/// Hoare's two-pointer partition (each point visited once, few moves), growing the box of
/// the side each point ends on. A branch-free Lomuto partition (every point swapped, the
/// boxes grown with selects) was measured slower for small cells too (quality goal, torus_1M
/// at 0.5 %, one thread, the kd stage: 36.1 ms all Hoare, 37.5 ms branch-free up to 48
/// points, 39.5 ms up to 512, 44 ms everywhere): a cell's points are near one another in
/// the order, so the branches predict well, and Lomuto moves every point.
fn partition<A: Copy>(
    v: &mut [Point],
    aux: &mut [A],
    axis: usize,
    at: f32,
) -> (usize, Bounds, Bounds) {
    let (mut l, mut r) = (Bounds::EMPTY, Bounds::EMPTY);
    let (mut i, mut j) = (0, v.len());
    loop {
        while i < j && v[i].p[axis] < at {
            l.add(&v[i].p);
            i += 1;
        }
        while i < j && v[j - 1].p[axis] >= at {
            r.add(&v[j - 1].p);
            j -= 1;
        }
        if i >= j {
            return (i, l, r);
        }
        v.swap(i, j - 1);
        aux.swap(i, j - 1);
        l.add(&v[i].p);
        r.add(&v[j - 1].p);
        i += 1;
        j -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(xs: &[f32]) -> Vec<Point> {
        xs.iter()
            .enumerate()
            .map(|(i, &x)| Point {
                p: [x, (i % 3) as f32, 0.0],
                id: i as u32,
            })
            .collect()
    }

    #[test]
    fn the_split_pass_moves_points_and_what_travels_beside_them() {
        let xs: Vec<f32> = (0..2000).map(|i| ((i * 7919) % 1000) as f32).collect();
        for n in [1, 2, 7, 100, 2000] {
            let mut a = points(&xs[..n]);
            let mut aux: Vec<u32> = (0..n as u32).collect();
            let (mid, l, r) = partition(&mut a, &mut aux, 0, 500.0);
            assert!(a[..mid].iter().all(|q| q.p[0] < 500.0));
            assert!(a[mid..].iter().all(|q| q.p[0] >= 500.0));
            assert_eq!(mid, xs[..n].iter().filter(|&&x| x < 500.0).count());
            assert!(a.iter().zip(&aux).all(|(q, &id)| q.id == id));
            if mid > 0 {
                assert_eq!(l, Bounds::of(&a[..mid]));
            }
            if mid < n {
                assert_eq!(r, Bounds::of(&a[mid..]));
            }
        }
        // No point below the cut: the median split, with the same moves beside.
        let mut a = points(&[3.0, 1.0, 2.0, 1.0]);
        let mut aux: Vec<u32> = (0..4).collect();
        let (mid, _, _, cut) = split_points(&mut a, &mut aux, Cut { axis: 0, at: 0.5 });
        assert_eq!((mid, cut.at), (2, 2.0));
        assert!(a.iter().zip(&aux).all(|(q, &id)| q.id == id));
    }

    #[test]
    fn box_tests_bound_the_displacement() {
        let b = Bounds {
            lo: [0.0, 0.0, 0.0],
            hi: [3.0, 4.0, 0.0],
        };
        assert_eq!(b.diagonal2(), 25.0);
        assert_eq!(b.half_largest_side(), 2.0);
        let c = b.cut().unwrap();
        assert_eq!((c.axis, c.at), (1, 2.0));
        let mut v = points(&[1.0, 1.0, 1.0]);
        v.iter_mut().for_each(|q| q.p = [1.0; 3]);
        assert!(Bounds::of(&v).cut().is_none());
    }
}
