//! Fixed blocks, ordered merge: how the pairs' contributions are summed
//! per particle (see the module docs of [`crate::forces`]; docs/model.md
//! §2). Particles are cut into [`Blocks`] of consecutive slots; each block
//! evaluates its rows in parallel into its own accumulators and a spill
//! for pairs reaching later blocks ([`accumulate`]), and a second pass adds
//! each block's incoming spills in ascending source order
//! ([`add_spills`]), so every sum is added in one order fixed by the
//! particle count alone. Also the pair results ([`PairOut`]) and pair
//! sources ([`PairSource`]) the kernels hand to the accumulation.

use rayon::prelude::*;

use crate::math::{Real, Vec3};
use crate::neighbours::NeighbourList;

/// Most particles per accumulation block (see the module docs and
/// [`Blocks`]).
pub(crate) const BLOCK: usize = 2048;

/// Fewest particles cut into two blocks: smaller worlds are one block (a
/// serial scatter's order), worlds of `SPLIT_MIN..=BLOCK` particles two.
///
/// Measured (release `opsim run --profile`, 2 cores, interleaved runs):
/// worlds of 400 particles and more gain at 2 threads and lose nothing at
/// one thread. Wall seconds at 2 threads, two blocks against one: `drape_sphere`
/// (400) 1.56-1.63 against 1.71-1.93; `cookbook/cloth_on_box` (576)
/// 7.86-8.24 against 9.68-11.57; `torus_shell` (679) 2.59-2.60 against
/// 3.38-3.70; `fig_10_interpolation` (up to 1,627) 3.05-3.25 against
/// 4.12-4.57. Smaller worlds gain nothing, the fork-join of a pass
/// costing what half its pairs save (`sphere_shell`, 363;
/// `fig_12_plastic`, 232; `cookbook/sheet_tear`, 155; `fig_08_crease`,
/// 90).
pub(crate) const SPLIT_MIN: usize = 384;

/// How `n` particles are cut into accumulation blocks: one block when
/// `n < SPLIT_MIN` (a serial scatter's order), two equal blocks up to
/// `BLOCK`, else `ceil(n / BLOCK)` rounded up to an even count of equal
/// blocks (the last one shorter by the remainder). The order of every sum
/// depends on `n` only, never on the thread count.
///
/// Equal halves for two threads: blocks are the units the pool's threads
/// share, so with `ceil(n / BLOCK)` full blocks one thread could be left
/// with a whole block more than the other: the 32,000-particle block of
/// the performance report was 15 full blocks and one of 1,280 particles,
/// one thread's half 16,384 particles' rows and the other's 15,616, the
/// pass waiting on the first; 16 blocks of 2,000 give 16,000 each.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Blocks {
    /// Particles per block (at least 2).
    pub size: usize,
    /// Number of blocks.
    pub count: usize,
    /// `ceil(2^64 / size)`: the block of a slot by a multiplication
    /// ([`Blocks::of`]).
    magic: u64,
}

impl Blocks {
    /// The blocks of `n` particles.
    pub(crate) fn new(n: usize) -> Self {
        let count = match n.div_ceil(BLOCK).max(2) {
            _ if n < SPLIT_MIN => 1,
            count => count + count % 2,
        };
        // At least 2: `magic` is then below 2^64.
        let size = n.div_ceil(count).max(2);
        Blocks {
            size,
            count: n.div_ceil(size),
            magic: u64::MAX / size as u64 + 1,
        }
    }

    /// The block of slot `j`, `j / size`, as `(magic * j) >> 64`: exact for
    /// every 32-bit `j` (Lemire, Kaser & Kurz 2019, "Faster remainder by
    /// direct computation", Theorem 1 with N = 32, F = 64), without the
    /// division per spilled pair.
    #[inline(always)]
    pub(crate) fn of(&self, j: u32) -> usize {
        ((u128::from(self.magic) * u128::from(j)) >> 64) as usize
    }
}

/// Result of one pair in the oriented kernel.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct OrientedPair {
    pub(super) force_j: Vec3,
    pub(super) torque_i: Vec3,
    pub(super) torque_j: Vec3,
    pub(super) energy: Real,
}

/// One block's accumulators (see the module docs).
#[derive(Default)]
pub(super) struct BlockScratch {
    /// Incoming force and torque of each particle of the block from the
    /// block's own rows (torques only for kernels with torques: the
    /// spacing kernel's accumulator stays half as large in cache).
    local_f: Vec<Vec3>,
    local_t: Vec<Vec3>,
    /// Contributions to particles of later blocks, in visiting order, then
    /// stably sorted by target block: target slots and forces (and torques,
    /// oriented kernel only).
    spill_targets: Vec<u32>,
    spill_forces: Vec<Vec3>,
    spill_torques: Vec<Vec3>,
    /// The spill's entries in use (its first `spill_len`). The spill's
    /// vectors only grow, their tails being scratch, so a row's pairs are
    /// written without first zeroing their slots ([`spill_row`]).
    spill_len: usize,
    /// Visiting order of the spill, grouped by target block.
    order: Vec<u32>,
    /// Start of each later block's group in `order` (block `b + 1 + g`
    /// at `starts[g]`), and a cursor per group while sorting.
    starts: Vec<u32>,
    cursor: Vec<u32>,
}

