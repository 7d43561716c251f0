//! View-dependent refinement (paper 003 §6.2–6.3): decode each nSP-cell only as far as the
//! camera needs, skip the cells outside the view, and join cells of different precisions
//! without overlaps or cracks.
//!
//! §6.2: a vertex shown at precision `b` is the centre of its kd-cell, at most half the cell's
//! diagonal (`√3/2 · step · 2^(p−b)`) from the point it stands for. A visible cell is refined
//! until that distance, projected at the cell's distance from the eye, is at most
//! `pixel_error` pixels; a cell that needs more than its last precision hands over to its
//! children. Cells outside the view frustum are not decoded further and not shown.
//!
//! §6.3: a top simplex on a border (a vertex in another displayed cell) is shown by the cell of
//! highest precision among those its vertices lie in (ties: the highest cell index); its
//! vertices that lie in a coarser displayed cell take that cell's representative point, so the
//! coarse side's triangles meet it exactly.
//!
//! [`ViewSession`] keeps every visited cell's decoder state, so that the next camera refines
//! from where the last one stopped instead of from the root (the coarsening direction restarts
//! a cell from its parent's hand-over state).

use std::sync::Arc;

use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};

use crate::ahead::Geometry;
use crate::complex::{Complex, POINT, Vertex};
use crate::decode::{Tsc, root_complex};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::kd_coder::{self, Limits, Span};

/// A perspective camera, the convention of `tessd render`: eye, target, up hint, vertical
/// field of view in degrees, image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, world units.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up hint.
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| a.map(|x| x / n))
}

/// The camera's frame: axes, the frustum's half-angle tangents, the focal length in pixels.
#[derive(Clone, Copy, Debug)]
struct Frame {
    eye: [f64; 3],
    forward: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
    tan_v: f64,
    tan_h: f64,
    focal: f64,
}

impl Frame {
    fn new(c: &Camera) -> Result<Self, CodecError> {
        let bad = |why: &str| CodecError::Parameter {
            name: "camera",
            why: why.to_string(),
        };
        if !(c.fov > 0.0 && c.fov < 180.0) {
            return Err(bad(&format!(
                "--fov {} is not between 0 and 180 degrees",
                c.fov
            )));
        }
        if c.width == 0 || c.height == 0 {
            return Err(bad("--size must be at least 1x1"));
        }
        let forward =
            unit(sub(c.target, c.eye)).ok_or_else(|| bad("--eye and --target coincide"))?;
        let right = unit(cross(forward, c.up))
            .ok_or_else(|| bad("--up is parallel to the view direction"))?;
        let up = cross(right, forward);
        let tan_v = (c.fov.to_radians() / 2.0).tan();
        let tan_h = tan_v * c.width as f64 / c.height as f64;
        Ok(Frame {
            eye: c.eye,
            forward,
            right,
            up,
            tan_v,
            tan_h,
            focal: c.height as f64 / 2.0 / tan_v,
        })
    }

    /// Whether any of the box can be in view: false when all its corners lie outside one
    /// plane of the frustum (conservative).
    fn sees(&self, min: [f64; 3], max: [f64; 3]) -> bool {
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                let c = [
                    if i & 1 == 0 { min[0] } else { max[0] },
                    if i & 2 == 0 { min[1] } else { max[1] },
                    if i & 4 == 0 { min[2] } else { max[2] },
                ];
                let d = sub(c, self.eye);
                [dot(d, self.right), dot(d, self.up), dot(d, self.forward)]
            })
            .collect();
        let outside = |f: &dyn Fn(&[f64; 3]) -> bool| corners.iter().all(f);
        !(outside(&|c| c[2] <= 0.0)
            || outside(&|c| c[0] > c[2] * self.tan_h)
            || outside(&|c| -c[0] > c[2] * self.tan_h)
            || outside(&|c| c[1] > c[2] * self.tan_v)
            || outside(&|c| -c[1] > c[2] * self.tan_v))
    }

    /// Distance from the eye to the box (0 inside).
    fn distance(&self, min: [f64; 3], max: [f64; 3]) -> f64 {
        let d: [f64; 3] =
            std::array::from_fn(|a| (min[a] - self.eye[a]).max(self.eye[a] - max[a]).max(0.0));
        dot(d, d).sqrt()
    }
}

