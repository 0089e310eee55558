//! Tests of the tools: erasers, shapers, movers.

use super::*;

use op_dynamics::particles::ParticleDesc;

/// An eraser ball sweeping along a row of still particles removes each
/// one when its centre is inside, exactly those, in any thread count;
/// a mover forgets the particles erased from its grip; survivors keep
/// their ids.
#[test]
fn eraser_removes_the_particles_it_passes_over() {
    use op_dynamics::{Material, WorldParams};
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut p = Particles::new();
                for k in 0..10 {
                    p.push(ParticleDesc::at(Point3::new(k as Real, 0.0, 0.0)))
                        .unwrap();
                }
                // Sweeps x from -1 to 4.5 over t in [0, 1]; radius 0.6
                // reaches x <= 5.1 at the end: particles 0..=5.
                let eraser = ToolParams {
                    name: "eraser".into(),
                    shape: ToolShape::Ball { radius: 0.6 },
                    path: ToolPath {
                        keyframes: vec![
                            Keyframe {
                                time: 0.0,
                                position: [-1.0, 0.0, 0.0],
                                rotation: [0.0; 3],
                            },
                            Keyframe {
                                time: 1.0,
                                position: [4.5, 0.0, 0.0],
                                rotation: [0.0; 3],
                            },
                        ],
                    },
                    role: Role::Eraser,
                    objects: None,
                };
                // Holds particles 1 and 8 in place.
                let holder = |x: Real| ToolParams {
                    name: "holder".into(),
                    shape: ToolShape::Ball { radius: 0.1 },
                    path: ToolPath::fixed([x, 0.0, 0.0]),
                    role: Role::Mover {
                        stiffness: 10.0,
                        damping: 0.0,
                        release: Real::INFINITY,
                    },
                    objects: None,
                };
                let params = WorldParams {
                    dt: 0.01,
                    ..WorldParams::default()
                };
                let mut w = Tools::world(
                    p,
                    &[Material::empty()],
                    params,
                    &[eraser, holder(1.0), holder(8.0)],
                )
                .unwrap();
                assert!(w.enabled().contains(&"tool:eraser".to_string()));
                let mut erased = Vec::new();
                let mut count_when_first_erased = None;
                while w.time() < 1.5 {
                    let now = w.step().unwrap().erased.clone();
                    if !now.is_empty() && count_when_first_erased.is_none() {
                        count_when_first_erased = Some(w.time());
                    }
                    erased.extend(now);
                }
                let grabbed: Vec<Vec<u32>> = Tools::of(&w)
                    .unwrap()
                    .tools()
                    .iter()
                    .map(|t| t.grabbed().collect())
                    .collect();
                (
                    erased,
                    w.particles().ids().to_vec(),
                    grabbed,
                    count_when_first_erased,
                )
            })
    };
    let (erased, mut ids, grabbed, first) = run(1);
    assert_eq!(erased, vec![0, 1, 2, 3, 4, 5]);
    ids.sort_unstable();
    assert_eq!(ids, vec![6, 7, 8, 9]);
    // The ball's surface reaches x = 0 at t = 0.4/5.5.
    let first = first.expect("something was erased");
    assert!((first - 0.4 / 5.5).abs() <= 0.011, "{first}");
    assert_eq!(grabbed, vec![vec![], vec![], vec![8]]);
    assert_eq!(run(2), run(1));
}

