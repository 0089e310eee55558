//! Bond memory: a bonded lattice that remembers where each partner sits in
//! each particle's own frame, and its plastic flow (seed 000 §8, fig. 12b).
//!
//! Seed 000 §8 shows a plastic surface (fig. 12b) and cites Terzopoulos &
//! Fleischer 1988 ("Modeling inelastic deformations: viscoelasticity,
//! plasticity, fracture") for it: there the rest *metric* and the rest
//! *curvature* of a deformable surface flow towards the current ones once
//! the deformation exceeds a yield limit. An oriented particle carries a
//! frame, so both can be remembered at once, per bond, as the partner's
//! position seen from the particle's frame (its *rest offset*): its length
//! is the bond's rest length (the metric), its direction against the
//! particle's normal is the bend of the surface there (the curvature,
//! whatever its direction; a crease is as easy to hold as a sphere).
//!
//! **Energy.** Each end `i` of a bond `(i, j)` whose material has a
//! [`BondMemory`] remembers the offset `d_ij` (body frame of `i`) and
//! contributes
//!
//! `E_ij = k_i/2 |r - R_i d_ij|²`,  `r = p_j - p_i`,
//!
//! with `R_i` the rotation of `i`'s orientation (body to world) and `k_i`
//! its material's `stiffness`. With `u = R_i d_ij` and `e = r - u`, the
//! gradients give (derived in [`emitted`], checked against finite
//! differences in the tests):
//!
//! - force on `j`: `-k e`, on `i`: `+k e` (equal and opposite);
//! - torque on `i`: `k u × r` (a rotation `δθ` of `i` moves `u` by
//!   `δθ × u`, `δE = -k e·(δθ × u) = -δθ·(k u × e)`, and `u × e = u × r`).
//!
//! Linear momentum is conserved pairwise, and so is angular momentum:
//! `p_i × k e - p_j × k e + k u × e = -k (r - u) × e = 0`. The energy
//! depends on `r` and `R_i` only through `R_iᵀ r`, so it is the same in
//! any rotated or translated frame. Both ends of a bond contribute their
//! own term, so a bond between two memory particles is held from both
//! sides.
//!
//! Bending is soft and transverse shear stiff, as in a thin plate: a
//! neighbourhood that bends with curvature `c` turns its frames with it
//! and leaves an offset error of second order, `c |r|²/2`, along the
//! normal; a neighbour displaced across the surface without the frames
//! turning leaves a first-order error.
//!
//! **Rest state.** Offsets are taken from the state in which a bond forms
//! ([`crate::bonds`]: when the world is built, or when one of its particles
//! is inserted), so a new lattice is at rest in the shape it is built in.
//!
//! **Flow** ([`OffsetFlow`]). After each step, every remembered offset
//! whose current value `c = R_iᵀ r` lies farther than `yield_offset` from
//! it moves towards it: with `e = c - d`, the excess `|e| - y` relaxes at
//! `rate`, integrated exactly over the step with `c` held,
//!
//! `d ← d + (1 - e^{-rate h}) (|e| - y) e/|e|`,
//!
//! a viscoplastic (Perzyna-type) return mapping of the vector offset, the
//! vector form of the scalar one of [`crate::plasticity`]: it never passes
//! the yield surface `|c - d| = y`, and a large `rate` returns to it within
//! a step (rate-independent plasticity). Within the band the lattice is
//! elastic, so what a deformation leaves behind springs back by at most
//! about `y` per bond. The flow changes the energy landscape between
//! steps: energy is not conserved across a plastic step, by design.
//!
//! **Determinism.** Forces are added in bond order (sorted by particle id)
//! into each particle's sum, one serial pass after the pair kernel; the
//! flow updates each remembered offset from the state alone. The same bits
//! at any thread count and slot order.
//!
//! **Cost.** Only worlds with a memory material run it: one pass over the
//! bonds per force evaluation, and one per step for the flow.
//!
//! **Not included.** Heat ([`crate::heat`]) does not weaken the memory,
//! and a bond that breaks ([`crate::bonds`]) forgets its offsets for good.

