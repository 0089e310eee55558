//! Heat (seed 000 §6, §8): weakened bonds are still exact energy gradients
//! and conserve momentum, cold material is exactly unweakened, heaters heat
//! only what they reach, conduction spreads heat without losing any, hot
//! bonds let go under a load cold ones carry, knives push like obstacles
//! and heat, stretching can be gated by temperature, and the result does
//! not depend on the thread count.

use op_dynamics::{
    ExternalParams, Flags, ForceWindow, HeatParams, HeatResponse, Material, ParticleDesc,
    Particles, Point3, Real, World, WorldParams,
};
use op_modeling::creation::{CreationParams, StretchingParams};
use op_modeling::tools::{Role, ToolParams, ToolPath, ToolShape, Tools};
use op_test_support::{
    assert_energy_gradients, assert_momentum_conserved, full_material, hex_sheet, in_pool,
    random_cluster, spacing_material, Rng,
};

const RESPONSE: HeatResponse = HeatResponse {
    melting: 10.0,
    residual: 0.2,
    cold_drag: 0.0,
};

fn heated(m: Material) -> Material {
    Material {
        heat: Some(RESPONSE),
        ..m
    }
}

fn heat(conduction: Real, cooling: Real) -> Option<HeatParams> {
    Some(HeatParams {
        conduction,
        cooling,
        ambient: 0.0,
    })
}

fn ball(centre: [Real; 3], radius: Real, role: Role) -> ToolParams {
    ToolParams {
        name: "ball".into(),
        shape: ToolShape::Ball { radius },
        path: ToolPath::fixed(centre),
        role,
        objects: None,
    }
}

fn heater(centre: [Real; 3], radius: Real, power: Real, reach: Real) -> ToolParams {
    ball(centre, radius, Role::Heater { power, reach })
}

/// A random cluster with temperatures spread over the whole response
/// (cold, weakening and molten particles).
fn warm_cluster(objects: u32) -> Particles {
    let mut rng = Rng::new(23);
    let mut p = random_cluster(&mut rng, 40, objects);
    for slot in 0..p.len() {
        p.set_temperature(slot, rng.uniform(-2.0, 14.0));
    }
    p
}

/// Forces and torques of a heated world are the central differences of its
/// energy at fixed temperatures (oriented kernel, two objects, spacing
/// kernel), and the weakening changes the energy.
#[test]
fn weakened_forces_and_torques_are_energy_gradients() {
    for (case, material, objects) in [
        ("full", full_material(true, 0.0), 1),
        ("full, two objects", full_material(false, 0.0), 2),
        ("spacing only", spacing_material(), 1),
    ] {
        let mut cold =
            World::new(warm_cluster(objects), &[material], WorldParams::default()).unwrap();
        let cold_energy = cold.evaluate_forces().2;
        let mut w = World::new(
            warm_cluster(objects),
            &[heated(material)],
            WorldParams::default(),
        )
        .unwrap();
        assert!(w.enabled().contains(&"heat_weakening".to_string()));
        let e = w.evaluate_forces().2;
        assert!(
            (e - cold_energy).abs() > 1e-3 * cold_energy.abs(),
            "{case}: weakening changed nothing ({e} vs {cold_energy})"
        );
        assert_energy_gradients(&mut w, &[0usize, 7, 19, 33], case);
    }
}

/// Weakened internal forces conserve linear and angular momentum.
#[test]
fn weakened_forces_conserve_momentum() {
    for material in [full_material(true, 1.0), spacing_material()] {
        let mut w =
            World::new(warm_cluster(2), &[heated(material)], WorldParams::default()).unwrap();
        assert_momentum_conserved(&mut w, "heated");
    }
}

/// At temperature 0 a material that weakens with heat gives the very same
/// forces, torques and energy as one that does not.
#[test]
fn cold_material_is_exactly_unweakened() {
    let mut rng = Rng::new(3);
    let p = random_cluster(&mut rng, 60, 1);
    let m = full_material(true, 0.0);
    let mut plain = World::new(p.clone(), &[m], WorldParams::default()).unwrap();
    let mut hot = World::new(p, &[heated(m)], WorldParams::default()).unwrap();
    let (f0, t0, e0) = plain.evaluate_forces();
    let (f0, t0) = (f0.to_vec(), t0.to_vec());
    let (f1, t1, e1) = hot.evaluate_forces();
    assert_eq!(e0, e1);
    assert_eq!(f0, f1);
    assert_eq!(t0, t1);
}

