//! Internal force evaluation: every pair visited once, both `E_ij` and
//! `E_ji` evaluated there (DESIGN §3), in parallel with results bitwise
//! identical at any thread count.
//!
//! The scheme is "parallel map, ordered collect" (STYLE): the half neighbour
//! list is flat, so a parallel pass over *pairs* writes each pair's result
//! into its own slot of a pair buffer; a second parallel pass over
//! *particles* gathers, in a fixed order, the contributions of the pairs
//! where the particle is second (the transposed index, ascending source)
//! and then of those where it is first (its row). No locks, no atomics, no
//! scheduling dependence, no allocation once the buffers are sized. On one
//! thread the pairs are scattered straight into the particle sums instead,
//! which adds the same terms in the same order: the same bits, without the
//! buffer's memory traffic.
//!
//! Two kernels are compiled and one is chosen when the world is built
//! (pay for what you use): [`Kernel::Spacing`] touches positions only;
//! [`Kernel::Oriented`] evaluates the full oriented interaction. Each is
//! compiled for two bond lookups ([`crate::bonds`]): worlds without bonded
//! materials run the instance whose lookup is the constant `true` (the
//! code they ran before bonds existed, no per-pair bond work); worlds with
//! them look each complete pair up in the bond store.

use rayon::prelude::*;

use crate::bonds::Bonds;
use crate::external::{ExternalAccumulator, ExternalParams};
use crate::flags::Flags;
use crate::heat::pair_strength;
use crate::integrators::StateRef;
use crate::interactions::{
    evaluate_pair, evaluate_pair_weakened, evaluate_spacing, evaluate_spacing_weakened, Coupling,
    ParticleView, PreparedMaterial,
};
use crate::math::{Real, Vec3};
use crate::neighbours::NeighbourList;
use crate::particles::Attributes;
use crate::tools::Tools;

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

/// Result slot of one pair in the oriented kernel.
#[derive(Copy, Clone, Debug, Default)]
struct OrientedPair {
    force_j: Vec3,
    torque_i: Vec3,
    torque_j: Vec3,
    energy: Real,
}

/// Scratch buffers of the force evaluation, owned by the world.
#[derive(Default)]
pub(crate) struct ForceScratch {
    /// Source particle of each pair of the current list.
    sources: Vec<u32>,
    /// Rebuild count of the list `sources` was made for.
    sources_for: u64,
    spacing_pairs: Vec<Option<SpacingPair>>,
    oriented_pairs: Vec<Option<OrientedPair>>,
    normals: Vec<Vec3>,
    tangents: Vec<Vec3>,
    /// Potential energy attributed to each particle (its row's pairs).
    energies: Vec<Real>,
    /// Total potential energy of the last evaluation.
    pub potential: Real,
    /// Number of force evaluations since the world was built.
    pub evaluations: u64,
    /// Seconds spent updating neighbour lists (accumulated).
    pub neighbour_seconds: f64,
}

impl ForceScratch {
    /// Forgets the pair sources cached for the current neighbour list (the
    /// world replaced the list: its rebuild count starts again).
    pub(crate) fn forget_list(&mut self) {
        self.sources.clear();
        self.sources_for = u64::MAX;
    }
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
    pub tools: &'a Tools,
    pub scratch: &'a mut ForceScratch,
}

/// The force evaluation's configuration and scratch, owned by the world:
/// the chosen kernel, the prepared materials, the neighbour list.
pub(crate) struct Pipeline {
    pub kernel: Kernel,
    pub materials: Vec<PreparedMaterial>,
    pub friction: bool,
    /// Some material in use weakens with heat.
    pub heated: bool,
    /// Some particle has a fixed position or orientation.
    pub has_fixed: bool,
    pub neighbours: Option<NeighbourList>,
    /// The bond store (`None`: no particle has a bonded material).
    pub bonds: Option<Bonds>,
    /// Tools acting on the particles (empty: no tool stage).
    pub tools: Tools,
    pub scratch: ForceScratch,
}

