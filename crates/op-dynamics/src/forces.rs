//! Internal force evaluation: every pair visited once, both `E_ij` and
//! `E_ji` evaluated there (docs/model.md §2), in parallel with results bitwise
//! identical at any thread count.
//!
//! The scheme is "fixed blocks, ordered merge": particles are cut
//! into blocks of consecutive slots (`Blocks`: an even number of equal
//! blocks of at most `BLOCK` (2048) particles, a function of the particle
//! count only, never of the thread count; the world keeps particles in
//! spatial order, so a block is a compact region). Each block, in parallel, visits the half-list rows
//! of its particles in order and evaluates every pair once: the pair's
//! share for its first particle goes into that particle's running sum, the
//! share for the second particle into the block's own accumulator when it
//! lies in the block, or into the block's *spill* (target slot and
//! contribution, in visiting order) when it lies in a later block. A second
//! parallel pass over blocks adds to each particle the spills aimed at it,
//! from the earlier blocks in ascending order. Every particle's sum is thus
//! added in one fixed order: its in-block incoming pairs (ascending source),
//! then its own row (list order), then its incoming pairs from earlier
//! blocks (ascending source). No locks, no atomics, no per-pair buffer: the
//! only memory beyond the sums is the spills (pairs crossing a block
//! boundary, a fraction of all pairs), the same at any thread count. A world
//! of at most one block adds exactly as a serial scatter would.
//!
//! Two kernels are compiled and one is chosen when the world is built
//! (pay for what you use): [`Kernel::Spacing`] touches positions only;
//! [`Kernel::Oriented`] evaluates the full oriented interaction. Each is
//! compiled for two bond lookups ([`crate::bonds`]): worlds without bonded
//! materials run the instance whose lookup is the constant `true` (the
//! code they ran before bonds existed, no per-pair bond work); worlds with
//! them look each complete pair up in the bond store. Worlds of one
//! spacing material run a loop per potential (`uniform_spacing`); with
//! 12-6 Lennard-Jones its pairs are evaluated in SIMD lanes dispatched at
//! run time ([`crate::lanes`]), which add up to the scalar loop's bits.
//! Oriented worlds of one such material (no heat, bonds, friction or spin)
//! evaluate the full oriented pair in lanes the same way
//! (`uniform_oriented`). Worlds with a bond memory
//! ([`crate::bond_memory`]) add it in one pass over the bonds after the
//! pairs.

use rayon::prelude::*;

use crate::bonds::Bonds;
use crate::contributors::{Contribution, Contributor, ContributorInput};
use crate::external::{ExternalAccumulator, ExternalParams, ForceWindows, UniformField};
use crate::flags::Flags;
use crate::integrators::StateRef;
use crate::interactions::{Coupling, PreparedMaterial};
use crate::math::{Real, Vec3};
use crate::neighbours::NeighbourList;
use crate::particles::Attributes;
use crate::tooling::ToolSet;

mod pair_kernels;
pub use pair_kernels::friction_force;
use pair_kernels::{frames, oriented_pair, spacing_pair};

/// Which pair kernel a world runs, fixed when the world is built.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// No interaction enabled: no neighbour list, no pair pass.
    None,
    /// Spacing forces (Lennard-Jones or cohesion) and the typing repulsion
    /// only: positions are the only per-pair data read.
    Spacing,
    /// The full oriented interaction (orientation terms, spin, friction).
    Oriented,
}

/// Most particles per accumulation block (see the module docs and
/// [`Blocks`]).
pub(crate) const BLOCK: usize = 2048;

/// How `n` particles are cut into accumulation blocks: one block when
/// `n <= BLOCK` (a serial scatter's order), else `ceil(n / BLOCK)` rounded
/// up to an even count of equal blocks (the last one shorter by the
/// remainder). The order of every sum depends on `n` only, never on the
/// thread count.
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
        let count = n.div_ceil(BLOCK);
        let count = if count > 1 { count + count % 2 } else { 1 };
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

mod uniform_spacing;
use uniform_spacing::uniform_spacing_pass;
mod uniform_oriented;
use uniform_oriented::uniform_oriented_pass;
#[cfg(test)]
mod pass_bits;

/// Result of one pair in the oriented kernel.
#[derive(Copy, Clone, Debug, Default)]
struct OrientedPair {
    force_j: Vec3,
    torque_i: Vec3,
    torque_j: Vec3,
    energy: Real,
}

