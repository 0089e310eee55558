//! Analytic shapes: spiral, chain, hexagonal sheet, sphere and torus shells.
//! Pure functions of validated parameters.

use std::f64::consts::PI;

use op_dynamics::math::tangent_axis;
use op_dynamics::{Point3, Real, Vec3};

use super::{CurvatureLaw, Generated};

/// An orthonormal right-handed frame `(e1, e2, n)` with `n` the given
/// direction (normalized) and `e1` chosen deterministically.
pub(super) fn plane_frame(normal: &[Real; 3]) -> (Vec3, Vec3, Vec3) {
    let n = Vec3::from(*normal).normalize();
    let e1 = tangent_axis(&n);
    let e2 = n.cross(&e1);
    (e1, e2, n)
}

/// Translates `positions` so their centroid is `center`.
fn recenter(positions: &mut [Point3], center: &[Real; 3]) {
    if positions.is_empty() {
        return;
    }
    let mean = positions.iter().map(|p| p.coords).sum::<Vec3>() / positions.len() as Real;
    let shift = Vec3::from(*center) - mean;
    for p in positions {
        *p += shift;
    }
}

/// Curvature at arc length `s` of a spiral of length `length` whose
/// curvature goes from `k0` to `k1` by `law`.
pub(super) fn spiral_curvature(
    law: CurvatureLaw,
    k0: Real,
    k1: Real,
    s: Real,
    length: Real,
) -> Real {
    if length <= 0.0 {
        return k0;
    }
    let x = s / length;
    match law {
        CurvatureLaw::Linear => k0 + (k1 - k0) * x,
        CurvatureLaw::Geometric => k0 * (k1 / k0).powf(x),
        CurvatureLaw::Quadratic => k0 + (k1 - k0) * x * x,
        CurvatureLaw::Sine => k0 + (k1 - k0) * (std::f64::consts::FRAC_PI_2 * x).sin(),
    }
}

/// Turning angle `θ(s) = ∫_0^s κ` of the spiral of [`spiral_curvature`].
fn spiral_angle(law: CurvatureLaw, k0: Real, k1: Real, s: Real, length: Real) -> Real {
    if length <= 0.0 {
        return k0 * s;
    }
    match law {
        CurvatureLaw::Linear => k0 * s + (k1 - k0) * s * s / (2.0 * length),
        CurvatureLaw::Geometric => {
            let log_ratio = (k1 / k0).ln();
            if log_ratio.abs() < 1e-12 {
                k0 * s
            } else {
                k0 * length / log_ratio * (log_ratio * s / length).exp_m1()
            }
        }
        CurvatureLaw::Quadratic => k0 * s + (k1 - k0) * s * s * s / (3.0 * length * length),
        CurvatureLaw::Sine => {
            let q = std::f64::consts::FRAC_PI_2 / length;
            // ∫ sin(q s) ds = (1 - cos(q s)) / q, written without cancellation.
            k0 * s + (k1 - k0) * 2.0 * (0.5 * q * s).sin().powi(2) / q
        }
    }
}

