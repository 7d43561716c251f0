//! A JSON value's type in words, for the refusals of every parser of the protocol (frames,
//! array tables, envelopes, job files, the registry). Its own file so that all of them can
//! name it from below.

use serde_json::Value;

/// A human name of a JSON value's type, for messages.
pub fn json_kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}
