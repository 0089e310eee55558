//! The sampling grid cut into blocks of [`BLOCK`] cells, and the narrow
//! band: which blocks can hold a piece of the skin, and their node values
//! splatted from the primitives that reach them.
//!
//! The field is the sum of compactly supported primitive fields (seed 002
//! §6), so a block can only be crossed by the surface where some
//! primitive's support reaches it. For each candidate block, the sum of
//! each primitive's kernel at its nearest and farthest distance to the
//! block bounds the field on the block (the kernel decreases with
//! distance; [`box_bounds`]); a block whose bounds lie both
//! below or both above the iso value has all its nodes on one side and no
//! crossing, and is skipped. The rest are sampled by splatting (each
//! primitive adds its field to the nodes of the block inside its bounding
//! sphere, in increasing primitive index: the terms of [`Field::value`]'s
//! sum in its order, so blocks far from every primitive cost nothing and
//! a node shared by two blocks gets the same bits in both. A point
//! primitive's term has [`Field::value`]'s bits; another skeleton's maps
//! the node into its frame with the rotation matrix where
//! [`Field::value`] rotates by the quaternion, so the two may differ in
//! the last bits).

use op_dynamics::{Point3, Real, Vec3};

use rayon::prelude::*;

use crate::field::{Field, ScalarField};
use crate::grid::{bucket, CellBox};
use crate::kernel::value_sq;
use crate::primitives::{PosedPrimitive, Skeleton};

/// Cells per block along x, y, z: long along x, the rows the primitives
/// are splatted along, so a row's setup is shared by more nodes.
pub(crate) const BLOCK: [usize; 3] = [16, 8, 8];

/// The node grid: origin, cell size and nodes per axis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    pub lo: Point3,
    pub h: Real,
    pub dims: [usize; 3],
}

impl Grid {
    /// World position of node `(i, j, k)`.
    #[inline]
    pub fn node(&self, i: usize, j: usize, k: usize) -> Point3 {
        self.lo + Vec3::new(i as Real, j as Real, k as Real) * self.h
    }

    /// Blocks per axis.
    pub fn blocks(&self) -> [usize; 3] {
        [0, 1, 2].map(|k| (self.dims[k] - 1).div_ceil(BLOCK[k]))
    }

    /// Block `b` (linear index, x fastest).
    pub fn block(&self, b: usize) -> Block {
        let nb = self.blocks();
        let idx = [b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])];
        let start = [0, 1, 2].map(|k| idx[k] * BLOCK[k]);
        let cells = [0, 1, 2].map(|k| BLOCK[k].min(self.dims[k] - 1 - start[k]));
        Block { start, cells }
    }
}

/// A block: its first node and its cells per axis (nodes: one more).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block {
    pub start: [usize; 3],
    pub cells: [usize; 3],
}

impl Block {
    /// Nodes per axis.
    pub fn nodes(&self) -> [usize; 3] {
        self.cells.map(|c| c + 1)
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes().iter().product()
    }

    /// The block's box `(lo, hi)` (its corner nodes).
    pub(crate) fn bounds(&self, grid: &Grid) -> (Point3, Point3) {
        let [i, j, k] = self.start;
        let [a, b, c] = self.cells;
        (grid.node(i, j, k), grid.node(i + a, j + b, k + c))
    }
}

