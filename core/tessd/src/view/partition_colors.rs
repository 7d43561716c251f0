//! `P`: the clustering partition that made a LOD (paper 004), shown on the input surface: each
//! face coloured by the cell its first vertex fell in, the way the papers' figures show
//! clusters. Cells are found through a uniform grid of buckets over their boxes.

use tessd_mesh::Mesh;
use tessd_simplify::Cell;

/// `mesh` with one face group per cell of `cells` (a face's group: the cell holding its first
/// corner; faces outside every cell, which clustering never leaves, get the last group).
pub fn colored_by_cell(mesh: &Mesh, cells: &[Cell]) -> Mesh {
    let locate = Buckets::new(cells);
    let cell_of: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| locate.find(cells, *p).unwrap_or(cells.len()) as u32)
        .collect();
    let mut out = mesh.clone();
    out.face_groups = (0..mesh.face_count())
        .map(|f| cell_of[mesh.face(f)[0] as usize])
        .collect();
    out.group_names = (0..=cells.len()).map(|i| format!("cell{i}")).collect();
    out
}

/// Cells listed by the grid buckets their boxes overlap.
struct Buckets {
    min: [f32; 3],
    size: [f32; 3],
    n: usize,
    lists: Vec<Vec<u32>>,
}

impl Buckets {
    fn new(cells: &[Cell]) -> Buckets {
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for c in cells {
            for a in 0..3 {
                min[a] = min[a].min(c.min[a]);
                max[a] = max[a].max(c.max[a]);
            }
        }
        let n = ((cells.len() as f64).cbrt().ceil() as usize).clamp(1, 64);
        let size = std::array::from_fn(|a| ((max[a] - min[a]) / n as f32).max(f32::MIN_POSITIVE));
        let mut b = Buckets {
            min,
            size,
            n,
            lists: vec![Vec::new(); n * n * n],
        };
        for (i, c) in cells.iter().enumerate() {
            let lo = b.index3(c.min);
            let hi = b.index3(c.max);
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        b.lists[(x * n + y) * n + z].push(i as u32);
                    }
                }
            }
        }
        b
    }

    fn index3(&self, p: [f32; 3]) -> [usize; 3] {
        std::array::from_fn(|a| {
            let t = ((p[a] - self.min[a]) / self.size[a]).floor();
            (t.max(0.0) as usize).min(self.n - 1)
        })
    }

    /// The first cell whose box holds `p`.
    fn find(&self, cells: &[Cell], p: [f32; 3]) -> Option<usize> {
        let [x, y, z] = self.index3(p);
        self.lists[(x * self.n + y) * self.n + z]
            .iter()
            .map(|&i| i as usize)
            .find(|&i| (0..3).all(|a| cells[i].min[a] <= p[a] && p[a] <= cells[i].max[a]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_take_the_cell_of_their_first_corner() {
        let mut mesh = Mesh {
            positions: vec![
                [0.1, 0.1, 0.1],
                [0.9, 0.1, 0.1],
                [0.1, 0.9, 0.1],
                [1.6, 0.5, 0.5],
            ],
            ..Mesh::default()
        };
        mesh.push_face(&[0, 1, 2]);
        mesh.push_face(&[3, 1, 2]);
        let cells = [
            Cell {
                min: [0.0; 3],
                max: [1.0; 3],
            },
            Cell {
                min: [1.0, 0.0, 0.0],
                max: [2.0, 1.0, 1.0],
            },
        ];
        let out = colored_by_cell(&mesh, &cells);
        assert_eq!(out.face_groups, vec![0, 1]);
    }
}
