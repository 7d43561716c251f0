//! Full-scene ray casting (`Renderer::ray_cast_brep`, paper 001 §4.1.2) against independent
//! references: (a) a sphere of known radius, whose every pixel's depth must be the analytic
//! ray–sphere intersection's (f64, the camera convention written out here) within 10⁻³ of
//! the radius, and whose coverage must be the analytic disk's except on silhouette pixels;
//! (b) trimmed parts, a plate with a round hole (pixels inside the hole are background,
//! pixels on the plate away from its borders are covered) and the tube with a round window
//! of core/brep's fixtures: every covered pixel's (u, v) is on its face by the CPU trim
//! classification (`TrimStructure::classify`), and `Surface::eval` there lies on the pixel's
//! ray.
//!
//! Runs on whatever adapter wgpu finds; in CI that is lavapipe. No adapter is a failure.

mod common;

use common::renderer;

use tessd_brep::Document;
use tessd_render::camera::Vec3;
use tessd_render::{Bounds, BrepScene, Camera, Frame, RenderSettings, View};
use tessd_trim::TrimStructure;

const W: u32 = 96;
const H: u32 = 64;

fn bounds(doc: &Document) -> Bounds {
    let b = doc.bounding_box().unwrap();
    Bounds {
        min: b.min,
        max: b.max,
    }
}

/// What a test needs of the prepared part besides the frame.
struct Part {
    /// The box diagonal.
    diagonal: f64,
    /// The world tolerance its trims were approximated with.
    trim_tolerance: f64,
}

/// Ray casts `doc` (prepared with the default trim tolerance) from `camera` at W × H, lit.
fn cast(doc: &Document, camera: &Camera) -> (Frame, Part) {
    let r = renderer();
    let start = std::time::Instant::now();
    let scene = BrepScene::new(doc, None).unwrap();
    let built = start.elapsed();
    assert!(scene.skipped.is_empty(), "{:?}", scene.skipped);
    let (faces, cells) = (scene.faces.len(), scene.ray_seeds().cells());
    let info = Part {
        diagonal: 2.0 * scene.bounds.radius(),
        trim_tolerance: scene.trim_tolerance,
    };
    let part = r.upload_brep(scene).unwrap();
    let settings = RenderSettings::new(W, H);
    let (frame, report) = r.ray_cast_brep(&part, camera, &settings).unwrap();
    println!(
        "{faces} faces, {cells} seed cells (scene built in {built:.2?}); {W}x{H} ray cast in \
         {:.2?}, {} pixels covered",
        report.timings.ray_cast,
        frame.covered()
    );
    assert_eq!(report.timings.ray_cast, report.timings.frame());
    (frame, info)
}

/// The pixel's ray direction, written out from the convention (not `Camera::ray`).
fn ray(camera: &Camera, x: u32, y: u32) -> Vec3 {
    let (f, r, u) = camera.basis();
    let t = (0.5 * camera.fov.to_radians()).tan();
    let sx = (2.0 * (x as f64 + 0.5) / W as f64 - 1.0) * t * W as f64 / H as f64;
    let sy = (1.0 - 2.0 * (y as f64 + 0.5) / H as f64) * t;
    f + ((r * sx) + (u * sy))
}

/// Whether every pixel of the 3 × 3 neighbourhood of (x, y) gives `f` the same answer.
fn interior(x: u32, y: u32, f: impl Fn(u32, u32) -> bool) -> bool {
    let c = f(x, y);
    (-1i32..=1).all(|j| {
        (-1i32..=1).all(|i| {
            let (a, b) = (x as i32 + i, y as i32 + j);
            a < 0 || b < 0 || a >= W as i32 || b >= H as i32 || f(a as u32, b as u32) == c
        })
    })
}

