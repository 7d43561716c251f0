//! Normals, UVs, face groups and generic attributes through clustering (beyond the paper,
//! which keeps geometry only).
//!
//! - Face-varying data (normals, UVs, `corner:` attributes): each output corner takes the
//!   average of the input values of its cluster *within its face group*, so two materials
//!   meeting in one cell keep their own values. The (cluster, group) slots are computed once
//!   ([`CornerSlots`]) and shared by every face-varying channel, whatever its width.
//! - `point:` attributes: the unweighted mean over the cluster's referenced input vertices
//!   (the representative's position is a weighted or optimised point, but a value such as a
//!   weight or a colour has no geometry to optimise, and the plain mean keeps it in the range
//!   of what the cluster held).
//! - `face:` attributes and face groups: those of the surviving input face.

use crate::cell_table::CellTable;
use crate::elimination::Eliminated;
use crate::partition::UNUSED;
use tessd_mesh::attribute::RowMeans;
use tessd_mesh::{Attribute, Domain, FaceVarying, Mesh};

/// The output's face groups (those of the surviving input faces).
pub(crate) fn carry_groups(input: &Mesh, kept: &Eliminated) -> Vec<u32> {
    if input.face_groups.is_empty() {
        return Vec::new();
    }
    kept.source_faces()
        .map(|f| input.face_groups[f as usize])
        .collect()
}

/// The (cluster, face group) slot of every input corner and of every output corner.
pub(crate) struct CornerSlots {
    /// Slot of each input corner.
    input: Vec<u32>,
    /// Slot of each output corner.
    output: Vec<u32>,
    /// Number of slots.
    count: usize,
}

impl CornerSlots {
    /// Numbers the (cluster, group) pairs of `input`'s corners; an output corner has the slot of
    /// its source corner (which lies in its source face, hence in the same group).
    pub(crate) fn new(input: &Mesh, cluster_of: &[u32], kept: &Eliminated) -> CornerSlots {
        let mut table = CellTable::with_capacity(kept.face_indices.len() / 2 + 16);
        let mut slots = Vec::with_capacity(input.face_indices.len());
        for (f, w) in input.face_offsets.windows(2).enumerate() {
            let group = input.face_groups.get(f).copied().unwrap_or(0);
            for &v in &input.face_indices[w[0] as usize..w[1] as usize] {
                let key = (u64::from(cluster_of[v as usize]) << 32) | u64::from(group);
                slots.push(table.id(key));
            }
        }
        let count = slots.iter().map(|&s| s as usize + 1).max().unwrap_or(0);
        let output = kept
            .source_corner
            .iter()
            .map(|&c| slots[c as usize])
            .collect();
        CornerSlots {
            input: slots,
            output,
            count,
        }
    }

    /// The mean of every slot of a channel whose input corner `c` holds `row(c)`
    /// (`components` floats).
    fn means<'a>(&self, components: usize, row: impl Fn(usize) -> &'a [f32]) -> RowMeans {
        let mut means = RowMeans::new(self.count, components);
        for (c, &slot) in self.input.iter().enumerate() {
            means.add(slot as usize, row(c));
        }
        means
    }
}

/// A face-varying attribute averaged per (cluster, face group); `normalize` renormalises the
/// averages (for normals). Only slots that output corners use become values.
pub(crate) fn carry_face_varying<const N: usize>(
    attr: &FaceVarying<[f32; N]>,
    slots: &CornerSlots,
    normalize: bool,
) -> FaceVarying<[f32; N]> {
    let means = slots.means(N, |c| &attr.values[attr.indices[c] as usize][..]);
    let mut remap = vec![u32::MAX; slots.count];
    let mut out = FaceVarying {
        values: Vec::new(),
        indices: Vec::with_capacity(slots.output.len()),
    };
    let mut row = Vec::with_capacity(N);
    for &slot in &slots.output {
        let slot = slot as usize;
        if remap[slot] == u32::MAX {
            remap[slot] = out.values.len() as u32;
            row.clear();
            means.push_mean(slot, &mut row);
            let mut v: [f32; N] = std::array::from_fn(|i| row[i]);
            if normalize {
                let len = v.iter().map(|x| x * x).sum::<f32>().sqrt();
                if len > 0.0 {
                    v.iter_mut().for_each(|x| *x /= len);
                }
            }
            out.values.push(v);
        }
        out.indices.push(remap[slot]);
    }
    out
}

/// The generic attributes of the output: point attributes averaged over each output vertex's
/// cluster (`new_id`: output vertex of each cluster or [`UNUSED`]; `vertices`: output vertex
/// count), corner attributes averaged per (cluster, group) slot (`slots` is `Some` whenever
/// the input has corner attributes), face attributes from the source faces.
pub(crate) fn carry_attributes(
    input: &Mesh,
    cluster_of: &[u32],
    new_id: &[u32],
    vertices: usize,
    kept: &Eliminated,
    slots: Option<&CornerSlots>,
) -> Vec<Attribute> {
    input
        .attributes
        .iter()
        .map(|a| match a.domain {
            Domain::Point => {
                let mut means = RowMeans::new(vertices, a.components);
                for (v, &c) in cluster_of.iter().enumerate() {
                    if c != UNUSED && new_id[c as usize] != UNUSED {
                        means.add(new_id[c as usize] as usize, a.row(v));
                    }
                }
                Attribute {
                    values: means.means(),
                    ..a.empty_like()
                }
            }
            Domain::Corner => {
                let slots = slots.expect("corner slots are built when corner attributes exist");
                let means = slots.means(a.components, |c| a.row(c));
                let mut values = Vec::with_capacity(slots.output.len() * a.components);
                for &slot in &slots.output {
                    means.push_mean(slot as usize, &mut values);
                }
                Attribute {
                    values,
                    ..a.empty_like()
                }
            }
            Domain::Face => a.gather(kept.source_faces().collect::<Vec<_>>().into_iter()),
        })
        .collect()
}
