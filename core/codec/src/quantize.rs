//! Quantisation of the input points to `p` bits per coordinate in their cubic bounding box
//! (paper 003 §5.1, "Quantification des coordonnées des points").
//!
//! The grid has `2^p` points per axis. Its origin is the box's minimum corner and its step is the
//! cube's side over `2^p - 1`, so the smallest and the largest coordinate of the longest axis land
//! exactly on grid points 0 and `2^p - 1`. Losslessness is then exact at this quantisation: decoding
//! gives back the integer grid coordinates, and `origin + q * step` in `f64`.

use crate::error::CodecError;

/// Largest number of bits per coordinate: 3 · 20 kd-tree levels fit the codec's level contexts.
pub const MAX_BITS: u32 = 20;

/// The integer grid a mesh is quantised to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantizer {
    /// Position of grid point (0, 0, 0).
    pub origin: [f64; 3],
    /// Distance between two neighbouring grid points, the same on every axis.
    pub step: f64,
    /// Bits per coordinate, `p`.
    pub bits: u32,
}

impl Quantizer {
    /// The grid of `bits` bits per coordinate over the cube around `min`..`max`.
    pub fn new(min: [f64; 3], max: [f64; 3], bits: u32) -> Result<Self, CodecError> {
        if !(1..=MAX_BITS).contains(&bits) {
            return Err(CodecError::Parameter {
                name: "--bits",
                why: format!("{bits} is outside 1..={MAX_BITS}"),
            });
        }
        if min.iter().chain(max.iter()).any(|c| !c.is_finite()) {
            return Err(CodecError::Input(
                "the bounding box is not finite (a coordinate is NaN or infinite)".into(),
            ));
        }
        let side = (0..3).map(|a| max[a] - min[a]).fold(0.0f64, f64::max);
        let cells = ((1u64 << bits) - 1) as f64;
        let step = if side > 0.0 { side / cells } else { 1.0 };
        Ok(Quantizer {
            origin: min,
            step,
            bits,
        })
    }

    /// The grid point nearest to `p`.
    pub fn quantize(&self, p: [f64; 3]) -> [u32; 3] {
        let top = ((1u64 << self.bits) - 1) as f64;
        std::array::from_fn(|a| {
            ((p[a] - self.origin[a]) / self.step)
                .round()
                .clamp(0.0, top) as u32
        })
    }

    /// The position of grid point `q` (fractional coordinates allowed, for cell centres).
    pub fn position(&self, q: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.origin[a] + q[a] * self.step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_box_corners_land_on_the_grid_ends() {
        let q = Quantizer::new([-1.0, 0.0, 2.0], [3.0, 1.0, 2.5], 12).unwrap();
        assert_eq!(q.quantize([-1.0, 0.0, 2.0]), [0, 0, 0]);
        assert_eq!(q.quantize([3.0, 1.0, 2.5])[0], 4095);
        let back = q.position([4095.0, 0.0, 0.0]);
        assert!((back[0] - 3.0).abs() < 1e-12);
    }

    #[test]
    fn bad_bits_and_nan_are_refused() {
        assert!(Quantizer::new([0.0; 3], [1.0; 3], 0).is_err());
        assert!(Quantizer::new([0.0; 3], [1.0; 3], 21).is_err());
        assert!(Quantizer::new([f64::NAN, 0.0, 0.0], [1.0; 3], 12).is_err());
    }
}
