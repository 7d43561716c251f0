//! The simplicial complex on the leaves of a kd-tree (paper 003 §3, §5.2a): vertices are kd-cells,
//! simplices are oriented triangles over them (a repeated vertex is allowed: a triangle whose
//! corners fell into one cell is the edge or point it became) and isolated points.
//!
//! Both the encoder (merging cells bottom-up) and the decoder (splitting them top-down) work on
//! this structure, so that the two sides see exactly the same state between two codes.

use crate::star_cache::StarCache;

/// Marks an isolated point in [`Simplex::kind`].
pub const POINT: u8 = 0;
/// Marks a triangle in [`Simplex::kind`].
pub const TRIANGLE: u8 = 1;

/// A top simplex over vertex ids: a triangle `(a, b, c)` up to rotation (orientation kept), or an
/// isolated point `(a, a, a)` with kind [`POINT`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Simplex {
    /// Vertex ids, rotated so that the sequence is the smallest of its three rotations.
    pub v: [u32; 3],
    /// [`TRIANGLE`] or [`POINT`].
    pub kind: u8,
    /// A byte of the padding that can only be zero, so that `Option<Simplex>` (a complex's slot)
    /// keeps its `None` there: 16 bytes a slot rather than 20, four slots a cache line.
    niche: Niche,
}

/// A one-value byte: its other 255 values are free for `Option`'s tag.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
enum Niche {
    #[default]
    Zero = 0,
}

const _: () = assert!(std::mem::size_of::<Option<Simplex>>() == 16);

impl Simplex {
    /// The two vertices after `v` in this triangle's turn order (`v` one of its corners).
    #[inline]
    pub fn after(&self, v: u32) -> (u32, u32) {
        let i = self
            .v
            .iter()
            .position(|&x| x == v)
            .expect("the triangle holds v");
        (self.v[(i + 1) % 3], self.v[(i + 2) % 3])
    }

    /// The triangle `(a, b, c)` in its canonical rotation.
    pub fn triangle(a: u32, b: u32, c: u32) -> Self {
        let r = [[a, b, c], [b, c, a], [c, a, b]];
        Simplex {
            v: *r.iter().min().unwrap(),
            kind: TRIANGLE,
            niche: Niche::Zero,
        }
    }

    /// The isolated point `a`.
    pub fn point(a: u32) -> Self {
        Simplex {
            v: [a, a, a],
            kind: POINT,
            niche: Niche::Zero,
        }
    }

    /// The same simplex over the vertices `f` gives, in canonical rotation again.
    pub fn map(self, f: impl Fn(u32) -> u32) -> Self {
        match self.kind {
            POINT => Simplex::point(f(self.v[0])),
            _ => Simplex::triangle(f(self.v[0]), f(self.v[1]), f(self.v[2])),
        }
    }

    /// The same simplex with every `from` replaced by `to`.
    pub fn renamed(self, from: u32, to: u32) -> Self {
        self.map(|x| if x == from { to } else { x })
    }

    /// Its distinct vertices, each once, in corner order (a point's one, a collapsed
    /// triangle's one or two): the vertices whose incidence lists hold its slot.
    #[inline]
    pub fn corners(self) -> impl Iterator<Item = u32> {
        let n = if self.kind == POINT { 1 } else { 3 };
        let v = self.v;
        (0..n)
            .filter(move |&i| !v[..i].contains(&v[i]))
            .map(move |i| v[i])
    }

    /// How many of its corners are `v` (points count once).
    pub fn multiplicity(&self, v: u32) -> usize {
        match self.kind {
            POINT => (self.v[0] == v) as usize,
            _ => self.v.iter().filter(|&&x| x == v).count(),
        }
    }
}

/// `s` as one integer ordered as [`Simplex`]'s own order (ids, then kind).
pub(crate) fn pack(s: &Simplex) -> u128 {
    ((s.v[0] as u128) << 104) | ((s.v[1] as u128) << 72) | ((s.v[2] as u128) << 40) | s.kind as u128
}

/// The simplex [`pack`] made `key` from.
pub(crate) fn unpack(key: u128) -> Simplex {
    Simplex {
        v: [(key >> 104) as u32, (key >> 72) as u32, (key >> 40) as u32],
        kind: key as u8,
        niche: Niche::Zero,
    }
}

/// A kd-cell in the complex: its lower corner on the full-precision grid and its kd level (the
/// number of binary splits, cycling x, y, z, that made it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Vertex {
    /// Lower corner, in grid units of the full precision `p`.
    pub corner: [u32; 3],
    /// kd level: the cell has `level / 3` (+1 for the first `level % 3` axes) bits per axis.
    pub level: u8,
}

/// Bits along `axis` of a cell at kd `level`.
pub const fn axis_bits(level: usize, axis: usize) -> u32 {
    (level / 3 + (axis < level % 3) as usize) as u32
}

impl Vertex {
    /// The cell's side along `axis`, in grid units, for a grid of `bits` bits.
    pub fn extent(&self, axis: usize, bits: u32) -> u64 {
        1u64 << (bits - axis_bits(self.level as usize, axis))
    }

    /// The cell's centre on the grid (the position a decoder shows for it).
    pub fn centre(&self, bits: u32) -> [f64; 3] {
        std::array::from_fn(|a| self.corner[a] as f64 + (self.extent(a, bits) - 1) as f64 / 2.0)
    }
}

