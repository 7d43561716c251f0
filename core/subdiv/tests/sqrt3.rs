//! √3: counts, orientation, Kobbelt's relaxation weights, the triadic split after two levels,
//! symmetry, and the cubic B-spline boundaries and creases, each expected value computed here
//! from the cage, not read back from the scheme.

use std::collections::HashMap;
use std::f64::consts::PI;

use tessd_mesh::{Crease, Mesh};
use tessd_subdiv::{
    Boundary, Level, Scheme, SubdivError, SubdivOptions, Topology, sqrt3, subdivide,
};

mod common;
use common::{
    P, PLANE, add, assert_misorientation_named, assert_oriented, assert_rows_sum_to_one,
    assert_two_levels_sum_to_one, boundary_loop_points, boundary_polygon, creased, cross, dist,
    dot, euler, faces_of, mesh, norm, normal, off_plane, on_plane, p64, print_open_level,
    refine_with, solid, unit_quad,
};

fn options(levels: u32, boundary: Boundary) -> SubdivOptions {
    common::options(Scheme::Sqrt3, levels, boundary)
}

/// One level through `refine` directly, with the new positions and creases.
fn refine(m: &Mesh, boundary: Boundary) -> (Level, Mesh) {
    refine_with(m, |faces, topo| sqrt3::refine(faces, topo, boundary))
}

/// The one closed loop made of `edges` (each vertex on two of them).
fn edge_loop(edges: &[(u32, u32)]) -> Vec<u32> {
    let mut around: HashMap<u32, Vec<u32>> = HashMap::new();
    for &(a, b) in edges {
        around.entry(a).or_default().push(b);
        around.entry(b).or_default().push(a);
    }
    assert!(around.values().all(|n| n.len() == 2), "a simple loop");
    let start = *around.keys().min().unwrap();
    let (mut prev, mut v) = (start, around[&start][0]);
    let mut out = vec![start];
    while v != start {
        out.push(v);
        let n = &around[&v];
        (prev, v) = (v, if n[0] == prev { n[1] } else { n[0] });
    }
    assert_eq!(out.len(), edges.len(), "one loop");
    out
}

/// `got` is `want` up to where the loop starts (and, unless `directed`, its direction).
fn assert_same_loop(got: &[P], want: &[P], directed: bool, tol: f64) {
    assert_eq!(got.len(), want.len(), "loop lengths");
    let n = want.len();
    let r = (0..n)
        .min_by(|&i, &j| dist(got[0], want[i]).total_cmp(&dist(got[0], want[j])))
        .unwrap();
    let forward = (0..n).all(|i| dist(got[i], want[(i + r) % n]) < tol);
    let backward = !directed && (0..n).all(|i| dist(got[i], want[(r + n - i) % n]) < tol);
    assert!(forward || backward, "loops differ: {got:?} vs {want:?}");
}

/// One cubic B-spline step of a closed polygon; points flagged `true` are corners and stay.
fn cubic_bspline(poly: &[(P, bool)]) -> Vec<(P, bool)> {
    let n = poly.len();
    let mut out = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (a, corner) = poly[i];
        let (prev, next) = (poly[(i + n - 1) % n].0, poly[(i + 1) % n].0);
        let moved = add(add(a.map(|x| 0.75 * x), prev, 0.125), next, 0.125);
        out.push((if corner { a } else { moved }, corner));
        out.push((add(a.map(|x| 0.5 * x), next, 0.5), false));
    }
    out
}

/// A convex polyhedron whose faces are the triangles of equal shortest edges (the regular
/// tetrahedron, octahedron, icosahedron), oriented outward.
fn regular(points: &[P]) -> Mesh {
    let n = points.len();
    let edge = (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .map(|(i, j)| dist(points[i], points[j]))
        .fold(f64::INFINITY, f64::min);
    solid(points.iter().map(|p| p.map(|x| x as f32)).collect(), edge)
}

fn tetrahedron() -> Mesh {
    regular(&[
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ])
}

fn octahedron() -> Mesh {
    regular(&[
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ])
}

fn icosahedron() -> Mesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pts = Vec::new();
    for a in [-1.0, 1.0] {
        for b in [-g, g] {
            pts.extend([[0.0, a, b], [a, b, 0.0], [b, 0.0, a]]);
        }
    }
    regular(&pts)
}

