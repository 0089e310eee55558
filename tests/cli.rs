//! End-to-end tests of the `opsim` binary (README "Running scenes"): run the real
//! binary in temporary directories and check exit codes, files and values.

use op_test_support::temp_dir;
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

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Whether `path` is a frame file, not a sequence's series file
/// (`<stem>.obj.series`).
fn is_frame_file(path: &Path) -> bool {
    path.extension().is_none_or(|e| e != "series")
}

/// Every frame file of a run (`frames/<stem>/<stem>_00000.obj`, ...), in
/// path order.
fn frame_files(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir.join("frames")).unwrap() {
        let path = e.unwrap().path();
        if path.is_dir() {
            v.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
        } else {
            v.push(path);
        }
    }
    v.retain(|p| is_frame_file(p));
    v.sort();
    v
}

/// The number of frames of a run: frame files per sequence folder, the
/// same for every sequence.
fn frame_count(dir: &Path) -> usize {
    let counts: Vec<usize> = std::fs::read_dir(dir.join("frames"))
        .unwrap()
        .map(|e| {
            std::fs::read_dir(e.unwrap().path())
                .unwrap()
                .filter(|f| is_frame_file(&f.as_ref().unwrap().path()))
                .count()
        })
        .collect();
    assert!(counts.windows(2).all(|w| w[0] == w[1]), "{counts:?}");
    counts.first().copied().unwrap_or(0)
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
    std::fs::create_dir_all(out).unwrap();
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
    // The demo also draws its run: a 3 x 3 contact sheet, path printed.
    let png = out.join("contact_sheet.png");
    assert!(
        text(&o).contains("contact sheet: opsim-out/spiral/contact_sheet.png"),
        "{}",
        text(&o)
    );
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (3 * 360, 3 * 300));
    let drawn = img
        .pixels()
        .filter(|p| i32::from(p.0[2]) > i32::from(p.0[0]) + 40)
        .count();
    assert!(drawn > 2000, "{drawn} particle pixels");
    // And animates it: every frame, at the scene's 2 frames a second.
    assert!(
        text(&o).contains("preview: opsim-out/spiral/preview.gif"),
        "{}",
        text(&o)
    );
    let frames = gif_frames(&out.join("preview.gif"));
    assert_eq!(frames.len() as u64, s["frames"].as_u64().unwrap());
    assert!(frames.iter().all(|f| (f.0, f.1, f.2) == (360, 300, 50)));
}

/// The frames of a GIF file: width, height, delay (hundredths of a
/// second) and RGBA pixels of each, after checking that it loops forever.
fn gif_frames(path: &Path) -> Vec<(u16, u16, u16, Vec<u8>)> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut decoder = options.read_info(std::io::BufReader::new(file)).unwrap();
    let mut frames = Vec::new();
    while let Some(f) = decoder.read_next_frame().unwrap() {
        frames.push((f.width, f.height, f.delay, f.buffer.to_vec()));
    }
    assert_eq!(decoder.repeat(), gif::Repeat::Infinite, "loops forever");
    frames
}

/// `render RUN --out run.gif` animates every frame of the run at its frame
/// rate (spiral: 2 frames a second, 50 hundredths each) from one camera,
/// `--frames A:B:S` a choice (each frame shown for the scene time to the
/// next); an output that is neither `.png` nor `.gif`, or a GIF of one
/// frame file, exits 2 and writes nothing.
#[test]
fn render_animates_a_run_to_gif() {
    let out = temp_dir("render-gif");
    let o = run_scene(&repo().join("scenes/spiral.ron"), &out, &["--frames", "21"]);
    assert!(o.status.success(), "{}", text(&o));
    let render = |name: &str, extra: &[&str]| {
        let mut args = vec![
            "render", ".", "--out", name, "--width", "160", "--height", "120",
        ];
        args.extend_from_slice(extra);
        let o = opsim(&args, &out);
        assert!(o.status.success(), "{extra:?}: {}", text(&o));
        gif_frames(&out.join(name))
    };
    let all = render("run.gif", &[]);
    assert_eq!(all.len(), 21, "every frame");
    assert!(all.iter().all(|f| (f.0, f.1, f.2) == (160, 120, 50)));
    let differing =
        |a: &[u8], b: &[u8]| a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| p != q).count();
    assert!(
        differing(&all[0].3, &all[20].3) > 300,
        "the spiral is pulled open by frame 20"
    );
    assert!(
        (1..21).all(|k| all[k].3 != all[k - 1].3),
        "each frame differs from the one before (its number at least)"
    );
    let chosen = render("chosen.gif", &["--frames", "0:20:10"]);
    assert_eq!(chosen.len(), 3);
    assert!(chosen.iter().all(|f| f.2 == 500), "10 frames at 2 a second");
    assert_eq!(chosen[2].3, all[20].3, "the same camera as the whole run's");
    for (args, says) in [
        (vec!["render", ".", "--out", "run.bmp"], ".png"),
        (vec!["render", ".", "--out", "run"], ".gif"),
        (
            vec![
                "render",
                "frames/spiral/spiral_00000.obj",
                "--out",
                "one.gif",
            ],
            "run directory",
        ),
    ] {
        let o = opsim(&args, &out);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains(says), "{args:?}: {}", text(&o));
    }
    assert!(!out.join("run.bmp").exists() && !out.join("run").exists());
    assert!(!out.join("one.gif").exists());
}

