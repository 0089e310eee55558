//! A world's state saved and restored (op-dynamics `checkpoint`): a world
//! restored from an encoded state into a world built from the same inputs
//! steps bit for bit as the world the state was taken from, for every
//! integrator (velocity Verlet's carried momenta, the adaptive scheme's
//! first-same-as-last stage and suggestion) and across neighbour-list
//! rebuilds; a state of another world is refused and leaves the world as
//! it was.

use op_dynamics::checkpoint::{decode, encode, encode_state, WorldState};
use op_dynamics::{
    AdaptiveParams, ExternalParams, Material, Particles, Scheme, World, WorldParams,
};
use op_test_support::{full_material, noisy_sheet, spacing_material, Rng};

/// Every particle's state, as bits, by id.
fn bits(w: &World) -> Vec<u64> {
    let p = w.particles();
    let mut out = Vec::new();
    for id in 0..p.id_bound() as u32 {
        let Some(s) = p.slot_of(id) else { continue };
        let (x, v, q, o) = (
            p.positions()[s],
            p.velocities()[s],
            p.orientations()[s],
            p.angular_velocities()[s],
        );
        out.extend(x.iter().chain(&v).chain(&o).map(|c| c.to_bits()));
        out.extend([q.i, q.j, q.k, q.w].map(|c| c.to_bits()));
    }
    out.push(w.time().to_bits());
    out.push(w.steps());
    out
}

fn world(p: &Particles, m: Material, scheme: Scheme) -> World {
    let params = WorldParams {
        scheme,
        dt: 2e-3,
        external: ExternalParams {
            linear_damping: 0.2,
            gravity: [0.0, 0.0, -0.5],
            ..Default::default()
        },
        ..Default::default()
    };
    World::new(p.clone(), &[m], params).expect("the world builds")
}

#[test]
fn a_restored_world_steps_bit_for_bit_as_the_saved_one() {
    let schemes = [
        Scheme::ExplicitEuler,
        Scheme::SymplecticEuler,
        Scheme::VelocityVerlet,
        Scheme::Rk4,
        Scheme::Adaptive(AdaptiveParams::default()),
    ];
    for material in [full_material(true, 1.0), spacing_material()] {
        for scheme in schemes {
            let mut rng = Rng::new(5);
            let p = noisy_sheet(&mut rng, 12, 10, 0.15);
            let mut original = world(&p, material, scheme);
            for _ in 0..40 {
                original.step().unwrap();
            }
            let state = original.state();
            let bytes = encode(&state);
            assert!(
                encode_state(&state).concat() == bytes,
                "{scheme:?}: the state's parts encoded side by side are its encoding"
            );
            assert!(
                original.encode_state().concat() == bytes,
                "{scheme:?}: the world's own parts are the state's encoding"
            );
            let saved: WorldState = decode(&bytes).unwrap();
            let mut restored = world(&p, material, scheme);
            restored.restore(saved).unwrap();
            assert_eq!(bits(&original), bits(&restored), "{scheme:?}: restored");
            for k in 0..120 {
                original.step().unwrap();
                restored.step().unwrap();
                assert!(
                    bits(&original) == bits(&restored),
                    "{scheme:?}: step {k} after the restore differs"
                );
            }
            let rebuilt = original.neighbours().map(|l| l.rebuilds());
            assert_eq!(rebuilt, restored.neighbours().map(|l| l.rebuilds()));
        }
    }
}

#[test]
fn a_state_of_another_world_is_refused() {
    let mut rng = Rng::new(6);
    let p = noisy_sheet(&mut rng, 6, 5, 0.1);
    let mut verlet = world(&p, full_material(true, 1.0), Scheme::VelocityVerlet);
    verlet.step().unwrap();
    let state = verlet.state();
    // Taken with another integrator: refused, the world left as it was.
    let mut rk4 = world(&p, full_material(true, 1.0), Scheme::Rk4);
    let before = bits(&rk4);
    let err = rk4.restore(state.clone()).unwrap_err();
    assert!(err.to_string().contains("another integrator"), "{err}");
    assert_eq!(before, bits(&rk4), "left as it was");
    // An encoding that lost its tail, or has bytes after it, does not
    // decode.
    let bytes = encode(&state);
    assert!(decode::<WorldState>(&bytes[..bytes.len() / 2]).is_err());
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(decode::<WorldState>(&longer).is_err());
    // The state carries its particles: a world of the same materials and
    // parameters takes them whatever it was built with (a scene's
    // checkpoint checks its inputs itself, op-scene `run::checkpoint`).
    let q = noisy_sheet(&mut rng, 4, 4, 0.1);
    let mut other = world(&q, full_material(true, 1.0), Scheme::VelocityVerlet);
    other.restore(state).expect("same materials and parameters");
    assert_eq!(bits(&other), bits(&verlet));
}

/// The adaptive scheme's count of steps forced through at `dt_min` in a
/// row is part of the state: a world restored part way through such a
/// run stops as diverged at the same step as the uninterrupted one, not
/// [`op_dynamics::world::MAX_FORCED_STEPS`] steps after its restore.
#[test]
fn a_restored_world_keeps_its_count_of_forced_steps() {
    let mut rng = Rng::new(7);
    let p = noisy_sheet(&mut rng, 4, 4, 0.1);
    let strict = Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-300));
    let mut original = world(&p, spacing_material(), strict);
    let forced = op_dynamics::world::MAX_FORCED_STEPS / 2;
    for _ in 0..forced {
        original.step().unwrap();
    }
    let saved: WorldState = decode(&encode(&original.state())).unwrap();
    let mut restored = world(&p, spacing_material(), strict);
    restored.restore(saved).unwrap();
    let stop = |w: &mut World| loop {
        if let Err(e) = w.step() {
            assert!(e.to_string().contains("no step meets"), "{e}");
            return e.step;
        }
    };
    let at = stop(&mut original);
    assert!(at > u64::from(forced), "{at}");
    assert_eq!(at, stop(&mut restored));
}
