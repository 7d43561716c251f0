//! Reading inputs and the figures of an input mesh that the searches and reports use.

use std::path::Path;
use tessd_mesh::Mesh;
use tessd_mesh::io::{ReadOptions, read_path};

use crate::methods;

/// Reads a mesh file (the error names the path).
pub fn read(path: &Path) -> Result<Mesh, String> {
    read_path(path, &ReadOptions::default()).map_err(|e| format!("{}: {e}", path.display()))
}

/// Figures of an input mesh.
pub struct Stats {
    /// Vertices referenced by a face.
    pub vertices: u64,
    /// Triangles after fan triangulation.
    pub triangles: u64,
    /// 12 B per position and per triangle: the indexed-triangle input.
    pub input_bytes: u64,
    /// Largest side of the bounding box.
    pub size: f64,
    /// Diagonal of the bounding box.
    pub diagonal: f64,
    /// Surface area.
    pub area: f64,
}

/// The figures of `m`.
pub fn stats(m: &Mesh) -> Stats {
    let (lo, hi) = m.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
    let d: Vec<f64> = (0..3).map(|k| f64::from(hi[k] - lo[k])).collect();
    let mut area = 0.0;
    for f in m.faces() {
        let p = |i: u32| m.positions[i as usize].map(f64::from);
        let o = p(f[0]);
        for k in 1..f.len() - 1 {
            let (a, b) = (p(f[k]), p(f[k + 1]));
            let u = [a[0] - o[0], a[1] - o[1], a[2] - o[2]];
            let v = [b[0] - o[0], b[1] - o[1], b[2] - o[2]];
            let c = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            area += 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        }
    }
    let triangles = m.triangle_count() as u64;
    Stats {
        vertices: methods::referenced(&m.face_indices, m.positions.len()),
        triangles,
        input_bytes: 12 * m.positions.len() as u64 + 12 * triangles,
        size: d.iter().copied().fold(0.0, f64::max),
        diagonal: d.iter().map(|x| x * x).sum::<f64>().sqrt(),
        area,
    }
}

/// The CPU's model name from `/proc/cpuinfo` (empty when unknown).
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find_map(|l| {
                l.strip_prefix("model name")
                    .map(|r| r.trim_start_matches([' ', '\t', ':']).to_string())
            })
        })
        .unwrap_or_default()
}
