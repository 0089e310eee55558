//! Tests of [`super`]: balance of the pair reactions, no gap and no
//! overlap of the deformed skins, determinism, C1 bulge.

use super::*;
use super::{crossing, BRACKET};
use crate::polygonize::{polygonize_field, PolygonizeParams};
use crate::primitives::Primitive;
use op_dynamics::{Material, ParticleDesc, Particles, Quat, WorldParams};
use op_test_support::Rng;
use std::collections::BTreeMap;

/// Velocity Verlet of unit masses (no other force) on `state`, whose
/// particle positions `positions` gives, from `velocities`, over
/// `duration` at step `dt`, under a contact of energy `energy` and forces
/// `forces`: the largest drift of the total energy (kinetic plus contact)
/// and the largest contact energy, both over the total at the start. The
/// contact energy tests' measure of the scheme's order
/// (`energy::tests`, `obstacle::tests`).
pub(super) fn verlet_energy_drift<S>(
    state: &mut S,
    velocities: &mut [Vec3],
    (dt, duration): (Real, Real),
    positions: impl Fn(&mut S) -> &mut [Point3],
    energy: impl Fn(&S) -> Real,
    forces: impl Fn(&S) -> Vec<Vec3>,
) -> (Real, Real) {
    let kinetic = |v: &[Vec3]| v.iter().map(|v| 0.5 * v.norm_squared()).sum::<Real>();
    let start = energy(state) + kinetic(velocities);
    let (mut drift, mut deepest): (Real, Real) = (0.0, 0.0);
    let mut f = forces(state);
    let steps = (duration / dt).round() as usize;
    for _ in 0..steps {
        for (i, p) in positions(state).iter_mut().enumerate() {
            velocities[i] += f[i] * (0.5 * dt);
            *p += velocities[i] * dt;
        }
        f = forces(state);
        for (v, f) in velocities.iter_mut().zip(&f) {
            *v += f * (0.5 * dt);
        }
        let contact = energy(state);
        drift = drift.max((contact + kinetic(velocities) - start).abs());
        deepest = deepest.max(contact);
    }
    (drift / start, deepest / start)
}

/// Asserts that `drifts` ([`verlet_energy_drift`] at steps halved from one
/// to the next) show second order: each halving divides the drift by 3 to
/// 5.5, and the contact energy peaks above a tenth of the total (the
/// objects `meet`).
pub(super) fn assert_second_order(drifts: &[(Real, Real)], meet: &str) {
    eprintln!("drift and peak contact energy over the kinetic: {drifts:?}");
    assert!(drifts.iter().all(|d| d.1 > 0.1), "{meet}");
    for pair in drifts.windows(2) {
        let ratio = pair[0].0 / pair[1].0;
        assert!((3.0..5.5).contains(&ratio), "ratio {ratio}");
    }
}

fn world_at(points: &[Point3]) -> World {
    let mut particles = Particles::new();
    for p in points {
        particles.push(ParticleDesc::at(*p)).unwrap();
    }
    World::new(particles, &[Material::default()], WorldParams::default()).unwrap()
}

/// A: two point blobs (particles 0, 1); B: one point blob (particle 2).
fn blobs() -> (Field, Field) {
    let q = Quat::identity();
    let a = Field::new(vec![
        Primitive::point(Vec3::zeros(), 1.0).posed(0, &Point3::new(-0.45, 0.15, 0.02), &q),
        Primitive::point(Vec3::zeros(), 1.0).posed(1, &Point3::new(-0.45, -0.15, 0.0), &q),
    ]);
    let b = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        2,
        &Point3::new(0.4, 0.05, -0.03),
        &q,
    )]);
    (a, b)
}

/// A: a tilted rectangle (particle 0); B: a point blob above it
/// (particle 1).
fn rectangle_and_point() -> (Field, Field) {
    let tilt = Quat::from_scaled_axis(Vec3::new(0.2, -0.1, 0.3));
    let rect = Primitive::rectangle(Vec3::zeros(), Quat::identity(), [0.4, 0.3], 0.6);
    let a = Field::new(vec![rect.posed(0, &Point3::new(0.01, -0.02, 0.0), &tilt)]);
    let b = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        1,
        &Point3::new(0.15, 0.1, 0.6),
        &Quat::identity(),
    )]);
    (a, b)
}

