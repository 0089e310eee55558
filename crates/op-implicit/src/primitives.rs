//! Skeleton primitives posed in a particle's local frame (seed 002 §6).
//!
//! "Each skeleton can be a complex object defined as a collection of
//! primitives placed in the oriented particle referential" (seed 002 §6).
//! A [`Primitive`] is a [`Skeleton`] with its own pose (offset and rotation)
//! in the body frame of the particle that carries it and a support radius
//! `R` for the field kernel ([`crate::kernel`]). Each frame the particle's
//! world pose is composed with the primitive's to give a [`PosedPrimitive`],
//! which measures the squared (possibly scaled) distance from world points
//! with an analytic gradient.
//!
//! Shapes, in the primitive's own frame:
//! - [`Skeleton::Point`]: the origin;
//! - [`Skeleton::Segment`]: `[-L, L]` along x;
//! - [`Skeleton::Rectangle`]: `[-a, a] x [-b, b]` in the x-y plane (the square
//!   skeletons of seed 002 fig. 6);
//! - [`Skeleton::Ellipsoid`]: the origin, with distance measured in the frame
//!   scaled per axis, `d^2 = sum (p_i / k_i)^2`: an anisotropic potential
//!   (seed 002 §6) whose support is an ellipsoid of semi-axes `k_i R`.
//!
//! For the first three, `d^2 = |p - proj(p)|^2` with `proj` the closest
//! point of the (convex) skeleton, and `grad d^2 = 2 (p - proj(p))`.

use nalgebra::{Isometry3, Matrix3, Translation3};
use op_dynamics::math::shortest_rotation;
use op_dynamics::{Point3, Quat, Real, Vec3};

use crate::kernel;

/// The geometry of a skeleton primitive in its own frame (module doc).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Skeleton {
    /// A point at the origin.
    Point,
    /// The segment from `(-half_length, 0, 0)` to `(half_length, 0, 0)`.
    Segment {
        /// Half the segment's length, >= 0.
        half_length: Real,
    },
    /// The rectangle `[-a, a] x [-b, b] x {0}`, `[a, b] = half_extents`.
    Rectangle {
        /// Half side lengths along x and y, each >= 0.
        half_extents: [Real; 2],
    },
    /// A point with the distance measured after dividing local coordinates
    /// by `scales` (each > 0): an ellipsoidal support of semi-axes
    /// `scales * radius`.
    Ellipsoid {
        /// Per-axis scale of the local frame.
        scales: Vec3,
    },
}

impl Skeleton {
    /// The (scaled) offset of local point `p` from the skeleton, whose
    /// squared length is the squared distance: from the nearest point of a
    /// point, segment or rectangle; `p` divided by the scales for an
    /// ellipsoid.
    #[inline]
    fn offset(&self, p: &Vec3) -> Vec3 {
        match *self {
            Skeleton::Point => *p,
            Skeleton::Segment { half_length } => {
                Vec3::new(p.x - p.x.clamp(-half_length, half_length), p.y, p.z)
            }
            Skeleton::Rectangle {
                half_extents: [a, b],
            } => Vec3::new(p.x - p.x.clamp(-a, a), p.y - p.y.clamp(-b, b), p.z),
            Skeleton::Ellipsoid { scales } => p.component_div(&scales),
        }
    }

    /// Squared (scaled) distance from local point `p`: the first part of
    /// [`Skeleton::distance2_and_gradient`], so the same bits.
    #[inline]
    pub fn distance2(&self, p: &Vec3) -> Real {
        self.offset(p).norm_squared()
    }

    /// Squared (scaled) distance from local point `p` and its gradient with
    /// respect to `p`.
    #[inline]
    pub fn distance2_and_gradient(&self, p: &Vec3) -> (Real, Vec3) {
        let q = self.offset(p);
        let g = match *self {
            Skeleton::Ellipsoid { scales } => q.component_div(&scales) * 2.0,
            _ => q * 2.0,
        };
        (q.norm_squared(), g)
    }

