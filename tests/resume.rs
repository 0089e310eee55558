//! Checkpoints and `opsim run --resume` (op-scene `run::checkpoint`,
//! docs/checkpoints.md): a run killed with SIGKILL at random moments and
//! resumed each time ends with the files of an uninterrupted run, byte for
//! byte (the wall-clock figures aside), at any thread count; a checkpoint
//! of another scene or run, or a damaged one, is refused with exit 2 and
//! nothing written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use op_test_support::{fresh_path, temp_dir};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn opsim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_opsim"))
}

fn run(args: &[&str]) -> Output {
    opsim().args(args).output().expect("run opsim")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every file of a run directory but the checkpoint, with its bytes: the
/// summary without its wall-clock fields (`wall_seconds`, `stages`,
/// `threads`), `metrics.csv` without its `wall_seconds` column.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<(String, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).expect("read the run directory") {
            let path = e.expect("an entry").path();
            if path.is_dir() {
                walk(&path, root, out);
                continue;
            }
            let name = path
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .into_owned();
            let bytes = std::fs::read(&path).expect("read a file");
            let bytes = match name.as_str() {
                "checkpoint.bin" => continue,
                "summary.json" => {
                    let mut s: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                    let map = s.as_object_mut().unwrap();
                    for wall in ["wall_seconds", "stages", "threads"] {
                        assert!(map.remove(wall).is_some(), "summary has {wall}");
                    }
                    serde_json::to_vec_pretty(&s).unwrap()
                }
                "metrics.csv" => String::from_utf8(bytes)
                    .unwrap()
                    .lines()
                    .map(|l| l.rsplit_once(',').expect("a wall_seconds column").0)
                    .collect::<Vec<_>>()
                    .join("\n")
                    .into_bytes(),
                _ => bytes,
            };
            out.push((name, bytes));
        }
    }
    let mut files = Vec::new();
    walk(dir, dir, &mut files);
    files.sort();
    files
}

/// A small deterministic generator (64-bit LCG) for the kill moments.
struct Moments(u64);

