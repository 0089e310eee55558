//! Sample normals (seed 000 §7 needs an oriented particle per sample):
//! local PCA, oriented consistently over the whole set by propagation
//! along a minimum spanning tree of `1 - |n_i . n_j|` (Hoppe et al. 1992,
//! "Surface reconstruction from unorganized points", §3.3).

use std::cmp::Ordering;

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use super::spacing::{pairs, Knn};
use super::FitError;

/// Unit normals by local PCA over the points within `radius`, oriented by
/// propagation along the maximum spanning tree of `|n_i . n_j|` (the
/// scenes' `creation.fit`; [`super::fit`] uses `knn_normals`).
///
/// # Errors
/// A point with fewer than 2 neighbours within `radius`.
pub fn estimate_normals(points: &[Point3], radius: Real) -> Result<Vec<Vec3>, FitError> {
    let n = points.len();
    let half = pairs(points, radius);
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, j) in half.iter_pairs() {
        rows[i].push(j);
        rows[j].push(i);
    }
    rows.par_iter_mut()
        .with_min_len(1024)
        .for_each(|r| r.sort_unstable());
    if let Some((i, row)) = rows.iter().enumerate().find(|(_, r)| r.len() < 2) {
        return Err(FitError::Input(format!(
            "sample {} has {} neighbours within {radius} spacings: cannot estimate its normal (give normals in the file, or a larger spacing)",
            i + 1,
            row.len()
        )));
    }
    let mut normals: Vec<Vec3> = rows
        .par_iter()
        .with_min_len(1024)
        .enumerate()
        .map(|(i, row)| pca_normal(points, i, row))
        .collect();
    orient(points, &rows, &mut normals, 0, false);
    Ok(normals)
}

/// Unit normals from the `k` nearest samples (Hoppe et al. 1992 §3.2: the
/// least-variance direction of the sample and its neighbours), oriented
/// over the symmetric k-nearest-neighbour graph (§3.3) from the sample
/// of largest `z`, whose normal is made to point along `+z` (outward on a
/// closed surface), along the tangent edges first (see [`orient`]'s
/// `tangent`). Independent of the particle spacing; no sample is
/// refused (every sample has `k` nearest others when there are `k + 1`).
pub(crate) fn knn_normals(points: &[Point3], knn: &Knn) -> Vec<Vec3> {
    let n = points.len();
    let mut normals: Vec<Vec3> = (0..n)
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| pca_normal(points, i, knn.neighbours(i)))
        .collect();
    let mut rows: Vec<Vec<usize>> = (0..n).map(|i| knn.neighbours(i).to_vec()).collect();
    for i in 0..n {
        for &j in knn.neighbours(i) {
            rows[j].push(i);
        }
    }
    rows.par_iter_mut().with_min_len(1024).for_each(|r| {
        r.sort_unstable();
        r.dedup();
    });
    orient(points, &rows, &mut normals, 2, true);
    normals
}

/// The share of `points` whose neighbourhood (the point and its `knn`
/// neighbours) is a curve rather than a surface: its second principal
/// variance below a tenth of the first (samples along a circle: about
/// 0.03; on a surface sampled at random: about 0.5 and more).
pub(crate) fn curve_like_share(points: &[Point3], knn: &Knn) -> Real {
    let curve = (0..points.len())
        .filter(|&i| {
            let (_, cov) = neighbourhood_covariance(points, i, knn.neighbours(i));
            let mut e: Vec<Real> = cov.symmetric_eigenvalues().iter().copied().collect();
            e.sort_by(|a, b| b.total_cmp(a));
            e[1] < 0.1 * e[0]
        })
        .count();
    curve as Real / points.len().max(1) as Real
}

/// Mean and covariance (the sum of the outer products of the deviations)
/// of `points`, summed in the order given.
pub(crate) fn covariance<'a>(
    points: impl Iterator<Item = &'a Point3> + Clone,
) -> (Vec3, op_dynamics::Mat3) {
    let (sum, n) = points
        .clone()
        .fold((Vec3::zeros(), 0usize), |(s, n), p| (s + p.coords, n + 1));
    let mean = sum / n.max(1) as Real;
    let mut cov = op_dynamics::Mat3::zeros();
    for p in points {
        let d = p.coords - mean;
        cov += d * d.transpose();
    }
    (mean, cov)
}

/// Weighted mean and covariance (the weighted sum of the outer products of
/// the deviations) of `(weight, point)` pairs, summed in the order given.
pub(crate) fn weighted_covariance<'a>(
    points: impl Iterator<Item = (Real, &'a Point3)> + Clone,
) -> (Vec3, op_dynamics::Mat3) {
    let (sum, total) = points.clone().fold((Vec3::zeros(), 0.0), |(s, t), (w, p)| {
        (s + p.coords * w, t + w)
    });
    let mean = sum / total;
    let mut cov = op_dynamics::Mat3::zeros();
    for (w, p) in points {
        let d = p.coords - mean;
        cov += d * d.transpose() * w;
    }
    (mean, cov)
}

