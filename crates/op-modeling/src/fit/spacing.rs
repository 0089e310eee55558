//! Sample spacing: nearest-sample distances, merging, the cohesion rest distance.

use std::collections::HashMap;
use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use op_dynamics::neighbours::{search, NeighbourBackend, PairList};
use op_dynamics::{Point3, Real};

use super::input::{bits, distinct_points, median_of};
use super::neighbourhood::Grid;
use super::FitError;

/// For each of the (distinct) points of `tree`, the distance to its
/// nearest other point (queries in parallel, collected in order).
pub(super) fn nearest_distances(tree: &Nearest) -> Vec<Real> {
    (0..tree.points().len())
        .into_par_iter()
        .map(|i| tree.others(i, 1).first().map_or(Real::INFINITY, |r| r.0))
        .collect()
}

/// The `k` nearest other points of each point (kiddo's immutable k-d
/// tree, queries in parallel, ordered collect): flat rows, nearest first,
/// ties by index.
pub(crate) struct Knn {
    k: usize,
    index: Vec<usize>,
    distance: Vec<Real>,
}

impl Knn {
    /// The `k` nearest others of each of `points` (fewer when there are at
    /// most `k` points). Exact duplicates count as neighbours at distance 0.
    pub(crate) fn new(points: &[Point3], k: usize) -> Knn {
        match Nearest::new(points) {
            Some(nearest) => Knn::over(&nearest, k),
            None => Knn {
                k: 0,
                index: Vec::new(),
                distance: Vec::new(),
            },
        }
    }

    /// [`Knn::new`] with the tree `nearest` already built over the points.
    pub(crate) fn over(nearest: &Nearest, k: usize) -> Knn {
        let points = nearest.points();
        let k = k.min(points.len().saturating_sub(1));
        let rows: Vec<Vec<(Real, usize)>> = (0..points.len())
            .into_par_iter()
            .map(|i| nearest.others(i, k))
            .collect();
        let k = rows.iter().map(Vec::len).min().unwrap_or(0);
        let mut index = Vec::with_capacity(k * points.len());
        let mut distance = Vec::with_capacity(k * points.len());
        for row in rows {
            for &(d, j) in &row[..k] {
                index.push(j);
                distance.push(d);
            }
        }
        Knn { k, index, distance }
    }

    /// Number of neighbours per point.
    pub(crate) fn k(&self) -> usize {
        self.k
    }

    /// The neighbours of point `i`, nearest first.
    pub(crate) fn neighbours(&self, i: usize) -> &[usize] {
        &self.index[i * self.k..(i + 1) * self.k]
    }

    /// The distance from each point to its `m`-th nearest other point
    /// (`1 <= m <= k`).
    pub(crate) fn distances_to(&self, m: usize) -> Vec<Real> {
        self.distance
            .chunks(self.k.max(1))
            .map(|row| row[m - 1])
            .collect()
    }
}

/// Candidates [`Nearest::nearest_to`] takes from the tree: the corners of
/// a lattice cell about its centre, more than tie with the nearest within
/// the last bit of a distance on scattered data.
const CANDIDATES: usize = 8;

/// Nearest-neighbour queries over points (kiddo's immutable k-d tree).
pub(crate) struct Nearest<'a> {
    points: &'a [Point3],
    tree: ImmutableKdTree<Real, 3>,
}

impl<'a> Nearest<'a> {
    /// The tree over `points`; `None` when kiddo cannot build one.
    pub(crate) fn new(points: &'a [Point3]) -> Option<Self> {
        let entries: Vec<[Real; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let tree = ImmutableKdTree::<Real, 3>::new_from_slice(&entries).ok()?;
        Some(Nearest { points, tree })
    }

    /// The points the tree is built over.
    pub(crate) fn points(&self) -> &'a [Point3] {
        self.points
    }

