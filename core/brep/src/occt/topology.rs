//! Step 4: the `TShapes` section — vertices, edges (their curve representations), wires,
//! faces, shells, solids, compounds — and the final root reference.
//!
//! A record's sub-shapes are `<orientation><number> <location>`, where the number counts from
//! the END of the section (the last record written is 1) and must name a record written above
//! (OCCT builds them in order), so the shape graph has no cycles. Every index a record holds
//! (curves, surfaces, locations, shapes) is checked here, so the later walk cannot fail on one.

use super::OcctError;
use super::geometry::Geometry;
use super::lexer::Lexer;
use super::locations::{LocId, Locations};

/// `TopAbs_ShapeEnum`, in its order (a compound is the most complex).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Kind {
    /// `Co`.
    Compound,
    /// `CS`.
    CompSolid,
    /// `So`.
    Solid,
    /// `Sh`.
    Shell,
    /// `Fa`.
    Face,
    /// `Wi`.
    Wire,
    /// `Ed`.
    Edge,
    /// `Ve`.
    Vertex,
}

/// `TopAbs_Orientation`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Orient {
    /// `+`.
    Forward,
    /// `-`.
    Reversed,
    /// `i`.
    Internal,
    /// `e`.
    External,
}

impl Orient {
    /// `TopAbs::Compose(parent, child)`: how a sub-shape is oriented in its parent's frame.
    pub fn compose(self, child: Orient) -> Orient {
        match (self, child) {
            (Orient::Forward, c) => c,
            (Orient::Reversed, Orient::Forward) => Orient::Reversed,
            (Orient::Reversed, Orient::Reversed) => Orient::Forward,
            (Orient::Reversed, c) => c,
            (Orient::Internal, _) => Orient::Internal,
            (Orient::External, _) => Orient::External,
        }
    }
}

/// A reference to a sub-shape.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SubShape {
    /// Its orientation in the parent.
    pub orient: Orient,
    /// The record, 0-based in written order.
    pub shape: usize,
    /// Its location in the parent.
    pub loc: LocId,
}

/// A curve representation of an edge that the document uses.
#[derive(Clone, Copy, Debug)]
pub(crate) enum EdgeRep {
    /// A 3D curve (`1`): `Curves` number, location, range.
    Curve3d {
        /// 1-based `Curves` number.
        curve: usize,
        /// Its location (relative to the edge).
        loc: LocId,
        /// The range.
        range: [f64; 2],
    },
    /// A pcurve on a surface (`2`), or the two of a seam on a closed surface (`3`).
    OnSurface {
        /// 1-based `Curve2ds` number (for a seam: the FORWARD edge's).
        pcurve: usize,
        /// A seam's second pcurve (the REVERSED edge's).
        pcurve2: Option<usize>,
        /// 1-based `Surfaces` number.
        surface: usize,
        /// Its location (relative to the edge).
        loc: LocId,
        /// The range.
        range: [f64; 2],
    },
}

/// An edge's own data.
#[derive(Clone, Debug)]
pub(crate) struct EdgeData {
    /// Its tolerance.
    pub tolerance: f64,
    /// The degenerated flag (a sphere's pole: no 3D curve is written).
    pub degenerated: bool,
    /// Its curve representations in written order (polygons and regularities left out).
    pub reps: Vec<EdgeRep>,
}

/// A face's own data.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FaceData {
    /// 1-based `Surfaces` number; `None` for a face without a surface.
    pub surface: Option<usize>,
    /// The surface's location (relative to the face).
    pub loc: LocId,
}

/// A record's data by kind.
#[derive(Clone, Debug)]
pub(crate) enum Data {
    /// A vertex's tolerance.
    Vertex(f64),
    /// An edge.
    Edge(EdgeData),
    /// A face.
    Face(FaceData),
    /// Wires, shells, solids, compounds carry none.
    None,
}

/// One `TShapes` record.
#[derive(Clone, Debug)]
pub(crate) struct TShape {
    /// Its kind.
    pub kind: Kind,
    /// The line of its kind token.
    pub line: u32,
    /// Its data.
    pub data: Data,
    /// Its sub-shapes in written order.
    pub subs: Vec<SubShape>,
}

/// The section and the root reference.
pub(crate) struct Topology {
    /// The records, 0-based in written order.
    pub shapes: Vec<TShape>,
    /// The root shape.
    pub root: SubShape,
}

