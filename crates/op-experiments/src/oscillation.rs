//! Oscillations of particle systems released near equilibrium (seed 002
//! §3, "Experiments and results"): the oscillation measure `O(t)` of
//! systems of `N` unoriented particles held by cohesion or by the matched
//! Lennard-Jones potential, with the same damping, mass and time step.
//!
//! The systems are planar patches of a hexagonal lattice of spacing `r0`
//! (the `N` lattice sites nearest to the centroid of one lattice triangle:
//! `N = 3` is the equilateral triangle). With both cut-offs at `1.5 r0` only
//! lattice neighbours interact, so the unperturbed lattice is an exact
//! equilibrium of both potentials. Each particle is displaced in the
//! lattice plane by a uniform random vector of the disc of radius
//! `perturbation · r0` (seeded), then released at rest. In-plane only: a
//! flat sheet held by pair forces alone has no out-of-plane stiffness.

use op_dynamics::interactions::Spacing;
use op_dynamics::world::DivergenceParams;
use op_dynamics::{
    ExternalParams, Material, ParticleDesc, Particles, Point3, Real, Scheme, Vec3, World,
    WorldParams,
};

/// Integration and damping settings shared by both potentials.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Dynamics {
    /// Time integration scheme.
    pub scheme: Scheme,
    /// Time step (largest step for the adaptive scheme).
    pub dt: Real,
    /// Linear damping `β0` (force `-β0 v`).
    pub damping: Real,
    /// Mass of every particle.
    pub mass: Real,
}

impl Default for Dynamics {
    /// Explicit Euler (the papers' integrator), `dt = 2e-3`, `β0 = 1`,
    /// unit masses.
    fn default() -> Self {
        Dynamics {
            scheme: Scheme::ExplicitEuler,
            dt: 2e-3,
            damping: 1.0,
            mass: 1.0,
        }
    }
}

/// The `count` sites of a hexagonal lattice of spacing `r0` in the plane
/// z = 0 nearest to the centroid of one lattice triangle (ties broken by
/// angle, so the patch is deterministic).
pub fn hex_patch(count: usize, r0: Real) -> Vec<Point3> {
    let half = (count as Real).sqrt().ceil() as i64 + 2;
    let centroid = Vec3::new(0.5, 3f64.sqrt() / 6.0, 0.0) * r0;
    let mut sites: Vec<(Real, Real, Point3)> = Vec::new();
    for j in -half..=half {
        for i in -half..=half {
            let p = Point3::new(
                (i as Real + 0.5 * j as Real) * r0,
                j as Real * 3f64.sqrt() / 2.0 * r0,
                0.0,
            );
            let d = p.coords - centroid;
            sites.push((d.norm(), d.y.atan2(d.x), p));
        }
    }
    sites.sort_by(|a, b| {
        (a.0 / r0 * 1e9)
            .round()
            .total_cmp(&(b.0 / r0 * 1e9).round())
            .then(a.1.total_cmp(&b.1))
    });
    sites.into_iter().take(count).map(|s| s.2).collect()
}

/// A small deterministic generator (SplitMix64) for seeded perturbations.
#[derive(Clone, Debug)]
pub struct SplitMix(u64);

impl SplitMix {
    /// A generator with this seed.
    pub fn new(seed: u64) -> Self {
        SplitMix(seed)
    }

    /// A uniform number in `[0, 1)`.
    pub fn uniform(&mut self) -> Real {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as Real / (1u64 << 53) as Real
    }
}

/// `positions`, each moved in the z = 0 plane by a uniform random vector
/// of the disc of radius `amplitude`.
pub fn perturbed(positions: &[Point3], amplitude: Real, seed: u64) -> Vec<Point3> {
    let mut rng = SplitMix::new(seed);
    positions
        .iter()
        .map(|p| {
            let radius = amplitude * rng.uniform().sqrt();
            let angle = std::f64::consts::TAU * rng.uniform();
            p + Vec3::new(radius * angle.cos(), radius * angle.sin(), 0.0)
        })
        .collect()
}

/// A world of unoriented particles at `positions` (at rest) held by
/// `spacing` only, with the settings of `d`. Speeds above `1e3` (a blow-up)
/// are reported as divergence by [`World::step`].
pub fn spacing_world(positions: &[Point3], spacing: Spacing, d: &Dynamics) -> World {
    let mut particles = Particles::new();
    for p in positions {
        let mut desc = ParticleDesc::at(*p);
        desc.mass = d.mass;
        particles.push(desc).expect("a valid particle");
    }
    let material = Material {
        spacing: Some(spacing),
        ..Material::empty()
    };
    let params = WorldParams {
        scheme: d.scheme,
        dt: d.dt,
        external: ExternalParams {
            linear_damping: d.damping,
            ..ExternalParams::default()
        },
        divergence: DivergenceParams { max_speed: 1e3 },
        ..WorldParams::default()
    };
    World::new(particles, &[material], params).expect("a valid world")
}

/// `O(t)` of one run, sampled at every step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OscillationRun {
    /// Number of particles.
    pub count: usize,
    /// Time after each step.
    pub times: Vec<Real>,
    /// Oscillation measure of each step.
    pub oscillation: Vec<Real>,
    /// The time from which `O` stays below the tolerance until the end of
    /// the run, if it does ([`OscillationRun::quiet_from`]).
    pub converged_at: Option<Real>,
    /// The divergence message, if the run blew up.
    pub diverged: Option<String>,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

impl OscillationRun {
    /// The time from which `O` stays below `tolerance · √N` until the end
    /// of the run (0 if it always did), or `None` if it is above at the
    /// end. A NaN counts as above.
    pub fn quiet_from(&self, tolerance: Real) -> Option<Real> {
        let limit = oscillation_tolerance(tolerance, self.count);
        let above = |o: &Real| o.is_nan() || *o >= limit;
        match self.oscillation.iter().rposition(above) {
            None => Some(0.0),
            Some(k) if k + 1 < self.times.len() => Some(self.times[k]),
            Some(_) => None,
        }
    }
}

/// The convergence tolerance on `O` for `count` particles: `tolerance`
/// times `√N` (`O` sums squared displacements over particles).
pub fn oscillation_tolerance(tolerance: Real, count: usize) -> Real {
    tolerance * (count as Real).sqrt()
}

/// Releases a perturbed hexagonal patch of `count` particles held by
/// `spacing` (see the module docs) and records `O(t)` for `duration`.
/// `tolerance` is per particle (see [`oscillation_tolerance`]).
pub fn release_near_equilibrium(
    spacing: Spacing,
    count: usize,
    perturbation: Real,
    seed: u64,
    d: &Dynamics,
    duration: Real,
    tolerance: Real,
) -> OscillationRun {
    let clock = std::time::Instant::now();
    let r0 = match &spacing {
        Spacing::Cohesion(c) => c.r0,
        Spacing::LennardJones(l) => l.r0,
    };
    let start = perturbed(&hex_patch(count, r0), perturbation * r0, seed);
    let mut world = spacing_world(&start, spacing, d);
    let mut run = OscillationRun {
        count,
        ..OscillationRun::default()
    };
    while world.time() < duration - 1e-9 * d.dt {
        if let Err(e) = world.step() {
            run.diverged = Some(e.to_string());
            break;
        }
        run.times.push(world.time());
        run.oscillation.push(world.oscillation());
    }
    if run.diverged.is_none() {
        run.converged_at = run.quiet_from(tolerance);
    }
    run.wall_seconds = clock.elapsed().as_secs_f64();
    run
}
