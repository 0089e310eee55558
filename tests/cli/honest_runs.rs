//! Runs that tell the truth: exit 0 only for a run that went right.

use super::*;

/// A particle falling from rest under gravity is not a runaway: the energy
/// scale is never zero (it was 1e-12 and the run exited 3).
#[test]
fn a_particle_falling_from_rest_is_not_a_divergence() {
    let dir = temp_dir("fall");
    let scene = scene_file(
        &dir,
        "fall.ron",
        &one_particle("dt: 1e-3, duration: 3, gravity: (0, 0, -9.81)", ""),
    );
    let o = run_scene(&scene, &dir.join("out"), &[]);
    assert!(o.status.success(), "{}", text(&o));
    let s = summary(&dir.join("out"));
    assert_eq!(s["warnings"].as_array().unwrap().len(), 0, "{s}");
    assert_outputs_finite(&dir.join("out"));
}

/// Values that cannot give a finite run of bounded work are refused by
/// `check`, naming the field and what is allowed.
#[test]
fn values_without_a_finite_run_are_refused() {
    let dir = temp_dir("bounds");
    let list = |a: &str, b: &str| {
        format!(
            "(name: \"l\", materials: {{\"m\": ()}}, objects: [(name: \"l\", material: \"m\", \
             generator: List(particles: [(position: {a}), (position: {b})]))])"
        )
    };
    let tool = |shape: &str, path: &str| {
        one_particle(
            "dt: 1e-3",
            &format!(", tools: [(shape: {shape}, path: [{path}], role: Obstacle(stiffness: 10))]"),
        )
    };
    let cases = [
        (one_particle("dt: 50, frame_rate: 2", ""), "world.dt"),
        (one_particle("dt: 1e12", ""), "world.dt"),
        (one_particle("dt: 1e-320", ""), "steps"),
        (one_particle("settle: 1e308", ""), "steps"),
        (one_particle("frame_rate: 1e-320", ""), "world.frame_rate"),
        (
            one_particle("heat: (conduction: 1e15, cooling: 0, ambient: 0)", ""),
            "world.heat.conduction",
        ),
        (list("(0, 0, 0)", "(1e308, 0, 0)"), "particles[1].position"),
        (
            one_particle(
                "dt: 1e-3",
                ", creation: Some((stretching: Some((d_min: 1e-320, d_max: 2.5))))",
            ),
            "creation.stretching.d_min",
        ),
        (
            tool("Ball(radius: 1e308)", "(time: 0, position: (0, 0, 0))"),
            "tools[0].shape",
        ),
        (
            tool(
                "Ball(radius: 1)",
                "(time: 0, position: (0, 0, 3), rotation: (1e308, 0, 0))",
            ),
            "rotation",
        ),
        (
            "(name: \"s\", materials: {\"m\": ()}, objects: [(name: \"s\", material: \"m\", \
             generator: Chain(count: 10, spacing: 1), skin: (primitive: Point, radius: 300, \
             cell_size: 0.25))])"
                .to_string(),
            "skin.cell_size",
        ),
    ];
    for (k, (body, field)) in cases.iter().enumerate() {
        let path = scene_file(&dir, &format!("case{k}.ron"), body);
        let o = opsim(&["check", path.to_str().unwrap()], &dir);
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "case {k}: {msg}");
        assert!(msg.contains(field), "case {k}: {msg}");
        assert!(msg.len() < 600, "case {k}: long message: {msg}");
        assert!(!msg.contains("0000000000"), "case {k}: long number: {msg}");
    }
    // Pair work is bounded too: a torus shell packed at a tenth of its
    // material's cut-off has hundreds of neighbours per particle (1.7e8
    // particle-steps pass 1e9; about 1.7e11 pair-steps do not pass 3e10).
    let torus = std::fs::read_to_string(repo().join("scenes/torus_shell.ron")).unwrap();
    let dense = scene_file(
        &dir,
        "dense.ron",
        &torus.replace("spacing: 1)", "spacing: 0.1)"),
    );
    let o = opsim(
        &[
            "check",
            dense.to_str().unwrap(),
            "--max-particle-steps",
            "1e9",
        ],
        &dir,
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("pair-steps"), "{}", text(&o));
    // The documented particle limit is checked without making the
    // particles: `check` of ten million is as quick as of ten.
    let big = scene_file(
        &dir,
        "big.ron",
        "(name: \"b\", materials: {\"m\": ()}, objects: [(name: \"b\", material: \"m\", \
         generator: Chain(count: 10000000, spacing: 1))])",
    );
    let start = std::time::Instant::now();
    let o = opsim(&["check", big.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("10000000 particles"), "{}", text(&o));
    assert!(
        start.elapsed().as_secs() < 30,
        "check built the particles: {:?}",
        start.elapsed()
    );
}

