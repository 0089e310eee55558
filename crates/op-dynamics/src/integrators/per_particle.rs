//! The per-particle updates of the integrators, run in parallel.
//!
//! An integrator's kick and drift (seed 000 §4: `ṗ = v`, `v̇ = f / m`, the
//! rotational part of [`super::velocity_verlet`]) update each particle from
//! its own state, force and torque only, so the particles can be updated in
//! any order, on any thread, with the same bits. The state is cut into
//! fixed chunks of [`CHUNK`] consecutive particles (a constant, not a
//! function of the thread count) that rayon runs in parallel; worlds of at
//! most one chunk run on the caller's thread (no hand-off to the pool for
//! the small scenes that take many short steps).
//!
//! Measured (oriented fcc block of LAMMPS' `in.lj`, 32,000 particles,
//! velocity Verlet with the rotational midpoint drift): the two serial
//! per-particle loops were 18% of the step's CPU time at one thread, all of
//! it on the calling thread while the pool's threads waited.

use rayon::prelude::*;

use super::{Particle, StateMut};
use crate::math::{Point3, Quat, Vec3};

/// Particles per parallel task (see the module docs).
pub(crate) const CHUNK: usize = 1024;

/// Calls `f(i, particle, a_i, b_i)` for every particle `i` of `state` with
/// its state (written back afterwards) and its slots of the two
/// per-particle arrays `a` and `b` (the integrator's own per-particle
/// quantities, such as velocity Verlet's angular momenta), in parallel
/// over chunks of [`CHUNK`] particles. `a` and `b` must have the state's
/// length.
pub(crate) fn update_each<F>(state: StateMut<'_>, a: &mut [Vec3], b: &mut [Vec3], f: F)
where
    F: Fn(usize, &mut Particle, &mut Vec3, &mut Vec3) + Sync,
{
    let n = state.len();
    assert!(
        a.len() == n && b.len() == n,
        "per-particle arrays and state have different lengths"
    );
    let chunk = |c: usize,
                 p: &mut [Point3],
                 v: &mut [Vec3],
                 q: &mut [Quat],
                 w: &mut [Vec3],
                 a: &mut [Vec3],
                 b: &mut [Vec3]| {
        for k in 0..p.len() {
            let mut s = Particle {
                p: p[k],
                v: v[k],
                q: q[k],
                w: w[k],
            };
            f(c * CHUNK + k, &mut s, &mut a[k], &mut b[k]);
            p[k] = s.p;
            v[k] = s.v;
            q[k] = s.q;
            w[k] = s.w;
        }
    };
    let StateMut {
        positions,
        velocities,
        orientations,
        angular_velocities,
    } = state;
    if n <= CHUNK {
        chunk(
            0,
            positions,
            velocities,
            orientations,
            angular_velocities,
            a,
            b,
        );
        return;
    }
    positions
        .par_chunks_mut(CHUNK)
        .zip(velocities.par_chunks_mut(CHUNK))
        .zip(orientations.par_chunks_mut(CHUNK))
        .zip(angular_velocities.par_chunks_mut(CHUNK))
        .zip(a.par_chunks_mut(CHUNK))
        .zip(b.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (((((p, v), q), w), a), b))| chunk(c, p, v, q, w, a, b));
}

/// Calls `f(i, position, velocity)` for every particle `i`, in parallel
/// over chunks of [`CHUNK`] particles (the translation-only updates: the
/// orientations and angular velocities are not touched).
pub(crate) fn update_translation<F>(state: StateMut<'_>, f: F)
where
    F: Fn(usize, &mut Point3, &mut Vec3) + Sync,
{
    let n = state.len();
    let chunk = |c: usize, p: &mut [Point3], v: &mut [Vec3]| {
        for (k, (p, v)) in p.iter_mut().zip(v.iter_mut()).enumerate() {
            f(c * CHUNK + k, p, v);
        }
    };
    if n <= CHUNK {
        chunk(0, state.positions, state.velocities);
        return;
    }
    state
        .positions
        .par_chunks_mut(CHUNK)
        .zip(state.velocities.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (p, v))| chunk(c, p, v));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Real;

    /// Every particle is visited once with its own index and slots, on
    /// one thread and on two, for sizes around the chunk boundaries.
    #[test]
    fn every_particle_is_updated_once_with_its_own_slots() {
        for n in [0, 1, CHUNK - 1, CHUNK, CHUNK + 1, 3 * CHUNK + 7] {
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut p: Vec<Point3> = (0..n).map(|i| Point3::new(i as Real, 0.0, 0.0)).collect();
                let mut v = vec![Vec3::zeros(); n];
                let mut q = vec![Quat::identity(); n];
                let mut w = vec![Vec3::zeros(); n];
                let mut a = vec![Vec3::zeros(); n];
                let mut b: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.0, i as Real, 0.0)).collect();
                pool.install(|| {
                    let state = StateMut {
                        positions: &mut p,
                        velocities: &mut v,
                        orientations: &mut q,
                        angular_velocities: &mut w,
                    };
                    update_each(state, &mut a, &mut b, |i, s, ai, bi| {
                        assert_eq!(s.p.x, i as Real);
                        assert_eq!(bi.y, i as Real);
                        s.v.x += 1.0;
                        s.w.z = 2.0 * i as Real;
                        ai.x += 1.0;
                    });
                    let state = StateMut {
                        positions: &mut p,
                        velocities: &mut v,
                        orientations: &mut q,
                        angular_velocities: &mut w,
                    };
                    update_translation(state, |i, pi, vi| {
                        assert_eq!(pi.x, i as Real);
                        vi.y += 1.0;
                    });
                });
                for i in 0..n {
                    assert_eq!(v[i], Vec3::new(1.0, 1.0, 0.0), "n {n} particle {i}");
                    assert_eq!(w[i].z, 2.0 * i as Real);
                    assert_eq!(a[i].x, 1.0);
                }
            }
        }
    }
}