/// The per-particle sums a force evaluation fills.
pub(super) struct Sums<'a> {
    pub(super) forces: &'a mut [Vec3],
    pub(super) torques: &'a mut [Vec3],
    pub(super) energies: &'a mut [Real],
}

/// One pair's contribution: the force on `j` (the force on `i` is its
/// negative), the torques on `i` and `j`, the pair energy.
pub(super) trait PairOut: Copy + Default + Send + Sync {
    fn force_j(&self) -> Vec3;
    fn torque_i(&self) -> Vec3;
    fn torque_j(&self) -> Vec3;
    fn energy(&self) -> Real;
}

/// Result slot of one pair in the spacing kernel.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct SpacingPair {
    pub(super) force_j: Vec3,
    pub(super) energy: Real,
}

impl PairOut for SpacingPair {
    #[inline]
    fn force_j(&self) -> Vec3 {
        self.force_j
    }
    #[inline]
    fn torque_i(&self) -> Vec3 {
        Vec3::zeros()
    }
    #[inline]
    fn torque_j(&self) -> Vec3 {
        Vec3::zeros()
    }
    #[inline]
    fn energy(&self) -> Real {
        self.energy
    }
}

impl PairOut for OrientedPair {
    #[inline]
    fn force_j(&self) -> Vec3 {
        self.force_j
    }
    #[inline]
    fn torque_i(&self) -> Vec3 {
        self.torque_i
    }
    #[inline]
    fn torque_j(&self) -> Vec3 {
        self.torque_j
    }
    #[inline]
    fn energy(&self) -> Real {
        self.energy
    }
}

/// A pair kernel as the accumulation sees it: `prepare` may evaluate a
/// whole row at once (the SIMD lanes, [`crate::lanes`]) into the block's
/// row scratch, then `pair` gives the result of the `k`-th pair `(i, j)` of
/// the row, `None` when it contributes nothing.
///
/// `DENSE` sources also give every in-block pair a result through
/// `pair_or_zero`: an exact zero (`+0.0` everywhere) for pairs that
/// contribute nothing. Adding it leaves every sum's bits as skipping the
/// pair would (the sums start at `+0.0` and, being sums, never become
/// `-0.0`), without the unpredictable branch on the cut-off.
pub(super) trait PairSource: Sync {
    type Out: PairOut;
    type Row: Default + Send;
    const DENSE: bool = false;
    fn prepare(&self, i: usize, row: &[u32], scratch: &mut Self::Row);
    fn pair(&self, i: usize, j: usize, k: usize, scratch: &Self::Row) -> Option<Self::Out>;
    #[inline(always)]
    fn pair_or_zero(&self, i: usize, j: usize, k: usize, scratch: &Self::Row) -> Self::Out {
        self.pair(i, j, k, scratch).unwrap_or_default()
    }
    /// [`Self::pair`] as a result and whether the pair contributes: `(+0
    /// everywhere, false)` for `None`. `DENSE` sources override it without
    /// a branch, so the spill ([`spill_row`]) writes every pair and keeps
    /// those that contribute.
    #[inline(always)]
    fn pair_kept(&self, i: usize, j: usize, k: usize, scratch: &Self::Row) -> (Self::Out, bool) {
        match self.pair(i, j, k, scratch) {
            Some(o) => (o, true),
            None => (Self::Out::default(), false),
        }
    }
    /// The pairs of row `i` whose second particle lies in the block
    /// starting at `b0` (`row`: the row's in-block prefix), in row order:
    /// each pair's force is subtracted from the row's running sums, which
    /// are returned `(force, torque, energy)` (starting from zero), and
    /// added to the second particle's slot of `local_f` (and `local_t`)
    /// (see [`accumulate`]). Sources whose row scratch is a set of flat
    /// arrays override it with the same additions in the same order over
    /// slices (no bounds check per pair, the sums kept in registers).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn in_block<const TORQUES: bool>(
        &self,
        i: usize,
        row: &[u32],
        b0: usize,
        scratch: &Self::Row,
        local_f: &mut [Vec3],
        local_t: &mut [Vec3],
    ) -> (Vec3, Vec3, Real) {
        let (mut fo, mut to, mut eo) = (Vec3::zeros(), Vec3::zeros(), 0.0);
        for (k, &j) in row.iter().enumerate() {
            let j = j as usize;
            let o = if Self::DENSE {
                self.pair_or_zero(i, j, k, scratch)
            } else {
                let Some(o) = self.pair(i, j, k, scratch) else {
                    continue;
                };
                o
            };
            let fj = o.force_j();
            fo -= fj;
            eo += o.energy();
            local_f[j - b0] += fj;
            if TORQUES {
                to += o.torque_i();
                local_t[j - b0] += o.torque_j();
            }
        }
        (fo, to, eo)
    }
}

