//! Structure-aware fuzzing of the `opsim` binary: mutants of the shipped
//! scenes' *structure* rather than their numbers (`tests/fuzz_scenes.rs`).
//! Each mutant is a shipped scene read through op-scene, turned into JSON
//! and changed by one to three of:
//!
//! - an object duplicated 2 to 1,000 times under new names (overlapping
//!   copies: the work estimate and the stable-step sample must stay
//!   bounded in total, not per object);
//! - an object renamed (empty, with a slash, 300 or 5,000 characters, like
//!   another object's name);
//! - the generators of two objects swapped, or one taken from another
//!   scene;
//! - a generator replaced by a `List` of 2 to 100,000 particles, spread in
//!   a box or all on one point;
//! - a section grafted from another scene (creation rules, a settle
//!   phase, heat, skins, tools, forces, initial velocities);
//! - a tool path of many keyframes.
//!
//! Every mutant is checked (`opsim check`) and, unless refused, run for three
//! frames under a particle-step budget. It must exit 0, 2 or 3, never panic,
//! the run must end within [`RUN_BOUND`] CPU seconds, and no output file may
//! hold NaN or infinity. A `check` beyond [`CHECK_BOUND`] CPU seconds or
//! [`CHECK_MEMORY_KB`] is counted (`check unbounded`) and fails the test
//! only with `OPSIM_FUZZ_STRICT=1` (times are CPU seconds of all the
//! process's threads, so a loaded machine does not inflate them).
//!
//! Two tests: 200 mutants with the tests (`OPSIM_FUZZ_STRUCT_CI_MUTANTS`
//! sets the count), and the long run by hand, 2,000 by default:
//! `OPSIM_FUZZ_STRUCT_MUTANTS=2000 OPSIM_FUZZ_STRUCT_SEED=11 cargo test
//! --profile ci --test fuzz_structure -- --ignored --nocapture`, with
//! `OPSIM_FUZZ_VERBOSE=1` to print each mutant's class and
//! `OPSIM_FUZZ_KEEP=DIR` to keep the mutants of the unusual classes;
//! `OPSIM_FUZZ_DUMP=DIR` with `OPSIM_FUZZ_STRUCT_FIRST=K` and
//! `OPSIM_FUZZ_STRUCT_MUTANTS=K+1` writes mutant K without running it.

mod fuzz_support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use fuzz_support::{non_finite_outputs, opsim, Outcome};
use op_test_support::Rng;
use serde_json::{json, Value};

/// Bound of `opsim check` on one mutant, in CPU seconds (all threads, so
/// a bound on the wall time of one core, and one that another build on a
/// loaded machine does not trip); killed at four times it in wall time.
const CHECK_BOUND: Duration = Duration::from_secs(5);
/// Peak memory bound of `opsim check` on one mutant, KiB (1 GiB).
const CHECK_MEMORY_KB: u64 = 1 << 20;
/// Bound of one mutant's three-frame run (one thread), in CPU seconds;
/// killed at three times it in wall time.
const RUN_BOUND: Duration = Duration::from_secs(90);
/// The particle-step budget of each run (as in `tests/fuzz_scenes.rs`).
const BUDGET: &str = "1e7";
/// Largest size of the copies of a duplicated object, as JSON text.
const DUPLICATES_BYTES: usize = 32 << 20;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every shipped scene as JSON, its relative file paths made absolute.
fn scenes() -> Vec<(String, Value)> {
    let mut out = Vec::new();
    for dir in ["scenes", "scenes/extreme", "scenes/cookbook"] {
        let Ok(entries) = std::fs::read_dir(repo().join(dir)) else {
            continue;
        };
        let mut paths: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
        paths.sort();
        for p in paths {
            if !matches!(p.extension().and_then(|e| e.to_str()), Some("ron" | "json")) {
                continue;
            }
            let scene = op_scene::load_scene(&p).expect("a shipped scene loads");
            let mut value = serde_json::to_value(&scene).expect("a scene is JSON");
            absolute_paths(&mut value, p.parent().unwrap());
            out.push((p.file_name().unwrap().to_string_lossy().into_owned(), value));
        }
    }
    out
}

