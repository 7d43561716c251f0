//! Generic attributes: named float data on the points, face corners or faces of a mesh, as
//! Blender, Houdini and USD keep them (weights, colours, extra UV maps, ids...).
//!
//! Every operation that makes a new mesh from an old one needs the same few moves to carry
//! them — take rows in a new order ([`Attribute::gather`]), average rows into slots
//! ([`RowMeans`]) — so they live here, below the crates that use them, and each algorithm only
//! says *which* rows go where.

use crate::MeshError;

/// Largest number of components (floats per row) of an attribute.
pub const MAX_COMPONENTS: usize = 64;

/// Longest attribute name, in bytes.
pub const MAX_NAME_BYTES: usize = 128;

/// Which elements an attribute has one row per.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Domain {
    /// One row per stored vertex (rows of `positions`).
    Point,
    /// One row per face corner, in `face_indices` order.
    Corner,
    /// One row per face.
    Face,
}

impl Domain {
    /// Every domain, in protocol order.
    pub const ALL: [Domain; 3] = [Domain::Point, Domain::Corner, Domain::Face];

    /// The protocol's prefix of the domain (`"point"`, `"corner"`, `"face"`).
    pub fn prefix(self) -> &'static str {
        match self {
            Domain::Point => "point",
            Domain::Corner => "corner",
            Domain::Face => "face",
        }
    }

    /// The elements counted, plural, for messages.
    pub fn elements(self) -> &'static str {
        match self {
            Domain::Point => "vertices",
            Domain::Corner => "face corners",
            Domain::Face => "faces",
        }
    }

    /// Splits a protocol name such as `"point:weight"` into its domain and name; `None` when
    /// it has none of the three prefixes.
    pub fn split_label(label: &str) -> Option<(Domain, &str)> {
        let (prefix, name) = label.split_once(':')?;
        let domain = Domain::ALL.into_iter().find(|d| d.prefix() == prefix)?;
        Some((domain, name))
    }
}

/// A named attribute: `components` floats per row, one row per element of its domain, rows
/// stored one after the other in `values`.
#[derive(Clone, Debug, PartialEq)]
pub struct Attribute {
    /// The name, without its domain prefix (non-empty, at most [`MAX_NAME_BYTES`] bytes).
    pub name: String,
    /// What the rows belong to.
    pub domain: Domain,
    /// Floats per row, 1..=[`MAX_COMPONENTS`].
    pub components: usize,
    /// `rows × components` floats.
    pub values: Vec<f32>,
    /// The values came as a plain list (one component, no row dimension): hosts get the same
    /// shape back. Ignored when `components` > 1.
    pub flat: bool,
}

impl Attribute {
    /// A new attribute of rows of `components` floats.
    pub fn new(name: &str, domain: Domain, components: usize, values: Vec<f32>) -> Attribute {
        Attribute {
            name: name.to_string(),
            domain,
            components,
            values,
            flat: false,
        }
    }

    /// The protocol name: domain prefix and name (`"point:weight"`).
    pub fn label(&self) -> String {
        format!("{}:{}", self.domain.prefix(), self.name)
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.values.len().checked_div(self.components).unwrap_or(0)
    }

    /// Row `i`.
    ///
    /// # Panics
    /// When `i` is out of range.
    pub fn row(&self, i: usize) -> &[f32] {
        &self.values[i * self.components..(i + 1) * self.components]
    }

    /// The same attribute with row `k` of the result taken from row `source[k]` of this one
    /// (reordering, repeating or dropping rows: triangulation, refinement, elimination).
    ///
    /// # Panics
    /// When an index in `source` is out of range.
    pub fn gather(&self, source: impl ExactSizeIterator<Item = u32>) -> Attribute {
        let c = self.components;
        let mut values = Vec::with_capacity(source.len() * c);
        for s in source {
            values.extend_from_slice(self.row(s as usize));
        }
        Attribute {
            values,
            ..self.empty_like()
        }
    }

    /// The same name, domain, components and shape, with no rows.
    pub fn empty_like(&self) -> Attribute {
        Attribute {
            name: self.name.clone(),
            domain: self.domain,
            components: self.components,
            values: Vec::new(),
            flat: self.flat,
        }
    }

    /// Checks the name, the component count, the row count against `expected` rows and that
    /// every value is finite; messages name the attribute by its protocol name.
    ///
    /// # Errors
    /// [`MeshError::Invalid`] such as `array "point:weight" has 10 rows; the mesh has 12
    /// vertices` or `point:weight row 7 is NaN`.
    pub fn check(&self, expected: usize) -> Result<(), MeshError> {
        let label = self.label();
        check_name(&label, &self.name)?;
        check_components(&label, self.components)?;
        if self.rows() * self.components != self.values.len() {
            return Err(MeshError::Invalid(format!(
                "array {label:?} holds {} values, not a whole number of rows of {}",
                self.values.len(),
                self.components
            )));
        }
        check_rows(&label, self.domain, self.rows(), expected)?;
        if let Some(i) = crate::block_scan::first_non_finite(&self.values) {
            return Err(MeshError::Invalid(format!(
                "{label} row {} is {}",
                i / self.components,
                self.values[i]
            )));
        }
        Ok(())
    }
}

