//! Step 8: the document's shared edges, as ocp.py's `_export_edge` writes them: the 3D curve
//! representation placed in the world (the edge's location × the representation's), on the
//! edge's range (`BRep_Tool::Range`: the 3D curve's, else the first pcurve's), none for a
//! degenerated edge; the edge's tolerance and its vertices' at either end of the range.

use super::curves::{on_range, transformed};
use super::explore::{Occ, Walker};
use super::geometry::Geometry;
use super::topology::{Data, EdgeRep, Orient};
use super::{OcctError, syntax, unsupported};
use crate::model::Edge;

/// Edge `eid` (its first occurrence) bounding `faces`.
pub(crate) fn export(
    w: &mut Walker,
    geometry: &Geometry,
    eid: usize,
    edge: Occ,
    faces: Vec<u64>,
) -> Result<Edge, OcctError> {
    let topo = w.topo;
    let record = &topo.shapes[edge.shape];
    let Data::Edge(data) = &record.data else {
        unreachable!("edges are mapped by kind");
    };
    let mut range = data.reps.first().map_or([0.0, 0.0], |r| match *r {
        EdgeRep::Curve3d { range, .. } | EdgeRep::OnSurface { range, .. } => range,
    });
    let mut curve = None;
    let curve3d = data.reps.iter().find_map(|r| match *r {
        EdgeRep::Curve3d { curve, loc, range } => Some((curve, loc, range)),
        EdgeRep::OnSurface { .. } => None,
    });
    if let (false, Some((k, loc, [a, b]))) = (data.degenerated, curve3d) {
        let (raw, line) = geometry.curves.get(k).expect("checked when read");
        let l = w.locs.mul(edge.loc, loc).map_err(syntax)?;
        let trsf = w
            .locs
            .trsf(l)
            .map_err(|e| unsupported(format!("edge {eid}: {}", e.message)))?;
        let (c, a, b) = on_range(raw, a, b).map_err(|why| {
            unsupported(format!(
                "edge {eid}: its curve is {why} (Curves[{k}], line {line})"
            ))
        })?;
        curve = Some(transformed(c, &trsf));
        range = [a, b];
    }
    Ok(Edge {
        id: eid as u64,
        curve,
        range,
        faces,
        tolerance: Some(tolerance(data.tolerance)),
        vertex_tolerances: vertex_tolerances(w, edge),
    })
}

/// The tolerances of the vertices at the start and the end of the range: OCCT's
/// `TopExp::FirstVertex / LastVertex` without the edge's orientation (the vertex stored
/// FORWARD in the edge sits at the curve's first parameter, REVERSED at its last); `None`
/// unless both are there.
fn vertex_tolerances(w: &Walker, edge: Occ) -> Option<[f64; 2]> {
    let topo = w.topo;
    let (mut first, mut last) = (None, None);
    for sub in &topo.shapes[edge.shape].subs {
        let Data::Vertex(tol) = topo.shapes[sub.shape].data else {
            continue;
        };
        match sub.orient {
            Orient::Forward => first = Some(tolerance(tol)),
            Orient::Reversed => last = Some(tolerance(tol)),
            _ => {}
        }
    }
    Some([first?, last?])
}

/// `BRep_Tool::Tolerance`: a stored tolerance, at least `Precision::Confusion()` (1e-7).
fn tolerance(t: f64) -> f64 {
    t.max(1e-7)
}
