//! Creation rules (seed 000 §7): stretching fills the gaps of a sheet
//! pulled apart, growing adds a ring around a seed patch and fills holes;
//! the candidates do not depend on thread count or slot order; bad
//! parameters are errors.

use op_dynamics::{Flags, ParticleDesc, Particles, Point3, Real, Vec3, World, WorldParams};
use op_modeling::creation::{self, CreationParams, GrowingParams, StretchingParams};
use op_test_support::{hex_sheet, in_pool, spacing_material, Rng};

fn store(points: &[Point3]) -> Particles {
    let mut p = Particles::new();
    for &q in points {
        p.push(ParticleDesc::at(q)).unwrap();
    }
    p
}

fn stretching() -> CreationParams {
    CreationParams {
        stretching: Some(StretchingParams::default()),
        ..CreationParams::new(1.0)
    }
}

fn growing(g: GrowingParams) -> CreationParams {
    CreationParams {
        growing: Some(g),
        ..CreationParams::new(1.0)
    }
}

fn min_distance(points: &[Point3]) -> Real {
    let mut m = Real::INFINITY;
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            m = m.min((points[i] - points[j]).norm());
        }
    }
    m
}

/// A sheet scaled by 2.2 (every neighbour pair 2.2 r0 apart, in
/// [d_min, d_max]): one particle appears at the midpoint of every edge of
/// the lattice, in the sheet's plane, with its normal; afterwards every
/// spacing is within [d_min / 2, d_min] and a second pass adds nothing.
#[test]
fn a_sheet_pulled_apart_gains_particles_between_far_pairs() {
    let (nx, ny) = (8, 7);
    let points: Vec<Point3> = hex_sheet(nx, ny, 2.2);
    let mut w = World::new(
        store(&points),
        &[spacing_material()],
        WorldParams::default(),
    )
    .unwrap();
    let params = stretching();
    let added = creation::apply(&mut w, &params).unwrap().inserted;
    // Edges of a hexagonal nx x ny patch.
    let edges = (nx - 1) * ny + (2 * nx - 1) * (ny - 1);
    assert_eq!(added, edges);
    let p = w.particles();
    assert_eq!(p.len(), nx * ny + edges);
    for s in 0..p.len() {
        assert!(p.positions()[s].z.abs() < 1e-12);
        assert!((p.normal(s) - Vec3::z()).norm() < 1e-12);
    }
    let all: Vec<Point3> = p.positions().to_vec();
    let dmin = min_distance(&all);
    assert!(dmin >= 1.0 - 1e-12, "closest pair {dmin} below d_min / 2");
    // Every particle now has a neighbour within d_min: no gap is left.
    for (i, a) in all.iter().enumerate() {
        let nearest = all
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, b)| (a - b).norm())
            .fold(Real::INFINITY, Real::min);
        assert!(nearest <= 2.0, "particle {i}: nearest {nearest}");
    }
    assert_eq!(params.candidates(w.particles()).unwrap().len(), 0);
}

/// Pairs closer than d_min or farther than d_max, or whose midpoint ball
/// is occupied, create nothing.
#[test]
fn stretching_respects_its_bounds_and_the_empty_ball() {
    let params = stretching();
    for d in [1.9, 2.6] {
        let p = store(&[Point3::origin(), Point3::new(d, 0.0, 0.0)]);
        assert!(params.candidates(&p).unwrap().is_empty(), "d = {d}");
    }
    let p = store(&[Point3::origin(), Point3::new(2.2, 0.0, 0.0)]);
    let c = params.candidates(&p).unwrap();
    assert_eq!(c.len(), 1);
    assert!((c[0].position - Point3::new(1.1, 0.0, 0.0)).norm() < 1e-12);
    let p = store(&[
        Point3::origin(),
        Point3::new(2.2, 0.0, 0.0),
        Point3::new(1.1, 0.95, 0.0),
    ]);
    assert!(params.candidates(&p).unwrap().is_empty(), "ball occupied");
    // The frame is averaged: two tilted normals give their bisector.
    let mut p = Particles::new();
    let n1 = Vec3::new(0.3, 0.0, 1.0).normalize();
    let n2 = Vec3::new(-0.3, 0.0, 1.0).normalize();
    p.push(ParticleDesc::at(Point3::origin()).with_normal(n1))
        .unwrap();
    p.push(ParticleDesc::at(Point3::new(2.2, 0.0, 0.0)).with_normal(n2))
        .unwrap();
    let c = params.candidates(&p).unwrap();
    assert!((c[0].orientation * c[0].normal_axis - Vec3::z()).norm() < 1e-12);
}

