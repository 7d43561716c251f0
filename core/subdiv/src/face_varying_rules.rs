//! The face-varying value rules of one refinement level, by OpenSubdiv's face-varying rules
//! (`Vtr::FVarLevel`), and the option that selects them ([`UvInterpolation`], Blender's
//! `uv_smooth`). [`crate::face_varying`] runs them level after level for a whole channel.
//!
//! A face-varying channel has its own topology: one value index per face corner. Around a
//! vertex, the corners that share a value form that value's *span*; a vertex with several
//! values sits on a *seam*, and a seam edge (different values on its two sides, at either end)
//! is a boundary of the UV topology. Each level is refined like the vertices, with one value per
//! child vertex and sibling values where seams split them:
//!
//! - face point: the centroid of the face's values;
//! - edge point: on a seam edge one value per side, the midpoint of that side's end values;
//!   elsewhere the vertex rule of the edge (smooth or crease mask) applied to the values;
//! - vertex point: where the UV topology matches the vertex topology (one value, no seam edge,
//!   not a UV corner) the vertex rule itself — creases, semi-sharp creases and the boundary
//!   option included, as OpenSubdiv does; at a seam each value follows its span: a *corner*
//!   keeps its value, a *crease* gets the boundary-curve mask `3/4 v + 1/8 (e₀ + e₁)` with the
//!   values at the far ends of the span's two bounding edges, and a span crossed by semi-sharp
//!   edges stays a corner until they decay, then blends the two by the fractional sharpness.
//!
//! Which spans are corners depends on [`UvInterpolation`], exactly as OpenSubdiv's
//! `FVarLinearInterpolation` decides it (one face in the span, an infinitely sharp or seam edge
//! inside it, a geometric boundary with linear boundaries, more than two values at a junction,
//! an interior seam end (dart)...). Tags are recomputed at each level from the refined topology,
//! which gives OpenSubdiv's propagated tags since refinement keeps every span's shape.

use crate::boundary::Boundary;
use crate::level::{RowBuilder, table_for};
use crate::sharpness::{INFINITELY_SHARP, decrement};
use crate::stencil::StencilTable;
use crate::topology::{Faces, NONE, Topology};

/// How UVs are interpolated: Blender's modifier option `uv_smooth`, i.e. OpenSubdiv's
/// `FVarLinearInterpolation`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum UvInterpolation {
    /// Everything linear (Blender `NONE`, OpenSubdiv `FVAR_LINEAR_ALL`): UVs follow the cage's
    /// UV polygons, refined bilinearly.
    Linear,
    /// Smooth, UV corners kept (Blender `PRESERVE_CORNERS`, its default; OpenSubdiv
    /// `FVAR_LINEAR_CORNERS_ONLY`).
    #[default]
    Corners,
    /// As `Corners`, and junctions of three or more UV islands kept (Blender
    /// `PRESERVE_CORNERS_AND_JUNCTIONS`, OpenSubdiv `FVAR_LINEAR_CORNERS_PLUS1`).
    CornersJunctions,
    /// As `CornersJunctions`, and concave corners kept (Blender
    /// `PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE`, OpenSubdiv `FVAR_LINEAR_CORNERS_PLUS2`).
    CornersJunctionsConcave,
    /// Smooth inside, UV boundaries linear (Blender `PRESERVE_BOUNDARIES`, OpenSubdiv
    /// `FVAR_LINEAR_BOUNDARIES`).
    Boundaries,
    /// Smooth everywhere, UV boundaries as smooth creases (Blender `SMOOTH_ALL`, OpenSubdiv
    /// `FVAR_LINEAR_NONE`).
    Smooth,
}

impl UvInterpolation {
    /// Every option, in protocol order.
    pub const ALL: [UvInterpolation; 6] = [
        UvInterpolation::Linear,
        UvInterpolation::Corners,
        UvInterpolation::CornersJunctions,
        UvInterpolation::CornersJunctionsConcave,
        UvInterpolation::Boundaries,
        UvInterpolation::Smooth,
    ];