    /// The Hessian of the squared (scaled) distance at local point `p`,
    /// diagonal in the skeleton's frame: 2 along the axes where the
    /// distance is measured (clamped axes inside the skeleton's extent give
    /// 0), `2 / scale^2` for an ellipsoid.
    #[inline]
    pub fn distance2_hessian_diagonal(&self, p: &Vec3) -> Vec3 {
        let outside = |x: Real, half: Real| if x.abs() < half { 0.0 } else { 2.0 };
        match *self {
            Skeleton::Point => Vec3::repeat(2.0),
            Skeleton::Segment { half_length } => Vec3::new(outside(p.x, half_length), 2.0, 2.0),
            Skeleton::Rectangle {
                half_extents: [a, b],
            } => Vec3::new(outside(p.x, a), outside(p.y, b), 2.0),
            Skeleton::Ellipsoid { scales } => scales.map(|k| 2.0 / (k * k)),
        }
    }

    /// Radius of the smallest origin-centred sphere holding the skeleton,
    /// and the factor by which the support radius grows along the worst axis
    /// (1 except for ellipsoids): the support lies within
    /// `extent + factor * R` of the origin.
    pub(crate) fn extent_and_factor(&self) -> (Real, Real) {
        match *self {
            Skeleton::Point => (0.0, 1.0),
            Skeleton::Segment { half_length } => (half_length, 1.0),
            Skeleton::Rectangle {
                half_extents: [a, b],
            } => (a.hypot(b), 1.0),
            Skeleton::Ellipsoid { scales } => (0.0, scales.max()),
        }
    }

    fn is_valid(&self) -> bool {
        match *self {
            Skeleton::Point => true,
            Skeleton::Segment { half_length } => half_length.is_finite() && half_length >= 0.0,
            Skeleton::Rectangle { half_extents } => {
                half_extents.iter().all(|h| h.is_finite() && *h >= 0.0)
            }
            Skeleton::Ellipsoid { scales } => scales.iter().all(|k| k.is_finite() && *k > 0.0),
        }
    }
}

/// A skeleton primitive posed in a particle's body frame, with the support
/// radius of its field kernel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Primitive {
    /// Origin of the primitive's frame in the particle's body frame.
    /// Default (constructors): zero unless given.
    pub offset: Vec3,
    /// Rotation of the primitive's frame relative to the particle's body
    /// frame.
    pub rotation: Quat,
    /// The skeleton geometry in the primitive's frame.
    pub shape: Skeleton,
    /// Support radius `R` of the kernel, > 0: the field vanishes at scaled
    /// distance `>= R` and the skin of an isolated primitive of weight 1
    /// lies at `R/2`.
    pub radius: Real,
    /// Amplitude `w` of the kernel, > 0: the primitive's field is
    /// `w f(d)`. Constructors set 1. A wider support with a weight below 1
    /// blends neighbours more smoothly at the same skin size
    /// ([`Primitive::weight_for_iso_distance`]).
    pub weight: Real,
}

impl Primitive {
    /// A point skeleton at `offset` (body frame).
    pub fn point(offset: Vec3, radius: Real) -> Self {
        Primitive {
            offset,
            rotation: Quat::identity(),
            shape: Skeleton::Point,
            radius,
            weight: 1.0,
        }
    }

    /// The segment from `a` to `b` (body frame).
    pub fn segment(a: Vec3, b: Vec3, radius: Real) -> Self {
        let d = b - a;
        let rotation = if d == Vec3::zeros() {
            Quat::identity()
        } else {
            shortest_rotation(&Vec3::x(), &d)
        };
        Primitive {
            offset: (a + b) * 0.5,
            rotation,
            shape: Skeleton::Segment {
                half_length: 0.5 * d.norm(),
            },
            radius,
            weight: 1.0,
        }
    }

    /// A rectangle centred at `offset`, its plane's x and y axes given by
    /// `rotation` (body frame), with half side lengths `half_extents`.
    pub fn rectangle(offset: Vec3, rotation: Quat, half_extents: [Real; 2], radius: Real) -> Self {
        Primitive {
            offset,
            rotation,
            shape: Skeleton::Rectangle { half_extents },
            radius,
            weight: 1.0,
        }
    }

