//! The fit's particle world at unit spacing: the seeds fixed, the
//! filling rounds, the release of the seeds and the relaxation (module
//! docs of [`super`], stages 3 and 4).

use rayon::prelude::*;

use op_dynamics::interactions::spacing::Spacing;
use op_dynamics::interactions::CohesionParams;
use op_dynamics::{
    ExternalParams, Flags, Material, ParamError, ParticleDesc, Particles, Point3, Real, Scheme,
    Vec3, World, WorldError, WorldParams,
};

use crate::creation::{CreationParams, GrowingParams, StretchingParams};

use super::{rounds, DataNeighbourhood, FitError, FitParams, MAX_PARTICLES, STEP};

/// The material and world of a fit's particles at unit spacing: cohesion
/// at the rest distance `rest` and co-circularity (module docs, stage 4).
pub(super) struct Relaxation {
    rest: Real,
    cutoff: Real,
    material: Material,
    params: WorldParams,
}

impl Relaxation {
    pub(super) fn new(rest: Real) -> Self {
        // At least `rest + 0.45`: the taper (from 0.9 cutoff) must start
        // beyond the maximum attraction, about `rest + 0.3` for the default
        // `alpha` whatever `rest` (a rest of 0.83 spacings, from the
        // 6th-neighbour spacing on samples along a curve, failed with
        // `1.5 rest`).
        let cutoff = (1.5 * rest).max(rest + 0.45);
        let material = Material {
            spacing: Some(Spacing::Cohesion(CohesionParams {
                r0: rest,
                cutoff: Some(cutoff),
                ..CohesionParams::default()
            })),
            cocircularity: 5.0,
            ..Material::empty()
        };
        let world_params = WorldParams {
            scheme: Scheme::VelocityVerlet,
            dt: STEP,
            external: ExternalParams {
                linear_damping: 2.0,
                angular_damping: 0.2,
                ..ExternalParams::default()
            },
            ..WorldParams::default()
        };
        Relaxation {
            rest,
            cutoff,
            material,
            params: world_params,
        }
    }

    /// A world of the seeds, fixed in position and orientation.
    pub(super) fn seed_world(
        &self,
        seeds: &[Point3],
        normals: &[Vec3],
    ) -> Result<World, WorldError> {
        // The descriptions (an orientation from each normal) in parallel,
        // pushed in order.
        let descs: Vec<ParticleDesc> = seeds
            .par_iter()
            .zip(normals)
            .with_min_len(4096)
            .map(|(p, nrm)| {
                let mut d = ParticleDesc::at(*p).with_normal(*nrm);
                d.flags = Flags::FIXED_POSITION.union(Flags::FIXED_ORIENTATION);
                d
            })
            .collect();
        let mut particles = Particles::new();
        for d in descs {
            particles.push(d)?;
        }
        World::new(
            particles,
            std::slice::from_ref(&self.material),
            self.params.clone(),
        )
    }

    /// Rounds of the creation rules near the data, each followed by a
    /// short relaxation of the new particles (seed 000 §7), until a round
    /// creates nothing or [`FitParams::max_rounds`].
    pub(super) fn fill(
        &self,
        world: &mut World,
        params: &FitParams,
        open: bool,
        seeds: &[Point3],
        seed_normals: &[Vec3],
    ) -> Result<(), FitError> {
        let rest = self.rest;
        let mut creation = CreationParams::new(rest);
        creation.stretching = Some(StretchingParams {
            d_min: params.d_min,
            d_max: params.d_max,
            reach: (0.6 * params.d_max).max(1.5),
            ..StretchingParams::default()
        });
        if !open {
            creation.growing = Some(GrowingParams {
                max_gap: 170f64.to_radians(),
                ..GrowingParams::default()
            });
        }
        creation.max_particles = (20 * seeds.len() + 1000).min(MAX_PARTICLES);
        let near = DataNeighbourhood::new(seeds, seed_normals, rest, params.d_max, open);
        for _ in 0..params.max_rounds {
            let mut descs = creation.candidates(world.particles())?;
            descs.retain(|d| near.contains(&d.position));
            if descs.is_empty() {
                break;
            }
            let new = world.insert_particles(&descs)?;
            rounds::relax_new(
                world,
                &new,
                0.1,
                self.cutoff,
                0.5 * rest,
                &self.material,
                &self.params,
            )?;
        }
        Ok(())
    }
}

/// Releases the seeds (seed 000 §7): the particles with the given ids are
/// removed and inserted again with their fixed flags cleared, at rest, in
/// the order given (op-dynamics fixes a particle's flags when it is
/// inserted). Returns their new ids, in the order of `ids`.
///
/// # Errors
/// An id that names no live particle (nothing is changed then).
pub fn release(world: &mut World, ids: &[u32]) -> Result<Vec<u32>, WorldError> {
    let p = world.particles();
    let mut descs = Vec::with_capacity(ids.len());
    for &id in ids {
        let Some(s) = p.slot_of(id) else {
            return Err(WorldError::from(ParamError::Invalid {
                field: "ids".into(),
                message: format!("particle id {id} does not exist"),
            }));
        };
        let mut d = at_rest(p, s);
        d.flags.remove(Flags::FIXED_POSITION);
        d.flags.remove(Flags::FIXED_ORIENTATION);
        descs.push(d);
    }
    world.remove_particles(ids)?;
    world.insert_particles(&descs)
}

/// The particle in `slot` at rest: its place, frame and attributes, no
/// velocity and the default temperature (as the fit's particles are).
pub(crate) fn at_rest(p: &Particles, slot: usize) -> ParticleDesc {
    let fresh = ParticleDesc::at(p.positions()[slot]);
    ParticleDesc {
        velocity: fresh.velocity,
        angular_velocity: fresh.angular_velocity,
        temperature: fresh.temperature,
        ..p.desc(slot)
    }
}

/// Advances `world` by `t` (a divergence is an error).
pub(super) fn advance(world: &mut World, t: Real) -> Result<(), FitError> {
    let end = world.time() + t;
    Ok(world.advance_to(end)?)
}
