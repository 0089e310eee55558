//! Probe systems of the stability sweep and their effective stiffness.
//!
//! Each probe is two particles of unit mass (inertia 0.1) one rest distance
//! `r0 = 1` apart along x, damped (`β0 = 1`, `β1 = 0.1`: both decay rates
//! 1 per unit time), released at rest from a perturbed state:
//!
//! - **cohesion** (seed 002 §3, stiffness parameter `E`) and
//!   **Lennard-Jones** 12-6 (seed 000 eq. 5, stiffness parameter the well
//!   depth `ε`): unoriented particles started at `0.9 r0`; cut-off 1.5.
//! - **form** (seed 002 §4, stiffness parameter the form weight): oriented
//!   particles held by the reference cohesion (`E = 200`) at `r0`, flat
//!   rest curvature, with the first particle's normal tilted by 0.2 rad
//!   about the pair axis.
//!
//! **Effective stiffness.** `λ`, the largest eigenvalue of the
//! mass-weighted Hessian `M^{-1/2} H M^{-1/2}` of the potential energy over
//! the 12 degrees of freedom (positions and rotation vectors), taken as the
//! larger of its values at the start and at rest: `λ = ω²` of the fastest
//! mode, so `sqrt(m/k) = 1/sqrt(λ)`. The Hessian is the central difference
//! of the forces and torques, which are the exact derivatives of the energy
//! (checked against finite differences of the energy by op-dynamics). The
//! cohesion force has zero slope at rest (`f'(r0) = 0`), so its stiffness
//! is that of the starting compression.
//!
//! **Outcome of one run** (docs/model.md §6). *Diverged*: [`World::step`] reports
//! it (non-finite state or a speed above `1e3`), or the pair is pulled
//! beyond the cut-off with more total energy than it started with: the
//! probe is damped and unforced, so its energy can only decrease, and a
//! gain (beyond `1e-3 (1 + |E0|)`) was put in by the integrator.
//! *Broke*: the pair is pulled beyond the cut-off without such a gain (the
//! bond broke: seed 002 footnote 4), an energetic outcome the integrator
//! need not be blamed for (the form probe's tilted normals push the pair apart through the
//! weight's `dψ/dr` with a force growing with the form weight, beyond the
//! cohesion's maximum attraction from a weight of about 30). *Converged*:
//! the first time the oscillation measure `O` is below `1e-6 √2` with the
//! distance within 1% of `r0` (and, for the form probe, the normals within
//! 0.01 of each other). *Oscillating*: neither by the end of the run.

use op_dynamics::interactions::{CohesionParams, LennardJonesParams, Spacing, WeightParams};
use op_dynamics::world::DivergenceParams;
use op_dynamics::{
    ExternalParams, Material, ParticleDesc, Particles, Point3, Quat, Real, Scheme, Vec3, World,
    WorldParams,
};

use crate::matching::reference_cohesion;

/// The potential whose stiffness a probe varies.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Potential {
    /// Cohesion, stiffness parameter `E`.
    Cohesion,
    /// Lennard-Jones 12-6, stiffness parameter `ε`.
    LennardJones,
    /// Form (shape memory) weight, over the reference cohesion.
    Form,
}

impl Potential {
    /// All three, in report order.
    pub const ALL: [Potential; 3] = [
        Potential::Cohesion,
        Potential::LennardJones,
        Potential::Form,
    ];

    /// Short name for tables and file names.
    pub fn name(self) -> &'static str {
        match self {
            Potential::Cohesion => "cohesion",
            Potential::LennardJones => "lennard_jones",
            Potential::Form => "form",
        }
    }

    /// The stiffness parameter's symbol.
    pub fn parameter(self) -> &'static str {
        match self {
            Potential::Cohesion => "E",
            Potential::LennardJones => "epsilon",
            Potential::Form => "form weight",
        }
    }
}

