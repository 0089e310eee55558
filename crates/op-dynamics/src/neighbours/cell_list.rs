//! Sorted uniform cell list: particles counting-sorted into cubic cells of
//! side `h >= radius / 2`, each particle scanning the 125 cells within two
//! cells of its own (LAMMPS' default bin size, half the neighbour radius;
//! Plimpton 1995), or, when the cell cap coarsens such cells, cells of side
//! `h >= radius` scanned one cell around (27 cells).
//!
//! The grid is dense over the bounding box of the finite positions, its
//! number of cells capped at `MAX_CELLS_PER_PARTICLE * n + 1024` (and
//! `2^20` per axis). A sheet tilted through its box needs many (mostly
//! empty) cells, hence the generous cap; a sparse cloud with a huge extent
//! gets larger cells instead (still correct, more candidates per particle).
//! Coordinates are clamped into the grid, which keeps any two particles
//! within `reach * h` of each other within `reach` cells of each other, so
//! overflowing or outlying coordinates cost time, never pairs.
//!
//! Rows are searched in particle order, so the search is fastest when the
//! particles are in spatial order (see [`spatial_order`](super::spatial_order)).

use rayon::prelude::*;

use super::csr::{arr, dist2, is_finite, squared_radius, PairList};
use crate::math::{Point3, Real};

/// Relative margin of the cell size over the radius: it absorbs the
/// round-off of the cell coordinates and of the pair test, so particles
/// that pass the pair test are never more than `reach` cells apart (cells
/// of side `radius / reach`).
const MARGIN: Real = 1e-6;
/// At most this many cells along one axis (keeps cell coordinates exact to
/// far better than `MARGIN`).
const MAX_AXIS_CELLS: Real = (1u32 << 20) as Real;
/// Cap on the cells per particle (4 bytes each): 32 left rotated 100k
/// sheets uncoarsened, where 8 cost them 20% more time.
const MAX_CELLS_PER_PARTICLE: usize = 32;
/// The most lines of cells a row scans: 5 x 5 (two cells around, the
/// largest reach `choose_grid` picks).
const LINES: usize = 25;
/// Candidates tested together in [`KeepWithin`] (a multiple of the f64
/// lanes of every instruction set pulp dispatches to, AVX-512's 8 the
/// most); the sorted arrays carry `CHUNK - 1` slots of padding after the
/// last.
const CHUNK: usize = 8;
/// Marks a particle that is in no cell (non-finite position).
const NO_CELL: u32 = u32::MAX;

/// Reusable buffers of the cell list.
#[derive(Clone, Debug, Default)]
pub(crate) struct GridScratch {
    /// Cell of each particle (`NO_CELL` when its position is not finite).
    cell_of: Vec<u32>,
    /// `cell_start[c]..cell_start[c + 1]` indexes `sorted_*` for cell `c`.
    cell_start: Vec<u32>,
    /// Positions in cell order, one coordinate per array (x, y, z): the
    /// pair test of a row runs over them in SIMD lanes.
    sorted_pos: [Vec<Real>; 3],
    /// Particle indices in cell order (ascending within a cell).
    sorted_idx: Vec<u32>,
}

#[cfg(test)]
impl GridScratch {
    /// Identifies the buffers (to test that rebuilds reuse them).
    pub(crate) fn buffer_ptrs(&self) -> [usize; 6] {
        [
            self.cell_of.as_ptr() as usize,
            self.cell_start.as_ptr() as usize,
            self.sorted_pos[0].as_ptr() as usize,
            self.sorted_pos[1].as_ptr() as usize,
            self.sorted_pos[2].as_ptr() as usize,
            self.sorted_idx.as_ptr() as usize,
        ]
    }
}

/// The grid geometry.
#[derive(Clone, Copy, Debug)]
struct Grid {
    min: [Real; 3],
    h: Real,
    dims: [usize; 3],
}

impl Grid {
    /// A grid over the box `[min, max]` with cells of side at least
    /// `radius * (1 + MARGIN)` and at most `max_cells` cells.
    fn new(min: [Real; 3], max: [Real; 3], radius: Real, max_cells: usize) -> Self {
        // Extents may overflow to infinity for coordinates near Real::MAX.
        let ext = [0, 1, 2].map(|k| {
            let e = max[k] - min[k];
            if e.is_finite() {
                e
            } else {
                Real::MAX
            }
        });
        let ext_max = ext[0].max(ext[1]).max(ext[2]);
        let mut h = (radius * (1.0 + MARGIN))
            .max(ext_max / MAX_AXIS_CELLS)
            .max(Real::MIN_POSITIVE);
        let dims_for = |h: Real| ext.map(|e| ((e / h).floor() as usize).saturating_add(1));
        let mut dims = dims_for(h);
        for _ in 0..10_000 {
            let cells = dims.iter().map(|&d| d as Real).product::<Real>();
            if cells <= max_cells as Real {
                break;
            }
            let grow = (cells / max_cells as Real).cbrt().max(1.05);
            h *= grow;
            dims = dims_for(h);
        }
        if dims.iter().map(|&d| d as Real).product::<Real>() > max_cells as Real {
            // Unreachable in practice; one cell is always correct.
            h = Real::INFINITY;
            dims = [1, 1, 1];
        }
        Grid { min, h, dims }
    }

