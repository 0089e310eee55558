//! Rotational kernels shared by the integrators: Euler's equations with a
//! diagonal body inertia, world angular momentum, rotational kinetic energy
//! and the truncated inverse differential of the exponential map used by the
//! Runge–Kutta–Munthe-Kaas schemes.
//!
//! Conventions (docs/model.md §2): angular velocities and torques are in the WORLD
//! frame; `inertia` holds the principal moments `(I_x, I_y, I_z)` in the
//! BODY frame of the orientation `q`, so the world inertia tensor is
//! `R(q) diag(I) R(q)ᵀ`.
//!
//! **Locked particles.** Rotational dynamics is active only when all three
//! moments are finite and strictly positive. Otherwise (a moment that is 0,
//! infinite, negative or NaN) the particle is *rotationally locked*: torques
//! do not change its angular velocity (zero angular acceleration, never NaN),
//! it keeps turning with the angular velocity it has (normally zero), and
//! [`angular_momentum`] / [`rotational_kinetic_energy`] count only the axes
//! whose moment is finite and positive.

use crate::math::{Mat3, Quat, Real, Vec3};

/// The inverse principal moments `1/I` when all three moments are finite and
/// strictly positive, `None` for a rotationally locked particle (see the
/// module docs).
#[inline]
pub fn inverse_moments(inertia: &Vec3) -> Option<Vec3> {
    if inertia.iter().all(|m| m.is_finite() && *m > 0.0) {
        Some(inertia.map(|m| 1.0 / m))
    } else {
        None
    }
}

/// The moments used for momentum and energy: finite positive moments kept,
/// anything else replaced by 0.
#[inline]
fn usable_moments(inertia: &Vec3) -> Vec3 {
    inertia.map(|m| if m.is_finite() && m > 0.0 { m } else { 0.0 })
}

/// World-frame angular acceleration `dω/dt` of a rigid body with diagonal
/// body inertia: Euler's equations in the body frame
/// `I ω̇_b = τ_b − ω_b × (I ω_b)` (gyroscopic term included), with
/// `ω_b = R(q)ᵀ ω`, `τ_b = R(q)ᵀ τ`, and the result mapped back to the world
/// as `R(q) ω̇_b` (valid because `d(Rω_b)/dt = ω × Rω_b + R ω̇_b` and
/// `ω × ω = 0`).
///
/// Returns zero for a rotationally locked particle (module docs).
#[inline]
pub fn angular_acceleration(q: &Quat, omega: &Vec3, torque: &Vec3, inertia: &Vec3) -> Vec3 {
    let Some(inv) = inverse_moments(inertia) else {
        return Vec3::zeros();
    };
    let wb = q.inverse_transform_vector(omega);
    let tb = q.inverse_transform_vector(torque);
    let lb = inertia.component_mul(&wb);
    let alpha_b = (tb - wb.cross(&lb)).component_mul(&inv);
    q.transform_vector(&alpha_b)
}

/// Newton iterations of [`gyroscopic_kick`] at most (it converges
/// quadratically: 2 to 4 iterations reach round-off at `h |ω| ≲ 0.1`).
const MAX_NEWTON_ITERATIONS: usize = 12;

/// The angular velocity after a kick of duration `h` by Euler's equations
/// with the gyroscopic term taken implicitly: the implicit midpoint rule
/// for the body-frame equations `I ω̇_b = τ_b − ω_b × (I ω_b)`,
///
/// `ω_b1 = ω_b0 + h I⁻¹ (τ_b − ω_m × (I ω_m))`, `ω_m = ½(ω_b0 + ω_b1)`,
///
/// in the body frame of `q` (held fixed during the kick), returned in the
/// world frame `ω₁ = R(q) ω_b1`. With `τ = 0` the midpoint rule conserves
/// the quadratic invariants of the free body, the kinetic energy
/// `½ ω_b·Iω_b` and `|I ω_b| = |L|`, exactly up to the solver tolerance and
/// round-off (Hairer, Lubich & Wanner, "Geometric Numerical Integration",
/// 2006, §IV.2, Theorem 2.1: the implicit midpoint rule conserves quadratic
/// first integrals; the body-frame Euler equations as in §VII.5). An
/// explicit gyroscopic term instead pumps energy into an asymmetric free
/// body until it blows up.
///
/// Solved by Newton's method from the explicit Euler guess, to round-off
/// (at most 12 iterations); a singular Jacobian (only at
/// `h |ω| ≫ 1`) falls back to one fixed-point update per iteration.
/// Returns `omega` unchanged for a rotationally locked particle.
pub fn gyroscopic_kick(q: &Quat, omega: &Vec3, torque: &Vec3, inertia: &Vec3, h: Real) -> Vec3 {
    let Some(inv) = inverse_moments(inertia) else {
        return *omega;
    };
    // Rotate with the normalized frame: the world ω is stored between steps
    // and read back in the next step's frame, so a norm |q| = 1 + δ left by
    // round-off would scale ω by |q|⁴ per step and the energy would drift
    // (2e-9 over 200,000 steps in the free-body test).
    let q = &Quat::new_normalize(*q.quaternion());
    let w0 = q.inverse_transform_vector(omega);
    let tb = q.inverse_transform_vector(torque);
    // Residual of the midpoint equation at the candidate `x`.
    let residual = |x: &Vec3| {
        let m = 0.5 * (w0 + x);
        x - w0 - h * (tb - m.cross(&inertia.component_mul(&m))).component_mul(&inv)
    };
    let mut x = w0 + h * (tb - w0.cross(&inertia.component_mul(&w0))).component_mul(&inv);
    for _ in 0..MAX_NEWTON_ITERATIONS {
        let g = residual(&x);
        let m = 0.5 * (w0 + x);
        // d(m × Im)/dm = [m]× diag(I) − [Im]×, and dm/dx = ½.
        let d_gyro = m.cross_matrix() * Mat3::from_diagonal(inertia)
            - inertia.component_mul(&m).cross_matrix();
        let jac = Mat3::identity() + Mat3::from_diagonal(&inv) * d_gyro * (0.5 * h);
        let step = jac.try_inverse().map_or(g, |j| j * g);
        x -= step;
        if step.norm() <= 4.0 * Real::EPSILON * x.norm() {
            break;
        }
    }
    q.transform_vector(&x)
}

