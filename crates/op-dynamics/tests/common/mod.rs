//! Shared helpers of the integration tests: a seeded RNG and small scenes.
#![allow(dead_code)]

use op_dynamics::interactions::{CohesionParams, Spacing, WeightParams, WeightShape};
use op_dynamics::{Material, ParticleDesc, Particles, Point3, Quat, Real, Vec3};

/// SplitMix64: a tiny deterministic generator for seeded configurations.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: Real, hi: Real) -> Real {
        lo + (hi - lo) * ((self.next_u64() >> 11) as Real / (1u64 << 53) as Real)
    }
    pub fn vec3(&mut self, s: Real) -> Vec3 {
        Vec3::new(
            self.uniform(-s, s),
            self.uniform(-s, s),
            self.uniform(-s, s),
        )
    }
    pub fn quat(&mut self, angle: Real) -> Quat {
        Quat::from_scaled_axis(self.vec3(angle))
    }
}

/// Hexagonal lattice positions, `nx` by `ny`, spacing `r0`, in the z=0 plane.
pub fn hex_sheet(nx: usize, ny: usize, r0: Real) -> Vec<Point3> {
    let mut v = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let x = (i as Real + 0.5 * (j % 2) as Real) * r0;
            let y = j as Real * r0 * (3.0_f64).sqrt() / 2.0;
            v.push(Point3::new(x, y, 0.0));
        }
    }
    v
}

/// A material with every complete-interaction term enabled (cohesion,
/// co-planarity, co-normality, co-circularity, form), optionally with an
/// anisotropic weight and friction; no spin.
pub fn full_material(anisotropic: bool, friction: Real) -> Material {
    Material {
        spacing: Some(Spacing::Cohesion(CohesionParams::default())),
        weight: WeightParams {
            shape: if anisotropic {
                WeightShape::Anisotropic { b: 0.7 }
            } else {
                WeightShape::Isotropic
            },
            ..Default::default()
        },
        coplanarity: 0.8,
        conormality: 0.5,
        cocircularity: 0.3,
        form: 0.6,
        friction,
        ..Default::default()
    }
}

/// A spacing-only material: cohesion with a cut-off of 1.5 r0 (only nearest
/// neighbours of a hexagonal sheet interact at rest).
pub fn spacing_material() -> Material {
    Material {
        spacing: Some(Spacing::Cohesion(CohesionParams {
            cutoff: Some(1.5),
            ..Default::default()
        })),
        ..Material::empty()
    }
}

/// A jittered cluster of `n` particles with random frames, curvatures and
/// velocities, on a jittered cubic lattice of spacing ~r0 = 1.
pub fn random_cluster(rng: &mut Rng, n: usize, objects: u32) -> Particles {
    let side = (n as Real).cbrt().ceil() as usize;
    let mut p = Particles::new();
    for k in 0..n {
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        let pos = Point3::new(i as Real, j as Real, l as Real) + rng.vec3(0.15);
        let mut d = ParticleDesc::at(pos);
        d.orientation = rng.quat(3.0);
        d.normal_axis = rng.vec3(1.0) + Vec3::new(0.0, 0.0, 0.5);
        d.velocity = rng.vec3(0.3);
        d.angular_velocity = rng.vec3(0.3);
        d.inertia = Vec3::new(0.1, 0.15, 0.2);
        d.mass = rng.uniform(0.5, 2.0);
        d.curvature = rng.uniform(-0.5, 0.5);
        d.object = (k as u32) % objects.max(1);
        p.push(d).unwrap();
    }
    p
}

/// A hexagonal sheet with noise in z, in the plane, and in the normals.
pub fn noisy_sheet(rng: &mut Rng, nx: usize, ny: usize, noise: Real) -> Particles {
    let mut p = Particles::new();
    for pos in hex_sheet(nx, ny, 1.0) {
        let jitter = Vec3::new(
            rng.uniform(-noise, noise),
            rng.uniform(-noise, noise),
            rng.uniform(-noise, noise),
        );
        let mut d = ParticleDesc::at(pos + jitter);
        d.orientation = rng.quat(noise);
        p.push(d).unwrap();
    }
    p
}

/// Runs `f` on a local pool of `threads` workers.
pub fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}