    /// The name used by the protocol.
    pub fn name(self) -> &'static str {
        match self {
            UvInterpolation::Linear => "linear",
            UvInterpolation::Corners => "corners",
            UvInterpolation::CornersJunctions => "corners-junctions",
            UvInterpolation::CornersJunctionsConcave => "corners-junctions-concave",
            UvInterpolation::Boundaries => "boundaries",
            UvInterpolation::Smooth => "smooth",
        }
    }

    /// The option called `name` (see [`UvInterpolation::name`]).
    pub fn from_name(name: &str) -> Option<UvInterpolation> {
        UvInterpolation::ALL.into_iter().find(|u| u.name() == name)
    }

    /// Blender's name for it (the modifier's `uv_smooth`).
    pub fn blender_name(self) -> &'static str {
        match self {
            UvInterpolation::Linear => "NONE",
            UvInterpolation::Corners => "PRESERVE_CORNERS",
            UvInterpolation::CornersJunctions => "PRESERVE_CORNERS_AND_JUNCTIONS",
            UvInterpolation::CornersJunctionsConcave => "PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE",
            UvInterpolation::Boundaries => "PRESERVE_BOUNDARIES",
            UvInterpolation::Smooth => "SMOOTH_ALL",
        }
    }
}

/// What an interpolation option makes sharp, derived as OpenSubdiv derives it.
pub(crate) struct Rules {
    /// Everything linear.
    pub(crate) linear_all: bool,
    /// Values on geometric boundaries and seams are corners.
    linear_boundaries: bool,
    /// Junctions: more than two values at a vertex make all of them corners.
    dependent: bool,
    /// A span of one face is a corner.
    corners_sharp: bool,
    /// With two values, a one-face span makes both corners.
    both_if_one_corner: bool,
    /// A seam ending inside the mesh is a corner there.
    sharpen_darts: bool,
    /// A geometric boundary vertex of one face is a UV corner even where UVs match.
    smooth_corners_sharp: bool,
    /// Geometric boundary vertices of one face are infinitely sharp (the boundary option).
    geometric_corners: bool,
}

impl Rules {
    pub(crate) fn new(interp: UvInterpolation, boundary: Boundary) -> Rules {
        use UvInterpolation as U;
        let linear_boundaries = matches!(interp, U::Linear | U::Boundaries);
        let both_if_one_corner = interp == U::CornersJunctionsConcave;
        let corners_sharp = interp != U::Smooth;
        Rules {
            linear_all: interp == U::Linear,
            linear_boundaries,
            dependent: matches!(interp, U::CornersJunctions | U::CornersJunctionsConcave),
            corners_sharp,
            both_if_one_corner,
            sharpen_darts: both_if_one_corner || linear_boundaries,
            smooth_corners_sharp: boundary != Boundary::EdgeAndCorner && corners_sharp,
            geometric_corners: boundary == Boundary::EdgeAndCorner,
        }
    }
}

/// One level of a channel: the faces, their adjacency and the value of every corner.
pub(crate) struct ChannelLevel<'a> {
    pub(crate) faces: &'a Faces,
    pub(crate) topo: &'a Topology,
    pub(crate) corner: &'a [u32],
}

