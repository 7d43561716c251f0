//! Typed scalar parameters every op reads the same way: booleans, non-negative integers,
//! positive amounts (a number or a percentage), and the plain decimals they are written in.
//! Each refusal names its parameter in backticks (the CLI turns it into the flag).

use serde_json::Value;
use tessd_ipc::error::OpError;
use tessd_ipc::registry::Request;

/// An optional boolean parameter.
///
/// # Errors
/// `invalid_request` when present with another type.
pub fn bool_param(request: &Request, key: &str) -> Result<Option<bool>, OpError> {
    match request.params.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Bool(b)) => Ok(Some(*b)),
        Some(v) => Err(OpError::request(format!(
            "parameter `{key}` must be true or false, got {v}"
        ))),
    }
}

/// An optional non-negative integer parameter (a JSON integer, or a number without a
/// fractional part).
///
/// # Errors
/// `invalid_request` when present and not such a number.
pub fn u64_param(request: &Request, key: &str) -> Result<Option<u64>, OpError> {
    match request.params.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => as_u64(v).map(Some).ok_or_else(|| {
            OpError::request(format!(
                "parameter `{key}` must be a non-negative integer, got {v}"
            ))
        }),
    }
}

/// A `u32` parameter with a default.
pub fn u32_param(request: &Request, key: &str, default: u32) -> Result<u32, OpError> {
    match u64_param(request, key)? {
        None => Ok(default),
        Some(v) => u32::try_from(v)
            .map_err(|_| OpError::request(format!("parameter `{key}` is too large: {v}"))),
    }
}

/// `v` as a non-negative integer, when it is one (`8` or `8.0`).
pub fn as_u64(v: &Value) -> Option<u64> {
    v.as_u64().or_else(|| {
        v.as_f64()
            .filter(|f| f.is_finite() && *f >= 0.0 && f.fract() == 0.0 && *f < 2f64.powi(63))
            .map(|f| f as u64)
    })
}

/// A positive amount, absolute or a percentage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Amount {
    /// A plain positive number.
    Absolute(f64),
    /// A positive percentage (`"0.5%"` is `Percent(0.5)`).
    Percent(f64),
}

/// Parses a positive amount: a JSON number, or a string holding a number (`"0.2"`) or a
/// percentage (`"0.5%"`). `what` names the parameter in messages.
///
/// # Errors
/// `invalid_request` for anything else: other types, text that is not a number (`"abc%"`),
/// zero, negative, NaN or infinite values.
pub fn parse_amount(what: &str, v: &Value) -> Result<Amount, OpError> {
    let bad = || {
        OpError::request(format!(
            "`{what}` must be a positive number or a percentage such as \"5%\", got {v}"
        ))
    };
    let (x, percent) = match v {
        Value::Number(n) => (n.as_f64().ok_or_else(bad)?, false),
        Value::String(s) => {
            let s = s.trim();
            let (digits, percent) = match s.strip_suffix('%') {
                Some(d) => (d.trim_end(), true),
                None => (s, false),
            };
            (plain_number(digits).ok_or_else(bad)?, percent)
        }
        _ => return Err(bad()),
    };
    if !x.is_finite() {
        return Err(bad());
    }
    if x <= 0.0 {
        let shown = if percent {
            format!("{x}%")
        } else {
            x.to_string()
        };
        return Err(OpError::request(format!(
            "`{what}` must be positive, got {shown}"
        )));
    }
    Ok(if percent {
        Amount::Percent(x)
    } else {
        Amount::Absolute(x)
    })
}

/// `text` as a number when it is a plain decimal (digits, sign, point, exponent): Rust's `parse`
/// also accepts `"inf"` and `"NaN"`, which no parameter wants.
pub fn plain_number(text: &str) -> Option<f64> {
    let plain = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E'));
    if plain { text.parse().ok() } else { None }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use tessd_ipc::error::ErrorCode;

    #[test]
    fn amounts() {
        let ok = |v: Value| parse_amount("x", &v).unwrap();
        assert_eq!(ok(json!(0.5)), Amount::Absolute(0.5));
        assert_eq!(ok(json!(20000)), Amount::Absolute(20000.0));
        assert_eq!(ok(json!("0.2")), Amount::Absolute(0.2));
        assert_eq!(ok(json!("0.5%")), Amount::Percent(0.5));
        assert_eq!(ok(json!(" 50 % ")), Amount::Percent(50.0));
        assert_eq!(ok(json!("1e-1%")), Amount::Percent(0.1));
        for bad in [
            json!("abc%"),
            json!("%"),
            json!(""),
            json!("-5%"),
            json!("0%"),
            json!("NaN%"),
            json!("inf%"),
            json!("infinity"),
            json!("1e400%"),
            json!("5%%"),
            json!(-1),
            json!(0),
            json!(true),
            json!([1]),
            json!(null),
        ] {
            let e = parse_amount("max_error", &bad).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest, "{bad}");
            assert!(e.message.contains("`max_error`"), "{}", e.message);
        }
        assert_eq!(
            parse_amount("max_error", &json!(-1)).unwrap_err().message,
            "`max_error` must be positive, got -1"
        );
        assert_eq!(
            parse_amount("t", &json!("-5%")).unwrap_err().message,
            "`t` must be positive, got -5%"
        );
    }

    #[test]
    fn integers() {
        assert_eq!(as_u64(&json!(8)), Some(8));
        assert_eq!(as_u64(&json!(8.0)), Some(8));
        assert_eq!(as_u64(&json!(8.5)), None);
        assert_eq!(as_u64(&json!(-1)), None);
        assert_eq!(as_u64(&json!("8")), None);
    }
}
