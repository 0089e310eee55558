//! Test problems for the integrator tests: a smooth conservative system
//! that exercises every part of the dynamics, a torque-free anisotropic
//! body, and helpers to run schemes and compare states.

use super::rigid;
use super::{Bodies, ForceField, Integrator, Scheme, StateMut, StateRef, StepInfo};
use crate::math::{Point3, Quat, Real, Vec3};

/// Particles on anharmonic springs (pairwise `½k x² + ¼k₄ x⁴`, `x = r − r₀`)
/// plus a spring to the origin, whose body axis `a` is pulled towards a
/// fixed direction `d` (`k_a (1 − n·d)`, `n = R a`) and towards each bonded
/// neighbour (`k_c (1 − n_i·r̂_ij)`, which couples rotation and translation).
/// Optional linear and angular damping. Forces and torques are the exact
/// negative gradients of [`Smooth::potential`].
#[derive(Clone, Debug)]
pub(crate) struct Smooth {
    pub k_origin: Real,
    pub k_pair: Real,
    pub k_quartic: Real,
    pub rest: Real,
    pub k_align: Real,
    pub direction: Vec3,
    pub axis: Vec3,
    pub k_couple: Real,
    pub damping: Real,
    pub angular_damping: Real,
    pub pairs: Vec<(usize, usize)>,
}

impl Default for Smooth {
    fn default() -> Self {
        Self {
            k_origin: 1.0,
            k_pair: 3.0,
            k_quartic: 2.0,
            rest: 1.5,
            k_align: 1.0,
            direction: Vec3::new(0.2, -0.3, 1.0).normalize(),
            axis: Vec3::z(),
            k_couple: 0.5,
            damping: 0.0,
            angular_damping: 0.0,
            pairs: vec![(0, 1), (1, 2), (2, 0)],
        }
    }
}

impl Smooth {
    /// Potential energy of state `s`.
    pub fn potential(&self, s: StateRef<'_>) -> Real {
        let mut e = 0.0;
        for i in 0..s.len() {
            e += 0.5 * self.k_origin * s.positions[i].coords.norm_squared();
            let n = s.orientations[i] * self.axis;
            e += self.k_align * (1.0 - n.dot(&self.direction));
        }
        for &(i, j) in &self.pairs {
            let r = s.positions[j] - s.positions[i];
            let x = r.norm() - self.rest;
            e += 0.5 * self.k_pair * x * x + 0.25 * self.k_quartic * x.powi(4);
            let n = s.orientations[i] * self.axis;
            e += self.k_couple * (1.0 - n.dot(&r.normalize()));
        }
        e
    }
}

impl ForceField for Smooth {
    fn forces(&mut self, _t: Real, s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        for i in 0..s.len() {
            forces[i] = -self.k_origin * s.positions[i].coords - self.damping * s.velocities[i];
            let n = s.orientations[i] * self.axis;
            torques[i] = self.k_align * n.cross(&self.direction)
                - self.angular_damping * s.angular_velocities[i];
        }
        for &(i, j) in &self.pairs {
            let r = s.positions[j] - s.positions[i];
            let rn = r.norm();
            let u = r / rn;
            let x = rn - self.rest;
            let fs = (self.k_pair * x + self.k_quartic * x.powi(3)) * u;
            forces[j] -= fs;
            forces[i] += fs;
            let n = s.orientations[i] * self.axis;
            let g = self.k_couple * (n - n.dot(&u) * u) / rn;
            forces[j] += g;
            forces[i] -= g;
            torques[i] += self.k_couple * n.cross(&u);
        }
    }
}

/// No force, no torque.
pub(crate) struct Free;

impl ForceField for Free {
    fn forces(&mut self, _t: Real, _s: StateRef<'_>, forces: &mut [Vec3], torques: &mut [Vec3]) {
        forces.fill(Vec3::zeros());
        torques.fill(Vec3::zeros());
    }
}

/// Owned particle state and mass properties.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct System {
    pub positions: Vec<Point3>,
    pub velocities: Vec<Vec3>,
    pub orientations: Vec<Quat>,
    pub angular_velocities: Vec<Vec3>,
    pub inv_mass: Vec<Real>,
    pub inertia: Vec<Vec3>,
}