/// Slots a vertex's list holds inline, before it moves to [`Incidence::spill`]: on a 1.1 M
/// triangle torus most lists a merge or split touches hold 4 to 31 slots (a kd-cell's star
/// holds its degenerate triangles too), and one 64-byte record is one cache line (aligned to
/// one: a list read is one line, not two).
const INLINE: usize = 15;

/// One vertex's list: up to [`INLINE`] slots in place, else (when `len > INLINE`) `slots[0]`
/// is the index of its list in [`Incidence::spill`].
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(64))]
struct Star {
    len: u32,
    slots: [u32; INLINE],
}

/// Per-vertex lists of simplex slots in one flat array of fixed records (no allocation per
/// vertex), long lists spilled to reused vectors.
#[derive(Clone, Debug, Default)]
struct Incidence {
    stars: Vec<Star>,
    spill: Vec<Vec<u32>>,
    /// Spill vectors no list uses now (emptied, capacity kept).
    free: Vec<u32>,
}

impl Incidence {
    fn list(&self, v: u32) -> &[u32] {
        let st = &self.stars[v as usize];
        if st.len as usize <= INLINE {
            &st.slots[..st.len as usize]
        } else {
            &self.spill[st.slots[0] as usize]
        }
    }

    /// Empties `v`'s list.
    fn clear(&mut self, v: u32) {
        let st = &mut self.stars[v as usize];
        if st.len as usize > INLINE {
            self.spill[st.slots[0] as usize].clear();
            self.free.push(st.slots[0]);
        }
        st.len = 0;
    }

    fn push(&mut self, v: u32, slot: u32) {
        let st = &mut self.stars[v as usize];
        let len = st.len as usize;
        if len < INLINE {
            st.slots[len] = slot;
        } else if len == INLINE {
            let i = match self.free.pop() {
                Some(i) => i,
                None => {
                    self.spill.push(Vec::new());
                    (self.spill.len() - 1) as u32
                }
            };
            let list = &mut self.spill[i as usize];
            list.extend_from_slice(&st.slots);
            list.push(slot);
            st.slots[0] = i;
        } else {
            self.spill[st.slots[0] as usize].push(slot);
        }
        st.len += 1;
    }

    /// Makes `slots` (in slot order) `v`'s list.
    fn set(&mut self, v: u32, slots: &[u32]) {
        self.clear(v);
        if slots.len() <= INLINE {
            let st = &mut self.stars[v as usize];
            st.slots[..slots.len()].copy_from_slice(slots);
            st.len = slots.len() as u32;
        } else {
            for &slot in slots {
                self.push(v, slot);
            }
        }
    }

    fn remove(&mut self, v: u32, slot: u32) {
        let st = &mut self.stars[v as usize];
        let len = st.len as usize;
        if len <= INLINE {
            // slots are listed in increasing order and the newest are removed most
            if let Some(k) = st.slots[..len].iter().rposition(|&t| t == slot) {
                st.slots.copy_within(k + 1..len, k);
                st.len -= 1;
            }
            return;
        }
        let i = st.slots[0];
        let list = &mut self.spill[i as usize];
        // long lists (a coarse vertex holds thousands) are found by halving: slots are sorted
        if let Ok(k) = list.binary_search(&slot) {
            list.remove(k);
            st.len -= 1;
            if st.len as usize == INLINE {
                st.slots.copy_from_slice(list);
                list.clear();
                self.free.push(i);
            }
        }
    }
}

/// Vertices, live simplices and who touches whom.
#[derive(Clone, Debug, Default)]
pub struct Complex {
    /// Every vertex ever made; dead ones stay (their ids are not reused).
    pub vertices: Vec<Vertex>,
    /// Simplex slots; `None` once removed.
    pub simplices: Vec<Option<Simplex>>,
    /// Per vertex, the slots of the live simplices holding it, each once, in slot order
    /// ([`Complex::remove`] takes a slot out of its vertices' lists at once, so that the lists
    /// are always clean and readers need no pruning pass; a merge or split that reuses a slot
    /// for a simplex over the same other vertices leaves their lists as they are).
    incident: Incidence,
    /// Live simplices.
    pub live: usize,
    /// Per slot, when its simplex was made: a count of the simplices made since the complex
    /// was built or last renumbered, which is the slot a split would have given it had it
    /// never reused one. [`Complex::reorder`] keeps each vertex's simplices in this order, so
    /// the decoder's output order does not depend on which slots were reused.
    born: Vec<u32>,
    made: u32,
    /// The split contexts' cached stars ([`crate::star_cache`]): every method here that changes
    /// a simplex first drops the records it could make stale, so that no caller can forget to.
    pub(crate) star_cache: StarCache,
}

impl Complex {
    /// Adds a vertex and returns its id.
    pub fn add_vertex(&mut self, v: Vertex) -> u32 {
        self.vertices.push(v);
        self.incident.stars.push(Star::default());
        let id = (self.vertices.len() - 1) as u32;
        self.star_cache.invalidate(id);
        id
    }

    /// Drops the cached stars a change to the simplex `s` could make stale (before it is added
    /// or removed): those of its corners, and the parallelograms of every vertex sharing a
    /// simplex with one (`s` may lie across one of its far edges, whose ends are `s`'s corners).
    fn drop_stars_of(&mut self, s: Simplex) {
        if self.star_cache.is_empty() {
            return;
        }
        let Complex {
            star_cache,
            incident,
            simplices,
            ..
        } = self;
        for x in s.corners() {
            star_cache.invalidate(x);
            for &slot in incident.list(x) {
                if let Some(t) = simplices[slot as usize] {
                    for y in t.v {
                        star_cache.drop_far(y);
                    }
                }
            }
        }
    }

