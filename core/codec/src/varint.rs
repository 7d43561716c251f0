//! LEB128 variable-length integers for the file's tables and index.

use crate::error::CodecError;

/// Appends `v`.
pub fn put(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// Reads one integer at `*at`; `base` is the slice's offset in the file, for errors.
pub fn get(bytes: &[u8], at: &mut usize, base: u64) -> Result<u64, CodecError> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let Some(&b) = bytes.get(*at) else {
            return Err(CodecError::corrupt(base + *at as u64, "truncated integer"));
        };
        *at += 1;
        v |= ((b & 0x7f) as u64) << shift;
        if b & 0x80 == 0 {
            return Ok(v);
        }
    }
    Err(CodecError::corrupt(
        base + *at as u64,
        "integer longer than 64 bits",
    ))
}