/// Per block, the primitives whose bounding sphere's box reaches one of
/// its nodes, in increasing index (CSR).
pub(crate) struct BlockLists {
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl BlockLists {
    /// Lists the primitives of `field` per block of `grid`.
    pub fn new(field: &Field, grid: &Grid) -> Self {
        Self::filtered(field, grid, |_, _| true)
    }

    /// Lists the primitives of `field` whose bounding sphere (centre,
    /// radius) `keep` accepts, per block of `grid`.
    pub fn filtered(
        field: &Field,
        grid: &Grid,
        keep: impl Fn(&Point3, Real) -> bool + Sync,
    ) -> Self {
        let ranges: Vec<Option<CellBox>> = field
            .primitives()
            .par_iter()
            .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
            .map(|p| {
                let (c, r) = p.bounding_sphere();
                keep(&c, r).then(|| block_range(grid, (c, r))).flatten()
            })
            .collect();
        let (starts, items) = bucket(grid.blocks(), &ranges);
        BlockLists { starts, items }
    }

    /// The primitives reaching block `b`, increasing.
    pub fn of(&self, b: usize) -> &[u32] {
        &self.items[self.starts[b] as usize..self.starts[b + 1] as usize]
    }
}

/// The blocks (per axis, inclusive) whose nodes the box of sphere
/// `(c, r)` may reach, or `None` when it reaches no node.
fn block_range(grid: &Grid, (c, r): (Point3, Real)) -> Option<[(usize, usize); 3]> {
    let mut out = [(0, 0); 3];
    for k in 0..3 {
        let (lo, hi) = node_range(grid, k, c[k] - r, c[k] + r)?;
        let last = (grid.dims[k] - 1).div_ceil(BLOCK[k]) - 1;
        // Block b holds nodes [b B, (b + 1) B].
        out[k] = (
            (lo.div_ceil(BLOCK[k])).saturating_sub(1).min(last),
            (hi / BLOCK[k]).min(last),
        );
    }
    Some(out)
}

/// The nodes along axis `k` within `[a, b]`, widened by one node each way
/// (rounding), or `None` when there are none.
fn node_range(grid: &Grid, k: usize, a: Real, b: Real) -> Option<(usize, usize)> {
    let n = grid.dims[k] as Real;
    let lo = floor((a - grid.lo[k]) / grid.h) - 1.0;
    let hi = ceil((b - grid.lo[k]) / grid.h) + 1.0;
    if hi < 0.0
        || lo > n - 1.0
        || lo.partial_cmp(&hi) == Some(std::cmp::Ordering::Greater)
        || lo.is_nan()
        || hi.is_nan()
    {
        return None;
    }
    Some((lo.max(0.0) as usize, hi.min(n - 1.0) as usize))
}

/// `x.floor()` without the libm call (SSE2 has no rounding instruction):
/// truncation, one down for negative non-integers. Exact for |x| < 2^53;
/// beyond, and for NaN, `x` itself (an integer, or NaN).
#[inline]
fn floor(x: Real) -> Real {
    if x.is_nan() || x.abs() >= 9.0e15 {
        return x;
    }
    let t = x as i64 as Real;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// `x.ceil()` as [`floor`]: `-floor(-x)`.
#[inline]
fn ceil(x: Real) -> Real {
    -floor(-x)
}

/// What sampling a block found.
pub(super) enum Sampled {
    /// All nodes are on one side of the iso value: no crossing.
    Skipped,
    /// Node values (x fastest), and how many primitive fields were
    /// evaluated.
    Values(Vec<Real>, usize),
}

/// Lower and upper bounds of the field on block `block` from the
/// primitives `list` (module doc).
fn field_bounds(field: &Field, grid: &Grid, block: &Block, list: &[u32]) -> (Real, Real) {
    let (lo, hi) = block.bounds(grid);
    box_bounds(field, (&lo, &hi), list)
}

/// Lower and upper bounds of the field on the box `(lo, hi)` from the
/// primitives `list`: each kernel at the box's farthest and nearest point
/// to its skeleton. The distance to the skeleton is at least the distance
/// to its bounding sphere's centre less the skeleton's extent (a point's
/// is 0), and a rectangle's at least the distance to its plane, so the
/// kernel there bounds the field above; a point's or an
/// ellipsoid's kernel at the farthest corner bounds it below (an
/// ellipsoid's scaled distance lies between the distance over its largest
/// and over its smallest semi-axis), another skeleton's by 0.
pub(crate) fn box_bounds(
    field: &Field,
    (lo, hi): (&Point3, &Point3),
    list: &[u32],
) -> (Real, Real) {
    let (mut upper, mut lower) = (0.0, 0.0);
    for &i in list {
        let prim = &field.primitives()[i as usize];
        let (c, r) = prim.bounding_sphere();
        let w = prim.weight();
        let (mut near, mut far) = (0.0, 0.0);
        for k in 0..3 {
            let d_near = (lo[k] - c[k]).max(c[k] - hi[k]).max(0.0);
            let d_far = (c[k] - lo[k]).max(hi[k] - c[k]);
            near += d_near * d_near;
            far += d_far * d_far;
        }
        match prim.shape() {
            Skeleton::Point => {
                upper += w * value_sq(near / (r * r));
                lower += w * value_sq(far / (r * r));
            }
            Skeleton::Ellipsoid { scales } => {
                let inner = r * scales.min() / scales.max();
                upper += w * value_sq(near / (r * r));
                lower += w * value_sq(far / (inner * inner));
            }
            shape => {
                let (extent, _) = shape.extent_and_factor();
                let support = r - extent;
                let mut gap = (near.sqrt() - extent).max(0.0);
                if let Skeleton::Rectangle { .. } = shape {
                    // No nearer than the rectangle's plane.
                    let n = prim.pose().rotation * Vec3::z();
                    let (mid, half) = ((lo.coords + hi.coords) * 0.5, (hi - lo) * 0.5);
                    let across = n.abs().dot(&half);
                    gap = gap.max((n.dot(&(mid - c.coords)).abs() - across).max(0.0));
                }
                upper += w * value_sq(gap * gap / (support * support));
            }
        }
    }
    (lower, upper)
}

/// A margin of the bounds well above the rounding of sums of a few
/// hundred terms.
pub(crate) fn margin(upper: Real) -> Real {
    1e-9 * (1.0 + upper)
}

/// Whether block `block` cannot cross `iso`: outside every primitive's
/// support, or inside enough of them ([`field_bounds`]).
fn can_skip(field: &Field, grid: &Grid, block: &Block, list: &[u32], iso: Real) -> bool {
    if list.is_empty() {
        return true;
    }
    let (lower, upper) = field_bounds(field, grid, block, list);
    upper + margin(upper) < iso || lower - margin(upper) > iso
}

/// Whether block `block` of a field nowhere above `bound` (its primitives
/// `list`) is entirely below `iso`: no crossing there.
pub(crate) fn below_everywhere(
    bound: &Field,
    grid: &Grid,
    block: &Block,
    list: &[u32],
    iso: Real,
) -> bool {
    if list.is_empty() {
        return true;
    }
    let (_, upper) = field_bounds(bound, grid, block, list);
    upper + margin(upper) < iso
}

/// The node values of block `b` splatted from the primitives of `field`
/// reaching it, as [`sample_band`] splats them, with the number of
/// primitive fields evaluated, or `None` when the field
/// is below `iso` everywhere in the block. Unlike [`sample_band`], a block
/// entirely inside the skin is sampled: the contact surface of two skins
/// may run through it (`crate::implicit_contact`).
pub(crate) fn sample_unless_below(
    field: &Field,
    grid: &Grid,
    lists: &BlockLists,
    b: usize,
    iso: Real,
    arch: pulp::Arch,
) -> Option<(Vec<Real>, usize)> {
    let block = grid.block(b);
    let list = lists.of(b);
    if below_everywhere(field, grid, &block, list, iso) {
        return None;
    }
    Some(splat_block(field, grid, &block, list, arch))
}

/// Samples block `b` of the narrow band: skipped, or its node values
/// splatted from the primitives reaching it (module doc).
pub(super) fn sample_band(
    field: &Field,
    grid: &Grid,
    lists: &BlockLists,
    b: usize,
    iso: Real,
    arch: pulp::Arch,
) -> Sampled {
    let block = grid.block(b);
    let list = lists.of(b);
    if can_skip(field, grid, &block, list, iso) {
        return Sampled::Skipped;
    }
    let (values, evaluations) = splat_block(field, grid, &block, list, arch);
    Sampled::Values(values, evaluations)
}

/// The node values of `block` from the primitives `list` of `field`
/// ([`Splat`]), and how many primitive fields were evaluated.
pub(crate) fn splat_block(
    field: &Field,
    grid: &Grid,
    block: &Block,
    list: &[u32],
    arch: pulp::Arch,
) -> (Vec<Real>, usize) {
    let [nx, ny, nz] = block.nodes();
    let mut values = vec![0.0; nx * ny * nz];
    let [s0, s1, s2] = block.start;
    // Node coordinates exactly as Grid::node computes them.
    let xs: Vec<Real> = (0..nx).map(|i| grid.node(s0 + i, 0, 0).x).collect();
    let ys: Vec<Real> = (0..ny).map(|j| grid.node(0, s1 + j, 0).y).collect();
    let zs: Vec<Real> = (0..nz).map(|k| grid.node(0, 0, s2 + k).z).collect();
    let evaluations = arch.dispatch(Splat {
        field,
        grid,
        block,
        list,
        nodes: [&xs, &ys, &zs],
        values: &mut values,
    });
    (values, evaluations)
}

/// The primitives of `list` splatted onto a block's node values
/// ([`sample_band`]), dispatched by pulp to the best instruction set of
/// the CPU (AVX-512 or AVX2 where present): the row loop is plain Rust,
/// inlined into pulp's `#[target_feature]` instances and vectorized there
/// with the wide registers. The same operations in the same order at any
/// width (no fused multiply-add: Rust does not contract), so the bits do
/// not depend on the instruction set or the thread count.
struct Splat<'a> {
    field: &'a Field,
    grid: &'a Grid,
    block: &'a Block,
    list: &'a [u32],
    /// Node coordinates along x, y and z.
    nodes: [&'a [Real]; 3],
    values: &'a mut [Real],
}

impl pulp::WithSimd for Splat<'_> {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> usize {
        splat(self)
    }
}

