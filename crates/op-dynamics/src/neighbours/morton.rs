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
    let max_coord = (1u64 << BITS) - 1;
    let mut keyed: Vec<(u64, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let key = if is_finite(p) {
                let a = arr(p);
                let c = [0, 1, 2].map(|k| {
                    let f = (a[k] - lo[k]) / h;
                    if f >= max_coord as Real {
                        max_coord
                    } else if f > 0.0 {
                        f as u64
                    } else {
                        0
                    }
                });
                spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
            } else {
                u64::MAX
            };
            (key, i as u32)
        })
        .collect();
    // Keys with the index appended are unique: any sort gives one result.
    keyed.par_sort_unstable();
    keyed.par_iter().map(|&(_, i)| i).collect()
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
