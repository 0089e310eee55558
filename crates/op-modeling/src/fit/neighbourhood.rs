//! Where the filling rules may create particles: near the data.

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use crate::cell_map::CellMap;

/// Where the filling rules of a fit may create particles (seed 000 §7):
/// near the data, so growth never runs away from it. A candidate is kept
/// within `reach` of a sample and within half a spacing of that sample's
/// tangent plane; `reach` is `d_max / 2` spacings for open data (every gap
/// up to the search range `d_max` closes, a wider one keeps a hole) and
/// `d_max / √3` for closed data (the farthest a point of a triangle of
/// samples at most `d_max` apart lies from its corners).
#[derive(Clone, Debug)]
pub struct DataNeighbourhood {
    grid: Grid,
    seeds: Vec<Point3>,
    normals: Vec<Vec3>,
    reach: Real,
    tolerance: Real,
}

impl DataNeighbourhood {
    /// The neighbourhood of the samples `seeds` with unit `normals`, for
    /// spacing `r0` and a search range `d_max` (in units of `r0`).
    pub fn new(seeds: &[Point3], normals: &[Vec3], r0: Real, d_max: Real, open: bool) -> Self {
        let reach = d_max * r0 * if open { 0.5 } else { 1.0 / 3f64.sqrt() };
        DataNeighbourhood {
            grid: Grid::new(seeds, reach),
            seeds: seeds.to_vec(),
            normals: normals.to_vec(),
            reach,
            tolerance: 0.5 * r0,
        }
    }

    /// Whether a particle may be created at `p`.
    pub fn contains(&self, p: &Point3) -> bool {
        self.grid
            .nearest_within(p, self.reach)
            .is_some_and(|s| self.normals[s].dot(&(p - self.seeds[s])).abs() <= self.tolerance)
    }
}

/// A hash grid of points for "which lie within `reach`" queries: the
/// points sorted by cell, each cell's run found through a [`CellMap`]. The
/// cells are a little over twice the reach, so that a query's ball meets
/// at most two cells along each axis (8 lookups, not the 27 of cells as
/// wide as the reach): a million samples make millions of queries, and
/// with cells of the reach (a quarter spacing when merging samples)
/// nearly every sample had a cell of its own and a query read 27 cells of
/// a million-cell map, most of them empty (merging a 1M-sample torus took
/// 1.26 s of lookups at one thread).
#[derive(Clone, Debug)]
pub(super) struct Grid {
    cell: Real,
    /// The half-width of the box about a query whose cells it reads, a
    /// little over the reach.
    search: Real,
    /// The points with their indices, by cell, ascending indices in each.
    sorted: Vec<(Point3, usize)>,
    /// Each cell's run in `sorted`.
    runs: CellMap<(usize, usize)>,
}

/// How far past the reach a query looks (a relative margin: rounding in
/// the distance test can never put a point it accepts in a cell not read).
const MARGIN: Real = 1.001;

impl Grid {
    /// The grid over `points`, indexed 0, 1, ..., for queries within
    /// `reach` (built in parallel: a sort of distinct pairs, the same at
    /// any thread count).
    pub(super) fn new(points: &[Point3], reach: Real) -> Self {
        let search = MARGIN * reach;
        // Wider than a query's box (2 `search`): it spans two cells at most.
        let cell = 2.0 * MARGIN * search;
        let mut keyed: Vec<([i64; 3], usize)> = points
            .par_iter()
            .enumerate()
            .map(|(i, p)| (cell_of(p, cell), i))
            .collect();
        keyed.par_sort_unstable();
        let runs = crate::cell_map::runs(&keyed);
        Grid {
            cell,
            search,
            sorted: keyed.into_par_iter().map(|(_, i)| (points[i], i)).collect(),
            runs,
        }
    }

    /// The points with their indices, cell by cell (ascending indices in
    /// each cell).
    pub(super) fn by_cell(&self) -> &[(Point3, usize)] {
        &self.sorted
    }

