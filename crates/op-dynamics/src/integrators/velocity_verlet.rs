//! Velocity Verlet (Swope, Andersen, Berens & Wilson 1982, J. Chem. Phys.
//! 76, 637) with a second-order, time-reversible rotational part.
//!
//! Translation: half kick `v½ = v + ½h f/m`, drift `p₁ = p + h v½`, forces
//! at the new state, half kick `v₁ = v½ + ½h f₁/m`.
//!
//! Rotation, in terms of the WORLD angular momentum `L = R I Rᵀ ω` (the
//! Strang splitting "kick L by the torque / free rotation / kick" of
//! Dullweber, Leimkuhler & McLachlan 1997, J. Chem. Phys. 107, 5840, with a
//! different free-rotation solver):
//!
//! 1. half kick `L½ = L + ½h τ`;
//! 2. drift `q₁ = exp(h ω_m) q` where `ω_m = ω(q_m, L½)` is the angular
//!    velocity of momentum `L½` at the midpoint orientation
//!    `q_m = exp(½h ω_m) q` — an implicit-midpoint rule on the rotation
//!    group, solved by fixed-point iteration ([`midpoint_drift`]);
//! 3. forces and torques at the new state, half kick `L₁ = L½ + ½h τ₁`,
//!    `ω₁ = R₁ I⁻¹ R₁ᵀ L₁`.
//!
//! With `τ = 0` the momentum `L` is conserved exactly: `L` is carried from
//! step to step ([`Momenta`]) rather than recomputed from `ω`, so only the
//! kicks change it. Measured in `tests/issue_13_engine.rs`: a free
//! asymmetric body keeps `L` bit for bit over 200,000 steps. The total
//! angular momentum `Σ p × m v + R I Rᵀ ω` of interacting oriented
//! particles (whose pair forces and torques have no net moment) is
//! conserved in exact arithmetic; in floating point the round-off of the
//! position and velocity updates accumulates with the number of steps:
//! 1.8e-12 of `Σ |p × m v| + |R I Rᵀ ω|` (6e-11 of `|L|`, the orbital
//! terms largely cancelling) after 20,000 steps of 27 particles; the
//! drift is symmetric (running it backwards from `q₁` with `−h` returns
//! `q`), so the whole step is symmetric and therefore second order, with
//! the gyroscopic effect of an anisotropic inertia contained in the drift.
//!
//! Forces are evaluated once per step: the forces at the end of a step are
//! kept by the [`super::Integrator`] and reused for the next first half kick.
//! They are evaluated at the new positions and orientations with the
//! HALF-STEP velocities `v½` and `ω(q₁, L½)` (the end velocities depend on
//! them). Consequence: velocity-dependent forces (damping `−β v`, friction)
//! lag by half a step; their contribution is only first order in `h`
//! (measured in `convergence_tests`) and explicit, so the usual explicit
//! stability limit `β h / m ≲ 2` applies. Conservative forces keep second
//! order.

use super::rigid::{self, angular_momentum, angular_velocity_from_momentum};
use super::{per_particle, Bodies, ForceField, Particle, StateMut};
use crate::math::{rotate_by, Quat, Real, Vec3};

/// Fixed-point iterations of [`midpoint_drift`] at most.
const MAX_ITERATIONS: usize = 50;

/// The implicit-midpoint free-rotation drift over `h` with constant world
/// angular momentum `l`: returns `(q₁, ω_m)` with `q₁ = exp(h ω_m) q`,
/// `ω_m = R_m I⁻¹ R_mᵀ l`, `q_m = exp(½h ω_m) q`.
///
/// Solved by fixed-point iteration from `ω(q, l)` until the update is at
/// round-off level (or [`MAX_ITERATIONS`]). The iteration contracts when
/// `h |ω|` times the inertia anisotropy `I_max/I_min` is below about 1,
/// far beyond the steps at which the translational part is accurate.
/// `inertia` must not be locked (see [`rigid`]); a locked particle drifts
/// with `q₁ = exp(h ω) q` instead.
pub(crate) fn midpoint_drift(q: &Quat, l: &Vec3, inertia: &Vec3, h: Real) -> (Quat, Vec3) {
    let omega =
        |q: &Quat| angular_velocity_from_momentum(q, l, inertia).unwrap_or_else(Vec3::zeros);
    let mut w = omega(q);
    for _ in 0..MAX_ITERATIONS {
        let next = omega(&rotate_by(q, &(0.5 * h * w)));
        let change = (next - w).norm();
        w = next;
        if change <= 4.0 * Real::EPSILON * w.norm() {
            break;
        }
    }
    (rotate_by(q, &(h * w)), w)
}