impl Topology {
    /// Reads `TShapes` and the root reference (anything after it is ignored).
    pub fn read(
        lx: &mut Lexer,
        version: u32,
        geometry: &Geometry,
        locations: &Locations,
    ) -> Result<Topology, OcctError> {
        lx.at("TShapes", None);
        lx.expect("TShapes")?;
        let n = lx.count("the shape count", 5)?;
        let mut shapes = Vec::with_capacity(n);
        let r = Refs {
            geometry,
            locations,
            version,
        };
        for i in 0..n {
            lx.at("TShapes", Some(i + 1));
            shapes.push(read_shape(lx, &r, n, i)?);
        }
        lx.at("TShapes", None);
        let root = sub_shape(lx, &r, n, n)?.ok_or_else(|| lx.error("no root shape"))?;
        Ok(Topology { shapes, root })
    }
}

/// What records refer to, for checking their numbers.
struct Refs<'g> {
    geometry: &'g Geometry,
    locations: &'g Locations,
    version: u32,
}

impl Refs<'_> {
    fn location(&self, lx: &mut Lexer) -> Result<LocId, OcctError> {
        let k = lx.int("a location number")?;
        self.locations.number(k).ok_or_else(|| {
            lx.error(format!(
                "location {k} out of range 0..{}",
                self.locations.count()
            ))
        })
    }

    /// A number of `section` (0 for none); `None` for 0.
    fn index(
        &self,
        lx: &mut Lexer,
        what: &str,
        count: usize,
        glued: bool,
    ) -> Result<Option<usize>, OcctError> {
        let k = if glued {
            lx.int_glued(what)?
        } else {
            lx.int(what)?
        };
        if k < 0 || k as usize > count {
            return Err(lx.error(format!("{what} {k} out of range 0..{count}")));
        }
        Ok((k > 0).then_some(k as usize))
    }
}

fn read_shape(lx: &mut Lexer, r: &Refs, n: usize, i: usize) -> Result<TShape, OcctError> {
    let t = lx.token("a shape type")?;
    let kind = match t.text {
        "Ve" => Kind::Vertex,
        "Ed" => Kind::Edge,
        "Wi" => Kind::Wire,
        "Fa" => Kind::Face,
        "Sh" => Kind::Shell,
        "So" => Kind::Solid,
        "CS" => Kind::CompSolid,
        "Co" => Kind::Compound,
        other => return Err(lx.error(format!("unknown shape type `{other}`"))),
    };
    let data = match kind {
        Kind::Vertex => read_vertex(lx, r)?,
        Kind::Edge => Data::Edge(read_edge(lx, r)?),
        Kind::Face => read_face(lx, r)?,
        _ => Data::None,
    };
    let flags = lx.token("the shape flags")?;
    if !flags.text.bytes().all(|b| b == b'0' || b == b'1') {
        return Err(lx.error(format!("expected the shape flags, found `{}`", flags.text)));
    }
    let mut subs = Vec::new();
    while let Some(s) = sub_shape(lx, r, n, i)? {
        subs.push(s);
    }
    Ok(TShape {
        kind,
        line: t.line,
        data,
        subs,
    })
}

/// `<orientation><number> <location>`, or `None` at the closing `*`. Record `i` (0-based) may
/// only name records above it: numbers `n - i + 1 ..= n`.
fn sub_shape(lx: &mut Lexer, r: &Refs, n: usize, i: usize) -> Result<Option<SubShape>, OcctError> {
    let t = lx.token("a sub-shape or `*`")?;
    if t.text == "*" {
        return Ok(None);
    }
    let orient = match t.text.as_bytes()[0] {
        b'+' => Orient::Forward,
        b'-' => Orient::Reversed,
        b'i' => Orient::Internal,
        b'e' => Orient::External,
        _ => return Err(lx.error(format!("expected a sub-shape, found `{}`", t.text))),
    };
    let number: i64 = t.text[1..]
        .parse()
        .map_err(|_| lx.error(format!("expected a sub-shape, found `{}`", t.text)))?;
    let lo = n - i + 1;
    if number < lo as i64 || number > n as i64 {
        let range = if lo > n {
            "(no record above this one)".to_string()
        } else {
            format!("{lo}..{n}")
        };
        return Err(lx.error(format!("sub-shape {number} out of range {range}")));
    }
    let loc = r.location(lx)?;
    Ok(Some(SubShape {
        orient,
        shape: n - number as usize,
        loc,
    }))
}

fn read_vertex(lx: &mut Lexer, r: &Refs) -> Result<Data, OcctError> {
    let tolerance = lx.real("the tolerance")?;
    lx.reals::<3>("the point")?;
    let g = r.geometry;
    loop {
        lx.real("a parameter")?;
        match lx.int("the representation type")? {
            0 => break,
            1 => {
                r.index(lx, "curve", g.curves.len(), false)?;
            }
            2 => {
                r.index(lx, "pcurve", g.curves2d.len(), false)?;
                r.index(lx, "surface", g.surfaces.len(), false)?;
            }
            3 => {
                lx.real("a parameter")?;
                r.index(lx, "surface", g.surfaces.len(), false)?;
            }
            t => return Err(lx.error(format!("unknown vertex representation {t}"))),
        }
        r.location(lx)?;
    }
    Ok(Data::Vertex(tolerance))
}

