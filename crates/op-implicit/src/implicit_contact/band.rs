//! The narrow band of the contact sampling grid: which grid edges can hold
//! a sample of the contact surface `e_A = e_B > 0`, found without sampling
//! the whole intersection of the two support boxes.
//!
//! A sample is the crossing of `e_A - e_B` on an edge where the common
//! excess is positive, so both fields exceed the iso value there: the
//! crossing lies strictly inside a bounding sphere of one of A's
//! primitives and one of B's (a field is zero outside its primitives'
//! bounding spheres, [`Field::for_each_near`]). The grid is cut into
//! blocks; a block is sampled only when the cells reached by A's spheres
//! and those reached by B's (each sphere's cell range padded by one cell)
//! both touch it. Each sampled block evaluates its nodes and one more layer
//! (the far ends of its edges), and lists the edges between its nodes
//! along which `e_A - e_B` changes sign with a positive end: the same
//! values, bit for bit, and the same test as a scan of every node, so the
//! list, sorted by node and axis, is the scan's list less edges that
//! cannot hold a sample. The contact reactions are therefore unchanged,
//! and a pair whose supports' boxes overlap but whose primitives meet in a
//! small region costs that region.

use op_dynamics::{Point3, Real, Vec3};
use rayon::prelude::*;

use crate::field::Field;
use crate::kernel::ISO;

/// Cells per block along x, y, z.
const BLOCK: [usize; 3] = [16, 8, 8];

/// The node grid of the contact sampling: origin, cell size, nodes per axis
/// (node `i` is `(i % nx, (i / nx) % ny, i / (nx ny))`).
#[derive(Clone, Copy, Debug)]
pub(super) struct ContactGrid {
    pub lo: Point3,
    pub h: Real,
    pub dims: [usize; 3],
}

impl ContactGrid {
    /// World position of node `(x, y, z)`.
    #[inline]
    pub fn node_at(&self, [x, y, z]: [usize; 3]) -> Point3 {
        self.lo + Vec3::new(x as Real, y as Real, z as Real) * self.h
    }

    /// World position of node `i`.
    #[inline]
    pub fn node(&self, i: usize) -> Point3 {
        self.node_at(self.coords(i))
    }

    /// Node `i`'s index along each axis.
    #[inline]
    fn coords(&self, i: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }

    /// Linear index of node `(x, y, z)`.
    #[inline]
    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        let [nx, ny, _] = self.dims;
        x + nx * (y + ny * z)
    }

    /// Cells per axis (at least 1: a grid one node thick along an axis
    /// has its nodes in one layer of blocks).
    fn cells(&self) -> [usize; 3] {
        self.dims.map(|n| n.saturating_sub(1).max(1))
    }

    /// Blocks per axis.
    fn blocks(&self) -> [usize; 3] {
        let cells = self.cells();
        [0, 1, 2].map(|k| cells[k].div_ceil(BLOCK[k]))
    }

    /// The blocks touched by the cells that `spheres` reach, as a mask
    /// over the blocks (x fastest).
    fn reached(&self, spheres: &[(Point3, Real)]) -> Vec<bool> {
        let (cells, nb) = (self.cells(), self.blocks());
        let mut mask = vec![false; nb.iter().product()];
        for (c, r) in spheres {
            let mut range = [(0, 0); 3];
            let mut outside = false;
            for k in 0..3 {
                let lo = ((c[k] - r - self.lo[k]) / self.h).floor() - 1.0;
                let hi = ((c[k] + r - self.lo[k]) / self.h).floor() + 1.0;
                if !(hi >= 0.0 && lo <= (cells[k] - 1) as Real) {
                    outside = true;
                    break;
                }
                let lo = lo.max(0.0) as usize;
                let hi = (hi as usize).min(cells[k] - 1);
                range[k] = (lo / BLOCK[k], hi / BLOCK[k]);
            }
            if outside {
                continue;
            }
            for z in range[2].0..=range[2].1 {
                for y in range[1].0..=range[1].1 {
                    for x in range[0].0..=range[0].1 {
                        mask[x + nb[0] * (y + nb[1] * z)] = true;
                    }
                }
            }
        }
        mask
    }
}