/// The body of [`Splat`]: the values added, and how many primitive
/// fields were evaluated.
#[inline(always)]
fn splat(s: Splat<'_>) -> usize {
    let Splat {
        field,
        grid,
        block,
        list,
        nodes: [xs, ys, zs],
        values,
    } = s;
    let [nx, ny, nz] = block.nodes();
    let h = grid.h;
    let mut evaluations = 0;
    let mut dx2 = vec![0.0; nx];
    for &i in list {
        let prim = &field.primitives()[i as usize];
        let (c, r) = prim.bounding_sphere();
        let local = |k: usize, n: usize| {
            let s = block.start[k] as Real;
            let a = (floor((c[k] - r - grid.lo[k]) / h) - s).max(0.0);
            let b = (ceil((c[k] + r - grid.lo[k]) / h) - s).min(n as Real - 1.0);
            (a as usize, b as isize)
        };
        let ((i0, i1), (j0, j1), (k0, k1)) = (local(0, nx), local(1, ny), local(2, nz));
        if i1 < i0 as isize || j1 < j0 as isize || k1 < k0 as isize {
            continue;
        }
        let (i1, j1, k1) = (i1 as usize, j1 as usize, k1 as usize);
        let r2 = r * r;
        if !matches!(prim.shape(), Skeleton::Point) {
            // Other skeletons: the nodes of the bounding box's rows that
            // meet the bounding sphere, mapped into the primitive's frame
            // (`skeleton_rows`).
            evaluations +=
                skeleton_rows(prim, [xs, ys, zs], (c, r), [i0, i1, j0, j1, k0, k1], values);
            continue;
        }
        // A point primitive: w f(s), s = |p - c|^2 / r^2, over the nodes of
        // its bounding box in the block; the squared x offsets are shared
        // by every row, nodes outside the support add exactly 0, and the
        // kernel is written branch-free so the row loop vectorizes.
        let inv = 1.0 / r2;
        let w = prim.weight();
        for (d, x) in dx2[i0..=i1].iter_mut().zip(&xs[i0..=i1]) {
            let dx = x - c.x;
            *d = dx * dx;
        }
        let dx2 = &dx2[i0..=i1];
        for (k, z) in zs.iter().enumerate().take(k1 + 1).skip(k0) {
            let dz = z - c.z;
            let dz2 = dz * dz;
            if dz2 >= r2 {
                continue;
            }
            for (j, y) in ys.iter().enumerate().take(j1 + 1).skip(j0) {
                let dy = y - c.y;
                let dyz = dy * dy + dz2;
                if dyz >= r2 {
                    continue;
                }
                let row = (k * ny + j) * nx;
                for (v, &d) in values[row + i0..=row + i1].iter_mut().zip(dx2) {
                    *v += w * kernel_row((d + dyz) * inv);
                }
                evaluations += dx2.len();
            }
        }
    }
    evaluations
}

