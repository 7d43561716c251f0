//! Step 7: one face of the document — its surface, its loops of trims, bounds and gap bridges
//! — exactly as the Python exporters assemble it (ocp.py / freecad.py `_export_face`, then
//! document.py `face_json`).
//!
//! The face is walked as if FORWARD: its wires (OCCT's outer wire first), each wire's boundary
//! edges in stored order with their orientation composed, each edge's pcurve on the face (the
//! curve-on-surface representation on the face's surface whose location is the face's,
//! pre-divided by the edge's — `BRep_Tool::CurveOnSurface`, seams by orientation, OCCT's
//! projection on planes that store none). A wire whose stored order does not chain in (u, v)
//! is re-chained by nearest start (freecad.py `_chained`). Then: empty loops dropped, mirrored
//! loops walked the other way, the outer loop confirmed by its signed area, bounds from the
//! trims (a face without trims: its surface's own bounded domain), straight bridges over gaps.

use std::f64::consts::TAU;

use super::curves::{mirrored, on_plane, on_range, transformed, trim_box};
use super::explore::{Occ, ShapeMap, Walker};
use super::geometry::Geometry;
use super::locations::LocId;
use super::surfaces::{Placed, place};
use super::topology::{Data, EdgeRep, Kind, Orient};
use super::{OcctError, syntax, unsupported};
use crate::model::{Curve, Curve2, Face, Loop, Trim};
use crate::vector::Point2;

/// Gaps between consecutive trims above this fraction of the bounds' size get a bridge
/// (document.py `GAP_BRIDGE`).
const GAP_BRIDGE: f64 = 1e-8;

/// A wire's stored order is kept where consecutive trims meet within this share of the face's
/// parameter range (freecad.py `_CHAIN_GAP`).
const CHAIN_GAP: f64 = 1e-4;

/// Samples per trim for the signed area (document.py `signed_area`).
const AREA_SAMPLES: usize = 16;

/// What every face shares: the geometry tables, the edge numbering, and which faces each edge
/// bounds (filled as the faces are walked).
pub(crate) struct Shared<'g> {
    /// The geometry.
    pub geometry: &'g Geometry,
    /// Edge ids: `TopExp::MapShapes` over each face's edges, in face order.
    pub edges: &'g ShapeMap,
    /// `faces` of each edge (index id − 1), in the order met.
    pub edge_faces: Vec<Vec<u64>>,
}

/// A trim under construction.
struct T {
    curve: Curve2,
    t0: f64,
    t1: f64,
    edge: Option<u64>,
}

impl T {
    fn start(&self) -> Point2 {
        self.curve.point(self.t0)
    }

    fn end(&self) -> Point2 {
        self.curve.point(self.t1)
    }

    fn bbox(&self) -> [f64; 4] {
        trim_box(&self.curve, self.t0, self.t1)
    }
}