/// Growing a seed patch (a particle and its six neighbours) adds the next
/// hexagonal ring: 12 particles at the lattice sites, in the plane, free
/// even when the seeds are fixed.
#[test]
fn growing_a_seed_patch_adds_a_ring() {
    let mut seed = vec![Point3::origin()];
    for k in 0..6 {
        let a = k as Real * std::f64::consts::FRAC_PI_3;
        seed.push(Point3::new(a.cos(), a.sin(), 0.0));
    }
    let mut p = Particles::new();
    for &q in &seed {
        let mut d = ParticleDesc::at(q);
        d.flags = Flags::FIXED_POSITION.union(Flags::FIXED_ORIENTATION);
        p.push(d).unwrap();
    }
    let c = growing(GrowingParams::default()).candidates(&p).unwrap();
    assert_eq!(c.len(), 12);
    let mut expected: Vec<Point3> = Vec::new();
    for k in 0..6 {
        let a = k as Real * std::f64::consts::FRAC_PI_3;
        expected.push(Point3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0));
        let b = a + std::f64::consts::FRAC_PI_6;
        let r = 3f64.sqrt();
        expected.push(Point3::new(r * b.cos(), r * b.sin(), 0.0));
    }
    for e in &expected {
        assert!(
            c.iter().any(|d| (d.position - e).norm() < 1e-9),
            "no new particle at {e:?}"
        );
    }
    for d in &c {
        assert!(!d.flags.contains(Flags::FIXED_POSITION));
        assert!((d.orientation * d.normal_axis - Vec3::z()).norm() < 1e-12);
    }
    // An isolated particle grows six around it.
    let lone = store(&[Point3::new(3.0, 1.0, 0.0)]);
    let c = growing(GrowingParams::default()).candidates(&lone).unwrap();
    assert_eq!(c.len(), 6);
    assert!(c
        .iter()
        .all(|d| ((d.position - Point3::new(3.0, 1.0, 0.0)).norm() - 1.0).abs() < 1e-12));
}

/// With `max_gap` below the 180° gap of a straight edge, a sheet with a
/// missing interior particle grows exactly one particle in the hole; the
/// only others fill the 120° notches of its zigzag sides, never beyond its
/// straight top and bottom edges.
#[test]
fn growing_fills_a_hole_without_growing_edges() {
    let (nx, ny) = (7, 6);
    let mut points = hex_sheet(nx, ny, 1.0);
    let hole = points.remove(3 * nx + 3);
    let g = GrowingParams {
        max_gap: 170f64.to_radians(),
        ..Default::default()
    };
    let c = growing(g).candidates(&store(&points)).unwrap();
    let in_hole = c
        .iter()
        .filter(|d| (d.position - hole).norm() < 1e-9)
        .count();
    assert_eq!(in_hole, 1);
    let (xmax, ymax) = (nx as Real - 0.5, (ny - 1) as Real * 3f64.sqrt() / 2.0);
    for d in c.iter().filter(|d| (d.position - hole).norm() >= 1e-9) {
        let q = d.position;
        assert!(q.x < 0.0 || q.x > xmax, "not a side notch: {q:?}");
        assert!(
            q.y > -1e-9 && q.y < ymax + 1e-9,
            "grew past a straight edge: {q:?}"
        );
    }
}

/// The same candidates (bits) at 1 and 2 threads and for a shuffled slot
/// order, on a noisy stretched sheet with both rules.
#[test]
fn candidates_do_not_depend_on_threads_or_slot_order() {
    let mut rng = Rng::new(4);
    let points: Vec<Point3> = hex_sheet(12, 10, 2.1)
        .into_iter()
        .map(|q| q + rng.vec3(0.2))
        .collect();
    let mut params = stretching();
    params.growing = Some(GrowingParams {
        radius: 2.6,
        max_neighbours: 5,
        ..Default::default()
    });
    let key = |c: Vec<ParticleDesc>| -> Vec<[u64; 7]> {
        c.iter()
            .map(|d| {
                let q = d.orientation;
                [d.position.x, d.position.y, d.position.z, q.i, q.j, q.k, q.w].map(f64::to_bits)
            })
            .collect()
    };
    let p = store(&points);
    let one = in_pool(1, || key(params.candidates(&p).unwrap()));
    let two = in_pool(2, || key(params.candidates(&p).unwrap()));
    assert!(!one.is_empty());
    assert!(one == two, "thread count changed the candidates");
    let mut shuffled = p.clone();
    let n = shuffled.len() as u32;
    let order: Vec<u32> = (0..n).map(|k| (k * 37) % n).collect();
    shuffled.permute(&order);
    assert!(
        key(params.candidates(&shuffled).unwrap()) == one,
        "slot order changed the candidates"
    );
}

