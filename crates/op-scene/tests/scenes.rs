//! Scene files end to end: every example scene loads, validates, builds and
//! steps; generators make what they promise; overrides, selections and
//! force windows land on the right particles; RON and JSON give the same
//! world; and every scene of the bad-scene corpus (`tests/bad_scenes/`)
//! fails with the right error.

use std::path::Path;

use op_dynamics::diagnostics::rest_shape_rms;
use op_dynamics::{Flags, ParticleType, Point3, Real, Vec3, World};
use op_scene::{load_scene, parse_scene, BuiltScene, Format, Scene};
use op_test_support::{scene_files, scenes_dir};

fn build(path: &Path) -> BuiltScene {
    let scene = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    scene
        .build(path.parent(), Some(path.to_path_buf()))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A scene from RON text, validated and built without a directory.
fn build_ron(text: &str) -> BuiltScene {
    let scene = parse_scene(text, Format::Ron, "<test>").unwrap_or_else(|e| panic!("{e}"));
    scene.build(None, None).unwrap_or_else(|e| panic!("{e}"))
}

/// Positions of `ids`, in that order.
fn positions_of(world: &World, ids: &[u32]) -> Vec<Point3> {
    let p = world.particles();
    ids.iter()
        .map(|&id| p.positions()[p.slot_of(id).unwrap()])
        .collect()
}

#[test]
fn every_example_scene_loads_builds_and_steps() {
    let files = scene_files();
    let names: Vec<String> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for expected in [
        "sheet.ron",
        "chain.json",
        "sphere_shell.ron",
        "torus_shell.ron",
        "two_sheets.ron",
        "hinge_spiral.ron",
        "points.ron",
        "spiral.ron",
        "spiral_8.ron",
        "spiral_13.ron",
        "spiral_x10.ron",
        "colliding_objects.ron",
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "missing scenes/{expected}"
        );
    }
    for path in &files {
        let mut built = build(path);
        let n = built.world().particles().len();
        assert!(n > 0 && n <= 2000, "{}: {n} particles", path.display());
        assert!(!built.objects().is_empty());
        for o in built.objects() {
            assert_eq!(o.ids.len(), o.rest.len());
            assert!(o.rest_spacing > 0.0 && o.rest_spacing.is_finite());
        }
        assert!(built.duration() > 0.0 && built.frame_rate() > 0.0);
        for _ in 0..5 {
            built
                .world_mut()
                .step()
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
        assert_eq!(built.world().steps(), 5);
    }
}

#[test]
fn the_demo_scene_matches_its_description() {
    // The spiral that uncoils and recovers (seed 002 fig. 5), embedded in
    // `opsim` as the default demo.
    let built = build(&scenes_dir().join("spiral.ron"));
    assert_eq!(built.name(), "spiral");
    assert_eq!(built.world().params().dt, 5e-3);
    assert_eq!((built.settle_duration(), built.duration()), (40.0, 80.0));
    assert_eq!(built.world().params().external.linear_damping, 0.3);
    assert_eq!(built.world().params().external.angular_damping, 0.05);
    assert_eq!(built.world().particles().len(), 10);
    let enabled = built.world().enabled();
    for term in [
        "term:cohesion",
        "term:form",
        "term:coplanarity",
        "friction",
        "damping",
        "force_windows",
    ] {
        assert!(enabled.iter().any(|e| e == term), "{enabled:?}");
    }
    let forces = &built.world().params().external.forces;
    assert_eq!(forces.len(), 2);
    assert_eq!(
        (forces[0].start, forces[0].end, forces[0].ramp),
        (40.0, 80.0, 10.0)
    );
}

/// Runs every example scene to its end (release: `cargo test --release -p
/// op-scene --test scenes -- --ignored --nocapture`) and prints the rest
/// shape error per object.
#[test]
#[ignore = "runs every scene to its end; slow in debug"]
fn every_example_scene_runs_to_the_end() {
    for path in scene_files() {
        let mut built = build(&path);
        let clock = std::time::Instant::now();
        built
            .settle()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let t0 = built.world().time();
        let frames = (built.duration() * built.frame_rate()).round() as usize;
        let mut worst = vec![0.0f64; built.objects().len()];
        for k in 1..=frames {
            let t = t0 + built.duration() * k as Real / frames as Real;
            built
                .world_mut()
                .advance_to(t)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for (o, w) in built.objects().iter().zip(&mut worst) {
                let err =
                    rest_shape_rms(&o.rest, &positions_of(built.world(), &o.ids)) / o.rest_spacing;
                *w = w.max(err);
            }
        }
        let d = built.world_mut().diagnostics();
        print!(
            "{}: {} particles, {} steps, {:.1} s, kinetic {:.2e}, potential {:.3e};",
            path.display(),
            built.world().particles().len(),
            built.world().steps(),
            clock.elapsed().as_secs_f64(),
            d.kinetic_translational + d.kinetic_rotational,
            d.potential
        );
        for (o, w) in built.objects().iter().zip(&worst) {
            let err =
                rest_shape_rms(&o.rest, &positions_of(built.world(), &o.ids)) / o.rest_spacing;
            print!(" {}: rest error final {err:.3} max {w:.3};", o.name);
        }
        println!();
    }
}

#[test]
fn overrides_and_selections_apply() {
    let built = build_ron(
        r#"(
        name: "o",
        materials: {"m": (spacing: LennardJones((cutoff: 1.5)))},
        objects: [
            (name: "a", material: "m", generator: Chain(count: 3, spacing: 1)),
            (name: "b", material: "m", generator: Chain(count: 10, spacing: 1, start: (0, 5, 0)),
             mass: 2, kind: Standard(3),
             overrides: [
                (particles: First(2), fixed_position: true, fixed_orientation: true),
                (particles: Range(4, 6), kind: Hinge, curvature: 0.5),
                (particles: List([9, 7]), unoriented: true, mass: 5),
                (particles: Last(1), unoriented: false),
                (particles: All, fixed_orientation: false),
             ]),
        ],
    )"#,
    );
    let p = built.world().particles();
    let at = |id: u32| p.slot_of(id).unwrap();
    assert_eq!(built.objects()[1].ids, (3..13).collect::<Vec<u32>>());
    for local in 0..10u32 {
        let s = at(3 + local);
        let i = local as usize;
        assert_eq!(p.objects()[s], 1);
        assert_eq!(p.flags()[s].contains(Flags::FIXED_POSITION), i < 2, "{i}");
        assert!(!p.flags()[s].contains(Flags::FIXED_ORIENTATION), "{i}");
        assert_eq!(p.flags()[s].contains(Flags::UNORIENTED), i == 7, "{i}");
        let kind = if (4..6).contains(&i) {
            ParticleType::Hinge
        } else {
            ParticleType::Standard(3)
        };
        assert_eq!(p.kinds()[s], kind, "{i}");
        assert_eq!(
            p.curvatures()[s],
            if (4..6).contains(&i) { 0.5 } else { 0.0 }
        );
        assert_eq!(
            p.masses()[s],
            if i == 7 || i == 9 { 5.0 } else { 2.0 },
            "{i}"
        );
    }
    for local in 0..3 {
        let s = at(local);
        assert_eq!(p.objects()[s], 0);
        assert_eq!(p.flags()[s], Flags::empty());
        assert_eq!(p.kinds()[s], ParticleType::Standard(0));
        assert_eq!(p.masses()[s], 1.0);
    }
}