/// A planar curve integrated in arc length (`θ'(s) = κ(s)`, `κ` going from
/// `k0` to `k1` by `law`), particles `spacing` apart in arc length,
/// centroid at `center`, normals `t × n_plane` (away from the centre of
/// curvature where `κ > 0`), rest curvature the analytic `κ_i`.
pub(super) fn spiral(
    count: usize,
    spacing: Real,
    (k0, k1, law): (Real, Real, CurvatureLaw),
    center: &[Real; 3],
    normal: &[Real; 3],
) -> Generated {
    let (e1, e2, n) = plane_frame(normal);
    let length = spacing * (count.saturating_sub(1)) as Real;
    let theta = |s: Real| spiral_angle(law, k0, k1, s, length);
    let tangent = |s: Real| {
        let t = theta(s);
        (t.cos(), t.sin())
    };
    // Composite Simpson rule per segment: the tangent turns by at most
    // |κ| spacing per segment, so 16 panels give ~1e-9 relative accuracy
    // even at one radian per segment.
    const PANELS: usize = 16;
    let mut x = 0.0;
    let mut y = 0.0;
    let mut positions = Vec::with_capacity(count);
    let mut normals = Vec::with_capacity(count);
    let mut curvatures = Vec::with_capacity(count);
    for i in 0..count {
        let s = i as Real * spacing;
        if i > 0 {
            let a = s - spacing;
            let h = spacing / PANELS as Real;
            let (mut sx, mut sy) = (0.0, 0.0);
            for k in 0..=PANELS {
                let w = if k == 0 || k == PANELS {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                let (c, sn) = tangent(a + k as Real * h);
                sx += w * c;
                sy += w * sn;
            }
            x += sx * h / 3.0;
            y += sy * h / 3.0;
        }
        positions.push(Point3::from(e1 * x + e2 * y));
        let (c, sn) = tangent(s);
        let t = e1 * c + e2 * sn;
        normals.push(t.cross(&n).normalize());
        curvatures.push(spiral_curvature(law, k0, k1, s, length));
    }
    recenter(&mut positions, center);
    Generated {
        positions,
        normals,
        curvatures,
    }
}

/// `count` particles on a straight line from `start`, `spacing` apart.
pub(super) fn chain(
    count: usize,
    spacing: Real,
    start: &[Real; 3],
    direction: &[Real; 3],
    normal: &[Real; 3],
) -> Generated {
    let d = Vec3::from(*direction).normalize();
    let n = Vec3::from(*normal).normalize();
    let p0 = Point3::from(*start);
    Generated {
        positions: (0..count).map(|i| p0 + d * (i as Real * spacing)).collect(),
        normals: vec![n; count],
        curvatures: vec![0.0; count],
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny seeded generator, enough
/// for reproducible jitter without a dependency.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[-1, 1)`.
    fn symmetric(&mut self) -> Real {
        (self.next_u64() >> 11) as Real * (2.0 / (1u64 << 53) as Real) - 1.0
    }
}

/// Parameters of [`hex_sheet`].
pub(super) struct HexSheet<'a> {
    pub nx: usize,
    pub ny: usize,
    pub spacing: Real,
    pub center: &'a [Real; 3],
    pub normal: &'a [Real; 3],
    pub noise: Real,
    pub seed: u64,
}

/// A hexagonal lattice of `nx` x `ny` particles in the plane through
/// `center` perpendicular to `normal`: rows `spacing √3/2` apart, odd rows
/// shifted by half a spacing. Noise adds a uniform displacement in
/// `[-noise, noise]` along each of the sheet's three axes; normals stay the
/// sheet normal.
pub(super) fn hex_sheet(p: &HexSheet<'_>) -> Generated {
    let (e1, e2, n) = plane_frame(p.normal);
    let count = p.nx * p.ny;
    let row = p.spacing * 3f64.sqrt() / 2.0;
    let mut rng = SplitMix64(p.seed);
    let mut positions = Vec::with_capacity(count);
    for j in 0..p.ny {
        for i in 0..p.nx {
            let x = (i as Real + 0.5 * (j % 2) as Real) * p.spacing;
            let y = j as Real * row;
            let mut q = e1 * x + e2 * y;
            if p.noise > 0.0 {
                q += (e1 * rng.symmetric() + e2 * rng.symmetric() + n * rng.symmetric()) * p.noise;
            }
            positions.push(Point3::from(q));
        }
    }
    recenter(&mut positions, p.center);
    Generated {
        positions,
        normals: vec![n; count],
        curvatures: vec![0.0; count],
    }
}

/// Particle count of a sphere shell: area over the area per particle of a
/// hexagonal lattice, `4πR² / (√3/2 h²)`, rounded.
pub(crate) fn sphere_count(radius: Real, spacing: Real) -> Real {
    (4.0 * PI * radius * radius * 2.0 / (3f64.sqrt() * spacing * spacing)).round()
}

/// A Fibonacci sphere of `count` particles: outward normals, curvature
/// `1/radius`.
pub(super) fn sphere_shell(count: usize, radius: Real, center: &[Real; 3]) -> Generated {
    let c = Point3::from(*center);
    let golden = PI * (3.0 - 5f64.sqrt());
    let mut positions = Vec::with_capacity(count);
    let mut normals = Vec::with_capacity(count);
    for i in 0..count {
        let z = 1.0 - (2 * i + 1) as Real / count as Real;
        let rho = (1.0 - z * z).max(0.0).sqrt();
        let phi = i as Real * golden;
        let u = Vec3::new(rho * phi.cos(), rho * phi.sin(), z);
        positions.push(c + u * radius);
        normals.push(u);
    }
    Generated {
        positions,
        normals,
        curvatures: vec![1.0 / radius; count],
    }
}

/// The rings of a torus shell: `(v, particles on the ring)`. Rings are
/// circles about the axis at tube angle `v` (`v = 0` outside), about
/// `spacing √3/2` apart along the tube; each ring holds about
/// `2π(R + r cos v) / spacing` particles (at least 3).
pub(super) fn torus_rings(major: Real, minor: Real, spacing: Real) -> Vec<(Real, usize)> {
    let nv = ((2.0 * PI * minor / (spacing * 3f64.sqrt() / 2.0)).round() as usize).max(3);
    (0..nv)
        .map(|j| {
            let v = 2.0 * PI * j as Real / nv as Real;
            let rho = major + minor * v.cos();
            (v, ((2.0 * PI * rho / spacing).round() as usize).max(3))
        })
        .collect()
}

/// Upper estimate of the particle count of a torus shell (before building
/// its rings): the area `4π² R r` over the hexagonal area per particle,
/// plus three per ring.
pub(crate) fn torus_estimate(major: Real, minor: Real, spacing: Real) -> Real {
    let area = 4.0 * PI * PI * major * minor;
    let rings = 2.0 * PI * minor / (spacing * 3f64.sqrt() / 2.0) + 4.0;
    area * 2.0 / (3f64.sqrt() * spacing * spacing) + 3.0 * rings + rings
}

/// A torus shell about `axis` through `center`: outward normals, rest
/// curvature the mean curvature `H = (R + 2r cos v) / (2r (R + r cos v))`.
pub(super) fn torus_shell(
    major: Real,
    minor: Real,
    spacing: Real,
    center: &[Real; 3],
    axis: &[Real; 3],
) -> Generated {
    let (e1, e2, a) = plane_frame(axis);
    let c = Point3::from(*center);
    let rings = torus_rings(major, minor, spacing);
    let count = rings.iter().map(|r| r.1).sum();
    let mut out = Generated {
        positions: Vec::with_capacity(count),
        normals: Vec::with_capacity(count),
        curvatures: Vec::with_capacity(count),
    };
    for (j, &(v, nu)) in rings.iter().enumerate() {
        let rho = major + minor * v.cos();
        let h = (major + 2.0 * minor * v.cos()) / (2.0 * minor * rho);
        let offset = 0.5 * (j % 2) as Real;
        for k in 0..nu {
            let u = 2.0 * PI * (k as Real + offset) / nu as Real;
            let radial = e1 * u.cos() + e2 * u.sin();
            out.positions.push(c + radial * rho + a * (minor * v.sin()));
            out.normals.push(radial * v.cos() + a * v.sin());
            out.curvatures.push(h);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spiral_angle_is_the_integral_of_the_curvature_for_every_law() {
        let laws = [
            CurvatureLaw::Linear,
            CurvatureLaw::Geometric,
            CurvatureLaw::Quadratic,
            CurvatureLaw::Sine,
        ];
        let (k0, k1, length) = (0.1, 0.9, 13.0);
        for law in laws {
            assert_eq!(spiral_angle(law, k0, k1, 0.0, length), 0.0);
            assert!((spiral_curvature(law, k0, k1, 0.0, length) - k0).abs() < 1e-12);
            assert!((spiral_curvature(law, k0, k1, length, length) - k1).abs() < 1e-12);
            for k in 1..13 {
                let (s, h) = (k as Real, 1e-5);
                let slope = (spiral_angle(law, k0, k1, s + h, length)
                    - spiral_angle(law, k0, k1, s - h, length))
                    / (2.0 * h);
                let kappa = spiral_curvature(law, k0, k1, s, length);
                assert!(
                    (slope - kappa).abs() < 1e-8,
                    "{law:?} at {s}: {slope} vs {kappa}"
                );
            }
        }
    }

    #[test]
    fn spiral_of_constant_curvature_is_a_circle_with_outward_normals() {
        let k = 0.25;
        let g = spiral(
            20,
            0.5,
            (k, k, CurvatureLaw::Linear),
            &[1.0, 2.0, 3.0],
            &[0.0, 0.0, 1.0],
        );
        // A geometric law of ratio 1 is the same circle.
        let geometric = spiral(
            20,
            0.5,
            (k, k, CurvatureLaw::Geometric),
            &[1.0, 2.0, 3.0],
            &[0.0, 0.0, 1.0],
        );
        assert_eq!(geometric, g);
        for (p, n) in g.positions.iter().zip(&g.normals) {
            let centre = p - n / k;
            let c0 = g.positions[0] - g.normals[0] / k;
            assert!((centre - c0).norm() < 1e-9, "{centre} vs {c0}");
            assert!((n.norm() - 1.0).abs() < 1e-12);
            assert!(n.z.abs() < 1e-12);
        }
        // Arc 0.5 on radius 4: chord 2 R sin(s / 2R).
        let chord = 2.0 * 4.0 * (0.5f64 / 8.0).sin();
        let d = (g.positions[1] - g.positions[0]).norm();
        assert!((d - chord).abs() < 1e-10, "{d} vs {chord}");
    }

    #[test]
    fn torus_mean_curvature_matches_principal_curvatures() {
        let (big, r) = (3.0, 1.0);
        let g = torus_shell(big, r, 0.3, &[0.0; 3], &[0.0, 0.0, 1.0]);
        let outer = g.curvatures[0];
        assert!((outer - 0.5 * (1.0 / r + 1.0 / (big + r))).abs() < 1e-12);
        for (p, n) in g.positions.iter().zip(&g.normals) {
            // The tube centre circle is at distance `minor` along -n.
            let q = p - n * r;
            assert!((q.z).abs() < 1e-12);
            assert!(((q.x * q.x + q.y * q.y).sqrt() - big).abs() < 1e-12);
        }
    }

    #[test]
    fn rng_is_in_range_and_seeded() {
        let mut a = SplitMix64(7);
        let mut b = SplitMix64(7);
        for _ in 0..1000 {
            let x = a.symmetric();
            assert!((-1.0..1.0).contains(&x));
            assert_eq!(x, b.symmetric());
        }
    }
}