/// `check` warns when dt exceeds the recommended step, and `run` refuses
/// a step beyond the edge of stability unless asked.
#[test]
fn a_step_above_the_stable_step_is_reported() {
    let dir = temp_dir("stable");
    let spiral = std::fs::read_to_string(repo().join("scenes/spiral.ron")).unwrap();
    // The spiral's stiffest mode is near ω² = 200: dt 0.5 (its frame
    // interval) is far beyond velocity Verlet's 2/ω ≈ 0.14.
    let path = scene_file(&dir, "spiral.ron", &spiral.replace("dt: 0.005", "dt: 0.5"));
    let o = opsim(&["check", path.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("exceeds the recommended step"),
        "{}",
        text(&o)
    );
    let o = run_scene(&path, &dir.join("out"), &["--frames", "2"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("beyond the estimated edge of stability")
            && text(&o).contains("--allow-unstable-step"),
        "{}",
        text(&o)
    );
    let o = opsim(
        &["check", repo().join("scenes/spiral.ron").to_str().unwrap()],
        &dir,
    );
    assert!(!text(&o).contains("warning"), "{}", text(&o));
    assert!(
        text(&o).contains("stable step: recommended at most") && text(&o).contains("edge"),
        "{}",
        text(&o)
    );
}

/// The slowest-mode search of `check` counts the pairs it evaluates, not
/// only its particles: the ten-times-larger spiral's material on a patch
/// of points ten times closer than its rest spacing (every pair deep
/// inside its cohesion table's start, whose energy takes a quadrature)
/// took check 13 s of settling; the search now stops on its work before
/// it settles, and says why.
#[test]
fn the_slowest_mode_search_counts_its_pairs() {
    let dir = temp_dir("mode-pairs");
    let spiral = std::fs::read_to_string(repo().join("scenes/spiral_x10.ron")).unwrap();
    let patch = repo().join("scenes/data/patch.xyz");
    let dense = spiral.replace(
        "Spiral(count: 10, spacing: 10, curvature_start: 0.025, curvature_end: 0.085)",
        &format!("Points(path: {:?})", patch.to_str().unwrap()),
    );
    assert!(dense.contains("patch.xyz"));
    let path = scene_file(&dir, "dense.ron", &dense);
    let o = opsim(&["check", path.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("slowest mode: not found: settling to find the slowest mode would take")
            && text(&o).contains("each pair's evaluation counted as one"),
        "{}",
        text(&o)
    );
    // A step's fixed cost counts too: the 8-particle chain of extreme
    // tight curvature thrown with a 40-unit settle spent 5.8 s in check's
    // search with its 24 particles and pairs a step counted alone.
    let chain = std::fs::read_to_string(repo().join("scenes/extreme/tight_curvature.ron"))
        .unwrap()
        .replace(
            "angular_damping: 0.05,",
            "angular_damping: 0.05, settle: 40,",
        )
        .replace(
            "overrides: [(curvature: 100)]",
            "velocity: (37, 0, -7), overrides: [(curvature: 100)]",
        );
    assert!(chain.contains("settle: 40") && chain.contains("velocity: (37"));
    let path = scene_file(&dir, "thrown.ron", &chain);
    let o = opsim(&["check", path.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("each step as 50 more"), "{}", text(&o));
}

/// Explicit Euler without damping has no stable step: `check`, its
/// warning and `run`'s refusal say so in words and name the remedy, not
/// "recommended at most 0".
#[test]
fn explicit_euler_without_damping_is_told_it_has_no_stable_step() {
    let dir = temp_dir("no-stable-step");
    let spiral = std::fs::read_to_string(repo().join("scenes/spiral.ron")).unwrap();
    let undamped = spiral
        .replace("integrator: VelocityVerlet", "integrator: ExplicitEuler")
        .replace("linear_damping: 0.3", "linear_damping: 0");
    assert!(undamped.contains("ExplicitEuler") && undamped.contains("linear_damping: 0,"));
    let path = scene_file(&dir, "euler.ron", &undamped);
    let o = opsim(&["check", path.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("stable step: none for ExplicitEuler"),
        "{}",
        text(&o)
    );
    assert!(!text(&o).contains("recommended at most 0"), "{}", text(&o));
    let o = run_scene(&path, &dir.join("out"), &["--frames", "2"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("is not stable") && text(&o).contains("world.linear_damping > 0"),
        "{}",
        text(&o)
    );
}

/// An object pulled apart is not a silent success: the run ends with exit
/// 3 after writing every frame, the summary names its pieces and says how
/// to accept it; `--allow-breakup` makes it a printed warning.
#[test]
fn break_up_is_reported() {
    let dir = temp_dir("breakup");
    let spiral = std::fs::read_to_string(repo().join("scenes/spiral.ron")).unwrap();
    let doubled = spiral
        .replace("0.0113329, -0.443191", "0.0226658, -0.886382")
        .replace("-0.0113329, 0.443191", "-0.0226658, 0.886382");
    assert_ne!(doubled, spiral);
    let path = scene_file(&dir, "spiral.ron", &doubled);
    let o = run_scene(&path, &dir.join("out"), &[]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(
        text(&o).contains("error: object \"spiral\" broke into 2 pieces"),
        "{}",
        text(&o)
    );
    let s = summary(&dir.join("out"));
    assert_eq!(s["diverged"], true);
    assert_eq!(s["objects"][0]["pieces"], 2);
    let o = run_scene(&path, &dir.join("out"), &["--allow-breakup"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("warning: object \"spiral\" broke into 2 pieces"),
        "{}",
        text(&o)
    );
    let s = summary(&dir.join("out"));
    assert_eq!(s["objects"][0]["pieces"], 2);
    assert!(s["objects"][0]["bond_stretch_max"].as_f64().unwrap() > 1.5);
    assert_eq!(s["warnings"].as_array().unwrap().len(), 1);
    // The demo's own pull keeps it whole.
    let o = run_scene(&repo().join("scenes/spiral.ron"), &dir.join("demo"), &[]);
    assert!(o.status.success(), "{}", text(&o));
    let s = summary(&dir.join("demo"));
    assert_eq!(s["objects"][0]["pieces"], 1);
    assert!(s["warnings"].as_array().unwrap().is_empty(), "{s}");
}

/// A reused output directory keeps nothing of the previous run; links
/// where opsim writes are refused; no temporary file is left.
#[test]
fn outputs_are_clean_and_never_written_through_links() {
    let dir = temp_dir("outputs");
    let scene = scene_file(&dir, "p.ron", &one_particle("dt: 1e-2, duration: 1", ""));
    let out = dir.join("out");
    let o = run_scene(&scene, &out, &["--frames", "10"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(frame_count(&out), 10);
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let o = run_scene(&scene, &out, &["--frames", "3"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(frame_count(&out), 3, "frames of the previous run were kept");
    assert_eq!(summary(&out)["frames"], 3);
    let rows = std::fs::read_to_string(out.join("metrics.csv")).unwrap();
    assert_eq!(rows.lines().count(), 4, "{rows}");
    assert!(
        out.join("notes.txt").is_file(),
        "a file opsim does not write was removed"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .chain(frame_files(&out))
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .filter(|n| n.contains("tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    // A `frames` link inside --out would send the frames elsewhere.
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let linked = dir.join("linked");
    std::fs::create_dir_all(&linked).unwrap();
    std::os::unix::fs::symlink(&elsewhere, linked.join("frames")).unwrap();
    let o = run_scene(&scene, &linked, &["--frames", "2"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("symbolic link"), "{}", text(&o));
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
    let linked = dir.join("linked2");
    std::fs::create_dir_all(&linked).unwrap();
    std::os::unix::fs::symlink(dir.join("victim.csv"), linked.join("metrics.csv")).unwrap();
    let o = run_scene(&scene, &linked, &["--frames", "2"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!dir.join("victim.csv").exists());
}

/// Messages: the OS error once, a BOM accepted, a huge name elided, a
/// device refused before it is read.
#[test]
fn messages_are_short_and_inputs_bounded() {
    let dir = temp_dir("messages");
    let o = opsim(&["check", dir.join("missing.ron").to_str().unwrap()], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(text(&o).matches("No such file").count(), 1, "{}", text(&o));
    let body = one_particle("dt: 1e-3", "");
    let bom = scene_file(&dir, "bom.ron", &format!("\u{feff}{body}"));
    let o = opsim(&["check", bom.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    let long = body.replacen(
        "name: \"p\"",
        &format!("name: \"{}/\"", "x".repeat(4_000_000)),
        1,
    );
    let long = scene_file(&dir, "long.ron", &long);
    let o = opsim(&["check", long.to_str().unwrap()], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).len() < 1000, "{} characters", text(&o).len());
    let dev = dir.join("dev.ron");
    std::os::unix::fs::symlink("/dev/zero", &dev).unwrap();
    let o = opsim(&["check", dev.to_str().unwrap()], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("not a regular file"), "{}", text(&o));
}

/// Particles that start inside an obstacle are named in a warning by
/// `check` and by `run` (the penalty throws them: a new user's chain inside
/// a ball was flung 124 scene sizes away, and check only advised a
/// smaller step).
#[test]
fn particles_starting_inside_an_obstacle_are_warned_about() {
    let out = temp_dir("inside");
    let scene = out.join("inside.ron");
    std::fs::write(
        &scene,
        r#"(
            name: "inside",
            world: (dt: 0.005, duration: 0.5, frame_rate: 2, linear_damping: 0.1),
            objects: [(name: "rope", material: "cloth", generator: Chain(count: 3, spacing: 1))],
            tools: [(name: "ball", shape: Ball(radius: 4),
                     role: Obstacle(stiffness: 200, margin: 0.5, damping: 1))],
        )"#,
    )
    .unwrap();
    let o = opsim(&["check", "inside.ron"], &out);
    assert!(o.status.success(), "{}", text(&o));
    // All three, the one at the ball's centre included (no projection there).
    assert!(
        text(&o).contains("3 particle(s) start inside obstacle \"ball\""),
        "{}",
        text(&o)
    );
    // The penalty of the particles inside makes the step unstable: the run
    // is asked for all the same, to show the warning.
    let o = run_scene(&scene, &out.join("run"), &["--allow-unstable-step"]);
    assert!(
        text(&o).contains("start inside obstacle \"ball\""),
        "{}",
        text(&o)
    );
    // Outside the ball: no such warning.
    let clear = std::fs::read_to_string(&scene).unwrap().replace(
        "Ball(radius: 4)",
        "Ball(radius: 4), path: [(time: 0, position: (0, 0, 10))]",
    );
    std::fs::write(&scene, clear).unwrap();
    let o = opsim(&["check", "inside.ron"], &out);
    assert!(!text(&o).contains("start inside"), "{}", text(&o));
}

/// An object of a bonded material sampled more coarsely than its bond
/// radius forms no bonds: `check` and `run` say so (a `plastic_clay` sheet
/// of spacing 2 was a cloud of loose particles, with no word).
#[test]
fn particles_without_a_bond_are_warned_about() {
    let out = temp_dir("unbonded");
    let scene = out.join("coarse.ron");
    std::fs::write(
        &scene,
        r#"(
            name: "coarse",
            world: (dt: 0.002, duration: 0.2, frame_rate: 10, linear_damping: 1),
            objects: [(name: "sheet", material: "plastic_clay",
                       generator: HexSheet(nx: 6, ny: 6, spacing: 2))],
        )"#,
    )
    .unwrap();
    let o = opsim(&["check", "coarse.ron"], &out);
    assert!(o.status.success(), "{}", text(&o));
    let needle = "36 of 36 particle(s) of object \"sheet\" have no bond";
    assert!(text(&o).contains(needle), "{}", text(&o));
    assert!(text(&o).contains("bond radius 1.5"), "{}", text(&o));
    let o = run_scene(&scene, &out.join("run"), &[]);
    assert!(text(&o).contains(needle), "{}", text(&o));
    // Sampled within the bond radius: every particle is bonded, no warning.
    let fine = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("spacing: 2", "spacing: 1");
    std::fs::write(&scene, fine).unwrap();
    let o = opsim(&["check", "coarse.ron"], &out);
    assert!(!text(&o).contains("no bond"), "{}", text(&o));
}