/// A view-dependent decode's result.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ViewMesh {
    /// Vertex positions, world units.
    pub positions: Vec<[f64; 3]>,
    /// Triangles over them (degenerate ones left out).
    pub triangles: Vec<[u32; 3]>,
    /// The displayed cells: (index in the tree, precision in bits).
    pub cells: Vec<(usize, u32)>,
    /// Bytes of code chunks the decoder read for this view (what the session had read for an
    /// earlier view is not counted again; a cell restarted to coarsen counts again).
    pub bytes_read: u64,
    /// Symbols decoded for this view.
    pub symbols: u64,
}

/// One cell's decoder state.
struct CellState {
    /// The complex handed over by the parent (or the root's single vertex), to restart from.
    start: (Complex, Vec<u32>),
    cx: Complex,
    alive: Vec<u32>,
    reader: SymbolReader,
    /// Geometry read ahead of the connectivity (§6.4).
    geometry: Option<Geometry>,
    /// Precision reached, in bits.
    bits: u32,
    /// The children's hand-over complexes, once this cell reached its last precision.
    parts: Option<Vec<(Complex, Vec<u32>)>>,
}

/// A `.tsc` file opened for a moving camera: decoder states kept between views.
pub struct ViewSession {
    tsc: Arc<Tsc>,
    states: FxHashMap<usize, CellState>,
}

impl ViewSession {
    /// A session with nothing decoded yet.
    pub fn new(tsc: Arc<Tsc>) -> Self {
        ViewSession {
            tsc,
            states: FxHashMap::default(),
        }
    }

    /// The file this session decodes.
    pub fn file(&self) -> &Tsc {
        &self.tsc
    }

    /// World box of tree node `i`.
    fn cell_box(&self, i: usize) -> ([f64; 3], [f64; 3]) {
        let node = &self.tsc.nodes[i];
        let side = (1u64 << self.tsc.header.params.side_log2(node.depth)) as f64;
        let grid = &self.tsc.header.grid;
        let lo = node.cell.map(|c| c as f64 * side - 0.5);
        let hi = lo.map(|c| c + side);
        (grid.position(lo), grid.position(hi))
    }

    /// The precision the camera needs in a cell at distance `d` (§6.2).
    fn needed_bits(&self, frame: &Frame, d: f64, pixel_error: f64) -> u32 {
        let p = self.tsc.header.params.bits;
        let step = self.tsc.header.grid.step;
        // half a kd-cell diagonal at precision b: √3/2 · step · 2^(p−b) ≤ pixel_error · d / focal
        let x = pixel_error * d / (frame.focal * step * 3f64.sqrt() / 2.0);
        // below one cell of full precision (or NaN at the eye): full precision
        if x.is_nan() || x < 1.0 {
            return p;
        }
        p.saturating_sub(x.log2().floor().min(p as f64) as u32)
    }

