//! Doo–Sabin: counts, the biquadratic B-spline on regular quads, the halving of regular
//! n-gons, symmetry, orientation, and the Chaikin boundary, each expected value computed here
//! from the cage, not read back from the scheme.

use tessd_mesh::Mesh;
use tessd_subdiv::{Boundary, Level, Scheme, SubdivOptions, doo_sabin, subdivide};

mod common;
use common::{
    P, PLANE, add, assert_misorientation_named, assert_oriented, assert_rows_sum_to_one,
    assert_two_levels_sum_to_one, boundary_loop_points, boundary_polygon, creased, cross, dist,
    euler, mesh, norm, off_plane, on_plane, p64, print_open_level, refine_with,
};

fn options(levels: u32, boundary: Boundary) -> SubdivOptions {
    common::options(Scheme::DooSabin, levels, boundary)
}

/// One level through `refine` directly, with the new positions.
fn refine(m: &Mesh, boundary: Boundary) -> (Level, Mesh) {
    refine_with(m, |faces, topo| doo_sabin::refine(faces, topo, boundary))
}

/// `got` is `want` up to where the loop starts.
fn assert_same_loop(got: &[P], want: &[P], tol: f64) {
    assert_eq!(got.len(), want.len(), "loop lengths");
    let r = (0..want.len())
        .min_by(|&i, &j| dist(got[0], want[i]).total_cmp(&dist(got[0], want[j])))
        .unwrap();
    for (i, g) in got.iter().enumerate() {
        let w = want[(i + r) % want.len()];
        assert!(dist(*g, w) < tol, "loop point {i}: {g:?} vs {w:?}");
    }
}

/// One Chaikin step of a closed polygon; points flagged `true` are corners, kept and
/// inserted between their edges' two points.
fn chaikin(poly: &[(P, bool)]) -> Vec<(P, bool)> {
    let n = poly.len();
    let mut out = Vec::with_capacity(3 * n);
    for i in 0..n {
        let (a, corner) = poly[i];
        let b = poly[(i + 1) % n].0;
        if corner {
            out.push((a, true));
        }
        out.push((add(a.map(|x| 0.75 * x), b, 0.25), false));
        out.push((add(a.map(|x| 0.25 * x), b, 0.75), false));
    }
    out
}

fn cube() -> Mesh {
    let positions = (0..8)
        .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { 1.0 } else { -1.0 }))
        .collect();
    // Outward (counter-clockwise seen from outside); vertex i has x = bit 0, y = bit 1, z = bit 2.
    let faces = [
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ];
    mesh(positions, &faces)
}

/// A prism over a regular `n`-gon: top cap, bottom cap, then the sides (outward).
fn prism(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for z in [-1.0f32, 1.0] {
        for i in 0..n {
            let a = 2.0 * std::f32::consts::PI * i as f32 / n as f32;
            positions.push([a.cos(), a.sin(), z]);
        }
    }
    let mut faces = vec![(n..2 * n).collect::<Vec<_>>(), (0..n).rev().collect()];
    faces.extend((0..n).map(|i| vec![i, (i + 1) % n, n + (i + 1) % n, n + i]));
    mesh(positions, &faces)
}

/// An `m` × `n` quad grid on a torus (every vertex of valence 4).
fn torus(m: u32, n: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..m {
        for j in 0..n {
            let (u, v) = (
                2.0 * std::f32::consts::PI * i as f32 / m as f32,
                2.0 * std::f32::consts::PI * j as f32 / n as f32,
            );
            let r = 3.0 + v.cos();
            positions.push([r * u.cos(), r * u.sin(), v.sin()]);
        }
    }
    let id = |i: u32, j: u32| (i % m) * n + j % n;
    let faces: Vec<Vec<u32>> = (0..m)
        .flat_map(|i| {
            (0..n).map(move |j| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
        })
        .collect();
    mesh(positions, &faces)
}

/// A `w` × `h` vertex quad grid in a tilted plane, moved about within the plane.
fn planar_grid(w: u32, h: u32) -> (Mesh, P, P) {
    let mut positions = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (x, y) = (
                i as f64 + 0.2 * (1.7 * j as f64 + i as f64).sin(),
                j as f64 + 0.15 * (2.3 * i as f64).cos(),
            );
            positions.push(on_plane(x, y));
        }
    }
    let faces: Vec<Vec<u32>> = (0..h - 1)
        .flat_map(|j| {
            (0..w - 1).map(move |i| {
                vec![
                    j * w + i,
                    j * w + i + 1,
                    (j + 1) * w + i + 1,
                    (j + 1) * w + i,
                ]
            })
        })
        .collect();
    (mesh(positions, &faces), PLANE[0], cross(PLANE[1], PLANE[2]))
}

