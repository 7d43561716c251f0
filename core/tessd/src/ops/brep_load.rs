//! `brep.load`: reads a B-Rep exchange document (docs/brep-format.md) from a file or inline,
//! resolves arrays by reference from the request's payload, validates it (`tessd-brep`), and
//! reports the face ids and the paper's table-1 counts, so a host learns before any
//! tessellation whether its export is sound and what it holds.
//!
//! Parameters are described in docs/protocol.md ("brep.load").

use serde_json::{Map, Value, json};
use tessd_brep::{Document, ValidationError};
use tessd_ipc::arrays::{Arrays, DType};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

/// Maps a refusal of the document to `invalid_brep`, its message naming the element.
pub fn brep_error(e: ValidationError) -> OpError {
    OpError::new(ErrorCode::InvalidBrep, e.to_string())
}

/// The operation.
///
/// # Errors
/// `invalid_request` for missing or conflicting parameters and unknown array references,
/// `io` when the file cannot be read, `invalid_brep` for a document the validator refuses
/// (its first error, with the count of the others).
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let value = request_document(&mut request)?;
    ctx.progress(0.3, "parse", "")?;
    let doc = Document::from_value(&value).map_err(brep_error)?;
    drop(value);
    ctx.progress(0.5, "validate", "")?;
    let errors = doc.errors();
    if let Some(first) = errors.first() {
        let mut message = first.to_string();
        if errors.len() > 1 {
            message.push_str(&format!(
                " (and {} more error{})",
                errors.len() - 1,
                if errors.len() == 2 { "" } else { "s" }
            ));
        }
        return Err(OpError::new(ErrorCode::InvalidBrep, message));
    }
    let result = json!({
        "format": doc.format,
        "version": doc.version,
        "units": doc.units.name(),
        "source": doc.source,
        "faces": doc.faces.iter().map(|f| f.id).collect::<Vec<_>>(),
        "edges": doc.edges.as_ref().map(|e| e.iter().map(|e| e.id).collect::<Vec<_>>()),
        "stats": doc.stats(),
    });
    ctx.progress(1.0, "done", "")?;
    Ok(Response::json(result))
}

/// The request's document as JSON, its payload array references resolved (shared by the ops
/// that take a B-Rep document: `brep.load`, `tessellate`).
///
/// # Errors
/// As [`document_value`] and [`resolve_array_refs`].
pub fn request_document(request: &mut Request) -> Result<Value, OpError> {
    let mut value = document_value(request)?;
    resolve_array_refs(&mut value, &request.arrays)?;
    Ok(value)
}

/// The document as JSON: the file `input` (resolved against the request's folder) or the
/// object `brep`, exactly one of them.
fn document_value(request: &mut Request) -> Result<Value, OpError> {
    let inline = request.params.remove("brep").filter(|v| !v.is_null());
    match (request.str_param("input")?, inline) {
        (Some(_), Some(_)) => Err(OpError::request(
            "give the document as `input` (a path) or `brep` (inline), not both",
        )),
        (Some(path), None) => {
            let path = request.resolve(path);
            let text = std::fs::read_to_string(&path).map_err(|e| {
                OpError::new(
                    ErrorCode::Io,
                    format!("cannot read {}: {e}", path.display()),
                )
            })?;
            serde_json::from_str(&text).map_err(|e| {
                OpError::new(
                    ErrorCode::InvalidBrep,
                    format!("{}: not JSON: {e}", path.display()),
                )
            })
        }
        (None, Some(v @ Value::Object(_))) => Ok(v),
        (None, Some(v)) => Err(OpError::request(format!(
            "`brep` must be the document as a JSON object, got {}",
            kind(&v)
        ))),
        (None, None) => Err(OpError::request(
            "`input` (a path to a B-Rep JSON document) or `brep` (the document inline) is required",
        )),
    }
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

#[cfg(test)]
mod tests {
    use super::*;
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
