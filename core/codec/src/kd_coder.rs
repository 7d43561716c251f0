//! The Gandoin–Devillers coder of one nSP-cell (paper 003 §3 and §5.2b).
//!
//! Geometry: the kd-tree splits every cell in two along x, y, z in turn; each split is coded as
//! "low half non-empty", "high half non-empty" or "both" ([`Family::Split`](crate::symbols::Family::Split)). Connectivity: when a
//! cell splits into two non-empty halves, its vertex `v` becomes `v1` (low) and `v2` (high), and
//! every simplex holding `v` is replaced by a non-empty subset of its candidate preimages
//! ([`crate::complex::candidates`]). That subset is the connectivity code, interleaved with the
//! geometry codes. This generalises GD02's edge-collapse and vertex-unification codes to any
//! triangle soup: a triangle whose corners fell into one cell survives as a degenerate triangle
//! (the edge or point it became), so orientation and non-manifold configurations come back exactly.
//!
//! The encoder runs bottom-up (merging the two halves of every cell, level by level, last cell
//! first) and the decoder top-down (splitting, first cell first), so that before each split the
//! decoder holds exactly the complex the encoder held after the matching merge.
//!
//! Predictions (the contexts of [`crate::symbols`]) are all computed from what the decoder
//! already has, by one function both sides run: `split_context` for a split (the
//! star's centroid, parallelograms, tangent plane, density) and `connectivity` for the
//! preimage masks (links, pivots, the midpoint's side and distance, unmatched fine edges); their
//! module docs say what each context is.
//!
//! This module is the loops and the data movement: merges and splits on [`Complex`] (both in
//! place: a merged or split simplex keeps its slot, so only the records of the split vertex and
//! its children change, see `Complex::weld` and `Complex::split`), buffers reused across a
//! cell's splits (`Scratch`), and the decoder's complex renumbered in kd order once per bit of
//! precision so that star walks stay local.

use crate::ahead::Geometry;
use crate::complex::{Complex, MaskList, Simplex, Weld};
use crate::connectivity::{Known, Read, code_connectivity};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::kd_cell::half;
use crate::split_context::split_coding;
use crate::symbols::Symbol;

/// Encodes one nSP-cell: merges the kd-cells of `cx` from kd level `hi` down to `lo` (§5.2b),
/// with the geometry `advance` kd levels ahead of the connectivity (§6.4; 0 interleaves each
/// split with its connectivity codes).
///
/// `alive` lists the vertices at level `hi` in kd order; on return it lists those at level `lo`.
/// The symbols come back in the decoder's order.
pub fn encode(
    cx: &mut Complex,
    alive: &mut Vec<u32>,
    bits: u32,
    lo: usize,
    hi: usize,
    advance: usize,
) -> Vec<Symbol> {
    let geometry = (advance > 0).then(|| {
        let top = alive
            .iter()
            .map(|&v| cx.vertices[v as usize].corner)
            .collect();
        Geometry::of_cells(top, lo, hi, bits)
    });
    // events are recorded in merge order and emitted reversed: (start, len) into `buffer`;
    // with geometry ahead, the connectivity events of level l end at `level_ends[l - lo]`
    let mut buffer: Vec<Symbol> = Vec::new();
    let mut events: Vec<(u32, u32)> = Vec::new();
    let mut level_ends = vec![0usize; hi - lo];
    // with geometry ahead: the split codes of every level, in kd order
    let mut ahead: Vec<Vec<Symbol>> = vec![Vec::new(); hi - lo];
    let mut conn: Vec<Symbol> = Vec::new();
    let mut scratch = Scratch::default();
    for level in (lo..hi).rev() {
        let a = level % 3;
        let h = half(level, bits);
        // group the children of each parent; both are adjacent in kd order
        let mut groups: Vec<(u32, Option<u32>)> = Vec::with_capacity(alive.len());
        let mut i = 0;
        let parent = |cx: &Complex, id: u32| {
            let mut c = cx.vertices[id as usize].corner;
            c[a] &= !h;
            c
        };
        while i < alive.len() {
            let x = alive[i];
            if i + 1 < alive.len() && parent(cx, alive[i + 1]) == parent(cx, x) {
                groups.push((x, Some(alive[i + 1])));
                i += 2;
            } else {
                groups.push((x, None));
                i += 1;
            }
        }
        // (each merge makes one vertex of two)
        cx.star_cache
            .set_kept(keep_stars(alive.len() - groups.len(), groups.len()));
        for &(x, y) in groups.iter().rev() {
            let start = buffer.len() as u32;
            conn.clear();
            let split = match y {
                None => {
                    let vx = &mut cx.vertices[x as usize];
                    let high = vx.corner[a] & h != 0;
                    vx.corner[a] &= !h;
                    vx.level = level as u8;
                    u8::from(high)
                }
                Some(v2) => {
                    merge(cx, x, v2, level, bits, &mut conn, &mut scratch);
                    2
                }
            };
            if geometry.is_none() {
                let coding = split_coding(cx, x, level, bits);
                buffer.push(Symbol::new(coding.ctx, coding.split_value(split)));
            }
            buffer.extend_from_slice(&conn);
            events.push((start, buffer.len() as u32 - start));
        }
        *alive = groups.iter().map(|&(x, _)| x).collect();
        level_ends[level - lo] = events.len();
        // the complex now stands where the decoder reads the splits of level `level + A − 1`
        // (of levels lo..lo+A at the start)
        if let Some(g) = &geometry {
            let first = if level == lo { lo } else { level + advance - 1 };
            for depth in first..(level + advance).min(hi) {
                let splits = g.splits(depth);
                ahead[depth - lo] = g
                    .codings(cx, alive, depth, bits)
                    .into_iter()
                    .zip(splits)
                    .map(|(c, &s)| Symbol::new(c.ctx, c.split_value(s)))
                    .collect();
            }
        }
    }
    let mut out = Vec::with_capacity(buffer.len() + ahead.iter().map(Vec::len).sum::<usize>());
    let emit = |out: &mut Vec<Symbol>, events: &[(u32, u32)]| {
        for &(start, len) in events.iter().rev() {
            out.extend_from_slice(&buffer[start as usize..(start + len) as usize]);
        }
    };
    if advance == 0 {
        emit(&mut out, &events);
        return out;
    }
    for symbols in &ahead[..advance.min(hi - lo)] {
        out.extend_from_slice(symbols);
    }
    for level in lo..hi {
        // level l's events lie between level l+1's end and its own (merge order)
        let from = if level + 1 < hi {
            level_ends[level + 1 - lo]
        } else {
            0
        };
        emit(&mut out, &events[from..level_ends[level - lo]]);
        if level + advance < hi {
            out.extend_from_slice(&ahead[level + advance - lo]);
        }
    }
    out
}

