//! Building the nSP-tree out of core (paper 003 §5.1): the points are read once for the cubic
//! box and once to quantise them (held at 6 bytes a point up to 16 bits, the RWP of the paper);
//! the tree grows one level per pass over the triangles (the root's level taken in the pass that
//! counts the triangles), a cell being split when at least `N_min` top simplices belong to it
//! and its children would not be tiny (`worth_splitting`); then one more pass writes every top
//! simplex to the region of each leaf it belongs to in a raw index file (the paper's RWI), sized
//! from the counts the level passes made, so that a leaf is later read back with one sequential
//! read.
//!
//! Only the points, the tree and one small write buffer per leaf are in memory: the triangles
//! stay on disk, in the input file and the RWI.
//!
//! Speed (issue 34, the 200 M-triangle run on 2 cores): each pass reads the file on one thread
//! and uses what it reads on another (`source::triangles_beside`); the counting pass counts the
//! cells of every depth the tree is likely to reach through a small cache per depth (`Counts`),
//! so that the tree needs no pass of its own; the RWI pass finds a point's leaf by the bits of
//! the tree's child masks. At 200 M triangles: two passes over the triangles, about half the
//! partition's former time.

use std::fs::File;

use rustc_hash::FxHashMap;

use crate::error::CodecError;
use crate::nsp_tree::{Node, Params};
use crate::positional_io;
use crate::quantize::Quantizer;
use crate::source::{MeshSource, mesh_error, triangles_beside, vertices_beside};

/// Marks an isolated point in the RWI: `[vertex, POINT_MARK, POINT_MARK]`.
pub const POINT_MARK: u32 = u32::MAX;

/// The quantised points (the paper's RWP), 6 bytes a point up to 16 bits, 12 beyond.
pub enum Points {
    /// Up to 16 bits per coordinate.
    Narrow(Vec<[u16; 3]>),
    /// 17 to 20 bits.
    Wide(Vec<[u32; 3]>),
}