/// A pair kernel evaluated one pair at a time.
pub(super) struct Scalar<F>(pub(super) F);

impl<O: PairOut, F: Fn(usize, usize) -> Option<O> + Sync> PairSource for Scalar<F> {
    type Out = O;
    type Row = ();
    #[inline(always)]
    fn prepare(&self, _: usize, _: &[u32], _: &mut ()) {}
    #[inline(always)]
    fn pair(&self, i: usize, j: usize, _: usize, _: &()) -> Option<O> {
        (self.0)(i, j)
    }
}

/// Evaluates every listed pair once and sums the contributions per
/// particle, block by block (see the module docs). `TORQUES` is false for
/// kernels without torques.
pub(super) fn accumulate<const TORQUES: bool, P: PairSource>(
    list: &NeighbourList,
    blocks: &mut Vec<BlockScratch>,
    src: P,
    out: Sums<'_>,
) {
    let pairs = list.pairs();
    let nbrs = pairs.neighbours();
    let Sums {
        forces,
        torques,
        energies,
    } = out;
    let n = forces.len();
    let cut = Blocks::new(n);
    let (size, nblocks) = (cut.size, cut.count);
    if blocks.len() < nblocks {
        blocks.resize_with(nblocks, BlockScratch::default);
    }
    let blocks = &mut blocks[..nblocks];
    // Pass 1: every block's rows; own-row and in-block sums, spills.
    let work =
        |b: usize, block: &mut BlockScratch, f: &mut [Vec3], t: &mut [Vec3], e: &mut [Real]| {
            let b0 = b * size;
            let b1 = b0 + f.len();
            block.local_f.clear();
            block.local_f.resize(f.len(), Vec3::zeros());
            block.local_t.clear();
            if TORQUES {
                block.local_t.resize(f.len(), Vec3::zeros());
            }
            block.spill_len = 0;
            let mut scratch = P::Row::default();
            for i in b0..b1 {
                // The row is sorted: targets in this block, then later ones.
                let row = &nbrs[pairs.row_range(i)];
                src.prepare(i, row, &mut scratch);
                let split = row.partition_point(|&j| (j as usize) < b1);
                let (mut fo, mut to, mut eo) = src.in_block::<TORQUES>(
                    i,
                    &row[..split],
                    b0,
                    &scratch,
                    &mut block.local_f,
                    &mut block.local_t,
                );
                (fo, to, eo) =
                    spill_row::<TORQUES, P>(&src, i, row, split, &scratch, block, (fo, to, eo));
                f[i - b0] = block.local_f[i - b0] + fo;
                t[i - b0] = if TORQUES {
                    block.local_t[i - b0] + to
                } else {
                    Vec3::zeros()
                };
                e[i - b0] = eo;
            }
            block.group_spills(b, &cut);
        };
    blocks
        .par_iter_mut()
        .zip(forces.par_chunks_mut(size))
        .zip(torques.par_chunks_mut(size))
        .zip(energies.par_chunks_mut(size))
        .enumerate()
        .for_each(|(b, (((block, f), t), e))| work(b, block, f, t, e));
    // Pass 2: each block adds the spills aimed at it, earlier blocks first.
    add_spills::<TORQUES>(blocks, size, forces, torques);
}