/// Velocity Verlet's world angular momenta, carried from one step to the
/// next: converting `ω → L` at the start of every step would redo the
/// `L → ω` conversion of the previous step's end in reverse, and the
/// round-off of that round trip accumulates (8e-11 relative drift of a free
/// body's `L` after 200,000 steps, against none when `L` is carried).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct Momenta {
    /// Per particle: `L½` within a step, `L₁` after it.
    l: Vec<Vec3>,
    /// The angular velocity `ω₁` each `L₁` gave: a state whose `ω` differs
    /// was edited outside the integrator, and its `L` is recomputed.
    w: Vec<Vec3>,
    /// `l` and `w` hold the end of the last [`step_all`].
    valid: bool,
}

impl Momenta {
    /// Forgets the carried momenta (the next step recomputes them from ω).
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Moves the momenta with their particles ([`super::Integrator::permute`]).
    pub(crate) fn permute(&mut self, order: &[u32]) {
        if !(self.valid && self.l.len() == order.len() && self.w.len() == order.len()) {
            self.valid = false;
            return;
        }
        self.l = order.iter().map(|&k| self.l[k as usize]).collect();
        self.w = order.iter().map(|&k| self.w[k as usize]).collect();
    }
}

/// First half of a step for one particle: half kick with the force and
/// torque at `s`, drift. `momentum` is the world angular momentum carried
/// from the previous step, if any (else computed from `s.w`). Returns the
/// particle at the new position and orientation with the half-step
/// velocities, and its half-step world angular momentum `L½` (zero for a
/// rotationally locked particle).
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn kick_drift(
    s: &Particle,
    f: &Vec3,
    tau: &Vec3,
    inv_mass: Real,
    inertia: &Vec3,
    h: Real,
    momentum: Option<Vec3>,
) -> (Particle, Vec3) {
    let v = s.v + (0.5 * h * inv_mass) * f;
    let p = s.p + h * v;
    if s.w == Vec3::zeros() && *tau == Vec3::zeros() {
        // Not rotating and no torque: the rotational half is the identity
        // (L = 0, q unchanged) and is skipped, so spacing-only scenes do
        // not pay for frames they never turn.
        return (
            Particle {
                p,
                v,
                q: s.q,
                w: s.w,
            },
            Vec3::zeros(),
        );
    }
    if rigid::inverse_moments(inertia).is_none() {
        let q = rotate_by(&s.q, &(h * s.w));
        return (Particle { p, v, q, w: s.w }, Vec3::zeros());
    }
    let l = momentum.unwrap_or_else(|| angular_momentum(&s.q, &s.w, inertia)) + 0.5 * h * tau;
    let (mut q, _) = midpoint_drift(&s.q, &l, inertia, h);
    // Keep |q| = 1 to round-off: the L → ω conversions assume a unit
    // quaternion, and an unnormalized one scales ω (with L recomputed from
    // ω each step, L drifted by 9e-9 relative over 200,000 free-body steps).
    q.renormalize();
    let w = angular_velocity_from_momentum(&q, &l, inertia).unwrap_or(s.w);
    (Particle { p, v, q, w }, l)
}

/// Second half of a step for one particle: half kick of the output `s` of
/// [`kick_drift`] (momentum `l`) with the force and torque at the new state.
/// Returns the particle and its world angular momentum `L₁`.
#[inline]
pub(crate) fn kick(
    s: &Particle,
    l: &Vec3,
    f: &Vec3,
    tau: &Vec3,
    inv_mass: Real,
    inertia: &Vec3,
    h: Real,
) -> (Particle, Vec3) {
    let v = s.v + (0.5 * h * inv_mass) * f;
    if *l == Vec3::zeros() && *tau == Vec3::zeros() && s.w == Vec3::zeros() {
        return (Particle { v, ..*s }, Vec3::zeros());
    }
    let l1 = l + 0.5 * h * tau;
    let w = angular_velocity_from_momentum(&s.q, &l1, inertia).unwrap_or(s.w);
    (Particle { v, w, ..*s }, l1)
}

