//! Normals, UVs and face groups through clustering (beyond the paper, which keeps geometry
//! only): each output corner takes the average of the input values of its cluster *within its
//! face group*, so two materials meeting in one cell keep their own values.

use crate::cell_table::CellTable;
use crate::elimination::Eliminated;
use tessd_mesh::{FaceVarying, Mesh};

/// The output's face groups (those of the surviving input faces).
pub(crate) fn carry_groups(input: &Mesh, kept: &Eliminated) -> Vec<u32> {
    if input.face_groups.is_empty() {
        return Vec::new();
    }
    kept.source_face
        .iter()
        .map(|&f| input.face_groups[f as usize])
        .collect()
}

/// A face-varying attribute averaged per (cluster, face group); `normalize` renormalises the
/// averages (for normals).
pub(crate) fn carry_face_varying<const N: usize>(
    input: &Mesh,
    attr: &FaceVarying<[f32; N]>,
    cluster_of: &[u32],
    kept: &Eliminated,
    normalize: bool,
) -> FaceVarying<[f32; N]> {
    let key = |corner: usize, face: usize| -> u64 {
        let v = input.face_indices[corner] as usize;
        let group = input.face_groups.get(face).copied().unwrap_or(0);
        (u64::from(cluster_of[v]) << 32) | u64::from(group)
    };
    // Sum every input corner's value into its (cluster, group) slot.
    let mut table = CellTable::with_capacity(kept.face_indices.len() / 2 + 16);
    let mut sums: Vec<[f64; N]> = Vec::new();
    let mut counts: Vec<u32> = Vec::new();
    for (f, w) in input.face_offsets.windows(2).enumerate() {
        for corner in w[0] as usize..w[1] as usize {
            let id = table.id(key(corner, f)) as usize;
            if id == sums.len() {
                sums.push([0.0; N]);
                counts.push(0);
            }
            let value = attr.values[attr.indices[corner] as usize];
            for k in 0..N {
                sums[id][k] += f64::from(value[k]);
            }
            counts[id] += 1;
        }
    }
    // Output corners point at their slot; only slots in use become values.
    let mut remap = vec![u32::MAX; sums.len()];
    let mut out = FaceVarying {
        values: Vec::new(),
        indices: Vec::with_capacity(kept.face_indices.len()),
    };
    for (f_out, w) in kept.face_offsets.windows(2).enumerate() {
        let f_in = kept.source_face[f_out] as usize;
        for k in w[0] as usize..w[1] as usize {
            let id = table.id(key(kept.source_corner[k] as usize, f_in)) as usize;
            if remap[id] == u32::MAX {
                remap[id] = out.values.len() as u32;
                let mut v: [f32; N] =
                    std::array::from_fn(|i| (sums[id][i] / f64::from(counts[id])) as f32);
                if normalize {
                    let len = v.iter().map(|x| x * x).sum::<f32>().sqrt();
                    if len > 0.0 {
                        v.iter_mut().for_each(|x| *x /= len);
                    }
                }
                out.values.push(v);
            }
            out.indices.push(remap[id]);
        }
    }
    out
}
