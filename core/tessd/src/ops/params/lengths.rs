//! Lengths, units and tolerances as requests give them: a number in the model's units, a
//! length with a unit (`"0.1mm"`), or a percentage of the part's bounding-box diagonal; and
//! the `units` a mesh request names (mesh files carry none).

use super::scalars::plain_number;
use crate::ops::library_errors::brep_error;
use serde_json::{Value, json};
use tessd_brep::{Document, Units};
use tessd_ipc::error::OpError;
use tessd_ipc::registry::Request;

/// `params.units`, the unit of a mesh's coordinates (mm, cm, m, in), when the request names
/// one: mesh files carry none.
///
/// # Errors
/// `invalid_request` for another name.
pub fn mesh_units(request: &Request) -> Result<Option<tessd_brep::Units>, OpError> {
    let Some(name) = request.str_param("units")? else {
        return Ok(None);
    };
    tessd_brep::Units::from_name(name).map(Some).ok_or_else(|| {
        OpError::request(format!(
            "`units` (the unit of the mesh's coordinates) must be mm, cm, m or in, got {name:?}"
        ))
    })
}

/// Parses a length: a positive number (document units) or a string holding one, optionally
/// with a unit suffix (`"0.1mm"`, `"0.01 in"`, `"2cm"`, `"0.001m"`) converted into `units`.
///
/// # Errors
/// `invalid_request` naming `what` for anything else.
pub fn parse_length(what: &str, v: &Value, units: Units) -> Result<f64, OpError> {
    let bad = || {
        OpError::request(format!(
            "`{what}` must be a positive length: a number in the document's units ({}) or a string such as \"0.1mm\" (mm, cm, m, in), got {v}",
            units.name()
        ))
    };
    let x = match v {
        Value::Number(n) => n.as_f64().ok_or_else(bad)?,
        Value::String(s) => {
            let s = s.trim();
            let split = s
                .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
                .unwrap_or(s.len());
            let (digits, unit) = (s[..split].trim(), s[split..].trim());
            let x = plain_number(digits).ok_or_else(bad)?;
            let metres = match unit {
                "" => units.meters_per_unit(),
                name => Units::from_name(name).ok_or_else(bad)?.meters_per_unit(),
            };
            x * metres / units.meters_per_unit()
        }
        _ => return Err(bad()),
    };
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(bad())
    }
}

/// A chordal tolerance as a request gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// A length in the document's units.
    Length(f64),
    /// A percentage of the part's bounding-box diagonal (`"0.05%"` is `Percent(0.05)`).
    Percent(f64),
}

/// Parses `tolerance`: a length as [`parse_length`] reads it, or a string holding a positive
/// percentage (`"0.05%"`, `" 0.05 % "`) of the part's bounding-box diagonal.
///
/// # Errors
/// `invalid_request` naming `tolerance` and the value for anything else (zero, negative, NaN or
/// infinite percentages included).
pub fn parse_tolerance(v: &Value, units: Units) -> Result<Tolerance, OpError> {
    if let Some(digits) = v.as_str().and_then(|s| s.trim().strip_suffix('%')) {
        return match plain_number(digits.trim_end()) {
            Some(p) if p.is_finite() && p > 0.0 => Ok(Tolerance::Percent(p)),
            _ => Err(OpError::request(format!(
                "`tolerance` must be a positive percentage of the part's bounding-box diagonal, such as \"0.05%\", got {v}"
            ))),
        };
    }
    parse_length("tolerance", v, units)
        .map(Tolerance::Length)
        .map_err(|_| {
            OpError::request(format!(
                "`tolerance` must be a positive length (a number in the document's units, {}, or a string such as \"0.1mm\": mm, cm, m, in) or a percentage of the part's bounding-box diagonal such as \"0.05%\", got {v}",
                units.name()
            ))
        })
}

