//! The ray caster's seed boxes ([`crate::ray_cast`]): the paper bounds its patches by their
//! control polygons' convex hulls; faces here are any of eight surface kinds, so each face's
//! patch is cut into a grid of seed cells (8 × 8, more along a direction in which the normal
//! turns a lot), each with a world box of sampled surface points inflated by a bound of the
//! surface's bulge between samples. A ray runs Newton from the centre of every cell whose box
//! it crosses, inside every face box it crosses.
//!
//! Built once per part on the CPU with the rest of the scene
//! ([`BrepScene::ray_seeds`](crate::brep_scene::BrepScene::ray_seeds), by [`face_seeds`]) and
//! uploaded on the first ray cast
//! ([`GpuBrepScene::ray_seeds`](crate::GpuBrepScene::ray_seeds)). They are scene data, kept
//! below both the scene and the pass that binds them.

use crate::camera::Vec3;
use crate::newton::{NEWTON_STEPS, NEWTON_TOLERANCE};
use bytemuck::{Pod, Zeroable};
use tessd_brep::{Curve, Curve3, Face, Surface};

/// Seed cells along a patch direction: at least this many…
const MIN_CELLS: usize = 8;
/// … at most this many…
const MAX_CELLS: usize = 96;
/// … and one per this much turning of the normal (radians) along the direction.
const TURN_PER_CELL: f64 = std::f64::consts::PI / 8.0;
/// Surface samples per seed cell side when building the cell boxes.
const SAMPLES_PER_CELL: usize = 4;

/// A world box relative to the scene origin (`SeedBox` in `ray_cast.wgsl`, 32 bytes): the
/// scene's face boxes first (`a` = their first cell's index, `b` = cells along s | cells along
/// t << 16), then every face's cells, row by row, s fastest (`a` = the face, `b` = the cell's
/// column | row << 16; [`face_seeds`] leaves them 0 and [`crate::BrepScene`] sets them).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SeedBox {
    /// Lower corner.
    pub lo: [f32; 3],
    /// Face box: index of its first cell.
    pub a: u32,
    /// Upper corner.
    pub hi: [f32; 3],
    /// Face box: cells along s in the low 16 bits, along t in the high ones.
    pub b: u32,
}

/// The most loop iterations one evaluation of `surface` costs in `shaders/surface_eval.wgsl`:
/// none for the analytic surfaces; for a B-spline the knot search, the Cox–de Boor triangle
/// and derivative loop of each basis, and the pole loops.
fn eval_loops(surface: &Surface) -> u32 {
    fn basis(p: usize, knots: usize) -> u32 {
        let p = p as u32;
        // Bisection, the triangle j = 1..=p with r < j, the derivatives and copies.
        (usize::BITS - knots.leading_zeros()) + p * (p + 1) / 2 + 3 * (p + 1) + 2
    }
    fn curve(c: &Curve3) -> u32 {
        match c {
            Curve::Bspline(b) => {
                let flat = b.mults.iter().map(|&m| m as usize).sum();
                basis(b.degree, flat) + b.degree as u32 + 1
            }
            _ => 0,
        }
    }
    match surface {
        Surface::Revolution { curve: c, .. } | Surface::Extrusion { curve: c, .. } => curve(c),
        Surface::Bspline(b) => {
            let sum = |m: &[u32]| m.iter().map(|&x| x as usize).sum::<usize>();
            let (fu, fv) = (sum(&b.mults_u), sum(&b.mults_v));
            basis(b.degree_u, fu)
                + basis(b.degree_v, fv)
                + (b.degree_u as u32 + 1) * (b.degree_v as u32 + 1)
        }
        _ => 0,
    }
}

/// The most loop iterations one seed cell of a face with basis surface `surface` costs in
/// the search: Newton's steps, each an evaluation, and the trim walk of the hit.
pub fn cell_cost(surface: &Surface) -> u32 {
    NEWTON_STEPS * (1 + eval_loops(surface)) + 32
}

/// The ray caster's seed boxes of a part: one box per face first (document order; a skipped
/// face's is empty, no cells), then every face's seed cells; and per face the worst-case loop
/// iterations of one of its cells ([`cell_cost`]), by which the work is batched.
pub struct RaySeeds {
    /// The boxes.
    pub boxes: Vec<SeedBox>,
    /// Per face, the loop cost of one seed cell.
    pub cell_costs: Vec<u32>,
}

impl RaySeeds {
    /// The seeds of `faces` (the part's, in document order) relative to `origin`, `built[f]`
    /// saying whether face `f` is drawn at all; boxes are inflated by Newton's tolerance (that
    /// of object filling, relative to the box `diagonal`) and a hair.
    pub fn new(faces: &[Face], built: &[bool], origin: [f64; 3], diagonal: f64) -> RaySeeds {
        let margin = (NEWTON_TOLERANCE + 1e-6) * diagonal.max(f64::MIN_POSITIVE);
        let first_cell = faces.len() as u32;
        let mut boxes = Vec::with_capacity(faces.len());
        let mut cells = Vec::new();
        for (f, face) in faces.iter().enumerate() {
            let (ns, nt, mut face_cells) = if built.get(f).copied().unwrap_or(false) {
                face_seeds(face, origin, margin)
            } else {
                (0, 0, Vec::new())
            };
            let first = first_cell + cells.len() as u32;
            // A cell knows its face and its (column, row): the search visits cells alone.
            for (k, c) in face_cells.iter_mut().enumerate() {
                c.a = f as u32;
                c.b = (k % ns.max(1)) as u32 | ((k / ns.max(1)) as u32) << 16;
            }
            boxes.push(face_box(&face_cells, first, ns, nt));
            cells.extend(face_cells);
        }
        boxes.extend(cells);
        RaySeeds {
            boxes,
            cell_costs: faces.iter().map(|f| cell_cost(&f.surface)).collect(),
        }
    }

