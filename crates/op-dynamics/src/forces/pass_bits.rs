//! Test support of the uniform passes: the 12-6 material they run, a
//! jittered block of particles and the bits of what a pass sums, at a
//! given thread count (the lanes against the scalar pair, one against two
//! threads).

use super::{BlockScratch, Sums};
use crate::interactions::test_support::Rng;
use crate::interactions::{LennardJonesParams, Material, PreparedMaterial, Spacing};
use crate::math::{Point3, Real, Vec3};

/// 12-6 Lennard-Jones with its well at 1.12 (`r0 = 2^(1/6)`), cut off at
/// 2.5 with a taper over the last 10%: the material of the SIMD and
/// cluster kernels.
pub(super) fn lj_12_6_material() -> PreparedMaterial {
    Material {
        spacing: Some(Spacing::LennardJones(LennardJonesParams {
            r0: (2.0 as Real).powf(1.0 / 6.0),
            taper: 0.1,
            ..Default::default()
        })),
        ..Material::empty()
    }
    .prepare()
    .unwrap()
}

/// `side³` particles on a cubic lattice of spacing 1.1, each coordinate
/// jittered by up to ±0.1.
pub(super) fn jittered_block(side: usize, rng: &mut Rng) -> Vec<Point3> {
    (0..side * side * side)
        .map(|k| {
            let (x, y, z) = (k % side, (k / side) % side, k / (side * side));
            let mut jitter = || 0.2 * (rng.uniform() - 0.5);
            Point3::new(
                1.1 * x as Real + jitter(),
                1.1 * y as Real + jitter(),
                1.1 * z as Real + jitter(),
            )
        })
        .collect()
}

/// The bits of the forces, torques and energies (in that order) that
/// `pass` sums for `n` particles, run in a pool of `threads` threads.
pub(super) fn pass_bits(
    n: usize,
    threads: usize,
    pass: impl Fn(&mut Vec<BlockScratch>, Sums<'_>) + Sync,
) -> Vec<u64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let (mut f, mut t, mut e) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n], vec![0.0; n]);
        let mut blocks = Vec::new();
        pass(
            &mut blocks,
            Sums {
                forces: &mut f,
                torques: &mut t,
                energies: &mut e,
            },
        );
        f.iter()
            .chain(&t)
            .flat_map(|v| [v.x, v.y, v.z])
            .chain(e)
            .map(Real::to_bits)
            .collect()
    })
}