const PARAMS: ImplicitContactParams = ImplicitContactParams {
    stiffness: 100.0,
    cell_size: 0.04,
    max_nodes_per_axis: 512,
};

/// Relative residuals of the total force and of the total torque about
/// the origin (`tau + p x F` over every particle), scaled by the sum of
/// the force magnitudes on A (times the length scale 1).
fn balance(a: &Field, b: &Field, r: &PairReactions) -> (Real, Real) {
    let at: BTreeMap<u32, Point3> = a
        .primitives()
        .iter()
        .chain(b.primitives())
        .map(|p| (p.particle(), *p.particle_position()))
        .collect();
    let (mut f, mut t) = (Vec3::zeros(), Vec3::zeros());
    let all = r.a().reactions().iter().chain(r.b().reactions());
    for x in all {
        f += x.force;
        t += x.torque + at[&x.particle].coords.cross(&x.force);
    }
    let scale: Real = r.a().reactions().iter().map(|x| x.force.norm()).sum();
    (f.norm() / scale, t.norm() / scale)
}

fn centre(field: &Field) -> Vec3 {
    let ps = field.primitives();
    ps.iter()
        .map(|p| p.particle_position().coords)
        .sum::<Vec3>()
        / ps.len() as Real
}

/// The reactions sum to zero (the lattice moves with the skins) and their
/// torques balance as the quadrature converges; the total pushes the
/// skins apart, and is the same at two cell sizes. Measured: relative
/// force residual <= 4e-16; torque residual 7e-6 / 9e-4 (blobs /
/// rectangle) at h = 0.04, 8e-7 / 5e-5 at 0.02; the totals at h = 0.04 and
/// 0.02 differ by 1e-3 and 4e-3.
#[test]
fn reactions_are_equal_opposite_and_repulsive() {
    for (name, (a, b)) in [("blobs", blobs()), ("rectangle", rectangle_and_point())] {
        let pair = ContactPair::new(&a, &b);
        let r = pair.reactions(&PARAMS).unwrap();
        assert!(
            r.edges_in_contact() > 50,
            "{name}: {}",
            r.edges_in_contact()
        );
        assert_eq!(r.a().samples_in_contact(), r.edges_in_contact());
        assert_eq!(r.b().samples_in_contact(), r.edges_in_contact());
        let (df, dt) = balance(&a, &b, &r);
        let fa = r.a().total_force();
        let fb = r.b().total_force();
        let finer = ImplicitContactParams {
            cell_size: 0.02,
            ..PARAMS
        };
        let r_fine = pair.reactions(&finer).unwrap();
        let (_, dt_fine) = balance(&a, &b, &r_fine);
        let fine = r_fine.a().total_force();
        let rel = (fine - fa).norm() / fa.norm();
        eprintln!(
            "{name}: {} edges, force on A {fa:?}, residuals force {df:.2e} torque {dt:.2e} \
             (h 0.02: {dt_fine:.2e}); total force h = 0.04 vs 0.02: relative difference {rel:.2e}",
            r.edges_in_contact()
        );
        assert!(df < 1e-13, "{name}: {df}");
        assert!((fa + fb).norm() < 1e-13 * fa.norm(), "{name}");
        assert!(dt < 3e-3 && dt_fine < dt / 3.0, "{name}: {dt} {dt_fine}");
        assert!(
            fa.dot(&(centre(&a) - centre(&b)).normalize()) > 0.9 * fa.norm(),
            "{name}"
        );
        assert!(rel < 0.03, "{name}: {rel}");
    }
}

