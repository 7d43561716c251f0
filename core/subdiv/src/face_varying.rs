//! Face-varying data (UVs, generic per-corner attributes) refined alongside the vertices, as
//! OpenSubdiv's `Far::PrimvarRefiner` refines it for Blender's Subdivision Surface modifier: the
//! channel's refiner ([`FaceVaryingRefiner`], topology once, apply per frame), the cage's UVs
//! refined ([`refine_uvs`]), and the welding of equal corner values into one value.
//!
//! A face-varying channel has its own topology: one value index per face corner. Each level's
//! values follow OpenSubdiv's value rules (spans, seams, corners, creases), chosen by
//! [`UvInterpolation`](crate::UvInterpolation): those are [`crate::face_varying_rules`].
//!
//! Children come in parent-corner order (see [`catmull_clark::split_faces`]), so the refined
//! UV topology's faces are the refined mesh's faces one to one and the result's indices follow
//! the refined mesh's corners. Schemes whose faces do not split that way (Butterfly, Doo–Sabin,
//! √3) carry no UVs: they are dropped ([`carries_face_varying`]). Loop can join: the value
//! rules (seams, spans, corners, creases) do not depend on the scheme; it needs its own masks
//! in `face_varying_rules::ChannelLevel` (no face values) and the child corners of
//! `loop_scheme::split_triangles` in `face_varying_rules::refine_level`.
//!
//! Like Blender's converter, corners of one vertex with equal UVs are one value (see

use crate::catmull_clark;
use crate::error::SubdivError;
use crate::face_varying_rules::{ChannelLevel, Rules, refine_level};
use crate::stencil::StencilTable;
use crate::topology::{Faces, Topology};
use crate::{Refiner, Scheme, SubdivOptions};
use tessd_mesh::{FaceVarying, Mesh};

/// True for the schemes whose refined faces follow the parent corners, so that face-varying
/// data can be refined with them.
pub fn carries_face_varying(scheme: Scheme) -> bool {
    matches!(scheme, Scheme::CatmullClark | Scheme::Bilinear)
}

/// Corners of one vertex whose values are equal (0 and −0 alike) get one value index, the
/// first such corner's: the UV topology is then that of the values, as Blender's converter
/// builds it, not of however the indices were written (per-corner UVs, duplicated indices).
pub fn weld_by_value<const N: usize>(face_indices: &[u32], fv: &FaceVarying<[f32; N]>) -> Vec<u32> {
    weld_rows(face_indices, &fv.indices, fv.values.as_flattened(), N)
}

