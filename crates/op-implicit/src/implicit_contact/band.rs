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
//! both touch it, and when neither field is below the iso value
//! everywhere in it (bounded per block as the polygonizer bounds it: a
//! sample's common excess is positive, so both fields exceed the iso value
//! there). Each sampled block splats both objects' primitives onto its
//! nodes and one more layer (the far ends of its edges), as the
//! polygonizer samples a skin, and lists the edges between its nodes along
//! which `e_A - e_B` changes sign with a positive end: the test of a scan
//! of every node, so the list, sorted by node and axis, is the scan's list
//! less edges that cannot hold a sample. (Splatted and evaluated node
//! values may differ in their last bits, so an edge whose end lies on the
//! contact surface to round-off may be listed by one and not the other.)
//! A pair whose supports' boxes overlap but whose primitives meet in a
//! small region costs that region. The contact energy's edges
//! ([`overlap_edges`]) are found the same way, with another test of the
//! edge's ends: both excesses positive at an end.

use op_dynamics::{Point3, Real};
use rayon::prelude::*;

use crate::field::Field;
use crate::kernel::ISO;
use crate::polygonize::blocks::{
    box_bounds, margin, sample_unless_below, splat_block, Block, BlockLists, Grid, BLOCK,
};

/// Node `i`'s index along each axis of `grid` (node `i` is
/// `(i % nx, (i / nx) % ny, i / (nx ny))`).
#[inline]
pub(super) fn coords(grid: &Grid, i: usize) -> [usize; 3] {
    let [nx, ny, _] = grid.dims;
    [i % nx, (i / nx) % ny, i / (nx * ny)]
}

/// World position of node `i` of `grid`.
#[inline]
pub(super) fn node(grid: &Grid, i: usize) -> Point3 {
    let [x, y, z] = coords(grid, i);
    grid.node(x, y, z)
}