impl Points {
    /// Grid coordinates of point `i`.
    #[inline]
    pub fn get(&self, i: u32) -> [u32; 3] {
        match self {
            Points::Narrow(v) => v[i as usize].map(u32::from),
            Points::Wide(v) => v[i as usize],
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Points::Narrow(v) => v.len(),
            Points::Wide(v) => v.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The partition of a mesh: grid, points, tree (pre-order) and each leaf's simplices on disk.
pub struct Partition {
    /// The quantisation grid.
    pub grid: Quantizer,
    /// The quantised points.
    pub points: Points,
    /// The tree in pre-order; `end_*` are filled by the coder.
    pub nodes: Vec<Node>,
    /// Per node: (first entry, entries) of its simplices in the RWI (leaves only).
    pub regions: Vec<(u64, u64)>,
    /// The raw index file: `[u32; 3]` entries (vertex indices; points marked).
    pub rwi: File,
    /// Vertices of the input.
    pub input_vertices: u64,
    /// Triangles of the input (after fan triangulation).
    pub input_triangles: u64,
    /// Whether each vertex is used by a triangle (bit per vertex).
    pub referenced: Vec<u64>,
}

impl Partition {
    /// The simplices of leaf `i`, read back from the RWI.
    pub fn leaf(&self, i: usize) -> Result<Vec<[u32; 3]>, CodecError> {
        let (first, count) = self.regions[i];
        let mut bytes = vec![0u8; count as usize * 12];
        positional_io::read_exact_at(&self.rwi, &mut bytes, first * 12)
            .map_err(|e| CodecError::io("reading the raw index file", e))?;
        Ok(bytes
            .chunks_exact(12)
            .map(|b| {
                std::array::from_fn(|k| u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap()))
            })
            .collect())
    }
}

/// Tree under construction: arena order (breadth-first).
struct Arena {
    nodes: Vec<Node>,
    /// Simplices belonging to each node.
    counts: Vec<u64>,
}

fn code(c: [u32; 3]) -> u64 {
    c[0] as u64 | (c[1] as u64) << 21 | (c[2] as u64) << 42
}

/// Distinct values among the (up to) three.
fn distinct3<T: PartialEq + Copy>(x: [T; 3]) -> impl Iterator<Item = T> {
    let keep = [true, x[1] != x[0], x[2] != x[0] && x[2] != x[1]];
    (0..3).filter(move |&k| keep[k]).map(move |k| x[k])
}

/// Reads `src` in passes and builds its partition; `progress` gets the fraction done.
pub fn build(
    src: &mut dyn MeshSource,
    params: Params,
    progress: &dyn Fn(f64) -> bool,
) -> Result<Partition, CodecError> {
    let budget = (src.vertex_count() / COUNT_BUDGET_SHARE).max(MIN_COUNT_BUDGET);
    build_with_count_budget(src, params, progress, budget)
}

/// Bytes of the leaves' write buffers of the RWI pass, all together (each holds at least 40
/// entries).
const RWI_BUFFERS: usize = 32 << 20;

/// Cells the counting pass may count at every depth at once, as a share of the vertices: the
/// counts cost about 32 bytes a cell against the points' 6 bytes a vertex.
pub const COUNT_BUDGET_SHARE: u64 = 32;
/// ... and at least this many.
pub const MIN_COUNT_BUDGET: u64 = 1 << 16;

/// [`build`], counting at most `budget` cells (summed over depths) in the counting pass: every
/// depth whose counts fit is grown without a pass of its own, the deeper ones one pass each.
/// The partition does not depend on `budget`.
pub fn build_with_count_budget(
    src: &mut dyn MeshSource,
    params: Params,
    progress: &dyn Fn(f64) -> bool,
    budget: u64,
) -> Result<Partition, CodecError> {
    let progress = |f: f64| {
        if progress(f) {
            Ok(())
        } else {
            Err(CodecError::Cancelled)
        }
    };
    let n = src.vertex_count();
    if n >= u32::MAX as u64 {
        return Err(CodecError::Input(format!(
            "{n} vertices: at most {} are supported",
            u32::MAX - 1
        )));
    }
    // pass 1: the cubic box
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    let mut bad: Option<(u64, [f32; 3])> = None;
    let mut k = 0u64;
    src.vertices(&mut |p| {
        if bad.is_none() && p.iter().any(|c| !c.is_finite()) {
            bad = Some((k, p));
        }
        for a in 0..3 {
            min[a] = min[a].min(p[a] as f64);
            max[a] = max[a].max(p[a] as f64);
        }
        k += 1;
    })
    .map_err(mesh_error)?;
    if let Some((i, p)) = bad {
        return Err(CodecError::Input(format!(
            "vertex {i} has a non-finite coordinate {p:?}"
        )));
    }
    if n == 0 {
        (min, max) = ([0.0; 3], [1.0; 3]);
    }
    let grid = Quantizer::new(min, max, params.bits)?;
    progress(0.05)?;
    // pass 2: quantise (the RWP)
    let mut points = if params.bits <= 16 {
        Points::Narrow(Vec::with_capacity(n as usize))
    } else {
        Points::Wide(Vec::with_capacity(n as usize))
    };
    vertices_beside(src, &mut |p| {
        let q = grid.quantize(p.map(f64::from));
        match &mut points {
            Points::Narrow(v) => v.push(q.map(|x| x as u16)),
            Points::Wide(v) => v.push(q),
        }
    })?;
    progress(0.1)?;
    // pass 3: triangle count, the referenced vertices, and the triangles of every cell at every
    // depth a split can reach (`counted[d]`: depth d + 1), the deepest depths dropped while the
    // cells counted exceed `budget` or are too many for the tree to reach them: the tree then
    // grows without passes of its own down to there (which cells split is known only once a
    // level is complete)
    let mut referenced = vec![0u64; (n as usize).div_ceil(64)];
    let mut triangles = 0u64;
    let depths = if n == 0 {
        0
    } else {
        (0..)
            .take_while(|&d| params.precision(d).1 < params.bits)
            .count()
    };
    let mut counted: Vec<Counts> = (0..depths).map(|_| Counts::new()).collect();
    let mut cells = 0u64;
    triangles_beside(src, &mut |t| {
        for x in t {
            referenced[x as usize / 64] |= 1 << (x % 64);
        }
        triangles += 1;
        // the grid points fetched once for every depth
        let q = t.map(|x| points.get(x));
        for (d, counts) in counted.iter_mut().enumerate() {
            cells += count_children(&params, d as u32, None, &q, counts);
        }
        // a depth whose cells would average under a sixteenth of what a split's children need
        // is unlikely to be reached: stop counting it (checked every 65 536 triangles). Under
        // a half, as it was, left out the one depth the 200 M-triangle torus reaches last
        // (13 bits), and its own pass over the file cost more than counting it here
        // (counting through `Counts` is cheap)
        let check = triangles.is_multiple_of(65_536);
        if check {
            // the map sizes must be whole to be compared
            for counts in counted.iter_mut() {
                cells += counts.settle();
            }
        }
        let likely = |c: &Counts| {
            !check || c.len() as u64 <= (16 * triangles * CHILD_SHARE / params.min_cell).max(4096)
        };
        while cells > budget || counted.last().is_some_and(|c| !likely(c)) {
            cells -= counted.pop().map_or(0, |c| c.len() as u64);
        }
    })?;
    let isolated: Vec<u32> = (0..n as u32)
        .filter(|&i| referenced[i as usize / 64] & (1 << (i % 64)) == 0)
        .collect();
    // the tree, one level per pass
    let mut arena = Arena {
        nodes: vec![Node::default()],
        counts: vec![triangles + isolated.len() as u64],
    };
    if n == 0 {
        arena.nodes.clear();
        arena.counts.clear();
    }
    let mut frontier: Vec<usize> = if n == 0 { Vec::new() } else { vec![0] };
    let mut depth = 0u32;
    while !frontier.is_empty() {
        let splitting: Vec<usize> = frontier
            .iter()
            .copied()
            .filter(|&i| {
                params.precision(depth).1 < params.bits && arena.counts[i] >= params.min_cell
            })
            .collect();
        if splitting.is_empty() {
            break;
        }
        let parents: FxHashMap<u64, usize> = splitting
            .iter()
            .map(|&i| (code(arena.nodes[i].cell), i))
            .collect();
        let mut child_counts = match counted.get_mut(depth as usize) {
            Some(all) => {
                let under = |c: &u64| {
                    parents.contains_key(&code(uncode(*c).map(|x| x / params.cell_split)))
                };
                let all = std::mem::replace(all, Counts::of(FxHashMap::default())).into_map();
                Counts::of(all.into_iter().filter(|(c, _)| under(c)).collect())
            }
            None => {
                let mut counts = Counts::new();
                triangles_beside(src, &mut |t| {
                    let q = t.map(|x| points.get(x));
                    count_children(&params, depth, Some(&parents), &q, &mut counts);
                })?;
                counts
            }
        };
        for &i in &isolated {
            let q = [points.get(i)];
            count_children(&params, depth, Some(&parents), &q, &mut child_counts);
        }
        let mut children: Vec<(u64, u64)> = child_counts.into_map().into_iter().collect();
        children.sort_unstable();
        let parent_of = |c: u64| {
            let cell = [
                (c & 0x1f_ffff) as u32,
                ((c >> 21) & 0x1f_ffff) as u32,
                (c >> 42) as u32,
            ];
            parents[&code(cell.map(|x| x / params.cell_split))]
        };
        // the split is made only when its children are not tiny (see `worth_splitting`)
        let mut made: FxHashMap<usize, (u64, u64)> = FxHashMap::default();
        for &(c, cnt) in &children {
            let e = made.entry(parent_of(c)).or_insert((0, 0));
            *e = (e.0 + cnt, e.1 + 1);
        }
        let mut next = Vec::new();
        for (c, cnt) in children {
            let cell = [
                (c & 0x1f_ffff) as u32,
                ((c >> 21) & 0x1f_ffff) as u32,
                (c >> 42) as u32,
            ];
            let parent = parent_of(c);
            let (sum, nonempty) = made[&parent];
            if !worth_splitting(&params, sum, nonempty) {
                continue;
            }
            let id = arena.nodes.len();
            arena.nodes.push(Node {
                depth: depth + 1,
                cell,
                ..Node::default()
            });
            arena.counts.push(cnt);
            let pos = {
                let nn = params.cell_split;
                let l = cell.map(|x| x % nn);
                (l[0] + nn * (l[1] + nn * l[2])) as usize
            };
            arena.nodes[parent].child_mask |= 1 << pos;
            arena.nodes[parent].children.push(id);
            next.push(id);
        }
        for &i in &splitting {
            let kids = std::mem::take(&mut arena.nodes[i].children);
            let mut kids: Vec<(usize, usize)> = kids
                .into_iter()
                .map(|k| (position(&params, &arena.nodes[k]), k))
                .collect();
            kids.sort_unstable();
            arena.nodes[i].children = kids.into_iter().map(|(_, k)| k).collect();
        }
        frontier = next;
        depth += 1;
        progress((0.1 + 0.05 * depth as f64).min(0.35))?;
    }
    // pre-order numbering
    let mut order = Vec::with_capacity(arena.nodes.len());
    if !arena.nodes.is_empty() {
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            order.push(i);
            stack.extend(arena.nodes[i].children.iter().rev());
        }
    }
    let mut new_id = vec![0usize; arena.nodes.len()];
    for (k, &i) in order.iter().enumerate() {
        new_id[i] = k;
    }
    let nodes: Vec<Node> = order
        .iter()
        .map(|&i| {
            let mut node = arena.nodes[i].clone();
            node.children = node.children.iter().map(|&c| new_id[c]).collect();
            node
        })
        .collect();
    // the counts of depths the tree did not reach are not needed any more
    drop(counted);
    // the leaf holding a point: down from the root by the child's position in its parent, the
    // children being in position order (a hash map of cells took a fifth of the partition)
    let leaf_of = |q: [u32; 3]| -> usize {
        // n is a power of two: masks and shifts, not divisions (three a level, a third of
        // this pass)
        let (lb, low) = (params.level_bits(), params.cell_split - 1);
        let mut i = 0usize;
        loop {
            let node = &nodes[i];
            if node.children.is_empty() {
                return i;
            }
            let c = params.cell_at(node.depth + 1, q).map(|x| x & low);
            let bit = 1u64 << (c[0] | (c[1] | c[2] << lb) << lb);
            if node.child_mask & bit == 0 {
                return i;
            }
            i = node.children[(node.child_mask & (bit - 1)).count_ones() as usize];
        }
    };
    // entries per leaf: a leaf's simplices are those with a vertex in it, which its level's pass
    // counted (no pass of their own); then one pass writes them (the RWI)
    let mut regions = vec![(0u64, 0u64); nodes.len()];
    let mut at = 0u64;
    for (k, &i) in order.iter().enumerate() {
        let s = if nodes[k].children.is_empty() {
            arena.counts[i]
        } else {
            0
        };
        regions[k] = (at, s);
        at += s;
    }
    progress(0.4)?;
    let rwi = tempfile::tempfile().map_err(|e| CodecError::io("creating the raw index file", e))?;
    rwi.set_len(at * 12)
        .map_err(|e| CodecError::io("sizing the raw index file", e))?;
    // one small buffer per leaf: an input in row order touches every leaf around a ring at
    // once, so their sum, not one of them, is what memory holds: RWI_BUFFERS shared out, and at
    // least 40 entries a leaf (100 k leaves take 48 MB); the fewer writes, the fewer system
    // calls (at 40 entries, one per 36 triangles)
    let leaves = nodes
        .iter()
        .filter(|n| n.children.is_empty())
        .count()
        .max(1);
    let flush = (RWI_BUFFERS / leaves / 12).clamp(40, 1 << 12) * 12;
    let mut buffers: Vec<Vec<u8>> = vec![Vec::new(); nodes.len()];
    let mut written = vec![0u64; nodes.len()];
    let mut failure: Option<std::io::Error> = None;
    {
        let mut put = |leaf: usize, e: [u32; 3]| {
            let b = &mut buffers[leaf];
            if b.capacity() == 0 {
                b.reserve_exact(flush);
            }
            for x in e {
                b.extend_from_slice(&x.to_le_bytes());
            }
            if b.len() >= flush {
                let off = (regions[leaf].0 + written[leaf]) * 12;
                if let Err(e) = positional_io::write_all_at(&rwi, b, off) {
                    failure.get_or_insert(e);
                }
                written[leaf] += (b.len() / 12) as u64;
                b.clear();
            }
        };
        if !nodes.is_empty() {
            // a vertex's leaf remembered by its index's low bits: an input's triangles come
            // near their vertices' others (about six a vertex), each found again here
            let mut memo = vec![(u32::MAX, 0u32); 1 << 16];
            triangles_beside(src, &mut |t| {
                let leaves = t.map(|x| {
                    let e = &mut memo[x as usize & 0xFFFF];
                    if e.0 != x {
                        *e = (x, leaf_of(points.get(x)) as u32);
                    }
                    e.1 as usize
                });
                for leaf in distinct3(leaves) {
                    put(leaf, t);
                }
            })?;
            for &i in &isolated {
                put(leaf_of(points.get(i)), [i, POINT_MARK, POINT_MARK]);
            }
        }
    }
    for (leaf, b) in buffers.iter().enumerate() {
        if !b.is_empty() {
            let off = (regions[leaf].0 + written[leaf]) * 12;
            if let Err(e) = positional_io::write_all_at(&rwi, b, off) {
                failure.get_or_insert(e);
            }
        }
    }
    if let Some(e) = failure {
        return Err(CodecError::io("writing the raw index file", e));
    }
    progress(0.5)?;
    Ok(Partition {
        grid,
        points,
        nodes,
        regions,
        rwi,
        input_vertices: n,
        input_triangles: triangles,
        referenced,
    })
}

/// Whether a cell whose split would make `nonempty` children holding `sum` simplices in all
/// (border simplices counted in each child they touch) is split: only when those children hold
/// on average at least `N_min / CHILD_SHARE` simplices. A split into tiny cells costs bits (every
/// border vertex is refined again in each child holding one of its simplices: 2.3 b/v on the
/// bunny at `N_min` = 8 000) and buys little memory; a cell holding `N_min` or more whose children
/// would be tiny stays a leaf, so a leaf holds fewer than `n³ · N_min / CHILD_SHARE` simplices
/// (the out-of-core bound) unless it is at full precision.
pub fn worth_splitting(params: &Params, sum: u64, nonempty: u64) -> bool {
    sum >= nonempty * (params.min_cell / CHILD_SHARE).max(1)
}

/// `N_min` over the fewest simplices a split's children must hold on average. Measured at 12
/// bits with `N_min` = 50 000 (issue 34 item 2): the bunny 43 cells -> 1 (the bare `N_min` rule
/// splits its 70 564-simplex root into 42 children of 1 700 on average), the 1.1 M-triangle torus
/// 318 -> 33 cells, 12.81 -> 12.09 b/v; 4 gives the same trees on the shared meshes.
pub const CHILD_SHARE: u64 = 8;

/// Adds the simplex whose vertices are at grid points `grid` to the counts of the cells at
/// `depth + 1` it belongs to (each once) whose parent is in `parents` (every cell when `None`);
/// returns how many cells it added.
fn count_children(
    params: &Params,
    depth: u32,
    parents: Option<&FxHashMap<u64, usize>>,
    grid: &[[u32; 3]],
    counts: &mut Counts,
) -> u64 {
    let mut cells = [[0u32; 3]; 3];
    let mut added = 0;
    for (k, &q) in grid.iter().enumerate() {
        let c = params.cell_at(depth + 1, q);
        cells[k] = c;
        if cells[..k].contains(&c) {
            continue;
        }
        if parents.is_none_or(|p| p.contains_key(&code(c.map(|x| x >> params.level_bits())))) {
            added += counts.add(code(c));
        }
    }
    added
}

/// Simplices per cell [`code`], counted through a small direct-mapped cache in front of the
/// hash map: consecutive triangles of a file mostly fall in the cells of the last few, and at
/// 200 M triangles the counting pass's maps (millions of cells) missed the processor's caches at
/// nearly every count (50 s of the pass, of ~11 s reading). The counts are the same; the map
/// holds a cell only once the cache lets it go, or [`Counts::settle`] empties the cache.
struct Counts {
    map: FxHashMap<u64, u64>,
    /// `(code, count not yet in the map)`; `u64::MAX`: empty.
    cache: Vec<(u64, u64)>,
}

/// Entries of a [`Counts`] cache (16 bytes each).
const COUNT_CACHE: usize = 1 << 11;

impl Counts {
    fn new() -> Self {
        Counts::of(FxHashMap::default())
    }

