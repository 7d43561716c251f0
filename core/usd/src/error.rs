//! The error type of this crate (writing and reading stages).

use tessd_mesh::MeshError;
use thiserror::Error;

/// Errors from writing or reading a USD stage.
///
/// Writing: everything that can be checked is checked *before* the first byte is written, so an
/// [`UsdError::InvalidMesh`], [`UsdError::InvalidOption`] or [`UsdError::TooLarge`] never leaves
/// half a stage in the output.
///
/// Reading ([`crate::reader`]): [`UsdError::Parse`] names the file, the line and the offending
/// element (prim path and attribute), [`UsdError::Unsupported`] refuses binary crate files and
/// `.usdz` packages, [`UsdError::NoMeshes`] says a stage shows no mesh.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum UsdError {
    /// A mesh breaks an invariant of [`tessd_mesh::Mesh`] (see [`tessd_mesh::Mesh::validate`]);
    /// `prim` names the mesh prim it was meant for (with the LOD variant, if any).
    #[error("mesh prim \"{prim}\": {source}")]
    InvalidMesh {
        /// The mesh prim's name as given in its options (plus ` (LODn)` for LOD levels).
        prim: String,
        /// What is wrong with the mesh.
        #[source]
        source: MeshError,
    },
    /// An option cannot be written as given (non-finite transform or `metersPerUnit`, the Loop
    /// scheme on a mesh that is not all triangles, no LOD levels...).
    #[error("{0}")]
    InvalidOption(String),
    /// An index does not fit USD's 32-bit signed `int`.
    #[error("{0}")]
    TooLarge(String),
    /// A `.usda` text cannot be read: bad syntax, a truncated file, or a mesh prim whose arrays
    /// break the `Mesh` schema (an index out of range, a non-finite point, counts that do not
    /// add up to the indices...). `message` names the prim path and attribute at fault.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file (or the name given to [`crate::reader::parse_usda`]).
        path: String,
        /// 1-based line of the offending element.
        line: usize,
        /// What is wrong, naming the prim and attribute.
        message: String,
    },
    /// The input is a USD file tessd does not read: a binary crate file (`PXR-USDC`) or a
    /// `.usdz` package. The message names the file and says to export `.usda`.
    #[error("{0}")]
    Unsupported(String),
    /// The stage holds no mesh a viewer would show (no visible `def Mesh` prim, in the selected
    /// variants, of its own or through its references and payloads to local `.usda` files).
    #[error("{path}: the stage has no visible Mesh prim")]
    NoMeshes {
        /// The file (or the name given to [`crate::reader::parse_usda`]).
        path: String,
    },
    /// Writing or reading failed. `path` is the file, or `<stream>` when writing to a caller's
    /// writer.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned, or `<stream>`.
        path: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl UsdError {
    /// A short stable machine code for this error, matching the codes of the wire protocol
    /// (`invalid_mesh`, `invalid_request`, `too_large`, `unsupported`, `io`).
    pub fn code(&self) -> &'static str {
        match self {
            UsdError::InvalidMesh { .. } | UsdError::Parse { .. } | UsdError::NoMeshes { .. } => {
                "invalid_mesh"
            }
            UsdError::Unsupported(_) => "unsupported",
            UsdError::InvalidOption(_) => "invalid_request",
            UsdError::TooLarge(_) => "too_large",
            UsdError::Io { .. } => "io",
        }
    }

    pub(crate) fn stream(source: std::io::Error) -> UsdError {
        UsdError::Io {
            path: STREAM.to_string(),
            source,
        }
    }
}

/// The `path` of [`UsdError::Io`] for failures of a caller-supplied writer.
pub(crate) const STREAM: &str = "<stream>";

/// File-level failures of [`tessd_mesh::io::write_atomic`] (creating, flushing or renaming the
/// temporary file) arrive as mesh I/O errors.
impl From<MeshError> for UsdError {
    fn from(e: MeshError) -> Self {
        match e {
            MeshError::Io { path, source } => UsdError::Io { path, source },
            other => UsdError::InvalidMesh {
                prim: String::new(),
                source: other,
            },
        }
    }
}
