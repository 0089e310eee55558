//! Contact reactions and rigid colliders' clipping of skins (seed 002 §6;
//! Gascuel 1993 with only the deformable skin compressed).
//!
//! A contact evaluation gives each particle a force and a torque about its
//! position ([`Reaction`], gathered in [`Reactions`]): "reaction forces are
//! then expressed at the skeleton center of mass as a pair (force, torque)
//! and integrated during the following time step" (seed 002 §6). They come
//! from a contact energy: a skin against a rigid obstacle
//! ([`crate::ObstacleContact`]) or two skins ([`crate::ContactPair`]).
//! [`ClippedField`] is a skin clipped at the obstacles it presses, for
//! display.

use op_dynamics::external::ExternalAccumulator;
use op_dynamics::{Point3, Real, Vec3, World};
use op_modeling::tools::signed_distance;
use parry3d_f64::math::Pose;
use parry3d_f64::shape::Shape;

use crate::field::{Field, ScalarField, ValueGradient};
use crate::kernel::ISO;

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

    /// The same reactions with `depth` as the deepest penetration.
    pub(crate) fn with_max_depth(self, depth: Real) -> Self {
        Reactions {
            max_depth: depth,
            ..self
        }
    }

    /// Per-particle reactions, in increasing particle id.
    pub fn reactions(&self) -> &[Reaction] {
        &self.reactions
    }

    /// Number of edges of the contact energy's lattice with a positive
    /// integral.
    pub fn samples_in_contact(&self) -> usize {
        self.samples_in_contact
    }

    /// Sum of the samples' reactions (equal to the sum of the particle
    /// forces).
    pub fn total_force(&self) -> Vec3 {
        self.total_force
    }

    /// The deepest penetration into an obstacle
    /// ([`crate::ObstacleContact::reactions`]; 0 for two skins, whose
    /// overlap [`crate::PairReactions::peak`] gives).
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

/// The bounding box `(lo, hi)` of `shape` at `pose` (infinite for an
/// unbounded shape, a half-space).
pub(crate) fn shape_box(shape: &dyn Shape, pose: &Pose) -> (Point3, Point3) {
    let b = shape.compute_aabb(pose);
    (
        Point3::new(b.mins.x, b.mins.y, b.mins.z),
        Point3::new(b.maxs.x, b.maxs.y, b.maxs.z),
    )
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
    /// Each collider's bounding box at its pose (infinite for a
    /// half-space).
    boxes: Vec<(Point3, Point3)>,
    slope: Real,
}

