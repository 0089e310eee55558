//! Frames land in Blender complete and upright: runs every
//! shipped scene with `--format obj,ply` (two frames, or the whole scene
//! when its schedule needs it), imports every object's OBJ file of its
//! first and last frame headless with Blender's OBJ importer (and the
//! legacy one when present) and its PLY file with the PLY importer, then
//! the whole run with the add-on `tools/blender/opsim_import.py` (from the
//! OBJ and from the PLY frames), and checks every object's vertex, edge and
//! face counts and its world-space bounds against the OBJ file (scene z-up
//! is Blender's Z-up), and the add-on's objects, frame rate and frame range
//! against the summary.
//!
//! Runs when `blender` is on PATH (`.ci/run` installs Debian's); skips with
//! a note otherwise.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn blender_available() -> bool {
    Command::new("blender")
        .args(["-b", "--factory-startup", "--version"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// What an importer should show of one OBJ file: counts and scene bounds.
#[derive(Debug)]
struct Expected {
    vertices: usize,
    edges: usize,
    faces: usize,
    min: [f64; 3],
    max: [f64; 3],
}

/// Reads one frame file as Blender should see it: `v` lines (converted
/// back to scene coordinates, y-up to z-up), triangles, and edges (the
/// `l` segments, or the distinct edges of the triangles).
fn expected(path: &Path) -> Expected {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut min, mut max) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let (mut vertices, mut faces) = (0, 0);
    let mut edges = BTreeSet::new();
    let index = |t: &str| t.split('/').next().unwrap().parse::<usize>().unwrap();
    for line in text.lines() {
        let mut t = line.split_whitespace();
        match t.next() {
            Some("v") => {
                let c: Vec<f64> = t.map(|x| x.parse().unwrap()).collect();
                // OBJ (x, y, z) is scene (x, -z, y).
                let scene = [c[0], -c[2], c[1]];
                for k in 0..3 {
                    min[k] = min[k].min(scene[k]);
                    max[k] = max[k].max(scene[k]);
                }
                vertices += 1;
            }
            Some("f") => {
                let v: Vec<usize> = t.map(index).collect();
                for k in 0..v.len() {
                    let (a, b) = (v[k], v[(k + 1) % v.len()]);
                    edges.insert((a.min(b), a.max(b)));
                }
                faces += 1;
            }
            Some("l") => {
                let v: Vec<usize> = t.map(index).collect();
                assert_eq!(v.len(), 2, "{}: {line}", path.display());
                edges.insert((v[0].min(v[1]), v[0].max(v[1])));
            }
            _ => {}
        }
    }
    Expected {
        vertices,
        edges: edges.len(),
        faces,
        min,
        max,
    }
}

/// Runs the shipped scene file `scene` into a fresh folder under `root`:
/// two frames, or the whole scene when it refuses so short a run (the fit
/// scenes release their seeds at t = 2); returns the folder and its frame
/// count.
fn run(scene: &Path, root: &Path) -> (PathBuf, usize) {
    let name = scene.file_stem().unwrap().to_string_lossy().into_owned();
    let out = root.join(&name);
    let go = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_opsim"))
            .arg("run")
            .arg(scene)
            .arg("--out")
            .arg(&out)
            .args(["--threads", "1", "--format", "obj,ply"])
            .args(extra)
            .output()
            .expect("run opsim")
    };
    let mut o = go(&["--frames", "2"]);
    if o.status.code() == Some(2) {
        o = go(&[]);
    }
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let frames = summary["frames"].as_u64().unwrap() as usize;
    (out, frames)
}

/// Checks one object as an importer saw it against its file.
fn check_object(what: &str, seen: &Value, want: &Expected, failures: &mut Vec<String>) {
    let seen = seen.as_array().expect("a list of imported meshes");
    if want.vertices == 0 {
        // An importer makes no object of an empty file; the add-on shows
        // an empty mesh.
        if seen.iter().any(|m| m["vertices"] != 0) {
            failures.push(format!("{what}: empty file, imported {seen:?}"));
        }
        return;
    }
    let [got] = seen.as_slice() else {
        failures.push(format!("{what}: {} objects imported, want 1", seen.len()));
        return;
    };
    let count = |k: &str| got[k].as_u64().unwrap() as usize;
    let counts = (count("vertices"), count("edges"), count("faces"));
    if counts != (want.vertices, want.edges, want.faces) {
        failures.push(format!(
            "{what}: imported (vertices, edges, faces) {counts:?}, file {:?}",
            (want.vertices, want.edges, want.faces)
        ));
    }
    // Upright: Blender's world coordinates are the scene's (z up).
    let size = (0..3)
        .map(|k| want.max[k] - want.min[k])
        .fold(1.0, f64::max);
    for (key, bound) in [("min", want.min), ("max", want.max)] {
        for k in 0..3 {
            let b = got[key][k].as_f64().unwrap();
            if (b - bound[k]).abs() > 1e-4 * size {
                failures.push(format!(
                    "{what}: {key}[{k}] = {b} in Blender, {} in the scene",
                    bound[k]
                ));
            }
        }
    }
}