/// A fixed hexagonal sheet of spacing-only particles.
fn fixed_sheet(nx: usize, ny: usize, material_heats: bool) -> (Particles, Material) {
    let mut p = Particles::new();
    for x in hex_sheet(nx, ny, 1.0) {
        let mut d = ParticleDesc::at(x);
        d.flags = Flags::FIXED_POSITION | Flags::FIXED_ORIENTATION;
        p.push(d).unwrap();
    }
    let m = if material_heats {
        heated(spacing_material())
    } else {
        spacing_material()
    };
    (p, m)
}

fn temperatures_by_id(w: &World) -> Vec<Real> {
    let p = w.particles();
    (0..p.len() as u32)
        .map(|id| p.temperatures()[p.slot_of(id).unwrap()])
        .collect()
}

/// Without conduction a heater adds exactly `power dt` per step inside it
/// and nothing beyond its reach; with conduction the same heat (cooling
/// off) spreads to particles the heater never reached.
#[test]
fn heaters_heat_what_they_reach_and_conduction_spreads_it() {
    let (power, reach, steps, dt) = (3.0, 0.5, 200, 1e-3);
    let run = |conduction: Real| {
        let (p, m) = fixed_sheet(12, 6, false);
        let params = WorldParams {
            dt,
            heat: heat(conduction, 0.0),
            ..WorldParams::default()
        };
        let mut w = Tools::world(
            p,
            &[m],
            params,
            &[heater([0.0, 0.0, 0.0], 0.6, power, reach)],
        )
        .unwrap();
        assert!(w.enabled().contains(&"tool:heater".to_string()));
        for _ in 0..steps {
            w.step().unwrap();
        }
        (
            temperatures_by_id(&w),
            w.particles().positions().to_vec(),
            w,
        )
    };
    let (insulated, _, w) = run(0.0);
    let positions: Vec<Point3> = (0..insulated.len() as u32)
        .map(|id| w.particles().positions()[w.particles().slot_of(id).unwrap()])
        .collect();
    let expected_total: Real = positions
        .iter()
        .map(|x| {
            let s = x.coords.norm() - 0.6;
            let rate = if s >= reach {
                0.0
            } else {
                power * (1.0 - s.max(0.0) / reach)
            };
            rate * dt * steps as Real
        })
        .sum();
    for (id, (&t, x)) in insulated.iter().zip(&positions).enumerate() {
        let s = x.coords.norm() - 0.6;
        if s <= 0.0 {
            assert!(
                (t - power * dt * steps as Real).abs() < 1e-9,
                "id {id}: {t}"
            );
        }
        if s >= reach {
            assert_eq!(t, 0.0, "id {id} is beyond the reach");
        }
    }
    let total: Real = insulated.iter().sum();
    assert!(total > 0.0 && (total - expected_total).abs() < 1e-9 * total);
    let (conducted, _, _) = run(2.0);
    let total_c: Real = conducted.iter().sum();
    assert!(
        (total_c - total).abs() < 1e-9 * total,
        "conduction lost or made heat: {total} -> {total_c}"
    );
    let reached = |t: &[Real]| {
        positions
            .iter()
            .zip(t)
            .filter(|(x, &t)| x.coords.norm() - 0.6 >= reach && t > 1e-6)
            .count()
    };
    assert_eq!(reached(&insulated), 0);
    assert!(reached(&conducted) > 3, "{conducted:?}");
}

/// Two particles pulled apart by a constant load between the hot and the
/// cold largest attraction force: the cold bond holds, the hot one lets go.
#[test]
fn hot_bonds_let_go_under_a_load_cold_ones_carry() {
    let m = heated(spacing_material());
    let f_max = m.prepare().unwrap().spacing().unwrap().max_attraction().1;
    let load = 0.6 * f_max; // between 0.2 f_max (molten) and f_max.
    let separation = |temperature: Real| {
        let mut p = Particles::new();
        for x in [-0.5, 0.5] {
            let mut d = ParticleDesc::at(Point3::new(x, 0.0, 0.0));
            d.temperature = temperature;
            p.push(d).unwrap();
        }
        let window = |id: u32, sign: Real| ForceWindow {
            particles: vec![id],
            force: [sign * load, 0.0, 0.0],
            start: 0.0,
            end: Real::INFINITY,
            ramp: 0.0,
        };
        let params = WorldParams {
            dt: 2e-3,
            external: ExternalParams {
                linear_damping: 0.5,
                forces: vec![window(0, -1.0), window(1, 1.0)],
                ..ExternalParams::default()
            },
            ..WorldParams::default()
        };
        let mut w = World::new(p, &[m], params).unwrap();
        w.advance_to(20.0).unwrap();
        let x = w.particles().positions();
        (x[1] - x[0]).norm()
    };
    let cold = separation(0.0);
    let hot = separation(20.0);
    assert!(cold < 1.5, "the cold bond broke: {cold}");
    assert!(hot > 3.0, "the hot bond held: {hot}");
}