    /// Seed cells in all (the boxes past the per-face ones).
    pub fn cells(&self) -> usize {
        self.boxes.len() - self.cell_costs.len()
    }
}

/// The face box of a face's seed `cells` (`ns × nt` of them, the first at index `first` of
/// the seed array): their union, empty (and never crossed) without cells.
fn face_box(cells: &[SeedBox], first: u32, ns: usize, nt: usize) -> SeedBox {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for c in cells {
        for k in 0..3 {
            lo[k] = lo[k].min(c.lo[k]);
            hi[k] = hi[k].max(c.hi[k]);
        }
    }
    SeedBox {
        lo,
        a: first,
        hi,
        b: ns as u32 | (nt as u32) << 16,
    }
}

/// The seed cells of one face: cells along s and t and their boxes (relative to `origin`);
/// no cells when the surface does not evaluate to finite points.
pub fn face_seeds(face: &Face, origin: [f64; 3], margin: f64) -> (usize, usize, Vec<SeedBox>) {
    let [u0, u1, v0, v1] = face.bounds;
    let uv = |s: f64, t: f64| (u0 + s * (u1 - u0), v0 + t * (v1 - v0));
    // How far the normal turns along s and along t (the most over a few lines).
    const PROBE: usize = 64;
    let normal = |s: f64, t: f64| {
        let (u, v) = uv(s, t);
        face.surface.eval(u, v).normal()
    };
    let angle = |a: Option<Vec3>, b: Option<Vec3>| match (a, b) {
        (Some(a), Some(b)) => a.dot(b).clamp(-1.0, 1.0).acos(),
        _ => 0.0,
    };
    let (mut turn_s, mut turn_t) = (0.0f64, 0.0f64);
    for line in 0..=4 {
        let c = line as f64 / 4.0;
        let (mut ts, mut tt) = (0.0, 0.0);
        for k in 0..PROBE {
            let (a, b) = (k as f64 / PROBE as f64, (k + 1) as f64 / PROBE as f64);
            ts += angle(normal(a, c), normal(b, c));
            tt += angle(normal(c, a), normal(c, b));
        }
        turn_s = turn_s.max(ts);
        turn_t = turn_t.max(tt);
    }
    let cells = |turn: f64| ((turn / TURN_PER_CELL).ceil() as usize).clamp(MIN_CELLS, MAX_CELLS);
    let (ns, nt) = (cells(turn_s), cells(turn_t));
    // Samples on a grid SAMPLES_PER_CELL times finer than the cells.
    let (gs, gt) = (ns * SAMPLES_PER_CELL, nt * SAMPLES_PER_CELL);
    let mut p = Vec::with_capacity((gs + 1) * (gt + 1));
    for j in 0..=gt {
        for i in 0..=gs {
            let (u, v) = uv(i as f64 / gs as f64, j as f64 / gt as f64);
            let q = face.surface.point(u, v);
            p.push([0, 1, 2].map(|k| q[k] - origin[k]));
        }
    }
    if p.iter().flatten().any(|x| !x.is_finite()) {
        return (0, 0, Vec::new());
    }
    let at = |i: usize, j: usize| p[j * (gs + 1) + i];
    let second = |a: [f64; 3], m: [f64; 3], b: [f64; 3]| {
        let d = [0, 1, 2].map(|k| a[k] - 2.0 * m[k] + b[k]);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    };
    let mut boxes = Vec::with_capacity(ns * nt);
    for cj in 0..nt {
        for ci in 0..ns {
            let (i0, j0) = (ci * SAMPLES_PER_CELL, cj * SAMPLES_PER_CELL);
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            // The largest second differences along s and t around the cell: the surface
            // strays from the bilinear patch of four samples by about an eighth of their sum.
            let mut bulge = 0.0f64;
            for j in j0..=j0 + SAMPLES_PER_CELL {
                for i in i0..=i0 + SAMPLES_PER_CELL {
                    let q = at(i, j);
                    for k in 0..3 {
                        lo[k] = lo[k].min(q[k]);
                        hi[k] = hi[k].max(q[k]);
                    }
                    let (ia, ib) = (i.saturating_sub(1), (i + 1).min(gs));
                    let (ja, jb) = (j.saturating_sub(1), (j + 1).min(gt));
                    let ds = if ib - ia == 2 {
                        second(at(ia, j), q, at(ib, j))
                    } else {
                        0.0
                    };
                    let dt = if jb - ja == 2 {
                        second(at(i, ja), q, at(i, jb))
                    } else {
                        0.0
                    };
                    bulge = bulge.max(ds + dt);
                }
            }
            // Four times the estimate, for curvature that grows within the cell.
            let pad = 0.5 * bulge + margin;
            boxes.push(SeedBox {
                lo: lo.map(|x| (x - pad) as f32),
                a: 0,
                hi: hi.map(|x| (x + pad) as f32),
                b: 0,
            });
        }
    }
    (ns, nt, boxes)
}
