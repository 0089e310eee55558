//! The amplitudes of an object's skins, chosen on the object: the contact
//! skin at its thickness, the displayed (blended) skin matched to the
//! contact skin; and the measured shape of default skins: round clumps,
//! flat and thin sheets, ribbons without bumps.
//!
//! **Thickness.** A primitive's field adds to its neighbours', so with the
//! amplitude of an isolated primitive (whose skin is `radius / 2` from it)
//! a sheet's skin is thicker than that, the more so the more neighbours
//! reach: a hexagonal sheet of squares of radius 0.8 is 1.27 r0 thick.
//! [`offset_weight`] sets the amplitude so the skin passes at the
//! thickness asked for (by default `radius / 2` for squares) along the
//! particles' normals, for the median particle; op-implicit's `stretch`
//! then keeps that thickness at the rim and as the sheet stretches.
//!
//! Blending (a kernel support of `smoothness · radius`, seed 002 §6's sum
//! of potentials over a wider reach) adds the neighbours' potentials to
//! every point near the object, so with the amplitude of an isolated
//! primitive the skin grows with the number of neighbours: a ribbon of
//! squares at spacing 1 and radius 0.8 becomes about 2 r0 thick at
//! smoothness 2 instead of 1 r0. The displayed skin's amplitude is
//! therefore chosen on the object itself: the contact skin (the plain
//! kernel, [`crate::skins::SkinSpec::contact_shape`]) is crossed along
//! probe rays from every particle (its normal both ways for a square, the
//! six world axis directions for a point), and the amplitude makes the
//! median displayed field at those crossings the iso value: the displayed
//! skin passes, on average, where the contact skin is. Blending then only
//! rounds the skin (fills the necks between particles, shaves their
//! bumps) without changing its size, and what is shown is where objects
//! touch.
//!
//! **Cost.** Both amplitudes are medians, so they are taken over a bounded,
//! evenly spread sample of at most [`MAX_PROBES`] rays ([`spread`]): a
//! probe ray from a particle deep inside a solid marches through it, and
//! every ray of a large solid made building it quadratic in its particles
//! (a solid torus of 23,636 particles spent 21 s here). The rays are
//! marched in parallel and collected in order, so the median, and the
//! amplitude, do not depend on the thread count. An object with at most
//! [`MAX_PROBES`] rays uses every one, as before.

use op_dynamics::{Point3, Real, Vec3};
use op_implicit::{Field, ISO};
use rayon::prelude::*;

/// The most probe rays an amplitude is measured on (module docs).
pub(crate) const MAX_PROBES: usize = 4096;

/// At most [`MAX_PROBES`] of `rays`, evenly spread over the list (every
/// ray when there are no more): ray `floor(k n / MAX_PROBES)` for `k` in
/// `0..MAX_PROBES`. The rays come particle by particle in the object's
/// order, a spatial order for the generators, so the sample covers the
/// whole object.
fn spread(rays: &[(Point3, Vec3)]) -> Vec<(Point3, Vec3)> {
    let n = rays.len();
    if n <= MAX_PROBES {
        return rays.to_vec();
    }
    (0..MAX_PROBES).map(|k| rays[k * n / MAX_PROBES]).collect()
}

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
/// `display_unit`: `ISO / median(display_unit(p))` over the contact skin's
/// crossings `p` of the probe rays `(x, u)` (at most [`MAX_PROBES`] of
/// them, evenly spread: module doc), each ray
/// stepped by `step` up to `reach`. The median, as in [`offset_weight`]:
/// the displayed skin passes where the contact skin does at the median
/// particle, however differently the two thin out at a sheet's rim (the
/// display reaches further). `None` when no ray crosses the contact skin
/// (the caller keeps the isolated primitive's amplitude).
pub(crate) fn matched_weight(
    contact: &Field,
    display_unit: &Field,
    rays: &[(Point3, Vec3)],
    step: Real,
    reach: Real,
) -> Option<Real> {
    let mut values: Vec<Real> = spread(rays)
        .par_iter()
        .filter_map(|(x, u)| crossing(contact, x, u, step, reach))
        .map(|p| display_unit.value(&p))
        .collect();
    values.sort_by(Real::total_cmp);
    let median = *values.get(values.len() / 2)?;
    (median.is_finite() && median > 0.0).then(|| ISO / median)
}