/// A knife pushes exactly like an obstacle of the same stiffness, margin
/// and damping, and heats the particles it touches.
#[test]
fn knives_push_like_obstacles_and_heat() {
    let points = [
        Point3::new(0.9, 0.0, 0.0),
        Point3::new(0.0, 1.05, 0.1),
        Point3::new(3.0, 0.0, 0.0),
    ];
    let run = |role: Role| {
        let mut p = Particles::new();
        for x in points {
            p.push(ParticleDesc::at(x)).unwrap();
        }
        let params = WorldParams {
            heat: heat(0.0, 0.0),
            ..WorldParams::default()
        };
        let mut w = Tools::world(
            p,
            &[Material::empty()],
            params,
            &[ball([0.0; 3], 1.0, role)],
        )
        .unwrap();
        let f = w.evaluate_forces().0.to_vec();
        w.step().unwrap();
        (f, temperatures_by_id(&w))
    };
    let (f_obstacle, t_obstacle) = run(Role::Obstacle {
        stiffness: 40.0,
        margin: 0.2,
        damping: 0.0,
        friction: 0.0,
    });
    let (f_knife, t_knife) = run(Role::Knife {
        stiffness: 40.0,
        margin: 0.2,
        damping: 0.0,
        power: 5.0,
        reach: 0.3,
    });
    assert_eq!(f_obstacle, f_knife);
    assert!(f_knife[0].norm() > 1.0 && f_knife[1].norm() > 0.1);
    assert_eq!(t_obstacle, vec![0.0; 3]);
    assert!(t_knife[0] > 0.0 && t_knife[1] > 0.0 && t_knife[2] == 0.0);
}

/// Stretching gated by temperature: a pair far enough apart to open a gap
/// does so only when both particles are hot, and the new particle takes
/// their (weighted mean) temperature.
#[test]
fn stretching_can_be_gated_by_temperature() {
    let pair = |t0: Real, t1: Real| {
        let mut p = Particles::new();
        for (x, t) in [(0.0, t0), (2.2, t1)] {
            let mut d = ParticleDesc::at(Point3::new(x, 0.0, 0.0));
            d.temperature = t;
            p.push(d).unwrap();
        }
        p
    };
    let mut rules = CreationParams::new(1.0);
    rules.stretching = Some(StretchingParams {
        min_temperature: Some(5.0),
        ..StretchingParams::default()
    });
    assert!(rules.candidates(&pair(0.0, 0.0)).unwrap().is_empty());
    assert!(rules.candidates(&pair(8.0, 1.0)).unwrap().is_empty());
    let made = rules.candidates(&pair(8.0, 6.0)).unwrap();
    assert_eq!(made.len(), 1);
    assert!(
        (made[0].temperature - 7.0).abs() < 1e-12,
        "{}",
        made[0].temperature
    );
    rules.stretching.as_mut().unwrap().min_temperature = None;
    assert_eq!(rules.candidates(&pair(0.0, 0.0)).unwrap().len(), 1);
}

/// A heater without the world's heat settings is refused with a message
/// that says what to add.
#[test]
fn heaters_need_heat_settings() {
    let params = WorldParams {
        ..WorldParams::default()
    };
    let err = Tools::world(
        Particles::new(),
        &[Material::empty()],
        params,
        &[heater([0.0; 3], 1.0, 1.0, 0.5)],
    )
    .err()
    .expect("refused");
    let msg = err.to_string();
    assert!(msg.contains("tools[0]") && msg.contains("heat"), "{msg}");
}

