//! Scripted tool motion (seed 000 §6: tools "can be moved interactively";
//! offline, a keyframed path stands in for the user's hand).
//!
//! Positions are interpolated linearly between keyframes and rotations by
//! spherical linear interpolation; before the first keyframe and after the
//! last the tool stays still. The velocity is piecewise constant (the
//! derivative of the interpolation), which the obstacle's normal damping
//! uses as the surface velocity.

use serde::{Deserialize, Serialize};

use op_dynamics::error::{self, ParamError};
use op_dynamics::math::{Quat, Real, Vec3};

/// A pose of the tool at a time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Time of the keyframe.
    pub time: Real,
    /// Position of the tool frame's origin.
    #[serde(default)]
    pub position: [Real; 3],
    /// Rotation of the tool frame as a rotation vector (axis times angle
    /// in radians). Default: none.
    #[serde(default)]
    pub rotation: [Real; 3],
}

/// The tool's motion: keyframes in increasing time. An empty path keeps
/// the tool at the origin, unrotated; one keyframe keeps it there.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(transparent)]
pub struct ToolPath {
    /// Keyframes in strictly increasing time.
    pub keyframes: Vec<Keyframe>,
}

/// Where a tool is and how it moves at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolPose {
    /// Position of the tool frame's origin.
    pub position: Vec3,
    /// Orientation of the tool frame.
    pub rotation: Quat,
    /// Linear velocity of the origin.
    pub velocity: Vec3,
    /// Angular velocity (world frame).
    pub angular_velocity: Vec3,
}

impl ToolPose {
    /// The velocity of the tool's material point at `p` (world frame).
    pub fn velocity_at(&self, p: &Vec3) -> Vec3 {
        self.velocity + self.angular_velocity.cross(&(p - self.position))
    }
}

impl ToolPath {
    /// A path that keeps the tool still at `position`.
    pub fn fixed(position: [Real; 3]) -> ToolPath {
        ToolPath {
            keyframes: vec![Keyframe {
                time: 0.0,
                position,
                rotation: [0.0; 3],
            }],
        }
    }

    /// Checks finite values and strictly increasing times.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (k, f) in self.keyframes.iter().enumerate() {
            let within = |e: ParamError| e.within(&format!("[{k}]"));
            error::finite("time", f.time).map_err(within)?;
            for v in f.position.iter().chain(&f.rotation) {
                error::finite("position/rotation", *v).map_err(within)?;
            }
            if k > 0 && f.time <= self.keyframes[k - 1].time {
                return Err(within(ParamError::Invalid {
                    field: "time".into(),
                    message: format!(
                        "{} is not after the previous keyframe's time {} (keyframes must be \
                         in strictly increasing time)",
                        f.time,
                        self.keyframes[k - 1].time
                    ),
                }));
            }
        }
        Ok(())
    }

    /// Whether the tool ever moves.
    pub fn is_static(&self) -> bool {
        self.keyframes
            .windows(2)
            .all(|w| w[0].position == w[1].position && w[0].rotation == w[1].rotation)
    }

    /// The pose at time `t`.
    pub fn pose(&self, t: Real) -> ToolPose {
        let still = |k: &Keyframe| ToolPose {
            position: Vec3::from(k.position),
            rotation: Quat::from_scaled_axis(Vec3::from(k.rotation)),
            velocity: Vec3::zeros(),
            angular_velocity: Vec3::zeros(),
        };
        let frames = &self.keyframes;
        let (Some(first), Some(last)) = (frames.first(), frames.last()) else {
            return ToolPose {
                position: Vec3::zeros(),
                rotation: Quat::identity(),
                velocity: Vec3::zeros(),
                angular_velocity: Vec3::zeros(),
            };
        };
        if t < first.time {
            return still(first);
        }
        if t >= last.time {
            return still(last);
        }
        // The segment [a, b] with a.time <= t < b.time.
        let k = frames.partition_point(|f| f.time <= t) - 1;
        let (a, b) = (&frames[k], &frames[k + 1]);
        let span = b.time - a.time;
        let s = (t - a.time) / span;
        let (pa, pb) = (Vec3::from(a.position), Vec3::from(b.position));
        let qa = Quat::from_scaled_axis(Vec3::from(a.rotation));
        let qb = Quat::from_scaled_axis(Vec3::from(b.rotation));
        // Relative rotation of the segment, in the world frame: qb = dq qa.
        let dq = qb * qa.inverse();
        let omega = dq.scaled_axis() / span;
        ToolPose {
            position: pa + s * (pb - pa),
            rotation: Quat::from_scaled_axis(dq.scaled_axis() * s) * qa,
            velocity: (pb - pa) / span,
            angular_velocity: omega,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> ToolPath {
        ToolPath {
            keyframes: vec![
                Keyframe {
                    time: 1.0,
                    position: [0.0, 0.0, 0.0],
                    rotation: [0.0; 3],
                },
                Keyframe {
                    time: 3.0,
                    position: [2.0, 0.0, 4.0],
                    rotation: [0.0, 0.0, 1.0],
                },
            ],
        }
    }

    #[test]
    fn interpolates_and_holds_at_the_ends() {
        let p = path();
        assert_eq!(p.pose(0.0).position, Vec3::zeros());
        assert_eq!(p.pose(0.0).velocity, Vec3::zeros());
        let mid = p.pose(2.0);
        assert!((mid.position - Vec3::new(1.0, 0.0, 2.0)).norm() < 1e-15);
        assert!((mid.rotation.angle() - 0.5).abs() < 1e-12);
        assert!((mid.velocity - Vec3::new(1.0, 0.0, 2.0)).norm() < 1e-15);
        assert!((mid.angular_velocity - Vec3::new(0.0, 0.0, 0.5)).norm() < 1e-12);
        let end = p.pose(5.0);
        assert_eq!(end.position, Vec3::new(2.0, 0.0, 4.0));
        assert!((end.rotation.angle() - 1.0).abs() < 1e-12);
        assert!(!p.is_static());
        assert!(ToolPath::fixed([1.0, 2.0, 3.0]).is_static());
    }

    #[test]
    fn velocity_is_the_derivative_of_the_pose() {
        let p = path();
        let (t, h) = (1.7, 1e-6);
        let (a, b) = (p.pose(t - h), p.pose(t + h));
        let fd = (b.position - a.position) / (2.0 * h);
        assert!((fd - p.pose(t).velocity).norm() < 1e-8);
        let dq = b.rotation * a.rotation.inverse();
        let w = dq.scaled_axis() / (2.0 * h);
        assert!((w - p.pose(t).angular_velocity).norm() < 1e-6);
    }

    #[test]
    fn rejects_unordered_keyframes() {
        let mut p = path();
        p.keyframes[1].time = 1.0;
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("[1].time"), "{e}");
        assert!(path().validate().is_ok());
    }
}
