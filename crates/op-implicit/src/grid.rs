//! A uniform cell grid over bounding spheres (DEPENDENCIES.md: a sorted
//! cell list beat kiddo on flat sheets such as skinned spirals): each cell
//! lists, in increasing order, the spheres whose bounding box overlaps it,
//! stored flat (CSR).

use std::sync::atomic::{AtomicU32, Ordering};

use op_dynamics::{Point3, Real, MIN_PARALLEL_LEN};
use rayon::prelude::*;

/// Cells are as large as the mean sphere radius: a lookup then scans the
/// spheres whose box overlaps a cell of side R, about (3 R)^3 / (4 R)^3 = 0.42
/// of those a cell of the mean diameter lists, each sphere sits in at most
/// 27 cells (for a sphere of mean size). The total cell count is capped at
/// this many per sphere (plus a constant) by coarsening the grid.
const MAX_CELLS_PER_SPHERE: usize = 64;

/// Up to this many spheres, the grid is one cell listing them all: a
/// lookup scans them all, which costs about what the lists would save,
/// and the grid costs nothing to build (a small skin is posed at every
/// contact evaluation: ball_vs_spiral's skins of 10 and 4 primitives
/// spent a quarter of their contact time building grids).
const ONE_CELL: usize = 16;

/// The grid: origin, cell size, dimensions, and the CSR lists.
#[derive(Clone, Debug, Default)]
pub(crate) struct CellGrid {
    origin: Point3,
    inv_cell: Real,
    dims: [usize; 3],
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    /// Builds the grid over `spheres` (centre, radius).
    pub(crate) fn new(spheres: &[(Point3, Real)]) -> Self {
        Self::new_listing(spheres, |_| true)
    }

    /// The grid of [`CellGrid::new`] (the same origin, cells and
    /// dimensions), its cells listing only the spheres `keep` accepts (by
    /// index): a lookup then hands over those of the spheres around the
    /// point, in the same order.
    pub(crate) fn new_listing(
        spheres: &[(Point3, Real)],
        keep: impl Fn(usize) -> bool + Sync,
    ) -> Self {
        if spheres.is_empty() {
            return CellGrid::default();
        }
        let mut lo = Point3::from([Real::INFINITY; 3]);
        let mut hi = Point3::from([Real::NEG_INFINITY; 3]);
        let mut mean_radius = 0.0;
        for (c, r) in spheres {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k] - r);
                hi[k] = hi[k].max(c[k] + r);
            }
            mean_radius += r;
        }
        mean_radius /= spheres.len() as Real;
        let extent = hi - lo;
        let mut cell = mean_radius.max(1e-9 * extent.max()).max(Real::MIN_POSITIVE);
        if spheres.len() <= ONE_CELL {
            // Twice the extent: the box's far corner falls in the first cell.
            cell = cell.max(2.0 * extent.max());
        }
        let budget = MAX_CELLS_PER_SPHERE * spheres.len() + 1024;
        let dims_for = |cell: Real| -> [usize; 3] {
            [0, 1, 2].map(|k| ((extent[k] / cell).floor() as usize + 1).max(1))
        };
        // Saturating: tiny primitives in a large extent ask for more cells
        // than a usize counts, before the loop coarsens the grid.
        let cells = |d: &[usize; 3]| d.iter().fold(1usize, |a, &n| a.saturating_mul(n));
        let mut dims = dims_for(cell);
        while cells(&dims) > budget {
            cell *= 1.5;
            dims = dims_for(cell);
        }
        let mut grid = CellGrid {
            origin: lo,
            inv_cell: 1.0 / cell,
            dims,
            starts: Vec::new(),
            items: Vec::new(),
        };
        let boxes: Vec<Option<CellBox>> = spheres
            .par_iter()
            .with_min_len(MIN_PARALLEL_LEN)
            .enumerate()
            .map(|(i, (c, r))| {
                let lo = [0, 1, 2].map(|k| grid.cell_coord(c[k] - r, k));
                let hi = [0, 1, 2].map(|k| grid.cell_coord(c[k] + r, k));
                keep(i).then(|| [0, 1, 2].map(|k| (lo[k], hi[k])))
            })
            .collect();
        (grid.starts, grid.items) = bucket(dims, &boxes);
        grid
    }

    fn cell_coord(&self, x: Real, k: usize) -> usize {
        let c = ((x - self.origin[k]) * self.inv_cell).floor();
        c.clamp(0.0, (self.dims[k] - 1) as Real) as usize
    }

    /// The spheres whose box overlaps the cell holding `p`, in increasing
    /// order (empty outside the grid).
    #[inline]
    pub(crate) fn candidates(&self, p: &Point3) -> &[u32] {
        self.cell_of(p).map_or(&[], |cell| self.items_of(cell))
    }

    /// The cell holding `p` (`None` outside the grid, or for a grid
    /// without cells). Monotone along each axis: the points of a box
    /// whose two opposite corners fall in one cell all fall in it.
    #[inline]
    pub(crate) fn cell_of(&self, p: &Point3) -> Option<usize> {
        if self.starts.is_empty() {
            return None;
        }
        let mut idx = [0usize; 3];
        for k in 0..3 {
            // Truncation is the floor on the grid (c >= 0).
            let c = (p[k] - self.origin[k]) * self.inv_cell;
            if !(c >= 0.0 && c < self.dims[k] as Real) {
                return None;
            }
            idx[k] = c as usize;
        }
        Some((idx[2] * self.dims[1] + idx[1]) * self.dims[0] + idx[0])
    }

    /// The spheres listed in `cell` ([`CellGrid::cell_of`]), in increasing
    /// order.
    #[inline]
    pub(crate) fn items_of(&self, cell: usize) -> &[u32] {
        &self.items[self.starts[cell] as usize..self.starts[cell + 1] as usize]
    }
}

