//! Meshes built to break a vertex-clustering error bound: features thinner than any cell, so
//! that their faces collapse and their images must still lie on the output. Shared by
//! `tests/surface_bound.rs` and the guarantee table of `bench/simplify` (`#[path]` include).

#![allow(dead_code)]

use tessd_mesh::Mesh;

/// A deterministic stream of uniform numbers in [0, 1) (SplitMix64).
pub struct Stream(u64);

impl Stream {
    /// A stream from a seed.
    pub fn new(seed: u64) -> Stream {
        Stream(seed)
    }

    /// The next number in [0, 1).
    pub fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// An `n × n` grid of triangles over the unit square, heights from `z(x, y)`; returns the mesh
/// and the index of the first vertex (row-major, `(n + 1)²` vertices).
fn grid(m: &mut Mesh, n: u32, z: impl Fn(f32, f32) -> f32) -> u32 {
    let first = m.positions.len() as u32;
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions.push([x, y, z(x, y)]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = first + j * (n + 1) + i;
            m.push_face(&[v, v + 1, v + n + 2]);
            m.push_face(&[v, v + n + 2, v + n + 1]);
        }
    }
    first
}

/// A flat 30 × 30 grid with 60 thin spikes: square pyramids 0.0002 wide at the base and 0.05
/// to 0.3 tall, standing on their own base vertices just above the plane.
pub fn spikes() -> Mesh {
    let mut m = Mesh::default();
    grid(&mut m, 30, |_, _| 0.0);
    let mut r = Stream::new(1);
    for _ in 0..60 {
        let (x, y, h) = (r.next(), r.next(), 0.05 + 0.25 * r.next());
        let w = 0.0001;
        let b = m.positions.len() as u32;
        m.positions.extend([
            [x - w, y - w, 0.0],
            [x + w, y - w, 0.0],
            [x + w, y + w, 0.0],
            [x - w, y + w, 0.0],
            [x, y, h],
        ]);
        for k in 0..4 {
            m.push_face(&[b + k, b + (k + 1) % 4, b + 4]);
        }
        m.push_face(&[b, b + 3, b + 2]);
        m.push_face(&[b, b + 2, b + 1]);
    }
    m
}

/// A 20 × 20 grid with 12 fins: thin closed walls 0.6 long, 0.0002 thick and 0.1 to 0.4 tall,
/// each side a strip of 24 quads (split in two triangles).
pub fn fins() -> Mesh {
    let mut m = Mesh::default();
    grid(&mut m, 20, |_, _| 0.0);
    let mut r = Stream::new(2);
    for _ in 0..12 {
        let (x0, y, h) = (0.2 * r.next(), r.next(), 0.1 + 0.3 * r.next());
        let t = 0.0001;
        let n = 24u32;
        let b = m.positions.len() as u32;
        // Four rows of n + 1 vertices: bottom and top of the near side, then the far side.
        for (dy, z) in [(-t, 0.0), (-t, h), (t, 0.0), (t, h)] {
            for i in 0..=n {
                m.positions
                    .push([x0 + 0.6 * i as f32 / n as f32, y + dy, z]);
            }
        }
        let row = |k: u32, i: u32| b + k * (n + 1) + i;
        for i in 0..n {
            // Near side (rows 0, 1), far side (rows 2, 3, reversed), and the top (1, 3).
            m.push_face(&[row(0, i), row(0, i + 1), row(1, i + 1)]);
            m.push_face(&[row(0, i), row(1, i + 1), row(1, i)]);
            m.push_face(&[row(2, i), row(3, i + 1), row(2, i + 1)]);
            m.push_face(&[row(2, i), row(3, i), row(3, i + 1)]);
            m.push_face(&[row(1, i), row(1, i + 1), row(3, i + 1)]);
            m.push_face(&[row(1, i), row(3, i + 1), row(3, i)]);
        }
        // The two ends.
        m.push_face(&[row(0, 0), row(1, 0), row(3, 0)]);
        m.push_face(&[row(0, 0), row(3, 0), row(2, 0)]);
        m.push_face(&[row(0, n), row(3, n), row(1, n)]);
        m.push_face(&[row(0, n), row(2, n), row(3, n)]);
    }
    m
}

