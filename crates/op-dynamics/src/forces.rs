//! Internal force evaluation: every pair visited once, both `E_ij` and
//! `E_ji` evaluated there (DESIGN §3), in parallel with results bitwise
//! identical at any thread count.
//!
//! The scheme is "parallel map, ordered collect" (STYLE): the half neighbour
//! list is flat, so a parallel pass over *pairs* writes each pair's result
//! into its own slot of a pair buffer; a second parallel pass over
//! *particles* gathers, in a fixed order, the contributions of the pairs
//! where the particle is first (its row) and then of those where it is
//! second (the transposed index). No locks, no atomics, no scheduling
//! dependence, no allocation once the buffers are sized.
//!
//! Two kernels are compiled and one is chosen when the world is built
//! (pay for what you use): [`Kernel::Spacing`] touches positions only;
//! [`Kernel::Oriented`] evaluates the full oriented interaction.

use rayon::prelude::*;

use crate::external::{ExternalAccumulator, ExternalParams};
use crate::flags::Flags;
use crate::integrators::StateRef;
use crate::interactions::{
    evaluate_pair, evaluate_spacing, Coupling, ParticleView, PreparedMaterial,
};
use crate::math::{Real, Vec3};
use crate::neighbours::NeighbourList;
use crate::particles::Attributes;

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
    spacing_pairs: Vec<[Real; 4]>,
    oriented_pairs: Vec<OrientedPair>,
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

/// Everything the internal force evaluation reads besides the state.
pub(crate) struct ForceContext<'a> {
    pub kernel: Kernel,
    pub attributes: Attributes<'a>,
    pub materials: &'a [PreparedMaterial],
    pub friction: bool,
    pub neighbours: Option<&'a mut NeighbourList>,
    pub external: &'a ExternalParams,
    pub accumulator: &'a ExternalAccumulator,
    pub scratch: &'a mut ForceScratch,
}

impl crate::integrators::ForceField for ForceContext<'_> {
    fn forces(&mut self, t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        self.evaluate(t, s, forces, torques);
    }
}

