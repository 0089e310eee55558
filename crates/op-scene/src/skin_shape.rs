//! The amplitude of a displayed (blended) skin, matched to the object's
//! contact skin, and the measured shape of default skins: round clumps,
//! flat sheets, ribbons without bumps (issue 19).
//!
//! Blending (a kernel support of `smoothness · radius`, seed 002 §6's sum
//! of potentials over a wider reach) adds the neighbours' potentials to
//! every point near the object, so with the amplitude of an isolated
//! primitive the skin grows with the number of neighbours: a ribbon of
//! squares at spacing 1 and radius 0.8 becomes about 2 r0 thick at
//! smoothness 2 instead of 1 r0. The displayed skin's amplitude is
//! therefore chosen on the object itself: the contact skin (the plain
//! kernel, [`crate::skins::SkinSpec::contact_primitive`]) is crossed along
//! probe rays from every particle (its normal both ways for a square, the
//! six world axis directions for a point), and the amplitude makes the
//! mean displayed field at those crossings the iso value: the displayed
//! skin passes, on average, where the contact skin is. Blending then only
//! rounds the skin (fills the necks between particles, shaves their
//! bumps) without changing its size, and what is shown is where objects
//! touch.

use op_dynamics::{Point3, Real, Vec3};
use op_implicit::{Field, ISO};

/// Bisection steps on a probe ray: the crossing to 2^-30 of a step.
const BISECTIONS: usize = 30;

