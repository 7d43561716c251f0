//! What leaves the renderer: the face-id PNG decoded with the `png` crate itself gives back the
//! face-id array; a B-Rep face tessellated at the pixel footprint shows its surface's (u, v),
//! checked against the analytic plane hit of each pixel's ray (an independent path).

mod common;

use common::renderer;

use tessd_render::{Bounds, Camera, RenderSettings, Scene, Shading, View};
/// A plate of three faces side by side: x in [0, 10], [10, 20], [20, 30], y in [0, 8], z = 0.
fn plate_doc() -> tessd_brep::Document {
    let face = |id: u64, x0: f64| {
        format!(
            r#"{{"id": {id}, "surface": {{"type": "plane", "origin": [{x0}, 0, 0],
                "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]}}, "bounds": [0, 10, 0, 8]}}"#
        )
    };
    let text = format!(
        r#"{{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [{}, {}, {}]}}"#,
        face(7, 0.0),
        face(8, 10.0),
        face(9, 20.0)
    );
    tessd_brep::Document::from_json(&text).unwrap()
}

#[test]
fn face_id_png_decodes_to_the_array() {
    let doc = plate_doc();
    let b = doc.bounding_box().unwrap();
    let bounds = Bounds {
        min: b.min,
        max: b.max,
    };
    let (w, h) = (97, 61); // odd sizes: rows need padding to 256 bytes
    let camera = Camera::fit(View::Iso, &bounds, 30.0, w as f64 / h as f64);
    let t = tessd_tessellate::tessellate(&doc, &tessd_tessellate::Options::new(0.01)).unwrap();
    let r = renderer();
    let gpu = r.upload(&Scene::from_tessellation(&t)).unwrap();
    let settings = RenderSettings::new(w, h).with_shading(Shading::FaceIds);
    let (frame, _) = r.render(&gpu, &camera, &settings).unwrap();

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ids.png");
    let rgba = tessd_render::image::face_ids_to_rgba(&frame.face_id);
    tessd_render::image::write_png(&path, w, h, &rgba).unwrap();

    // Decoded with the png crate directly, not with the crate's helper.
    let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (w, h));
    assert_eq!(info.color_type, png::ColorType::Rgba);
    let ids: Vec<u32> = buf[..info.buffer_size()]
        .chunks_exact(4)
        .map(|p| {
            assert_eq!(p[3], 255);
            p[0] as u32 + 256 * p[1] as u32 + 65536 * p[2] as u32
        })
        .collect();
    assert_eq!(ids, frame.face_id);
    // Face indices 0, 1, 2 in document order (ids 7, 8, 9 in the file) and the background.
    let mut seen = ids.clone();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen, [0, 1, 2, 3]);
}

#[test]
fn brep_uv_matches_the_analytic_plane() {
    let doc = plate_doc();
    let b = doc.bounding_box().unwrap();
    let bounds = Bounds {
        min: b.min,
        max: b.max,
    };
    let (w, h) = (160, 120);
    let camera = Camera::new([12.0, -9.0, 20.0], [15.0, 4.0, 0.0], [0.0, 0.0, 1.0], 35.0)
        .clipped_to(&bounds);
    let tolerance = tessd_render::pixel_tolerance(&camera, &bounds, h);
    let t = tessd_tessellate::tessellate(&doc, &tessd_tessellate::Options::new(tolerance)).unwrap();
    let r = renderer();
    let gpu = r.upload(&Scene::from_tessellation(&t)).unwrap();
    let (frame, _) = r.render(&gpu, &camera, &RenderSettings::new(w, h)).unwrap();

    let (mut checked, mut worst) = (0, 0f64);
    for y in 0..h {
        for x in 0..w {
            // The ray hits z = 0 at eye + s·d, s = −eye.z / d.z.
            let d = camera.ray(x, y, w, h);
            let s = -camera.eye[2] / d[2];
            let p = camera.eye + (d * s);
            let face = (p[0] / 10.0).floor();
            let inside = (0.0..30.0).contains(&p[0]) && (0.0..8.0).contains(&p[1]);
            let i = (y * w + x) as usize;
            // Keep away from face borders and the outline (a pixel's footprint is ~0.15 mm).
            let (u, v) = (p[0] - 10.0 * face, p[1]);
            let margin = 0.5;
            if !inside || u < margin || u > 10.0 - margin || v < margin || v > 8.0 - margin {
                continue;
            }
            assert_eq!(frame.face_id[i], face as u32 + 1, "pixel ({x}, {y})");
            let got = frame.uv[i];
            worst = worst.max((got[0] as f64 - u).abs().max((got[1] as f64 - v).abs()));
            // camera depth: s·(d·forward) = s, since d·forward = 1.
            let dz = (frame.depth[i] as f64 - s).abs() / s;
            assert!(dz < 1e-4, "depth at ({x}, {y}) off by {dz:.2e}");
            checked += 1;
        }
    }
    println!("{checked} pixels checked, (u, v) off by at most {worst:.2e} mm");
    assert!(checked > 2000, "only {checked} pixels inside the faces");
    // Interpolating an affine (u, v) over planar triangles is exact up to f32 rounding.
    assert!(worst < 1e-3, "(u, v) off by {worst:.2e}");
    assert!(frame.face_id.contains(&0));
}
