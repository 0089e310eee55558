//! The brute-force `O(n^2)` search: the test oracle of the other backends.

use super::csr::{arr, dist2, squared_radius, PairList};
use crate::math::{Point3, Real};

/// Fills `out` with every pair `(i, j)`, `i < j`, whose squared distance
/// `dx*dx + dy*dy + dz*dz` (with `d = p_j - p_i`) is `<= radius^2`:
/// the pair test is **inclusive**, and shared bit for bit by every backend.
///
/// Serial and `O(n^2)`: use it as the reference in tests, or for a handful
/// of particles. A NaN or negative `radius` gives a list without pairs;
/// particles with a non-finite coordinate have no neighbours.
///
/// # Panics
/// If there are `u32::MAX` particles or more, or more than `u32::MAX` pairs.
pub fn all_pairs(positions: &[Point3], radius: Real, out: &mut PairList) {
    let n = positions.len();
    let Some(r2) = squared_radius(radius) else {
        out.set_empty(n);
        return;
    };
    out.build_serial(n, |i, row| {
        let p = arr(&positions[i]);
        for (j, q) in positions.iter().enumerate().skip(i + 1) {
            if dist2(&p, &arr(q)) <= r2 {
                row.push(j as u32);
            }
        }
    });
}
