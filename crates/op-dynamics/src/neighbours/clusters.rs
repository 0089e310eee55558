//! Cluster pair lists (the nbnxm scheme of GROMACS, Páll & Hess 2013):
//! the particles, kept by the world in column order
//! ([`cluster_order`](super::cluster_order): columns along z, each sorted
//! by z, so four consecutive slots are close in all three axes), are cut
//! into clusters of [`CLUSTER`] consecutive slots, and the list holds, for
//! every cluster, the clusters it must be paired with. A kernel then
//! evaluates a cluster against a cluster as a `CLUSTER x CLUSTER` tile:
//! the second cluster's coordinates are one contiguous load per axis (no
//! gather), and the tile's lanes are masked by the cut-off instead of
//! being listed pair by pair.
//!
//! **The pairs of the particle list, without it.** A cluster pair is
//! listed when some particle pair of the two clusters is within
//! `cutoff + skin` at the last build of the [`NeighbourList`] (its
//! reference positions): exactly the clusters of the particle pairs its
//! half list holds, with the same pair test, so the list covers every pair
//! the particle list covers, with the same rebuild rule, and is rebuilt
//! whenever that list is. The rows are searched straight from the
//! reference positions (a cell list over particles, scanned once around
//! each cluster's box, a partner cluster tested no further once found),
//! so a world that runs only the cluster kernel never builds the
//! particle rows ([`NeighbourList::update_reference`]).
//!
//! **Half rows.** Like the particle list, a cluster's row holds the
//! partner clusters at or after it (ascending, itself first): each
//! cluster pair is listed once, and a kernel adds both sides of a tile.

use super::cell_list::{cluster_rows, GridScratch};
use super::NeighbourList;
#[cfg(test)]
use super::PairList;
use crate::math::{Point3, Real};

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
    /// The build of the list these rows are of: its build count and
    /// particle count (a different pair means a rebuild).
    source: Option<(u64, usize)>,
    /// `offsets[c]..offsets[c + 1]` is the range of row `c` in `partners`.
    offsets: Vec<u32>,
    partners: Vec<u32>,
    /// Scratch: the rows before they are packed.
    upper: Vec<Vec<u32>>,
    /// Scratch: the cell list of the search.
    grid: GridScratch,
}

impl ClusterPairs {
    /// An empty list, built at the first [`ClusterPairs::update`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Rebuilds the rows from `list`'s reference positions if the list was
    /// rebuilt since the last call (or is over another particle count);
    /// returns whether it did. `list` need not hold its particle rows.
    pub fn update(&mut self, list: &NeighbourList, n: usize) -> bool {
        let source = (list.rebuilds(), n);
        if self.source == Some(source) {
            return false;
        }
        debug_assert_eq!(list.reference_positions().len(), n);
        self.build(list.reference_positions(), list.radius());
        self.source = Some(source);
        true
    }

    /// Builds the rows of every pair within `radius` (inclusive) of the
    /// positions `p`. The result depends on `p` and `radius` only (any
    /// thread count).
    pub fn build(&mut self, p: &[Point3], radius: Real) {
        let nc = p.len().div_ceil(CLUSTER);
        assert!(
            u32::try_from(nc).is_ok(),
            "ClusterPairs: more than u32::MAX clusters"
        );
        self.upper.resize_with(nc, Vec::new);
        cluster_rows(p, radius, CLUSTER, &mut self.grid, &mut self.upper[..nc]);
        self.pack(nc);
    }

    /// Builds the rows from the half pair list `pairs` over `n` particles:
    /// the oracle of [`ClusterPairs::build`] in the tests.
    #[cfg(test)]
    fn build_from_pairs(&mut self, pairs: &PairList, n: usize) {
        let nc = n.div_ceil(CLUSTER);
        self.upper.resize_with(nc, Vec::new);
        for (c, row) in self.upper.iter_mut().enumerate() {
            row.clear();
            row.push(c as u32);
            for i in CLUSTER * c..(CLUSTER * (c + 1)).min(n) {
                row.extend(pairs.row(i).iter().map(|&j| j / CLUSTER as u32));
            }
            row.sort_unstable();
            row.dedup();
        }
        self.pack(nc);
    }