    fn num_cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Clamped cell coordinate along axis `k` (NaN lands in cell 0).
    #[inline]
    fn coord(&self, x: Real, k: usize) -> usize {
        let f = (x - self.min[k]) / self.h;
        let last = self.dims[k] - 1;
        if f >= last as Real {
            last
        } else if f > 0.0 {
            f as usize
        } else {
            0
        }
    }

    #[inline]
    fn cell_id(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    #[inline]
    fn decode(&self, id: usize) -> [usize; 3] {
        let x = id % self.dims[0];
        let yz = id / self.dims[0];
        [x, yz % self.dims[1], yz / self.dims[1]]
    }
}

/// Bounding box and count of the finite positions (in parallel; minima
/// and maxima are exact, so the same box at any thread count).
pub(super) fn finite_bounds(positions: &[Point3]) -> ([Real; 3], [Real; 3], usize) {
    let empty = ([Real::INFINITY; 3], [Real::NEG_INFINITY; 3], 0usize);
    positions
        .par_iter()
        .with_min_len(4096)
        .fold(
            || empty,
            |(mut lo, mut hi, n), p| {
                if !is_finite(p) {
                    return (lo, hi, n);
                }
                let a = arr(p);
                for k in 0..3 {
                    lo[k] = lo[k].min(a[k]);
                    hi[k] = hi[k].max(a[k]);
                }
                (lo, hi, n + 1)
            },
        )
        .reduce(
            || empty,
            |(lo1, hi1, n1), (lo2, hi2, n2)| {
                (
                    [0, 1, 2].map(|k| lo1[k].min(lo2[k])),
                    [0, 1, 2].map(|k| hi1[k].max(hi2[k])),
                    n1 + n2,
                )
            },
        )
}

/// Fills `out` with the half list of all pairs within `radius` (inclusive),
/// using a sorted uniform cell list. Same output as
/// [`all_pairs`](super::all_pairs).
pub(crate) fn cell_list(positions: &[Point3], radius: Real, out: &mut PairList) {
    let n = positions.len();
    let mut s = std::mem::take(&mut out.scratch.grid);
    match RowSearch::prepare(positions, radius, &mut s) {
        Some(search) => out.build_parallel(n, |i, row| search.row(i, row)),
        None => out.set_empty(n),
    }
    out.scratch.grid = s;
}

/// Fills `rows` (one per cluster of `cluster` consecutive particles) with
/// the cluster rows of [`ClusterPairs`](super::ClusterPairs) straight from
/// the positions: row `c` lists `c`, then every cluster `d > c` with some
/// particle within `radius` (inclusive, the pair test of every backend)
/// of some particle of `c`, ascending. The same rows as the clusters of
/// the half list of [`cell_list`], without building that list.
///
/// Each row scans once the cells around the box of its cluster's
/// particles, testing every candidate particle against all of them; a
/// cluster found once is stamped and its other particles skipped. Rows
/// are independent (one per task), hence the same at any thread count.
pub(super) fn cluster_rows(
    positions: &[Point3],
    radius: Real,
    cluster: usize,
    scratch: &mut GridScratch,
    rows: &mut [Vec<u32>],
) {
    let n = positions.len();
    let nc = rows.len();
    assert!(
        (1..=4).contains(&cluster),
        "cluster_rows: clusters of 1 to 4 particles"
    );
    debug_assert_eq!(nc, n.div_ceil(cluster));
    let Some(search) = RowSearch::prepare(positions, radius, scratch) else {
        rows.par_iter_mut().enumerate().for_each(|(c, row)| {
            row.clear();
            row.push(c as u32);
        });
        return;
    };
    // The cluster size as a constant: a candidate's cluster is then a
    // shift (or a multiplication), not a division, which cost a quarter of
    // the search at a runtime size.
    match cluster {
        1 => search.cluster_rows::<1>(rows),
        2 => search.cluster_rows::<2>(rows),
        3 => search.cluster_rows::<3>(rows),
        _ => search.cluster_rows::<4>(rows),
    }
}

/// The grid of the search and how many cells around its own each particle
/// scans.
fn choose_grid(min: [Real; 3], max: [Real; 3], radius: Real, n: usize) -> (Grid, usize) {
    let max_cells = n
        .saturating_mul(MAX_CELLS_PER_PARTICLE)
        .saturating_add(1024)
        .min(1 << 31);
    // Half cells scanned two cells around (LAMMPS' default bins of half
    // the neighbour radius): 125 cells of (h/2)^3 hold 58% of the
    // candidates of 27 cells of h^3. When the cap would coarsen them,
    // whole cells scanned one around.
    let half = Grid::new(min, max, 0.5 * radius, max_cells);
    if half.h <= 0.5 * radius * (1.0 + 2.0 * MARGIN) {
        (half, 2)
    } else {
        (Grid::new(min, max, radius, max_cells), 1)
    }
}

impl GridScratch {
    /// The slots `a..b` of cells `x0..=x1` of the line `[y, z]` of
    /// `grid` (contiguous in cell order).
    #[inline(always)]
    fn line(&self, grid: &Grid, (x0, x1): (usize, usize), [y, z]: [usize; 2]) -> (usize, usize) {
        (
            self.cell_start[grid.cell_id([x0, y, z])] as usize,
            self.cell_start[grid.cell_id([x1, y, z]) + 1] as usize,
        )
    }