/// The pairs of row `i` from `split` on (second particles in later
/// blocks), in row order: each pair's force is subtracted from the row's
/// running `sums` `(force, torque, energy)`, which are returned, and the
/// pair is pushed to the block's spill (see [`accumulate`]).
///
/// Branch-free: every pair is written at the spill's end and the length
/// advances only for pairs that contribute ([`PairSource::pair_kept`]; a
/// branch on the cut-off mispredicts for the ~30% of listed pairs beyond
/// it). A pair that contributes nothing is `+0` everywhere, so adding it
/// to the running sums leaves their bits as skipping it would (see
/// [`PairSource`]). Not inlined: inlined into the block loop, the running
/// sums lived in stack slots, a store-to-load chain per pair.
#[inline(never)]
fn spill_row<const TORQUES: bool, P: PairSource>(
    src: &P,
    i: usize,
    row: &[u32],
    split: usize,
    scratch: &P::Row,
    block: &mut BlockScratch,
    sums: (Vec3, Vec3, Real),
) -> (Vec3, Vec3, Real) {
    let (mut fo, mut to, mut eo) = sums;
    let mut len = block.spill_len;
    let end = len + (row.len() - split);
    let grown = |have: usize| end.max(2 * have);
    if block.spill_targets.len() < end {
        let m = grown(block.spill_targets.len());
        block.spill_targets.resize(m, 0);
        block.spill_forces.resize(m, Vec3::zeros());
    }
    if TORQUES && block.spill_torques.len() < end {
        let m = grown(block.spill_torques.len());
        block.spill_torques.resize(m, Vec3::zeros());
    }
    let targets = &mut block.spill_targets[..end];
    let forces = &mut block.spill_forces[..end];
    for (k, &j) in row.iter().enumerate().skip(split) {
        let (o, kept) = src.pair_kept(i, j as usize, k, scratch);
        let fj = o.force_j();
        fo -= fj;
        eo += o.energy();
        targets[len] = j;
        forces[len] = fj;
        if TORQUES {
            to += o.torque_i();
            block.spill_torques[len] = o.torque_j();
        }
        len += usize::from(kept);
    }
    block.spill_len = len;
    (fo, to, eo)
}

/// Pass 2 of [`accumulate`]: each block (of `size` particles) of `forces`
/// and `torques` adds the spills aimed at it, from the earlier blocks in
/// ascending order.
fn add_spills<const TORQUES: bool>(
    blocks: &[BlockScratch],
    size: usize,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
) {
    forces
        .par_chunks_mut(size)
        .zip(torques.par_chunks_mut(size))
        .enumerate()
        .for_each(|(target, (f, t))| {
            let t0 = target * size;
            for (b, src) in blocks[..target].iter().enumerate() {
                let g = target - (b + 1);
                let range = src.starts[g] as usize..src.starts[g + 1] as usize;
                for &k in &src.order[range] {
                    let k = k as usize;
                    let j = src.spill_targets[k] as usize - t0;
                    f[j] += src.spill_forces[k];
                    if TORQUES {
                        t[j] += src.spill_torques[k];
                    }
                }
            }
        });
}

impl BlockScratch {
    /// Groups block `b`'s spill by target block (of `cut`), keeping the
    /// visiting order within each group: a counting sort of the visiting
    /// indices into `order`, with each group's range in `starts`.
    fn group_spills(&mut self, b: usize, cut: &Blocks) {
        let first = b + 1;
        self.starts.clear();
        self.starts.resize(cut.count - first + 1, 0);
        let spill = &self.spill_targets[..self.spill_len];
        for &j in spill {
            self.starts[cut.of(j) - first + 1] += 1;
        }
        for g in 1..self.starts.len() {
            self.starts[g] += self.starts[g - 1];
        }
        self.order.clear();
        self.order.resize(spill.len(), 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.starts);
        for (k, &j) in spill.iter().enumerate() {
            let c = &mut self.cursor[cut.of(j) - first];
            self.order[*c as usize] = k as u32;
            *c += 1;
        }
    }
}

#[cfg(test)]
mod block_tests {
    use super::*;

    /// One block below `SPLIT_MIN` particles; from there, an even count
    /// of equal blocks of at most `BLOCK` covering every slot (two up to
    /// `2 BLOCK`); the block of a slot
    /// by multiplication equals the division, for every slot of those
    /// sizes and at the top of the 32-bit range.
    #[test]
    fn blocks_are_even_equal_and_found_by_multiplication() {
        for n in [
            0,
            1,
            2,
            3,
            SPLIT_MIN - 1,
            SPLIT_MIN,
            SPLIT_MIN + 1,
            BLOCK - 1,
            BLOCK,
            BLOCK + 1,
            3 * BLOCK,
            32_000,
            97_556,
        ] {
            let cut = Blocks::new(n);
            assert!(cut.size >= 2 && cut.size <= BLOCK.max(2), "{n}: {cut:?}");
            assert!(cut.count * cut.size >= n && (cut.count.max(1) - 1) * cut.size < n.max(1));
            if n >= SPLIT_MIN {
                assert_eq!(cut.count % 2, 0, "{n}: {cut:?}");
                assert_eq!(cut.count == 2, n <= 2 * BLOCK, "{n}: {cut:?}");
            } else {
                assert!(cut.count <= 1);
            }
            for j in 0..n as u32 {
                assert_eq!(cut.of(j), j as usize / cut.size);
            }
        }
        assert_eq!(Blocks::new(32_000).size, 2000);
        for size in [2, 3, 1000, 2000, 2047, 2048] {
            let cut = Blocks {
                size,
                count: 0,
                magic: u64::MAX / size as u64 + 1,
            };
            for j in (u32::MAX - 5000..=u32::MAX).chain(0..5000) {
                assert_eq!(cut.of(j), j as usize / size, "size {size} slot {j}");
            }
        }
    }
}
