//! Generic attributes and sharp edges through refinement, on a cube centred at the origin
//! whose 12 edges are all sharp:
//!
//! - `point:x` = x: vertex stencils are affine combinations (rows sum to 1), so the refined
//!   attribute is the refined vertex's x, for every scheme;
//! - `face:id` = the face index: each refined face lies on its cage face's side of the cube
//!   (the largest coordinate of its centroid points along that face's normal);
//! - sharp edges: 12 × 2^levels, all on the cube's edges (bilinear: both ends on one cube
//!   edge; Catmull–Clark: ends in the cube's symmetry planes through that edge);
//! - `corner:` attributes: a constant stays constant; a corner value equal to its vertex's x
//!   (no seam) stays equal to the refined vertex's x, and with linear face-varying rules to
//!   the bilinear refinement's.

use tessd_mesh::{Attribute, Domain, Mesh};
use tessd_subdiv::{Scheme, SubdivOptions, UvInterpolation, attributes::dropped, subdivide};

/// The cube [-0.5, 0.5]³ with outward quads, `point:x`, `face:id`, a constant
/// `corner:uv2` (2 components), `corner:cx` (the corner's vertex x) and its 12 edges sharp.
fn cube() -> Mesh {
    let mut m = Mesh {
        positions: (0..8)
            .map(|i| {
                [
                    (i & 1) as f32 - 0.5,
                    ((i >> 1) & 1) as f32 - 0.5,
                    ((i >> 2) & 1) as f32 - 0.5,
                ]
            })
            .collect(),
        ..Mesh::default()
    };
    for f in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        m.push_face(&f);
    }
    let x: Vec<f32> = m.positions.iter().map(|p| p[0]).collect();
    let cx: Vec<f32> = m
        .face_indices
        .iter()
        .map(|&v| m.positions[v as usize][0])
        .collect();
    m.attributes = vec![
        Attribute::new("x", Domain::Point, 1, x),
        Attribute::new("id", Domain::Face, 1, (0..6).map(|f| f as f32).collect()),
        Attribute::new("uv2", Domain::Corner, 2, [0.5, 0.125].repeat(24)),
        Attribute::new("cx", Domain::Corner, 1, cx),
    ];
    // The 12 cube edges: vertex pairs differing in one bit.
    for a in 0u32..8 {
        for bit in [1, 2, 4] {
            if a & bit == 0 {
                m.sharp_edges.push([a | bit, a]);
            }
        }
    }
    m.validate().unwrap();
    m
}

fn attribute<'a>(m: &'a Mesh, name: &str) -> &'a Attribute {
    m.attributes.iter().find(|a| a.name == name).unwrap()
}

/// The axis and sign of a cage face's outward normal: the dominant coordinate of its centroid.
fn side(points: impl Iterator<Item = [f32; 3]>) -> (usize, bool) {
    let mut c = [0f64; 3];
    let mut n = 0.0;
    for p in points {
        for k in 0..3 {
            c[k] += f64::from(p[k]);
        }
        n += 1.0;
    }
    let k = (0..3)
        .max_by(|&a, &b| c[a].abs().total_cmp(&c[b].abs()))
        .unwrap();
    assert!(c[k].abs() / n > 1e-3, "no dominant side");
    (k, c[k] > 0.0)
}

fn run(scheme: Scheme, levels: u32, uv: UvInterpolation) -> (Mesh, Mesh) {
    let cage = cube();
    let options = SubdivOptions {
        scheme,
        levels,
        uv_interpolation: uv,
        ..SubdivOptions::default()
    };
    let out = subdivide(&cage, &options).unwrap();
    out.validate().unwrap();
    (cage, out)
}

fn check_common(scheme: Scheme, levels: u32) -> Mesh {
    let (cage, out) = run(scheme, levels, UvInterpolation::Corners);
    let what = format!("{} level {levels}", scheme.name());
    let x = attribute(&out, "x");
    assert_eq!(x.rows(), out.vertex_count(), "{what}");
    for (v, p) in out.positions.iter().enumerate() {
        assert!((x.row(v)[0] - p[0]).abs() <= 1e-5, "{what}: vertex {v}");
    }
    let id = attribute(&out, "id");
    assert_eq!(id.rows(), out.face_count(), "{what}");
    for (f, face) in out.faces().enumerate() {
        let parent = id.row(f)[0] as usize;
        let want = side(
            cage.face(parent)
                .iter()
                .map(|&v| cage.positions[v as usize]),
        );
        let got = side(face.iter().map(|&v| out.positions[v as usize]));
        assert_eq!(got, want, "{what}: face {f} has id {parent}");
    }
    let uv2 = attribute(&out, "uv2");
    assert_eq!(uv2.rows(), out.face_indices.len(), "{what}");
    // Stencil weights are f32 and sum to 1 within rounding.
    let near = |r: &[f32]| (r[0] - 0.5).abs() <= 1e-6 && (r[1] - 0.125).abs() <= 1e-6;
    assert!(uv2.values.chunks(2).all(near), "{what}: uv2 changed");
    // Sharp edges: the right count, each an edge of a face, each vertex on 2 (3 at cube
    // corners) of them — closed lines along the cube's edges.
    assert_eq!(out.sharp_edges.len(), 12 << levels, "{what}");
    let mut degree = vec![0u32; out.vertex_count()];
    for &[a, b] in &out.sharp_edges {
        let is_edge = out.faces().any(|f| {
            (0..f.len()).any(|k| {
                let (p, q) = (f[k], f[(k + 1) % f.len()]);
                (p, q) == (a, b) || (p, q) == (b, a)
            })
        });
        assert!(is_edge, "{what}: sharp edge ({a}, {b}) is no face edge");
        degree[a as usize] += 1;
        degree[b as usize] += 1;
    }
    assert_eq!(
        degree.iter().filter(|&&d| d == 3).count(),
        8,
        "{what}: cube corners"
    );
    assert!(degree.iter().all(|&d| d == 0 || d == 2 || d == 3), "{what}");
    assert!(
        dropped(
            &cage,
            &SubdivOptions {
                scheme,
                ..SubdivOptions::default()
            }
        )
        .is_empty()
    );
    out
}

