//! The undirected edges of a set of triangles with the triangles on each
//! (seed 000 §5: a triangulation's Euler characteristic and boundary
//! loops, a fit's winding and holes), built by one parallel sort.
//!
//! Every half-edge is keyed by its edge `a << 32 | b` (`a < b`) and its
//! slot `3 t + k` (edge `k` of triangle `t`: from corner `k` to corner
//! `k + 1`); sorting the pairs groups each edge's triangles, in ascending
//! triangle order. The pairs are distinct, so the table is the same at
//! any thread count: what a map from edges to triangle lists filled in
//! triangle order holds, without a hash or a list per edge.

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

/// Fewest triangles whose half-edges are sorted and grouped into edges in
/// parallel: below, the pool's fork-join costs more than it saves.
const PARALLEL_TRIANGLES: usize = 4096;

/// The key of the undirected edge `{a, b}`.
#[inline]
fn key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// The edges of a set of triangles (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct EdgeTable {
    /// Edge keys, ascending, one per edge.
    keys: Vec<u64>,
    /// `starts[e]..starts[e + 1]`: edge `e`'s half-edge slots in `slots`.
    starts: Vec<u32>,
    /// Half-edge slots `3 t + k`, ascending within each edge.
    slots: Vec<u32>,
    /// The edge of each half-edge slot.
    edge_of: Vec<u32>,
}

impl EdgeTable {
    /// The table of `triangles` (vertex indices).
    ///
    /// # Panics
    /// With more than `u32::MAX / 3` triangles.
    pub fn new(triangles: &[[u32; 3]]) -> Self {
        assert!(
            triangles.len() <= (u32::MAX / 3) as usize,
            "too many triangles for an edge table"
        );
        let half = |(t, f): (usize, &[u32; 3])| {
            let f = *f;
            (0..3).map(move |k| (key(f[k], f[(k + 1) % 3]), (3 * t + k) as u32))
        };
        if triangles.len() >= PARALLEL_TRIANGLES {
            let mut pairs: Vec<(u64, u32)> = triangles
                .par_iter()
                .enumerate()
                .flat_map_iter(half)
                .collect();
            pairs.par_sort_unstable();
            return Self::from_sorted_in_parallel(&pairs);
        }
        let mut pairs: Vec<(u64, u32)> = triangles.iter().enumerate().flat_map(half).collect();
        pairs.sort_unstable();
        let mut keys = Vec::new();
        let mut starts = Vec::new();
        let mut slots = Vec::with_capacity(pairs.len());
        let mut edge_of = vec![0; pairs.len()];
        for &(k, s) in &pairs {
            if keys.last() != Some(&k) {
                keys.push(k);
                starts.push(slots.len() as u32);
            }
            edge_of[s as usize] = (keys.len() - 1) as u32;
            slots.push(s);
        }
        starts.push(slots.len() as u32);
        EdgeTable {
            keys,
            starts,
            slots,
            edge_of,
        }
    }

    /// The table of the sorted `(edge key, slot)` pairs of every triangle
    /// side, built in parallel: the serial loop's table (each edge's run
    /// starts at the first pair of its key; every slot, a side, appears
    /// once, so each is written once).
    fn from_sorted_in_parallel(pairs: &[(u64, u32)]) -> Self {
        let n = pairs.len();
        let mut starts: Vec<u32> = (0..n)
            .into_par_iter()
            .filter(|&i| i == 0 || pairs[i].0 != pairs[i - 1].0)
            .map(|i| i as u32)
            .collect();
        let keys: Vec<u64> = starts.par_iter().map(|&i| pairs[i as usize].0).collect();
        starts.push(n as u32);
        let slots: Vec<u32> = pairs.par_iter().map(|p| p.1).collect();
        let edge_of: Vec<AtomicU32> = (0..n).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        (0..keys.len()).into_par_iter().for_each(|e| {
            for &s in &slots[starts[e] as usize..starts[e + 1] as usize] {
                edge_of[s as usize].store(e as u32, Ordering::Relaxed);
            }
        });
        EdgeTable {
            keys,
            starts,
            slots,
            edge_of: edge_of.into_par_iter().map(AtomicU32::into_inner).collect(),
        }
    }

    /// Number of distinct edges.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// True when there is no edge (no triangle).
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// The vertices `(a, b)`, `a < b`, of edge `e`.
    pub fn vertices(&self, e: usize) -> (u32, u32) {
        let k = self.keys[e];
        ((k >> 32) as u32, k as u32)
    }

    /// The half-edge slots `3 t + k` on edge `e` (triangle `t`, its edge
    /// `k`), ascending: one per triangle holding the edge, twice for a
    /// triangle holding it twice.
    pub fn slots(&self, e: usize) -> &[u32] {
        &self.slots[self.starts[e] as usize..self.starts[e + 1] as usize]
    }

    /// Number of half-edges on edge `e` (triangles holding it).
    pub fn count(&self, e: usize) -> usize {
        (self.starts[e + 1] - self.starts[e]) as usize
    }

    /// The edge `{a, b}`, if a triangle holds it.
    pub fn find(&self, a: u32, b: u32) -> Option<usize> {
        self.keys.binary_search(&key(a, b)).ok()
    }

    /// Number of triangles holding `{a, b}` (0 when none does).
    pub fn count_of(&self, a: u32, b: u32) -> usize {
        self.find(a, b).map_or(0, |e| self.count(e))
    }

    /// The edges of triangle `t`'s three sides as they were when the table
    /// was built (side `k` from corner `k` to corner `k + 1`).
    pub fn sides(&self, t: usize) -> [usize; 3] {
        [0, 1, 2].map(|k| self.edge_of[3 * t + k] as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// Random triangles over few vertices (shared, repeated and degenerate
    /// edges): the table holds what a map filled in triangle order holds,
    /// on both the serial and the parallel path.
    #[test]
    fn the_table_is_a_map_from_edges_to_their_triangles() {
        let mut s = 7u64;
        let mut next = |m: u32| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) % u64::from(m)) as u32
        };
        for n in [0, 1, 50, 3 * PARALLEL_TRIANGLES] {
            let triangles: Vec<[u32; 3]> = (0..n).map(|_| [next(40), next(40), next(40)]).collect();
            let mut map: BTreeMap<(u32, u32), Vec<u32>> = BTreeMap::new();
            for (t, f) in triangles.iter().enumerate() {
                for k in 0..3 {
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    map.entry((a.min(b), a.max(b)))
                        .or_default()
                        .push((3 * t + k) as u32);
                }
            }
            let table = EdgeTable::new(&triangles);
            assert_eq!(table.len(), map.len());
            assert_eq!(table.is_empty(), n == 0);
            for (e, (&(a, b), slots)) in map.iter().enumerate() {
                assert_eq!(table.vertices(e), (a, b));
                assert_eq!(table.slots(e), slots.as_slice());
                assert_eq!(table.find(b, a), Some(e));
                assert_eq!(table.count_of(a, b), slots.len());
            }
            for (t, f) in triangles.iter().enumerate() {
                let sides = table.sides(t);
                for k in 0..3 {
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    assert_eq!(table.vertices(sides[k]), (a.min(b), a.max(b)));
                }
            }
            assert_eq!(table.count_of(41, 42), 0);
        }
    }
}
