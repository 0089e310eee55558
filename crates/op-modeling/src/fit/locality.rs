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
//! interleaved, Z order) costs one parallel sort. It also makes the fit
//! independent of the order the samples were given in, up to samples in
//! the same quantization cell (2^-21 of the bounding box), which keep
//! their given order.

use op_dynamics::{Point3, Real};
use rayon::prelude::*;

use super::PointSet;

/// Bits per coordinate in a Morton code (three interleaved in a `u64`).
const BITS: u32 = 21;

/// `data` in Morton order over its bounding box, the normals with their
/// samples; `None` when a coordinate is not finite or there are fewer
/// than 3 samples (left to the input checks, which name the sample as
/// given).
pub(super) fn in_curve_order(data: &PointSet) -> Option<PointSet> {
    let p = &data.positions;
    if p.len() < 3 || !p.par_iter().all(|x| x.iter().all(|c| c.is_finite())) {
        return None;
    }
    let (lo, hi) = p
        .par_iter()
        .fold(
            || {
                (
                    Point3::from([Real::INFINITY; 3]),
                    Point3::from([Real::NEG_INFINITY; 3]),
                )
            },
            |(lo, hi), x| (lo.inf(x), hi.sup(x)),
        )
        .reduce(
            || {
                (
                    Point3::from([Real::INFINITY; 3]),
                    Point3::from([Real::NEG_INFINITY; 3]),
                )
            },
            |(a, b), (c, d)| (a.inf(&c), b.sup(&d)),
        );
    // Halves first: the extent of any finite box is finite.
    let extent = (0..3)
        .map(|k| 0.5 * hi[k] - 0.5 * lo[k])
        .fold(0.0, Real::max);
    let scale = if extent > 0.0 {
        ((1u64 << BITS) - 1) as Real / extent
    } else {
        0.0
    };
    let mut keys: Vec<(u64, u32)> = p
        .par_iter()
        .enumerate()
        .map(|(i, x)| {
            let cell = |k: usize| ((0.5 * x[k] - 0.5 * lo[k]) * scale) as u64;
            (morton(cell(0), cell(1), cell(2)), i as u32)
        })
        .collect();
    keys.par_sort_unstable();
    Some(PointSet {
        positions: keys.par_iter().map(|&(_, i)| p[i as usize]).collect(),
        normals: data
            .normals
            .as_ref()
            .map(|n| keys.par_iter().map(|&(_, i)| n[i as usize]).collect()),
    })
}

/// The Morton code of cell `(x, y, z)` (each below `2^BITS`): their bits
/// interleaved, x lowest.
fn morton(x: u64, y: u64, z: u64) -> u64 {
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

/// The low [`BITS`] bits of `v`, two zeros after each.
fn spread(v: u64) -> u64 {
    let mut v = v & ((1 << BITS) - 1);
    v = (v | (v << 32)) & 0x001f_0000_0000_ffff;
    v = (v | (v << 16)) & 0x001f_0000_ff00_00ff;
    v = (v | (v << 8)) & 0x100f_00f0_0f00_f00f;
    v = (v | (v << 4)) & 0x10c3_0c30_c30c_30c3;
    v = (v | (v << 2)) & 0x1249_2492_4924_9249;
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_dynamics::Vec3;

    /// Spreading puts bit `b` at `3 b`, for every bit of a coordinate.
    #[test]
    fn spread_moves_each_bit_to_three_times_its_place() {
        for b in 0..BITS {
            assert_eq!(spread(1 << b), 1 << (3 * b), "bit {b}");
        }
        assert_eq!(spread(u64::MAX), 0x1249_2492_4924_9249);
        assert_eq!(morton(1, 1, 1), 7);
        assert_eq!(morton(2, 0, 0), 8);
    }

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
