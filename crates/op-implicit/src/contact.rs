//! Contact of a skin against a rigid parry collider (seed 002 §6;
//! Gascuel 1993 with only the deformable skin compressed).
//!
//! The skin is sampled (for instance at the vertices of its polygonization,
//! [`crate::Mesh::positions`]). Each sample inside the collider gets the
//! reaction `k * depth * n`, where `n` is the collider's outward normal at
//! the closest surface point and `depth` the distance to it. The reaction is
//! shared among the primitives producing the field at the sample, in
//! proportion to their field values there, and each share acts on the
//! primitive's particle as a force and a torque about the particle's
//! position: "reaction forces are then expressed at the skeleton center of
//! mass as a pair (force, torque) and integrated during the following time
//! step" (seed 002 §6).
//!
//! Samples are tested in parallel (ordered collect) and accumulated
//! serially in sample order, so the result does not depend on the thread
//! count. The stiffness is per sample: the total reaction grows with the
//! sampling density (keep the polygonization cell size fixed in a scene).
//! Contact between two implicit objects is in [`crate::implicit_contact`].

use std::collections::BTreeMap;

use op_dynamics::external::ExternalAccumulator;
use op_dynamics::{Point3, Real, Vec3, World};
use op_modeling::tools::signed_distance;
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::Shape;
use rayon::prelude::*;

use crate::field::{Field, ScalarField, ValueGradient};
use crate::kernel::ISO;

/// Parameters of [`collider_reactions`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Reaction per unit penetration depth, per sample, >= 0 (force/length).
    pub stiffness: Real,
}

/// Force and torque (world frame, torque about the particle's position)
/// on one particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reaction {
    /// Particle id.
    pub particle: u32,
    /// Force.
    pub force: Vec3,
    /// Torque about the particle's position.
    pub torque: Vec3,
}

/// The reactions of one contact evaluation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reactions {
    reactions: Vec<Reaction>,
    samples_in_contact: usize,
    total_force: Vec3,
    max_depth: Real,
}

impl Reactions {
    /// Reactions already summed per particle (in increasing particle id),
    /// from `samples` samples or nodes in contact.
    pub(crate) fn from_parts(reactions: Vec<Reaction>, samples: usize, total_force: Vec3) -> Self {
        Reactions {
            reactions,
            samples_in_contact: samples,
            total_force,
            max_depth: 0.0,
        }
    }

    /// Per-particle reactions, in increasing particle id.
    pub fn reactions(&self) -> &[Reaction] {
        &self.reactions
    }

    /// Number of samples in contact: inside the collider, or, for two
    /// skins ([`crate::ContactPair::reactions`]), edges of the contact
    /// energy's lattice with a positive integral.
    pub fn samples_in_contact(&self) -> usize {
        self.samples_in_contact
    }

    /// Sum of the samples' reactions (equal to the sum of the particle
    /// forces).
    pub fn total_force(&self) -> Vec3 {
        self.total_force
    }

    /// Depth of the deepest sample inside the collider
    /// ([`collider_reactions`]; 0 for implicit contact, which measures
    /// its overlap per sample, see [`crate::ContactSample`]).
    pub fn max_depth(&self) -> Real {
        self.max_depth
    }

    /// Adds every reaction to `world` for its next step
    /// (`World::add_external_force`).
    pub fn apply(&self, world: &mut World) {
        for r in &self.reactions {
            world.add_external_force(r.particle, r.force, r.torque);
        }
    }

    /// Adds every reaction to `held` (by particle id; `held` must hold
    /// every id): a force contributor that acts over a whole interval
    /// ([`op_dynamics::contributors`], `World::advance_to_with`).
    pub fn add_to(&self, held: &mut ExternalAccumulator) {
        for r in &self.reactions {
            held.add(r.particle, r.force, r.torque);
        }
    }
}

fn to_parry(p: &Point3) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

