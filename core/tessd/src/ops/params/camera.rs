//! The camera and image parameters of `render` and `codec.view`: points and directions as
//! `[x, y, z]`, and the image size.

use crate::ops::library_errors::render_error;
use serde_json::Value;
use tessd_ipc::error::OpError;
use tessd_ipc::registry::Request;

/// The default image size.
pub const DEFAULT_SIZE: (u32, u32) = (1280, 720);

/// Parses `size`: `"WIDTHxHEIGHT"` or `[width, height]`, checked against the renderer's limits
/// ([`tessd_render::check_size`]).
///
/// # Errors
/// `invalid_request` naming the value.
pub fn parse_size(v: Option<&Value>) -> Result<(u32, u32), OpError> {
    let bad = |v: &Value| {
        OpError::request(format!(
            "`size` must be \"WIDTHxHEIGHT\" (such as \"1280x720\") or [width, height], got {v}"
        ))
    };
    let (w, h) = match v {
        None | Some(Value::Null) => DEFAULT_SIZE,
        Some(v @ Value::String(s)) => {
            let (a, b) = s.trim().split_once(['x', 'X']).ok_or_else(|| bad(v))?;
            let parse = |t: &str| t.trim().parse::<u32>().map_err(|_| bad(v));
            (parse(a)?, parse(b)?)
        }
        Some(v @ Value::Array(items)) if items.len() == 2 => {
            let side = |x: &Value| {
                x.as_u64()
                    .and_then(|n| u32::try_from(n).ok())
                    .ok_or_else(|| bad(v))
            };
            (side(&items[0])?, side(&items[1])?)
        }
        Some(v) => return Err(bad(v)),
    };
    tessd_render::check_size(w, h, tessd_render::MAX_SIDE).map_err(render_error)?;
    Ok((w, h))
}

/// An optional `[x, y, z]` of finite numbers.
pub fn vec3_param(request: &Request, key: &str) -> Result<Option<[f64; 3]>, OpError> {
    match request.params.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => {
            let bad = || {
                OpError::request(format!(
                    "`{key}` must be [x, y, z] (finite numbers), got {v}"
                ))
            };
            let items = v.as_array().filter(|a| a.len() == 3).ok_or_else(bad)?;
            let mut out = [0.0; 3];
            for (k, item) in items.iter().enumerate() {
                out[k] = item.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
            }
            Ok(Some(out))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use tessd_ipc::error::ErrorCode;

    #[test]
    fn sizes() {
        assert_eq!(parse_size(None).unwrap(), (1280, 720));
        assert_eq!(parse_size(Some(&json!("640x480"))).unwrap(), (640, 480));
        assert_eq!(parse_size(Some(&json!([3, 2]))).unwrap(), (3, 2));
        for (bad, shown) in [
            (json!("0x0"), "0x0"),
            (json!("100000x100000"), "100000x100000"),
            (json!("12"), "\"12\""),
            (json!("-1x5"), "\"-1x5\""),
            (json!([1]), "[1]"),
        ] {
            let e = parse_size(Some(&bad)).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest);
            assert!(e.message.contains(shown), "{}", e.message);
        }
    }
}