    /// Drops the cached stars a change to every simplex holding a vertex of `seeds` could make
    /// stale (before the change, whose simplices hold `seeds` and their neighbours only): the
    /// stars of `seeds` and of their neighbours, and the parallelograms that read a vertex of
    /// `seeds`. Those of a vertex `u` read `v` where a triangle `(u, x, y)` meets `(y, x, v)`
    /// across the edge `x → y`, which is where `v`'s own parallelograms read `u`: they are
    /// `v`'s record's far corners when it has them, else the corners of the triangles holding
    /// the far edges of `v`'s star.
    fn drop_stars_around(&mut self, seeds: &[u32]) {
        if self.star_cache.is_empty() {
            return;
        }
        let Complex {
            star_cache,
            incident,
            simplices,
            ..
        } = self;
        for &v in seeds {
            let readers = star_cache.far_corners(v);
            if let Some(ids) = readers {
                for y in ids {
                    star_cache.drop_far(y);
                }
            }
            star_cache.invalidate(v);
            for &slot in incident.list(v) {
                let Some(s) = simplices[slot as usize] else {
                    continue;
                };
                for y in s.v {
                    star_cache.invalidate(y);
                }
                if readers.is_some() || s.kind == POINT || s.multiplicity(v) != 1 {
                    continue;
                }
                // the star triangle (v, a, b): the triangles (b, a, u) across its far edge
                let (a, b) = s.after(v);
                if a == b {
                    continue;
                }
                for &t in incident.list(b) {
                    if let Some(t) = simplices[t as usize] {
                        for u in t.v {
                            star_cache.drop_far(u);
                        }
                    }
                }
            }
        }
    }

    /// Adds `s`, which the caller knows is not there yet (no duplicate check: every caller adds
    /// distinct simplices, and [`crate::encode`]'s union of cells removes its duplicates first).
    pub fn add(&mut self, s: Simplex) {
        self.drop_stars_of(s);
        let slot = self.simplices.len() as u32;
        self.simplices.push(Some(s));
        self.born.push(self.made);
        self.made += 1;
        self.live += 1;
        for x in s.corners() {
            self.incident.push(x, slot);
        }
    }

    /// Removes the simplex in `slot`, and its slot from its vertices' lists.
    pub fn remove(&mut self, slot: u32) {
        let Some(s) = self.simplices[slot as usize] else {
            return;
        };
        self.drop_stars_of(s);
        self.simplices[slot as usize] = None;
        self.live -= 1;
        for x in s.corners() {
            self.incident.remove(x, slot);
        }
    }

    /// Splits `v` into itself and `v2` (the decoder's kd split, §3): each coarse simplex of
    /// `decoded` (every simplex holding `v`, whose slots `coarse_slots` lists) is replaced by
    /// the preimages its mask selects, in that order ([`preimages`]). The first preimage takes
    /// its coarse simplex's slot (the same other vertices: their lists stay as they are), the
    /// others new slots; only the lists of `v` and `v2` are rebuilt.
    pub fn split(
        &mut self,
        v: u32,
        v2: u32,
        coarse_slots: &[u32],
        decoded: &[(Simplex, u8)],
        work: &mut Weld,
    ) {
        self.drop_stars_around(&[v, v2]);
        let Weld {
            slots,
            high,
            coarse,
            at,
            ..
        } = work;
        // each coarse simplex's slot, found by a hash of the simplex
        coarse.clear();
        coarse.extend(
            coarse_slots
                .iter()
                .map(|&slot| self.simplices[slot as usize].expect("listed slots are live")),
        );
        at.build(coarse.iter());
        slots.clear();
        high.clear();
        for &(c, mask) in decoded {
            let k = at
                .find(&c, |k| coarse[k] == c)
                .expect("a coarse simplex of v");
            let mut reuse = Some(coarse_slots[k]);
            preimages(&c, v, v2, mask, |f| {
                let made = self.made;
                self.made += 1;
                let slot = match reuse.take() {
                    Some(slot) => {
                        self.simplices[slot as usize] = Some(f);
                        self.born[slot as usize] = made;
                        slot
                    }
                    None => {
                        let slot = self.simplices.len() as u32;
                        self.simplices.push(Some(f));
                        self.born.push(made);
                        self.live += 1;
                        // v's and v2's lists are rebuilt below
                        for x in f.corners().filter(|&x| x != v && x != v2) {
                            self.incident.push(x, slot);
                        }
                        slot
                    }
                };
                if f.v.contains(&v) {
                    slots.push(slot);
                }
                if f.v.contains(&v2) {
                    high.push(slot);
                }
            });
        }
        slots.sort_unstable();
        high.sort_unstable();
        self.incident.set(v, slots);
        self.incident.set(v2, high);
    }

    /// Removes the simplices in `slots`, which are every simplex holding the vertices `stars`:
    /// their lists are emptied at once rather than slot by slot (a coarse vertex's list is
    /// long). The coder's merges and splits reuse slots instead ([`Complex::weld`],
    /// [`Complex::split`]); this is the plain form, which the tests check them against.
    pub fn remove_stars(&mut self, slots: &[u32], stars: &[u32]) {
        self.drop_stars_around(stars);
        if !self.star_cache.is_empty() {
            // (the slots should all hold a vertex of `stars`; any other is dropped around too)
            for &slot in slots {
                if let Some(s) = self.simplices[slot as usize]
                    && !s.v.iter().any(|x| stars.contains(x))
                {
                    self.drop_stars_of(s);
                }
            }
        }
        for &x in stars {
            self.incident.clear(x);
        }
        for &slot in slots {
            let Some(s) = self.simplices[slot as usize].take() else {
                continue;
            };
            self.live -= 1;
            for x in s.corners().filter(|x| !stars.contains(x)) {
                self.incident.remove(x, slot);
            }
        }
    }

