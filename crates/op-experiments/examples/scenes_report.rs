//! The whole-scene benchmark: writes `reports/scenes.md`.
//!
//! ```sh
//! cargo build --release --bin opsim
//! cargo run --release -p op-experiments --example scenes_report
//! ```
//!
//! Every shipped scene (`scenes/*.ron`, `scenes/cookbook/*.ron`) and a few
//! scaled-up scenes a production user runs (skinned cloths draped on a
//! sphere, a skinned solid ball dropped on another, `opsim fit` of torus
//! samples, at growing sizes) are run by the release `opsim` binary, each
//! measurement its own process, at 1 and 2 threads, interleaved (every
//! repetition runs every case at 1 then 2 threads). Figures are medians
//! [min-max] over the repetitions (`OP_REPS`, default 3); the stage
//! shares and seconds come from each run's `summary.json` (`stages`, which
//! add up to `wall_seconds`); peak memory is the child's maximum resident
//! set from `/usr/bin/time` when it is installed, and so are its CPU
//! seconds (user and system): divided by the process's wall time, the
//! cores it kept busy on average. At 1 thread a value above one is work
//! beside the pool (the frame writer's own thread, the kernel's file
//! work); at 2 threads what falls short of two is time a thread waited,
//! the serial part of the run. Each run also records the share of the
//! machine's CPU time the hypervisor gave to other guests meanwhile
//! (steal, `/proc/stat`): this project's 2-core virtual machine lost
//! 0-27% of its time that way in bursts of seconds (measured 2026-12-03,
//! runs of the same scene 0.79-1.11 s), invisible in the load average and
//! in the run's own CPU seconds. A run during
//! which steal passed `OP_STEAL_LIMIT` percent (default 2) is run again,
//! at most `OP_TRIES` runs in all (default 3), keeping the one with the
//! least steal; the tables print the steal of the runs kept. For each scaled-up
//! family the report fits the exponent `a` of `t ~ N^a` (least squares on
//! the logarithms) to the wall time and to its largest stages.
//! `OP_QUICK=1` runs only the smallest scaled-up size of each family and
//! one repetition (a check that the generator works, not a report to
//! keep).
//!
//! For a many-core machine, four more variables: `OP_THREADS` (the thread
//! counts, comma-separated, default `1,2`; speed-ups are against the
//! first), `OP_ONLY` (comma-separated pieces of case labels: only cases
//! whose label contains one of them run), `OP_REPORT` (the report's path,
//! default `reports/scenes.md`), `OPSIM` (the binary, default
//! `target/release/opsim`) and `OP_ROOT` (the checkout whose `scenes/`
//! are run, default this workspace).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use op_experiments::machine::CpuTimes;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Thread counts measured unless `OP_THREADS` names others.
const THREADS: [usize; 2] = [1, 2];

/// One thing to run: a label, the `opsim` arguments before `--threads`
/// (the output folder is added), its size for the exponent fit, and its
/// family (scaled-up cases; `None` for a shipped scene).
struct Case {
    label: String,
    args: Vec<String>,
    size: usize,
    family: Option<&'static str>,
}

/// One measurement of a case.
#[derive(Clone, Debug, Default)]
struct Sample {
    wall: f64,
    stages: BTreeMap<String, f64>,
    peak_mb: Option<f64>,
    /// CPU seconds (user + system) over the process's wall seconds.
    cores_busy: Option<f64>,
    /// The share of the machine's CPU time the hypervisor took while it
    /// ran ([`op_experiments::machine::CpuTimes`]).
    steal: Option<f64>,
    /// The runs it took ([`measure_quietly`]): 1 unless steal was above
    /// the limit.
    runs: usize,
    exit: i32,
    particles: usize,
}