    /// The position in slot `slot` of the cell order.
    #[inline(always)]
    fn position(&self, slot: usize) -> [Real; 3] {
        [0, 1, 2].map(|k| self.sorted_pos[k][slot])
    }

    /// Cell of every particle (`NO_CELL` for non-finite positions).
    fn assign_cells(&mut self, positions: &[Point3], grid: &Grid) {
        self.cell_of.resize(positions.len(), 0);
        self.cell_of
            .par_iter_mut()
            .zip(positions.par_iter())
            .with_min_len(4096)
            .for_each(|(c, p)| {
                *c = if is_finite(p) {
                    let a = arr(p);
                    grid.cell_id([0, 1, 2].map(|k| grid.coord(a[k], k))) as u32
                } else {
                    NO_CELL
                };
            });
    }

    /// Counting sort of the `finite` particles into cells (stable:
    /// ascending index within a cell).
    fn sort_into_cells(&mut self, positions: &[Point3], grid: &Grid, finite: usize) {
        let ncells = grid.num_cells();
        self.cell_start.clear();
        self.cell_start.resize(ncells + 1, 0);
        for &c in &self.cell_of {
            if c != NO_CELL {
                self.cell_start[c as usize + 1] += 1;
            }
        }
        for c in 0..ncells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        // Padding for the pair test's last chunk (whose lanes past a line's
        // end are masked out, whatever they hold).
        for axis in &mut self.sorted_pos {
            axis.resize(finite + CHUNK - 1, Real::NAN);
        }
        self.sorted_idx.resize(finite + CHUNK - 1, 0);
        for (i, &c) in self.cell_of.iter().enumerate() {
            if c != NO_CELL {
                let slot = self.cell_start[c as usize] as usize;
                self.cell_start[c as usize] += 1;
                let p = arr(&positions[i]);
                for (axis, x) in self.sorted_pos.iter_mut().zip(p) {
                    axis[slot] = x;
                }
                self.sorted_idx[slot] = i as u32;
            }
        }
        // Each start was advanced to the next cell's start: shift back.
        self.cell_start.copy_within(0..ncells, 1);
        self.cell_start[0] = 0;
    }
}

/// The pair test of one row, dispatched by pulp to the best instruction
/// set of the CPU: writes to `out`, in order, every candidate of `lines`
/// (slots of the cell order), advancing past the ones kept (`j > i` and
/// `dist2 <= r2`), and returns how many it kept. Each [`CHUNK`] of
/// candidates computes its squared distances and tests in lanes (the same
/// operations as [`dist2`], so the same pairs), then writes them one by
/// one without a branch (whether `j > i` is a coin toss in spatial order:
/// a branch on it mispredicts half the time). One candidate at a time,
/// the test was three quarters of a 32k fcc block's list build; in lanes
/// the build takes 0.62-0.66 of that time (AVX2).
struct KeepWithin<'a> {
    scratch: &'a GridScratch,
    p: [Real; 3],
    i: u32,
    r2: Real,
    lines: &'a [(usize, usize)],
    out: &'a mut [u32],
}