/// Makes every `"path": "<relative file>"` absolute against `dir` (the
/// mutants are written elsewhere).
fn absolute_paths(v: &mut Value, dir: &Path) {
    match v {
        Value::Object(map) => {
            for (k, x) in map.iter_mut() {
                match x {
                    Value::String(s) if k == "path" && Path::new(s.as_str()).is_relative() => {
                        *s = dir.join(&*s).to_string_lossy().into_owned();
                    }
                    _ => absolute_paths(x, dir),
                }
            }
        }
        Value::Array(a) => a.iter_mut().for_each(|x| absolute_paths(x, dir)),
        _ => {}
    }
}

fn objects(scene: &mut Value) -> &mut Vec<Value> {
    scene["objects"].as_array_mut().expect("objects")
}

/// One structural mutation of `scene` (others: the other shipped scenes,
/// for grafts); says what it did.
fn mutate(scene: &mut Value, others: &[(String, Value)], rng: &mut Rng) -> String {
    let n = objects(scene).len();
    if n == 0 {
        return "nothing (no object)".into();
    }
    let k = rng.below(n);
    match rng.below(7) {
        0 => {
            let wanted = [2, 5, 50, 1000][rng.below(4)];
            let original = objects(scene)[k].clone();
            // At most DUPLICATES_BYTES of copies: a list of 100,000
            // particles copied a thousand times would take this test
            // tens of gigabytes as JSON values (and the scene file is
            // refused beyond 256 MiB anyway).
            let size = serde_json::to_string(&original).map_or(1, |t| t.len().max(1));
            let copies = wanted.min((DUPLICATES_BYTES / size).max(1));
            let name = original["name"].as_str().unwrap_or("o").to_string();
            for c in 0..copies {
                let mut copy = original.clone();
                copy["name"] = json!(format!("{name}_dup{c}"));
                objects(scene).push(copy);
            }
            format!("object {k} duplicated {copies} times")
        }
        1 => {
            let other = objects(scene)[(k + 1) % n]["name"].clone();
            let names = [
                json!(""),
                json!("a/b"),
                json!("x".repeat(300)),
                json!("y".repeat(5000)),
                json!("été ☃"),
                other,
            ];
            let pick = rng.below(names.len());
            objects(scene)[k]["name"] = names[pick].clone();
            format!("object {k} renamed ({pick})")
        }
        2 => {
            let (j, from) = if n > 1 && rng.below(2) == 0 {
                let j = (k + 1 + rng.below(n - 1)) % n;
                (j, objects(scene)[j]["generator"].clone())
            } else {
                let (name, other) = &others[rng.below(others.len())];
                let os = other["objects"].as_array().unwrap();
                let j = rng.below(os.len().max(1));
                let g = os.get(j).map_or(Value::Null, |o| o["generator"].clone());
                return {
                    objects(scene)[k]["generator"] = g;
                    format!("object {k} takes the generator of {name} object {j}")
                };
            };
            let mine = std::mem::replace(&mut objects(scene)[k]["generator"], from);
            objects(scene)[j]["generator"] = mine;
            format!("generators of objects {k} and {j} swapped")
        }
        3 => {
            let count = [2, 1000, 20_000, 100_000][rng.below(4)];
            let on_a_point = rng.below(2) == 0;
            let side = (count as f64).cbrt();
            let particles: Vec<Value> = (0..count)
                .map(|_| {
                    let p = if on_a_point {
                        [0.0; 3]
                    } else {
                        [0, 1, 2].map(|_| rng.uniform(0.0, side))
                    };
                    json!({ "position": p })
                })
                .collect();
            objects(scene)[k]["generator"] = json!({ "List": { "particles": particles } });
            format!("object {k} made a list of {count} particles (on a point: {on_a_point})")
        }
        4 => graft(scene, others, rng),
        5 => {
            let v = [rng.uniform(-50.0, 50.0), 0.0, rng.uniform(-50.0, 50.0)];
            objects(scene)[k]["velocity"] = json!(v);
            let settle = [0.0, 1.0, 40.0][rng.below(3)];
            scene["world"]["settle"] = json!(settle);
            format!("object {k} given velocity {v:?}, settle {settle}")
        }
        _ => {
            let Some(tools) = scene.get_mut("tools").and_then(Value::as_array_mut) else {
                return graft(scene, others, rng);
            };
            if tools.is_empty() {
                return "nothing (no tool)".into();
            }
            let t = rng.below(tools.len());
            let count = [10, 1000, 100_000][rng.below(3)];
            let keys: Vec<Value> = (0..count)
                .map(
                    |i| json!({ "time": i as f64 * 0.01, "position": [i as f64 * 1e-3, 0.0, 0.0] }),
                )
                .collect();
            tools[t]["path"] = json!(keys);
            format!("tool {t} given a path of {count} keyframes")
        }
    }
}

