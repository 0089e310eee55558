//! Engine edge cases pinned at the world level (neighbour
//! radius errors instead of panics, exact angular momentum of velocity
//! Verlet, force windows at the end of a settle phase).

use op_dynamics::interactions::{LennardJonesParams, RepulsionParams, Spacing, WeightParams};
use op_dynamics::{
    AdaptiveParams, ExternalParams, ForceWindow, Material, NeighbourParams, ParticleDesc,
    Particles, Point3, Real, Scheme, Vec3, World, WorldParams,
};
use op_test_support::{full_material, random_cluster, spacing_material, Rng};

fn two_particles(objects: [u32; 2]) -> Particles {
    let mut p = Particles::new();
    for (k, o) in objects.into_iter().enumerate() {
        let mut d = ParticleDesc::at(Point3::new(1.1 * k as Real, 0.0, 0.0));
        d.object = o;
        d.angular_velocity = Vec3::new(0.1, 0.0, 0.2);
        p.push(d).unwrap();
    }
    p
}

fn with_skin(skin: Real) -> WorldParams {
    WorldParams {
        neighbours: NeighbourParams {
            skin,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A cut-off or skin of 1e308 passed validation and panicked inside
/// `NeighbourList::new`; now the skin is bounded by `validate()` and a
/// cut-off whose neighbour radius overflows is a typed error.
#[test]
fn issue_13_huge_cutoff_or_skin_is_an_error_not_a_panic() {
    // The skin alone: refused by validate, saying what is allowed.
    let e = WorldParams::validate(&with_skin(1e308), 2)
        .unwrap_err()
        .to_string();
    assert!(e.contains("neighbours.skin") && e.contains("<= 10"), "{e}");
    let e = World::new(
        two_particles([0, 0]),
        &[Material::default()],
        with_skin(1e308),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("neighbours.skin"), "{e}");

    // Each cut-off at 1e308: fine with the default skin (finite radius
    // 1.2e308, the world steps), an error when the radius overflows.
    let huge = 1e308;
    let materials = [
        (
            "weight",
            Material {
                weight: WeightParams {
                    cutoff: huge,
                    ..Default::default()
                },
                coplanarity: 1.0,
                ..Material::empty()
            },
            [0, 0],
        ),
        (
            "repulsion",
            Material {
                repulsion: RepulsionParams {
                    cutoff: huge,
                    ..Default::default()
                },
                ..Material::empty()
            },
            [0, 1],
        ),
        (
            "lennard-jones",
            Material {
                spacing: Some(Spacing::LennardJones(LennardJonesParams {
                    cutoff: huge,
                    ..Default::default()
                })),
                ..Material::empty()
            },
            [0, 0],
        ),
    ];
    for (name, m, objects) in materials {
        let mut w = World::new(two_particles(objects), &[m], with_skin(0.2)).unwrap();
        assert_eq!(w.neighbours().unwrap().cutoff(), huge, "{name}");
        for _ in 0..3 {
            w.step().unwrap();
        }
        let e = World::new(two_particles(objects), &[m], with_skin(1.0))
            .err()
            .unwrap_or_else(|| panic!("{name}: accepted an infinite neighbour radius"))
            .to_string();
        assert!(
            e.contains("materials[0]") && e.contains("not a finite number"),
            "{name}: {e}"
        );
        // Also when the material is not used by any particle yet (it could
        // be by inserted particles).
        let e = World::new(
            two_particles(objects),
            &[Material::default(), m],
            with_skin(1.0),
        )
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("materials[1]"), "{name}: {e}");
    }
}

/// Total angular momentum `sum(p x m v + R I Rᵀ ω)` of a world.
fn angular_momentum(w: &World) -> (Vec3, Real) {
    let p = w.particles();
    let (mut total, mut scale) = (Vec3::zeros(), 0.0);
    for i in 0..p.len() {
        let m = p.masses()[i];
        let orbital = p.positions()[i].coords.cross(&(m * p.velocities()[i]));
        let q = p.orientations()[i];
        let wb = q.inverse_transform_vector(&p.angular_velocities()[i]);
        let spin = q.transform_vector(&p.inertias()[i].component_mul(&wb));
        total += orbital + spin;
        scale += orbital.norm() + spin.norm();
    }
    (total, scale)
}

/// Velocity Verlet kicks the angular momentum by the torque only and its
/// free rotation keeps it. One free asymmetric body: `L` is carried from
/// step to step and keeps its bits (measured through `R I Rᵀ ω`: a few
/// ulps). Interacting oriented particles without damping or external
/// forces (the pair forces and torques have no net moment): conserved in
/// exact arithmetic; in floating point the round-off of the position and
/// velocity updates accumulates with the number of steps (not with `h`:
/// 1.9e-11, 6.2e-11, 1.0e-10 of `|L0|` after 10k, 20k, 40k steps of 2e-3,
/// 1e-3, 5e-4), 1.8e-12 of `Σ |p × m v| + |R I Rᵀ ω|` after 20,000 steps.
#[test]
fn issue_13_velocity_verlet_conserves_angular_momentum_to_round_off() {
    // One free asymmetric body (the one symplectic Euler blew up).
    let mut p = Particles::new();
    let mut d = ParticleDesc::at(Point3::new(0.3, -0.2, 0.1));
    d.inertia = Vec3::new(0.04, 0.15, 0.3);
    d.angular_velocity = Vec3::new(3.0, 1.0, -2.0);
    p.push(d).unwrap();
    let mut w = World::new(p, &[Material::empty()], WorldParams::default()).unwrap();
    let (l0, _) = angular_momentum(&w);
    let mut worst: Real = 0.0;
    for _ in 0..200_000 {
        w.step().unwrap();
        worst = worst.max((angular_momentum(&w).0 - l0).norm() / l0.norm());
    }
    eprintln!("velocity Verlet, free body, 200k steps: max |L - L0|/|L0| = {worst:.2e}");
    // L itself is carried exactly; this measures it through R I Rᵀ ω, which
    // adds a few ulps (not accumulating).
    assert!(worst < 1e-14, "{worst:e}");

    // Interacting oriented particles (every orientation term, anisotropic
    // weight, no friction), spinning and moving.
    let mut rng = Rng::new(13);
    let p = random_cluster(&mut rng, 27, 1);
    let params = WorldParams {
        dt: 1e-3,
        ..Default::default()
    };
    let mut w = World::new(p, &[full_material(true, 0.0)], params).unwrap();
    let (l0, scale0) = angular_momentum(&w);
    let (mut worst, mut worst_scale): (Real, Real) = (0.0, 0.0);
    for _ in 0..20_000 {
        w.step().unwrap();
        let (l, scale) = angular_momentum(&w);
        worst = worst.max((l - l0).norm() / l0.norm());
        worst_scale = worst_scale.max((l - l0).norm() / scale.max(scale0));
    }
    eprintln!(
        "velocity Verlet, 27 interacting particles, 20k steps: max |L - L0|/|L0| = {worst:.2e} \
         (|L0| = {:.3}, {:.2e} of sum |p x mv| + |I w|)",
        l0.norm(),
        worst_scale
    );
    assert!(worst_scale < 5e-12, "{worst_scale:e}");
    assert!(worst < 2e-10, "{worst:e}");
}

/// A world with a force window starting at `settle` (scene time 0), or
/// without it.
fn settle_world(scheme: Scheme, dt: Real, settle: Real, window: bool) -> World {
    let mut rng = Rng::new(5);
    let p = random_cluster(&mut rng, 8, 1);
    let forces = if window {
        vec![ForceWindow {
            particles: vec![0, 3],
            force: [5.0, -2.0, 1.0],
            start: settle,
            end: Real::INFINITY,
            ramp: 0.0,
        }]
    } else {
        Vec::new()
    };
    let params = WorldParams {
        scheme,
        dt,
        external: ExternalParams {
            linear_damping: 0.3,
            forces,
            ..Default::default()
        },
        ..Default::default()
    };
    World::new(p, &[spacing_material()], params).unwrap()
}

/// Bits of every position and velocity.
fn bits(w: &World) -> Vec<u64> {
    let p = w.particles();
    p.positions()
        .iter()
        .zip(p.velocities())
        .flat_map(|(x, v)| [x.x, x.y, x.z, v.x, v.y, v.z].map(Real::to_bits))
        .collect()
}

/// "Forces of a window starting at 0 already act in the last settle step":
/// the force was evaluated at the end time of that step, where a step load
/// was already on. A window starting at the end of the settle phase must
/// leave the settled state unchanged, bit for bit, and act right after.
#[test]
fn issue_13_window_at_the_end_of_settling_does_not_act_in_it() {
    let schemes = [
        Scheme::VelocityVerlet,
        Scheme::SymplecticEuler,
        Scheme::ExplicitEuler,
        Scheme::Rk4,
        Scheme::Adaptive(AdaptiveParams::with_tolerance(1e-6)),
    ];
    for scheme in schemes {
        for (dt, settle) in [(1e-2, 0.5), (1e-2, 0.37), (3e-3, 1.0 / 3.0), (0.07, 0.7)] {
            let mut with = settle_world(scheme, dt, settle, true);
            let mut without = settle_world(scheme, dt, settle, false);
            with.advance_to(settle).unwrap();
            without.advance_to(settle).unwrap();
            assert_eq!(with.time(), settle);
            assert!(
                bits(&with) == bits(&without),
                "{scheme:?} dt {dt} settle {settle}: the window acted before its start"
            );
            with.step().unwrap();
            without.step().unwrap();
            assert!(
                bits(&with) != bits(&without),
                "{scheme:?} dt {dt} settle {settle}: the window does not act after its start"
            );
        }
    }
}
