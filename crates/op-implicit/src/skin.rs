//! An implicit object skinned on oriented particles (seed 002 §6: "we
//! propose the use of an oriented particles system to handle skeletons").

use std::sync::atomic::{AtomicUsize, Ordering};

use op_dynamics::{Particles, Point3, Quat, World};
use rayon::prelude::*;

use crate::error::SkinError;
use crate::field::Field;
use crate::primitives::{PosedPrimitive, Primitive};
use crate::stretch::StretchCompensation;

/// The part of a [`Skin`] that changes during a run ([`Skin::state`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SkinState {
    attachments: Vec<(u32, Primitive)>,
    stretch: Option<StretchCompensation>,
}

impl SkinState {
    /// Number of attachments (primitives).
    pub fn len(&self) -> usize {
        self.attachments.len()
    }

    /// Whether it has no attachment.
    pub fn is_empty(&self) -> bool {
        self.attachments.is_empty()
    }

    /// The field of these attachments posed where `pose` puts each
    /// particle (position and orientation by id), before the stretch
    /// compensation ([`SkinState::compensate`] adds it). Errors: the first
    /// primitive on a particle `pose` does not know.
    pub fn posed_uncompensated(
        &self,
        pose: impl Fn(u32) -> Option<(Point3, Quat)> + Sync,
    ) -> Result<Field, SkinError> {
        Ok(Field::new(pose_attachments(&self.attachments, pose)?))
    }

    /// [`SkinState::posed_uncompensated`] without its pruning grid, for a
    /// caller that lists it where it will read it
    /// ([`Field::list_within`]): until then every value is 0.
    pub(crate) fn posed_unlisted(
        &self,
        pose: impl Fn(u32) -> Option<(Point3, Quat)> + Sync,
    ) -> Result<Field, SkinError> {
        Ok(Field::new_within(
            pose_attachments(&self.attachments, pose)?,
            Some(&[]),
        ))
    }

    /// Applies the stretch compensation's held references to `field`
    /// (posed by [`SkinState::posed_uncompensated`]), on the primitives
    /// that meet one of the boxes `regions` only when given
    /// ([`StretchCompensation::apply_held_within`]).
    pub fn compensate(&self, field: &mut Field, regions: Option<&[(Point3, Point3)]>) {
        if let Some(stretch) = &self.stretch {
            stretch.apply_held_within(field, regions);
        }
    }
}

/// An implicit object: skeleton primitives attached to particles of an
/// op-dynamics world, and the field they produce at the particles' current
/// poses. Call [`Skin::repose`] after the world moved to follow it.
#[derive(Clone, Debug)]
pub struct Skin {
    attachments: Vec<(u32, Primitive)>,
    field: Field,
    stretch: Option<StretchCompensation>,
}

impl Skin {
    /// Builds the skin of `attachments` (particle id, primitive in that
    /// particle's body frame) posed on `world`'s particles.
    pub fn new(world: &World, attachments: Vec<(u32, Primitive)>) -> Result<Skin, SkinError> {
        Self::from_particles(world.particles(), attachments)
    }

    /// As [`Skin::new`], from a particle store.
    pub fn from_particles(
        particles: &Particles,
        attachments: Vec<(u32, Primitive)>,
    ) -> Result<Skin, SkinError> {
        if let Some(index) = attachments.iter().position(|(_, p)| !p.is_valid()) {
            return Err(SkinError::InvalidPrimitive { index });
        }
        let mut skin = Skin {
            attachments,
            field: Field::default(),
            stretch: None,
        };
        skin.repose_particles(particles)?;
        Ok(skin)
    }

    /// Re-poses every primitive from the current particle frames of
    /// `world` and rebuilds the field's pruning grid.
    pub fn repose(&mut self, world: &World) -> Result<(), SkinError> {
        self.repose_particles(world.particles())
    }

    /// As [`Skin::repose`], from a particle store.
    pub fn repose_particles(&mut self, particles: &Particles) -> Result<(), SkinError> {
        let positions = particles.positions();
        let orientations = particles.orientations();
        let posed = pose_attachments(&self.attachments, |id| {
            let slot = particles.slot_of(id).filter(|&s| s < positions.len())?;
            Some((positions[slot], orientations[slot]))
        })?;
        self.field = Field::new(posed);
        if let Some(stretch) = self.stretch.as_mut() {
            stretch.apply(&mut self.field);
        }
        Ok(())
    }

    /// Whether `state` is this skin's [`Skin::state`] (without copying it).
    pub fn has_state(&self, state: &SkinState) -> bool {
        self.attachments == state.attachments && self.stretch == state.stretch
    }

    /// What changes of the skin during a run (a checkpoint saves it):
    /// its attachments (particles created by the creation rules gain one,
    /// removed particles lose theirs) and the stretch references kept. The
    /// field is not part of it: it follows from them at each pose.
    pub fn state(&self) -> SkinState {
        SkinState {
            attachments: self.attachments.clone(),
            stretch: self.stretch.clone(),
        }
    }

