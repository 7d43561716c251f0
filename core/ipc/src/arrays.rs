//! Typed binary arrays carried in a frame's payload (docs/protocol.md, "Arrays").
//!
//! Each received array is read from the socket straight into its own buffer, a `Vec` of its
//! element size: it is viewed in place ([`Arrays::get`]) or moved out whole ([`Arrays::take`],
//! e.g. into a mesh) without a copy. Arrays to send own their `Vec` and are written from it
//! directly, so large meshes are never copied into an intermediate frame buffer.

use crate::json_kind::json_kind;
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
            return Err(format!("`arrays` must be a list, got {}", json_kind(v)));
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
                    dtype_names().join(", ")
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

/// A received array taken out of its frame: its elements and its shape.
pub type TakenArray<T> = (Vec<T>, Vec<u64>);

/// The storage of one received array, typed by element size: any array is aligned for its
/// dtype, and [`Arrays::take`] can hand it over as a `Vec` of its elements without a copy.
#[derive(Debug)]
enum Buffer {
    B1(Vec<u8>),
    B2(Vec<u16>),
    B4(Vec<u32>),
    B8(Vec<u64>),
}

impl Buffer {
    /// A zeroed buffer of `len` bytes for elements of `dtype` (`len` a multiple of its size).
    /// A zeroed allocation is lazily committed by the OS, so memory follows the bytes received.
    fn zeroed(dtype: DType, len: usize) -> Buffer {
        match dtype.size() {
            1 => Buffer::B1(vec![0; len]),
            2 => Buffer::B2(vec![0; len / 2]),
            4 => Buffer::B4(vec![0; len / 4]),
            _ => Buffer::B8(vec![0; len / 8]),
        }
    }

    fn bytes(&self) -> &[u8] {
        match self {
            Buffer::B1(v) => v,
            Buffer::B2(v) => bytemuck::cast_slice(v),
            Buffer::B4(v) => bytemuck::cast_slice(v),
            Buffer::B8(v) => bytemuck::cast_slice(v),
        }
    }

    fn bytes_mut(&mut self) -> &mut [u8] {
        match self {
            Buffer::B1(v) => v,
            Buffer::B2(v) => bytemuck::cast_slice_mut(v),
            Buffer::B4(v) => bytemuck::cast_slice_mut(v),
            Buffer::B8(v) => bytemuck::cast_slice_mut(v),
        }
    }

    /// The buffer as a `Vec<T>` (`T` of the buffer's element size), moved, not copied.
    fn into_vec<T: Element>(self) -> Vec<T> {
        fn cast<A: Pod, T: Pod>(v: Vec<A>) -> Vec<T> {
            // Same size and alignment (checked by the caller's dtype match), so this moves.
            bytemuck::allocation::try_cast_vec(v)
                .unwrap_or_else(|(_, v)| bytemuck::cast_slice(&v).to_vec())
        }
        match self {
            Buffer::B1(v) => cast(v),
            Buffer::B2(v) => cast(v),
            Buffer::B4(v) => cast(v),
            Buffer::B8(v) => cast(v),
        }
    }
}

/// Arrays received in a frame: their table and one buffer per array.
#[derive(Debug, Default)]
pub struct Arrays {
    bufs: Vec<Buffer>,
    len: usize,
    descs: Vec<ArrayDesc>,
}

impl Arrays {
    /// Zeroed buffers for the arrays of `descs` (a checked table), in a payload of `len`
    /// bytes: the frame reader ([`crate::frame::read_frame`]) then reads each array straight
    /// into [`Arrays::bytes_mut`].
    pub(crate) fn zeroed(descs: Vec<ArrayDesc>, len: usize) -> Arrays {
        let bufs: Vec<Buffer> = descs
            .iter()
            .map(|d| Buffer::zeroed(d.dtype, d.length as usize))
            .collect();
        Arrays { bufs, len, descs }
    }

    /// The bytes of array `i` (in table order), to be filled from the stream.
    pub(crate) fn bytes_mut(&mut self, i: usize) -> &mut [u8] {
        self.bufs[i].bytes_mut()
    }

    /// Builds received-style arrays from owned ones (used by in-process job runs, so that a job
    /// file goes through exactly the code path of a socket request).
    pub fn from_owned(arrays: &[OwnedArray]) -> Arrays {
        let (descs, len) = layout(arrays);
        let bufs = arrays
            .iter()
            .map(|a| {
                let mut b = Buffer::zeroed(a.dtype, a.bytes().len());
                b.bytes_mut().copy_from_slice(a.bytes());
                b
            })
            .collect();
        Arrays {
            bufs,
            len: len as usize,
            descs,
        }
    }

    /// The table of arrays.
    pub fn descs(&self) -> &[ArrayDesc] {
        &self.descs
    }

    /// Whether there are no arrays.
    pub fn is_empty(&self) -> bool {
        self.descs.is_empty()
    }

    /// Payload size in bytes (as received, arrays taken out included).
    pub fn payload_len(&self) -> usize {
        self.len
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.descs.iter().position(|d| d.name == name)
    }

    /// The entry named `name`.
    pub fn desc(&self, name: &str) -> Option<&ArrayDesc> {
        self.index(name).map(|i| &self.descs[i])
    }

    /// The raw bytes of array `name`.
    pub fn bytes(&self, name: &str) -> Option<&[u8]> {
        self.index(name).map(|i| self.bufs[i].bytes())
    }

    /// Array `name` viewed as `T` in place, with its shape.
    ///
    /// # Errors
    /// When the array's dtype is not `T`'s (the message names the array and both dtypes).
    pub fn get<T: Element>(&self, name: &str) -> Option<Result<TypedView<'_, T>, String>> {
        let i = self.index(name)?;
        let d = &self.descs[i];
        if d.dtype != T::DTYPE {
            return Some(Err(dtype_mismatch::<T>(d)));
        }
        // Each buffer is a Vec of elements of the dtype's size, so the cast cannot fail.
        Some(Ok((bytemuck::cast_slice(self.bufs[i].bytes()), &d.shape)))
    }

    /// Takes array `name` out as a `Vec<T>` with its shape, moving its buffer (no copy); it is
    /// then gone from the table. A wrong dtype leaves it in place.
    ///
    /// # Errors
    /// When the array's dtype is not `T`'s (the message names the array and both dtypes).
    pub fn take<T: Element>(&mut self, name: &str) -> Option<Result<TakenArray<T>, String>> {
        let i = self.index(name)?;
        if self.descs[i].dtype != T::DTYPE {
            return Some(Err(dtype_mismatch::<T>(&self.descs[i])));
        }
        let d = self.descs.remove(i);
        Some(Ok((self.bufs.remove(i).into_vec(), d.shape)))
    }
}

fn dtype_mismatch<T: Element>(d: &ArrayDesc) -> String {
    format!(
        "array {:?} has dtype {}; expected {}",
        d.name,
        d.dtype.name(),
        T::DTYPE.name()
    )
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

impl AsBytes for Buffer {
    fn as_bytes(&self) -> &[u8] {
        self.bytes()
    }
}

impl Arrays {
    /// Turns the received arrays into arrays to send, moving their buffers (no copy).
    pub fn into_owned(self) -> Vec<OwnedArray> {
        self.descs
            .into_iter()
            .zip(self.bufs)
            .map(|(d, b)| OwnedArray {
                name: d.name,
                dtype: d.dtype,
                shape: d.shape,
                data: Box::new(b),
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

/// The dtype names accepted on the wire, for messages.
pub fn dtype_names() -> Vec<&'static str> {
    DType::ALL.iter().map(|d| d.name()).collect()
}
