//! Symplectic (semi-implicit) Euler: kick, then drift with the new
//! velocities (Hairer, Lubich & Wanner, "Geometric Numerical Integration",
//! 2006, §I.1.2; the usual game-physics integrator).
//!
//! `v₁ = v + h f/m`, `ω₁ = ω + h ω̇(q, ω, τ)`, then `p₁ = p + h v₁`,
//! `q₁ = exp(h ω₁) q`. Forces, torques and the gyroscopic term are taken at
//! the old state. First order; for separable translational problems it is
//! symplectic (bounded energy error), the explicit gyroscopic term makes the
//! rotational part merely first order.

use super::rigid;
use super::Particle;
use crate::math::{rotate_by, Real, Vec3};

/// One symplectic Euler step of one particle, given the force and torque at
/// its current state.
#[inline]
pub(crate) fn step(
    s: &Particle,
    f: &Vec3,
    tau: &Vec3,
    inv_mass: Real,
    inertia: &Vec3,
    h: Real,
) -> Particle {
    let alpha = rigid::angular_acceleration(&s.q, &s.w, tau, inertia);
    let v = s.v + (h * inv_mass) * f;
    let w = s.w + h * alpha;
    Particle {
        p: s.p + h * v,
        v,
        q: rotate_by(&s.q, &(h * w)),
        w,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Quat};

    #[test]
    fn drifts_with_the_new_velocities() {
        let s = Particle {
            p: Point3::origin(),
            v: Vec3::zeros(),
            q: Quat::identity(),
            w: Vec3::zeros(),
        };
        let f = Vec3::new(2.0, 0.0, 0.0);
        let tau = Vec3::new(0.0, 0.0, 3.0);
        let n = step(&s, &f, &tau, 0.5, &Vec3::repeat(1.5), 0.1);
        assert!((n.v - Vec3::new(0.1, 0.0, 0.0)).norm() < 1e-15);
        assert!((n.p - Point3::new(0.01, 0.0, 0.0)).norm() < 1e-15);
        assert!((n.w - Vec3::new(0.0, 0.0, 0.2)).norm() < 1e-15);
        assert!((n.q.angle() - 0.02).abs() < 1e-15);
    }
}