fn main() -> Res<()> {
    let started = Instant::now();
    let root = std::env::var_os("OP_ROOT")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(op_experiments::workspace_root);
    let opsim = std::env::var_os("OPSIM")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("target/release/opsim"));
    if !opsim.exists() {
        return Err(format!(
            "{} is missing: build it first with `cargo build --release --bin opsim`",
            opsim.display()
        )
        .into());
    }
    let quick = std::env::var("OP_QUICK").is_ok_and(|v| v == "1");
    let reps: usize = match std::env::var("OP_REPS") {
        Ok(v) => v.parse().map_err(|_| format!("OP_REPS={v}: not a count"))?,
        Err(_) if quick => 1,
        Err(_) => 3,
    };
    let work = std::env::temp_dir().join(format!("op-scenes-report-{}", std::process::id()));
    std::fs::create_dir_all(&work)?;
    let threads = thread_counts()?;
    let quiet = quiet_limits()?;
    let only: Vec<String> = std::env::var("OP_ONLY")
        .map(|v| v.split(',').map(str::to_string).collect())
        .unwrap_or_default();
    let mut cases = shipped(&root)?;
    cases.extend(scaled(&work, quick)?);
    cases.retain(|c| only.is_empty() || only.iter().any(|o| c.label.contains(o.as_str())));
    let load_before = op_experiments::machine::load_average();
    let cpu_before = CpuTimes::now();
    let path = std::env::var_os("OP_REPORT")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("reports/scenes.md"));
    let mut results: Vec<Vec<Vec<Sample>>> =
        cases.iter().map(|_| vec![vec![]; threads.len()]).collect();
    for rep in 0..reps {
        for (c, case) in cases.iter().enumerate() {
            for (k, &t) in threads.iter().enumerate() {
                let s = measure_quietly(&opsim, case, t, &work, quiet)?;
                eprintln!(
                    "rep {rep} {} {t} thread(s): {:.3} s (exit {}, steal {})",
                    case.label,
                    s.wall,
                    s.exit,
                    s.steal
                        .map_or("unknown".into(), |x| format!("{:.1}%", 100.0 * x)),
                );
                results[c][k].push(s);
            }
            // Written after every case, so that a run cut short leaves the
            // figures it has (cases not yet run show NaN).
            let load_now = op_experiments::machine::load_average();
            let stolen = CpuTimes::now()
                .zip(cpu_before)
                .and_then(|(now, before)| now.steal_since(&before));
            let conditions = Conditions {
                load: (&load_before, &load_now),
                stolen,
                quiet,
            };
            let md = report(&cases, &results, &threads, reps, started, &conditions)?;
            std::fs::write(&path, md)?;
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// The steal share above which a run is repeated, and the most runs of
/// one measurement ([`measure_quietly`]): `OP_STEAL_LIMIT` (percent,
/// default 2) and `OP_TRIES` (default 3; 1 never repeats).
fn quiet_limits() -> Res<(f64, usize)> {
    let limit = match std::env::var("OP_STEAL_LIMIT") {
        Ok(v) => match v.parse::<f64>() {
            Ok(p) if (0.0..=100.0).contains(&p) => p / 100.0,
            _ => return Err(format!("OP_STEAL_LIMIT={v}: a percentage, 0 to 100").into()),
        },
        Err(_) => 0.02,
    };
    let tries = match std::env::var("OP_TRIES") {
        Ok(v) => match v.parse::<usize>() {
            Ok(n) if n >= 1 => n,
            _ => return Err(format!("OP_TRIES={v}: a count of at least 1").into()),
        },
        Err(_) => 3,
    };
    Ok((limit, tries))
}

/// [`measure`], repeated while the hypervisor took more than `limit` of
/// the machine's CPU time during the run, at most `tries` runs in all: the
/// run with the least steal is kept (steal comes in bursts of seconds on
/// a shared host; a run in one is slower by work done elsewhere). The
/// choice reads only the machine's counters, never the run's time.
fn measure_quietly(
    opsim: &Path,
    case: &Case,
    threads: usize,
    work: &Path,
    (limit, tries): (f64, usize),
) -> Res<Sample> {
    let mut kept = measure(opsim, case, threads, work)?;
    let mut runs = 1;
    // A quiet run has less steal than the kept noisy one, so it is kept
    // and ends the loop.
    while runs < tries && kept.steal.is_some_and(|s| s > limit) {
        let sample = measure(opsim, case, threads, work)?;
        runs += 1;
        if sample.steal.unwrap_or(0.0) < kept.steal.unwrap_or(0.0) {
            kept = sample;
        }
    }
    kept.runs = runs;
    Ok(kept)
}

/// The thread counts to measure: `OP_THREADS`, or [`THREADS`].
fn thread_counts() -> Res<Vec<usize>> {
    let Ok(v) = std::env::var("OP_THREADS") else {
        return Ok(THREADS.to_vec());
    };
    let counts = v
        .split(',')
        .map(|t| t.trim().parse::<usize>().ok().filter(|&t| t > 0))
        .collect::<Option<Vec<usize>>>()
        .filter(|c| !c.is_empty())
        .ok_or_else(|| format!("OP_THREADS={v}: not a comma-separated list of thread counts"))?;
    Ok(counts)
}

/// The shipped scenes, in path order.
fn shipped(root: &Path) -> Res<Vec<Case>> {
    let mut paths = Vec::new();
    for dir in ["scenes", "scenes/cookbook"] {
        for e in std::fs::read_dir(root.join(dir))? {
            let p = e?.path();
            if p.extension().is_some_and(|x| x == "ron" || x == "json") {
                paths.push(p);
            }
        }
    }
    paths.sort();
    Ok(paths
        .into_iter()
        .map(|p| {
            let label = p
                .strip_prefix(root.join("scenes"))
                .unwrap_or(&p)
                .with_extension("")
                .display()
                .to_string();
            Case {
                label,
                args: vec!["run".into(), p.display().to_string()],
                size: 0,
                family: None,
            }
        })
        .collect())
}

/// The scaled-up cases, their scene and sample files written into `work`.
fn scaled(work: &Path, quick: bool) -> Res<Vec<Case>> {
    let mut cases = Vec::new();
    let take = |sizes: &[usize]| -> Vec<usize> {
        if quick {
            sizes[..1].to_vec()
        } else {
            sizes.to_vec()
        }
    };
    for n in take(&[30, 100, 316]) {
        let path = work.join(format!("cloth_{n}.ron"));
        std::fs::write(&path, cloth(n))?;
        cases.push(Case {
            label: format!("skinned cloth {n}x{n} on a sphere, 50 steps"),
            args: vec!["run".into(), path.display().to_string()],
            size: n * n,
            family: Some("skinned cloth draped on a sphere"),
        });
    }
    for r in take(&[5, 12, 29]) {
        let path = work.join(format!("balls_{r}.ron"));
        std::fs::write(&path, balls(r))?;
        cases.push(Case {
            label: format!("skinned ball of radius {r} dropped on another, 50 steps"),
            args: vec!["run".into(), path.display().to_string()],
            size: 0,
            family: Some("skinned ball on a skinned ball"),
        });
    }
    let (scene, points) = (work.join("solid_torus.ron"), work.join("solid_torus.xyz"));
    std::fs::write(&points, solid_torus_points())?;
    std::fs::write(&scene, SOLID_TORUS)?;
    cases.push(Case {
        label:
            "skinned solid torus (24,536 particles, point skins of radius 2, cell 0.25), one step"
                .into(),
        args: vec!["run".into(), scene.display().to_string()],
        size: 0,
        family: Some("skinned solid torus (one size: building and one polygonization)"),
    });
    for n in take(&[10_000, 100_000, 1_000_000]) {
        let path = work.join(format!("torus_{n}.xyz"));
        std::fs::write(&path, torus_samples(n))?;
        cases.push(Case {
            label: format!("opsim fit of {n} torus samples"),
            args: vec![
                "fit".into(),
                path.display().to_string(),
                "--out".into(),
                work.join(format!("torus_{n}.obj")).display().to_string(),
            ],
            size: n,
            family: Some("opsim fit (torus samples)"),
        });
    }
    Ok(cases)
}

/// A solid torus on the unit lattice (major radius 20, minor 7.93:
/// 24,536 points), the object whose build issue 31 timed at 37-39 s.
fn solid_torus_points() -> String {
    let mut out = String::new();
    for x in -30i32..=30 {
        for y in -30i32..=30 {
            for z in -9i32..=9 {
                let d = f64::from(x).hypot(f64::from(y)) - 20.0;
                if d * d + f64::from(z * z) <= 7.93 * 7.93 {
                    out.push_str(&format!("{x} {y} {z}\n"));
                }
            }
        }
    }
    out
}

/// [`solid_torus_points`] skinned by point primitives of radius 2 at cell
/// 0.25, run for one step (two frames): building, posing and
/// polygonizing the skin.
const SOLID_TORUS: &str = r#"(
    name: "solid_torus",
    world: (integrator: VelocityVerlet, dt: 0.004, duration: 0.004, frame_rate: 250),
    materials: {
        "solid": (spacing: LennardJones((epsilon: 5, r0: 1, cutoff: 1.3))),
    },
    objects: [
        (
            name: "torus",
            material: "solid",
            generator: Points(path: "solid_torus.xyz"),
            skin: Some((primitive: Point, radius: 2, cell_size: 0.25, stiffness: 100)),
        ),
    ],
)
"#;

/// `sheet_on_sphere`'s cloth at `n x n` particles over a sphere of radius
/// `n / 5`, dropped from just above it: 50 steps, 3 frames. At most about
/// 500 across: the skin's polygonization grid has at most
/// `op_implicit::MAX_NODES_PER_AXIS` nodes per axis at its cell size of
/// 0.25.
fn cloth(n: usize) -> String {
    let radius = n as f64 / 5.0;
    format!(
        r#"(
    name: "cloth_{n}",
    world: (integrator: VelocityVerlet, dt: 0.004, duration: 0.2, frame_rate: 10,
            gravity: (0, 0, -1), linear_damping: 0.3, angular_damping: 0.1),
    materials: {{
        "sheet": (
            spacing: LennardJones((epsilon: 20, r0: 1, cutoff: 1.5)),
            coplanarity: 1,
            conormality: 1,
            bonds: (radius: 1.2),
        ),
    }},
    objects: [
        (
            name: "sheet",
            material: "sheet",
            generator: HexSheet(nx: {n}, ny: {n}, spacing: 1, center: (0, 0, {z})),
            skin: Some((primitive: Square(half_side: 0.5), radius: 0.8, cell_size: 0.25, stiffness: 100)),
        ),
    ],
    tools: [
        (name: "sphere", shape: Ball(radius: {radius}), path: [(time: 0, position: (0, 0, 0))],
         role: Obstacle(stiffness: 1600)),
    ],
)
"#,
        z = radius + 0.6,
    )
}

