//! Time integrators for oriented particles (docs/model.md §4, seed 000 §4).
//!
//! Each particle is a rigid body with position `p`, velocity `v`,
//! orientation unit quaternion `q` (a full frame), WORLD-frame angular
//! velocity `ω`, inverse mass and diagonal BODY-frame inertia. The equations
//! of motion (seed 000 §4, eq. 12-13 and the Newton–Euler equations below
//! them) are
//!
//! ```text
//! ṗ = v,   v̇ = f / m,   q̇ = ω̂ q,   ω̇ = R I⁻¹ Rᵀ (τ − ω × (R I Rᵀ ω))
//! ```
//!
//! the last one being Euler's equations with the gyroscopic term, see
//! [`rigid::angular_acceleration`]. The orientation is always advanced on the
//! unit sphere by the quaternion exponential ([`crate::math::rotate_by`]),
//! never by adding to `q`.
//!
//! | [`Scheme`] | order | force evaluations per step | file |
//! |---|---|---|---|
//! | [`Scheme::ExplicitEuler`] | 1 | 1 | `explicit_euler.rs` |
//! | [`Scheme::SymplecticEuler`] | 1 | 1 | `symplectic_euler.rs` |
//! | [`Scheme::VelocityVerlet`] | 2 (1 with velocity-dependent forces) | 1 (cached) | `velocity_verlet.rs` |
//! | [`Scheme::Rk4`] | 4 | 4 | `rk4.rs` |
//! | [`Scheme::Adaptive`] | 5(4) | 6 per attempt (FSAL) | `adaptive.rs` |
//!
//! The world supplies forces through [`ForceField`]; the [`Integrator`] owns
//! only scratch buffers (sized on first use or when the particle count
//! changes, then reused: no allocation per step) and, for velocity Verlet
//! and the adaptive scheme, the forces at the end of the previous step,
//! reused by the next step until [`Integrator::invalidate`] is called.
//!
//! **Fixed and locked particles.** Fixed particles are the world's business
//! (it returns zero force, torque and velocities for them). A particle with
//! `inv_mass == 0` does not accelerate; a particle whose inertia has a moment
//! that is 0, infinite or not finite is rotationally locked: torques do not
//! change its angular velocity (see [`rigid`]). Neither produces NaN as long
//! as its force and torque are finite.

mod adaptive;
mod explicit_euler;
pub(crate) mod per_particle;
pub mod rigid;
mod rk4;
mod rkmk;
mod symplectic_euler;
mod velocity_verlet;

#[cfg(test)]
mod behaviour_tests;
#[cfg(test)]
mod convergence_tests;
#[cfg(test)]
mod test_problem;

pub use adaptive::AdaptiveParams;

use crate::error::ParamError;
use crate::math::{Point3, Quat, Real, Vec3};
use rkmk::RkBuffers;

/// Read-only view of the dynamic state of all particles (structure of
/// arrays, all slices of the same length).
#[derive(Clone, Copy, Debug)]
pub struct StateRef<'a> {
    /// Positions `p`.
    pub positions: &'a [Point3],
    /// Linear velocities `v`.
    pub velocities: &'a [Vec3],
    /// Orientations `q` (unit quaternions, body to world).
    pub orientations: &'a [Quat],
    /// Angular velocities `ω`, world frame.
    pub angular_velocities: &'a [Vec3],
}

/// Mutable view of the dynamic state of all particles (structure of arrays,
/// all slices of the same length).
#[derive(Debug)]
pub struct StateMut<'a> {
    /// Positions `p`.
    pub positions: &'a mut [Point3],
    /// Linear velocities `v`.
    pub velocities: &'a mut [Vec3],
    /// Orientations `q` (unit quaternions, body to world).
    pub orientations: &'a mut [Quat],
    /// Angular velocities `ω`, world frame.
    pub angular_velocities: &'a mut [Vec3],
}

/// Per-particle mass properties.
#[derive(Clone, Copy, Debug)]
pub struct Bodies<'a> {
    /// Inverse masses `1/m`: finite and `>= 0`; `0` means infinite mass (the
    /// particle never accelerates).
    pub inv_mass: &'a [Real],
    /// Principal moments of inertia `(I_x, I_y, I_z)` in the body frame.
    /// If any moment is `0`, infinite or not finite, the particle is
    /// rotationally locked: torques never change its angular velocity (see
    /// [`rigid`]).
    pub inertia: &'a [Vec3],
}