/// Per-particle initial velocities: drawn at a temperature
/// (net momentum removed, kinetic temperature exact, added to the uniform
/// `velocity`, deterministic) or read from a points file (one per particle,
/// the count checked).
#[test]
fn initial_velocities_from_a_temperature_or_a_file() {
    let text = |velocities: &str| {
        format!(
            r#"(
            name: "v",
            materials: {{"m": (spacing: LennardJones((cutoff: 1.5)))}},
            objects: [(name: "a", material: "m", generator: Chain(count: 40, spacing: 1),
                       mass: 2, velocity: (1, 0, 0), velocities: Some({velocities}))],
        )"#
        )
    };
    let velocities = |b: &BuiltScene| -> Vec<Vec3> {
        let p = b.world().particles();
        (0..40u32)
            .map(|id| p.velocities()[p.slot_of(id).unwrap()])
            .collect()
    };
    let hot = velocities(&build_ron(&text("Temperature(t: 1.44, seed: 87287)")));
    let mean = hot.iter().fold(Vec3::zeros(), |s, v| s + v) / 40.0;
    assert!((mean - Vec3::x()).norm() < 1e-12, "{mean}");
    let t: Real = hot
        .iter()
        .map(|v| 2.0 * (v - mean).norm_squared())
        .sum::<Real>()
        / 117.0;
    assert!((t - 1.44).abs() < 1e-12, "{t}");
    assert_eq!(
        hot,
        velocities(&build_ron(&text("Temperature(t: 1.44, seed: 87287)")))
    );
    assert_ne!(
        hot,
        velocities(&build_ron(&text("Temperature(t: 1.44, seed: 1)")))
    );

    let dir = std::env::temp_dir().join(format!("op-scene-velocities-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lines: String = (0..40).map(|k| format!("{k} 0.5 -{k}\n")).collect();
    std::fs::write(dir.join("v.xyz"), lines).unwrap();
    let scene = dir.join("s.ron");
    std::fs::write(&scene, text(r#"File("v.xyz")"#)).unwrap();
    let from_file = velocities(&build(&scene));
    for (k, v) in from_file.iter().enumerate() {
        assert_eq!(*v, Vec3::new(k as Real + 1.0, 0.5, -(k as Real)));
    }
    std::fs::write(dir.join("v.xyz"), "1 2 3\n").unwrap();
    let err = load_scene(&scene).unwrap_err().to_string();
    assert!(
        err.contains("velocities.File") && err.contains("40 particles"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn particles_are_oriented_from_their_normal_axis() {
    let built = build_ron(
        r#"(name: "n", materials: {"m": ()}, objects: [
            (name: "s", material: "m", normal_axis: (1, 0, 0),
             generator: SphereShell(radius: 2, spacing: 1)),
        ])"#,
    );
    let p = built.world().particles();
    for s in 0..p.len() {
        assert_eq!(p.normal_axes()[s], Vec3::x());
        let n = p.normal(s);
        let outward = p.positions()[s].coords.normalize();
        assert!((n - outward).norm() < 1e-9);
    }
}

#[test]
fn force_windows_map_to_global_ids() {
    let built = build_ron(
        r#"(
        name: "f",
        materials: {"m": ()},
        objects: [
            (name: "a", material: "m", generator: Chain(count: 4, spacing: 1)),
            (name: "b", material: "m", generator: Chain(count: 6, spacing: 1, start: (0, 3, 0))),
        ],
        forces: [
            (object: "b", particles: Range(1, 3), force: (1, 0, 0), start: 0.5, end: 2, ramp: 0.25),
            (object: "a", particles: Last(1), force: (0, 0, -1)),
            (object: "b", force: (0, 1, 0)),
            (object: "a", particles: List([2, 0, 2]), force: (0, 1, 0)),
        ],
    )"#,
    );
    let forces = &built.world().params().external.forces;
    assert_eq!(forces.len(), 4);
    assert_eq!(forces[0].particles, vec![5, 6]);
    assert_eq!(
        (forces[0].start, forces[0].end, forces[0].ramp),
        (0.5, 2.0, 0.25)
    );
    assert_eq!(forces[0].force, [1.0, 0.0, 0.0]);
    assert_eq!(forces[1].particles, vec![3]);
    assert_eq!(forces[1].end, Real::INFINITY);
    assert_eq!(forces[2].particles, (4..10).collect::<Vec<u32>>());
    assert_eq!(forces[3].particles, vec![0, 2], "sorted, each once");
}

/// A settle phase runs before frame 0: force windows count from its end,
/// the rest shape is the settled one, reported times start at 0.
#[test]
fn settle_phase_shifts_forces_and_sets_the_rest_shape() {
    let text = |settle: &str| {
        format!(
            r#"(
            name: "settle",
            world: (dt: 0.01, duration: 1, frame_rate: 4, settle: {settle}, linear_damping: 0.5),
            materials: {{"m": (spacing: Cohesion((cutoff: 1.5)), form: 2, weight: (cutoff: 1.5))}},
            objects: [(name: "s", material: "m",
                generator: Spiral(count: 6, spacing: 1, curvature_start: 0.3, curvature_end: 0.9))],
            forces: [(object: "s", particles: First(1), force: (0.1, 0, 0), start: 0.25, end: 0.75, ramp: 0.25)],
        )"#
        )
    };
    let plain = build_ron(&text("0"));
    assert!(plain.is_settled());
    let mut built = build_ron(&text("2.5"));
    assert!(!built.is_settled());
    let w = &built.world().params().external.forces[0];
    assert_eq!((w.start, w.end, w.ramp), (2.75, 3.25, 0.25));
    let generated = built.objects()[0].rest.clone();
    assert_eq!(generated, plain.objects()[0].rest, "build does not settle");
    built.settle().unwrap();
    assert!(built.is_settled());
    assert_eq!(built.world().time(), 2.5);
    assert_eq!(built.scene_time(), 0.0);
    let settled = positions_of(built.world(), &built.objects()[0].ids);
    assert_eq!(
        built.objects()[0].rest,
        settled,
        "the settled shape is the reference"
    );
    let moved = rest_shape_rms(&generated, &settled);
    assert!(
        moved > 1e-6,
        "the analytic spiral is not exactly at rest: {moved}"
    );
    // Mean nearest-neighbour distance, by brute force.
    let mean = |p: &[Point3]| {
        let nearest = |i: usize| {
            (0..p.len())
                .filter(|&j| j != i)
                .map(|j| (p[j] - p[i]).norm())
                .fold(Real::INFINITY, Real::min)
        };
        (0..p.len()).map(nearest).sum::<Real>() / p.len() as Real
    };
    assert!((built.objects()[0].rest_spacing - mean(&settled)).abs() < 1e-12);
    built.settle().unwrap();
    assert_eq!(built.world().time(), 2.5, "settles once");
    // The runner settles, then reports scene time.
    let dir = std::env::temp_dir().join(format!("op-scene-settle-{}", std::process::id()));
    let mut again = build_ron(&text("2.5"));
    let summary = op_scene::run(
        &mut again,
        &op_scene::RunOptions {
            out_dir: dir.clone(),
            frames: None,
            formats: vec![op_scene::export::FrameFormat::OBJ],
            ..Default::default()
        },
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(summary.settle, 2.5);
    assert!(
        (summary.sim_time - 1.0).abs() < 1e-12,
        "{}",
        summary.sim_time
    );
    assert_eq!(summary.frames, 5);
    let metrics = std::fs::read_to_string(dir.join("metrics.csv")).unwrap();
    let first: Vec<&str> = metrics.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(first[1].parse::<Real>().unwrap(), 0.0);
    assert!(summary.objects[0].rest_shape_error_max > 0.0);
    let _ = std::fs::remove_dir_all(dir);
}

/// A step load starting at scene time 0 (world time `settle`) does not
/// act in the last settle step: it leaves the settled state unchanged,
/// bit for bit, whatever the scheme, and acts in the first step after it.
#[test]
fn window_starting_at_scene_time_zero_does_not_act_in_the_settle_phase() {
    let text = |scheme: &str, settle: &str, forces: &str| {
        format!(
            r#"(
            name: "settle-window",
            world: (dt: 0.01, integrator: {scheme}, duration: 1, frame_rate: 4, settle: {settle}),
            materials: {{"m": (spacing: Cohesion((cutoff: 1.5)), form: 2, weight: (cutoff: 1.5))}},
            objects: [(name: "s", material: "m",
                generator: Spiral(count: 6, spacing: 1, curvature_start: 0.3, curvature_end: 0.9))],
            forces: [{forces}],
        )"#
        )
    };
    let window = r#"(object: "s", particles: First(2), force: (3, -1, 0.5), start: 0)"#;
    let state = |b: &BuiltScene| {
        let p = b.world().particles();
        let ids = &b.objects()[0].ids;
        let v: Vec<Vec3> = ids
            .iter()
            .map(|&id| p.velocities()[p.slot_of(id).unwrap()])
            .collect();
        (positions_of(b.world(), ids), v)
    };
    for scheme in ["VelocityVerlet", "SymplecticEuler", "Rk4"] {
        for settle in ["0.5", "0.37", "0.123"] {
            let mut with = build_ron(&text(scheme, settle, window));
            let mut without = build_ron(&text(scheme, settle, ""));
            with.settle().unwrap();
            without.settle().unwrap();
            assert!(
                state(&with) == state(&without),
                "{scheme}, settle {settle}: the window acted before scene time 0"
            );
            with.world_mut().step().unwrap();
            without.world_mut().step().unwrap();
            assert!(
                state(&with) != state(&without),
                "{scheme}, settle {settle}: the window does not act after scene time 0"
            );
        }
    }
}

#[test]
fn only_used_materials_enter_the_world() {
    let built = build_ron(
        r#"(
        name: "m",
        materials: {
            "a_unused": (spacing: LennardJones(()), coplanarity: 3),
            "b_used": (spacing: Cohesion((cutoff: 1.5))),
            "c_unused": (form: 1),
        },
        objects: [(name: "x", material: "b_used", generator: Chain(count: 3, spacing: 1))],
    )"#,
    );
    assert_eq!(built.world().materials().len(), 1);
    assert_eq!(built.world().particles().materials(), &[0, 0, 0]);
    let enabled = built.world().enabled();
    assert!(
        enabled.contains(&"term:cohesion".to_string()),
        "{enabled:?}"
    );
    assert!(!enabled
        .iter()
        .any(|e| e.contains("coplanarity") || e.contains("form")));
}

/// Every observable of two worlds.
fn assert_same_world(a: &World, b: &World) {
    assert_eq!(a.params(), b.params());
    assert_eq!(a.materials(), b.materials());
    assert_eq!(a.kernel(), b.kernel());
    assert_eq!(a.enabled(), b.enabled());
    let (p, q) = (a.particles(), b.particles());
    assert_eq!(p.ids(), q.ids());
    assert_eq!(p.positions(), q.positions());
    assert_eq!(p.velocities(), q.velocities());
    assert_eq!(p.orientations(), q.orientations());
    assert_eq!(p.angular_velocities(), q.angular_velocities());
    assert_eq!(p.masses(), q.masses());
    assert_eq!(p.inertias(), q.inertias());
    assert_eq!(p.normal_axes(), q.normal_axes());
    assert_eq!(p.flags(), q.flags());
    assert_eq!(p.objects(), q.objects());
    assert_eq!(p.kinds(), q.kinds());
    assert_eq!(p.materials(), q.materials());
    assert_eq!(p.curvatures(), q.curvatures());
}

/// `scenes/chain.json`, written in RON.
const CHAIN_RON: &str = r#"(
    name: "chain",
    world: (integrator: VelocityVerlet, dt: 1e-3, duration: 10, frame_rate: 10,
            gravity: (0, 0, -1), linear_damping: 0.05),
    materials: {"rope": (spacing: LennardJones((epsilon: 10, r0: 1, cutoff: 1.5)))},
    objects: [(
        name: "chain", material: "rope",
        generator: Chain(count: 20, spacing: 1, start: (0, 0, 0), direction: (1, 0, 0)),
        mass: 0.1,
        overrides: [(particles: First(1), fixed_position: true)],
    )],
    forces: [(object: "chain", particles: Last(1), force: (0, 0.5, 0), start: 4, end: 6, ramp: 0.5)],
    outputs: (particles: Points, metrics: true),
)"#;