/// The name rules: non-empty, at most [`MAX_NAME_BYTES`] bytes (`label` names it in messages).
///
/// # Errors
/// [`MeshError::Invalid`] naming the array.
pub fn check_name(label: &str, name: &str) -> Result<(), MeshError> {
    if name.is_empty() {
        return Err(MeshError::Invalid(format!(
            "array {label:?} needs a name after the domain prefix"
        )));
    }
    if name.len() > MAX_NAME_BYTES {
        return Err(MeshError::Invalid(format!(
            "array {label:?}: attribute names are at most {MAX_NAME_BYTES} bytes, this one has {}",
            name.len()
        )));
    }
    Ok(())
}

/// The component rule: 1..=[`MAX_COMPONENTS`].
///
/// # Errors
/// [`MeshError::Invalid`] naming the array and the count.
pub fn check_components(label: &str, components: usize) -> Result<(), MeshError> {
    if !(1..=MAX_COMPONENTS).contains(&components) {
        return Err(MeshError::Invalid(format!(
            "array {label:?} has {components} components per row; 1 to {MAX_COMPONENTS} are allowed"
        )));
    }
    Ok(())
}

/// The row rule: one row per element of the domain. Callers that copy the data check this
/// first, so that a hostile row count never sizes an allocation.
///
/// # Errors
/// [`MeshError::Invalid`]: `array "point:weight" has 10 rows; the mesh has 12 vertices`.
pub fn check_rows(
    label: &str,
    domain: Domain,
    rows: usize,
    expected: usize,
) -> Result<(), MeshError> {
    if rows != expected {
        return Err(MeshError::Invalid(format!(
            "array {label:?} has {rows} rows; the mesh has {expected} {}",
            domain.elements()
        )));
    }
    Ok(())
}

/// Unweighted means of rows gathered into slots: `add(slot, row)` for every contributing
/// row, then [`RowMeans::mean`] per slot. Sums are kept in f64 so that averaging thousands of
/// rows loses nothing visible in f32. Used where several input elements merge into one output
/// element (clusters of vertices, clusters of corners).
#[derive(Clone, Debug)]
pub struct RowMeans {
    components: usize,
    sums: Vec<f64>,
    counts: Vec<u32>,
}

impl RowMeans {
    /// `slots` empty slots of `components` floats.
    pub fn new(slots: usize, components: usize) -> RowMeans {
        RowMeans {
            components,
            sums: vec![0.0; slots * components],
            counts: vec![0; slots],
        }
    }

    /// Adds `row` to `slot`.
    pub fn add(&mut self, slot: usize, row: &[f32]) {
        let c = self.components;
        for (s, &v) in self.sums[slot * c..(slot + 1) * c].iter_mut().zip(row) {
            *s += f64::from(v);
        }
        self.counts[slot] += 1;
    }

    /// Appends the mean of `slot` to `out` (zeros for a slot nothing was added to).
    pub fn push_mean(&self, slot: usize, out: &mut Vec<f32>) {
        let c = self.components;
        let n = f64::from(self.counts[slot].max(1));
        out.extend(
            self.sums[slot * c..(slot + 1) * c]
                .iter()
                .map(|s| (s / n) as f32),
        );
    }

    /// Every slot's mean, in slot order.
    pub fn means(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.sums.len());
        for slot in 0..self.counts.len() {
            self.push_mean(slot, &mut out);
        }
        out
    }
}

/// The key of an undirected edge (either order gives the same key).
pub fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gather_and_means() {
        let a = Attribute::new("w", Domain::Point, 2, vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(a.label(), "point:w");
        assert_eq!(a.rows(), 3);
        let g = a.gather([2u32, 0, 2].into_iter());
        assert_eq!(g.values, vec![4.0, 5.0, 0.0, 1.0, 4.0, 5.0]);
        let mut m = RowMeans::new(2, 2);
        m.add(0, a.row(0));
        m.add(0, a.row(2));
        m.add(1, a.row(1));
        assert_eq!(m.means(), vec![2.0, 3.0, 2.0, 3.0]);
    }

    #[test]
    fn labels_split() {
        assert_eq!(
            Domain::split_label("corner:uv:2"),
            Some((Domain::Corner, "uv:2"))
        );
        assert_eq!(Domain::split_label("face:"), Some((Domain::Face, "")));
        assert_eq!(Domain::split_label("vertex:x"), None);
        assert_eq!(Domain::split_label("positions"), None);
    }

    #[test]
    fn checks_name_the_array() {
        let mut a = Attribute::new("weight", Domain::Point, 1, vec![0.0; 10]);
        assert_eq!(
            a.check(12).unwrap_err().to_string(),
            "array \"point:weight\" has 10 rows; the mesh has 12 vertices"
        );
        a.values[7] = f32::NAN;
        assert_eq!(
            a.check(10).unwrap_err().to_string(),
            "point:weight row 7 is NaN"
        );
        a.components = 65;
        assert!(
            a.check(10)
                .unwrap_err()
                .to_string()
                .contains("65 components")
        );
        let long = Attribute::new(&"n".repeat(129), Domain::Face, 1, vec![]);
        assert!(
            long.check(0)
                .unwrap_err()
                .to_string()
                .contains("at most 128 bytes")
        );
    }
}
