//! Flat (CSR) half neighbour lists with a transposed "incoming" index.
//!
//! The fast backends fill a [`PairList`] through one parallel machinery
//! (`build_parallel`), the all-pairs oracle through a separate serial path
//! (`build_serial`). All decide pairs with the same test ([`dist2`]) and
//! sort their rows, so the lists are canonical: for given positions and
//! radius every backend produces the same arrays, bit for bit, at any
//! thread count.

use std::ops::Range;

use rayon::prelude::*;

use super::{cell_list::GridScratch, kd_tree::KdScratch};
use crate::math::{Point3, Real};

/// Particles per block of the parallel fill. Blocks are the unit of work
/// and of scratch storage; the output does not depend on how rayon
/// schedules them.
pub(crate) const BLOCK: usize = 256;

/// Squared distance between `a` and `b`, computed as
/// `dx*dx + dy*dy + dz*dz` with `d = b - a` (no fused multiply-add). It is
/// symmetric in its arguments bit for bit, which makes the pair test
/// symmetric too. Every backend decides "is a pair" with this one formula.
#[inline(always)]
pub(crate) fn dist2(a: &[Real; 3], b: &[Real; 3]) -> Real {
    let dx = b[0] - a[0];
    let dy = b[1] - a[1];
    let dz = b[2] - a[2];
    dx * dx + dy * dy + dz * dz
}

/// A point as a plain array.
#[inline(always)]
pub(crate) fn arr(p: &Point3) -> [Real; 3] {
    [p.x, p.y, p.z]
}

/// True when every coordinate of `p` is finite.
#[inline(always)]
pub(crate) fn is_finite(p: &Point3) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.z.is_finite()
}

/// The squared search radius, or `None` when `radius` is NaN or negative
/// (such a search finds no pairs).
pub(crate) fn squared_radius(radius: Real) -> Option<Real> {
    (radius >= 0.0).then_some(radius * radius)
}

/// The scratch storage of one block of the parallel fill.
#[derive(Default)]
struct Block {
    /// The row being built.
    row: Vec<u32>,
    /// The block's half rows, concatenated.
    upper: Vec<u32>,
}

/// Reusable scratch buffers of the searches, kept in the [`PairList`] so
/// that rebuilding with stable sizes allocates nothing (except the k-d
/// tree, which kiddo allocates).
#[derive(Default)]
pub(crate) struct Scratch {
    blocks: Vec<Block>,
    /// Fill cursors of the parallel transpose (one per particle).
    cursor: Vec<u32>,
    pub(crate) grid: GridScratch,
    pub(crate) kd: KdScratch,
}

/// A flat (CSR) **half** neighbour list over `len()` particles.
///
/// Pair `k` is `(i, j)` with `i < j` and `|p_j - p_i| <= radius`
/// (inclusive), stored in row `i`. Rows are sorted ascending, so the list is
/// canonical: every backend and thread count gives identical arrays. Pair
/// indices `k` run over the flat array of all rows, row 0 first, so they are
/// ordered by `(i, j)`.
///
/// The transposed **incoming** index lists, for each particle `j`, the pair
/// indices `k` whose second particle is `j`, ascending (hence ordered by
/// their first particle `i`). With both, a parallel loop over particles can
/// gather the contributions of every pair touching a particle in a fixed
/// order, without atomics: deterministic reductions. It is built on
/// request ([`PairList::build_incoming`]; [`super::search`] and
/// [`super::all_pairs`] always build it), since the force evaluation does
/// not read it: a [`super::NeighbourList`] rebuilds only its rows, and the
/// stages that gather (heat, plasticity) ask for the index. Measured on
/// the 32,000-particle Lennard-Jones block of LAMMPS' `in.lj`: the
/// transpose was about a fifth of a rebuild and 3% of the spacing step's
/// CPU time.
///
/// Particles with a non-finite coordinate (NaN or infinite) have no
/// neighbours: the pair test `dx*dx + dy*dy + dz*dz <= radius^2` is false
/// for them.
///
/// The list also keeps the scratch buffers of the searches, so rebuilding a
/// list of stable size does not reallocate. `Clone` copies the lists only.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct PairList {
    /// `offsets[i]..offsets[i + 1]` is the pair range of row `i` (`n + 1` entries).
    offsets: Vec<u32>,
    /// Second particle `j` of every pair, row by row.
    neighbours: Vec<u32>,
    /// `in_offsets[j]..in_offsets[j + 1]` is the range of `incoming` for `j`.
    in_offsets: Vec<u32>,
    /// Pair indices grouped by their second particle.
    incoming: Vec<u32>,
    /// `in_offsets` and `incoming` describe the current rows.
    has_incoming: bool,
    #[serde(skip)]
    pub(crate) scratch: Scratch,
}

