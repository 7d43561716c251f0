//! OpenCASCADE's own BREP text (`BRepTools::Write`, FreeCAD's `Shape.exportBrepToString()`,
//! `.brep` files) read straight into a [`Document`], so hosts built on OpenCASCADE hand the
//! daemon their shape in the kernel's format (a few ms in C++) instead of walking it face by
//! face in Python. The document is the one the Python exporters write for the same shape
//! (python/tessd/brep/{ocp,freecad,document}.py): faces in `TopExp::MapShapes` order, edges
//! numbered in each face's order, the same loops, mirror rule, bounds and gap bridges.
//!
//! Specification: OCCT's "BRep Format" (dev.opencascade.org, specification__brep_format).

use std::fmt;

use crate::model::{Document, FORMAT, Units, VERSION};

mod curves;
mod edges;
mod explore;
mod faces;
mod geometry;
mod lexer;
mod locations;
mod segment;
mod surfaces;
mod topology;

use explore::{Occ, ShapeMap, Walker};
use geometry::Geometry;
use lexer::Lexer;
use locations::Locations;
use topology::{Kind, Topology};

/// What the reader needs besides the text: OCCT's BREP carries no length unit.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// The unit of the file's coordinates (FreeCAD and most OCCT programs: millimetres).
    pub units: Units,
    /// The document's `source` (free text naming where the shape came from).
    pub source: Option<String>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            units: Units::Millimetres,
            source: None,
        }
    }
}

/// Why a BREP text was not read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OcctErrorKind {
    /// The text breaks the format (truncated, a bad number, an index out of range).
    Syntax,
    /// Well-formed, but holds geometry the exchange format has no exact type for (offset
    /// surfaces, ...): a host can fall back to its own exporter.
    Unsupported,
}

/// A BREP text the reader refused; the message names the line and the element.
#[derive(Clone, Debug, PartialEq)]
pub struct OcctError {
    /// Syntax or unsupported geometry.
    pub kind: OcctErrorKind,
    /// What and where (`line 812: Surfaces[14]: unknown surface type 12`, `face 7: offset
    /// surface`).
    pub message: String,
}

impl fmt::Display for OcctError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for OcctError {}

/// Whether `text` looks like an OCCT BREP text (its first non-blank line is
/// `DBRep_DrawableShape` or `CASCADE Topology V…`), so callers can tell it from JSON.
pub fn is_occt_brep(text: &str) -> bool {
    let first = text.lines().map(str::trim).find(|l| !l.is_empty());
    matches!(first, Some(l) if l == "DBRep_DrawableShape" || l.starts_with("CASCADE Topology V"))
}

/// Reads a BREP text into a document (not yet validated: call [`Document::validate`]).
///
/// The document is the one the Python exporters write for the same shape: faces numbered by
/// `TopExp::MapShapes(shape, FACE)`, edges by the faces' edges in that order, coordinates as
/// in the text (in `options.units`). Versions 1, 2 and 3 of "CASCADE Topology" are read;
/// polygons and triangulations are read past.
///
/// # Errors
/// [`OcctErrorKind::Syntax`] for text that breaks the format, [`OcctErrorKind::Unsupported`]
/// for geometry without an exact exchange-format type.
pub fn read(text: &str, options: &ReadOptions) -> Result<Document, OcctError> {
    let (version, mut lx) = header(text)?;
    let mut locations = Locations::read(&mut lx)?;
    let geometry = Geometry::read(&mut lx, version)?;
    let topology = Topology::read(&mut lx, version, &geometry, &locations)?;
    let mut w = Walker::new(&topology, &mut locations);
    let root = Occ::root(&topology.root);

    let mut face_map = ShapeMap::default();
    for f in w.explore(root, Kind::Face)? {
        face_map.add(f);
    }
    let mut edge_map = ShapeMap::default();
    for &f in &face_map.items {
        for e in w.explore(f, Kind::Edge)? {
            edge_map.add(e);
        }
    }
    let mut shared = faces::Shared {
        geometry: &geometry,
        edges: &edge_map,
        edge_faces: vec![Vec::new(); edge_map.items.len()],
    };
    let mut faces = Vec::with_capacity(face_map.items.len());
    for (i, &f) in face_map.items.iter().enumerate() {
        faces.push(faces::export(&mut w, &mut shared, i + 1, f)?);
    }
    let edge_faces = std::mem::take(&mut shared.edge_faces);
    let mut edges = Vec::with_capacity(edge_map.items.len());
    for ((i, &e), f) in edge_map.items.iter().enumerate().zip(edge_faces) {
        edges.push(edges::export(&mut w, &geometry, i + 1, e, f)?);
    }
    Ok(Document {
        format: FORMAT.to_string(),
        version: VERSION,
        units: options.units,
        source: options.source.clone(),
        faces,
        edges: Some(edges),
    })
}

/// The version of the `CASCADE Topology V<n>, …` line (after an optional
/// `DBRep_DrawableShape` line) and a lexer at the line after it.
fn header(text: &str) -> Result<(u32, Lexer<'_>), OcctError> {
    let mut pos = 0;
    let mut content_type = false;
    for (i, raw) in text.split_inclusive('\n').enumerate() {
        let line = raw.trim();
        pos += raw.len();
        let number = i as u32 + 1;
        if line.is_empty() {
            continue;
        }
        if line == "DBRep_DrawableShape" && !content_type {
            content_type = true;
            continue;
        }
        let Some(rest) = line.strip_prefix("CASCADE Topology V") else {
            return Err(OcctError {
                kind: OcctErrorKind::Syntax,
                message: format!(
                    "line {number}: header: expected `CASCADE Topology V1`, `V2` or `V3`, \
                     found `{}`",
                    line.chars().take(60).collect::<String>()
                ),
            });
        };
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        return match digits.parse::<u32>() {
            Ok(v @ 1..=3) => Ok((v, Lexer::new(text, pos, number + 1))),
            _ => Err(OcctError {
                kind: OcctErrorKind::Unsupported,
                message: format!(
                    "line {number}: header: CASCADE Topology V{digits}: only versions 1, 2 \
                     and 3 are read"
                ),
            }),
        };
    }
    Err(OcctError {
        kind: OcctErrorKind::Syntax,
        message: "header: no `CASCADE Topology` line (an empty or truncated text)".into(),
    })
}

/// An error of the location algebra (a hostile chain) as a syntax error.
fn syntax(message: String) -> OcctError {
    OcctError {
        kind: OcctErrorKind::Syntax,
        message: format!("TShapes: {message}"),
    }
}

/// Geometry the exchange format has no exact type for.
fn unsupported(message: String) -> OcctError {
    OcctError {
        kind: OcctErrorKind::Unsupported,
        message,
    }
}