/// Whether the split contexts should keep their cached stars at a kd level where `changes` of
/// `vertices` merge or split: a change drops the records of its vertex's neighbours, so where
/// they are many the records are dropped before they are read again.
fn keep_stars(changes: usize, vertices: usize) -> bool {
    changes * STAR_CHANGES < vertices
}

/// One change in this many vertices or more at a level turns the cached stars off there.
const STAR_CHANGES: usize = 8;

/// Buffers one cell's merges or splits reuse, so that a split allocates nothing of its own.
#[derive(Default)]
struct Scratch {
    slots: Vec<u32>,
    coarse: Vec<Simplex>,
    masks: MaskList,
    /// The encoder's merge's buffers.
    weld: Weld,
    /// The coarse simplices with their preimage masks, as the connectivity coder returns them.
    decoded: Vec<(Simplex, u8)>,
}

/// Merges `v2` (high child) into `v1` (low child) and appends the connectivity codes of the
/// inverse split, in the decoder's order.
fn merge(
    cx: &mut Complex,
    v1: u32,
    v2: u32,
    level: usize,
    bits: u32,
    out: &mut Vec<Symbol>,
    scratch: &mut Scratch,
) {
    let mut masks = std::mem::take(&mut scratch.masks);
    cx.weld(v1, v2, &mut masks, &mut scratch.weld);
    cx.vertices[v1 as usize].level = level as u8;
    cx.vertices[v2 as usize].level = u8::MAX;
    cx.forget(v2);
    let coarse = &mut scratch.coarse;
    coarse.clear();
    coarse.extend(masks.0.iter().map(|e| e.0));
    let mut known = Known { masks, out };
    code_connectivity(
        cx,
        coarse,
        (v1, v2),
        level,
        bits,
        &mut known,
        &mut scratch.decoded,
    )
    .expect("the encoder knows every mask");
    scratch.masks = known.masks;
}

/// Limits a decoder holds a cell to, so that a corrupt file cannot make it grow without bound.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Most vertices the cell's complex may hold.
    pub vertices: usize,
    /// Most live simplices.
    pub simplices: usize,
}

