//! World-level checks of the assembled internal forces: they are the
//! gradient of the world's potential energy (finite differences through the
//! whole pipeline: neighbour list, pair kernel, gather), they conserve
//! linear and angular momentum, and they are invariant under rigid motions.

use op_dynamics::{Material, Particles, Point3, Quat, Real, Vec3, World, WorldParams};
use op_test_support::{
    assert_energy_gradients, assert_momentum_conserved, full_material, random_cluster,
    spacing_material, Rng,
};

fn world(p: Particles, m: Material) -> World {
    World::new(p, &[m], WorldParams::default()).unwrap()
}

fn energy(w: &mut World) -> Real {
    w.evaluate_forces().2
}

/// Central differences of the world energy against forces and torques of a
/// few particles, for the full oriented material (isotropic and
/// anisotropic), two objects (repulsion between them) and spacing-only.
#[test]
fn world_forces_and_torques_are_energy_gradients() {
    for (case, material, objects) in [
        ("full isotropic", full_material(false, 0.0), 1),
        ("full anisotropic", full_material(true, 0.0), 1),
        ("full, two objects", full_material(false, 0.0), 2),
        ("spacing only", spacing_material(), 1),
    ] {
        let mut rng = Rng::new(11);
        let p = random_cluster(&mut rng, 40, objects);
        let mut w = world(p, material);
        assert_energy_gradients(&mut w, &[0usize, 7, 19, 33], case);
    }
}

/// Internal forces (with friction, without external actions) conserve
/// linear and angular momentum: sum F = 0 and sum (p x F + tau) = 0.
#[test]
fn internal_forces_conserve_momentum() {
    for (material, objects) in [
        (full_material(false, 0.0), 1),
        (full_material(true, 2.0), 1),
        (full_material(true, 2.0), 3),
        (spacing_material(), 2),
    ] {
        let mut rng = Rng::new(5);
        let p = random_cluster(&mut rng, 125, objects);
        let mut w = world(p, material);
        assert_momentum_conserved(&mut w, "internal forces");
    }
}

/// Translating and rotating the whole system leaves the energy unchanged
/// and rotates forces and torques.
#[test]
fn rigid_motion_invariance() {
    let mut rng = Rng::new(3);
    let p = random_cluster(&mut rng, 64, 1);
    let rot = Quat::from_euler_angles(0.4, -1.2, 2.5);
    let shift = Vec3::new(3.0, -7.0, 11.0);
    let mut moved = p.clone();
    for s in 0..moved.len() {
        let x = rot * moved.positions()[s] + shift;
        let q = rot * moved.orientations()[s];
        moved.set_position(s, x);
        moved.set_orientation(s, q);
    }
    let mut a = world(p, full_material(true, 0.0));
    let mut b = world(moved, full_material(true, 0.0));
    let (fa, ta, ea) = a.evaluate_forces();
    let (fa, ta) = (fa.to_vec(), ta.to_vec());
    let ids_a = a.particles().ids().to_vec();
    let (fb, tb, eb) = b.evaluate_forces();
    let (fb, tb) = (fb.to_vec(), tb.to_vec());
    assert!((ea - eb).abs() <= 1e-10 * ea.abs().max(1.0), "{ea} vs {eb}");
    for (sa, &id) in ids_a.iter().enumerate() {
        let sb = b.particles().slot_of(id).unwrap();
        assert!((rot * fa[sa] - fb[sb]).norm() <= 1e-9 * (1.0 + fa[sa].norm()));
        assert!((rot * ta[sa] - tb[sb]).norm() <= 1e-9 * (1.0 + ta[sa].norm()));
    }
}

/// Object membership and typing (seed 002 §5): pairs of different objects,
/// of different standard types, or of two hinges only repel; a hinge and a
/// standard particle, or two standard particles of one type, interact
/// completely (here: the cohesion well, negative energy at r0).
#[test]
fn typing_decides_complete_or_repulsion() {
    use op_dynamics::ParticleDesc;
    use op_dynamics::ParticleType::{Hinge, Standard};
    let cases = [
        (0, Standard(0), 0, Standard(0), true),
        (0, Standard(1), 0, Standard(1), true),
        (0, Standard(0), 0, Standard(1), false),
        (0, Hinge, 0, Standard(3), true),
        (0, Standard(3), 0, Hinge, true),
        (0, Hinge, 0, Hinge, false),
        (0, Standard(0), 1, Standard(0), false),
        (0, Hinge, 1, Standard(0), false),
    ];
    for (oa, ka, ob, kb, complete) in cases {
        let mut p = Particles::new();
        for (x, o, k) in [(0.0, oa, ka), (1.0, ob, kb)] {
            let mut d = ParticleDesc::at(Point3::new(x, 0.0, 0.0));
            d.object = o;
            d.kind = k;
            p.push(d).unwrap();
        }
        let mut w = world(p, full_material(false, 0.0));
        let e = energy(&mut w);
        if complete {
            assert!(
                e < -0.01,
                "{ka:?}/{oa} with {kb:?}/{ob}: expected the cohesion well, got {e}"
            );
        } else {
            assert!(
                e > 0.01,
                "{ka:?}/{oa} with {kb:?}/{ob}: expected repulsion, got {e}"
            );
        }
    }
}

/// An unoriented particle keeps spacing forces and drops orientation terms:
/// rotating it changes nothing.
#[test]
fn unoriented_particles_have_no_orientation_energy() {
    use op_dynamics::{Flags, ParticleDesc};
    let mut p = Particles::new();
    let mut d = ParticleDesc::at(Point3::origin());
    d.flags = Flags::UNORIENTED;
    p.push(d).unwrap();
    let mut d = ParticleDesc::at(Point3::new(1.1, 0.2, 0.3));
    d.orientation = Quat::from_euler_angles(0.5, 0.2, 0.1);
    p.push(d).unwrap();
    let mut w = world(p, full_material(false, 0.0));
    let e0 = energy(&mut w);
    let (_, t, _) = w.evaluate_forces();
    assert!(t.iter().all(|t| t.norm() == 0.0));
    w.particles_mut()
        .set_orientation(0, Quat::from_euler_angles(1.0, 2.0, 3.0));
    assert_eq!(e0, energy(&mut w));
}