    /// Packs the first `nc` rows of `upper` into `offsets` and `partners`.
    fn pack(&mut self, nc: usize) {
        self.offsets.clear();
        self.offsets.push(0);
        let mut total = 0u32;
        for row in &self.upper[..nc] {
            total += row.len() as u32;
            self.offsets.push(total);
        }
        self.partners.clear();
        self.partners.reserve(total as usize);
        for row in &self.upper[..nc] {
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

    /// The rows of `p` at `radius`, searched directly and from the particle
    /// list of every backend (the oracle), are the same arrays.
    fn assert_same_as_particle_list(p: &[Point3], radius: Real) {
        let mut direct = ClusterPairs::new();
        direct.build(p, radius);
        for backend in [NeighbourBackend::CellList, NeighbourBackend::AllPairs] {
            let mut pairs = PairList::new();
            crate::neighbours::search(backend, p, radius, &mut pairs);
            let mut oracle = ClusterPairs::new();
            oracle.build_from_pairs(&pairs, p.len());
            assert_eq!(
                direct.offsets, oracle.offsets,
                "{backend:?}, radius {radius}"
            );
            assert_eq!(
                direct.partners, oracle.partners,
                "{backend:?}, radius {radius}"
            );
        }
    }

    /// Spatially sorted and shuffled volumes, a sheet, padded last
    /// clusters, non-finite particles, coincident points, pairs exactly at
    /// the radius, and radii that find nothing.
    #[test]
    fn direct_search_gives_the_rows_of_the_particle_list() {
        let mut rng = Rng::new(0x9e37_79b9);
        let cloud: Vec<Point3> = (0..1003)
            .map(|_| {
                Point3::new(
                    rng.range(0.0, 8.0),
                    rng.range(0.0, 8.0),
                    rng.range(0.0, 8.0),
                )
            })
            .collect();
        let order = crate::neighbours::spatial_order(&cloud, 1.5);
        let sorted: Vec<Point3> = order.iter().map(|&i| cloud[i as usize]).collect();
        for r in [0.0, 0.5, 1.5, 3.0] {
            assert_same_as_particle_list(&cloud, r);
            assert_same_as_particle_list(&sorted, r);
        }
        // A unit lattice sheet: pairs exactly at the radius (inclusive).
        let sheet: Vec<Point3> = (0..30 * 17)
            .map(|k| Point3::new((k % 30) as Real, (k / 30) as Real, 0.0))
            .collect();
        assert_same_as_particle_list(&sheet, 1.0);
        assert_same_as_particle_list(&sheet, 2.0_f64.sqrt());
        // Non-finite and coincident particles.
        let mut odd = sorted[..203].to_vec();
        odd[5] = Point3::new(Real::NAN, 1.0, 1.0);
        odd[6] = Point3::new(Real::INFINITY, 1.0, 1.0);
        odd[40] = odd[41];
        odd[100] = Point3::new(Real::NEG_INFINITY, Real::NAN, 0.0);
        assert_same_as_particle_list(&odd, 1.5);
        for r in [Real::NAN, -1.0] {
            let mut cp = ClusterPairs::new();
            cp.build(&odd, r);
            assert!((0..cp.clusters()).all(|c| cp.row(c) == [c as u32]));
        }
        let mut cp = ClusterPairs::new();
        cp.build(&[], 1.0);
        assert_eq!((cp.clusters(), cp.num_entries()), (0, 0));
    }

    /// The direct search gives the same rows at one and two threads.
    #[test]
    fn direct_search_is_the_same_at_any_thread_count() {
        let mut rng = Rng::new(7);
        let p: Vec<Point3> = (0..5000)
            .map(|_| {
                Point3::new(
                    rng.range(0.0, 12.0),
                    rng.range(0.0, 12.0),
                    rng.range(0.0, 12.0),
                )
            })
            .collect();
        let rows = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut cp = ClusterPairs::new();
                cp.build(&p, 1.7);
                (cp.offsets, cp.partners)
            })
        };
        assert_eq!(rows(1), rows(2));
    }
}
