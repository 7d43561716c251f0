//! The crack check of a tessellation: vertices of equal position welded (bit for bit, as the
//! tessellator writes shared edge samples once), then every edge counted by the triangles using
//! it. On a closed solid an edge used by one triangle is a crack (or a hole); one used by more
//! than two is non-manifold. Written like `core/tessellate/tests/common` (`open_edges`), with
//! counts instead of a list.

use std::collections::HashMap;
use tessd_tessellate::Tessellation;

/// What the check found.
#[derive(Clone, Debug, Default)]
pub struct Cracks {
    /// Distinct positions.
    pub welded_vertices: usize,
    /// Edges used by exactly one triangle.
    pub open_edges: usize,
    /// Edges used by more than two triangles.
    pub nonmanifold_edges: usize,
    /// Triangles with two corners welded together (left out of the count).
    pub collapsed_triangles: usize,
    /// Up to four open edges, as their two end points.
    pub examples: Vec<[[f32; 3]; 2]>,
    /// Up to four non-manifold edges: their end points and the face groups using them.
    pub nonmanifold_examples: Vec<([[f32; 3]; 2], Vec<u32>)>,
}

/// Welds `t`'s positions and counts its edges' uses.
pub fn cracks(t: &Tessellation) -> Cracks {
    let mesh = &t.mesh;
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut pos: Vec<[f32; 3]> = Vec::new();
    let welded: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            // -0.0 and 0.0 are the same point.
            let key = p.map(|c| if c == 0.0 { 0 } else { c.to_bits() });
            *ids.entry(key).or_insert_with(|| {
                pos.push(*p);
                (pos.len() - 1) as u32
            })
        })
        .collect();
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    let mut groups: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    let mut out = Cracks {
        welded_vertices: pos.len(),
        ..Cracks::default()
    };
    for (i, f) in mesh.faces().enumerate() {
        let w: Vec<u32> = f.iter().map(|&v| welded[v as usize]).collect();
        let n = w.len();
        if (0..n).any(|k| w[k] == w[(k + 1) % n]) || (n == 3 && w[0] == w[2]) {
            out.collapsed_triangles += 1;
            continue;
        }
        for k in 0..n {
            let (a, b) = (w[k], w[(k + 1) % n]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            groups
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push(mesh.face_groups[i]);
        }
    }
    for (&(a, b), &n) in &uses {
        if n == 1 {
            out.open_edges += 1;
            if out.examples.len() < 4 {
                out.examples.push([pos[a as usize], pos[b as usize]]);
            }
        } else if n > 2 {
            out.nonmanifold_edges += 1;
            if out.nonmanifold_examples.len() < 4 {
                out.nonmanifold_examples.push((
                    [pos[a as usize], pos[b as usize]],
                    groups.remove(&(a, b)).unwrap_or_default(),
                ));
            }
        }
    }
    out
}

/// The chordal deviation of a tessellation, estimated at triangle centroids: the distance from
/// a triangle's centroid to its face's surface, found by projecting the centroid onto the
/// surface with a few Gauss–Newton steps started at the mean of the corners' (u, v) (the
/// untrimmed surface, parameters clamped to the face's bounds). The same measure is taken of
/// OCP's meshes (peer_ocp.py), so the two compare; a triangle's largest deviation is usually
/// near its centroid, so this is a close lower bound of the chordal error.
#[derive(Clone, Debug, Default)]
pub struct Deviation {
    /// The largest, document units.
    pub max: f64,
    /// The 99th percentile.
    pub p99: f64,
    /// Triangles over the tolerance.
    pub over: usize,
    /// The face id of the largest.
    pub worst_face: Option<u64>,
    /// The (u, v) of the worst triangle's corners.
    pub worst_uvs: Vec<[f64; 2]>,
}

/// Gauss–Newton steps of the projection.
const PROJECTION_STEPS: usize = 6;

/// The distance from `c` to `face`'s surface near (u, v).
pub fn distance_to_surface(face: &tessd_brep::Face, c: [f64; 3], uv: [f64; 2]) -> f64 {
    let [u0, u1, v0, v1] = face.bounds;
    let (mut u, mut v) = (uv[0], uv[1]);
    let c = tessd_brep::DVec3::from(c);
    let mut best = f64::INFINITY;
    for _ in 0..=PROJECTION_STEPS {
        let sp = face.surface.eval(u, v);
        let r = c - sp.point;
        best = best.min(r.length());
        let (a, b, d) = (sp.du.dot(sp.du), sp.du.dot(sp.dv), sp.dv.dot(sp.dv));
        let det = a * d - b * b;
        if !(det.abs() > 1e-30 && det.is_finite()) {
            break;
        }
        let (gu, gv) = (sp.du.dot(r), sp.dv.dot(r));
        u = (u + (d * gu - b * gv) / det).clamp(u0, u1);
        v = (v + (a * gv - b * gu) / det).clamp(v0, v1);
    }
    best
}

/// Measures `t`'s centroid deviation from `doc`'s surfaces against `tol` (document units).
pub fn deviation(doc: &tessd_brep::Document, t: &Tessellation, tol: f64) -> Deviation {
    let mesh = &t.mesh;
    let mut all = Vec::with_capacity(mesh.face_count());
    let mut out = Deviation::default();
    for (i, f) in mesh.faces().enumerate() {
        let face = &doc.faces[mesh.face_groups[i] as usize];
        let n = f.len() as f64;
        let mut uv = [0.0; 2];
        let mut c = [0.0; 3];
        // The absolute positions: the f32 ones are relative to `t.placement`'s origin for a
        // part far from the origin (hammer.iges).
        for &v in f {
            let (q, p) = (t.uvs[v as usize], t.points[v as usize]);
            uv = [uv[0] + q[0] / n, uv[1] + q[1] / n];
            for k in 0..3 {
                c[k] += p[k] / n;
            }
        }
        let d = distance_to_surface(face, c, uv);
        if !d.is_finite() {
            continue;
        }
        if d > out.max {
            out.max = d;
            out.worst_face = Some(face.id);
            out.worst_uvs = f.iter().map(|&v| t.uvs[v as usize]).collect();
        }
        out.over += usize::from(d > tol);
        all.push(d);
    }
    if !all.is_empty() {
        let k = ((all.len() as f64 * 0.99) as usize).min(all.len() - 1);
        all.select_nth_unstable_by(k, f64::total_cmp);
        out.p99 = all[k];
    }
    out
}