fn read_edge(lx: &mut Lexer, r: &Refs) -> Result<EdgeData, OcctError> {
    let tolerance = lx.real("the tolerance")?;
    lx.flag("the same-parameter flag")?;
    lx.flag("the same-range flag")?;
    let degenerated = lx.flag("the degenerated flag")?;
    let g = r.geometry;
    let mut reps = Vec::new();
    loop {
        match lx.int("the representation type")? {
            0 => break,
            1 => {
                let curve = r.index(lx, "curve", g.curves.len(), false)?;
                let loc = r.location(lx)?;
                let range = lx.reals::<2>("the range")?;
                // Curve 0 is a null curve, which OCCT skips.
                if let Some(curve) = curve {
                    reps.push(EdgeRep::Curve3d { curve, loc, range });
                }
            }
            t @ (2 | 3) => {
                let pcurve = r.index(lx, "pcurve", g.curves2d.len(), false)?;
                let pcurve2 = if t == 3 {
                    let second = r.index(lx, "pcurve", g.curves2d.len(), true)?;
                    continuity(lx)?;
                    Some(second)
                } else {
                    None
                };
                let surface = r.index(lx, "surface", g.surfaces.len(), false)?;
                let loc = r.location(lx)?;
                let range = lx.reals::<2>("the range")?;
                // UV points follow in version 2 only (OCCT 7.9 writes them for V2, not V3).
                if r.version == 2 {
                    lx.reals::<4>("the UV points")?;
                }
                if let (Some(pcurve), Some(surface), Some(pcurve2)) =
                    (pcurve, surface, pcurve2.map_or(Some(None), |p| p.map(Some)))
                {
                    reps.push(EdgeRep::OnSurface {
                        pcurve,
                        pcurve2,
                        surface,
                        loc,
                        range,
                    });
                }
            }
            4 => {
                continuity(lx)?;
                r.index(lx, "surface", g.surfaces.len(), false)?;
                r.location(lx)?;
                r.index(lx, "surface", g.surfaces.len(), false)?;
                r.location(lx)?;
            }
            5 => {
                lx.int("a polygon number")?;
                r.location(lx)?;
            }
            6 => {
                lx.int("a polygon number")?;
                lx.int("a triangulation number")?;
                r.location(lx)?;
            }
            7 => {
                lx.int("a polygon number")?;
                lx.int("a polygon number")?;
                lx.int("a triangulation number")?;
                r.location(lx)?;
            }
            t => return Err(lx.error(format!("unknown edge representation {t}"))),
        }
    }
    Ok(EdgeData {
        tolerance,
        degenerated,
        reps,
    })
}

fn continuity(lx: &mut Lexer) -> Result<(), OcctError> {
    let t = lx.token("a continuity")?;
    match t.text {
        "C0" | "C1" | "C2" | "C3" | "CN" | "G1" | "G2" => Ok(()),
        other => Err(lx.error(format!(
            "expected a continuity (C0…CN, G1, G2), found `{other}`"
        ))),
    }
}

fn read_face(lx: &mut Lexer, r: &Refs) -> Result<Data, OcctError> {
    let g = r.geometry;
    let face = match lx.int_in("the natural-restriction flag", 0, 2)? {
        // 2: a face with only a triangulation.
        2 => {
            lx.int("a triangulation number")?;
            return Ok(Data::Face(FaceData {
                surface: None,
                loc: super::locations::IDENTITY,
            }));
        }
        _ => {
            lx.real("the tolerance")?;
            let surface = r.index(lx, "surface", g.surfaces.len(), false)?;
            let loc = r.location(lx)?;
            FaceData { surface, loc }
        }
    };
    // The triangulation line `2 <number>` may follow (the flags word that comes otherwise is
    // seven 0/1 digits, never `2`).
    if lx.peek().map(|t| t.text) == Some("2") {
        lx.token("2")?;
        lx.int("a triangulation number")?;
    }
    Ok(Data::Face(face))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compose_is_topabs() {
        use Orient::*;
        assert_eq!(Reversed.compose(Reversed), Forward);
        assert_eq!(Reversed.compose(Internal), Internal);
        assert_eq!(Internal.compose(Forward), Internal);
        assert_eq!(Forward.compose(External), External);
    }
}
