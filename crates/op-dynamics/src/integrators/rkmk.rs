//! Explicit Runge–Kutta–Munthe-Kaas machinery shared by [`super::rk4`] and
//! [`super::adaptive`] (Munthe-Kaas 1999, "High order Runge–Kutta methods on
//! manifolds", Appl. Numer. Math. 29, 115-127; Iserles, Munthe-Kaas, Nørsett
//! & Zanna 2000, "Lie-group methods", Acta Numerica §5).
//!
//! `p`, `v` and `ω` are integrated by the plain Runge–Kutta method. The
//! orientation is written `q = exp(θ) q_n` with a rotation vector `θ`
//! (world frame) that starts at 0; `θ` lives in a vector space and obeys
//! `θ̇ = dexp⁻¹_θ(ω)` ([`rigid::dexp_inv`]), so it too is integrated by the
//! plain method: stage `k` has `θ_k = h Σ_j a_kj Θ_j`, orientation
//! `q_k = exp(θ_k) q_n` and slope `Θ_k = dexp⁻¹_{θ_k}(ω_k)`; the step ends
//! with `q₁ = exp(h Σ_j b_j Θ_j) q_n`. Orientations stay on the unit
//! sphere by construction.

use super::rigid;
use super::{Bodies, ForceField, Particle, StateRef};
use crate::math::{rotate_by, Point3, Quat, Real, Vec3};

/// The time derivative of one particle's state at an RKMK stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Deriv {
    /// `ṗ = v`.
    pub dp: Vec3,
    /// `v̇ = f/m`.
    pub dv: Vec3,
    /// `θ̇ = dexp⁻¹_θ(ω)`.
    pub dth: Vec3,
    /// `ω̇` from Euler's equations.
    pub dw: Vec3,
}

/// The stage slope of one particle at state `s` whose orientation is
/// `exp(theta) q_n`, under force `f` and torque `tau`.
#[inline]
pub(crate) fn derivative(
    s: &Particle,
    theta: &Vec3,
    f: &Vec3,
    tau: &Vec3,
    inv_mass: Real,
    inertia: &Vec3,
) -> Deriv {
    Deriv {
        dp: s.v,
        dv: inv_mass * f,
        dth: rigid::dexp_inv(theta, &s.w),
        dw: rigid::angular_acceleration(&s.q, &s.w, tau, inertia),
    }
}

/// One particle's state after `y + h Σ_j coeffs[j] K_j`, with the rotation
/// vector `θ` it used. `k(j)` gives slope `j` of this particle.
#[inline]
pub(crate) fn combine(
    y: &Particle,
    h: Real,
    coeffs: &[Real],
    k: impl Fn(usize) -> Deriv,
) -> (Particle, Vec3) {
    let mut sum = Deriv::default();
    for (j, &c) in coeffs.iter().enumerate() {
        if c != 0.0 {
            let kj = k(j);
            sum.dp += c * kj.dp;
            sum.dv += c * kj.dv;
            sum.dth += c * kj.dth;
            sum.dw += c * kj.dw;
        }
    }
    let theta = h * sum.dth;
    let s = Particle {
        p: y.p + h * sum.dp,
        v: y.v + h * sum.dv,
        q: rotate_by(&y.q, &theta),
        w: y.w + h * sum.dw,
    };
    (s, theta)
}

/// An explicit Butcher tableau: `a[s]` has `s` entries, `c[s] = Σ a[s]`.
#[derive(Debug)]
pub(crate) struct Tableau {
    pub a: &'static [&'static [Real]],
    pub c: &'static [Real],
}

impl Tableau {
    pub fn stages(&self) -> usize {
        self.c.len()
    }
}

/// Stage state and slopes, reused across steps.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct RkBuffers {
    pub positions: Vec<Point3>,
    pub velocities: Vec<Vec3>,
    pub orientations: Vec<Quat>,
    pub angular_velocities: Vec<Vec3>,
    pub thetas: Vec<Vec3>,
    /// Slopes, stage-major: `k[s * n + i]`.
    pub k: Vec<Deriv>,
    n: usize,
}