/// Face `fid` (its first occurrence in the map) as the document's face.
pub(crate) fn export(
    w: &mut Walker,
    s: &mut Shared,
    fid: usize,
    face: Occ,
) -> Result<Face, OcctError> {
    let topo = w.topo;
    let record = &topo.shapes[face.shape];
    let Data::Face(data) = &record.data else {
        unreachable!("faces are mapped by kind");
    };
    let reversed = face.orient == Orient::Reversed;
    let face = face.forward();
    let Some(surface) = data.surface else {
        return Err(unsupported(format!(
            "face {fid}: no surface (TShapes record at line {})",
            record.line
        )));
    };
    let (raw, line) = s.geometry.surfaces.get(surface).expect("checked when read");
    let surf_loc = w.locs.mul(face.loc, data.loc).map_err(syntax)?;
    let trsf = w
        .locs
        .trsf(surf_loc)
        .map_err(|e| unsupported(format!("face {fid}: {}", e.message)))?;
    let placed = place(raw, &trsf).map_err(|why| {
        unsupported(format!(
            "face {fid}: {why} (Surfaces[{surface}], line {line})"
        ))
    })?;

    // The wires (TopExp_Explorer(face, WIRE)) and their boundary trims.
    let mut wires: Vec<Vec<T>> = Vec::new();
    for wire in w.explore(face, Kind::Wire)? {
        let mut trims = Vec::new();
        for edge in w.children(wire)? {
            if w.kind(edge) != Kind::Edge
                || !matches!(edge.orient, Orient::Forward | Orient::Reversed)
            {
                continue;
            }
            let eid = s.edges.find(edge).map(|i| i as u64);
            let t = trim(w, s, edge, eid, surface, surf_loc, &placed, fid)?;
            if let Some(id) = eid {
                let faces = &mut s.edge_faces[id as usize - 1];
                if !faces.contains(&(fid as u64)) {
                    faces.push(fid as u64);
                }
            }
            trims.push(t);
        }
        wires.push(trims);
    }

    // OCCT's outer wire (BRepTools::OuterWire): the last wire whose (u, v) box holds the
    // boxes of the one chosen so far; first, then the others in their order.
    let boxes: Vec<[f64; 4]> = wires.iter().map(|w| union(w.iter().map(T::bbox))).collect();
    let mut outer = 0;
    for (i, b) in boxes.iter().enumerate().skip(1) {
        let o = boxes[outer];
        if b[0] <= o[0] && b[1] >= o[1] && b[2] <= o[2] && b[3] >= o[3] {
            outer = i;
        }
    }
    if outer > 0 {
        let w = wires.remove(outer);
        wires.insert(0, w);
    }

    // freecad.py `_chained`, against the face's parameter range.
    let all = union(boxes.iter().copied());
    let size = diagonal(all);
    let size = if size.is_finite() {
        size
    } else {
        f64::INFINITY
    };
    let wires: Vec<Vec<T>> = wires.into_iter().map(|w| chained(w, size)).collect();

    // document.py `face_json`.
    let mut loops: Vec<Vec<T>> = Vec::new();
    for trims in wires {
        if trims.is_empty() {
            continue;
        }
        let trims = if placed.mirror {
            trims
                .into_iter()
                .rev()
                .map(|t| T {
                    t0: t.t1,
                    t1: t.t0,
                    ..t
                })
                .collect()
        } else {
            trims
        };
        loops.push(trims);
    }
    if loops.len() > 1 && signed_area(&loops[0]) < 0.0 {
        let ccw: Vec<usize> = (0..loops.len())
            .filter(|&i| signed_area(&loops[i]) > 0.0)
            .collect();
        if let [i] = ccw[..] {
            let l = loops.remove(i);
            loops.insert(0, l);
        }
    }
    let bounds = if loops.is_empty() {
        let natural = placed.natural.ok_or_else(|| {
            unsupported(format!(
                "face {fid}: no boundary on an unbounded {} surface",
                placed.surface.type_name()
            ))
        })?;
        if placed.mirror {
            [TAU - natural[1], TAU - natural[0], natural[2], natural[3]]
        } else {
            natural
        }
    } else {
        union(loops.iter().flatten().map(T::bbox))
    };
    if !bounds.iter().all(|b| b.is_finite()) {
        return Err(unsupported(format!(
            "face {fid}: unbounded parameter range {bounds:?}"
        )));
    }
    let size = diagonal(bounds);
    let loops = loops
        .into_iter()
        .map(|l| Loop {
            trims: bridged(l, size)
                .into_iter()
                .map(|t| Trim {
                    curve: t.curve,
                    range: [t.t0, t.t1],
                    edge: t.edge,
                })
                .collect(),
        })
        .collect();
    Ok(Face {
        id: fid as u64,
        reversed: reversed != placed.mirror,
        surface: placed.surface,
        bounds,
        loops,
    })
}

/// The trim of `edge` (an occurrence in the FORWARD face) on the face: its pcurve on the
/// surface's range, mirrored where the surface is, walked backwards for a REVERSED edge.
#[allow(clippy::too_many_arguments)]
fn trim(
    w: &mut Walker,
    s: &Shared,
    edge: Occ,
    eid: Option<u64>,
    surface: usize,
    surf_loc: LocId,
    placed: &Placed,
    fid: usize,
) -> Result<T, OcctError> {
    let name = match eid {
        Some(id) => format!("face {fid}: edge {id}"),
        None => format!("face {fid}: an edge"),
    };
    let Data::Edge(data) = &w.topo.shapes[edge.shape].data else {
        unreachable!("checked by kind");
    };
    // BRep_Tool::CurveOnSurface: the representation on this surface whose location is the
    // face's surface location pre-divided by the edge's.
    let inv = w.locs.inv(edge.loc).map_err(syntax)?;
    let target = w.locs.mul(inv, surf_loc).map_err(syntax)?;
    let found = data.reps.iter().find_map(|r| match *r {
        EdgeRep::OnSurface {
            pcurve,
            pcurve2,
            surface: on,
            loc,
            range,
        } if on == surface && loc == target => {
            let k = match (pcurve2, edge.orient) {
                (Some(second), Orient::Reversed) => second,
                _ => pcurve,
            };
            Some((k, range))
        }
        _ => None,
    });
    let (curve, t0, t1) = if let Some((k, [a, b])) = found {
        let (raw, line) = s.geometry.curves2d.get(k).expect("checked when read");
        on_range(raw, a, b).map_err(|why| {
            unsupported(format!(
                "{name}: its pcurve is {why} (Curve2ds[{k}], line {line})"
            ))
        })?
    } else {
        plane_pcurve(w, s, edge, placed, &name)?
    };
    let curve = if placed.mirror {
        mirrored(curve)
    } else {
        curve
    };
    let (t0, t1) = if edge.orient == Orient::Reversed {
        (t1, t0)
    } else {
        (t0, t1)
    };
    Ok(T {
        curve,
        t0,
        t1,
        edge: eid,
    })
}