    /// The square skeleton of seed 002 fig. 6: centred on the particle,
    /// normal to the body-frame axis `normal_axis` (the particle's normal
    /// axis, usually +z), half side `half_side`.
    pub fn square(normal_axis: Vec3, half_side: Real, radius: Real) -> Self {
        let rotation = shortest_rotation(&Vec3::z(), &normal_axis);
        Self::rectangle(Vec3::zeros(), rotation, [half_side; 2], radius)
    }

    /// An ellipsoidal (anisotropic) point primitive at `offset`, its axes
    /// given by `rotation` (body frame), scaled per axis by `scales`.
    pub fn ellipsoid(offset: Vec3, rotation: Quat, scales: Vec3, radius: Real) -> Self {
        Primitive {
            offset,
            rotation,
            shape: Skeleton::Ellipsoid { scales },
            radius,
            weight: 1.0,
        }
    }

    /// The same primitive with amplitude `weight`.
    pub fn with_weight(mut self, weight: Real) -> Self {
        self.weight = weight;
        self
    }

    /// The weight that puts the skin of an isolated primitive of support
    /// `radius` at distance `distance` from its skeleton: `w f(distance) =
    /// ISO`. With `distance = R/2` it is 1; a support `k` times wider at the
    /// same skin distance takes `w = ISO / f(1/(2k))`, below 1 (Wyvill et
    /// al.'s kernel, [`kernel`]). `distance` must be below `radius`.
    pub fn weight_for_iso_distance(distance: Real, radius: Real) -> Real {
        kernel::ISO / kernel::value(distance, radius)
    }

    /// Whether every number is finite, the radius positive and the shape's
    /// sizes non-negative (ellipsoid scales positive).
    pub fn is_valid(&self) -> bool {
        self.offset.iter().all(|x| x.is_finite())
            && self.rotation.coords.iter().all(|x| x.is_finite())
            && self.radius.is_finite()
            && self.radius > 0.0
            && self.weight.is_finite()
            && self.weight > 0.0
            && self.shape.is_valid()
    }

    /// Poses the primitive on a particle at `position` with orientation
    /// `orientation`, owned by particle `particle`.
    pub fn posed(&self, particle: u32, position: &Point3, orientation: &Quat) -> PosedPrimitive {
        let body = Isometry3::from_parts(Translation3::from(position.coords), *orientation);
        let local = Isometry3::from_parts(Translation3::from(self.offset), self.rotation);
        let pose = body * local;
        let (extent, factor) = self.shape.extent_and_factor();
        PosedPrimitive {
            particle,
            particle_position: *position,
            pose,
            shape: self.shape,
            inv_radius2: 1.0 / (self.radius * self.radius),
            bound: extent + factor * self.radius,
            weight: self.weight,
        }
    }
}

/// A primitive in world space: its frame composed with its particle's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PosedPrimitive {
    particle: u32,
    particle_position: Point3,
    pose: Isometry3<Real>,
    shape: Skeleton,
    inv_radius2: Real,
    bound: Real,
    weight: Real,
}

impl PosedPrimitive {
    /// Id of the particle carrying the primitive.
    #[inline]
    pub fn particle(&self) -> u32 {
        self.particle
    }

    /// World position of the carrying particle (the point about which
    /// contact torques act).
    #[inline]
    pub fn particle_position(&self) -> &Point3 {
        &self.particle_position
    }

    /// The kernel's support radius `R`.
    #[inline]
    pub fn radius(&self) -> Real {
        self.inv_radius2.sqrt().recip()
    }

    /// World pose of the primitive's frame.
    #[inline]
    pub fn pose(&self) -> &Isometry3<Real> {
        &self.pose
    }

    /// The skeleton geometry.
    #[inline]
    pub fn shape(&self) -> &Skeleton {
        &self.shape
    }