    /// Counts starting from `map`.
    fn of(map: FxHashMap<u64, u64>) -> Self {
        Counts {
            map,
            cache: vec![(u64::MAX, 0); COUNT_CACHE],
        }
    }

    /// Counts one simplex in cell `code`; returns how many cells the map gained (0 or 1).
    #[inline]
    fn add(&mut self, code: u64) -> u64 {
        let slot = (code.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 53) as usize & (COUNT_CACHE - 1);
        let e = &mut self.cache[slot];
        if e.0 == code {
            e.1 += 1;
            return 0;
        }
        let (old, n) = std::mem::replace(e, (code, 1));
        if old == u64::MAX {
            return 0;
        }
        Counts::put(&mut self.map, old, n)
    }

    fn put(map: &mut FxHashMap<u64, u64>, code: u64, n: u64) -> u64 {
        let e = map.entry(code).or_insert(0);
        let new = (*e == 0) as u64;
        *e += n;
        new
    }

    /// Moves the cache's counts into the map; returns how many cells it gained.
    fn settle(&mut self) -> u64 {
        let mut added = 0;
        for e in &mut self.cache {
            if e.0 != u64::MAX {
                added += Counts::put(&mut self.map, e.0, e.1);
                *e = (u64::MAX, 0);
            }
        }
        added
    }

    /// Cells in the map (all cells counted, after [`Counts::settle`]).
    fn len(&self) -> usize {
        self.map.len()
    }

    /// The counts, the cache settled.
    fn into_map(mut self) -> FxHashMap<u64, u64> {
        self.settle();
        self.map
    }
}

/// The cell coordinates of a [`code`].
fn uncode(c: u64) -> [u32; 3] {
    [
        (c & 0x1f_ffff) as u32,
        ((c >> 21) & 0x1f_ffff) as u32,
        (c >> 42) as u32,
    ]
}

/// Position of `node` among its parent's children.
fn position(params: &Params, node: &Node) -> usize {
    let n = params.cell_split;
    let l = node.cell.map(|x| x % n);
    (l[0] + n * (l[1] + n * l[2])) as usize
}