impl Pipeline {
    /// The force field of the world's particles with these attributes and
    /// external actions.
    pub fn context<'a>(
        &'a mut self,
        attributes: Attributes<'a>,
        external: &'a ExternalParams,
        accumulator: &'a ExternalAccumulator,
    ) -> ForceContext<'a> {
        ForceContext {
            kernel: self.kernel,
            attributes,
            materials: &self.materials,
            friction: self.friction,
            heated: self.heated,
            has_fixed: self.has_fixed,
            neighbours: self.neighbours.as_mut(),
            bonds: self.bonds.as_ref(),
            external,
            step_start: None,
            accumulator,
            tools: &self.tools,
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
    /// Computes forces, torques and the potential energy at state `s`.
    ///
    /// On one thread the pairs are scattered directly into the particle
    /// sums; on several, each pair's result goes into its slot of a pair
    /// buffer and each particle gathers its slots. Both add, for every
    /// particle, its incoming pairs in ascending order and then its own row
    /// in list order, so the two paths give the same bits.
    pub fn evaluate(
        &mut self,
        t: Real,
        s: StateRef<'_>,
        forces: &mut [Vec3],
        torques: &mut [Vec3],
    ) {
        let n = s.positions.len();
        let ForceScratch {
            sources,
            sources_for,
            spacing_pairs,
            oriented_pairs,
            normals,
            tangents,
            energies,
            potential,
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
                let serial = rayon::current_num_threads() == 1;
                if !serial {
                    refresh_sources(sources, sources_for, list);
                }
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
                if let (Kernel::Spacing, Some(b)) = (kernel, bonds) {
                    let pair = |i: usize, j: usize| spacing_pair(a, m, b, heated, cutoff2, s, i, j);
                    accumulate::<false, _, _>(list, sources, spacing_pairs, serial, pair, out);
                } else if kernel == Kernel::Spacing {
                    if uniform_spacing(a) && !heated {
                        // One material, every pair complete: the dedicated
                        // spacing loop, small enough to be inlined whole.
                        let (m0, p) = (&m[0], s.positions);
                        let pair = |i: usize, j: usize| uniform_spacing_pair(m0, cutoff2, p, i, j);
                        accumulate::<false, _, _>(list, sources, spacing_pairs, serial, pair, out);
                    } else {
                        let pair = |i: usize, j: usize| {
                            spacing_pair(a, m, &Unbonded, heated, cutoff2, s, i, j)
                        };
                        accumulate::<false, _, _>(list, sources, spacing_pairs, serial, pair, out);
                    }
                } else {
                    frames(normals, tangents, a, s);
                    let (normals, tangents) = (&*normals, &*tangents);
                    let (friction, nv, tv) = (self.friction, normals, tangents);
                    if let Some(b) = bonds {
                        let pair = |i: usize, j: usize| {
                            oriented_pair(a, m, b, friction, heated, cutoff2, nv, tv, s, i, j)
                        };
                        accumulate::<true, _, _>(list, sources, oriented_pairs, serial, pair, out);
                    } else {
                        let pair = |i: usize, j: usize| {
                            oriented_pair(
                                a, m, &Unbonded, friction, heated, cutoff2, nv, tv, s, i, j,
                            )
                        };
                        accumulate::<true, _, _>(list, sources, oriented_pairs, serial, pair, out);
                    }
                }
            }
        }
        if !self.tools.is_empty() {
            self.tools
                .add(t, s, &self.attributes, forces, &mut energies[..]);
        }
        *potential = energies.iter().sum();
        self.add_external(t, s, forces, torques);
    }

    /// Gravity, force windows, damping (with the cold drag of heated
    /// materials), pending accumulator; fixed particles get zero force /
    /// torque (seed 000 eq. 12-13).
    fn add_external(&self, t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        let g = self.external.gravity();
        let b0 = self.external.linear_damping;
        let b1 = self.external.angular_damping;
        let a = &self.attributes;
        let acc = self.accumulator;
        // Cold drag (crate::heat::HeatResponse::cold_drag): only when some
        // material in use has one.
        let cold_drag = self.heated
            && self
                .materials
                .iter()
                .any(|m| m.heat_response().is_some_and(|h| h.cold_drag > 0.0));
        let drag = |i: usize| {
            self.materials[a.materials[i] as usize]
                .heat_response()
                .map_or(0.0, |h| h.drag(a.temperatures[i]))
        };
        let uniform = g != Vec3::zeros() || b0 != 0.0 || b1 != 0.0 || acc.is_active() || cold_drag;
        if uniform {
            forces
                .par_iter_mut()
                .zip(torques.par_iter_mut())
                .enumerate()
                .for_each(|(i, (f, tq))| {
                    let b = if cold_drag { b0 + drag(i) } else { b0 };
                    *f += a.masses[i] * g - b * s.velocities[i];
                    *tq -= b1 * s.angular_velocities[i];
                    if acc.is_active() {
                        let (fe, te) = acc.get(a.ids[i]);
                        *f += fe;
                        *tq += te;
                    }
                });
        }
        for w in &self.external.forces {
            let k = match self.step_start {
                Some(t0) => w.factor_within(t, t0),
                None => w.factor(t),
            };
            if k != 0.0 {
                let fw = k * Vec3::from(w.force);
                for &id in &w.particles {
                    // Removed particles (World::remove_particles) are skipped.
                    if let Some(&slot) = a.slot_of.get(id as usize) {
                        if slot != crate::particles::Particles::REMOVED {
                            forces[slot as usize] += fw;
                        }
                    }
                }
            }
        }
        if !self.has_fixed {
            return;
        }
        for (i, fl) in a.flags.iter().enumerate() {
            if fl.contains(Flags::FIXED_POSITION) {
                forces[i] = Vec3::zeros();
            }
            if fl.contains(Flags::FIXED_ORIENTATION) {
                torques[i] = Vec3::zeros();
            }
        }
    }
}

