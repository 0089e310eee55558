//! Internal force evaluation: every pair visited once, both `E_ij` and
//! `E_ji` evaluated there (docs/model.md §2), in parallel with results bitwise
//! identical at any thread count.
//!
//! The scheme is "fixed blocks, ordered merge": particles are cut
//! into blocks of consecutive slots (`Blocks`: one block below
//! `SPLIT_MIN` (384) particles, else an even number of equal blocks of at
//! most `BLOCK` (2048) particles, a function of the particle count only,
//! never of the thread count; the world keeps particles in
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
//! (`uniform_oriented`). In mixed precision ([`Precision::Mixed`]),
//! spacing-only worlds of one 12-6 material run cluster-pair tiles in
//! `f32` lanes instead (`cluster_spacing`), summed by blocks and an
//! ordered merge of their own. Worlds with a bond memory
//! ([`crate::bond_memory`]) add it in one pass over the bonds after the
//! pairs.

use crate::bonds::Bonds;
use crate::contributors::{Contribution, Contributor, ContributorInput};
use crate::external::{ExternalAccumulator, ExternalParams, ForceWindows, UniformField};
use crate::flags::Flags;
use crate::integrators::StateRef;
use crate::interactions::{Coupling, LennardJones, PreparedMaterial};
use crate::math::{Real, Vec3};
use crate::neighbours::NeighbourList;
use crate::particles::Attributes;
use crate::tooling::ToolSet;

mod pair_kernels;
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

mod blocks;
pub(crate) use blocks::SPLIT_MIN;
use blocks::{accumulate, BlockScratch, OrientedPair, PairSource, Scalar, SpacingPair, Sums};
mod cluster_spacing;
pub use cluster_spacing::Precision;
use cluster_spacing::{cluster_spacing_pass, ClusterScratch};
mod uniform_spacing;
use uniform_spacing::uniform_spacing_pass;
mod uniform_oriented;
use uniform_oriented::uniform_oriented_pass;
#[cfg(test)]
mod pass_bits;

/// Scratch buffers of the force evaluation, owned by the world.
#[derive(Default)]
pub(crate) struct ForceScratch {
    blocks: Vec<BlockScratch>,
    /// The mixed-precision cluster kernel's scratch.
    clusters: ClusterScratch<f32>,
    normals: Vec<Vec3>,
    tangents: Vec<Vec3>,
    /// Potential energy attributed to each particle (its row's pairs).
    energies: Vec<Real>,
    /// Number of force evaluations since the world was built.
    pub evaluations: u64,
    /// Seconds spent updating neighbour lists (accumulated).
    pub neighbour_seconds: f64,
    /// Seconds each contributor of the interval
    /// ([`crate::World::advance_to_with`]'s `extra`) spent, since the
    /// interval began.
    pub extra_seconds: Vec<f64>,
    /// Seconds each after-step action of the interval
    /// ([`crate::World::advance_to_with`]'s `after_steps`) spent, since
    /// the interval began.
    pub lent_after_step_seconds: Vec<f64>,
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
    /// Arithmetic of the cluster kernels.
    pub precision: Precision,
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
    /// Arithmetic of the cluster kernels.
    pub precision: Precision,
    pub neighbours: Option<NeighbourList>,
    /// The bond store (`None`: no particle has a bonded material).
    pub bonds: Option<Bonds>,
    /// Tools acting on the particles ([`crate::World::set_tools`]; none:
    /// no tool stage).
    pub tools: Option<Box<dyn ToolSet>>,
    pub scratch: ForceScratch,
}