/// [`weld_by_value`] for rows of any width: corner `c` holds row `rows[c]` of `values`
/// (`components` floats per row); the result gives each corner the row of the first corner of
/// its vertex holding an equal row. Corners are sorted by (vertex, row bits, corner), so the
/// first of each run of equals is the first in corner order; no per-corner allocation.
pub fn weld_rows(
    face_indices: &[u32],
    rows: &[u32],
    values: &[f32],
    components: usize,
) -> Vec<u32> {
    let c = components.max(1);
    let row = |k: usize| &values[rows[k] as usize * c..rows[k] as usize * c + c];
    let bits = |x: f32| if x == 0.0 { 0 } else { x.to_bits() };
    let same_row =
        |a: usize, b: usize| row(a).iter().zip(row(b)).all(|(&x, &y)| bits(x) == bits(y));
    let mut order: Vec<u32> = (0..face_indices.len() as u32).collect();
    order.sort_unstable_by(|&a, &b| {
        let (a, b) = (a as usize, b as usize);
        face_indices[a]
            .cmp(&face_indices[b])
            .then_with(|| {
                row(a)
                    .iter()
                    .zip(row(b))
                    .map(|(&x, &y)| bits(x).cmp(&bits(y)))
                    .find(|o| o.is_ne())
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .then(a.cmp(&b))
    });
    let mut out = vec![0u32; face_indices.len()];
    let mut first = usize::MAX;
    for &k in &order {
        let k = k as usize;
        let new_run =
            first == usize::MAX || face_indices[first] != face_indices[k] || !same_row(first, k);
        if new_run {
            first = k;
        }
        out[k] = rows[first];
    }
    out
}

/// The topology phase for one face-varying channel: one stencil table per level over the
/// channel's values and the last level's value of every corner. Build once per cage topology
/// and UV layout; [`FaceVaryingRefiner::apply`] then refines any data laid out that way.
#[derive(Clone, Debug)]
pub struct FaceVaryingRefiner {
    /// Values of level `i + 1` from those of level `i`.
    pub tables: Vec<StencilTable>,
    /// Value of each corner of the last level (corners in the order of `faces.indices`).
    pub indices: Vec<u32>,
    /// Faces of the last level (the vertex refiner's, face for face).
    pub faces: Faces,
    /// Values of the cage's channel.
    pub source_count: usize,
}

impl FaceVaryingRefiner {
    /// Refines the channel whose corner values are `indices` (over `value_count` values) on the
    /// cage `faces` with `creases`, as `options` says (scheme, levels, boundary,
    /// `uv_interpolation`). `None` when the scheme carries no face-varying data.
    ///
    /// # Errors
    /// Indices that do not fit the cage, and the cage errors of [`Topology::build`].
    pub fn new(
        faces: &Faces,
        creases: &[([u32; 2], f32)],
        indices: &[u32],
        value_count: usize,
        options: &SubdivOptions,
    ) -> Result<Option<FaceVaryingRefiner>, SubdivError> {
        if !carries_face_varying(options.scheme) {
            return Ok(None);
        }
        if indices.len() != faces.indices.len() {
            return Err(SubdivError::InvalidOption(format!(
                "{} face-varying indices given for {} face corners",
                indices.len(),
                faces.indices.len()
            )));
        }
        if let Some((c, &i)) = indices
            .iter()
            .enumerate()
            .find(|&(_, &i)| i as usize >= value_count)
        {
            return Err(SubdivError::InvalidOption(format!(
                "face corner {c} uses face-varying value {i}; there are {value_count}"
            )));
        }
        let rules = Rules::new(options.uv_interpolation, options.boundary);
        let linear = rules.linear_all || options.scheme == Scheme::Bilinear;
        let mut faces = faces.clone();
        let mut creases = creases.to_vec();
        let mut corner = indices.to_vec();
        let mut count = value_count as u32;
        let mut tables = Vec::with_capacity(options.levels as usize);
        for _ in 0..options.levels {
            let topo = Topology::build(&faces, &creases)?;
            let level = ChannelLevel {
                faces: &faces,
                topo: &topo,
                corner: &corner,
            };
            let (table, next_corner) = refine_level(&level, count, linear, &rules);
            let (next_faces, _) = catmull_clark::split_faces(&faces, &topo);
            creases = catmull_clark::split_creases(&topo, faces.len());
            count = table.len() as u32;
            tables.push(table);
            corner = next_corner;
            faces = next_faces;
        }
        Ok(Some(FaceVaryingRefiner {
            tables,
            indices: corner,
            faces,
            source_count: value_count,
        }))
    }

    /// The last level's values from the cage channel's `values`.
    ///
    /// # Errors
    /// When `values` does not hold the channel's value count.
    pub fn apply<const N: usize>(&self, values: &[[f32; N]]) -> Result<Vec<[f32; N]>, SubdivError> {
        if N == 0 {
            self.check_count(values.len())?;
            return Ok(vec![
                [0.0; N];
                self.tables.last().map_or(values.len(), |t| t.len())
            ]);
        }
        let flat = self.apply_rows(values.as_flattened(), N)?;
        Ok(flat
            .chunks_exact(N)
            .map(|c| std::array::from_fn(|k| c[k]))
            .collect())
    }

    /// [`FaceVaryingRefiner::apply`] for rows of `components` floats (≥ 1) stored one after
    /// the other: generic attributes of any width.
    ///
    /// # Errors
    /// When `values` does not hold the channel's value count.
    pub fn apply_rows(&self, values: &[f32], components: usize) -> Result<Vec<f32>, SubdivError> {
        let c = components.max(1);
        if values.len() / c * c != values.len() {
            return Err(SubdivError::InvalidOption(format!(
                "{} face-varying floats are not rows of {c}",
                values.len()
            )));
        }
        self.check_count(values.len() / c)?;
        Ok(StencilTable::apply_chain(&self.tables, values, c))
    }

    fn check_count(&self, rows: usize) -> Result<(), SubdivError> {
        if rows != self.source_count {
            return Err(SubdivError::InvalidOption(format!(
                "{rows} face-varying values given; the channel has {}",
                self.source_count
            )));
        }
        Ok(())
    }
}

/// The cage's UVs refined with `refiner` (built from `cage` with `options`), their indices
/// following the refined mesh's corners; `None` when the cage has no UVs or the scheme carries
/// none ([`carries_face_varying`]). Interpolation: `options.uv_interpolation`.
///
/// # Errors
/// UVs that do not fit the cage; a `refiner` not built from this cage and scheme.
pub fn refine_uvs(
    cage: &Mesh,
    refiner: &Refiner,
    options: &SubdivOptions,
) -> Result<Option<FaceVarying<[f32; 2]>>, SubdivError> {
    let Some(uvs) = &cage.uvs else {
        return Ok(None);
    };
    if !carries_face_varying(options.scheme) {
        return Ok(None);
    }
    if uvs.indices.len() != cage.face_indices.len() {
        return Err(SubdivError::InvalidOption(format!(
            "{} uv indices given for {} face corners",
            uvs.indices.len(),
            cage.face_indices.len()
        )));
    }
    if let Some((c, &i)) = uvs
        .indices
        .iter()
        .enumerate()
        .find(|&(_, &i)| i as usize >= uvs.values.len())
    {
        return Err(SubdivError::InvalidOption(format!(
            "face corner {c} uses uv {i}; there are {}",
            uvs.values.len()
        )));
    }
    let welded = weld_by_value(&cage.face_indices, uvs);
    let Some(channel) = cage_channel(cage, refiner, &welded, uvs.values.len(), options)? else {
        return Ok(None);
    };
    Ok(Some(FaceVarying {
        values: channel.apply(&uvs.values)?,
        indices: channel.indices,
    }))
}

/// The channel of `cage` whose corners use values `indices` (of `value_count`), refined as
/// `refiner` was (`None` when the scheme carries no face-varying data).
///
/// # Errors
/// Indices that do not fit the cage; a `refiner` not built from this cage and scheme.
pub fn cage_channel(
    cage: &Mesh,
    refiner: &Refiner,
    indices: &[u32],
    value_count: usize,
    options: &SubdivOptions,
) -> Result<Option<FaceVaryingRefiner>, SubdivError> {
    let faces = Faces {
        offsets: cage.face_offsets.clone(),
        indices: cage.face_indices.clone(),
        vertex_count: cage.positions.len() as u32,
    };
    let creases: Vec<([u32; 2], f32)> =
        cage.creases.iter().map(|c| ([c.a, c.b], c.value)).collect();
    let Some(channel) = FaceVaryingRefiner::new(&faces, &creases, indices, value_count, options)?
    else {
        return Ok(None);
    };
    // Corners correspond one to one (both split faces in parent-corner order); vertex
    // numbers may differ, face-varying indices do not need them.
    if channel.faces.offsets != refiner.faces.offsets {
        return Err(SubdivError::InvalidOption(
            "the refiner's faces are not this cage's refined faces (another cage, scheme or level count)"
                .to_string(),
        ));
    }
    Ok(Some(channel))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::Boundary;
    use crate::face_varying_rules::UvInterpolation;
    use crate::subdivide;
    use crate::test_meshes::cube;
    use tessd_mesh::Crease;

    /// An nx × ny grid of quads, warped in z, with per-vertex UVs `uv(position)` (no seams).
    fn grid(nx: u32, ny: u32, uv: impl Fn([f32; 3]) -> [f32; 2]) -> Mesh {
        let mut m = Mesh::default();
        for y in 0..=ny {
            for x in 0..=nx {
                let (fx, fy) = (x as f32, y as f32);
                m.positions
                    .push([fx * 1.1, fy * 0.9 + 0.05 * fx, 0.3 * (fx * 0.7 + fy).sin()]);
            }
        }
        for y in 0..ny {
            for x in 0..nx {
                let v = y * (nx + 1) + x;
                m.push_face(&[v, v + 1, v + nx + 2, v + nx + 1]);
            }
        }
        m.uvs = Some(FaceVarying {
            values: m.positions.iter().map(|&p| uv(p)).collect(),
            indices: m.face_indices.clone(),
        });
        m
    }

    fn options(
        levels: u32,
        uv: UvInterpolation,
        boundary: Boundary,
        scheme: Scheme,
    ) -> SubdivOptions {
        SubdivOptions {
            scheme,
            levels,
            boundary,
            uv_interpolation: uv,
            ..SubdivOptions::default()
        }
    }

    fn corner_uv(m: &Mesh, c: usize) -> [f32; 2] {
        let uv = m.uvs.as_ref().expect("refined UVs");
        uv.values[uv.indices[c] as usize]
    }

    #[test]
    fn linear_uvs_of_a_planar_grid_equal_the_bilinear_positions() {
        let cage = grid(4, 3, |p| [p[0], p[1]]);
        for levels in 1..=3 {
            let uv_opts = options(
                levels,
                UvInterpolation::Linear,
                Boundary::EdgeOnly,
                Scheme::CatmullClark,
            );
            let m = subdivide(&cage, &uv_opts).unwrap();
            let flat = subdivide(
                &cage,
                &options(
                    levels,
                    UvInterpolation::Linear,
                    Boundary::EdgeOnly,
                    Scheme::Bilinear,
                ),
            )
            .unwrap();
            assert_eq!(m.face_offsets, flat.face_offsets);
            for (c, &v) in flat.face_indices.iter().enumerate() {
                let p = flat.positions[v as usize];
                let uv = corner_uv(&m, c);
                assert!(
                    (uv[0] - p[0]).abs() < 1e-5 && (uv[1] - p[1]).abs() < 1e-5,
                    "level {levels} corner {c}: uv {uv:?}, position {p:?}"
                );
                // The bilinear scheme carries the same UVs.
                assert_eq!(corner_uv(&flat, c), uv);
            }
        }
    }

    /// Where the UV topology is the vertex topology, UVs that are an affine function of the
    /// positions stay that function of the refined positions: the vertex rules (creases,
    /// semi-sharp blends, boundaries) are reused exactly.
    #[test]
    fn matching_topology_follows_the_vertex_rules() {
        let f = |p: [f32; 3]| [p[0] + 0.3 * p[2] - 0.1, p[1] - 0.2 * p[2]];
        let creased = |mut m: Mesh| {
            m.creases = vec![
                Crease {
                    a: 6,
                    b: 7,
                    value: 10.0,
                },
                Crease {
                    a: 7,
                    b: 8,
                    value: 10.0,
                },
                Crease {
                    a: 11,
                    b: 12,
                    value: 1.5,
                },
                Crease {
                    a: 12,
                    b: 13,
                    value: 2.0,
                },
                Crease {
                    a: 13,
                    b: 18,
                    value: 0.5,
                },
            ];
            m
        };
        let cases = [
            (
                creased(grid(4, 4, f)),
                UvInterpolation::Smooth,
                Boundary::EdgeOnly,
            ),
            (
                creased(grid(4, 4, f)),
                UvInterpolation::Corners,
                Boundary::EdgeAndCorner,
            ),
            (
                {
                    let mut m = cube();
                    m.uvs = Some(FaceVarying {
                        values: m.positions.iter().map(|&p| f(p)).collect(),
                        indices: m.face_indices.clone(),
                    });
                    m.creases = vec![
                        Crease {
                            a: 0,
                            b: 1,
                            value: 1.5,
                        },
                        Crease {
                            a: 1,
                            b: 3,
                            value: 10.0,
                        },
                    ];
                    m
                },
                UvInterpolation::Corners,
                Boundary::EdgeOnly,
            ),
        ];
        for (cage, uv, boundary) in cases {
            for levels in 1..=3 {
                let m =
                    subdivide(&cage, &options(levels, uv, boundary, Scheme::CatmullClark)).unwrap();
                for (c, &v) in m.face_indices.iter().enumerate() {
                    let want = f(m.positions[v as usize]);
                    let got = corner_uv(&m, c);
                    assert!(
                        (got[0] - want[0]).abs() < 1e-5 && (got[1] - want[1]).abs() < 1e-5,
                        "{uv:?} {boundary:?} level {levels} corner {c}: {got:?} vs {want:?}"
                    );
                }
            }
        }
    }

    /// Every face of a cube its own UV island: no refined value is shared across islands, and
    /// each island's values stay in its own square (all masks are convex in its values).
    #[test]
    fn seams_stay_seams() {
        let mut cage = cube();
        let mut values = Vec::new();
        for f in 0..6 {
            let o = [2.0 * f as f32, 0.5 * f as f32];
            values.extend_from_slice(&[
                [o[0], o[1]],
                [o[0] + 1.0, o[1]],
                [o[0] + 1.0, o[1] + 1.0],
                [o[0], o[1] + 1.0],
            ]);
        }
        cage.uvs = Some(FaceVarying {
            values,
            indices: (0..24).collect(),
        });
        for uv in UvInterpolation::ALL {
            for levels in 1..=3 {
                let opts = options(levels, uv, Boundary::EdgeOnly, Scheme::CatmullClark);
                let refiner = Refiner::new(&cage, &opts).unwrap();
                let m = subdivide(&cage, &opts).unwrap();
                let fv = m.uvs.as_ref().unwrap();
                let mut island = vec![u32::MAX; fv.values.len()];
                for f in 0..m.face_count() {
                    let cage_face = refiner.face_origin[f];
                    for c in m.face_offsets[f] as usize..m.face_offsets[f + 1] as usize {
                        let x = fv.indices[c] as usize;
                        assert!(
                            island[x] == u32::MAX || island[x] == cage_face,
                            "{uv:?} level {levels}: value {x} on islands {} and {cage_face}",
                            island[x]
                        );
                        island[x] = cage_face;
                        let p = fv.values[x];
                        let o = [2.0 * cage_face as f32, 0.5 * cage_face as f32];
                        assert!(
                            (o[0] - 1e-6..=o[0] + 1.0 + 1e-6).contains(&p[0])
                                && (o[1] - 1e-6..=o[1] + 1.0 + 1e-6).contains(&p[1]),
                            "{uv:?} level {levels}: {p:?} outside island {cage_face}"
                        );
                    }
                }
                // Each island's four cage corners are kept by every mode but `Smooth`.
                if uv != UvInterpolation::Smooth {
                    for corner in &cage.uvs.as_ref().unwrap().values {
                        assert!(
                            fv.values.contains(corner),
                            "{uv:?}: corner {corner:?} moved"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn per_corner_uvs_weld_like_indexed_ones() {
        let indexed = grid(3, 2, |p| [p[0], p[1]]);
        let mut per_corner = indexed.clone();
        let uv = indexed.uvs.as_ref().unwrap();
        per_corner.uvs = Some(FaceVarying {
            values: uv.indices.iter().map(|&i| uv.values[i as usize]).collect(),
            indices: (0..uv.indices.len() as u32).collect(),
        });
        let opts = options(
            2,
            UvInterpolation::Corners,
            Boundary::EdgeOnly,
            Scheme::CatmullClark,
        );
        let (a, b) = (
            subdivide(&indexed, &opts).unwrap(),
            subdivide(&per_corner, &opts).unwrap(),
        );
        for c in 0..a.face_indices.len() {
            let (p, q) = (corner_uv(&a, c), corner_uv(&b, c));
            assert!((p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6);
        }
        assert_eq!(
            a.uvs.as_ref().unwrap().values.len(),
            b.uvs.as_ref().unwrap().values.len()
        );
    }

    /// Random UV layouts (random seams, darts, junctions, bowties in UV space) on a cage with
    /// a non-manifold vertex: no panic, and every refined value is a convex combination of
    /// the cage's (within their bounds).
    #[test]
    fn random_layouts_stay_convex() {
        let mut seed = 12345u64;
        let mut rand = |n: u32| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) % u64::from(n)) as u32
        };
        let mut cage = grid(4, 3, |p| [p[0], p[1]]);
        // A quad touching the grid at one corner only (a bowtie vertex) and a triangle.
        let base = cage.positions.len() as u32;
        cage.positions
            .extend_from_slice(&[[5.0, 3.0, 0.0], [5.0, 4.0, 0.0], [4.4, 4.0, 0.0]]);
        cage.push_face(&[19, base, base + 1, base + 2]);
        cage.push_face(&[0, 5, 1]);
        let corners = cage.face_indices.len();
        for trial in 0..20 {
            let values: Vec<[f32; 2]> = (0..12)
                .map(|_| [rand(1000) as f32 / 1000.0, rand(1000) as f32 / 1000.0])
                .collect();
            // Few values, so that neighbouring corners often share one.
            let indices: Vec<u32> = (0..corners).map(|_| rand(12)).collect();
            cage.uvs = Some(FaceVarying {
                values: values.clone(),
                indices,
            });
            let lo = values
                .iter()
                .fold([f32::MAX; 2], |a, v| [a[0].min(v[0]), a[1].min(v[1])]);
            let hi = values
                .iter()
                .fold([f32::MIN; 2], |a, v| [a[0].max(v[0]), a[1].max(v[1])]);
            for uv in UvInterpolation::ALL {
                for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
                    let opts = options(2, uv, boundary, Scheme::CatmullClark);
                    let m = subdivide(&cage, &opts).unwrap();
                    let fv = m.uvs.unwrap();
                    assert_eq!(fv.indices.len(), m.face_indices.len());
                    for p in &fv.values {
                        assert!(
                            (0..2).all(|k| p[k] >= lo[k] - 1e-5 && p[k] <= hi[k] + 1e-5),
                            "trial {trial} {uv:?}: {p:?} outside {lo:?}..{hi:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn schemes_without_corner_order_drop_uvs() {
        let quads = grid(2, 2, |p| [p[0], p[1]]);
        let mut triangles = quads.clone();
        triangles.face_offsets = vec![0];
        triangles.face_indices.clear();
        for q in quads.faces() {
            triangles.push_face(&[q[0], q[1], q[2]]);
            triangles.push_face(&[q[0], q[2], q[3]]);
        }
        let uv = quads.uvs.as_ref().unwrap();
        triangles.uvs = Some(FaceVarying {
            values: uv.values.clone(),
            indices: triangles.face_indices.clone(),
        });
        let cases = [
            (&quads, Scheme::DooSabin),
            (&triangles, Scheme::Loop),
            (&triangles, Scheme::Butterfly),
            (&triangles, Scheme::Sqrt3),
        ];
        for (cage, scheme) in cases {
            assert!(!carries_face_varying(scheme));
            let opts = options(1, UvInterpolation::Corners, Boundary::EdgeOnly, scheme);
            if let Ok(refiner) = Refiner::new(cage, &opts) {
                assert_eq!(refine_uvs(cage, &refiner, &opts).unwrap(), None);
            }
        }
    }
}
