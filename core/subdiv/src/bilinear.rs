//! Bilinear refinement, one level (OpenSubdiv's `SCHEME_BILINEAR`, Blender's "Simple"): the
//! faces of a Catmull–Clark step with linear masks — a face point is its face's centroid, an
//! edge point its edge's midpoint, a vertex point the vertex itself. The surface does not move,
//! it only gets denser, so it is what face-varying data uses when it must stay linear.
//!
//! Faces and creases come from [`catmull_clark::split_faces`] and
//! [`catmull_clark::split_creases`], so a bilinear level has the same faces, face for face and
//! vertex for vertex, as a Catmull–Clark level of the same cage. Sharpness does not change the
//! masks but is still carried down (decremented per level) so that the refined mesh keeps its
//! creases.

use crate::boundary::Boundary;
use crate::catmull_clark;
use crate::error::SubdivError;
use crate::level::{Level, RowBuilder, table_for};
use crate::topology::{Faces, Topology};

/// Refines `faces` (with adjacency `topo`) one level; `boundary` has no effect (boundaries of
/// a bilinear surface are its edges). New vertices are numbered face points, edge points, then
/// vertex points, as Catmull–Clark's.
///
/// # Errors
/// None for now; the signature is every scheme's.
pub fn refine(faces: &Faces, topo: &Topology, _boundary: Boundary) -> Result<Level, SubdivError> {
    let (nf, ne, nv) = (
        faces.len(),
        topo.edge_vertices.len(),
        faces.vertex_count as usize,
    );
    let mut table = table_for(faces.vertex_count, nf + ne + nv);
    let mut row = RowBuilder::default();
    for f in 0..nf {
        row.add_face(faces.face(f), 1.0);
        row.push_to(&mut table);
    }
    for &[a, b] in &topo.edge_vertices {
        row.add(a, 0.5);
        row.add(b, 0.5);
        row.push_to(&mut table);
    }
    for v in 0..nv as u32 {
        row.add(v, 1.0);
        row.push_to(&mut table);
    }
    let (out, face_parent) = catmull_clark::split_faces(faces, topo);
    Ok(Level {
        creases: catmull_clark::split_creases(topo, nf),
        faces: out,
        table,
        face_parent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stencil::StencilTable;

    /// A 3×2 grid of quads with a pentagon glued on top: n-gons and boundaries both.
    fn cage() -> (Faces, Vec<[f64; 2]>) {
        let mut pts = Vec::new();
        for y in 0..3 {
            for x in 0..4 {
                pts.push([x as f64 * 1.3, y as f64 * 0.7 + 0.1 * x as f64]);
            }
        }
        pts.push([2.0, 2.4]);
        let mut indices = Vec::new();
        let mut offsets = vec![0u32];
        for y in 0..2u32 {
            for x in 0..3u32 {
                let v = y * 4 + x;
                indices.extend_from_slice(&[v, v + 1, v + 5, v + 4]);
                offsets.push(indices.len() as u32);
            }
        }
        // The pentagon shares the grid's top edges; vertex 12 is its apex.
        indices.extend_from_slice(&[8, 9, 10, 11, 12]);
        offsets.push(indices.len() as u32);
        (
            Faces {
                offsets,
                indices,
                vertex_count: pts.len() as u32,
            },
            pts,
        )
    }

    fn refine_n(faces: &Faces, levels: usize) -> (Vec<StencilTable>, Faces) {
        let mut cur = faces.clone();
        let mut tables = Vec::new();
        for _ in 0..levels {
            let topo = Topology::build(&cur, &[]).unwrap();
            let level = refine(&cur, &topo, Boundary::EdgeOnly).unwrap();
            tables.push(level.table);
            cur = level.faces;
        }
        (tables, cur)
    }

    #[test]
    fn linear_functions_are_reproduced_exactly() {
        let (faces, pts) = cage();
        // f(x, y) = 3x − 2y + 0.5 on the cage; bilinear refinement must give f of the refined
        // points, whatever the level.
        let f = |p: [f64; 2]| 3.0 * p[0] - 2.0 * p[1] + 0.5;
        let data: Vec<f32> = pts
            .iter()
            .flat_map(|&p| [p[0] as f32, p[1] as f32, f(p) as f32])
            .collect();
        for levels in 1..=3 {
            let (tables, out) = refine_n(&faces, levels);
            let refined = StencilTable::apply_chain(&tables, &data, 3);
            assert_eq!(refined.len(), out.vertex_count as usize * 3);
            for r in refined.chunks_exact(3) {
                let want = f([f64::from(r[0]), f64::from(r[1])]);
                assert!(
                    (f64::from(r[2]) - want).abs() < 1e-5,
                    "level {levels}: {} vs {want}",
                    r[2]
                );
            }
        }
    }

    #[test]
    fn faces_equal_catmull_clarks() {
        use crate::{Refiner, Scheme, SubdivOptions};
        use tessd_mesh::{Crease, Mesh};
        let (faces, pts) = cage();
        let cage = Mesh {
            positions: pts
                .iter()
                .map(|p| [p[0] as f32, p[1] as f32, 0.0])
                .collect(),
            face_offsets: faces.offsets.clone(),
            face_indices: faces.indices.clone(),
            creases: vec![Crease {
                a: 5,
                b: 6,
                value: 2.5,
            }],
            ..Mesh::default()
        };
        let refine_with = |scheme| {
            let options = SubdivOptions {
                scheme,
                ..SubdivOptions::default()
            };
            Refiner::new(&cage, &options).unwrap()
        };
        let (ours, cc) = (
            refine_with(Scheme::Bilinear),
            refine_with(Scheme::CatmullClark),
        );
        assert_eq!(ours.faces, cc.faces);
        assert_eq!(ours.face_origin, cc.face_origin);
        assert_eq!(ours.tables[0].len(), cc.tables[0].len());
        let sorted = |c: &[([u32; 2], f32)]| {
            let mut c: Vec<_> = c
                .iter()
                .map(|&([a, b], s)| ([a.min(b), a.max(b)], s))
                .collect();
            c.sort_by_key(|c| c.0);
            c
        };
        assert_eq!(sorted(&ours.creases), sorted(&cc.creases));
        // The cage corners stay where they are.
        let topo = Topology::build(&faces, &[]).unwrap();
        let vp = faces.len() + topo.edge_vertices.len();
        for v in 0..faces.vertex_count as usize {
            assert_eq!(
                ours.tables[0].row(vp + v).collect::<Vec<_>>(),
                vec![(v as u32, 1.0)]
            );
        }
    }
}