#[test]
fn bilinear_carries_everything_exactly() {
    for levels in 1..=3 {
        let out = check_common(Scheme::Bilinear, levels);
        // Both ends of every sharp edge on one cube edge: two coordinates at ±0.5, the same.
        for &[a, b] in &out.sharp_edges {
            let (p, q) = (out.positions[a as usize], out.positions[b as usize]);
            let on = |p: [f32; 3]| -> Vec<usize> {
                (0..3)
                    .filter(|&k| (p[k].abs() - 0.5).abs() < 1e-6)
                    .collect()
            };
            let common: Vec<usize> = on(p).into_iter().filter(|k| on(q).contains(k)).collect();
            assert!(common.len() >= 2, "edge ({a}, {b}): {p:?} {q:?}");
            assert!(common.iter().take(2).all(|&k| p[k] == q[k]));
        }
        // The corner value that equals its vertex's x stays equal to it.
        let cx = attribute(&out, "cx");
        for (c, &v) in out.face_indices.iter().enumerate() {
            assert!((cx.row(c)[0] - out.positions[v as usize][0]).abs() <= 1e-6);
        }
    }
    assert_eq!(check_common(Scheme::Bilinear, 1).sharp_edges.len(), 24);
}

#[test]
fn catmull_clark_carries_everything() {
    for levels in 1..=2 {
        let out = check_common(Scheme::CatmullClark, levels);
        // By symmetry, points refined from a cube edge have equal |coordinates| on the two
        // axes that edge is off-centre on.
        for &[a, b] in &out.sharp_edges {
            for p in [out.positions[a as usize], out.positions[b as usize]] {
                let mut m = p.map(f32::abs);
                m.sort_by(f32::total_cmp);
                assert!((m[2] - m[1]).abs() < 1e-6, "{p:?} is off the cube's edges");
            }
        }
        // `cx` (the corner's vertex x) has no seam, so it follows the vertex rule: it stays
        // the refined vertex's x.
        let cx = attribute(&out, "cx");
        for (c, &v) in out.face_indices.iter().enumerate() {
            assert!((cx.row(c)[0] - out.positions[v as usize][0]).abs() <= 1e-5);
        }
        // With linear face-varying rules it is refined bilinearly instead: the bilinear
        // refinement's x at the same corner (both schemes split faces alike).
        let (_, linear) = run(Scheme::CatmullClark, levels, UvInterpolation::Linear);
        let (_, bilinear) = run(Scheme::Bilinear, levels, UvInterpolation::Corners);
        let cx = attribute(&linear, "cx");
        for (c, &v) in bilinear.face_indices.iter().enumerate() {
            assert!((cx.row(c)[0] - bilinear.positions[v as usize][0]).abs() <= 1e-5);
        }
    }
}

#[test]
fn triangle_schemes_split_sharp_edges() {
    // A triangulated cube: each quad's diagonal (0-3 style) is no cube edge.
    let mut cage = cube();
    let quads: Vec<Vec<u32>> = cage.faces().map(<[u32]>::to_vec).collect();
    cage.face_offsets = vec![0];
    cage.face_indices.clear();
    for q in &quads {
        cage.push_face(&[q[0], q[1], q[2]]);
        cage.push_face(&[q[0], q[2], q[3]]);
    }
    cage.attributes.retain(|a| a.domain == Domain::Point);
    cage.validate().unwrap();
    for scheme in [Scheme::Loop, Scheme::Butterfly] {
        let options = SubdivOptions {
            scheme,
            levels: 2,
            ..SubdivOptions::default()
        };
        let out = subdivide(&cage, &options).unwrap();
        assert_eq!(out.sharp_edges.len(), 12 << 2, "{}", scheme.name());
        let x = attribute(&out, "x");
        for (v, p) in out.positions.iter().enumerate() {
            assert!((x.row(v)[0] - p[0]).abs() <= 1e-5);
        }
    }
    // √3 and Doo–Sabin keep no edge of the cage: sharp edges are dropped, and said to be.
    for scheme in [Scheme::Sqrt3, Scheme::DooSabin] {
        let options = SubdivOptions {
            scheme,
            levels: 1,
            ..SubdivOptions::default()
        };
        let out = subdivide(&cage, &options).unwrap();
        assert!(out.sharp_edges.is_empty());
        assert_eq!(dropped(&cage, &options), vec!["sharp_edges".to_string()]);
    }
}

#[test]
fn corner_attributes_are_dropped_without_face_varying_refinement() {
    let (cage, _) = run(Scheme::Bilinear, 1, UvInterpolation::Corners);
    let options = SubdivOptions {
        scheme: Scheme::DooSabin,
        ..SubdivOptions::default()
    };
    let out = subdivide(&cage, &options).unwrap();
    let names: Vec<String> = out.attributes.iter().map(Attribute::label).collect();
    assert_eq!(names, ["point:x", "face:id"]);
    assert_eq!(
        dropped(&cage, &options),
        ["sharp_edges", "corner:uv2", "corner:cx"]
    );
}
