//! The trim quadtree over the normalised (u, v) domain (paper 000, section 4): cells are
//! split 2 × 2 until each leaf is fully on the face, fully off, or crossed by at most two
//! curves — two only with a separating line (section 5.2, [`crate::separate`]). Subdivision
//! stops at depth [`MAX_DEPTH`] = 13; the leaves still violating the rule there are *failures*,
//! counted as in table 4, and answer with their coverage bit. Coverage is computed bottom up
//! (sections 4 and 5.3): a leaf's fraction on the face (1, 0, or sampled on a grid), a node's
//! the mean of its children's; the bit is fraction ≥ ½. Finally the level `k_i` of section 6:
//! the shallowest level at which at least 40 % of the domain is covered by tessellation
//! triangles (t_u = t_v = 2^k, cells split along their diagonal) that classify whole.
//!
//! One guard goes beyond the paper's text: the one-curve rule of section 5.1 is exact only
//! on the arc; its region is closed by the curve's end tangents, extended as rays. A leaf is
//! therefore also split when such a ray from outside re-enters the cell (a strongly curved
//! piece), and a separating line is accepted only when each curve's rays starting in the
//! cell (junctions) lead away from that curve's side — otherwise, at a corner where a trim
//! meets a seam line, the seam's extension would decide points that belong to the other
//! curve.

use crate::bezier::Quadratic;
use crate::classify::{leaf_point, leaf_triangle};
use crate::implicit::{Implicit, ImplicitKind};
use crate::separate::{Ray, separating_line};
use crate::trim_source::{NodeKind, NodeRecord, TrimSource, curve_ref, ref_index};
use crate::winding::WindingIndex;

/// The depth at which subdivision gives up (section 8, table 4).
pub const MAX_DEPTH: u32 = 13;

/// The share of the domain that must be classifiable at level k_i (section 6).
pub const K_FRACTION: f64 = 0.4;

/// Samples per side when estimating a curve leaf's coverage.
const COVERAGE_GRID: usize = 4;

/// At most this many levels of triangles below a leaf are tested for k_i; finer levels
/// reuse the coarser triangles' verdicts (an approximation on large leaves).
const TRIANGLE_LEVELS: u32 = 3;

/// No index.
pub const NONE: u32 = u32::MAX;

/// A quadtree node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// What it is.
    pub kind: NodeKind,
    /// Its depth (the root is 0).
    pub depth: u32,
    /// The normalised coordinates of its lower-left corner; its side is 2^−depth.
    pub origin: [f64; 2],
    /// The first child (internal nodes), or [`NONE`].
    pub first_child: u32,
    /// The crossing curves (leaves), [`NONE`] where absent.
    pub curves: [u32; 2],
    /// The separating line (two-curve leaves), or [`NONE`].
    pub line: u32,
    /// How many curves cross a failed leaf.
    pub crossing: u32,
    /// The fraction of the cell on the face.
    pub coverage: f64,
    /// The coverage bit: `coverage ≥ ½`.
    pub covered: bool,
}

impl Node {
    /// The side length, normalised.
    pub fn size(&self) -> f64 {
        (0.5f64).powi(self.depth as i32)
    }

    /// The node's square `[u0, u1, v0, v1]` widened by 1e-9 of its side: the rectangle curves
    /// are clipped to, so that a curve along a cell side counts in both neighbours.
    pub fn clip_rect(&self) -> [f64; 4] {
        let h = self.size();
        let m = 1e-9 * h;
        [
            self.origin[0] - m,
            self.origin[0] + h + m,
            self.origin[1] - m,
            self.origin[1] + h + m,
        ]
    }
}

