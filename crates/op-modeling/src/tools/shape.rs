//! Tool shapes (seed 000 §6: "planes, spheres, cylinders and polyhedra"),
//! described in the tool's own frame and built as parry colliders.
//!
//! The parry types are glam-based from parry 0.26 on; conversion to and
//! from the nalgebra types of the simulation happens here and in
//! [`super::Tool`] only.

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::{SharedShape, TriMeshFlags};
use serde::{Deserialize, Serialize};

use op_dynamics::error::{self, ParamError};
use op_dynamics::math::{Quat, Real, Vec3};

/// A tool's shape in its own frame (the frame its path moves).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub enum ToolShape {
    /// The half-space below the plane through the origin with outward
    /// (upward) `normal`.
    Plane {
        /// Outward normal (need not be unit; must be non-zero).
        #[schemars(transform = op_dynamics::schema_rules::non_zero_vector)]
        normal: [Real; 3],
    },
    /// A ball centred at the origin.
    Ball {
        /// Radius, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: Real,
    },
    /// A box centred at the origin.
    Cuboid {
        /// Half extents along x, y, z, each > 0.
        #[schemars(transform = op_dynamics::schema_rules::positive_items)]
        half_extents: [Real; 3],
    },
    /// A cylinder centred at the origin with its axis along y.
    Cylinder {
        /// Half height, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        half_height: Real,
        /// Radius, > 0.
        #[schemars(extend("exclusiveMinimum" = 0))]
        radius: Real,
    },
    /// The convex hull of points (a convex polyhedron).
    ConvexHull {
        /// At least four points, not all coplanar.
        #[schemars(length(min = 4))]
        points: Vec<[Real; 3]>,
    },
    /// A closed, consistently oriented triangle mesh (a general
    /// polyhedron; inside tests need it closed).
    TriMesh {
        /// Vertex positions.
        vertices: Vec<[Real; 3]>,
        /// Triangles as vertex indices, counter-clockwise seen from outside.
        triangles: Vec<[u32; 3]>,
    },
}

fn vector(p: &[Real; 3]) -> Vector {
    Vector::new(p[0], p[1], p[2])
}

fn positive3(field: &str, v: &[Real; 3]) -> Result<(), ParamError> {
    v.iter().try_for_each(|&x| error::positive(field, x))
}

impl ToolShape {
    /// Checks the parameters and builds the parry collider.
    pub fn build(&self) -> Result<SharedShape, ParamError> {
        let invalid = |field: &str, message: String| ParamError::Invalid {
            field: field.into(),
            message,
        };
        match self {
            ToolShape::Plane { normal } => {
                let n = Vec3::from(*normal);
                if !n.iter().all(|x| x.is_finite()) || n.norm() == 0.0 {
                    return Err(invalid(
                        "Plane.normal",
                        format!("{normal:?} must be a finite, non-zero vector"),
                    ));
                }
                let n = n.normalize();
                Ok(SharedShape::halfspace(Vector::new(n.x, n.y, n.z)))
            }
            ToolShape::Ball { radius } => {
                error::positive("Ball.radius", *radius)?;
                Ok(SharedShape::ball(*radius))
            }
            ToolShape::Cuboid { half_extents } => {
                positive3("Cuboid.half_extents", half_extents)?;
                let [x, y, z] = *half_extents;
                Ok(SharedShape::cuboid(x, y, z))
            }
            ToolShape::Cylinder {
                half_height,
                radius,
            } => {
                error::positive("Cylinder.half_height", *half_height)?;
                error::positive("Cylinder.radius", *radius)?;
                Ok(SharedShape::cylinder(*half_height, *radius))
            }
            ToolShape::ConvexHull { points } => {
                for p in points {
                    p.iter()
                        .try_for_each(|&x| error::finite("ConvexHull.points", x))?;
                }
                let pts: Vec<Vector> = points.iter().map(vector).collect();
                let solid = spans_volume(points);
                solid
                    .then(|| SharedShape::convex_hull(&pts))
                    .flatten()
                    .ok_or_else(|| {
                        invalid(
                            "ConvexHull.points",
                            format!(
                                "the hull of these {} points is degenerate (give at least four \
                             points that are not all coplanar)",
                                points.len()
                            ),
                        )
                    })
            }
            ToolShape::TriMesh {
                vertices,
                triangles,
            } => {
                for p in vertices {
                    p.iter()
                        .try_for_each(|&x| error::finite("TriMesh.vertices", x))?;
                }
                if let Some(t) = triangles
                    .iter()
                    .find(|t| t.iter().any(|&i| i as usize >= vertices.len()))
                {
                    return Err(invalid(
                        "TriMesh.triangles",
                        format!(
                            "triangle {t:?} refers to a vertex that does not exist ({} vertices)",
                            vertices.len()
                        ),
                    ));
                }
                SharedShape::trimesh_with_flags(
                    vertices.iter().map(vector).collect(),
                    triangles.clone(),
                    TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES,
                )
                .map_err(|e| invalid("TriMesh", format!("not a valid triangle mesh: {e}")))
            }
        }
    }