/// A skinned solid ball of radius `r` (spacing 1, point skins) falling
/// onto a fixed-size skinned solid ball below it, already touching: 50
/// steps, 3 frames.
fn balls(r: usize) -> String {
    let r = r as f64;
    format!(
        r#"(
    name: "balls_{r}",
    world: (integrator: VelocityVerlet, dt: 0.004, duration: 0.2, frame_rate: 10,
            gravity: (0, 0, -1), linear_damping: 0.3, angular_damping: 0.1),
    materials: {{
        "solid": (spacing: LennardJones((epsilon: 5, r0: 1, cutoff: 1.3)), bonds: (radius: 1.2)),
    }},
    objects: [
        (
            name: "ball",
            material: "solid",
            generator: SolidBall(radius: {r}, spacing: 1, center: (0, 0, {top})),
            skin: Some((primitive: Point, radius: 1.6, cell_size: 0.25, stiffness: 100)),
        ),
        (
            name: "base",
            material: "solid",
            generator: SolidBall(radius: {r}, spacing: 1, center: (0, 0, 0)),
            skin: Some((primitive: Point, radius: 1.6, cell_size: 0.25, stiffness: 100)),
        ),
    ],
)
"#,
        top = 2.0 * r + 1.2,
    )
}

/// `n` samples of a torus (major radius 2, minor 0.8) with their normals,
/// on a golden-angle lattice of its parameter square.
fn torus_samples(n: usize) -> String {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut s = String::with_capacity(n * 60);
    for k in 0..n {
        let u = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
        let v = golden * k as f64;
        let (big, small) = (2.0, 0.8);
        let n_ = [u.cos() * v.cos(), u.sin() * v.cos(), v.sin()];
        let p = [
            (big + small * v.cos()) * u.cos(),
            (big + small * v.cos()) * u.sin(),
            small * v.sin(),
        ];
        let _ = writeln!(
            s,
            "{:.9} {:.9} {:.9} {:.9} {:.9} {:.9}",
            p[0], p[1], p[2], n_[0], n_[1], n_[2]
        );
    }
    s
}