    /// Welds `v2` into `v1` (the encoder's merge of two kd-cells, §3): every simplex holding
    /// either becomes its image with `v2` renamed `v1`, each image once. The images keep the
    /// slots of their preimages (the first in image order where several meet), so the lists of
    /// the other vertices stay as they are but for the few preimages that met: a merge touches
    /// the records of `v1` and `v2` only, not those of the whole star. `masks` receives every
    /// image with its preimage mask (a bit per preimage, numbered by [`candidate_of`]), sorted
    /// by image.
    pub fn weld(&mut self, v1: u32, v2: u32, masks: &mut MaskList, work: &mut Weld) {
        self.drop_stars_around(&[v1, v2]);
        let Weld { keys, slots, .. } = work;
        keys.clear();
        slots.clear();
        {
            // both lists are in slot order: one merge of the two lists, a simplex on both once
            let (a, b) = (self.incident.list(v1), self.incident.list(v2));
            let (mut i, mut j) = (0, 0);
            while i < a.len() || j < b.len() {
                let slot = if j == b.len() || (i < a.len() && a[i] < b[j]) {
                    i += 1;
                    a[i - 1]
                } else {
                    if i < a.len() && a[i] == b[j] {
                        i += 1;
                    }
                    j += 1;
                    b[j - 1]
                };
                let s = self.simplices[slot as usize].expect("listed slots are live");
                let bit = 1u8 << candidate_of(&s, v1, v2);
                keys.push((pack(&s.renamed(v2, v1)), slot, bit));
                slots.push(slot);
            }
        }
        keys.sort_unstable_by_key(|e| e.0);
        masks.0.clear();
        for k in 0..keys.len() {
            let (key, slot, bit) = keys[k];
            let image = unpack(key);
            if k > 0 && keys[k - 1].0 == key {
                // a second preimage of one image: its slot goes, from its other vertices too
                // (the image's, v1 aside, are the preimage's)
                masks.0.last_mut().expect("the image's first preimage").1 |= bit;
                self.simplices[slot as usize] = None;
                self.live -= 1;
                for x in image.corners().filter(|&x| x != v1) {
                    self.incident.remove(x, slot);
                }
            } else {
                masks.0.push((image, bit));
                self.simplices[slot as usize] = Some(image);
            }
        }
        masks.hash_positions();
        // v1's list: the slots that stay, in slot order
        slots.retain(|&t| self.simplices[t as usize].is_some());
        self.incident.clear(v2);
        self.incident.set(v1, slots);
    }

    /// The slots of the live simplices holding `v`, each once.
    pub fn incident(&mut self, v: u32) -> &[u32] {
        self.incident.list(v)
    }

    /// The slots of the live simplices holding `v`, each once, in slot order.
    pub fn listed(&self, v: u32) -> &[u32] {
        self.incident.list(v)
    }

    /// The oriented star of `v`: each triangle holding it (points left out), as the two
    /// vertices after `v` in the triangle's turn order.
    pub fn star(&self, v: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.listed(v).iter().filter_map(move |&slot| {
            let s = self.simplices[slot as usize].expect("incidence lists hold live slots");
            (s.kind != POINT).then(|| s.after(v))
        })
    }

    /// Marks a vertex that holds nothing any more and never will (a merged-away child); its
    /// list is already empty and holds no memory of its own.
    pub fn forget(&mut self, v: u32) {
        debug_assert!(self.incident.list(v).is_empty());
    }

    /// Renumbers the complex in the order of `alive` (vertex `alive[i]` becomes `i`), keeps only
    /// those vertices and the live simplices, and stores each simplex beside its first vertex
    /// (slots follow the vertices' order): with `alive` in kd order, the vertices and
    /// simplices a star walk reads lie close together in memory again, after a level of merges
    /// or splits scattered them. `alive` becomes `0..n`. Leaves the complex as it is when a live
    /// simplex holds a vertex `alive` does not list.
    pub fn reorder(&mut self, alive: &mut [u32]) {
        let mut new_id = vec![u32::MAX; self.vertices.len()];
        for (i, &v) in alive.iter().enumerate() {
            new_id[v as usize] = i as u32;
        }
        let mut out = Complex {
            vertices: alive.iter().map(|&v| self.vertices[v as usize]).collect(),
            simplices: Vec::with_capacity(self.live),
            incident: Incidence {
                stars: vec![Star::default(); alive.len()],
                spill: Vec::new(),
                free: Vec::new(),
            },
            live: 0,
            born: Vec::with_capacity(self.live),
            made: 0,
            star_cache: StarCache::default(),
        };
        // a vertex's simplices, in the order they were made
        let mut owned: Vec<(u32, Simplex)> = Vec::new();
        for &v in alive.iter() {
            let id = new_id[v as usize];
            owned.clear();
            for &slot in self.listed(v) {
                let s = self.simplices[slot as usize].expect("listed slots are live");
                // stored once, by its first vertex in the new numbering: the smallest new id
                // (a canonical rotation starts with its smallest id), found before renaming
                let n = s.v.map(|x| new_id[x as usize]);
                if n[0].min(n[1]).min(n[2]) != id {
                    continue;
                }
                if n.contains(&u32::MAX) {
                    return;
                }
                let r = match s.kind {
                    POINT => Simplex::point(id),
                    _ => Simplex::triangle(n[0], n[1], n[2]),
                };
                owned.push((self.born[slot as usize], r));
            }
            owned.sort_unstable_by_key(|e| e.0);
            for &(_, r) in &owned {
                out.add(r);
            }
        }
        if out.live != self.live {
            return;
        }
        // the same stars under the new ids (cheaper than walking them all again)
        out.star_cache = self.star_cache.renumbered(alive, &new_id);
        *self = out;
        for (i, v) in alive.iter_mut().enumerate() {
            *v = i as u32;
        }
    }

