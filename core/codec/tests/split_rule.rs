//! The nSP-tree's split rule (issue 34 item 2): a cell is split when it holds `N_min` simplices
//! and its children would not be tiny, so a mesh of fewer than ~50 k triangles stays one cell
//! (border vertices cost bits in every child) while a large mesh still splits into bounded cells.

use std::io::Cursor;

use tessd_codec::partition::CHILD_SHARE;
use tessd_codec::{Params, Tsc, compress};

fn cells(positions: &[[f32; 3]], tris: &[[u32; 3]], params: Params) -> Tsc {
    let mut file = Cursor::new(Vec::new());
    compress(positions, tris, params, &mut file, &|_| true).unwrap();
    Tsc::open(&file.into_inner()).unwrap()
}

fn bunny() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let path = tessd_testdata::shared("mesh/bun_zipper.ply");
    let mesh = tessd_mesh::io::read_path(&path, &Default::default()).unwrap();
    let tris = mesh.faces().map(|f| [f[0], f[1], f[2]]).collect();
    (mesh.positions, tris)
}

#[test]
fn the_bunny_stays_one_cell_by_default_but_splits_at_a_small_n_min() {
    let (p, t) = bunny();
    // its root holds 70 564 simplices, more than N_min: the children decide
    assert_eq!(cells(&p, &t, Params::default()).nodes.len(), 1);
    let small = Params {
        min_cell: 8000,
        ..Params::default()
    };
    assert_eq!(cells(&p, &t, small).nodes.len(), 43);
}

#[test]
fn a_large_surface_splits_into_bounded_cells() {
    // a wavy 300 x 300 grid: 178 802 triangles over one face of the box
    let n = 300u32;
    let positions: Vec<[f32; 3]> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32, (i / n) as f32);
            [x, y, 20.0 * (x / 17.0).sin() * (y / 23.0).cos()]
        })
        .collect();
    let mut tris = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let v = y * n + x;
            tris.push([v, v + 1, v + n]);
            tris.push([v + 1, v + n + 1, v + n]);
        }
    }
    let params = Params::default();
    let tsc = cells(&positions, &tris, params);
    assert!(tsc.nodes.len() > 4, "{} cells", tsc.nodes.len());
    let bound = 64 * params.min_cell / CHILD_SHARE;
    for node in tsc.nodes.iter().filter(|n| n.children.is_empty()) {
        assert!(
            node.end_simplices < bound,
            "a leaf of {}",
            node.end_simplices
        );
    }
}

/// Counts the passes over the triangles.
struct Counting<'a> {
    inner: tessd_codec::source::Slices<'a>,
    triangle_passes: usize,
}

impl tessd_codec::source::MeshSource for Counting<'_> {
    fn vertex_count(&self) -> u64 {
        self.inner.vertex_count()
    }
    fn vertices(&mut self, f: &mut dyn FnMut([f32; 3])) -> Result<(), tessd_mesh::MeshError> {
        self.inner.vertices(f)
    }
    fn triangles(&mut self, f: &mut dyn FnMut([u32; 3])) -> Result<(), tessd_mesh::MeshError> {
        self.triangle_passes += 1;
        self.inner.triangles(f)
    }
}

#[test]
fn each_leaf_region_holds_exactly_its_simplices_after_two_passes_over_the_triangles() {
    use tessd_codec::partition::{POINT_MARK, build, build_with_count_budget};
    let (mut p, t) = bunny();
    // a few unreferenced points, as the bunny has: they are simplices too
    p.extend([[0.0, 0.1, 0.0], [-0.05, 0.15, 0.02]]);
    let params = Params {
        min_cell: 1000,
        ..Params::default()
    };
    let mut src = Counting {
        inner: tessd_codec::source::Slices {
            positions: &p,
            triangles: &t,
        },
        triangle_passes: 0,
    };
    let part = build(&mut src, params, &|_| true).unwrap();
    let depth = part.nodes.iter().map(|n| n.depth).max().unwrap();
    assert!(depth >= 2, "a tree of depth {depth}");
    // every level counted in the pass that counts the triangles, then the write
    assert_eq!(src.triangle_passes, 2);
    // the same partition with no cell counted ahead: one pass per level
    src.triangle_passes = 0;
    let slow = build_with_count_budget(&mut src, params, &|_| true, 0).unwrap();
    assert!(
        src.triangle_passes > depth as usize,
        "{}",
        src.triangle_passes
    );
    assert_eq!(slow.nodes, part.nodes);
    assert_eq!(slow.regions, part.regions);
    // the leaf holding a grid point, down from the root
    let leaf_of = |q: [u32; 3]| {
        let mut i = 0;
        loop {
            let n = &part.nodes[i];
            match params.child_of(n.depth, n.cell, q) {
                Some(pos) if n.child_mask & (1 << pos) != 0 => {
                    i = n.children[(n.child_mask & ((1u64 << pos) - 1)).count_ones() as usize]
                }
                _ => return i,
            }
        }
    };
    let mut expected = vec![Vec::new(); part.nodes.len()];
    let mut used = vec![false; p.len()];
    for tri in &t {
        let mut leaves: Vec<usize> = tri.iter().map(|&x| leaf_of(part.points.get(x))).collect();
        leaves.dedup();
        leaves.sort_unstable();
        leaves.dedup();
        for l in leaves {
            expected[l].push(*tri);
        }
        tri.iter().for_each(|&x| used[x as usize] = true);
    }
    for (i, _) in used.iter().enumerate().filter(|(_, u)| !**u) {
        let i = i as u32;
        expected[leaf_of(part.points.get(i))].push([i, POINT_MARK, POINT_MARK]);
    }
    for (i, want) in expected.iter_mut().enumerate() {
        let mut got = part.leaf(i).unwrap();
        assert_eq!(got.len() as u64, part.regions[i].1);
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(&got, want, "cell {i}");
    }
}
