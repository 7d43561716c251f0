//! The B-Rep pipeline of paper 001 (per-frame basis-surface tessellation, GPU trimming, crack
//! detection and filling) against an independent path: the CPU tessellation of the same
//! document at a fraction of a pixel (tessd-tessellate, watertight and trimmed exactly on the
//! CPU), rendered by the mesh pass. Face ids must agree away from face borders and
//! silhouettes, and the GPU-trimmed (u, v) of every covered pixel must classify on its face
//! with the CPU classifier.

mod common;

use common::{PARTS, doc, renderer};
use tessd_render::{BrepScene, Camera, Cracks, Frame, RenderSettings, Scene, View};

/// Pixels whose 3 × 3 neighbourhood in `f` holds more than one face id (background included).
fn border(f: &Frame) -> Vec<bool> {
    let (w, h) = (f.width as i64, f.height as i64);
    let mut out = vec![false; f.face_id.len()];
    for y in 0..h {
        for x in 0..w {
            let id = f.face_id[(y * w + x) as usize];
            'n: for dy in -1..=1 {
                for dx in -1..=1 {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx >= 0
                        && yy >= 0
                        && xx < w
                        && yy < h
                        && f.face_id[(yy * w + xx) as usize] != id
                    {
                        out[(y * w + x) as usize] = true;
                        break 'n;
                    }
                }
            }
        }
    }
    out
}

fn reference(d: &tessd_brep::Document, camera: &Camera, settings: &RenderSettings) -> Frame {
    let b = d.bounding_box().unwrap();
    let diag = ((0..3).map(|k| (b.max[k] - b.min[k]).powi(2)).sum::<f64>()).sqrt();
    let opts = tessd_tessellate::Options::new(1e-4 * diag);
    let t = tessd_tessellate::tessellate(d, &opts).unwrap();
    let r = renderer();
    let gpu = r.upload(&Scene::from_tessellation(&t)).unwrap();
    r.render(&gpu, camera, settings).unwrap().0
}

/// Face-id agreement with the reference away from borders, and reference pixels the frame
/// leaves as background (holes) away from borders.
fn compare(truth: &Frame, f: &Frame) -> (usize, usize, usize) {
    let edge = border(truth);
    let (mut agree, mut both, mut holes) = (0, 0, 0);
    for (i, &on_edge) in edge.iter().enumerate() {
        if on_edge || truth.face_id[i] == 0 {
            continue;
        }
        if f.face_id[i] == 0 {
            holes += 1;
        } else {
            both += 1;
            agree += usize::from(truth.face_id[i] == f.face_id[i]);
        }
    }
    (agree, both, holes)
}

#[test]
fn parts_match_the_cpu_tessellation_in_every_crack_mode() {
    let r = renderer();
    let settings = RenderSettings::new(200, 150);
    for name in PARTS {
        let d = doc(name);
        let scene = BrepScene::new(&d, None).unwrap();
        assert!(scene.skipped.is_empty(), "{name}: {:?}", scene.skipped);
        let bounds = scene.bounds;
        let part = r.upload_brep(scene).unwrap();
        for view in [View::Iso, View::Front, View::Top] {
            let camera = Camera::fit(view, &bounds, 30.0, settings.aspect());
            let truth = reference(&d, &camera, &settings);
            for cracks in Cracks::ALL {
                let (f, rep) = r.render_brep(&part, &camera, &settings, cracks).unwrap();
                let (agree, both, holes) = compare(&truth, &f);
                println!(
                    "{name} {} {}: face ids {agree}/{both}, holes {holes}, cracks {} filled {}, \
                     cells {}, frame {:.1} ms",
                    view.name(),
                    cracks.name(),
                    rep.cracks_detected,
                    rep.cracks_filled,
                    rep.cells,
                    rep.timings.frame().as_secs_f64() * 1e3,
                );
                if std::env::var_os("TESSD_RENDER_DUMP").is_some() {
                    let p = format!("/tmp/{name}_{}_{}.png", view.name(), cracks.name());
                    tessd_render::image::write_png(p.as_ref(), f.width, f.height, &f.color)
                        .unwrap();
                }
                assert!(
                    agree as f64 >= 0.995 * both as f64,
                    "{name}: {agree}/{both}"
                );
                assert!(
                    4 * both >= truth.covered(),
                    "{name}: {both} of {}",
                    truth.covered()
                );
                if cracks == Cracks::Object {
                    assert_eq!(
                        holes,
                        0,
                        "{name} {}: holes with object filling",
                        view.name()
                    );
                }
            }
        }
    }
}

/// Issue 21: "GPU trimming = the CPU classifier (`trim.classify`) at the (u, v) of every
/// covered pixel, outside pixels whose footprint straddles a trim curve". A pixel whose
/// footprint straddles a trim curve shows another face or the background on the curve's
/// other side, so its 3 × 3 neighbourhood holds two ids: those pixels are left out.
#[test]
fn gpu_trimming_equals_the_cpu_classifier() {
    let r = renderer();
    let settings = RenderSettings::new(240, 180);
    for name in [
        "bottle.json",
        "CrankArm.json",
        "freecad_drilling1_body.json",
        "Pump_Nut.json",
    ] {
        let d = doc(name);
        let scene = BrepScene::new(&d, None).unwrap();
        let eps = scene.trim_tolerance;
        let bounds = scene.bounds;
        let part = r.upload_brep(scene).unwrap();
        let mut trims: Vec<Option<tessd_trim::TrimStructure>> = vec![None; d.faces.len()];
        let (mut checked, mut off) = (0usize, 0usize);
        for view in [View::Iso, View::Left, View::Bottom] {
            let camera = Camera::fit(view, &bounds, 30.0, settings.aspect());
            let (f, _) = r
                .render_brep(&part, &camera, &settings, Cracks::None)
                .unwrap();
            let edge = border(&f);
            for (i, &id) in f.face_id.iter().enumerate() {
                if id == 0 || edge[i] {
                    continue;
                }
                let face = (id - 1) as usize;
                let trim = trims[face].get_or_insert_with(|| {
                    tessd_trim::TrimStructure::build(&d.faces[face], eps).unwrap()
                });
                let [u, v] = f.uv[i];
                checked += 1;
                if !trim.classify(u as f64, v as f64) {
                    off += 1;
                }
            }
        }
        println!("{name}: {checked} covered pixels classified on the CPU, {off} off the face");
        assert!(checked > 3_000, "{name}: {checked}");
        assert_eq!(
            off, 0,
            "{name}: GPU-trimmed pixels the CPU classifier puts off the face"
        );
    }
}
