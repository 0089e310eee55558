//! Tools in a world (seed 000 §6): obstacles hold particles up with the
//! penalty's equilibrium depth, forces are the gradient of the tool
//! energies the world reports, movers carry what they grabbed, object
//! selections are honoured, and results do not depend on the thread count.

use op_dynamics::{
    ExternalParams, Material, ParticleDesc, Particles, Point3, Real, Scheme, Vec3, World,
    WorldParams,
};
use op_modeling::tools::{Keyframe, Role, ToolParams, ToolPath, ToolShape, Tools};
use op_test_support::{in_pool, spacing_material};

fn particles(points: &[Point3], object: impl Fn(usize) -> u32) -> Particles {
    let mut p = Particles::new();
    for (k, x) in points.iter().enumerate() {
        let mut d = ParticleDesc::at(*x);
        d.object = object(k);
        p.push(d).unwrap();
    }
    p
}

fn floor(stiffness: Real, damping: Real) -> ToolParams {
    ToolParams {
        name: "floor".into(),
        shape: ToolShape::Plane {
            normal: [0.0, 0.0, 1.0],
        },
        path: ToolPath::default(),
        role: Role::Obstacle {
            stiffness,
            margin: 0.0,
            damping,
            friction: 0.0,
        },
        objects: None,
    }
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

/// A particle dropped on a floor under gravity, with damping, comes to rest
/// where the penalty carries its weight: depth `m g / k`.
#[test]
fn obstacle_carries_weight_at_the_penalty_depth() {
    let (k, g) = (1.0e4, 9.81);
    let params = WorldParams {
        scheme: Scheme::VelocityVerlet,
        dt: 1e-3,
        external: ExternalParams {
            gravity: [0.0, 0.0, -g],
            ..ExternalParams::default()
        },
        ..WorldParams::default()
    };
    let p = particles(&[Point3::new(0.3, -0.2, 0.5)], |_| 0);
    let mut w = Tools::world(p, &[Material::empty()], params, &[floor(k, 20.0)]).unwrap();
    assert!(w.enabled().contains(&"tool:obstacle".to_string()));
    w.advance_to(4.0).unwrap();
    let z = w.particles().positions()[0].z;
    assert!((z + g / k).abs() < 1e-6, "rest height {z}, want {}", -g / k);
    assert!(w.particles().velocities()[0].norm() < 1e-6);
}

/// The world's potential energy includes the tool energies and its forces
/// are their negative gradient (central differences), for an obstacle
/// ball with a margin, an attractor and a moving mover at once, with the
/// particles also interacting.
#[test]
fn tool_forces_are_the_gradient_of_the_tool_energies() {
    let points = [
        Point3::new(0.9, 0.1, 0.0),  // inside the obstacle's margin
        Point3::new(0.2, 2.1, 0.3),  // in the attractor's well, outside
        Point3::new(-0.1, 1.8, 0.2), // inside the attractor
        Point3::new(3.05, 0.0, 0.0), // grabbed by the mover
        Point3::new(5.0, 5.0, 5.0),  // far from everything
    ];
    let tools = gradient_test_tools();
    let params = WorldParams::default();
    let mut w = Tools::world(
        particles(&points, |_| 0),
        &[spacing_material()],
        params,
        &tools,
    )
    .unwrap();
    let grabbed = |w: &World| {
        Tools::of(w).unwrap().tools()[2]
            .grabbed()
            .collect::<Vec<_>>()
    };
    assert_eq!(grabbed(&w), vec![3]);
    // Advance the clock (the mover has moved), then put the particles back
    // where the test wants them.
    w.advance_to(0.37).unwrap();
    for (id, x) in points.iter().enumerate() {
        let slot = w.particles().slot_of(id as u32).unwrap();
        w.particles_mut().set_position(slot, *x);
    }
    let (forces, _, energy) = w.evaluate_forces();
    let forces = forces.to_vec();
    assert!(energy != 0.0);
    let slots: Vec<usize> = (0..points.len() as u32)
        .map(|id| w.particles().slot_of(id).unwrap())
        .collect();
    assert_forces_are_energy_gradient(&mut w, &slots, &forces);
    // Every particle near a tool feels it.
    for &i in &slots[..4] {
        assert!(forces[i].norm() > 1e-3, "slot {i}: {}", forces[i]);
    }
}

/// The tools of [`tool_forces_are_the_gradient_of_the_tool_energies`]: an
/// obstacle ball with a margin at the origin, an attractor at `(0, 2, 0)`
/// and a cuboid mover moving from `(3, 0, 0)`.
fn gradient_test_tools() -> Vec<ToolParams> {
    let mover_path = ToolPath {
        keyframes: vec![
            Keyframe {
                time: 0.0,
                position: [3.0, 0.0, 0.0],
                rotation: [0.0; 3],
            },
            Keyframe {
                time: 1.0,
                position: [4.0, 0.0, 0.5],
                rotation: [0.0, 0.3, 0.0],
            },
        ],
    };
    vec![
        ball(
            [0.0, 0.0, 0.0],
            1.0,
            Role::Obstacle {
                stiffness: 50.0,
                margin: 0.2,
                damping: 0.0,
                friction: 0.0,
            },
        ),
        ball(
            [0.0, 2.0, 0.0],
            0.25,
            Role::Attractor {
                strength: 7.0,
                reach: 0.5,
            },
        ),
        ToolParams {
            name: "hand".into(),
            shape: ToolShape::Cuboid {
                half_extents: [0.2, 0.2, 0.2],
            },
            path: mover_path,
            role: Role::Mover {
                stiffness: 30.0,
                damping: 0.0,
                release: Real::INFINITY,
            },
            objects: None,
        },
    ]
}

/// Asserts that each of the `slots`' `forces` is the negative gradient
/// of the world's potential energy (central differences, step `1e-6`).
fn assert_forces_are_energy_gradient(w: &mut World, slots: &[usize], forces: &[Vec3]) {
    let h = 1e-6;
    for &i in slots {
        for axis in 0..3 {
            let p0 = w.particles().positions()[i];
            let shifted = |w: &mut World, d: Real| {
                let mut p = p0;
                p[axis] += d;
                w.particles_mut().set_position(i, p);
                let e = w.evaluate_forces().2;
                w.particles_mut().set_position(i, p0);
                e
            };
            let fd = -(shifted(w, h) - shifted(w, -h)) / (2.0 * h);
            let f = forces[i][axis];
            assert!(
                (fd - f).abs() <= 1e-5 * (1.0 + f.abs()),
                "particle {i} axis {axis}: fd {fd} vs force {f}"
            );
        }
    }
}

/// A mover carries the particles it held at time 0 along its path and
/// lets them go at `release`; particles outside it stay.
#[test]
fn mover_carries_grabbed_particles() {
    let points = [Point3::new(0.05, 0.0, 0.0), Point3::new(2.0, 0.0, 0.0)];
    let tool = ToolParams {
        name: "hand".into(),
        shape: ToolShape::Ball { radius: 0.5 },
        path: ToolPath {
            keyframes: vec![
                Keyframe {
                    time: 0.0,
                    position: [0.0; 3],
                    rotation: [0.0; 3],
                },
                Keyframe {
                    time: 1.0,
                    position: [0.0, 0.0, 3.0],
                    rotation: [0.0; 3],
                },
            ],
        },
        role: Role::Mover {
            stiffness: 400.0,
            damping: 40.0,
            release: 2.0,
        },
        objects: None,
    };
    let params = WorldParams {
        ..WorldParams::default()
    };
    let mut w = Tools::world(
        particles(&points, |_| 0),
        &[Material::empty()],
        params,
        &[tool],
    )
    .unwrap();
    w.advance_to(1.5).unwrap();
    let p = w.particles().positions();
    assert!(
        (p[0] - Point3::new(0.05, 0.0, 3.0)).norm() < 1e-2,
        "{:?}",
        p[0]
    );
    assert_eq!(p[1], Point3::new(2.0, 0.0, 0.0));
    w.advance_to(2.5).unwrap();
    let v = w.particles().velocities()[0];
    w.advance_to(3.0).unwrap();
    // Released: no force, so it drifts at constant velocity.
    assert!((w.particles().velocities()[0] - v).norm() < 1e-12);
}

/// A tool restricted to object 1 leaves object 0 alone.
#[test]
fn tools_act_only_on_their_objects() {
    let points = [Point3::new(0.0, 0.0, -0.1), Point3::new(3.0, 0.0, -0.1)];
    let mut tool = floor(100.0, 0.0);
    tool.objects = Some(vec![1]);
    let params = WorldParams {
        ..WorldParams::default()
    };
    let mut w = Tools::world(
        particles(&points, |k| k as u32),
        &[Material::empty()],
        params,
        &[tool],
    )
    .unwrap();
    let f = w.evaluate_forces().0.to_vec();
    assert_eq!(f[0], Vec3::zeros());
    assert!((f[1] - Vec3::new(0.0, 0.0, 10.0)).norm() < 1e-12);
}

/// A sheet dropped on a moving cylinder gives the same bits on one and two
/// threads.
#[test]
fn tools_are_deterministic_across_thread_counts() {
    let mut points = Vec::new();
    for i in 0..12 {
        for j in 0..12 {
            points.push(Point3::new(
                i as Real + 0.5 * j as Real - 5.0,
                j as Real * 0.866 - 5.0,
                1.2,
            ));
        }
    }
    let cylinder = ToolParams {
        name: "roller".into(),
        shape: ToolShape::Cylinder {
            half_height: 8.0,
            radius: 1.0,
        },
        path: ToolPath {
            keyframes: vec![
                Keyframe {
                    time: 0.0,
                    position: [0.0; 3],
                    rotation: [0.0, 0.0, std::f64::consts::FRAC_PI_2],
                },
                Keyframe {
                    time: 1.0,
                    position: [1.0, 0.0, 0.0],
                    rotation: [0.0, 0.0, std::f64::consts::FRAC_PI_2],
                },
            ],
        },
        role: Role::Obstacle {
            stiffness: 500.0,
            margin: 0.1,
            damping: 1.0,
            friction: 0.0,
        },
        objects: None,
    };
    let run = |threads| {
        in_pool(threads, || {
            let params = WorldParams {
                dt: 2e-3,
                external: ExternalParams {
                    gravity: [0.0, 0.0, -9.81],
                    ..ExternalParams::default()
                },
                ..WorldParams::default()
            };
            let mut w = Tools::world(
                particles(&points, |_| 0),
                &[spacing_material()],
                params,
                &[cylinder.clone(), floor(500.0, 1.0)],
            )
            .unwrap();
            w.advance_to(0.6).unwrap();
            w.particles()
                .positions()
                .iter()
                .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
                .collect::<Vec<u64>>()
        })
    };
    assert_eq!(run(1), run(2));
}

/// A contributor passed for an interval acts over every step of it, also
/// when the adaptive scheme takes several, and not after it; a pending
/// force (`add_external_force`) acts over one step only.
#[test]
fn interval_contributors_act_over_the_whole_interval() {
    let params = WorldParams {
        scheme: Scheme::Adaptive(op_dynamics::AdaptiveParams::default()),
        dt: 0.05,
        ..WorldParams::default()
    };
    let p = particles(&[Point3::origin()], |_| 0);
    let mut w = World::new(p, &[Material::empty()], params).unwrap();
    let mut held = op_dynamics::external::ExternalAccumulator::new(1);
    held.add(0, Vec3::new(2.0, 0.0, 0.0), Vec3::zeros());
    w.advance_to_with(1.0, &[&held], &mut []).unwrap();
    assert!(w.steps() >= 20);
    let v = w.particles().velocities()[0];
    assert!((v - Vec3::new(2.0, 0.0, 0.0)).norm() < 1e-12, "{v}");
    w.advance_to(2.0).unwrap();
    assert_eq!(w.particles().velocities()[0], v);
    // One step of a pending force: dv = F dt / m.
    let steps = w.steps();
    w.add_external_force(0, Vec3::new(0.0, 1.0, 0.0), Vec3::zeros());
    w.advance_to(3.0).unwrap();
    assert!(w.steps() > steps + 1);
    let dv = w.particles().velocities()[0] - v;
    assert!(
        dv.x.abs() < 1e-12 && dv.y > 0.0 && dv.y <= 0.05 + 1e-12,
        "{dv}"
    );
}

/// Obstacle damping slows a separating particle's push but never pulls it
/// back: the normal force stays >= 0.
#[test]
fn obstacle_damping_never_pulls() {
    let params = WorldParams {
        ..WorldParams::default()
    };
    let mut p = Particles::new();
    let mut d = ParticleDesc::at(Point3::new(0.0, 0.0, -0.01));
    d.velocity = Vec3::new(0.0, 0.0, 10.0);
    p.push(d).unwrap();
    let mut w = Tools::world(p, &[Material::empty()], params, &[floor(100.0, 100.0)]).unwrap();
    assert_eq!(w.evaluate_forces().0[0], Vec3::zeros());
    // Approaching, the damping adds to the penalty push.
    w.particles_mut().set_velocity(0, Vec3::new(0.0, 0.0, -0.1));
    let f = w.evaluate_forces().0[0];
    assert!((f.z - (100.0 * 0.01 + 100.0 * 0.1)).abs() < 1e-12, "{f}");
}