/// Rest distance of every probe.
pub const R0: Real = 1.0;
/// Cut-off of every probe's spacing potential (and orientation weight).
pub const CUTOFF: Real = 1.5;
/// Starting distance of the spacing probes, in `r0`.
pub const START_DISTANCE: Real = 0.9;
/// Starting tilt of the form probe's first normal (radians).
pub const START_TILT: Real = 0.2;
/// Linear damping `β0` (unit masses).
pub const LINEAR_DAMPING: Real = 1.0;
/// Angular damping `β1` (inertia 0.1: the same decay rate).
pub const ANGULAR_DAMPING: Real = 0.1;
/// Moment of inertia of the probe particles.
pub const INERTIA: Real = 0.1;

/// A probe: a potential at one value of its stiffness parameter.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Probe {
    /// Which potential.
    pub potential: Potential,
    /// Its stiffness parameter (`E`, `ε` or the form weight).
    pub value: Real,
}

impl Probe {
    /// The material of the probe's particles.
    pub fn material(&self) -> Material {
        let cohesion = |e: Real| {
            Spacing::Cohesion(CohesionParams {
                e,
                cutoff: Some(CUTOFF),
                ..reference_cohesion()
            })
        };
        match self.potential {
            Potential::Cohesion => Material {
                spacing: Some(cohesion(self.value)),
                ..Material::empty()
            },
            Potential::LennardJones => Material {
                spacing: Some(Spacing::LennardJones(LennardJonesParams {
                    epsilon: self.value,
                    r0: R0,
                    cutoff: CUTOFF,
                    ..LennardJonesParams::default()
                })),
                ..Material::empty()
            },
            Potential::Form => Material {
                spacing: Some(cohesion(reference_cohesion().e)),
                weight: WeightParams {
                    k: 1.0,
                    a: 1.0,
                    cutoff: CUTOFF,
                    ..WeightParams::default()
                },
                form: self.value,
                ..Material::empty()
            },
        }
    }

    /// The two particles at rest (`perturbed = false`) or in the starting
    /// state.
    pub fn particles(&self, perturbed: bool) -> Particles {
        let oriented = self.potential == Potential::Form;
        let d = if perturbed && !oriented {
            START_DISTANCE * R0
        } else {
            R0
        };
        let mut p = Particles::new();
        for (k, x) in [0.0, d].into_iter().enumerate() {
            let mut desc = ParticleDesc::at(Point3::new(x, 0.0, 0.0));
            desc.inertia = Vec3::repeat(INERTIA);
            if oriented && perturbed && k == 0 {
                desc.orientation = Quat::from_axis_angle(&Vec3::x_axis(), START_TILT);
            }
            p.push(desc).expect("a valid probe particle");
        }
        p
    }

    /// A world of the probe in its starting state, stepped by `scheme` at
    /// `dt`, with the damping of the module docs and speeds above `1e3`
    /// reported as divergence.
    pub fn world(&self, scheme: Scheme, dt: Real, perturbed: bool) -> World {
        let params = WorldParams {
            scheme,
            dt,
            external: ExternalParams {
                linear_damping: LINEAR_DAMPING,
                angular_damping: ANGULAR_DAMPING,
                ..ExternalParams::default()
            },
            divergence: DivergenceParams { max_speed: 1e3 },
            ..WorldParams::default()
        };
        World::new(self.particles(perturbed), &[self.material()], params)
            .expect("a valid probe world")
    }

    /// The effective stiffness `λ` (1/time²) of the module docs.
    pub fn stiffness(&self) -> Real {
        [true, false]
            .into_iter()
            .map(|perturbed| {
                largest_mass_weighted_eigenvalue(&mut self.world(
                    Scheme::VelocityVerlet,
                    1e-3,
                    perturbed,
                ))
            })
            .fold(0.0, Real::max)
    }
}

