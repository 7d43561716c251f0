//! A verified upper bound on the symmetric Hausdorff distance between the input and the
//! output surfaces (reported as `surface_error`).
//!
//! From `coverage.rs`: output → input is at most the largest vertex displacement `D`, and so
//! is input → output for every input face whose image lies on the output. For an input face
//! `T` whose image `E` (a segment or a point) does not, a point `p` of `T` maps to a point `p'`
//! of `E` with `|p − p'| ≤ D_T` (the largest displacement of `T`'s corners), so
//! `d(p, output) ≤ D_T + max over E of d(·, output)`. The distance to a surface is 1-Lipschitz,
//! so on a segment sampled every `h`, between samples at distances `f₀` and `f₁` it is at most
//! `(f₀ + f₁ + h) / 2`: an upper bound from exact closest-point queries, not an estimate.

use crate::coverage::{Gaps, Piece, collapsed_image};
use tessd_compare::SurfaceIndex;
use tessd_mesh::Mesh;

/// Most samples on one image segment; past it the spacing grows (the bound stays valid, only
/// looser by half a spacing).
const MAX_SEGMENT_SAMPLES: usize = 256;

/// The bound: `max(max_displacement, D_T + d(E_T, output))` over the faces `T` of `gaps`
/// (input faces of `mesh` whose image `E_T` under `cluster_of` and `reps` is not on `output`).
/// `None` when the output has no surface at all (every face collapsed).
pub(crate) fn surface_bound(
    mesh: &Mesh,
    cluster_of: &[u32],
    reps: &[[f32; 3]],
    output: &Mesh,
    gaps: &Gaps,
    max_displacement: f64,
) -> Option<f64> {
    if gaps.is_empty() {
        return Some(max_displacement);
    }
    let index = SurfaceIndex::new(output).ok()?;
    let rep = |c: u32| reps[c as usize].map(f64::from);
    // Samples of every gap face's image, in runs: (face displacement, first sample, samples,
    // spacing) — a point is a run of one sample with spacing 0.
    let mut samples: Vec<[f64; 3]> = Vec::new();
    let mut runs: Vec<(f64, usize, usize, f64)> = Vec::new();
    let spacing = max_displacement.max(f64::MIN_POSITIVE) / 16.0;
    for &f in &gaps.faces {
        let face = mesh.face(f as usize);
        let moved = face
            .iter()
            .map(|&v| dist(mesh.positions[v as usize], rep(cluster_of[v as usize])))
            .fold(0.0, f64::max);
        let mut pieces = Vec::new();
        collapsed_image(face, cluster_of, |piece| {
            pieces.push(match piece {
                Piece::Segment(a, b) => Piece::Segment(a.min(b), a.max(b)),
                point => point,
            })
        });
        // (A segment repeated further apart is only measured twice.)
        pieces.dedup();
        for piece in pieces {
            match piece {
                Piece::Point(c) => {
                    runs.push((moved, samples.len(), 1, 0.0));
                    samples.push(rep(c));
                }
                Piece::Segment(a, b) => {
                    let (pa, pb) = (rep(a), rep(b));
                    let len = dist3(pa, pb);
                    let n = ((len / spacing).ceil() as usize).clamp(1, MAX_SEGMENT_SAMPLES);
                    runs.push((moved, samples.len(), n + 1, len / n as f64));
                    samples.extend((0..=n).map(|i| {
                        let t = i as f64 / n as f64;
                        [0, 1, 2].map(|k| pa[k] + t * (pb[k] - pa[k]))
                    }));
                }
            }
        }
    }
    let d = index.distances(&samples);
    let gap_bound = runs
        .iter()
        .map(|&(moved, first, n, h)| {
            let run = &d[first..first + n];
            let along = if n == 1 {
                run[0]
            } else {
                run.windows(2)
                    .map(|w| 0.5 * (w[0] + w[1] + h))
                    .fold(0.0, f64::max)
            };
            moved + along
        })
        .fold(0.0, f64::max);
    Some(gap_bound.max(max_displacement))
}

fn dist(a: [f32; 3], b: [f64; 3]) -> f64 {
    dist3(a.map(f64::from), b)
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::find_gaps;
    use crate::elimination::eliminate;

    #[test]
    fn a_lost_spike_is_bounded_by_its_distance_to_the_output() {
        // A unit square (two triangles) and a spike rising 2 above corner 1, whose tip vertex
        // 5 shares a cluster with 4: the spike folds onto the segment 1–4/5, off the output.
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 2.0],
                [1.0, 0.0, 2.0],
            ],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[0, 2, 3]);
        m.push_face(&[1, 4, 5]);
        let cluster_of = [0, 1, 2, 3, 4, 4];
        let reps: Vec<[f32; 3]> = m.positions[..5].to_vec();
        let kept = eliminate(&m, &cluster_of, &reps, false);
        let gaps = find_gaps(&m, &cluster_of, &kept, 5);
        assert_eq!(gaps.faces, vec![2]);
        let mut out = Mesh {
            positions: reps.clone(),
            ..Mesh::default()
        };
        out.push_face(&[0, 1, 2]);
        out.push_face(&[0, 2, 3]);
        let bound = surface_bound(&m, &cluster_of, &reps, &out, &gaps, 0.0).unwrap();
        // The tip is 2 above the square; the bound may exceed it by half a sample spacing.
        assert!(
            (2.0..=2.0 + 2.0 / MAX_SEGMENT_SAMPLES as f64).contains(&bound),
            "{bound}"
        );
    }
}
