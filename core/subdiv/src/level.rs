//! What one refinement step of any scheme produces, and the row builder every scheme writes
//! its stencils with.

use crate::stencil::StencilTable;
use crate::topology::Faces;

/// One refined level.
#[derive(Clone, Debug, Default)]
pub struct Level {
    /// The new faces.
    pub faces: Faces,
    /// New vertices from the old (each scheme documents its vertex order).
    pub table: StencilTable,
    /// Sharp edges of the new level ((a, b), sharpness), boundary edges not listed.
    pub creases: Vec<([u32; 2], f32)>,
    /// The old face each new face comes from.
    pub face_parent: Vec<u32>,
}

/// A stencil row under construction: (source, weight) terms, duplicates merged when pushed.
#[derive(Default)]
pub struct RowBuilder(Vec<(u32, f64)>);

impl RowBuilder {
    /// Adds `w` times old vertex `v`.
    pub fn add(&mut self, v: u32, w: f64) {
        self.0.push((v, w));
    }

    /// Adds the centroid of `face` with weight `w`.
    pub fn add_face(&mut self, face: &[u32], w: f64) {
        let each = w / face.len() as f64;
        face.iter().for_each(|&v| self.add(v, each));
    }

    /// Appends the merged row (sources ascending) to `t` and empties this builder.
    pub fn push_to(&mut self, t: &mut StencilTable) {
        self.0.sort_unstable_by_key(|e| e.0);
        let mut last = u32::MAX;
        for &(v, w) in &self.0 {
            if v == last {
                *t.weights.last_mut().expect("a term") += w as f32;
            } else {
                t.sources.push(v);
                t.weights.push(w as f32);
                last = v;
            }
        }
        t.offsets.push(t.sources.len() as u32);
        self.0.clear();
    }
}

/// An empty table over `source_count` old vertices with room for `rows` rows.
pub fn table_for(source_count: u32, rows: usize) -> StencilTable {
    let mut offsets = Vec::with_capacity(rows + 1);
    offsets.push(0);
    StencilTable {
        offsets,
        source_count,
        ..StencilTable::default()
    }
}