/// The shipped scenes: `scenes/*.ron` and `scenes/*.json`.
fn shipped_scenes() -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(repo().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("ron" | "json")))
        .collect();
    scenes.sort();
    scenes
}

#[test]
fn shipped_scenes_import_into_blender_complete_and_upright() {
    if !blender_available() {
        eprintln!("note: blender is not on PATH; skipping the Blender import test");
        return;
    }
    let root = std::env::temp_dir().join(format!("opsim-blender-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    // Every shipped scene, its first and last frame; one Blender process.
    let runs: Vec<(PathBuf, Vec<usize>)> = shipped_scenes()
        .iter()
        .map(|scene| {
            let (out, frames) = run(scene, &root);
            (out, vec![0, frames - 1])
        })
        .collect();
    let results = blender_check(&runs);
    let mut failures = Vec::new();
    let mut table = Vec::new();
    for ((out, frames), seen) in runs.iter().zip(&results) {
        check_run(out, frames, seen, &mut failures, &mut table);
    }
    let _ = std::fs::remove_dir_all(&root);
    for row in &table {
        println!("{row}");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Runs `tools/blender/check_run.py` in one Blender process over the runs
/// (`(folder, frames)`): what it saw of each, in order.
fn blender_check(runs: &[(PathBuf, Vec<usize>)]) -> Vec<Value> {
    let o = Command::new("blender")
        .args(["-b", "--factory-startup", "--python"])
        .arg(repo().join("tools/blender/check_run.py"))
        .arg("--")
        .args(runs.iter().map(|(out, frames)| {
            let frames: Vec<String> = frames.iter().map(|k| k.to_string()).collect();
            format!("{}@{}", out.display(), frames.join(","))
        }))
        .output()
        .expect("run blender");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let results: Vec<Value> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("OPSIM-CHECK "))
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(
        results.len(),
        runs.len(),
        "blender checked {} of {} runs (exit {:?}):\n{stdout}\n{}",
        results.len(),
        runs.len(),
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    results
}

/// Checks what Blender saw of the run in `out` (its `frames`): the
/// add-on's scenes, then every importer's objects against the OBJ files;
/// adds the add-on's last frame to `table`.
fn check_run(
    out: &Path,
    frames: &[usize],
    seen: &Value,
    failures: &mut Vec<String>,
    table: &mut Vec<String>,
) {
    let scene = out.file_name().unwrap().to_string_lossy().into_owned();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let sequences = summary["files"]["sequences"].as_array().unwrap();
    let last = frames[frames.len() - 1];
    check_addon_scenes(&scene, &summary, seen, last, failures);
    let importers = importers(seen);
    for &k in frames {
        for s in sequences {
            let (name, stem) = (s["name"].as_str().unwrap(), s["stem"].as_str().unwrap());
            let file = out.join(format!("frames/{stem}/{stem}_{k:05}.obj"));
            let want = expected(&file);
            for importer in &importers {
                let got = &seen[importer.as_str()][k.to_string()][name];
                check_object(
                    &format!("{scene} frame {k} {name} ({importer})"),
                    got,
                    &want,
                    failures,
                );
                if k == last && importer.as_str() == "addon" {
                    table.push(format!(
                        "{scene} frame {k} {name}: file {} vertices {} faces, Blender {} \
                         vertices {} faces",
                        want.vertices, want.faces, got[0]["vertices"], got[0]["faces"]
                    ));
                }
            }
        }
    }
}

/// The add-on's scenes (from the OBJ and from the PLY frames) against the
/// run's `summary`: frame rate, frame range `0..=last`, objects.
fn check_addon_scenes(
    scene: &str,
    summary: &Value,
    seen: &Value,
    last: usize,
    failures: &mut Vec<String>,
) {
    let sequences = summary["files"]["sequences"].as_array().unwrap();
    let names: Vec<&str> = sequences
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    let rate = summary["frame_rate"].as_f64().unwrap();
    for key in ["addon_scene", "addon_ply_scene"] {
        let scene_info = &seen[key];
        if (scene_info["fps"].as_f64().unwrap() - rate).abs() > 1e-6 * rate {
            failures.push(format!(
                "{scene}: {key} fps {}, run {rate}",
                scene_info["fps"]
            ));
        }
        if scene_info["frame_end"] != last || scene_info["frame_start"] != 0 {
            failures.push(format!("{scene}: {key} frame range {scene_info}"));
        }
        let created: Vec<&str> = scene_info["objects"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        if created != names {
            failures.push(format!("{scene}: {key} objects {created:?}, run {names:?}"));
        }
    }
}

/// The importers Blender ran: every one, the PLY ones included, must show
/// the OBJ file's counts and bounds; the four expected must be there.
fn importers(seen: &Value) -> Vec<&String> {
    let importers: Vec<&String> = seen
        .as_object()
        .unwrap()
        .keys()
        .filter(|k| !k.ends_with("_scene") && *k != "run")
        .collect();
    for want in ["obj_import", "ply", "addon", "addon_ply"] {
        assert!(
            importers.iter().any(|k| *k == want),
            "{want}: {importers:?}"
        );
    }
    importers
}
