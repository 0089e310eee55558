//! Where the filling rules may create particles: near the data.

use std::collections::HashMap;

use op_dynamics::{Point3, Real, Vec3};

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

/// A hash grid of points for "is there one within `cell`" queries.
#[derive(Clone, Debug)]
pub(super) struct Grid {
    cell: Real,
    map: HashMap<[i64; 3], Vec<(Point3, usize)>>,
    len: usize,
}

impl Grid {
    pub(super) fn new(points: &[Point3], cell: Real) -> Self {
        let mut g = Grid {
            cell,
            map: HashMap::new(),
            len: 0,
        };
        points.iter().for_each(|p| g.insert(*p));
        g
    }

    fn key(&self, p: &Point3) -> [i64; 3] {
        [p.x, p.y, p.z].map(|c| (c / self.cell).floor() as i64)
    }

    /// Inserts `p` with the next index (0, 1, ...).
    pub(super) fn insert(&mut self, p: Point3) {
        let k = self.key(&p);
        self.map.entry(k).or_default().push((p, self.len));
        self.len += 1;
    }

    /// The points (with their indices) of the 27 cells around `p`'s, in
    /// cell order: every point within a cell of `p`.
    fn around<'a>(&'a self, p: &Point3) -> impl Iterator<Item = &'a (Point3, usize)> + 'a {
        let k = self.key(p);
        (0..27).flat_map(move |c: i64| {
            let cell = [c / 9 - 1, (c / 3) % 3 - 1, c % 3 - 1];
            self.map
                .get(&[0, 1, 2].map(|a| k[a].saturating_add(cell[a])))
                .into_iter()
                .flatten()
        })
    }

    /// The index of the nearest point within `dist` (at most the cell
    /// size) of `p` (the smallest index among equals).
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

    /// The indices of the points within `dist` (at most the cell size) of
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
