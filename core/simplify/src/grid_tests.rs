//! The grid's fused passes (`grid_cells.rs`, `grid_sums.rs`) against a plain sequential
//! reference — a hash map from cell to cluster in vertex order, f64 barycentres, a set of
//! sorted cluster triples for duplicates — and against themselves on 1, 2 and 7 threads.

use crate::grid_frame::Grid;
use crate::{GridSize, Method, Representative, Simplified, SimplifyOptions, simplify};
use std::collections::{HashMap, HashSet};
use tessd_mesh::Mesh;

/// A closed, bumpy torus of `nu × nv` quads split into triangles, vertices in row order.
pub(crate) fn torus(nu: u32, nv: u32) -> Mesh {
    let mut m = Mesh::default();
    let tau = std::f64::consts::TAU;
    for i in 0..nu {
        let u = tau * f64::from(i) / f64::from(nu);
        for j in 0..nv {
            let v = tau * f64::from(j) / f64::from(nv);
            let r = 0.4 * (1.0 + 0.1 * (6.0 * u).sin() * (4.0 * v).cos())
                + 0.002 * ((i * 7919 + j * 104_729) % 97) as f64 / 97.0;
            let ring = 1.0 + r * v.cos();
            m.positions.push([
                (ring * u.cos()) as f32,
                (ring * u.sin()) as f32,
                (r * v.sin()) as f32,
            ]);
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let (i1, j1) = ((i + 1) % nu, (j + 1) % nv);
            let (a, b, c, d) = (i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1);
            m.push_face(&[a, b, c]);
            m.push_face(&[a, c, d]);
        }
    }
    m
}

fn bunny() -> Mesh {
    let path = tessd_testdata::shared("mesh/stanford_bunny.obj");
    tessd_mesh::io::read_path(&path, &tessd_mesh::io::ReadOptions::default()).unwrap()
}

/// (clusters, output vertices, output faces, degenerate, duplicates) and the positions, the
/// straightforward way, for a triangle mesh and the barycentre.
fn reference(mesh: &Mesh, cells: u32) -> ([u64; 5], Vec<[f32; 3]>) {
    let w = crate::weights::vertex_weights(mesh, crate::Weighting::LongestEdge);
    let (bounds, _) = crate::partition::referenced_bounds(&mesh.positions, &w).unwrap();
    let (grid, _) = Grid::new(&bounds, GridSize::CellsPerAxis(cells));
    let mut id: HashMap<[u32; 3], u32> = HashMap::new();
    let mut cluster_of = vec![u32::MAX; mesh.positions.len()];
    let mut sums: Vec<[f64; 4]> = Vec::new();
    for (v, p) in mesh.positions.iter().enumerate() {
        if w[v] > 0.0 {
            let n = id.len() as u32;
            let c = *id.entry(grid.locate(p).0).or_insert(n);
            if c == n {
                sums.push([0.0; 4]);
            }
            cluster_of[v] = c;
            let wv = f64::from(w[v]);
            let s = &mut sums[c as usize];
            for k in 0..3 {
                s[k] += wv * f64::from(p[k]);
            }
            s[3] += wv;
        }
    }
    let reps: Vec<[f32; 3]> = sums
        .iter()
        .map(|s| std::array::from_fn(|k| (s[k] / s[3]) as f32))
        .collect();
    let (mut seen, mut used) = (HashSet::new(), HashSet::new());
    let (mut faces, mut degenerate, mut duplicates) = (0u64, 0u64, 0u64);
    for t in mesh.triangles().unwrap() {
        let c = t.map(|v| cluster_of[v as usize]);
        let p = c.map(|c| glam::Vec3::from_array(reps[c as usize]).as_dvec3());
        let zero = (p[1] - p[0]).cross(p[2] - p[0]) == glam::DVec3::ZERO;
        if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] || zero {
            degenerate += 1;
            continue;
        }
        let mut key = c;
        key.sort_unstable();
        if !seen.insert(key) {
            duplicates += 1;
            continue;
        }
        faces += 1;
        used.extend(c);
    }
    let mut out: Vec<u32> = used.into_iter().collect();
    out.sort_unstable();
    let counts = [
        sums.len() as u64,
        out.len() as u64,
        faces,
        degenerate,
        duplicates,
    ];
    (counts, out.iter().map(|&c| reps[c as usize]).collect())
}

fn run(mesh: &Mesh, options: &SimplifyOptions, threads: usize) -> Simplified {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| simplify(mesh, options, &mut |_, _| true).unwrap())
}

fn grid(cells: u32, rep: Representative) -> SimplifyOptions {
    SimplifyOptions::new(Method::Grid(GridSize::CellsPerAxis(cells))).with_representative(rep)
}