/// Mean picture row of the cloth's (blue) and the tool's (orange) pixels.
fn rows_of_cloth_and_tool(png: &Path) -> (f64, f64) {
    let img = image::open(png).unwrap().to_rgb8();
    let (mut blue, mut orange) = ((0.0, 0.0), (0.0, 0.0));
    for (_, y, p) in img.enumerate_pixels() {
        let [r, _, b] = p.0.map(i32::from);
        if b > r + 40 {
            blue = (blue.0 + f64::from(y), blue.1 + 1.0);
        } else if r > b + 40 {
            orange = (orange.0 + f64::from(y), orange.1 + 1.0);
        }
    }
    assert!(blue.1 > 100.0 && orange.1 > 100.0, "{blue:?} {orange:?}");
    (blue.0 / blue.1, orange.0 / orange.1)
}

/// `render` shows a z-up scene upright by default (the cloth above the
/// sphere it falls on), from any `--view`, and upside down when asked
/// with `--up`; looking straight down takes +y as up; bad directions exit
/// 2.
#[test]
fn render_is_upright_by_default_and_follows_view_and_up() {
    let out = temp_dir("upright");
    // The drape's particles only (its surface would cover the blue discs)
    // and the renderer's own default view.
    let text_of = std::fs::read_to_string(repo().join("scenes/fig_12_drape.ron")).unwrap();
    let particles_only: String = text_of
        .lines()
        .filter(|l| !l.contains("triangulation: true") && !l.contains("view: Some"))
        .collect::<Vec<_>>()
        .join("\n");
    let scene = out.join("drape.ron");
    std::fs::write(&scene, particles_only).unwrap();
    let o = run_scene(&scene, &out, &["--frames", "1"]);
    assert!(o.status.success(), "{}", text(&o));
    let render = |name: &str, extra: &[&str]| {
        let png = out.join(name);
        let mut args = vec![
            "render", ".", "--out", name, "--width", "240", "--height", "180",
        ];
        args.extend_from_slice(extra);
        let o = opsim(&args, &out);
        assert!(o.status.success(), "{extra:?}: {}", text(&o));
        rows_of_cloth_and_tool(&png)
    };
    let (cloth, tool) = render("default.png", &[]);
    assert!(
        cloth < tool,
        "default view: cloth row {cloth}, sphere row {tool}"
    );
    let (cloth, tool) = render("side.png", &["--view", "0,1,0"]);
    assert!(
        cloth + 20.0 < tool,
        "side view: cloth row {cloth}, sphere row {tool}"
    );
    let (cloth, tool) = render("flipped.png", &["--view", "0,1,0", "--up", "0,0,-1"]);
    assert!(
        cloth > tool + 20.0,
        "upside down: cloth row {cloth}, sphere row {tool}"
    );
    // Straight down without an up: the default up (the run's, +z) is
    // along the view, so +y is taken instead of refusing.
    let png = out.join("top.png");
    let o = opsim(
        &["render", ".", "--out", "top.png", "--view", "0,0,-1"],
        &out,
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(png.exists());
    for bad in [
        vec!["--view", "0,0,0"],
        vec!["--view", "1,2"],
        vec!["--up", "0,0,x"],
        vec!["--view", "0,0,-1", "--up", "0,0,1"],
        vec!["--frames", "0"],
    ] {
        let mut args = vec!["render", ".", "--out", "bad.png"];
        args.extend_from_slice(&bad);
        let o = opsim(&args, &out);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {}", text(&o));
        assert!(!out.join("bad.png").exists());
    }
    // A frame that is not OBJ is refused as such (it used to read as
    // an OBJ without vertices).
    std::fs::write(out.join("frame.ply"), "ply\nformat ascii 1.0\nend_header\n").unwrap();
    let o = opsim(&["render", "frame.ply", "--out", "bad.png"], &out);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains(".obj"), "{}", text(&o));
    assert!(!out.join("bad.png").exists());
}

