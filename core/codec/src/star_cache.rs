//! A cache of each vertex's star topology, for the split contexts (issue 34's "neighbour list
//! cached per vertex"). A split context sums positions over a vertex's star and over the
//! triangles across its far edges ([`crate::split_context`]); the ids it reads depend on the
//! topology only, and most kd splits move a vertex alone in its cell without changing it. A
//! [`Record`] holds those ids as a short flat list, so that a context reads one record and the
//! current positions instead of walking incidence lists, level after level.
//!
//! Records hold ids, never positions, and are dropped ([`StarCache::invalidate`]) by every
//! method of [`crate::complex::Complex`] that changes a simplex, for every vertex whose star or
//! far edges could see the change; a record that is present therefore always equals what a walk
//! of the complex would find (split_context checks so under `debug_assertions`). This file knows
//! nothing of the complex (it sits below it): it stores, drops and renumbers records.

/// Distinct vertices a record holds: its star's neighbours, then the third corners across its
/// far edges.
pub(crate) const ENTRIES: usize = 16;
/// Star triangles `(v, x, y)` with three distinct corners a record holds.
pub(crate) const TRIANGLES: usize = 14;

/// The record holds the star's neighbours and triangles.
const BASE: u8 = 1;
/// The star holds a collapsed triangle (`v v x` or `v v v`).
const COLLAPSED: u8 = 2;
/// The record also holds the parallelograms (the far edges' third corners).
const FAR: u8 = 4;
/// The star does not fit a record (or its parallelograms do not, with [`BASE`]): walk it.
const WALK: u8 = 8;

/// One vertex's star as ids, 128 bytes (two cache lines, one aligned pair). The star's sums
/// are weighted sums over the entries' positions: `weight` counts an entry as a neighbour
/// (the centroid and reach), `par` is its coefficient in the parallelograms' sum
/// Σ (x + y − z), and `tri` lists the star triangles (the normal) as pairs of entries.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(128))]
pub(crate) struct Record {
    flags: u8,
    /// Entries in use: the neighbours first (`base` of them), then the far corners.
    pub(crate) len: u8,
    /// Entries that are neighbours (with a weight; the others' weight is 0).
    pub(crate) base: u8,
    /// Triangles in [`Record::tri`].
    pub(crate) tris: u8,
    /// Vertex ids of the entries.
    pub(crate) ids: [u32; ENTRIES],
    /// Per entry, how many times the star counts it as a neighbour.
    pub(crate) weight: [u8; ENTRIES],
    /// Per entry, its coefficient in Σ (x + y − z) over the parallelograms (with [`FAR`]):
    /// their sum (1 + 1 − 1 each) is how many parallelograms there are.
    pub(crate) par: [i8; ENTRIES],
    /// The star triangles `(v, x, y)` (`x`, `y`, `v` distinct) as entry indices.
    pub(crate) tri: [[u8; 2]; TRIANGLES],
}

const _: () = assert!(std::mem::size_of::<Record>() == 128);

impl Default for Record {
    fn default() -> Self {
        Record {
            flags: 0,
            len: 0,
            base: 0,
            tris: 0,
            ids: [0; ENTRIES],
            weight: [0; ENTRIES],
            par: [0; ENTRIES],
            tri: [[0; 2]; TRIANGLES],
        }
    }
}

impl Record {
    /// Whether this star must be walked (it does not fit a record).
    pub(crate) fn walk(&self) -> bool {
        self.flags & WALK != 0
    }

    /// Whether the star holds a collapsed triangle.
    pub(crate) fn collapsed(&self) -> bool {
        self.flags & COLLAPSED != 0
    }

    /// Whether the parallelograms are recorded (else [`RecordBuilder::far`] adds them).
    pub(crate) fn far(&self) -> bool {
        self.flags & FAR != 0
    }

    /// The entry holding `id`, made if need be with no weight; `None` when the record is full.
    fn entry(&mut self, id: u32) -> Option<usize> {
        let len = self.len as usize;
        if let Some(i) = self.ids[..len].iter().position(|&x| x == id) {
            return Some(i);
        }
        if len == ENTRIES {
            return None;
        }
        self.ids[len] = id;
        self.weight[len] = 0;
        self.par[len] = 0;
        self.len += 1;
        Some(len)
    }
}

/// Builds a record from a walk of the star (in the walk's order: its triangles' far edges
/// are numbered as they come); a star that does not fit makes a record that says to walk it.
pub(crate) struct RecordBuilder {
    r: Record,
    fits: bool,
}

impl RecordBuilder {
    /// Starts the record of a star (its neighbours and triangles).
    pub(crate) fn new() -> Self {
        RecordBuilder {
            r: Record {
                flags: BASE,
                ..Record::default()
            },
            fits: true,
        }
    }

