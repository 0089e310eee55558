//! Every shipped scene runs to the end without a warning, unless its header
//! says which one it expects (`// expect-warning: TEXT (why)`: a warning
//! containing TEXT must then be printed, as for the tearing scenes).

use std::path::PathBuf;
use std::process::Command;
use std::sync::Mutex;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
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
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(repo().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("ron" | "json")))
        .collect();
    scenes.sort();
    let root = std::env::temp_dir().join(format!("opsim-shipped-{}", std::process::id()));
    let failures = Mutex::new(Vec::new());
    let queue = Mutex::new(scenes.clone());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let Some(scene) = queue.lock().unwrap().pop() else {
                    break;
                };
                let name = scene.file_stem().unwrap().to_string_lossy().into_owned();
                let out = root.join(&name);
                let o = Command::new(env!("CARGO_BIN_EXE_opsim"))
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
                let mut fail =
                    |why: String| failures.lock().unwrap().push(format!("{name}: {why}"));
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
                let _ = std::fs::remove_dir_all(&out);
            });
        }
    });
    let _ = std::fs::remove_dir_all(&root);
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