/// Where the ray `x + t u` (`t >= 0`) leaves `{contact >= ISO}`, found by
/// stepping `step` along it up to `reach`, then bisecting; `None` when `x`
/// is not inside the skin or the ray does not leave it within `reach`.
fn crossing(contact: &Field, x: &Point3, u: &Vec3, step: Real, reach: Real) -> Option<Point3> {
    if contact.value(x) < ISO {
        return None;
    }
    let mut t = 0.0;
    while t < reach {
        let next = t + step;
        if contact.value(&(x + u * next)) < ISO {
            let (mut lo, mut hi) = (t, next);
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if contact.value(&(x + u * mid)) >= ISO {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Some(x + u * (0.5 * (lo + hi)));
        }
        t = next;
    }
    None
}

/// The amplitude of the displayed skin whose unit-amplitude field is
/// `display_unit`: `ISO / mean(display_unit(p))` over the contact skin's
/// crossings `p` of the probe rays `(x, u)` (module doc), each ray
/// stepped by `step` up to `reach`. `None` when no ray crosses the contact
/// skin (the caller keeps the isolated primitive's amplitude).
pub(crate) fn matched_weight(
    contact: &Field,
    display_unit: &Field,
    rays: &[(Point3, Vec3)],
    step: Real,
    reach: Real,
) -> Option<Real> {
    let (sum, n) = rays
        .iter()
        .filter_map(|(x, u)| crossing(contact, x, u, step, reach))
        .fold((0.0, 0usize), |(s, n), p| {
            (s + display_unit.value(&p), n + 1)
        });
    let mean = sum / n as Real;
    (n > 0 && mean.is_finite() && mean > 0.0).then(|| ISO / mean)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::built_scene::BuiltObject;
    use crate::skins::{SkinPrimitive, SkinSpec, DEFAULT_SMOOTHNESS};
    use op_dynamics::{Material, ParticleDesc, Particles, Quat, World, WorldParams};
    use op_implicit::Mesh;

    /// The skin mesh of one object made of particles at `at` (normals
    /// along +z).
    fn skin_of(at: &[Point3], spec: &SkinSpec, spacing: Real) -> Mesh {
        let frames: Vec<(Point3, Quat)> = at.iter().map(|x| (*x, Quat::identity())).collect();
        oriented_skin_of(&frames, spec, spacing)
    }

    /// The skin mesh of one object made of particles at the given
    /// positions and orientations (body normal axis +z).
    fn oriented_skin_of(frames: &[(Point3, Quat)], spec: &SkinSpec, spacing: Real) -> Mesh {
        let at: Vec<Point3> = frames.iter().map(|(x, _)| *x).collect();
        let mut p = Particles::new();
        for (x, q) in frames {
            let mut d = ParticleDesc::at(*x);
            d.orientation = *q;
            p.push(d).unwrap();
        }
        let world = World::new(p, &[Material::empty()], WorldParams::default()).unwrap();
        let object = BuiltObject {
            name: "o".into(),
            ids: (0..at.len() as u32).collect(),
            rest: at.clone(),
            rest_spacing: spacing,
            created: Vec::new(),
        };
        crate::skins::build_skin(&world, 0, &object, spec, [0.0, 0.0, 1.0])
            .unwrap()
            .mesh()
            .unwrap()
    }

    /// RMS distance of `points` to their least-squares sphere, over its
    /// radius (algebraic fit: `|x|² = 2 c·x + k`, then the RMS of
    /// `|x - c| - r`).
    fn sphere_roundness(points: &[Point3]) -> Real {
        let mut a = nalgebra::Matrix4::<Real>::zeros();
        let mut b = nalgebra::Vector4::<Real>::zeros();
        for p in points {
            let row = nalgebra::Vector4::new(2.0 * p.x, 2.0 * p.y, 2.0 * p.z, 1.0);
            a += row * row.transpose();
            b += row * p.coords.norm_squared();
        }
        let sol = a.lu().solve(&b).unwrap();
        let c = Vec3::new(sol[0], sol[1], sol[2]);
        let r = (sol[3] + c.norm_squared()).sqrt();
        let ms = points
            .iter()
            .map(|p| ((p.coords - c).norm() - r).powi(2))
            .sum::<Real>()
            / points.len() as Real;
        ms.sqrt() / r
    }

    fn point_skin(radius: Real, smoothness: Real) -> SkinSpec {
        SkinSpec {
            primitive: SkinPrimitive::Point,
            radius,
            cell_size: 0.05,
            stiffness: 100.0,
            smoothness,
            thickness: None,
            smoothing: 0,
        }
    }

    /// The ball of `ball_vs_spiral`: four point primitives of radius 1.2 in
    /// a tetrahedron of edge 1. With the plain kernel its skin is a rounded
    /// tetrahedron; with smoothness 2 it is round within 5%.
    #[test]
    fn blended_skin_of_a_tetrahedron_is_round() {
        let h = (2.0 as Real / 3.0).sqrt();
        let tetra = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.5, (0.75 as Real).sqrt(), 0.0),
            Point3::new(0.5, (0.75 as Real).sqrt() / 3.0, h),
        ];
        let mut table = Vec::new();
        for s in [1.0, 1.5, 2.0, 3.0] {
            let mesh = skin_of(&tetra, &point_skin(1.2, s), 1.0);
            table.push((s, sphere_roundness(mesh.positions())));
        }
        println!("smoothness -> RMS off the best-fit sphere / radius: {table:?}");
        assert!(table[0].1 > 0.05, "the plain kernel is lumpy: {table:?}");
        assert!(table[2].1 < 0.05, "roundness at smoothness 2: {table:?}");
        // The default skin (the scene's spec without a smoothness).
        let default = skin_of(&tetra, &point_skin(1.2, DEFAULT_SMOOTHNESS), 1.0);
        let off = sphere_roundness(default.positions());
        println!("default smoothness {DEFAULT_SMOOTHNESS}: {off:.4}");
        assert!(off < 0.05, "default skin off its sphere by {off}");
    }

    /// The bumps of a curved ribbon's skin: square primitives (half side
    /// 0.5, radius 0.8: the spiral of `ball_vs_spiral`) at spacing 1 (the
    /// chord) on a closed ring of 13 (radius 2.09, curvature 0.48, mid-range
    /// of the spiral's 0.25-0.85; closed so no end tapers the skin), each
    /// perpendicular to the radius. Over the skin's vertices at mid-height
    /// (|z| < 0.25), the peak-to-peak spread of the distance to the ring's
    /// axis on the outer face and on the inner face, the larger, in units
    /// of the spacing r0 = 1: a smooth ribbon has the same offset all
    /// around; a bumpy one is thicker at the particles than between them.
    /// Returns the mean inner and outer face radii and the larger
    /// spread.
    fn ribbon_bumps(smoothness: Real) -> (Real, Real, Real) {
        let n = 13;
        let step = 2.0 * std::f64::consts::PI / n as Real;
        let rho = 0.5 / (0.5 * step).sin();
        let frames: Vec<(Point3, Quat)> = (0..n)
            .map(|i| {
                let a = i as Real * step;
                let radial = Vec3::new(a.cos(), a.sin(), 0.0);
                let q = Quat::rotation_between(&Vec3::z(), &radial).unwrap();
                (Point3::from(radial * rho), q)
            })
            .collect();
        let spec = SkinSpec {
            primitive: SkinPrimitive::Square { half_side: 0.5 },
            radius: 0.8,
            cell_size: 0.05,
            stiffness: 100.0,
            smoothness,
            thickness: None,
            smoothing: 0,
        };
        let mesh = oriented_skin_of(&frames, &spec, 1.0);
        // Where the mesh crosses mid-height rays from the axis, 20 rays per
        // spacing: the nearest crossing is the inner face, the farthest
        // the outer (Moller-Trumbore ray-triangle intersection).
        let rays = 20 * n;
        let mut faces = vec![(Real::MAX, Real::MIN); rays];
        for (k, face) in faces.iter_mut().enumerate() {
            let a = (k as Real + 0.5) / rays as Real * 2.0 * std::f64::consts::PI;
            let d = Vec3::new(a.cos(), a.sin(), 0.0);
            for t in mesh.triangles() {
                let [p0, p1, p2] = t.map(|i| mesh.positions()[i as usize]);
                let (e1, e2) = (p1 - p0, p2 - p0);
                let q = d.cross(&e2);
                let det = e1.dot(&q);
                if det.abs() < 1e-14 {
                    continue;
                }
                let s = -p0.coords;
                let u = s.dot(&q) / det;
                let r = s.cross(&e1);
                let v = d.dot(&r) / det;
                let dist = e2.dot(&r) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dist > 0.0 {
                    *face = (face.0.min(dist), face.1.max(dist));
                }
            }
        }
        let spread = |pick: fn(&(Real, Real)) -> Real| {
            let (lo, hi) = faces
                .iter()
                .map(pick)
                .fold((Real::MAX, Real::MIN), |(a, b), r| (a.min(r), b.max(r)));
            hi - lo
        };
        let (inner, outer) = (spread(|f| f.0), spread(|f| f.1));
        assert!(
            faces.iter().all(|f| f.0 < rho && f.1 > rho),
            "a ray misses a face"
        );
        let mean = |pick: fn(&(Real, Real)) -> Real| {
            faces.iter().map(pick).sum::<Real>() / faces.len() as Real
        };
        let (r_in, r_out) = (mean(|f| f.0), mean(|f| f.1));
        println!(
            "smoothness {smoothness}: faces at {r_in:.3} and {r_out:.3} (ring {rho:.3}); \
             peak-to-peak inner {inner:.4}, outer {outer:.4} r0"
        );
        (r_in, r_out, inner.max(outer))
    }

    /// A curved ribbon's default skin ([`ribbon_bumps`]) is about as thick
    /// as its contact skin (the plain kernel's: measured 0.96 r0 against
    /// 1.03 r0, the blended amplitude being matched to it at the particles)
    /// and blending adds no bumps. It does not remove
    /// them either: measured peak-to-peak 0.137 r0 with the plain kernel,
    /// 0.133 at smoothness 2, 0.177 at 3 (issue 19's "no bumps" is not met;
    /// the ripple follows from flat squares one spacing apart on a curve,
    /// at an offset of half the support).
    #[test]
    fn curved_ribbon_default_skin_keeps_its_size_and_adds_no_bumps() {
        let (in1, out1, plain) = ribbon_bumps(1.0);
        let (in2, out2, default) = ribbon_bumps(DEFAULT_SMOOTHNESS);
        println!("ribbon bumps, peak-to-peak / r0: smoothness 1 {plain:.4}, default {default:.4}");
        assert!(
            ((out2 - in2) - (out1 - in1)).abs() < 0.1,
            "{in1} {out1} vs {in2} {out2}"
        );
        assert!(default <= plain, "{default} vs {plain}");
    }

    /// A flat hexagonal sheet with square primitives and a thickness: its
    /// skin is flat (the top vertices over the inner sheet within 1% r0 of
    /// one height) at the height asked for, within 2% r0 (measured at
    /// thickness 0.15: 1.2% r0, 0.2: 1.0%, 0.25 and up: below 1%).
    #[test]
    fn sheet_skin_is_flat_at_the_thickness_asked_for() {
        let mut at = Vec::new();
        for j in 0..12 {
            for i in 0..12 {
                let x = i as Real + 0.5 * (j % 2) as Real;
                at.push(Point3::new(x, j as Real * (0.75 as Real).sqrt(), 0.0));
            }
        }
        for thickness in [0.25, 0.4] {
            let spec = SkinSpec {
                primitive: SkinPrimitive::Square { half_side: 0.5 },
                radius: 1.2,
                cell_size: 0.05,
                stiffness: 100.0,
                smoothness: 2.0,
                thickness: Some(thickness),
                smoothing: 0,
            };
            let mesh = skin_of(&at, &spec, 1.0);
            let top: Vec<Real> = mesh
                .positions()
                .iter()
                .filter(|p| (3.0..8.0).contains(&p.x) && (3.0..7.0).contains(&p.y) && p.z > 0.0)
                .map(|p| p.z)
                .collect();
            let (lo, hi) = top
                .iter()
                .fold((Real::MAX, Real::MIN), |(a, b), &z| (a.min(z), b.max(z)));
            println!(
                "thickness {thickness}: {} top vertices at z {lo:.4}..{hi:.4}",
                top.len()
            );
            assert!(top.len() > 100);
            assert!(hi - lo < 0.01, "flat within 1% r0: {lo}..{hi}");
            assert!(
                (0.5 * (lo + hi) - thickness).abs() < 0.02,
                "{lo}..{hi} vs {thickness}"
            );
        }
    }
}
