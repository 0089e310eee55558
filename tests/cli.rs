//! End-to-end tests of the `opsim` binary (DESIGN §6 contract): run the real
//! binary in temporary directories and check exit codes, files and values.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn opsim(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_opsim"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run opsim")
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("opsim-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn frames(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v
}

/// `opsim run SCENE --out OUT [extra..]` in `out`; returns the output.
fn run_scene(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    opsim(&args, out)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// No argument: the embedded demo runs from any directory, writes under
/// ./opsim-out/<scene>/ and prints that path.
#[test]
fn no_argument_runs_the_demo() {
    let cwd = temp_dir("demo");
    let o = opsim(&[], &cwd);
    assert!(o.status.success(), "{}", text(&o));
    let out = cwd.join("opsim-out").join("spiral");
    assert!(text(&o).contains("opsim-out/spiral"), "{}", text(&o));
    assert!(out.join("summary.json").is_file());
    assert!(out.join("metrics.csv").is_file());
    let s = summary(&out);
    assert_eq!(s["diverged"], false);
    assert!(s["objects"][0]["rest_shape_error_final"]
        .as_f64()
        .unwrap()
        .is_finite());
}

/// `run` writes the frames, metrics and summary; the OBJ frames re-read
/// with the expected counts and finite values.
#[test]
fn run_writes_frames_metrics_and_summary() {
    let out = temp_dir("run");
    let scene = repo().join("scenes/two_sheets.ron");
    let o = run_scene(&scene, &out, &["--frames", "4"]);
    assert!(o.status.success(), "{}", text(&o));
    let f = frames(&out);
    assert_eq!(f.len(), 4);
    for path in &f {
        let obj = wavefront_obj::obj::parse(std::fs::read_to_string(path).unwrap()).unwrap();
        assert_eq!(obj.objects.len(), 2, "one OBJ object per scene object");
        for (o, name) in obj.objects.iter().zip(["upper", "lower"]) {
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
    let (a, b) = (frames(&outs[0]), frames(&outs[1]));
    assert_eq!(a.len(), 6);
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
    let o = run_scene(&scene, &out, &[]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let msg = text(&o);
    assert!(
        msg.contains("diverged at step") && msg.contains("particle"),
        "{msg}"
    );
    let s = summary(&out);
    assert_eq!(s["diverged"], true);
    for path in frames(&out) {
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

/// `render` produces a PNG of the requested size for each style.
#[test]
fn render_each_style() {
    let out = temp_dir("render");
    let scene = repo().join("scenes/sheet.ron");
    let o = run_scene(&scene, &out, &["--frames", "2"]);
    assert!(o.status.success(), "{}", text(&o));
    let frame = &frames(&out)[1];
    for style in ["axes", "discs", "wireframe", "shaded"] {
        let png = out.join(format!("{style}.png"));
        let o = opsim(
            &[
                "render",
                frame.to_str().unwrap(),
                "--out",
                png.to_str().unwrap(),
                "--style",
                style,
                "--width",
                "320",
                "--height",
                "200",
            ],
            &out,
        );
        assert!(o.status.success(), "{style}: {}", text(&o));
        let img = image::open(&png).unwrap();
        assert_eq!((img.width(), img.height()), (320, 200));
        let rgb = img.to_rgb8();
        let drawn = rgb.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        assert!(drawn > 500, "{style}: only {drawn} pixels drawn");
    }
    let sheet = out.join("sheet.png");
    let o = opsim(
        &[
            "render",
            out.to_str().unwrap(),
            "--out",
            sheet.to_str().unwrap(),
            "--width",
            "100",
            "--height",
            "80",
            "--frames",
            "2",
        ],
        &out,
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(sheet.is_file());
    let o = opsim(
        &[
            "render",
            frame.to_str().unwrap(),
            "--out",
            "x.png",
            "--style",
            "plasma",
        ],
        &out,
    );
    assert_eq!(o.status.code(), Some(2));
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