impl ChannelLevel<'_> {
    /// The value at vertex `v` in face `f` (`v` is a corner of `f`).
    fn value_at(&self, f: u32, v: u32) -> u32 {
        let start = self.faces.offsets[f as usize] as usize;
        let k = self
            .faces
            .face(f as usize)
            .iter()
            .position(|&x| x == v)
            .expect("the vertex is a corner of the face");
        self.corner[start + k]
    }

    /// Adds `w` times the centroid of face `f`'s values.
    fn add_face(&self, f: u32, w: f64, row: &mut RowBuilder) {
        let (s, e) = (
            self.faces.offsets[f as usize] as usize,
            self.faces.offsets[f as usize + 1] as usize,
        );
        row.add_face(&self.corner[s..e], w);
    }

    /// The value across edge `e` from `v` (taken in the edge's first face).
    fn across(&self, e: u32, v: u32) -> u32 {
        self.value_at(self.topo.edge_faces[e as usize][0], self.topo.other(e, v))
    }

    /// Adds `w` times the smooth edge mask `(a + b + F₀ + F₁) / 4` in values.
    fn smooth_edge(&self, e: u32, w: f64, row: &mut RowBuilder) {
        let [a, b] = self.topo.edge_vertices[e as usize];
        let [f0, f1] = self.topo.edge_faces[e as usize];
        row.add(self.value_at(f0, a), 0.25 * w);
        row.add(self.value_at(f0, b), 0.25 * w);
        for f in [f0, f1].into_iter().filter(|&f| f != NONE) {
            self.add_face(f, 0.25 * w, row);
        }
    }

    /// The edge point of a continuous edge: Catmull–Clark's edge rule (smooth, crease, or
    /// their blend by fractional sharpness) read in values.
    fn edge_mask(&self, e: u32, row: &mut RowBuilder) {
        let s = self.topo.edge_sharpness[e as usize];
        if s <= 0.0 {
            return self.smooth_edge(e, 1.0, row);
        }
        let w = if decrement(s) > 0.0 {
            1.0
        } else {
            f64::from(s.min(1.0))
        };
        let [a, b] = self.topo.edge_vertices[e as usize];
        let f0 = self.topo.edge_faces[e as usize][0];
        row.add(self.value_at(f0, a), 0.5 * w);
        row.add(self.value_at(f0, b), 0.5 * w);
        if w < 1.0 {
            self.smooth_edge(e, 1.0 - w, row);
        }
    }

    /// The vertex point of a vertex whose single value `x` matches its topology:
    /// Catmull–Clark's vertex rule (smooth, crease, corner, blended across a sharpness
    /// transition) read in values.
    fn vertex_mask(&self, v: u32, x: u32, shape: &VertexShape, row: &mut RowBuilder) {
        let topo = self.topo;
        let edges = topo.edges_of(v as usize);
        let corner = !shape.manifold || shape.sharp_corner;
        let sharpness = |e: u32| topo.edge_sharpness[e as usize];
        let rule_of = |sharp: &dyn Fn(u32) -> bool| -> VertexRule {
            if corner {
                return VertexRule::Corner;
            }
            match edges.iter().filter(|&&e| sharp(e)).count() {
                0 | 1 => VertexRule::Smooth,
                2 => VertexRule::Crease,
                _ => VertexRule::Corner,
            }
        };
        let parent_sharp = |e: u32| sharpness(e) > 0.0;
        let child_sharp = |e: u32| decrement(sharpness(e)) > 0.0;
        let parent = rule_of(&parent_sharp);
        let child = rule_of(&child_sharp);
        if parent == child {
            return self.vertex_rule(v, x, parent, &parent_sharp, 1.0, row);
        }
        // Edges going from sharp to smooth set how much of the sharper rule remains.
        let w = crate::crease_rules::transition_weight(edges.iter().map(|&e| sharpness(e)));
        if w > 0.0 {
            self.vertex_rule(v, x, parent, &parent_sharp, w, row);
        }
        if w < 1.0 {
            self.vertex_rule(v, x, child, &child_sharp, 1.0 - w, row);
        }
    }

    /// Adds `w` times the mask of `rule` at vertex `v` (value `x`); `sharp` picks the edges
    /// the crease rule follows.
    fn vertex_rule(
        &self,
        v: u32,
        x: u32,
        rule: VertexRule,
        sharp: &dyn Fn(u32) -> bool,
        w: f64,
        row: &mut RowBuilder,
    ) {
        let edges = self.topo.edges_of(v as usize);
        match rule {
            VertexRule::Corner => row.add(x, w),
            VertexRule::Crease => {
                row.add(x, 0.75 * w);
                for &e in edges.iter().filter(|&&e| sharp(e)) {
                    row.add(self.across(e, v), 0.125 * w);
                }
            }
            VertexRule::Smooth => {
                let n = edges.len() as f64;
                row.add(x, w * (n - 2.0) / n);
                for &e in edges {
                    row.add(self.across(e, v), w / (n * n));
                }
                for &f in self.topo.faces_of(v as usize) {
                    self.add_face(f, w / (n * n), row);
                }
            }
        }
    }
}