    /// Ids of the vertices that still hold a simplex, in id order.
    pub fn used_vertices(&self) -> Vec<u32> {
        let mut used = vec![false; self.vertices.len()];
        for s in self.simplices.iter().flatten() {
            for &x in &s.v {
                used[x as usize] = true;
            }
        }
        (0..self.vertices.len() as u32)
            .filter(|&i| used[i as usize])
            .collect()
    }

    /// The live simplices.
    pub fn live_simplices(&self) -> impl Iterator<Item = Simplex> + '_ {
        self.simplices.iter().flatten().copied()
    }
}

/// Buffers of [`Complex::weld`] and [`Complex::split`], reused from merge to merge.
#[derive(Clone, Debug, Default)]
pub struct Weld {
    /// (packed image, slot, candidate bit of the preimage in that slot).
    keys: Vec<(u128, u32, u8)>,
    /// The welded slots in slot order; a split's slots holding its low child.
    slots: Vec<u32>,
    /// A split's slots holding its high child.
    high: Vec<u32>,
    /// A split's coarse simplices, and where each lies among them.
    coarse: Vec<Simplex>,
    at: Positions,
}

/// The preimage masks of a merge's coarse simplices, sorted by simplex, with a small hash table
/// of their positions (the connectivity coder asks for each mask once, in its own order; a
/// merge has a dozen or two, and a scan's unpredictable exit cost more than a hash).
#[derive(Clone, Debug, Default)]
pub struct MaskList(pub Vec<(Simplex, u8)>, Positions);

/// Open-addressed positions of [`MaskList`]'s entries (index + 1; 0 is empty), built by
/// [`MaskList::settle`] and [`Complex::weld`]; a lookup checks the simplex it finds, and falls
/// back to a search when the list changed since.
#[derive(Clone, Debug, Default)]
struct Positions {
    at: Vec<u32>,
    shift: u32,
}

/// A multiplicative hash of a simplex, its top bits the table index.
fn hash(c: &Simplex) -> u32 {
    (c.v[0].wrapping_mul(0x9e37_79b1)
        ^ c.v[1].wrapping_mul(0x85eb_ca77)
        ^ c.v[2].wrapping_mul(0xc2b2_ae3d))
    .wrapping_add(u32::from(c.kind).wrapping_mul(0x2545_f491))
}

impl Positions {
    /// Builds the table of the positions of `items` (at most half full).
    fn build<'a>(&mut self, items: impl ExactSizeIterator<Item = &'a Simplex>) {
        let bits = (2 * items.len())
            .max(16)
            .next_power_of_two()
            .trailing_zeros();
        self.at.clear();
        self.at.resize(1 << bits, 0);
        self.shift = 32 - bits;
        let wrap = self.at.len() - 1;
        for (k, c) in items.enumerate() {
            let mut i = (hash(c) >> self.shift) as usize;
            while self.at[i] != 0 {
                i = (i + 1) & wrap;
            }
            self.at[i] = k as u32 + 1;
        }
    }

    /// The position of `c`, given whether the item at a position is `c`.
    fn find(&self, c: &Simplex, is: impl Fn(usize) -> bool) -> Option<usize> {
        if self.at.is_empty() {
            return None;
        }
        let wrap = self.at.len() - 1;
        let mut i = (hash(c) >> self.shift) as usize;
        while self.at[i] != 0 {
            let k = self.at[i] as usize - 1;
            if is(k) {
                return Some(k);
            }
            i = (i + 1) & wrap;
        }
        None
    }
}

impl MaskList {
    /// The position of coarse simplex `c`.
    fn find(&self, c: &Simplex) -> Option<usize> {
        let list = &self.0;
        if let Some(k) = self.1.find(c, |k| list.get(k).is_some_and(|e| e.0 == *c)) {
            return Some(k);
        }
        if self.0.len() <= 16 {
            self.0.iter().position(|e| e.0 == *c)
        } else {
            self.0.binary_search_by(|e| e.0.cmp(c)).ok()
        }
    }

    /// Builds the hash table of the entries' positions (at most half full).
    fn hash_positions(&mut self) {
        self.1.build(self.0.iter().map(|e| &e.0));
    }

    /// Sorts the `(coarse simplex, candidate bit)` pairs pushed so far and merges the pairs of
    /// one simplex into its mask.
    pub fn settle(&mut self) {
        let list = &mut self.0;
        list.sort_unstable_by_key(|e| e.0);
        let mut w = 0;
        for r in 0..list.len() {
            if w > 0 && list[w - 1].0 == list[r].0 {
                list[w - 1].1 |= list[r].1;
            } else {
                list[w] = list[r];
                w += 1;
            }
        }
        list.truncate(w);
        self.hash_positions();
    }
}