/// One block's accumulators (see the module docs).
#[derive(Default)]
struct BlockScratch {
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

/// Scratch buffers of the force evaluation, owned by the world.
#[derive(Default)]
pub(crate) struct ForceScratch {
    blocks: Vec<BlockScratch>,
    normals: Vec<Vec3>,
    tangents: Vec<Vec3>,
    /// Potential energy attributed to each particle (its row's pairs).
    energies: Vec<Real>,
    /// Number of force evaluations since the world was built.
    pub evaluations: u64,
    /// Seconds spent updating neighbour lists (accumulated).
    pub neighbour_seconds: f64,
}

/// Everything the internal force evaluation reads besides the state.
pub(crate) struct ForceContext<'a> {
    pub kernel: Kernel,
    pub attributes: Attributes<'a>,
    pub materials: &'a [PreparedMaterial],
    pub friction: bool,
    /// Some material in use weakens with heat ([`crate::heat`]): complete
    /// pairs read the temperatures.
    pub heated: bool,
    /// Some material in use has a bond memory ([`crate::bond_memory`]).
    pub memory: bool,
    /// Some particle has a fixed position or orientation.
    pub has_fixed: bool,
    pub neighbours: Option<&'a mut NeighbourList>,
    /// The bond store (`None`: no particle has a bonded material).
    pub bonds: Option<&'a Bonds>,
    pub external: &'a ExternalParams,
    /// Start time of the world step being taken: force windows are
    /// evaluated from inside it
    /// ([`crate::external::ForceWindow::factor_within`]). `None` outside a
    /// step (plain [`crate::external::ForceWindow::factor`]).
    pub step_start: Option<Real>,
    pub accumulator: &'a ExternalAccumulator,
    /// The caller's contributors for this interval
    /// ([`crate::World::advance_to_with`]).
    pub extra: &'a [&'a dyn Contributor],
    /// Contributors callers registered with the world, before `extra`.
    pub registered: &'a [Box<dyn Contributor + Send>],
    /// The world's tools, asked first ([`crate::tooling`]).
    pub tools: Option<&'a dyn ToolSet>,
    pub scratch: &'a mut ForceScratch,
}

/// The force evaluation's configuration and scratch, owned by the world:
/// the chosen kernel, the prepared materials, the neighbour list.
pub(crate) struct ForceModel {
    pub kernel: Kernel,
    pub materials: Vec<PreparedMaterial>,
    pub friction: bool,
    /// Some material in use weakens with heat.
    pub heated: bool,
    /// Some material in use has a bond memory ([`crate::bond_memory`]).
    pub memory: bool,
    /// Some particle has a fixed position or orientation.
    pub has_fixed: bool,
    pub neighbours: Option<NeighbourList>,
    /// The bond store (`None`: no particle has a bonded material).
    pub bonds: Option<Bonds>,
    /// Tools acting on the particles ([`crate::World::set_tools`]; none:
    /// no tool stage).
    pub tools: Option<Box<dyn ToolSet>>,
    /// Contributors callers registered ([`crate::World::add_contributor`]).
    pub contributors: Vec<Box<dyn Contributor + Send>>,
    pub scratch: ForceScratch,
}

impl ForceScratch {
    /// Total potential energy of the last evaluation: the per-particle
    /// energies summed in slot order. Summed when asked (a serial pass
    /// over every particle, which the steps themselves never read).
    pub fn potential(&self) -> Real {
        self.energies.iter().sum()
    }
}

impl ForceModel {
    /// The force field of the world's particles with these attributes and
    /// external actions.
    pub fn context<'a>(
        &'a mut self,
        attributes: Attributes<'a>,
        external: &'a ExternalParams,
        accumulator: &'a ExternalAccumulator,
        extra: &'a [&'a dyn Contributor],
    ) -> ForceContext<'a> {
        ForceContext {
            kernel: self.kernel,
            attributes,
            materials: &self.materials,
            friction: self.friction,
            heated: self.heated,
            memory: self.memory,
            has_fixed: self.has_fixed,
            neighbours: self.neighbours.as_mut(),
            bonds: self.bonds.as_ref(),
            external,
            step_start: None,
            accumulator,
            extra,
            registered: &self.contributors,
            tools: self.tools.as_deref(),
            scratch: &mut self.scratch,
        }
    }
}

impl crate::integrators::ForceField for ForceContext<'_> {
    fn forces(&mut self, t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        self.evaluate(t, s, forces, torques);
    }
}