use serde::{Deserialize, Serialize};

use crate::bonds::Bonds;
use crate::error::{non_negative, positive, ParamError};
use crate::integrators::StateRef;
use crate::interactions::PreparedMaterial;
use crate::math::{Quat, Real, Vec3};
use crate::particles::{live_slot, Attributes, Particles};

/// A bonded lattice's memory of its shape: each bonded partner's offset in
/// the particle's own frame (its rest length and its tilt against the
/// particle's normal), held by a spring of `stiffness` and, when `flow` is
/// given, following the current offset beyond a yield, so the lattice
/// keeps the shape it is pushed into (a plastic surface, seed 000 fig.
/// 12b). The offsets are taken when the bonds form.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BondMemory {
    /// Stiffness `k` of the remembered offsets (force per length, finite
    /// and > 0): the energy of one end of a bond is `k/2 |r - R d|²`, `r`
    /// the partner's offset now and `R d` the remembered one turned with
    /// the particle.
    pub stiffness: Real,
    /// Plastic flow of the remembered offsets, or `None` (the default) for
    /// an elastic memory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flow: Option<OffsetFlow>,
}

/// Plastic flow of remembered offsets: where the current offset of a
/// bonded partner is farther than `yield_offset` from the remembered one,
/// the remembered one moves towards it at `rate` until it is
/// `yield_offset` away; within that band the lattice is elastic.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OffsetFlow {
    /// Yield offset `y` (length, finite, >= 0): a current offset within `y`
    /// of the remembered one deforms elastically. 0 makes every
    /// deformation flow.
    pub yield_offset: Real,
    /// Rate (1/time, finite, > 0) at which the excess beyond the yield
    /// relaxes: the remembered offset reaches the yield surface with time
    /// constant `1 / rate`.
    pub rate: Real,
}

impl BondMemory {
    /// Rejects NaN, infinite and out-of-range values, naming the field.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("stiffness", self.stiffness)?;
        if let Some(f) = &self.flow {
            f.validate().map_err(|e| e.within("flow"))?;
        }
        Ok(())
    }
}

impl OffsetFlow {
    /// Rejects NaN, infinite and out-of-range values, naming the field.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("yield_offset", self.yield_offset)?;
        positive("rate", self.rate)
    }

    /// The remembered offset `d` after a step of length `dt` with current
    /// offset `current` (the return mapping of the module docs). Unchanged
    /// (the same bits) within the yield band.
    #[inline]
    pub fn relax(&self, d: Vec3, current: Vec3, dt: Real) -> Vec3 {
        let e = current - d;
        let len = e.norm();
        let y = self.yield_offset;
        if len <= y {
            return d;
        }
        d + e * ((1.0 - (-self.rate * dt).exp()) * (len - y) / len)
    }
}

/// What one end `i` of a bond contributes (module docs).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Emitted {
    /// `k/2 |r - R_i d|²`.
    pub energy: Real,
    /// Force on `i` (the force on `j` is its negative).
    pub force_i: Vec3,
    /// Torque on `i` (none on `j`).
    pub torque_i: Vec3,
}

/// The term of end `i` with stiffness `k`, orientation `q_i`, remembered
/// offset `d` (body frame) and `r = p_j - p_i`.
#[inline]
pub fn emitted(k: Real, q_i: &Quat, d: &Vec3, r: &Vec3) -> Emitted {
    let u = q_i * d;
    let e = r - u;
    Emitted {
        energy: 0.5 * k * e.norm_squared(),
        force_i: e * k,
        torque_i: u.cross(r) * k,
    }
}

/// The offset of `r` in the body frame of orientation `q`.
#[inline]
pub fn offset(q: &Quat, r: &Vec3) -> Vec3 {
    q.inverse_transform_vector(r)
}

/// The memory of the material of slot `i`, if any.
#[inline]
fn memory_of<'m>(
    a: &Attributes<'_>,
    materials: &'m [PreparedMaterial],
    i: usize,
) -> Option<&'m BondMemory> {
    materials[a.materials[i] as usize].bond_memory()
}

