//! Normals, UVs, face groups and generic attributes through clustering (beyond the paper,
//! which keeps geometry only).
//!
//! - Face-varying data (normals, UVs, `corner:` attributes): each output corner takes the
//!   average of the input values of its cluster *within its face group*, so two materials
//!   meeting in one cell keep their own values. The (cluster, group) slots are numbered once
//!   ([`CornerSlots`]) and shared by every face-varying channel, whatever its width.
//! - `point:` attributes: the unweighted mean over the cluster's referenced input vertices
//!   (the representative's position is a weighted or optimised point, but a value such as a
//!   weight or a colour has no geometry to optimise, and the plain mean keeps it in the range
//!   of what the cluster held).
//! - `face:` attributes and face groups: those of the surviving input face.
//!
//! Only slots that output corners use are numbered, in the order the output corners first
//! meet them (the order of the output's values). A slot is found from its cluster through a
//! flat array, not by hashing every corner: a cluster's first slot and that slot's group are
//! kept by cluster id, and only a cluster met in a second group (a material border) asks a
//! hash map. A channel is then carried in one pass over the input corners, adding into
//! preallocated sums in input order (so the sums, hence the output's bits, do not depend on
//! the thread count), with no per-corner slot array stored between channels.

use crate::elimination::Eliminated;
use crate::partition::UNUSED;
use std::collections::HashMap;
use tessd_mesh::attribute::RowMeans;
use tessd_mesh::{Attribute, Domain, FaceVarying, Mesh};

/// No slot: a cluster without output corners, or a (cluster, group) pair no output corner has.
const NONE: u32 = u32::MAX;

/// The output's face groups (those of the surviving input faces).
pub(crate) fn carry_groups(input: &Mesh, kept: &Eliminated) -> Vec<u32> {
    if input.face_groups.is_empty() {
        return Vec::new();
    }
    kept.source_faces()
        .map(|f| input.face_groups[f as usize])
        .collect()
}

/// The (cluster, face group) slots of the output corners, numbered in the order the output
/// corners first meet them, and how to find the slot of an input corner.
pub(crate) struct CornerSlots<'a> {
    /// The input mesh.
    input: &'a Mesh,
    /// Cluster of each input vertex.
    cluster_of: &'a [u32],
    /// Finds a (cluster, group) pair's slot.
    index: SlotIndex,
    /// Slot of each output corner.
    output: Vec<u32>,
}

/// The slot of each (cluster, group) pair that output corners have: a cluster's first slot
/// (and its group) in flat arrays by cluster id, the slots of its other groups in a map.
struct SlotIndex {
    /// The first slot of each cluster ([`NONE`]: none).
    first: Vec<u32>,
    /// The group of that slot (empty when the mesh has no groups).
    first_group: Vec<u32>,
    /// The slots of a cluster's further groups, by (cluster, group) key.
    extra: HashMap<u64, u32>,
    /// Slots numbered.
    len: u32,
}

impl SlotIndex {
    /// The slot of (`cluster`, `group`), numbering it when new.
    #[inline]
    fn number(&mut self, cluster: u32, group: u32) -> u32 {
        let c = cluster as usize;
        if self.first[c] == NONE {
            self.first[c] = self.len;
            if let Some(g) = self.first_group.get_mut(c) {
                *g = group;
            }
            self.len += 1;
            self.first[c]
        } else if self.first_group.is_empty() || self.first_group[c] == group {
            self.first[c]
        } else {
            let next = self.len;
            let slot = *self.extra.entry(key(cluster, group)).or_insert(next);
            self.len += u32::from(slot == next);
            slot
        }
    }

    /// The slot of (`cluster`, `group`), or [`NONE`] when no output corner has it.
    #[inline]
    fn find(&self, cluster: u32, group: u32) -> u32 {
        let c = cluster as usize;
        match self.first.get(c) {
            None | Some(&NONE) => NONE,
            Some(&s) if self.first_group.is_empty() || self.first_group[c] == group => s,
            Some(_) => self.find_extra(cluster, group),
        }
    }

    #[cold]
    fn find_extra(&self, cluster: u32, group: u32) -> u32 {
        self.extra
            .get(&key(cluster, group))
            .copied()
            .unwrap_or(NONE)
    }
}

/// How many corners ahead the cluster of a corner's vertex is asked into cache.
const PREFETCH: usize = 32;

/// Asks for the cache line at `p` (a hint that never faults).
#[inline]
fn prefetch(p: *const u32) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetching is a hint that never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch(p as *const i8, std::arch::x86_64::_MM_HINT_T0)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// A (cluster, group) pair as one map key.
fn key(cluster: u32, group: u32) -> u64 {
    (u64::from(cluster) << 32) | u64::from(group)
}