impl std::ops::Index<&Simplex> for MaskList {
    type Output = u8;

    fn index(&self, c: &Simplex) -> &u8 {
        let i = self.find(c).expect("a coarse simplex of this merge");
        &self.0[i].1
    }
}

/// Roles of the corners of a fine simplex in a split of `v` into `v1` (low) and `v2` (high):
/// 1 or 2 for the children, 0 for another vertex (`v1` ≠ `v2`).
#[inline]
fn role(x: u32, v1: u32, v2: u32) -> u8 {
    u8::from(x == v1) | u8::from(x == v2) << 1
}

/// The candidate number of a triangle from its corners' roles (as [`role`] gives them).
const fn candidate_by_roles(r: [u8; 3]) -> u8 {
    let mut held = 0;
    let mut ones = 0;
    let mut k = 0;
    while k < 3 {
        held += (r[k] != 0) as u8;
        ones += (r[k] == 1) as u8;
        k += 1;
    }
    match held {
        1 => {
            let i = if r[0] != 0 {
                0
            } else if r[1] != 0 {
                1
            } else {
                2
            };
            r[i] - 1
        }
        2 => {
            // rotate so that the other vertex is last: (r0, r1, x)
            let i = if r[0] == 0 {
                0
            } else if r[1] == 0 {
                1
            } else {
                2
            };
            let (r0, r1) = (r[(i + 1) % 3], r[(i + 2) % 3]);
            (r0 - 1) * 2 + (r1 - 1)
        }
        _ => match ones {
            3 => 0,
            0 => 1,
            2 => 2,
            _ => 3,
        },
    }
}

/// [`candidate_by_roles`] of every triple of roles, indexed by `9 r0 + 3 r1 + r2`: one load per
/// preimage instead of a chain of branches on its shape.
const CANDIDATE: [u8; 27] = {
    let mut t = [0u8; 27];
    let mut i = 0;
    while i < 27 {
        let r = [(i / 9) as u8, (i / 3 % 3) as u8, (i % 3) as u8];
        // a triangle holds v1 or v2 (no entry is read for one holding neither)
        if r[0] + r[1] + r[2] > 0 {
            t[i] = candidate_by_roles(r);
        }
        i += 1;
    }
    t
};

/// Which candidate preimage of its coarse simplex the fine simplex `s` is (§3, the connectivity
/// codes of a vertex split): the coarse simplex is `s` with `v2` renamed `v1`; the candidates are
/// numbered as [`candidates`] lists them.
#[inline]
pub fn candidate_of(s: &Simplex, v1: u32, v2: u32) -> usize {
    if s.kind == POINT {
        return (role(s.v[0], v1, v2) - 1) as usize;
    }
    let r = s.v.map(|x| role(x, v1, v2));
    CANDIDATE[(r[0] * 9 + r[1] * 3 + r[2]) as usize] as usize
}

/// The candidate preimages of coarse simplex `c` (holding `v`) when `v` splits into `v1` = `v`
/// and `v2`, in the numbering of [`candidate_of`].
pub fn candidates(c: &Simplex, v: u32, v2: u32) -> Vec<Simplex> {
    candidate_array(c, v, v2).as_slice().to_vec()
}

/// Two or four candidate preimages, held inline (no allocation per split).
#[derive(Clone, Copy, Debug)]
pub struct Candidates {
    items: [Simplex; 4],
    len: u8,
}

impl Candidates {
    /// The candidates, in the numbering of [`candidate_of`].
    pub fn as_slice(&self) -> &[Simplex] {
        &self.items[..self.len as usize]
    }
}

/// Calls `f` with each candidate preimage of `c` (holding `v`, which splits into `v` and `v2`)
/// that `mask` selects, in the numbering of [`candidate_of`]: the decoder's split. A once-held
/// triangle (most of them) builds only the preimages it has, the first being `c` itself.
#[inline]
pub fn preimages(c: &Simplex, v: u32, v2: u32, mask: u8, mut f: impl FnMut(Simplex)) {
    if c.kind != POINT && c.multiplicity(v) == 1 {
        if mask & 1 != 0 {
            f(*c);
        }
        if mask & 2 != 0 {
            let (a, b) = c.after(v);
            f(Simplex::triangle(v2, a, b));
        }
        return;
    }
    for (i, s) in candidate_array(c, v, v2).as_slice().iter().enumerate() {
        if mask & (1 << i) != 0 {
            f(*s);
        }
    }
}

