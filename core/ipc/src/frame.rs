//! Frame encoding and decoding (docs/protocol.md, "Frames" and "Arrays").
//!
//! A frame is a 24-byte little-endian header, a JSON object and a binary payload of 8-byte
//! aligned arrays. Decoding treats every byte as hostile: sizes are checked against
//! [`Limits`] before anything is allocated, and each failure has its own [`FrameError`].

use crate::arrays::{ArrayDesc, Arrays, OwnedArray, layout};
use crate::json_kind::json_kind;
use serde_json::{Map, Value};
use std::io::{self, Read, Write};
use thiserror::Error;

/// The four bytes every frame starts with.
pub const MAGIC: [u8; 4] = *b"TSSD";
/// The protocol version this build speaks.
pub const PROTOCOL_VERSION: u16 = 1;
/// Header size in bytes.
pub const HEADER_LEN: usize = 24;
/// Largest JSON document accepted, whatever the limits say (16 MiB).
pub const MAX_JSON_LEN: u32 = 16 << 20;

/// Size limits applied while decoding, before any allocation.
#[derive(Clone, Copy, Debug)]
#[non_exhaustive]
pub struct Limits {
    /// Largest JSON document, bytes.
    pub max_json: u32,
    /// Largest payload, bytes.
    pub max_payload: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_json: MAX_JSON_LEN,
            max_payload: 4 << 30,
        }
    }
}

impl Limits {
    /// Sets the largest payload accepted.
    pub fn with_max_payload(mut self, bytes: u64) -> Self {
        self.max_payload = bytes;
        self
    }
}

/// Why a byte sequence is not a valid frame. After any of these the stream is out of step.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FrameError {
    /// The peer closed the connection cleanly between frames.
    #[error("connection closed")]
    Closed,
    /// The first four bytes are not `TSSD`.
    #[error("bad magic {0:02x?}; expected \"TSSD\"")]
    BadMagic([u8; 4]),
    /// Unsupported protocol version.
    #[error("protocol version {0} is not supported; this daemon speaks version {PROTOCOL_VERSION}")]
    BadVersion(u16),
    /// Reserved header fields are not zero.
    #[error("reserved header field {field} is {value}; it must be 0")]
    Reserved {
        /// `flags` or `reserved`.
        field: &'static str,
        /// The value found.
        value: u32,
    },
    /// `json_len` is 0 or over the limit.
    #[error("JSON length {len} is out of range (1..={max})")]
    JsonLength {
        /// Declared length.
        len: u32,
        /// Limit.
        max: u32,
    },
    /// `payload_len` is over the limit.
    #[error("payload of {len} bytes exceeds the limit of {max} bytes")]
    PayloadTooLarge {
        /// Declared length.
        len: u64,
        /// Limit.
        max: u64,
    },
    /// The stream ended inside a frame.
    #[error("frame truncated in the {part}: expected {expected} bytes, got {got}")]
    Truncated {
        /// `header`, `JSON` or `payload`.
        part: &'static str,
        /// Bytes expected.
        expected: u64,
        /// Bytes received.
        got: u64,
    },
    /// The JSON bytes are not UTF-8 JSON.
    #[error("JSON document is invalid: {0}")]
    BadJson(String),
    /// The JSON document is not an object.
    #[error("JSON document must be an object, got {0}")]
    NotAnObject(&'static str),
    /// The `arrays` table disagrees with the payload.
    #[error("array table: {0}")]
    BadArrays(String),
    /// Transport failure.
    #[error("i/o error: {0}")]
    Io(#[from] io::Error),
}

impl FrameError {
    /// The protocol error code for this error (`too_large` or `invalid_frame`).
    pub fn code(&self) -> &'static str {
        match self {
            FrameError::PayloadTooLarge { .. } => "too_large",
            FrameError::JsonLength { len, max } if len > max => "too_large",
            _ => "invalid_frame",
        }
    }
}