/// The source of forces and torques (implemented by the world).
pub trait ForceField {
    /// World-frame force and torque on every particle at state `s` and time
    /// `t` (velocity-dependent forces such as damping included). Overwrites
    /// `forces`/`torques`.
    fn forces(&mut self, t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]);
}

/// The time-stepping method.
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub enum Scheme {
    /// Forward (explicit) Euler, the seeds' choice (seed 000 §4.1, after
    /// Press et al. 1988, "Numerical Recipes" §16.1): every update from the
    /// old state. First order; kept as the papers' baseline. Its energy
    /// grows steadily on conservative problems.
    ExplicitEuler,
    /// Symplectic (semi-implicit) Euler: kick the velocities with the old
    /// forces, then drift positions and orientations with the NEW
    /// velocities (Hairer, Lubich & Wanner, "Geometric Numerical
    /// Integration", 2006, §I.1.2). First order.
    SymplecticEuler,
    /// Velocity Verlet (Swope, Andersen, Berens & Wilson 1982, J. Chem.
    /// Phys. 76) for the translation. For the rotation, the same
    /// kick-drift-kick splitting on the world angular momentum `L`
    /// (Dullweber, Leimkuhler & McLachlan 1997, J. Chem. Phys. 107): half
    /// kick `L += ½h τ`; drift `q₁ = exp(h ω_m) q` with `ω_m` the angular
    /// velocity of `L` at the midpoint orientation `exp(½h ω_m) q`
    /// (implicit midpoint on the rotation group, solved by fixed-point
    /// iteration, which converges while `h‖ω‖·I_max/I_min` is below about
    /// 1); half kick with the new torque. The gyroscopic effect lives in the
    /// drift; torque-free `L` is conserved to round-off.
    ///
    /// Second order and time-reversible for velocity-independent forces.
    /// One force evaluation per step: the end-of-step forces are reused by
    /// the next step (see [`Integrator::invalidate`]). They are evaluated
    /// with the half-step velocities, so velocity-dependent forces (damping,
    /// friction) lag half a step: with them the scheme is first order and
    /// their treatment explicit (stable for `β h / m ≲ 2`). Details in
    /// `velocity_verlet.rs`.
    VelocityVerlet,
    /// Classical fourth-order Runge–Kutta (Kutta 1901) on `p, v, ω`, and its
    /// Runge–Kutta–Munthe-Kaas version on the orientation (Munthe-Kaas 1999,
    /// "High order Runge–Kutta methods on manifolds", Appl. Numer. Math.
    /// 29): stage orientations `exp(θ_k) q`, with `θ_k` built from the stage
    /// angular velocities through `dexp⁻¹` truncated after its second-order
    /// term ([`rigid::dexp_inv`]). Four force evaluations per step.
    Rk4,
    /// Embedded Dormand–Prince 5(4) pair (Dormand & Prince 1980, J. Comput.
    /// Appl. Math. 6) in the same Munthe-Kaas form as [`Scheme::Rk4`], with
    /// error control, step rejection and the standard controller (Hairer,
    /// Nørsett & Wanner, "Solving ODEs I", §II.4); the error norm, its
    /// units and the controller are documented on [`AdaptiveParams`].
    /// Seven stages, the last one reused as the next step's first (FSAL):
    /// six force evaluations per attempt.
    Adaptive(AdaptiveParams),
}

impl Scheme {
    /// Checks the scheme's parameters (only [`Scheme::Adaptive`] has any).
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Scheme::Adaptive(p) => p.validate().map_err(|e| e.within("adaptive")),
            _ => Ok(()),
        }
    }

    /// A short lower-case name for reports: `explicit_euler`,
    /// `symplectic_euler`, `velocity_verlet`, `rk4`, `adaptive`.
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::ExplicitEuler => "explicit_euler",
            Scheme::SymplecticEuler => "symplectic_euler",
            Scheme::VelocityVerlet => "velocity_verlet",
            Scheme::Rk4 => "rk4",
            Scheme::Adaptive(_) => "adaptive",
        }
    }

    /// The order of accuracy for smooth, velocity-independent forces
    /// (the adaptive scheme reports the order of the solution it keeps, 5).
    pub fn order(&self) -> u32 {
        match self {
            Scheme::ExplicitEuler | Scheme::SymplecticEuler => 1,
            Scheme::VelocityVerlet => 2,
            Scheme::Rk4 => 4,
            Scheme::Adaptive(_) => 5,
        }
    }
}