    /// Decodes what `camera` needs within `pixel_error` pixels and returns the mesh to show.
    pub fn view(&mut self, camera: &Camera, pixel_error: f64) -> Result<ViewMesh, CodecError> {
        if !(pixel_error > 0.0 && pixel_error.is_finite()) {
            return Err(CodecError::Parameter {
                name: "--pixel-error",
                why: format!("{pixel_error} is not a positive number of pixels"),
            });
        }
        let frame = Frame::new(camera)?;
        let mut out = ViewMesh::default();
        if self.tsc.nodes.is_empty() {
            return Ok(out);
        }
        let plan = self.plan(&frame, pixel_error);
        // the cells are decoded a tree depth at a time, each depth's cells in parallel (paper
        // 003 §5.4: cells are independent once their parent handed them over); what comes out
        // does not depend on the order, only the counters are summed
        let deepest = plan.iter().map(|v| v.depth).max().unwrap_or(0);
        if !self.states.contains_key(&0) {
            // only the root is created here; children come from their parent's hand-over
            let state = self.tsc.cell_state(0, root_complex(&self.tsc.header))?;
            self.states.insert(0, state);
        }
        for depth in 0..=deepest {
            let visits: Vec<&Visit> = plan.iter().filter(|v| v.depth == depth).collect();
            let mut work: Vec<(&Visit, CellState)> = visits
                .iter()
                .map(|v| {
                    let state = self.states.remove(&v.cell);
                    (*v, state.expect("handed over by its parent"))
                })
                .collect();
            let tsc = &self.tsc;
            let counted: Vec<Result<(u64, u64), CodecError>> = work
                .par_iter_mut()
                .map(|(v, state)| {
                    let counts = refine(tsc, v.cell, state, v.target)?;
                    if v.descend && state.parts.is_none() {
                        state.parts = Some(tsc.partition(v.cell, &state.cx, &state.alive));
                    }
                    Ok(counts)
                })
                .collect();
            for (v, state) in work {
                self.states.insert(v.cell, state);
            }
            // the first failure in the walk's order, whatever thread met it
            for c in counted {
                let (symbols, bytes) = c?;
                out.symbols += symbols;
                out.bytes_read += bytes;
            }
            for v in visits.iter().filter(|v| v.descend) {
                let node = &self.tsc.nodes[v.cell];
                for (k, &child) in node.children.iter().enumerate() {
                    if !self.states.contains_key(&child) {
                        let parts = self.states[&v.cell].parts.as_ref();
                        let part = parts.expect("made above")[k].clone();
                        let state = self.tsc.cell_state(child, part)?;
                        self.states.insert(child, state);
                    }
                }
            }
        }
        let visited: FxHashSet<usize> = plan.iter().map(|v| v.cell).collect();
        let displayed: Vec<(usize, u32)> = plan
            .iter()
            .filter(|v| !v.descend)
            .map(|v| (v.cell, v.target))
            .collect();
        // the cells not visited are coarsened away: their memory is freed
        self.states.retain(|i, _| visited.contains(i));
        self.assemble(&displayed, &mut out);
        out.cells = displayed;
        Ok(out)
    }

    /// The cells `frame` sees, in the order of a depth-first walk of the tree, each with the
    /// precision it needs (§6.2) and whether its children are shown instead: all of it follows
    /// from the camera and the tree, before anything is decoded.
    fn plan(&self, frame: &Frame, pixel_error: f64) -> Vec<Visit> {
        let p = self.tsc.header.params.bits;
        let mut plan = Vec::new();
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let (min, max) = self.cell_box(i);
            if !frame.sees(min, max) {
                continue;
            }
            let node = &self.tsc.nodes[i];
            let leaf = node.children.is_empty();
            let (start, end) = self.tsc.header.params.precision(node.depth);
            let end = if leaf { p } else { end };
            let need = self
                .needed_bits(frame, frame.distance(min, max), pixel_error)
                .max(start);
            let descend = need > end && !leaf;
            plan.push(Visit {
                cell: i,
                depth: node.depth,
                target: need.min(end),
                descend,
            });
            if descend {
                stack.extend(node.children.iter().copied());
            }
        }
        plan
    }

    /// The displayed cells' simplices with the border rule of §6.3, welded into one mesh.
    fn assemble(&self, displayed: &[(usize, u32)], out: &mut ViewMesh) {
        let params = &self.tsc.header.params;
        let p = params.bits;
        let grid = &self.tsc.header.grid;
        let precision: FxHashMap<usize, u32> = displayed.iter().copied().collect();
        // vertex maps of the displayed cells: corner at the cell's level → vertex
        let maps: FxHashMap<usize, FxHashMap<[u32; 3], u32>> = displayed
            .iter()
            .map(|&(i, _)| {
                let cx = &self.states[&i].cx;
                let m = self.states[&i]
                    .alive
                    .iter()
                    .map(|&v| (cx.vertices[v as usize].corner, v))
                    .collect();
                (i, m)
            })
            .collect();
        // the displayed cell holding a grid point, walking down the tree
        let owner = |q: [u32; 3]| -> Option<usize> {
            let i = self.tsc.descend(q, |i| precision.contains_key(&i));
            precision.contains_key(&i).then_some(i)
        };
        let mut ids: FxHashMap<(usize, [u32; 3]), u32> = FxHashMap::default();
        for &(c, pc) in displayed {
            let state = &self.states[&c];
            let cx = &state.cx;
            'simplex: for s in cx.live_simplices() {
                if s.kind == POINT {
                    continue;
                }
                let mut corners = [[0u32; 3]; 3];
                let mut owners = [c; 3];
                for k in 0..3 {
                    let vx = cx.vertices[s.v[k] as usize];
                    corners[k] = vx.corner;
                    let ci = owner(vx.corner).unwrap_or(c);
                    let pi = precision.get(&ci).copied().unwrap_or(pc);
                    if pi > pc || (pi == pc && ci > c) {
                        continue 'simplex;
                    }
                    owners[k] = ci;
                }
                let mut tri = [0u32; 3];
                for k in 0..3 {
                    let ci = owners[k];
                    // a vertex in another displayed cell (as coarse or coarser) takes that
                    // cell's kd-cell holding it
                    let level = 3 * precision[&ci] as usize;
                    let (owner_cell, vx) = match maps[&ci].get(&truncate(corners[k], level, p)) {
                        Some(&v) if ci != c => (ci, self.states[&ci].cx.vertices[v as usize]),
                        _ => (c, cx.vertices[s.v[k] as usize]),
                    };
                    tri[k] = *ids.entry((owner_cell, vx.corner)).or_insert_with(|| {
                        let at = match &self.states[&owner_cell].geometry {
                            Some(g) => g.position(&vx, p),
                            None => vx.centre(p),
                        };
                        out.positions.push(grid.position(at));
                        (out.positions.len() - 1) as u32
                    });
                }
                if tri[0] != tri[1] && tri[1] != tri[2] && tri[2] != tri[0] {
                    out.triangles.push(tri);
                }
            }
        }
    }
}

