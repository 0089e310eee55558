//! Running the measurements: this executable as a measuring child, LAMMPS
//! on its inputs (and once to write the initial state both codes start
//! from), the machine's load and its floating-point peak.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use crate::{Measure, Res, Runs, CELLS, STEPS, WORKS};

pub(crate) fn parse(line: &str) -> Measure {
    line.split_whitespace()
        .filter_map(|kv| kv.split_once('='))
        .filter_map(|(k, v)| Some((k.to_string(), v.parse().ok()?)))
        .collect()
}

/// Runs this executable as a measuring child.
pub(crate) fn ours(
    kind: &str,
    threads: usize,
    steps: usize,
    xv: &str,
    cells: usize,
) -> Res<Measure> {
    let exe = std::env::current_exe()?;
    let out = Command::new(exe)
        .args(["child", kind])
        .arg(threads.to_string())
        .arg(steps.to_string())
        .arg(xv)
        .arg(cells.to_string())
        .output()?;
    if !out.status.success() {
        return Err(format!(
            "child {kind} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        )
        .into());
    }
    Ok(parse(&String::from_utf8_lossy(&out.stdout)))
}

/// One LAMMPS run of `input` on `ranks` MPI ranks in `dir`: loop seconds,
/// average listed neighbours per particle, neighbour-list builds, peak
/// resident memory of the largest process (kB, `/usr/bin/time`).
pub(crate) fn lammps(dir: &Path, input: &Path, ranks: usize) -> Res<Measure> {
    let log = dir.join(format!("log.{ranks}"));
    let mut cmd = Command::new("/usr/bin/time");
    cmd.current_dir(dir).args(["-f", "maxrss_kb=%M"]);
    if ranks > 1 {
        cmd.args(["mpirun", "--allow-run-as-root", "-np", &ranks.to_string()]);
    }
    let out = cmd
        .arg("lmp")
        .arg("-in")
        .arg(input)
        .arg("-log")
        .arg(&log)
        .args(["-screen", "none"])
        .output()?;
    if !out.status.success() {
        return Err(format!("lmp failed: {}", String::from_utf8_lossy(&out.stderr)).into());
    }
    let text = std::fs::read_to_string(&log)?;
    let field = |prefix: &str, k: usize| -> Option<f64> {
        text.lines()
            .find(|l| l.starts_with(prefix))
            .and_then(|l| l.split_whitespace().nth(k))
            .and_then(|v| v.parse().ok())
    };
    let mut m = parse(&String::from_utf8_lossy(&out.stderr));
    m.insert(
        "seconds".into(),
        field("Loop time", 3).ok_or("no loop time")?,
    );
    m.insert(
        "neighbours".into(),
        field("Ave neighs/atom", 3).unwrap_or(0.0),
    );
    m.insert(
        "builds".into(),
        field("Neighbor list builds", 4).unwrap_or(0.0),
    );
    // "68.4% CPU use with 1 MPI tasks x 1 OpenMP threads": CPU seconds of
    // the loop over all ranks.
    let pct = text
        .lines()
        .find(|l| l.contains("% CPU use with"))
        .and_then(|l| l.split('%').next())
        .and_then(|v| v.trim().parse::<f64>().ok())
        .unwrap_or(100.0);
    m.insert("cpu".into(), m["seconds"] * pct / 100.0 * ranks as f64);
    Ok(m)
}

/// The measured floating-point peak of one core: independent chains of
/// fused multiply-adds (`S::mul_add_f64s`, 16 accumulator registers, more
/// than the FMA latency times the issue width) on the instruction set the
/// engine's SIMD lanes dispatch to (`op_dynamics::simd_isa`), best of 5
/// repetitions, timed by this thread's CPU time. GFLOP/s, two flops per lane per fused multiply-add.
pub(crate) fn peak_gflops() -> f64 {
    struct Chains(usize);
    impl pulp::WithSimd for Chains {
        type Output = (f64, usize);
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, simd: S) -> (f64, usize) {
            let mut acc = [simd.splat_f64s(1.0); 16];
            let (a, b) = (simd.splat_f64s(0.999_999), simd.splat_f64s(1e-7));
            for _ in 0..self.0 {
                for x in acc.iter_mut() {
                    *x = simd.mul_add_f64s(*x, a, b);
                }
            }
            let mut sum = simd.splat_f64s(0.0);
            for x in acc {
                sum = simd.add_f64s(sum, x);
            }
            (simd.reduce_sum_f64s(sum), S::F64_LANES)
        }
    }
    let iters = 20_000_000;
    // CPU time of this thread (`/proc/thread-self/schedstat`, ns on the
    // CPU): on a loaded machine wall-clock time would count the time
    // slices other processes took.
    let on_cpu = || -> Option<f64> {
        let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
        Some(s.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
    };
    (0..5)
        .map(|_| {
            let (clock, cpu0) = (Instant::now(), on_cpu());
            let (checksum, lanes) = pulp::Arch::new().dispatch(Chains(iters));
            let secs = match (cpu0, on_cpu()) {
                (Some(a), Some(b)) if b > a => b - a,
                _ => clock.elapsed().as_secs_f64(),
            };
            assert!(checksum.is_finite());
            2.0 * 16.0 * lanes as f64 * iters as f64 / secs / 1e9
        })
        .fold(0.0, f64::max)
}

/// Has LAMMPS write the positions and velocities of `in.lj` (both codes
/// start from them) into `dir`, and count the pairs within the cut-off in
/// its periodic block (step 0). The path of the state file, and the pair
/// count.
pub(crate) fn lammps_initial_state(dir: &Path, peers: &Path) -> Res<(String, f64)> {
    let lj_in = std::fs::read_to_string(peers.join("in.lj"))?;
    let dump = lj_in.replace(
        "run\t\t100",
        "write_dump all custom xv.txt id x y z vx vy vz modify sort id format float %.17g\nrun 0",
    );
    std::fs::write(dir.join("dump.in"), dump)?;
    let status = Command::new("lmp")
        .current_dir(dir)
        .args(["-in", "dump.in", "-log", "none", "-screen", "none"])
        .status()?;
    if !status.success() {
        return Err("lmp could not write the initial state".into());
    }
    let xv = dir.join("xv.txt");
    let xv = xv.to_str().ok_or("temporary path")?.to_string();
    // Pairs within the cut-off in LAMMPS' periodic block (step 0).
    let count_in = std::fs::read_to_string(peers.join("in.dipole3d"))?.replace(
        "run\t\t${nsteps}",
        "compute cn all coord/atom cutoff 2.5\ncompute cs all reduce sum c_cn\n\
         thermo_style custom step c_cs\nthermo_modify norm no\nrun 0",
    );
    std::fs::write(dir.join("count.in"), count_in)?;
    Command::new("lmp")
        .current_dir(dir)
        .args(["-in", "count.in", "-log", "count.log", "-screen", "none"])
        .status()?;
    let count_log = std::fs::read_to_string(dir.join("count.log")).unwrap_or_default();
    let lammps_pairs = count_log
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("Step"))
        .nth(1)
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(864_000.0, |c| c / 2.0);
    Ok((xv, lammps_pairs))
}

