//! The GPU trim walk (paper 000 §5.1–5.3, `shaders/trim_walk.wgsl`) against its CPU
//! reference [`MultiPack::walk`], on the faces of the shared B-Rep fixtures and core/trim's
//! bottle packed at ε = 0.01 (as core/trim's multi-pack tests pack them).
//!
//! The shader does the reference's f32 operations in the same order, so the answers must be
//! equal; the one allowed difference is a driver fusing a multiply-add, which can move a point
//! lying within an ulp of a separating line or a curve to its other side. A disagreement is
//! therefore accepted only when the CPU walk gives the GPU's answer somewhere within 10⁻⁵
//! (quadtree-normalised units) of the point; such points are counted and printed.
//!
//! Runs on whatever adapter wgpu finds; in CI that is lavapipe. No adapter is a failure, not a
//! skip.

use std::sync::OnceLock;

use tessd_brep::Document;
use tessd_gpu::GpuContext;
use tessd_render::TrimWalk;
use tessd_trim::TrimStructure;
use tessd_trim::multi_pack::MultiPack;

/// The world tolerance the fixtures are packed at (document units).
const EPS: f64 = 0.01;

/// How far (quadtree-normalised units) a disagreement may lie from a line or a curve.
const NEAR: f64 = 1e-5;

struct Fixture {
    walk: TrimWalk,
    pack: MultiPack,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let mut faces = Vec::new();
        for text in [
            include_str!("../../brep/tests/data/bspline_face.json"),
            include_str!("../../brep/tests/data/cylinder_with_hole.json"),
            include_str!("../../trim/tests/data/bottle.json"),
        ] {
            faces.extend(Document::from_json(text).unwrap().faces);
        }
        let mut pack = MultiPack::new();
        for f in &faces {
            pack.push(&TrimStructure::build(f, EPS).unwrap(), f.bounds);
        }
        let gpu = GpuContext::open("tessd-render trim_walk test")
            .unwrap_or_else(|e| panic!("no GPU for the trim-walk tests: {e}"));
        println!("adapter: {}", gpu.describe());
        let walk = TrimWalk::new(&gpu).expect("trim walk pass builds");
        Fixture { walk, pack }
    })
}

/// splitmix64: a reproducible stream of numbers in [0, 1).
struct Stream(u64);

impl Stream {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Whether the CPU walk answers `on` somewhere within [`NEAR`] of patch point (s, t) of face
/// `face` (eight directions, in quadtree units): the point is that close to a line or curve.
fn near_boundary(pack: &MultiPack, face: usize, s: f32, t: f32, on: bool) -> bool {
    let h = &pack.headers[face];
    let (ds, dt) = (NEAR / f64::from(h.scale[0]), NEAR / f64::from(h.scale[1]));
    (-1..=1).any(|i| {
        (-1..=1).any(|j| {
            let (ps, pt) = (
                (f64::from(s) + f64::from(i) * ds) as f32,
                (f64::from(t) + f64::from(j) * dt) as f32,
            );
            (i, j) != (0, 0) && pack.walk(face, ps, pt) == on
        })
    })
}

/// Disagreements between the GPU and CPU walks, all within [`NEAR`] of a boundary.
#[derive(Default)]
struct Disagreements {
    /// At patch-edge points (s or t ∈ {0, 1}), where trims often run exactly along the face's
    /// bounds, so a grid point there lies *on* a curve.
    edge: usize,
    /// Elsewhere.
    interior: usize,
}

/// Runs `queries` on the device and compares every answer with the CPU walk (the test fails
/// on a disagreement farther than [`NEAR`] from a boundary).
fn compare(queries: &[(u32, f32, f32)], what: &str) -> Disagreements {
    let fx = fixture();
    let (gpu, timings) = fx.walk.run_timed(&fx.pack, queries).unwrap();
    assert_eq!(gpu.len(), queries.len());
    let mut near = Disagreements::default();
    let (mut far, mut on) = (0usize, 0usize);
    for (&(f, s, t), &g) in queries.iter().zip(&gpu) {
        on += usize::from(g);
        if fx.pack.walk(f as usize, s, t) == g {
            continue;
        }
        if !near_boundary(&fx.pack, f as usize, s, t, g) {
            far += 1;
            println!("{what}: face {f} ({s}, {t}): GPU {g} disagrees far from any boundary");
        } else if s == 0.0 || s == 1.0 || t == 0.0 || t == 1.0 {
            near.edge += 1;
        } else {
            near.interior += 1;
            println!("{what}: face {f} ({s}, {t}): GPU {g}, within {NEAR} of a boundary");
        }
    }
    println!(
        "{what}: {} points on {} faces ({on} on the face); disagreements within {NEAR} of a \
         line or curve: {} at patch-edge points, {} elsewhere; {far} farther. {} points: \
         upload {:?}, dispatch {:?}, read-back {:?}",
        queries.len(),
        fx.pack.headers.len(),
        near.edge,
        near.interior,
        queries.len(),
        timings.upload,
        timings.dispatch,
        timings.readback
    );
    assert_eq!(
        far, 0,
        "{what}: GPU and CPU walks disagree away from boundaries"
    );
    near
}

#[test]
fn gpu_walk_matches_cpu_walk_on_grid_and_random_points() {
    let fx = fixture();
    let mut queries = Vec::new();
    for f in 0..fx.pack.headers.len() as u32 {
        for i in 0..=64u32 {
            for j in 0..=64u32 {
                queries.push((f, i as f32 / 64.0, j as f32 / 64.0));
            }
        }
        let mut rng = Stream(u64::from(f) * 31 + 7);
        for _ in 0..2000 {
            queries.push((f, rng.next(), rng.next()));
        }
    }
    let near = compare(&queries, "grid + random");
    // A fused multiply-add flips only points within an ulp or so of a boundary: rare, except
    // on the patch edges, where grid points lie exactly on trims along the bounds.
    assert!(
        near.edge * 100 <= queries.len(),
        "{} edge points",
        near.edge
    );
    assert!(
        near.interior * 10_000 <= queries.len(),
        "{} interior points",
        near.interior
    );
}

/// About 100 000 random points over all faces in one dispatch, timed; also points just
/// outside the patch and an out-of-range face index (off).
#[test]
fn gpu_walk_of_a_hundred_thousand_points() {
    let fx = fixture();
    let faces = fx.pack.headers.len() as u32;
    let mut rng = Stream(12345);
    let mut queries: Vec<(u32, f32, f32)> = (0..100_000)
        .map(|_| {
            let f = ((rng.next() * faces as f32) as u32).min(faces - 1);
            (f, rng.next() * 1.2 - 0.1, rng.next() * 1.2 - 0.1)
        })
        .collect();
    let near = compare(&queries, "100k random");
    assert!(near.interior * 10_000 <= queries.len());
    queries.truncate(3);
    queries.push((faces, 0.5, 0.5));
    let on = fx.walk.run(&fx.pack, &queries).unwrap();
    assert!(!on[3], "a face beyond the pack is off");
    assert!(fx.walk.run(&fx.pack, &[]).unwrap().is_empty());
}