/// The quadtree of one face, in coordinates normalised to its domain.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadtree {
    /// `[u0, u1, v0, v1]`: the (u, v) rectangle of the root.
    pub domain: [f64; 4],
    /// The curves, normalised.
    pub curves: Vec<Quadratic>,
    /// Their implicit forms.
    pub implicits: Vec<Implicit>,
    /// The separating lines, `a s + b t + c ≥ 0` on the first curve's side.
    pub lines: Vec<[f32; 3]>,
    /// The nodes, breadth first; children consecutive.
    pub nodes: Vec<Node>,
    /// Failed leaves (table 4).
    pub failures: u32,
    /// Leaves per depth, index = depth.
    pub leaves_per_depth: Vec<u32>,
    /// The level of section 6, or `None` when no level reaches 40 %.
    pub k_i: Option<u32>,
    /// The share of the domain classifiable by triangles at each level 0 ..= k_i (or all
    /// levels tried).
    pub classifiable: Vec<f64>,
    /// The winding number of the root's rectangle before any curve counts: 1 when the
    /// face's outer loop was the rectangle itself and left out
    /// ([`crate::patch_boundary`]), else 0. A point is on the face where this plus its
    /// winding number about the curves is positive.
    pub base_winding: i32,
}

impl TrimSource for Quadtree {
    fn domain(&self) -> [f64; 4] {
        self.domain
    }

    fn node(&self, i: u32) -> NodeRecord {
        let n = &self.nodes[i as usize];
        let r = |c: u32| {
            if c == NONE {
                NONE
            } else {
                curve_ref(c, self.implicits[c as usize].kind)
            }
        };
        NodeRecord {
            kind: n.kind,
            covered: n.covered,
            a: if n.kind == NodeKind::Internal {
                n.first_child
            } else {
                r(n.curves[0])
            },
            b: r(n.curves[1]),
            line: n.line,
        }
    }

    fn implicit(&self, r: u32) -> Implicit {
        self.implicits[ref_index(r) as usize]
    }

    fn line(&self, i: u32) -> [f32; 3] {
        self.lines[i as usize]
    }
}

impl Quadtree {
    /// Builds the tree over `curves` (closed loops in normalised coordinates, material on
    /// their left), the root covering `domain` in (u, v); `base_winding` is
    /// [`Quadtree::base_winding`].
    pub fn build(domain: [f64; 4], curves: Vec<Quadratic>, base_winding: i32) -> Quadtree {
        let implicits = curves.iter().map(Implicit::of).collect();
        let mut tree = Quadtree {
            domain,
            curves,
            implicits,
            lines: Vec::new(),
            nodes: Vec::new(),
            failures: 0,
            leaves_per_depth: vec![0; MAX_DEPTH as usize + 1],
            k_i: None,
            classifiable: Vec::new(),
            base_winding,
        };
        tree.subdivide();
        tree.coverage();
        tree.level_for_triangles();
        tree
    }