/// One velocity Verlet step of all particles. `forces`/`torques` hold the
/// forces at the current state when `cached`, and hold the forces at the
/// end of the step on return. Returns the number of force evaluations.
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_all<F: ForceField>(
    field: &mut F,
    bodies: &Bodies<'_>,
    t: Real,
    h: Real,
    mut state: StateMut<'_>,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    momenta: &mut Momenta,
    cached: bool,
) -> u32 {
    let n = state.len();
    let carried = momenta.valid && momenta.l.len() == n;
    momenta.l.resize(n, Vec3::zeros());
    momenta.w.resize(n, Vec3::zeros());
    momenta.valid = false;
    let mut evals = 0;
    if !cached {
        field.forces(t, state.view(), forces, torques);
        evals += 1;
    }
    // Per-particle kick and drift, in parallel (each particle reads and
    // writes only its own slots: the same bits at any thread count).
    let (f0, t0) = (&*forces, &*torques);
    per_particle::update_each(
        state.reborrow(),
        &mut momenta.l,
        &mut momenta.w,
        |i, s, l, w1| {
            if s.w == Vec3::zeros() && t0[i] == Vec3::zeros() {
                // Translation only (see `kick_drift`): p and v.
                s.v += (0.5 * h * bodies.inv_mass[i]) * f0[i];
                s.p += h * s.v;
                *l = Vec3::zeros();
                return;
            }
            let l0 = (carried && *w1 == s.w).then_some(*l);
            let (s1, l1) = kick_drift(
                s,
                &f0[i],
                &t0[i],
                bodies.inv_mass[i],
                &bodies.inertia[i],
                h,
                l0,
            );
            *s = s1;
            *l = l1;
        },
    );
    field.forces(t + h, state.view(), forces, torques);
    evals += 1;
    let (f1, t1) = (&*forces, &*torques);
    per_particle::update_each(
        state.reborrow(),
        &mut momenta.l,
        &mut momenta.w,
        |i, s, l, w1| {
            if *l == Vec3::zeros() && t1[i] == Vec3::zeros() && s.w == Vec3::zeros() {
                s.v += (0.5 * h * bodies.inv_mass[i]) * f1[i];
                *w1 = Vec3::zeros();
                return;
            }
            let (s1, l1) = kick(
                s,
                l,
                &f1[i],
                &t1[i],
                bodies.inv_mass[i],
                &bodies.inertia[i],
                h,
            );
            *s = s1;
            *l = l1;
            *w1 = s1.w;
        },
    );
    momenta.valid = true;
    evals
}

