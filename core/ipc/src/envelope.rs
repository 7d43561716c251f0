//! The request envelope (docs/protocol.md, "Requests"): the `id`, `op` and `params` every
//! request frame carries, and the parameters of the server's built-in ops. Kept apart from the
//! server so that the fuzz target `envelope` runs the very checks the daemon runs.

use crate::error::OpError;
use crate::json_kind::json_kind;
use serde_json::{Map, Value};

/// A request's envelope, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Envelope {
    /// The client's request id: replies carry it back.
    pub id: u64,
    /// The operation's name, not yet looked up.
    pub op: String,
    /// The operation's parameters (absent or `null`: empty).
    pub params: Map<String, Value>,
}

/// Checks a request's `id`, `op` and `params`, taking `op` and `params` out of `json`.
///
/// Errors are `invalid_request`, naming the offending member and what it was.
pub fn parse_envelope(json: &mut Map<String, Value>) -> Result<Envelope, OpError> {
    let id = match json.get("id") {
        Some(v) => v.as_u64().ok_or_else(|| {
            OpError::request(format!(
                "`id` must be a non-negative integer, got {}",
                describe(v)
            ))
        })?,
        None => return Err(OpError::request("the request has no `id`")),
    };
    let op = match json.remove("op") {
        Some(Value::String(s)) => s,
        Some(v) => {
            return Err(OpError::request(format!(
                "`op` must be a string, got {}",
                json_kind(&v)
            )));
        }
        None => return Err(OpError::request("the request has no `op`")),
    };
    let params = match json.remove("params") {
        None | Some(Value::Null) => Map::new(),
        Some(Value::Object(m)) => m,
        Some(v) => {
            return Err(OpError::request(format!(
                "`params` must be an object, got {}",
                json_kind(&v)
            )));
        }
    };
    Ok(Envelope { id, op, params })
}

/// The `pid` parameter of `session.hold` / `session.release`: a positive process id.
pub fn holder_pid(params: &Map<String, Value>, op: &str) -> Result<u32, OpError> {
    let Some(v) = params.get("pid") else {
        return Err(OpError::request(format!(
            "{op} needs `params.pid`, the holding program's process id"
        )));
    };
    v.as_u64()
        .and_then(|n| u32::try_from(n).ok())
        .filter(|&n| n > 0 && i32::try_from(n).is_ok())
        .ok_or_else(|| {
            OpError::request(format!(
                "parameter `pid` must be a positive integer (a process id), got {}",
                describe(v)
            ))
        })
}

/// An optional boolean parameter (absent or null: false).
pub fn bool_param(params: &Map<String, Value>, key: &str) -> Result<bool, OpError> {
    match params.get(key) {
        None | Some(Value::Null) => Ok(false),
        Some(Value::Bool(b)) => Ok(*b),
        Some(v) => Err(OpError::request(format!(
            "parameter `{key}` must be true or false, got {}",
            json_kind(v)
        ))),
    }
}

/// A number as written, anything else by its JSON kind.
fn describe(v: &Value) -> String {
    match v {
        Value::Number(n) => format!("{n}"),
        other => json_kind(other).to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ErrorCode;
    use serde_json::json;

    fn parse(v: Value) -> Result<Envelope, OpError> {
        let Value::Object(mut m) = v else {
            unreachable!()
        };
        parse_envelope(&mut m)
    }

    #[test]
    fn accepts_a_request_and_takes_its_members_out() {
        let mut m = json!({"id": 7, "op": "ping", "params": {"echo": 1}, "extra": true});
        let m = m.as_object_mut().unwrap();
        let e = parse_envelope(m).unwrap();
        assert_eq!((e.id, e.op.as_str()), (7, "ping"));
        assert_eq!(e.params.get("echo"), Some(&json!(1)));
        assert_eq!(m.keys().collect::<Vec<_>>(), ["extra", "id"]);
        assert!(
            parse(json!({"id": 0, "op": "x", "params": null}))
                .unwrap()
                .params
                .is_empty()
        );
    }

    #[test]
    fn refusals_name_the_member_and_what_it_was() {
        for (request, says) in [
            (json!({"op": "ping"}), "has no `id`"),
            (
                json!({"id": -1, "op": "ping"}),
                "`id` must be a non-negative integer, got -1",
            ),
            (json!({"id": 1.5, "op": "ping"}), "got 1.5"),
            (json!({"id": "3", "op": "ping"}), "got a string"),
            (json!({"id": 1}), "has no `op`"),
            (
                json!({"id": 1, "op": 2}),
                "`op` must be a string, got a number",
            ),
            (
                json!({"id": 1, "op": "x", "params": [1]}),
                "`params` must be an object, got an array",
            ),
        ] {
            let e = parse(request.clone()).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest);
            assert!(e.message.contains(says), "{request}: {}", e.message);
        }
    }

    #[test]
    fn builtin_parameters() {
        let p = |v: Value| v.as_object().unwrap().clone();
        assert_eq!(
            holder_pid(&p(json!({"pid": 42})), "session.hold").unwrap(),
            42
        );
        for bad in [
            json!({}),
            json!({"pid": 0}),
            json!({"pid": -5}),
            json!({"pid": 1u64 << 31}),
        ] {
            let e = holder_pid(&p(bad), "session.hold").unwrap_err();
            assert!(e.message.contains("pid"), "{}", e.message);
        }
        assert!(!bool_param(&p(json!({"if_unheld": null})), "if_unheld").unwrap());
        assert!(bool_param(&p(json!({"if_unheld": true})), "if_unheld").unwrap());
        let e = bool_param(&p(json!({"if_unheld": "yes"})), "if_unheld").unwrap_err();
        assert!(
            e.message.contains("`if_unheld` must be true or false"),
            "{}",
            e.message
        );
    }
}