/// Whether the edge between nodes of excesses `(ea, eb)` and `(fa, fb)`
/// is crossed by `e_A = e_B` with a positive end (a candidate sample).
#[inline]
fn crossed((ea, eb): (Real, Real), (fa, fb): (Real, Real)) -> bool {
    (ea > eb) != (fa > fb) && ea.max(eb).max(fa).max(fb) > 0.0
}

/// The edges `(node, axis)` of `grid` that can hold a sample of the
/// contact surface of `a` and `b` (module docs), in increasing node and
/// axis: nodes are evaluated only in the blocks both objects reach.
pub(super) fn crossing_edges(grid: &ContactGrid, a: &Field, b: &Field) -> Vec<(usize, usize)> {
    let (in_a, in_b) = (grid.reached(a.spheres()), grid.reached(b.spheres()));
    let nb = grid.blocks();
    let active: Vec<usize> = (0..in_a.len()).filter(|&k| in_a[k] && in_b[k]).collect();
    let mut edges: Vec<(usize, usize)> = active
        .par_iter()
        .flat_map_iter(|&block| {
            let idx = [
                block % nb[0],
                (block / nb[0]) % nb[1],
                block / (nb[0] * nb[1]),
            ];
            block_edges(grid, a, b, idx)
        })
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// The crossed edges between the nodes of block `idx` and its far layer.
fn block_edges(grid: &ContactGrid, a: &Field, b: &Field, idx: [usize; 3]) -> Vec<(usize, usize)> {
    let start = [0, 1, 2].map(|k| idx[k] * BLOCK[k]);
    let nodes = [0, 1, 2].map(|k| (BLOCK[k] + 1).min(grid.dims[k] - start[k]));
    let local = |[x, y, z]: [usize; 3]| x + nodes[0] * (y + nodes[1] * z);
    let mut excess = Vec::with_capacity(nodes.iter().product());
    for z in 0..nodes[2] {
        for y in 0..nodes[1] {
            for x in 0..nodes[0] {
                let p = grid.node_at([start[0] + x, start[1] + y, start[2] + z]);
                excess.push((a.value(&p) - ISO, b.value(&p) - ISO));
            }
        }
    }
    let mut edges = Vec::new();
    for z in 0..nodes[2] {
        for y in 0..nodes[1] {
            for x in 0..nodes[0] {
                let here = [x, y, z];
                for k in 0..3 {
                    if here[k] + 1 == nodes[k] {
                        continue;
                    }
                    let mut next = here;
                    next[k] += 1;
                    if crossed(excess[local(here)], excess[local(next)]) {
                        let global = [0, 1, 2].map(|j| start[j] + here[j]);
                        edges.push((grid.index(global), k));
                    }
                }
            }
        }
    }
    edges
}

/// Every crossed edge of the grid, from every node: the oracle of
/// [`crossing_edges`].
#[cfg(test)]
pub(super) fn crossing_edges_dense(
    grid: &ContactGrid,
    a: &Field,
    b: &Field,
) -> Vec<(usize, usize)> {
    let n: usize = grid.dims.iter().product();
    let excess: Vec<(Real, Real)> = (0..n)
        .map(|i| {
            let p = grid.node(i);
            (a.value(&p) - ISO, b.value(&p) - ISO)
        })
        .collect();
    let strides = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let mut edges = Vec::new();
    for (i, &e) in excess.iter().enumerate() {
        let ijk = grid.coords(i);
        for k in 0..3 {
            if ijk[k] + 1 < grid.dims[k] && crossed(e, excess[i + strides[k]]) {
                edges.push((i, k));
            }
        }
    }
    edges
}