#[test]
fn ron_and_json_versions_build_identical_worlds() {
    let json_path = scenes_dir().join("chain.json");
    let from_json = load_scene(&json_path).unwrap();
    let from_ron = parse_scene(CHAIN_RON, Format::Ron, "<chain.ron>").unwrap();
    assert_eq!(
        Scene {
            origin: String::new(),
            limits: Default::default(),
            frames_override: None,
            expected_warnings: Vec::new(),
            ..from_json.clone()
        },
        Scene {
            origin: String::new(),
            limits: Default::default(),
            frames_override: None,
            expected_warnings: Vec::new(),
            ..from_ron.clone()
        }
    );
    let mut a = from_json.build(json_path.parent(), None).unwrap();
    let mut b = from_ron.build(None, None).unwrap();
    assert_same_world(a.world(), b.world());
    for _ in 0..20 {
        a.world_mut().step().unwrap();
        b.world_mut().step().unwrap();
    }
    assert_same_world(a.world(), b.world());
}

#[test]
fn every_example_scene_survives_ron_and_json_round_trips() {
    for path in scene_files() {
        let scene = load_scene(&path).unwrap();
        let texts = [
            (
                ron::ser::to_string_pretty(&scene, Default::default()).unwrap(),
                Format::Ron,
            ),
            (serde_json::to_string_pretty(&scene).unwrap(), Format::Json),
        ];
        for (text, format) in texts {
            let back = op_scene::load::parse_unvalidated(&text, format, &scene.origin)
                .unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()));
            // Points paths are relative to the scene's directory.
            back.validate(path.parent()).unwrap();
            // The expected warnings are header comments, not data.
            let back = Scene {
                expected_warnings: scene.expected_warnings.clone(),
                ..back
            };
            assert_eq!(back, scene, "{} via {format:?}", path.display());
        }
    }
}

/// `precision: mixed` reaches the world: the shipped Lennard-Jones ball
/// runs in mixed precision without a warning; the same ball with an
/// orientation term cannot, runs in double precision, and the run says so.
#[test]
fn mixed_precision_runs_or_says_why_not() {
    let path = scenes_dir().join("lj_ball_mixed.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let run = |text: &str| {
        let scene = parse_scene(text, Format::Ron, "<test>").unwrap_or_else(|e| panic!("{e}"));
        scene
            .build_for_run(None, None)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let ball = run(&text);
    assert!(ball.world().runs_mixed_precision());
    assert!(
        ball.step_warnings().is_empty(),
        "{:?}",
        ball.step_warnings()
    );
    let oriented = text.replace("\"argon\": (", "\"argon\": (\n            coplanarity: 1,");
    assert_ne!(oriented, text);
    let built = run(&oriented);
    assert!(!built.world().runs_mixed_precision());
    assert!(
        built
            .step_warnings()
            .iter()
            .any(|w| w.starts_with("world.precision: mixed has no effect")),
        "{:?}",
        built.step_warnings()
    );
}