/// What one call of [`Integrator::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// The step actually taken (`== dt` for fixed-step schemes, `<= dt` for
    /// the adaptive scheme).
    pub dt_taken: Real,
    /// The suggested next step (`dt` for fixed-step schemes; the error
    /// controller's proposal, within `[dt_min, dt_max]`, for the adaptive
    /// scheme).
    pub dt_next: Real,
    /// Attempts rejected by the error control before the accepted one.
    pub rejected: u32,
    /// Calls of [`ForceField::forces`] made by this step.
    pub force_evaluations: u32,
    /// The adaptive scheme's error norm of the accepted step (tolerance met
    /// when `<= 1`; see [`AdaptiveParams`]); `None` for fixed-step schemes.
    /// A value above 1 means the step was forced through at `dt_min`.
    pub error_norm: Option<Real>,
}

impl StepInfo {
    /// False only when the adaptive scheme had to accept a step at `dt_min`
    /// with its error still above the tolerance.
    pub fn tolerance_met(&self) -> bool {
        self.error_norm.is_none_or(|e| e <= 1.0)
    }
}

/// One particle's dynamic state (used by the per-scheme kernels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Particle {
    pub p: Point3,
    pub v: Vec3,
    pub q: Quat,
    pub w: Vec3,
}

impl StateRef<'_> {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there is no particle.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    fn assert_consistent(&self) {
        let n = self.len();
        assert!(
            self.velocities.len() == n
                && self.orientations.len() == n
                && self.angular_velocities.len() == n,
            "state slices have different lengths"
        );
    }

    #[inline]
    pub(crate) fn particle(&self, i: usize) -> Particle {
        Particle {
            p: self.positions[i],
            v: self.velocities[i],
            q: self.orientations[i],
            w: self.angular_velocities[i],
        }
    }
}

impl StateMut<'_> {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there is no particle.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// A read-only view of the same state.
    pub fn view(&self) -> StateRef<'_> {
        StateRef {
            positions: self.positions,
            velocities: self.velocities,
            orientations: self.orientations,
            angular_velocities: self.angular_velocities,
        }
    }

    /// A shorter-lived mutable view of the same state.
    pub fn reborrow(&mut self) -> StateMut<'_> {
        StateMut {
            positions: self.positions,
            velocities: self.velocities,
            orientations: self.orientations,
            angular_velocities: self.angular_velocities,
        }
    }

    #[inline]
    pub(crate) fn set(&mut self, i: usize, s: Particle) {
        self.positions[i] = s.p;
        self.velocities[i] = s.v;
        self.orientations[i] = s.q;
        self.angular_velocities[i] = s.w;
    }
}

/// Steps the particle state with a [`Scheme`].
///
/// Owns only scratch buffers (state lives in the world), the forces cached at
/// the end of the previous step (velocity Verlet, and the FSAL stage of the
/// adaptive scheme) and the adaptive scheme's suggested step.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Integrator {
    scheme: Scheme,
    /// Forces and torques: the last evaluation, and between steps the cache.
    forces: Vec<Vec3>,
    torques: Vec<Vec3>,
    /// True when `forces`/`torques` hold the forces at the end of the last
    /// step (valid input for the next step's first stage / half kick).
    cache_valid: bool,
    /// Verlet: world angular momenta, carried from step to step.
    momenta: velocity_verlet::Momenta,
    /// Runge–Kutta stage state and derivatives.
    rk: RkBuffers,
    /// Adaptive: the step proposed by the controller after the last step.
    dt_suggested: Option<Real>,
    /// The caller guarantees no particle rotates and no torque acts
    /// (see [`Integrator::set_translation_only`]).
    translation_only: bool,
}

impl Integrator {
    /// An integrator for `scheme`, with empty buffers (sized at the first
    /// step).
    ///
    /// # Panics
    ///
    /// If [`Scheme::validate`] fails (use [`Integrator::try_new`] to get the
    /// error instead).
    pub fn new(scheme: Scheme) -> Self {
        match Self::try_new(scheme) {
            Ok(i) => i,
            Err(e) => panic!("invalid integrator scheme: {e}"),
        }
    }

    /// An integrator for `scheme`, or the reason its parameters are invalid.
    pub fn try_new(scheme: Scheme) -> Result<Self, ParamError> {
        scheme.validate()?;
        Ok(Self {
            scheme,
            forces: Vec::new(),
            torques: Vec::new(),
            cache_valid: false,
            momenta: velocity_verlet::Momenta::default(),
            rk: RkBuffers::default(),
            dt_suggested: None,
            translation_only: false,
        })
    }