impl ForceScratch {
    /// Drops what was derived from the neighbour list (the cluster pairs):
    /// the world restored another list, which may carry the same build
    /// count as the one they came from.
    pub fn forget_lists(&mut self) {
        self.clusters = ClusterScratch::default();
    }

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
            precision: self.precision,
            neighbours: self.neighbours.as_mut(),
            bonds: self.bonds.as_ref(),
            external,
            step_start: None,
            accumulator,
            extra,
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
        self.scratch.evaluations += 1;
        self.scratch.energies.resize(n, 0.0);
        self.pair_pass(s, forces, torques);
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
                &mut self.scratch.energies,
            );
        }
        self.add_contributors(t, s, forces, torques);
        if self.has_fixed {
            fix(&self.attributes, forces, torques);
        }
    }

    /// The pair pass: updates the neighbour list and sets the sums to the
    /// chosen kernel's pairs (zero without a kernel or a list).
    fn pair_pass(&mut self, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        let ForceScratch {
            blocks,
            clusters,
            normals,
            tangents,
            energies,
            neighbour_seconds,
            ..
        } = &mut *self.scratch;
        let list = match (self.kernel, self.neighbours.as_deref_mut()) {
            (Kernel::None, _) | (_, None) => {
                forces.iter_mut().for_each(|f| *f = Vec3::zeros());
                torques.iter_mut().for_each(|t| *t = Vec3::zeros());
                energies.iter_mut().for_each(|e| *e = 0.0);
                return;
            }
            (_, Some(list)) => list,
        };
        let clock = std::time::Instant::now();
        // The cluster kernel searches its own rows from the reference
        // positions: its worlds never search the particle rows.
        let clustered = cluster_material(
            self.precision,
            self.kernel,
            &self.attributes,
            self.materials,
            self.heated,
            self.bonds.is_some(),
        );
        if clustered.is_some() {
            list.update_reference(s.positions);
        } else {
            list.update(s.positions);
        }
        *neighbour_seconds += clock.elapsed().as_secs_f64();
        let pass = PairPass {
            a: &self.attributes,
            m: self.materials,
            cutoff2: list.cutoff() * list.cutoff(),
            heated: self.heated,
            friction: self.friction,
            bonds: self.bonds,
            s,
            list: &*list,
        };
        let out = Sums {
            forces,
            torques,
            energies,
        };
        if self.kernel == Kernel::Spacing {
            pass.spacing(blocks, clusters, clustered, out);
        } else {
            pass.oriented(blocks, normals, tangents, out);
        }
    }

    /// Adds the contributors in the order of the module docs of
    /// `crate::contributors`: tools, uniform field, accumulated actions,
    /// the interval's contributors, force windows.
    fn add_contributors(
        &mut self,
        t: Real,
        s: StateRef<'_>,
        forces: &mut [Vec3],
        torques: &mut [Vec3],
    ) {
        let input = ContributorInput {
            t,
            step_start: self.step_start,
            state: s,
            attributes: &self.attributes,
            materials: self.materials,
        };
        let mut out = Contribution {
            forces,
            torques,
            energies: &mut self.scratch.energies[..],
        };
        // The order of the module docs of `crate::contributors`.
        let uniform = UniformField::new(self.external, self.materials, self.heated);
        let windows = ForceWindows(&self.external.forces);
        let built_in: [&dyn Contributor; 2] = [&uniform, self.accumulator];
        let tools = self.tools.map(|t| t as &dyn Contributor);
        for c in tools.into_iter().chain(built_in) {
            if c.is_active() {
                c.contribute(&input, &mut out);
            }
        }
        // The interval's contributors, each timed.
        let seconds = &mut self.scratch.extra_seconds;
        seconds.resize(self.extra.len(), 0.0);
        for (c, spent) in self.extra.iter().zip(seconds.iter_mut()) {
            if c.is_active() {
                let clock = std::time::Instant::now();
                c.contribute(&input, &mut out);
                *spent += clock.elapsed().as_secs_f64();
            }
        }
        if windows.is_active() {
            windows.contribute(&input, &mut out);
        }
    }
}

/// What one pair pass reads: the attributes, materials and flags of the
/// force context, the state and the updated neighbour list.
#[derive(Clone, Copy)]
struct PairPass<'p> {
    a: &'p Attributes<'p>,
    m: &'p [PreparedMaterial],
    cutoff2: Real,
    heated: bool,
    friction: bool,
    bonds: Option<&'p Bonds>,
    s: StateRef<'p>,
    list: &'p NeighbourList,
}

