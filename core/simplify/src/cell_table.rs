//! An open-addressing hash map from 64-bit cell keys to dense cluster ids: the grid partition
//! meets each vertex's cell once and needs its cluster id back fast, and most grids are far
//! too sparse for a dense array.

/// Maps cell keys to cluster ids `0..len` in order of first insertion.
pub(crate) struct CellTable {
    /// (key, id) slots side by side: a probe touches one cache line, not two.
    slots: Vec<(u64, u32)>,
    mask: usize,
    len: u32,
}

const EMPTY: u64 = u64::MAX;

impl CellTable {
    /// A table sized for about `capacity` distinct keys; it grows past that, staying under half
    /// full.
    pub(crate) fn with_capacity(capacity: usize) -> CellTable {
        let size = (capacity.max(8) * 2).next_power_of_two();
        CellTable {
            slots: vec![(EMPTY, 0); size],
            mask: size - 1,
            len: 0,
        }
    }

    /// The id of `key`, assigning the next id when it is new. `key` must not be `u64::MAX`.
    #[inline]
    pub(crate) fn id(&mut self, key: u64) -> u32 {
        if (self.len as usize + 1) * 2 > self.slots.len() {
            self.grow();
        }
        let mut slot = (mix(key) as usize) & self.mask;
        loop {
            let (k, id) = self.slots[slot];
            if k == key {
                return id;
            }
            if k == EMPTY {
                self.slots[slot] = (key, self.len);
                self.len += 1;
                return self.len - 1;
            }
            slot = (slot + 1) & self.mask;
        }
    }

    /// Asks for the slot where `key` starts its probe to be brought into cache (a hint; the
    /// merge of the grid's blocks calls it a few keys ahead, so that the table's cache misses
    /// overlap instead of following one another).
    #[inline]
    pub(crate) fn prefetch(&self, key: u64) {
        #[cfg(target_arch = "x86_64")]
        {
            let slot = (mix(key) as usize) & self.mask;
            let p = self.slots.as_ptr().wrapping_add(slot) as *const i8;
            // SAFETY: prefetching is a hint that never faults, whatever the address.
            unsafe { std::arch::x86_64::_mm_prefetch(p, std::arch::x86_64::_MM_HINT_T0) };
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = key;
    }

    /// Doubles the table, keeping every key's id.
    #[cold]
    fn grow(&mut self) {
        let size = self.slots.len() * 2;
        let old = std::mem::replace(&mut self.slots, vec![(EMPTY, 0); size]);
        self.mask = size - 1;
        for (k, id) in old.into_iter().filter(|(k, _)| *k != EMPTY) {
            let mut slot = (mix(k) as usize) & self.mask;
            while self.slots[slot].0 != EMPTY {
                slot = (slot + 1) & self.mask;
            }
            self.slots[slot] = (k, id);
        }
    }

    /// Number of distinct keys seen.
    pub(crate) fn len(&self) -> u32 {
        self.len
    }
}

/// A cheap 64-bit finaliser (from MurmurHash3) so neighbouring cells spread over the table.
#[inline]
pub(crate) fn mix(mut k: u64) -> u64 {
    k ^= k >> 33;
    k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
    k ^= k >> 33;
    k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    k ^ (k >> 33)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_follow_first_insertion() {
        let mut t = CellTable::with_capacity(4);
        assert_eq!(t.id(10), 0);
        assert_eq!(t.id(7), 1);
        assert_eq!(t.id(10), 0);
        for k in 0..1000 {
            t.id(k * 977);
        }
        assert_eq!(t.id(7), 1);
        assert_eq!(t.len(), 1002); // 10, 7, and 0, 977, ..., 976 023
    }
}