#[test]
fn fused_grid_counts_match_a_sequential_reference() {
    // 4 000 cells a side: far more bricks than the small torus has vertices, so the hash
    // (grid_partition.rs) takes over; the counts must not change either.
    let meshes = [
        ("torus", torus(300, 120)),
        ("bunny", bunny()),
        ("small", torus(40, 16)),
    ];
    for (name, mesh) in meshes {
        let sizes: &[u32] = if name == "small" {
            &[4000]
        } else {
            &[3, 20, 90, 400]
        };
        for &cells in sizes {
            let (want, positions) = reference(&mesh, cells);
            let got = run(&mesh, &grid(cells, Representative::Barycenter), 1);
            let r = &got.report;
            let counts = [
                r.clusters,
                r.output_vertices,
                r.output_faces,
                r.degenerate_faces,
                r.duplicate_faces,
            ];
            assert_eq!(counts, want, "{name} at {cells} cells");
            // Positions: the same up to the last bits of the sums.
            let size = 2.0f32;
            for (a, b) in got.mesh.positions.iter().zip(&positions) {
                for k in 0..3 {
                    assert!(
                        (a[k] - b[k]).abs() <= 1e-6 * size,
                        "{name} {cells}: {a:?} {b:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn fused_grid_is_the_same_bytes_on_1_2_and_7_threads() {
    let mut quads = torus(150, 60);
    // Every other pair of triangles as one quad: a polygon mesh, kept as polygons.
    let tris = quads.triangles().unwrap().to_vec();
    quads.face_offsets = vec![0];
    quads.face_indices.clear();
    for (i, pair) in tris.chunks(2).enumerate() {
        if i % 2 == 0 {
            let [a, b, c] = pair[0];
            quads.push_face(&[a, b, c, pair[1][2]]);
        } else {
            pair.iter().for_each(|t| quads.push_face(t));
        }
    }
    let meshes = [
        ("torus", torus(400, 160)),
        ("quads", quads),
        ("bunny", bunny()),
    ];
    let reps = [
        Representative::Barycenter,
        Representative::Quadric,
        Representative::Heaviest,
    ];
    for (name, mesh) in &meshes {
        for cells in [7, 60, 250] {
            for rep in reps {
                let mut options = grid(cells, rep);
                options.keep_partition = true;
                let one = run(mesh, &options, 1);
                assert!(one.mesh.face_count() > 0);
                for threads in [2, 7] {
                    let other = run(mesh, &options, threads);
                    let bits = |s: &Simplified| -> Vec<u32> {
                        s.mesh
                            .positions
                            .iter()
                            .flatten()
                            .map(|x| x.to_bits())
                            .collect()
                    };
                    let what = format!("{name} {cells} {rep:?} on {threads} threads");
                    assert!(bits(&one) == bits(&other), "{what}");
                    assert_eq!(one.mesh.face_indices, other.mesh.face_indices, "{what}");
                    assert_eq!(one.mesh.face_offsets, other.mesh.face_offsets, "{what}");
                    assert_eq!(one.cells, other.cells, "{what}");
                    assert_eq!(one.report, other.report, "{what}");
                }
            }
        }
    }
}

/// A mesh of triangles alone is checked inside the weights' and bounds' passes, not by
/// `Mesh::validate` (`Prepared::plain_triangles`): every fault, in the first block or a later
/// one, one fault or several, gives validation's own words, on 1 and 2 threads.
#[test]
fn plain_triangles_fail_as_validation_does() {
    let good = torus(200, 100); // 40 000 triangles: three blocks of faces.
    let nv = good.positions.len() as u32;
    type Fault = fn(&mut Mesh, u32);
    let faults: [(&str, Fault); 8] = [
        ("index in block 0", |m, nv| m.face_indices[5] = nv),
        ("index in block 2", |m, nv| {
            m.face_indices[3 * 39_000 + 1] = nv + 7
        }),
        ("NaN", |m, _| m.positions[1234][1] = f32::NAN),
        ("infinity, last vertex", |m, _| {
            m.positions.last_mut().unwrap()[2] = f32::NEG_INFINITY
        }),
        ("unreferenced NaN", |m, _| {
            m.positions.push([f32::NAN, 0.0, 0.0])
        }),
        ("steps 2 and 4", |m, _| m.face_offsets[20_000] -= 1),
        ("offsets past the corners", |m, _| {
            *m.face_offsets.last_mut().unwrap() += 3;
        }),
        ("NaN and index", |m, nv| {
            m.face_indices[9] = nv;
            m.positions[15_000][0] = f32::INFINITY;
        }),
    ];
    let methods = [
        Method::Grid(GridSize::CellsPerAxis(20)),
        Method::Quality(crate::Length::Relative(0.01)),
    ];
    for (what, fault) in faults {
        let mut m = good.clone();
        fault(&mut m, nv);
        let want = crate::SimplifyError::from(m.validate().expect_err(what)).to_string();
        for method in methods {
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let options = SimplifyOptions::new(method);
                let got = pool.install(|| simplify(&m, &options, &mut |_, _| true));
                let got = got.err().map(|e| e.to_string());
                assert_eq!(
                    got.as_deref(),
                    Some(want.as_str()),
                    "{what} {method:?} {threads}"
                );
            }
        }
    }
    // The good mesh takes the checked path and simplifies as before.
    assert!(simplify(&good, &SimplifyOptions::new(methods[0]), &mut |_, _| true).is_ok());
}

/// The grid's face pass with the quadrics in it (`grid_quadrics.rs`: F before the
/// representatives, the area test after them) gives what the separate passes give — every
/// cluster's quadric to the bit (`representative.rs`'s chunks), and the same fates, faces,
/// corners and counts as `elimination::fates` with the representatives known — on 1, 2 and 7
/// threads; the representatives put many kept faces at zero area, so pass O has work.
#[test]
fn face_pass_quadrics_and_fates_match_the_separate_passes() {
    for (name, mesh) in [("torus", torus(400, 160)), ("bunny", bunny())] {
        // The bunny's few polygons fan-triangulated: the pass takes triangle meshes.
        let mesh = crate::triangulate::triangulate(&mesh);
        let w = crate::weights::vertex_weights(&mesh, crate::Weighting::LongestEdge);
        let (bounds, _) = crate::partition::referenced_bounds(&mesh.positions, &w).unwrap();
        // (Up to 150 cells a side: the brick table, not the hash, takes these.)
        for cells in [7, 60, 150] {
            let size = GridSize::CellsPerAxis(cells);
            let cells_of =
                crate::grid_cells::grid_cells(&mesh.positions, &w, None, &bounds, size, false, 0);
            let (p, _) = cells_of.unwrap();
            let n = p.clusters;
            // Even clusters on one line (their faces have zero area), odd ones off it.
            let reps: Vec<[f32; 3]> = (0..n)
                .map(|c| {
                    let t = (c % 7) as f32;
                    if c % 2 == 0 {
                        [t, 2.0 * t, 3.0 * t]
                    } else {
                        [t, 0.5 * c as f32, 1.0]
                    }
                })
                .collect();
            let mut want_q = Vec::new();
            crate::representative::for_each_quadric_chunk(
                &mesh,
                &p.cluster_of,
                n,
                crate::representative::GRID_SHARE,
                |_, q| want_q.extend_from_slice(q),
            );
            let want = crate::elimination::eliminate(&mesh, &p.cluster_of, &reps, true);
            assert!(want.flattened > 0, "{name} {cells}");
            let bits = |q: &[crate::Quadric]| -> Vec<u64> {
                q.iter()
                    .flat_map(|q| q.a.iter().chain(&q.b).chain([&q.c]).map(|x| x.to_bits()))
                    .collect()
            };
            for threads in [1, 2, 7] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let triangles = mesh.triangles().unwrap();
                let (fates, q) = pool.install(|| {
                    crate::grid_quadrics::faces_and_quadrics(
                        &mesh.positions,
                        triangles,
                        &p.cluster_of,
                        n,
                    )
                });
                let what = format!("{name} {cells} cells, {threads} threads");
                assert!(bits(&q) == bits(&want_q), "{what}");
                let got = pool.install(|| fates.eliminate(&mesh, &p.cluster_of, &reps, true));
                assert_eq!(got.fate, want.fate, "{what}");
                assert_eq!(got.face_indices, want.face_indices, "{what}");
                assert_eq!(got.face_offsets, want.face_offsets, "{what}");
                assert_eq!(got.source_corner, want.source_corner, "{what}");
                let counts =
                    |e: &crate::elimination::Eliminated| [e.degenerate, e.flattened, e.duplicates];
                assert_eq!(counts(&got), counts(&want), "{what}");
            }
        }
    }
}

/// The cell pass takes the clusters' boxes while they are at most the limit, the same as the
/// separate pass over the vertices, on every core count; beyond the limit it takes none.
#[test]
fn cell_pass_boxes_match_the_vertex_pass_or_are_left() {
    let mesh = torus(300, 120);
    let w = crate::weights::vertex_weights(&mesh, crate::Weighting::LongestEdge);
    let (bounds, _) = crate::partition::referenced_bounds(&mesh.positions, &w).unwrap();
    for cells in [5, 60] {
        let size = GridSize::CellsPerAxis(cells);
        for threads in [1, 2, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let cells_with = |limit: usize| {
                pool.install(|| {
                    crate::grid_cells::grid_cells(
                        &mesh.positions,
                        &w,
                        None,
                        &bounds,
                        size,
                        false,
                        limit,
                    )
                })
                .unwrap()
            };
            let (p, all) = cells_with(usize::MAX);
            let n = p.clusters;
            let want = crate::grid_sums::cluster_boxes(&mesh.positions, &p.cluster_of, n);
            assert_eq!(all.boxes, want, "{cells} cells, {threads} threads");
            let (_, exact) = cells_with(n);
            assert_eq!(
                exact.boxes, want,
                "{cells} cells, {threads} threads, limit n"
            );
            let (_, fewer) = cells_with(n - 1);
            assert!(fewer.boxes.is_empty(), "{cells} cells, {threads} threads");
            let (_, none) = cells_with(0);
            assert!(none.boxes.is_empty());
        }
    }
}