/// [`covariance`] of `points[i]` and its neighbours `points[row]`.
fn neighbourhood_covariance(
    points: &[Point3],
    i: usize,
    row: &[usize],
) -> (Vec3, op_dynamics::Mat3) {
    covariance(std::iter::once(&i).chain(row).map(|&k| &points[k]))
}

/// The least-variance direction of `points[i]` and `points[row]`.
fn pca_normal(points: &[Point3], i: usize, row: &[usize]) -> Vec3 {
    let (_, cov) = neighbourhood_covariance(points, i, row);
    let eig = cov.symmetric_eigen();
    let (k, _) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1).then(a.0.cmp(&b.0)))
        .unwrap_or((0, &0.0));
    eig.eigenvectors.column(k).normalize()
}

/// Orients `normals` by Prim's maximum spanning tree of `|n_i . n_j|`
/// over the graph `rows` (the minimum spanning tree of Hoppe's
/// `1 - |n_i . n_j|`), started in each connected component at its point
/// of largest coordinate along `axis` (ties by index), whose normal is
/// made to point along `+axis` (for `axis` 0, the x of the scenes: its
/// largest component positive).
///
/// With `tangent`, an edge's weight `|n_i . n_j|` is multiplied by the
/// cosines of the angles at which the edge leaves the two tangent planes
/// (`sqrt(1 - (n . e)²)`, `e` the edge's direction). Across a feature
/// thinner than the neighbourhood (the two sides of an ear, two parallel
/// sheets) the normals are parallel, so Hoppe's weight prefers the edge
/// straight across, which carries one side's orientation to the other
/// unchanged: all wrong on that side. Such an edge stands steeply on both
/// tangent planes, so with the factors the tree goes round the rim, along
/// which the normals turn. Measured on a coin (two discs 2.25 spacings
/// apart joined by a round rim, 3,000 random samples): 1,260 of the
/// bottom's 1,261 normals wrong without the factors.
fn orient(
    points: &[Point3],
    rows: &[Vec<usize>],
    normals: &mut [Vec3],
    axis: usize,
    tangent: bool,
) {
    let n = points.len();
    let mut done = vec![false; n];
    // The frontier: per point not yet oriented but next to one that is,
    // the best edge to it (an indexed heap). The best of all pops first,
    // as from a heap of every edge pushed (the edges' order being total),
    // without the edges that lose to a later one: a million random torus
    // samples pushed 3.7 million edges, 2.8 million of them stale, into a
    // heap of up to 1.6 million (orientation 5.1 s; 2.8 s with edges
    // that lose not pushed; 0.71 s with a frontier of one edge per point;
    // the same mesh).
    let mut frontier = Frontier::new(n);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b][axis].total_cmp(&points[a][axis]).then(a.cmp(&b)));
    for &start in &order {
        if done[start] {
            continue;
        }
        let s = normals[start];
        let big = if axis == 0 {
            (0..3)
                .max_by(|&a, &b| s[a].abs().total_cmp(&s[b].abs()).then(b.cmp(&a)))
                .unwrap_or(0)
        } else {
            axis
        };
        if s[big] < 0.0 {
            normals[start] = -s;
        }
        done[start] = true;
        // Edges to points already oriented are never taken: they are not
        // offered. 200,000 random samples of the torus: the orientation
        // 1.20-1.30 -> 0.46 s.
        let offer = |frontier: &mut Frontier, normals: &[Vec3], done: &[bool], i: usize| {
            for &j in rows[i].iter().filter(|&&j| !done[j]) {
                let mut weight = normals[i].dot(&normals[j]).abs();
                if tangent {
                    let e = (points[j] - points[i])
                        .try_normalize(0.0)
                        .unwrap_or(Vec3::zeros());
                    let leave = |n: &Vec3| (1.0 - n.dot(&e).powi(2)).max(0.0).sqrt();
                    weight *= leave(&normals[i]) * leave(&normals[j]);
                }
                frontier.offer(Edge {
                    weight,
                    from: i,
                    to: j,
                });
            }
        };
        offer(&mut frontier, normals, &done, start);
        while let Some(e) = frontier.pop() {
            done[e.to] = true;
            if normals[e.from].dot(&normals[e.to]) < 0.0 {
                normals[e.to] = -normals[e.to];
            }
            offer(&mut frontier, normals, &done, e.to);
        }
    }
}