impl Default for PairList {
    fn default() -> Self {
        Self::new()
    }
}

impl Clone for PairList {
    fn clone(&self) -> Self {
        Self {
            offsets: self.offsets.clone(),
            neighbours: self.neighbours.clone(),
            in_offsets: self.in_offsets.clone(),
            incoming: self.incoming.clone(),
            has_incoming: self.has_incoming,
            scratch: Scratch::default(),
        }
    }
}

impl PartialEq for PairList {
    /// Equal lists: same rows, and the same incoming index when both
    /// have built it (it is a function of the rows; scratch ignored).
    fn eq(&self, other: &Self) -> bool {
        self.offsets == other.offsets
            && self.neighbours == other.neighbours
            && (!(self.has_incoming && other.has_incoming)
                || (self.in_offsets == other.in_offsets && self.incoming == other.incoming))
    }
}

impl Eq for PairList {}

impl std::fmt::Debug for PairList {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PairList")
            .field("len", &self.len())
            .field("num_pairs", &self.num_pairs())
            .field("offsets", &self.offsets)
            .field("neighbours", &self.neighbours)
            .field("in_offsets", &self.in_offsets)
            .field("incoming", &self.incoming)
            .field("has_incoming", &self.has_incoming)
            .finish()
    }
}

impl PairList {
    /// An empty list over zero particles.
    pub fn new() -> Self {
        Self {
            offsets: vec![0],
            neighbours: Vec::new(),
            in_offsets: vec![0],
            incoming: Vec::new(),
            has_incoming: true,
            scratch: Scratch::default(),
        }
    }

    /// Whether the list is well formed over `n` rows: offsets that start
    /// at 0, never decrease and end at the pair count, second particles
    /// below `n`, and the same of the incoming index when it is built (a
    /// list read back from a checkpoint is checked before use).
    pub(crate) fn is_consistent(&self, n: usize) -> bool {
        fn index_ok(offsets: &[u32], entries: &[u32], rows: usize, bound: usize) -> bool {
            offsets.len() == rows + 1
                && offsets.first() == Some(&0)
                && offsets.windows(2).all(|w| w[0] <= w[1])
                && offsets.last().map(|&o| o as usize) == Some(entries.len())
                && entries.iter().all(|&e| (e as usize) < bound)
        }
        index_ok(&self.offsets, &self.neighbours, n, n)
            && (!self.has_incoming
                || index_ok(&self.in_offsets, &self.incoming, n, self.neighbours.len()))
    }

    /// Number of particles (rows).
    #[inline]
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True when the list covers no particle.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of pairs (each unordered pair counted once).
    #[inline]
    pub fn num_pairs(&self) -> usize {
        self.neighbours.len()
    }

    /// The neighbours `j > i` of particle `i`, ascending.
    ///
    /// # Panics
    /// If `i >= len()`.
    #[inline]
    pub fn row(&self, i: usize) -> &[u32] {
        &self.neighbours[self.row_range(i)]
    }

    /// The pair indices of row `i`: `row(i)[m]` is the second particle of
    /// pair `row_range(i).start + m`.
    ///
    /// # Panics
    /// If `i >= len()`.
    #[inline]
    pub fn row_range(&self, i: usize) -> Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// The pair indices `k` with `pair_target(k) == j`, ascending (so
    /// ordered by their first particle `i < j`).
    ///
    /// # Panics
    /// If `j >= len()`, or if the incoming index of the current rows is not
    /// built ([`PairList::build_incoming`]; lists from [`super::search`]
    /// have it).
    #[inline]
    pub fn incoming(&self, j: usize) -> &[u32] {
        assert!(
            self.has_incoming,
            "PairList::incoming: the incoming index is not built (call build_incoming)"
        );
        &self.incoming[self.in_offsets[j] as usize..self.in_offsets[j + 1] as usize]
    }