/// The field of `prim`, a skeleton other than a point, added to the
/// nodes `i0..=i1` of the rows `(j, k)` in `j0..=j1`, `k0..=k1` of a
/// block (node coordinates `xs`, `ys`, `zs`; values x fastest) that meet
/// its bounding sphere `(c, r)`; returns the nodes evaluated. Each node is
/// mapped into the primitive's frame by the same operations, in the same
/// order, as `m * (p - t)` and the skeleton's squared distance and kernel
/// evaluated at one point (`PosedPrimitive::field_in_frame`; the
/// column products summed left to right, the clamp as a maximum and a
/// minimum, the squared distance `(x^2 + y^2) + z^2`, the kernel without a
/// branch), so the bits are those of evaluating each node alone, and the
/// row loop has no branch and vectorizes.
#[inline(always)]
fn skeleton_rows(
    prim: &PosedPrimitive,
    [xs, ys, zs]: [&[Real]; 3],
    (c, r): (Point3, Real),
    [i0, i1, j0, j1, k0, k1]: [usize; 6],
    values: &mut [Real],
) -> usize {
    match *prim.shape() {
        Skeleton::Point => unreachable!("point primitives are splatted by `splat`"),
        Skeleton::Segment { half_length: a } => rows(
            prim,
            [xs, ys, zs],
            (c, r),
            [i0, i1, j0, j1, k0, k1],
            values,
            |x, y, z| {
                let dx = x - x.max(-a).min(a);
                (dx * dx + y * y) + z * z
            },
        ),
        Skeleton::Rectangle {
            half_extents: [a, b],
        } => rows(
            prim,
            [xs, ys, zs],
            (c, r),
            [i0, i1, j0, j1, k0, k1],
            values,
            |x, y, z| {
                let (dx, dy) = (x - x.max(-a).min(a), y - y.max(-b).min(b));
                (dx * dx + dy * dy) + z * z
            },
        ),
        Skeleton::Ellipsoid { scales } => rows(
            prim,
            [xs, ys, zs],
            (c, r),
            [i0, i1, j0, j1, k0, k1],
            values,
            |x, y, z| {
                let (qx, qy, qz) = (x / scales.x, y / scales.y, z / scales.z);
                (qx * qx + qy * qy) + qz * qz
            },
        ),
    }
}

