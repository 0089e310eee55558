//! The integrators driven through the public API only, the way the world
//! drives them: an external `ForceField`, `dt = min(dt_next, dt_frame)`,
//! `invalidate()` after changing the state from outside.

use op_dynamics::integrators::{
    rigid, AdaptiveParams, Bodies, ForceField, Integrator, Scheme, StateMut, StateRef,
};
use op_dynamics::{Point3, Quat, Real, Vec3};
use std::f64::consts::PI;

/// A spring to the origin (`½k|p|²`) and a torque pulling the body z axis
/// towards the world z axis (`k_a (1 − n·z)`).
struct SpringAndAlign {
    k: Real,
    k_align: Real,
}

impl SpringAndAlign {
    fn potential(&self, p: &Point3, q: &Quat) -> Real {
        0.5 * self.k * p.coords.norm_squared() + self.k_align * (1.0 - (q * Vec3::z()).z)
    }
}

impl ForceField for SpringAndAlign {
    fn forces(&mut self, _t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        for i in 0..s.positions.len() {
            forces[i] = -self.k * s.positions[i].coords;
            torques[i] = self.k_align * (s.orientations[i] * Vec3::z()).cross(&Vec3::z());
        }
    }
}

/// One particle of unit mass with anisotropic inertia.
struct One {
    p: [Point3; 1],
    v: [Vec3; 1],
    q: [Quat; 1],
    w: [Vec3; 1],
    inv_mass: [Real; 1],
    inertia: [Vec3; 1],
}

impl One {
    fn new() -> Self {
        One {
            p: [Point3::new(1.0, 0.0, 0.0)],
            v: [Vec3::new(0.0, 1.0, 0.0)],
            q: [Quat::from_scaled_axis(Vec3::new(0.4, 0.1, 0.0))],
            w: [Vec3::new(0.3, -0.2, 1.5)],
            inv_mass: [1.0],
            inertia: [Vec3::new(0.5, 0.8, 1.2)],
        }
    }

    fn parts(&mut self) -> (StateMut<'_>, Bodies<'_>) {
        (
            StateMut {
                positions: &mut self.p,
                velocities: &mut self.v,
                orientations: &mut self.q,
                angular_velocities: &mut self.w,
            },
            Bodies {
                inv_mass: &self.inv_mass,
                inertia: &self.inertia,
            },
        )
    }

    fn energy(&self, field: &SpringAndAlign) -> Real {
        0.5 * self.v[0].norm_squared()
            + rigid::rotational_kinetic_energy(&self.q[0], &self.w[0], &self.inertia[0])
            + field.potential(&self.p[0], &self.q[0])
    }
}

fn schemes() -> [Scheme; 5] {
    [
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
        Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-9)),
    ]
}

#[test]
fn every_scheme_closes_one_oscillation_period() {
    // With k = 1 the translation has period 2π: the particle comes back.
    let bounds = [0.1, 1e-3, 1e-3, 1e-8, 1e-9];
    for (scheme, bound) in schemes().into_iter().zip(bounds) {
        let mut one = One::new();
        let mut field = SpringAndAlign {
            k: 1.0,
            k_align: 2.0,
        };
        let mut integrator = Integrator::new(scheme);
        let (state, bodies) = one.parts();
        integrator.advance(&mut field, &bodies, 0.0, 2.0 * PI, 2.0 * PI / 400.0, state);
        let miss = (one.p[0] - Point3::new(1.0, 0.0, 0.0)).norm();
        eprintln!("{:>16}: miss after one period {miss:.2e}", scheme.name());
        assert!(miss < bound, "{}: {miss:e}", scheme.name());
    }
}

#[test]
fn long_verlet_run_keeps_unit_quaternions_and_bounded_energy() {
    let mut one = One::new();
    let mut field = SpringAndAlign {
        k: 1.0,
        k_align: 2.0,
    };
    let e0 = one.energy(&field);
    let mut integrator = Integrator::new(Scheme::VelocityVerlet);
    let dt = 0.01;
    let mut worst: Real = 0.0;
    for k in 0..100_000 {
        let (state, bodies) = one.parts();
        integrator.step(&mut field, &bodies, k as Real * dt, dt, state);
        if k % 100 == 0 {
            worst = worst.max((one.energy(&field) - e0).abs());
        }
    }
    let unit = (one.q[0].quaternion().norm() - 1.0).abs();
    eprintln!("verlet 1e5 steps: ||q| - 1| = {unit:.1e}, max |dE| = {worst:.2e} (E = {e0:.3})");
    assert!(unit < 1e-12, "||q| - 1| = {unit:e}");
    assert!(worst < 1e-3 * e0, "energy deviation {worst:e} of {e0}");
}

#[test]
fn world_style_adaptive_loop_with_an_external_kick() {
    let mut one = One::new();
    let mut field = SpringAndAlign {
        k: 1.0,
        k_align: 2.0,
    };
    let mut integrator = Integrator::new(Scheme::Adaptive(AdaptiveParams::default()));
    let (dt_frame, t_end): (Real, Real) = (0.25, 5.0);
    let (mut t, mut dt_next): (Real, Real) = (0.0, dt_frame);
    let mut kicked = false;
    while t < t_end {
        let dt = dt_next.min(dt_frame).min(t_end - t);
        let (state, bodies) = one.parts();
        let info = integrator.step(&mut field, &bodies, t, dt, state);
        assert!(info.dt_taken <= dt && info.tolerance_met());
        t += info.dt_taken;
        dt_next = info.dt_next;
        if !kicked && t > 2.0 {
            // A tool hits the particle: the cached forces are stale.
            one.v[0] += Vec3::new(0.0, 0.0, 3.0);
            integrator.invalidate();
            kicked = true;
        }
    }
    assert!(
        kicked && t >= t_end - 1e-12 && t <= t_end + 1e-12,
        "t = {t}"
    );
    assert!(one.p[0]
        .iter()
        .chain(one.w[0].iter())
        .all(|x| x.is_finite()));
}