/// A wavy sheet 40 × 40 folded back on itself: the upper layer lies 0.0002 above the lower one
/// and the two meet along a fold at x = 1.
pub fn folded_sheet() -> Mesh {
    let mut m = Mesh::default();
    let n = 40u32;
    let wave = |x: f32, y: f32| 0.05 * (6.0 * x).sin() * (4.0 * y).cos();
    let lower = grid(&mut m, n, wave);
    let upper = grid(&mut m, n, |x, y| wave(x, y) + 0.0002);
    // Weld the upper layer's column x = 1 onto the lower one's: the fold.
    let last = n;
    for f in m.face_indices.iter_mut() {
        let v = *f;
        if v >= upper && (v - upper) % (n + 1) == last {
            *f = lower + (v - upper);
        }
    }
    m
}

/// A comb: a spine strip along x and 80 slivers (teeth 0.7 long, 0.00005 wide at the spine,
/// alternately tilted up and down), each tooth one triangle.
pub fn comb() -> Mesh {
    let mut m = Mesh::default();
    let teeth = 80u32;
    // The spine: two rows of teeth + 1 vertices, 0.05 apart.
    for y in [0.0f32, 0.05] {
        for i in 0..=teeth {
            m.positions.push([i as f32 / teeth as f32, y, 0.0]);
        }
    }
    for i in 0..teeth {
        let (a, b) = (i, teeth + 1 + i);
        m.push_face(&[a, a + 1, b + 1]);
        m.push_face(&[a, b + 1, b]);
    }
    for i in 0..teeth {
        let x = (i as f32 + 0.5) / teeth as f32;
        let z = if i % 2 == 0 { 0.15 } else { -0.15 };
        let b = m.positions.len() as u32;
        m.positions.extend([
            [x - 0.000025, 0.05, 0.0],
            [x + 0.000025, 0.05, 0.0],
            [x, 0.75, z],
        ]);
        m.push_face(&[b, b + 1, b + 2]);
    }
    m
}

/// A scanned-like surface: a sphere of radius 1 as a 160 × 80 latitude-longitude grid whose
/// vertices are displaced radially by noise of up to ±0.5 % and by 200 sharp bumps.
pub fn noisy_scan() -> Mesh {
    let mut m = Mesh::default();
    let (nu, nv) = (160u32, 80u32);
    let mut r = Stream::new(5);
    let bumps: Vec<[f32; 3]> = (0..200)
        .map(|_| {
            let (u, v) = (
                std::f32::consts::TAU * r.next(),
                std::f32::consts::PI * r.next(),
            );
            [v.sin() * u.cos(), v.sin() * u.sin(), v.cos()]
        })
        .collect();
    for j in 0..=nv {
        for i in 0..nu {
            let (u, v) = (
                std::f32::consts::TAU * i as f32 / nu as f32,
                std::f32::consts::PI * j as f32 / nv as f32,
            );
            let d = [v.sin() * u.cos(), v.sin() * u.sin(), v.cos()];
            let bump: f32 = bumps
                .iter()
                .map(|b| {
                    let c = d[0] * b[0] + d[1] * b[1] + d[2] * b[2];
                    0.05 * (((c - 1.0) * 2000.0).exp())
                })
                .sum();
            let radius = 1.0 + 0.01 * (r.next() - 0.5) + bump;
            m.positions.push(d.map(|x| x * radius));
        }
    }
    let at = |i: u32, j: u32| j * nu + i % nu;
    for j in 0..nv {
        for i in 0..nu {
            m.push_face(&[at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            m.push_face(&[at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    m
}

/// Every adversarial mesh with its name.
pub fn all() -> Vec<(&'static str, Mesh)> {
    vec![
        ("spikes", spikes()),
        ("fins", fins()),
        ("folded sheet", folded_sheet()),
        ("comb of slivers", comb()),
        ("noisy scan", noisy_scan()),
    ]
}