/// Runs `case` at `threads` threads in its own process.
fn measure(opsim: &Path, case: &Case, threads: usize, work: &Path) -> Res<Sample> {
    let out = work.join("out");
    let _ = std::fs::remove_dir_all(&out);
    let time = Path::new("/usr/bin/time");
    let mut cmd = if time.exists() {
        let mut c = Command::new(time);
        c.args(["-f", "peak-kb %M\ncpu-s %U %S"]).arg(opsim);
        c
    } else {
        Command::new(opsim)
    };
    cmd.args(&case.args);
    if case.args[0] == "run" {
        cmd.arg("--threads").arg(threads.to_string());
        cmd.arg("--out").arg(&out);
    } else {
        // `opsim fit` runs on rayon's global pool, sized by this variable;
        // `--profile` prints its stages' seconds on standard error.
        cmd.env("RAYON_NUM_THREADS", threads.to_string());
        cmd.arg("--profile");
    }
    let ticks = CpuTimes::now();
    let clock = Instant::now();
    let output = cmd.output()?;
    let elapsed = clock.elapsed().as_secs_f64();
    let steal = CpuTimes::now()
        .zip(ticks)
        .and_then(|(after, before)| after.steal_since(&before));
    let stderr = String::from_utf8_lossy(&output.stderr);
    let peak_mb = stderr
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("peak-kb "))
        .and_then(|v| v.trim().parse::<f64>().ok())
        .map(|kb| kb / 1024.0);
    let cpu: Option<f64> = stderr
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("cpu-s "))
        .and_then(|v| {
            v.split_whitespace()
                .map(|x| x.parse::<f64>().ok())
                .sum::<Option<f64>>()
        });
    let mut sample = Sample {
        wall: elapsed,
        peak_mb,
        cores_busy: cpu.map(|c| c / elapsed),
        steal,
        runs: 1,
        exit: output.status.code().unwrap_or(-1),
        ..Sample::default()
    };
    if case.args[0] == "run" {
        let Ok(text) = std::fs::read_to_string(out.join("summary.json")) else {
            // Refused or failed before its summary: reported as such.
            eprintln!("{}: no summary.json: {stderr}", case.label);
            sample.wall = f64::NAN;
            return Ok(sample);
        };
        let v: serde_json::Value = serde_json::from_str(&text)?;
        sample.wall = v["wall_seconds"].as_f64().unwrap_or(elapsed);
        if let Some(stages) = v["stages"].as_object() {
            for (k, t) in stages {
                sample.stages.insert(k.clone(), t.as_f64().unwrap_or(0.0));
            }
        }
        sample.particles = v["objects"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|o| o["particles"].as_u64())
                    .sum::<u64>() as usize
            })
            .unwrap_or(0);
    } else if output.status.success() {
        let line = String::from_utf8_lossy(&output.stdout);
        let v: serde_json::Value = serde_json::from_str(line.trim())?;
        sample.particles = v["particles"].as_u64().unwrap_or(0) as usize;
        sample.stages = fit_stages(&stderr);
    } else {
        eprintln!("{} failed: {stderr}", case.label);
        sample.wall = f64::NAN;
    }
    Ok(sample)
}

