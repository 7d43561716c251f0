//! Helpers shared by the integration tests: options, test meshes, f64 point arithmetic,
//! mesh checks (orientation, Euler characteristic, stencil rows), the shared-data lookup and
//! order-independent distances between point sets. Not every test uses every helper.

#![allow(dead_code)]

use std::collections::HashMap;
use std::path::PathBuf;

use tessd_mesh::{Crease, Mesh};
use tessd_subdiv::{
    Boundary, Faces, Level, Scheme, SubdivError, SubdivOptions, Topology, subdivide,
};

/// A point in f64, for expected values computed in the tests.
pub type P = [f64; 3];

// Options and refinement.

/// Options for `levels` levels of `scheme` with the boundary rule `boundary`, the rest default.
pub fn options(scheme: Scheme, levels: u32, boundary: Boundary) -> SubdivOptions {
    SubdivOptions {
        scheme,
        levels,
        boundary,
        ..SubdivOptions::default()
    }
}

/// The faces of `m` as the schemes' `refine` functions take them.
pub fn faces_of(m: &Mesh) -> Faces {
    Faces {
        offsets: m.face_offsets.clone(),
        indices: m.face_indices.clone(),
        vertex_count: m.positions.len() as u32,
    }
}

/// One level of `m` through a scheme's `refine` directly (called with the faces and topology
/// of `m`), with the level and the refined mesh: new positions, faces and creases.
pub fn refine_with(
    m: &Mesh,
    refine: impl FnOnce(&Faces, &Topology) -> Result<Level, SubdivError>,
) -> (Level, Mesh) {
    let faces = faces_of(m);
    let creases: Vec<([u32; 2], f32)> = m.creases.iter().map(|c| ([c.a, c.b], c.value)).collect();
    let topo = Topology::build(&faces, &creases).unwrap();
    let level = refine(&faces, &topo).unwrap();
    let mut flat = vec![0.0; level.table.len() * 3];
    level.table.apply(m.positions.as_flattened(), 3, &mut flat);
    let out = Mesh {
        positions: flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        face_offsets: level.faces.offsets.clone(),
        face_indices: level.faces.indices.clone(),
        creases: level
            .creases
            .iter()
            .map(|&([a, b], value)| Crease { a, b, value })
            .collect(),
        ..Mesh::default()
    };
    (level, out)
}

/// The cage's edges in [`Topology`] order: new vertex `e` of a triangle scheme is the point of
/// edge `e`.
pub fn edges(m: &Mesh) -> Vec<[u32; 2]> {
    Topology::build(&faces_of(m), &[]).unwrap().edge_vertices
}

// Test meshes.

/// A mesh with these positions and faces, nothing else.
pub fn mesh(positions: Vec<[f32; 3]>, faces: &[Vec<u32>]) -> Mesh {
    let mut m = Mesh {
        positions,
        ..Mesh::default()
    };
    faces.iter().for_each(|f| m.push_face(f));
    m
}

/// `m` with its creases replaced by `creases`, each `(a, b, sharpness)`.
pub fn creased(mut m: Mesh, creases: &[(u32, u32, f32)]) -> Mesh {
    m.creases = creases
        .iter()
        .map(|&(a, b, value)| Crease { a, b, value })
        .collect();
    m
}

/// The unit square's corners in z = 0, in the order (0, 0), (1, 0), (0, 1), (1, 1).
fn square_corners() -> Vec<[f32; 3]> {
    vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]
}

/// Two triangles sharing edge (1, 2): a valid cage for every scheme.
pub fn pair() -> Mesh {
    mesh(square_corners(), &[vec![0, 1, 2], vec![2, 1, 3]])
}

/// Two triangles that both run their shared edge (1, 2) from 1 to 2: inconsistent orientation.
pub fn misoriented_pair() -> Mesh {
    mesh(square_corners(), &[vec![0, 1, 2], vec![1, 2, 3]])
}

/// The unit square in z = 0 as one quad, counter-clockwise.
pub fn unit_quad() -> Mesh {
    mesh(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        &[vec![0, 1, 2, 3]],
    )
}

