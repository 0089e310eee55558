//! Features thinner than the triangulation radius (ears, fingers, thin
//! walls of a scan): where the two sides of the surface are mutual
//! neighbours of the triangulation (seed 000 §5), which may join them
//! unless their normals tell them apart. A fit names them
//! ([`super::Fit::thin_features`]) whether or not it closed there.
//!
//! A *thin pair* is two samples within the radius whose unoriented
//! normals are parallel within 30° (`|n_i . n_j| >= cos 30°`) and whose
//! connecting segment leaves both tangent planes at more than 30°
//! (`|n . e| >= 1/2`): two sides facing each other, not two neighbours on
//! one side (a surface sampled finely for its curvature radius `R` has
//! its neighbours within `r` at most `r / 2R` radians off its tangent
//! plane: 30° needs `R` below the radius). Its thickness is the mean of
//! the two offsets along the normals. The samples of thin pairs that lie
//! within the radius of each other make one feature, when there are at
//! least 3 (more than a single pair).

use op_dynamics::{Point3, Real, Vec3};

use super::spacing::pairs;
use crate::disjoint_sets::DisjointSets;

/// A feature of the samples thinner than the triangulation radius.
#[derive(Clone, Debug, PartialEq)]
pub struct ThinFeature {
    /// Mean position of its samples (data coordinates).
    pub centre: Point3,
    /// Number of samples in it.
    pub samples: usize,
    /// Smallest distance between its two sides, along their normals
    /// (absolute).
    pub thickness: Real,
}

/// The thin features of `samples` with unit `normals` (any orientation)
/// for the triangulation radius `radius`, largest first (ties by their
/// first sample): centres and thicknesses in the samples' coordinates.
pub(super) fn thin_features(
    samples: &[Point3],
    normals: &[Vec3],
    radius: Real,
) -> Vec<ThinFeature> {
    const COS_30: Real = 0.866_025_403_784_438_6;
    let n = samples.len();
    let mut parts = DisjointSets::new(n);
    let mut thin = vec![Real::INFINITY; n];
    let near = pairs(samples, radius);
    for (i, j) in near.iter_pairs() {
        let d = samples[j] - samples[i];
        let len = d.norm();
        let (ni, nj) = (normals[i], normals[j]);
        if len == 0.0 || ni.dot(&nj).abs() < COS_30 {
            continue;
        }
        let (oi, oj) = (ni.dot(&d).abs(), nj.dot(&d).abs());
        if oi < 0.5 * len || oj < 0.5 * len {
            continue;
        }
        let t = 0.5 * (oi + oj);
        thin[i] = thin[i].min(t);
        thin[j] = thin[j].min(t);
    }
    for (i, j) in near.iter_pairs() {
        if thin[i].is_finite() && thin[j].is_finite() {
            parts.union(i, j);
        }
    }
    let mut features: Vec<(usize, Vec3, usize, Real)> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    for i in 0..n {
        if thin[i].is_infinite() {
            continue;
        }
        let r = parts.root(i);
        if slot[r] == usize::MAX {
            slot[r] = features.len();
            features.push((i, Vec3::zeros(), 0, Real::INFINITY));
        }
        let f = &mut features[slot[r]];
        f.1 += samples[i].coords;
        f.2 += 1;
        f.3 = f.3.min(thin[i]);
    }
    // A single thin pair (two samples) is not yet a feature.
    features.retain(|f| f.2 >= 3);
    features.sort_by(|a, b| b.2.cmp(&a.2).then(a.0.cmp(&b.0)));
    features
        .into_iter()
        .map(|(_, sum, count, thickness)| ThinFeature {
            centre: Point3::from(sum / count as Real),
            samples: count,
            thickness,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two parallel square sheets 0.6 apart (normals facing away) with a
    /// radius of 2: one feature of all their samples, 0.6 thick; 3 apart:
    /// none; one sheet alone: none.
    #[test]
    fn two_close_sheets_are_one_thin_feature() {
        let sheets = |gap: Real| {
            let mut p = Vec::new();
            let mut n = Vec::new();
            for (z, s) in [(0.0, -1.0), (gap, 1.0)] {
                for k in 0..25 {
                    p.push(Point3::new((k % 5) as Real, (k / 5) as Real, z));
                    n.push(Vec3::new(0.0, 0.0, s));
                }
            }
            (p, n)
        };
        let (p, n) = sheets(0.6);
        let f = thin_features(&p, &n, 2.0);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].samples, 50);
        assert!((f[0].thickness - 0.6).abs() < 1e-12);
        assert!((f[0].centre - Point3::new(2.0, 2.0, 0.3)).norm() < 1e-12);
        let (p, n) = sheets(3.0);
        assert!(thin_features(&p, &n, 2.0).is_empty());
        assert!(thin_features(&p[..25], &n[..25], 2.0).is_empty());
    }
}