/// The stages of `opsim fit --profile`'s table on standard error (`name
/// seconds share%` lines between the `stage` header and the `wall` line).
fn fit_stages(stderr: &str) -> BTreeMap<String, f64> {
    let mut stages = BTreeMap::new();
    let mut inside = false;
    for line in stderr.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.first() == Some(&"stage") && words.get(1) == Some(&"seconds") {
            inside = true;
            continue;
        }
        if !inside || words.len() < 3 {
            continue;
        }
        if words[0] == "wall" {
            break;
        }
        let name = words[..words.len() - 2].join(" ");
        if let Ok(t) = words[words.len() - 2].parse::<f64>() {
            stages.insert(name, t);
        }
    }
    stages
}

/// Median and range of the finite values of `xs` (NaN when none: every
/// run failed).
fn stats(xs: Vec<f64>) -> (f64, f64, f64) {
    let mut xs: Vec<f64> = xs.into_iter().filter(|x| x.is_finite()).collect();
    if xs.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    let median = if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    };
    (median, xs[0], xs[n - 1])
}

/// `median [min-max]` of seconds.
fn spread(xs: Vec<f64>) -> String {
    let (m, lo, hi) = stats(xs);
    format!("{m:.2} [{lo:.2}-{hi:.2}]")
}

/// The median seconds of stage `name` over `samples`.
fn stage(samples: &[Sample], name: &str) -> f64 {
    stats(
        samples
            .iter()
            .map(|s| s.stages.get(name).copied().unwrap_or(0.0))
            .collect(),
    )
    .0
}