    /// The kernel's amplitude `w` ([`Primitive::weight`]).
    #[inline]
    pub fn weight(&self) -> Real {
        self.weight
    }

    /// Multiplies the amplitude by `factor` (the support is unchanged).
    #[inline]
    pub fn scale_weight(&mut self, factor: Real) {
        self.weight *= factor;
    }

    /// The map from world points to the primitive's frame, `x -> M (x -
    /// t)`, as the rotation matrix `M` and the translation `t`: one matrix
    /// product per point where [`PosedPrimitive::field`] rotates by a
    /// quaternion, for fields sampled at many points (the polygonizer's
    /// splat).
    #[inline]
    pub(crate) fn world_to_frame(&self) -> (nalgebra::Matrix3<Real>, Vec3) {
        let m = self
            .pose
            .rotation
            .inverse()
            .to_rotation_matrix()
            .into_inner();
        (m, self.pose.translation.vector)
    }

    /// `1 / R^2`, `R` the support radius.
    #[inline]
    pub(crate) fn inv_radius2(&self) -> Real {
        self.inv_radius2
    }

    /// The field at the point `local` of the primitive's frame
    /// ([`PosedPrimitive::world_to_frame`]): [`PosedPrimitive::field`]
    /// without the world transform, to round-off. The oracle of the
    /// polygonizer's splat, which evaluates it a row at a time.
    #[cfg(test)]
    pub(crate) fn field_in_frame(&self, local: &Vec3) -> Real {
        let (d2, _) = self.shape.distance2_and_gradient(local);
        self.weight * kernel::value_sq(d2 * self.inv_radius2)
    }

    /// Centre and radius of a sphere holding the field's support.
    #[inline]
    pub fn bounding_sphere(&self) -> (Point3, Real) {
        (Point3::from(self.pose.translation.vector), self.bound)
    }

    /// Squared (scaled) distance from world point `p`: the first part of
    /// [`PosedPrimitive::distance2_and_gradient`], so the same bits,
    /// without turning the gradient back into the world.
    #[inline]
    pub fn distance2(&self, p: &Point3) -> Real {
        if let Skeleton::Point = self.shape {
            return (p.coords - self.pose.translation.vector).norm_squared();
        }
        let local = self.pose.inverse_transform_point(p).coords;
        self.shape.distance2(&local)
    }

    /// Squared (scaled) distance from world point `p` and its world-frame
    /// gradient.
    #[inline]
    pub fn distance2_and_gradient(&self, p: &Point3) -> (Real, Vec3) {
        if let Skeleton::Point = self.shape {
            // Rotations keep lengths: the local offset's length and
            // direction, rotated back, are the world offset's.
            let d = p.coords - self.pose.translation.vector;
            return (d.norm_squared(), d * 2.0);
        }
        let local = self.pose.inverse_transform_point(p).coords;
        let (d2, g) = self.shape.distance2_and_gradient(&local);
        (d2, self.pose.rotation * g)
    }

    /// The primitive's field at `p` ([`kernel::value_sq`] of
    /// `d^2 / R^2`) and its world gradient. Zero outside the support.
    ///
    /// The operations of [`PosedPrimitive::distance2_and_gradient`], but
    /// the local gradient is turned back into the world frame (a
    /// quaternion rotation) only inside the support: a point the pruning
    /// grid hands over lies in the bounding sphere, and about half of a
    /// flat skeleton's bounding sphere is outside its support.
    #[inline]
    pub fn field_and_gradient(&self, p: &Point3) -> (Real, Vec3) {
        let (s, g) = if let Skeleton::Point = self.shape {
            let d = p.coords - self.pose.translation.vector;
            (d.norm_squared() * self.inv_radius2, d * 2.0)
        } else {
            let local = self.pose.inverse_transform_point(p).coords;
            let (d2, g) = self.shape.distance2_and_gradient(&local);
            (d2 * self.inv_radius2, g)
        };
        if s >= 1.0 {
            return (0.0, Vec3::zeros());
        }
        let g = match self.shape {
            Skeleton::Point => g,
            _ => self.pose.rotation * g,
        };
        (
            self.weight * kernel::value_sq(s),
            g * (self.weight * kernel::derivative_sq(s) * self.inv_radius2),
        )
    }

