//! Paper 000 §6 as the renderer has it: the level k_i at which triangle classification decides
//! at least 40 % of a face's quadtree square is estimated on the CPU
//! (`classification_level`, from the packed structure) and must be what the classification
//! pass really decides on the GPU: at k_i − 1, k_i and k_i + 1, the share of cells the pass
//! reads back as wholly on or off equals the CPU's share, face by face, and at k_i it is at
//! least 40 % while at k_i − 1 it is not. Cells wholly on must also be on by the CPU
//! classifier at their centre, cells wholly off off.

mod common;

use common::{PARTS, doc, renderer};

use tessd_render::BrepScene;
use tessd_render::brep_scene::MAX_CLASSIFICATION_LEVEL;
use tessd_render::classification_level::{classification_level, decided_share};
use tessd_render::patch_tessellation::FrameTessellation;
use tessd_trim::TrimStructure;

#[test]
fn the_gpu_decides_the_cells_the_cpu_level_counts_on() {
    let renderer = renderer();
    for name in PARTS {
        let d = doc(name);
        let scene = BrepScene::new(&d, None).unwrap();
        let eps = scene.trim_tolerance;
        let trims: Vec<TrimStructure> = d
            .faces
            .iter()
            .map(|f| TrimStructure::build(f, eps).unwrap())
            .collect();
        let levels: Vec<Option<u32>> = (0..d.faces.len())
            .map(|f| classification_level(&scene.trims, f, MAX_CLASSIFICATION_LEVEL))
            .collect();
        for (f, info) in scene.faces.iter().enumerate() {
            assert_eq!(info.k_i, levels[f], "{name} face {f}");
        }
        let gpu = renderer.upload_brep(scene).unwrap();
        let pack = &gpu.scene.trims;
        let (mut checked, mut whole_cells) = (0, 0);
        for k in 0..=MAX_CLASSIFICATION_LEVEL {
            let frame = FrameTessellation::uniform(&gpu.scene, k);
            let cells = renderer.classify_cells(&gpu, &frame).unwrap();
            assert_eq!(cells.len(), frame.cells as usize);
            let n = 1u32 << k;
            let mut decided = vec![0u32; d.faces.len()];
            for c in &cells {
                let face = frame.patches[c.patch as usize].face as usize;
                let Some(on) = c.whole else { continue };
                decided[face] += 1;
                whole_cells += 1;
                // The cell's centre, in (u, v) through the quadtree's domain.
                let dom = trims[face].packed.domain;
                let (x, y) = (
                    (f64::from(c.column) + 0.5) / f64::from(n),
                    (f64::from(c.row) + 0.5) / f64::from(n),
                );
                let (u, v) = (
                    dom[0] + x * (dom[1] - dom[0]),
                    dom[2] + y * (dom[3] - dom[2]),
                );
                assert_eq!(
                    trims[face].classify(u, v),
                    on,
                    "{name} face {face} level {k} cell ({}, {})",
                    c.column,
                    c.row
                );
            }
            for (face, level) in levels.iter().enumerate() {
                let Some(ki) = *level else { continue };
                if k + 1 < ki || k > ki + 1 {
                    continue;
                }
                let gpu_share = f64::from(decided[face]) / f64::from(n * n);
                let cpu_share = decided_share(pack, face, k);
                // Cells whose corner lies on the line in f32 may go either way: one cell.
                assert!(
                    (gpu_share - cpu_share).abs() <= 1.0 / f64::from(n * n) + 1e-12,
                    "{name} face {face} level {k}: GPU {gpu_share} CPU {cpu_share}"
                );
                if k == ki {
                    assert!(
                        gpu_share >= 0.4 - 1.0 / f64::from(n * n),
                        "{name} face {face}"
                    );
                }
                if k + 1 == ki {
                    assert!(cpu_share < 0.4, "{name} face {face}");
                }
                checked += 1;
            }
        }
        eprintln!(
            "{name}: {checked} (face, level) shares compared, {whole_cells} whole cells checked, \
             k_i histogram {:?}",
            histogram(&levels)
        );
        assert!(checked >= d.faces.len(), "{name}: {checked}");
    }
}

fn histogram(levels: &[Option<u32>]) -> Vec<(String, usize)> {
    let mut out: Vec<(String, usize)> = Vec::new();
    for l in levels {
        let key = l.map_or("none".to_string(), |k| k.to_string());
        match out.iter_mut().find(|(k, _)| *k == key) {
            Some(e) => e.1 += 1,
            None => out.push((key, 1)),
        }
    }
    out.sort();
    out
}
