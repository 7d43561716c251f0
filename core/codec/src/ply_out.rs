//! Full decoding straight into a binary PLY, in bounded memory (paper 003 §5's out-of-core
//! promise, on the way back): the tree is decoded depth first twice. The first pass writes
//! every leaf's own vertices (those inside its cell) in kd order, and keeps their kd keys in a
//! scratch file; the second pass writes every leaf's own triangles (those whose first vertex in
//! kd order is its own), finding a neighbour's vertex index by binary search in that leaf's
//! keys, read back from the scratch file. Only the cells on the way down, the per-leaf offsets
//! and a few neighbours' keys are in memory, whatever the file's size.

use std::io::{BufWriter, Write};

use rustc_hash::FxHashMap;

use crate::complex::{Complex, POINT};
use crate::decode::Tsc;
use crate::error::CodecError;
use crate::kd_cell::kd_key;
use crate::positional_io;

/// What [`Tsc::write_ply`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlyReport {
    /// Vertices written.
    pub vertices: u64,
    /// Triangles written (degenerate ones included, as the input had them).
    pub triangles: u64,
    /// Cells decoded (each twice).
    pub cells: u64,
}

/// Leaves whose keys are kept in memory at once.
const CACHED_LEAVES: usize = 256;

impl Tsc {
    /// The leaf holding grid point `q`.
    fn leaf_of(&self, q: [u32; 3]) -> usize {
        self.descend(q, |_| false)
    }

    /// Whether grid point `q` lies in cell `i`.
    fn inside(&self, i: usize, q: [u32; 3]) -> bool {
        let node = &self.nodes[i];
        self.header.params.cell_at(node.depth, q) == node.cell
    }

    /// The kd key of the first vertex (in kd order) of every triangle is owned by one leaf.
    fn first_corner(cx: &Complex, v: [u32; 3], full: usize, bits: u32) -> [u32; 3] {
        let c = v.map(|x| cx.vertices[x as usize].corner);
        *c.iter().min_by_key(|q| kd_key(**q, full, bits)).unwrap()
    }

    /// Decodes the whole file into a binary little-endian PLY written to `out`.
    pub fn write_ply(
        &self,
        out: &mut dyn Write,
        progress: &(dyn Fn(f64) -> bool + Sync),
    ) -> Result<PlyReport, CodecError> {
        let p = self.header.params.bits;
        let full = 3 * p as usize;
        let grid = self.header.grid;
        let w = |e| CodecError::io("writing the decoded mesh", e);
        let (nv, nt) = (self.header.vertices, self.header.triangles);
        write!(
            out,
            "ply\nformat binary_little_endian 1.0\ncomment decoded by tessd from a .tsc file\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\nelement face {nt}\nproperty list uchar uint vertex_indices\nend_header\n"
        )
        .map_err(w)?;
        let keys_file =
            tempfile::tempfile().map_err(|e| CodecError::io("creating the scratch key file", e))?;
        let mut keys_out = BufWriter::with_capacity(1 << 20, &keys_file);
        // pass 1: every leaf's own vertices, in kd order
        let mut bases: Vec<(u64, u64)> = vec![(0, 0); self.nodes.len()];
        let mut written = 0u64;
        let leaves = self
            .nodes
            .iter()
            .filter(|n| n.children.is_empty())
            .count()
            .max(1) as f64;
        let mut done = 0.0;
        let (_, cells) = self.visit(p, &mut |i, cx, alive, _| {
            let base = written;
            for &v in alive {
                let q = cx.vertices[v as usize].corner;
                if !self.inside(i, q) {
                    continue;
                }
                let pos = grid.position(q.map(f64::from));
                for c in pos {
                    out.write_all(&(c as f32).to_le_bytes()).map_err(w)?;
                }
                keys_out
                    .write_all(&kd_key(q, full, p).to_le_bytes())
                    .map_err(|e| CodecError::io("writing the scratch key file", e))?;
                written += 1;
            }
            bases[i] = (base, written - base);
            done += 1.0;
            if !progress(0.5 * done / leaves) {
                return Err(CodecError::Cancelled);
            }
            Ok(())
        })?;
        if written != nv {
            return Err(CodecError::corrupt(
                48,
                format!("the header says {nv} vertices, the cells hold {written}"),
            ));
        }
        keys_out
            .flush()
            .map_err(|e| CodecError::io("writing the scratch key file", e))?;
        drop(keys_out);
        // pass 2: every leaf's own triangles, with neighbours' indices from their keys
        let mut cache: FxHashMap<usize, Vec<u64>> = FxHashMap::default();
        let load =
            |leaf: usize, cache: &mut FxHashMap<usize, Vec<u64>>| -> Result<(), CodecError> {
                if cache.contains_key(&leaf) {
                    return Ok(());
                }
                if cache.len() >= CACHED_LEAVES {
                    let any = *cache.keys().next().unwrap();
                    cache.remove(&any);
                }
                let (base, count) = bases[leaf];
                let mut bytes = vec![0u8; 8 * count as usize];
                positional_io::read_exact_at(&keys_file, &mut bytes, 8 * base)
                    .map_err(|e| CodecError::io("reading the scratch key file", e))?;
                cache.insert(
                    leaf,
                    bytes
                        .chunks_exact(8)
                        .map(|b| u64::from_le_bytes(b.try_into().unwrap()))
                        .collect(),
                );
                Ok(())
            };
        let mut triangles = 0u64;
        done = 0.0;
        self.visit(p, &mut |i, cx, _alive, _| {
            load(i, &mut cache)?;
            for s in cx.live_simplices() {
                if s.kind == POINT || !self.inside(i, Self::first_corner(cx, s.v, full, p)) {
                    continue;
                }
                let mut idx = [0u32; 3];
                for (k, &x) in s.v.iter().enumerate() {
                    let q = cx.vertices[x as usize].corner;
                    let leaf = if self.inside(i, q) {
                        i
                    } else {
                        self.leaf_of(q)
                    };
                    load(leaf, &mut cache)?;
                    let key = kd_key(q, full, p);
                    let rank = cache[&leaf].binary_search(&key).map_err(|_| {
                        CodecError::corrupt(
                            self.nodes[i].offset,
                            format!("cell {i} uses a vertex cell {leaf} does not hold"),
                        )
                    })?;
                    idx[k] = (bases[leaf].0 + rank as u64) as u32;
                }
                out.write_all(&[3]).map_err(w)?;
                for x in idx {
                    out.write_all(&x.to_le_bytes()).map_err(w)?;
                }
                triangles += 1;
            }
            // the current leaf may be dropped from the cache later; keep it while its
            // neighbours are decoded
            done += 1.0;
            if !progress(0.5 + 0.5 * done / leaves) {
                return Err(CodecError::Cancelled);
            }
            Ok(())
        })?;
        if triangles != nt {
            return Err(CodecError::corrupt(
                56,
                format!("the header says {nt} triangles, the cells hold {triangles}"),
            ));
        }
        Ok(PlyReport {
            vertices: nv,
            triangles,
            cells,
        })
    }
}
