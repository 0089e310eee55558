//! Diagnostics (docs/model.md §6): kinetic (translational + rotational), potential
//! and total energy, linear and angular momentum, the oscillation measure of
//! seed 002 §3, and the rest shape error used by the shape-memory tests.

use crate::math::{Point3, Real, Vec3};
use crate::particles::Particles;

/// A snapshot of the world's global quantities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// `sum 1/2 m |v|^2`.
    pub kinetic_translational: Real,
    /// `sum 1/2 w . (R I R^T) w`.
    pub kinetic_rotational: Real,
    /// Internal potential energy (sum of pair energies).
    pub potential: Real,
    /// Kinetic + potential.
    pub total: Real,
    /// `sum m v`.
    pub linear_momentum: Vec3,
    /// `sum p x m v + R I R^T w`, about the origin.
    pub angular_momentum: Vec3,
    /// Oscillation measure of the last step (see [`oscillation`]).
    pub oscillation: Real,
    /// Largest particle speed.
    pub max_speed: Real,
}

/// Kinetic energies, momenta and the largest speed of `p` (the potential
/// and oscillation fields are left at zero).
pub fn kinematic(p: &Particles) -> Diagnostics {
    let mut d = Diagnostics::default();
    for i in 0..p.len() {
        let m = p.masses()[i];
        let v = p.velocities()[i];
        let w = p.angular_velocities()[i];
        let q = p.orientations()[i];
        let wb = q.inverse_transform_vector(&w);
        let lb = p.inertias()[i].component_mul(&wb);
        d.kinetic_translational += 0.5 * m * v.norm_squared();
        d.kinetic_rotational += 0.5 * wb.dot(&lb);
        d.linear_momentum += m * v;
        d.angular_momentum += p.positions()[i].coords.cross(&(m * v)) + q * lb;
        d.max_speed = d.max_speed.max(v.norm());
    }
    d.total = d.kinetic_translational + d.kinetic_rotational;
    d
}

/// The oscillation measure of seed 002 §3 for one step from `before` to
/// `after`: `sqrt(sum_i |dx_i|^2 - |sum_i dx_i|^2 / N)`, the spread of the
/// per-step displacements about their mean (movement about the mass centre
/// for equal masses). 0 for fewer than two particles.
pub fn oscillation(before: &[Point3], after: &[Point3]) -> Real {
    let n = before.len().min(after.len());
    if n < 2 {
        return 0.0;
    }
    let mut sum = Vec3::zeros();
    let mut sum2 = 0.0;
    for (a, b) in before.iter().zip(after) {
        let d = b - a;
        sum += d;
        sum2 += d.norm_squared();
    }
    (sum2 - sum.norm_squared() / n as Real).max(0.0).sqrt()
}

/// RMS distance between `current` and `rest` after the best rigid alignment
/// (Kabsch), the rest shape error of docs/model.md §6 before division by r0.
pub fn rest_shape_rms(rest: &[Point3], current: &[Point3]) -> Real {
    let n = rest.len().min(current.len());
    if n == 0 {
        return 0.0;
    }
    let c0 = rest[..n].iter().fold(Vec3::zeros(), |s, p| s + p.coords) / n as Real;
    let c1 = current[..n].iter().fold(Vec3::zeros(), |s, p| s + p.coords) / n as Real;
    let mut h = crate::math::Mat3::zeros();
    for k in 0..n {
        h += (rest[k].coords - c0) * (current[k].coords - c1).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u.unwrap_or_default(), svd.v_t.unwrap_or_default());
    let mut d = crate::math::Mat3::identity();
    if (v_t.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = v_t.transpose() * d * u.transpose();
    let sum: Real = (0..n)
        .map(|k| (r * (rest[k].coords - c0) - (current[k].coords - c1)).norm_squared())
        .sum();
    (sum / n as Real).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;

    #[test]
    fn oscillation_ignores_rigid_translation() {
        let a = [Point3::origin(), Point3::new(1.0, 0.0, 0.0)];
        let b = [Point3::new(0.5, 0.0, 0.0), Point3::new(1.5, 0.0, 0.0)];
        assert!(oscillation(&a, &b) < 1e-15);
        let c = [Point3::new(-0.1, 0.0, 0.0), Point3::new(1.1, 0.0, 0.0)];
        assert!((oscillation(&a, &c) - (0.02_f64).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn rest_shape_rms_ignores_rigid_motion() {
        let rest: Vec<Point3> = (0..7)
            .map(|k| Point3::new(k as Real, (k * k) as Real * 0.1, (k % 3) as Real))
            .collect();
        let q = Quat::from_euler_angles(0.3, -1.1, 2.0);
        let moved: Vec<Point3> = rest
            .iter()
            .map(|p| q * p + Vec3::new(3.0, -2.0, 1.0))
            .collect();
        assert!(rest_shape_rms(&rest, &moved) < 1e-12);
        let mut bent = moved.clone();
        bent[3] += Vec3::new(0.0, 0.0, 0.7);
        assert!(rest_shape_rms(&rest, &bent) > 0.1);
    }
}
