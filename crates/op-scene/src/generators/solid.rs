//! Solid shapes: a ball filled with particles.
//!
//! The oriented-particle papers model surfaces and curves; a solid is the
//! particle system of Szeliski & Tonnesen §2 before orientation matters: a
//! packing whose spacing potential holds every particle at its
//! neighbours' rest distance. The face-centred cubic packing is the
//! densest packing of equal spheres: every interior particle has twelve
//! neighbours at the spacing and the next ones at `spacing √2`, so a
//! spacing potential whose cut-off lies between the two (or bonds of that
//! radius) gives each particle the same twelve partners, and the lattice is
//! stiff against shear as well as compression.

use std::f64::consts::PI;

use op_dynamics::{Point3, Real, Vec3};

use super::Generated;

/// The four lattice points of the face-centred cubic cell, in units of the
/// cube edge.
const FCC_BASIS: [[Real; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.5, 0.0, 0.5],
    [0.0, 0.5, 0.5],
];

/// The expected particle count of [`solid_ball`]: the ball's volume times
/// the packing's density `√2 / spacing³`.
pub(crate) fn solid_ball_estimate(radius: Real, spacing: Real) -> Real {
    4.0 / 3.0 * PI * (radius / spacing).powi(3) * 2f64.sqrt()
}

/// The face-centred cubic packing of nearest-neighbour distance `spacing`
/// (cube edge `spacing √2`, axes along x, y, z, a lattice point at the
/// centre) cut to the points within `radius` of `center`. Normals point
/// away from the centre (+z for the centre particle), curvature 0 (a solid
/// has no rest curvature). Points are ordered by cell, then by basis point:
/// the order is a function of the parameters alone.
pub(super) fn solid_ball(radius: Real, spacing: Real, center: &[Real; 3]) -> Generated {
    let edge = spacing * 2f64.sqrt();
    let cells = (radius / edge).ceil() as i64 + 1;
    let c = Point3::from(*center);
    let bound = radius * radius * (1.0 + 1e-12);
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in -cells..=cells {
        for j in -cells..=cells {
            for k in -cells..=cells {
                for b in &FCC_BASIS {
                    let u = Vec3::new(
                        (i as Real + b[0]) * edge,
                        (j as Real + b[1]) * edge,
                        (k as Real + b[2]) * edge,
                    );
                    if u.norm_squared() <= bound {
                        let n = u.try_normalize(0.0).unwrap_or_else(Vec3::z);
                        positions.push(c + u);
                        normals.push(n);
                    }
                }
            }
        }
    }
    let count = positions.len();
    Generated {
        positions,
        normals,
        curvatures: vec![0.0; count],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interior_particles_have_twelve_neighbours_at_the_spacing() {
        let g = solid_ball(3.0, 0.7, &[1.0, -2.0, 0.5]);
        let c = Point3::new(1.0, -2.0, 0.5);
        let mut interior = 0;
        for (a, p) in g.positions.iter().enumerate() {
            assert!((p - c).norm() <= 3.0 + 1e-9);
            let near: Vec<Real> = g
                .positions
                .iter()
                .enumerate()
                .filter(|&(b, _)| b != a)
                .map(|(_, q)| (q - p).norm())
                .collect();
            let nearest = near.iter().copied().fold(Real::INFINITY, Real::min);
            assert!((nearest - 0.7).abs() < 1e-9, "nearest {nearest}");
            if (p - c).norm() < 3.0 - 1.5 {
                interior += 1;
                let at_spacing = near.iter().filter(|&&d| (d - 0.7).abs() < 1e-9).count();
                assert_eq!(at_spacing, 12);
                let closer_than_second = near.iter().filter(|&&d| d < 0.7 * 1.4).count();
                assert_eq!(closer_than_second, 12);
            }
        }
        assert!(interior > 10);
    }

    #[test]
    fn count_follows_the_packing_density() {
        for (r, s) in [(3.0, 1.0), (5.0, 1.0), (2.0, 0.25)] {
            let n = solid_ball(r, s, &[0.0; 3]).len() as Real;
            let e = solid_ball_estimate(r, s);
            assert!((n / e - 1.0).abs() < 0.12, "r {r} s {s}: {n} against {e}");
        }
    }

    #[test]
    fn centre_particle_faces_up_and_others_face_out() {
        let g = solid_ball(1.5, 1.0, &[0.0; 3]);
        for (p, n) in g.positions.iter().zip(&g.normals) {
            if p.coords.norm() == 0.0 {
                assert_eq!(*n, Vec3::z());
            } else {
                assert!((n - p.coords.normalize()).norm() < 1e-12);
            }
        }
    }
}
