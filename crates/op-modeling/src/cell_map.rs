//! Hash maps keyed by the integer cells of a spatial grid.
//!
//! Grids over samples or particles look cells up tens of millions of
//! times (every point's 27 neighbouring cells). The keys are grid
//! coordinates, not chosen by anyone, so the default SipHash's protection
//! buys nothing there: [`CellHasher`], a multiply-xor of the key's words
//! (FxHash's), is several times cheaper.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A map from grid cells (integer coordinates) to `V`, hashed by
/// [`CellHasher`].
pub type CellMap<V> = HashMap<[i64; 3], V, BuildHasherDefault<CellHasher>>;

/// The hasher of [`CellMap`]'s keys: each 64-bit word mixed in by a
/// rotation, an exclusive or and a multiplication (FxHash's constant).
#[derive(Clone, Copy, Debug, Default)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// Each cell's run `(start, end)` in `sorted`, entries sorted by their
/// cell (the first of each pair).
pub fn runs<T>(sorted: &[([i64; 3], T)]) -> CellMap<(usize, usize)> {
    let mut runs = CellMap::default();
    let mut start = 0;
    for k in 1..=sorted.len() {
        if k == sorted.len() || sorted[k].0 != sorted[start].0 {
            runs.insert(sorted[start].0, (start, k));
            start = k;
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Neighbouring cells hash apart, and a map finds what it holds.
    #[test]
    fn neighbouring_cells_hash_apart() {
        let mut map: CellMap<usize> = CellMap::default();
        let mut k = 0;
        for x in -3..=3 {
            for y in -3..=3 {
                for z in -3..=3 {
                    map.insert([x, y, z], k);
                    k += 1;
                }
            }
        }
        assert_eq!(map.len(), 343);
        assert_eq!(map[&[-3, -3, -3]], 0);
        assert_eq!(map[&[3, 3, 3]], 342);
        let hash = |c: [i64; 3]| {
            use std::hash::BuildHasher;
            BuildHasherDefault::<CellHasher>::default().hash_one(c)
        };
        let mut hashes: Vec<u64> = (0..27).map(|i| hash([i % 3, (i / 3) % 3, i / 9])).collect();
        hashes.sort_unstable();
        hashes.dedup();
        assert_eq!(hashes.len(), 27);
    }
}