impl RkBuffers {
    /// Sizes the buffers for `n` particles and `stages` stages (allocates
    /// only when the size changes).
    pub fn ensure(&mut self, n: usize, stages: usize) {
        if self.n != n || self.k.len() != n * stages {
            self.positions.resize(n, Point3::origin());
            self.velocities.resize(n, Vec3::zeros());
            self.orientations.resize(n, Quat::identity());
            self.angular_velocities.resize(n, Vec3::zeros());
            self.thetas.resize(n, Vec3::zeros());
            self.k.resize(n * stages, Deriv::default());
            self.n = n;
        }
    }

    /// The stage state as a force-field input.
    pub fn view(&self) -> StateRef<'_> {
        StateRef {
            positions: &self.positions,
            velocities: &self.velocities,
            orientations: &self.orientations,
            angular_velocities: &self.angular_velocities,
        }
    }

    /// Writes `y + h Σ coeffs[j] K_j` for every particle into the stage
    /// state.
    pub fn combine_all(&mut self, y: StateRef<'_>, h: Real, coeffs: &[Real]) {
        let n = self.n;
        for i in 0..n {
            let (s, theta) = combine(&y.particle(i), h, coeffs, |j| self.k[j * n + i]);
            self.positions[i] = s.p;
            self.velocities[i] = s.v;
            self.orientations[i] = s.q;
            self.angular_velocities[i] = s.w;
            self.thetas[i] = theta;
        }
    }
}

/// Stage 0 slopes (at `y`, `θ = 0`) from the forces at `y`.
pub(crate) fn first_slope(
    bodies: &Bodies<'_>,
    y: StateRef<'_>,
    forces: &[Vec3],
    torques: &[Vec3],
    k0: &mut [Deriv],
) {
    let zero = Vec3::zeros();
    for (i, k) in k0.iter_mut().enumerate() {
        *k = derivative(
            &y.particle(i),
            &zero,
            &forces[i],
            &torques[i],
            bodies.inv_mass[i],
            &bodies.inertia[i],
        );
    }
}

/// Stages `1..` of `tab` (stage 0 slopes must be in `buf.k`): builds each
/// stage state, evaluates the forces at time `t + c h` into
/// `forces`/`torques`, and stores the slopes. Returns the number of force
/// evaluations. On return the stage state and forces are those of the last
/// stage.
#[allow(clippy::too_many_arguments)]
pub(crate) fn later_stages<F: ForceField>(
    field: &mut F,
    bodies: &Bodies<'_>,
    t: Real,
    h: Real,
    y: StateRef<'_>,
    tab: &Tableau,
    buf: &mut RkBuffers,
    forces: &mut [Vec3],
    torques: &mut [Vec3],
) -> u32 {
    let n = buf.n;
    for s in 1..tab.stages() {
        buf.combine_all(y, h, tab.a[s]);
        field.forces(t + tab.c[s] * h, buf.view(), forces, torques);
        for i in 0..n {
            let stage = buf.view().particle(i);
            buf.k[s * n + i] = derivative(
                &stage,
                &buf.thetas[i],
                &forces[i],
                &torques[i],
                bodies.inv_mass[i],
                &bodies.inertia[i],
            );
        }
    }
    (tab.stages() - 1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn combine_with_zero_step_is_identity() {
        let y = Particle {
            p: Point3::new(1.0, 2.0, 3.0),
            v: Vec3::new(0.1, 0.2, 0.3),
            q: Quat::from_scaled_axis(Vec3::new(0.1, 0.2, 0.3)),
            w: Vec3::new(1.0, 0.0, 0.0),
        };
        let k = Deriv {
            dp: Vec3::repeat(1.0),
            dv: Vec3::repeat(1.0),
            dth: Vec3::repeat(1.0),
            dw: Vec3::repeat(1.0),
        };
        let (s, theta) = combine(&y, 0.0, &[0.5, 0.5], |_| k);
        assert_eq!(theta, Vec3::zeros());
        assert_eq!(s.p, y.p);
        assert!(s.q.angle_to(&y.q) < 1e-16);
    }
}