impl System {
    /// Three particles with anisotropic inertia, for [`Smooth`].
    pub fn three() -> Self {
        Self {
            positions: vec![
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(-0.5, 0.9, 0.1),
                Point3::new(-0.4, -0.8, -0.2),
            ],
            velocities: vec![
                Vec3::new(0.0, 0.3, 0.1),
                Vec3::new(-0.2, 0.0, 0.2),
                Vec3::new(0.1, -0.2, 0.0),
            ],
            orientations: vec![
                Quat::from_scaled_axis(Vec3::new(0.3, 0.2, -0.1)),
                Quat::from_scaled_axis(Vec3::new(-0.8, 0.4, 1.2)),
                Quat::from_scaled_axis(Vec3::new(1.5, -0.3, 0.2)),
            ],
            angular_velocities: vec![
                Vec3::new(0.5, -0.3, 0.8),
                Vec3::new(-0.4, 0.9, 0.1),
                Vec3::new(0.2, 0.1, -1.0),
            ],
            inv_mass: vec![1.0, 1.0 / 1.5, 1.0 / 0.8],
            inertia: vec![
                Vec3::new(0.4, 0.7, 1.0),
                Vec3::new(0.6, 0.9, 0.5),
                Vec3::new(0.3, 0.5, 0.45),
            ],
        }
    }

    /// One torque-free body with strongly anisotropic inertia, spinning
    /// about no principal axis.
    pub fn tumbling() -> Self {
        let q = Quat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8));
        Self {
            positions: vec![Point3::origin()],
            velocities: vec![Vec3::new(0.1, 0.0, 0.0)],
            orientations: vec![q],
            // Close to the unstable middle axis: a hard case.
            angular_velocities: vec![q * Vec3::new(0.3, 1.0, -0.4)],
            inv_mass: vec![1.0],
            inertia: vec![Vec3::new(1.0, 2.0, 3.0)],
        }
    }

    pub fn view(&self) -> StateRef<'_> {
        StateRef {
            positions: &self.positions,
            velocities: &self.velocities,
            orientations: &self.orientations,
            angular_velocities: &self.angular_velocities,
        }
    }

    pub fn split(&mut self) -> (StateMut<'_>, Bodies<'_>) {
        (
            StateMut {
                positions: &mut self.positions,
                velocities: &mut self.velocities,
                orientations: &mut self.orientations,
                angular_velocities: &mut self.angular_velocities,
            },
            Bodies {
                inv_mass: &self.inv_mass,
                inertia: &self.inertia,
            },
        )
    }

    /// Total kinetic energy (translation and rotation).
    pub fn kinetic(&self) -> Real {
        (0..self.positions.len())
            .map(|i| {
                let m = 1.0 / self.inv_mass[i];
                0.5 * m * self.velocities[i].norm_squared()
                    + rigid::rotational_kinetic_energy(
                        &self.orientations[i],
                        &self.angular_velocities[i],
                        &self.inertia[i],
                    )
            })
            .sum()
    }

    /// Total world angular momentum about the origin (orbital and spin).
    pub fn angular_momentum(&self) -> Vec3 {
        (0..self.positions.len())
            .map(|i| {
                let m = 1.0 / self.inv_mass[i];
                m * self.positions[i].coords.cross(&self.velocities[i])
                    + rigid::angular_momentum(
                        &self.orientations[i],
                        &self.angular_velocities[i],
                        &self.inertia[i],
                    )
            })
            .sum()
    }

    /// One step of `integrator` at time `t`.
    pub fn step<F: ForceField>(
        &mut self,
        integrator: &mut Integrator,
        field: &mut F,
        t: Real,
        dt: Real,
    ) -> StepInfo {
        let (state, bodies) = self.split();
        integrator.step(field, &bodies, t, dt, state)
    }

    /// `steps` steps of size `dt` with `scheme`, calling `each` after every
    /// step with the time reached.
    pub fn run<F: ForceField>(
        &mut self,
        scheme: Scheme,
        field: &mut F,
        dt: Real,
        steps: usize,
        mut each: impl FnMut(&Self, Real),
    ) {
        let mut integrator = Integrator::new(scheme);
        for k in 0..steps {
            self.step(&mut integrator, field, k as Real * dt, dt);
            each(self, (k + 1) as Real * dt);
        }
    }

    /// The largest, over particles, of `|Δp| + |Δv| + angle(q, q') + |Δω|`.
    pub fn distance(&self, other: &Self) -> Real {
        (0..self.positions.len())
            .map(|i| {
                (self.positions[i] - other.positions[i]).norm()
                    + (self.velocities[i] - other.velocities[i]).norm()
                    + self.orientations[i].angle_to(&other.orientations[i])
                    + (self.angular_velocities[i] - other.angular_velocities[i]).norm()
            })
            .fold(0.0, Real::max)
    }
}

/// Least-squares slope of `log(y)` against `log(x)`.
pub(crate) fn log_slope(x: &[Real], y: &[Real]) -> Real {
    let lx: Vec<Real> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<Real> = y.iter().map(|v| v.ln()).collect();
    let n = lx.len() as Real;
    let (mx, my) = (lx.iter().sum::<Real>() / n, ly.iter().sum::<Real>() / n);
    let sxy: Real = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: Real = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}