/// The absolute tolerance `asked` means for `doc`, with, for a percentage, the bounding-box
/// diagonal it was taken of.
///
/// # Errors
/// `invalid_request` naming `tolerance` and the value when a percentage has no geometry to be
/// taken of (no faces, or a box of zero size); `invalid_brep` when that is because the
/// document does not validate.
pub fn absolute_tolerance(asked: Tolerance, doc: &Document) -> Result<(f64, Option<f64>), OpError> {
    let p = match asked {
        Tolerance::Length(x) => return Ok((x, None)),
        Tolerance::Percent(p) => p,
    };
    let diagonal = doc.bounding_box().map_or(0.0, |b| b.diagonal());
    let tolerance = p / 100.0 * diagonal;
    if tolerance.is_finite() && tolerance > 0.0 {
        return Ok((tolerance, Some(diagonal)));
    }
    if let Some(e) = doc.errors().into_iter().next() {
        return Err(brep_error(e));
    }
    if diagonal.is_finite() && diagonal > 0.0 {
        return Err(OpError::request(format!(
            "`tolerance` \"{p}%\" of the part's {diagonal} {} diagonal is not a finite length",
            doc.units.name()
        )));
    }
    Err(OpError::request(format!(
        "`tolerance` \"{p}%\" is a percentage of the part's bounding-box diagonal, but the document ({} faces) has no extent to take it of (diagonal {diagonal} {})",
        doc.faces.len(),
        doc.units.name()
    )))
}

