//! What background work hands back to the render thread: the meshes it made (subdivision
//! levels, LOD chains, `.tsc` refinements) or why it failed. Below both the workers
//! ([`super::subdivision`], [`super::background`]) and the frame loop that takes it.

use tessd_mesh::Mesh;
use tessd_simplify::Cell;

/// What background work hands back to the render thread.
pub enum Done {
    /// Item `item` subdivided `level` times.
    Subdivided {
        /// The item.
        item: usize,
        /// The level.
        level: u32,
        /// The refined mesh.
        mesh: Box<Mesh>,
        /// The scheme's name.
        scheme: &'static str,
        /// Where the apply phase ran (`CPU`, `GPU`).
        device: &'static str,
        /// Whether the topology phase ran for this request (not for a frame of the same cage).
        topology_built: bool,
        /// The frame of `--frames` refined (none: the cage).
        frame: Option<usize>,
        /// Topology (when built) and apply, ms.
        ms: f64,
    },
    /// A subdivision request superseded by a newer one for the same item.
    Skipped,
    /// Item `item`'s LOD chain (coarser and coarser), with each level's partition cells.
    Lods {
        /// The item.
        item: usize,
        /// The levels.
        levels: Vec<(Mesh, Vec<Cell>)>,
        /// Time, ms.
        ms: f64,
    },
    /// A refinement of item `item` for the camera it was asked for.
    Refined {
        /// The item.
        item: usize,
        /// The triangles to draw, made on the worker (the render thread only uploads them).
        scene: Box<tessd_render::Scene>,
        /// Cells shown, triangles, and the code bytes this view read.
        cells: usize,
        /// Triangles of the view.
        triangles: usize,
        /// Bytes of code read for this view.
        bytes_read: u64,
        /// Decode time, ms.
        ms: f64,
    },
    /// Work that failed, with why.
    Failed(String),
}