impl<'a> CornerSlots<'a> {
    /// Numbers the (cluster, group) pairs of the output corners in order. An output corner
    /// has the slot of its source corner: that corner lies in the output face's source face,
    /// hence in its group, and its vertex is in the output corner's cluster.
    pub(crate) fn new(input: &'a Mesh, cluster_of: &'a [u32], kept: &Eliminated) -> Self {
        let clusters = kept
            .face_indices
            .iter()
            .max()
            .map_or(0, |&c| c as usize + 1);
        let groups = &input.face_groups;
        let mut index = SlotIndex {
            first: vec![NONE; clusters],
            first_group: if groups.is_empty() {
                Vec::new()
            } else {
                vec![0; clusters]
            },
            extra: HashMap::new(),
            len: 0,
        };
        let mut output = Vec::with_capacity(kept.face_indices.len());
        if groups.is_empty() {
            output.extend(kept.face_indices.iter().map(|&c| index.number(c, 0)));
        } else {
            for (w, f) in kept.face_offsets.windows(2).zip(kept.source_faces()) {
                let group = groups[f as usize];
                let corners = &kept.face_indices[w[0] as usize..w[1] as usize];
                output.extend(corners.iter().map(|&c| index.number(c, group)));
            }
        }
        debug_assert!(
            (kept.source_corner.iter().zip(&kept.face_indices))
                .all(|(&s, &c)| cluster_of[input.face_indices[s as usize] as usize] == c)
        );
        CornerSlots {
            input,
            cluster_of,
            index,
            output,
        }
    }

    /// Number of slots (the output's distinct values of a face-varying channel).
    fn len(&self) -> usize {
        self.index.len as usize
    }

    /// Calls `visit(corner, slot)` for every input corner, in order, whose slot output
    /// corners have.
    #[inline]
    fn for_each_input(&self, mut visit: impl FnMut(usize, usize)) {
        let (mesh, cluster_of, index) = (self.input, self.cluster_of, &self.index);
        // Vertices far apart in the numbering make `cluster_of` a random read per corner: it
        // is asked for some corners ahead (1.31 M triangles, vertices shuffled: 32 -> 21 ms).
        let ahead = &mesh.face_indices[PREFETCH.min(mesh.face_indices.len())..];
        if mesh.face_groups.is_empty() {
            for (c, &v) in mesh.face_indices.iter().enumerate() {
                if let Some(&next) = ahead.get(c) {
                    prefetch(cluster_of.as_ptr().wrapping_add(next as usize));
                }
                let slot = index.find(cluster_of[v as usize], 0);
                if slot != NONE {
                    visit(c, slot as usize);
                }
            }
        } else {
            let faces = mesh.face_offsets.windows(2).zip(&mesh.face_groups);
            for (w, &group) in faces {
                for c in w[0] as usize..w[1] as usize {
                    if let Some(&next) = ahead.get(c) {
                        prefetch(cluster_of.as_ptr().wrapping_add(next as usize));
                    }
                    let slot = index.find(cluster_of[mesh.face_indices[c] as usize], group);
                    if slot != NONE {
                        visit(c, slot as usize);
                    }
                }
            }
        }
    }

    /// The mean of every slot of a channel whose input corner `c` holds `row(c)`
    /// (`components` floats).
    fn means<'r>(&self, components: usize, row: impl Fn(usize) -> &'r [f32]) -> RowMeans {
        let mut means = RowMeans::new(self.len(), components);
        self.for_each_input(|c, slot| means.add(slot, row(c)));
        means
    }
}