    /// The point nearest to `q` (the first by index among equally near),
    /// by the exact squared distance `(p - q).norm_squared()`, from the
    /// tree's [`CANDIDATES`] nearest (its own distances may differ from
    /// these in the last bit): the point a scan of them all picks unless
    /// more than [`CANDIDATES`] points tie with it; `None` when there are
    /// none.
    pub(crate) fn nearest_to(&self, q: &Point3) -> Option<usize> {
        let want = NonZeroUsize::new(CANDIDATES.min(self.points.len()))?;
        self.tree
            .query(&[q.x, q.y, q.z])
            .nearest_n::<SquaredEuclidean<Real>>(want)
            .execute()
            .into_iter()
            .map(|r| r.item as usize)
            .min_by(|&a, &b| {
                let d = |j: usize| (self.points[j] - q).norm_squared();
                d(a).total_cmp(&d(b)).then(a.cmp(&b))
            })
    }

    /// The `k` nearest points to `points[i]` other than itself (fewer when
    /// there are fewer): exact distance and index, nearest first, ties by
    /// index; exact duplicates count, at distance 0.
    pub(crate) fn others(&self, i: usize, k: usize) -> Vec<(Real, usize)> {
        let Some(want) = NonZeroUsize::new(k + 1) else {
            return Vec::new();
        };
        let q = self.points[i];
        let mut row: Vec<(Real, usize)> = self
            .tree
            .query(&[q.x, q.y, q.z])
            .nearest_n::<SquaredEuclidean<Real>>(want)
            .execute()
            .into_iter()
            .map(|r| r.item as usize)
            .filter(|&j| j != i)
            .map(|j| ((self.points[j] - q).norm(), j))
            .collect();
        row.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        row.truncate(k);
        row
    }
}

/// Half pair list of `points` within `radius`.
pub(super) fn pairs(points: &[Point3], radius: Real) -> PairList {
    let mut half = PairList::new();
    search(NeighbourBackend::CellList, points, radius, &mut half);
    half
}

/// Median over the points of the distance to the nearest other point (0
/// for a point with a duplicate), by a k-d tree over the distinct points.
pub fn median_nearest_distance(points: &[Point3]) -> Result<Real, FitError> {
    let distinct = distinct_points(points);
    if distinct.len() < 2 {
        return Err(FitError::Input(
            "all samples coincide: no spacing can be estimated".into(),
        ));
    }
    let tree = Nearest::new(&distinct).ok_or_else(|| {
        FitError::Input("no nearest-neighbour tree over the samples could be built".into())
    })?;
    let nearest = nearest_distances(&tree);
    let mut count: HashMap<[u64; 3], usize> = HashMap::new();
    for p in points {
        *count.entry(bits(p)).or_default() += 1;
    }
    let all: Vec<Real> = distinct
        .iter()
        .zip(nearest)
        .flat_map(|(p, d)| {
            let k = count.get(&bits(p)).copied().unwrap_or(1);
            std::iter::once(if k > 1 { 0.0 } else { d }).chain(std::iter::repeat_n(0.0, k - 1))
        })
        .collect();
    let h = median_of(all);
    if !(h.is_finite() && h > 0.0) {
        return Err(FitError::Input(format!(
            "the median nearest-sample distance is {h} (duplicate samples?): pass a spacing"
        )));
    }
    Ok(h)
}

/// Indices of the points kept when each point within `dist` of an earlier
/// kept point is merged into it.
///
/// The earlier points within `dist` of each point are found in parallel
/// (most points have none); one pass in point order then keeps a point when
/// none of them was kept: the greedy merge, the same at any thread count.
pub(super) fn merge_close(points: &[Point3], dist: Real) -> Vec<usize> {
    let grid = Grid::new(points, dist);
    // The points with an earlier one within `dist` (few), queried in the
    // grid's cell order so that queries one after the other read the same
    // cells (in the samples' order, a million queries missed the cache).
    let mut earlier: Vec<(usize, Vec<u32>)> = grid
        .by_cell()
        .par_iter()
        .with_min_len(1024)
        .map(|&(p, k)| (k, grid.before_within(&p, dist, k)))
        .filter(|(_, close)| !close.is_empty())
        .collect();
    earlier.par_sort_unstable();
    // In index order: a point is kept when no kept point before it is
    // that close (a point with none is kept).
    let mut keep = vec![true; points.len()];
    for (k, close) in &earlier {
        keep[*k] = !close.iter().any(|&j| keep[j as usize]);
    }
    (0..points.len()).filter(|&k| keep[k]).collect()
}