impl ForceContext<'_> {
    /// Computes forces, torques and the potential energy at state `s`.
    pub fn evaluate(
        &mut self,
        t: Real,
        s: StateRef<'_>,
        forces: &mut [Vec3],
        torques: &mut [Vec3],
    ) {
        let n = s.positions.len();
        let sc = &mut *self.scratch;
        sc.evaluations += 1;
        sc.energies.resize(n, 0.0);
        match (self.kernel, self.neighbours.as_deref_mut()) {
            (Kernel::None, _) | (_, None) => {
                forces.iter_mut().for_each(|f| *f = Vec3::zeros());
                torques.iter_mut().for_each(|t| *t = Vec3::zeros());
                sc.energies.iter_mut().for_each(|e| *e = 0.0);
            }
            (kernel, Some(list)) => {
                let clock = std::time::Instant::now();
                list.update(s.positions);
                sc.neighbour_seconds += clock.elapsed().as_secs_f64();
                refresh_sources(sc, list);
                match kernel {
                    Kernel::Spacing => spacing_pass(sc, list, &self.attributes, self.materials, s),
                    _ => {
                        oriented_pass(sc, list, &self.attributes, self.materials, self.friction, s)
                    }
                }
                gather(sc, list, kernel, forces, torques);
            }
        }
        sc.potential = sc.energies.iter().sum();
        self.add_external(t, s, forces, torques);
    }

    /// Gravity, force windows, damping, pending accumulator; fixed
    /// particles get zero force / torque (seed 000 eq. 12-13).
    fn add_external(&self, t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        let g = self.external.gravity();
        let b0 = self.external.linear_damping;
        let b1 = self.external.angular_damping;
        let a = &self.attributes;
        let acc = self.accumulator;
        forces
            .par_iter_mut()
            .zip(torques.par_iter_mut())
            .enumerate()
            .for_each(|(i, (f, tq))| {
                *f += a.masses[i] * g - b0 * s.velocities[i];
                *tq -= b1 * s.angular_velocities[i];
                if acc.is_active() {
                    let (fe, te) = acc.get(a.ids[i]);
                    *f += fe;
                    *tq += te;
                }
            });
        for w in &self.external.forces {
            let k = w.factor(t);
            if k != 0.0 {
                let fw = k * Vec3::from(w.force);
                for &id in &w.particles {
                    forces[a.slot_of[id as usize] as usize] += fw;
                }
            }
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
fn refresh_sources(sc: &mut ForceScratch, list: &NeighbourList) {
    if sc.sources_for == list.rebuilds() && sc.sources.len() == list.pairs().num_pairs() {
        return;
    }
    let pairs = list.pairs();
    sc.sources.clear();
    for i in 0..pairs.len() {
        let r = pairs.row_range(i);
        sc.sources.extend(std::iter::repeat_n(i as u32, r.len()));
    }
    sc.sources_for = list.rebuilds();
}

/// Coupling of two particles: object membership, then typing, then
/// orientation (seed 002 §5; unoriented particles drop orientation terms).
#[inline]
fn coupling(a: &Attributes<'_>, i: usize, j: usize) -> Coupling {
    if a.objects[i] != a.objects[j] || !a.kinds[i].complete_with(a.kinds[j]) {
        Coupling::RepulsionOnly
    } else {
        let oriented =
            !(a.flags[i].contains(Flags::UNORIENTED) || a.flags[j].contains(Flags::UNORIENTED));
        Coupling::Complete { oriented }
    }
}

fn spacing_pass(
    sc: &mut ForceScratch,
    list: &NeighbourList,
    a: &Attributes<'_>,
    materials: &[PreparedMaterial],
    s: StateRef<'_>,
) {
    let pairs = list.pairs();
    let nbrs = pairs.neighbours();
    let cutoff2 = list.cutoff() * list.cutoff();
    sc.spacing_pairs.resize(nbrs.len(), [0.0; 4]);
    let src = &sc.sources;
    let p = s.positions;
    sc.spacing_pairs
        .par_iter_mut()
        .with_min_len(256)
        .enumerate()
        .for_each(|(k, out)| {
            let i = src[k] as usize;
            let j = nbrs[k] as usize;
            let r = p[j] - p[i];
            let d2 = r.norm_squared();
            if d2 > cutoff2 {
                *out = [0.0; 4];
                return;
            }
            let dist = d2.sqrt();
            let (mi, mj) = (
                &materials[a.materials[i] as usize],
                &materials[a.materials[j] as usize],
            );
            let (e, f) = match coupling(a, i, j) {
                Coupling::Complete { .. } => evaluate_spacing(mi, mj, &r, dist),
                Coupling::RepulsionOnly => {
                    let res = evaluate_pair(
                        &view(p[i], Vec3::zeros(), Vec3::zeros(), 0.0, mi),
                        &view(p[j], Vec3::zeros(), Vec3::zeros(), 0.0, mj),
                        Coupling::RepulsionOnly,
                    );
                    (res.energy, res.force_j)
                }
            };
            *out = [f.x, f.y, f.z, e];
        });
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

fn oriented_pass(
    sc: &mut ForceScratch,
    list: &NeighbourList,
    a: &Attributes<'_>,
    materials: &[PreparedMaterial],
    friction: bool,
    s: StateRef<'_>,
) {
    let n = s.positions.len();
    sc.normals.resize(n, Vec3::zeros());
    sc.tangents.resize(n, Vec3::zeros());
    sc.normals
        .par_iter_mut()
        .zip(sc.tangents.par_iter_mut())
        .enumerate()
        .for_each(|(i, (nv, tv))| {
            let q = &s.orientations[i];
            *nv = q * a.normal_axes[i];
            *tv = q * a.tangent_axes[i];
        });
    let pairs = list.pairs();
    let nbrs = pairs.neighbours();
    let cutoff2 = list.cutoff() * list.cutoff();
    sc.oriented_pairs
        .resize(nbrs.len(), OrientedPair::default());
    let (src, normals, tangents) = (&sc.sources, &sc.normals, &sc.tangents);
    let p = s.positions;
    sc.oriented_pairs
        .par_iter_mut()
        .with_min_len(128)
        .enumerate()
        .for_each(|(k, out)| {
            let i = src[k] as usize;
            let j = nbrs[k] as usize;
            let r = p[j] - p[i];
            let d2 = r.norm_squared();
            if d2 > cutoff2 {
                *out = OrientedPair::default();
                return;
            }
            let (mi, mj) = (
                &materials[a.materials[i] as usize],
                &materials[a.materials[j] as usize],
            );
            let c = coupling(a, i, j);
            let res = evaluate_pair(
                &view(p[i], normals[i], tangents[i], a.curvatures[i], mi),
                &view(p[j], normals[j], tangents[j], a.curvatures[j], mj),
                c,
            );
            let mut force_j = res.force_j;
            if friction && matches!(c, Coupling::Complete { .. }) {
                force_j +=
                    friction_force(mi, mj, &r, d2.sqrt(), &(s.velocities[j] - s.velocities[i]));
            }
            *out = OrientedPair {
                force_j,
                torque_i: res.torque_i,
                torque_j: res.torque_j,
                energy: res.energy,
            };
        });
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

/// Sums each particle's pair contributions in a fixed order: its row first
/// (it is `i`: force `-F_j`, torque `tau_i`), then the incoming pairs (it
/// is `j`: `F_j`, `tau_j`).
fn gather(
    sc: &mut ForceScratch,
    list: &NeighbourList,
    kernel: Kernel,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
) {
    let pairs = list.pairs();
    let (sp, op) = (&sc.spacing_pairs, &sc.oriented_pairs);
    forces
        .par_iter_mut()
        .zip(torques.par_iter_mut())
        .zip(sc.energies.par_iter_mut())
        .enumerate()
        .with_min_len(256)
        .for_each(|(i, ((f, t), e))| {
            let mut fo = Vec3::zeros();
            let mut to = Vec3::zeros();
            let mut eo = 0.0;
            match kernel {
                Kernel::Spacing => {
                    for k in pairs.row_range(i) {
                        let o = &sp[k];
                        fo -= Vec3::new(o[0], o[1], o[2]);
                        eo += o[3];
                    }
                    for &k in pairs.incoming(i) {
                        let o = &sp[k as usize];
                        fo += Vec3::new(o[0], o[1], o[2]);
                    }
                }
                _ => {
                    for k in pairs.row_range(i) {
                        let o = &op[k];
                        fo -= o.force_j;
                        to += o.torque_i;
                        eo += o.energy;
                    }
                    for &k in pairs.incoming(i) {
                        let o = &op[k as usize];
                        fo += o.force_j;
                        to += o.torque_j;
                    }
                }
            }
            *f = fo;
            *t = to;
            *e = eo;
        });
}