/// `reps` interleaved repetitions: in each, for 1 then 2 threads, ours then
/// LAMMPS on every work. `results[work][threads - 1]` holds `(ours,
/// lammps)` per repetition.
pub(crate) fn interleaved_runs(
    dir: &Path,
    peers: &Path,
    xv: &str,
    reps: usize,
) -> Res<Vec<[Runs; 2]>> {
    let mut results: Vec<[Runs; 2]> = WORKS.iter().map(|_| [Vec::new(), Vec::new()]).collect();
    for rep in 0..reps {
        for threads in [1usize, 2] {
            for (w, work) in WORKS.iter().enumerate() {
                let o = ours(work.kind, threads, STEPS, xv, CELLS)?;
                let l = lammps(dir, &peers.join(work.input), threads)?;
                eprintln!(
                    "rep {rep} {} t={threads}: ours {:.3} s, lammps {:.3} s",
                    work.kind, o["seconds"], l["seconds"]
                );
                results[w][threads - 1].push((o, l));
            }
        }
    }
    Ok(results)
}

/// The scaling runs of one size and work: lattice cells a side, the work,
/// and per repetition ours at 1 and at 2 threads.
pub(crate) type ScalingRun = (usize, &'static str, Vec<(Measure, Measure)>);

/// Repetitions of the scaling runs. A time slice lost to another process
/// moves a short run's speed-up by several percent (10 steps at 100k took
/// 0.3-0.7 s at 2 threads, and three runs of the same code gave the
/// spacing speed-up 1.65, 1.77 and 1.86 with work-bound 1.88-2.00): the
/// figures are medians over interleaved repetitions, as the side-by-side
/// ones are, and the 100k runs take 40 steps.
const SCALING_REPS: usize = 3;

/// Scaling at 100k and 1M particles (100k only and one repetition when
/// `quick`): our own Maxwell velocities, 40 steps, 5 at 1M; every
/// repetition runs each size and work at 1 then 2 threads.
pub(crate) fn scaling_runs(quick: bool) -> Res<Vec<ScalingRun>> {
    let sizes: &[usize] = if quick { &[29] } else { &[29, 63] };
    let reps = if quick { 1 } else { SCALING_REPS };
    let mut scaling: Vec<ScalingRun> = sizes
        .iter()
        .flat_map(|&cells| ["spacing", "oriented"].map(|kind| (cells, kind, Vec::new())))
        .collect();
    for rep in 0..reps {
        for (cells, kind, runs) in scaling.iter_mut() {
            let steps = if *cells > 40 { 5 } else { 40 };
            let one = ours(kind, 1, steps, "-", *cells)?;
            let two = ours(kind, 2, steps, "-", *cells)?;
            eprintln!(
                "rep {rep} scaling {kind} cells={cells}: {:.3} s / {:.3} s",
                one["seconds"], two["seconds"]
            );
            runs.push((one, two));
        }
    }
    Ok(scaling)
}
