//! Coulomb friction of a skinned particle on a rigid collider.
//!
//! Seed 002 §6 gives the skin's contact with a rigid collider only its
//! normal reaction: the skin inside the collider is pushed out along its
//! normal ([`crate::ObstacleContact`]), so a skin rests on a
//! level collider but slides down any slope and off any edge its overhang
//! drags it over. Coulomb's law adds the tangential reaction: a contact
//! pressed by the normal reaction `N` resists sliding with a force of at
//! most `μ |N|` opposite the sliding velocity, and sticks (no sliding)
//! while the force needed to hold it is below that bound.
//!
//! **Per particle.** The normal reaction of a skinned particle is its
//! share of the contact energy's gradient ([`crate::Reactions`]), `N_i`, along the
//! collider normals where it touches. Its sliding velocity is its velocity
//! relative to the collider's material point at the particle, less its
//! component along `N_i`: `v_t`. The friction force is
//!
//! `F_i = -min(μ |N_i|, m_i |v_t| / h) v_t / |v_t|`,
//!
//! applied at the particle over the contact interval `h` (the skin contact
//! is explicit: one evaluation per interval of at most `dt`). The first
//! bound is Coulomb's; the second is the force that brings `v_t` to zero
//! over the interval, so friction never reverses the sliding (no chatter
//! about `v_t = 0`): a particle whose sliding the bound can stop is
//! stopped each interval, and the forces that act during the interval
//! (gravity along a slope, say) leave it creeping at most their
//! acceleration times `h` (measured in `tests/skin_friction.rs`).
//! Friction acts along the collider's tangent plane only, never pulls, and
//! dissipates energy: `F_i · v_t <= 0`.
//!
//! **Normal damping.** The obstacle's `damping` acts on a pressed skinned
//! particle as on a particle the obstacle touches directly: `-c (v·n) n`
//! ([`normal_damping`]), so a skin dropped on a collider comes to rest on
//! it instead of bouncing (the explicit penalty reaction keeps a bounce
//! going).

use op_dynamics::{Real, Vec3};

/// The friction force on a particle of mass `mass` pressed on a collider
/// by the normal reaction `normal`, sliding at `velocity` relative to the
/// collider, with coefficient `mu` over an interval `h` (module docs).
/// Zero without a normal reaction, a positive mass and interval, or
/// sliding.
pub fn coulomb(normal: Vec3, velocity: Vec3, mass: Real, mu: Real, h: Real) -> Vec3 {
    let load = normal.norm();
    if !(load > 0.0 && mu > 0.0 && mass > 0.0 && h > 0.0) {
        return Vec3::zeros();
    }
    let n = normal / load;
    let tangential = velocity - n * velocity.dot(&n);
    let speed = tangential.norm();
    if !(speed > 0.0 && speed.is_finite()) {
        return Vec3::zeros();
    }
    let magnitude = (mu * load).min(mass * speed / h);
    -tangential * (magnitude / speed)
}

/// The damping of the normal velocity of a particle pressed on a
/// collider by `normal`, moving at `velocity` relative to it, with
/// coefficient `c`: `-c (v·n) n` along the unit normal `n` of the
/// reaction, as a penalty obstacle damps the particles it touches
/// (`op_modeling::tools::Role::Obstacle`), limited so that the total normal
/// force, reaction included, never pulls: at most `|N|` against the
/// reaction. Dissipative, not from an energy. Zero without a reaction.
pub fn normal_damping(normal: Vec3, velocity: Vec3, c: Real) -> Vec3 {
    let load = normal.norm();
    if !(load > 0.0 && c > 0.0) {
        return Vec3::zeros();
    }
    let n = normal / load;
    let along = (-c * velocity.dot(&n)).max(-load);
    n * along
}

#[cfg(test)]
mod tests {
    use super::*;

    const N: Vec3 = Vec3::new(0.0, 0.0, 2.0);

    #[test]
    fn sliding_fast_meets_the_coulomb_bound_against_the_tangential_velocity() {
        // Tangential (3, 4, 0), normal component ignored.
        let f = coulomb(N, Vec3::new(3.0, 4.0, -7.0), 1.0, 0.5, 0.01);
        assert!((f - Vec3::new(-0.6, -0.8, 0.0)).norm() < 1e-15, "{f:?}");
        assert!((f.norm() - 0.5 * 2.0).abs() < 1e-15);
    }

    #[test]
    fn slow_sliding_is_stopped_over_the_interval_and_never_reversed() {
        let v = Vec3::new(1e-3, 0.0, 0.0);
        let (m, h) = (2.0, 0.01);
        let f = coulomb(N, v, m, 0.5, h);
        // m |v| / h = 0.2 < mu |N| = 1: exactly the stopping force.
        assert!((f - Vec3::new(-0.2, 0.0, 0.0)).norm() < 1e-15, "{f:?}");
        assert!((v + f * h / m).norm() < 1e-18);
    }

    #[test]
    fn dissipative_tangential_and_zero_without_load_or_sliding() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as Real / (1u64 << 53) as Real) * 2.0 - 1.0
        };
        for _ in 0..200 {
            let n = Vec3::new(rnd(), rnd(), rnd());
            let v = Vec3::new(rnd(), rnd(), rnd()) * 3.0;
            let mu = rnd().abs();
            let f = coulomb(n, v, 1.0 + rnd().abs(), mu, 0.01);
            assert!(f.dot(&v) <= 1e-15, "does work {}", f.dot(&v));
            assert!(f.dot(&n).abs() <= 1e-12 * (1.0 + n.norm()), "normal part");
            assert!(f.norm() <= mu * n.norm() * (1.0 + 1e-12), "beyond Coulomb");
        }
        assert_eq!(
            coulomb(Vec3::zeros(), Vec3::x(), 1.0, 1.0, 0.01),
            Vec3::zeros()
        );
        assert_eq!(coulomb(N, Vec3::z(), 1.0, 1.0, 0.01), Vec3::zeros());
        assert_eq!(coulomb(N, Vec3::x(), 1.0, 0.0, 0.01), Vec3::zeros());
    }

    #[test]
    fn normal_damping_opposes_the_normal_velocity_and_never_pulls() {
        // Moving into the collider (v·n < 0): pushed back, -c v_n.
        let d = normal_damping(N, Vec3::new(5.0, 0.0, -0.1), 3.0);
        assert!((d - Vec3::new(0.0, 0.0, 0.3)).norm() < 1e-15, "{d:?}");
        // Leaving fast: held back by at most the reaction itself.
        let d = normal_damping(N, Vec3::new(0.0, 0.0, 10.0), 3.0);
        assert!((d + N).norm() < 1e-15, "{d:?}");
        assert_eq!(normal_damping(Vec3::zeros(), Vec3::z(), 3.0), Vec3::zeros());
    }
}
