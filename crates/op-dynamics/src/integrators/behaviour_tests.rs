//! Behaviour tests of [`Integrator`]: unit quaternions, locked particles,
//! force caching, stage times, and the adaptive controller (step limits,
//! rejections, determinism, the `dt_min` floor).

use super::test_problem::{Free, Smooth, System};
use super::{AdaptiveParams, Bodies, ForceField, Integrator, Scheme, StateRef, StepInfo};
use crate::math::{Point3, Quat, Real, Vec3};

fn all_schemes() -> [Scheme; 5] {
    [
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
        Scheme::Adaptive(AdaptiveParams::default()),
    ]
}

#[test]
fn quaternions_stay_unit() {
    for scheme in all_schemes() {
        let mut sys = System::three();
        // Explicit Euler gains energy: a shorter run keeps it bounded.
        let (dt, steps) = if scheme == Scheme::ExplicitEuler {
            (0.002, 20_000)
        } else {
            (0.01, 20_000)
        };
        sys.run(scheme, &mut Smooth::default(), dt, steps, |_, _| {});
        let drift = sys
            .orientations
            .iter()
            .map(|q| (q.quaternion().norm() - 1.0).abs())
            .fold(0.0, Real::max);
        eprintln!(
            "{:>16}: {steps} steps, max ||q| - 1| = {drift:.1e}",
            scheme.name()
        );
        assert!(drift < 1e-12, "{}: |q| - 1 = {drift:e}", scheme.name());
    }
}

/// A constant force and torque on every particle.
struct Push;

impl ForceField for Push {
    fn forces(&mut self, _t: Real, _s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        forces.fill(Vec3::new(1.0, 2.0, 3.0));
        torques.fill(Vec3::new(0.5, -1.0, 2.0));
    }
}

#[test]
fn locked_particles_never_accelerate() {
    let inf = Real::INFINITY;
    let n = 4;
    let q0 = Quat::from_scaled_axis(Vec3::new(0.2, 0.1, -0.3));
    for scheme in all_schemes() {
        let mut sys = System {
            positions: vec![Point3::new(1.0, 2.0, 3.0); n],
            velocities: vec![Vec3::zeros(); n],
            orientations: vec![q0; n],
            angular_velocities: vec![Vec3::zeros(); n],
            inv_mass: vec![1.0, 0.0, 0.0, 0.0],
            inertia: vec![
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::repeat(inf),
                Vec3::zeros(),
                Vec3::new(1.0, inf, 1.0),
            ],
        };
        let start = sys.clone();
        sys.run(scheme, &mut Push, 0.01, 100, |_, _| {});
        assert!(
            sys.positions[0] != start.positions[0] && sys.orientations[0] != start.orientations[0]
        );
        for i in 1..n {
            assert_eq!(
                sys.positions[i],
                start.positions[i],
                "{} particle {i}",
                scheme.name()
            );
            assert_eq!(sys.velocities[i], Vec3::zeros());
            assert_eq!(sys.angular_velocities[i], Vec3::zeros());
            assert!(sys.orientations[i].angle_to(&q0) < 1e-15);
        }
    }
}

#[test]
fn empty_state_is_fine() {
    for scheme in all_schemes() {
        let mut sys = System {
            positions: vec![],
            velocities: vec![],
            orientations: vec![],
            angular_velocities: vec![],
            inv_mass: vec![],
            inertia: vec![],
        };
        let mut integrator = Integrator::new(scheme);
        let info = sys.step(&mut integrator, &mut Free, 0.0, 0.1);
        assert_eq!(info.dt_taken, 0.1);
    }
}

#[test]
fn verlet_reuses_end_of_step_forces() {
    let mut cached = System::three();
    let mut fresh = System::three();
    let mut a = Integrator::new(Scheme::VelocityVerlet);
    let mut b = Integrator::new(Scheme::VelocityVerlet);
    let dt = 0.01;
    for k in 0..200 {
        let t = k as Real * dt;
        let info = cached.step(&mut a, &mut Smooth::default(), t, dt);
        assert_eq!(info.force_evaluations, if k == 0 { 2 } else { 1 });
        b.invalidate_forces();
        assert_eq!(
            fresh
                .step(&mut b, &mut Smooth::default(), t, dt)
                .force_evaluations,
            2
        );
    }
    // Position-only forces: reusing them changes nothing, to the bit.
    assert_eq!(cached, fresh);
}

/// `F = (cos t, 0, 0)` on a unit mass: `v(t) = sin t`.
struct Forcing;

impl ForceField for Forcing {
    fn forces(&mut self, t: Real, _s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        forces.fill(Vec3::new(t.cos(), 0.0, 0.0));
        torques.fill(Vec3::zeros());
    }
}

#[test]
fn forces_are_evaluated_at_stage_times() {
    let bounds = [5e-3, 5e-3, 1e-5, 1e-10, 1e-8];
    for (scheme, bound) in all_schemes().into_iter().zip(bounds) {
        let mut sys = System::tumbling();
        sys.velocities[0] = Vec3::zeros();
        let mut integrator = Integrator::new(scheme);
        let (state, bodies) = sys.split();
        integrator.advance(&mut Forcing, &bodies, 0.0, 1.0, 0.01, state);
        let err = (sys.velocities[0].x - Real::sin(1.0)).abs();
        assert!(err < bound, "{}: {err:e}", scheme.name());
    }
}

