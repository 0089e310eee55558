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
                    let u = lattice_point([i, j, k], b, edge);
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

/// The lattice point of cell `cell` and basis point `b`, relative to the
/// ball's centre, for a cube edge `edge`: the one expression
/// [`solid_ball`] and [`solid_ball_count`] both test.
fn lattice_point(cell: [i64; 3], b: &[Real; 3], edge: Real) -> Vec3 {
    Vec3::new(
        (cell[0] as Real + b[0]) * edge,
        (cell[1] as Real + b[1]) * edge,
        (cell[2] as Real + b[2]) * edge,
    )
}

/// The number of particles [`solid_ball`] makes, counted without making
/// them: per column of the lattice (a cell's `i`, `j` and a basis point),
/// the points inside form one run of consecutive `k` (the distance grows
/// with `|k + b_z|`), whose ends are found from the square root and then
/// settled with [`solid_ball`]'s own test. Work `O((radius /
/// spacing)²)`, memory `O(1)`: `opsim check` counts a ball of ten million
/// particles without allocating them (issue 38).
pub(crate) fn solid_ball_count(radius: Real, spacing: Real) -> usize {
    let edge = spacing * 2f64.sqrt();
    let cells = (radius / edge).ceil() as i64 + 1;
    let bound = radius * radius * (1.0 + 1e-12);
    let mut count = 0usize;
    for i in -cells..=cells {
        for j in -cells..=cells {
            for b in &FCC_BASIS {
                let inside = |k: i64| lattice_point([i, j, k], b, edge).norm_squared() <= bound;
                let xy = lattice_point([i, j, 0], b, edge).norm_squared();
                let h = (bound - xy).max(0.0).sqrt() / edge;
                let mut hi = ((h - b[2]).floor() as i64).clamp(-cells - 1, cells);
                while hi < cells && inside(hi + 1) {
                    hi += 1;
                }
                while hi >= -cells && !inside(hi) {
                    hi -= 1;
                }
                let mut lo = ((-h - b[2]).ceil() as i64).clamp(-cells, cells + 1);
                while lo > -cells && inside(lo - 1) {
                    lo -= 1;
                }
                while lo <= cells && !inside(lo) {
                    lo += 1;
                }
                if hi >= lo {
                    count += (hi - lo + 1) as usize;
                }
            }
        }
    }
    count
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
    fn the_count_is_the_number_of_particles_made() {
        // Radii on lattice shells (whole multiples of the spacing and of
        // the cube edge), between them, and below one spacing.
        let edge = 2f64.sqrt();
        for (r, s) in [
            (3.0, 1.0),
            (5.0, 1.0),
            (2.0, 0.25),
            (2.0 * edge, 1.0),
            (3.0f64.sqrt(), 1.0),
            (4.37, 0.61),
            (0.5, 1.0),
            (1.0, 1.0),
            (7.0, 0.7),
        ] {
            let made = solid_ball(r, s, &[0.3, -2.0, 5.0]).len();
            assert_eq!(solid_ball_count(r, s), made, "radius {r}, spacing {s}");
        }
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