impl pulp::WithSimd for KeepWithin<'_> {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) -> usize {
        let KeepWithin {
            scratch,
            p,
            i,
            r2,
            lines,
            out,
        } = self;
        let [xs, ys, zs] = &scratch.sorted_pos;
        let [px, py, pz] = p.map(|x| simd.splat_f64s(x));
        let r2s = simd.splat_f64s(r2);
        let (yes, no) = (simd.splat_u64s(1), simd.splat_u64s(0));
        let mut len = 0;
        for &(a, b) in lines {
            // Whole chunks from `a`: the last one reads past `b` (into the
            // next cells, or the padding of `sort_into_cells`) and masks
            // those lanes out.
            for s in (a..b).step_by(CHUNK) {
                let (x, _) = S::as_simd_f64s(&xs[s..s + CHUNK]);
                let (y, _) = S::as_simd_f64s(&ys[s..s + CHUNK]);
                let (z, tail) = S::as_simd_f64s(&zs[s..s + CHUNK]);
                debug_assert!(tail.is_empty(), "CHUNK is a multiple of the lanes");
                let mut near = [0u64; CHUNK];
                let (lanes, _) = S::as_mut_simd_u64s(&mut near);
                for (v, lane) in lanes.iter_mut().enumerate() {
                    // `dist2(p, q)`: (dx² + dy²) + dz².
                    let (dx, dy, dz) = (
                        simd.sub_f64s(x[v], px),
                        simd.sub_f64s(y[v], py),
                        simd.sub_f64s(z[v], pz),
                    );
                    let d2 = simd.add_f64s(
                        simd.add_f64s(simd.mul_f64s(dx, dx), simd.mul_f64s(dy, dy)),
                        simd.mul_f64s(dz, dz),
                    );
                    *lane = simd.select_u64s(simd.less_than_or_equal_f64s(d2, r2s), yes, no);
                }
                let js = &scratch.sorted_idx[s..s + CHUNK];
                for (l, (&j, &near)) in js.iter().zip(&near).enumerate() {
                    out[len] = j;
                    len += near as usize & usize::from(j > i) & usize::from(s + l < b);
                }
            }
        }
        len
    }
}

/// What the search of one row reads: the positions, the squared radius,
/// the grid, the reach in cells and the particles sorted into cells.
struct RowSearch<'a> {
    positions: &'a [Point3],
    r2: Real,
    grid: Grid,
    reach: usize,
    scratch: &'a GridScratch,
    /// The instruction set the pair test runs with ([`KeepWithin`]).
    arch: pulp::Arch,
}

impl<'a> RowSearch<'a> {
    /// Sorts the finite `positions` into the cells of a search of
    /// `radius` (in `scratch`), or `None` when the search finds no pairs
    /// (a NaN or negative radius, fewer than two finite positions).
    fn prepare(
        positions: &'a [Point3],
        radius: Real,
        scratch: &'a mut GridScratch,
    ) -> Option<Self> {
        let r2 = squared_radius(radius)?;
        let (min, max, finite) = finite_bounds(positions);
        if finite < 2 {
            return None;
        }
        let (grid, reach) = choose_grid(min, max, radius, positions.len());
        scratch.assign_cells(positions, &grid);
        scratch.sort_into_cells(positions, &grid, finite);
        Some(RowSearch {
            positions,
            r2,
            grid,
            reach,
            scratch,
            arch: pulp::Arch::new(),
        })
    }

    /// Appends to `row` the particles `j > i` within the radius of `i`,
    /// scanning the cells within `reach` of its own.
    #[inline(always)]
    fn row(&self, i: usize, row: &mut Vec<u32>) {
        let RowSearch {
            positions,
            r2,
            grid,
            reach,
            scratch,
            ..
        } = *self;
        let c = scratch.cell_of[i];
        if c == NO_CELL {
            return;
        }
        let p = arr(&positions[i]);
        let [cx, cy, cz] = grid.decode(c as usize);
        let x0 = cx.saturating_sub(reach);
        let x1 = (cx + reach).min(grid.dims[0] - 1);
        let zs = cz.saturating_sub(reach)..=(cz + reach).min(grid.dims[2] - 1);
        let ys = cy.saturating_sub(reach)..=(cy + reach).min(grid.dims[1] - 1);
        // Cells x0..=x1 of a (y, z) line are contiguous in cell order:
        // their candidates are the slots `a..b` of `sorted_*`.
        let mut lines = [(0, 0); LINES];
        let mut count = 0;
        let mut candidates = 0;
        for z in zs {
            for y in ys.clone() {
                let (a, b) = scratch.line(&grid, (x0, x1), [y, z]);
                lines[count] = (a, b);
                count += 1;
                candidates += b - a;
            }
        }
        // Room for every candidate, made once per row (one fill, not one
        // per line).
        let start = row.len();
        row.resize(start + candidates + CHUNK, 0);
        let kept = self.arch.dispatch(KeepWithin {
            scratch,
            p,
            i: i as u32,
            r2,
            lines: &lines[..count],
            out: &mut row[start..],
        });
        row.truncate(start + kept);
    }