    fn subdivide(&mut self) {
        let blank = Node {
            kind: NodeKind::Internal,
            depth: 0,
            origin: [0.0, 0.0],
            first_child: NONE,
            curves: [NONE; 2],
            line: NONE,
            crossing: 0,
            coverage: 0.0,
            covered: false,
        };
        self.nodes.push(blank);
        let mut candidates: Vec<Vec<u32>> = vec![(0..self.curves.len() as u32).collect()];
        let index = WindingIndex::new(&self.curves);
        let mut i = 0;
        while i < self.nodes.len() {
            let node = self.nodes[i];
            let h = node.size();
            let rect = node.clip_rect();
            let mine = std::mem::take(&mut candidates[i]);
            let crossing: Vec<(u32, [f64; 2])> = mine
                .iter()
                .filter_map(|&c| self.curves[c as usize].clip(rect).map(|r| (c, r)))
                .collect();
            let mut split = false;
            match crossing.len() {
                0 => {
                    let c = [node.origin[0] + h / 2.0, node.origin[1] + h / 2.0];
                    self.nodes[i].kind = if self.base_winding + index.winding(c[0], c[1]) > 0 {
                        NodeKind::On
                    } else {
                        NodeKind::Off
                    };
                }
                1 if self.rule_fits(crossing[0].0, rect) => {
                    self.nodes[i].kind = NodeKind::One;
                    self.nodes[i].curves = [crossing[0].0, NONE];
                }
                1 => split = true,
                2 if !(self.rule_fits(crossing[0].0, rect)
                    && self.rule_fits(crossing[1].0, rect)) =>
                {
                    split = true
                }
                2 => {
                    let (a, ra) = crossing[0];
                    let (b, rb) = crossing[1];
                    match separating_line(
                        &self.curves[a as usize],
                        ra,
                        &self.rays_inside(a, rect),
                        &self.curves[b as usize],
                        rb,
                        &self.rays_inside(b, rect),
                        h,
                    ) {
                        Some(l) => {
                            self.nodes[i].kind = NodeKind::Two;
                            self.nodes[i].curves = [a, b];
                            self.nodes[i].line = self.lines.len() as u32;
                            self.lines.push(l.map(|x| x as f32));
                        }
                        None => split = true,
                    }
                }
                _ => split = true,
            }
            if split {
                if node.depth >= MAX_DEPTH {
                    self.nodes[i].kind = NodeKind::Failed;
                    self.nodes[i].crossing = crossing.len() as u32;
                    self.failures += 1;
                } else {
                    self.nodes[i].first_child = self.nodes.len() as u32;
                    let ids: Vec<u32> = crossing.iter().map(|c| c.0).collect();
                    for k in 0..4 {
                        let mut child = blank;
                        child.depth = node.depth + 1;
                        child.origin = [
                            node.origin[0] + if k & 1 == 1 { h / 2.0 } else { 0.0 },
                            node.origin[1] + if k & 2 == 2 { h / 2.0 } else { 0.0 },
                        ];
                        self.nodes.push(child);
                        candidates.push(ids.clone());
                    }
                }
            }
            if self.nodes[i].kind != NodeKind::Internal {
                self.leaves_per_depth[node.depth as usize] += 1;
            }
            i += 1;
        }
    }

    /// Whether curve `c`'s classification rule (section 5.1) holds in the cell `rect`: the
    /// rule's region is bounded by the arc *and its two end tangents* extended as rays (a
    /// line's, by the whole line), so a ray that comes back into the cell — a strongly curved
    /// piece whose end lies outside — would misclassify part of it; such cells are split
    /// further. A ray starting inside the cell (a junction) is fine.
    fn rule_fits(&self, c: u32, rect: [f64; 4]) -> bool {
        self.rays(c).iter().all(|&(o, d)| !ray_hits(o, d, rect))
    }

    /// The end-tangent rays bounding curve `c`'s rule region: backwards from p0, forwards
    /// from p2.
    fn rays(&self, c: u32) -> [Ray; 2] {
        let [p0, p1, p2] = self.curves[c as usize].p;
        let sub = |a: [f64; 2], b: [f64; 2]| [a[0] - b[0], a[1] - b[1]];
        if self.implicits[c as usize].kind == ImplicitKind::Line {
            [(p0, sub(p0, p2)), (p2, sub(p2, p0))]
        } else {
            [(p0, sub(p0, p1)), (p2, sub(p2, p1))]
        }
    }

    /// The rays of curve `c` that start inside `rect`.
    fn rays_inside(&self, c: u32, rect: [f64; 4]) -> Vec<Ray> {
        let inside =
            |o: [f64; 2]| o[0] >= rect[0] && o[0] <= rect[1] && o[1] >= rect[2] && o[1] <= rect[3];
        self.rays(c).into_iter().filter(|r| inside(r.0)).collect()
    }