    /// The first particle `i` of pair `k` (binary search over the row
    /// offsets: `O(log len)`; iterate rows when visiting every pair).
    ///
    /// # Panics
    /// If `k >= num_pairs()`.
    #[inline]
    pub fn pair_source(&self, k: usize) -> usize {
        assert!(k < self.num_pairs(), "pair index {k} out of range");
        self.offsets.partition_point(|&o| o as usize <= k) - 1
    }

    /// The second particle `j` of pair `k`.
    ///
    /// # Panics
    /// If `k >= num_pairs()`.
    #[inline]
    pub fn pair_target(&self, k: usize) -> usize {
        self.neighbours[k] as usize
    }

    /// The flat array of second particles, row after row (`num_pairs()` entries).
    #[inline]
    pub fn neighbours(&self) -> &[u32] {
        &self.neighbours
    }

    /// The row offsets (`len() + 1` entries): row `i` is
    /// `neighbours()[offsets()[i]..offsets()[i + 1]]`.
    #[inline]
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// Iterates over all pairs `(i, j)` in pair-index order.
    pub fn iter_pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.len()).flat_map(move |i| self.row(i).iter().map(move |&j| (i, j as usize)))
    }

    /// Fills `out` with the first particle of every pair, in pair-index
    /// order (the table [`PairList::pair_source`] searches, built in one
    /// pass for loops over all pairs).
    pub fn sources_into(&self, out: &mut Vec<u32>) {
        out.clear();
        for i in 0..self.len() {
            out.extend(std::iter::repeat_n(i as u32, self.row_range(i).len()));
        }
    }

    /// The full neighbour rows of this half list: for each particle, every
    /// neighbour in either direction, ascending.
    ///
    /// With the incoming index ([`PairList::build_incoming`]; lists from
    /// [`super::search`] have it) each row is built on its own, in
    /// parallel: the first particles of its incoming pairs (ascending,
    /// below it) then its own row (ascending, above it).
    pub fn full_rows(&self) -> Vec<Vec<u32>> {
        if !self.has_incoming {
            return self.full_rows_serial();
        }
        let mut sources = Vec::new();
        self.sources_into(&mut sources);
        (0..self.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| {
                let (incoming, row) = (self.incoming(i), self.row(i));
                let mut full = Vec::with_capacity(incoming.len() + row.len());
                full.extend(incoming.iter().map(|&k| sources[k as usize]));
                full.extend_from_slice(row);
                full
            })
            .collect()
    }

    /// [`PairList::full_rows`] without the incoming index: every pair
    /// pushed to both rows, each row sorted.
    fn full_rows_serial(&self) -> Vec<Vec<u32>> {
        let mut rows = vec![Vec::new(); self.len()];
        for (i, j) in self.iter_pairs() {
            rows[i].push(j as u32);
            rows[j].push(i as u32);
        }
        rows.iter_mut().for_each(|r| r.sort_unstable());
        rows
    }

    /// Makes this a list of `n` particles with no pairs.
    pub(crate) fn set_empty(&mut self, n: usize) {
        check_particle_count(n);
        self.offsets.clear();
        self.offsets.resize(n + 1, 0);
        self.in_offsets.clear();
        self.in_offsets.resize(n + 1, 0);
        self.neighbours.clear();
        self.incoming.clear();
        self.has_incoming = true;
    }

    /// Whether the incoming index of the current rows is built.
    pub fn has_incoming(&self) -> bool {
        self.has_incoming
    }

    /// Builds the incoming index of the current rows if it is not built
    /// (a parallel transpose, the same at any thread count).
    pub fn build_incoming(&mut self) {
        if !self.has_incoming {
            self.transpose_parallel();
            self.has_incoming = true;
        }
    }

    /// Serial build from half rows: `half_row(i, out)` appends the
    /// neighbours `j > i` of `i` in ascending order. The incoming index is
    /// then built by a serial transpose. Used by the all-pairs oracle, so
    /// it shares no code path with the parallel fill it checks.
    pub(crate) fn build_serial<F>(&mut self, n: usize, mut half_row: F)
    where
        F: FnMut(usize, &mut Vec<u32>),
    {
        check_particle_count(n);
        self.offsets.clear();
        self.offsets.push(0);
        self.neighbours.clear();
        for i in 0..n {
            half_row(i, &mut self.neighbours);
            self.offsets.push(to_u32_pairs(self.neighbours.len()));
        }
        self.transpose_serial();
        self.has_incoming = true;
    }

    /// Rebuilds `in_offsets` and `incoming` from the rows, serially.
    fn transpose_serial(&mut self) {
        let n = self.len();
        self.in_offsets.clear();
        self.in_offsets.resize(n + 1, 0);
        for &j in &self.neighbours {
            self.in_offsets[j as usize + 1] += 1;
        }
        for j in 0..n {
            self.in_offsets[j + 1] += self.in_offsets[j];
        }
        self.incoming.clear();
        self.incoming.resize(self.neighbours.len(), 0);
        let mut cursor = self.in_offsets[..n].to_vec();
        for i in 0..n {
            for k in self.row_range(i) {
                let j = self.neighbours[k] as usize;
                self.incoming[cursor[j] as usize] = k as u32;
                cursor[j] += 1;
            }
        }
    }

    /// Parallel build: `row(i, out)` appends neighbours of `i` in any
    /// order, without duplicates; entries `j <= i` are ignored, so a backend
    /// may push whole neighbourhoods or only the half it keeps.
    ///
    /// Pass 1 fills blocks of [`BLOCK`] particles in parallel (each row
    /// filtered to `j > i` and sorted) and records the row lengths; after a
    /// prefix sum the blocks are copied into place. The incoming index is
    /// left unbuilt ([`PairList::build_incoming`]: a parallel transpose
    /// over ranges of target particles). The result depends only on the
    /// rows: the same for any thread count.
    pub(crate) fn build_parallel<F>(&mut self, n: usize, row: F)
    where
        F: Fn(usize, &mut Vec<u32>) + Sync,
    {
        check_particle_count(n);
        let nblocks = n.div_ceil(BLOCK);
        if self.scratch.blocks.len() < nblocks {
            self.scratch.blocks.resize_with(nblocks, Block::default);
        }
        let blocks = &mut self.scratch.blocks[..nblocks];
        self.offsets.resize(n + 1, 0);
        self.offsets[0] = 0;

        // Pass 1: half rows per block, sorted; row lengths in place.
        blocks
            .par_iter_mut()
            .zip(self.offsets[1..].par_chunks_mut(BLOCK))
            .enumerate()
            .for_each(|(b, (block, counts))| {
                block.upper.clear();
                for (m, count) in counts.iter_mut().enumerate() {
                    let i = b * BLOCK + m;
                    block.row.clear();
                    row(i, &mut block.row);
                    block.row.retain(|&j| j as usize > i);
                    block.row.sort_unstable();
                    block.upper.extend_from_slice(&block.row);
                    *count = block.row.len() as u32;
                }
            });
        let total = prefix_sum(&mut self.offsets);
        self.neighbours.resize(total, 0);
        let blocks = &self.scratch.blocks[..nblocks];
        copy_blocks(blocks, &self.offsets, 0, nblocks, &mut self.neighbours);
        self.has_incoming = false;
    }

    /// Rebuilds the incoming index from the rows, in parallel: the targets
    /// `0..n` are cut into ranges; the task of a range scans the rows that
    /// can reach it (`i` below the range end, last entry inside or above
    /// it), first to count, then (in order of `i`) to fill.
    fn transpose_parallel(&mut self) {
        let n = self.len();
        let tasks = (2 * rayon::current_num_threads()).clamp(1, n.div_ceil(BLOCK).max(1));
        let ctx = Transpose {
            offsets: &self.offsets,
            neighbours: &self.neighbours,
            n,
            tasks,
        };
        self.in_offsets.clear();
        self.in_offsets.resize(n + 1, 0);
        ctx.run(0, tasks, &mut self.in_offsets[1..], &mut [], true);
        prefix_sum(&mut self.in_offsets);
        self.incoming.resize(self.neighbours.len(), 0);
        self.scratch.cursor.clear();
        self.scratch.cursor.extend_from_slice(&self.in_offsets[..n]);
        let cursor = &mut self.scratch.cursor;
        // `run` needs the incoming base of each range: it reads the cursors'
        // first values, which are the ranges' `in_offsets`.
        ctx.run(0, tasks, cursor, &mut self.incoming, false);
    }
}

