//! The renderer against an independent path: an analytic CPU ray caster written here from the
//! camera convention of issue 21 (pixel (x, y)'s ray through `forward + sx·right + sy·up'`),
//! intersecting every triangle in f64. The GPU's face-id image must equal the ray-cast one on
//! ≥ 99.5 % of pixels, and differ only where the reference itself changes id within the
//! pixel's 3 × 3 neighbourhood (a silhouette or a face border, where the rasteriser's
//! fixed-point edge test and the f64 ray can round a pixel centre to different sides).
//!
//! Runs on whatever adapter wgpu finds; in CI that is lavapipe. No adapter is a failure, not a
//! skip.

mod common;

use common::renderer;
use tessd_mesh::Mesh;
use tessd_render::camera::Vec3;
use tessd_render::{Camera, Frame, RenderSettings, Scene, Shading, View};

fn bunny() -> Mesh {
    let path = tessd_testdata::shared("mesh/stanford_bunny.obj");
    tessd_mesh::io::read_path(&path, &Default::default())
        .unwrap_or_else(|e| panic!("reading {}: {e} (set TESSD_SHARED_DATA)", path.display()))
}

/// A unit cube, one face group per side (ids 1..=6), two triangles per side.
fn cube() -> Mesh {
    let mut m = Mesh::default();
    for i in 0..8u32 {
        m.positions
            .push([0, 1, 2].map(|k| if i >> k & 1 == 1 { 1.0 } else { 0.0 }));
    }
    let sides: [[u32; 4]; 6] = [
        [0, 2, 3, 1], // z = 0
        [4, 5, 7, 6], // z = 1
        [0, 1, 5, 4], // y = 0
        [2, 6, 7, 3], // y = 1
        [0, 4, 6, 2], // x = 0
        [1, 3, 7, 5], // x = 1
    ];
    for (g, s) in sides.iter().enumerate() {
        m.push_face(&[s[0], s[1], s[2]]);
        m.push_face(&[s[0], s[2], s[3]]);
        m.face_groups.extend([g as u32; 2]);
        m.group_names.push(format!("side{g}"));
    }
    m.validate().unwrap();
    m
}

/// The reference: per pixel the id (group + 1, or 1 without groups; 0 for no hit) and camera
/// depth of the nearest triangle along the pixel's ray (Möller–Trumbore, f64).
fn ray_cast(mesh: &Mesh, camera: &Camera, w: u32, h: u32) -> (Vec<u32>, Vec<f64>) {
    let grouped = mesh.face_groups.len() == mesh.face_count();
    let mut tris: Vec<([Vec3; 3], u32)> = Vec::new();
    for f in 0..mesh.face_count() {
        let c = mesh.face(f);
        let id = if grouped { mesh.face_groups[f] + 1 } else { 1 };
        let p = |i: u32| Vec3::from_array(mesh.positions[i as usize].map(|x| x as f64));
        for k in 1..c.len() - 1 {
            tris.push(([p(c[0]), p(c[k]), p(c[k + 1])], id));
        }
    }
    // The convention, written out here rather than taken from the crate.
    let forward = {
        let d = camera.target - camera.eye;
        d * (1.0 / d.dot(d).sqrt())
    };
    let right = {
        let r = forward.cross(camera.up);
        r * (1.0 / r.dot(r).sqrt())
    };
    let up = right.cross(forward);
    let t = (camera.fov.to_radians() / 2.0).tan();
    let (wf, hf) = (w as f64, h as f64);
    // Bin each triangle into the pixels its projected box covers (one pixel of margin), so a
    // pixel tests a handful of triangles, not all of them. Every test scene lies in front of
    // the eye.
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); (w * h) as usize];
    for (k, (tri, _)) in tris.iter().enumerate() {
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in tri {
            let v = *p - camera.eye;
            let z = v.dot(forward);
            assert!(z > 0.0, "test scenes lie in front of the eye");
            let sx = v.dot(right) / z;
            let sy = v.dot(up) / z;
            let px = (sx / (t * wf / hf) + 1.0) * wf / 2.0 - 0.5;
            let py = (1.0 - sy / t) * hf / 2.0 - 0.5;
            (x0, x1, y0, y1) = (x0.min(px), x1.max(px), y0.min(py), y1.max(py));
        }
        let clamp_x = |v: f64| v.clamp(0.0, wf - 1.0) as u32;
        let clamp_y = |v: f64| v.clamp(0.0, hf - 1.0) as u32;
        if x1 < -1.0 || y1 < -1.0 || x0 > wf || y0 > hf {
            continue;
        }
        for y in clamp_y(y0.floor() - 1.0)..=clamp_y(y1.ceil() + 1.0) {
            for x in clamp_x(x0.floor() - 1.0)..=clamp_x(x1.ceil() + 1.0) {
                bins[(y * w + x) as usize].push(k as u32);
            }
        }
    }
    let mut ids = vec![0; (w * h) as usize];
    let mut depth = vec![f64::INFINITY; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let sx = (2.0 * (x as f64 + 0.5) / wf - 1.0) * t * wf / hf;
            let sy = (1.0 - 2.0 * (y as f64 + 0.5) / hf) * t;
            let dir = forward + ((right * sx) + (up * sy));
            let i = (y * w + x) as usize;
            let mut best = f64::INFINITY;
            let mut best_id = 0;
            for &k in &bins[i] {
                let (tri, id) = &tris[k as usize];
                if let Some(s) = hit(camera.eye, dir, tri)
                    && s < best
                {
                    best = s;
                    best_id = *id;
                }
            }
            ids[i] = best_id;
            // dir·forward = 1, so the ray parameter is the camera depth.
            depth[i] = best;
        }
    }
    (ids, depth)
}