/// The blocks of `grid` touched by the cells that `spheres` reach, as a
/// mask over the blocks (x fastest; the grid has at least two nodes along
/// each axis).
fn reached(grid: &Grid, spheres: &[(Point3, Real)]) -> Vec<bool> {
    let nb = grid.blocks();
    let mut mask = vec![false; nb.iter().product()];
    for (c, r) in spheres {
        let mut range = [(0, 0); 3];
        let mut outside = false;
        for k in 0..3 {
            let last = grid.dims[k] - 2;
            let lo = ((c[k] - r - grid.lo[k]) / grid.h).floor() - 1.0;
            let hi = ((c[k] + r - grid.lo[k]) / grid.h).floor() + 1.0;
            if !(hi >= 0.0 && lo <= last as Real) {
                outside = true;
                break;
            }
            let lo = lo.max(0.0) as usize;
            let hi = (hi as usize).min(last);
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

/// Whether the edge between nodes of excesses `(ea, eb)` and `(fa, fb)`
/// is crossed by `e_A = e_B` with a positive end (a candidate sample).
#[inline]
fn crossed((ea, eb): (Real, Real), (fa, fb): (Real, Real)) -> bool {
    (ea > eb) != (fa > fb) && ea.max(eb).max(fa).max(fb) > 0.0
}

/// Whether both excesses are positive at an end of the edge between nodes
/// of excesses `(ea, eb)` and `(fa, fb)`: where the interpenetration
/// region can reach the edge (a field monotone along it is positive
/// somewhere on it only if it is at an end).
#[inline]
pub(super) fn overlapped((ea, eb): (Real, Real), (fa, fb): (Real, Real)) -> bool {
    ea.max(fa) > 0.0 && eb.max(fb) > 0.0
}

/// The edges `(node, axis)` of `grid` that can hold a sample of the
/// contact surface of `a` and `b` (module docs), in increasing node and
/// axis: nodes are evaluated only in the blocks both objects reach.
pub(super) fn crossing_edges(grid: &Grid, a: &Field, b: &Field) -> Vec<(usize, usize)> {
    let arch = pulp::Arch::new();
    edges_in_active_blocks(grid, a, b, |k, lists_a, lists_b| {
        let Some((va, _)) = sample_unless_below(a, grid, lists_a, k, ISO, arch) else {
            return Vec::new();
        };
        let Some((vb, _)) = sample_unless_below(b, grid, lists_b, k, ISO, arch) else {
            return Vec::new();
        };
        block_edges(grid, &va, &vb, &grid.block(k), crossed)
    })
}

/// The edges `(node, axis)` of `grid` that the interpenetration region of
/// `a` and `b` can reach ([`overlapped`]), in increasing node and axis:
/// the edges of the contact energy's line integrals. A block both objects
/// reach is sampled only when both fields' upper bounds on it reach the
/// iso value ([`box_bounds`]); A is splatted, and B only on the nodes
/// where A passes it and their neighbours, when its bound there reaches
/// it too: skins near each other but apart cost one splat.
pub(super) fn overlap_edges(grid: &Grid, a: &Field, b: &Field) -> Vec<(usize, usize)> {
    let arch = pulp::Arch::new();
    edges_in_active_blocks(grid, a, b, |k, lists_a, lists_b| {
        let block = grid.block(k);
        let (lo, hi) = block.bounds(grid);
        let (list_a, list_b) = near_each_other((a, lists_a.of(k)), (b, lists_b.of(k)), grid.h);
        let reaches = |field: &Field, list: &[u32]| {
            let (_, upper) = box_bounds(field, (&lo, &hi), list);
            upper + margin(upper) >= ISO
        };
        if list_a.is_empty() || !(reaches(a, &list_a) && reaches(b, &list_b)) {
            return Vec::new();
        }
        let (va, _) = splat_block(a, grid, &block, &list_a, arch);
        // An edge passing the test has an end where A is positive: it lies
        // in the box of those nodes widened by one node, where B is
        // bounded, then splatted.
        let Some(part) = positive_part(&block, &va) else {
            return Vec::new();
        };
        let (lo, hi) = part.bounds(grid);
        let (_, upper) = box_bounds(b, (&lo, &hi), &list_b);
        if upper + margin(upper) < ISO {
            return Vec::new();
        }
        let va = restricted(&block, &va, &part);
        let (vb, _) = splat_block(b, grid, &part, &list_b, arch);
        block_edges(grid, &va, &vb, &part, overlapped)
    })
}

/// The most pairs of primitives [`near_each_other`] tests in a block;
/// beyond, the lists are kept whole (testing every pair would cost about
/// what splatting the block does).
const NEAR_PAIRS: usize = 1 << 14;

/// A's primitives of `list_a` whose bounding sphere comes within `h` of
/// one of `list_b`'s, and B's of `list_b` within `h` of one of those,
/// increasing: the fields they sum are exact at both ends of every edge
/// with A above the iso value at an end and B at an end (such an end lies
/// in a kept sphere of each, the edge is `h` long, and every sphere
/// reaching either end comes within `h` of those), and an edge passes
/// [`overlapped`] with them exactly when it passes with the whole fields
/// (a pass needs such ends). Two skins near each other but apart keep
/// nothing.
fn near_each_other(
    (a, list_a): (&Field, &[u32]),
    (b, list_b): (&Field, &[u32]),
    h: Real,
) -> (Vec<u32>, Vec<u32>) {
    if list_a.len() * list_b.len() > NEAR_PAIRS {
        return (list_a.to_vec(), list_b.to_vec());
    }
    // A hundredth more than the edge's length: kept spheres are a superset.
    let pad = 1.01 * h;
    let sphere = |field: &Field, i: u32| field.primitives()[i as usize].bounding_sphere();
    let near = |(c, r): (Point3, Real), (d, s): (Point3, Real)| {
        (c - d).norm_squared() < (r + s + pad) * (r + s + pad)
    };
    let kept_a: Vec<u32> = list_a
        .iter()
        .copied()
        .filter(|&i| list_b.iter().any(|&j| near(sphere(a, i), sphere(b, j))))
        .collect();
    let kept_b: Vec<u32> = list_b
        .iter()
        .copied()
        .filter(|&j| kept_a.iter().any(|&i| near(sphere(a, i), sphere(b, j))))
        .collect();
    (kept_a, kept_b)
}

/// The smallest block within `block` holding every node where `values`
/// (x fastest) exceed the iso value and their neighbours along each axis:
/// every edge with a positive end; `None` when there is none.
fn positive_part(block: &Block, values: &[Real]) -> Option<Block> {
    let nodes = block.nodes();
    let (mut lo, mut hi) = ([usize::MAX; 3], [0; 3]);
    for (i, _) in values.iter().enumerate().filter(|(_, &v)| v > ISO) {
        let here = [
            i % nodes[0],
            (i / nodes[0]) % nodes[1],
            i / (nodes[0] * nodes[1]),
        ];
        for k in 0..3 {
            lo[k] = lo[k].min(here[k].saturating_sub(1));
            hi[k] = hi[k].max((here[k] + 1).min(nodes[k] - 1));
        }
    }
    // A node and a neighbour span a cell along each axis: the part has
    // at least one cell along each.
    (lo[0] != usize::MAX).then(|| Block {
        start: [0, 1, 2].map(|k| block.start[k] + lo[k]),
        cells: [0, 1, 2].map(|k| hi[k] - lo[k]),
    })
}

/// The values of `block` (x fastest) at the nodes of `part`, a block
/// within it.
fn restricted(block: &Block, values: &[Real], part: &Block) -> Vec<Real> {
    let (nodes, sub) = (block.nodes(), part.nodes());
    let offset = [0, 1, 2].map(|k| part.start[k] - block.start[k]);
    let mut out = Vec::with_capacity(part.node_count());
    for z in 0..sub[2] {
        for y in 0..sub[1] {
            let row = offset[0] + nodes[0] * (offset[1] + y + nodes[1] * (offset[2] + z));
            out.extend_from_slice(&values[row..row + sub[0]]);
        }
    }
    out
}

/// The edges `per_block` lists in the blocks of `grid` that both objects'
/// spheres reach (given the block and each object's primitives per
/// block), listed in parallel, in increasing node and axis and each once
/// (a block lists the edges of its far faces too).
fn edges_in_active_blocks(
    grid: &Grid,
    a: &Field,
    b: &Field,
    per_block: impl Fn(usize, &BlockLists, &BlockLists) -> Vec<(usize, usize)> + Sync,
) -> Vec<(usize, usize)> {
    // The two masks side by side (one after the other they took 1% of a
    // skinned ball's run at 2 threads, on one thread; a task per range of
    // spheres cost more than it saved: each needs a mask of every block),
    // small skins' one after the other (waking a thread for them made
    // ball_vs_spiral, 14 particles, 1.1x slower at 2 threads than at 1).
    let (mask_a, mask_b) = (|| reached(grid, a.spheres()), || reached(grid, b.spheres()));
    let (in_a, in_b) = match super::min_len(a, b, 2) {
        1 => rayon::join(mask_a, mask_b),
        _ => (mask_a(), mask_b()),
    };
    let active: Vec<usize> = (0..in_a.len()).filter(|&k| in_a[k] && in_b[k]).collect();
    if active.is_empty() {
        return Vec::new();
    }
    let (lists_a, lists_b) = (BlockLists::new(a, grid), BlockLists::new(b, grid));
    let mut edges: Vec<(usize, usize)> = active
        .par_iter()
        .with_min_len(super::min_len(a, b, active.len()))
        .flat_map_iter(|&k| per_block(k, &lists_a, &lists_b))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// The edges between the nodes of `block` and its far layer whose
/// ends pass `test`, from both fields' values there (`fa`, `fb`, x
/// fastest).
pub(super) fn block_edges(
    grid: &Grid,
    fa: &[Real],
    fb: &[Real],
    block: &Block,
    test: impl Fn((Real, Real), (Real, Real)) -> bool,
) -> Vec<(usize, usize)> {
    let (start, nodes) = (block.start, block.nodes());
    let local = |[x, y, z]: [usize; 3]| x + nodes[0] * (y + nodes[1] * z);
    let excess: Vec<(Real, Real)> = fa.iter().zip(fb).map(|(a, b)| (a - ISO, b - ISO)).collect();
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
                    if test(excess[local(here)], excess[local(next)]) {
                        let [x, y, z] = [0, 1, 2].map(|j| start[j] + here[j]);
                        edges.push((x + grid.dims[0] * (y + grid.dims[1] * z), k));
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
pub(super) fn crossing_edges_dense(grid: &Grid, a: &Field, b: &Field) -> Vec<(usize, usize)> {
    dense_edges(grid, a, b, crossed)
}

/// Every overlapped edge of the grid, from every node: the oracle of
/// [`overlap_edges`].
#[cfg(test)]
pub(super) fn overlap_edges_dense(grid: &Grid, a: &Field, b: &Field) -> Vec<(usize, usize)> {
    dense_edges(grid, a, b, overlapped)
}

/// The edges of the grid whose ends' excesses pass `test`, from every
/// node's evaluated field values.
#[cfg(test)]
fn dense_edges(
    grid: &Grid,
    a: &Field,
    b: &Field,
    test: impl Fn((Real, Real), (Real, Real)) -> bool,
) -> Vec<(usize, usize)> {
    let n: usize = grid.dims.iter().product();
    let excess: Vec<(Real, Real)> = (0..n)
        .map(|i| {
            let p = node(grid, i);
            (a.value(&p) - ISO, b.value(&p) - ISO)
        })
        .collect();
    let strides = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    let mut edges = Vec::new();
    for (i, &e) in excess.iter().enumerate() {
        let ijk = coords(grid, i);
        for k in 0..3 {
            if ijk[k] + 1 < grid.dims[k] && test(e, excess[i + strides[k]]) {
                edges.push((i, k));
            }
        }
    }
    edges
}