#[test]
fn cube_counts_and_points() {
    let (level, out) = refine(&cube(), Boundary::EdgeOnly);
    assert_eq!(out.positions.len(), 24);
    assert_eq!(out.face_count(), 6 + 12 + 8);
    let sizes: Vec<usize> = out.faces().map(<[u32]>::len).collect();
    assert!(sizes[..18].iter().all(|&s| s == 4) && sizes[18..].iter().all(|&s| s == 3));
    assert_oriented(&out, true);
    assert_rows_sum_to_one(&level);
    assert!(level.creases.is_empty());
    // Corner (1, 1, 1) of the face z = 1: 9/16 of it, 3/16 of each neighbour, 1/16 of the
    // opposite corner, i.e. (1/2, 1/2, 1) and its images; all at √1.5 from the centre.
    for p in &out.positions {
        let mut a = p64(*p).map(f64::abs);
        a.sort_by(f64::total_cmp);
        assert!(dist(a, [0.5, 0.5, 1.0]) < 1e-6, "{p:?}");
    }
    let through = subdivide(&cube(), &options(1, Boundary::EdgeOnly)).unwrap();
    assert_eq!(through.positions, out.positions);
    assert_eq!(through.face_indices, out.face_indices);
}

#[test]
fn euler_characteristic_is_kept_on_closed_meshes() {
    for (name, m, chi) in [
        ("cube", cube(), 2),
        ("pentagonal prism", prism(5), 2),
        ("heptagonal prism", prism(7), 2),
        ("torus", torus(6, 5), 0),
    ] {
        assert_eq!(euler(&m), chi, "{name} cage");
        let (mut v, mut e, mut f) = (m.positions.len(), m.face_indices.len() / 2, m.face_count());
        for levels in 1..=3 {
            let out = subdivide(&m, &options(levels, Boundary::EdgeOnly)).unwrap();
            assert_eq!(euler(&out), chi, "{name} level {levels}");
            assert_oriented(&out, true);
            // One point per corner; an F-face per face, an E-face per edge, a V-face per vertex.
            (v, e, f) = (2 * e, 4 * e, f + e + v);
            assert_eq!(out.positions.len(), v, "{name} level {levels} vertices");
            assert_eq!(out.face_count(), f, "{name} level {levels} faces");
            println!(
                "{name} level {levels}: {} vertices, {} faces, χ = {chi}",
                out.positions.len(),
                out.face_count()
            );
        }
    }
}

/// The biquadratic B-spline corner point of corner `k` of quad `c`.
fn biquadratic(m: &Mesh, c: &[u32], k: usize) -> P {
    let p = |i: usize| p64(m.positions[c[(k + i) % 4] as usize]);
    let mut out = p(0).map(|x| 9.0 / 16.0 * x);
    out = add(out, p(1), 3.0 / 16.0);
    out = add(out, p(3), 3.0 / 16.0);
    add(out, p(2), 1.0 / 16.0)
}