/// A face-varying attribute averaged per (cluster, face group); `normalize` renormalises the
/// averages (for normals). Only slots that output corners use become values, in the order
/// the output corners first use them.
pub(crate) fn carry_face_varying<const N: usize>(
    attr: &FaceVarying<[f32; N]>,
    slots: &CornerSlots,
    normalize: bool,
) -> FaceVarying<[f32; N]> {
    // Sums in f64, as RowMeans keeps them: averaging thousands of rows loses nothing in f32.
    let mut sums = vec![[0f64; N]; slots.len()];
    let mut counts = vec![0u32; slots.len()];
    slots.for_each_input(|c, slot| {
        let row = &attr.values[attr.indices[c] as usize];
        for (s, &x) in sums[slot].iter_mut().zip(row) {
            *s += f64::from(x);
        }
        counts[slot] += 1;
    });
    let values = (sums.iter().zip(&counts))
        .map(|(sum, &count)| {
            let n = f64::from(count.max(1));
            let mut v: [f32; N] = std::array::from_fn(|k| (sum[k] / n) as f32);
            if normalize {
                let len = v.iter().map(|x| x * x).sum::<f32>().sqrt();
                if len > 0.0 {
                    v.iter_mut().for_each(|x| *x /= len);
                }
            }
            v
        })
        .collect();
    FaceVarying {
        values,
        indices: slots.output.clone(),
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elimination;
    use crate::{Count, Method, SimplifyOptions, simplify};

    /// A wavy n × n grid of quads, every third one split into two triangles, with per-corner
    /// UVs that wrap at x = 0.6 (a seam: corners of one vertex hold u and u + 1), indexed
    /// normals (one per vertex, and a flipped copy on the faces of the third group), a
    /// two-component corner attribute, and `groups` face groups (0: none) in stripes and a
    /// patch, so that clusters straddle group borders.
    fn seamed_grid(n: u32, groups: u32) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                m.positions
                    .push([x, y, 0.1 * (7.0 * x).sin() * (4.0 * y).cos()]);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                if (i + 2 * j) % 3 == 0 {
                    m.push_face(&[v, v + 1, v + n + 2]);
                    m.push_face(&[v, v + n + 2, v + n + 1]);
                } else {
                    m.push_face(&[v, v + 1, v + n + 2, v + n + 1]);
                }
            }
        }
        if groups > 0 {
            m.face_groups = (0..m.face_count() as u32)
                .map(|f| {
                    let w = &m.face_offsets[f as usize..f as usize + 2];
                    let p = m.positions[m.face_indices[w[0] as usize] as usize];
                    if p[0] > 0.3 && p[0] < 0.5 && p[1] > 0.2 && p[1] < 0.7 {
                        groups - 1
                    } else {
                        ((p[1] * 5.0) as u32) % groups
                    }
                })
                .collect();
            m.group_names = (0..groups).map(|g| format!("g{g}")).collect();
        }
        let mut uvs = Vec::new();
        let mut normal_indices = Vec::new();
        let mut corner = Vec::new();
        for f in 0..m.face_count() {
            let w = &m.face_offsets[f..f + 2];
            let face = &m.face_indices[w[0] as usize..w[1] as usize];
            let low = face.iter().any(|&v| m.positions[v as usize][0] < 0.6);
            let flipped = m.face_groups.get(f) == Some(&2);
            for &v in face {
                let p = m.positions[v as usize];
                let u = if p[0] >= 0.6 || !low {
                    p[0] - 0.6
                } else {
                    p[0] + 0.4
                };
                uvs.push([u, p[1] * 0.75 + p[2]]);
                normal_indices.push(v + if flipped { m.positions.len() as u32 } else { 0 });
                corner.extend([p[2] * 3.0 + f as f32 * 1e-3, 1.0 / (1.0 + v as f32)]);
            }
        }
        let up = |s: f32| {
            move |p: &[f32; 3]| {
                let n = [
                    -0.7 * (7.0 * p[0]).cos() * s,
                    0.4 * (4.0 * p[1]).sin() * s,
                    s,
                ];
                let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                n.map(|x| x / l)
            }
        };
        let normals = m
            .positions
            .iter()
            .map(up(1.0))
            .chain(m.positions.iter().map(up(-1.0)));
        m.uvs = Some(FaceVarying {
            indices: (0..uvs.len() as u32).collect(),
            values: uvs,
        });
        m.normals = Some(FaceVarying {
            values: normals.collect(),
            indices: normal_indices,
        });
        m.attributes
            .push(Attribute::new("wear", Domain::Corner, 2, corner));
        m
    }

    /// Vertices clustered in cells of `cell` × `cell` grid steps (offset so that cells do not
    /// line up with the seam or the groups), and each cluster's mean position.
    fn clusters(m: &Mesh, n: u32, cell: u32) -> (Vec<u32>, Vec<[f32; 3]>) {
        let per_row = (n + 1) / cell + 2;
        let raw: Vec<u32> = (0..m.positions.len() as u32)
            .map(|v| {
                let (i, j) = (v % (n + 1) + 1, v / (n + 1) + 2);
                (j / cell) * per_row + i / cell
            })
            .collect();
        // Dense ids in order of first vertex.
        let mut id = HashMap::new();
        let cluster_of: Vec<u32> = raw
            .iter()
            .map(|&r| {
                let next = id.len() as u32;
                *id.entry(r).or_insert(next)
            })
            .collect();
        let mut sums = vec![([0f64; 3], 0f64); id.len()];
        for (v, &c) in cluster_of.iter().enumerate() {
            for k in 0..3 {
                sums[c as usize].0[k] += f64::from(m.positions[v][k]);
            }
            sums[c as usize].1 += 1.0;
        }
        let reps = sums
            .iter()
            .map(|(s, n)| s.map(|x| (x / n) as f32))
            .collect();
        (cluster_of, reps)
    }

    /// The mean per (cluster, group) the plain way: the input corners of every pair listed in
    /// order, each output corner's pair found from its source corner's face, values numbered
    /// as the output first meets them.
    fn reference<const N: usize>(
        m: &Mesh,
        cluster_of: &[u32],
        kept: &Eliminated,
        row: impl Fn(usize) -> [f32; N],
        normalize: bool,
    ) -> (Vec<[f32; N]>, Vec<u32>) {
        let face_of = |c: u32| m.face_offsets.partition_point(|&o| o <= c) - 1;
        let pair = |c: u32| {
            let group = m.face_groups.get(face_of(c)).copied().unwrap_or(0);
            (cluster_of[m.face_indices[c as usize] as usize], group)
        };
        let mut members: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for c in 0..m.face_indices.len() as u32 {
            members.entry(pair(c)).or_default().push(c);
        }
        let mut number = HashMap::new();
        let (mut values, mut indices) = (Vec::new(), Vec::new());
        for &s in &kept.source_corner {
            let p = pair(s);
            let i = *number.entry(p).or_insert_with(|| {
                let corners = &members[&p];
                let mut sum = [0f64; N];
                for &c in corners {
                    let r = row(c as usize);
                    (0..N).for_each(|k| sum[k] += f64::from(r[k]));
                }
                let mut v = sum.map(|s| (s / corners.len() as f64) as f32);
                if normalize {
                    let len = v.iter().map(|x| x * x).sum::<f32>().sqrt();
                    v.iter_mut().for_each(|x| *x /= len);
                }
                values.push(v);
                values.len() as u32 - 1
            });
            indices.push(i);
        }
        (values, indices)
    }

    fn bits<const N: usize>(v: &[[f32; N]]) -> Vec<[u32; N]> {
        v.iter().map(|r| r.map(f32::to_bits)).collect()
    }

    #[test]
    fn carried_corner_values_equal_the_plain_means_bit_for_bit() {
        let n = 40;
        for (groups, cell) in [(0, 3), (3, 3), (3, 5), (4, 2)] {
            let m = seamed_grid(n, groups);
            m.validate().unwrap();
            let (cluster_of, reps) = clusters(&m, n, cell);
            let kept = elimination::eliminate(&m, &cluster_of, &reps, true);
            assert!(kept.face_indices.len() > 100 && kept.degenerate > 0);
            let slots = CornerSlots::new(&m, &cluster_of, &kept);
            let (uvs, normals) = (m.uvs.as_ref().unwrap(), m.normals.as_ref().unwrap());

            let got = carry_face_varying(uvs, &slots, false);
            let want = reference(&m, &cluster_of, &kept, |c| uvs.values[c], false);
            assert_eq!(bits(&got.values), bits(&want.0), "uvs, {groups} groups");
            assert_eq!(got.indices, want.1);
            // Corners merged: far fewer values than input corners.
            assert!(got.values.len() < uvs.values.len() / 4);

            let got = carry_face_varying(normals, &slots, true);
            let row = |c: usize| normals.values[normals.indices[c] as usize];
            let want = reference(&m, &cluster_of, &kept, row, true);
            assert_eq!(bits(&got.values), bits(&want.0), "normals, {groups} groups");
            assert_eq!(got.indices, want.1);
            if groups > 0 {
                // Groups split slots: more values than clusters used.
                let used: std::collections::HashSet<_> = kept.face_indices.iter().collect();
                assert!(got.values.len() > used.len());
            }

            let new_id = vec![0; reps.len()];
            let got = carry_attributes(&m, &cluster_of, &new_id, 1, &kept, Some(&slots));
            let wear = &m.attributes[0];
            let row = |c: usize| [wear.values[2 * c], wear.values[2 * c + 1]];
            let (values, indices) = reference(&m, &cluster_of, &kept, row, false);
            let want: Vec<[f32; 2]> = indices.iter().map(|&i| values[i as usize]).collect();
            let got: Vec<[f32; 2]> = got[0].values.chunks(2).map(|r| [r[0], r[1]]).collect();
            assert_eq!(bits(&got), bits(&want), "corner attribute, {groups} groups");
        }
    }

    #[test]
    fn carried_uvs_are_the_same_on_1_2_and_7_threads() {
        let m = seamed_grid(120, 3);
        let options = SimplifyOptions::new(Method::Complexity(Count::Relative(0.1)));
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| simplify(&m, &options, &mut |_, _| true).unwrap().mesh)
        };
        let one = run(1);
        assert!(one.uvs.as_ref().is_some_and(|t| !t.values.is_empty()));
        for threads in [2, 7] {
            let other = run(threads);
            let uv_bits = |x: &Mesh| bits(&x.uvs.as_ref().unwrap().values);
            assert_eq!(uv_bits(&one), uv_bits(&other), "{threads} threads");
            assert_eq!(one, other, "{threads} threads");
        }
    }
}