/// Rewrites the length parameters `keys` (a value, or a list of values such as `lod`'s
/// `levels`) given with a unit (`"5mm"`, `"0.2 in"`; mm, cm, m, in) as numbers in the mesh's
/// model unit, which `params.units` names: a mesh file carries no unit, so a length with one
/// needs it (refused otherwise, saying so). Plain numbers (`0.2`, `"0.2"`) are model units and
/// percentages (`"1%"`) stay as they are.
///
/// # Errors
/// `invalid_request` for an unknown `units`, a unit-bearing length without `units`, or a
/// length [`parse_length`] refuses.
pub fn lengths_in_model_units(request: &mut Request, keys: &[&str]) -> Result<(), OpError> {
    let units = mesh_units(request)?;
    let convert = |key: &str, v: &mut Value| -> Result<(), OpError> {
        let Some(text) = v.as_str() else {
            return Ok(());
        };
        let t = text.trim();
        let has_unit = !t.ends_with('%')
            && t.chars()
                .any(|c| c.is_ascii_alphabetic() && c != 'e' && c != 'E');
        if !has_unit {
            // A plain number written as text is a number in model units.
            if let Some(x) = plain_number(t) {
                *v = json!(x);
            }
            return Ok(());
        }
        let Some(units) = units else {
            return Err(OpError::request(format!(
                "`{key}` {text:?} has a unit, but a mesh file has none: give `units` (the unit \
                 of the mesh's coordinates: mm, cm, m or in), or a number in model units"
            )));
        };
        *v = json!(parse_length(key, v, units)?);
        Ok(())
    };
    for &key in keys {
        match request.params.get_mut(key) {
            Some(Value::Array(items)) => {
                for item in items {
                    convert(key, item)?;
                }
            }
            Some(v) => convert(key, v)?,
            None => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use tessd_ipc::error::ErrorCode;

    #[test]
    fn lengths() {
        let mm = Units::Millimetres;
        let ok = |v: Value, u: Units| parse_length("tolerance", &v, u).unwrap();
        assert_eq!(ok(json!(0.1), mm), 0.1);
        assert_eq!(ok(json!("0.1"), mm), 0.1);
        assert!((ok(json!("0.1mm"), mm) - 0.1).abs() < 1e-12);
        assert!((ok(json!("1 cm"), mm) - 10.0).abs() < 1e-12);
        assert!((ok(json!("0.1mm"), Units::Metres) - 1e-4).abs() < 1e-15);
        assert!((ok(json!("1in"), mm) - 25.4).abs() < 1e-12);
        assert!((ok(json!("1e-1mm"), mm) - 0.1).abs() < 1e-12);
        for bad in [
            json!("0.1ft"),
            json!("-1mm"),
            json!(0),
            json!("mm"),
            json!(true),
        ] {
            let e = parse_length("tolerance", &bad, mm).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest, "{bad}");
        }
        // `trim.classify` shares parse_length: a percentage is not a length there.
        assert!(parse_length("tolerance", &json!("0.05%"), mm).is_err());
    }

    #[test]
    fn tolerances() {
        let mm = Units::Millimetres;
        let ok = |v: Value| parse_tolerance(&v, mm).unwrap();
        assert_eq!(ok(json!("0.05%")), Tolerance::Percent(0.05));
        assert_eq!(ok(json!(" 0.05 % ")), Tolerance::Percent(0.05));
        assert_eq!(ok(json!("5e-2%")), Tolerance::Percent(0.05));
        assert_eq!(ok(json!("2%")), Tolerance::Percent(2.0));
        assert_eq!(ok(json!(0.1)), Tolerance::Length(0.1));
        assert_eq!(ok(json!("0.1")), Tolerance::Length(0.1));
        match ok(json!("0.1mm")) {
            Tolerance::Length(x) => assert!((x - 0.1).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
        match parse_tolerance(&json!("1cm"), Units::Metres).unwrap() {
            Tolerance::Length(x) => assert!((x - 0.01).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        for (bad, shown) in [
            (json!("0%"), r#""0%""#),
            (json!("-0.05%"), r#""-0.05%""#),
            (json!("NaN%"), r#""NaN%""#),
            (json!("inf%"), r#""inf%""#),
            (json!("1e400%"), r#""1e400%""#),
            (json!("%"), r#""%""#),
            (json!("0.05%%"), r#""0.05%%""#),
            (json!("abc%"), r#""abc%""#),
            (json!("0.05 %mm"), r#""0.05 %mm""#),
            (json!("0.1ft"), r#""0.1ft""#),
            (json!(-1), "-1"),
            (json!(0), "0"),
            (json!(true), "true"),
        ] {
            let e = parse_tolerance(&bad, mm).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest, "{bad}");
            assert!(e.message.starts_with("`tolerance` "), "{}", e.message);
            assert!(
                e.message.ends_with(&format!("got {shown}")),
                "{}",
                e.message
            );
        }
        assert_eq!(
            parse_tolerance(&json!("0%"), mm).unwrap_err().message,
            r#"`tolerance` must be a positive percentage of the part's bounding-box diagonal, such as "0.05%", got "0%""#
        );
    }

    fn plate(scale: f64) -> Document {
        // A 40 × 30 plane face at z = 10 (times `scale`): a 50 diagonal.
        Document::from_value(&json!({
            "format": "tessd-brep", "version": 1, "units": "mm",
            "faces": [{"id": 0, "surface": {"type": "plane", "origin": [0, 0, 10.0 * scale],
                       "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]},
                       "bounds": [0, 40.0 * scale, 0, 30.0 * scale]}]
        }))
        .unwrap()
    }

    #[test]
    fn percent_of_the_diagonal() {
        let (t, d) = absolute_tolerance(Tolerance::Percent(0.05), &plate(1.0)).unwrap();
        assert!((d.unwrap() - 50.0).abs() < 1e-12 && (t - 0.025).abs() < 1e-12);
        let (t, d) = absolute_tolerance(Tolerance::Percent(0.05), &plate(1e-3)).unwrap();
        assert!((d.unwrap() - 0.05).abs() < 1e-15 && (t - 2.5e-5).abs() < 1e-15);
        assert_eq!(
            absolute_tolerance(Tolerance::Length(0.1), &plate(1e-3)).unwrap(),
            (0.1, None)
        );
        let mut empty = plate(1.0);
        empty.faces.clear();
        let e = absolute_tolerance(Tolerance::Percent(0.05), &empty).unwrap_err();
        assert_eq!(e.code, ErrorCode::InvalidRequest);
        assert!(
            e.message
                .starts_with(r#"`tolerance` "0.05%" is a percentage"#)
                && e.message.contains("0 faces"),
            "{}",
            e.message
        );
        // A face of zero size does not validate: that error, not the missing extent.
        let e = absolute_tolerance(Tolerance::Percent(1.0), &plate(0.0)).unwrap_err();
        assert_eq!(e.code, ErrorCode::InvalidBrep, "{}", e.message);
    }
}