#[test]
fn regular_quads_give_the_biquadratic_b_spline() {
    let cage = torus(8, 6);
    let one = subdivide(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
    let two = subdivide(&cage, &options(2, Boundary::EdgeOnly)).unwrap();
    let mut worst: f64 = 0.0;
    for (m, next) in [(&cage, &one), (&one, &two)] {
        assert!(m.faces().all(|c| c.len() == 4), "still a regular quad mesh");
        for (f, c) in m.faces().enumerate() {
            for k in 0..4 {
                let got = p64(next.positions[m.face_offsets[f] as usize + k]);
                worst = worst.max(dist(got, biquadratic(m, c, k)));
            }
        }
    }
    println!("torus: largest distance to the biquadratic corner points {worst:.2e}");
    assert!(worst < 1e-5);
}

#[test]
fn regular_polygons_shrink_by_half_about_their_centre() {
    for n in [3, 5, 6, 7, 9] {
        let cage = prism(n);
        let (level, out) = refine(&cage, Boundary::EdgeOnly);
        assert_rows_sum_to_one(&level);
        assert_oriented(&out, true);
        for (f, c) in cage.faces().enumerate() {
            let centre = c.iter().fold([0.0; 3], |s, &v| {
                add(s, p64(cage.positions[v as usize]), 1.0 / c.len() as f64)
            });
            for (k, &v) in c.iter().enumerate() {
                let want = add(
                    centre,
                    add(p64(cage.positions[v as usize]), centre, -1.0),
                    0.5,
                );
                let got = p64(out.positions[cage.face_offsets[f] as usize + k]);
                assert!(dist(got, want) < 1e-6, "n = {n}, face {f}, corner {k}");
            }
        }
    }
}

#[test]
fn cube_refinements_keep_the_cube_symmetries() {
    let out = subdivide(&cube(), &options(2, Boundary::EdgeOnly)).unwrap();
    assert_eq!(out.positions.len(), 96);
    let pts: Vec<P> = out.positions.iter().map(|&p| p64(p)).collect();
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut classes: Vec<Vec<usize>> = Vec::new();
    let mut class_of = vec![usize::MAX; pts.len()];
    for (i, p) in pts.iter().enumerate() {
        if class_of[i] == usize::MAX {
            class_of[i] = classes.len();
            classes.push(vec![i]);
        }
        for perm in perms {
            for signs in 0..8 {
                let q: P = [0, 1, 2].map(|k| {
                    let s = if signs >> k & 1 == 1 { -1.0 } else { 1.0 };
                    s * p[perm[k]]
                });
                let j = (0..pts.len())
                    .find(|&j| dist(pts[j], q) < 1e-5)
                    .unwrap_or_else(|| panic!("the image {q:?} of point {i} is missing"));
                if class_of[j] == usize::MAX {
                    class_of[j] = class_of[i];
                    classes[class_of[i]].push(j);
                }
            }
        }
    }
    // Corners of F-, E- and V-faces of the first level: 24, 48 and 24 points.
    let mut sizes: Vec<usize> = classes.iter().map(Vec::len).collect();
    sizes.sort_unstable();
    assert_eq!(sizes, [24, 24, 48]);
    for class in &classes {
        let r = norm(pts[class[0]]);
        assert!(class.iter().all(|&i| (norm(pts[i]) - r).abs() < 1e-6));
        println!("{} points at distance {r:.6}", class.len());
    }
}

#[test]
fn face_parents_are_faces_they_take_points_from() {
    let cage = prism(5);
    let (level, out) = refine(&cage, Boundary::EdgeOnly);
    let corner_face: Vec<u32> = (0..cage.face_count())
        .flat_map(|f| std::iter::repeat_n(f as u32, cage.face(f).len()))
        .collect();
    for (f, c) in out.faces().enumerate() {
        let from: Vec<u32> = c.iter().map(|&v| corner_face[v as usize]).collect();
        if f < cage.face_count() {
            assert_eq!(level.face_parent[f], f as u32);
            assert!(from.iter().all(|&g| g == f as u32));
        } else {
            assert_eq!(
                level.face_parent[f],
                *from.iter().min().unwrap(),
                "face {f}"
            );
        }
    }
}

#[test]
fn open_grid_stays_planar_and_its_boundary_is_chaikin() {
    let (cage, origin, normal) = planar_grid(5, 4);
    for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
        let keep = boundary == Boundary::EdgeAndCorner;
        let mut want = boundary_polygon(&cage, keep);
        assert_eq!(
            want.iter().filter(|w| w.1).count(),
            if keep { 4 } else { 0 }
        );
        for levels in 1..=3 {
            want = chaikin(&want);
            let out = subdivide(&cage, &options(levels, boundary)).unwrap();
            assert_eq!(euler(&out), 1, "a disc");
            let off = off_plane(&out, origin, normal);
            assert!(
                off < 1e-5,
                "{boundary:?} level {levels}: {off} off the plane"
            );
            let got = boundary_loop_points(&out);
            assert_same_loop(&got, &want.iter().map(|w| w.0).collect::<Vec<_>>(), 1e-5);
            print_open_level(boundary, levels, &out, got.len());
        }
    }
}