/// The amplitude that puts the skin whose unit-amplitude field is
/// `unit` at distance `offset` from the skeleton along the probe rays
/// `(x, u)` (a particle and its normal axis, both ways): `ISO / median(
/// unit(x + offset u))`. The median particle's skin is at `offset`: in a
/// sheet, the interior's; a particle with fewer neighbours (a rim, a
/// chain) is a little thinner. `None` without rays or with no field there.
pub(crate) fn offset_weight(unit: &Field, rays: &[(Point3, Vec3)], offset: Real) -> Option<Real> {
    let mut values: Vec<Real> = spread(rays)
        .par_iter()
        .map(|(x, u)| unit.value(&(x + u * offset)))
        .collect();
    values.sort_by(Real::total_cmp);
    let median = *values.get(values.len() / 2)?;
    (median.is_finite() && median > 0.0).then(|| ISO / median)
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

    /// The skin of a curved ribbon: square primitives (half side 0.5,
    /// radius 0.8: the spiral of `ball_vs_spiral`) at spacing 1 (the
    /// chord) on a closed ring of `n` (13: radius 2.09, curvature 0.48,
    /// mid-range of the spiral's 0.25-0.85; closed so no end tapers the
    /// skin), each perpendicular to the radius, at a thickness of 0.4 (the
    /// default, `radius / 2`). Over rays from the ring's axis at
    /// mid-height, 20 per spacing:
    /// the mean distance of the inner face and of the outer face from the
    /// ring (their offsets from the skeleton), and the larger
    /// peak-to-peak spread of either face, all in units of the spacing
    /// r0 = 1: a smooth ribbon has the same offset all around; a bumpy
    /// one is thicker at the particles than between them.
    fn ring_ribbon(n: usize, smoothness: Real) -> (Real, Real, Real) {
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
            thickness: Some(0.4),
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
                // A tolerance so a ray through a shared edge hits one of
                // its triangles.
                let tol = 1e-9;
                if u >= -tol && v >= -tol && u + v <= 1.0 + tol && dist > 0.0 {
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
        let (r_in, r_out) = (rho - mean(|f| f.0), mean(|f| f.1) - rho);
        println!(
            "ring of {n}, smoothness {smoothness}: faces {r_in:.3} inside and {r_out:.3} \
             outside; peak-to-peak inner {inner:.4}, outer {outer:.4} r0"
        );
        (r_in, r_out, inner.max(outer))
    }

    /// A curved ribbon's skin at the default smoothness ([`ring_ribbon`])
    /// shows no bumps between its particles and lies at its thickness on
    /// both faces, on
    /// rings of 8 to 30 particles (curvature 0.77 to 0.21). The plain
    /// kernel of squares keeps the polygon of flat squares (bumps 0.10 to
    /// 0.25 r0, the convex face 0.44 to 0.54 out); blending squares does
    /// not remove it (0.13 r0 at smoothness 2 on 13), the ellipsoids of
    /// [`SkinSpec::display_shape`] do. Measured peak-to-peak at smoothness
    /// 1.25 / 1.5 / 1.75 / 2: 0.023-0.062 / 0.015-0.024 / 0.025-0.046 /
    /// 0.006-0.049 r0; the convex face's offset at 8 particles 0.41 / 0.35
    /// / 0.28 / 0.21 (a wider blend thickens the concave side, where the
    /// neighbours' kernels overlap, at the convex side's expense): 1.5, the
    /// default, is smooth and symmetric on every ring.
    #[test]
    fn curved_ribbon_default_skin_shows_no_bumps_at_its_thickness() {
        for n in [8, 13, 20, 30] {
            let (_, _, plain) = ring_ribbon(n, 1.0);
            assert!(plain > 0.09, "the plain squares' polygon shows: {plain}");
            let (inner, outer, bumps) = ring_ribbon(n, DEFAULT_SMOOTHNESS);
            assert!(bumps < 0.03, "ring of {n}: bumps {bumps} r0");
            for face in [inner, outer] {
                assert!(
                    (face - 0.4).abs() < 0.06,
                    "ring of {n}: faces {inner} {outer}"
                );
            }
        }
    }

    /// A flat hexagonal sheet of square primitives: its skin is flat (the
    /// top vertices over the inner sheet within 1% r0 of one height) at the
    /// thickness asked for, within 2% r0.
    /// A flat hexagonal sheet of 12 x 12 particles at spacing 1 in the
    /// plane z = 0.
    fn hex_sheet() -> Vec<Point3> {
        let mut at = Vec::new();
        for j in 0..12 {
            for i in 0..12 {
                let x = i as Real + 0.5 * (j % 2) as Real;
                at.push(Point3::new(x, j as Real * (0.75 as Real).sqrt(), 0.0));
            }
        }
        at
    }

    /// The heights of the top vertices of a [`hex_sheet`]'s skin over its
    /// inner part (away from the rim), and their range.
    fn top_face(mesh: &Mesh) -> (Vec<Real>, Real, Real) {
        let top: Vec<Real> = mesh
            .positions()
            .iter()
            .filter(|p| (3.0..8.0).contains(&p.x) && (3.0..7.0).contains(&p.y) && p.z > 0.0)
            .map(|p| p.z)
            .collect();
        let (lo, hi) = top
            .iter()
            .fold((Real::MAX, Real::MIN), |(a, b), &z| (a.min(z), b.max(z)));
        (top, lo, hi)
    }

    /// Square primitives small against the spacing (half side 0.25 and
    /// radius 0.4, or half side 0.1 and radius 0.3, at spacing 1) still
    /// make a flat, closed sheet at a thickness of half the radius: the displayed
    /// kernel reaches at least 1.5 spacings in the sheet's plane. Measured
    /// flat within 0.43% and 0.31% r0 (without the floor the skin reached
    /// the sheet's plane between particles).
    #[test]
    fn small_squares_still_cover_a_sheet() {
        let at = hex_sheet();
        for (half_side, radius) in [(0.25, 0.4), (0.1, 0.3)] {
            let spec = SkinSpec {
                primitive: SkinPrimitive::Square { half_side },
                radius,
                cell_size: 0.04,
                stiffness: 100.0,
                smoothness: DEFAULT_SMOOTHNESS,
                thickness: Some(0.5 * radius),
                smoothing: 0,
            };
            let mesh = skin_of(&at, &spec, 1.0);
            assert!(mesh.is_closed_oriented_manifold());
            let (_, lo, hi) = top_face(&mesh);
            println!("half side {half_side}, radius {radius}: top at {lo:.4}..{hi:.4}");
            assert!(hi - lo < 0.01, "flat within 1% r0: {lo}..{hi}");
            assert!((0.5 * (lo + hi) - 0.5 * radius).abs() < 0.02, "{lo}..{hi}");
        }
    }

    #[test]
    fn sheet_skin_is_flat_at_the_thickness_asked_for() {
        let at = hex_sheet();
        for asked in [0.25, 0.4, 0.6] {
            let spec = SkinSpec {
                primitive: SkinPrimitive::Square { half_side: 0.5 },
                radius: 1.2,
                cell_size: 0.05,
                stiffness: 100.0,
                smoothness: DEFAULT_SMOOTHNESS,
                thickness: Some(asked),
                smoothing: 0,
            };
            let thickness = asked;
            let mesh = skin_of(&at, &spec, 1.0);
            let (top, lo, hi) = top_face(&mesh);
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
