//! Face-varying data (UVs) refined alongside the vertices, by OpenSubdiv's face-varying rules
//! (`Vtr::FVarLevel` / `Far::PrimvarRefiner`), which Blender's Subdivision Surface modifier
//! runs for its UV maps.
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
//!
//! Children come in parent-corner order (see [`catmull_clark::split_faces`]), so the refined
//! UV topology's faces are the refined mesh's faces one to one and the result's indices follow
//! the refined mesh's corners. Schemes whose faces do not split that way (Butterfly, Doo–Sabin,
//! √3) carry no UVs: they are dropped ([`carries_face_varying`]). Loop can join: the value
//! rules (seams, spans, corners, creases) do not depend on the scheme; it needs its own masks
//! in `ChannelLevel` (no face values) and the child corners of `loop_scheme::split_triangles`
//! in `refine_level`.
//!
//! Like Blender's converter, corners of one vertex with equal UVs are one value (see
//! [`weld_by_value`]); Blender welds within 1e-4 while we weld exact equals only.

use crate::boundary::Boundary;
use crate::catmull_clark;
use crate::error::SubdivError;
use crate::level::{RowBuilder, table_for};
use crate::sharpness::{INFINITELY_SHARP, decrement};
use crate::stencil::StencilTable;
use crate::topology::{Faces, NONE, Topology};
use crate::{Refiner, Scheme, SubdivOptions};
use tessd_mesh::{FaceVarying, Mesh};

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

/// True for the schemes whose refined faces follow the parent corners, so that face-varying
/// data can be refined with them.
pub fn carries_face_varying(scheme: Scheme) -> bool {
    matches!(scheme, Scheme::CatmullClark | Scheme::Bilinear)
}