#[test]
fn reactions_are_shared_and_applied_to_the_world() {
    let (a, b) = blobs();
    let pts: Vec<Point3> = a
        .primitives()
        .iter()
        .chain(b.primitives())
        .map(|p| *p.particle_position())
        .collect();
    let mut world = world_at(&pts);
    let r = ContactPair::new(&a, &b).reactions(&PARAMS).unwrap();
    let ids: Vec<u32> = r.a().reactions().iter().map(|x| x.particle).collect();
    assert_eq!(ids, [0, 1]);
    assert_eq!(r.b().reactions().len(), 1);
    let before = world.evaluate_forces().0.to_vec();
    r.apply(&mut world);
    let after = world.evaluate_forces().0.to_vec();
    for x in r.a().reactions().iter().chain(r.b().reactions()) {
        let i = x.particle as usize;
        let applied = after[i] - before[i];
        assert!((applied - x.force).norm() < 1e-12 * (1.0 + x.force.norm()));
    }
}

#[test]
fn no_reaction_without_overlap() {
    let q = Quat::identity();
    let a = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        0,
        &Point3::new(-0.52, 0.0, 0.0),
        &q,
    )]);
    let b = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        1,
        &Point3::new(0.52, 0.0, 0.0),
        &q,
    )]);
    let r = ContactPair::new(&a, &b).reactions(&PARAMS).unwrap();
    assert_eq!(r, PairReactions::default());
    let far = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        1,
        &Point3::new(5.0, 0.0, 0.0),
        &q,
    )]);
    let r = ContactPair::new(&a, &far).reactions(&PARAMS).unwrap();
    assert_eq!(r, PairReactions::default());
    let empty = Field::default();
    let r = ContactPair::new(&a, &empty).reactions(&PARAMS).unwrap();
    assert_eq!(r, PairReactions::default());
    let bad = ImplicitContactParams {
        cell_size: -1.0,
        ..PARAMS
    };
    assert!(ContactPair::new(&a, &b).reactions(&bad).is_err());
}

#[test]
fn thread_count_determinism() {
    let (a, b) = rectangle_and_point();
    let pair = ContactPair::new(&a, &b);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| pair.reactions(&PARAMS).unwrap())
    };
    let one = run(1);
    assert_eq!(one, run(2));
}

/// No point is inside both deformed objects, and the contact samples
/// lie on both deformed skins. Measured: max of min(e'_A, e'_B) over the
/// random points -2.3e-4 (never positive); |e'| at the samples <= 6.7e-16;
/// polygonized (h = 0.04), A's deformed vertices reach at most 8.4e-4
/// (field units) into B's deformed object.
#[test]
fn deformed_skins_have_no_gap_and_no_overlap() {
    for bulge in [None, Some(Bulge::with_width(0.2))] {
        for (a, b) in [blobs(), rectangle_and_point()] {
            let pair = ContactPair::new(&a, &b).with_bulge(bulge);
            let (da, db) = (pair.deformed_a(), pair.deformed_b());
            let mut rng = Rng::new(17);
            let mut worst = Real::NEG_INFINITY;
            let mut both_raw = 0;
            for _ in 0..5_000 {
                let p = Point3::from(rng.vec3(1.0) * 0.6);
                let (ea, eb) = (da.value(&p) - ISO, db.value(&p) - ISO);
                worst = worst.max(ea.min(eb));
                both_raw += usize::from(a.value(&p) > ISO && b.value(&p) > ISO);
            }
            assert!(both_raw > 100, "the test points cover the overlap");
            assert!(worst <= 1e-15, "{worst}");
            let on_skin = pair
                .contact_surface(&PARAMS)
                .unwrap()
                .iter()
                .map(|s| {
                    let ea = da.value(&s.position) - ISO;
                    let eb = db.value(&s.position) - ISO;
                    ea.abs().max(eb.abs())
                })
                .fold(0.0, Real::max);
            assert!(on_skin < 1e-12, "{on_skin}");
            let mesh_params = PolygonizeParams::with_cell_size(0.04);
            let ma = polygonize_field(&da, &mesh_params).unwrap();
            let mb = polygonize_field(&db, &mesh_params).unwrap();
            assert!(ma.is_closed_oriented_manifold() && mb.is_closed_oriented_manifold());
            let overlap = ma
                .positions()
                .iter()
                .map(|p| db.value(p) - ISO)
                .fold(Real::NEG_INFINITY, Real::max);
            eprintln!(
                "bulge {bulge:?}: min(e'_A, e'_B) max {worst:.2e}, \
                 |e'| at samples {on_skin:.2e}, A's vertices into B {overlap:.2e}"
            );
            assert!(overlap < 3e-3, "{overlap}");
        }
    }
}

