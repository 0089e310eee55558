//! What the fuzz tests share (`tests/fuzz_scenes.rs`, numbers of scenes
//! mutated; `tests/fuzz_structure.rs`, their structure): running the
//! binary under a time bound while watching its memory, and finding
//! non-finite numbers in a run's outputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How a mutant ended.
#[derive(Debug)]
pub enum Outcome {
    /// The exit code (-1 when killed by a signal).
    Exit(i32),
    /// Killed at the time bound.
    Timeout,
}

/// Runs `opsim` with `args` under the wall-clock `bound` (killed beyond
/// it). Returns how it ended, its standard error (at most 1 MiB), its wall
/// seconds and its peak resident memory in KiB (sampled every 20 ms from
/// `/proc`; 0 where that does not exist).
pub fn opsim(args: &[&str], bound: Duration) -> (Outcome, String, f64, u64) {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_opsim"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run opsim");
    let stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        use std::io::Read;
        let mut s = String::new();
        let _ = std::io::BufReader::new(stderr)
            .take(1 << 20)
            .read_to_string(&mut s);
        s
    });
    let status = format!("/proc/{}/status", child.id());
    let mut peak = 0;
    let outcome = loop {
        // VmHWM: the peak resident set so far.
        if let Ok(s) = std::fs::read_to_string(&status) {
            if let Some(kb) = s
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            {
                peak = peak.max(kb);
            }
        }
        if let Some(status) = child.try_wait().unwrap() {
            break Outcome::Exit(status.code().unwrap_or(-1));
        }
        if start.elapsed() > bound {
            let _ = child.kill();
            let _ = child.wait();
            break Outcome::Timeout;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let msg = reader.join().unwrap_or_default();
    (outcome, msg, start.elapsed().as_secs_f64(), peak)
}

/// Files under `out` holding a non-finite number: a `null` value in
/// `summary.json` (serde's form of NaN and infinity), a field of
/// `metrics.csv` or a coordinate of a frame that does not parse as a finite
/// number.
pub fn non_finite_outputs(out: &Path) -> Vec<PathBuf> {
    fn has_null(v: &serde_json::Value) -> bool {
        match v {
            serde_json::Value::Null => true,
            serde_json::Value::Array(a) => a.iter().any(has_null),
            serde_json::Value::Object(o) => o.values().any(has_null),
            _ => false,
        }
    }
    let finite = |t: &str| t.parse::<f64>().is_ok_and(f64::is_finite);
    let mut bad = Vec::new();
    let summary = out.join("summary.json");
    if let Ok(t) = std::fs::read_to_string(&summary) {
        if serde_json::from_str::<serde_json::Value>(&t).map_or(true, |v| has_null(&v)) {
            bad.push(summary);
        }
    }
    let metrics = out.join("metrics.csv");
    if let Ok(t) = std::fs::read_to_string(&metrics) {
        if !t.lines().skip(1).flat_map(|l| l.split(',')).all(finite) {
            bad.push(metrics);
        }
    }
    // Frame files: frames/<stem>/<stem>_00000.obj, one folder per object.
    let files = std::fs::read_dir(out.join("frames"))
        .into_iter()
        .flatten()
        .flat_map(|e| std::fs::read_dir(e.unwrap().path()).into_iter().flatten())
        .map(|e| e.unwrap().path());
    for f in files {
        let t = std::fs::read_to_string(&f).unwrap_or_default();
        let ok = t
            .lines()
            .filter(|l| l.starts_with("v ") || l.starts_with("vn "))
            .flat_map(|l| l.split_whitespace().skip(1))
            .all(finite);
        if !ok {
            bad.push(f);
        }
    }
    bad
}

/// The number in environment variable `name`, else `default` (a fuzz
/// test's mutant count or seed, set by hand to run more or others).
pub fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