/// Copies the half rows of blocks `first..last` into `dst` (their part of
/// the neighbour array), splitting the work with `rayon::join`.
fn copy_blocks(blocks: &[Block], offsets: &[u32], first: usize, last: usize, dst: &mut [u32]) {
    match last - first {
        0 => {}
        1 => dst.copy_from_slice(&blocks[first].upper),
        len => {
            let mid = first + len / 2;
            let at = (offsets[mid * BLOCK] - offsets[first * BLOCK]) as usize;
            let (lo, hi) = dst.split_at_mut(at);
            rayon::join(
                || copy_blocks(blocks, offsets, first, mid, lo),
                || copy_blocks(blocks, offsets, mid, last, hi),
            );
        }
    }
}

/// The read-only side of the parallel transpose.
struct Transpose<'a> {
    offsets: &'a [u32],
    neighbours: &'a [u32],
    n: usize,
    tasks: usize,
}

impl Transpose<'_> {
    /// First target particle of range `t`.
    fn bound(&self, t: usize) -> usize {
        t * self.n / self.tasks
    }

    /// Runs ranges `first..last`. Counting (`count`): `per_target` holds the
    /// incoming counts of the targets of these ranges. Filling: it holds
    /// their cursors (initially their `in_offsets`) and `incoming` the part
    /// of the incoming array that starts at the first cursor.
    fn run(
        &self,
        first: usize,
        last: usize,
        per_target: &mut [u32],
        incoming: &mut [u32],
        count: bool,
    ) {
        if last - first > 1 {
            let mid = first + (last - first) / 2;
            let (pt_lo, pt_hi) = per_target.split_at_mut(self.bound(mid) - self.bound(first));
            let (inc_lo, inc_hi) = if count || pt_hi.is_empty() {
                incoming.split_at_mut(0)
            } else {
                let at = (pt_hi[0] - pt_lo.first().copied().unwrap_or(pt_hi[0])) as usize;
                incoming.split_at_mut(at)
            };
            rayon::join(
                || self.run(first, mid, pt_lo, inc_lo, count),
                || self.run(mid, last, pt_hi, inc_hi, count),
            );
            return;
        }
        let (lo, hi) = (self.bound(first), self.bound(last));
        let base = per_target.first().copied().unwrap_or(0);
        for i in 0..hi.min(self.n) {
            let (a, b) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
            // Rows are sorted: skip rows that end below the range.
            if a == b || (self.neighbours[b - 1] as usize) < lo {
                continue;
            }
            let row = &self.neighbours[a..b];
            // Most rows lie wholly inside one range: search only at the edges.
            let from = if row[0] as usize >= lo {
                0
            } else {
                row.partition_point(|&j| (j as usize) < lo)
            };
            let to = if (row[row.len() - 1] as usize) < hi {
                row.len()
            } else {
                from + row[from..].partition_point(|&j| (j as usize) < hi)
            };
            for (k, &j) in (a + from..).zip(&row[from..to]) {
                let slot = &mut per_target[j as usize - lo];
                if !count {
                    incoming[(*slot - base) as usize] = k as u32;
                }
                *slot += 1;
            }
        }
    }
}

