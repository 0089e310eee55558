//! Every shipped scene runs to the end without a warning; a finding its
//! header expects (`// expect-warning: TEXT (why)`, as for the tearing
//! scenes) must be printed as `opsim: expected: ...` with TEXT, and its
//! frames hash to the golden value in `tests/data/golden_frames.txt` (a
//! refactoring of the step must not change a bit; a change of the physics
//! named in its commit re-blesses them with `OPSIM_BLESS=1`).
//! Every exported skin frame must be a closed manifold.
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
/// object and frame, less the sequences' `.series` index files, which list
/// the frames' names and times), each its path relative to `frames/` then
/// its bytes, in path order; then the number of files.
fn frames_hash(out: &std::path::Path) -> String {
    let root = out.join("frames");
    let mut files = files_under(&root);
    files.retain(|f| f.extension().is_none_or(|e| e != "series"));
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

/// The skin frames (OBJ files under `frames/*_skin/`) whose triangles do
/// not form a closed, edge-manifold, consistently oriented surface: every
/// directed edge `a -> b` once and its reverse once, no triangle repeating
/// a vertex (the check of `op_implicit::is_closed_oriented_manifold`, on
/// the exported indices), with the reason.
fn open_skin_frames(out: &std::path::Path) -> Vec<String> {
    let mut bad = Vec::new();
    for f in files_under(&out.join("frames")) {
        let skin = f
            .parent()
            .and_then(|d| d.file_name())
            .is_some_and(|d| d.to_string_lossy().ends_with("_skin"));
        if !skin || f.extension().and_then(|e| e.to_str()) != Some("obj") {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let mut directed: std::collections::HashMap<(u64, u64), u32> = Default::default();
        let mut why = None;
        let mut faces = 0;
        for line in text.lines() {
            let Some(rest) = line.strip_prefix("f ") else {
                continue;
            };
            faces += 1;
            let t: Vec<u64> = rest
                .split_whitespace()
                .map(|v| v.split('/').next().unwrap().parse().unwrap())
                .collect();
            if t.len() != 3 || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                why.get_or_insert(format!("degenerate face {t:?}"));
                continue;
            }
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &directed {
            if n != 1 || directed.get(&(b, a)) != Some(&1) {
                why.get_or_insert(format!(
                    "edge {a}-{b} used {n} times, its reverse {:?}",
                    directed.get(&(b, a))
                ));
            }
        }
        if faces == 0 {
            why.get_or_insert("no triangles".to_string());
        }
        if let Some(why) = why {
            bad.push(format!("{}: {why}", f.display()));
        }
    }
    bad
}

fn golden_path() -> PathBuf {
    repo().join("tests/data/golden_frames.txt")
}

/// The expected warnings of a scene: the TEXT of its `expect-warning` lines.
fn expected(text: &str) -> Vec<String> {
    op_scene::schema::expected_warnings(text)
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
                let lines = |prefix: &str| -> Vec<String> {
                    stderr
                        .lines()
                        .filter_map(|l| l.strip_prefix(prefix))
                        .map(str::to_string)
                        .collect()
                };
                let (warnings, found) = (lines("opsim: warning: "), lines("opsim: expected: "));
                let expect = expected(&std::fs::read_to_string(&scene).unwrap());
                let fail = |why: String| failures.lock().unwrap().push(format!("{name}: {why}"));
                if !o.status.success() {
                    fail(format!("exit {:?}: {stderr}", o.status.code()));
                }
                // An expected finding is printed as `expected:`, never as
                // a warning; every other warning is unexpected.
                for w in &warnings {
                    fail(format!("unexpected warning: {w}"));
                }
                for e in &expect {
                    if !found.iter().any(|w| w.contains(e.as_str())) {
                        fail(format!(
                            "expected a finding containing {e:?}, got {found:?}"
                        ));
                    }
                }
                // Every frame of every skin is a closed manifold.
                for bad in open_skin_frames(&out) {
                    fail(format!("skin not closed and manifold: {bad}"));
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
