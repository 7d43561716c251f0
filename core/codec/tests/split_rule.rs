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