/// A section of another scene put into `scene`: creation rules, skins,
/// tools, forces, the settle phase or heat.
fn graft(scene: &mut Value, others: &[(String, Value)], rng: &mut Rng) -> String {
    let (name, other) = &others[rng.below(others.len())];
    let sections = ["creation", "skins", "tools", "forces", "presets"];
    let s = sections[rng.below(sections.len())];
    if rng.below(3) == 0 {
        for field in ["settle", "heat", "integrator"] {
            scene["world"][field] = other["world"][field].clone();
        }
        return format!("world settle, heat and integrator of {name}");
    }
    match other.get(s) {
        Some(v) => {
            scene[s] = v.clone();
            format!("{s} of {name}")
        }
        None => "nothing (no section)".into(),
    }
}

/// The classes of outcomes counted.
#[derive(Default)]
struct Tally {
    counts: BTreeMap<&'static str, usize>,
    failures: Vec<String>,
}

/// A few hundred mutants run with the tests (`OPSIM_FUZZ_STRUCT_CI_MUTANTS`,
/// default 200, seed 2026): about a minute on the 2-core machine.
#[test]
fn structural_mutants_are_checked_and_run_within_bounds() {
    let count = fuzz_support::env_or("OPSIM_FUZZ_STRUCT_CI_MUTANTS", 200);
    fuzz(0..count, 2026);
}

/// The long run, by hand: `OPSIM_FUZZ_STRUCT_MUTANTS` (default 2,000) and
/// `OPSIM_FUZZ_STRUCT_SEED` (default 5): `cargo test --profile ci --test
/// fuzz_structure -- --ignored --nocapture`.
#[test]
#[ignore = "about 9 minutes on the 2-core machine; run by hand"]
fn many_structural_mutants() {
    let count = fuzz_support::env_or("OPSIM_FUZZ_STRUCT_MUTANTS", 2000);
    let seed = fuzz_support::env_or("OPSIM_FUZZ_STRUCT_SEED", 5);
    // To go on with a run stopped part way: the first mutant to make.
    let first = fuzz_support::env_or("OPSIM_FUZZ_STRUCT_FIRST", 0);
    fuzz(first..count, seed);
}

/// Makes, checks and runs mutants `range` from `seed` on two workers,
/// prints the counts by class and fails on any failure found.
fn fuzz(range: std::ops::Range<usize>, seed: u64) {
    let verbose = std::env::var_os("OPSIM_FUZZ_VERBOSE").is_some();
    // Where to keep the mutants of the classes worth a look (all but
    // "ran", the refusals by check and run's refusals of a budget or an
    // unstable step), as m<k>.json.
    let keep = std::env::var_os("OPSIM_FUZZ_KEEP").map(PathBuf::from);
    // Where to write every mutant, as m<k>.json, without checking or
    // running it (to look at one mutant of a long run).
    let dump = std::env::var_os("OPSIM_FUZZ_DUMP").map(PathBuf::from);
    let scenes = scenes();
    let root = std::env::temp_dir().join(format!(
        "opsim-fuzz-structure-{}-{seed}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let next = AtomicUsize::new(range.start);
    let tally = Mutex::new(Tally::default());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= range.end {
                    break;
                }
                let mut rng = Rng::new(seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
                let (name, original) = &scenes[rng.below(scenes.len())];
                let mut scene = original.clone();
                let what: Vec<String> = (0..1 + rng.below(3))
                    .map(|_| mutate(&mut scene, &scenes, &mut rng))
                    .collect();
                let label = format!("mutant {k} of {name} ({})", what.join("; "));
                let work = root.join(format!("m{k}"));
                std::fs::create_dir_all(&work).unwrap();
                let file = work.join("scene.json");
                std::fs::write(&file, serde_json::to_vec(&scene).unwrap()).unwrap();
                if let Some(dump) = &dump {
                    let _ = std::fs::create_dir_all(dump);
                    std::fs::copy(&file, dump.join(format!("m{k}.json"))).unwrap();
                    eprintln!("{label}: written");
                    let _ = std::fs::remove_dir_all(&work);
                    continue;
                }
                let (class, failure) = try_mutant(&file, &work.join("out"));
                if verbose {
                    eprintln!("{label}: {class}");
                }
                let usual = matches!(
                    class,
                    "ran"
                        | "refused by check"
                        | "over the run's budget"
                        | "unstable step"
                        | "too long for 3 frames"
                );
                if let (Some(keep), false) = (&keep, usual) {
                    let _ = std::fs::create_dir_all(keep);
                    let _ = std::fs::copy(&file, keep.join(format!("m{k}.json")));
                }
                let mut t = tally.lock().unwrap();
                *t.counts.entry(class).or_default() += 1;
                if let Some(f) = failure {
                    t.failures.push(format!("{label}: {f}"));
                }
                drop(t);
                let _ = std::fs::remove_dir_all(&work);
            });
        }
    });
    let _ = std::fs::remove_dir_all(&root);
    let t = tally.into_inner().unwrap();
    eprintln!(
        "structural fuzz: mutants {range:?} (seed {seed}): {:?}",
        t.counts
    );
    assert!(t.failures.is_empty(), "{}", t.failures.join("\n"));
}

