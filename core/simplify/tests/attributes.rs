//! Generic attributes, sharp edges and creases through simplification, checked against
//! quantities the output can be measured by:
//!
//! - with uniform weights and barycentre representatives, an output vertex is the plain mean
//!   of its cluster's vertices, exactly what a point attribute gets — so `point:x` = x;
//! - a constant corner attribute stays that constant;
//! - `face:id` names a source face, so every output vertex of the face lies within the
//!   reported `max_displacement` of one of that source face's corners;
//! - sharp edges (and creases on the same edges) land on output face edges near sharp input
//!   edges.
//!
//! On a mesh built here (always) and on shared meshes (the Stanford bunny, and Spot's quads
//! for the fan triangulation), skipped when the data folder is missing.

use std::collections::HashSet;
use tessd_mesh::io::{ReadOptions, read_path};
use tessd_mesh::{Attribute, Crease, Domain, Mesh};
use tessd_simplify::{
    Count, GridSize, Length, Method, Representative, SimplifyOptions, Weighting, simplify,
};

/// A mesh of the shared test data (`$TESSD_SHARED_DATA`, else `../shared/data` beside the
/// repository), asserted to exist: a missing file fails the test rather than skipping it.
fn shared(name: &str) -> Mesh {
    read_path(
        &tessd_testdata::shared(&format!("mesh/{name}")),
        &ReadOptions::default(),
    )
    .unwrap()
}

/// A bumpy open grid of quads (n × n), some faces split into triangles.
fn bumpy_grid(n: u32) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions
                .push([x, y, 0.1 * (6.0 * x).sin() * (5.0 * y).cos()]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            if (i + j) % 5 == 0 {
                m.push_face(&[v, v + 1, v + n + 2]);
                m.push_face(&[v, v + n + 2, v + n + 1]);
            } else {
                m.push_face(&[v, v + 1, v + n + 2, v + n + 1]);
            }
        }
    }
    m
}

/// Sharp edges: every face edge crossing the plane x = `at` (a band across the mesh), or with
/// `along`, every face edge with both ends within 1e-6 of that plane (a feature line).
fn sharp_edges(m: &Mesh, at: f32, along: bool) -> Vec<[u32; 2]> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for f in m.faces() {
        for (k, &a) in f.iter().enumerate() {
            let b = f[(k + 1) % f.len()];
            let (xa, xb) = (m.positions[a as usize][0], m.positions[b as usize][0]);
            let pick = if along {
                (xa - at).abs() < 1e-6 && (xb - at).abs() < 1e-6
            } else {
                (xa - at) * (xb - at) < 0.0
            };
            if pick && seen.insert((a.min(b), a.max(b))) {
                out.push([a, b]);
            }
        }
    }
    out
}

/// The mesh with `point:x` (x of each vertex), `point:xyz` (the position, 3 components),
/// `corner:uvmap2` (constant, 2 components), `face:id` (the face index), sharp edges and
/// creases of value 2 on the same edges (the edges of [`sharp_edges`] through the middle of
/// the bounding box).
fn with_attributes(mut m: Mesh, along: bool) -> Mesh {
    let x: Vec<f32> = m.positions.iter().map(|p| p[0]).collect();
    let xyz: Vec<f32> = m.positions.as_flattened().to_vec();
    let corners = m.face_indices.len();
    let uv: Vec<f32> = (0..corners).flat_map(|_| [0.25f32, -2.0]).collect();
    let id: Vec<f32> = (0..m.face_count()).map(|f| f as f32).collect();
    m.attributes = vec![
        Attribute::new("x", Domain::Point, 1, x),
        Attribute::new("xyz", Domain::Point, 3, xyz),
        Attribute::new("uvmap2", Domain::Corner, 2, uv),
        Attribute::new("id", Domain::Face, 1, id),
    ];
    let (lo, hi) = m.bounds().unwrap();
    let at = 0.5 * (lo[0] + hi[0]) + if along { 0.0 } else { 1e-4 };
    m.sharp_edges = sharp_edges(&m, at, along);
    assert!(m.sharp_edges.len() > 10);
    m.creases = m
        .sharp_edges
        .iter()
        .map(|&[a, b]| Crease { a, b, value: 2.0 })
        .collect();
    m.validate().unwrap();
    m
}