/// Recomputes the source particle of every pair after a list rebuild.
fn refresh_sources(sources: &mut Vec<u32>, sources_for: &mut u64, list: &NeighbourList) {
    if *sources_for == list.rebuilds() && sources.len() == list.pairs().num_pairs() {
        return;
    }
    list.pairs().sources_into(sources);
    *sources_for = list.rebuilds();
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
#[inline]
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

/// Evaluates every listed pair once and sums the contributions per
/// particle: incoming pairs first (ascending source), then the particle's
/// own row (list order). `TORQUES` is false for kernels without torques.
fn accumulate<const TORQUES: bool, O: PairOut, P: Fn(usize, usize) -> Option<O> + Sync>(
    list: &NeighbourList,
    sources: &[u32],
    buffer: &mut Vec<Option<O>>,
    serial: bool,
    pair: P,
    out: Sums<'_>,
) {
    let pairs = list.pairs();
    let nbrs = pairs.neighbours();
    let Sums {
        forces,
        torques,
        energies,
    } = out;
    if serial {
        forces.iter_mut().for_each(|f| *f = Vec3::zeros());
        torques.iter_mut().for_each(|t| *t = Vec3::zeros());
        for i in 0..forces.len() {
            let (mut fo, mut to, mut eo) = (Vec3::zeros(), Vec3::zeros(), 0.0);
            for k in pairs.row_range(i) {
                let j = nbrs[k] as usize;
                let Some(o) = pair(i, j) else { continue };
                fo -= o.force_j();
                eo += o.energy();
                forces[j] += o.force_j();
                if TORQUES {
                    to += o.torque_i();
                    torques[j] += o.torque_j();
                }
            }
            forces[i] += fo;
            if TORQUES {
                torques[i] += to;
            }
            energies[i] = eo;
        }
        return;
    }
    buffer.resize(nbrs.len(), None);
    buffer
        .par_iter_mut()
        .with_min_len(256)
        .enumerate()
        .for_each(|(k, o)| *o = pair(sources[k] as usize, nbrs[k] as usize));
    let buffer = &*buffer;
    forces
        .par_iter_mut()
        .zip(torques.par_iter_mut())
        .zip(energies.par_iter_mut())
        .enumerate()
        .with_min_len(256)
        .for_each(|(i, ((f, t), e))| {
            let (mut fin, mut tin) = (Vec3::zeros(), Vec3::zeros());
            for &k in pairs.incoming(i) {
                let Some(o) = &buffer[k as usize] else {
                    continue;
                };
                fin += o.force_j();
                if TORQUES {
                    tin += o.torque_j();
                }
            }
            let (mut fo, mut to, mut eo) = (Vec3::zeros(), Vec3::zeros(), 0.0);
            for k in pairs.row_range(i) {
                let Some(o) = &buffer[k] else { continue };
                fo -= o.force_j();
                eo += o.energy();
                if TORQUES {
                    to += o.torque_i();
                }
            }
            *f = fin + fo;
            *t = if TORQUES { tin + to } else { Vec3::zeros() };
            *e = eo;
        });
}

/// World normals and tangents of every particle at state `s`.
fn frames(normals: &mut Vec<Vec3>, tangents: &mut Vec<Vec3>, a: &Attributes<'_>, s: StateRef<'_>) {
    let n = s.positions.len();
    normals.resize(n, Vec3::zeros());
    tangents.resize(n, Vec3::zeros());
    normals
        .par_iter_mut()
        .zip(tangents.par_iter_mut())
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, (nv, tv))| {
            let q = &s.orientations[i];
            *nv = q * a.normal_axes[i];
            *tv = q * a.tangent_axes[i];
        });
}

/// The spacing kernel's pair when every particle has the same material and
/// every pair interacts completely ([`uniform_spacing`]).
#[inline]
fn uniform_spacing_pair(
    m: &PreparedMaterial,
    cutoff2: Real,
    p: &[crate::math::Point3],
    i: usize,
    j: usize,
) -> Option<SpacingPair> {
    let r = p[j] - p[i];
    let d2 = r.norm_squared();
    if d2 > cutoff2 {
        return None;
    }
    let (energy, force_j) = evaluate_spacing(m, m, &r, d2.sqrt());
    Some(SpacingPair { force_j, energy })
}