/// Checks and runs one mutant; its class, and what is wrong when
/// something is.
fn try_mutant(file: &Path, out: &Path) -> (&'static str, Option<String>) {
    let scene = file.to_str().unwrap();
    let check = opsim(&["check", scene], CHECK_BOUND * 4);
    let msg = check.stderr;
    let short = |m: &str| m.chars().take(400).collect::<String>();
    let panicked = |m: &str| m.contains("internal error") || m.contains("panicked");
    if panicked(&msg) {
        return (
            "check panic",
            Some(format!("check panicked: {}", short(&msg))),
        );
    }
    let timed_out = matches!(check.outcome, Outcome::Timeout);
    if timed_out || check.cpu > CHECK_BOUND.as_secs_f64() || check.peak_kb > CHECK_MEMORY_KB {
        let strict = std::env::var_os("OPSIM_FUZZ_STRICT").is_some();
        return (
            "check unbounded",
            strict.then(|| {
                format!(
                    "check took {:.1} s of CPU ({:.1} s wall) and {} KiB",
                    check.cpu, check.wall, check.peak_kb
                )
            }),
        );
    }
    match check.outcome {
        Outcome::Exit(0) => {}
        Outcome::Exit(2) => return ("refused by check", None),
        other => {
            return (
                "check failed",
                Some(format!("check: {other:?}: {}", short(&msg))),
            )
        }
    }
    let args = [
        "run",
        scene,
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "3",
        "--threads",
        "1",
        "--max-particle-steps",
        BUDGET,
    ];
    let run = opsim(&args, RUN_BOUND * 3);
    let msg = run.stderr;
    if panicked(&msg) {
        return ("run panic", Some(format!("run panicked: {}", short(&msg))));
    }
    let bad = non_finite_outputs(out);
    if !bad.is_empty() {
        return (
            "non-finite output",
            Some(format!("non-finite values in {bad:?}")),
        );
    }
    if matches!(run.outcome, Outcome::Timeout) || run.cpu > RUN_BOUND.as_secs_f64() {
        let took = format!("ran {:.0} s of CPU, {:.0} s wall", run.cpu, run.wall);
        return ("run unbounded", Some(took));
    }
    match run.outcome {
        Outcome::Exit(0) => ("ran", None),
        // The run's particle-step budget, which check did not apply.
        Outcome::Exit(2) if msg.contains("--no-work-limits") => ("over the run's budget", None),
        // A step beyond the stable step, which check warns of and run
        // refuses.
        Outcome::Exit(2) if msg.contains("--allow-unstable-step") => ("unstable step", None),
        // A field that needs a longer run than three frames.
        Outcome::Exit(2) if msg.contains("(set by --frames") => ("too long for 3 frames", None),
        // A start check accepted that ended in a bad-input error.
        Outcome::Exit(2) => ("refused by run", None),
        Outcome::Exit(3) => ("diverged", None),
        other => ("run failed", Some(format!("{other:?}: {}", short(&msg)))),
    }
}