#[test]
fn single_quad_counts() {
    let (cage, _, _) = planar_grid(2, 2);
    let (level, out) = refine(&cage, Boundary::EdgeOnly);
    // 4 corner points and 2 Chaikin points per boundary edge; 1 F-, 4 E-, 4 V-faces.
    assert_eq!((out.positions.len(), out.face_count()), (12, 9));
    assert_rows_sum_to_one(&level);
    let (level, out) = refine(&cage, Boundary::EdgeAndCorner);
    assert_eq!((out.positions.len(), out.face_count()), (16, 9));
    assert_rows_sum_to_one(&level);
    for v in 0..4 {
        assert_eq!(out.positions[12 + v], cage.positions[v], "corner {v} kept");
    }
}

#[test]
fn bowtie_vertex_is_kept_as_a_corner() {
    // Two triangles meeting at vertex 0 only.
    let positions = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    let cage = mesh(positions, &[vec![0, 1, 2], vec![0, 3, 4]]);
    let (level, out) = refine(&cage, Boundary::EdgeOnly);
    assert_rows_sum_to_one(&level);
    assert_oriented(&out, false);
    let kept: Vec<usize> = (0..out.positions.len())
        .filter(|&v| out.positions[v] == [0.0; 3])
        .collect();
    assert_eq!(kept.len(), 1);
    let faces_at = out
        .faces()
        .filter(|c| c.contains(&(kept[0] as u32)))
        .count();
    assert_eq!(faces_at, 2, "both V-faces at the bowtie share its point");
}

#[test]
fn rows_sum_to_one_on_mixed_polygons() {
    let (grid, _, _) = planar_grid(4, 3);
    for m in [cube(), prism(8), torus(4, 3), grid] {
        assert_two_levels_sum_to_one(&m, refine);
    }
}

#[test]
fn creases_are_ignored() {
    let cage = creased(cube(), &[(0, 2, 10.0)]);
    let (level, out) = refine(&cage, Boundary::EdgeOnly);
    assert!(level.creases.is_empty());
    assert_eq!(
        out.positions,
        refine(&cube(), Boundary::EdgeOnly).1.positions
    );
    let through = subdivide(&cage, &options(2, Boundary::EdgeOnly)).unwrap();
    assert!(through.creases.is_empty());
}

#[test]
fn inconsistent_orientation_is_named() {
    // Both faces run edge (1, 2) from 1 to 2.
    let err = assert_misorientation_named(Scheme::DooSabin);
    println!("{err}");
}

#[test]
fn interior_vertices_of_two_faces_get_no_v_face() {
    // Two quads back to back: every vertex is interior with two faces. Their V-faces would be
    // two-point faces; without them the result is a closed box of 2 F-faces and 4 E-faces.
    let pillow = mesh(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        &[vec![0, 1, 2, 3], vec![3, 2, 1, 0]],
    );
    let (_, out) = refine(&pillow, Boundary::EdgeOnly);
    assert_eq!(out.face_count(), 6);
    assert!(out.faces().all(|f| f.len() == 4));
    assert_oriented(&out, true);
    assert_eq!(euler(&out), 2);
    // Suzanne (open, with one interior vertex of two faces) refines to a valid mesh, levels 1–2.
    let suzanne = common::read_mesh("mesh/suzanne.obj");
    for levels in 1..=2 {
        let m = subdivide(&suzanne, &options(levels, Boundary::EdgeOnly)).unwrap();
        m.validate().unwrap();
        assert!(m.faces().all(|f| f.len() >= 3));
        assert_oriented(&m, false);
    }
}