/// The contact removes volume from both skins; the bulge gives some
/// back around the contact.
#[test]
fn bulge_adds_volume_around_the_contact() {
    let (a, b) = blobs();
    let params = PolygonizeParams::with_cell_size(0.04);
    let volume = |bulge| {
        let pair = ContactPair::new(&a, &b).with_bulge(bulge);
        polygonize_field(&pair.deformed_a(), &params)
            .unwrap()
            .signed_volume()
    };
    let free = crate::polygonize(&a, &params).unwrap().signed_volume();
    let (flat, bulged) = (volume(None), volume(Some(Bulge::with_width(0.2))));
    eprintln!("volume of A: free {free:.4}, contact {flat:.4}, with bulge {bulged:.4}");
    assert!(flat < free && bulged > flat, "{free} {flat} {bulged}");
}

#[test]
fn bulge_profile_is_c1() {
    let b = Bulge {
        width: 0.3,
        peak: 0.4,
    };
    let s0 = b.peak * b.width;
    let eps = 1e-7;
    for s in [0.0, s0, b.width] {
        let (lo, dlo) = b.profile(s - eps);
        let (hi, dhi) = b.profile(s + eps);
        assert!((lo - hi).abs() < 3.0 * eps, "value jump at {s}");
        let left = if s == 0.0 { 0.0 } else { dlo };
        let right = if s == 0.0 { 1.0 } else { dhi };
        assert!(
            (dlo - left).abs() < 1e-6 && (dhi - right).abs() < 1e-6,
            "{s}"
        );
        if s > 0.0 {
            assert!((dlo - dhi).abs() < 1e-5, "slope jump at {s}");
        }
    }
    assert!((b.profile(s0).0 - 2.0 / 3.0 * s0).abs() < 1e-15);
    let h = 1e-6;
    for k in 1..300 {
        let s = b.width * k as Real / 300.0;
        let (g, dg) = b.profile(s);
        let fd = (b.profile(s + h).0 - b.profile(s - h).0) / (2.0 * h);
        assert!((fd - dg).abs() < 1e-6, "{s}");
        assert!((0.0..=s).contains(&g), "0 <= g(s) <= s at {s}");
    }
    assert!(!Bulge::with_width(0.6).is_valid() && Bulge::with_width(0.5).is_valid());
}

/// The deformed field's gradient matches central differences away from
/// the region boundaries, and with the bulge on it is continuous
/// across the interpenetration boundary `e_B = 0` (C1 there).
#[test]
fn deformed_gradient_and_c1_join() {
    let (a, b) = blobs();
    let pair = ContactPair::new(&a, &b).with_bulge(Some(Bulge::with_width(0.2)));
    let da = pair.deformed_a();
    let mut rng = Rng::new(3);
    let h = 1e-6;
    let mut tested = 0;
    for _ in 0..3000 {
        let p = Point3::from(rng.vec3(1.0) * 0.7);
        let (ea, eb) = (a.value(&p) - ISO, b.value(&p) - ISO);
        if ea.abs().min(eb.abs()) < 1e-3 || (-eb - 0.1).abs() < 1e-3 || (-eb - 0.2).abs() < 1e-3 {
            continue;
        }
        let (_, g) = da.value_and_gradient(&p);
        for k in 0..3 {
            let mut e = Vec3::zeros();
            e[k] = h;
            let fd = (da.value(&(p + e)) - da.value(&(p - e))) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-6, "{p:?}");
        }
        tested += 1;
    }
    assert!(tested > 2000);
    // Along the x axis from A's centre to B's: find e_B = 0 inside A.
    let line = |x: Real| Point3::new(x, 0.0, 0.0);
    let (mut lo, mut hi) = (-0.5, 0.0);
    assert!(b.value(&line(lo)) < ISO && b.value(&line(hi)) > ISO && a.value(&line(hi)) > ISO);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if b.value(&line(mid)) < ISO {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let eps = 1e-7;
    let (vo, go) = da.value_and_gradient(&line(lo - eps));
    let (vi, gi) = da.value_and_gradient(&line(hi + eps));
    assert!((vo - vi).abs() < 1e-6);
    assert!(
        (go - gi).norm() < 1e-5 * gi.norm().max(1.0),
        "{go:?} {gi:?}"
    );
}