/// One cell of a view's walk.
struct Visit {
    cell: usize,
    depth: u32,
    /// Precision to decode it to, in bits.
    target: u32,
    /// Its children are shown instead of it.
    descend: bool,
}

/// Brings cell `i`'s `state` to `bits` bits: onwards from where it is, or from its start when
/// it must coarsen. Returns the symbols and the code bytes read.
fn refine(tsc: &Tsc, i: usize, state: &mut CellState, bits: u32) -> Result<(u64, u64), CodecError> {
    if bits < state.bits {
        *state = tsc.cell_state(i, state.start.clone())?;
    }
    if bits <= state.bits {
        return Ok((0, 0));
    }
    let node = &tsc.nodes[i];
    let before = state.reader.read;
    let bytes_before = if before == 0 {
        0
    } else {
        state.reader.consumed_bytes()
    };
    let limits = Limits {
        vertices: node.end_vertices as usize,
        simplices: node.end_simplices as usize,
    };
    let params = &tsc.header.params;
    let end = if node.children.is_empty() {
        params.bits
    } else {
        params.precision(node.depth).1
    };
    let span = Span {
        bits: params.bits,
        lo: 3 * state.bits as usize,
        hi: 3 * bits as usize,
        end: 3 * end as usize,
        advance: params.advance(),
    };
    kd_coder::decode(
        &mut state.cx,
        &mut state.alive,
        span,
        &mut state.reader,
        limits,
        &mut state.geometry,
    )?;
    state.bits = bits;
    let bytes = state.reader.consumed_bytes().min(node.len) - bytes_before.min(node.len);
    Ok((state.reader.read - before, bytes))
}

/// `corner` cleared below kd `level`: the corner of the kd-cell at that level holding it.
fn truncate(corner: [u32; 3], level: usize, bits: u32) -> [u32; 3] {
    let v = Vertex {
        corner,
        level: level as u8,
    };
    std::array::from_fn(|a| {
        let e = v.extent(a, bits) as u32;
        corner[a] & !(e - 1)
    })
}

impl Tsc {
    /// A fresh decoder state of cell `i` from its hand-over complex.
    fn cell_state(&self, i: usize, start: (Complex, Vec<u32>)) -> Result<CellState, CodecError> {
        let node = &self.nodes[i];
        let reader = self.reader(i)?;
        Ok(CellState {
            cx: start.0.clone(),
            alive: start.1.clone(),
            start,
            reader,
            geometry: None,
            bits: self.header.params.precision(node.depth).0,
            parts: None,
        })
    }
}