/// A binary max-heap of edges holding at most one per destination point,
/// the best offered ([`Edge`]'s order), with each point's place in it.
struct Frontier {
    heap: Vec<Edge>,
    /// Per point, its edge's index in `heap` ([`Frontier::ABSENT`]: none).
    place: Vec<usize>,
}

impl Frontier {
    const ABSENT: usize = usize::MAX;

    fn new(n: usize) -> Self {
        Frontier {
            heap: Vec::new(),
            place: vec![Self::ABSENT; n],
        }
    }

    /// Keeps `e` if its point has no edge yet or `e` beats it.
    fn offer(&mut self, e: Edge) {
        let to = e.to;
        let k = match self.place[to] {
            Self::ABSENT => {
                self.heap.push(e);
                self.heap.len() - 1
            }
            k if e > self.heap[k] => {
                self.heap[k] = e;
                k
            }
            _ => return,
        };
        self.place[to] = k;
        self.up(k);
    }

    /// The best edge, removed.
    fn pop(&mut self) -> Option<Edge> {
        let last = self.heap.len().checked_sub(1)?;
        self.heap.swap(0, last);
        let best = self.heap.pop()?;
        self.place[best.to] = Self::ABSENT;
        if !self.heap.is_empty() {
            self.place[self.heap[0].to] = 0;
            self.down(0);
        }
        Some(best)
    }

    fn up(&mut self, mut k: usize) {
        while k > 0 {
            let parent = (k - 1) / 2;
            if self.heap[k] <= self.heap[parent] {
                break;
            }
            self.swap(k, parent);
            k = parent;
        }
    }

    fn down(&mut self, mut k: usize) {
        loop {
            let (l, r) = (2 * k + 1, 2 * k + 2);
            let mut top = k;
            if l < self.heap.len() && self.heap[l] > self.heap[top] {
                top = l;
            }
            if r < self.heap.len() && self.heap[r] > self.heap[top] {
                top = r;
            }
            if top == k {
                break;
            }
            self.swap(k, top);
            k = top;
        }
    }

    fn swap(&mut self, a: usize, b: usize) {
        self.heap.swap(a, b);
        self.place[self.heap[a].to] = a;
        self.place[self.heap[b].to] = b;
    }
}

/// An edge of the orientation graph, ordered by weight then indices.
#[derive(PartialEq)]
struct Edge {
    weight: Real,
    from: usize,
    to: usize,
}

impl Eq for Edge {}

impl Ord for Edge {
    fn cmp(&self, other: &Self) -> Ordering {
        self.weight
            .total_cmp(&other.weight)
            .then(other.from.cmp(&self.from))
            .then(other.to.cmp(&self.to))
    }
}

impl PartialOrd for Edge {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_test_support::Rng;
    use std::collections::BinaryHeap;

    /// The frontier pops what a heap of every offered edge pops, skipping
    /// edges to points already popped: random weights, with ties, offered
    /// between pops.
    #[test]
    fn the_frontier_pops_as_a_heap_of_every_edge() {
        let mut rng = Rng::new(3);
        let n = 300;
        let mut frontier = Frontier::new(n);
        let mut all = BinaryHeap::new();
        let mut done = vec![false; n];
        let (mut popped, mut stale) = (0, 0);
        let edge = |rng: &mut Rng| Edge {
            // A tenth of a unit apart: many ties.
            weight: (rng.uniform(0.0, 1.0) * 10.0).floor() / 10.0,
            from: (rng.uniform(0.0, n as Real) as usize).min(n - 1),
            to: (rng.uniform(0.0, n as Real) as usize).min(n - 1),
        };
        for round in 0..2000 {
            for _ in 0..3 {
                let e = edge(&mut rng);
                if !done[e.to] {
                    frontier.offer(Edge { ..e });
                    all.push(e);
                }
            }
            if round % 2 == 0 {
                continue;
            }
            let expected = loop {
                match all.pop() {
                    Some(e) if done[e.to] => stale += 1,
                    other => break other,
                }
            };
            let got = frontier.pop();
            assert_eq!(
                got.as_ref().map(|e| (e.weight, e.from, e.to)),
                expected.as_ref().map(|e| (e.weight, e.from, e.to)),
                "pop {popped}"
            );
            if let Some(e) = got {
                done[e.to] = true;
                popped += 1;
            }
        }
        assert!(popped > 250 && stale > 100, "{popped} pops, {stale} stale");
    }

    #[test]
    fn pca_normals_of_a_plane_are_oriented_consistently() {
        let pts: Vec<Point3> = (0..100)
            .map(|k| {
                Point3::new(
                    (k % 10) as Real,
                    (k / 10) as Real,
                    0.01 * ((k * 7) % 3) as Real,
                )
            })
            .collect();
        let n = estimate_normals(&pts, 2.5).unwrap();
        assert!(n.iter().all(|v| v.z > 0.99), "{n:?}");
    }
}
