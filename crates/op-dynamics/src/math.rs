//! Scalar and linear-algebra aliases used throughout the workspace.
//!
//! The simulation is 3-D and `f64` everywhere (docs/model.md §1): stiff cases and
//! error measurements need the precision.

/// The scalar type of the simulation.
pub type Real = f64;
/// A 3-vector (displacement, velocity, force, torque, angular velocity).
pub type Vec3 = nalgebra::Vector3<Real>;
/// A 3-D point (particle position).
pub type Point3 = nalgebra::Point3<Real>;
/// A unit quaternion: a particle's full frame (seed 002 §5).
pub type Quat = nalgebra::UnitQuaternion<Real>;
/// A 3x3 matrix (rotation matrices, inertia tensors).
pub type Mat3 = nalgebra::Matrix3<Real>;

/// Rotates `q` by the rotation vector `theta` given in the world frame:
/// `exp(theta) * q`, the quaternion exponential update of seed 000 §4.
///
/// The result is a unit quaternion by construction (no renormalization
/// needed beyond round-off), which keeps orientations on the unit sphere.
#[inline]
pub fn rotate_by(q: &Quat, theta: &Vec3) -> Quat {
    Quat::from_scaled_axis(*theta) * q
}

/// A unit vector perpendicular to `a` chosen deterministically from the
/// body axes: the body x axis made orthogonal to `a`, or the body y axis
/// when `a` is (nearly) parallel to x. Used as a particle's local tangent
/// axis ("local x" of seed 000 eq. 14-15) when its normal axis is `a`.
pub fn tangent_axis(a: &Vec3) -> Vec3 {
    let x = Vec3::x();
    let t = x - a * a.dot(&x);
    if t.norm_squared() > 1e-6 {
        t.normalize()
    } else {
        let y = Vec3::y();
        (y - a * a.dot(&y)).normalize()
    }
}

/// The shortest rotation taking the direction `from` to the direction
/// `to` (neither need be unit; `from` must not be zero). Opposite
/// directions have no shortest rotation: they get the half turn about
/// [`tangent_axis`] of `from`, written exactly (scalar part 0).
/// `Quat::from_axis_angle(t, π)` would give the scalar part
/// `cos(π/2) = 6e-17`, which tilts the image of `from` by 1e-16 out of
/// every plane containing it: enough to seed an out-of-plane motion of a
/// planar object whose terms leave such motion free (a chain's torsion,
/// which no orientation term sees), as the tip of a spiral whose last
/// normal is `-x` showed.
pub fn shortest_rotation(from: &Vec3, to: &Vec3) -> Quat {
    let (a, b) = (from.normalize(), to.normalize());
    Quat::rotation_between(&a, &b).unwrap_or_else(|| {
        let t = tangent_axis(&a);
        Quat::new_normalize(nalgebra::Quaternion::new(0.0, t.x, t.y, t.z))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_axis_is_unit_and_orthogonal() {
        for a in [Vec3::z(), Vec3::x(), Vec3::new(1.0, 2.0, -0.5).normalize()] {
            let t = tangent_axis(&a);
            assert!((t.norm() - 1.0).abs() < 1e-14);
            assert!(t.dot(&a).abs() < 1e-14);
        }
        assert!((tangent_axis(&Vec3::z()) - Vec3::x()).norm() < 1e-15);
    }

    #[test]
    fn rotate_by_stays_unit() {
        let mut q = Quat::identity();
        for k in 0..1000 {
            q = rotate_by(&q, &Vec3::new(0.3, -0.2, 0.1 * k as Real));
        }
        assert!((q.quaternion().norm() - 1.0).abs() < 1e-12);
    }
}