/// Ray parameter of the hit of `o + s·d` with the triangle, if any (s > 0).
fn hit(o: Vec3, d: Vec3, [a, b, c]: &[Vec3; 3]) -> Option<f64> {
    let e1 = *b - *a;
    let e2 = *c - *a;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let t = o - *a;
    let u = t.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = t.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let s = e2.dot(q) * inv;
    (s > 0.0).then_some(s)
}

fn render(mesh: &Mesh, camera: &Camera, w: u32, h: u32, shading: Shading) -> Frame {
    let r = renderer();
    let scene = r.upload(&Scene::from_mesh(mesh)).unwrap();
    let settings = RenderSettings::new(w, h).with_shading(shading);
    r.render(&scene, camera, &settings).unwrap().0
}

/// Compares face ids and depths; returns the fraction of equal ids.
fn compare(name: &str, frame: &Frame, reference: &(Vec<u32>, Vec<f64>)) -> f64 {
    let (w, h) = (frame.width as i64, frame.height as i64);
    let (ids, depth) = reference;
    let mut equal = 0;
    let mut interior_mismatch = Vec::new();
    let mut depth_err: f64 = 0.0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if frame.face_id[i] == ids[i] {
                equal += 1;
                if ids[i] != 0 {
                    let rel = (frame.depth[i] as f64 - depth[i]).abs() / depth[i];
                    depth_err = depth_err.max(rel);
                }
                continue;
            }
            let mut border = false;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if (0..w).contains(&nx)
                        && (0..h).contains(&ny)
                        && ids[(ny * w + nx) as usize] != ids[i]
                    {
                        border = true;
                    }
                }
            }
            if !border {
                interior_mismatch.push((x, y, frame.face_id[i], ids[i]));
            }
        }
    }
    let fraction = equal as f64 / (w * h) as f64;
    let covered = ids.iter().filter(|&&id| id != 0).count();
    println!(
        "{name}: {:.3} % of pixels equal, {covered} covered, largest relative depth error {depth_err:.2e}",
        100.0 * fraction
    );
    assert!(
        interior_mismatch.is_empty(),
        "{name}: pixels away from any border differ (x, y, gpu, reference): {:?}",
        &interior_mismatch[..interior_mismatch.len().min(10)]
    );
    // f32 depth through the projection: a few 1e-5 relative; 1e-3 leaves room for any driver.
    assert!(depth_err < 1e-3, "{name}: depth off by {depth_err:.2e}");
    assert!(covered > 0, "{name}: the reference sees nothing");
    fraction
}