/// The three largest stages of `samples` (medians) as `name share%`.
fn top_stages(samples: &[Sample]) -> String {
    let wall = stats(samples.iter().map(|s| s.wall).collect()).0;
    let mut names: Vec<&String> = samples.iter().flat_map(|s| s.stages.keys()).collect();
    names.sort();
    names.dedup();
    let mut rows: Vec<(f64, &String)> = names.iter().map(|n| (stage(samples, n), *n)).collect();
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    rows.iter()
        .take(3)
        .map(|(t, n)| format!("{n} {:.0}%", 100.0 * t / wall.max(f64::MIN_POSITIVE)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Per-repetition speed-ups `t1 / t2`.
fn speedup(one: &[Sample], two: &[Sample]) -> (f64, f64, f64) {
    stats(one.iter().zip(two).map(|(a, b)| a.wall / b.wall).collect())
}

/// `1 thread` or `T threads`.
fn threads_label(t: usize) -> String {
    if t == 1 {
        "1 thread".into()
    } else {
        format!("{t} threads")
    }
}

/// The Markdown report.
fn report(
    cases: &[Case],
    results: &[Vec<Vec<Sample>>],
    threads: &[usize],
    reps: usize,
    started: Instant,
    conditions: &Conditions<'_>,
) -> Res<String> {
    let mut md = String::new();
    intro(&mut md, results, (threads, reps, started), conditions)?;
    shipped_table(&mut md, cases, results, threads)?;
    scaled_table(&mut md, cases, results, threads)?;
    growth_table(&mut md, cases, results)?;
    Ok(md)
}

/// What the machine did while the report ran.
struct Conditions<'a> {
    /// The load averages before and now.
    load: (&'a str, &'a str),
    /// The share of the CPU time the hypervisor took so far.
    stolen: Option<f64>,
    /// [`quiet_limits`].
    quiet: (f64, usize),
}

/// The report's title, how it was made, and the machine's load.
fn intro(
    md: &mut String,
    results: &[Vec<Vec<Sample>>],
    (threads, reps, started): (&[usize], usize, Instant),
    conditions: &Conditions<'_>,
) -> std::fmt::Result {
    let Conditions {
        load,
        stolen,
        quiet: (limit, tries),
    } = conditions;
    let samples: Vec<&Sample> = results.iter().flatten().flatten().collect();
    let repeated = samples.iter().filter(|s| s.runs > 1).count();
    let noisy = samples
        .iter()
        .filter(|s| s.steal.is_some_and(|x| x > *limit))
        .count();
    let counts: Vec<String> = threads.iter().map(|t| t.to_string()).collect();
    let flags: Vec<String> = threads.iter().map(|t| format!("`--threads {t}`")).collect();
    writeln!(
        md,
        "# Whole scenes: wall time and stages at {} threads\n",
        counts.join(", ")
    )?;
    writeln!(
        md,
        "Generated by `cargo build --release --bin opsim && cargo run --release -p \
         op-experiments --example scenes_report` ({:.0} s). Every case is its own `opsim` \
         process at {}, interleaved over {reps} repetition(s); seconds are medians [min-max], \
         speed-ups are per-repetition ratios to {}. A run's wall time is its `summary.json` \
         `wall_seconds` (building the scene included), whose `stages` add up to it; \
         `opsim fit` is timed as a whole process. Cores busy: the process's CPU seconds \
         (user and system, `/usr/bin/time`) over its wall seconds, the median: above 1 at \
         1 thread for work beside the pool (the frame writer's thread, the kernel's file \
         work); at 2 threads, what falls short of 2 is time a thread waited (the serial \
         part of the run). Steal: the share of the machine's CPU time that the hypervisor \
         gave to other guests while the run went on (`/proc/stat`), the median: on a \
         shared virtual machine a run is slower by that much work done elsewhere, which \
         neither the load average nor the run's CPU seconds show. A run during which \
         steal passed {:.0}% was run again, at most {tries} times in all, and the run with \
         the least steal kept (`OP_STEAL_LIMIT`, `OP_TRIES`).\n",
        started.elapsed().as_secs_f64(),
        flags.join(", "),
        threads_label(threads[0]),
        100.0 * limit,
    )?;
    md.push_str(&op_experiments::machine::table(&[
        (
            "load average before / after",
            format!("{} / {}", load.0, load.1),
        ),
        (
            "CPU time stolen by the hypervisor over the report",
            stolen.map_or("unknown".into(), |s| format!("{:.1}%", 100.0 * s)),
        ),
        (
            "measurements run again for steal / kept above the limit",
            format!("{repeated} / {noisy} of {}", samples.len()),
        ),
    ]));
    writeln!(md)?;
    Ok(())
}

/// The header cells shared by both tables: seconds at each thread count,
/// then the speed-up of each later count.
fn thread_columns(threads: &[usize]) -> (String, String) {
    let mut head = String::new();
    let mut rule = String::new();
    for &t in threads {
        head.push_str(&format!(" {} (s) |", threads_label(t)));
        rule.push_str("---|");
    }
    for &t in &threads[1..] {
        head.push_str(&format!(" speed-up {t} |"));
        rule.push_str("---|");
    }
    (head, rule)
}

/// The cells of [`thread_columns`] for one case.
fn thread_cells(per_thread: &[Vec<Sample>]) -> String {
    let mut row = String::new();
    for samples in per_thread {
        row.push_str(&format!(
            " {} |",
            spread(samples.iter().map(|x| x.wall).collect())
        ));
    }
    for samples in &per_thread[1..] {
        let (s, lo, hi) = speedup(&per_thread[0], samples);
        row.push_str(&format!(" {s:.2} [{lo:.2}-{hi:.2}] |"));
    }
    row
}

/// The median steal share at each thread count, in percent: `1.2 / 3.4`.
fn steal_cell(per_thread: &[Vec<Sample>]) -> String {
    per_thread
        .iter()
        .map(|samples| {
            let (m, _, _) = stats(samples.iter().filter_map(|x| x.steal).collect());
            if m.is_finite() {
                format!("{:.1}", 100.0 * m)
            } else {
                "n/a".into()
            }
        })
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The table of the shipped scenes, and which are slower with more
/// threads.
fn shipped_table(
    md: &mut String,
    cases: &[Case],
    results: &[Vec<Vec<Sample>>],
    threads: &[usize],
) -> std::fmt::Result {
    if cases.iter().all(|c| c.family.is_some()) {
        return Ok(());
    }
    let last = *threads.last().unwrap_or(&1);
    writeln!(md, "## Shipped scenes\n")?;
    let (head, rule) = thread_columns(threads);
    let at_last = if threads.len() > 1 {
        format!(" largest stages at {} |", threads_label(last))
    } else {
        String::new()
    };
    let counts: Vec<String> = threads.iter().map(|t| t.to_string()).collect();
    writeln!(
        md,
        "| scene | particles |{head} steal % at {} threads | build (s) | largest stages at {} \
         |{at_last} exit |",
        counts.join(" / "),
        threads_label(threads[0])
    )?;
    writeln!(
        md,
        "|---|---|{rule}---|---|---|{}---|",
        if at_last.is_empty() { "" } else { "---|" }
    )?;
    let mut slower = Vec::new();
    for (case, per_thread) in cases.iter().zip(results) {
        if case.family.is_some() || per_thread[0].is_empty() {
            continue;
        }
        for (samples, &t) in per_thread.iter().zip(threads).skip(1) {
            let (s, lo, hi) = speedup(&per_thread[0], samples);
            if hi < 1.0 {
                slower.push(format!("{} at {t} ({s:.2} [{lo:.2}-{hi:.2}])", case.label));
            }
        }
        let last_stages = if threads.len() > 1 {
            format!(" {} |", top_stages(&per_thread[per_thread.len() - 1]))
        } else {
            String::new()
        };
        writeln!(
            md,
            "| {} | {} |{} {} | {:.3} | {} |{last_stages} {} |",
            case.label,
            per_thread[0][0].particles,
            thread_cells(per_thread),
            steal_cell(per_thread),
            stage(&per_thread[0], "build"),
            top_stages(&per_thread[0]),
            per_thread[0][0].exit,
        )?;
    }
    writeln!(md)?;
    if slower.is_empty() {
        writeln!(
            md,
            "No shipped scene is slower with more threads than at {} in every repetition.\n",
            threads_label(threads[0])
        )?;
    } else {
        writeln!(
            md,
            "Slower than at {} in every repetition: {}.\n",
            threads_label(threads[0]),
            slower.join(", ")
        )?;
    }
    Ok(())
}

/// The table of the scaled-up cases: times, stages, peak memory.
fn scaled_table(
    md: &mut String,
    cases: &[Case],
    results: &[Vec<Vec<Sample>>],
    threads: &[usize],
) -> std::fmt::Result {
    if cases.iter().all(|c| c.family.is_none()) {
        return Ok(());
    }
    writeln!(md, "## Scaled-up scenes\n")?;
    let (head, rule) = thread_columns(threads);
    let counts: Vec<String> = threads.iter().map(|t| t.to_string()).collect();
    writeln!(
        md,
        "| case | particles |{head} steal % at {} threads | build | contact | integrate | export \
         | largest stages at {} | cores busy at {} threads | peak memory at {} threads (MB) |",
        counts.join(" / "),
        threads_label(threads[0]),
        counts.join(" / "),
        counts.join(" / ")
    )?;
    writeln!(md, "|---|---|{rule}---|---|---|---|---|---|---|---|")?;
    for (case, per_thread) in cases.iter().zip(results) {
        if case.family.is_none() || per_thread[0].is_empty() {
            continue;
        }
        let peak = |xs: &[Sample]| {
            xs.iter()
                .filter_map(|x| x.peak_mb)
                .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
                .map_or("n/a".to_string(), |v| format!("{v:.0}"))
        };
        // The median over the repetitions.
        let busy = |xs: &[Sample]| {
            let mut v: Vec<f64> = xs.iter().filter_map(|x| x.cores_busy).collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2)
                .map_or("n/a".to_string(), |b| format!("{b:.2}"))
        };
        let one = &per_thread[0];
        let peaks: Vec<String> = per_thread.iter().map(|s| peak(s)).collect();
        let busies: Vec<String> = per_thread.iter().map(|s| busy(s)).collect();
        writeln!(
            md,
            "| {} | {} |{} {} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} |",
            case.label,
            one[0].particles,
            thread_cells(per_thread),
            steal_cell(per_thread),
            stage(one, "build"),
            stage(one, "contact"),
            stage(one, "integrate"),
            stage(one, "export"),
            top_stages(one),
            busies.join(" / "),
            peaks.join(" / "),
        )?;
    }
    Ok(())
}

/// The families of the scaled-up cases of at least two sizes (an
/// exponent needs two), in case order.
fn families(cases: &[Case]) -> Vec<&'static str> {
    let mut families: Vec<&str> = cases.iter().filter_map(|c| c.family).collect();
    families.dedup();
    families.retain(|f| cases.iter().filter(|c| c.family == Some(f)).count() >= 2);
    families
}

/// The measured cases of `family` with their samples at the first thread
/// count.
fn members<'a>(
    cases: &'a [Case],
    results: &'a [Vec<Vec<Sample>>],
    family: &str,
) -> Vec<(&'a Case, &'a [Sample])> {
    cases
        .iter()
        .zip(results)
        .filter(|(c, r)| c.family == Some(family) && !r[0].is_empty())
        .map(|(c, r)| (c, r[0].as_slice()))
        .collect()
}

