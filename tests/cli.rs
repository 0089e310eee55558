//! End-to-end tests of the `opsim` binary (README "Running scenes"): run the real
//! binary in temporary directories and check exit codes, files and values.

use op_test_support::temp_dir;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "cli/commands.rs"]
mod commands;
#[path = "cli/honest_runs.rs"]
mod honest_runs;
#[path = "cli/render.rs"]
mod render;

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