impl ForceContext<'_> {
    /// Computes forces, torques and the per-particle potential energies at
    /// state `s`: updates the neighbour list (rebuilding it when the
    /// particles moved too far), evaluates the pair kernel chosen when the
    /// world was built, then adds the contributors (tools, uniform field,
    /// accumulated actions, registered and extra contributors, force
    /// windows), and
    /// zeroes what fixed particles hold (the total potential energy is summed
    /// on request, [`ForceScratch::potential`]).
    ///
    /// The pairs are summed by fixed blocks and an ordered merge of their
    /// spills (see the module docs): one path at every thread count, so
    /// every particle's sum is added in the same order, with the same
    /// bits, on any number of threads.
    pub fn evaluate(
        &mut self,
        t: Real,
        s: StateRef<'_>,
        forces: &mut [Vec3],
        torques: &mut [Vec3],
    ) {
        let n = s.positions.len();
        let ForceScratch {
            blocks,
            normals,
            tangents,
            energies,
            evaluations,
            neighbour_seconds,
        } = &mut *self.scratch;
        *evaluations += 1;
        energies.resize(n, 0.0);
        match (self.kernel, self.neighbours.as_deref_mut()) {
            (Kernel::None, _) | (_, None) => {
                forces.iter_mut().for_each(|f| *f = Vec3::zeros());
                torques.iter_mut().for_each(|t| *t = Vec3::zeros());
                energies.iter_mut().for_each(|e| *e = 0.0);
            }
            (kernel, Some(list)) => {
                let clock = std::time::Instant::now();
                list.update(s.positions);
                *neighbour_seconds += clock.elapsed().as_secs_f64();
                let a = &self.attributes;
                let m = self.materials;
                let cutoff2 = list.cutoff() * list.cutoff();
                let out = Sums {
                    forces,
                    torques,
                    energies,
                };
                let heated = self.heated;
                let bonds = self.bonds;
                let list = &*list;
                if let (Kernel::Spacing, Some(b)) = (kernel, bonds) {
                    let pair = |i: usize, j: usize| spacing_pair(a, m, b, heated, cutoff2, s, i, j);
                    accumulate::<false, _>(list, blocks, Scalar(pair), out);
                } else if kernel == Kernel::Spacing {
                    if uniform_spacing(a) && !heated {
                        // One material, every pair complete: a dedicated
                        // loop per spacing potential (monomorphized, no
                        // per-pair dispatch).
                        uniform_spacing_pass(&m[0], cutoff2, s.positions, list, blocks, out, true);
                    } else {
                        let pair = |i: usize, j: usize| {
                            spacing_pair(a, m, &Unbonded, heated, cutoff2, s, i, j)
                        };
                        accumulate::<false, _>(list, blocks, Scalar(pair), out);
                    }
                } else {
                    frames(normals, tangents, a, s);
                    let (normals, tangents) = (&*normals, &*tangents);
                    let (friction, nv, tv) = (self.friction, normals, tangents);
                    if let Some(b) = bonds {
                        let pair = |i: usize, j: usize| {
                            oriented_pair::<false>(
                                a, m, b, friction, heated, cutoff2, nv, tv, s, i, j,
                            )
                        };
                        accumulate::<true, _>(list, blocks, Scalar(pair), out);
                    } else if let Some(c) = (!heated && !friction && uniform_oriented(a))
                        .then(|| m[0].oriented_lane_constants())
                        .flatten()
                    {
                        let input = crate::lanes::OrientedInput {
                            c: &c,
                            cutoff2,
                            p: s.positions,
                            normals: nv,
                            curvatures: a.curvatures,
                        };
                        uniform_oriented_pass(input, list, blocks, out);
                    } else if !heated && uniform_oriented(a) {
                        let pair = |i: usize, j: usize| {
                            oriented_pair::<true>(
                                a, m, &Unbonded, friction, false, cutoff2, nv, tv, s, i, j,
                            )
                        };
                        accumulate::<true, _>(list, blocks, Scalar(pair), out);
                    } else {
                        let pair = |i: usize, j: usize| {
                            oriented_pair::<false>(
                                a, m, &Unbonded, friction, heated, cutoff2, nv, tv, s, i, j,
                            )
                        };
                        accumulate::<true, _>(list, blocks, Scalar(pair), out);
                    }
                }
            }
        }
        // The bond memory of plastic lattices (`crate::bond_memory`): one
        // pass over the bonds, in bond order, after the pairs.
        if let (true, Some(b)) = (self.memory, self.bonds) {
            crate::bond_memory::add_forces(
                b,
                self.materials,
                &self.attributes,
                s,
                forces,
                torques,
                energies,
            );
        }
        let input = ContributorInput {
            t,
            step_start: self.step_start,
            state: s,
            attributes: &self.attributes,
            materials: self.materials,
        };
        let mut out = Contribution {
            forces: &mut *forces,
            torques: &mut *torques,
            energies: &mut energies[..],
        };
        // The order of the module docs of `crate::contributors`.
        let uniform = UniformField::new(self.external, self.materials, self.heated);
        let windows = ForceWindows(&self.external.forces);
        let built_in: [&dyn Contributor; 2] = [&uniform, self.accumulator];
        let tools = self.tools.map(|t| t as &dyn Contributor);
        let registered = self.registered.iter().map(|c| &**c as &dyn Contributor);
        for c in tools
            .into_iter()
            .chain(built_in)
            .chain(registered)
            .chain(self.extra.iter().copied())
            .chain(std::iter::once(&windows as &dyn Contributor))
        {
            if c.is_active() {
                c.contribute(&input, &mut out);
            }
        }
        if self.has_fixed {
            fix(&self.attributes, forces, torques);
        }
    }
}