/// The largest eigenvalue of `M^{-1/2} H M^{-1/2}` at the world's current
/// state, `H` the Hessian of the potential energy over positions and
/// rotation vectors, by central differences (step `1e-6`) of the forces
/// and torques. Velocities must be zero (damping would enter the forces).
pub fn largest_mass_weighted_eigenvalue(world: &mut World) -> Real {
    let n = world.particles().len();
    let dof = 6 * n;
    let h = 1e-6;
    let base_p: Vec<Point3> = world.particles().positions().to_vec();
    let base_q: Vec<Quat> = world.particles().orientations().to_vec();
    let weights: Vec<Real> = (0..dof)
        .map(|k| {
            let s = k / 6;
            if k % 6 < 3 {
                world.particles().masses()[s]
            } else {
                world.particles().inertias()[s][k % 3]
            }
        })
        .collect();
    let mut hess = vec![vec![0.0; dof]; dof];
    for col in 0..dof {
        let mut g = [vec![0.0; dof], vec![0.0; dof]];
        for (side, sign) in [-1.0, 1.0].into_iter().enumerate() {
            {
                let p = world.particles_mut();
                for s in 0..n {
                    p.set_position(s, base_p[s]);
                    p.set_orientation(s, base_q[s]);
                }
                let (s, c) = (col / 6, col % 6);
                if c < 3 {
                    let mut x = base_p[s];
                    x[c] += sign * h;
                    p.set_position(s, x);
                } else {
                    let mut axis = Vec3::zeros();
                    axis[c - 3] = sign * h;
                    p.set_orientation(s, Quat::from_scaled_axis(axis) * base_q[s]);
                }
            }
            let (f, t, _) = world.evaluate_forces();
            for s in 0..n {
                for c in 0..3 {
                    g[side][6 * s + c] = -f[s][c];
                    g[side][6 * s + 3 + c] = -t[s][c];
                }
            }
        }
        for row in 0..dof {
            hess[row][col] =
                (g[1][row] - g[0][row]) / (2.0 * h) / (weights[row] * weights[col]).sqrt();
        }
    }
    let p = world.particles_mut();
    for s in 0..n {
        p.set_position(s, base_p[s]);
        p.set_orientation(s, base_q[s]);
    }
    let mut sym = vec![vec![0.0; dof]; dof];
    for (r, row) in sym.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = 0.5 * (hess[r][c] + hess[c][r]);
        }
    }
    symmetric_eigenvalues(sym).into_iter().fold(0.0, Real::max)
}

/// Eigenvalues of a symmetric matrix by cyclic Jacobi rotations (Golub &
/// Van Loan, "Matrix Computations", §8.5), to round-off: small matrices
/// only.
pub fn symmetric_eigenvalues(mut a: Vec<Vec<Real>>) -> Vec<Real> {
    let n = a.len();
    for _sweep in 0..100 {
        let off: Real = (0..n)
            .flat_map(|p| (0..n).filter(move |&q| q != p).map(move |q| (p, q)))
            .map(|(p, q)| a[p][q] * a[p][q])
            .sum();
        let scale: Real = (0..n).map(|p| a[p][p] * a[p][p]).sum::<Real>() + Real::MIN_POSITIVE;
        if off <= 1e-30 * scale {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if a[p][q] == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (top, bottom) = a.split_at_mut(q);
                for (x, y) in top[p].iter_mut().zip(bottom[0].iter_mut()) {
                    let (apk, aqk) = (*x, *y);
                    *x = c * apk - s * aqk;
                    *y = s * apk + c * aqk;
                }
            }
        }
    }
    (0..n).map(|p| a[p][p]).collect()
}

/// How one probe run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Converged at this time.
    Converged(Real),
    /// Neither converged nor diverged by the end of the run.
    Oscillating,
    /// The pair was pulled beyond the cut-off at this time.
    Broke(Real),
    /// Diverged at this time, for this reason.
    Diverged(Real, String),
}

impl Outcome {
    /// True for [`Outcome::Diverged`].
    pub fn diverged(&self) -> bool {
        matches!(self, Outcome::Diverged(..))
    }

