//! Runs that blow up end with exit 3, wherever the blow-up happens: a
//! shipped scene run at a step above its stable step breaks into pieces,
//! during its settle phase or after it, and `opsim run` must not report
//! that as success. A scene that tears on purpose says so in its header,
//! and `--allow-breakup` accepts any breakup.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A shipped scene with its `dt` line replaced by `dt`, written into a
/// fresh folder `tag` (the scene file and the run's output go there).
fn scene_with_step(scene: &str, old_dt: &str, dt: f64, tag: &str) -> PathBuf {
    let text = std::fs::read_to_string(repo().join("scenes").join(scene)).unwrap();
    let line = format!("        dt: {old_dt},");
    assert!(text.contains(&line), "{scene} has no line {line:?}");
    let dir = std::env::temp_dir().join(format!("opsim-explosions-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(scene);
    std::fs::write(&path, text.replace(&line, &format!("        dt: {dt:e},"))).unwrap();
    path
}

fn run(scene: &Path, extra: &[&str]) -> (Output, serde_json::Value) {
    let out = scene.parent().unwrap().join("out");
    let output = Command::new(env!("CARGO_BIN_EXE_opsim"))
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(&out)
        .args(extra)
        .output()
        .unwrap();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap_or_default();
    let summary = serde_json::from_str(&summary).unwrap_or(serde_json::Value::Null);
    (output, summary)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `fig_12_plastic` at twice its estimated stable step (1.929e-2): the
/// shell shatters, already while settling (178 pieces at frame 0). Before,
/// the energy scale was taken after the settle phase, from the shattered
/// state, and the run exited 0 with a warning.
#[test]
fn a_blow_up_while_settling_exits_3() {
    let scene = scene_with_step("fig_12_plastic.ron", "2e-3", 2.0 * 1.929e-2, "settle");
    let (o, summary) = run(&scene, &["--frames", "20", "--allow-unstable-step"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(summary["diverged"], true, "{summary}");
    let why = summary["divergence"].as_str().unwrap_or_default();
    assert!(
        why.contains("runaway energy") || why.contains("object \"shell\" broke into"),
        "{why}"
    );
    let _ = std::fs::remove_dir_all(scene.parent().unwrap());
}

/// `ball_vs_spiral` at a step of 0.14, the edge of stability of the
/// spiral's own stiffest mode (0.1422, contact left out; contact evaluated
/// in the step runs clean up to 0.12): the spiral breaks apart without a
/// runaway energy; `--allow-breakup` turns that into a warning.
#[test]
fn a_skinned_scene_breaking_apart_exits_3() {
    let scene = scene_with_step("ball_vs_spiral.ron", "0.005", 0.14, "contact");
    let (o, summary) = run(&scene, &["--frames", "20", "--allow-unstable-step"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(summary["diverged"], true, "{summary}");
    let why = summary["divergence"].as_str().unwrap_or_default();
    assert!(why.contains("broke into"), "{why}");
    assert!(
        why.contains("--allow-breakup"),
        "the message says how to accept it: {why}"
    );

    let (o, summary) = run(
        &scene,
        &["--frames", "20", "--allow-breakup", "--allow-unstable-step"],
    );
    assert_eq!(o.status.code(), Some(0), "accepted: {}", stderr(&o));
    assert_eq!(summary["diverged"], false, "{summary}");
    let warnings = summary["warnings"].to_string();
    assert!(
        warnings.contains("broke into"),
        "still a warning: {warnings}"
    );
    let _ = std::fs::remove_dir_all(scene.parent().unwrap());
}

/// A scene that declares its breakup runs to exit 0 and lists the breakup
/// under `expected`, not as a warning (nor prints it as one); the
/// declaration accepts only the object it names.
#[test]
fn a_declared_breakup_is_a_warning_and_only_for_its_object() {
    let text = std::fs::read_to_string(repo().join("scenes/fig_12_tearing.ron")).unwrap();
    assert!(text.starts_with("// expect-warning: object \"sheet\" broke into 2 pieces"));
    let dir = std::env::temp_dir().join(format!("opsim-explosions-tear-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let declared = dir.join("declared.ron");
    std::fs::write(&declared, &text).unwrap();
    let (o, summary) = run(&declared, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(summary["expected"]
        .to_string()
        .contains("broke into 2 pieces"));
    assert!(
        !summary["warnings"].to_string().contains("broke into"),
        "{summary}"
    );
    assert!(
        stderr(&o).contains("opsim: expected: object \"sheet\" broke into 2 pieces"),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("warning: object"), "{}", stderr(&o));

    let other = dir.join("other.ron");
    std::fs::write(
        &other,
        text.replacen(
            "expect-warning: object \"sheet\"",
            "expect-warning: object \"cloth\"",
            1,
        ),
    )
    .unwrap();
    let (o, summary) = run(&other, &[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(summary["diverged"], true);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stable step counts skin contact: `ball_vs_spiral` broke at 0.6 of
/// the bound `check` printed when it left contact out (0.1422), while the
/// contact was held over each step; the bound with contact lies below that
/// step, and at the recommended step both skinned scenes measured run
/// clean.
#[test]
fn the_stable_step_of_a_skinned_scene_counts_its_contact() {
    for (scene, old_dt, failed_at) in [
        ("ball_vs_spiral.ron", "0.005", 0.6 * 0.1422),
        ("sheet_on_box.ron", "0.004", 0.8 * 0.04385),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_opsim"))
            .arg("check")
            .arg(repo().join("scenes").join(scene))
            .output()
            .unwrap();
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let number = |after: &str| -> f64 {
            let rest = &out[out.find(after).unwrap_or_else(|| panic!("{out}")) + after.len()..];
            rest.split_whitespace().next().unwrap().parse().unwrap()
        };
        let recommended = number("recommended at most ");
        let edge = number("), edge ");
        assert!(out.contains("skin contact at most"), "{out}");
        assert!(
            edge < failed_at,
            "{scene}: edge {edge} not below {failed_at}"
        );
        assert!(recommended < edge, "{out}");
        let tag = scene.trim_end_matches(".ron");
        // Just below the printed (rounded) value: the whole run.
        let path = scene_with_step(scene, old_dt, 0.999 * recommended, tag);
        let (o, summary) = run(&path, &[]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{scene} at {recommended}: {}",
            stderr(&o)
        );
        assert_eq!(summary["warnings"], serde_json::json!([]), "{summary}");
        let _ = std::fs::remove_dir_all(path.parent().unwrap());
    }
}

/// An adaptive scene whose tolerances no step can meet (1e-300) used to
/// crawl at `dt_min` to its end (hours); it now stops as diverged after a
/// thousand forced steps, exit 3, its frame 0 written and the summary
/// saying why (issue 38).
#[test]
fn unmeetable_tolerances_exit_3() {
    let dir = std::env::temp_dir().join(format!("opsim-explosions-tol-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("strict.ron");
    std::fs::write(
        &scene,
        r#"(name: "strict", world: (dt: 0.01, duration: 2, frame_rate: 10,
            integrator: Adaptive((rtol: 1e-300, atol_position: 1e-300, atol_velocity: 1e-300,
                atol_angle: 1e-300, atol_angular_velocity: 1e-300))),
        materials: {"m": (coplanarity: 10)},
        objects: [(name: "s", material: "m",
            generator: HexSheet(nx: 6, ny: 6, spacing: 1, noise: 0.1))])"#,
    )
    .unwrap();
    let (o, summary) = run(&scene, &[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(summary["diverged"], true, "{summary}");
    assert_eq!(summary["frames"], 1, "{summary}");
    let why = summary["divergence"].as_str().unwrap_or_default();
    assert!(why.contains("no step meets these tolerances"), "{why}");
    let _ = std::fs::remove_dir_all(&dir);
}
