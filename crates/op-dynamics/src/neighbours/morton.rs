//! Spatial (Morton, Z-order) ordering of particles.
//!
//! Memory order dominates the cost of neighbour searches and pair loops
//! (DEPENDENCIES.md: spatially sorted particles were 3-5x faster than
//! random order), so the world re-sorts its particles at list rebuilds.

use rayon::prelude::*;

use super::cell_list::finite_bounds;
use super::csr::{arr, is_finite};
use crate::math::{Point3, Real};

/// Bits per axis of a Morton key (3 x 21 = 63 bits).
const BITS: u32 = 21;
const AXIS_CELLS: Real = (1u32 << BITS) as Real;

/// A permutation of `0..positions.len()` listing the particles in Z-order
/// (Morton order) of the cubic cell of side `cell` that holds them: `order[m]`
/// is the particle to put at position `m`. Particles in the same cell keep
/// their relative order (ties broken by index), so the result is
/// deterministic. Particles with a non-finite coordinate go last.
///
/// Cells are counted from the bounding box of the finite positions, at
/// most `2^21` per axis: for a larger extent (or a `cell` that is not
/// finite and positive) the cell side grows to `extent / 2^21`. A cell near
/// the neighbour radius is a good choice.
///
/// # Panics
/// If there are more than `u32::MAX` particles.
pub fn spatial_order(positions: &[Point3], cell: Real) -> Vec<u32> {
    assert!(
        positions.len() <= u32::MAX as usize,
        "spatial_order indexes particles with u32"
    );
    let (lo, hi, _) = finite_bounds(positions);
    let ext =
        (0..3).map(|k| hi[k] - lo[k]).fold(
            0.0,
            |m: Real, e| if e.is_finite() { m.max(e) } else { Real::MAX },
        );
    let mut h = ext / AXIS_CELLS;
    if cell.is_finite() && cell > h {
        h = cell;
    }
    let h = h.max(Real::MIN_POSITIVE);
    order_by(positions, |a| {
        let c = [0, 1, 2].map(|k| quantize(a[k] - lo[k], h));
        spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
    })
}

/// The cell coordinate of `x` (an offset from the box's low corner) in
/// cells of side `h`, clamped to `0..2^21` (NaN lands in cell 0).
fn quantize(x: Real, h: Real) -> u64 {
    let max_coord = (1u64 << BITS) - 1;
    let f = x / h;
    if f >= max_coord as Real {
        max_coord
    } else if f > 0.0 {
        f as u64
    } else {
        0
    }
}

/// The permutation that sorts the particles by `key` of their position
/// (below `u64::MAX`), non-finite positions last, ties in index order.
fn order_by(positions: &[Point3], key: impl Fn([Real; 3]) -> u64 + Sync) -> Vec<u32> {
    let mut keyed: Vec<(u64, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let k = if is_finite(p) { key(arr(p)) } else { u64::MAX };
            (k, i as u32)
        })
        .collect();
    // Keys with the index appended are unique: any sort gives one result.
    keyed.par_sort_unstable();
    keyed.par_iter().map(|&(_, i)| i).collect()
}

/// A permutation that puts `cluster` consecutive particles close
/// together in all three axes, for the cluster kernels
/// ([`ClusterPairs`](super::ClusterPairs)): particles in columns along z,
/// the columns in Z-order, each column sorted by z (the grid of GROMACS'
/// nbnxm scheme, Páll & Hess 2013). A column's side makes a cluster about
/// cubic: `(cluster * V / n)^(1/3)` over the box's volume `V`, or
/// `(cluster * A / n)^(1/2)` over its x-y area `A` for a flat cloud,
/// whichever is larger. Columns of odd x run down, so consecutive
/// columns meet at the same end and a cluster that spans two stays
/// short.
///
/// `order[m]` is the particle to put at position `m`; ties (equal keys)
/// keep index order, so the result is deterministic at any thread count.
/// Particles with a non-finite coordinate go last.
///
/// # Panics
/// If there are more than `u32::MAX` particles.
pub fn cluster_order(positions: &[Point3], cluster: usize) -> Vec<u32> {
    assert!(
        positions.len() <= u32::MAX as usize,
        "cluster_order indexes particles with u32"
    );
    let (lo, hi, finite) = finite_bounds(positions);
    let ext = [0, 1, 2].map(|k| {
        let e = hi[k] - lo[k];
        if e.is_finite() {
            e.max(0.0)
        } else {
            Real::MAX
        }
    });
    let per = cluster as Real / finite.max(1) as Real;
    let side = (per * ext[0] * ext[1] * ext[2])
        .cbrt()
        .max((per * ext[0] * ext[1]).sqrt());
    // At most 2^21 columns along x and y, 2^21 steps along z.
    let side = side
        .max(ext[0].max(ext[1]) / AXIS_CELLS)
        .max(Real::MIN_POSITIVE);
    let dz = (ext[2] / AXIS_CELLS).max(Real::MIN_POSITIVE);
    let max_coord = (1u64 << BITS) - 1;
    // One key: the column's 42-bit Z-order code, then 21 bits of z.
    order_by(positions, |a| {
        let (x, y) = (quantize(a[0] - lo[0], side), quantize(a[1] - lo[1], side));
        let z = quantize(a[2] - lo[2], dz);
        // Columns of odd x run down: consecutive columns in Z-order meet
        // at the same end, so a cluster that spans two columns stays
        // short.
        let z = if x % 2 == 1 { max_coord - z } else { z };
        ((spread2(x) | (spread2(y) << 1)) << BITS) | z
    })
}

