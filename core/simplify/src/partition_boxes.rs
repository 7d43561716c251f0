//! The partition's cells as geometry, for the dialog's "show partition" option (section 6):
//! a mesh of boxes (six quads each, for USD and hosts that draw it as wireframe) or an OBJ of
//! wire boxes (twelve `l` lines each).

use crate::partition::Cell;
use std::io::{self, Write};
use tessd_mesh::Mesh;

/// Corner `i` (bits x, y, z) of a cell.
fn corner(c: &Cell, i: usize) -> [f32; 3] {
    std::array::from_fn(|k| if i >> k & 1 == 1 { c.max[k] } else { c.min[k] })
}

/// The cells as a mesh of closed boxes (8 vertices, 6 outward quads each).
pub fn boxes_mesh(cells: &[Cell]) -> Mesh {
    const QUADS: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut m = Mesh::default();
    for c in cells {
        let base = m.positions.len() as u32;
        m.positions.extend((0..8).map(|i| corner(c, i)));
        for q in QUADS {
            m.push_face(&q.map(|i| base + i));
        }
    }
    m
}

/// Writes the cells as an OBJ of wire boxes: 8 `v` and 12 `l` records per cell.
///
/// # Errors
/// Write failures.
pub fn write_wire_obj(cells: &[Cell], w: &mut dyn Write) -> io::Result<()> {
    const EDGES: [[usize; 2]; 12] = [
        [0, 1],
        [2, 3],
        [4, 5],
        [6, 7],
        [0, 2],
        [1, 3],
        [4, 6],
        [5, 7],
        [0, 4],
        [1, 5],
        [2, 6],
        [3, 7],
    ];
    writeln!(w, "# tessd partition: {} cells", cells.len())?;
    for c in cells {
        for i in 0..8 {
            let p = corner(c, i);
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
    }
    for k in 0..cells.len() {
        let base = 8 * k + 1;
        for [a, b] in EDGES {
            writeln!(w, "l {} {}", base + a, base + b)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_unit_box_is_closed_and_outward() {
        let m = boxes_mesh(&[Cell {
            min: [0.0; 3],
            max: [1.0; 3],
        }]);
        m.validate().unwrap();
        let s = tessd_mesh::stats::compute(&m);
        assert_eq!(
            (s.vertices, s.faces, s.boundary_edges, s.non_manifold_edges),
            (8, 6, 0, 0)
        );
        // Outward: the signed volume of the closed box is +1.
        let mut vol = 0.0;
        for f in m.faces() {
            for k in 1..f.len() - 1 {
                let (a, b, c) = (
                    m.positions[f[0] as usize],
                    m.positions[f[k] as usize],
                    m.positions[f[k + 1] as usize],
                );
                vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0;
            }
        }
        assert!((vol - 1.0).abs() < 1e-6, "{vol}");
        let mut text = Vec::new();
        write_wire_obj(
            &[Cell {
                min: [0.0; 3],
                max: [1.0; 3],
            }],
            &mut text,
        )
        .unwrap();
        let text = String::from_utf8(text).unwrap();
        assert_eq!(text.lines().filter(|l| l.starts_with("l ")).count(), 12);
    }
}
