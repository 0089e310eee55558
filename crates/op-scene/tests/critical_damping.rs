//! `linear_damping: "Critical"` (`op_scene::damping`, seed 002 §5): how a
//! scene spells it in RON and JSON, what building resolves it to, and the
//! scenes it refuses with the reason. Runs of user spirals with it are in
//! the root package's `tests/critical_damping.rs`.

use std::path::Path;

use op_scene::damping::{resolve, CriticalSchedule};
use op_scene::modes::Basis;
use op_scene::{load_scene, parse_scene, Damping, Format, Scene};

fn shipped(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenes/{name}.ron"));
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A chain of three Lennard-Jones particles with `damping` as its world's
/// `linear_damping` value, in RON.
fn chain(damping: &str) -> String {
    format!(
        r#"(name: "chain", world: (dt: 0.01, linear_damping: {damping}),
            materials: {{"lj": (spacing: LennardJones((cutoff: 1.5)))}},
            objects: [(name: "c", material: "lj", generator: Chain(count: 3, spacing: 1))])"#
    )
}

/// RON and JSON both write the rule as the string `"Critical"` and a
/// coefficient as a number; it round-trips through both. A bare
/// `Critical` in RON, a misspelling, `null` and a negative number are
/// refused, each saying what is allowed.
#[test]
fn the_rule_is_spelt_critical_in_ron_and_json() {
    let ron = parse_scene(&chain("\"Critical\""), Format::Ron, "<t>").unwrap();
    assert_eq!(ron.world.linear_damping, Damping::Critical);
    let number = parse_scene(&chain("0.5"), Format::Ron, "<t>").unwrap();
    assert_eq!(number.world.linear_damping, Damping::Value(0.5));
    let json_text = serde_json::to_string(&ron).unwrap();
    assert!(
        json_text.contains(r#""linear_damping":"Critical""#),
        "{json_text}"
    );
    let json = parse_scene(&json_text, Format::Json, "<t>").unwrap();
    assert_eq!(json.world.linear_damping, Damping::Critical);
    let ron_text = ron::to_string(&ron).unwrap();
    let again = parse_scene(&ron_text, Format::Ron, "<t>").unwrap();
    assert_eq!(again.world.linear_damping, Damping::Critical);
    for (text, says) in [
        (chain("Critical"), "quoted, in RON too"),
        (chain("\"critical\""), "a number >= 0 or \"Critical\""),
        (chain("-1"), "world.linear_damping"),
    ] {
        let e = parse_scene(&text, Format::Ron, "<t>")
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{e}");
    }
    let null = json_text.replace(r#""linear_damping":"Critical""#, r#""linear_damping":null"#);
    let e = parse_scene(&null, Format::Json, "<t>")
        .unwrap_err()
        .to_string();
    assert!(e.contains("\"Critical\""), "{e}");
}

/// The rule sets the angular damping: a number beside it is refused.
#[test]
fn an_angular_damping_beside_the_rule_is_refused() {
    let text =
        chain("\"Critical\"").replace("linear_damping", "angular_damping: 0.05, linear_damping");
    let e = parse_scene(&text, Format::Ron, "<t>")
        .unwrap_err()
        .to_string();
    assert!(e.contains("world.angular_damping = 0.05"), "{e}");
    assert!(e.contains("leave it out"), "{e}");
}

/// The seed spiral (`scenes/spiral.ron`) with `"Critical"`: built with
/// `β0 = 2 ω1` (unit masses), `β1 = 2 ω1 I` (moments 0.1), its slowest
/// mode taken in its plane (ω1 = 0.30, as `reports/shape_memory.md` has
/// it), a settle phase of at least 12 τ (its own 40 is just above) and a
/// run to 20 τ after the load ends at 40, rounded up to a whole frame; the
/// same numbers in the built world and in `BuiltScene::critical_damping`.
#[test]
fn the_seed_spiral_resolves_to_the_rule() {
    let mut scene = shipped("spiral");
    scene.world.linear_damping = Damping::Critical;
    scene.world.angular_damping = 0.0;
    let built = scene.build(None, None).unwrap();
    let c = built.critical_damping().expect("resolved").clone();
    eprintln!("{c:?}");
    assert_eq!(c.mode.basis, Basis::Planar);
    assert!((c.mode.omega1 - 0.30).abs() < 0.01, "{}", c.mode.omega1);
    assert_eq!((c.mode.mass, c.mode.inertia), (1.0, 0.1));
    assert_eq!(c.linear_damping, 2.0 * c.mode.omega1);
    assert_eq!(c.angular_damping, 2.0 * c.mode.omega1 * 0.1);
    let s = CriticalSchedule::default();
    assert_eq!(c.settle, scene.world.settle.max(s.settle * c.tau));
    assert_eq!(c.release, Some(40.0));
    assert!(c.duration >= 40.0 + s.recovery * c.tau);
    assert!(c.duration < 40.0 + s.recovery * c.tau + 1.0 / scene.world.frame_rate);
    let e = &built.world().params().external;
    assert_eq!(
        (e.linear_damping, e.angular_damping),
        (c.linear_damping, c.angular_damping)
    );
    assert_eq!(
        (built.settle_duration(), built.duration()),
        (c.settle, c.duration)
    );
    assert!((2..=4).contains(&c.passes), "{}", c.passes);
}

/// Scenes the rule cannot serve are refused when built, naming the field
/// and why: a free hinge (a mechanism: its slowest mode has no stiffness),
/// a skinned object (skin contact is not in the world's forces), a scene
/// too large for the dense modes.
#[test]
fn scenes_without_a_slowest_mode_are_refused() {
    for (name, says) in [
        ("hinge_spiral", "no restoring force"),
        ("ball_vs_spiral", "has a skin"),
        ("sheet", "degrees of freedom"),
    ] {
        let mut scene = shipped(name);
        scene.world.linear_damping = Damping::Critical;
        scene.world.angular_damping = 0.0;
        let e = match resolve(&scene, None) {
            Ok(_) => panic!("{name}: resolved"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains("world.linear_damping = \"Critical\""),
            "{name}: {e}"
        );
        assert!(e.contains(says), "{name}: {e}");
    }
}