/// `BRep_Tool::CurveOnPlane`: an edge on a plane without a stored pcurve gets its 3D curve's
/// projection, on the 3D curve's range.
fn plane_pcurve(
    w: &mut Walker,
    s: &Shared,
    edge: Occ,
    placed: &Placed,
    name: &str,
) -> Result<(Curve2, f64, f64), OcctError> {
    let Data::Edge(data) = &w.topo.shapes[edge.shape].data else {
        unreachable!("checked by kind");
    };
    let none = || unsupported(format!("{name} has no pcurve on the face"));
    let Some(frame) = placed.plane else {
        return Err(none());
    };
    let Some((k, loc, [a, b])) = data.reps.iter().find_map(|r| match *r {
        EdgeRep::Curve3d { curve, loc, range } => Some((curve, loc, range)),
        EdgeRep::OnSurface { .. } => None,
    }) else {
        return Err(none());
    };
    let (raw, line) = s.geometry.curves.get(k).expect("checked when read");
    let l = w.locs.mul(edge.loc, loc).map_err(syntax)?;
    let trsf = w
        .locs
        .trsf(l)
        .map_err(|e| unsupported(format!("{name}: {}", e.message)))?;
    let why = |why: String| {
        unsupported(format!(
            "{name}: no pcurve on the plane, and {why} (Curves[{k}], line {line})"
        ))
    };
    let (c, a, b) = on_range(raw, a, b).map_err(|w| why(format!("its 3D curve is {w}")))?;
    let c2 = on_plane(&transformed(c, &trsf), &frame).map_err(why)?;
    Ok((c2, a, b))
}

fn union(boxes: impl Iterator<Item = [f64; 4]>) -> [f64; 4] {
    boxes.fold(
        [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ],
        |a, b| {
            [
                a[0].min(b[0]),
                a[1].max(b[1]),
                a[2].min(b[2]),
                a[3].max(b[3]),
            ]
        },
    )
}

fn diagonal(b: [f64; 4]) -> f64 {
    (b[1] - b[0]).hypot(b[3] - b[2])
}

fn gap(a: &T, b: &T) -> f64 {
    let (p, q) = (a.end(), b.start());
    (q[0] - p[0]).hypot(q[1] - p[1])
}

/// freecad.py `_chained`: the trims as stored where consecutive ones meet in (u, v), else
/// chained from the first by the nearest start.
fn chained(trims: Vec<T>, size: f64) -> Vec<T> {
    let n = trims.len();
    if n < 2 || (0..n).all(|i| gap(&trims[i], &trims[(i + 1) % n]) <= CHAIN_GAP * size) {
        return trims;
    }
    let mut rest: Vec<T> = trims;
    let mut out = vec![rest.remove(0)];
    while !rest.is_empty() {
        let last = out.last().expect("never empty");
        let k = (0..rest.len())
            .min_by(|&i, &j| gap(last, &rest[i]).total_cmp(&gap(last, &rest[j])))
            .expect("rest is not empty");
        out.push(rest.remove(k));
    }
    out
}

/// document.py `signed_area`: the shoelace area of 16 samples per trim.
fn signed_area(l: &[T]) -> f64 {
    let pts: Vec<Point2> = l
        .iter()
        .flat_map(|t| {
            (0..AREA_SAMPLES).map(move |k| {
                t.curve
                    .point(t.t0 + (t.t1 - t.t0) * k as f64 / AREA_SAMPLES as f64)
            })
        })
        .collect();
    let n = pts.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
}

/// document.py `bridge_gaps`: a straight (u, v) segment without an edge across each gap
/// above `GAP_BRIDGE` × the bounds' size.
fn bridged(l: Vec<T>, size: f64) -> Vec<T> {
    if size.is_nan() || size <= 0.0 {
        return l;
    }
    let n = l.len();
    let ends: Vec<(Point2, Point2)> = l.iter().map(|t| (t.start(), t.end())).collect();
    let mut out = Vec::with_capacity(n);
    for (i, t) in l.into_iter().enumerate() {
        out.push(t);
        let (a, b) = (ends[i].1, ends[(i + 1) % n].0);
        let d = b - a;
        let g = d.length();
        if g > GAP_BRIDGE * size {
            out.push(T {
                curve: Curve::Line {
                    origin: a,
                    dir: d / g,
                },
                t0: 0.0,
                t1: g,
                edge: None,
            });
        }
    }
    out
}
