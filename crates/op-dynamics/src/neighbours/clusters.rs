//! Cluster pair lists (the nbnxm scheme of GROMACS, Páll & Hess 2013):
//! the particles, kept in spatial (Morton) order by the world, are cut
//! into clusters of [`CLUSTER`] consecutive slots, and the list holds, for
//! every cluster, the clusters it must be paired with. A kernel then
//! evaluates a cluster against a cluster as a `CLUSTER x CLUSTER` tile:
//! the second cluster's coordinates are one contiguous load per axis (no
//! gather), and the tile's lanes are masked by the cut-off instead of
//! being listed pair by pair.
//!
//! **Built from the particle list.** A cluster pair is listed when some
//! particle pair of the two clusters is in the half list of the
//! [`NeighbourList`] (within `cutoff + skin` at the last build). The list
//! therefore covers every pair the particle list covers, with the same
//! rebuild rule, and is rebuilt whenever that list is.
//!
//! **Half rows.** Like the particle list, a cluster's row holds the
//! partner clusters at or after it (ascending, itself first): each
//! cluster pair is listed once, and a kernel adds both sides of a tile.

use rayon::prelude::*;

use super::{NeighbourList, PairList};

/// Particles per cluster: one AVX2 register of `f64` lanes, half an
/// AVX-512 one (a tile is `CLUSTER x CLUSTER` pairs).
pub const CLUSTER: usize = 4;

/// The cluster pairs of a [`NeighbourList`], a half list: row `c` lists
/// the clusters `d >= c` (ascending, `c` itself first) such that some
/// particle of `c` and some particle of `d` form a listed pair. Cluster `c` holds the
/// slots `CLUSTER * c .. CLUSTER * (c + 1)`; the last one is padded past
/// the particle count.
#[derive(Clone, Debug, Default)]
pub struct ClusterPairs {
    /// The particle list this was built from: its build count, particle
    /// count and pair count (a different triple means a rebuild).
    source: Option<(u64, usize, usize)>,
    /// `offsets[c]..offsets[c + 1]` is the range of row `c` in `partners`.
    offsets: Vec<u32>,
    partners: Vec<u32>,
    /// Scratch: the rows before they are packed.
    upper: Vec<Vec<u32>>,
}

impl ClusterPairs {
    /// An empty list, built at the first [`ClusterPairs::update`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Rebuilds the rows from `list` if it changed since the last build
    /// (rebuilt, or over another particle count); returns whether it did.
    pub fn update(&mut self, list: &NeighbourList, n: usize) -> bool {
        let source = (list.rebuilds(), n, list.pairs().num_pairs());
        if self.source == Some(source) {
            return false;
        }
        self.build(list.pairs(), n);
        self.source = Some(source);
        true
    }

    /// Builds the rows from the half pair list `pairs` over `n` particles.
    /// The result depends on the list only (any thread count).
    pub fn build(&mut self, pairs: &PairList, n: usize) {
        let nc = n.div_ceil(CLUSTER);
        assert!(
            u32::try_from(nc).is_ok(),
            "ClusterPairs: more than u32::MAX clusters"
        );
        // Upper half rows, in parallel: the clusters of every listed
        // second particle of the cluster's rows (`j > i`, so `d >= c`),
        // and the cluster itself (its own pairs).
        self.upper.resize_with(nc, Vec::new);
        self.upper.par_iter_mut().enumerate().for_each(|(c, row)| {
            row.clear();
            row.push(c as u32);
            for i in CLUSTER * c..(CLUSTER * (c + 1)).min(n) {
                // A particle row is ascending: its clusters come in runs.
                let mut last = u32::MAX;
                for &j in pairs.row(i) {
                    let d = j / CLUSTER as u32;
                    if d != last {
                        row.push(d);
                        last = d;
                    }
                }
            }
            row.sort_unstable();
            row.dedup();
        });
        self.offsets.clear();
        self.offsets.push(0);
        let mut total = 0u32;
        for row in &self.upper {
            total += row.len() as u32;
            self.offsets.push(total);
        }
        self.partners.clear();
        self.partners.reserve(total as usize);
        for row in &self.upper {
            self.partners.extend_from_slice(row);
        }
    }

    /// The number of clusters.
    pub fn clusters(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The partner clusters `d >= c` of cluster `c`, ascending, `c` first.
    pub fn row(&self, c: usize) -> &[u32] {
        &self.partners[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }

    /// The number of listed cluster pairs (a cluster's pairing with itself
    /// included).
    pub fn num_entries(&self) -> usize {
        self.partners.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::test_support::Rng;
    use crate::math::Point3;
    use crate::neighbours::NeighbourBackend;

    /// Every listed particle pair has its cluster pair in the row of its
    /// first particle's cluster, rows are ascending and start with their
    /// own cluster, and no row lists a cluster without a listed pair
    /// (compared with a brute-force set).
    #[test]
    fn rows_are_the_cluster_pairs_of_the_particle_pairs() {
        let mut rng = Rng::new(0x2545_f491);
        // 1,001 particles: the last cluster is padded.
        let p: Vec<Point3> = (0..1001)
            .map(|_| {
                Point3::new(
                    rng.range(0.0, 10.0),
                    rng.range(0.0, 10.0),
                    rng.range(0.0, 3.0),
                )
            })
            .collect();
        let mut list = NeighbourList::new(NeighbourBackend::CellList, 1.0, 0.2);
        list.update(&p);
        let mut cp = ClusterPairs::new();
        assert!(cp.update(&list, p.len()));
        assert!(!cp.update(&list, p.len()), "unchanged list: no rebuild");
        let nc = p.len().div_ceil(CLUSTER);
        assert_eq!(cp.clusters(), nc);
        let mut want = vec![std::collections::BTreeSet::new(); nc];
        for (i, j) in list.pairs().iter_pairs() {
            let (c, d) = (i / CLUSTER, j / CLUSTER);
            assert!(c <= d);
            want[c].insert(d as u32);
        }
        for (c, w) in want.iter_mut().enumerate() {
            w.insert(c as u32);
            let row = cp.row(c);
            assert!(row.windows(2).all(|w| w[0] < w[1]), "row {c} ascending");
            assert_eq!(row[0] as usize, c);
            assert_eq!(
                row.to_vec(),
                w.iter().copied().collect::<Vec<_>>(),
                "row {c}"
            );
        }
        assert_eq!(
            cp.num_entries(),
            want.iter().map(|w| w.len()).sum::<usize>()
        );
    }
}
