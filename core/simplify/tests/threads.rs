//! The same bytes whatever the thread count (issue 15, "every core"): every parallel pass
//! works in fixed blocks and combines them in block order, so 1, 2 and 7 threads must give
//! identical positions (to the bit) and faces.

use tessd_mesh::io::{ReadOptions, read_path};
use tessd_simplify::{
    Count, GridSize, Length, Method, Representative, Simplified, SimplifyOptions, simplify,
};

fn run(mesh: &tessd_mesh::Mesh, options: &SimplifyOptions, threads: usize) -> Simplified {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| simplify(mesh, options, &mut |_, _| true).unwrap())
}

fn bits(s: &Simplified) -> (Vec<u32>, &[u32], &[u32]) {
    let p = s
        .mesh
        .positions
        .iter()
        .flatten()
        .map(|x| x.to_bits())
        .collect();
    (p, &s.mesh.face_offsets, &s.mesh.face_indices)
}

#[test]
fn outputs_are_identical_on_1_2_and_7_threads() {
    let path = tessd_testdata::shared("mesh/stanford_bunny.obj");
    let mesh = read_path(&path, &ReadOptions::default()).unwrap();
    let reps = [Representative::Barycenter, Representative::Quadric];
    let methods = [
        Method::Grid(GridSize::CellsPerAxis(60)),
        Method::Grid(GridSize::CellsPerAxis(8)),
        Method::Quality(Length::Relative(0.01)),
        Method::Complexity(Count::Relative(0.1)),
    ];
    for method in methods {
        for rep in reps {
            let options = SimplifyOptions::new(method).with_representative(rep);
            let one = run(&mesh, &options, 1);
            assert!(one.mesh.face_count() > 0);
            for threads in [2, 7] {
                let other = run(&mesh, &options, threads);
                assert!(
                    bits(&one) == bits(&other),
                    "{method:?} {rep:?}: {threads} threads differ from 1"
                );
                assert_eq!(one.report, other.report, "{method:?} {rep:?}");
            }
        }
    }
}