/// An `m` × `n` triangulated torus grid (each quad cut by the same diagonal, so every vertex
/// has valence 6); also returns each vertex's six neighbours.
fn torus(m: u32, n: u32) -> (Mesh, Vec<Vec<u32>>) {
    let id = |i: i64, j: i64| (i.rem_euclid(m as i64) as u32) * n + j.rem_euclid(n as i64) as u32;
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut neighbours = Vec::new();
    for i in 0..m as i64 {
        for j in 0..n as i64 {
            let (u, v) = (
                2.0 * PI * i as f64 / m as f64,
                2.0 * PI * j as f64 / n as f64,
            );
            let r = 3.0 + v.cos();
            positions.push([(r * u.cos()) as f32, (r * u.sin()) as f32, v.sin() as f32]);
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            faces.push(vec![a, b, c]);
            faces.push(vec![a, c, d]);
            neighbours.push(
                [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1)]
                    .map(|(di, dj)| id(i + di, j + dj))
                    .to_vec(),
            );
        }
    }
    (mesh(positions, &faces), neighbours)
}

/// A regular triangle grid of `w` × `h` vertices on the lattice spanned by (1, 0) and
/// (1/2, √3/2), in the plane z = 0, counter-clockwise.
fn triangle_grid(w: u32, h: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (x, y) = (i as f64 + 0.5 * j as f64, j as f64 * 3f64.sqrt() / 2.0);
            positions.push([x as f32, y as f32, 0.0]);
        }
    }
    let id = |i: u32, j: u32| j * w + i;
    let mut faces = Vec::new();
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            faces.push(vec![id(i, j), id(i + 1, j), id(i, j + 1)]);
            faces.push(vec![id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    mesh(positions, &faces)
}

#[test]
fn closed_meshes_triple_their_faces_and_keep_euler() {
    for (name, m, chi) in [
        ("tetrahedron", tetrahedron(), 2),
        ("octahedron", octahedron(), 2),
        ("icosahedron", icosahedron(), 2),
        ("torus", torus(6, 5).0, 0),
    ] {
        assert_eq!(euler(&m), chi, "{name} cage");
        let (mut v, mut f) = (m.positions.len(), m.face_count());
        for levels in 1..=3 {
            let out = subdivide(&m, &options(levels, Boundary::EdgeOnly)).unwrap();
            (v, f) = (v + f, 3 * f);
            assert_eq!(out.positions.len(), v, "{name} level {levels} vertices");
            assert_eq!(out.face_count(), f, "{name} level {levels} faces");
            assert_eq!(euler(&out), chi, "{name} level {levels}");
            assert_oriented(&out, true);
            println!("{name} level {levels}: {v} vertices, {f} faces, χ = {chi}");
        }
    }
}

#[test]
fn every_face_turns_like_its_parent_on_convex_meshes() {
    for (name, cage) in [
        ("tetrahedron", tetrahedron()),
        ("octahedron", octahedron()),
        ("icosahedron", icosahedron()),
    ] {
        let mut m = cage;
        let mut worst = f64::INFINITY;
        for _ in 0..3 {
            let (level, out) = refine(&m, Boundary::EdgeOnly);
            assert_eq!(level.face_parent.len(), out.face_count());
            for (f, c) in out.faces().enumerate() {
                let parent = m.face(level.face_parent[f] as usize);
                let (n, np) = (normal(&out, c), normal(&m, parent));
                let cos = dot(n, np) / (norm(n) * norm(np));
                worst = worst.min(cos);
                let centre = c.iter().fold([0.0; 3], |s, &v| {
                    add(s, p64(out.positions[v as usize]), 1.0)
                });
                assert!(cos > 0.0, "{name}: face {f} turns against its parent");
                assert!(dot(n, centre) > 0.0, "{name}: face {f} points inward");
            }
            m = out;
        }
        println!("{name}: smallest cosine between a face's normal and its parent's {worst:.3}");
    }
}

#[test]
fn regular_vertices_keep_two_thirds_and_take_one_eighteenth_of_each_neighbour() {
    let (cage, neighbours) = torus(7, 6);
    let (level, _) = refine(&cage, Boundary::EdgeOnly);
    assert!((sqrt3::alpha(6) - 1.0 / 3.0).abs() < 1e-12);
    for (v, ns) in neighbours.iter().enumerate() {
        let row: HashMap<u32, f32> = level.table.row(v).collect();
        assert_eq!(row.len(), 7, "vertex {v}");
        assert!((row[&(v as u32)] - 2.0 / 3.0).abs() < 1e-6, "vertex {v}");
        for n in ns {
            assert!(
                (row[n] - 1.0 / 18.0).abs() < 1e-6,
                "vertex {v}, neighbour {n}"
            );
        }
    }
    // Face points are centroids.
    let nv = cage.positions.len();
    for (f, c) in cage.faces().enumerate() {
        let row: HashMap<u32, f32> = level.table.row(nv + f).collect();
        assert!(c.iter().all(|v| (row[v] - 1.0 / 3.0).abs() < 1e-6));
        assert_eq!(row.len(), 3);
    }
}

#[test]
fn two_levels_are_the_triadic_split() {
    let ico = icosahedron();
    let out = subdivide(&ico, &options(2, Boundary::EdgeOnly)).unwrap();
    // Each edge in three, one new vertex inside each face: V + 2E + F = 12 + 60 + 20.
    assert_eq!((out.positions.len(), out.face_count()), (92, 180));

    // On a regular planar grid, away from the boundary, the vertices of two levels are
    // exactly the lattice of a third of the spacing.
    let (w, h) = (10u32, 10u32);
    let grid = triangle_grid(w, h);
    let out = subdivide(&grid, &options(2, Boundary::EdgeOnly)).unwrap();
    let s3 = 3f64.sqrt();
    let (lo, hi) = (2.0, (w - 3) as f64);
    let mut seen = HashMap::new();
    for (i, p) in out.positions.iter().enumerate() {
        let (x, y) = (f64::from(p[0]), f64::from(p[1]));
        let b = y * 2.0 / s3;
        let a = x - b / 2.0;
        if a < lo - 0.1 || a > hi + 0.1 || b < lo - 0.1 || b > hi + 0.1 {
            continue;
        }
        let (ta, tb) = ((3.0 * a).round(), (3.0 * b).round());
        assert!(
            (3.0 * a - ta).abs() < 1e-4 && (3.0 * b - tb).abs() < 1e-4,
            "vertex {i} at {p:?} is off the lattice"
        );
        if (lo..=hi).contains(&(ta / 3.0)) && (lo..=hi).contains(&(tb / 3.0)) {
            assert!(
                seen.insert((ta as i64, tb as i64), i).is_none(),
                "vertex {i} twice"
            );
        }
    }
    let side = (3.0 * (hi - lo)) as usize + 1;
    assert_eq!(seen.len(), side * side, "every lattice point is a vertex");
}

#[test]
fn icosahedron_vertices_move_to_one_radius() {
    let ico = icosahedron();
    let (level, out) = refine(&ico, Boundary::EdgeOnly);
    assert_rows_sum_to_one(&level);
    let a5 = (4.0 - 2.0 * (2.0 * PI / 5.0).cos()) / 9.0;
    let edge = dist(p64(ico.positions[0]), p64(ico.positions[1])).min(
        (2..12)
            .map(|j| dist(p64(ico.positions[0]), p64(ico.positions[j])))
            .fold(f64::INFINITY, f64::min),
    );
    let mut radii = Vec::new();
    for v in 0..12 {
        let p = p64(ico.positions[v]);
        let ring: Vec<P> = (0..12)
            .map(|j| p64(ico.positions[j]))
            .filter(|&q| (dist(p, q) - edge).abs() < 1e-5)
            .collect();
        assert_eq!(ring.len(), 5);
        let mean = ring.iter().fold([0.0; 3], |s, &q| add(s, q, 0.2));
        let want = add(p.map(|x| (1.0 - a5) * x), mean, a5);
        let got = p64(out.positions[v]);
        assert!(dist(got, want) < 1e-5, "vertex {v}: {got:?} vs {want:?}");
        radii.push(norm(got));
    }
    let face_radii: Vec<f64> = out.positions[12..].iter().map(|&p| norm(p64(p))).collect();
    assert_eq!(face_radii.len(), 20);
    for r in [&radii, &face_radii] {
        let spread = r.iter().fold(0.0f64, |m, &x| m.max((x - r[0]).abs()));
        assert!(spread < 1e-5, "radii {r:?}");
    }
    println!(
        "icosahedron (radius {:.6}): vertices to {:.6}, face points at {:.6}",
        norm(p64(ico.positions[0])),
        radii[0],
        face_radii[0]
    );
}

#[test]
fn rows_sum_to_one() {
    let creased_octahedron = creased(octahedron(), &[(0, 1, 2.5)]);
    for m in [
        tetrahedron(),
        icosahedron(),
        torus(4, 5).0,
        triangle_grid(4, 3),
        creased_octahedron,
    ] {
        assert_two_levels_sum_to_one(&m, refine);
    }
}

#[test]
fn open_mesh_stays_planar_and_its_boundary_is_a_cubic_b_spline() {
    // The regular grid moved about within a tilted plane.
    let mut cage = triangle_grid(5, 4);
    for p in &mut cage.positions {
        let (x, y) = (f64::from(p[0]), f64::from(p[1]));
        let (x, y) = (x + 0.2 * (1.3 * y).sin(), y + 0.1 * (2.1 * x).cos());
        *p = on_plane(x, y);
    }
    let [o, u, v] = PLANE;
    let plane = cross(u, v);
    for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
        let keep = boundary == Boundary::EdgeAndCorner;
        let mut want = boundary_polygon(&cage, keep);
        assert_eq!(
            want.iter().filter(|w| w.1).count(),
            if keep { 2 } else { 0 }
        );
        let (mut f, mut b) = (cage.face_count(), want.len());
        for levels in 1..=3 {
            want = cubic_bspline(&want);
            let out = subdivide(&cage, &options(levels, boundary)).unwrap();
            // Three triangles per triangle and one more per boundary edge, which splits.
            (f, b) = (3 * f + b, 2 * b);
            assert_eq!(out.face_count(), f, "{boundary:?} level {levels}");
            assert_eq!(euler(&out), 1, "a disc");
            let off = off_plane(&out, o, plane);
            assert!(
                off < 1e-5,
                "{boundary:?} level {levels}: {off} off the plane"
            );
            for c in out.faces() {
                assert!(dot(normal(&out, c), plane) > 0.0, "a face turned over");
            }
            let got = boundary_loop_points(&out);
            let want_pts: Vec<P> = want.iter().map(|w| w.0).collect();
            assert_same_loop(&got, &want_pts, true, 1e-5);
            print_open_level(boundary, levels, &out, got.len());
        }
    }
}