    /// The primitive's field at `p`, its world gradient and its world
    /// Hessian ([`PosedPrimitive::field_and_gradient`]; the Hessian is
    /// `w (f''(s) ∇s ∇s^T + f'(s) ∇^2 s)` with `s = d^2 / R^2`). Zero
    /// outside the support.
    #[inline]
    pub fn field_gradient_hessian(&self, p: &Point3) -> (Real, Vec3, Matrix3<Real>) {
        let (d2, g) = self.distance2_and_gradient(p);
        let s = d2 * self.inv_radius2;
        if s >= 1.0 {
            return (0.0, Vec3::zeros(), Matrix3::zeros());
        }
        let (first, second) = (kernel::derivative_sq(s), kernel::second_derivative_sq(s));
        let ds = g * self.inv_radius2;
        let curvature = match self.shape {
            Skeleton::Point => Matrix3::from_diagonal_element(2.0),
            shape => {
                let local = self.pose.inverse_transform_point(p).coords;
                let r = self.pose.rotation.to_rotation_matrix().into_inner();
                r * Matrix3::from_diagonal(&shape.distance2_hessian_diagonal(&local))
                    * r.transpose()
            }
        };
        let hessian =
            (ds * ds.transpose() * second + curvature * (first * self.inv_radius2)) * self.weight;
        (
            self.weight * kernel::value_sq(s),
            g * (self.weight * first * self.inv_radius2),
            hessian,
        )
    }

