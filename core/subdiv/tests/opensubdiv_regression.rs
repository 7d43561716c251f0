//! One step of ours applied to OpenSubdiv's own regression outputs (`shared/data/subdiv`,
//! Hbr baselines) must give its next level: every vertex within 1e-6 (relative to the bounding
//! box), order-independently, and the same vertex and face counts.

use tessd_subdiv::{Boundary, SubdivOptions, subdivide};

mod common;
use common::{both_sided, one_sided, read, size};

fn check(shape: &str, boundary: Boundary) {
    for k in 0..2 {
        let cage = read(&format!("{shape}_level{k}.obj"));
        let want = read(&format!("{shape}_level{}.obj", k + 1));
        let options = SubdivOptions {
            boundary,
            ..SubdivOptions::default()
        };
        let got = subdivide(&cage, &options).unwrap();
        let size = size(&want);
        let used: Vec<[f32; 3]> = {
            let mut seen = vec![false; got.positions.len()];
            got.face_indices
                .iter()
                .for_each(|&v| seen[v as usize] = true);
            (0..got.positions.len())
                .filter(|&v| seen[v])
                .map(|v| got.positions[v])
                .collect()
        };
        assert_eq!(
            used.len(),
            want.positions.len(),
            "{shape} level {k}: vertices"
        );
        assert_eq!(
            got.face_count(),
            want.face_count(),
            "{shape} level {k}: faces"
        );
        let d = both_sided(&used, &want.positions);
        println!(
            "{shape} level {k} -> {}: max distance {:.3e} of size {size}",
            k + 1,
            d
        );
        assert!(d <= 1e-6 * size, "{shape} level {k}: off by {d}");
    }
}

#[test]
fn catmark_cube_matches_opensubdiv() {
    check("catmark_cube", Boundary::EdgeOnly);
}

#[test]
fn catmark_edgecorner_matches_opensubdiv() {
    check("catmark_edgecorner", Boundary::EdgeAndCorner);
}

#[test]
fn edge_only_boundary_is_not_the_reference_corner_rule() {
    // The negative control: the wrong corner rule must be caught by the same comparison.
    let cage = read("catmark_edgecorner_level0.obj");
    let want = read("catmark_edgecorner_level1.obj");
    let got = subdivide(&cage, &SubdivOptions::default()).unwrap();
    assert!(one_sided(&want.positions, &got.positions) > 1e-3);
}