/// Mean distance between points and their neighbours within `ring`, when
/// at least half of the points have one; otherwise 1 (the points are
/// farther apart than the unit spacing, and the few close pairs would bias
/// the mean up to `ring`).
pub(super) fn first_ring_mean(points: &[Point3], ring: Real) -> Real {
    let half = pairs(points, ring);
    let mut has = vec![false; points.len()];
    let (sum, count) = half.iter_pairs().fold((0.0, 0usize), |(s, c), (i, j)| {
        has[i] = true;
        has[j] = true;
        (s + (points[i] - points[j]).norm(), c + 1)
    });
    if 2 * has.iter().filter(|&&h| h).count() < points.len() {
        1.0
    } else {
        sum / count as Real
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`Nearest::nearest_to`] picks the point a scan of them all picks
    /// (the first of equally near ones), for queries on, near and far
    /// from a lattice with repeated distances.
    #[test]
    fn nearest_to_is_the_first_nearest_of_a_scan() {
        let pts: Vec<Point3> = (0..1000)
            .map(|k| Point3::new((k % 10) as Real, ((k / 10) % 10) as Real, (k / 100) as Real))
            .collect();
        let tree = Nearest::new(&pts).unwrap();
        for k in 0..500 {
            let t = k as Real;
            // Every fourth query is a lattice point or a midpoint (ties).
            let q = match k % 4 {
                0 => Point3::new((k % 9) as Real + 0.5, (k % 7) as Real, 3.0),
                1 => pts[k * 2],
                _ => Point3::new(
                    (t * 0.37).sin() * 12.0,
                    (t * 0.11).cos() * 9.0,
                    t * 0.05 - 5.0,
                ),
            };
            let scan = (0..pts.len()).min_by(|&a, &b| {
                (pts[a] - q)
                    .norm_squared()
                    .total_cmp(&(pts[b] - q).norm_squared())
            });
            assert_eq!(tree.nearest_to(&q), scan, "at {q:?}");
        }
    }

    #[test]
    fn median_spacing_of_a_grid() {
        let pts: Vec<Point3> = (0..100)
            .map(|k| Point3::new((k % 10) as Real * 0.3, (k / 10) as Real * 0.3, 0.0))
            .collect();
        assert!((median_nearest_distance(&pts).unwrap() - 0.3).abs() < 1e-12);
    }

    use crate::fit::shapes::scattered;

    /// The k-d tree's nearest distances equal brute force, bit for bit,
    /// also on planar data (ties on one axis) and with a far outlier.
    #[test]
    fn kd_tree_nearest_distances_match_brute_force() {
        let mut sets = vec![scattered(500, 1.0)];
        let mut plane = scattered(300, 1.0);
        plane.iter_mut().for_each(|p| p.z = 0.0);
        sets.push(plane);
        let mut outlier = scattered(100, 1e-3);
        outlier.push(Point3::new(1e3, 0.0, 0.0));
        sets.push(outlier);
        for pts in sets {
            let fast = nearest_distances(&Nearest::new(&pts).unwrap());
            for (i, p) in pts.iter().enumerate() {
                let slow = pts
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, q)| (q - p).norm())
                    .fold(Real::INFINITY, Real::min);
                assert_eq!(fast[i], slow, "point {i}");
            }
        }
    }

    /// Duplicates count as nearest distance 0 in the scene's spacing
    /// estimate; `-0` equals `+0`; all coincident is an error.
    #[test]
    fn distinct_points_and_duplicates() {
        let pts = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(-0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(3.0, 0.0, 0.0),
        ];
        assert_eq!(distinct_points(&pts).len(), 3);
        // Nearest: 0, 0, 1, 2: median (index 2 of 4) is 1.
        assert_eq!(median_nearest_distance(&pts).unwrap(), 1.0);
        let same = vec![Point3::new(1.0, 2.0, 3.0); 5];
        assert!(median_nearest_distance(&same).is_err());
    }
}
