//! Sample normals: local PCA, oriented over the whole set (Hoppe et al. 1992).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use op_dynamics::{Point3, Real, Vec3};

use super::spacing::pairs;
use super::FitError;

/// Unit normals by local PCA over the points within `radius`, oriented by
/// propagation along the maximum spanning tree of `|n_i . n_j|`.
pub(crate) fn estimate_normals(points: &[Point3], radius: Real) -> Result<Vec<Vec3>, FitError> {
    let n = points.len();
    let half = pairs(points, radius);
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, j) in half.iter_pairs() {
        rows[i].push(j);
        rows[j].push(i);
    }
    rows.iter_mut().for_each(|r| r.sort_unstable());
    let mut normals = Vec::with_capacity(n);
    for (i, row) in rows.iter().enumerate() {
        if row.len() < 2 {
            return Err(FitError::Input(format!(
                "sample {} has {} neighbours within {radius} spacings: cannot estimate its normal (give normals in the file, or a larger spacing)",
                i + 1,
                row.len()
            )));
        }
        let mean = row
            .iter()
            .fold(points[i].coords, |s, &j| s + points[j].coords)
            / (row.len() + 1) as Real;
        let mut cov = op_dynamics::Mat3::zeros();
        for &k in std::iter::once(&i).chain(row) {
            let d = points[k].coords - mean;
            cov += d * d.transpose();
        }
        let eig = cov.symmetric_eigen();
        let (k, _) = eig
            .eigenvalues
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1).then(a.0.cmp(&b.0)))
            .unwrap_or((0, &0.0));
        normals.push(eig.eigenvectors.column(k).normalize());
    }
    // Orientation: Prim's maximum spanning tree from each component's
    // sample of largest x (ties by index).
    let mut done = vec![false; n];
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].x.total_cmp(&points[a].x).then(a.cmp(&b)));
    for &start in &order {
        if done[start] {
            continue;
        }
        let s = normals[start];
        let big = (0..3)
            .max_by(|&a, &b| s[a].abs().total_cmp(&s[b].abs()).then(b.cmp(&a)))
            .unwrap_or(0);
        if s[big] < 0.0 {
            normals[start] = -s;
        }
        done[start] = true;
        let mut heap = BinaryHeap::new();
        let push = |heap: &mut BinaryHeap<Edge>, normals: &[Vec3], i: usize| {
            for &j in &rows[i] {
                heap.push(Edge {
                    weight: normals[i].dot(&normals[j]).abs(),
                    from: i,
                    to: j,
                });
            }
        };
        push(&mut heap, &normals, start);
        while let Some(e) = heap.pop() {
            if done[e.to] {
                continue;
            }
            done[e.to] = true;
            if normals[e.from].dot(&normals[e.to]) < 0.0 {
                normals[e.to] = -normals[e.to];
            }
            push(&mut heap, &normals, e.to);
        }
    }
    Ok(normals)
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
