//! Typed binary arrays carried in a frame's payload (docs/protocol.md, "Arrays").
//!
//! Received arrays stay in the frame's payload buffer and are viewed in place; arrays to send
//! own their `Vec` and are written from it directly, so large meshes are never copied into an
//! intermediate frame buffer.

use crate::frame::FrameError;
use bytemuck::Pod;
use serde_json::{Value, json};

/// Element types of arrays on the wire (always little-endian).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DType {
    /// `u8`
    U8,
    /// `u16`
    U16,
    /// `u32`
    U32,
    /// `u64`
    U64,
    /// `i32`
    I32,
    /// `i64`
    I64,
    /// `f32`
    F32,
    /// `f64`
    F64,
}

impl DType {
    /// Every dtype, in wire-name order.
    pub const ALL: [DType; 8] = [
        DType::U8,
        DType::U16,
        DType::U32,
        DType::U64,
        DType::I32,
        DType::I64,
        DType::F32,
        DType::F64,
    ];

    /// The wire name.
    pub fn name(self) -> &'static str {
        match self {
            DType::U8 => "u8",
            DType::U16 => "u16",
            DType::U32 => "u32",
            DType::U64 => "u64",
            DType::I32 => "i32",
            DType::I64 => "i64",
            DType::F32 => "f32",
            DType::F64 => "f64",
        }
    }

    /// Size of one element in bytes.
    pub fn size(self) -> u64 {
        match self {
            DType::U8 => 1,
            DType::U16 => 2,
            DType::U32 | DType::I32 | DType::F32 => 4,
            DType::U64 | DType::I64 | DType::F64 => 8,
        }
    }

    /// Parses a wire name.
    pub fn from_name(s: &str) -> Option<DType> {
        DType::ALL.into_iter().find(|d| d.name() == s)
    }
}

/// A Rust element type that maps to a wire dtype.
pub trait Element: Pod + Send + Sync {
    /// Its dtype.
    const DTYPE: DType;
}

macro_rules! element {
    ($($t:ty => $d:ident),*) => { $(impl Element for $t { const DTYPE: DType = DType::$d; })* };
}
element!(u8 => U8, u16 => U16, u32 => U32, u64 => U64, i32 => I32, i64 => I64, f32 => F32, f64 => F64);

/// One entry of a frame's array table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArrayDesc {
    /// Unique name within the frame.
    pub name: String,
    /// Element type.
    pub dtype: DType,
    /// Shape; the element count is the product.
    pub shape: Vec<u64>,
    /// Byte offset within the payload (multiple of 8).
    pub offset: u64,
    /// Byte length (= elements × dtype size).
    pub length: u64,
}

impl ArrayDesc {
    /// The JSON form of this entry.
    pub fn to_json(&self) -> Value {
        json!({"name": self.name, "dtype": self.dtype.name(), "shape": self.shape,
               "offset": self.offset, "length": self.length})
    }

    /// Parses and checks an `arrays` table against the payload length: types, dtype names,
    /// shape × item size = length, 8-byte alignment, bounds, unique names, no overlap.
    ///
    /// # Errors
    /// A message naming the entry and the field at fault.
    pub fn parse_table(v: &Value, payload_len: u64) -> Result<Vec<ArrayDesc>, String> {
        let Value::Array(items) = v else {
            return Err(format!(
                "`arrays` must be a list, got {}",
                crate::frame::json_kind(v)
            ));
        };
        let mut out: Vec<ArrayDesc> = Vec::with_capacity(items.len().min(1024));
        for (i, item) in items.iter().enumerate() {
            let d = Self::parse_one(i, item, payload_len)?;
            if out.iter().any(|o| o.name == d.name) {
                return Err(format!("array {i} repeats the name {:?}", d.name));
            }
            out.push(d);
        }
        let mut spans: Vec<(u64, u64, usize)> = out
            .iter()
            .enumerate()
            .map(|(i, d)| (d.offset, d.offset + d.length, i))
            .collect();
        spans.sort_unstable();
        for w in spans.windows(2) {
            if w[1].0 < w[0].1 {
                return Err(format!(
                    "arrays {:?} and {:?} overlap in the payload",
                    out[w[0].2].name, out[w[1].2].name
                ));
            }
        }
        Ok(out)
    }