    /// Continues `r` (which holds its star's base) with its parallelograms, and marks them
    /// found.
    pub(crate) fn far(r: &Record) -> Self {
        let mut r = *r;
        r.flags |= FAR;
        r.par = [0; ENTRIES];
        r.len = r.base;
        RecordBuilder { r, fits: true }
    }

    /// Marks the star as holding a collapsed triangle.
    pub(crate) fn collapsed(&mut self) {
        self.r.flags |= COLLAPSED;
    }

    /// Counts `x` as a neighbour `times` more times; returns its entry ([`ENTRIES`] if it
    /// did not fit).
    #[inline]
    pub(crate) fn neighbour(&mut self, x: u32, times: u8) -> u8 {
        let r = &mut self.r;
        let Some(i) = r.entry(x) else {
            self.fits = false;
            return ENTRIES as u8;
        };
        // (weights stay below 128: a record's star has few triangles)
        r.weight[i] = r.weight[i].saturating_add(times).min(128);
        self.fits &= r.weight[i] < 128;
        r.base = r.len;
        i as u8
    }

    /// Adds the star triangle `(v, x, y)` by its corners' entries (as [`Self::neighbour`]
    /// returned them; distinct): its far edge is the next one.
    #[inline]
    pub(crate) fn triangle(&mut self, i: u8, j: u8) {
        let r = &mut self.r;
        if (i as usize) < ENTRIES && (j as usize) < ENTRIES && (r.tris as usize) < TRIANGLES {
            r.tri[r.tris as usize] = [i, j];
            r.tris += 1;
        } else {
            self.fits = false;
        }
    }

    /// Adds the parallelogram `x + y − z` of the triangle `(y, x, z)` across far edge
    /// number `t`.
    #[inline]
    pub(crate) fn parallelogram(&mut self, t: usize, z: u32) {
        if !self.fits || t >= self.r.tris as usize {
            self.fits = false;
            return;
        }
        let r = &mut self.r;
        let Some(k) = r.entry(z) else {
            self.fits = false;
            return;
        };
        let [i, j] = r.tri[t];
        for (e, d) in [(i as usize, 1), (j as usize, 1), (k, -1)] {
            match r.par[e].checked_add(d) {
                Some(c) => r.par[e] = c,
                None => self.fits = false,
            }
        }
    }

    /// Marks the parallelograms found (all of them added).
    pub(crate) fn far_done(&mut self) {
        self.r.flags |= FAR;
    }

    /// The finished record, or one that says to walk the star if it did not fit.
    pub(crate) fn done(self) -> Record {
        if self.fits {
            self.r
        } else {
            Record {
                flags: BASE | WALK,
                ..Record::default()
            }
        }
    }
}

/// A copy of a record's entry ids.
#[derive(Clone, Copy)]
pub(crate) struct Entries {
    ids: [u32; ENTRIES],
    len: u8,
}

impl IntoIterator for Entries {
    type Item = u32;
    type IntoIter = std::iter::Take<std::array::IntoIter<u32, ENTRIES>>;

    fn into_iter(self) -> Self::IntoIter {
        self.ids.into_iter().take(self.len as usize)
    }
}

/// The records of a complex's vertices, indexed by vertex id (grown as records are stored),
/// and whether each is present apart, a byte a vertex: the drops a change makes touch those
/// bytes only, not the records' cache lines.
#[derive(Clone, Default)]
pub(crate) struct StarCache {
    /// Per vertex, [`BASE`] if its record is present and [`FAR`] if its parallelograms are.
    state: Vec<u8>,
    records: Vec<Record>,
    /// Records present: none means there is nothing to drop.
    present: usize,
    /// Records are not kept ([`StarCache::set_kept`]).
    off: bool,
}

impl std::fmt::Debug for StarCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "StarCache({} records)", self.present)
    }
}

impl StarCache {
    /// `v`'s record, if one is present (a copy, saying whether its parallelograms are).
    #[inline]
    pub(crate) fn get(&self, v: u32) -> Option<Record> {
        let state = *self.state.get(v as usize)?;
        if state & BASE == 0 {
            return None;
        }
        let mut r = self.records[v as usize];
        r.flags = (r.flags & !FAR) | (state & FAR);
        Some(r)
    }

    /// Stores `r` as `v`'s record.
    pub(crate) fn store(&mut self, v: u32, r: Record) {
        let v = v as usize;
        if v >= self.records.len() {
            let n = (v + 1).max(2 * self.records.len()).max(64);
            self.records.resize(n, Record::default());
            self.state.resize(n, 0);
        }
        if self.state[v] & BASE == 0 {
            self.present += 1;
        }
        self.state[v] = BASE | (r.flags & FAR);
        self.records[v] = r;
    }

    /// Whether records are made and kept: where most vertices split or merge (the coarse kd
    /// levels) nearly every record is dropped before it is read again, and making and dropping
    /// them costs more than the walks they save. Turning them off drops them all.
    pub(crate) fn set_kept(&mut self, kept: bool) {
        if !kept && self.present > 0 {
            self.state.fill(0);
            self.present = 0;
        }
        self.off = !kept;
    }

