//! Feeds bytes to the frame decoder as a socket stream, then each decoded frame's JSON to the
//! request envelope (`tessd_ipc::envelope::parse_envelope`), the parameters of the server's
//! built-in ops (`holder_pid`, `bool_param`) and the lookup of the op among the daemon's
//! registered ones (`tessd::ops::registry`): everything the daemon does to a request before an
//! operation runs.
//!
//! Must hold: no panic, no hang; an accepted envelope has the frame's `id` as an integer and
//! takes `op` and `params` out of the JSON; a refused one, an unknown op, a bad `pid` or a bad
//! `if_unheld` is an `invalid_request` whose message names the offending member.
#![no_main]

use libfuzzer_sys::fuzz_target;
use serde_json::Value;
use std::sync::OnceLock;
use tessd_ipc::ErrorCode;
use tessd_ipc::envelope::{bool_param, holder_pid, parse_envelope};
use tessd_ipc::frame::{Limits, read_frame};
use tessd_ipc::registry::{Registry, unknown_op};

fn registry() -> &'static Registry {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    REGISTRY.get_or_init(tessd::ops::registry)
}

fuzz_target!(|data: &[u8]| {
    let mut stream = data;
    for _ in 0..4 {
        let Ok(frame) = read_frame(&mut stream, &Limits::default()) else {
            return;
        };
        let mut json = frame.json;
        let raw_id = json.get("id").cloned();
        match parse_envelope(&mut json) {
            Ok(envelope) => {
                assert_eq!(raw_id.as_ref().and_then(Value::as_u64), Some(envelope.id));
                assert!(!json.contains_key("op") && !json.contains_key("params"));
                let params = &envelope.params;
                match envelope.op.as_str() {
                    "session.hold" | "session.release" => match holder_pid(params, &envelope.op) {
                        Ok(pid) => assert!(pid > 0 && pid <= i32::MAX as u32),
                        Err(e) => {
                            assert_eq!(e.code, ErrorCode::InvalidRequest);
                            assert!(e.message.contains("pid"), "{}", e.message);
                        }
                    },
                    "shutdown" => {
                        if let Err(e) = bool_param(params, "if_unheld") {
                            assert_eq!(e.code, ErrorCode::InvalidRequest);
                            assert!(e.message.contains("if_unheld"), "{}", e.message);
                        }
                    }
                    op if registry().get(op).is_none() => {
                        let e = unknown_op(op, &registry().names());
                        assert_eq!(e.code, ErrorCode::InvalidRequest);
                        assert!(e.message.contains(&format!("{op:?}")), "{}", e.message);
                    }
                    _ => {}
                }
            }
            Err(e) => {
                assert_eq!(e.code, ErrorCode::InvalidRequest);
                let named = ["`id`", "`op`", "`params`"];
                assert!(named.iter().any(|m| e.message.contains(m)), "{}", e.message);
            }
        }
    }
});