#[test]
fn sphere_depths_match_the_analytic_intersection() {
    let (c, r) = ([1000.0, -40.0, 25.0], 5.0);
    let text = format!(
        r#"{{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [
            {{"id": 1, "surface": {{"type": "sphere", "origin": [{}, {}, {}], "x_dir": [1, 0, 0],
              "y_dir": [0, 1, 0], "radius": {r}}},
              "bounds": [0, 6.283185307179586, -1.5707963267948966, 1.5707963267948966]}}]}}"#,
        c[0], c[1], c[2]
    );
    let doc = Document::from_json(&text).unwrap();
    let camera = Camera::fit(View::Iso, &bounds(&doc), 30.0, W as f64 / H as f64);
    let (frame, _) = cast(&doc, &camera);
    let (forward, _, _) = camera.basis();
    // Nearest t > 0 of |eye + t·d − c| = r.
    let hit = |x: u32, y: u32| {
        let d = ray(&camera, x, y);
        let o = camera.eye - Vec3::from(c);
        let (a, b, cc) = (d.dot(d), o.dot(d), o.dot(o) - r * r);
        let disc = b * b - a * cc;
        (disc >= 0.0).then(|| (-b - disc.sqrt()) / a * d.dot(forward))
    };
    let (mut worst, mut checked, mut silhouette) = (0.0f64, 0, 0);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let expected = hit(x, y);
            let covered = frame.face_id[i] != 0;
            if covered != expected.is_some() {
                assert!(
                    !interior(x, y, |a, b| hit(a, b).is_some()),
                    "pixel ({x}, {y}): ray cast {covered}, analytic {}",
                    expected.is_some()
                );
                silhouette += 1;
                continue;
            }
            if let Some(z) = expected {
                assert_eq!(frame.face_id[i], 1);
                let err = (frame.depth[i] as f64 - z).abs();
                assert!(
                    err <= 1e-3 * r,
                    "pixel ({x}, {y}): depth {} vs analytic {z} (error {err:e})",
                    frame.depth[i]
                );
                worst = worst.max(err);
                checked += 1;
            } else {
                assert_eq!(frame.color[4 * i..4 * i + 4], [224, 224, 224, 255]);
                assert!(frame.depth[i].is_infinite());
            }
        }
    }
    println!(
        "sphere r = {r}: {checked} pixels, worst depth error {worst:.3e} ({:.3e} r), {silhouette} \
         silhouette pixels differ",
        worst / r
    );
    assert!(checked > 500, "{checked}");
}

/// A plate 20 × 20 in z = 0 around (1000, 0, 0), with a round hole of radius 4 in its middle.
fn plate_with_hole() -> Document {
    let line = |o: [f64; 2], d: [f64; 2]| {
        format!(
            r#"{{"curve": {{"type": "line", "origin": [{}, {}], "dir": [{}, {}]}}, "range": [0, 20]}}"#,
            o[0], o[1], d[0], d[1]
        )
    };
    let text = format!(
        r#"{{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [
            {{"id": 1, "surface": {{"type": "plane", "origin": [1000, 0, 0], "x_dir": [1, 0, 0],
              "y_dir": [0, 1, 0]}}, "bounds": [-10, 10, -10, 10], "loops": [
              {{"edges": [{}, {}, {}, {}]}},
              {{"edges": [{{"curve": {{"type": "circle", "center": [0, 0], "x_dir": [1, 0],
                "y_dir": [0, -1], "radius": 4}}, "range": [0, 6.283185307179586]}}]}}]}}]}}"#,
        line([-10.0, -10.0], [1.0, 0.0]),
        line([10.0, -10.0], [0.0, 1.0]),
        line([10.0, 10.0], [-1.0, 0.0]),
        line([-10.0, 10.0], [0.0, -1.0]),
    );
    Document::from_json(&text).unwrap()
}