/// Two blobs meeting along x, each symmetric about the planes y = 0 and
/// z = 0: the sampling grid is centred on the common box, so the
/// reaction has no y or z part (to rounding). Anchored at the box's
/// corner, the grid's offset (the box is not a whole number of cells)
/// made one, and a ball hitting a ribbon in its plane pushed it out of it
/// (`scenes/ball_vs_spiral.ron`).
#[test]
fn symmetric_contact_is_sampled_symmetrically() {
    let q = Quat::identity();
    let a = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        0,
        &Point3::new(-0.4, 0.0, 0.0),
        &q,
    )]);
    let b = Field::new(vec![Primitive::point(Vec3::zeros(), 1.13).posed(
        1,
        &Point3::new(0.43, 0.0, 0.0),
        &q,
    )]);
    for h in [0.03, 0.047, 0.061] {
        let params = ImplicitContactParams {
            cell_size: h,
            ..PARAMS
        };
        let r = ContactPair::new(&a, &b).reactions(&params).unwrap();
        let f = r.b().total_force();
        assert!(f.x > 0.0, "B is pushed away from A: {f:?}");
        let off_axis = f.y.hypot(f.z) / f.x;
        assert!(
            off_axis < 1e-9,
            "cell {h}: off-axis force {off_axis:e} of the push"
        );
    }
}

/// A: a wavy row of squares along x (particles 0..24); B: a clump of point
/// blobs (particles 100..) around `centre`.
fn ribbon_and_clump(rng: &mut Rng, centre: Point3) -> (Field, Field) {
    let a = Field::new(
        (0..24)
            .map(|i| {
                let x = 0.5 * i as Real - 6.0;
                let q = Quat::from_scaled_axis(Vec3::new(0.0, 0.3 * (0.4 * x).cos(), 0.0));
                Primitive::square(Vec3::z(), 0.25, 0.4).posed(
                    i,
                    &Point3::new(x, 0.0, 0.4 * (0.4 * x).sin()),
                    &q,
                )
            })
            .collect(),
    );
    let b = Field::new(
        (0..12)
            .map(|i| {
                Primitive::point(Vec3::zeros(), 0.6).posed(
                    100 + i,
                    &(centre + rng.vec3(0.6)),
                    &rng.quat(3.0),
                )
            })
            .collect(),
    );
    (a, b)
}

/// The narrow band tests' skins: two blobs, a rectangle and a point, and
/// six clumps pressed into a long ribbon at random places (seed `seed`).
fn band_cases(seed: u64) -> Vec<(Field, Field)> {
    let mut rng = Rng::new(seed);
    let mut cases = vec![blobs(), rectangle_and_point()];
    for _ in 0..6 {
        let centre = Point3::new(rng.uniform(-5.0, 5.0), rng.uniform(-0.5, 0.5), 0.6);
        cases.push(ribbon_and_clump(&mut rng, centre));
    }
    cases
}

