//! `opsim run` and `opsim check`: the files a run writes, its exit codes,
//! and what `check` prints.

use super::*;

/// `run` writes the frames, metrics and summary; the OBJ frames re-read
/// with the expected counts and finite values.
#[test]
fn run_writes_frames_metrics_and_summary() {
    let out = temp_dir("run");
    let scene = repo().join("scenes/two_sheets.ron");
    let o = run_scene(&scene, &out, &["--frames", "4"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(frame_count(&out), 4);
    for k in 0..4 {
        for name in ["upper", "lower"] {
            let path = out.join(format!("frames/{name}/{name}_{k:05}.obj"));
            let obj = wavefront_obj::obj::parse(std::fs::read_to_string(path).unwrap()).unwrap();
            assert_eq!(obj.objects.len(), 1, "one OBJ object per file");
            let o = &obj.objects[0];
            assert_eq!(o.name, name);
            // Discs: a centre and six rim vertices per particle, six triangles.
            assert_eq!(o.vertices.len(), 144 * 7);
            let tris: usize = o.geometry.iter().map(|g| g.shapes.len()).sum();
            assert_eq!(tris, 144 * 6);
            assert!(o
                .vertices
                .iter()
                .all(|v| v.x.is_finite() && v.y.is_finite() && v.z.is_finite()));
            assert!(o
                .normals
                .iter()
                .all(|n| ((n.x * n.x + n.y * n.y + n.z * n.z).sqrt() - 1.0).abs() < 1e-5));
        }
    }
    let csv = std::fs::read_to_string(out.join("metrics.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "frame,time,kinetic,potential,total,oscillation,max_speed,wall_seconds"
    );
    assert_eq!(lines.len(), 5);
    let s = summary(&out);
    for key in [
        "scene",
        "steps",
        "sim_time",
        "wall_seconds",
        "diverged",
        "objects",
    ] {
        assert!(s.get(key).is_some(), "summary lacks {key}");
    }
    assert_eq!(s["objects"].as_array().unwrap().len(), 2);
    assert_eq!(s["objects"][0]["particles"], 144);
}

/// Same frames, byte for byte, at --threads 1 and --threads 2.
#[test]
fn same_frames_at_one_and_two_threads() {
    let scene = repo().join("scenes/sheet.ron");
    let mut outs = Vec::new();
    for t in ["1", "2"] {
        let out = temp_dir(&format!("threads{t}"));
        let o = run_scene(&scene, &out, &["--frames", "6", "--threads", t]);
        assert!(o.status.success(), "{}", text(&o));
        outs.push(out);
    }
    let (a, b) = (frame_files(&outs[0]), frame_files(&outs[1]));
    assert_eq!(frame_count(&outs[0]), 6);
    assert_eq!(a.len(), b.len());
    for (fa, fb) in a.iter().zip(&b) {
        assert!(
            std::fs::read(fa).unwrap() == std::fs::read(fb).unwrap(),
            "{} differs",
            fa.display()
        );
    }
}

/// A forced divergence exits with 3, names step, time and particle, keeps
/// the frames already written valid and says so in the summary.
#[test]
fn divergence_exits_3_and_keeps_valid_frames() {
    let out = temp_dir("diverge");
    let scene = repo().join("tests/data/diverge.ron");
    // Explicit Euler without damping: beyond the edge of stability at any
    // step, refused unless asked.
    let o = run_scene(&scene, &out, &["--allow-unstable-step"]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let msg = text(&o);
    assert!(
        msg.contains("diverged at step") && msg.contains("particle"),
        "{msg}"
    );
    let s = summary(&out);
    assert_eq!(s["diverged"], true);
    for path in frame_files(&out) {
        let t = std::fs::read_to_string(&path).unwrap();
        assert!(
            !t.contains("NaN") && !t.contains("inf"),
            "{}",
            path.display()
        );
        wavefront_obj::obj::parse(t).unwrap();
    }
}

/// Bad input exits with 2 and a message naming the problem, never a panic.
#[test]
fn bad_input_exits_2_with_a_message() {
    let dir = temp_dir("bad");
    let cases: [(&str, &str, &str); 5] = [
        ("bad.yaml", "name: x", "yaml"),
        ("syntax.ron", "(name: \"x\", world: (", "syntax.ron:"),
        ("unknown.ron", "(name: \"x\", wrold: ())", "wrold"),
        ("mass.ron", "(name: \"x\", materials: {\"m\": ()}, objects: [(name: \"a\", material: \"m\", mass: -1, generator: Chain(count: 3, spacing: 1))])", "mass"),
        ("nan.ron", "(name: \"x\", world: (dt: NaN), materials: {\"m\": ()}, objects: [(name: \"a\", material: \"m\", generator: Chain(count: 3, spacing: 1))])", "dt"),
    ];
    for (file, body, expect) in cases {
        let path = dir.join(file);
        std::fs::write(&path, body).unwrap();
        let o = opsim(&["check", path.to_str().unwrap()], &dir);
        assert_eq!(o.status.code(), Some(2), "{file}: {}", text(&o));
        let msg = text(&o);
        assert!(msg.contains(expect), "{file}: {msg}");
        assert!(!msg.contains("panicked"), "{file}: {msg}");
    }
    let o = opsim(&["run", dir.join("missing.ron").to_str().unwrap()], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("missing.ron"));
    let o = opsim(&["run", "--frames", "0", "x.ron"], &dir);
    assert_eq!(o.status.code(), Some(2));
}

/// `check` prints what the scene enables.
#[test]
fn check_prints_enabled_terms() {
    let scene = repo().join("scenes/sheet.ron");
    let o = opsim(&["check", scene.to_str().unwrap()], &repo());
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("lennard_jones") || t.contains("lennard-jones"),
        "{t}"
    );
    assert!(t.contains("coplanarity"), "{t}");
    assert!(
        !t.contains("repulsion"),
        "a one-object scene does not build the repulsion: {t}"
    );
}

/// `check` gives the extent of a hexagonal sheet that is not square (rows
/// are `spacing √3/2` apart, so `nx = ny` is longer than wide) and the
/// `ny` that makes it square; a square one gets no note.
#[test]
fn check_says_when_a_hex_sheet_is_not_square() {
    let dir = temp_dir("hex-aspect");
    let sheet = |nx: usize, ny: usize| {
        format!(
            "(name: \"s\", materials: {{\"m\": ()}}, objects: [(name: \"sheet\", \
             material: \"m\", generator: HexSheet(nx: {nx}, ny: {ny}, spacing: 1))])"
        )
    };
    let path = scene_file(&dir, "long.ron", &sheet(20, 20));
    let o = opsim(&["check", path.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("a sheet 19.5 wide and 16.5 long") && t.contains("ny = 24 makes it square"),
        "{t}"
    );
    let path = scene_file(&dir, "square.ron", &sheet(20, 24));
    let o = opsim(&["check", path.to_str().unwrap()], &dir);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains("makes it square"), "{}", text(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A reader that closes the pipe early (`opsim check SCENE | head -0`)
/// ends `opsim` quietly: exit 0 and no panic message, whether the pipe was
/// closed before or after it wrote.
#[test]
fn closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_opsim"))
        .args(["check", "scenes/fig_07_knife.ron"])
        .current_dir(root)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run opsim");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
}
