//! The B-Rep face model of tessd: the exchange format (docs/brep-format.md) that carries CAD
//! faces — basis surfaces with trim loops in their parameter plane — from exporters (OCP,
//! FreeCAD) to the daemon, its validation, and the evaluation of surfaces and curves that the
//! trim and tessellation stages build on.
//!
//! ```
//! let doc = tessd_brep::Document::from_json(r#"{
//!     "format": "tessd-brep", "version": 1, "units": "mm",
//!     "faces": [{"id": 0, "surface": {"type": "plane", "origin": [0, 0, 0],
//!                "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]}, "bounds": [0, 1, 0, 1]}]
//! }"#).unwrap();
//! doc.validate().unwrap();
//! assert_eq!(doc.faces[0].surface.point(0.5, 0.25).to_array(), [0.5, 0.25, 0.0]);
//! assert_eq!(doc.stats().faces_by_surface["plane"], 1);
//! ```
//!
//! The crate knows nothing about sockets or requests: the daemon's `brep.load` resolves
//! payload arrays into the JSON before handing it here.

#![warn(missing_docs)]

pub mod bounds;
pub mod bspline;
pub mod curve;
pub mod knot_cache;
pub mod model;
pub mod occt;
pub mod stats;
pub mod surface;
pub mod tolerances;
pub mod transform;
pub mod validate;
pub mod validation_error;
pub mod vector;

pub use bounds::BoundingBox;
/// The point / vector types of the model ([`vector::Point2`], [`vector::Point3`]), and glam itself,
/// so dependents use the very version the document types are made of.
pub use glam::{self, DVec2, DVec3};
pub use model::{
    BSplineCurve, BSplineSurface, Curve, Curve2, Curve3, Document, Edge, FORMAT, Face, Frame, Loop,
    Surface, Trim, Units, VERSION,
};
pub use stats::Stats;
pub use surface::SurfacePoint;
pub use validation_error::{Place, ValidationError};

use serde::Deserialize;
use serde_json::Value;

impl Document {
    /// Reads a document from JSON text: syntax, then `format` and `version` (so a future
    /// version is refused as such, not as a pile of structure errors), then the structure.
    /// The geometry is not checked yet: call [`Document::validate`].
    ///
    /// # Errors
    /// [`ValidationError::Json`], `Format`, `Version`, or `Structure` naming the face, loop and
    /// trim whose JSON is wrong.
    pub fn from_json(text: &str) -> Result<Document, ValidationError> {
        let value: Value = serde_json::from_str(text).map_err(|e| ValidationError::Json {
            message: e.to_string(),
        })?;
        Document::from_value(&value)
    }

    /// Reads a document from an already parsed JSON value (a request's inline document).
    ///
    /// # Errors
    /// As [`Document::from_json`], less `Json`.
    pub fn from_value(value: &Value) -> Result<Document, ValidationError> {
        let Value::Object(map) = value else {
            return Err(ValidationError::Structure {
                at: "document".into(),
                message: format!("expected a JSON object, got {value}"),
            });
        };
        match map.get("format") {
            Some(Value::String(s)) if s == FORMAT => {}
            other => {
                return Err(ValidationError::Format {
                    found: other.map_or("nothing".into(), Value::to_string),
                });
            }
        }
        match map.get("version") {
            Some(v) if v.as_u64() == Some(VERSION) => {}
            other => {
                return Err(ValidationError::Version {
                    found: other.map_or("nothing".into(), Value::to_string),
                });
            }
        }
        Document::deserialize(value).map_err(|e| locate(value, e))
    }

    /// The document as JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Checks every rule of docs/brep-format.md ("Validation").
    ///
    /// # Errors
    /// The first [`ValidationError`] in document order; [`Document::errors`] lists them all.
    pub fn validate(&self) -> Result<(), ValidationError> {
        match validate::validate(self).into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Every validation error, in document order (empty for a valid document).
    pub fn errors(&self) -> Vec<ValidationError> {
        validate::validate(self)
    }

    /// The table-1 counts of the document.
    pub fn stats(&self) -> Stats {
        Stats::of(self)
    }

    /// The face with `id`.
    pub fn face(&self, id: u64) -> Option<&Face> {
        self.faces.iter().find(|f| f.id == id)
    }
}

/// Turns serde's error about the whole document into one naming the element: the first face
/// (then its surface, then its trims) or edge that does not deserialise on its own.
fn locate(doc: &Value, whole: serde_json::Error) -> ValidationError {
    let structure = |at: String, e: serde_json::Error| ValidationError::Structure {
        at,
        message: e.to_string(),
    };
    let named = |kind: &str, v: &Value, i: usize| match v.get("id").and_then(Value::as_u64) {
        Some(id) => format!("{kind} {id}"),
        None => format!("{kind} at index {i}"),
    };
    for (i, f) in doc
        .get("faces")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
    {
        let Err(e) = Face::deserialize(f) else {
            continue;
        };
        let name = named("face", f, i);
        if let Some(Err(e)) = f.get("surface").map(Surface::deserialize) {
            return structure(format!("{name}, surface"), e);
        }
        for (l, lp) in f
            .get("loops")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            for (t, trim) in lp
                .get("edges")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .enumerate()
            {
                if let Err(e) = Trim::deserialize(trim) {
                    return structure(format!("{name}, loop {l}, trim {t}"), e);
                }
            }
            if let Err(e) = Loop::deserialize(lp) {
                return structure(format!("{name}, loop {l}"), e);
            }
        }
        return structure(name, e);
    }
    for (i, edge) in doc
        .get("edges")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
    {
        if let Err(e) = Edge::deserialize(edge) {
            return structure(named("edge", edge, i), e);
        }
    }
    structure("document".into(), whole)
}