    /// The primitive's field at `p` (no gradient).
    #[inline]
    pub fn field(&self, p: &Point3) -> Real {
        let d2 = self.distance2(p);
        self.weight * kernel::value_sq(d2 * self.inv_radius2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use op_test_support::Rng;

    fn kinds() -> Vec<Primitive> {
        let rot = Quat::from_scaled_axis(Vec3::new(0.3, -0.7, 0.5));
        vec![
            Primitive::point(Vec3::new(0.1, 0.0, -0.2), 0.8),
            Primitive::segment(Vec3::new(-0.3, 0.1, 0.0), Vec3::new(0.2, 0.3, 0.1), 0.7),
            Primitive::rectangle(Vec3::new(0.0, 0.1, 0.0), rot, [0.3, 0.15], 0.6),
            Primitive::square(Vec3::new(0.2, 0.1, 1.0), 0.25, 0.6),
            Primitive::ellipsoid(Vec3::zeros(), rot, Vec3::new(1.0, 0.6, 1.4), 0.7),
        ]
    }

    #[test]
    fn gradients_match_central_differences_in_rotated_frames() {
        let mut rng = Rng::new(7);
        let h = 1e-6;
        for prim in kinds() {
            assert!(prim.is_valid());
            let q = Quat::from_scaled_axis(rng.vec3(1.0) * 2.0);
            let x = Point3::from(rng.vec3(1.0));
            let posed = prim.posed(3, &x, &q);
            for _ in 0..200 {
                let p = x + rng.vec3(1.0) * 0.9;
                let (d2, g) = posed.distance2_and_gradient(&p);
                let (f, gf) = posed.field_and_gradient(&p);
                assert_eq!(f, posed.field(&p));
                // The gradient is distance2_and_gradient's, scaled: the
                // same bits (only where it is rotated back differs).
                let s = d2 * posed.inv_radius2;
                let scaled = match s < 1.0 {
                    true => g * (posed.weight * kernel::derivative_sq(s) * posed.inv_radius2),
                    false => Vec3::zeros(),
                };
                assert_eq!(gf, scaled, "{prim:?}");
                for k in 0..3 {
                    let mut e = Vec3::zeros();
                    e[k] = h;
                    let fd2 = (posed.distance2_and_gradient(&(p + e)).0
                        - posed.distance2_and_gradient(&(p - e)).0)
                        / (2.0 * h);
                    let ff = (posed.field(&(p + e)) - posed.field(&(p - e))) / (2.0 * h);
                    assert!((fd2 - g[k]).abs() < 1e-6, "{prim:?} d2 {d2}");
                    assert!((ff - gf[k]).abs() < 1e-6, "{prim:?} f {f}");
                }
            }
        }
    }

    /// The Hessian is the derivative of the gradient, away from the
    /// skeleton's edges and the support's boundary (where `f` is C1).
    #[test]
    fn hessians_match_central_differences_of_the_gradient() {
        let mut rng = Rng::new(13);
        let h = 1e-6;
        let mut compared = 0;
        for prim in kinds() {
            let q = Quat::from_scaled_axis(rng.vec3(1.0) * 2.0);
            let x = Point3::from(rng.vec3(1.0));
            let posed = prim.posed(3, &x, &q);
            for _ in 0..200 {
                let p = x + rng.vec3(1.0) * 0.9;
                let (f, g, hessian) = posed.field_gradient_hessian(&p);
                assert_eq!((f, g), posed.field_and_gradient(&p));
                assert!((hessian - hessian.transpose()).norm() < 1e-12);
                let mut fd = Matrix3::zeros();
                for k in 0..3 {
                    let mut e = Vec3::zeros();
                    e[k] = h;
                    let up = posed.field_and_gradient(&(p + e)).1;
                    let down = posed.field_and_gradient(&(p - e)).1;
                    fd.set_column(k, &((up - down) / (2.0 * h)));
                }
                // A kink within the difference's reach: the Hessian jumps.
                let near_kink = (fd - fd.transpose()).norm() > 1e-4;
                if f > 0.0 && !near_kink {
                    assert!(
                        (fd - hessian).norm() < 1e-5 * (1.0 + hessian.norm()),
                        "{prim:?}"
                    );
                    compared += 1;
                }
            }
        }
        assert!(compared > 300, "{compared}");
    }

    #[test]
    fn support_lies_in_bounding_sphere() {
        let mut rng = Rng::new(11);
        for prim in kinds() {
            let posed = prim.posed(
                0,
                &Point3::new(1.0, 2.0, 3.0),
                &Quat::from_scaled_axis(rng.vec3(1.0)),
            );
            let (c, r) = posed.bounding_sphere();
            for _ in 0..2000 {
                let p = c + rng.vec3(1.0) * 2.0;
                if posed.field(&p) > 0.0 {
                    assert!((p - c).norm() <= r + 1e-12, "{prim:?}");
                }
            }
        }
    }

    #[test]
    fn distances_of_simple_shapes() {
        let seg = Primitive::segment(Vec3::zeros(), Vec3::new(0.0, 2.0, 0.0), 1.0).posed(
            0,
            &Point3::origin(),
            &Quat::identity(),
        );
        assert!((seg.distance2_and_gradient(&Point3::new(0.5, 1.0, 0.0)).0 - 0.25).abs() < 1e-14);
        assert!((seg.distance2_and_gradient(&Point3::new(0.0, 3.0, 0.0)).0 - 1.0).abs() < 1e-14);
        let sq =
            Primitive::square(Vec3::z(), 1.0, 1.0).posed(0, &Point3::origin(), &Quat::identity());
        assert!((sq.distance2_and_gradient(&Point3::new(0.5, -0.5, 0.3)).0 - 0.09).abs() < 1e-14);
        assert!((sq.distance2_and_gradient(&Point3::new(2.0, 0.0, 0.0)).0 - 1.0).abs() < 1e-14);
        let ell = Primitive::ellipsoid(
            Vec3::zeros(),
            Quat::identity(),
            Vec3::new(2.0, 1.0, 1.0),
            1.0,
        )
        .posed(0, &Point3::origin(), &Quat::identity());
        assert!((ell.distance2_and_gradient(&Point3::new(2.0, 0.0, 0.0)).0 - 1.0).abs() < 1e-14);
    }
}
