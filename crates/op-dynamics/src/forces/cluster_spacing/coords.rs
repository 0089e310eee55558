//! The particle coordinates in the layout the tiles read.

use rayon::prelude::*;

use super::tile::{Lane, TILE};
use crate::math::Point3;
use crate::neighbours::CLUSTER;

/// The cluster coordinates in lanes of `F`, laid out as the partner side
/// of a tile reads them: cluster `c` owns `TILE` slots per axis, slot
/// `TILE * c + k` holding particle `CLUSTER * c + k % CLUSTER` less the
/// origin (its `CLUSTER` coordinates repeated `CLUSTER` times, so a tile
/// loads them contiguously); padding slots are NaN (no pair).
#[derive(Default)]
pub(crate) struct ClusterCoords<F> {
    x: Vec<F>,
    y: Vec<F>,
    z: Vec<F>,
}

impl<F: Lane> ClusterCoords<F> {
    pub(super) fn fill(&mut self, p: &[Point3], origin: Point3) {
        let len = p.len().div_ceil(CLUSTER) * TILE;
        for v in [&mut self.x, &mut self.y, &mut self.z] {
            v.resize(len, F::NAN);
        }
        const SLOTS: usize = 256 * TILE;
        self.x
            .par_chunks_mut(SLOTS)
            .zip(self.y.par_chunks_mut(SLOTS))
            .zip(self.z.par_chunks_mut(SLOTS))
            .enumerate()
            .for_each(|(k, ((x, y), z))| {
                // Each particle converted once, then repeated over its
                // cluster's `CLUSTER` slot groups.
                let first = k * SLOTS / TILE;
                for (c, ((x, y), z)) in x
                    .chunks_exact_mut(TILE)
                    .zip(y.chunks_exact_mut(TILE))
                    .zip(z.chunks_exact_mut(TILE))
                    .enumerate()
                {
                    for m in 0..CLUSTER {
                        let q = p.get((first + c) * CLUSTER + m).map(|q| q - origin);
                        let q = q.map_or([F::NAN; 3], |q| [F::of(q.x), F::of(q.y), F::of(q.z)]);
                        for r in (m..TILE).step_by(CLUSTER) {
                            (x[r], y[r], z[r]) = (q[0], q[1], q[2]);
                        }
                    }
                }
            });
    }

    /// The partner side of cluster `c`: its coordinates repeated.
    #[inline(always)]
    pub(super) fn partner(&self, c: usize) -> [&[F; TILE]; 3] {
        fn take<F>(v: &[F], c: usize) -> &[F; TILE] {
            v[TILE * c..TILE * (c + 1)].try_into().unwrap()
        }
        [take(&self.x, c), take(&self.y, c), take(&self.z, c)]
    }

    /// The own side of cluster `c`: lane `CLUSTER * a + b` holds its
    /// particle `a`.
    #[inline(always)]
    pub(super) fn own(&self, c: usize) -> [[F; TILE]; 3] {
        let [x, y, z] = self.partner(c);
        let spread = |v: &[F; TILE]| std::array::from_fn(|k| v[k / CLUSTER]);
        [spread(x), spread(y), spread(z)]
    }
}
