//! The GPU apply phase against the CPU one (`StencilTable::apply_chain`), on whatever adapter
//! wgpu finds; in CI that is lavapipe, Mesa's software Vulkan driver. No adapter is a failure,
//! not a skip: a test that silently skips would hide a broken CI setup.

use std::sync::OnceLock;

use tessd_gpu::{GpuError, GpuStencils};
use tessd_subdiv::StencilTable;

/// One device for all tests (creating one compiles the kernel, slow on lavapipe).
fn gpu() -> &'static GpuStencils {
    static GPU: OnceLock<GpuStencils> = OnceLock::new();
    GPU.get_or_init(|| match GpuStencils::new() {
        Ok(g) => {
            println!("adapter: {}", g.adapter_info());
            g
        }
        Err(e) => panic!("no GPU for the stencil tests: {e}"),
    })
}

/// SplitMix64: small, deterministic, good enough for test data.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n`.
    fn below(&mut self, n: u32) -> u32 {
        (((self.next() >> 32) * n as u64) >> 32) as u32
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A valid random table: `rows` rows of 1–12 terms over `source_count` sources, positive
/// weights summing to 1 per row.
fn random_table(rng: &mut Rng, source_count: u32, rows: usize) -> StencilTable {
    let mut t = StencilTable {
        offsets: vec![0],
        source_count,
        ..Default::default()
    };
    for _ in 0..rows {
        let terms = 1 + rng.below(12) as usize;
        let raw: Vec<f32> = (0..terms).map(|_| 0.05 + rng.unit()).collect();
        let sum: f32 = raw.iter().sum();
        for w in raw {
            t.sources.push(rng.below(source_count));
            t.weights.push(w / sum);
        }
        t.offsets.push(t.sources.len() as u32);
    }
    t
}

/// A chain of three levels: `cage` rows growing roughly ×4 per level like Catmull–Clark.
fn random_chain(rng: &mut Rng, cage: u32, levels: usize) -> Vec<StencilTable> {
    let mut tables = Vec::new();
    let mut rows = cage;
    for _ in 0..levels {
        let next = rows * 4 - rng.below(rows);
        tables.push(random_table(rng, rows, next as usize));
        rows = next;
    }
    tables
}

fn random_data(rng: &mut Rng, floats: usize) -> Vec<f32> {
    (0..floats).map(|_| (rng.unit() - 0.5) * 200.0).collect()
}

/// Asserts `gpu` equals `cpu` within 1e-5 relative to the data's magnitude.
fn assert_close(gpu: &[f32], cpu: &[f32], what: &str) {
    assert_eq!(gpu.len(), cpu.len(), "{what}: lengths");
    let scale = cpu.iter().fold(1e-30f32, |m, x| m.max(x.abs()));
    let (mut worst, mut at) = (0.0f32, 0);
    for (i, (g, c)) in gpu.iter().zip(cpu).enumerate() {
        let d = (g - c).abs();
        // NaN counts as worst.
        if d > worst || d.is_nan() {
            (worst, at) = (d, i);
        }
    }
    assert!(
        worst <= 1e-5 * scale,
        "{what}: GPU {} vs CPU {} at {at}: difference {worst} over 1e-5 × {scale}",
        gpu[at],
        cpu[at]
    );
}

#[test]
fn matches_cpu_three_levels() {
    let gpu = gpu();
    let mut rng = Rng(0x7E55_D000);
    let tables = random_chain(&mut rng, 300, 3);
    let rows: Vec<usize> = tables.iter().map(|t| t.len()).collect();
    let uploaded = gpu.upload(&tables).expect("upload");
    assert_eq!(uploaded.levels(), 3);
    for stride in [3, 5] {
        // Two frames on the same upload: topology is reused across an animation.
        for frame in 0..2 {
            let src = random_data(&mut rng, 300 * stride);
            let cpu = StencilTable::apply_chain(&tables, &src, stride);
            let (out, time) = gpu.apply_timed(&uploaded, &src, stride).expect("apply");
            println!("stride {stride} frame {frame}: rows {rows:?}, GPU apply {time:?}");
            assert_close(&out, &cpu, &format!("stride {stride} frame {frame}"));
        }
    }
}

#[test]
fn wide_rows_and_single_level() {
    // Stride over the kernel's 8-component block, and an odd number of levels (result in
    // the second buffer) against an even one.
    let gpu = gpu();
    let mut rng = Rng(42);
    let tables = random_chain(&mut rng, 100, 2);
    for (levels, stride) in [(1, 11), (2, 11), (2, 16), (1, 1)] {
        let chain = &tables[..levels];
        let src = random_data(&mut rng, 100 * stride);
        let cpu = StencilTable::apply_chain(chain, &src, stride);
        let out = gpu
            .apply(&gpu.upload(chain).unwrap(), &src, stride)
            .unwrap();
        assert_close(&out, &cpu, &format!("{levels} levels, stride {stride}"));
    }
}

#[test]
fn empty_tables() {
    let gpu = gpu();
    // No levels: the data comes back unchanged, like apply_chain.
    let none = gpu.upload(&[]).unwrap();
    assert_eq!(gpu.apply(&none, &[], 3).unwrap(), Vec::<f32>::new());
    // A level with no rows, then a level reading those zero rows and making none.
    let empty = StencilTable {
        offsets: vec![0],
        source_count: 4,
        ..Default::default()
    };
    let empty2 = StencilTable {
        offsets: vec![0],
        source_count: 0,
        ..Default::default()
    };
    let src = [1.0f32; 12];
    for chain in [vec![empty.clone()], vec![empty, empty2]] {
        let t = gpu.upload(&chain).unwrap();
        assert_eq!(t.output_rows(), 0);
        assert_eq!(
            gpu.apply(&t, &src, 3).unwrap(),
            StencilTable::apply_chain(&chain, &src, 3)
        );
    }
    // Rows with no terms are zero.
    let zero_terms = StencilTable {
        offsets: vec![0, 0, 0],
        source_count: 4,
        ..Default::default()
    };
    let t = gpu.upload(std::slice::from_ref(&zero_terms)).unwrap();
    assert_eq!(gpu.apply(&t, &src, 3).unwrap(), vec![0.0; 6]);
    // Stride 0: nothing to compute.
    assert_eq!(gpu.apply(&t, &[], 0).unwrap(), Vec::<f32>::new());
}

#[test]
fn wrong_src_length_is_an_error() {
    let gpu = gpu();
    let mut rng = Rng(7);
    let tables = random_chain(&mut rng, 50, 2);
    let t = gpu.upload(&tables).unwrap();
    for len in [0, 50 * 3 - 1, 50 * 3 + 1] {
        let err = gpu.apply(&t, &vec![0.0; len], 3).unwrap_err();
        assert!(
            matches!(err, GpuError::SrcLength { got, expected: 150, .. } if got == len),
            "{err}"
        );
    }
}

#[test]
fn malformed_tables_are_errors() {
    let gpu = gpu();
    let good = StencilTable {
        offsets: vec![0, 1, 3],
        sources: vec![0, 0, 1],
        weights: vec![1.0, 0.5, 0.5],
        source_count: 2,
    };
    let mut bad_source = good.clone();
    bad_source.sources[2] = 2;
    let mut bad_offsets = good.clone();
    bad_offsets.offsets = vec![0, 3, 2];
    let mut short = good.clone();
    short.weights.pop();
    for t in [bad_source, bad_offsets, short] {
        let err = gpu.upload(&[t]).err().expect("malformed table accepted");
        assert!(
            matches!(err, GpuError::InvalidTable { level: 0, .. }),
            "{err}"
        );
    }
    // The second level must read the rows the first makes.
    let mut next = good.clone();
    next.source_count = 3;
    let err = gpu
        .upload(&[good, next])
        .err()
        .expect("mismatched chain accepted");
    assert!(
        matches!(err, GpuError::InvalidTable { level: 1, .. }),
        "{err}"
    );
}

#[test]
fn two_dimensional_grid() {
    // More rows than one dispatch dimension covers (65535 workgroups × 64 by default), so the
    // kernel runs on a 2-D grid; rows near the end land in the second grid row.
    let gpu = gpu();
    let per_dim = gpu.limits().max_compute_workgroups_per_dimension as usize;
    let rows = per_dim * 64 + 5000;
    let mut rng = Rng(99);
    let mut t = StencilTable {
        offsets: Vec::with_capacity(rows + 1),
        source_count: 1000,
        ..Default::default()
    };
    t.offsets.push(0);
    for _ in 0..rows {
        let a = rng.below(1000);
        let w = rng.unit();
        t.sources.extend([a, (a + 1) % 1000]);
        t.weights.extend([w, 1.0 - w]);
        t.offsets.push(t.sources.len() as u32);
    }
    let chain = [t];
    let src = random_data(&mut rng, 1000);
    let cpu = StencilTable::apply_chain(&chain, &src, 1);
    let (out, time) = gpu
        .apply_timed(&gpu.upload(&chain).unwrap(), &src, 1)
        .unwrap();
    println!("2-D grid: {rows} rows, GPU apply {time:?}");
    assert_close(&out, &cpu, "2-D grid");
}