/// [`skeleton_rows`] for the squared distance `d2` in the primitive's
/// frame.
#[inline(always)]
fn rows(
    prim: &PosedPrimitive,
    [xs, ys, zs]: [&[Real]; 3],
    (c, r): (Point3, Real),
    [i0, i1, j0, j1, k0, k1]: [usize; 6],
    values: &mut [Real],
    d2: impl Fn(Real, Real, Real) -> Real,
) -> usize {
    let (nx, ny) = (xs.len(), ys.len());
    let (m, t) = prim.world_to_frame();
    let (w, inv, r2) = (prim.weight(), prim.inv_radius2(), r * r);
    let mut evaluations = 0;
    for (k, z) in zs.iter().enumerate().take(k1 + 1).skip(k0) {
        let dz = z - c.z;
        if dz * dz >= r2 {
            continue;
        }
        let oz = z - t.z;
        let from_z = [m[(0, 2)] * oz, m[(1, 2)] * oz, m[(2, 2)] * oz];
        for (j, y) in ys.iter().enumerate().take(j1 + 1).skip(j0) {
            let dy = y - c.y;
            if dy * dy + dz * dz >= r2 {
                continue;
            }
            let oy = y - t.y;
            let from_y = [m[(0, 1)] * oy, m[(1, 1)] * oy, m[(2, 1)] * oy];
            let row = (k * ny + j) * nx;
            for (v, x) in values[row + i0..=row + i1].iter_mut().zip(&xs[i0..=i1]) {
                let ox = x - t.x;
                let local = |a: usize| (m[(a, 0)] * ox + from_y[a]) + from_z[a];
                *v += w * kernel_row(d2(local(0), local(1), local(2)) * inv);
            }
            evaluations += i1 + 1 - i0;
        }
    }
    evaluations
}

/// [`value_sq`] written without a branch, so the splat's row loops
/// vectorize: the same operations, so the same bits, for every `s` but
/// NaN.
#[inline(always)]
fn kernel_row(s: Real) -> Real {
    let f = 1.0 + s * (-22.0 / 9.0 + s * (17.0 / 9.0 - s * (4.0 / 9.0)));
    if s < 1.0 {
        f
    } else {
        0.0
    }
}

/// Samples block `b` of any field at every node (no band: the field's
/// primitives are unknown).
pub(super) fn sample_dense<F: ScalarField + ?Sized>(field: &F, grid: &Grid, b: usize) -> Sampled {
    let block = grid.block(b);
    let [nx, ny, nz] = block.nodes();
    let mut values = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let [a, bb, c] = block.start;
                values.push(field.value(&grid.node(a + i, bb + j, c + k)));
            }
        }
    }
    let n = values.len();
    Sampled::Values(values, n)
}