/// Every covered pixel: on its face by the CPU classification (trims at the part's trim
/// tolerance) at its (u, v), and the CPU surface point there on the pixel's ray (distance ≤
/// 10⁻⁴ of the diagonal) at the returned depth.
fn check_hits(doc: &Document, camera: &Camera, frame: &Frame, part: &Part) {
    let tol = 1e-4 * part.diagonal;
    let trims: Vec<TrimStructure> = doc
        .faces
        .iter()
        .map(|f| TrimStructure::build(f, part.trim_tolerance).unwrap())
        .collect();
    let (forward, _, _) = camera.basis();
    let (mut worst, mut worst_depth, mut n) = (0.0f64, 0.0f64, 0);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let id = frame.face_id[i];
            if id == 0 {
                continue;
            }
            let f = (id - 1) as usize;
            let [u, v] = frame.uv[i].map(|c| c as f64);
            assert!(
                trims[f].classify(u, v),
                "pixel ({x}, {y}): face {id} (u, v) = ({u}, {v}) is off the face"
            );
            let p = doc.faces[f].surface.point(u, v);
            let d = ray(camera, x, y);
            let q = Vec3::from(p) - camera.eye;
            let t = q.dot(d) / d.dot(d);
            let off = q - (d * t);
            let dist = off.dot(off).sqrt();
            assert!(
                dist <= tol,
                "pixel ({x}, {y}): S(u, v) is {dist:e} from the ray"
            );
            let depth_err = (frame.depth[i] as f64 - t * d.dot(forward)).abs();
            assert!(
                depth_err <= tol,
                "pixel ({x}, {y}): depth off by {depth_err:e}"
            );
            worst = worst.max(dist);
            worst_depth = worst_depth.max(depth_err);
            n += 1;
        }
    }
    println!(
        "{n} covered pixels on their faces; worst distance of S(u, v) to the ray {worst:.3e}, \
         worst depth error {worst_depth:.3e} (tolerance {tol:.1e})"
    );
}

#[test]
fn plate_hole_is_background_and_hits_are_on_the_face() {
    let doc = plate_with_hole();
    let b = bounds(&doc);
    let camera = Camera::fit(View::Iso, &b, 30.0, W as f64 / H as f64);
    let (frame, part) = cast(&doc, &camera);
    // The analytic plane hit's (x − 1000, y) of each pixel.
    let plane = |x: u32, y: u32| {
        let d = ray(&camera, x, y);
        let t = -camera.eye[2] / d[2];
        let p = camera.eye + (d * t);
        [p[0] - 1000.0, p[1]]
    };
    let in_hole = |x: u32, y: u32| {
        let p = plane(x, y);
        p[0].hypot(p[1]) < 4.0
    };
    let on_plate = |x: u32, y: u32| {
        let p = plane(x, y);
        !in_hole(x, y) && p[0].abs() < 10.0 && p[1].abs() < 10.0
    };
    let (mut hole, mut plate) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            if in_hole(x, y) && interior(x, y, in_hole) {
                assert_eq!(frame.face_id[i], 0, "pixel ({x}, {y}) in the hole");
                hole += 1;
            }
            if on_plate(x, y) && interior(x, y, on_plate) {
                assert_eq!(frame.face_id[i], 1, "pixel ({x}, {y}) on the plate");
                plate += 1;
            }
        }
    }
    println!("plate: {hole} hole pixels background, {plate} plate pixels covered");
    assert!(hole > 50 && plate > 300, "{hole} {plate}");
    check_hits(&doc, &camera, &frame, &part);
}

#[test]
fn tube_window_hits_are_on_their_faces() {
    let doc = Document::from_json(include_str!(
        "../../brep/tests/data/cylinder_with_hole.json"
    ))
    .unwrap();
    // Looking at the window (u = π, the −x side) from −x, a little above.
    let camera = Camera::new([-60.0, -8.0, 18.0], [0.0, 0.0, 10.0], [0.0, 0.0, 1.0], 30.0);
    let (frame, part) = cast(&doc, &camera);
    check_hits(&doc, &camera, &frame, &part);
    // Through the window the inside of the far wall shows: some tube pixels have u near 0
    // (or 2π) — the far side, x > 0.
    let far = frame
        .face_id
        .iter()
        .zip(&frame.uv)
        .filter(|(id, uv)| **id == 1 && (uv[0] < 1.0 || uv[0] > 5.3))
        .count();
    println!(
        "tube: {} covered, {far} far-wall pixels seen through the window",
        frame.covered()
    );
    assert!(far > 10, "{far}");
}