#[test]
fn sharp_crease_is_a_cubic_b_spline_curve() {
    let mut cage = octahedron();
    let around: Vec<u32> = (0..6)
        .filter(|&v| cage.positions[v][2] == 0.0)
        .map(|v| v as u32)
        .collect();
    let equator: Vec<(u32, u32)> = (0..4)
        .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
        .map(|(i, j)| (around[i], around[j]))
        .filter(|&(a, b)| {
            dist(
                p64(cage.positions[a as usize]),
                p64(cage.positions[b as usize]),
            ) < 1.5
        })
        .collect();
    assert_eq!(equator.len(), 4);
    cage.creases = equator
        .iter()
        .map(|&(a, b)| Crease { a, b, value: 10.0 })
        .collect();
    let mut want: Vec<(P, bool)> = edge_loop(&equator)
        .iter()
        .map(|&v| (p64(cage.positions[v as usize]), false))
        .collect();
    let mut f = cage.face_count();
    for levels in 1..=3 {
        want = cubic_bspline(&want);
        let out = subdivide(&cage, &options(levels, Boundary::EdgeOnly)).unwrap();
        // Both faces of a crease edge split it.
        f = 3 * f + 2 * (out.creases.len() / 2);
        assert_eq!(out.face_count(), f, "level {levels}");
        assert_eq!(euler(&out), 2);
        assert_oriented(&out, true);
        assert!(out.creases.iter().all(|c| c.value == 10.0));
        let edges: Vec<(u32, u32)> = out.creases.iter().map(|c| (c.a, c.b)).collect();
        let got: Vec<P> = edge_loop(&edges)
            .iter()
            .map(|&v| p64(out.positions[v as usize]))
            .collect();
        assert!(
            got.iter().all(|p| p[2].abs() < 1e-6),
            "the crease stays flat"
        );
        let want_pts: Vec<P> = want.iter().map(|w| w.0).collect();
        assert_same_loop(&got, &want_pts, false, 1e-5);
        println!("crease level {levels}: {} points, {f} faces", got.len());
    }
}