impl<'a, F: ScalarField + ?Sized> ClippedField<'a, F> {
    /// `field` clipped by `colliders` (shape, pose) with slope `slope`
    /// (> 0; `ISO / cell_size` makes the clip one cell thick).
    pub fn new(field: &'a F, colliders: Vec<(&'a dyn Shape, Pose)>, slope: Real) -> Self {
        let boxes = colliders
            .iter()
            .map(|(shape, pose)| shape_box(*shape, pose))
            .collect();
        ClippedField {
            field,
            colliders,
            boxes,
            slope,
        }
    }

    /// The smallest `ISO + g s_k` and its gradient over every collider
    /// (the tests' reference for [`ClippedField::clip_below`]).
    #[cfg(test)]
    fn clip(&self, p: &Point3) -> Option<(Real, Vec3)> {
        self.clip_below(p, Real::INFINITY)
    }

    /// A value no higher than collider `k`'s clip `ISO + g s_k` at `p`,
    /// from its bounding box alone: a point outside the box by `d` is at
    /// least `d` from the shape, and the signed distance's round-off is far
    /// below the millionth (of `1 + d` and the coordinates' size) taken
    /// off; rounding keeps the order of `ISO + g s` in `s` for `g > 0`. In
    /// the box (where the point may be inside, `s_k < 0`), minus infinity.
    fn clip_floor(&self, k: usize, p: &Point3) -> Real {
        let (lo, hi) = &self.boxes[k];
        let d = (0..3)
            .map(|i| (lo[i] - p[i]).max(p[i] - hi[i]).max(0.0).powi(2))
            .sum::<Real>()
            .sqrt();
        if d > 0.0 {
            ISO + self.slope * (d - 1e-6 * (1.0 + d + p.coords.amax()))
        } else {
            Real::NEG_INFINITY
        }
    }

    /// The smallest `ISO + g s_k` and its gradient among the colliders
    /// whose clip can be below `f` at `p`: a collider whose
    /// [`ClippedField::clip_floor`] is at least `f` is passed over without
    /// its signed distance (a clip at or above the field leaves the field
    /// as it is, so the clipped value and gradient are the same bits as
    /// with every collider's).
    fn clip_below(&self, p: &Point3, f: Real) -> Option<(Real, Vec3)> {
        let mut best: Option<(Real, Vec3)> = None;
        for (k, (shape, pose)) in self.colliders.iter().enumerate() {
            if self.slope > 0.0 && self.clip_floor(k, p) >= f {
                continue;
            }
            // Exactly on the surface the normal is undefined: s = 0 there.
            let (s, n) = signed_distance(*shape, pose, &p.coords).unwrap_or((0.0, Vec3::zeros()));
            let v = ISO + self.slope * s;
            if best.is_none_or(|(b, _)| v < b) {
                best = Some((v, self.slope * n));
            }
        }
        best
    }

    /// The clip's value at `p` where it can be below `f` (the smallest
    /// `ISO + g s_k` of the colliders [`ClippedField::clip_below`] keeps),
    /// for lowering a value `f` to it.
    pub(crate) fn clip_value_below(&self, p: &Point3, f: Real) -> Option<Real> {
        self.clip_below(p, f).map(|(v, _)| v)
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
        match self.clip_below(p, f) {
            Some((c, _)) => f.min(c),
            None => f,
        }
    }

    fn value_and_gradient(&self, p: &Point3) -> ValueGradient {
        let (f, g) = self.field.value_and_gradient(p);
        match self.clip_below(p, f) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::Primitive;
    use crate::skin::Skin;
    use crate::{ImplicitContactParams, ObstacleContact};
    use op_dynamics::{Material, ParticleDesc, Particles, WorldParams};
    use parry3d_f64::math::Vector;
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

    /// A point skin of radius 1 on every particle of `world`.
    fn skin_of(world: &World) -> Skin {
        let n = world.particles().len() as u32;
        let prims = (0..n)
            .map(|id| (id, Primitive::point(Vec3::zeros(), 1.0)))
            .collect();
        Skin::new(world, prims).unwrap()
    }

    /// The reactions of `skin` against the floor.
    fn on_floor(skin: &Skin) -> Reactions {
        let (slab, pose) = floor();
        ObstacleContact::new(skin.field(), &slab, &pose)
            .reactions(&ImplicitContactParams::new(10.0, 0.05))
            .unwrap()
    }

    /// The clip answers as with every signed distance computed: for
    /// points around a tilted box, a ball and a half-space (a fifth of them
    /// just beyond the ball's box at a face centre, where the ball touches
    /// its box) and field values just above, at and below the clip, the
    /// clipped value and the gradient chosen have the same bits. A bound
    /// that took 1e-4 too much (the margin's sign flipped and widened)
    /// fails it.
    #[test]
    fn the_box_floor_leaves_the_clip_as_it_was() {
        use op_test_support::Rng;
        use parry3d_f64::math::Rotation;
        use parry3d_f64::shape::{Ball, HalfSpace};
        let tilted = Cuboid::new(Vector::new(1.0, 0.5, 0.25));
        let turned = Pose::from_parts(
            Vector::new(0.5, -0.3, 0.2),
            Rotation::from_scaled_axis(Vector::new(0.3, -0.5, 0.7)),
        );
        let ball = Ball::new(1.5);
        let half = HalfSpace::new(Vector::new(0.1, -0.2, 1.0).normalize());
        let at = Pose::from_parts(Vector::new(0.3, -0.1, 0.2), Rotation::IDENTITY);
        let empty = Field::new(Vec::new());
        let g = ISO / 0.25;
        let clipped = ClippedField::new(
            &empty,
            vec![
                (&tilted as &dyn Shape, turned),
                (&ball as &dyn Shape, at),
                (&half as &dyn Shape, at),
            ],
            g,
        );
        let one = |k: usize| {
            let (shape, pose) = clipped.colliders[k];
            ClippedField::new(&empty, vec![(shape, pose)], g)
        };
        let fields = [one(0), one(1), one(2), clipped];
        let mut rng = Rng::new(23);
        let mut near = 0;
        for field in &fields {
            for _ in 0..3000 {
                let mut x = Point3::new(
                    rng.uniform(-4.0, 4.0),
                    rng.uniform(-4.0, 4.0),
                    rng.uniform(-4.0, 4.0),
                );
                if rng.uniform(0.0, 1.0) < 0.2 {
                    // Beyond the ball's +x face centre, by 0 to 0.3.
                    x = Point3::new(1.8 + rng.uniform(0.0, 0.3), -0.1, 0.2);
                }
                let full = field.clip(&x);
                let Some((v, _)) = full else { continue };
                for f in [
                    v - 1e-3,
                    v - 1e-9,
                    v,
                    v + 1e-9,
                    v + 1e-5,
                    v + 1e-3,
                    0.0,
                    1.0,
                ] {
                    let fast = field.clip_below(&x, f);
                    let value = |c: Option<(Real, Vec3)>| c.map_or(f, |(c, _)| f.min(c));
                    let chosen = |c: Option<(Real, Vec3)>| match c {
                        Some((c, gc)) if c < f => Some((c, gc)),
                        _ => None,
                    };
                    assert_eq!(value(fast).to_bits(), value(full).to_bits(), "{x} {f}");
                    assert_eq!(chosen(fast), chosen(full), "{x} {f}");
                    near += usize::from(fast.is_none());
                }
            }
        }
        // The shortcut was taken.
        assert!(near > 1000, "{near}");
    }

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
        let skin = skin_of(&world);
        let r = on_floor(&skin);
        assert!(r.samples_in_contact() > 10);
        let f = r.total_force();
        // Sideways only by the lattice's offset from the ball's axis.
        assert!(f.z > 0.0 && f.xy().norm() < 1e-3 * f.z, "{f:?}");
        assert!(
            r.max_depth() > 0.09 && r.max_depth() < 0.1,
            "{}",
            r.max_depth()
        );
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
    fn reaction_is_shared_among_the_primitives_in_contact() {
        let world = world_at(&[Point3::new(-0.3, 0.0, 0.4), Point3::new(0.3, 0.0, 0.4)]);
        let skin = skin_of(&world);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| on_floor(&skin))
        };
        let r = run(2);
        assert_eq!(r, run(1));
        let [left, right] = [r.reactions()[0], r.reactions()[1]];
        assert_eq!((left.particle, right.particle), (0, 1));
        let sum = left.force + right.force;
        assert!((sum - r.total_force()).norm() < 1e-12 * sum.norm());
        assert!(left.force.z > 0.0 && right.force.z > 0.0);
        assert!((left.force.z - right.force.z).abs() < 0.1 * left.force.z);
        // The lens is deeper between them: each is pushed up and outwards.
        assert!(
            left.force.x < 0.0 && right.force.x > 0.0,
            "{left:?} {right:?}"
        );
        // A point primitive centred on its particle does not turn with it:
        // the energy's gradient has no torque.
        for x in [left, right] {
            assert!(x.torque.norm() < 1e-12 * x.force.norm(), "{x:?}");
        }
    }

    #[test]
    fn no_reaction_without_penetration() {
        let world = world_at(&[Point3::new(0.0, 0.0, 0.6)]);
        assert_eq!(on_floor(&skin_of(&world)), Reactions::default());
    }
}
