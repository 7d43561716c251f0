//! Side-by-side panels: frames of one size tiled into one image, row by row, so that a LOD
//! chain or a cage beside its subdivided surface becomes one thumbnail (`tessd render A B C
//! OUT.png`, or a USD stage's LOD variants). Every panel keeps its own pixels — colour,
//! depth, face ids, (u, v) — at its place in the grid; slots past the last panel are
//! background.

use crate::Frame;
use crate::surface::BACKGROUND;

/// The number of columns for `n` panels when the caller gives none: one row up to four
/// panels (a LOD chain reads left to right), else the smallest square-ish grid.
pub fn default_columns(n: usize) -> usize {
    if n <= 4 {
        n.max(1)
    } else {
        (n as f64).sqrt().ceil() as usize
    }
}

/// Where panel `index` lands: its top-left pixel in the tiled image.
pub fn panel_origin(index: usize, columns: usize, width: u32, height: u32) -> (u32, u32) {
    let columns = columns.max(1);
    (
        (index % columns) as u32 * width,
        (index / columns) as u32 * height,
    )
}

/// Tiles `frames` (all the same size) into `columns` columns.
///
/// # Panics
/// When `frames` is empty or the frames differ in size.
pub fn tile(frames: &[Frame], columns: usize) -> Frame {
    let first = frames.first().expect("at least one panel");
    let (w, h) = (first.width as usize, first.height as usize);
    assert!(
        frames
            .iter()
            .all(|f| f.width as usize == w && f.height as usize == h),
        "panels of one size"
    );
    let columns = columns.clamp(1, frames.len());
    let rows = frames.len().div_ceil(columns);
    let (tw, th) = (w * columns, h * rows);
    let mut out = Frame {
        width: tw as u32,
        height: th as u32,
        color: BACKGROUND.repeat(tw * th),
        depth: vec![f32::INFINITY; tw * th],
        face_id: vec![0; tw * th],
        uv: vec![[0.0; 2]; tw * th],
    };
    for (i, f) in frames.iter().enumerate() {
        let (x0, y0) = panel_origin(i, columns, w as u32, h as u32);
        let (x0, y0) = (x0 as usize, y0 as usize);
        for y in 0..h {
            let src = y * w;
            let dst = (y0 + y) * tw + x0;
            out.color[4 * dst..4 * (dst + w)].copy_from_slice(&f.color[4 * src..4 * (src + w)]);
            out.depth[dst..dst + w].copy_from_slice(&f.depth[src..src + w]);
            out.face_id[dst..dst + w].copy_from_slice(&f.face_id[src..src + w]);
            out.uv[dst..dst + w].copy_from_slice(&f.uv[src..src + w]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` frame whose every pixel carries `id` (colour, depth and uv derived from it
    /// and the pixel's position, so a misplaced copy shows).
    fn frame(w: u32, h: u32, id: u32) -> Frame {
        let n = (w * h) as usize;
        let mut color = Vec::with_capacity(4 * n);
        for p in 0..n {
            color.extend_from_slice(&[id as u8, p as u8, (p / 256) as u8, 255]);
        }
        Frame {
            width: w,
            height: h,
            color,
            depth: (0..n).map(|p| id as f32 * 1000.0 + p as f32).collect(),
            face_id: vec![id; n],
            uv: (0..n).map(|p| [p as f32, id as f32]).collect(),
        }
    }

    #[test]
    fn panels_land_row_by_row_and_empty_slots_are_background() {
        let frames: Vec<Frame> = (1..=5).map(|id| frame(3, 2, id)).collect();
        assert_eq!(default_columns(5), 3);
        let t = tile(&frames, 3);
        assert_eq!((t.width, t.height), (9, 4));
        for (i, f) in frames.iter().enumerate() {
            let (x0, y0) = panel_origin(i, 3, 3, 2);
            for y in 0..2 {
                for x in 0..3 {
                    let (s, d) = ((y * 3 + x) as usize, ((y0 + y) * 9 + x0 + x) as usize);
                    assert_eq!(t.face_id[d], f.face_id[s]);
                    assert_eq!(t.depth[d], f.depth[s]);
                    assert_eq!(t.uv[d], f.uv[s]);
                    assert_eq!(t.color[4 * d..4 * d + 4], f.color[4 * s..4 * s + 4]);
                }
            }
        }
        // The sixth slot (column 2, row 1) is background.
        let d = (2 * 9 + 6) as usize;
        assert_eq!(t.face_id[d], 0);
        assert!(t.depth[d].is_infinite());
        assert_eq!(t.color[4 * d..4 * d + 4], BACKGROUND);
        assert_eq!(t.covered(), 5 * 6);
    }

    #[test]
    fn a_chain_of_up_to_four_is_one_row() {
        assert_eq!(
            (1..=6).map(default_columns).collect::<Vec<_>>(),
            [1, 2, 3, 4, 3, 3]
        );
        let t = tile(&[frame(2, 2, 1), frame(2, 2, 2)], default_columns(2));
        assert_eq!((t.width, t.height), (4, 2));
        assert_eq!(t.face_id, [1, 1, 2, 2, 1, 1, 2, 2]);
    }
}