#[test]
fn advance_lands_on_the_end_time() {
    let mut sys = System::three();
    let mut integrator = Integrator::new(Scheme::VelocityVerlet);
    let (state, bodies) = sys.split();
    let info = integrator.advance(&mut Smooth::default(), &bodies, 0.0, 0.35, 0.1, state);
    assert_eq!(info.steps, 4);
    assert_eq!(info.max_error_norm, None);
    let mut manual = System::three();
    let mut integrator = Integrator::new(Scheme::VelocityVerlet);
    for (t, dt) in [
        (0.0, 0.1),
        (0.1, 0.1),
        (0.2, 0.1),
        (0.30000000000000004, 0.35 - 0.30000000000000004),
    ] {
        manual.step(&mut integrator, &mut Smooth::default(), t, dt);
    }
    assert_eq!(sys, manual);
}

#[test]
fn scheme_names_orders_and_validation() {
    let names: Vec<_> = all_schemes()
        .iter()
        .map(|s| (s.name(), s.order()))
        .collect();
    assert_eq!(
        names,
        [
            ("explicit_euler", 1),
            ("symplectic_euler", 1),
            ("velocity_verlet", 2),
            ("rk4", 4),
            ("adaptive", 5)
        ]
    );
    let integrator = Integrator::new(Scheme::Rk4);
    assert_eq!(integrator.scheme(), Scheme::Rk4);
}

#[test]
#[should_panic(expected = "adaptive.dt_min")]
fn new_panics_on_invalid_parameters() {
    Integrator::new(Scheme::Adaptive(AdaptiveParams {
        dt_min: -1.0,
        ..Default::default()
    }));
}

/// Adaptive steps of the smooth problem with requested steps alternating
/// between 0.05 and 0.003: the record of every step.
fn adaptive_record() -> (System, Vec<StepInfo>) {
    let mut sys = System::three();
    let mut integrator = Integrator::new(Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-7)));
    let mut t = 0.0;
    let mut record = Vec::new();
    for k in 0..300 {
        let dt = if k % 7 == 6 { 0.003 } else { 0.05 };
        let info = sys.step(&mut integrator, &mut Smooth::default(), t, dt);
        assert!(info.dt_taken <= dt, "step {k}: {} > {dt}", info.dt_taken);
        assert!(info.tolerance_met());
        t += info.dt_taken;
        record.push(info);
    }
    (sys, record)
}

#[test]
fn adaptive_never_exceeds_dt_and_is_deterministic() {
    let (a, record_a) = adaptive_record();
    let (b, record_b) = adaptive_record();
    assert_eq!(a, b);
    assert_eq!(record_a, record_b);
    // FSAL: 6 evaluations per attempt, plus one at the very first step.
    for (k, info) in record_a.iter().enumerate() {
        let first = if k == 0 { 1 } else { 0 };
        assert_eq!(
            info.force_evaluations,
            first + 6 * (info.rejected + 1),
            "step {k}"
        );
    }
    // A step clipped to 0.003 does not shrink the next proposal.
    assert!(record_a[6].dt_taken == 0.003 && record_a[7].dt_taken > 0.01);
}

/// A stiff exponential wall at `x = 1`: `U = A exp((x − 1)/δ)`.
struct Wall {
    strength: Real,
    width: Real,
}

impl Wall {
    fn potential(&self, s: StateRef<'_>) -> Real {
        s.positions
            .iter()
            .map(|p| self.strength * ((p.x - 1.0) / self.width).exp())
            .sum()
    }
}

impl ForceField for Wall {
    fn forces(&mut self, _t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        for (f, p) in forces.iter_mut().zip(s.positions) {
            *f = Vec3::new(
                -self.strength / self.width * ((p.x - 1.0) / self.width).exp(),
                0.0,
                0.0,
            );
        }
        torques.fill(Vec3::zeros());
    }
}

#[test]
fn adaptive_rejects_steps_on_a_stiff_transient() {
    let mut wall = Wall {
        strength: 1e-3,
        width: 2e-3,
    };
    let mut sys = System::tumbling();
    sys.velocities[0] = Vec3::new(1.0, 0.2, 0.0);
    let energy = |s: &System, w: &Wall| s.kinetic() + w.potential(s.view());
    let e0 = energy(&sys, &wall);
    let mut integrator = Integrator::new(Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-8)));
    let (dt, mut t) = (0.1, 0.0);
    let (mut rejected, mut smallest, mut largest) = (0, Real::INFINITY, 0.0);
    while t < 2.0 {
        let info = sys.step(&mut integrator, &mut wall, t, dt);
        assert!(info.dt_taken <= dt && info.tolerance_met());
        rejected += info.rejected;
        smallest = info.dt_taken.min(smallest);
        largest = info.dt_taken.max(largest);
        t += info.dt_taken;
    }
    let drift = (energy(&sys, &wall) - e0).abs() / e0;
    eprintln!("wall: {rejected} rejections, steps in [{smallest:.2e}, {largest:.2e}], energy drift {drift:.1e}");
    assert!(rejected > 0);
    assert!(smallest < 1e-3 && largest == dt);
    assert!(
        (sys.velocities[0].x + 1.0).abs() < 1e-5,
        "{}",
        sys.velocities[0].x
    );
    assert!(drift < 1e-5, "{drift}");
}

#[test]
fn adaptive_accepts_dt_min_when_the_tolerance_is_unreachable() {
    let params = AdaptiveParams {
        dt_min: 0.01,
        ..AdaptiveParams::with_tolerance(1e-15)
    };
    let mut sys = System::three();
    let mut integrator = Integrator::new(Scheme::Adaptive(params));
    let bodies = Bodies {
        inv_mass: &sys.inv_mass.clone(),
        inertia: &sys.inertia.clone(),
    };
    let (state, _) = sys.split();
    let info = integrator.step(&mut Smooth::default(), &bodies, 0.0, 0.1, state);
    assert_eq!(info.dt_taken, 0.01);
    assert_eq!(info.dt_next, 0.01);
    assert!(info.rejected >= 1 && !info.tolerance_met(), "{info:?}");
    assert!(sys
        .positions
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite())));
}