/// A decoded frame: its JSON object and its arrays.
#[derive(Debug)]
pub struct Frame {
    /// The JSON document.
    pub json: Map<String, Value>,
    /// The payload arrays, described by `json["arrays"]`.
    pub arrays: Arrays,
}

/// The parsed fixed header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// JSON length in bytes.
    pub json_len: u32,
    /// Payload length in bytes.
    pub payload_len: u64,
}

impl Header {
    /// Encodes the header.
    pub fn encode(&self) -> [u8; HEADER_LEN] {
        let mut h = [0u8; HEADER_LEN];
        h[0..4].copy_from_slice(&MAGIC);
        h[4..6].copy_from_slice(&PROTOCOL_VERSION.to_le_bytes());
        h[8..12].copy_from_slice(&self.json_len.to_le_bytes());
        h[16..24].copy_from_slice(&self.payload_len.to_le_bytes());
        h
    }

    /// Decodes and checks a header against `limits`.
    ///
    /// # Errors
    /// Bad magic, version, non-zero reserved fields, or sizes out of range.
    pub fn decode(h: &[u8; HEADER_LEN], limits: &Limits) -> Result<Header, FrameError> {
        let magic: [u8; 4] = h[0..4].try_into().unwrap();
        if magic != MAGIC {
            return Err(FrameError::BadMagic(magic));
        }
        let version = u16::from_le_bytes([h[4], h[5]]);
        if version != PROTOCOL_VERSION {
            return Err(FrameError::BadVersion(version));
        }
        let flags = u16::from_le_bytes([h[6], h[7]]);
        if flags != 0 {
            return Err(FrameError::Reserved {
                field: "flags",
                value: flags.into(),
            });
        }
        let reserved = u32::from_le_bytes(h[12..16].try_into().unwrap());
        if reserved != 0 {
            return Err(FrameError::Reserved {
                field: "reserved",
                value: reserved,
            });
        }
        let json_len = u32::from_le_bytes(h[8..12].try_into().unwrap());
        let max = limits.max_json.min(MAX_JSON_LEN);
        if json_len == 0 || json_len > max {
            return Err(FrameError::JsonLength { len: json_len, max });
        }
        let payload_len = u64::from_le_bytes(h[16..24].try_into().unwrap());
        if payload_len > limits.max_payload {
            return Err(FrameError::PayloadTooLarge {
                len: payload_len,
                max: limits.max_payload,
            });
        }
        Ok(Header {
            json_len,
            payload_len,
        })
    }
}

/// Reads as many bytes as are available up to `buf.len()`; returns how many.
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

fn read_part(r: &mut impl Read, buf: &mut [u8], part: &'static str) -> Result<(), FrameError> {
    let got = read_full(r, buf)?;
    if got < buf.len() {
        return Err(FrameError::Truncated {
            part,
            expected: buf.len() as u64,
            got: got as u64,
        });
    }
    Ok(())
}

/// Reads one frame.
///
/// # Errors
/// [`FrameError::Closed`] on a clean end of stream before a header; any other variant when the
/// bytes are not a valid frame (the stream should then be closed).
pub fn read_frame(r: &mut impl Read, limits: &Limits) -> Result<Frame, FrameError> {
    let mut h = [0u8; HEADER_LEN];
    let got = read_full(r, &mut h)?;
    if got == 0 {
        return Err(FrameError::Closed);
    }
    if got < HEADER_LEN {
        return Err(FrameError::Truncated {
            part: "header",
            expected: HEADER_LEN as u64,
            got: got as u64,
        });
    }
    let header = Header::decode(&h, limits)?;
    let mut json = vec![0u8; header.json_len as usize];
    read_part(r, &mut json, "JSON")?;
    let json = parse_object(&json)?;
    // The table first, so that each array is read straight into its own typed buffer (and a
    // bad table is refused before a large payload is read).
    let descs = match json.get("arrays") {
        None => Vec::new(),
        Some(v) => ArrayDesc::parse_table(v, header.payload_len).map_err(FrameError::BadArrays)?,
    };
    let arrays = read_payload(r, descs, header.payload_len)?;
    Ok(Frame { json, arrays })
}