/// A free, weakening sheet under a moving knife, with conduction and
/// cooling: the same positions and temperatures to the bit on 1 and 2
/// threads.
#[test]
fn heat_is_deterministic_across_thread_counts() {
    let run = || {
        let mut p = Particles::new();
        for x in hex_sheet(14, 8, 1.0) {
            p.push(ParticleDesc::at(x)).unwrap();
        }
        let knife = ToolParams {
            name: "knife".into(),
            shape: ToolShape::Cuboid {
                half_extents: [0.1, 2.0, 2.0],
            },
            path: ToolPath {
                keyframes: vec![
                    op_modeling::Keyframe {
                        time: 0.0,
                        position: [6.5, -3.0, 0.0],
                        rotation: [0.0; 3],
                    },
                    op_modeling::Keyframe {
                        time: 0.3,
                        position: [6.5, 10.0, 0.0],
                        rotation: [0.0; 3],
                    },
                ],
            },
            role: Role::Knife {
                stiffness: 50.0,
                margin: 0.3,
                damping: 0.0,
                power: 40.0,
                reach: 0.5,
            },
            objects: None,
        };
        let params = WorldParams {
            heat: heat(1.0, 0.5),
            ..WorldParams::default()
        };
        let mut w =
            Tools::world(p, &[heated(full_material(false, 0.5))], params, &[knife]).unwrap();
        for _ in 0..300 {
            w.step().unwrap();
        }
        (w.particles().positions().to_vec(), temperatures_by_id(&w))
    };
    let one = in_pool(1, run);
    let two = in_pool(2, run);
    assert!(one.1.iter().any(|&t| t > 1.0), "the knife heated nothing");
    assert_eq!(one, two);
}

/// Velocity Verlet evaluates forces once per step, reusing the ones of the
/// step's end; a weakening material at changing temperatures drops them
/// (they were computed at the old temperatures) and costs a second
/// evaluation per step, while heat without a weakening material does not.
#[test]
fn changing_temperatures_refresh_forces_only_when_materials_weaken() {
    let evaluations_per_step = |material: Material| {
        let mut p = Particles::new();
        for x in hex_sheet(8, 6, 1.0) {
            p.push(ParticleDesc::at(x)).unwrap();
        }
        let params = WorldParams {
            heat: heat(1.0, 0.5),
            ..WorldParams::default()
        };
        let mut w = Tools::world(
            p,
            &[material],
            params,
            &[heater([3.0, 2.0, 0.0], 1.0, 5.0, 1.0)],
        )
        .unwrap();
        w.step().unwrap();
        let before = w.force_evaluations();
        for _ in 0..10 {
            w.step().unwrap();
        }
        (w.force_evaluations() - before) as Real / 10.0
    };
    assert_eq!(evaluations_per_step(spacing_material()), 1.0);
    assert_eq!(evaluations_per_step(heated(spacing_material())), 2.0);
}

/// The cold drag of a heated material: `-c (1 - T / melting) v` on each
/// particle, clamped to none at and above the melting temperature, added
/// to the world's uniform damping; a material without it leaves the forces
/// exactly as they were.
#[test]
fn cold_drag_slows_cold_particles_only() {
    let drag = 40.0;
    let material = |cold_drag: Real| Material {
        heat: Some(HeatResponse {
            cold_drag,
            ..RESPONSE
        }),
        ..spacing_material()
    };
    // Three particles far apart (no pair forces): cold, half molten, molten.
    let build = |cold_drag: Real| {
        let mut p = Particles::new();
        for (k, t) in [0.0, 5.0, 12.0].into_iter().enumerate() {
            let mut d = ParticleDesc::at(Point3::new(10.0 * k as Real, 0.0, 0.0));
            d.velocity = op_dynamics::Vec3::new(1.0, -2.0, 0.5);
            d.temperature = t;
            p.push(d).unwrap();
        }
        let params = WorldParams {
            heat: heat(0.0, 0.0),
            external: ExternalParams {
                linear_damping: 1.5,
                ..Default::default()
            },
            ..Default::default()
        };
        World::new(p, &[material(cold_drag)], params).unwrap()
    };
    let mut with = build(drag);
    let mut without = build(0.0);
    let (f_with, _, _) = with.evaluate_forces();
    let f_with = f_with.to_vec();
    let (f_without, _, _) = without.evaluate_forces();
    let v = op_dynamics::Vec3::new(1.0, -2.0, 0.5);
    for (k, fraction) in [1.0, 0.5, 0.0].into_iter().enumerate() {
        let slot = with.particles().slot_of(k as u32).unwrap();
        let expected = -(1.5 + drag * fraction) * v;
        assert!(
            (f_with[slot] - expected).norm() < 1e-12,
            "particle {k}: {:?} against {expected:?}",
            f_with[slot]
        );
        assert_eq!(f_without[slot], -1.5 * v, "no cold drag: damping only");
    }
    let bad = HeatResponse {
        cold_drag: -1.0,
        ..RESPONSE
    };
    assert!(bad
        .validate()
        .unwrap_err()
        .to_string()
        .contains("cold_drag"));
}
