//! The registered features (`op_scene::features`) act as their settings
//! say, are listed and timed as stages of the scene's driver, and bad
//! settings are refused with the field path.

use op_dynamics::Real;
use op_scene::{parse_scene, Format, SceneError};

/// A scene of one free particle (no interaction) and of a second one
/// far away, both at rest, with `features`.
fn two_particles(features: &str) -> String {
    format!(
        r#"(
        name: "drift",
        world: (dt: 1e-3, duration: 2),
        materials: {{ "inert": () }},
        objects: [
            (name: "a", material: "inert", mass: 2,
             generator: List(particles: [(position: (0, 0, 0))])),
            (name: "b", material: "inert",
             generator: List(particles: [(position: (100, 0, 0))])),
        ],
        features: [{features}],
    )"#
    )
}

fn built(features: &str) -> op_scene::BuiltScene {
    parse_scene(&two_particles(features), Format::Ron, "<test>")
        .and_then(|s| s.build(None, None))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn velocity(scene: &op_scene::BuiltScene, object: usize) -> op_dynamics::Vec3 {
    let p = scene.world().particles();
    p.velocities()[p.slot_of(scene.objects()[object].ids[0]).unwrap()]
}

/// A particle of mass m left to a wind of velocity w and drag c reaches
/// `v(t) = w (1 - exp(-c t / m))`, to the first order in `dt` of a
/// velocity-dependent force under velocity Verlet (halving the step
/// halves the error); an object the wind does not blow on stays at rest.
#[test]
fn wind_drags_a_particle_toward_the_air_speed() {
    let t = 2.0;
    let expected = 3.0 * (1.0 - (-0.5 * t / 2.0 as Real).exp());
    let mut errors = Vec::new();
    for dt in [1e-3, 5e-4] {
        let text = two_particles(r#"Wind((velocity: (3, 0, 0), drag: 0.5, objects: ["a"]))"#)
            .replace("dt: 1e-3", &format!("dt: {dt}"));
        let mut s = parse_scene(&text, Format::Ron, "<test>")
            .and_then(|s| s.build(None, None))
            .unwrap();
        assert!(s.stages().contains(&"wind".to_string()));
        assert!(!s.is_passive(), "wind adds energy");
        s.advance_to(t).unwrap();
        let v = velocity(&s, 0);
        println!("dt {dt}: v = {v}, expected {expected}");
        assert!(v.y.abs() < 1e-12 && v.z.abs() < 1e-12);
        assert_eq!(velocity(&s, 1).norm(), 0.0, "b is not blown on");
        errors.push((v.x - expected).abs());
    }
    assert!(errors[0] < 1e-3 * expected, "{errors:?}");
    let ratio = errors[0] / errors[1];
    assert!((1.8..2.2).contains(&ratio), "first order: {errors:?}");
}

/// Gust keyframes add to the wind: a gust along +y that ramps up from 0
/// at t = 1 to 2 at t = 2 only pushes along y after t = 1.
#[test]
fn gusts_blow_only_when_their_keyframes_say() {
    let mut s = built(
        r#"Wind((drag: 1, gusts: [(time: 1, velocity: (0, 0, 0)), (time: 2, velocity: (0, 2, 0))]))"#,
    );
    s.advance_to(1.0).unwrap();
    assert!(velocity(&s, 0).norm() < 1e-12, "no wind before the gust");
    s.advance_to(2.0).unwrap();
    let v = velocity(&s, 0);
    assert!(
        v.y > 0.1 && v.x.abs() < 1e-12,
        "the gust pushes along y: {v}"
    );
}

/// A particle thrown faster than the clamp is slowed to it after the
/// first step and keeps its direction; the unclamped one keeps its speed.
#[test]
fn the_speed_clamp_limits_the_chosen_objects() {
    let text = two_particles(r#"SpeedClamp((max_speed: 2, objects: ["a"]))"#)
        .replace(r#"mass: 2,"#, r#"mass: 2, velocity: (6, 8, 0),"#)
        .replace(
            r#"(name: "b", material: "inert","#,
            r#"(name: "b", material: "inert", velocity: (0, 0, 20),"#,
        );
    let mut s = parse_scene(&text, Format::Ron, "<test>")
        .and_then(|s| s.build(None, None))
        .unwrap();
    assert!(s.is_passive(), "a clamp only removes energy");
    // One step.
    s.advance_to(1e-3).unwrap();
    assert_eq!(s.world().steps(), 1);
    let v = velocity(&s, 0);
    assert!((v.norm() - 2.0).abs() < 1e-12, "clamped: {v}");
    assert!((v.x / v.y - 0.75).abs() < 1e-12, "direction kept: {v}");
    assert_eq!(velocity(&s, 1).z, 20.0, "b is not clamped");
    let timings = s.timings();
    let timed: Vec<&str> = timings.iter().map(|(n, _)| n.as_str()).collect();
    assert!(timed.contains(&"speed_clamp"), "timed: {timed:?}");
    assert!(s.stages().contains(&"speed_clamp".to_string()));
}

/// A feature is listed once: a second entry of one kind is refused,
/// naming it (the driver refuses a second stage of a name as well,
/// `op_dynamics::driver` tests); the features' stages are listed after the
/// world's.
#[test]
fn a_stage_name_is_registered_once() {
    let text =
        two_particles(r#"SpeedClamp((max_speed: 2)), Wind((drag: 1)), SpeedClamp((max_speed: 3))"#);
    let e = parse_scene(&text, Format::Ron, "<test>")
        .and_then(|s| s.build(None, None))
        .err()
        .expect("two clamps are refused");
    let message = e.to_string();
    assert!(
        message.contains("features[2].SpeedClamp") && message.contains("twice"),
        "{message}"
    );
    let s = built(r#"SpeedClamp((max_speed: 2)), Wind((drag: 1))"#);
    let stages = s.stages();
    assert!(
        stages.ends_with(&["speed_clamp".to_string(), "wind".to_string()]),
        "{stages:?}"
    );
}

fn refused(features: &str) -> String {
    match parse_scene(&two_particles(features), Format::Ron, "<test>")
        .and_then(|s| s.build(None, None))
    {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        Err(e) => panic!("not a validation error: {e}"),
        Ok(_) => panic!("accepted: {features}"),
    }
}

#[test]
fn bad_feature_settings_are_refused_with_their_path() {
    for (features, expected) in [
        ("Wind((drag: 0))", "features[0].Wind.drag"),
        ("Wind((drag: 1, velocity: (1, 0, inf)))", "features[0].Wind.velocity"),
        (
            "Wind((drag: 1, gusts: [(time: 2, velocity: (0, 0, 0)), (time: 1, velocity: (0, 0, 0))]))",
            "features[0].Wind.gusts[1].time",
        ),
        (r#"Wind((drag: 1, objects: ["c"]))"#, "features[0].Wind.objects[0]"),
        ("Wind((drag: 1)), Wind((drag: 2))", "features[1].Wind"),
        ("SpeedClamp((max_speed: -1))", "features[0].SpeedClamp.max_speed"),
        (
            "SpeedClamp((max_speed: 1)), SpeedClamp((max_speed: 2))",
            "features[1].SpeedClamp",
        ),
    ] {
        let message = refused(features);
        println!("{features}: {message}");
        assert!(message.contains(expected), "{message}");
    }
}