impl PairPass<'_> {
    /// The spacing kernel: bonded pairs, one 12-6 material's cluster tiles
    /// in mixed precision (`clustered`: that material, from
    /// [`cluster_material`]), one uniform material's dedicated loop, or
    /// the general spacing pair.
    fn spacing(
        self,
        blocks: &mut Vec<BlockScratch>,
        clusters: &mut ClusterScratch<f32>,
        clustered: Option<&LennardJones>,
        out: Sums<'_>,
    ) {
        let PairPass {
            a,
            m,
            cutoff2,
            heated,
            bonds,
            s,
            list,
            ..
        } = self;
        if let Some(b) = bonds {
            let pair = |i: usize, j: usize| spacing_pair(a, m, b, heated, cutoff2, s, i, j);
            accumulate::<false, _>(list, blocks, Scalar(pair), out);
        } else if let Some(lj) = clustered {
            // One 12-6 Lennard-Jones material, every pair complete, in
            // mixed precision: the cluster-pair tiles in `f32` lanes.
            cluster_spacing_pass(lj, cutoff2, s.positions, list, clusters, out);
        } else if uniform_spacing(a) && !heated {
            // One material, every pair complete: a dedicated
            // loop per spacing potential (monomorphized, no
            // per-pair dispatch).
            uniform_spacing_pass(&m[0], cutoff2, s.positions, list, blocks, out, true);
        } else {
            let pair = |i: usize, j: usize| spacing_pair(a, m, &Unbonded, heated, cutoff2, s, i, j);
            accumulate::<false, _>(list, blocks, Scalar(pair), out);
        }
    }

    /// The oriented kernel: the particle frames, then bonded pairs, one
    /// uniform material's SIMD lanes or scalar loop (heated or not), or the
    /// general oriented pair.
    fn oriented(
        self,
        blocks: &mut Vec<BlockScratch>,
        normals: &mut Vec<Vec3>,
        tangents: &mut Vec<Vec3>,
        out: Sums<'_>,
    ) {
        let PairPass {
            a,
            m,
            cutoff2,
            heated,
            friction,
            bonds,
            s,
            list,
        } = self;
        frames(normals, tangents, a, s);
        let (normals, tangents) = (&*normals, &*tangents);
        let (nv, tv) = (normals, tangents);
        if let Some(b) = bonds {
            let pair = |i: usize, j: usize| {
                oriented_pair::<false>(a, m, b, friction, heated, cutoff2, nv, tv, s, i, j)
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
                oriented_pair::<true>(a, m, &Unbonded, friction, false, cutoff2, nv, tv, s, i, j)
            };
            accumulate::<true, _>(list, blocks, Scalar(pair), out);
        } else if uniform_oriented(a) {
            // Heated, of one material: the same pair without the per-pair
            // lookups (sculpting one piece of clay, seed 000 §8).
            let pair = |i: usize, j: usize| {
                oriented_pair::<true>(a, m, &Unbonded, friction, true, cutoff2, nv, tv, s, i, j)
            };
            accumulate::<true, _>(list, blocks, Scalar(pair), out);
        } else {
            let pair = |i: usize, j: usize| {
                oriented_pair::<false>(a, m, &Unbonded, friction, heated, cutoff2, nv, tv, s, i, j)
            };
            accumulate::<true, _>(list, blocks, Scalar(pair), out);
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

/// The 12-6 Lennard-Jones material whose pairs run on the cluster tiles
/// (`cluster_spacing`): that of a world in mixed precision whose kernel is
/// the spacing one, of one such material, every pair complete, without
/// heat or bonds; `None` for every other world (it runs in double
/// precision).
pub(crate) fn cluster_material<'m>(
    precision: Precision,
    kernel: Kernel,
    a: &Attributes<'_>,
    m: &'m [PreparedMaterial],
    heated: bool,
    bonded: bool,
) -> Option<&'m LennardJones> {
    let eligible = precision == Precision::Mixed
        && kernel == Kernel::Spacing
        && !heated
        && !bonded
        && uniform_spacing(a);
    eligible.then(|| m.first()?.lennard_jones_12_6()).flatten()
}

/// True when every particle has material 0, object 0's id and type
/// `Standard(0)`'s coupling: then every pair is a complete spacing pair of
/// material 0 and the spacing kernel skips the per-pair lookups.
fn uniform_spacing(a: &Attributes<'_>) -> bool {
    let (o, k) = match (a.objects.first(), a.kinds.first()) {
        (Some(&o), Some(&k)) => (o, k),
        _ => return true,
    };
    // Checked at every evaluation: in parallel, as a large world's other
    // passes (a serial scan of the 32k block's three arrays took 0.7% of
    // a mixed-precision step at 2 threads).
    use rayon::prelude::*;
    let min = crate::MIN_PARALLEL_LEN;
    k != crate::particles::ParticleType::Hinge
        && a.materials.par_iter().with_min_len(min).all(|&m| m == 0)
        && a.objects.par_iter().with_min_len(min).all(|&x| x == o)
        && a.kinds.par_iter().with_min_len(min).all(|&x| x == k)
}

/// [`uniform_spacing`] and no particle unoriented: every pair is complete
/// and oriented, of material 0.
fn uniform_oriented(a: &Attributes<'_>) -> bool {
    uniform_spacing(a) && a.flags.iter().all(|f| !f.contains(Flags::UNORIENTED))
}