/// An item's box of bins: the inclusive index range along each axis.
pub(crate) type CellBox = [(usize, usize); 3];

/// Lists, per bin of a `dims` grid (x fastest), the indices of the items
/// whose box (`boxes[i]`, none for an item in no bin) covers it, in
/// increasing order, flat (CSR: the bin `b` holds
/// `items[starts[b]..starts[b + 1]]`). A counting sort in chunks of the
/// items, one per thread (none under [`MIN_PARALLEL_LEN`] items): each
/// chunk counts its items per bin, the counts are summed bin by bin in
/// chunk order, and each chunk fills its places, so every bin lists its
/// items in increasing order whatever the number of chunks: the same
/// lists at any thread count.
pub(crate) fn bucket(dims: [usize; 3], boxes: &[Option<CellBox>]) -> (Vec<u32>, Vec<u32>) {
    let n_bins: usize = dims.iter().product();
    let per_chunk = boxes
        .len()
        .div_ceil(rayon::current_num_threads().max(1))
        .max(MIN_PARALLEL_LEN);
    let chunks: Vec<&[Option<CellBox>]> = boxes.chunks(per_chunk).collect();
    let mut places: Vec<Vec<u32>> = chunks
        .par_iter()
        .map(|chunk| {
            let mut counts = vec![0u32; n_bins];
            for b in chunk.iter().flatten() {
                bins_of(dims, b, |bin| counts[bin] += 1);
            }
            counts
        })
        .collect();
    // Each chunk's count becomes its first place in the bin.
    let mut starts = vec![0u32; n_bins + 1];
    let mut total = 0u32;
    for bin in 0..n_bins {
        starts[bin] = total;
        for counts in places.iter_mut() {
            let count = counts[bin];
            counts[bin] = total;
            total += count;
        }
    }
    starts[n_bins] = total;
    // Made and read back in parallel (a 100k-particle skin lists about a
    // million places).
    let items: Vec<AtomicU32> = (0..total)
        .into_par_iter()
        .with_min_len(MIN_PARALLEL_LEN)
        .map(|_| AtomicU32::new(0))
        .collect();
    chunks
        .par_iter()
        .zip(places.par_iter_mut())
        .enumerate()
        .for_each(|(c, (chunk, next))| {
            for (k, b) in chunk.iter().enumerate() {
                let Some(b) = b else { continue };
                let item = (c * per_chunk + k) as u32;
                bins_of(dims, b, |bin| {
                    // Each place is written once, by its chunk.
                    items[next[bin] as usize].store(item, Ordering::Relaxed);
                    next[bin] += 1;
                });
            }
        });
    (
        starts,
        items
            .into_par_iter()
            .with_min_len(MIN_PARALLEL_LEN)
            .map(AtomicU32::into_inner)
            .collect(),
    )
}

/// Calls `f` with every bin of `b` in a `dims` grid (x fastest), in
/// increasing order: a generic function, so that `f` is inlined into the
/// loops (through a `dyn FnMut` each bin was an indirect call).
#[inline(always)]
fn bins_of(dims: [usize; 3], b: &CellBox, mut f: impl FnMut(usize)) {
    for z in b[2].0..=b[2].1 {
        for y in b[1].0..=b[1].1 {
            let row = (z * dims[1] + y) * dims[0];
            for x in b[0].0..=b[0].1 {
                f(row + x);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Primitives far smaller than their extent (a skin radius of 1e-320,
    /// found by the fuzz test, seed 7) coarsen the grid instead of
    /// overflowing its cell count.
    #[test]
    fn tiny_spheres_in_a_large_extent_do_not_overflow() {
        let spheres = vec![
            (Point3::new(0.0, 0.0, 0.0), 1e-320),
            (Point3::new(10.0, 10.0, 10.0), 1e-320),
        ];
        let grid = CellGrid::new(&spheres);
        assert!(grid.dims.iter().product::<usize>() <= MAX_CELLS_PER_SPHERE * 2 + 1024);
    }

    /// The chunked bucketing lists every bin's items in increasing order,
    /// the same at one and several threads and as one serial pass.
    #[test]
    fn buckets_are_the_same_at_any_thread_count() {
        let dims = [7, 5, 3];
        let boxes: Vec<Option<CellBox>> = (0..5000usize)
            .map(|i| {
                let x = (i * 7919) % 6;
                let y = (i * 104_729) % 4;
                (i % 11 != 0).then_some([(x, x + i % 2), (y, y + 1), (i % 3, i % 3)])
            })
            .collect();
        let mut serial = vec![Vec::new(); 7 * 5 * 3];
        for (i, b) in boxes.iter().enumerate() {
            let Some(b) = b else { continue };
            for z in b[2].0..=b[2].1 {
                for y in b[1].0..=b[1].1 {
                    for x in b[0].0..=b[0].1 {
                        serial[(z * 5 + y) * 7 + x].push(i as u32);
                    }
                }
            }
        }
        for threads in [1, 2, 3, 8] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (starts, items) = pool.install(|| bucket(dims, &boxes));
            for (bin, expected) in serial.iter().enumerate() {
                let got = &items[starts[bin] as usize..starts[bin + 1] as usize];
                assert_eq!(got, &expected[..], "bin {bin} at {threads} threads");
            }
        }
    }
}