    /// Whether the shape is unbounded (a half-space): its bounding box is
    /// infinite and every particle must be tested.
    pub fn is_unbounded(&self) -> bool {
        matches!(self, ToolShape::Plane { .. })
    }
}

/// Whether the points span a volume (not all on one plane, relative to
/// their extent): a convex obstacle needs an inside.
fn spans_volume(points: &[[Real; 3]]) -> bool {
    let p: Vec<Vec3> = points.iter().map(|x| Vec3::from(*x)).collect();
    let Some(a) = p.first() else { return false };
    let farthest = |score: &dyn Fn(&Vec3) -> Real| {
        p.iter()
            .map(|x| (score(x), *x))
            .fold((0.0, *a), |best, c| if c.0 > best.0 { c } else { best })
    };
    let (ab, b) = farthest(&|x| (x - a).norm());
    let (area, c) = farthest(&|x| (b - a).cross(&(x - a)).norm());
    let n = (b - a).cross(&(c - a));
    let (volume, _) = farthest(&|x| n.dot(&(x - a)).abs());
    ab > 0.0 && area > 1e-9 * ab * ab && volume > 1e-9 * area * ab
}

/// The parry pose of a tool frame.
pub fn parry_pose(position: &Vec3, rotation: &Quat) -> Pose {
    let q = rotation.quaternion();
    Pose::from_parts(
        Vector::new(position.x, position.y, position.z),
        parry3d_f64::math::Rotation::from_xyzw(q.i, q.j, q.k, q.w),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_every_shape_and_rejects_bad_ones() {
        let cube: Vec<[Real; 3]> = (0..8)
            .map(|k| {
                [
                    (k & 1) as Real,
                    ((k >> 1) & 1) as Real,
                    ((k >> 2) & 1) as Real,
                ]
            })
            .collect();
        let ok = [
            ToolShape::Plane {
                normal: [0.0, 0.0, 2.0],
            },
            ToolShape::Ball { radius: 1.0 },
            ToolShape::Cuboid {
                half_extents: [1.0, 2.0, 3.0],
            },
            ToolShape::Cylinder {
                half_height: 1.0,
                radius: 0.5,
            },
            ToolShape::ConvexHull {
                points: cube.clone(),
            },
        ];
        for s in &ok {
            assert!(s.build().is_ok(), "{s:?}");
        }
        let bad = [
            ToolShape::Plane { normal: [0.0; 3] },
            ToolShape::Ball { radius: -1.0 },
            ToolShape::ConvexHull {
                points: cube[..3].to_vec(),
            },
            ToolShape::TriMesh {
                vertices: cube.clone(),
                triangles: vec![[0, 1, 9]],
            },
        ];
        for s in &bad {
            assert!(s.build().is_err(), "{s:?}");
        }
    }

    #[test]
    fn pose_conversion_matches_nalgebra() {
        let q = Quat::from_scaled_axis(Vec3::new(0.3, -0.2, 0.9));
        let x = Vec3::new(1.0, 2.0, 3.0);
        let pose = parry_pose(&x, &q);
        let p = Vec3::new(0.5, -0.7, 0.2);
        let got = pose.transform_point(Vector::new(p.x, p.y, p.z));
        let want = q * p + x;
        assert!((Vec3::new(got.x, got.y, got.z) - want).norm() < 1e-14);
        // A ball moved by the pose contains the transformed centre.
        let ball = ToolShape::Ball { radius: 0.1 }.build().unwrap();
        assert!(ball.contains_point(&pose, Vector::new(x.x, x.y, x.z)));
    }
}