    /// The points (with their indices) of the cells that the box of
    /// half-width `search` about `p` meets: every point within the reach
    /// of `p`, and some farther.
    fn around<'a>(&'a self, p: &Point3) -> impl Iterator<Item = &'a (Point3, usize)> + 'a {
        let lo = cell_of(&(p - Vec3::repeat(self.search)), self.cell);
        // Two cells at most (so even where coordinates are too large for
        // the quotients to keep their units).
        let hi = cell_of(&(p + Vec3::repeat(self.search)), self.cell);
        let hi = [0, 1, 2].map(|a| hi[a].min(lo[a].saturating_add(1)));
        (lo[0]..=hi[0]).flat_map(move |x| {
            (lo[1]..=hi[1]).flat_map(move |y| {
                (lo[2]..=hi[2]).flat_map(move |z| {
                    let (a, b) = self.runs.get(&[x, y, z]).copied().unwrap_or((0, 0));
                    &self.sorted[a..b]
                })
            })
        })
    }

    /// The index of the nearest point within `dist` (at most the reach)
    /// of `p` (the smallest index among equals).
    pub(super) fn nearest_within(&self, p: &Point3, dist: Real) -> Option<usize> {
        let mut best: Option<(Real, usize)> = None;
        for &(q, i) in self.around(p) {
            let d = (q - p).norm();
            if d <= dist && best.is_none_or(|(b, j)| d < b || (d == b && i < j)) {
                best = Some((d, i));
            }
        }
        best.map(|(_, q)| q)
    }

    /// The indices of the points within `dist` (at most the reach) of
    /// `p`, ascending, among those before index `before`.
    pub(super) fn before_within(&self, p: &Point3, dist: Real, before: usize) -> Vec<u32> {
        let mut found: Vec<u32> = self
            .around(p)
            .filter(|&&(q, i)| i < before && (q - p).norm() <= dist)
            .map(|&(_, i)| i as u32)
            .collect();
        found.sort_unstable();
        found
    }
}

/// The cell of `p` in a grid of cell `cell`.
fn cell_of(p: &Point3, cell: Real) -> [i64; 3] {
    [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_test_support::Rng;

    /// The grid's queries find what a scan of all points finds, for
    /// points scattered at several densities and for points exactly at
    /// the reach along each axis (on cell borders when the reach divides
    /// the coordinates).
    #[test]
    fn queries_find_what_a_scan_finds() {
        let mut rng = Rng::new(11);
        for (reach, spread) in [(0.25, 3.0), (1.0, 5.0), (0.7, 0.5)] {
            let mut points: Vec<Point3> = (0..600)
                .map(|_| {
                    Point3::new(
                        rng.uniform(-spread, spread),
                        rng.uniform(-spread, spread),
                        rng.uniform(-spread, spread),
                    )
                })
                .collect();
            // A lattice at the reach: neighbours exactly at the reach.
            for k in 0..64 {
                let c = [k % 4, (k / 4) % 4, k / 16].map(|c| c as Real * reach);
                points.push(Point3::new(c[0], c[1], c[2]));
            }
            let grid = Grid::new(&points, reach);
            for (k, p) in points.iter().enumerate() {
                let within: Vec<u32> = (0..k)
                    .filter(|&j| (points[j] - p).norm() <= reach)
                    .map(|j| j as u32)
                    .collect();
                assert_eq!(grid.before_within(p, reach, k), within);
                let nearest = (0..points.len())
                    .filter(|&j| (points[j] - p).norm() <= 0.5 * reach)
                    .min_by(|&a, &b| {
                        let d = |j: usize| (points[j] - p).norm();
                        d(a).total_cmp(&d(b)).then(a.cmp(&b))
                    });
                assert_eq!(grid.nearest_within(p, 0.5 * reach), nearest);
            }
            let lattice_pairs: usize = (points.len() - 64..points.len())
                .map(|k| grid.before_within(&points[k], reach, k).len())
                .sum();
            assert!(lattice_pairs >= 144, "{lattice_pairs} pairs at the reach");
        }
    }
}