fn attribute<'a>(m: &'a Mesh, name: &str) -> &'a Attribute {
    m.attributes
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no attribute {name}"))
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (f64::from(a[k]) - f64::from(b[k])).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn check(input: &Mesh, method: Method, what: &str) {
    let options = SimplifyOptions::new(method)
        .with_weighting(Weighting::Uniform)
        .with_representative(Representative::Barycenter);
    let s = simplify(input, &options, &mut |_, _| true).unwrap();
    let out = &s.mesh;
    out.validate().unwrap();
    assert!(
        out.face_count() > 10,
        "{what}: {} faces left",
        out.face_count()
    );
    assert_eq!(out.attributes.len(), 4, "{what}");

    // point:x = x and point:xyz = the position, vertex by vertex.
    let x = attribute(out, "x");
    let xyz = attribute(out, "xyz");
    assert_eq!(x.rows(), out.vertex_count(), "{what}");
    for (v, p) in out.positions.iter().enumerate() {
        assert!(
            (x.row(v)[0] - p[0]).abs() <= 1e-5,
            "{what}: vertex {v}: {} vs {p:?}",
            x.row(v)[0]
        );
        for (a, b) in xyz.row(v).iter().zip(p) {
            assert!((a - b).abs() <= 1e-5, "{what}: vertex {v} xyz");
        }
    }

    // The constant corner attribute, one row per output corner.
    let uv = attribute(out, "uvmap2");
    assert_eq!(uv.rows(), out.face_indices.len(), "{what}");
    assert!(
        uv.values.chunks(2).all(|r| r == [0.25, -2.0]),
        "{what}: uvmap2 changed"
    );

    // face:id names a source face whose corners moved onto the output face.
    let id = attribute(out, "id");
    assert_eq!(id.rows(), out.face_count(), "{what}");
    let reach = s.report.max_displacement * (1.0 + 1e-6) + 1e-6;
    for (f, face) in out.faces().enumerate() {
        let src = id.row(f)[0];
        assert_eq!(src.fract(), 0.0, "{what}: face {f} id {src}");
        let src = input.face(src as usize);
        for &v in face {
            let p = out.positions[v as usize];
            let near = src
                .iter()
                .map(|&u| dist(p, input.positions[u as usize]))
                .fold(f64::INFINITY, f64::min);
            assert!(
                near <= reach,
                "{what}: face {f} vertex {v} is {near} from its source face (max displacement {})",
                s.report.max_displacement
            );
        }
    }

    // Sharp edges: output face edges, each near a sharp input edge; creases on the same edges.
    assert!(!out.sharp_edges.is_empty(), "{what}: no sharp edge left");
    let out_edges: HashSet<(u32, u32)> = out
        .faces()
        .flat_map(|f| (0..f.len()).map(move |k| (f[k], f[(k + 1) % f.len()])))
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    let key = |[a, b]: [u32; 2]| (a.min(b), a.max(b));
    for &e in &out.sharp_edges {
        assert!(
            out_edges.contains(&key(e)),
            "{what}: sharp edge {e:?} is no face edge"
        );
        let (pa, pb) = (out.positions[e[0] as usize], out.positions[e[1] as usize]);
        let near = input
            .sharp_edges
            .iter()
            .map(|&[a, b]| {
                let (qa, qb) = (input.positions[a as usize], input.positions[b as usize]);
                dist(pa, qa)
                    .max(dist(pb, qb))
                    .min(dist(pa, qb).max(dist(pb, qa)))
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            near <= reach,
            "{what}: sharp edge {e:?} is {near} from every input sharp edge"
        );
    }
    let sharp: HashSet<_> = out.sharp_edges.iter().map(|&e| key(e)).collect();
    assert_eq!(
        sharp.len(),
        out.sharp_edges.len(),
        "{what}: repeated sharp edges"
    );
    let creased: HashSet<_> = out.creases.iter().map(|c| key([c.a, c.b])).collect();
    assert_eq!(sharp, creased, "{what}: creases and sharp edges differ");
    assert!(out.creases.iter().all(|c| c.value == 2.0), "{what}");
}

fn methods() -> [(Method, &'static str); 3] {
    [
        (Method::Grid(GridSize::CellsPerAxis(12)), "grid"),
        (Method::Quality(Length::Relative(0.02)), "quality"),
        (Method::Complexity(Count::Relative(0.1)), "complexity"),
    ]
}

#[test]
fn attributes_follow_clusters_on_a_built_mesh() {
    let m = with_attributes(bumpy_grid(40), true);
    for (method, name) in methods() {
        check(&m, method, name);
    }
}

#[test]
fn attributes_follow_clusters_on_the_bunny() {
    let m = shared("stanford_bunny.obj");
    let m = with_attributes(m, false);
    for (method, name) in methods() {
        check(&m, method, &format!("bunny {name}"));
    }
}

#[test]
fn attributes_survive_the_fan_triangulation_of_quads() {
    // Spot's quads: the quality and complexity goals triangulate first.
    let m = shared("spot_quadrangulated.obj");
    assert!(m.faces().all(|f| f.len() == 4));
    let m = with_attributes(Mesh { uvs: None, ..m }, false);
    for (method, name) in methods() {
        check(&m, method, &format!("spot {name}"));
    }
}

#[test]
fn a_mesh_without_extras_gets_none() {
    let m = bumpy_grid(20);
    let options = SimplifyOptions::new(Method::Complexity(Count::Relative(0.2)));
    let s = simplify(&m, &options, &mut |_, _| true).unwrap();
    assert!(s.mesh.attributes.is_empty() && s.mesh.sharp_edges.is_empty());
    assert!(s.mesh.creases.is_empty());
}

#[test]
fn lod_levels_carry_attributes() {
    let m = with_attributes(bumpy_grid(30), true);
    let options = SimplifyOptions::new(Method::Complexity(Count::Relative(0.5)))
        .with_weighting(Weighting::Uniform);
    let levels = [
        Method::Complexity(Count::Relative(0.5)),
        Method::Complexity(Count::Relative(0.1)),
    ];
    let chain = tessd_simplify::lod::lod_chain(&m, &levels, &options, &mut |_, _| true).unwrap();
    for s in &chain {
        let x = attribute(&s.mesh, "x");
        for (v, p) in s.mesh.positions.iter().enumerate() {
            assert!((x.row(v)[0] - p[0]).abs() <= 1e-5);
        }
        assert!(!s.mesh.sharp_edges.is_empty());
    }
}
