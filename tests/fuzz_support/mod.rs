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

/// What one `opsim` process did.
pub struct Run {
    /// How it ended.
    pub outcome: Outcome,
    /// Its standard error (at most 1 MiB).
    pub stderr: String,
    /// Wall-clock seconds.
    pub wall: f64,
    /// CPU seconds of all its threads, user and system: the work it did,
    /// which a loaded machine does not inflate as it does the wall time.
    pub cpu: f64,
    /// Peak resident memory, KiB.
    pub peak_kb: u64,
}

/// Runs `opsim` with `args` under the wall-clock `bound` (killed beyond
/// it). Memory (`VmHWM` of `/proc/PID/status`) and CPU time (`utime` and
/// `stime` of `/proc/PID/stat`, in the kernel's 100 Hz user ticks) are
/// sampled every 20 ms; both read 0 where `/proc` does not exist.
pub fn opsim(args: &[&str], bound: Duration) -> Run {
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
        // The first MiB is kept; the rest is read and dropped, so that a
        // long message is not cut off by a closed pipe.
        let mut stderr = std::io::BufReader::new(stderr);
        let mut s = String::new();
        let _ = (&mut stderr).take(1 << 20).read_to_string(&mut s);
        let _ = std::io::copy(&mut stderr, &mut std::io::sink());
        s
    });
    let proc_dir = PathBuf::from(format!("/proc/{}", child.id()));
    let (mut peak_kb, mut ticks) = (0, 0);
    let outcome = loop {
        peak_kb = peak_kb.max(peak_resident_kb(&proc_dir).unwrap_or(0));
        ticks = ticks.max(cpu_ticks(&proc_dir).unwrap_or(0));
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
    Run {
        outcome,
        stderr: reader.join().unwrap_or_default(),
        wall: start.elapsed().as_secs_f64(),
        cpu: ticks as f64 / 100.0,
        peak_kb,
    }
}

/// `VmHWM`, the peak resident set so far, of the process at `proc_dir`.
fn peak_resident_kb(proc_dir: &Path) -> Option<u64> {
    let s = std::fs::read_to_string(proc_dir.join("status")).ok()?;
    s.lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}

/// User plus system time of the process at `proc_dir`, all its threads, in
/// clock ticks (fields 14 and 15 of `stat`, counted after the command name,
/// which may hold spaces and ends at the last parenthesis).
fn cpu_ticks(proc_dir: &Path) -> Option<u64> {
    let s = std::fs::read_to_string(proc_dir.join("stat")).ok()?;
    let mut fields = s[s.rfind(')')? + 1..].split_whitespace().skip(11);
    let user: u64 = fields.next()?.parse().ok()?;
    let system: u64 = fields.next()?.parse().ok()?;
    Some(user + system)
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
