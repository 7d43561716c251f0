//! The B-Rep input of a request (`brep.load`, `tessellate`, `trim.classify`, `render`): the
//! exchange format's JSON from a file or inline, payload arrays by reference, or
//! OpenCASCADE's BREP text, and the `units` that text needs.

use crate::ops::library_errors::brep_error;
use serde_json::{Map, Value};
use std::path::Path;
use tessd_brep::occt::{self, OcctError, OcctErrorKind};
use tessd_brep::{Document, Units};
use tessd_ipc::arrays::{Arrays, DType};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::registry::Request;

/// The request's B-Rep as a document, not yet validated (shared by the ops that take one:
/// `brep.load`, `tessellate`, `trim.classify`, `render`). Either the exchange format's JSON —
/// the file `input` or the object `brep`, payload array references resolved — or
/// OpenCASCADE's own BREP text — an `input` ending `.brep` / `.brp`, or `brep` as a string
/// (FreeCAD's `Shape.exportBrepToString()`) — read by `tessd_brep::occt` in the units of
/// `units` (default `"mm"`; that text carries none).
///
/// # Errors
/// `invalid_request` for missing or conflicting parameters and unknown array references,
/// `io` when the file cannot be read, `invalid_brep` for JSON that is no document or BREP
/// text that breaks its format (naming the line), `unsupported` for BREP geometry the
/// exchange format has no exact type for (a host can fall back to its own exporter).
pub fn request_brep(request: &mut Request) -> Result<Document, OpError> {
    let units = occt_units(request)?;
    let inline = request.params.remove("brep").filter(|v| !v.is_null());
    let (mut value, where_) = match (request.str_param("input")?, inline) {
        (Some(_), Some(_)) => {
            return Err(OpError::request(
                "give the document as `input` (a path) or `brep` (inline), not both",
            ));
        }
        (Some(path), None) => {
            let path = request.resolve(path);
            let text = std::fs::read_to_string(&path).map_err(|e| {
                OpError::new(
                    ErrorCode::Io,
                    format!("cannot read {}: {e}", path.display()),
                )
            })?;
            let name = path.display().to_string();
            if is_occt_path(&path) || occt::is_occt_brep(&text) {
                let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned());
                return read_occt(&text, units, &name, file_name);
            }
            let value = serde_json::from_str(&text).map_err(|e| {
                OpError::new(
                    ErrorCode::InvalidBrep,
                    format!("{name}: not JSON: {e}{}", cad_file_hint(&path)),
                )
            })?;
            (value, name)
        }
        (None, Some(Value::String(text))) => {
            if !occt::is_occt_brep(&text) {
                return Err(OpError::new(
                    ErrorCode::InvalidBrep,
                    "`brep` as a string must be OpenCASCADE BREP text (starting \
                     `DBRep_DrawableShape` or `CASCADE Topology V1`); give a tessd-brep \
                     document as a JSON object, a file's path as `input`",
                ));
            }
            return read_occt(&text, units, "`brep`", None);
        }
        (None, Some(v @ Value::Object(_))) => (v, "`brep`".to_string()),
        (None, Some(v)) => {
            return Err(OpError::request(format!(
                "`brep` must be the document as a JSON object or OpenCASCADE BREP text as a string, got {}",
                kind(&v)
            )));
        }
        (None, None) => {
            return Err(OpError::request(
                "`input` (a path to a B-Rep JSON document or an OpenCASCADE .brep file) or `brep` (the document inline) is required",
            ));
        }
    };
    if units.is_some() {
        return Err(OpError::request(format!(
            "`units` applies to OpenCASCADE BREP text only: the document {where_} names its own"
        )));
    }
    resolve_array_refs(&mut value, &request.arrays)?;
    Document::from_value(&value).map_err(brep_error)
}

/// Whether `path` names OpenCASCADE BREP text by its extension (`.brep`, `.brp`, any case).
pub fn is_occt_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("brep") || e.eq_ignore_ascii_case("brp"))
}