/// [`step_all`] for a state that never rotates (every angular velocity zero,
/// no torque): positions and velocities only. Same arguments, same result.
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_translation<F: ForceField>(
    field: &mut F,
    bodies: &Bodies<'_>,
    t: Real,
    h: Real,
    mut state: StateMut<'_>,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    momenta: &mut Momenta,
    cached: bool,
) -> u32 {
    // The rotational state is not followed: forget the momenta.
    momenta.invalidate();
    let mut evals = 0;
    if !cached {
        field.forces(t, state.view(), forces, torques);
        evals += 1;
    }
    let (f0, m) = (&*forces, bodies.inv_mass);
    per_particle::update_translation(state.reborrow(), |i, p, v| {
        *v += (0.5 * h * m[i]) * f0[i];
        *p += h * *v;
    });
    field.forces(t + h, state.view(), forces, torques);
    evals += 1;
    let f1 = &*forces;
    per_particle::update_translation(state.reborrow(), |i, _, v| {
        *v += (0.5 * h * m[i]) * f1[i];
    });
    evals
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::StateRef;
    use crate::math::Point3;

    /// Anharmonic springs to the origin, no torque.
    struct Springs;
    impl ForceField for Springs {
        fn forces(&mut self, _t: Real, s: StateRef<'_>, f: &mut [Vec3], tau: &mut [Vec3]) {
            for i in 0..f.len() {
                let x = s.positions[i].coords;
                f[i] = -x * (1.0 + x.norm_squared());
                tau[i] = Vec3::zeros();
            }
        }
    }

    #[test]
    fn translation_only_step_equals_the_general_step() {
        let n = 5;
        let mut p: Vec<Point3> = (0..n)
            .map(|k| Point3::new(k as Real * 0.3, 1.0 - k as Real * 0.2, 0.1))
            .collect();
        let mut v: Vec<Vec3> = (0..n)
            .map(|k| Vec3::new(0.1, -0.05 * k as Real, 0.2))
            .collect();
        let mut q = vec![Quat::from_scaled_axis(Vec3::new(0.2, 0.1, -0.3)); n];
        let mut w = vec![Vec3::zeros(); n];
        let (mut p2, mut v2, mut q2, mut w2) = (p.clone(), v.clone(), q.clone(), w.clone());
        let inv_mass = vec![0.7; n];
        let inertia = vec![Vec3::new(1.0, 2.0, 3.0); n];
        let bodies = Bodies {
            inv_mass: &inv_mass,
            inertia: &inertia,
        };
        let (mut f1, mut t1, mut m1) = (
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
            Momenta::default(),
        );
        let (mut f2, mut t2, mut m2) = (
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
            Momenta::default(),
        );
        for k in 0..50 {
            let t = k as Real * 0.01;
            let a = StateMut {
                positions: &mut p,
                velocities: &mut v,
                orientations: &mut q,
                angular_velocities: &mut w,
            };
            step_all(
                &mut Springs,
                &bodies,
                t,
                0.01,
                a,
                &mut f1,
                &mut t1,
                &mut m1,
                k > 0,
            );
            let b = StateMut {
                positions: &mut p2,
                velocities: &mut v2,
                orientations: &mut q2,
                angular_velocities: &mut w2,
            };
            step_translation(
                &mut Springs,
                &bodies,
                t,
                0.01,
                b,
                &mut f2,
                &mut t2,
                &mut m2,
                k > 0,
            );
        }
        assert_eq!(p, p2);
        assert_eq!(v, v2);
        assert_eq!(q, q2);
        assert_eq!(w, w2);
    }

    #[test]
    fn midpoint_drift_is_symmetric() {
        let q = Quat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8));
        let inertia = Vec3::new(1.0, 2.0, 3.0);
        let l = Vec3::new(1.5, -0.7, 2.2);
        let h = 0.05;
        let (q1, _) = midpoint_drift(&q, &l, &inertia, h);
        let (back, _) = midpoint_drift(&q1, &l, &inertia, -h);
        assert!(back.angle_to(&q) < 1e-14, "{}", back.angle_to(&q));
    }

    #[test]
    fn midpoint_drift_solves_its_equation() {
        let q = Quat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8));
        let inertia = Vec3::new(1.0, 2.0, 3.0);
        let l = Vec3::new(1.5, -0.7, 2.2);
        let h = 0.1;
        let (q1, w) = midpoint_drift(&q, &l, &inertia, h);
        let qm = rotate_by(&q, &(0.5 * h * w));
        let wm = angular_velocity_from_momentum(&qm, &l, &inertia).unwrap();
        assert!((wm - w).norm() < 1e-14);
        assert!(q1.angle_to(&rotate_by(&q, &(h * w))) < 1e-15);
    }

    #[test]
    fn torque_free_step_keeps_momentum_exactly() {
        let inertia = Vec3::new(1.0, 2.0, 3.0);
        let mut s = Particle {
            p: Default::default(),
            v: Vec3::zeros(),
            q: Quat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8)),
            w: Vec3::new(1.0, 0.4, -0.8),
        };
        let l0 = angular_momentum(&s.q, &s.w, &inertia);
        let z = Vec3::zeros();
        for _ in 0..1000 {
            let (s1, l) = kick_drift(&s, &z, &z, 1.0, &inertia, 0.01, None);
            s = kick(&s1, &l, &z, &z, 1.0, &inertia, 0.01).0;
        }
        let l1 = angular_momentum(&s.q, &s.w, &inertia);
        // Round-off only (about 1e-15 relative per step).
        assert!((l1 - l0).norm() < 1e-11 * l0.norm(), "{}", (l1 - l0).norm());
    }
}