/// A regular triangulated `n × n` vertex grid (vertex `i + n j` at `point(i, j)`), each square
/// cut from `(i, j)` to `(i + 1, j + 1)`.
fn grid_of(n: u32, point: impl Fn(u32, u32) -> [f32; 3]) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..n {
        for i in 0..n {
            m.positions.push(point(i, j));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = i + n * j;
            m.push_face(&[v, v + 1, v + 1 + n]);
            m.push_face(&[v, v + 1 + n, v + n]);
        }
    }
    m
}

/// A regular triangulated `n × n` vertex grid over `[0, 1]²` (vertex `i + n j` at `(i, j)/(n
/// − 1)`), each square cut from `(i, j)` to `(i + 1, j + 1)`, heights `z(x, y)`; computed in
/// f64 and rounded to f32.
pub fn grid(n: u32, z: impl Fn(f64, f64) -> f64) -> Mesh {
    let h = 1.0 / f64::from(n - 1);
    grid_of(n, |i, j| {
        let (x, y) = (f64::from(i) * h, f64::from(j) * h);
        [x as f32, y as f32, z(x, y) as f32]
    })
}

/// The grid of [`grid`], computed in f32 throughout.
pub fn grid_f32(n: u32, z: impl Fn(f32, f32) -> f32) -> Mesh {
    let h = 1.0 / (n - 1) as f32;
    grid_of(n, |i, j| {
        let (x, y) = (i as f32 * h, j as f32 * h);
        [x, y, z(x, y)]
    })
}

/// The tilted plane of the planar open-mesh tests: its origin, then the images of the x and y
/// axes; its normal is their cross product.
pub const PLANE: [P; 3] = [[0.3, -0.2, 0.5], [1.0, 0.2, -0.3], [0.1, 0.9, 0.4]];

/// The point at `(x, y)` in the plane's coordinates of [`PLANE`], in f32.
pub fn on_plane(x: f64, y: f64) -> [f32; 3] {
    let [o, u, v] = PLANE;
    [0, 1, 2].map(|k| (o[k] + x * u[k] + y * v[k]) as f32)
}

/// A bumpy height that is not polynomial.
pub fn bumps(x: f64, y: f64) -> f64 {
    0.2 * (7.0 * x).sin() * (5.0 * y + 1.0).cos()
}

/// [`bumps`] computed in f32.
pub fn bumps_f32(x: f32, y: f32) -> f32 {
    0.2 * (7.0 * x).sin() * (5.0 * y + 1.0).cos()
}

/// The triangles of a convex polyhedron around the origin whose edges all have length `edge`
/// (within 1e-4), oriented outward, in the order of their sorted corners.
pub fn solid(points: Vec<[f32; 3]>, edge: f64) -> Mesh {
    let n = points.len() as u32;
    let adjacent =
        |a: u32, b: u32| (dist32(points[a as usize], points[b as usize]) - edge).abs() < 1e-4;
    let mut faces = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                if adjacent(a, b) && adjacent(b, c) && adjacent(a, c) {
                    let [p, q, r] = [a, b, c].map(|v| p64(points[v as usize]));
                    let centre = add(add(p, q, 1.0), r, 1.0);
                    let outward = dot(cross(sub(q, p), sub(r, p)), centre) > 0.0;
                    faces.push(if outward {
                        vec![a, b, c]
                    } else {
                        vec![a, c, b]
                    });
                }
            }
        }
    }
    mesh(points, &faces)
}

/// The octahedron with vertices ±x, ±y, ±z (in that order), in f32.
pub fn octahedron() -> Mesh {
    let mut p = Vec::new();
    for k in 0..3 {
        for s in [1.0, -1.0] {
            let mut v = [0.0; 3];
            v[k] = s;
            p.push(v);
        }
    }
    solid(p, 2f64.sqrt())
}

/// The icosahedron of edge 2 with vertices (0, ±1, ±g) and their cyclic shifts (g the golden
/// ratio, in f32).
pub fn icosahedron() -> Mesh {
    let g = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p = Vec::new();
    for s in [1.0, -1.0] {
        for t in [g, -g] {
            p.extend([[0.0, s, t], [s, t, 0.0], [t, 0.0, s]]);
        }
    }
    solid(p, 2.0)
}