/// [`candidates`] without an allocation.
pub fn candidate_array(c: &Simplex, v: u32, v2: u32) -> Candidates {
    let v1 = v;
    let two = |a: Simplex, b: Simplex| Candidates {
        items: [a, b, a, b],
        len: 2,
    };
    if c.kind == POINT {
        return two(Simplex::point(v1), Simplex::point(v2));
    }
    let items = match c.multiplicity(v) {
        1 => {
            let i = c.v.iter().position(|&x| x == v).unwrap();
            let (a, b) = (c.v[(i + 1) % 3], c.v[(i + 2) % 3]);
            return two(Simplex::triangle(v1, a, b), Simplex::triangle(v2, a, b));
        }
        2 => {
            let x = *c.v.iter().find(|&&x| x != v).unwrap();
            [(v1, v1), (v1, v2), (v2, v1), (v2, v2)].map(|(a, b)| Simplex::triangle(a, b, x))
        }
        _ => [
            Simplex::triangle(v1, v1, v1),
            Simplex::triangle(v2, v2, v2),
            Simplex::triangle(v1, v1, v2),
            Simplex::triangle(v1, v2, v2),
        ],
    };
    Candidates { items, len: 4 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_and_their_numbers_agree() {
        // v = 0 splits into 0 and 9; others 5, 6
        let (v, v2) = (0u32, 9u32);
        for c in [
            Simplex::triangle(v, 5, 6),
            Simplex::triangle(5, v, v),
            Simplex::triangle(v, v, v),
            Simplex::point(v),
        ] {
            let all = candidates(&c, v, v2);
            for (i, f) in all.iter().enumerate() {
                assert_eq!(candidate_of(f, v, v2), i, "{c:?} {f:?}");
                assert_eq!(f.renamed(v2, v), c);
            }
            for mask in 1..1u8 << all.len() {
                let mut got = Vec::new();
                preimages(&c, v, v2, mask, |f| got.push(f));
                let want: Vec<Simplex> = (0..all.len())
                    .filter(|&i| mask & (1 << i) != 0)
                    .map(|i| all[i])
                    .collect();
                assert_eq!(got, want, "{c:?} mask {mask}");
            }
        }
    }

    #[test]
    fn reorder_keeps_the_complex_under_the_new_numbers() {
        let mut cx = Complex::default();
        for i in 0..6u32 {
            cx.add_vertex(Vertex {
                corner: [i, 0, 0],
                level: 3,
            });
        }
        // vertex 4 is dead (holds nothing); vertex 0 holds more simplices than a record inline
        let mut before = Vec::new();
        for (a, b, c) in [(0, 1, 2), (2, 1, 3), (5, 0, 0), (3, 3, 3), (1, 5, 2)] {
            before.push(Simplex::triangle(a, b, c));
        }
        before.push(Simplex::point(5));
        for a in [1, 2, 3, 5] {
            for b in [1, 2, 3, 5] {
                let s = Simplex::triangle(0, a, b);
                if !before.contains(&s) {
                    before.push(s);
                }
            }
        }
        for &s in &before {
            cx.add(s);
        }
        assert!(cx.listed(0).len() > INLINE);
        cx.remove(0);
        before.remove(0);
        let mut alive = vec![5, 3, 0, 2, 1];
        let old = alive.clone();
        cx.reorder(&mut alive);
        assert_eq!(alive, vec![0, 1, 2, 3, 4]);
        let new_of = |x: u32| old.iter().position(|&v| v == x).unwrap() as u32;
        let mut want: Vec<Simplex> = before.iter().map(|s| s.map(new_of)).collect();
        let mut got: Vec<Simplex> = cx.live_simplices().collect();
        want.sort();
        got.sort();
        assert_eq!(got, want);
        assert_eq!(cx.live, want.len());
        for v in 0..5u32 {
            let listed: Vec<Simplex> = cx
                .listed(v)
                .iter()
                .map(|&t| cx.simplices[t as usize].unwrap())
                .collect();
            let holding: Vec<Simplex> = want.iter().copied().filter(|s| s.v.contains(&v)).collect();
            assert_eq!(listed.len(), holding.len(), "vertex {v}");
            assert!(listed.iter().all(|s| holding.contains(s)));
        }
        // a live simplex on a vertex `alive` leaves out: nothing changes
        let mut partial = vec![0, 1];
        cx.reorder(&mut partial);
        assert_eq!(partial, vec![0, 1]);
        assert_eq!(cx.live, want.len());
        assert_eq!(cx.vertices.len(), 6 - 1);
    }

    /// Every vertex's list holds exactly the live slots holding it, each once, in slot order.
    fn assert_lists_clean(cx: &Complex) {
        for v in 0..cx.vertices.len() as u32 {
            let want: Vec<u32> = (0..cx.simplices.len() as u32)
                .filter(|&t| cx.simplices[t as usize].is_some_and(|s| s.v.contains(&v)))
                .collect();
            assert_eq!(cx.listed(v), &want[..], "vertex {v}");
        }
    }

    #[test]
    fn weld_renames_in_place_and_keeps_each_image_once() {
        let mut cx = Complex::default();
        for i in 0..8u32 {
            cx.add_vertex(Vertex {
                corner: [i, 0, 0],
                level: 3,
            });
        }
        // v1 = 0, v2 = 1: a simplex on each child with the same image (meet), one on both,
        // collapsed ones, a point, enough on 0 to spill its list, and some not on either
        let mut all = vec![
            Simplex::triangle(0, 2, 3),
            Simplex::triangle(1, 2, 3),
            Simplex::triangle(0, 1, 4),
            Simplex::triangle(1, 0, 4),
            Simplex::triangle(1, 1, 5),
            Simplex::triangle(0, 0, 1),
            Simplex::point(1),
            Simplex::triangle(2, 3, 4),
        ];
        for a in 2..8 {
            for b in 2..8 {
                let s = Simplex::triangle(0, a, b);
                if a != b && !all.contains(&s) {
                    all.push(s);
                }
            }
        }
        all.push(Simplex::triangle(1, 6, 7));
        for &s in &all {
            cx.add(s);
        }
        assert!(cx.listed(0).len() > INLINE);
        let (mut masks, mut work) = (MaskList::default(), Weld::default());
        cx.weld(0, 1, &mut masks, &mut work);
        let mut want: Vec<Simplex> = all.iter().map(|s| s.renamed(1, 0)).collect();
        want.sort();
        want.dedup();
        let mut got: Vec<Simplex> = cx.live_simplices().collect();
        got.sort();
        assert_eq!(got, want);
        assert_eq!(cx.live, want.len());
        assert!(cx.listed(1).is_empty());
        assert_lists_clean(&cx);
        // every image once, sorted, with a bit per preimage: the masks a split decodes back
        let mut expected: Vec<(Simplex, u8)> = Vec::new();
        for s in all.iter().filter(|s| s.v.contains(&0) || s.v.contains(&1)) {
            let image = s.renamed(1, 0);
            let bit = 1u8 << candidate_of(s, 0, 1);
            match expected.iter_mut().find(|e| e.0 == image) {
                Some(e) => e.1 |= bit,
                None => expected.push((image, bit)),
            }
        }
        expected.sort();
        assert_eq!(masks.0, expected);
        assert!(expected.iter().any(|e| e.1.count_ones() > 1));
        for &(image, mask) in &masks.0 {
            assert_eq!(masks[&image], mask);
            for (i, f) in candidates(&image, 0, 1).iter().enumerate() {
                let held = all.contains(f);
                assert_eq!(mask & (1 << i) != 0, held, "{image:?} candidate {f:?}");
            }
        }
    }

    #[test]
    fn mask_lists_find_every_mask_by_hash_and_after_a_change() {
        for n in [1u32, 5, 17, 200] {
            let mut masks = MaskList::default();
            for i in 0..n {
                // pairs of one simplex merged, points beside triangles of the same corners
                masks
                    .0
                    .push((Simplex::triangle(1000, i, i + 1), 1 << (i % 4)));
                masks.0.push((Simplex::triangle(1000, i, i + 1), 2));
                masks.0.push((Simplex::point(i), 1));
                masks.0.push((Simplex::triangle(i, i, i), 8));
            }
            masks.settle();
            assert_eq!(masks.0.len(), 3 * n as usize);
            for i in 0..n {
                assert_eq!(masks[&Simplex::triangle(i + 1, 1000, i)], 1 << (i % 4) | 2);
                assert_eq!(masks[&Simplex::point(i)], 1);
                assert_eq!(masks[&Simplex::triangle(i, i, i)], 8);
                assert_eq!(masks.find(&Simplex::triangle(1000, i + 1, i)), None);
            }
            // a list changed after its table was built is still searched right
            masks.0.reverse();
            masks.0.truncate(2);
            let kept = masks.0.clone();
            for (c, m) in kept {
                assert_eq!(masks[&c], m);
            }
            assert_eq!(masks.find(&Simplex::point(n + 5)), None);
        }
    }

    #[test]
    fn split_in_place_gives_the_complex_and_order_of_remove_and_add() {
        // v = 0 splits into 0 and 9 (added last); its star: once-, twice-, thrice-held
        // triangles and a point, enough to spill its list; other simplices around
        let mut cx = Complex::default();
        for i in 0..9u32 {
            cx.add_vertex(Vertex {
                corner: [i, 0, 0],
                level: 3,
            });
        }
        for a in 1..7u32 {
            cx.add(Simplex::triangle(0, a, a + 1));
            cx.add(Simplex::triangle(a, 8, a + 1));
            cx.add(Simplex::triangle(0, a + 1, a));
        }
        for s in [
            Simplex::triangle(0, 0, 3),
            Simplex::triangle(5, 0, 0),
            Simplex::triangle(0, 0, 0),
            Simplex::point(0),
            Simplex::triangle(0, 2, 5),
        ] {
            cx.add(s);
        }
        cx.remove(3);
        assert!(cx.listed(0).len() > INLINE);
        let v2 = cx.add_vertex(Vertex {
            corner: [0, 1, 0],
            level: 4,
        });
        let slots = cx.listed(0).to_vec();
        // masks cycling through each simplex's candidates, in an order other than the slots'
        let mut decoded: Vec<(Simplex, u8)> = slots
            .iter()
            .enumerate()
            .map(|(k, &t)| {
                let c = cx.simplices[t as usize].unwrap();
                let n = candidates(&c, 0, v2).len();
                (c, 1 + (k % ((1 << n) - 1)) as u8)
            })
            .collect();
        decoded.reverse();
        decoded.swap(0, 3);
        let mut old = cx.clone();
        old.remove_stars(&slots, &[0]);
        for &(c, mask) in &decoded {
            preimages(&c, 0, v2, mask, |f| old.add(f));
        }
        let mut new = cx.clone();
        new.split(0, v2, &slots, &decoded, &mut Weld::default());
        assert_eq!(new.live, old.live);
        assert_lists_clean(&new);
        let mut a: Vec<Simplex> = new.live_simplices().collect();
        let mut b: Vec<Simplex> = old.live_simplices().collect();
        a.sort();
        b.sort();
        assert_eq!(a, b);
        // renumbered, both keep each vertex's simplices in the order they were made
        let mut alive: Vec<u32> = vec![8, 0, 9, 1, 2, 3, 4, 5, 6, 7];
        let mut alive2 = alive.clone();
        new.reorder(&mut alive);
        old.reorder(&mut alive2);
        assert_eq!(
            new.live_simplices().collect::<Vec<_>>(),
            old.live_simplices().collect::<Vec<_>>()
        );
        assert_lists_clean(&new);
    }

    #[test]
    fn rotation_is_canonical_and_keeps_orientation() {
        assert_eq!(Simplex::triangle(3, 1, 2), Simplex::triangle(1, 2, 3));
        assert_ne!(Simplex::triangle(1, 3, 2), Simplex::triangle(1, 2, 3));
    }
}