/// The rest offsets of a bond `(lower id, higher id)` formed now: the
/// higher one seen from the lower one's frame, and the reverse.
pub(crate) fn rest_offsets(particles: &Particles, lo: usize, hi: usize) -> [Vec3; 2] {
    let (p, q) = (particles.positions(), particles.orientations());
    let r = p[hi] - p[lo];
    [offset(&q[lo], &r), offset(&q[hi], &-r)]
}

/// Adds every bond end's memory term at state `s` to the forces, torques
/// and energies (each end's energy to its own particle), in bond order.
pub(crate) fn add_forces(
    bonds: &Bonds,
    materials: &[PreparedMaterial],
    a: &Attributes<'_>,
    s: StateRef<'_>,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    energies: &mut [Real],
) {
    for (&(lo, hi), rest) in bonds.pairs().iter().zip(bonds.rest_offsets()) {
        let (Some(i), Some(j)) = (live_slot(a.slot_of, lo), live_slot(a.slot_of, hi)) else {
            continue;
        };
        let r = s.positions[j] - s.positions[i];
        for (e, f, d, r) in [(i, j, &rest[0], r), (j, i, &rest[1], -r)] {
            if let Some(m) = memory_of(a, materials, e) {
                let t = emitted(m.stiffness, &s.orientations[e], d, &r);
                forces[e] += t.force_i;
                forces[f] -= t.force_i;
                torques[e] += t.torque_i;
                energies[e] += t.energy;
            }
        }
    }
}