/// Spreads the low 21 bits of `x` to every second bit.
fn spread2(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
    x = (x | (x << 8)) & 0x00ff_00ff_00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333_3333_3333;
    x = (x | (x << 1)) & 0x5555_5555_5555_5555;
    x
}

/// Spreads the low 21 bits of `x` to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_permutation(order: &[u32]) -> bool {
        let mut seen = vec![false; order.len()];
        order.iter().all(|&i| {
            let i = i as usize;
            i < seen.len() && !std::mem::replace(&mut seen[i], true)
        })
    }

    #[test]
    fn spread_interleaves_bits() {
        assert_eq!(spread(0b1), 0b1);
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0x1f_ffff), 0x1249_2492_4924_9249);
    }

    #[test]
    fn spatial_order_is_a_permutation() {
        let mut pts: Vec<Point3> = (0..1000)
            .map(|i| {
                let t = i as Real;
                Point3::new((t * 0.37).sin() * 10.0, (t * 0.11).cos() * 5.0, t * 0.01)
            })
            .collect();
        pts[3] = Point3::new(Real::NAN, 0.0, 0.0);
        pts[7] = Point3::new(1e300, -1e300, 0.0);
        for cell in [1.0, 0.0, -1.0, Real::NAN, 1e-300, 1e9] {
            let order = spatial_order(&pts, cell);
            assert_eq!(order.len(), pts.len());
            assert!(is_permutation(&order), "cell {cell}");
            assert_eq!(*order.last().unwrap(), 3, "non-finite goes last");
        }
        assert!(spatial_order(&[], 1.0).is_empty());
        assert_eq!(spatial_order(&[Point3::origin(); 3], 1.0), [0, 1, 2]);
    }

    #[test]
    fn cluster_order_is_a_permutation_with_non_finite_last() {
        let mut pts: Vec<Point3> = (0..1001)
            .map(|i| {
                let t = i as Real;
                Point3::new((t * 0.37).sin() * 10.0, (t * 0.11).cos() * 5.0, t * 0.01)
            })
            .collect();
        pts[3] = Point3::new(Real::NAN, 0.0, 0.0);
        let order = cluster_order(&pts, 4);
        assert!(is_permutation(&order) && order.len() == pts.len());
        assert_eq!(*order.last().unwrap(), 3, "non-finite goes last");
        pts[7] = Point3::new(1e300, -1e300, 0.0);
        assert!(is_permutation(&cluster_order(&pts, 4)));
        // Flat, degenerate and empty clouds.
        let sheet: Vec<Point3> = (0..100)
            .map(|k| Point3::new((k % 10) as Real, 0.0, (k / 10) as Real))
            .collect();
        assert!(is_permutation(&cluster_order(&sheet, 4)));
        assert_eq!(cluster_order(&[Point3::origin(); 3], 4), [0, 1, 2]);
        assert!(cluster_order(&[], 4).is_empty());
    }

    /// Clusters of four consecutive particles of the column order are
    /// shorter than those of Morton order on a random cloud (the
    /// kernel's lanes): the median and 90th percentile of their longest
    /// side. The same order at one thread.
    #[test]
    fn cluster_order_makes_compact_clusters() {
        let mut rng = crate::interactions::test_support::Rng::new(11);
        let side = 16.0;
        let cloud: Vec<Point3> = (0..4096)
            .map(|_| {
                Point3::new(
                    rng.range(0.0, side),
                    rng.range(0.0, side),
                    rng.range(0.0, side),
                )
            })
            .collect();
        let extents = |order: &[u32]| {
            let mut e: Vec<Real> = order
                .chunks(4)
                .map(|c| {
                    let p = c.iter().map(|&i| cloud[i as usize]);
                    let lo = p.clone().reduce(|a, b| a.inf(&b)).unwrap();
                    let hi = p.reduce(|a, b| a.sup(&b)).unwrap();
                    (hi - lo).max()
                })
                .collect();
            e.sort_by(Real::total_cmp);
            let at = |q: Real| e[(q * (e.len() - 1) as Real) as usize];
            (at(0.5), at(0.9))
        };
        let columns = extents(&cluster_order(&cloud, 4));
        let morton = extents(&spatial_order(&cloud, 2.0));
        assert!(columns.0 < 0.8 * morton.0, "{columns:?} vs {morton:?}");
        assert!(columns.1 < 0.8 * morton.1, "{columns:?} vs {morton:?}");
        let order = cluster_order(&cloud, 4);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        assert_eq!(pool.install(|| cluster_order(&cloud, 4)), order);
    }

    #[test]
    fn spatial_order_follows_z_order() {
        // The 2 x 2 x 2 corners of unit cells: Morton order is x fastest,
        // then y, then z.
        let mut pts = Vec::new();
        for z in [1.0, 0.0] {
            for y in [1.0, 0.0] {
                for x in [1.0, 0.0] {
                    pts.push(Point3::new(x, y, z));
                }
            }
        }
        let order = spatial_order(&pts, 1.0);
        let sorted: Vec<Point3> = order.iter().map(|&i| pts[i as usize]).collect();
        for (m, p) in sorted.iter().enumerate() {
            let expect = Point3::new(
                (m & 1) as Real,
                ((m >> 1) & 1) as Real,
                ((m >> 2) & 1) as Real,
            );
            assert_eq!(*p, expect);
        }
    }
}