/// What part of a cell's code one [`decode`] call reads.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    /// Bits per coordinate of the file, `p`.
    pub bits: u32,
    /// kd level the complex is at.
    pub lo: usize,
    /// kd level to stop at.
    pub hi: usize,
    /// The cell's last kd level (its code ends there).
    pub end: usize,
    /// kd levels of geometry ahead of the connectivity (3 × `--ahead`).
    pub advance: usize,
}

/// Decodes one nSP-cell: splits the kd-cells of `cx` from kd level `span.lo` up to `span.hi`
/// (§6.2). With geometry ahead (§6.4), `geometry` carries what was read ahead from one call to
/// the next (`None` at the cell's start).
///
/// `alive` lists the vertices at level `lo` in kd order; on return, those at level `hi`.
pub fn decode(
    cx: &mut Complex,
    alive: &mut Vec<u32>,
    span: Span,
    reader: &mut SymbolReader,
    limits: Limits,
    geometry: &mut Option<Geometry>,
) -> Result<(), CodecError> {
    let Span {
        bits,
        lo,
        hi,
        end,
        advance,
    } = span;
    if advance > 0 && geometry.is_none() {
        let mut g = Geometry::start(cx, alive, lo, bits);
        for depth in lo..(lo + advance).min(end) {
            g.read(cx, alive, depth, bits, |ctx| reader.next(ctx))?;
        }
        *geometry = Some(g);
    }
    let mut scratch = Scratch::default();
    for level in lo..hi {
        let a = level % 3;
        let h = half(level, bits);
        let mut next = Vec::with_capacity(alive.len() * 2);
        for (i, &v) in alive.iter().enumerate() {
            let split = match geometry {
                Some(g) => *g.splits(level).get(i).ok_or_else(|| {
                    CodecError::corrupt(reader.offset, "the geometry ahead lost a kd-cell")
                })?,
                None => {
                    let coding = split_coding(cx, v, level, bits);
                    coding.split(reader.next(coding.ctx)?)
                }
            };
            let vx = cx.vertices[v as usize];
            let mut high = vx;
            high.corner[a] += h;
            high.level = level as u8 + 1;
            match split {
                0 => {
                    cx.vertices[v as usize].level = level as u8 + 1;
                    next.push(v);
                }
                1 => {
                    cx.vertices[v as usize] = high;
                    next.push(v);
                }
                _ => {
                    if cx.vertices.len() >= limits.vertices {
                        return Err(CodecError::corrupt(
                            reader.offset,
                            format!(
                                "the cell grows past its recorded {} vertices at kd level {level}",
                                limits.vertices
                            ),
                        ));
                    }
                    let v2 = cx.add_vertex(high);
                    split_vertex(cx, v, v2, level, bits, reader, &mut scratch)?;
                    next.push(v);
                    next.push(v2);
                    if cx.live > limits.simplices {
                        return Err(CodecError::corrupt(
                            reader.offset,
                            format!(
                                "the cell grows past its recorded {} simplices at kd level {level}",
                                limits.simplices
                            ),
                        ));
                    }
                }
            }
        }
        // the next level's split fraction is most like this one's
        cx.star_cache
            .set_kept(keep_stars(next.len() - alive.len(), alive.len()));
        *alive = next;
        // new vertices and simplices were appended far from their neighbours: renumber in kd
        // order once per bit of precision, so the next levels' star walks stay local
        if level % 3 == 2 {
            cx.reorder(alive);
        }
        if let Some(g) = geometry {
            g.drop_above(level + 1);
            if level + advance < end {
                g.read(cx, alive, level + advance, bits, |ctx| reader.next(ctx))?;
            }
        }
    }
    Ok(())
}

/// Splits `v` into itself (low half) and `v2` (high half), reading one connectivity code per
/// simplex holding `v`.
fn split_vertex(
    cx: &mut Complex,
    v: u32,
    v2: u32,
    level: usize,
    bits: u32,
    reader: &mut SymbolReader,
    scratch: &mut Scratch,
) -> Result<(), CodecError> {
    let Scratch {
        slots,
        coarse,
        decoded,
        weld,
        ..
    } = scratch;
    slots.clear();
    slots.extend_from_slice(cx.incident(v));
    coarse.clear();
    coarse.extend(
        slots
            .iter()
            .map(|&s| cx.simplices[s as usize].expect("live")),
    );
    code_connectivity(
        cx,
        coarse,
        (v, v2),
        level,
        bits,
        &mut Read { reader },
        decoded,
    )?;
    cx.split(v, v2, slots, decoded, weld);
    cx.vertices[v as usize].level = level as u8 + 1;
    Ok(())
}