    /// The scheme this integrator runs.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// Forget cached forces (Verlet and the adaptive scheme reuse the forces
    /// from the end of the previous step, Verlet also the angular momenta;
    /// the world calls this when the state or forces changed outside the
    /// integrator). The adaptive step
    /// suggestion is kept: a bad guess only costs a rejected attempt.
    pub fn invalidate(&mut self) {
        self.cache_valid = false;
        self.momenta.invalidate();
    }

    /// Follows a reordering of the particles (new slot `s` holds the
    /// particle of old slot `order[s]`, [`crate::Particles::permute`]) that
    /// changed nothing else: velocity Verlet's cached forces, torques and
    /// angular momenta move with their particles instead of being
    /// recomputed (other schemes forget their cache, as
    /// [`Integrator::invalidate`]).
    pub fn permute(&mut self, order: &[u32]) {
        fn apply(v: &mut Vec<Vec3>, order: &[u32]) {
            if v.len() == order.len() {
                *v = order.iter().map(|&k| v[k as usize]).collect();
            }
        }
        let n = order.len();
        let verlet = matches!(self.scheme, Scheme::VelocityVerlet);
        if verlet && self.cache_valid && self.forces.len() == n && self.torques.len() == n {
            apply(&mut self.forces, order);
            apply(&mut self.torques, order);
        } else {
            self.cache_valid = false;
        }
        self.momenta.permute(order);
    }

    /// Forget the cached forces only: the force field changed (external
    /// forces cleared, curvatures or temperatures updated) but the state
    /// did not, so velocity Verlet keeps carrying its angular momenta.
    pub fn invalidate_forces(&mut self) {
        self.cache_valid = false;
    }

    /// Declares that, until further notice, every angular velocity is zero
    /// and the force field produces no torque (a spacing-only world without
    /// spin). Velocity Verlet then updates positions and velocities only,
    /// without reading the rotational state: the same result, less memory
    /// traffic. Other schemes ignore the flag.
    pub fn set_translation_only(&mut self, on: bool) {
        self.translation_only = on;
    }

    /// Advances the state by `dt` (fixed-step schemes) or by at most `dt`
    /// (adaptive: retries with smaller steps while the error is above
    /// tolerance, never exceeds `dt`, returns the suggested next step).
    ///
    /// Stages, by scheme: Euler variants evaluate the forces at the old
    /// state then update; velocity Verlet half-kicks with the cached (or
    /// freshly evaluated) forces, drifts, evaluates the forces at the new
    /// positions and orientations (with the half-step velocities), and
    /// half-kicks again; RK4 evaluates four stages and combines them; the
    /// adaptive scheme evaluates seven stages (the first reused from the
    /// previous step's last), estimates the error, and accepts or retries.
    ///
    /// The adaptive scheme tries `min(dt, dt_max, previous suggestion)`
    /// first (or `min(dt, dt_max)` on its first step), never goes below
    /// `min(dt_min, dt)`, and accepts a step at that floor even when its
    /// error is still too large ([`StepInfo::tolerance_met`] is then false).
    ///
    /// # Panics
    ///
    /// If `dt` is not finite and positive, or the slices of `state` and
    /// `bodies` do not all have the same length.
    pub fn step<F: ForceField>(
        &mut self,
        field: &mut F,
        bodies: &Bodies<'_>,
        t: Real,
        dt: Real,
        state: StateMut<'_>,
    ) -> StepInfo {
        self.prepare_step(bodies, dt, &state);
        let fixed = |evals| StepInfo {
            dt_taken: dt,
            dt_next: dt,
            rejected: 0,
            force_evaluations: evals,
            error_norm: None,
        };
        match self.scheme {
            Scheme::ExplicitEuler | Scheme::SymplecticEuler => {
                self.euler_step(field, bodies, t, dt, state);
                fixed(1)
            }
            Scheme::VelocityVerlet => {
                let step = if self.translation_only {
                    velocity_verlet::step_translation
                } else {
                    velocity_verlet::step_all
                };
                let evals = step(
                    field,
                    bodies,
                    t,
                    dt,
                    state,
                    &mut self.forces,
                    &mut self.torques,
                    &mut self.momenta,
                    self.cache_valid,
                );
                self.cache_valid = true;
                fixed(evals)
            }
            Scheme::Rk4 => {
                let evals = rk4::step_all(
                    field,
                    bodies,
                    t,
                    dt,
                    state,
                    &mut self.forces,
                    &mut self.torques,
                    &mut self.rk,
                );
                self.cache_valid = false;
                fixed(evals)
            }
            Scheme::Adaptive(params) => {
                let info = adaptive::step_all(
                    &params,
                    field,
                    bodies,
                    t,
                    dt,
                    state,
                    &mut self.forces,
                    &mut self.torques,
                    &mut self.rk,
                    self.cache_valid,
                    self.dt_suggested,
                );
                self.cache_valid = true;
                self.dt_suggested = Some(info.dt_next);
                info
            }
        }
    }