#[test]
fn semi_sharp_creases_lose_one_per_level() {
    let ico = icosahedron();
    let (a, b) = (ico.face(0)[0], ico.face(0)[1]);
    let cage = creased(ico, &[(a, b, 2.0)]);
    let (_, one) = refine(&cage, Boundary::EdgeOnly);
    assert_eq!(one.creases.len(), 2, "both halves");
    assert!(one.creases.iter().all(|c| c.value == 1.0));
    for c in &one.creases {
        assert!([c.a, c.b].contains(&a) != [c.a, c.b].contains(&b), "{c:?}");
    }
    let (_, two) = refine(&one, Boundary::EdgeOnly);
    assert!(two.creases.is_empty());
    let through = subdivide(&cage, &options(2, Boundary::EdgeOnly)).unwrap();
    assert_eq!(through.positions, two.positions);
    assert_eq!(through.face_indices, two.face_indices);
}

#[test]
fn corner_of_one_face_keeps_a_single_face() {
    let cage = mesh(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[vec![0, 1, 2]],
    );
    for levels in 1..=3 {
        let out = subdivide(&cage, &options(levels, Boundary::EdgeAndCorner)).unwrap();
        for v in 0..3u32 {
            assert_eq!(out.positions[v as usize], cage.positions[v as usize]);
            assert_eq!(out.faces().filter(|c| c.contains(&v)).count(), 1);
        }
        assert_oriented(&out, false);
        assert_eq!(euler(&out), 1);
    }
}

#[test]
fn non_triangles_are_refused() {
    let quad = unit_quad();
    let want = SubdivError::NotTriangles {
        scheme: "sqrt3",
        face: 0,
        corners: 4,
    };
    assert_eq!(
        subdivide(&quad, &options(1, Boundary::EdgeOnly)).unwrap_err(),
        want
    );
    let faces = faces_of(&quad);
    let topo = Topology::build(&faces, &[]).unwrap();
    assert_eq!(
        sqrt3::refine(&faces, &topo, Boundary::EdgeOnly).unwrap_err(),
        want
    );
}

#[test]
fn inconsistent_orientation_is_named() {
    assert_misorientation_named(Scheme::Sqrt3);
}