/// In-place exclusive prefix sum of counts stored at `v[1..]` (with
/// `v[0] == 0`); returns the total.
///
/// # Panics
/// If the total does not fit the `u32` pair indices.
fn prefix_sum(v: &mut [u32]) -> usize {
    let mut acc: u64 = 0;
    for x in v.iter_mut() {
        acc += u64::from(*x);
        *x = to_u32_pairs(acc as usize);
    }
    acc as usize
}

fn to_u32_pairs(count: usize) -> u32 {
    u32::try_from(count).unwrap_or_else(|_| {
        panic!("neighbour list holds {count} pairs; pair indices are u32 (radius too large?)")
    })
}

fn check_particle_count(n: usize) {
    assert!(
        n < u32::MAX as usize,
        "neighbour lists index particles with u32; got {n} particles"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A list from explicit half rows, through the serial path.
    fn from_rows(rows: &[&[u32]]) -> PairList {
        let mut l = PairList::new();
        l.build_serial(rows.len(), |i, out| out.extend_from_slice(rows[i]));
        l
    }

    #[test]
    fn accessors_on_a_small_list() {
        let l = from_rows(&[&[1, 2], &[2], &[], &[]]);
        assert_eq!(l.len(), 4);
        assert_eq!(l.num_pairs(), 3);
        assert_eq!(l.row(0), &[1, 2]);
        assert_eq!(l.row_range(1), 2..3);
        assert_eq!(l.incoming(2), &[1, 2]);
        assert_eq!(l.incoming(0), &[] as &[u32]);
        assert_eq!(
            (0..3).map(|k| l.pair_source(k)).collect::<Vec<_>>(),
            [0, 0, 1]
        );
        assert_eq!(l.iter_pairs().collect::<Vec<_>>(), [(0, 1), (0, 2), (1, 2)]);
    }

    #[test]
    fn parallel_build_equals_serial_build() {
        // A symmetric relation on 1000 particles spanning several blocks:
        // i ~ j when |i - j| <= 3 or both are multiples of 97.
        let n = 1000usize;
        let rel = |i: usize, j: usize| {
            i != j && (i.abs_diff(j) <= 3 || (i.is_multiple_of(97) && j.is_multiple_of(97)))
        };
        let mut serial = PairList::new();
        serial.build_serial(n, |i, out| {
            out.extend((i + 1..n).filter(|&j| rel(i, j)).map(|j| j as u32))
        });
        let mut parallel = PairList::new();
        parallel.build_parallel(n, |i, out| {
            out.extend((0..n).rev().filter(|&j| rel(i, j)).map(|j| j as u32))
        });
        assert!(!parallel.has_incoming());
        assert_eq!(serial, parallel);
        parallel.build_incoming();
        assert_eq!(serial.in_offsets, parallel.in_offsets);
        assert_eq!(serial.incoming, parallel.incoming);
        // Rebuilding into the same list (reused buffers) gives the same list.
        parallel.build_parallel(n, |i, out| {
            out.extend((0..n).filter(|&j| rel(i, j)).map(|j| j as u32))
        });
        parallel.build_incoming();
        assert_eq!(serial.in_offsets, parallel.in_offsets);
        assert_eq!(serial.incoming, parallel.incoming);
        // Full rows from the incoming index equal every pair pushed both
        // ways and sorted; every neighbour by the relation, ascending.
        let full = parallel.full_rows();
        assert_eq!(full, parallel.full_rows_serial());
        for (i, row) in full.iter().enumerate() {
            let expected: Vec<u32> = (0..n).filter(|&j| rel(i, j)).map(|j| j as u32).collect();
            assert_eq!(row, &expected, "row {i}");
        }
    }

    #[test]
    fn rebuilding_with_stable_sizes_does_not_reallocate() {
        let n = 3000usize;
        let rows = |i: usize, out: &mut Vec<u32>| {
            out.extend((i.saturating_sub(5)..(i + 6).min(n)).map(|j| j as u32));
        };
        let mut l = PairList::new();
        l.build_parallel(n, rows);
        l.build_incoming();
        let ptrs = |l: &PairList| {
            [
                l.offsets.as_ptr() as usize,
                l.neighbours.as_ptr() as usize,
                l.in_offsets.as_ptr() as usize,
                l.incoming.as_ptr() as usize,
                l.scratch.cursor.as_ptr() as usize,
                l.scratch.blocks.as_ptr() as usize,
                l.scratch.blocks[3].upper.as_ptr() as usize,
            ]
        };
        let before = ptrs(&l);
        for _ in 0..3 {
            l.build_parallel(n, rows);
            l.build_incoming();
            assert_eq!(ptrs(&l), before);
        }
        assert_eq!(l.num_pairs(), (n - 5) * 5 + 4 + 3 + 2 + 1);
    }

    #[test]
    fn empty_and_tiny_lists() {
        let mut l = PairList::new();
        l.build_parallel(0, |_, _| {});
        assert_eq!(l, PairList::new());
        l.build_parallel(1, |_, _| {});
        assert_eq!((l.len(), l.num_pairs()), (1, 0));
        l.set_empty(5);
        assert_eq!((l.len(), l.num_pairs()), (5, 0));
        assert!(PairList::default().is_empty());
    }

    #[test]
    fn pair_test_is_inclusive_and_symmetric() {
        let a = [0.0, 0.0, 0.0];
        let b = [1.0, 0.0, 0.0];
        assert!(dist2(&a, &b) <= 1.0);
        let c = [0.1, -0.7, 0.3];
        let d = [-0.3, 0.2, 0.9];
        assert_eq!(dist2(&c, &d).to_bits(), dist2(&d, &c).to_bits());
        assert_eq!(squared_radius(-1.0), None);
        assert_eq!(squared_radius(Real::NAN), None);
        assert_eq!(squared_radius(0.0), Some(0.0));
    }
}