#[test]
fn apply_acts_at_its_interval_and_bad_parameters_are_errors() {
    let points = vec![Point3::origin(), Point3::new(2.2, 0.0, 0.0)];
    let mut w = World::new(
        store(&points),
        &[spacing_material()],
        WorldParams::default(),
    )
    .unwrap();
    let mut params = stretching();
    params.interval = 3;
    w.step().unwrap();
    assert_eq!(creation::apply(&mut w, &params).unwrap().inserted, 0);
    w.step().unwrap();
    w.step().unwrap();
    assert_eq!(creation::apply(&mut w, &params).unwrap().inserted, 1);
    assert_eq!(w.particles().len(), 3);

    let mut bad = stretching();
    bad.stretching = Some(StretchingParams {
        d_max: 1.5,
        ..Default::default()
    });
    let e = creation::apply(&mut w, &bad).unwrap_err().to_string();
    assert!(e.contains("stretching.d_max"), "{e}");
    let mut bad = stretching();
    bad.interval = 0;
    assert!(bad.validate().unwrap_err().to_string().contains("interval"));
    let bad = growing(GrowingParams {
        min_neighbours: 4,
        max_neighbours: 2,
        ..Default::default()
    });
    assert!(bad
        .validate()
        .unwrap_err()
        .to_string()
        .contains("growing.max_neighbours"));
    let bad = growing(GrowingParams {
        clearance: Real::NAN,
        ..Default::default()
    });
    assert!(bad
        .validate()
        .unwrap_err()
        .to_string()
        .contains("clearance"));
    let mut capped = stretching();
    capped.max_particles = 2;
    assert_eq!(capped.candidates(w.particles()).unwrap().len(), 0);
}

/// A candidate is moved off the pair's midpoint along the averaged normal
/// onto its neighbours' mean position; it must then also keep `d_min / 2`
/// from every particle there. Here the midpoint's ball is empty (the third
/// particle is 1.05 from it), but the neighbours' mean lifts the candidate
/// to 0.65 from the third particle: no candidate. Without the third
/// particle the midpoint is taken.
#[test]
fn stretching_checks_the_shifted_candidate_too() {
    let pair = [Point3::new(0.0, 0.0, 0.0), Point3::new(2.2, 0.0, 0.0)];
    let alone = stretching().candidates(&store(&pair)).unwrap();
    assert_eq!(alone.len(), 1);
    assert!((alone[0].position - Point3::new(1.1, 0.0, 0.0)).norm() < 1e-12);
    let crowded = [pair[0], pair[1], Point3::new(1.1, 0.0, 1.05)];
    let found = stretching().candidates(&store(&crowded)).unwrap();
    assert!(
        found.is_empty(),
        "{:?}",
        found.iter().map(|d| d.position).collect::<Vec<_>>()
    );
}

/// Two facing sheets (opposite normals) far enough apart to open a gap do
/// not stretch into each other; the same pair on one sheet (parallel
/// normals) does, and a wider normal-angle limit lets the facing pair
/// stretch too.
#[test]
fn facing_sheets_do_not_stretch_into_each_other() {
    let pair = |n1: Vec3| {
        let mut p = Particles::new();
        p.push(ParticleDesc::at(Point3::origin()).with_normal(Vec3::z()))
            .unwrap();
        p.push(ParticleDesc::at(Point3::new(0.0, 0.0, 2.2)).with_normal(n1))
            .unwrap();
        p
    };
    // Nearly opposite (163 degrees): the averaged normal does not vanish.
    let facing = Vec3::new(0.3, 0.0, -1.0).normalize();
    let rules = stretching();
    assert!(rules.candidates(&pair(facing)).unwrap().is_empty());
    assert!(rules
        .candidates(&pair(Vec3::new(1.0, 0.0, -0.05).normalize()))
        .unwrap()
        .is_empty());
    let side_by_side = {
        let mut p = Particles::new();
        for x in [0.0, 2.2] {
            p.push(ParticleDesc::at(Point3::new(x, 0.0, 0.0))).unwrap();
        }
        p
    };
    assert_eq!(rules.candidates(&side_by_side).unwrap().len(), 1);
    let mut wide = stretching();
    wide.stretching.as_mut().unwrap().max_normal_angle = std::f64::consts::PI;
    assert_eq!(wide.candidates(&pair(facing)).unwrap().len(), 1);
}