/// Fixed particles get zero force or torque (seed 000 eq. 12-13 with the
/// particle held).
fn fix(a: &Attributes<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
    for (i, fl) in a.flags.iter().enumerate() {
        if fl.contains(Flags::FIXED_POSITION) {
            forces[i] = Vec3::zeros();
        }
        if fl.contains(Flags::FIXED_ORIENTATION) {
            torques[i] = Vec3::zeros();
        }
    }
}

/// The bond lookup of the pair kernels ([`crate::bonds`]): whether a pair
/// that membership and typing would couple completely keeps its complete
/// interaction.
pub(crate) trait BondLookup: Sync {
    fn complete(&self, a: &Attributes<'_>, i: usize, j: usize) -> bool;
}

/// The lookup of worlds without bonded materials: every pair keeps it (a
/// constant the compiler folds away).
pub(crate) struct Unbonded;

impl BondLookup for Unbonded {
    #[inline(always)]
    fn complete(&self, _: &Attributes<'_>, _: usize, _: usize) -> bool {
        true
    }
}

impl BondLookup for Bonds {
    /// Pairs governed by bonds keep it only when bonded.
    #[inline]
    fn complete(&self, a: &Attributes<'_>, i: usize, j: usize) -> bool {
        !self.governs(a.materials[i], a.materials[j]) || self.contains(a.ids[i], a.ids[j])
    }
}

/// Coupling of two particles: object membership, then typing, then bonds,
/// then orientation (seed 002 §5; unoriented particles drop orientation
/// terms; bond-governed pairs that are not bonded only repel).
#[inline(always)]
pub(crate) fn coupling(
    a: &Attributes<'_>,
    bonds: &impl BondLookup,
    i: usize,
    j: usize,
) -> Coupling {
    if a.objects[i] != a.objects[j]
        || !a.kinds[i].complete_with(a.kinds[j])
        || !bonds.complete(a, i, j)
    {
        Coupling::RepulsionOnly
    } else {
        let oriented =
            !(a.flags[i].contains(Flags::UNORIENTED) || a.flags[j].contains(Flags::UNORIENTED));
        Coupling::Complete { oriented }
    }
}

/// True when every particle has material 0, object 0's id and type
/// `Standard(0)`'s coupling: then every pair is a complete spacing pair of
/// material 0 and the spacing kernel skips the per-pair lookups.
fn uniform_spacing(a: &Attributes<'_>) -> bool {
    let (o, k) = match (a.objects.first(), a.kinds.first()) {
        (Some(&o), Some(&k)) => (o, k),
        _ => return true,
    };
    k != crate::particles::ParticleType::Hinge
        && a.materials.iter().all(|&m| m == 0)
        && a.objects.iter().all(|&x| x == o)
        && a.kinds.iter().all(|&x| x == k)
}

/// [`uniform_spacing`] and no particle unoriented: every pair is complete
/// and oriented, of material 0.
fn uniform_oriented(a: &Attributes<'_>) -> bool {
    uniform_spacing(a) && a.flags.iter().all(|f| !f.contains(Flags::UNORIENTED))
}

/// The per-particle sums a force evaluation fills.
struct Sums<'a> {
    forces: &'a mut [Vec3],
    torques: &'a mut [Vec3],
    energies: &'a mut [Real],
}

/// One pair's contribution: the force on `j` (the force on `i` is its
/// negative), the torques on `i` and `j`, the pair energy.
trait PairOut: Copy + Default + Send + Sync {
    fn force_j(&self) -> Vec3;
    fn torque_i(&self) -> Vec3;
    fn torque_j(&self) -> Vec3;
    fn energy(&self) -> Real;
}

/// Result slot of one pair in the spacing kernel.
#[derive(Copy, Clone, Debug, Default)]
struct SpacingPair {
    force_j: Vec3,
    energy: Real,
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
trait PairSource: Sync {
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
struct Scalar<F>(F);

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
fn accumulate<const TORQUES: bool, P: PairSource>(
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

    /// One block up to `BLOCK` particles; above, an even count of equal
    /// blocks of at most `BLOCK` covering every slot; the block of a slot
    /// by multiplication equals the division, for every slot of those
    /// sizes and at the top of the 32-bit range.
    #[test]
    fn blocks_are_even_equal_and_found_by_multiplication() {
        for n in [
            0,
            1,
            2,
            3,
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
            if n > BLOCK {
                assert_eq!(cut.count % 2, 0, "{n}: {cut:?}");
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