/// The vertex topology's rule at a vertex, by how many sharp edges meet there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum VertexRule {
    Smooth,
    Crease,
    Corner,
}

/// A vertex's place in the mesh, as the value rules need it.
struct VertexShape {
    boundary: bool,
    manifold: bool,
    faces: usize,
    /// Infinitely sharp in the vertex topology (a kept corner with `Boundary::EdgeAndCorner`).
    sharp_corner: bool,
}

fn vertex_shape(topo: &Topology, v: usize, corners_kept: bool) -> VertexShape {
    let fan = topo.fan(v);
    VertexShape {
        boundary: fan.boundary_edges > 0,
        manifold: fan.manifold,
        faces: fan.faces,
        sharp_corner: corners_kept && fan.boundary_edges > 0 && fan.faces == 1,
    }
}

/// The faces of one value around a vertex, as OpenSubdiv's `ValueSpan`.
#[derive(Clone, Default)]
struct Span {
    /// Faces with this value at the vertex.
    size: usize,
    /// The value at the far end of each bounding edge (a seam or geometric boundary), taken in
    /// the span's face.
    ends: Vec<u32>,
    /// Seam edges inside the span (both sides have this value here, not at the far end).
    seams: usize,
    /// The two far-end values of the last seam inside the span (a dart's crease ends).
    dart: [u32; 2],
    /// Infinitely sharp edges inside the span.
    infinite: usize,
    /// Semi-sharp edges inside the span.
    semi: Vec<u32>,
}

fn spans(
    level: &ChannelLevel,
    v: u32,
    values: &[u32],
    sharpness: &dyn Fn(u32) -> f32,
) -> Vec<Span> {
    let topo = level.topo;
    let slot = |x: u32| values.iter().position(|&s| s == x).expect("a value of v");
    let mut out = vec![Span::default(); values.len()];
    for &f in topo.faces_of(v as usize) {
        out[slot(level.value_at(f, v))].size += 1;
    }
    for &e in topo.edges_of(v as usize) {
        let [f0, f1] = topo.edge_faces[e as usize];
        let w = topo.other(e, v);
        let s0 = level.value_at(f0, v);
        if f1 == NONE {
            out[slot(s0)].ends.push(level.value_at(f0, w));
            continue;
        }
        let s1 = level.value_at(f1, v);
        if s0 != s1 {
            out[slot(s0)].ends.push(level.value_at(f0, w));
            out[slot(s1)].ends.push(level.value_at(f1, w));
            continue;
        }
        let span = &mut out[slot(s0)];
        let (w0, w1) = (level.value_at(f0, w), level.value_at(f1, w));
        let s = sharpness(e);
        if w0 != w1 {
            span.seams += 1;
            span.dart = [w0, w1];
        } else if s >= INFINITELY_SHARP {
            span.infinite += 1;
        } else if s > 0.0 {
            span.semi.push(e);
        }
    }
    out
}

/// A value's rule at a vertex where the UV topology does not match the vertex topology.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ValueRule {
    /// Keeps its value.
    Corner,
    /// Boundary-curve mask along its two ends.
    Crease,
    /// A corner until the semi-sharp edges of span `from` decay.
    SemiSharp { from: usize },
}

