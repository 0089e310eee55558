//! Neighbour search with kiddo's immutable k-d tree.
//!
//! The tree holds the finite positions; each particle runs an unsorted
//! radius query in parallel. kiddo's own distance may differ from ours in
//! the last bits, so the query radius is slightly enlarged and every
//! candidate is re-tested with the shared pair test: the lists are exactly
//! those of the other backends.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::csr::{arr, dist2, is_finite, squared_radius, PairList};
use crate::math::{Point3, Real};

/// Reusable buffers of the k-d tree search (the tree itself is allocated
/// by kiddo at every build).
#[derive(Default)]
pub(crate) struct KdScratch {
    /// Finite positions, in index order.
    points: Vec<[Real; 3]>,
    /// Particle index of each entry of `points` (used only when some
    /// positions are not finite).
    index: Vec<u32>,
}

/// Fills `out` with the half list of all pairs within `radius` (inclusive),
/// using kiddo's `ImmutableKdTree`. Same output as
/// [`all_pairs`](super::all_pairs).
pub(crate) fn kd_tree(positions: &[Point3], radius: Real, out: &mut PairList) {
    let n = positions.len();
    let Some(r2) = squared_radius(radius) else {
        out.set_empty(n);
        return;
    };
    let mut s = std::mem::take(&mut out.scratch.kd);
    s.points.clear();
    s.index.clear();
    for (i, p) in positions.iter().enumerate() {
        if is_finite(p) {
            s.points.push(arr(p));
            s.index.push(i as u32);
        }
    }
    if s.points.len() < 2 {
        out.set_empty(n);
        out.scratch.kd = s;
        return;
    }
    let tree = match ImmutableKdTree::<Real, 3>::new_from_slice(&s.points) {
        Ok(tree) => tree,
        Err(_) => {
            // Only fails when indices overflow u32, which PairList rules
            // out anyway; the cell list gives the same lists.
            out.scratch.kd = s;
            super::cell_list::cell_list(positions, radius, out);
            return;
        }
    };
    // Enlarged query radius (covers kiddo's round-off, and underflow of
    // tiny squared distances when radius is 0); candidates are re-tested.
    let query_r2 = r2 * (1.0 + 1e-5) + 1e-300;
    let all_finite = s.points.len() == n;
    let scratch = &s;
    out.build_parallel(n, |i, row| {
        let p = &positions[i];
        if !is_finite(p) {
            return;
        }
        let q = arr(p);
        tree.query(&q)
            .within::<SquaredEuclidean<Real>>(query_r2)
            .unsorted()
            .visit(|res| {
                let e = res.item as usize;
                let j = if all_finite {
                    e
                } else {
                    scratch.index[e] as usize
                };
                if j > i && dist2(&q, &scratch.points[e]) <= r2 {
                    row.push(j as u32);
                }
            });
    });
    out.scratch.kd = s;
}