impl Moments {
    /// Uniform in `[0, 1)`.
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Runs `scene` uninterrupted, then again killed (SIGKILL) `kills` times
/// at random moments and resumed after each (from scratch while no
/// checkpoint exists yet), alternating 1 and 2 threads; the two runs must
/// end with the same files. With `first_checkpoint`, the first run is let
/// run until it has written a checkpoint, for a scene whose making takes
/// most of its run (so that random kills would rarely let one be written).
/// Returns how many runs the kills ended and how many of the restarts
/// resumed.
fn killed_and_resumed(
    scene: &str,
    extra: &[&str],
    kills: usize,
    seed: u64,
    first_checkpoint: bool,
) -> (usize, usize) {
    let scene = repo().join(scene);
    let scene = scene.to_str().unwrap();
    let reference = fresh_path("resume-reference");
    let clock = Instant::now();
    let out = run(&[
        &["run", scene, "--out", reference.to_str().unwrap()],
        &["--checkpoint-every", "off"][..],
        extra,
    ]
    .concat());
    let uninterrupted = clock.elapsed();
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let dir = fresh_path("resume-killed");
    let dir_arg = dir.to_str().unwrap();
    let mut moments = Moments(seed);
    let mut resumed = 0;
    let mut killed = 0;
    for k in 0..=kills {
        let resume = dir.join("checkpoint.bin").exists();
        resumed += usize::from(resume);
        let threads = if k % 2 == 0 { "2" } else { "1" };
        let mut args = vec!["run", scene, "--out", dir_arg, "--checkpoint-every", "1"];
        args.extend(["--threads", threads]);
        args.extend(extra);
        if resume {
            args.push("--resume");
        }
        let mut child = opsim()
            .args(&args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("start opsim");
        if k == kills {
            let out = child.wait_with_output().expect("the last run ends");
            assert_eq!(out.status.code(), Some(0), "{}", text(&out));
            break;
        }
        // Anywhere in the run, the making of the scene and the writing of
        // checkpoints included; the first checkpoint comes after frame 0,
        // so a run that has none yet (the spiral settles for a third of its
        // run before frame 0) gets long enough to reach it.
        let share = if resume || first_checkpoint {
            2.0 * moments.next() / kills.max(1) as f64
        } else {
            0.4 + 0.4 * moments.next()
        };
        if first_checkpoint && !resume {
            while !dir.join("checkpoint.bin").exists() && child.try_wait().unwrap().is_none() {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        let wait = uninterrupted.mul_f64(share);
        std::thread::sleep(wait.max(Duration::from_millis(5)));
        let _ = child.kill();
        let out = child.wait_with_output().expect("the killed run ends");
        // A run that ended before its kill must have ended well.
        match out.status.code() {
            Some(code) => assert_eq!(code, 0, "{}", text(&out)),
            None => killed += 1,
        }
    }
    let expected = outputs(&reference);
    let got = outputs(&dir);
    assert_eq!(
        expected.iter().map(|(n, _)| n).collect::<Vec<_>>(),
        got.iter().map(|(n, _)| n).collect::<Vec<_>>(),
        "the same files"
    );
    for ((name, a), (_, b)) in expected.iter().zip(&got) {
        assert!(
            a == b,
            "{name} differs after {kills} kills and {resumed} resumes"
        );
    }
    let _ = std::fs::remove_dir_all(&reference);
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!(
        "{scene}: {killed} of {kills} kills ended a run, {resumed} restarts resumed, \
         {} files identical to the uninterrupted run's",
        got.len()
    );
    (killed, resumed)
}

/// A skinned, bonded, plastic, heated sheet with creation rules and an
/// eraser (every stage at once), in all four formats (the USD cache, one
/// file for the run, read back on every resume).
#[test]
fn a_skinned_scene_with_creation_and_erasers_resumes_bit_identically() {
    let (killed, resumed) = killed_and_resumed(
        "tests/data/skinned_cut.ron",
        &["--format", "obj,ply,vtu,usd", "--allow-breakup"],
        10,
        7,
        false,
    );
    assert!(killed >= 5, "only {killed} kills landed in a run");
    assert!(resumed >= 3, "only {resumed} restarts found a checkpoint");
}

/// The demo spiral over its 161 frames, killed 20 times.
#[test]
fn a_long_run_killed_twenty_times_resumes_bit_identically() {
    let (killed, resumed) = killed_and_resumed("scenes/spiral.ron", &[], 20, 11, false);
    assert!(killed >= 10, "only {killed} kills landed in a run");
    assert!(resumed >= 10, "only {resumed} restarts found a checkpoint");
}

/// A scene whose damping is resolved at build (`linear_damping:
/// "Critical"`, `op_scene::damping`): every restart resolves it again to
/// the same numbers, so the resumed run is the uninterrupted one.
#[test]
fn a_critically_damped_scene_resumes_bit_identically() {
    let text = std::fs::read_to_string(repo().join("tests/data/user_spiral_14_quadratic.ron"))
        .expect("read the user's spiral");
    let fixed = "        linear_damping: 0.3,\n        angular_damping: 0.05,\n";
    assert!(text.contains(fixed), "the recipe's damping lines");
    let dir = temp_dir("resume-critical");
    let scene = dir.join("critical.ron");
    std::fs::write(
        &scene,
        text.replace(fixed, "        linear_damping: \"Critical\",\n"),
    )
    .expect("write the scene");
    let (killed, resumed) = killed_and_resumed(scene.to_str().unwrap(), &[], 8, 5, true);
    assert!(killed >= 4, "only {killed} kills landed in a run");
    assert!(resumed >= 3, "only {resumed} restarts found a checkpoint");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A finished short run of the spiral with a checkpoint at its end, in a
/// folder of its own with its own copy of the scene file.
fn finished_run() -> (PathBuf, PathBuf) {
    let dir = temp_dir("resume-refuse");
    let scene = dir.join("spiral.ron");
    std::fs::copy(repo().join("scenes/spiral.ron"), &scene).unwrap();
    let out = dir.join("out");
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "4",
        "--checkpoint-every",
        "2",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    (scene, out)
}

/// Resumes `scene` into `out` with `extra` arguments (`--frames 4` when
/// they give none); must be refused (exit 2) with `message`, leaving every
/// file as it was.
fn refused(scene: &Path, out: &Path, extra: &[&str], message: &str) {
    let before = outputs(out);
    let frames: &[&str] = if extra.contains(&"--frames") {
        &[]
    } else {
        &["--frames", "4"]
    };
    let o = run(&[
        &[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ][..],
        &["--resume"],
        frames,
        extra,
    ]
    .concat());
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let said = text(&o);
    assert!(said.contains("cannot resume from"), "{said}");
    assert!(said.contains(message), "expected {message:?} in: {said}");
    assert!(before == outputs(out), "a refused resume wrote nothing");
}

#[test]
fn resume_refuses_another_scene_or_run() {
    let (scene, out) = finished_run();
    // The finished run resumes to the same end.
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "4",
        "--resume",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // Another frame count, other formats.
    refused(&scene, &out, &["--frames", "5"], "another run");
    refused(&scene, &out, &["--format", "obj,ply"], "another run");
    // The scene file edited: another damping.
    let edited = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("linear_damping: 0.3", "linear_damping: 0.31");
    std::fs::write(&scene, edited).unwrap();
    refused(&scene, &out, &[], "another run");
    let _ = std::fs::remove_dir_all(scene.parent().unwrap());
}

#[test]
fn resume_refuses_a_damaged_or_missing_checkpoint() {
    let (scene, out) = finished_run();
    let path = out.join("checkpoint.bin");
    let good = std::fs::read(&path).unwrap();
    // Truncated: in its payload, and in its header.
    std::fs::write(&path, &good[..good.len() - 100]).unwrap();
    refused(&scene, &out, &[], "truncated");
    std::fs::write(&path, &good[..20]).unwrap();
    refused(&scene, &out, &[], "truncated");
    // One bit flipped, at several places of the payload.
    for at in [good.len() / 3, good.len() / 2, good.len() - 1] {
        let mut bad = good.clone();
        bad[at] ^= 0x10;
        std::fs::write(&path, &bad).unwrap();
        refused(&scene, &out, &[], "damaged");
    }
    // Not a checkpoint at all, or of another format version.
    std::fs::write(&path, b"frame 3\n").unwrap();
    refused(&scene, &out, &[], "not an opsim checkpoint");
    let mut other = good.clone();
    other[b"opsim checkpoint\n".len()] ^= 1;
    std::fs::write(&path, &other).unwrap();
    refused(&scene, &out, &[], "resumes only its own");
    // None at all.
    std::fs::remove_file(&path).unwrap();
    refused(&scene, &out, &[], "cannot read it");
    let _ = std::fs::remove_dir_all(scene.parent().unwrap());
}