/// Each value's rule and crease ends (when its span has two).
fn classify(
    spans: &[Span],
    shape: &VertexShape,
    rules: &Rules,
) -> Vec<(ValueRule, Option<[u32; 2]>)> {
    let n = spans.len();
    let mut all_sharp = rules.linear_boundaries
        || shape.sharp_corner
        || !shape.manifold
        || (rules.dependent && n > 2)
        || (rules.sharpen_darts && n == 1 && !shape.boundary);
    let mut dependent_on = None;
    if !all_sharp && rules.dependent && n == 2 {
        all_sharp = spans.iter().any(|s| s.infinite > 0 || s.seams > 0)
            || (rules.both_if_one_corner && spans.iter().any(|s| s.size == 1));
        let semi = [!spans[0].semi.is_empty(), !spans[1].semi.is_empty()];
        if semi[0] != semi[1] {
            dependent_on = Some(if semi[0] { 0 } else { 1 });
        }
    }
    spans
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let ends = if s.ends.len() == 2 && s.seams == 0 {
                Some([s.ends[0], s.ends[1]])
            } else if s.ends.is_empty() && s.seams == 1 {
                Some(s.dart)
            } else {
                None
            };
            let corner = all_sharp || s.infinite > 0 || (s.size == 1 && rules.corners_sharp);
            let rule = match ends {
                _ if corner => ValueRule::Corner,
                None => ValueRule::Corner,
                Some(_) if !s.semi.is_empty() => ValueRule::SemiSharp { from: i },
                Some(_) => match dependent_on {
                    Some(from) => ValueRule::SemiSharp { from },
                    None => ValueRule::Crease,
                },
            };
            (rule, ends)
        })
        .collect()
}

/// How much of the corner rule remains where semi-sharp edges of a span become smooth: the
/// mean sharpness of those edges, at most 1 (OpenSubdiv's fractional weight).
fn fraction(topo: &Topology, span: &Span) -> f64 {
    let (sum, count) = span
        .semi
        .iter()
        .map(|&e| topo.edge_sharpness[e as usize])
        .filter(|&s| decrement(s) <= 0.0)
        .fold((0.0f64, 0usize), |(sum, n), s| (sum + f64::from(s), n + 1));
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).min(1.0)
    }
}