/// The flow stage (module docs): every remembered offset of a flowing
/// memory relaxes towards the current one over `dt`. Returns true when
/// some offset changed.
pub(crate) fn flow(
    bonds: &mut Bonds,
    particles: &Particles,
    materials: &[PreparedMaterial],
    dt: Real,
) -> bool {
    let a = particles.attributes();
    let (p, q) = (particles.positions(), particles.orientations());
    let mut changed = false;
    let (pairs, rest) = bonds.pairs_and_rest_mut();
    for (&(lo, hi), rest) in pairs.iter().zip(rest.iter_mut()) {
        let (Some(i), Some(j)) = (live_slot(a.slot_of, lo), live_slot(a.slot_of, hi)) else {
            continue;
        };
        let r = p[j] - p[i];
        let [d_lo, d_hi] = rest;
        for (e, d, r) in [(i, d_lo, r), (j, d_hi, -r)] {
            if let Some(rule) = memory_of(&a, materials, e).and_then(|m| m.flow.as_ref()) {
                let new = rule.relax(*d, offset(&q[e], &r), dt);
                changed |= new != *d;
                *d = new;
            }
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::test_support::Rng;
    use nalgebra::{Unit, UnitQuaternion};

    fn random_quat(rng: &mut Rng) -> Quat {
        UnitQuaternion::from_axis_angle(
            &Unit::new_normalize(rng.unit_vector()),
            rng.range(-3.0, 3.0),
        )
    }

    #[test]
    fn forces_and_torques_are_the_energy_gradients() {
        let mut rng = Rng::new(21);
        for _ in 0..50 {
            let k = rng.range(0.5, 200.0);
            let q = random_quat(&mut rng);
            let d = rng.unit_vector() * rng.range(0.5, 1.5);
            let r = rng.unit_vector() * rng.range(0.5, 1.5);
            let t = emitted(k, &q, &d, &r);
            let h = 1e-6;
            let scale = 1.0 + t.force_i.norm() + t.torque_i.norm();
            for axis in 0..3 {
                let mut dv = Vec3::zeros();
                dv[axis] = h;
                // Moving j by dv changes r by +dv: force on j = -dE/dr.
                let de = (emitted(k, &q, &d, &(r + dv)).energy
                    - emitted(k, &q, &d, &(r - dv)).energy)
                    / (2.0 * h);
                assert!((de - t.force_i[axis]).abs() < 1e-6 * scale, "force {axis}");
                // Turning i by a small rotation about the axis.
                let turn =
                    |s: Real| UnitQuaternion::from_axis_angle(&Unit::new_normalize(dv), s * h) * q;
                let de = (emitted(k, &turn(1.0), &d, &r).energy
                    - emitted(k, &turn(-1.0), &d, &r).energy)
                    / (2.0 * h);
                assert!(
                    (-de - t.torque_i[axis]).abs() < 1e-6 * scale,
                    "torque {axis}"
                );
            }
        }
    }

    #[test]
    fn internal_forces_conserve_momentum_and_angular_momentum() {
        let mut rng = Rng::new(22);
        for _ in 0..50 {
            let k = rng.range(0.5, 200.0);
            let (q_i, q_j) = (random_quat(&mut rng), random_quat(&mut rng));
            let (d_ij, d_ji) = (rng.unit_vector(), rng.unit_vector());
            let p_i = rng.unit_vector() * 3.0;
            let p_j = p_i + rng.unit_vector() * rng.range(0.5, 1.5);
            let r = p_j - p_i;
            let a = emitted(k, &q_i, &d_ij, &r);
            let b = emitted(k, &q_j, &d_ji, &-r);
            let (f_i, f_j) = (a.force_i - b.force_i, b.force_i - a.force_i);
            assert!((f_i + f_j).norm() < 1e-12);
            let l = p_i.cross(&f_i) + p_j.cross(&f_j) + a.torque_i + b.torque_i;
            assert!(l.norm() < 1e-10 * (1.0 + f_i.norm()), "{l}");
        }
    }

    #[test]
    fn at_rest_in_the_state_it_remembers_in_any_frame() {
        let mut rng = Rng::new(23);
        let q = random_quat(&mut rng);
        let r = rng.unit_vector();
        let d = offset(&q, &r);
        let t = emitted(50.0, &q, &d, &r);
        assert!(t.energy < 1e-24 && t.force_i.norm() < 1e-12 && t.torque_i.norm() < 1e-12);
        // The same bond turned and moved as a whole is still at rest.
        let turn = random_quat(&mut rng);
        let t = emitted(50.0, &(turn * q), &d, &(turn * r));
        assert!(t.energy < 1e-24 && t.force_i.norm() < 1e-12 && t.torque_i.norm() < 1e-12);
    }

    #[test]
    fn flow_stops_at_the_yield_surface_and_not_before() {
        let rule = OffsetFlow {
            yield_offset: 0.1,
            rate: 10.0,
        };
        let d = Vec3::new(1.0, 0.0, 0.0);
        // Within the band: the same bits.
        let inside = Vec3::new(1.05, 0.05, 0.0);
        assert_eq!(rule.relax(d, inside, 0.01), d);
        // Beyond it: towards the current offset, along the difference,
        // never past the yield surface, and onto it after a long time.
        let current = Vec3::new(1.0, 0.5, 0.0);
        let mut m = d;
        let mut last = (current - m).norm();
        for _ in 0..200 {
            m = rule.relax(m, current, 0.01);
            let gap = (current - m).norm();
            assert!(gap < last || (gap - 0.1).abs() < 1e-9);
            assert!(gap >= 0.1 - 1e-12, "{gap}");
            assert!(m.x == 1.0 && m.z == 0.0);
            last = gap;
        }
        assert!((last - 0.1).abs() < 1e-6, "{last}");
        // One step of length h moves the excess by 1 - exp(-rate h).
        let one = rule.relax(d, current, 0.05);
        let moved = (one - d).norm();
        assert!((moved - (1.0 - (-0.5 as Real).exp()) * 0.4).abs() < 1e-12);
    }

    #[test]
    fn validation_names_the_field() {
        let bad = BondMemory {
            stiffness: 0.0,
            flow: None,
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("stiffness"));
        let bad = BondMemory {
            stiffness: 1.0,
            flow: Some(OffsetFlow {
                yield_offset: -1.0,
                rate: 1.0,
            }),
        };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("flow.yield_offset"), "{e}");
        let bad = BondMemory {
            stiffness: 1.0,
            flow: Some(OffsetFlow {
                yield_offset: 0.0,
                rate: Real::NAN,
            }),
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("flow.rate"));
    }
}