/// Reactions of the skin of `field`, sampled at `samples`, against
/// `collider` at `pose` (module doc for the model).
pub fn collider_reactions(
    field: &Field,
    samples: &[Point3],
    collider: &dyn Shape,
    pose: &Pose,
    params: &ContactParams,
) -> Reactions {
    let hits: Vec<Option<(Point3, Vec3, Real)>> = samples
        .par_iter()
        .map(|p| {
            let proj = collider.project_point(pose, to_parry(p), false);
            if !proj.is_inside {
                return None;
            }
            let surface = Vec3::new(proj.point.x, proj.point.y, proj.point.z);
            let out = surface - p.coords;
            let depth = out.norm();
            (depth > 0.0).then(|| (*p, out * params.stiffness, depth))
        })
        .collect();
    let mut acc = ReactionAccumulator::default();
    let mut max_depth: Real = 0.0;
    for (p, force, depth) in hits.into_iter().flatten() {
        acc.add(field, &p, force);
        max_depth = max_depth.max(depth);
    }
    Reactions {
        max_depth,
        ..acc.finish()
    }
}

/// A skin pressed against rigid colliders, deformed so that it lies on
/// their surfaces where it would enter them (Gascuel with only the
/// deformable skin compressed, seed 002 §6): the exported skin of an object
/// on an obstacle. With `s_k` the signed distance to collider `k`
/// (positive outside) and `g` a slope,
/// `f'(p) = min(f(p), min_k (ISO + g s_k(p)))`: continuous, equal to `f`
/// wherever `f < ISO + g s_k` (everywhere away from the colliders), below
/// the iso value inside them, so its iso-surface is the skin clipped
/// exactly at the collider surfaces, with the colliders' normals there.
pub struct ClippedField<'a, F: ScalarField + ?Sized> {
    field: &'a F,
    colliders: Vec<(&'a dyn Shape, Pose)>,
    slope: Real,
}

impl<'a, F: ScalarField + ?Sized> ClippedField<'a, F> {
    /// `field` clipped by `colliders` (shape, pose) with slope `slope`
    /// (> 0; `ISO / cell_size` makes the clip one cell thick).
    pub fn new(field: &'a F, colliders: Vec<(&'a dyn Shape, Pose)>, slope: Real) -> Self {
        ClippedField {
            field,
            colliders,
            slope,
        }
    }

    /// The smallest `ISO + g s_k` and its gradient, if any collider is
    /// near enough to matter at `p` (the clip only bites where it is below
    /// the field's largest value, 1).
    fn clip(&self, p: &Point3) -> Option<(Real, Vec3)> {
        let mut best: Option<(Real, Vec3)> = None;
        for (shape, pose) in &self.colliders {
            // Exactly on the surface the normal is undefined: s = 0 there.
            let (s, n) = signed_distance(*shape, pose, &p.coords).unwrap_or((0.0, Vec3::zeros()));
            let v = ISO + self.slope * s;
            if best.is_none_or(|(b, _)| v < b) {
                best = Some((v, self.slope * n));
            }
        }
        best
    }

    /// The clip's value at `p`: the smallest `ISO + g s_k`, if any
    /// collider.
    pub(crate) fn clip_value(&self, p: &Point3) -> Option<Real> {
        self.clip(p).map(|(v, _)| v)
    }

    /// A lower bound of the clip's value over the ball of centre `c` and
    /// radius `r` (a signed distance moves by at most the distance
    /// moved); infinite without colliders.
    pub(crate) fn clip_lower_bound(&self, c: &Point3, r: Real) -> Real {
        self.colliders
            .iter()
            .map(|(shape, pose)| {
                let s = signed_distance(*shape, pose, &c.coords).map_or(0.0, |(s, _)| s);
                ISO + self.slope * (s - r)
            })
            .fold(Real::INFINITY, Real::min)
    }
}