#[test]
fn cube_face_ids_match_the_ray_caster() {
    let mesh = cube();
    let b = tessd_render::Bounds {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    let (w, h) = (160, 120);
    // With the sides each camera sees: x = 1 (id 6), y = 0 (id 3), z = 1 (id 2); z = 0 (id 1).
    let cameras = [
        (
            Camera::fit(View::Iso, &b, 30.0, w as f64 / h as f64),
            vec![2, 3, 6],
        ),
        (
            Camera::new([2.5, -1.7, 1.9], [0.4, 0.6, 0.45], [0.1, 0.0, 1.0], 40.0).clipped_to(&b),
            vec![2, 3, 6],
        ),
        (
            Camera::fit(View::Bottom, &b, 30.0, w as f64 / h as f64),
            vec![1],
        ),
    ];
    for (k, (camera, sides)) in cameras.iter().enumerate() {
        let frame = render(&mesh, camera, w, h, Shading::FaceIds);
        let reference = ray_cast(&mesh, camera, w, h);
        let f = compare(&format!("cube camera {k}"), &frame, &reference);
        assert!(f >= 0.995, "cube camera {k}: only {:.3} % equal", 100.0 * f);
        // Each visible side shows up with its own id.
        let mut seen: Vec<u32> = frame.face_id.iter().copied().filter(|&i| i != 0).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(&seen, sides, "cube camera {k}");
    }
}

#[test]
fn bunny_face_ids_match_the_ray_caster() {
    let mesh = bunny();
    let scene = Scene::from_mesh(&mesh);
    let b = scene.bounds.unwrap();
    let (w, h) = (160, 120);
    for view in [View::Iso, View::Front, View::Top] {
        let camera = Camera::fit(view, &b, 30.0, w as f64 / h as f64);
        let frame = render(&mesh, &camera, w, h, Shading::Lit);
        let reference = ray_cast(&mesh, &camera, w, h);
        let f = compare(&format!("bunny {}", view.name()), &frame, &reference);
        assert!(
            f >= 0.995,
            "bunny {}: only {:.3} % equal",
            view.name(),
            100.0 * f
        );
    }
}

/// Per-triangle ids (a group per triangle) on the bunny: every pixel sees one of ~70 000
/// triangles, most smaller than a pixel, so this checks that the GPU finds the same nearest
/// triangle as the ray, not only the silhouette.
#[test]
fn bunny_triangle_ids_match_the_ray_caster() {
    let mut mesh = bunny();
    let n = mesh.face_count();
    mesh.face_groups = (0..n as u32).collect();
    mesh.group_names = (0..n).map(|i| format!("t{i}")).collect();
    let scene = Scene::from_mesh(&mesh);
    let (w, h) = (160, 120);
    let camera = Camera::fit(View::Iso, &scene.bounds.unwrap(), 30.0, w as f64 / h as f64);
    let frame = render(&mesh, &camera, w, h, Shading::FaceIds);
    let reference = ray_cast(&mesh, &camera, w, h);
    let f = compare("bunny triangles", &frame, &reference);
    assert!(f >= 0.99, "bunny triangles: only {:.3} % equal", 100.0 * f);
}

/// Negative control: a camera one pixel off must fail the comparison, so the test can fail.
#[test]
fn a_shifted_camera_is_caught() {
    let mesh = cube();
    let b = tessd_render::Bounds {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    let (w, h) = (160, 120);
    let camera = Camera::fit(View::Iso, &b, 30.0, w as f64 / h as f64);
    let frame = render(&mesh, &camera, w, h, Shading::FaceIds);
    let mut wrong = camera;
    wrong.fov *= 1.03;
    let reference = ray_cast(&mesh, &wrong, w, h);
    let result = std::panic::catch_unwind(|| compare("shifted", &frame, &reference));
    assert!(result.is_err(), "a 3 % wider field of view went unnoticed");
}
