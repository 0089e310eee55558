//! The samples in the order of a space-filling curve: neighbours in space
//! become neighbours in memory.
//!
//! Every stage of the fit queries each sample's nearest others (normals,
//! spacing, outliers, noise, seeding, distances), in sample order. Scans
//! arrive in scan-line order and synthetic sets in random order: with a
//! million random samples, consecutive queries land in distant parts of
//! the k-d trees and of the per-sample arrays, and the fit spent most of
//! its time waiting on memory (63 s, against 33 s for the same samples in
//! curve order, the same mesh up to the order of its vertices). Sorting
//! by Morton code (the bits of the three quantized coordinates
//! interleaved, Z order; the world's own particle order,
//! [`op_dynamics::neighbours::spatial_order`]) costs one parallel sort.
//! It also makes the fit independent of the order the samples were given
//! in, up to samples in the same quantization cell (2^-21 of the bounding
//! box's largest side), which keep their given order.

use op_dynamics::neighbours::spatial_order;
use rayon::prelude::*;

use super::PointSet;

/// `data` in Morton order over its bounding box (cells of `2^-21` of its
/// largest side, [`spatial_order`], the world's own particle order), the
/// normals with their samples; `None` when a coordinate is not finite or
/// there are fewer than 3 samples (left to the input checks, which name
/// the sample as given).
pub(super) fn in_curve_order(data: &PointSet) -> Option<PointSet> {
    let p = &data.positions;
    if p.len() < 3 || !p.par_iter().all(|x| x.iter().all(|c| c.is_finite())) {
        return None;
    }
    // A cell of 0: the finest, 2^21 cells along the box's largest side.
    let order = spatial_order(p, 0.0);
    Some(PointSet {
        positions: order.par_iter().map(|&i| p[i as usize]).collect(),
        normals: data
            .normals
            .as_ref()
            .map(|n| order.par_iter().map(|&i| n[i as usize]).collect()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_dynamics::{Point3, Real, Vec3};

    /// The same set in two orders comes out in one order, with each
    /// normal beside its sample; non-finite samples are left to the
    /// checks.
    #[test]
    fn any_order_gives_one_order_with_normals_alongside() {
        let positions: Vec<Point3> = (0..500)
            .map(|i| {
                let t = i as Real * 0.731;
                Point3::new(t.sin() * 3.0, (1.7 * t).cos(), (0.37 * t).sin() * 1e-3)
            })
            .collect();
        let normals: Vec<Vec3> = positions.iter().map(|p| p.coords.normalize()).collect();
        let given = PointSet {
            positions: positions.clone(),
            normals: Some(normals.clone()),
        };
        let reversed = PointSet {
            positions: positions.iter().rev().copied().collect(),
            normals: Some(normals.iter().rev().copied().collect()),
        };
        let a = in_curve_order(&given).unwrap();
        let b = in_curve_order(&reversed).unwrap();
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.normals, b.normals);
        assert_ne!(a.positions, positions, "sorted");
        for (p, n) in a.positions.iter().zip(a.normals.as_ref().unwrap()) {
            assert_eq!(*n, p.coords.normalize());
        }
        // Consecutive samples are near: the mean step along the curve is
        // a small part of the mean step in the given order.
        let step = |v: &[Point3]| v.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<Real>();
        assert!(step(&a.positions) < 0.25 * step(&positions));
        let mut bad = given.clone();
        bad.positions[7].y = Real::NAN;
        assert!(in_curve_order(&bad).is_none());
    }
}
