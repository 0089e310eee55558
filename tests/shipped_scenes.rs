//! Every shipped scene runs to the end without a warning, unless its header
//! says which one it expects (`// expect-warning: TEXT (why)`: a warning
//! containing TEXT must then be printed, as for the tearing scenes), and its
//! frames hash to the golden value in `tests/data/golden_frames.txt` (a
//! refactoring of the step must not change a bit; a change of the physics
//! named in its commit re-blesses them with `OPSIM_BLESS=1`).
//! `OPSIM_BIN` runs another build of `opsim` (to bless the goldens of an
//! earlier commit).

use std::path::PathBuf;
use std::process::Command;
use std::sync::Mutex;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir`, recursively.
fn files_under(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten() {
        let path = e.unwrap().path();
        if path.is_dir() {
            files.extend(files_under(&path));
        } else {
            files.push(path);
        }
    }
    files
}

/// FNV-1a over the run's frame files (every file under `frames/`, one per
/// object and frame), each its path relative to `frames/` then its bytes,
/// in path order; then the number of files.
fn frames_hash(out: &std::path::Path) -> String {
    let root = out.join("frames");
    let mut files = files_under(&root);
    files.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for f in &files {
        let name = f
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        for b in name
            .into_bytes()
            .into_iter()
            .chain(std::fs::read(f).unwrap())
        {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    format!("{h:016x} {}", files.len())
}

fn golden_path() -> PathBuf {
    repo().join("tests/data/golden_frames.txt")
}

/// The expected warnings of a scene: the TEXT of its `expect-warning` lines.
fn expected(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("// expect-warning: "))
        .map(|t| t.split(" (").next().unwrap_or(t).trim().to_string())
        .collect()
}

#[test]
fn shipped_scenes_run_without_unexpected_warnings() {
    let mut scenes: Vec<PathBuf> = ["scenes", "scenes/cookbook"]
        .iter()
        .flat_map(|d| std::fs::read_dir(repo().join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("ron" | "json")))
        .collect();
    scenes.sort();
    let root = std::env::temp_dir().join(format!("opsim-shipped-{}", std::process::id()));
    let failures = Mutex::new(Vec::new());
    let hashes = Mutex::new(Vec::new());
    let bin = std::env::var("OPSIM_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_opsim").into());
    let queue = Mutex::new(scenes.clone());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let Some(scene) = queue.lock().unwrap().pop() else {
                    break;
                };
                let name = scene.file_stem().unwrap().to_string_lossy().into_owned();
                let out = root.join(&name);
                let o = Command::new(&bin)
                    .args([
                        "run",
                        scene.to_str().unwrap(),
                        "--out",
                        out.to_str().unwrap(),
                    ])
                    .args(["--threads", "1"])
                    .output()
                    .expect("run opsim");
                let stderr = String::from_utf8_lossy(&o.stderr);
                let warnings: Vec<&str> = stderr
                    .lines()
                    .filter_map(|l| l.strip_prefix("opsim: warning: "))
                    .collect();
                let expect = expected(&std::fs::read_to_string(&scene).unwrap());
                let fail = |why: String| failures.lock().unwrap().push(format!("{name}: {why}"));
                if !o.status.success() {
                    fail(format!("exit {:?}: {stderr}", o.status.code()));
                }
                for w in &warnings {
                    if !expect.iter().any(|e| w.contains(e.as_str())) {
                        fail(format!("unexpected warning: {w}"));
                    }
                }
                for e in &expect {
                    if !warnings.iter().any(|w| w.contains(e.as_str())) {
                        fail(format!(
                            "expected a warning containing {e:?}, got {warnings:?}"
                        ));
                    }
                }
                hashes
                    .lock()
                    .unwrap()
                    .push(format!("{name} {}", frames_hash(&out)));
                let _ = std::fs::remove_dir_all(&out);
            });
        }
    });
    let _ = std::fs::remove_dir_all(&root);
    let mut hashes = hashes.into_inner().unwrap();
    hashes.sort();
    let mut failures = failures.into_inner().unwrap();
    if std::env::var_os("OPSIM_BLESS").is_some() {
        std::fs::write(golden_path(), hashes.join("\n") + "\n").unwrap();
    } else {
        let golden = std::fs::read_to_string(golden_path()).unwrap_or_default();
        let golden: Vec<&str> = golden.lines().collect();
        for h in &hashes {
            if !golden.contains(&h.as_str()) {
                failures.push(format!(
                    "frames differ from tests/data/golden_frames.txt: {h} (re-bless with \
                     OPSIM_BLESS=1 only for a change of the physics named in the commit)"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