/// World angular momentum `L = R diag(I) Rᵀ ω`.
#[inline]
pub fn angular_momentum(q: &Quat, omega: &Vec3, inertia: &Vec3) -> Vec3 {
    let wb = q.inverse_transform_vector(omega);
    q.transform_vector(&usable_moments(inertia).component_mul(&wb))
}

/// World angular velocity `ω = R diag(1/I) Rᵀ L` for the world angular
/// momentum `L`. `None` for a rotationally locked particle.
#[inline]
pub fn angular_velocity_from_momentum(q: &Quat, momentum: &Vec3, inertia: &Vec3) -> Option<Vec3> {
    let inv = inverse_moments(inertia)?;
    let lb = q.inverse_transform_vector(momentum);
    Some(q.transform_vector(&inv.component_mul(&lb)))
}

/// Rotational kinetic energy `½ ω_bᵀ diag(I) ω_b`.
#[inline]
pub fn rotational_kinetic_energy(q: &Quat, omega: &Vec3, inertia: &Vec3) -> Real {
    let wb = q.inverse_transform_vector(omega);
    0.5 * wb.dot(&usable_moments(inertia).component_mul(&wb))
}

/// The inverse differential of the exponential map of SO(3), truncated
/// after the second-order term:
/// `dexp⁻¹_θ(ω) ≈ ω − ½ θ×ω + (1/12) θ×(θ×ω)`.
///
/// For `q(t) = exp(θ(t)) q_n` and the world angular velocity `ω`
/// (`q̇ = ω̂ q`), the rotation vector obeys `θ̇ = dexp⁻¹_θ(ω)`, whose
/// series is `Σ B_k/k! ad_θ^k ω` (Bernoulli numbers `B_k`, `ad_θ ω = θ×ω`).
/// A Runge–Kutta–Munthe-Kaas method of order `p` needs the terms of degree
/// `≤ p − 2` (Munthe-Kaas 1999, "High order Runge–Kutta methods on
/// manifolds", Appl. Numer. Math. 29); the degree-3 term vanishes
/// (`B_3 = 0`), so this truncation serves order 4 (classical RK4) and order
/// 5 (Dormand–Prince) alike.
#[inline]
pub fn dexp_inv(theta: &Vec3, omega: &Vec3) -> Vec3 {
    let tw = theta.cross(omega);
    omega - 0.5 * tw + theta.cross(&tw) / 12.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rotate_by;

    fn anisotropic() -> Vec3 {
        Vec3::new(1.0, 2.0, 3.5)
    }

    fn some_orientation() -> Quat {
        Quat::from_scaled_axis(Vec3::new(0.4, -0.9, 0.3))
    }

    #[test]
    fn isotropic_inertia_has_no_gyroscopic_term() {
        let q = some_orientation();
        let w = Vec3::new(1.0, -2.0, 0.5);
        let i = Vec3::repeat(2.5);
        assert!(angular_acceleration(&q, &w, &Vec3::zeros(), &i).norm() < 1e-14);
        let tau = Vec3::new(0.3, 0.2, -1.0);
        let a = angular_acceleration(&q, &w, &tau, &i);
        assert!((a - tau / 2.5).norm() < 1e-14);
    }

    #[test]
    fn matches_world_frame_euler_equation() {
        // I_w ω̇ = τ − ω × (I_w ω) with I_w = R diag(I) Rᵀ.
        let q = some_orientation();
        let w = Vec3::new(0.7, -1.1, 2.0);
        let tau = Vec3::new(-0.4, 0.9, 0.1);
        let inertia = anisotropic();
        let r = q.to_rotation_matrix().into_inner();
        let iw = r * crate::math::Mat3::from_diagonal(&inertia) * r.transpose();
        let a = angular_acceleration(&q, &w, &tau, &inertia);
        let residual = iw * a - (tau - w.cross(&(iw * w)));
        assert!(residual.norm() < 1e-13, "{residual}");
    }

    #[test]
    fn torque_free_rotation_conserves_momentum_and_energy() {
        // Derivatives of L and T along the exact flow vanish.
        let q = some_orientation();
        let w = Vec3::new(0.7, -1.1, 2.0);
        let inertia = anisotropic();
        let a = angular_acceleration(&q, &w, &Vec3::zeros(), &inertia);
        let h = 1e-6;
        let l = |q: &Quat, w: &Vec3| angular_momentum(q, w, &inertia);
        let e = |q: &Quat, w: &Vec3| rotational_kinetic_energy(q, w, &inertia);
        let (qp, wp) = (rotate_by(&q, &(h * w)), w + h * a);
        let (qm, wm) = (rotate_by(&q, &(-h * w)), w - h * a);
        let dl = (l(&qp, &wp) - l(&qm, &wm)) / (2.0 * h);
        let de = (e(&qp, &wp) - e(&qm, &wm)) / (2.0 * h);
        assert!(dl.norm() < 1e-8, "dL/dt = {dl}");
        assert!(de.abs() < 1e-8, "dT/dt = {de}");
        // And the energy matches ½ ω·L.
        assert!((e(&q, &w) - 0.5 * w.dot(&l(&q, &w))).abs() < 1e-14);
    }

    #[test]
    fn gyroscopic_kick_solves_the_midpoint_equation() {
        let q = some_orientation();
        let w = Vec3::new(0.7, -1.1, 2.0);
        let tau = Vec3::new(-0.4, 0.9, 0.1);
        let inertia = anisotropic();
        let h = 0.05;
        let w1 = gyroscopic_kick(&q, &w, &tau, &inertia, h);
        // In the world frame (q fixed): I_w (ω₁ − ω)/h = τ − ω_m × I_w ω_m.
        let r = q.to_rotation_matrix().into_inner();
        let iw = r * Mat3::from_diagonal(&inertia) * r.transpose();
        let wm = 0.5 * (w + w1);
        let residual = iw * (w1 - w) / h - (tau - wm.cross(&(iw * wm)));
        assert!(residual.norm() < 1e-12, "{residual}");
        // Torque-free: kinetic energy and |L| kept to round-off.
        let w1 = gyroscopic_kick(&q, &w, &Vec3::zeros(), &inertia, h);
        let e = |w: &Vec3| rotational_kinetic_energy(&q, w, &inertia);
        let l = |w: &Vec3| angular_momentum(&q, w, &inertia).norm();
        assert!((e(&w1) - e(&w)).abs() < 1e-15 * e(&w) * 8.0);
        assert!((l(&w1) - l(&w)).abs() < 1e-15 * l(&w) * 8.0);
        // Locked particles keep their angular velocity.
        assert_eq!(gyroscopic_kick(&q, &w, &tau, &Vec3::zeros(), h), w);
    }

    #[test]
    fn momentum_round_trip() {
        let q = some_orientation();
        let w = Vec3::new(0.7, -1.1, 2.0);
        let l = angular_momentum(&q, &w, &anisotropic());
        let back = angular_velocity_from_momentum(&q, &l, &anisotropic()).unwrap();
        assert!((back - w).norm() < 1e-14);
    }

    #[test]
    fn locked_particles_do_not_accelerate() {
        let q = some_orientation();
        let w = Vec3::new(0.7, -1.1, 2.0);
        let tau = Vec3::new(5.0, 1.0, 2.0);
        for inertia in [
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(Real::INFINITY, 1.0, 1.0),
            Vec3::repeat(Real::INFINITY),
            Vec3::zeros(),
            Vec3::new(1.0, Real::NAN, 1.0),
        ] {
            let a = angular_acceleration(&q, &w, &tau, &inertia);
            assert_eq!(a, Vec3::zeros());
            assert!(angular_momentum(&q, &w, &inertia)
                .iter()
                .all(|x| x.is_finite()));
            assert!(rotational_kinetic_energy(&q, &w, &inertia).is_finite());
            assert!(angular_velocity_from_momentum(&q, &w, &inertia).is_none());
        }
    }

    #[test]
    fn dexp_inv_inverts_the_exponential_differential() {
        // d/dt exp(θ + tθ̇) at t=0 equals ω̂ exp(θ) with θ̇ = dexp⁻¹_θ(ω),
        // up to the truncation error O(|θ|⁴ |ω|).
        let omega = Vec3::new(0.3, -1.0, 0.6);
        for scale in [1e-1, 5e-2, 2.5e-2] {
            let theta = scale * Vec3::new(1.0, 0.5, -0.7);
            let dtheta = dexp_inv(&theta, &omega);
            let h = 1e-6;
            let qp = Quat::from_scaled_axis(theta + h * dtheta);
            let qm = Quat::from_scaled_axis(theta - h * dtheta);
            // Spatial angular velocity: log(qp qm⁻¹) / 2h.
            let w = (qp * qm.inverse()).scaled_axis() / (2.0 * h);
            let err = (w - omega).norm();
            assert!(err < 2.0 * scale.powi(4) + 1e-8, "scale {scale}: {err}");
        }
    }
}