/// The narrow band ([`super::band`]) samples exactly what the scan of
/// every node of the common box samples, bit for bit, and in the same
/// order: two blobs, a rectangle and a point, and a clump pressed into a
/// long ribbon at random places (where the common box is the clump's and
/// most of it is away from the ribbon), at two cell sizes.
#[test]
fn the_band_samples_what_every_node_samples() {
    let cases = band_cases(41);
    let mut compared = 0;
    for (n, (a, b)) in cases.iter().enumerate() {
        let pair = ContactPair::new(a, b);
        for h in [0.04, 0.1] {
            let grid = pair
                .sampling_grid(h, 512)
                .unwrap()
                .expect("overlapping boxes");
            let band = band::crossing_edges(&grid, a, b);
            let dense = band::crossing_edges_dense(&grid, a, b);
            assert!(
                band.iter().all(|e| dense.binary_search(e).is_ok()),
                "case {n}"
            );
            let samples = pair.samples(&grid, &band);
            assert_eq!(samples, pair.samples(&grid, &dense), "case {n}, h {h}");
            eprintln!(
                "case {n}, h {h}: {} nodes, {} crossed edges of {} in the band, {} samples",
                grid.dims.iter().product::<usize>(),
                band.len(),
                dense.len(),
                samples.len()
            );
            compared += samples.len();
        }
    }
    assert!(compared > 100, "{compared} samples compared");
}

/// The contact energy's band ([`band::overlap_edges`]) lists the edges a
/// scan of every node lists: B is splatted only near where A is positive
/// (the same cases as above). Splatted and evaluated values may differ in
/// their last bits, so an edge with an end at the iso value to round-off
/// may be listed by one and not the other.
#[test]
fn the_overlap_band_lists_what_every_node_lists() {
    let cases = band_cases(43);
    let mut compared = 0;
    for (n, (a, b)) in cases.iter().enumerate() {
        let pair = ContactPair::new(a, b);
        for h in [0.04, 0.1] {
            let grid = pair
                .sampling_grid(h, 512)
                .unwrap()
                .expect("overlapping boxes");
            let band = band::overlap_edges(&grid, a, b);
            let dense = band::overlap_edges_dense(&grid, a, b);
            let at_iso = |&(i, k): &(usize, usize)| {
                let p = band::node(&grid, i);
                let mut q = p;
                q[k] += h;
                [a, b]
                    .iter()
                    .any(|f| [p, q].iter().any(|x| (f.value(x) - ISO).abs() < 1e-12))
            };
            let missing: Vec<_> = dense
                .iter()
                .filter(|e| band.binary_search(e).is_err() && !at_iso(e))
                .collect();
            let extra: Vec<_> = band
                .iter()
                .filter(|e| dense.binary_search(e).is_err() && !at_iso(e))
                .collect();
            assert!(
                missing.is_empty() && extra.is_empty(),
                "case {n}, h {h}: missing {missing:?}, extra {extra:?}"
            );
            compared += dense.len();
        }
    }
    assert!(compared > 1000, "{compared} edges compared");
}

/// Plain bisection to round-off (48 halvings, to 2^-49 of the edge): the
/// oracle of [`crossing`].
fn bisected(phi: impl Fn(Real) -> Real) -> Real {
    let (mut t0, mut t1) = (0.0, 1.0);
    let positive0 = phi(0.0) > 0.0;
    for _ in 0..48 {
        let tm = 0.5 * (t0 + t1);
        if (phi(tm) > 0.0) == positive0 {
            t0 = tm;
        } else {
            t1 = tm;
        }
    }
    0.5 * (t0 + t1)
}