/// What an interpolation option makes sharp, derived as OpenSubdiv derives it.
struct Rules {
    /// Everything linear.
    linear_all: bool,
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
    fn new(interp: UvInterpolation, boundary: Boundary) -> Rules {
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

/// Corners of one vertex whose values are equal (0 and −0 alike) get one value index, the
/// first such corner's: the UV topology is then that of the values, as Blender's converter
/// builds it, not of however the indices were written (per-corner UVs, duplicated indices).
pub fn weld_by_value<const N: usize>(face_indices: &[u32], fv: &FaceVarying<[f32; N]>) -> Vec<u32> {
    weld_rows(face_indices, &fv.indices, fv.values.as_flattened(), N)
}

/// [`weld_by_value`] for rows of any width: corner `c` holds row `rows[c]` of `values`
/// (`components` floats per row); the result gives each corner the row of the first corner of
/// its vertex holding an equal row. Corners are sorted by (vertex, row bits, corner), so the
/// first of each run of equals is the first in corner order; no per-corner allocation.
pub fn weld_rows(
    face_indices: &[u32],
    rows: &[u32],
    values: &[f32],
    components: usize,
) -> Vec<u32> {
    let c = components.max(1);
    let row = |k: usize| &values[rows[k] as usize * c..rows[k] as usize * c + c];
    let bits = |x: f32| if x == 0.0 { 0 } else { x.to_bits() };
    let same_row =
        |a: usize, b: usize| row(a).iter().zip(row(b)).all(|(&x, &y)| bits(x) == bits(y));
    let mut order: Vec<u32> = (0..face_indices.len() as u32).collect();
    order.sort_unstable_by(|&a, &b| {
        let (a, b) = (a as usize, b as usize);
        face_indices[a]
            .cmp(&face_indices[b])
            .then_with(|| {
                row(a)
                    .iter()
                    .zip(row(b))
                    .map(|(&x, &y)| bits(x).cmp(&bits(y)))
                    .find(|o| o.is_ne())
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .then(a.cmp(&b))
    });
    let mut out = vec![0u32; face_indices.len()];
    let mut first = usize::MAX;
    for &k in &order {
        let k = k as usize;
        let new_run =
            first == usize::MAX || face_indices[first] != face_indices[k] || !same_row(first, k);
        if new_run {
            first = k;
        }
        out[k] = rows[first];
    }
    out
}

/// The topology phase for one face-varying channel: one stencil table per level over the
/// channel's values and the last level's value of every corner. Build once per cage topology
/// and UV layout; [`FaceVaryingRefiner::apply`] then refines any data laid out that way.
#[derive(Clone, Debug)]
pub struct FaceVaryingRefiner {
    /// Values of level `i + 1` from those of level `i`.
    pub tables: Vec<StencilTable>,
    /// Value of each corner of the last level (corners in the order of `faces.indices`).
    pub indices: Vec<u32>,
    /// Faces of the last level (the vertex refiner's, face for face).
    pub faces: Faces,
    /// Values of the cage's channel.
    pub source_count: usize,
}

impl FaceVaryingRefiner {
    /// Refines the channel whose corner values are `indices` (over `value_count` values) on the
    /// cage `faces` with `creases`, as `options` says (scheme, levels, boundary,
    /// `uv_interpolation`). `None` when the scheme carries no face-varying data.
    ///
    /// # Errors
    /// Indices that do not fit the cage, and the cage errors of [`Topology::build`].
    pub fn new(
        faces: &Faces,
        creases: &[([u32; 2], f32)],
        indices: &[u32],
        value_count: usize,
        options: &SubdivOptions,
    ) -> Result<Option<FaceVaryingRefiner>, SubdivError> {
        if !carries_face_varying(options.scheme) {
            return Ok(None);
        }
        if indices.len() != faces.indices.len() {
            return Err(SubdivError::InvalidOption(format!(
                "{} face-varying indices given for {} face corners",
                indices.len(),
                faces.indices.len()
            )));
        }
        if let Some((c, &i)) = indices
            .iter()
            .enumerate()
            .find(|&(_, &i)| i as usize >= value_count)
        {
            return Err(SubdivError::InvalidOption(format!(
                "face corner {c} uses face-varying value {i}; there are {value_count}"
            )));
        }
        let rules = Rules::new(options.uv_interpolation, options.boundary);
        let linear = rules.linear_all || options.scheme == Scheme::Bilinear;
        let mut faces = faces.clone();
        let mut creases = creases.to_vec();
        let mut corner = indices.to_vec();
        let mut count = value_count as u32;
        let mut tables = Vec::with_capacity(options.levels as usize);
        for _ in 0..options.levels {
            let topo = Topology::build(&faces, &creases)?;
            let level = ChannelLevel {
                faces: &faces,
                topo: &topo,
                corner: &corner,
            };
            let (table, next_corner) = refine_level(&level, count, linear, &rules);
            let (next_faces, _) = catmull_clark::split_faces(&faces, &topo);
            creases = catmull_clark::split_creases(&topo, faces.len());
            count = table.len() as u32;
            tables.push(table);
            corner = next_corner;
            faces = next_faces;
        }
        Ok(Some(FaceVaryingRefiner {
            tables,
            indices: corner,
            faces,
            source_count: value_count,
        }))
    }

    /// The last level's values from the cage channel's `values`.
    ///
    /// # Errors
    /// When `values` does not hold the channel's value count.
    pub fn apply<const N: usize>(&self, values: &[[f32; N]]) -> Result<Vec<[f32; N]>, SubdivError> {
        if N == 0 {
            self.check_count(values.len())?;
            return Ok(vec![
                [0.0; N];
                self.tables.last().map_or(values.len(), |t| t.len())
            ]);
        }
        let flat = self.apply_rows(values.as_flattened(), N)?;
        Ok(flat
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|k| c[k]))
            .collect())
    }

    /// [`FaceVaryingRefiner::apply`] for rows of `components` floats (≥ 1) stored one after
    /// the other: generic attributes of any width.
    ///
    /// # Errors
    /// When `values` does not hold the channel's value count.
    pub fn apply_rows(&self, values: &[f32], components: usize) -> Result<Vec<f32>, SubdivError> {
        let c = components.max(1);
        if values.len() / c * c != values.len() {
            return Err(SubdivError::InvalidOption(format!(
                "{} face-varying floats are not rows of {c}",
                values.len()
            )));
        }
        self.check_count(values.len() / c)?;
        Ok(StencilTable::apply_chain(&self.tables, values, c))
    }

    fn check_count(&self, rows: usize) -> Result<(), SubdivError> {
        if rows != self.source_count {
            return Err(SubdivError::InvalidOption(format!(
                "{rows} face-varying values given; the channel has {}",
                self.source_count
            )));
        }
        Ok(())
    }
}

/// The cage's UVs refined with `refiner` (built from `cage` with `options`), their indices
/// following the refined mesh's corners; `None` when the cage has no UVs or the scheme carries
/// none ([`carries_face_varying`]). Interpolation: `options.uv_interpolation`.
///
/// # Errors
/// UVs that do not fit the cage; a `refiner` not built from this cage and scheme.
pub fn refine_uvs(
    cage: &Mesh,
    refiner: &Refiner,
    options: &SubdivOptions,
) -> Result<Option<FaceVarying<[f32; 2]>>, SubdivError> {
    let Some(uvs) = &cage.uvs else {
        return Ok(None);
    };
    if !carries_face_varying(options.scheme) {
        return Ok(None);
    }
    if uvs.indices.len() != cage.face_indices.len() {
        return Err(SubdivError::InvalidOption(format!(
            "{} uv indices given for {} face corners",
            uvs.indices.len(),
            cage.face_indices.len()
        )));
    }
    if let Some((c, &i)) = uvs
        .indices
        .iter()
        .enumerate()
        .find(|&(_, &i)| i as usize >= uvs.values.len())
    {
        return Err(SubdivError::InvalidOption(format!(
            "face corner {c} uses uv {i}; there are {}",
            uvs.values.len()
        )));
    }
    let welded = weld_by_value(&cage.face_indices, uvs);
    let Some(channel) = cage_channel(cage, refiner, &welded, uvs.values.len(), options)? else {
        return Ok(None);
    };
    Ok(Some(FaceVarying {
        values: channel.apply(&uvs.values)?,
        indices: channel.indices,
    }))
}

/// The channel of `cage` whose corners use values `indices` (of `value_count`), refined as
/// `refiner` was (`None` when the scheme carries no face-varying data).
///
/// # Errors
/// Indices that do not fit the cage; a `refiner` not built from this cage and scheme.
pub fn cage_channel(
    cage: &Mesh,
    refiner: &Refiner,
    indices: &[u32],
    value_count: usize,
    options: &SubdivOptions,
) -> Result<Option<FaceVaryingRefiner>, SubdivError> {
    let faces = Faces {
        offsets: cage.face_offsets.clone(),
        indices: cage.face_indices.clone(),
        vertex_count: cage.positions.len() as u32,
    };
    let creases: Vec<([u32; 2], f32)> =
        cage.creases.iter().map(|c| ([c.a, c.b], c.value)).collect();
    let Some(channel) = FaceVaryingRefiner::new(&faces, &creases, indices, value_count, options)?
    else {
        return Ok(None);
    };
    // Corners correspond one to one (both split faces in parent-corner order); vertex
    // numbers may differ, face-varying indices do not need them.
    if channel.faces.offsets != refiner.faces.offsets {
        return Err(SubdivError::InvalidOption(
            "the refiner's faces are not this cage's refined faces (another cage, scheme or level count)"
                .to_string(),
        ));
    }
    Ok(Some(channel))
}

/// One level of a channel: the faces, their adjacency and the value of every corner.
struct ChannelLevel<'a> {
    faces: &'a Faces,
    topo: &'a Topology,
    corner: &'a [u32],
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
/// [`catmull_clark::split_faces`]). `linear`: every value bilinear.
fn refine_level(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subdivide;
    use crate::test_meshes::cube;
    use tessd_mesh::Crease;

    /// An nx × ny grid of quads, warped in z, with per-vertex UVs `uv(position)` (no seams).
    fn grid(nx: u32, ny: u32, uv: impl Fn([f32; 3]) -> [f32; 2]) -> Mesh {
        let mut m = Mesh::default();
        for y in 0..=ny {
            for x in 0..=nx {
                let (fx, fy) = (x as f32, y as f32);
                m.positions
                    .push([fx * 1.1, fy * 0.9 + 0.05 * fx, 0.3 * (fx * 0.7 + fy).sin()]);
            }
        }
        for y in 0..ny {
            for x in 0..nx {
                let v = y * (nx + 1) + x;
                m.push_face(&[v, v + 1, v + nx + 2, v + nx + 1]);
            }
        }
        m.uvs = Some(FaceVarying {
            values: m.positions.iter().map(|&p| uv(p)).collect(),
            indices: m.face_indices.clone(),
        });
        m
    }

    fn options(
        levels: u32,
        uv: UvInterpolation,
        boundary: Boundary,
        scheme: Scheme,
    ) -> SubdivOptions {
        SubdivOptions {
            scheme,
            levels,
            boundary,
            uv_interpolation: uv,
            ..SubdivOptions::default()
        }
    }

    fn corner_uv(m: &Mesh, c: usize) -> [f32; 2] {
        let uv = m.uvs.as_ref().expect("refined UVs");
        uv.values[uv.indices[c] as usize]
    }

    #[test]
    fn linear_uvs_of_a_planar_grid_equal_the_bilinear_positions() {
        let cage = grid(4, 3, |p| [p[0], p[1]]);
        for levels in 1..=3 {
            let uv_opts = options(
                levels,
                UvInterpolation::Linear,
                Boundary::EdgeOnly,
                Scheme::CatmullClark,
            );
            let m = subdivide(&cage, &uv_opts).unwrap();
            let flat = subdivide(
                &cage,
                &options(
                    levels,
                    UvInterpolation::Linear,
                    Boundary::EdgeOnly,
                    Scheme::Bilinear,
                ),
            )
            .unwrap();
            assert_eq!(m.face_offsets, flat.face_offsets);
            for (c, &v) in flat.face_indices.iter().enumerate() {
                let p = flat.positions[v as usize];
                let uv = corner_uv(&m, c);
                assert!(
                    (uv[0] - p[0]).abs() < 1e-5 && (uv[1] - p[1]).abs() < 1e-5,
                    "level {levels} corner {c}: uv {uv:?}, position {p:?}"
                );
                // The bilinear scheme carries the same UVs.
                assert_eq!(corner_uv(&flat, c), uv);
            }
        }
    }

    /// Where the UV topology is the vertex topology, UVs that are an affine function of the
    /// positions stay that function of the refined positions: the vertex rules (creases,
    /// semi-sharp blends, boundaries) are reused exactly.
    #[test]
    fn matching_topology_follows_the_vertex_rules() {
        let f = |p: [f32; 3]| [p[0] + 0.3 * p[2] - 0.1, p[1] - 0.2 * p[2]];
        let creased = |mut m: Mesh| {
            m.creases = vec![
                Crease {
                    a: 6,
                    b: 7,
                    value: 10.0,
                },
                Crease {
                    a: 7,
                    b: 8,
                    value: 10.0,
                },
                Crease {
                    a: 11,
                    b: 12,
                    value: 1.5,
                },
                Crease {
                    a: 12,
                    b: 13,
                    value: 2.0,
                },
                Crease {
                    a: 13,
                    b: 18,
                    value: 0.5,
                },
            ];
            m
        };
        let cases = [
            (
                creased(grid(4, 4, f)),
                UvInterpolation::Smooth,
                Boundary::EdgeOnly,
            ),
            (
                creased(grid(4, 4, f)),
                UvInterpolation::Corners,
                Boundary::EdgeAndCorner,
            ),
            (
                {
                    let mut m = cube();
                    m.uvs = Some(FaceVarying {
                        values: m.positions.iter().map(|&p| f(p)).collect(),
                        indices: m.face_indices.clone(),
                    });
                    m.creases = vec![
                        Crease {
                            a: 0,
                            b: 1,
                            value: 1.5,
                        },
                        Crease {
                            a: 1,
                            b: 3,
                            value: 10.0,
                        },
                    ];
                    m
                },
                UvInterpolation::Corners,
                Boundary::EdgeOnly,
            ),
        ];
        for (cage, uv, boundary) in cases {
            for levels in 1..=3 {
                let m =
                    subdivide(&cage, &options(levels, uv, boundary, Scheme::CatmullClark)).unwrap();
                for (c, &v) in m.face_indices.iter().enumerate() {
                    let want = f(m.positions[v as usize]);
                    let got = corner_uv(&m, c);
                    assert!(
                        (got[0] - want[0]).abs() < 1e-5 && (got[1] - want[1]).abs() < 1e-5,
                        "{uv:?} {boundary:?} level {levels} corner {c}: {got:?} vs {want:?}"
                    );
                }
            }
        }
    }

    /// Every face of a cube its own UV island: no refined value is shared across islands, and
    /// each island's values stay in its own square (all masks are convex in its values).
    #[test]
    fn seams_stay_seams() {
        let mut cage = cube();
        let mut values = Vec::new();
        for f in 0..6 {
            let o = [2.0 * f as f32, 0.5 * f as f32];
            values.extend_from_slice(&[
                [o[0], o[1]],
                [o[0] + 1.0, o[1]],
                [o[0] + 1.0, o[1] + 1.0],
                [o[0], o[1] + 1.0],
            ]);
        }
        cage.uvs = Some(FaceVarying {
            values,
            indices: (0..24).collect(),
        });
        for uv in UvInterpolation::ALL {
            for levels in 1..=3 {
                let opts = options(levels, uv, Boundary::EdgeOnly, Scheme::CatmullClark);
                let refiner = Refiner::new(&cage, &opts).unwrap();
                let m = subdivide(&cage, &opts).unwrap();
                let fv = m.uvs.as_ref().unwrap();
                let mut island = vec![u32::MAX; fv.values.len()];
                for f in 0..m.face_count() {
                    let cage_face = refiner.face_origin[f];
                    for c in m.face_offsets[f] as usize..m.face_offsets[f + 1] as usize {
                        let x = fv.indices[c] as usize;
                        assert!(
                            island[x] == u32::MAX || island[x] == cage_face,
                            "{uv:?} level {levels}: value {x} on islands {} and {cage_face}",
                            island[x]
                        );
                        island[x] = cage_face;
                        let p = fv.values[x];
                        let o = [2.0 * cage_face as f32, 0.5 * cage_face as f32];
                        assert!(
                            (o[0] - 1e-6..=o[0] + 1.0 + 1e-6).contains(&p[0])
                                && (o[1] - 1e-6..=o[1] + 1.0 + 1e-6).contains(&p[1]),
                            "{uv:?} level {levels}: {p:?} outside island {cage_face}"
                        );
                    }
                }
                // Each island's four cage corners are kept by every mode but `Smooth`.
                if uv != UvInterpolation::Smooth {
                    for corner in &cage.uvs.as_ref().unwrap().values {
                        assert!(
                            fv.values.contains(corner),
                            "{uv:?}: corner {corner:?} moved"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn per_corner_uvs_weld_like_indexed_ones() {
        let indexed = grid(3, 2, |p| [p[0], p[1]]);
        let mut per_corner = indexed.clone();
        let uv = indexed.uvs.as_ref().unwrap();
        per_corner.uvs = Some(FaceVarying {
            values: uv.indices.iter().map(|&i| uv.values[i as usize]).collect(),
            indices: (0..uv.indices.len() as u32).collect(),
        });
        let opts = options(
            2,
            UvInterpolation::Corners,
            Boundary::EdgeOnly,
            Scheme::CatmullClark,
        );
        let (a, b) = (
            subdivide(&indexed, &opts).unwrap(),
            subdivide(&per_corner, &opts).unwrap(),
        );
        for c in 0..a.face_indices.len() {
            let (p, q) = (corner_uv(&a, c), corner_uv(&b, c));
            assert!((p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6);
        }
        assert_eq!(
            a.uvs.as_ref().unwrap().values.len(),
            b.uvs.as_ref().unwrap().values.len()
        );
    }

    /// Random UV layouts (random seams, darts, junctions, bowties in UV space) on a cage with
    /// a non-manifold vertex: no panic, and every refined value is a convex combination of
    /// the cage's (within their bounds).
    #[test]
    fn random_layouts_stay_convex() {
        let mut seed = 12345u64;
        let mut rand = |n: u32| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) % u64::from(n)) as u32
        };
        let mut cage = grid(4, 3, |p| [p[0], p[1]]);
        // A quad touching the grid at one corner only (a bowtie vertex) and a triangle.
        let base = cage.positions.len() as u32;
        cage.positions
            .extend_from_slice(&[[5.0, 3.0, 0.0], [5.0, 4.0, 0.0], [4.4, 4.0, 0.0]]);
        cage.push_face(&[19, base, base + 1, base + 2]);
        cage.push_face(&[0, 5, 1]);
        let corners = cage.face_indices.len();
        for trial in 0..20 {
            let values: Vec<[f32; 2]> = (0..12)
                .map(|_| [rand(1000) as f32 / 1000.0, rand(1000) as f32 / 1000.0])
                .collect();
            // Few values, so that neighbouring corners often share one.
            let indices: Vec<u32> = (0..corners).map(|_| rand(12)).collect();
            cage.uvs = Some(FaceVarying {
                values: values.clone(),
                indices,
            });
            let lo = values
                .iter()
                .fold([f32::MAX; 2], |a, v| [a[0].min(v[0]), a[1].min(v[1])]);
            let hi = values
                .iter()
                .fold([f32::MIN; 2], |a, v| [a[0].max(v[0]), a[1].max(v[1])]);
            for uv in UvInterpolation::ALL {
                for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
                    let opts = options(2, uv, boundary, Scheme::CatmullClark);
                    let m = subdivide(&cage, &opts).unwrap();
                    let fv = m.uvs.unwrap();
                    assert_eq!(fv.indices.len(), m.face_indices.len());
                    for p in &fv.values {
                        assert!(
                            (0..2).all(|k| p[k] >= lo[k] - 1e-5 && p[k] <= hi[k] + 1e-5),
                            "trial {trial} {uv:?}: {p:?} outside {lo:?}..{hi:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn schemes_without_corner_order_drop_uvs() {
        let quads = grid(2, 2, |p| [p[0], p[1]]);
        let mut triangles = quads.clone();
        triangles.face_offsets = vec![0];
        triangles.face_indices.clear();
        for q in quads.faces() {
            triangles.push_face(&[q[0], q[1], q[2]]);
            triangles.push_face(&[q[0], q[2], q[3]]);
        }
        let uv = quads.uvs.as_ref().unwrap();
        triangles.uvs = Some(FaceVarying {
            values: uv.values.clone(),
            indices: triangles.face_indices.clone(),
        });
        let cases = [
            (&quads, Scheme::DooSabin),
            (&triangles, Scheme::Loop),
            (&triangles, Scheme::Butterfly),
            (&triangles, Scheme::Sqrt3),
        ];
        for (cage, scheme) in cases {
            assert!(!carries_face_varying(scheme));
            let opts = options(1, UvInterpolation::Corners, Boundary::EdgeOnly, scheme);
            if let Ok(refiner) = Refiner::new(cage, &opts) {
                assert_eq!(refine_uvs(cage, &refiner, &opts).unwrap(), None);
            }
        }
    }
}