impl<F: ScalarField + ?Sized> ScalarField for ClippedField<'_, F> {
    fn value(&self, p: &Point3) -> Real {
        let f = self.field.value(p);
        match self.clip(p) {
            Some((c, _)) => f.min(c),
            None => f,
        }
    }

    fn value_and_gradient(&self, p: &Point3) -> ValueGradient {
        let (f, g) = self.field.value_and_gradient(p);
        match self.clip(p) {
            Some((c, gc)) if c < f => (c, gc),
            _ => (f, g),
        }
    }

    /// The field's own support box: clipping only lowers the field.
    fn support_box(&self) -> Option<(Point3, Point3)> {
        self.field.support_box()
    }

    /// The field's own bound: clipping only lowers the field.
    fn bounding_field(&self) -> Option<&Field> {
        self.field.bounding_field()
    }
}

/// Serial accumulator of sample reactions into per-particle (force,
/// torque) pairs, shared among primitives by field share (module doc).
#[derive(Default)]
struct ReactionAccumulator {
    per_particle: BTreeMap<u32, (Vec3, Vec3)>,
    shares: Vec<(usize, Real)>,
    samples: usize,
    total_force: Vec3,
}

impl ReactionAccumulator {
    /// Shares `force`, acting at `p`, among the primitives of `field` with
    /// a positive field at `p`; returns false (and adds nothing) when there
    /// are none.
    fn add(&mut self, field: &Field, p: &Point3, force: Vec3) -> bool {
        self.shares.clear();
        field.for_each_near(p, |i, prim| {
            let f = prim.field(p);
            if f > 0.0 {
                self.shares.push((i, f));
            }
        });
        let total: Real = self.shares.iter().map(|s| s.1).sum();
        if total <= 0.0 {
            return false;
        }
        self.samples += 1;
        self.total_force += force;
        for &(i, f) in &self.shares {
            let prim = &field.primitives()[i];
            let share = force * (f / total);
            let lever = p - prim.particle_position();
            let entry = self.per_particle.entry(prim.particle()).or_default();
            entry.0 += share;
            entry.1 += lever.cross(&share);
        }
        true
    }