/// Reads a payload of `len` bytes laid out as `descs` say (a checked table: in bounds, no
/// overlap), each array straight into its own buffer; gaps and trailing bytes are read and
/// dropped.
///
/// # Errors
/// [`FrameError::Truncated`] when the stream ends early (with the payload bytes received),
/// [`FrameError::Io`].
fn read_payload(r: &mut impl Read, descs: Vec<ArrayDesc>, len: u64) -> Result<Arrays, FrameError> {
    let size = usize::try_from(len).map_err(|_| FrameError::PayloadTooLarge {
        len,
        max: usize::MAX as u64,
    })?;
    // Each array's (offset, length): the table itself moves into the arrays.
    let spans: Vec<(u64, u64)> = descs.iter().map(|d| (d.offset, d.length)).collect();
    let mut arrays = Arrays::zeroed(descs, size);
    let mut order: Vec<usize> = (0..spans.len()).collect();
    order.sort_unstable_by_key(|&i| spans[i].0);
    let mut pos = 0u64;
    let truncated = |got: u64| FrameError::Truncated {
        part: "payload",
        expected: len,
        got,
    };
    for i in order {
        let (offset, length) = spans[i];
        let skipped = skip(r, offset - pos)?;
        if skipped < offset - pos {
            return Err(truncated(pos + skipped));
        }
        let got = read_full(r, arrays.bytes_mut(i))? as u64;
        if got < length {
            return Err(truncated(offset + got));
        }
        pos = offset + length;
    }
    let skipped = skip(r, len - pos)?;
    if skipped < len - pos {
        return Err(truncated(pos + skipped));
    }
    Ok(arrays)
}

/// Reads and drops `n` bytes; returns how many were there.
fn skip(r: &mut impl Read, n: u64) -> io::Result<u64> {
    io::copy(&mut Read::take(r, n), &mut io::sink())
}

/// Parses a JSON object from bytes.
///
/// # Errors
/// [`FrameError::BadJson`] or [`FrameError::NotAnObject`].
pub fn parse_object(bytes: &[u8]) -> Result<Map<String, Value>, FrameError> {
    let v: Value = serde_json::from_slice(bytes).map_err(|e| FrameError::BadJson(e.to_string()))?;
    match v {
        Value::Object(m) => Ok(m),
        other => Err(FrameError::NotAnObject(json_kind(&other))),
    }
}

/// Writes one frame: `json` (its `arrays` member is replaced by the table of `arrays`) followed
/// by the arrays, each 8-byte aligned. Array bytes are written straight from their buffers.
///
/// # Errors
/// Transport errors.
pub fn write_frame(
    w: &mut impl Write,
    mut json: Map<String, Value>,
    arrays: &[OwnedArray],
) -> io::Result<()> {
    let (descs, payload_len) = layout(arrays);
    if !arrays.is_empty() || json.contains_key("arrays") {
        json.insert(
            "arrays".into(),
            descs.iter().map(ArrayDesc::to_json).collect(),
        );
    }
    // Header and JSON go out in one write: small replies then cost one system call.
    let mut head = vec![0u8; HEADER_LEN];
    serde_json::to_writer(&mut head, &json).map_err(io::Error::other)?;
    let json_len = u32::try_from(head.len() - HEADER_LEN)
        .ok()
        .filter(|&n| n <= MAX_JSON_LEN)
        .ok_or_else(|| io::Error::other("JSON document over 16 MiB"))?;
    head[..HEADER_LEN].copy_from_slice(
        &Header {
            json_len,
            payload_len,
        }
        .encode(),
    );
    w.write_all(&head)?;
    const PAD: [u8; 8] = [0; 8];
    for a in arrays {
        let b = a.bytes();
        w.write_all(b)?;
        w.write_all(&PAD[..(b.len().next_multiple_of(8) - b.len())])?;
    }
    w.flush()
}

#[cfg(test)]
#[path = "frame_tests.rs"]
mod tests;