    /// Fills `rows` as [`cluster_rows`] does, for clusters of `K`
    /// particles.
    fn cluster_rows<const K: usize>(&self, rows: &mut [Vec<u32>]) {
        let (n, nc) = (self.positions.len(), rows.len());
        rows.par_iter_mut().enumerate().for_each_init(
            || vec![u32::MAX; nc],
            |stamp, (c, row)| {
                row.clear();
                row.push(c as u32);
                let members = K * c..(K * (c + 1)).min(n);
                self.cluster_candidates::<K>(members, c as u32, stamp, row);
                row[1..].sort_unstable();
            },
        );
    }

    /// Appends to `row` the clusters `d > c` (of `K <= 4` particles,
    /// `members` the slots of `c`) that hold a particle within
    /// the radius of some member, stamping each (`stamp[d] = c`) so that
    /// its other particles are skipped. Scans once the cells around the
    /// bounding box of the members; each candidate is tested against the
    /// four members at once (missing and non-finite members never pass).
    #[inline(always)]
    fn cluster_candidates<const K: usize>(
        &self,
        members: std::ops::Range<usize>,
        c: u32,
        stamp: &mut [u32],
        row: &mut Vec<u32>,
    ) {
        let RowSearch {
            positions,
            r2,
            grid,
            scratch,
            ..
        } = *self;
        let mut m = [[Real::NAN; 3]; 4];
        let (mut lo, mut hi) = ([Real::INFINITY; 3], [Real::NEG_INFINITY; 3]);
        for (k, i) in members.enumerate() {
            if scratch.cell_of[i] != NO_CELL {
                m[k] = arr(&positions[i]);
                for a in 0..3 {
                    lo[a] = lo[a].min(m[k][a]);
                    hi[a] = hi[a].max(m[k][a]);
                }
            }
        }
        if lo[0] > hi[0] {
            return;
        }
        // Every particle within the radius of a member lies within the
        // members' box grown by the radius (and a round-off margin).
        let radius = r2.sqrt() * (1.0 + MARGIN);
        let grow = |x: Real| radius + 4.0 * Real::EPSILON * x.abs();
        let from = [0, 1, 2].map(|a| grid.coord(lo[a] - grow(lo[a]), a));
        let to = [0, 1, 2].map(|a| grid.coord(hi[a] + grow(hi[a]), a));
        for z in from[2]..=to[2] {
            for y in from[1]..=to[1] {
                let (a, b) = scratch.line(&grid, (from[0], to[0]), [y, z]);
                for (slot, &j) in (a..b).zip(&scratch.sorted_idx[a..b]) {
                    let q = &scratch.position(slot);
                    let d = j / K as u32;
                    if d <= c || stamp[d as usize] == c {
                        continue;
                    }
                    let near = m.iter().fold(false, |any, p| any | (dist2(p, q) <= r2));
                    if near {
                        stamp[d as usize] = c;
                        row.push(d);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_caps_cells_and_keeps_cell_size_above_radius() {
        let g = Grid::new([0.0; 3], [1e6, 1e6, 1e6], 1.0, 10_000);
        assert!(g.num_cells() <= 10_000, "{g:?}");
        assert!(g.h >= 1.0);
        let g = Grid::new([-Real::MAX; 3], [Real::MAX; 3], 1.0, 1000);
        assert!(g.num_cells() <= 1000, "{g:?}");
        assert_eq!(g.coord(Real::MAX, 0), g.dims[0] - 1);
        assert_eq!(g.coord(-Real::MAX, 0), 0);
        let g = Grid::new([1.0; 3], [1.0; 3], 0.0, 1000);
        assert_eq!(g.dims, [1, 1, 1]);
        let g = Grid::new([0.0; 3], [1.0; 3], Real::INFINITY, 1000);
        assert_eq!(g.dims, [1, 1, 1]);
        assert_eq!(g.coord(Real::NAN, 1), 0);
    }

    #[test]
    fn decode_inverts_cell_id() {
        let g = Grid::new([0.0; 3], [10.0, 5.0, 3.0], 1.0, 10_000);
        for id in 0..g.num_cells() {
            assert_eq!(g.cell_id(g.decode(id)), id);
        }
    }
}
