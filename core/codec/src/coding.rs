//! How a coded value maps to what it means (paper 003 §3): a split's halves or a simplex's
//! preimage mask, relative to the predicted child, and the band of a once-held triangle's
//! midpoint on the predicted side. Shared by the split contexts, the connectivity
//! contexts and the geometry ahead.

use crate::symbols::Family;

/// Swaps the roles of the two children in a mask over the four candidates of a twice-held
/// triangle: (1,1) ↔ (2,2), (1,2) ↔ (2,1).
fn swap_children(mask: u8) -> u8 {
    ((mask & 1) << 3) | ((mask & 8) >> 3) | ((mask & 2) << 1) | ((mask & 4) >> 1)
}

/// How a symbol's value maps to a preimage mask: for the three-valued families, which child is
/// predicted (value 0); for the twice-held triangles, whether the children are swapped.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coding {
    pub(crate) ctx: usize,
    pub(crate) family: Family,
    /// Predicted child is the high one / children swapped.
    pub(crate) flip: bool,
}

impl Coding {
    /// The value coding a split (0 = low half only, 1 = high half only, 2 = both).
    pub(crate) fn split_value(self, split: u8) -> u8 {
        if split == 2 {
            2
        } else {
            u8::from((split == 1) != self.flip)
        }
    }

    /// The split a value codes (the inverse of [`Coding::split_value`]).
    pub(crate) fn split(self, value: u8) -> u8 {
        if value == 2 {
            2
        } else {
            u8::from((value == 1) != self.flip)
        }
    }

    pub(crate) fn value(self, mask: u8) -> u8 {
        match self.family {
            Family::Twice | Family::Thrice => {
                if self.flip {
                    swap_children(mask) - 1
                } else {
                    mask - 1
                }
            }
            _ => match mask {
                3 => 2,
                m => u8::from((m == 2) != self.flip),
            },
        }
    }

    pub(crate) fn mask(self, value: u8) -> u8 {
        match self.family {
            Family::Twice | Family::Thrice => {
                if self.flip {
                    swap_children(value + 1)
                } else {
                    value + 1
                }
            }
            _ => match value {
                2 => 3,
                v => {
                    if (v == 1) != self.flip {
                        2
                    } else {
                        1
                    }
                }
            },
        }
    }
}

/// Six bands of `mid` (a once-held triangle's midpoint from the split plane, in quarters of a
/// child's side) on the side of the predicted child (`flip`: the high one), far on the other side
/// first.
pub(crate) fn midpoint_band(mid: i64, flip: bool) -> usize {
    match if flip { mid } else { -1 - mid } {
        ..=-5 => 0,
        -4..=-3 => 1,
        -2..=-1 => 2,
        0..=1 => 3,
        2..=3 => 4,
        _ => 5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbols::context;

    #[test]
    fn values_and_masks_round_trip_in_every_family() {
        for family in crate::symbols::ALL {
            let masks: Vec<u8> = if family.alphabet() == 3 {
                vec![1, 2, 3]
            } else {
                (1..16).collect()
            };
            for flip in [false, true] {
                let coding = Coding {
                    ctx: context(family, 0, 0),
                    family,
                    flip,
                };
                for &m in &masks {
                    let value = coding.value(m);
                    assert!((value as usize) < family.alphabet());
                    assert_eq!(coding.mask(value), m, "{family:?} flip {flip}");
                }
            }
        }
    }
}
