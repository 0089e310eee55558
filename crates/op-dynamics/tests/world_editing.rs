//! Particle insertion and deletion (`World::insert_particles`,
//! `World::remove_particles`): after an edit, stepping gives the same bits
//! as a world built directly from the edited particle set, at 1 and 2
//! threads; survivors keep their ids; bad ids are rejected.

use op_dynamics::{
    ExternalParams, ForceWindow, Material, ParticleDesc, Particles, Point3, Scheme, Vec3, World,
    WorldParams,
};
use op_test_support::{desc_of, full_material, in_pool, noisy_sheet, spacing_material, Rng};

/// State bits of particle `id`.
fn bits(w: &World, id: u32) -> Vec<u64> {
    let p = w.particles();
    let s = p.slot_of(id).expect("live id");
    let (x, v, q, o) = (
        p.positions()[s],
        p.velocities()[s],
        p.orientations()[s],
        p.angular_velocities()[s],
    );
    [
        x.x, x.y, x.z, v.x, v.y, v.z, q.i, q.j, q.k, q.w, o.x, o.y, o.z,
    ]
    .iter()
    .map(|c| c.to_bits())
    .collect()
}

fn params(scheme: Scheme) -> WorldParams {
    WorldParams {
        scheme,
        dt: 2e-3,
        external: ExternalParams {
            linear_damping: 0.3,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Steps a sheet, removes some particles and inserts others (one on a
/// second object, so the typing repulsion switches on), steps again; a
/// world built from the edited set in the same slot order, stepped as
/// much, has the same bits particle for particle.
fn edited_matches_direct(material: Material, scheme: Scheme) -> (Vec<Vec<u64>>, usize) {
    let mut rng = Rng::new(7);
    let p = noisy_sheet(&mut rng, 10, 9, 0.1);
    let mut a = World::new(p, std::slice::from_ref(&material), params(scheme)).unwrap();
    for _ in 0..20 {
        a.step().unwrap();
    }
    let removed = a.remove_particles(&[3, 40, 41, 40, 77]).unwrap();
    assert_eq!(removed, 4);
    let mut fresh = Vec::new();
    for k in 0..5 {
        let mut d = ParticleDesc::at(Point3::new(1.3 * k as f64 + 0.2, -0.9, 0.05));
        d.velocity = rng.vec3(0.1);
        d.orientation = rng.quat(0.2);
        d.object = (k % 2) as u32;
        fresh.push(d);
    }
    let new_ids = a.insert_particles(&fresh).unwrap();
    assert_eq!(
        new_ids,
        (90..95).collect::<Vec<u32>>(),
        "ids are never reused"
    );
    assert!(a.particles().slot_of(40).is_none());
    // The edited set, in slot order, is the direct world's input.
    let ids_at_edit: Vec<u32> = a.particles().ids().to_vec();
    let mut direct = Particles::new();
    for s in 0..a.particles().len() {
        direct.push(desc_of(a.particles(), s)).unwrap();
    }
    let mut b = World::new(direct, &[material], params(scheme)).unwrap();
    // `Particles::push` normalizes orientations, which is not idempotent in
    // floating point: give the direct world the edited world's exact bits.
    for s in 0..a.particles().len() {
        let q = a.particles().orientations()[s];
        b.particles_mut().set_orientation(s, q);
    }
    // Same configuration (kernel, terms: the second object brings the typing
    // repulsion when the material has one).
    assert_eq!(a.enabled(), b.enabled());
    for _ in 0..30 {
        a.step().unwrap();
        b.step().unwrap();
    }
    let mut out = Vec::new();
    for (k, &id) in ids_at_edit.iter().enumerate() {
        let (x, y) = (bits(&a, id), bits(&b, k as u32));
        assert_eq!(x, y, "particle {id} (direct {k}) differs");
        out.push(x);
    }
    // Oscillation pairs positions of the same particles before and after.
    assert_eq!(
        a.oscillation().to_bits(),
        b.oscillation().to_bits(),
        "oscillation"
    );
    (out, a.particles().len())
}

#[test]
fn insert_and_remove_then_step_matches_a_direct_world_at_1_and_2_threads() {
    for (material, scheme) in [
        (full_material(true, 0.5), Scheme::VelocityVerlet),
        (full_material(false, 0.0), Scheme::Rk4),
        (spacing_material(), Scheme::SymplecticEuler),
    ] {
        let one = in_pool(1, || edited_matches_direct(material, scheme));
        let two = in_pool(2, || edited_matches_direct(material, scheme));
        assert_eq!(one.1, 91);
        assert_eq!(one, two, "thread count changed the result");
    }
}

/// A world of one particle has no kernel; inserting neighbours enables it
/// (and the neighbour list), removing them disables it again.
#[test]
fn kernel_follows_the_particle_set() {
    let mut p = Particles::new();
    p.push(ParticleDesc::at(Point3::origin())).unwrap();
    let mut w = World::new(p, &[spacing_material()], WorldParams::default()).unwrap();
    assert!(w.neighbours().is_none());
    let ids = w
        .insert_particles(&[ParticleDesc::at(Point3::new(0.9, 0.0, 0.0))])
        .unwrap();
    assert_eq!(ids, vec![1]);
    assert!(w.neighbours().is_some());
    w.step().unwrap();
    // Compressed pair (0.9 < r0 = 1): they push apart.
    let p = w.particles();
    let (s0, s1) = (p.slot_of(0).unwrap(), p.slot_of(1).unwrap());
    assert!(p.velocities()[s1].x > 0.0 && p.velocities()[s0].x < 0.0);
    w.remove_particles(&[0]).unwrap();
    assert!(w.neighbours().is_none());
    assert_eq!(w.particles().len(), 1);
    w.step().unwrap();
    assert_eq!(w.particles().ids(), &[1]);
}

#[test]
fn bad_edits_are_rejected_and_change_nothing() {
    let mut rng = Rng::new(3);
    let p = noisy_sheet(&mut rng, 4, 4, 0.05);
    let mut w = World::new(p, &[spacing_material()], WorldParams::default()).unwrap();
    let e = w.remove_particles(&[2, 99]).unwrap_err().to_string();
    assert!(e.contains("99") && e.contains("ids"), "{e}");
    assert_eq!(w.particles().len(), 16);
    w.remove_particles(&[2]).unwrap();
    let e = w.remove_particles(&[2]).unwrap_err().to_string();
    assert!(e.contains("particle id 2"), "{e}");
    let mut bad = ParticleDesc::at(Point3::origin());
    bad.mass = 0.0;
    let e = w
        .insert_particles(&[ParticleDesc::at(Point3::origin()), bad])
        .unwrap_err()
        .to_string();
    assert!(e.contains("particles[1].mass"), "{e}");
    let mut bad = ParticleDesc::at(Point3::origin());
    bad.material = 4;
    let e = w.insert_particles(&[bad]).unwrap_err().to_string();
    assert!(e.contains("particles[0].material"), "{e}");
    assert_eq!(w.particles().len(), 15);
}

/// Force windows and pending external forces on a removed particle are
/// ignored; those on survivors still act.
#[test]
fn external_actions_skip_removed_particles() {
    let mut p = Particles::new();
    for k in 0..3 {
        p.push(ParticleDesc::at(Point3::new(5.0 * k as f64, 0.0, 0.0)))
            .unwrap();
    }
    let params = WorldParams {
        external: ExternalParams {
            forces: vec![ForceWindow {
                particles: vec![0, 1],
                force: [1.0, 0.0, 0.0],
                start: 0.0,
                end: f64::INFINITY,
                ramp: 0.0,
            }],
            ..Default::default()
        },
        ..Default::default()
    };
    let mut w = World::new(p, &[Material::empty()], params).unwrap();
    w.remove_particles(&[0]).unwrap();
    let ids = w
        .insert_particles(&[ParticleDesc::at(Point3::new(20.0, 0.0, 0.0))])
        .unwrap();
    w.add_external_force(ids[0], Vec3::y(), Vec3::zeros());
    w.step().unwrap();
    let p = w.particles();
    assert!(p.velocities()[p.slot_of(1).unwrap()].x > 0.0);
    assert_eq!(p.velocities()[p.slot_of(2).unwrap()], Vec3::zeros());
    assert!(p.velocities()[p.slot_of(3).unwrap()].y > 0.0);
}

/// Empty edits change nothing: no force evaluation is added (velocity
/// Verlet keeps its cached forces) and the particles keep their bits
/// against a world that was never edited.
#[test]
fn empty_edits_keep_the_cached_forces() {
    let mut rng = Rng::new(5);
    let sheet = noisy_sheet(&mut rng, 6, 5, 0.1);
    let build = || {
        World::new(
            sheet.clone(),
            &[spacing_material()],
            params(Scheme::VelocityVerlet),
        )
        .unwrap()
    };
    let (mut edited, mut plain) = (build(), build());
    for w in [&mut edited, &mut plain] {
        w.step().unwrap();
    }
    let before = edited.force_evaluations();
    assert!(edited.insert_particles(&[]).unwrap().is_empty());
    assert_eq!(edited.remove_particles(&[]).unwrap(), 0);
    for w in [&mut edited, &mut plain] {
        w.step().unwrap();
    }
    assert_eq!(
        edited.force_evaluations(),
        before + 1,
        "one evaluation per step"
    );
    assert_eq!(edited.force_evaluations(), plain.force_evaluations());
    for id in 0..sheet.len() as u32 {
        assert_eq!(bits(&edited, id), bits(&plain, id), "particle {id}");
    }
}