    /// Puts back a state taken by [`Skin::state`] and poses the skin on
    /// `particles`; the skin is unchanged when it fails (an invalid
    /// primitive, a particle that is not in `particles`).
    pub fn restore(&mut self, state: SkinState, particles: &Particles) -> Result<(), SkinError> {
        if let Some(index) = state.attachments.iter().position(|(_, p)| !p.is_valid()) {
            return Err(SkinError::InvalidPrimitive { index });
        }
        let mut restored = Skin {
            attachments: state.attachments,
            field: Field::default(),
            stretch: state.stretch,
        };
        restored.repose_particles(particles)?;
        *self = restored;
        Ok(())
    }

    /// From now on, keeps the skin's thickness as the object stretches
    /// ([`crate::stretch`]), with the reference densities `compensation`
    /// (measured on [`Skin::field`] at rest), applied now and at every
    /// [`Skin::repose`].
    pub fn keep_thickness(&mut self, mut compensation: StretchCompensation) {
        compensation.apply(&mut self.field);
        self.stretch = Some(compensation);
    }

    /// Attaches more primitives (particle id, primitive in its body frame),
    /// after the existing ones: particles the creation rules added to the
    /// skinned object. They enter the field at the next [`Skin::repose`].
    ///
    /// # Errors
    ///
    /// An invalid primitive (nothing is attached then).
    pub fn attach(&mut self, attachments: &[(u32, Primitive)]) -> Result<(), SkinError> {
        if let Some(k) = attachments.iter().position(|(_, p)| !p.is_valid()) {
            return Err(SkinError::InvalidPrimitive {
                index: self.attachments.len() + k,
            });
        }
        self.attachments.extend_from_slice(attachments);
        Ok(())
    }

    /// Keeps the attachments whose particle id `keep` accepts (the others'
    /// particles were removed: merged, erased, released). The field follows
    /// at the next [`Skin::repose`]. Returns how many were dropped.
    pub fn retain(&mut self, mut keep: impl FnMut(u32) -> bool) -> usize {
        let before = self.attachments.len();
        self.attachments.retain(|(id, _)| keep(*id));
        if let Some(stretch) = self.stretch.as_mut() {
            let kept: std::collections::HashSet<u32> =
                self.attachments.iter().map(|(id, _)| *id).collect();
            stretch.retain(|id| kept.contains(&id));
        }
        before - self.attachments.len()
    }

    /// The (particle id, primitive) attachments, in the order given.
    pub fn attachments(&self) -> &[(u32, Primitive)] {
        &self.attachments
    }

    /// The field at the last pose; `field().primitives()[i]` is
    /// `attachments()[i]` posed.
    pub fn field(&self) -> &Field {
        &self.field
    }
}