/// Whether `path` names a B-Rep input by its extension: a JSON document or BREP text.
pub fn is_brep_path(path: &Path) -> bool {
    is_occt_path(path)
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// The `units` parameter, `None` when absent.
fn occt_units(request: &Request) -> Result<Option<Units>, OpError> {
    let Some(name) = request.str_param("units")? else {
        return Ok(None);
    };
    Units::from_name(name).map(Some).ok_or_else(|| {
        OpError::request(format!(
            "`units` must be \"mm\", \"cm\", \"m\" or \"in\", got {name:?}"
        ))
    })
}

/// BREP text read into a document; errors name `where_` (the file or `brep`).
fn read_occt(
    text: &str,
    units: Option<Units>,
    where_: &str,
    source: Option<String>,
) -> Result<Document, OpError> {
    let options = occt::ReadOptions {
        units: units.unwrap_or(Units::Millimetres),
        source,
    };
    occt::read(text, &options).map_err(|e: OcctError| {
        let code = match e.kind {
            OcctErrorKind::Syntax => ErrorCode::InvalidBrep,
            OcctErrorKind::Unsupported => ErrorCode::Unsupported,
        };
        OpError::new(code, format!("{where_}: {e}"))
    })
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

/// Replaces every `{"array": "name"}` in the document by the payload array `name` as nested
/// lists of its shape (docs/brep-format.md, "Arrays by reference"), so the B-Rep crate reads
/// one JSON model whichever way the numbers travelled.
///
/// # Errors
/// `invalid_request` for a reference to an array the request does not carry, or of a dtype
/// that is not numeric; `invalid_brep` for a NaN or infinite element (naming the array and
/// the element's index).
pub fn resolve_array_refs(value: &mut Value, arrays: &Arrays) -> Result<(), OpError> {
    match value {
        Value::Object(map) => {
            if let Some(name) = array_ref(map) {
                *value = array_value(&name, arrays)?;
                return Ok(());
            }
            for v in map.values_mut() {
                resolve_array_refs(v, arrays)?;
            }
            Ok(())
        }
        Value::Array(items) => items
            .iter_mut()
            .try_for_each(|v| resolve_array_refs(v, arrays)),
        _ => Ok(()),
    }
}

/// The name of a reference object: exactly one key `array` holding a string.
fn array_ref(map: &Map<String, Value>) -> Option<String> {
    match (map.len(), map.get("array")) {
        (1, Some(Value::String(name))) => Some(name.clone()),
        _ => None,
    }
}

/// Array `name` as f64 values with its shape, from any numeric dtype, every element finite.
fn array_f64(name: &str, arrays: &Arrays) -> Result<(Vec<f64>, Vec<u64>), OpError> {
    let (data, shape) = array_as_f64(name, arrays)?;
    if let Some(i) = data.iter().position(|x| !x.is_finite()) {
        return Err(OpError::new(
            ErrorCode::InvalidBrep,
            format!("array {name:?}: element {i} is not finite"),
        ));
    }
    Ok((data, shape))
}

/// Array `name` as f64 values with its shape, from f64, f32 or a 32-bit or smaller integer
/// dtype (shared with `trim.classify`, which checks its points itself).
///
/// # Errors
/// `invalid_request` for a missing array or another dtype.
pub fn array_as_f64(name: &str, arrays: &Arrays) -> Result<(Vec<f64>, Vec<u64>), OpError> {
    let desc = arrays.desc(name).ok_or_else(|| {
        OpError::request(format!(
            "the document refers to array {name:?}, which the request does not carry"
        ))
    })?;
    fn conv<T: tessd_ipc::arrays::Element + Into<f64>>(
        arrays: &Arrays,
        name: &str,
    ) -> Result<(Vec<f64>, Vec<u64>), OpError> {
        let (data, shape) = arrays
            .get::<T>(name)
            .ok_or_else(|| OpError::request(format!("no array {name:?}")))?
            .map_err(OpError::request)?;
        Ok((data.iter().map(|&x| x.into()).collect(), shape.to_vec()))
    }
    let (data, shape) = match desc.dtype {
        DType::F64 => conv::<f64>(arrays, name)?,
        DType::F32 => conv::<f32>(arrays, name)?,
        DType::U32 => conv::<u32>(arrays, name)?,
        DType::I32 => conv::<i32>(arrays, name)?,
        DType::U16 => conv::<u16>(arrays, name)?,
        DType::U8 => conv::<u8>(arrays, name)?,
        other => {
            return Err(OpError::request(format!(
                "array {name:?} has dtype {}; a B-Rep array must be f64, f32 or a 32-bit integer type",
                other.name()
            )));
        }
    };
    Ok((data, shape))
}

/// Array `name` as nested JSON lists of its shape.
fn array_value(name: &str, arrays: &Arrays) -> Result<Value, OpError> {
    let (data, shape) = array_f64(name, arrays)?;
    Ok(nest(&data, &shape))
}

fn nest(data: &[f64], shape: &[u64]) -> Value {
    match shape.split_first() {
        None => number(data.first().copied().unwrap_or(0.0)),
        Some((_, [])) => Value::Array(data.iter().map(|&x| number(x)).collect()),
        Some((&n, rest)) => {
            let stride: u64 = rest.iter().product();
            Value::Array(
                (0..n)
                    .map(|i| {
                        let start = (i * stride) as usize;
                        nest(&data[start..start + stride as usize], rest)
                    })
                    .collect(),
            )
        }
    }
}

/// A JSON number; whole values as integers, so that multiplicities sent as floats still read
/// as integers (and coordinates read integers as floats anyway).
fn number(x: f64) -> Value {
    if x.fract() == 0.0 && x.abs() < 9.0e15 {
        Value::from(x as i64)
    } else {
        serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
    }
}

/// The next step for a CAD exchange file tessd does not read itself (STEP, IGES): export it
/// to a `tessd-brep` JSON document through OCP; empty for other files.
pub fn cad_file_hint(path: &std::path::Path) -> String {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let kind = match ext.as_str() {
        "step" | "stp" => "STEP",
        "iges" | "igs" => "IGES",
        _ => return String::new(),
    };
    let file = path
        .file_name()
        .map_or_else(|| "PART".into(), |n| n.to_string_lossy().into_owned());
    let json = path
        .file_stem()
        .map_or_else(|| "PART".into(), |n| n.to_string_lossy().into_owned());
    format!(
        "; tessd reads B-Rep JSON documents and OpenCASCADE .brep files, not {kind}: export it \
         first with `python -m tessd.brep export {file} {json}.json` (it needs OCP: \
         `pip install 'tessd[cad]'`, or the CAD venv .venv-cad from scripts/setup.sh)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use tessd_ipc::arrays::OwnedArray;

    #[test]
    fn references_become_nested_lists() {
        let arrays = Arrays::from_owned(&[
            OwnedArray::new("p", vec![2, 1, 3], vec![1.5f64, 2.0, 3.0, 4.0, 5.0, 6.25]),
            OwnedArray::new("m", vec![2], vec![3.0f32, 3.0]),
            OwnedArray::new("bad", vec![1], vec![f64::NAN]),
        ]);
        let mut v = json!({"poles": {"array": "p"}, "mults": {"array": "m"},
                           "keep": {"array": "p", "other": 1}});
        resolve_array_refs(&mut v, &arrays).unwrap();
        assert_eq!(v["poles"], json!([[[1.5, 2, 3]], [[4, 5, 6.25]]]));
        assert_eq!(v["mults"], json!([3, 3]));
        assert_eq!(v["keep"], json!({"array": "p", "other": 1}));
        let e = resolve_array_refs(&mut json!([{"array": "missing"}]), &arrays).unwrap_err();
        assert_eq!(e.code, ErrorCode::InvalidRequest);
        assert!(e.message.contains("\"missing\""), "{}", e.message);
        let e = resolve_array_refs(&mut json!({"w": {"array": "bad"}}), &arrays).unwrap_err();
        assert_eq!(e.code, ErrorCode::InvalidBrep);
        assert!(e.message.contains("element 0"), "{}", e.message);
    }
}
