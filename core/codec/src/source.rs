//! Where a compression reads its mesh from, in passes (paper 003 §5.1: the points are read and
//! quantised before the triangles are distributed): `tessd-mesh`'s streaming readers, so that a
//! PLY or OBJ file is never held whole.

pub use tessd_mesh::io::stream::{MeshSource, ObjFile, PlyFile, Slices, streamable};

use crate::error::CodecError;

/// A mesh reading error as the codec reports it: the input's fault, or I/O.
pub fn mesh_error(e: tessd_mesh::MeshError) -> CodecError {
    match e {
        tessd_mesh::MeshError::Io { path, source } => {
            CodecError::io(format!("reading {path}"), source)
        }
        other => CodecError::Input(other.to_string()),
    }
}

/// Opens a streaming reader for a PLY or OBJ file.
pub fn open(path: &std::path::Path) -> Result<Box<dyn MeshSource>, CodecError> {
    tessd_mesh::io::stream::open(path).map_err(mesh_error)
}

/// Items handed from the reading thread to the using one at a time.
const BATCH: usize = 1 << 14;

/// Inputs with fewer vertices than this are read and used on one thread (a thread per pass
/// costs more than it saves).
const BESIDE_FROM: u64 = 1 << 16;

/// One pass over `src`'s triangles with the reading on this thread and `f` on another (paper
/// 003 §5.4 puts the cores to work; the partition's passes would otherwise leave one idle): at
/// 15 M triangles, parsing the PLY and placing the triangles each took about half of a pass.
/// `f` sees every triangle in order, as [`MeshSource::triangles`] would give them.
pub fn triangles_beside(
    src: &mut dyn MeshSource,
    f: &mut (dyn FnMut([u32; 3]) + Send),
) -> Result<(), CodecError> {
    if src.vertex_count() < BESIDE_FROM {
        return src.triangles(f).map_err(mesh_error);
    }
    beside(|sink| src.triangles(sink).map_err(mesh_error), f)
}

/// [`triangles_beside`] for the vertices.
pub fn vertices_beside(
    src: &mut dyn MeshSource,
    f: &mut (dyn FnMut([f32; 3]) + Send),
) -> Result<(), CodecError> {
    if src.vertex_count() < BESIDE_FROM {
        return src.vertices(f).map_err(mesh_error);
    }
    beside(|sink| src.vertices(sink).map_err(mesh_error), f)
}

/// Runs `read` here, handing what it yields to `f` on a second thread in batches of [`BATCH`]
/// (two batches in flight, the emptied ones sent back for reuse).
fn beside<T: Send + Copy>(
    read: impl FnOnce(&mut dyn FnMut(T)) -> Result<(), CodecError>,
    f: &mut (dyn FnMut(T) + Send),
) -> Result<(), CodecError> {
    use std::sync::mpsc::{channel, sync_channel};
    let (full_tx, full_rx) = sync_channel::<Vec<T>>(2);
    let (empty_tx, empty_rx) = channel::<Vec<T>>();
    std::thread::scope(|scope| {
        let user = scope.spawn(move || {
            for mut batch in full_rx {
                for &item in &batch {
                    f(item);
                }
                batch.clear();
                // the reader may be gone (it failed): then the batch is simply dropped
                let _ = empty_tx.send(batch);
            }
        });
        let mut batch = Vec::with_capacity(BATCH);
        let mut gone = false;
        let read = read(&mut |item| {
            batch.push(item);
            if batch.len() == BATCH {
                let next = empty_rx
                    .try_recv()
                    .unwrap_or_else(|_| Vec::with_capacity(BATCH));
                // the user thread only stops early by panicking, which the join below repeats
                gone |= full_tx.send(std::mem::replace(&mut batch, next)).is_err();
            }
        });
        if read.is_ok() && !gone && !batch.is_empty() {
            let _ = full_tx.send(batch);
        }
        drop(full_tx);
        if let Err(panic) = user.join() {
            std::panic::resume_unwind(panic);
        }
        read
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pass_beside_sees_every_item_in_order() {
        let n = 3 * BESIDE_FROM as usize + 17;
        let positions: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 0.0, 1.0]).collect();
        let triangles: Vec<[u32; 3]> = (0..n as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        let mut src = Slices {
            positions: &positions,
            triangles: &triangles,
        };
        let mut seen = Vec::new();
        triangles_beside(&mut src, &mut |t| seen.push(t)).unwrap();
        assert!(seen == triangles);
        let mut xs = Vec::new();
        vertices_beside(&mut src, &mut |p| xs.push(p)).unwrap();
        assert!(xs == positions);
    }

    /// A source whose triangle pass fails after `good` triangles.
    struct Failing {
        good: u32,
    }

    impl MeshSource for Failing {
        fn vertex_count(&self) -> u64 {
            4 * BESIDE_FROM
        }
        fn vertices(&mut self, _: &mut dyn FnMut([f32; 3])) -> Result<(), tessd_mesh::MeshError> {
            Ok(())
        }
        fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), tessd_mesh::MeshError> {
            for i in 0..self.good {
                f([i, i + 1, i + 2]);
            }
            Err(tessd_mesh::MeshError::Parse {
                path: "failing.ply".into(),
                line: 0,
                message: "the file ends inside face 40000".into(),
            })
        }
    }

    #[test]
    fn a_failing_pass_beside_reports_its_error_after_the_triangles_before_it() {
        let mut seen = 0u32;
        let e = triangles_beside(&mut Failing { good: 40_000 }, &mut |t| {
            assert_eq!(t[0], seen);
            seen += 1;
        })
        .unwrap_err();
        assert!(e.to_string().contains("ends inside face 40000"), "{e}");
        // the batches read before the failure may or may not have been used: never more
        assert!(seen <= 40_000);
    }
}