    fn parse_one(i: usize, item: &Value, payload_len: u64) -> Result<ArrayDesc, String> {
        let Value::Object(m) = item else {
            return Err(format!("array {i} must be an object"));
        };
        let name = match m.get("name") {
            Some(Value::String(s)) if !s.is_empty() => s.clone(),
            _ => return Err(format!("array {i} needs a non-empty string `name`")),
        };
        let field = |k: &str| -> Result<u64, String> {
            m.get(k)
                .and_then(Value::as_u64)
                .ok_or_else(|| format!("array {name:?} needs a non-negative integer `{k}`"))
        };
        let dtype = match m.get("dtype") {
            Some(Value::String(s)) => DType::from_name(s).ok_or_else(|| {
                format!(
                    "array {name:?} has unknown dtype {s:?}; expected one of {}",
                    crate::frame::dtype_names().join(", ")
                )
            })?,
            _ => return Err(format!("array {name:?} needs a string `dtype`")),
        };
        let shape: Vec<u64> = match m.get("shape") {
            Some(Value::Array(dims)) if dims.len() <= 8 => dims
                .iter()
                .map(|d| {
                    d.as_u64()
                        .ok_or_else(|| format!("array {name:?} has a bad dimension {d}"))
                })
                .collect::<Result<_, _>>()?,
            _ => {
                return Err(format!(
                    "array {name:?} needs a `shape` list of at most 8 dimensions"
                ));
            }
        };
        let (offset, length) = (field("offset")?, field("length")?);
        let expected = shape
            .iter()
            .try_fold(dtype.size(), |acc, &d| acc.checked_mul(d))
            .ok_or_else(|| format!("array {name:?} shape {shape:?} overflows"))?;
        if expected != length {
            return Err(format!(
                "array {name:?} has length {length} bytes but shape {shape:?} of {} needs {expected}",
                dtype.name()
            ));
        }
        if offset % 8 != 0 {
            return Err(format!(
                "array {name:?} offset {offset} is not a multiple of 8"
            ));
        }
        if offset
            .checked_add(length)
            .is_none_or(|end| end > payload_len)
        {
            return Err(format!(
                "array {name:?} spans bytes {offset}..{} but the payload has {payload_len}",
                offset.saturating_add(length)
            ));
        }
        Ok(ArrayDesc {
            name,
            dtype,
            shape,
            offset,
            length,
        })
    }
}

/// A received array viewed in place: its elements and its shape.
pub type TypedView<'a, T> = (&'a [T], &'a [u64]);

/// Arrays received in a frame: the payload buffer and its table.
#[derive(Debug, Default)]
pub struct Arrays {
    words: Vec<u64>,
    len: usize,
    descs: Vec<ArrayDesc>,
}

impl Arrays {
    /// A zeroed payload of `len` bytes (8-aligned storage).
    ///
    /// # Errors
    /// When the length does not fit in memory addressing.
    pub(crate) fn zeroed(len: u64) -> Result<Arrays, FrameError> {
        let len = usize::try_from(len).map_err(|_| FrameError::PayloadTooLarge {
            len,
            max: usize::MAX as u64,
        })?;
        let words = vec![0u64; len.div_ceil(8)];
        Ok(Arrays {
            words,
            len,
            descs: Vec::new(),
        })
    }

    pub(crate) fn bytes_mut(&mut self) -> &mut [u8] {
        &mut bytemuck::cast_slice_mut::<u64, u8>(&mut self.words)[..self.len]
    }

    pub(crate) fn set_descs(&mut self, descs: Vec<ArrayDesc>) {
        self.descs = descs;
    }

    /// Builds received-style arrays from owned ones (used by in-process job runs, so that a job
    /// file goes through exactly the code path of a socket request).
    pub fn from_owned(arrays: &[OwnedArray]) -> Arrays {
        let (descs, len) = layout(arrays);
        let mut out = Arrays {
            words: vec![0u64; len as usize / 8],
            len: len as usize,
            descs,
        };
        for (a, d) in arrays.iter().zip(out.descs.clone()) {
            out.bytes_mut()[d.offset as usize..(d.offset + d.length) as usize]
                .copy_from_slice(a.bytes());
        }
        out
    }

    /// The table of arrays.
    pub fn descs(&self) -> &[ArrayDesc] {
        &self.descs
    }

    /// Whether there are no arrays.
    pub fn is_empty(&self) -> bool {
        self.descs.is_empty()
    }

    /// Payload size in bytes.
    pub fn payload_len(&self) -> usize {
        self.len
    }

    /// The entry named `name`.
    pub fn desc(&self, name: &str) -> Option<&ArrayDesc> {
        self.descs.iter().find(|d| d.name == name)
    }