fn merging(distance: Real) -> CreationParams {
    CreationParams {
        merging: Some(creation::MergingParams { distance }),
        ..CreationParams::new(1.0)
    }
}

#[test]
fn coincident_particles_of_one_object_merge_into_the_smaller_id() {
    // 0 and 1 nearly coincide; 2 is as close to 0 but another object; 3 is
    // at the merging distance from 1's partner 0 but 0 is taken; 4 is far.
    let mut descs: Vec<ParticleDesc> = [
        (0.0, 0.0, 0.0),
        (0.1, 0.0, 0.0),
        (0.0, 0.1, 0.0),
        (0.0, 0.0, 0.2),
        (3.0, 0.0, 0.0),
    ]
    .iter()
    .map(|&(x, y, z)| ParticleDesc::at(Point3::new(x, y, z)))
    .collect();
    descs[0].velocity = Vec3::new(1.0, 0.0, 0.0);
    descs[1].velocity = Vec3::new(0.0, 1.0, 0.0);
    descs[1].mass = 3.0;
    descs[0].temperature = 4.0;
    descs[2].object = 1;
    let mut p = Particles::new();
    for d in descs {
        p.push(d).unwrap();
    }
    let mut w = World::new(p, &[spacing_material()], WorldParams::default()).unwrap();
    let params = merging(0.3);
    let merges = params.merges(w.particles()).unwrap();
    assert_eq!(merges.len(), 1, "{merges:?}");
    let m = &merges[0];
    assert_eq!((m.survivor, m.removed), (0, 1));
    assert!((m.position - Point3::new(0.075, 0.0, 0.0)).norm() < 1e-12);
    assert!((m.velocity - Vec3::new(0.25, 0.75, 0.0)).norm() < 1e-12);
    assert!((m.temperature - 1.0).abs() < 1e-12);
    let applied = creation::apply(&mut w, &params).unwrap();
    assert_eq!(applied.merged, 1);
    let p = w.particles();
    assert!(p.slot_of(1).is_none());
    assert_eq!(p.len(), 4);
    assert!((p.positions()[p.slot_of(0).unwrap()] - m.position).norm() < 1e-12);
    // Particle 3 is 0.2 from 0's new position (0.075 away along x):
    // the next application merges it.
    assert_eq!(creation::apply(&mut w, &params).unwrap().merged, 1);
    assert!(w.particles().slot_of(3).is_none());
    assert_eq!(creation::apply(&mut w, &params).unwrap().merged, 0);
    assert_eq!(w.particles().len(), 3, "the other object's particle stays");
}

#[test]
fn a_fixed_particle_survives_a_merge_in_place_and_two_fixed_never_merge() {
    let mut descs: Vec<ParticleDesc> = [(0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.1, 0.0)]
        .iter()
        .map(|&(x, y, z)| ParticleDesc::at(Point3::new(x, y, z)))
        .collect();
    descs[1].flags = Flags::FIXED_POSITION;
    descs[2].flags = Flags::FIXED_POSITION;
    let mut p = Particles::new();
    for d in descs {
        p.push(d).unwrap();
    }
    let merges = merging(0.3).merges(&p).unwrap();
    assert_eq!(merges.len(), 1, "{merges:?}");
    assert_eq!((merges[0].survivor, merges[0].removed), (1, 0));
    assert_eq!(merges[0].position, Point3::new(0.1, 0.0, 0.0));
}

#[test]
fn merges_do_not_depend_on_threads_or_slot_order() {
    let mut rng = Rng::new(7);
    let points: Vec<Point3> = (0..400)
        .map(|_| {
            Point3::new(
                rng.uniform(0.0, 6.0),
                rng.uniform(0.0, 6.0),
                rng.uniform(0.0, 1.0),
            )
        })
        .collect();
    let params = merging(0.3);
    let base = in_pool(1, || params.merges(&store(&points)).unwrap());
    assert!(
        base.len() > 10,
        "the random cloud has close pairs: {}",
        base.len()
    );
    assert_eq!(base, in_pool(2, || params.merges(&store(&points)).unwrap()));
    // The same particles (same ids) in reversed slots.
    let mut shuffled = store(&points);
    let order: Vec<u32> = (0..points.len() as u32).rev().collect();
    shuffled.permute(&order);
    assert_eq!(
        base,
        params.merges(&shuffled).unwrap(),
        "slot order changed the merges"
    );
    let bad = merging(1.5);
    assert!(bad
        .validate()
        .unwrap_err()
        .to_string()
        .contains("merging.distance"));
}
