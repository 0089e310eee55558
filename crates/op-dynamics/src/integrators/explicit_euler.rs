//! Forward (explicit) Euler, the seeds' integrator (seed 000 §4.1, after
//! Press et al. 1988, "Numerical Recipes" §16.1), kept as the baseline.
//!
//! Every update uses the OLD state only:
//! `p₁ = p + h v`, `v₁ = v + h f/m`, `q₁ = exp(h ω) q`,
//! `ω₁ = ω + h ω̇(q, ω, τ)` (Euler's equations, [`rigid::angular_acceleration`]).
//! First order; on conservative problems its energy grows steadily (by a
//! factor `≈ 1 + h²Ω²` per step for an oscillation of frequency `Ω`).

use super::rigid;
use super::Particle;
use crate::math::{rotate_by, Real, Vec3};

/// One explicit Euler step of one particle, given the force and torque at
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
    Particle {
        p: s.p + h * s.v,
        v: s.v + (h * inv_mass) * f,
        q: rotate_by(&s.q, &(h * s.w)),
        w: s.w + h * alpha,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Point3, Quat};

    #[test]
    fn uses_only_the_old_state() {
        let s = Particle {
            p: Point3::new(1.0, 2.0, 3.0),
            v: Vec3::new(0.5, 0.0, -1.0),
            q: Quat::identity(),
            w: Vec3::new(0.0, 0.0, 2.0),
        };
        let f = Vec3::new(2.0, 0.0, 0.0);
        let n = step(&s, &f, &Vec3::zeros(), 0.5, &Vec3::repeat(1.0), 0.1);
        assert!((n.p - Point3::new(1.05, 2.0, 2.9)).norm() < 1e-15);
        assert!((n.v - Vec3::new(0.6, 0.0, -1.0)).norm() < 1e-15);
        assert!((n.q.angle() - 0.2).abs() < 1e-15);
        assert_eq!(n.w, s.w);
    }
}