    /// The raw bytes of array `name`.
    pub fn bytes(&self, name: &str) -> Option<&[u8]> {
        let d = self.desc(name)?;
        let all = &bytemuck::cast_slice::<u64, u8>(&self.words)[..self.len];
        Some(&all[d.offset as usize..(d.offset + d.length) as usize])
    }

    /// Array `name` viewed as `T` in place, with its shape.
    ///
    /// # Errors
    /// When the array's dtype is not `T`'s (the message names the array and both dtypes).
    pub fn get<T: Element>(&self, name: &str) -> Option<Result<TypedView<'_, T>, String>> {
        let d = self.desc(name)?;
        if d.dtype != T::DTYPE {
            return Some(Err(format!(
                "array {name:?} has dtype {}; expected {}",
                d.dtype.name(),
                T::DTYPE.name()
            )));
        }
        // Offsets are multiples of 8 in 8-aligned storage, so the cast cannot fail.
        Some(Ok((bytemuck::cast_slice(self.bytes(name)?), &d.shape)))
    }
}

/// An array to send: its description and the buffer holding it.
pub struct OwnedArray {
    name: String,
    dtype: DType,
    shape: Vec<u64>,
    data: Box<dyn AsBytes>,
}

impl std::fmt::Debug for OwnedArray {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OwnedArray")
            .field("name", &self.name)
            .field("dtype", &self.dtype)
            .field("shape", &self.shape)
            .finish()
    }
}

trait AsBytes: Send + Sync {
    fn as_bytes(&self) -> &[u8];
}

impl<T: Pod + Send + Sync> AsBytes for Vec<T> {
    fn as_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(self)
    }
}

/// A slice of a shared received payload, so received arrays can be sent back without a copy.
struct PayloadSlice {
    payload: std::sync::Arc<Arrays>,
    start: usize,
    end: usize,
}

impl AsBytes for PayloadSlice {
    fn as_bytes(&self) -> &[u8] {
        &bytemuck::cast_slice::<u64, u8>(&self.payload.words)[self.start..self.end]
    }
}

impl Arrays {
    /// Turns the received arrays into arrays to send, sharing the payload buffer (no copy).
    pub fn into_owned(self) -> Vec<OwnedArray> {
        let descs = self.descs.clone();
        let payload = std::sync::Arc::new(self);
        descs
            .into_iter()
            .map(|d| OwnedArray {
                name: d.name,
                dtype: d.dtype,
                shape: d.shape,
                data: Box::new(PayloadSlice {
                    payload: payload.clone(),
                    start: d.offset as usize,
                    end: (d.offset + d.length) as usize,
                }),
            })
            .collect()
    }
}

impl OwnedArray {
    /// Wraps a vector of elements `E` with the given shape.
    ///
    /// # Panics
    /// If the shape's element count differs from `data.len()` (a bug in the caller).
    pub fn new<E: Element>(name: &str, shape: Vec<u64>, data: Vec<E>) -> OwnedArray {
        assert_eq!(
            shape.iter().product::<u64>(),
            data.len() as u64,
            "shape of {name}"
        );
        OwnedArray {
            name: name.into(),
            dtype: E::DTYPE,
            shape,
            data: Box::new(data),
        }
    }

    /// Wraps a vector of fixed-size rows (e.g. `[f32; 3]` positions) as an `[n, N]` array.
    pub fn rows<E: Element, const N: usize>(name: &str, data: Vec<[E; N]>) -> OwnedArray
    where
        [E; N]: Pod,
    {
        let shape = vec![data.len() as u64, N as u64];
        OwnedArray {
            name: name.into(),
            dtype: E::DTYPE,
            shape,
            data: Box::new(data),
        }
    }

    /// The array's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The bytes to send.
    pub fn bytes(&self) -> &[u8] {
        self.data.as_bytes()
    }

    /// Its table entry when placed at `offset`.
    pub fn desc_at(&self, offset: u64) -> ArrayDesc {
        ArrayDesc {
            name: self.name.clone(),
            dtype: self.dtype,
            shape: self.shape.clone(),
            offset,
            length: self.bytes().len() as u64,
        }
    }
}

/// Lays arrays out in a payload as [`crate::frame::write_frame`] sends them: each at the next
/// multiple of 8. Returns their table and the payload length.
pub fn layout(arrays: &[OwnedArray]) -> (Vec<ArrayDesc>, u64) {
    let mut offset = 0u64;
    let descs = arrays
        .iter()
        .map(|a| {
            let d = a.desc_at(offset);
            offset = (offset + d.length).next_multiple_of(8);
            d
        })
        .collect();
    (descs, offset)
}