/// Two shaping balls closing along z on a row of still particles along
/// z (fixed: only the trap rule acts) delete exactly the particles
/// within both margins: those in the gap between them once it is
/// narrower than two margins, none while the gap is wider, none near
/// one ball only; the same ids at 1 and 2 threads. A single shaping
/// tool deletes nothing (a world with one does not even look).
#[test]
fn shapers_delete_the_particles_trapped_between_them() {
    use op_dynamics::{Flags, Material, WorldParams};
    let shaper = |from: Real, to: Real| ToolParams {
        name: "shaper".into(),
        shape: ToolShape::Ball { radius: 1.0 },
        path: ToolPath {
            keyframes: vec![
                Keyframe {
                    time: 0.0,
                    position: [0.0, 0.0, from],
                    rotation: [0.0; 3],
                },
                Keyframe {
                    time: 1.0,
                    position: [0.0, 0.0, to],
                    rotation: [0.0; 3],
                },
            ],
        },
        role: Role::Shaper {
            stiffness: 10.0,
            margin: 0.3,
            damping: 0.0,
        },
        objects: None,
    };
    // Particles at z = -2.0, -1.9, ..., 2.0 (ids 0..=40), held fixed.
    let row = || {
        let mut p = Particles::new();
        for k in 0..=40 {
            let mut d = ParticleDesc::at(Point3::new(0.0, 0.0, -2.0 + 0.1 * k as Real));
            d.flags = Flags::FIXED_POSITION | Flags::FIXED_ORIENTATION;
            p.push(d).unwrap();
        }
        p
    };
    let run = |threads: usize, tools: Vec<ToolParams>| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let params = WorldParams {
                    dt: 0.01,
                    ..WorldParams::default()
                };
                let mut w = Tools::world(row(), &[Material::empty()], params, &tools).unwrap();
                let mut erased = Vec::new();
                let mut first = None;
                while w.time() < 1.0 - 1e-9 {
                    let now = w.step().unwrap().erased.clone();
                    if !now.is_empty() && first.is_none() {
                        first = Some(w.time());
                    }
                    erased.extend(now);
                }
                (erased, first, Tools::of(&w).map_or(0, |t| t.tools().len()))
            })
    };
    // Ball surfaces at z = ±(2.5 - 1.0 - 1.25 t): the gap 2 (1.5 - 1.25
    // t) falls below two margins (0.6) at t = 0.96; at t = 1 the gap is
    // (-0.25, 0.25) and the particles within 0.3 of both surfaces are
    // those with |z| < 0.05.
    let closing = vec![shaper(2.5, 1.25), shaper(-2.5, -1.25)];
    let (erased, first, _) = run(1, closing.clone());
    assert_eq!(erased, vec![20], "only z = 0 lies within both margins");
    let first = first.expect("something was trapped");
    assert!(first >= 0.96 - 1e-9, "trapped too early: t = {first}");
    assert_eq!(
        run(2, closing),
        run(1, vec![shaper(2.5, 1.25), shaper(-2.5, -1.25)])
    );
    // Overlapping: the surfaces reach z = ∓0.25 at t = 1 (inside a
    // ball counts as within its margin), so every particle with
    // |z| < 0.55 is within 0.3 of both, and is deleted on the way.
    let (mut wide, _, _) = run(1, vec![shaper(2.5, 0.75), shaper(-2.5, -0.75)]);
    wide.sort_unstable();
    assert_eq!(wide, (15..=25).collect::<Vec<u32>>());
    // One shaper alone, pushed through the whole row, deletes nothing.
    let (alone, _, _) = run(1, vec![shaper(2.5, -2.5)]);
    assert!(alone.is_empty(), "{alone:?}");
    let one = Tools::new(&[shaper(2.5, -2.5)], &row()).unwrap();
    assert!(!one.removes_particles());
    assert!(Tools::new(&[shaper(2.5, 1.0), shaper(-2.5, -1.0)], &row())
        .unwrap()
        .removes_particles());
}

/// Every shape's output mesh is closed where the shape is, outward
/// oriented (positive signed volume close to the shape's), and posed.
#[test]
fn surface_meshes_are_outward_and_posed() {
    let particles = {
        let mut p = Particles::new();
        p.push(ParticleDesc::at(Point3::new(9.0, 9.0, 9.0)))
            .unwrap();
        p
    };
    let shapes = [
        (
            ToolShape::Ball { radius: 1.0 },
            4.0 / 3.0 * std::f64::consts::PI,
        ),
        (
            ToolShape::Cuboid {
                half_extents: [1.0, 2.0, 0.5],
            },
            8.0,
        ),
        (
            ToolShape::Cylinder {
                half_height: 1.0,
                radius: 0.5,
            },
            std::f64::consts::PI * 0.25 * 2.0,
        ),
    ];
    for (shape, volume) in shapes {
        let tool = Tool::new(
            &ToolParams {
                name: String::new(),
                shape: shape.clone(),
                path: ToolPath::fixed([1.0, 2.0, 3.0]),
                role: Role::Obstacle {
                    stiffness: 1.0,
                    margin: 0.0,
                    damping: 0.0,
                    friction: 0.0,
                },
                objects: None,
            },
            &particles,
        )
        .unwrap();
        let (v, t) = tool.surface_mesh(0.0, 1.0);
        let centre = Vec3::new(1.0, 2.0, 3.0);
        let signed: Real = t
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|k| v[k as usize].coords - centre);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum();
        assert!(
            signed > 0.0 && (signed - volume).abs() < 0.1 * volume,
            "{shape:?}: {signed} vs {volume}"
        );
    }
}