/// The Illinois crossing brackets the root of the edge to `1e-12` of its
/// length, where bisection to round-off puts it, in a fraction of the
/// evaluations: on every crossed edge of the contacts of
/// [`the_band_samples_what_every_node_samples`]'s cases, and on steep and
/// flat one-dimensional functions.
#[test]
fn iterations_of_the_crossing() {
    use std::cell::Cell;
    let count = |phi: &dyn Fn(Real) -> Real| {
        let n = Cell::new(0usize);
        let (t0, t1) = crossing(|t| {
            n.set(n.get() + 1);
            phi(t)
        });
        (t0, t1, n.get())
    };
    type Phi = Box<dyn Fn(Real) -> Real>;
    let functions: [(&str, Phi); 4] = [
        ("linear", Box::new(|t| 0.3 - t)),
        (
            "cubic",
            Box::new(|t| (t - 0.71).powi(3) + 0.01 * (t - 0.71)),
        ),
        ("steep", Box::new(|t| (40.0 * (t - 0.2)).tanh())),
        ("flat end", Box::new(|t| (1.0 - t).powi(4) - 0.0001)),
    ];
    for (name, phi) in &functions {
        let (t0, t1, n) = count(phi.as_ref());
        let root = bisected(phi.as_ref());
        eprintln!("{name}: {n} evaluations, bracket {:.1e}", t1 - t0);
        assert!(
            t1 - t0 <= BRACKET && t0 <= root + 4e-15 && root <= t1 + 4e-15,
            "{name}"
        );
        assert!(n <= 25, "{name}: {n} evaluations (bisection: 50)");
    }
    let cases = band_cases(41);
    let (mut edges, mut evaluations, mut most, mut worst) = (0, 0, 0, 0.0 as Real);
    for (a, b) in &cases {
        let pair = ContactPair::new(a, b);
        let grid = pair.sampling_grid(0.04, 512).unwrap().unwrap();
        for (i, k) in band::crossing_edges(&grid, a, b) {
            let p0 = band::node(&grid, i);
            let mut dir = Vec3::zeros();
            dir[k] = grid.h;
            let phi = |t: Real| {
                let p = p0 + dir * t;
                a.value(&p) - b.value(&p)
            };
            let (t0, t1, n) = count(&phi);
            worst = worst.max((0.5 * (t0 + t1) - bisected(phi)).abs());
            edges += 1;
            evaluations += n;
            most = most.max(n);
        }
    }
    let mean = evaluations as Real / edges as Real;
    eprintln!(
        "{edges} crossed edges: {mean:.1} evaluations on average, {most} at most (bisection: 50); \
         farthest from the bisected crossing {worst:.1e} of the edge"
    );
    assert!(worst <= BRACKET, "{worst}");
    assert!(mean <= 12.0, "{mean}");
}

/// A skin whose particle went to a non-finite position (a run that blew
/// up) is an error of the pair, not an index past the sampling grid.
#[test]
fn a_non_finite_skin_is_an_error() {
    let a = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        0,
        &Point3::new(Real::NAN, 0.0, 0.0),
        &Quat::identity(),
    )]);
    let b = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        1,
        &Point3::origin(),
        &Quat::identity(),
    )]);
    let params = ImplicitContactParams::new(100.0, 0.1);
    assert_eq!(
        ContactPair::new(&a, &b).reactions(&params).unwrap_err(),
        PolygonizeError::NonFiniteRegion
    );
    // Not only the first primitive: the box's min and max would drop a
    // later one's NaN.
    let q = Quat::identity();
    let c = Field::new(vec![
        Primitive::point(Vec3::zeros(), 1.0).posed(0, &Point3::new(0.5, 0.0, 0.0), &q),
        Primitive::point(Vec3::zeros(), 1.0).posed(2, &Point3::new(0.0, Real::NAN, 0.0), &q),
    ]);
    assert_eq!(
        ContactPair::new(&b, &c).reactions(&params).unwrap_err(),
        PolygonizeError::NonFiniteRegion
    );
    assert_eq!(
        crate::polygonize(&c, &crate::PolygonizeParams::with_cell_size(0.1)).unwrap_err(),
        PolygonizeError::NonFiniteRegion
    );
    let far = Field::new(vec![Primitive::point(Vec3::zeros(), 1.0).posed(
        0,
        &Point3::new(1e300, 0.0, 0.0),
        &Quat::identity(),
    )]);
    assert_eq!(
        crate::polygonize(&far, &crate::PolygonizeParams::with_cell_size(1e-300)).unwrap_err(),
        PolygonizeError::TooManyNodes {
            needed: usize::MAX,
            max: crate::MAX_NODES_PER_AXIS
        }
    );
}