/// `attachments` posed where `pose` puts each particle, collected in place
/// (an indexed collect; a collect into `Result` gathers pieces and copies
/// them, 1.6% of a skinned cloth's run), a primitive on an unknown particle
/// posed at the origin until the error, the first such primitive, is
/// returned.
fn pose_attachments(
    attachments: &[(u32, Primitive)],
    pose: impl Fn(u32) -> Option<(Point3, Quat)> + Sync,
) -> Result<Vec<PosedPrimitive>, SkinError> {
    let unknown = AtomicUsize::new(usize::MAX);
    let posed: Vec<_> = attachments
        .par_iter()
        .with_min_len(op_dynamics::MIN_PARALLEL_LEN)
        .enumerate()
        .map(|(index, &(id, prim))| {
            let (position, orientation) = pose(id).unwrap_or_else(|| {
                unknown.fetch_min(index, Ordering::Relaxed);
                (Point3::origin(), Quat::identity())
            });
            prim.posed(id, &position, &orientation)
        })
        .collect();
    match unknown.into_inner() {
        usize::MAX => Ok(posed),
        index => Err(SkinError::UnknownParticle {
            index,
            id: attachments[index].0,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::ISO;
    use crate::polygonize::{polygonize, PolygonizeParams};
    use op_dynamics::{Material, ParticleDesc, Point3, Quat, Real, Vec3, WorldParams};

    fn row_world(n: usize) -> World {
        let mut particles = Particles::new();
        for i in 0..n {
            particles
                .push(ParticleDesc::at(Point3::new(i as Real * 0.5, 0.0, 0.0)))
                .unwrap();
        }
        World::new(particles, &[Material::default()], WorldParams::default()).unwrap()
    }

    fn squares(n: u32) -> Vec<(u32, Primitive)> {
        (0..n)
            .map(|id| (id, Primitive::square(Vec3::z(), 0.25, 0.4)))
            .collect()
    }

    #[test]
    fn moving_and_turning_particles_moves_the_skin() {
        let mut world = row_world(4);
        let mut skin = Skin::new(&world, squares(4)).unwrap();
        let params = PolygonizeParams::with_cell_size(0.05);
        let before = polygonize(skin.field(), &params).unwrap();
        let top = |m: &crate::Mesh| m.positions().iter().map(|p| p.z).fold(Real::MIN, Real::max);
        assert!(top(&before) < 0.4);

        // Lift particle 3 and stand it on its edge (normal along +x).
        let old = Point3::new(1.5, 0.0, 0.0);
        let new = Point3::new(1.5, 0.0, 1.0);
        let slot = world.particles().slot_of(3).unwrap();
        world.particles_mut().set_position(slot, new);
        let turn = Quat::rotation_between(&Vec3::z(), &Vec3::x()).unwrap();
        world.particles_mut().set_orientation(slot, turn);
        // The field is still at the old pose until re-posed.
        assert!(skin.field().value(&old) > ISO);
        skin.repose(&world).unwrap();
        assert!(skin.field().value(&old) < ISO);
        assert!(skin.field().value(&new) > ISO);
        // The turned square now extends along z, not along x.
        assert!(skin.field().value(&(new + Vec3::new(0.0, 0.0, 0.3))) > ISO);
        assert!(skin.field().value(&(new + Vec3::new(0.3, 0.0, 0.0))) < ISO);
        let after = polygonize(skin.field(), &params).unwrap();
        assert!(top(&after) > 1.3);
        assert!(after.is_closed_oriented_manifold());
        assert!(after.signed_volume() > 0.0);
    }

    #[test]
    fn bad_attachments_are_reported() {
        let world = row_world(2);
        let err = Skin::new(
            &world,
            vec![
                (0, Primitive::point(Vec3::zeros(), 0.3)),
                (7, Primitive::point(Vec3::zeros(), 0.3)),
            ],
        );
        assert_eq!(
            err.unwrap_err(),
            SkinError::UnknownParticle { index: 1, id: 7 }
        );
        let err = Skin::new(&world, vec![(0, Primitive::point(Vec3::zeros(), -1.0))]);
        assert_eq!(err.unwrap_err(), SkinError::InvalidPrimitive { index: 0 });
    }

    /// A pose that does not know a particle fails with the first primitive
    /// on it, at any thread count; otherwise the field is the world's.
    #[test]
    fn posing_reports_the_first_unknown_particle() {
        let n = 3000;
        let world = row_world(n);
        let state = Skin::new(&world, squares(n as u32)).unwrap().state();
        let known = |id: u32| {
            let p = world.particles();
            let s = p.slot_of(id)?;
            Some((p.positions()[s], p.orientations()[s]))
        };
        let field = state.posed_uncompensated(known).unwrap();
        let skin = Skin::new(&world, squares(n as u32)).unwrap();
        assert_eq!(field.primitives(), skin.field().primitives());
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let err = pool.install(|| {
                state.posed_uncompensated(|id| match id % 1000 == 999 {
                    true => None,
                    false => known(id),
                })
            });
            assert_eq!(
                err.unwrap_err(),
                SkinError::UnknownParticle {
                    index: 999,
                    id: 999
                },
                "{threads} threads"
            );
        }
    }

    /// Timing probe, run in release:
    /// `cargo test -p op-implicit --release -- --ignored --nocapture`.
    /// 1024 particles on a flat spiral (seed 002 fig. 5-6), each with a square.
    #[test]
    #[ignore]
    fn timing_1k_skinned_spiral() {
        use std::time::Instant;
        let mut particles = Particles::new();
        let n = 1024;
        for i in 0..n {
            let t = 0.05 * i as Real;
            let r = 0.3 + 0.06 * t;
            let p = Point3::new(r * t.cos(), r * t.sin(), 0.0);
            particles.push(ParticleDesc::at(p)).unwrap();
        }
        let world = World::new(particles, &[Material::default()], WorldParams::default()).unwrap();
        let t0 = Instant::now();
        let skin = Skin::new(&world, squares(n as u32)).unwrap();
        let build = t0.elapsed();
        let (lo, hi) = skin.field().support_box().unwrap();
        let m = 100usize;
        let pts: Vec<Point3> = (0..m * m * m)
            .map(|i| {
                let u = Vec3::new(
                    (i % m) as Real,
                    ((i / m) % m) as Real,
                    (i / (m * m)) as Real,
                ) / m as Real;
                lo + (hi - lo).component_mul(&u)
            })
            .collect();
        let t1 = Instant::now();
        let vg = skin.field().values_and_gradients(&pts);
        let eval = t1.elapsed();
        assert_eq!(vg.len(), pts.len());
        for h in [0.04, 0.02] {
            let t2 = Instant::now();
            let mesh = polygonize(skin.field(), &PolygonizeParams::with_cell_size(h)).unwrap();
            eprintln!(
                "h {h}: polygonize {:?}, {} triangles, manifold {}",
                t2.elapsed(),
                mesh.triangles().len(),
                mesh.is_closed_oriented_manifold()
            );
        }
        eprintln!(
            "1024 squares: skin build/repose {build:?}; 1e6 value+gradient {eval:?}; box {:?}",
            hi - lo
        );
    }
}
