//! Feeds bytes, as text, to the job-file reader (`tessd_ipc::job_file::parse`): one request
//! `{"op", "params"}` or `{"jobs": [...]}`.
//!
//! Must hold: no panic, no hang; non-UTF-8 is refused before this (`tessd job run` reads the
//! file as a string); a file that parses gives jobs each with its op name, and an error is an
//! `invalid_request` with a message.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tessd_ipc::ErrorCode;
use tessd_ipc::job_file::parse;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse(text) {
        Ok(jobs) => {
            for job in jobs {
                // Params are an object by construction; the op is whatever string was given.
                let _ = (job.op.len(), job.params.len());
            }
        }
        Err(e) => {
            assert_eq!(e.code, ErrorCode::InvalidRequest);
            assert!(!e.message.is_empty());
        }
    }
});