/// The exponent `a` of `t ~ N^a` over `members`, `t` from `f`.
fn exponent(members: &[(&Case, &[Sample])], f: &dyn Fn(&[Sample]) -> f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = members
        .iter()
        .map(|(c, s)| ((c.size.max(s[0].particles)) as f64, f(s)))
        .collect();
    op_experiments::stability::sweep::log_log_slope(&pts)
}

/// The exponent of `t ~ N^a` per scaled-up family, for the wall time and
/// the largest stages (at the first thread count).
fn growth_table(md: &mut String, cases: &[Case], results: &[Vec<Vec<Sample>>]) -> std::fmt::Result {
    if cases.iter().all(|c| c.family.is_none()) {
        return Ok(());
    }
    writeln!(md)?;
    writeln!(
        md,
        "Growth with the number of particles N (exponent a of t ~ N^a, least squares over \
         the sizes above, first thread count):\n"
    )?;
    writeln!(
        md,
        "| family | wall | build | contact | integrate | export |"
    )?;
    writeln!(md, "|---|---|---|---|---|---|")?;
    for family in families(cases) {
        let members = members(cases, results, family);
        let fit = |f: &dyn Fn(&[Sample]) -> f64| {
            exponent(&members, f).map_or("-".to_string(), |a| format!("{a:.2}"))
        };
        writeln!(
            md,
            "| {family} | {} | {} | {} | {} | {} |",
            fit(&|s| stats(s.iter().map(|x| x.wall).collect()).0),
            fit(&|s| stage(s, "build")),
            fit(&|s| stage(s, "contact")),
            fit(&|s| stage(s, "integrate")),
            fit(&|s| stage(s, "export")),
        )?;
    }
    writeln!(md)?;
    writeln!(
        md,
        "Every stage of at least 2% of the largest case's wall time, exponent a (first thread \
         count):\n"
    )?;
    for family in families(cases) {
        let members = members(cases, results, family);
        let Some((_, largest)) = members.last() else {
            continue;
        };
        let wall = stats(largest.iter().map(|x| x.wall).collect()).0;
        let mut names: Vec<&String> = largest.iter().flat_map(|s| s.stages.keys()).collect();
        names.sort();
        names.dedup();
        let mut cells = Vec::new();
        for name in names {
            if stage(largest, name) < 0.02 * wall {
                continue;
            }
            if let Some(a) = exponent(&members, &|s| stage(s, name)) {
                cells.push(format!("{name} {a:.2}"));
            }
        }
        writeln!(md, "- {family}: {}", cells.join(", "))?;
    }
    Ok(())
}