// Point arithmetic.

/// Distance between two f32 points, differences taken in f32 and summed in f64.
pub fn dist32(p: [f32; 3], q: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| f64::from(p[k] - q[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// An f32 point in f64.
pub fn p64(p: [f32; 3]) -> P {
    p.map(f64::from)
}

/// `a + w b`.
pub fn add(a: P, b: P, w: f64) -> P {
    [a[0] + w * b[0], a[1] + w * b[1], a[2] + w * b[2]]
}

/// `a − b`.
pub fn sub(a: P, b: P) -> P {
    add(a, b, -1.0)
}

/// The dot product.
pub fn dot(a: P, b: P) -> f64 {
    (0..3).map(|k| a[k] * b[k]).sum()
}

/// The cross product.
pub fn cross(a: P, b: P) -> P {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Distance between two f64 points.
pub fn dist(a: P, b: P) -> f64 {
    dot(sub(a, b), sub(a, b)).sqrt()
}

/// Length of `a`.
pub fn norm(a: P) -> f64 {
    dot(a, a).sqrt()
}

/// The (unnormalised) normal of face `c` of `m` from its first three corners.
pub fn normal(m: &Mesh, c: &[u32]) -> P {
    let p = |i: usize| p64(m.positions[c[i] as usize]);
    cross(sub(p(1), p(0)), sub(p(2), p(0)))
}

// Mesh checks.

/// Directed edges of `m`, each asserted to be used once; on a closed mesh each reverse too.
pub fn assert_oriented(m: &Mesh, closed: bool) -> HashMap<(u32, u32), usize> {
    let mut directed = HashMap::new();
    for (f, c) in m.faces().enumerate() {
        for k in 0..c.len() {
            let d = (c[k], c[(k + 1) % c.len()]);
            assert!(
                directed.insert(d, f).is_none(),
                "edge {d:?} runs the same way in two faces"
            );
        }
    }
    if closed {
        for &(a, b) in directed.keys() {
            assert!(
                directed.contains_key(&(b, a)),
                "edge ({a}, {b}) has one face"
            );
        }
    }
    directed
}

/// Edges (a, b), a < b, with how many faces use each.
pub fn edge_uses(m: &Mesh) -> HashMap<(u32, u32), usize> {
    let mut uses = HashMap::new();
    for f in m.faces() {
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    uses
}

/// V − E + F over the vertices the faces use.
pub fn euler(m: &Mesh) -> i64 {
    let mut used = vec![false; m.positions.len()];
    m.face_indices.iter().for_each(|&v| used[v as usize] = true);
    used.iter().filter(|&&u| u).count() as i64 - edge_uses(m).len() as i64 + m.face_count() as i64
}

/// The boundary loop of a mesh with one boundary, following the faces' direction.
pub fn boundary_loop(m: &Mesh) -> Vec<u32> {
    let directed = assert_oriented(m, false);
    let next: HashMap<u32, u32> = directed
        .keys()
        .filter(|&&(a, b)| !directed.contains_key(&(b, a)))
        .map(|&(a, b)| (a, b))
        .collect();
    let start = *next.keys().min().expect("a boundary");
    let mut out = vec![start];
    let mut v = next[&start];
    while v != start {
        out.push(v);
        v = next[&v];
    }
    assert_eq!(out.len(), next.len(), "one boundary loop");
    out
}

/// The positions of [`boundary_loop`] of `m`, in f64.
pub fn boundary_loop_points(m: &Mesh) -> Vec<P> {
    boundary_loop(m)
        .iter()
        .map(|&v| p64(m.positions[v as usize]))
        .collect()
}

/// The boundary polygon of an open mesh with one boundary, each point flagged `true` as a
/// corner when `corners` and its vertex is in one face only.
pub fn boundary_polygon(cage: &Mesh, corners: bool) -> Vec<(P, bool)> {
    let mut faces_at = vec![0; cage.positions.len()];
    cage.face_indices
        .iter()
        .for_each(|&v| faces_at[v as usize] += 1);
    boundary_loop(cage)
        .iter()
        .map(|&v| {
            (
                p64(cage.positions[v as usize]),
                corners && faces_at[v as usize] == 1,
            )
        })
        .collect()
}

/// The largest distance of a vertex of `m` from the plane through `origin` with normal
/// `normal` (of any length).
pub fn off_plane(m: &Mesh, origin: P, normal: P) -> f64 {
    m.positions
        .iter()
        .map(|&p| (dot(sub(p64(p), origin), normal) / norm(normal)).abs())
        .fold(0.0, f64::max)
}

/// Prints the sizes of `out`, level `levels` of an open mesh with boundary rule `boundary`
/// and a boundary of `boundary_points` points.
pub fn print_open_level(boundary: Boundary, levels: u32, out: &Mesh, boundary_points: usize) {
    println!(
        "{boundary:?} level {levels}: {} vertices, {} faces, boundary of {} points",
        out.positions.len(),
        out.face_count(),
        boundary_points
    );
}

/// Every row of `level`'s table sums to one and has only positive weights.
pub fn assert_rows_sum_to_one(level: &Level) {
    for i in 0..level.table.len() {
        let s: f64 = level.table.row(i).map(|(_, w)| f64::from(w)).sum();
        assert!((s - 1.0).abs() < 1e-6, "row {i} sums to {s}");
        assert!(level.table.row(i).all(|(_, w)| w > 0.0), "row {i}");
    }
}

/// Two levels of `m` through `refine` (one level with a boundary rule), with each rule: every
/// row of both levels' tables sums to one and has only positive weights.
pub fn assert_two_levels_sum_to_one(m: &Mesh, refine: impl Fn(&Mesh, Boundary) -> (Level, Mesh)) {
    for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
        let (level, out) = refine(m, boundary);
        assert_rows_sum_to_one(&level);
        let (level, _) = refine(&out, boundary);
        assert_rows_sum_to_one(&level);
    }
}

/// One level of `scheme` on [`misoriented_pair`] is refused, naming face 1; the error.
pub fn assert_misorientation_named(scheme: Scheme) -> SubdivError {
    let options = options(scheme, 1, Boundary::EdgeOnly);
    let err = subdivide(&misoriented_pair(), &options).unwrap_err();
    assert!(
        matches!(err, SubdivError::DegenerateFace { face: 1, .. }),
        "{err}"
    );
    err
}

// Shared data and point-set distances.

/// The path of `name` in the shared test data's `subdiv` folder (`$TESSD_SHARED_DATA`, else
/// `../../../shared/data` from this crate), asserted to exist.
pub fn data(name: &str) -> PathBuf {
    shared(&format!("subdiv/{name}"))
}

/// A file of the shared test data (`TESSD_SHARED_DATA`, else `../shared/data` beside the repo),
/// by its path under that folder.
pub fn shared(rel: &str) -> PathBuf {
    tessd_testdata::shared(rel)
}

/// A mesh of the shared test data, by its path under that folder (`mesh/suzanne.obj`).
pub fn read_mesh(rel: &str) -> Mesh {
    tessd_mesh::io::read_path(&shared(rel), &Default::default()).unwrap()
}

pub fn read(name: &str) -> Mesh {
    tessd_mesh::io::read_path(&data(name), &Default::default()).unwrap()
}

/// Largest distance from a point of `a` to its nearest point of `b`.
pub fn one_sided(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    a.iter()
        .map(|&p| {
            b.iter()
                .map(|&q| dist32(p, q))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// The symmetric (Hausdorff) distance between the point sets `a` and `b`, in any order.
pub fn both_sided(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    one_sided(a, b).max(one_sided(b, a))
}

/// The longest side of `m`'s bounding box.
pub fn size(m: &Mesh) -> f64 {
    let (lo, hi) = m.bounds().unwrap();
    (0..3).map(|i| hi[i] - lo[i]).fold(0.0f32, f32::max) as f64
}