    /// The accumulated reactions, in increasing particle id.
    fn finish(self) -> Reactions {
        Reactions {
            reactions: self
                .per_particle
                .into_iter()
                .map(|(particle, (force, torque))| Reaction {
                    particle,
                    force,
                    torque,
                })
                .collect(),
            samples_in_contact: self.samples,
            total_force: self.total_force,
            max_depth: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygonize::{polygonize, PolygonizeParams};
    use crate::primitives::Primitive;
    use crate::skin::Skin;
    use op_dynamics::{Material, ParticleDesc, Particles, WorldParams};
    use parry3d_f64::shape::Cuboid;

    fn world_at(points: &[Point3]) -> World {
        let mut particles = Particles::new();
        for p in points {
            particles.push(ParticleDesc::at(*p)).unwrap();
        }
        World::new(particles, &[Material::default()], WorldParams::default()).unwrap()
    }

    /// A slab whose top face is the plane z = 0.
    fn floor() -> (Cuboid, Pose) {
        (
            Cuboid::new(Vector::new(5.0, 5.0, 1.0)),
            Pose::from_translation(Vector::new(0.0, 0.0, -1.0)),
        )
    }

    fn skin_and_samples(world: &World) -> (Skin, Vec<Point3>) {
        let n = world.particles().len() as u32;
        let prims = (0..n)
            .map(|id| (id, Primitive::point(Vec3::zeros(), 1.0)))
            .collect();
        let skin = Skin::new(world, prims).unwrap();
        let mesh = polygonize(skin.field(), &PolygonizeParams::with_cell_size(0.05)).unwrap();
        (skin, mesh.positions().to_vec())
    }

    const PARAMS: ContactParams = ContactParams { stiffness: 10.0 };

    /// A ball skin sunk into a floor, clipped by it: the mesh stays
    /// closed and outward, no vertex is below the floor's top face, the
    /// vertices on it lie on the plane with the floor's downward-facing
    /// (skin-outward) normal, and away from the floor the skin is unchanged.
    #[test]
    fn clipped_skin_lies_on_the_collider_surface() {
        let centre = Point3::new(0.0, 0.0, 0.3);
        let field = Field::new(vec![Primitive::point(Vec3::zeros(), 2.0).posed(
            0,
            &centre,
            &op_dynamics::Quat::identity(),
        )]);
        let (floor, pose) = floor();
        let h = 0.05;
        let clipped = ClippedField::new(&field, vec![(&floor as &dyn Shape, pose)], ISO / h);
        let params = crate::polygonize::PolygonizeParams::with_cell_size(h);
        let mesh = crate::polygonize::polygonize_field(&clipped, &params).unwrap();
        assert!(mesh.is_closed_oriented_manifold());
        assert!(mesh.signed_volume() > 0.0);
        let r = crate::kernel::iso_radius(2.0);
        let mut on_floor = 0;
        // Vertices come through the crate's f32 unit cube: 1e-5 is its
        // rounding at this box size.
        for (p, n) in mesh.positions().iter().zip(mesh.normals()) {
            assert!(p.z > -1e-5, "vertex below the floor: {p:?}");
            if p.z < 1e-5 {
                on_floor += 1;
                assert!(n.z < -0.99, "normal on the floor: {n:?}");
            } else if p.z > 0.5 {
                // Above the contact region: the undeformed sphere.
                assert!(((p - centre).norm() - r).abs() < 0.1 * h, "{p:?}");
            }
        }
        assert!(on_floor > 20, "{on_floor} vertices on the floor");
    }

    #[test]
    fn ball_pressed_on_floor_is_pushed_up_without_spin() {
        let c = Point3::new(0.013, -0.021, 0.4);
        let mut world = world_at(&[c]);
        let (skin, samples) = skin_and_samples(&world);
        let (slab, pose) = floor();
        let r = collider_reactions(skin.field(), &samples, &slab, &pose, &PARAMS);
        assert!(r.samples_in_contact() > 10);
        let f = r.total_force();
        assert!(f.z > 0.0 && f.x == 0.0 && f.y == 0.0, "{f:?}");
        assert_eq!(r.reactions().len(), 1);
        let one = r.reactions()[0];
        assert!((one.force - f).norm() < 1e-12 * f.norm());
        assert!(
            one.torque.norm() < 0.05 * f.norm() * 0.5,
            "{:?}",
            one.torque
        );
        // Applied, the reaction is part of the next force evaluation.
        r.apply(&mut world);
        let (forces, torques, _) = world.evaluate_forces();
        assert!((forces[0] - one.force).norm() < 1e-12 * f.norm());
        assert!((torques[0] - one.torque).norm() < 1e-12 * f.norm());
    }

    #[test]
    fn reaction_is_shared_among_the_primitives_producing_the_field() {
        let world = world_at(&[Point3::new(-0.3, 0.0, 0.4), Point3::new(0.3, 0.0, 0.4)]);
        let (skin, samples) = skin_and_samples(&world);
        let (slab, pose) = floor();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| collider_reactions(skin.field(), &samples, &slab, &pose, &PARAMS))
        };
        let r = run(2);
        assert_eq!(r, run(1));
        let [left, right] = [r.reactions()[0], r.reactions()[1]];
        assert_eq!((left.particle, right.particle), (0, 1));
        let sum = left.force + right.force;
        assert!((sum - r.total_force()).norm() < 1e-12 * sum.norm());
        assert!(left.force.z > 0.0 && right.force.z > 0.0);
        assert!((left.force.z - right.force.z).abs() < 0.1 * left.force.z);
        // Each particle is pushed more on its inner side: opposite spins.
        assert!(left.torque.y < 0.0 && right.torque.y > 0.0);
    }

    #[test]
    fn no_reaction_without_penetration() {
        let world = world_at(&[Point3::new(0.0, 0.0, 0.6)]);
        let (skin, samples) = skin_and_samples(&world);
        let (slab, pose) = floor();
        let r = collider_reactions(skin.field(), &samples, &slab, &pose, &PARAMS);
        assert_eq!(r, Reactions::default());
    }
}