    /// Whether records are made and kept.
    #[inline]
    pub(crate) fn kept(&self) -> bool {
        !self.off
    }

    /// Whether no record is present (so that a change to the complex has none to drop).
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.present == 0
    }

    /// Drops `v`'s record.
    #[inline]
    pub(crate) fn invalidate(&mut self, v: u32) {
        if let Some(s) = self.state.get_mut(v as usize)
            && *s & BASE != 0
        {
            *s = 0;
            self.present -= 1;
        }
    }

    /// Drops `v`'s parallelograms (its star stays): a triangle across its far edges changed.
    #[inline]
    pub(crate) fn drop_far(&mut self, v: u32) {
        if let Some(s) = self.state.get_mut(v as usize) {
            *s &= !FAR;
        }
    }

    /// The entries of `v`'s record (its neighbours, then its parallelograms' far corners)
    /// when it holds its parallelograms.
    #[inline]
    pub(crate) fn far_corners(&self, v: u32) -> Option<Entries> {
        let r = self.get(v).filter(|r| r.far() && !r.walk())?;
        Some(Entries {
            ids: r.ids,
            len: r.len,
        })
    }

    /// The cache under a renumbering: vertex `alive[i]` becomes `i`, `new_id` maps every old
    /// id to its new one (`u32::MAX` for a vertex that goes; a record naming one is dropped).
    pub(crate) fn renumbered(&self, alive: &[u32], new_id: &[u32]) -> StarCache {
        if self.present == 0 {
            return StarCache {
                off: self.off,
                ..StarCache::default()
            };
        }
        let mut out = StarCache {
            state: vec![0; alive.len()],
            records: vec![Record::default(); alive.len()],
            present: 0,
            off: self.off,
        };
        for (i, &v) in alive.iter().enumerate() {
            let Some(mut r) = self.get(v) else {
                continue;
            };
            let mut kept = true;
            for id in &mut r.ids[..r.len as usize] {
                *id = new_id[*id as usize];
                kept &= *id != u32::MAX;
            }
            if kept {
                out.state[i] = BASE | (r.flags & FAR);
                out.records[i] = r;
                out.present += 1;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_are_stored_dropped_and_renumbered() {
        let mut c = StarCache::default();
        assert!(c.get(3).is_none() && c.is_empty());
        let mut b = RecordBuilder::new();
        let i = b.neighbour(7, 2);
        let j = b.neighbour(9, 2);
        b.triangle(i, j);
        c.store(3, b.done());
        assert!(!c.is_empty() && !c.get(3).unwrap().far());
        let mut f = RecordBuilder::far(&c.get(3).unwrap());
        f.parallelogram(0, 11);
        c.store(3, f.done());
        let r = c.get(3).unwrap();
        assert!(r.far() && !r.walk() && !r.collapsed());
        assert_eq!((r.len, r.base), (3, 2));
        assert_eq!(&r.par[..3], &[1, 1, -1]);
        // 3 → 0, 7 → 1, 9 → 2, 11 → 3
        let mut new_id = vec![u32::MAX; 12];
        for (i, v) in [3, 7, 9, 11].into_iter().enumerate() {
            new_id[v] = i as u32;
        }
        let d = c.renumbered(&[3, 7, 9, 11], &new_id);
        assert_eq!(&d.get(0).unwrap().ids[..3], &[1, 2, 3]);
        assert!(d.get(1).is_none());
        // a record naming a vertex that goes is dropped
        new_id[11] = u32::MAX;
        assert!(c.renumbered(&[3, 7, 9], &new_id).is_empty());
        // the parallelograms dropped, the star kept
        let ids: Vec<u32> = c.far_corners(3).unwrap().into_iter().collect();
        assert_eq!(ids, vec![7, 9, 11]);
        c.drop_far(3);
        assert!(!c.get(3).unwrap().far() && c.get(3).unwrap().base == 2);
        assert!(c.far_corners(3).is_none());
        c.invalidate(3);
        c.invalidate(3);
        assert!(c.get(3).is_none() && c.is_empty());
    }

    #[test]
    fn a_star_too_big_does_not_fit() {
        let full = || {
            let mut b = RecordBuilder::new();
            for x in 0..ENTRIES as u32 {
                b.neighbour(x, 2);
            }
            b
        };
        assert!(!full().done().walk());
        let mut b = full();
        b.neighbour(99, 1);
        assert!(b.done().walk());
        let mut b = full();
        b.triangle(0, 1);
        b.parallelogram(0, 99);
        assert!(b.done().walk(), "no entry left for the far corner");
        let mut b = RecordBuilder::new();
        b.neighbour(1, 100);
        b.neighbour(1, 100);
        assert!(b.done().walk(), "weights stay below 128");
    }
}
