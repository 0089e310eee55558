//! A uniform cell grid over bounding spheres (DEPENDENCIES.md: a sorted
//! cell list beat kiddo on flat sheets such as skinned spirals): each cell
//! lists, in increasing order, the spheres whose bounding box overlaps it,
//! stored flat (CSR).

use op_dynamics::{Point3, Real};

/// Cells are as large as the mean sphere radius: a lookup then scans the
/// spheres whose box overlaps a cell of side R, about (3 R)^3 / (4 R)^3 = 0.42
/// of those a cell of the mean diameter lists, each sphere sits in at most
/// 27 cells (for a sphere of mean size). The total cell count is capped at
/// this many per sphere (plus a constant) by coarsening the grid.
const MAX_CELLS_PER_SPHERE: usize = 64;

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
        let n_cells: usize = dims.iter().product();
        let mut counts = vec![0u32; n_cells + 1];
        grid.for_each_cell_of(spheres, |_, cell| counts[cell + 1] += 1);
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; counts[n_cells] as usize];
        grid.for_each_cell_of(spheres, |i, cell| {
            items[fill[cell] as usize] = i as u32;
            fill[cell] += 1;
        });
        grid.starts = counts;
        grid.items = items;
        grid
    }

    fn cell_coord(&self, x: Real, k: usize) -> usize {
        let c = ((x - self.origin[k]) * self.inv_cell).floor();
        c.clamp(0.0, (self.dims[k] - 1) as Real) as usize
    }

    fn for_each_cell_of(&self, spheres: &[(Point3, Real)], mut visit: impl FnMut(usize, usize)) {
        for (i, (c, r)) in spheres.iter().enumerate() {
            let lo = [0, 1, 2].map(|k| self.cell_coord(c[k] - r, k));
            let hi = [0, 1, 2].map(|k| self.cell_coord(c[k] + r, k));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        visit(i, (z * self.dims[1] + y) * self.dims[0] + x);
                    }
                }
            }
        }
    }

    /// The spheres whose box overlaps the cell holding `p`, in increasing
    /// order (empty outside the grid).
    #[inline]
    pub(crate) fn candidates(&self, p: &Point3) -> &[u32] {
        if self.starts.is_empty() {
            return &[];
        }
        let mut idx = [0usize; 3];
        for k in 0..3 {
            // Truncation is the floor on the grid (c >= 0).
            let c = (p[k] - self.origin[k]) * self.inv_cell;
            if !(c >= 0.0 && c < self.dims[k] as Real) {
                return &[];
            }
            idx[k] = c as usize;
        }
        let cell = (idx[2] * self.dims[1] + idx[1]) * self.dims[0] + idx[0];
        &self.items[self.starts[cell] as usize..self.starts[cell + 1] as usize]
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
}