/// `render RUN --frame K` draws frame K alone and `--frames A:B:S` the
/// frames numbered A to B every S, from the camera that frames the whole
/// run; a choice that selects no frame, a reversed range and a frame
/// asked of a single frame file exit 2 and write nothing.
#[test]
fn render_chooses_frames_by_number() {
    let out = temp_dir("render-frames");
    let o = run_scene(&repo().join("scenes/spiral.ron"), &out, &["--frames", "61"]);
    assert!(o.status.success(), "{}", text(&o));
    let render = |name: &str, extra: &[&str]| {
        let mut args = vec![
            "render", ".", "--out", name, "--width", "160", "--height", "120",
        ];
        args.extend_from_slice(extra);
        let o = opsim(&args, &out);
        assert!(o.status.success(), "{extra:?}: {}", text(&o));
        image::open(out.join(name)).unwrap().to_rgb8()
    };
    let first = render("f0.png", &["--frame", "0"]);
    let pulled = render("f60.png", &["--frame", "60"]);
    assert_eq!(first.dimensions(), (160, 120), "one frame, one picture");
    let differing = first
        .pixels()
        .zip(pulled.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differing > 500,
        "frame 0 and frame 60 (the spiral pulled open) look alike: {differing} pixels differ"
    );
    let sheet = render("sheet.png", &["--frames", "0:60:20"]);
    assert_eq!(
        sheet.dimensions(),
        (320, 240),
        "frames 0, 20, 40, 60 in a 2 x 2 grid"
    );
    for (bad, says) in [
        (vec!["--frame", "9999"], "the run has frames 0 to 60"),
        (vec!["--frames", "5:2:1"], "A <= B"),
        (vec!["--frames", "0:10:0"], "step >= 1"),
    ] {
        let mut args = vec!["render", ".", "--out", "bad.png"];
        args.extend_from_slice(&bad);
        let o = opsim(&args, &out);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {}", text(&o));
        assert!(text(&o).contains(says), "{bad:?}: {}", text(&o));
        assert!(!out.join("bad.png").exists());
    }
    let file = frame_files(&out)[0].clone();
    let o = opsim(
        &[
            "render",
            file.to_str().unwrap(),
            "--out",
            "bad.png",
            "--frame",
            "3",
        ],
        &out,
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!out.join("bad.png").exists());
}

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

/// `render` produces a PNG of the requested size for each style.
#[test]
fn render_each_style() {
    let out = temp_dir("render");
    let scene = repo().join("scenes/sheet.ron");
    let o = run_scene(&scene, &out, &["--frames", "2"]);
    assert!(o.status.success(), "{}", text(&o));
    let frame = &frame_files(&out)[1];
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

// ---- Runs that tell the truth (exit 0 only for a run that went right) ----

/// Writes `body` as `name` in `dir` and returns its path.
fn scene_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, body).unwrap();
    path
}

/// One particle, with `world` settings and `extra` top-level fields.
fn one_particle(world: &str, extra: &str) -> String {
    format!(
        "(name: \"p\", world: ({world}), materials: {{\"m\": ()}}, \
         objects: [(name: \"p\", material: \"m\", generator: List(particles: [(position: (0, 0, 0))]))]{extra})"
    )
}

/// Every value in every output file is finite.
fn assert_outputs_finite(out: &Path) {
    let mut files = vec![out.join("summary.json"), out.join("metrics.csv")];
    if out.join("frames").is_dir() {
        files.extend(frame_files(out));
    }
    for f in files.iter().filter(|f| f.is_file()) {
        let t = std::fs::read_to_string(f).unwrap().to_lowercase();
        assert!(
            !t.contains("nan") && !t.contains("inf") && !t.contains("null"),
            "{}",
            f.display()
        );
    }
}

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
             generator: Chain(count: 10, spacing: 1), skin: (primitive: Point, radius: 100, \
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