/// One level of a channel: the table making the child values from `level`'s `value_count`
/// values, and the child value of every child corner (in the order of
/// [`crate::catmull_clark::split_faces`]). `linear`: every value bilinear.
pub(crate) fn refine_level(
    level: &ChannelLevel,
    value_count: u32,
    linear: bool,
    rules: &Rules,
) -> (StencilTable, Vec<u32>) {
    let (faces, topo) = (level.faces, level.topo);
    let (nf, ne, nv) = (
        faces.len(),
        topo.edge_vertices.len(),
        faces.vertex_count as usize,
    );
    // Seam edges: two faces whose values differ at either end.
    let seam: Vec<bool> = (0..ne)
        .map(|e| {
            let [f0, f1] = topo.edge_faces[e];
            let [a, b] = topo.edge_vertices[e];
            f1 != NONE
                && (level.value_at(f0, a) != level.value_at(f1, a)
                    || level.value_at(f0, b) != level.value_at(f1, b))
        })
        .collect();
    // The values around each vertex, in face order (CSR).
    let mut value_offsets = Vec::with_capacity(nv + 1);
    value_offsets.push(0u32);
    let mut values = Vec::with_capacity(faces.indices.len());
    for v in 0..nv {
        let start = values.len();
        for &f in topo.faces_of(v) {
            let x = level.value_at(f, v as u32);
            if !values[start..].contains(&x) {
                values.push(x);
            }
        }
        value_offsets.push(values.len() as u32);
    }
    // Child values: one per face, one per edge (one per side on a seam), one per vertex value.
    let mut edge_base = Vec::with_capacity(ne);
    let mut next = nf as u32;
    for &s in &seam {
        edge_base.push(next);
        next += if s { 2 } else { 1 };
    }
    let vertex_base = next;
    let rows = vertex_base as usize + values.len();
    let mut table = table_for(value_count, rows);
    let mut row = RowBuilder::default();
    for f in 0..nf as u32 {
        level.add_face(f, 1.0, &mut row);
        row.push_to(&mut table);
    }
    for (e, &on_seam) in seam.iter().enumerate() {
        let [a, b] = topo.edge_vertices[e];
        let [f0, f1] = topo.edge_faces[e];
        if on_seam {
            // Each side is a boundary of the UV topology: its midpoint.
            for f in [f0, f1] {
                row.add(level.value_at(f, a), 0.5);
                row.add(level.value_at(f, b), 0.5);
                row.push_to(&mut table);
            }
            continue;
        }
        if linear {
            row.add(level.value_at(f0, a), 0.5);
            row.add(level.value_at(f0, b), 0.5);
        } else {
            level.edge_mask(e as u32, &mut row);
        }
        row.push_to(&mut table);
    }
    let parent_sharpness = |e: u32| topo.edge_sharpness[e as usize];
    let child_sharpness = |e: u32| decrement(topo.edge_sharpness[e as usize]);
    for v in 0..nv {
        let vals = &values[value_offsets[v] as usize..value_offsets[v + 1] as usize];
        if vals.is_empty() {
            continue;
        }
        if linear {
            for &x in vals {
                row.add(x, 1.0);
                row.push_to(&mut table);
            }
            continue;
        }
        let shape = vertex_shape(topo, v, rules.geometric_corners);
        let mismatched = topo.edges_of(v).iter().any(|&e| seam[e as usize])
            || (shape.boundary && rules.linear_boundaries)
            || (shape.boundary && shape.faces == 1 && rules.smooth_corners_sharp)
            || (!shape.manifold && vals.len() > 1);
        if !mismatched {
            level.vertex_mask(v as u32, vals[0], &shape, &mut row);
            row.push_to(&mut table);
            continue;
        }
        let parent_spans = spans(level, v as u32, vals, &parent_sharpness);
        let parent = classify(&parent_spans, &shape, rules);
        let child = classify(
            &spans(level, v as u32, vals, &child_sharpness),
            &shape,
            rules,
        );
        for (i, &x) in vals.iter().enumerate() {
            match (child[i].0, parent[i].1) {
                (ValueRule::Crease, Some([e0, e1])) => {
                    let w = match parent[i].0 {
                        ValueRule::SemiSharp { from } => fraction(topo, &parent_spans[from]),
                        _ => 0.0,
                    };
                    row.add(e0, (1.0 - w) * 0.125);
                    row.add(e1, (1.0 - w) * 0.125);
                    row.add(x, (1.0 - w) * 0.75 + w);
                }
                _ => row.add(x, 1.0),
            }
            row.push_to(&mut table);
        }
    }
    debug_assert_eq!(table.len(), rows);
    // Child corners in the order of `catmull_clark::split_faces`.
    let value_slot = |v: u32, x: u32| -> u32 {
        let s = value_offsets[v as usize];
        let vals = &values[s as usize..value_offsets[v as usize + 1] as usize];
        vertex_base + s + vals.iter().position(|&y| y == x).expect("a value of v") as u32
    };
    let edge_value = |e: u32, f: u32| -> u32 {
        let e = e as usize;
        edge_base[e] + u32::from(seam[e] && topo.edge_faces[e][1] == f)
    };
    let mut child_corner = Vec::with_capacity(faces.indices.len() * 4);
    for f in 0..nf {
        let c = faces.face(f);
        let base = faces.offsets[f] as usize;
        let n = c.len();
        for (k, &v) in c.iter().enumerate() {
            let e_next = topo.corner_edge[base + k];
            let e_prev = topo.corner_edge[base + (k + n - 1) % n];
            child_corner.extend_from_slice(&[
                value_slot(v, level.corner[base + k]),
                edge_value(e_next, f as u32),
                f as u32,
                edge_value(e_prev, f as u32),
            ]);
        }
    }
    (table, child_corner)
}
