//! What a document holds, counted as the paper's table 1 counts a model (faces per basis
//! surface type, trim curves per curve type, B-spline trims per degree), plus the loop, edge and
//! pole totals that size the later stages (trim structures, tessellation).

use crate::model::{Curve, Document, Surface};
use serde::Serialize;
use std::collections::BTreeMap;

/// Counts of a document's elements. Per-type maps list every type, zeros included, so
/// tables from different models line up.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Stats {
    /// Faces.
    pub faces: usize,
    /// Faces per surface `type`.
    pub faces_by_surface: BTreeMap<String, usize>,
    /// Faces with `reversed: true`.
    pub reversed_faces: usize,
    /// Loops (outer loops and holes).
    pub loops: usize,
    /// Loops after the first of their face.
    pub holes: usize,
    /// Trims (trim curves) over all loops.
    pub trims: usize,
    /// Trims per curve `type`.
    pub trims_by_curve: BTreeMap<String, usize>,
    /// B-spline trims per degree (JSON keys `"1"`, `"2"`, …), as table 1 splits NURBS trims.
    pub bspline_trims_by_degree: BTreeMap<usize, usize>,
    /// Rational B-spline trims (with weights).
    pub rational_trims: usize,
    /// B-spline surfaces per degree pair (`"3x3"`).
    pub bspline_surfaces_by_degree: BTreeMap<String, usize>,
    /// Rational B-spline surfaces (with weights).
    pub rational_surfaces: usize,
    /// Poles of all B-spline surfaces.
    pub surface_poles: usize,
    /// Poles of all B-spline trims.
    pub trim_poles: usize,
    /// Shared edges (0 without topology).
    pub edges: usize,
    /// Edges per 3D curve `type` (`"none"` for degenerate edges).
    pub edges_by_curve: BTreeMap<String, usize>,
    /// Poles of all B-spline edge curves.
    pub edge_poles: usize,
}

impl Stats {
    /// Counts `doc` (valid or not: counting never fails).
    pub fn of(doc: &Document) -> Stats {
        let mut s = Stats {
            faces: doc.faces.len(),
            ..Stats::default()
        };
        for name in Surface::TYPE_NAMES {
            s.faces_by_surface.insert(name.into(), 0);
        }
        for name in Curve::<[f64; 2]>::TYPE_NAMES {
            s.trims_by_curve.insert(name.into(), 0);
            s.edges_by_curve.insert(name.into(), 0);
        }
        s.edges_by_curve.insert("none".into(), 0);
        for face in &doc.faces {
            *s.faces_by_surface
                .entry(face.surface.type_name().into())
                .or_default() += 1;
            s.reversed_faces += usize::from(face.reversed);
            if let Surface::Bspline(b) = &face.surface {
                *s.bspline_surfaces_by_degree
                    .entry(format!("{}x{}", b.degree_u, b.degree_v))
                    .or_default() += 1;
                s.rational_surfaces += usize::from(b.weights.is_some());
                s.surface_poles += b.poles.iter().map(Vec::len).sum::<usize>();
            }
            s.loops += face.loops.len();
            s.holes += face.loops.len().saturating_sub(1);
            for trim in face.loops.iter().flat_map(|l| &l.trims) {
                s.trims += 1;
                *s.trims_by_curve
                    .entry(trim.curve.type_name().into())
                    .or_default() += 1;
                if let Curve::Bspline(b) = &trim.curve {
                    *s.bspline_trims_by_degree.entry(b.degree).or_default() += 1;
                    s.rational_trims += usize::from(b.weights.is_some());
                    s.trim_poles += b.poles.len();
                }
            }
        }
        for edge in doc.edges.iter().flatten() {
            s.edges += 1;
            let name = edge.curve.as_ref().map_or("none", |c| c.type_name());
            *s.edges_by_curve.entry(name.into()).or_default() += 1;
            if let Some(Curve::Bspline(b)) = &edge.curve {
                s.edge_poles += b.poles.len();
            }
        }
        s
    }
}