/// The heat strength of the pair `(i, j)` when the world is `heated`
/// ([`crate::heat::pair_strength`]), else 1.
#[inline]
fn strength(
    a: &Attributes<'_>,
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    heated: bool,
    i: usize,
    j: usize,
) -> Real {
    if heated {
        pair_strength(
            mi.heat_response(),
            mj.heat_response(),
            a.temperatures[i],
            a.temperatures[j],
        )
    } else {
        1.0
    }
}

/// The spacing kernel's pair: spacing potential for complete pairs
/// (weakened by heat when `heated`), the typing repulsion otherwise; zero
/// beyond the cut-off.
#[allow(clippy::too_many_arguments)]
#[inline]
fn spacing_pair(
    a: &Attributes<'_>,
    materials: &[PreparedMaterial],
    bonds: &impl BondLookup,
    heated: bool,
    cutoff2: Real,
    s: StateRef<'_>,
    i: usize,
    j: usize,
) -> Option<SpacingPair> {
    let p = s.positions;
    let r = p[j] - p[i];
    let d2 = r.norm_squared();
    if d2 > cutoff2 {
        return None;
    }
    let dist = d2.sqrt();
    let (mi, mj) = (
        &materials[a.materials[i] as usize],
        &materials[a.materials[j] as usize],
    );
    let (energy, force_j) = match coupling(a, bonds, i, j) {
        Coupling::Complete { .. } => {
            let st = strength(a, mi, mj, heated, i, j);
            if st < 1.0 {
                evaluate_spacing_weakened(mi, mj, &r, dist, st)
            } else {
                evaluate_spacing(mi, mj, &r, dist)
            }
        }
        Coupling::RepulsionOnly => {
            let res = evaluate_pair(
                &view(p[i], Vec3::zeros(), Vec3::zeros(), 0.0, mi),
                &view(p[j], Vec3::zeros(), Vec3::zeros(), 0.0, mj),
                Coupling::RepulsionOnly,
            );
            (res.energy, res.force_j)
        }
    };
    Some(SpacingPair { force_j, energy })
}

#[inline]
fn view(
    position: crate::math::Point3,
    normal: Vec3,
    tangent: Vec3,
    kappa: Real,
    material: &PreparedMaterial,
) -> ParticleView<'_> {
    ParticleView {
        position,
        normal,
        tangent,
        kappa,
        material,
    }
}

/// The oriented kernel's pair: the full interaction of the pair's coupling
/// (weakened by heat when `heated`) plus inter-particle friction; zero
/// beyond the cut-off.
#[allow(clippy::too_many_arguments)]
#[inline]
fn oriented_pair(
    a: &Attributes<'_>,
    materials: &[PreparedMaterial],
    bonds: &impl BondLookup,
    friction: bool,
    heated: bool,
    cutoff2: Real,
    normals: &[Vec3],
    tangents: &[Vec3],
    s: StateRef<'_>,
    i: usize,
    j: usize,
) -> Option<OrientedPair> {
    let p = s.positions;
    let r = p[j] - p[i];
    let d2 = r.norm_squared();
    if d2 > cutoff2 {
        return None;
    }
    let (mi, mj) = (
        &materials[a.materials[i] as usize],
        &materials[a.materials[j] as usize],
    );
    let c = coupling(a, bonds, i, j);
    let (vi, vj) = (
        view(p[i], normals[i], tangents[i], a.curvatures[i], mi),
        view(p[j], normals[j], tangents[j], a.curvatures[j], mj),
    );
    let res = if heated && matches!(c, Coupling::Complete { .. }) {
        evaluate_pair_weakened(&vi, &vj, c, strength(a, mi, mj, heated, i, j))
    } else {
        evaluate_pair(&vi, &vj, c)
    };
    let mut force_j = res.force_j;
    if friction && matches!(c, Coupling::Complete { .. }) {
        let v_rel = s.velocities[j] - s.velocities[i];
        force_j += friction_force(mi, mj, &r, d2.sqrt(), &v_rel);
    }
    Some(OrientedPair {
        force_j,
        torque_i: res.torque_i,
        torque_j: res.torque_j,
        energy: res.energy,
    })
}

/// Inter-particle friction (seed 002 §3, §5): damping of the relative
/// velocity of two particles. Applied along the line of centres (the
/// dissipative force of DPD), so it conserves linear *and* angular momentum;
/// weight `1 - r/r_c` over the spacing cut-off, coefficient the mean of the
/// two materials'. Returns the force on j (the force on i is its negative).
#[inline]
pub fn friction_force(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    r: &Vec3,
    dist: Real,
    v_rel: &Vec3,
) -> Vec3 {
    let gamma = 0.5 * (mi.friction() + mj.friction());
    let rc = mi.spacing_cutoff().max(mj.spacing_cutoff());
    if gamma == 0.0 || dist >= rc || dist == 0.0 {
        return Vec3::zeros();
    }
    let e = r / dist;
    -gamma * (1.0 - dist / rc) * v_rel.dot(&e) * e
}
