//! `opsim render`: pictures and animations of runs and frame files.

use super::*;

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
    // A frame that is not OBJ is refused as such, not read as an OBJ
    // without vertices.
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