    /// One letter for tables: `C`, `O`, `B` or `D`.
    pub fn letter(&self) -> &'static str {
        match self {
            Outcome::Converged(_) => "C",
            Outcome::Oscillating => "O",
            Outcome::Broke(_) => "B",
            Outcome::Diverged(..) => "D",
        }
    }
}

/// Runs `probe` with `scheme` at `dt` until it converges, diverges, the
/// time reaches `t_max` or `max_steps` steps were taken (see the module
/// docs).
pub fn run(probe: &Probe, scheme: Scheme, dt: Real, t_max: Real, max_steps: u64) -> Outcome {
    let mut world = probe.world(scheme, dt, true);
    let e0 = world.diagnostics().total;
    let tol = 1e-6 * 2f64.sqrt();
    while world.time() < t_max && world.steps() < max_steps {
        if let Err(e) = world.step() {
            return Outcome::Diverged(world.time(), e.reason);
        }
        let p = world.particles();
        let d = (p.positions()[1] - p.positions()[0]).norm();
        if d >= CUTOFF {
            let t = world.time();
            let e = world.diagnostics().total;
            return if e > e0 + 1e-3 * (1.0 + e0.abs()) {
                Outcome::Diverged(
                    t,
                    format!(
                        "the pair broke with total energy {e:.3e} > the initial {e0:.3e}: \
                         energy put in by the integrator"
                    ),
                )
            } else {
                Outcome::Broke(t)
            };
        }
        let aligned =
            probe.potential != Potential::Form || (p.normal(0) - p.normal(1)).norm() < 1e-2;
        if world.oscillation() < tol && (d - R0).abs() < 1e-2 * R0 && aligned {
            return Outcome::Converged(world.time());
        }
    }
    Outcome::Oscillating
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_finds_the_eigenvalues_of_a_known_matrix() {
        // [[2, 1], [1, 2]] has eigenvalues 1 and 3; a diagonal block adds 5.
        let a = vec![
            vec![2.0, 1.0, 0.0],
            vec![1.0, 2.0, 0.0],
            vec![0.0, 0.0, 5.0],
        ];
        let mut e = symmetric_eigenvalues(a);
        e.sort_by(Real::total_cmp);
        for (x, y) in e.iter().zip([1.0, 3.0, 5.0]) {
            assert!((x - y).abs() < 1e-12, "{e:?}");
        }
    }

    #[test]
    fn lennard_jones_pair_stiffness_is_twice_u_second_derivative_over_mass() {
        // At rest U''(r0) = 72 ε / r0² for the 12-6 potential (with the
        // taper starting beyond r0), and the pair mode has ω² = 2 U'' / m;
        // at 0.9 r0 the curvature is larger.
        let probe = Probe {
            potential: Potential::LennardJones,
            value: 1.0,
        };
        let at_rest =
            largest_mass_weighted_eigenvalue(&mut probe.world(Scheme::VelocityVerlet, 1e-3, false));
        assert!((at_rest - 144.0).abs() < 1e-3 * 144.0, "{at_rest}");
        assert!(probe.stiffness() > at_rest);
    }

    #[test]
    fn form_stiffness_grows_linearly_with_its_weight() {
        let k = |w: Real| {
            Probe {
                potential: Potential::Form,
                value: w,
            }
            .stiffness()
        };
        let (a, b) = (k(100.0), k(400.0));
        assert!((b / a - 4.0).abs() < 0.2, "{a} {b}");
    }

    #[test]
    fn small_steps_converge_and_huge_steps_diverge() {
        let probe = Probe {
            potential: Potential::LennardJones,
            value: 1.0,
        };
        let dt_ref = 1.0 / probe.stiffness().sqrt();
        let fine = run(
            &probe,
            Scheme::VelocityVerlet,
            0.05 * dt_ref,
            60.0,
            1_000_000,
        );
        assert!(matches!(fine, Outcome::Converged(_)), "{fine:?}");
        let coarse = run(&probe, Scheme::VelocityVerlet, 5.0 * dt_ref, 60.0, 10_000);
        assert!(coarse.diverged(), "{coarse:?}");
    }
}
