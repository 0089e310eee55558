//! The skinned spiral hit by a deformable implicit ball (seed 002 §6,
//! fig. 6; `scenes/ball_vs_spiral.ron`): the skins come into contact
//! without interpenetrating (Gascuel implicit contact), the spiral deforms
//! and recovers its rest shape. Also: skins and contact are stages only
//! when the scene uses them.

use std::path::{Path, PathBuf};

use oriented_particles::op_scene::{self, load_scene, RunOptions, Scene};

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.ron"));
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn stages_include_skins_and_contact_only_when_used() {
    let plain = scene("spiral").build(None, None).expect("builds");
    assert!(plain.skins().is_empty());
    let stages = plain.stages();
    for s in ["skin", "polygonize", "contact"] {
        assert!(!stages.iter().any(|x| x == s), "{s} in {stages:?}");
    }
    assert_eq!(stages, plain.world().enabled());

    let skinned = scene("ball_vs_spiral").build(None, None).expect("builds");
    assert_eq!(skinned.skins().len(), 2);
    let stages = skinned.stages();
    for s in ["skin", "polygonize", "contact"] {
        assert!(stages.iter().any(|x| x == s), "{s} not in {stages:?}");
    }
}

/// The scene's `// claim:` line.
fn claim() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/ball_vs_spiral.ron");
    std::fs::read_to_string(path)
        .expect("scene")
        .lines()
        .find_map(|l| l.strip_prefix("// claim: ").map(str::to_string))
        .expect("ball_vs_spiral states its claim")
}

#[test]
fn ball_hits_spiral_which_deforms_and_recovers() {
    println!("claim: {}", claim());
    let scene = scene("ball_vs_spiral");
    // The scene's camera sees the contact: it looks across the ball's
    // approach (+y), not along it (from the front the ball hides where it
    // presses the spiral).
    let view = scene.outputs.view.expect("the scene chooses its view");
    let along = view[1].abs() / view.iter().map(|c| c * c).sum::<f64>().sqrt();
    assert!(along < 0.5, "the view {view:?} looks along the ball's path");
    let mut built = scene.build(None, None).expect("builds");
    let out: PathBuf =
        std::env::temp_dir().join(format!("opsim-ball-vs-spiral-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let opts = RunOptions {
        out_dir: out.clone(),
        frames: None,
        formats: vec![op_scene::export::FrameFormat::OBJ],
        ..Default::default()
    };
    let summary = op_scene::run(&mut built, &opts, &mut |_, _| {}).expect("runs");
    assert!(!summary.diverged);
    let contact = summary.contact.expect("a contact scene reports contact");
    let spiral = &summary.objects[0];
    println!(
        "contact {contact:?}, spiral max {} final {}",
        spiral.rest_shape_error_max, spiral.rest_shape_error_final
    );
    assert!(contact.total_impulse > 0.0, "no contact: {contact:?}");
    assert!(
        contact.max_penetration < 0.05,
        "skins interpenetrate by {} r0",
        contact.max_penetration
    );
    assert_eq!(spiral.name, "spiral");
    assert!(spiral.rest_shape_error_max >= 0.2, "{spiral:?}");
    assert!(spiral.rest_shape_error_final <= 0.02, "{spiral:?}");

    // The frames hold both skins as named objects with vertex normals,
    // one file each.
    for name in ["spiral_skin", "ball_skin"] {
        let path = out.join(format!("frames/{name}/{name}_00010.obj"));
        let frame = std::fs::read_to_string(path).expect("frame");
        assert!(
            frame.lines().any(|l| l == format!("o {name}")),
            "{name} missing"
        );
        assert!(frame.lines().any(|l| l.starts_with("vn ")));
    }
    let json = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    let v: serde_json::Value = serde_json::from_str(&json).expect("json");
    assert!(v["contact"]["total_impulse"].as_f64().is_some());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn skins_are_validated() {
    use op_scene::{parse_scene, Format};
    let text = |skin: &str| {
        format!(
            r#"(name: "s", materials: {{"m": ()}},
               objects: [(name: "o", material: "m",
                          generator: Chain(count: 3, spacing: 1), skin: Some({skin}))])"#
        )
    };
    let ok = text("(primitive: Square(half_side: 0.5), radius: 1, cell_size: 0.2)");
    let s = parse_scene(&ok, Format::Ron, "<ok>").expect("parses");
    let built = s.build(None, None).expect("builds");
    assert_eq!(built.skins().len(), 1);
    assert_eq!(built.skins()[0].name, "o_skin");
    assert!(!built.has_contact());

    let bad = text("(primitive: Point, radius: -1, cell_size: 0.2)");
    let err = parse_scene(&bad, Format::Ron, "<bad>")
        .and_then(|s| s.build(None, None).map(|_| ()))
        .expect_err("negative radius");
    assert!(err.to_string().contains("skin.radius"), "{err}");

    let unknown = text("(primitive: Point, radius: 1, cell_size: 0.2, colour: 1)");
    let err = parse_scene(&unknown, Format::Ron, "<unknown>").expect_err("unknown field");
    assert!(err.to_string().contains("colour"), "{err}");
}