    fn coverage(&mut self) {
        let g = COVERAGE_GRID;
        let index = WindingIndex::new(&self.curves);
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            let h = node.size();
            let fraction = match node.kind {
                NodeKind::On => 1.0,
                NodeKind::Off => 0.0,
                NodeKind::Internal => {
                    let c = node.first_child as usize;
                    self.nodes[c..c + 4].iter().map(|n| n.coverage).sum::<f64>() / 4.0
                }
                NodeKind::One | NodeKind::Two | NodeKind::Failed => {
                    let rec = self.node(i as u32);
                    let mut on = 0;
                    for a in 0..g {
                        for b in 0..g {
                            let s = node.origin[0] + h * (a as f64 + 0.5) / g as f64;
                            let t = node.origin[1] + h * (b as f64 + 0.5) / g as f64;
                            let inside = if node.kind == NodeKind::Failed {
                                self.base_winding + index.winding(s, t) > 0
                            } else {
                                leaf_point(self, &rec, s, t)
                            };
                            on += usize::from(inside);
                        }
                    }
                    on as f64 / (g * g) as f64
                }
            };
            self.nodes[i].coverage = fraction;
            self.nodes[i].covered = fraction >= 0.5;
        }
    }

    /// The share of the domain whose level-k tessellation triangles classify whole.
    pub fn classifiable_at(&self, k: u32) -> f64 {
        let mut area = 0.0;
        for (i, node) in self.nodes.iter().enumerate() {
            if node.kind == NodeKind::Internal || node.depth > k {
                continue;
            }
            let h = node.size();
            match node.kind {
                NodeKind::On | NodeKind::Off => area += h * h,
                NodeKind::One | NodeKind::Two => {
                    let rec = self.node(i as u32);
                    let levels = (k - node.depth).min(TRIANGLE_LEVELS);
                    let cells = 1usize << levels;
                    let c = h / cells as f64;
                    for a in 0..cells {
                        for b in 0..cells {
                            let s0 = node.origin[0] + a as f64 * c;
                            let t0 = node.origin[1] + b as f64 * c;
                            let (s1, t1) = (s0 + c, t0 + c);
                            let lower = [[s0, t0], [s1, t0], [s1, t1]];
                            let upper = [[s0, t0], [s1, t1], [s0, t1]];
                            for tri in [lower, upper] {
                                if leaf_triangle(self, &rec, &tri).is_some() {
                                    area += c * c / 2.0;
                                }
                            }
                        }
                    }
                }
                NodeKind::Internal | NodeKind::Failed => {}
            }
        }
        area
    }

    fn level_for_triangles(&mut self) {
        let deepest = self
            .leaves_per_depth
            .iter()
            .rposition(|&n| n > 0)
            .unwrap_or(0) as u32;
        // Below the deepest leaf the level-k triangles still subdivide the leaves (up to
        // TRIANGLE_LEVELS), so a shallow tree may reach the 40 % there: search that far too.
        for k in 0..=(deepest + TRIANGLE_LEVELS).min(MAX_DEPTH) {
            let f = self.classifiable_at(k);
            self.classifiable.push(f);
            if f >= K_FRACTION {
                self.k_i = Some(k);
                return;
            }
        }
    }
}

/// Whether the ray `o + t d`, t > 0, meets the rectangle `[u0, u1, v0, v1]`; false for an
/// origin inside it (see `rule_fits`).
fn ray_hits(o: [f64; 2], d: [f64; 2], r: [f64; 4]) -> bool {
    if o[0] >= r[0] && o[0] <= r[1] && o[1] >= r[2] && o[1] <= r[3] {
        return false;
    }
    if d[0] == 0.0 && d[1] == 0.0 {
        return false;
    }
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for axis in 0..2 {
        let (a, b) = (r[2 * axis], r[2 * axis + 1]);
        if d[axis] == 0.0 {
            if o[axis] < a || o[axis] > b {
                return false;
            }
        } else {
            let t1 = (a - o[axis]) / d[axis];
            let t2 = (b - o[axis]) / d[axis];
            lo = lo.max(t1.min(t2));
            hi = hi.min(t1.max(t2));
        }
    }
    lo <= hi && hi > 0.0
}