    /// Checks the arguments of [`Integrator::step`] and sizes the force
    /// and torque buffers to the particles (forgetting the cache when they
    /// change size).
    fn prepare_step(&mut self, bodies: &Bodies<'_>, dt: Real, state: &StateMut<'_>) {
        assert!(
            dt.is_finite() && dt > 0.0,
            "time step must be finite and > 0, got {dt}"
        );
        let n = state.len();
        state.view().assert_consistent();
        assert!(
            bodies.inv_mass.len() == n && bodies.inertia.len() == n,
            "bodies and state have different lengths"
        );
        if self.forces.len() != n {
            self.forces.resize(n, Vec3::zeros());
            self.torques.resize(n, Vec3::zeros());
            self.cache_valid = false;
        }
    }

    /// One explicit or symplectic Euler step: the forces at the old state,
    /// then each particle updated by the scheme's kernel.
    fn euler_step<F: ForceField>(
        &mut self,
        field: &mut F,
        bodies: &Bodies<'_>,
        t: Real,
        dt: Real,
        mut state: StateMut<'_>,
    ) {
        let n = state.len();
        field.forces(t, state.view(), &mut self.forces, &mut self.torques);
        let kernel = if self.scheme == Scheme::ExplicitEuler {
            explicit_euler::step
        } else {
            symplectic_euler::step
        };
        for i in 0..n {
            let s = state.view().particle(i);
            let (f, tau) = (&self.forces[i], &self.torques[i]);
            let new = kernel(&s, f, tau, bodies.inv_mass[i], &bodies.inertia[i], dt);
            state.set(i, new);
        }
        self.cache_valid = false;
    }

    /// Advances the state by exactly `duration` with repeated calls of
    /// [`Integrator::step`]: steps of `dt` for fixed-step schemes (the last
    /// one shortened to land on `t + duration`; a remainder within `1e-12 dt`
    /// of `dt` is taken as one step), or as many adaptive steps as needed,
    /// each at most `dt` and the last one clipped to the end time.
    ///
    /// # Panics
    ///
    /// As [`Integrator::step`], or if `duration` is negative or not finite.
    pub fn advance<F: ForceField>(
        &mut self,
        field: &mut F,
        bodies: &Bodies<'_>,
        t: Real,
        duration: Real,
        dt: Real,
        mut state: StateMut<'_>,
    ) -> AdvanceInfo {
        assert!(
            duration.is_finite() && duration >= 0.0,
            "duration must be finite and >= 0, got {duration}"
        );
        let end = t + duration;
        let mut now = t;
        let mut total = AdvanceInfo {
            steps: 0,
            rejected: 0,
            force_evaluations: 0,
            max_error_norm: None,
            dt_next: dt,
        };
        while now < end {
            let remaining = end - now;
            let h = if remaining <= dt * (1.0 + 1e-12) {
                remaining
            } else {
                dt
            };
            let info = self.step(field, bodies, now, h, state.reborrow());
            now = if info.dt_taken == remaining {
                end
            } else {
                now + info.dt_taken
            };
            total.steps += 1;
            total.rejected += info.rejected;
            total.force_evaluations += info.force_evaluations;
            total.dt_next = info.dt_next;
            total.max_error_norm = match (total.max_error_norm, info.error_norm) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
        }
        total
    }
}

/// What one call of [`Integrator::advance`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdvanceInfo {
    /// Accepted steps taken.
    pub steps: u32,
    /// Rejected attempts, in total.
    pub rejected: u32,
    /// Calls of [`ForceField::forces`], in total.
    pub force_evaluations: u32,
    /// The largest error norm of the accepted adaptive steps (`None` for
    /// fixed-step schemes or when no step was taken).
    pub max_error_norm: Option<Real>,
    /// The last step suggestion (`dt` when no step was taken).
    pub dt_next: Real,
}
