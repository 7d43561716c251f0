//! The context of a kd split (paper 003 §3, §5.3): the half the vertex's neighbours' centroid
//! predicts, the margin of that prediction, and whether the cell holds a collapsed triangle.
//! Encoder and decoder both run [`split_coding`] on the same complex, so they cannot drift.

use crate::coding::{Coding, margin_context};
use crate::complex::{Complex, POINT};
use crate::kd_cell::half;
use crate::symbols::{Family, context};

/// The coding of the split decision of vertex `v` (before its split at `level`): predicted half
/// from its neighbours' centroid, sub-context from that prediction's margin and from whether the
/// cell holds a collapsed triangle (then it likely holds several points).
pub(crate) fn split_coding(cx: &mut Complex, v: u32, level: usize, bits: u32) -> Coding {
    let a = level % 3;
    let corner = cx.vertices[v as usize].corner;
    let h = half(level, bits) as f64;
    let mut collapsed = false;
    // the distinct neighbours, on the stack while they are few (the usual case)
    let mut few = [0u32; 48];
    let mut count = 0usize;
    let mut many: Vec<u32> = Vec::new();
    cx.prune(v);
    for &slot in cx.listed(v) {
        let s = cx.simplices[slot as usize].expect("live");
        if s.kind != POINT && s.multiplicity(v) >= 2 {
            collapsed = true;
        }
        for &x in &s.v {
            if x == v || few[..count].contains(&x) {
                continue;
            }
            if count < few.len() {
                few[count] = x;
                count += 1;
            } else {
                many.push(x);
            }
        }
    }
    if !many.is_empty() {
        many.extend_from_slice(&few);
        many.sort_unstable();
        many.dedup();
    }
    let others: &[u32] = if many.is_empty() {
        &few[..count]
    } else {
        &many
    };
    let (margin, high) = if others.is_empty() {
        (0, false)
    } else {
        let sum: f64 = others
            .iter()
            .map(|&x| {
                let w = &cx.vertices[x as usize];
                w.corner[a] as f64 + (w.extent(a, bits) - 1) as f64 / 2.0
            })
            .sum();
        let mean = sum / others.len() as f64;
        let d = ((mean - (corner[a] as f64 + h - 0.5)) / h).abs();
        (margin_context(d), mean > corner[a] as f64 + h - 0.5)
    };
    let family = Family::Split;
    Coding {
        ctx: context(family, usize::from(collapsed) * 7 + margin, level),
        family,
        flip: high,
    }
}
