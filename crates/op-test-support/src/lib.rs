//! Test support of the oriented-particles workspace (unpublished): the one
//! seeded generator ([`Rng`], SplitMix64), small particle sets (hex sheets,
//! random clusters, noisy sheets), materials, a fixed-size thread pool
//! ([`in_pool`], for the same-bits-at-any-thread-count checks), temporary
//! directories ([`temp_dir`]), and the checks every force term must pass:
//! energy gradients against finite differences
//! ([`assert_energy_gradients`]) and momentum conservation
//! ([`assert_momentum_conserved`]).

use op_dynamics::interactions::{CohesionParams, Spacing, WeightParams, WeightShape};
use op_dynamics::{Material, ParticleDesc, Particles, Point3, Quat, Real, Vec3, World};

/// SplitMix64: a tiny deterministic generator for seeded configurations.
pub struct Rng(u64);

impl Rng {
    /// The generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (`n > 0`; the modulo bias is below `n / 2^64`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: Real, hi: Real) -> Real {
        lo + (hi - lo) * ((self.next_u64() >> 11) as Real / (1u64 << 53) as Real)
    }
    /// A vector with components uniform in `[-s, s)`.
    pub fn vec3(&mut self, s: Real) -> Vec3 {
        Vec3::new(
            self.uniform(-s, s),
            self.uniform(-s, s),
            self.uniform(-s, s),
        )
    }
    /// A rotation whose scaled axis has components uniform in `[-angle, angle)`.
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

/// The description of the particle in `slot`, current state included.
pub fn desc_of(p: &Particles, slot: usize) -> ParticleDesc {
    p.desc(slot)
}

/// Asserts that the forces and torques of the particles in `slots` are
/// the central differences (step 1e-6) of the world's potential energy,
/// under translations and small world rotations of each particle.
pub fn assert_energy_gradients(w: &mut World, slots: &[usize], case: &str) {
    let energy = |w: &mut World| w.evaluate_forces().2;
    let (f, t, _) = w.evaluate_forces();
    let (f, t) = (f.to_vec(), t.to_vec());
    let h = 1e-6;
    for &slot in slots {
        for k in 0..3 {
            let mut e = Vec3::zeros();
            e[k] = h;
            let p0 = w.particles().positions()[slot];
            w.particles_mut().set_position(slot, p0 + e);
            let ep = energy(w);
            w.particles_mut().set_position(slot, p0 - e);
            let em = energy(w);
            w.particles_mut().set_position(slot, p0);
            let fd = -(ep - em) / (2.0 * h);
            let scale = f[slot].norm().max(1e-3);
            assert!(
                (fd - f[slot][k]).abs() <= 1e-6 * scale + 1e-8,
                "{case}: force slot {slot} axis {k}: fd {fd} vs {}",
                f[slot][k]
            );
            let q0 = w.particles().orientations()[slot];
            w.particles_mut()
                .set_orientation(slot, Quat::from_scaled_axis(e) * q0);
            let ep = energy(w);
            w.particles_mut()
                .set_orientation(slot, Quat::from_scaled_axis(-e) * q0);
            let em = energy(w);
            w.particles_mut().set_orientation(slot, q0);
            let fd = -(ep - em) / (2.0 * h);
            let scale = t[slot].norm().max(1e-3);
            assert!(
                (fd - t[slot][k]).abs() <= 1e-6 * scale + 1e-8,
                "{case}: torque slot {slot} axis {k}: fd {fd} vs {}",
                t[slot][k]
            );
        }
    }
}

/// Asserts that the world's forces and torques (internal ones: build it
/// without external actions) sum to no force and no moment:
/// `sum F = 0`, `sum (p x F + tau) = 0`, relative to their size.
pub fn assert_momentum_conserved(w: &mut World, case: &str) {
    let (f, t, _) = w.evaluate_forces();
    let (f, t) = (f.to_vec(), t.to_vec());
    let pos = w.particles().positions();
    let (mut lin, mut ang, mut scale) = (Vec3::zeros(), Vec3::zeros(), 0.0);
    for i in 0..f.len() {
        lin += f[i];
        ang += pos[i].coords.cross(&f[i]) + t[i];
        scale += f[i].norm() * (1.0 + pos[i].coords.norm()) + t[i].norm();
    }
    assert!(scale > 1.0, "{case}: the test needs non-trivial forces");
    assert!(
        lin.norm() <= 1e-12 * scale,
        "{case}: linear {lin:?} (scale {scale})"
    );
    assert!(
        ang.norm() <= 1e-12 * scale,
        "{case}: angular {ang:?} (scale {scale})"
    );
}

/// A new, empty directory under the system's temporary directory, unique
/// to this call (`op-test-<tag>-<pid>-<n>`).
///
/// # Panics
///
/// If the directory cannot be created.
pub fn temp_dir(tag: &str) -> std::path::PathBuf {
    let dir = fresh_path(tag);
    std::fs::create_dir_all(&dir).expect("create the test's temporary directory");
    dir
}

/// A path under the system's temporary directory, unique to this call
/// (`op-test-<tag>-<pid>-<n>`), where nothing exists: for programs under
/// test that create their output directory themselves.
pub fn fresh_path(tag: &str) -> std::path::PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let path = std::env::temp_dir().join(format!("op-test-{tag}-{}-{n}", std::process::id()));
    // A leftover of an earlier run with the same pid: start from nothing.
    let _ = std::fs::remove_dir_all(&path);
    path
}

/// The workspace's root directory (where `scenes/` and `tests/data/` are).
pub fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The shipped scenes' directory, `scenes/`.
pub fn scenes_dir() -> std::path::PathBuf {
    workspace_root().join("scenes")
}

/// The shipped scenes at the top of `scenes/` (`.ron` and `.json`), sorted.
///
/// # Panics
///
/// If `scenes/` cannot be read.
pub fn scene_files() -> Vec<std::path::PathBuf> {
    let mut v: Vec<std::path::PathBuf> = std::fs::read_dir(scenes_dir())
        .expect("scenes/ exists")
        .map(|e| e.expect("a readable entry of scenes/").path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("ron" | "json")))
        .collect();
    v.sort();
    v
}

/// Every scene file (`.ron` and `.json`) under `roots`, their
/// subfolders included, sorted.
///
/// # Panics
///
/// If a folder cannot be read.
pub fn scene_files_under(roots: &[std::path::PathBuf]) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut dirs = roots.to_vec();
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).expect("a readable folder of scenes") {
            let p = e.expect("a readable entry").path();
            if p.is_dir() {
                dirs.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("ron" | "json")) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}
