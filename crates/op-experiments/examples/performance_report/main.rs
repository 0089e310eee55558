//! Writes `reports/performance.md`: the engine against LAMMPS on
//! the same 32,000-particle fcc block (LAMMPS' LJ melt benchmark, `in.lj`),
//! interleaved, at 1 and 2 threads / MPI ranks.
//!
//! ```text
//! cargo run --release -p op-experiments --example performance_report
//! ```
//!
//! - **Spacing only**: our Lennard-Jones spacing (cut-off 2.5 sigma, well at
//!   `2^(1/6)` sigma) against LAMMPS `lj/cut 2.5`, per step, from the same
//!   positions and the same initial velocities (LAMMPS writes them, we read
//!   them back).
//! - **Full oriented material**: the same block with random orientations and
//!   every orientation term on (co-planarity, co-normality, co-circularity,
//!   form; isotropic weight cut at 2.5) against LAMMPS
//!   `lj/cut/dipole/cut 2.5` + `nve/sphere update dipole`, per pair within
//!   the cut-off.
//!
//! Each measurement runs in a child process (this executable with `child`
//! arguments), so its peak memory (`VmHWM`) is its own. LAMMPS
//! (`/usr/bin/lmp`, see `../shared/peers/`) must be installed; without it
//! only our figures are written. About ten minutes on a 2-core machine.
//!
//! `performance_report child <spacing|spacing-mixed|oriented> <threads>
//! <steps> [xv file or -] [cells]` runs one measurement and prints one
//! `key=value` line (`spacing-mixed`: the spacing block in mixed
//! precision).
//!
//! - **The fastest CPU pair codes** (issue 37): our spacing pass, in double
//!   and in mixed precision, against LAMMPS `lj/cut/opt` and GROMACS
//!   (`gmx`, when installed) on the same block, interleaved.
//!
//! Modules: `child` (the measuring child process), `measure` (running
//! both codes, the machine's load and peak), `sections` (the report's
//! tables and paragraphs), `fastest` (LAMMPS `lj/cut/opt` and GROMACS).

mod child;
mod fastest;
mod measure;
mod sections;

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use fastest::{fastest_runs, fastest_section};
use measure::{interleaved_runs, lammps_initial_state, peak_gflops, scaling_runs};
use op_experiments::machine::load_average;
use sections::{
    cpu_table, flops_section, header, memory_section, pairs_paragraph, scaling_section,
    side_by_side, speedup_section, targets, targets_section,
};

type Res<T> = Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// LAMMPS' block of `in.lj`: 20 lattice cells a side.
const CELLS: usize = 20;
/// Steps of every measurement on the 32k block.
const STEPS: usize = 100;
/// Interleaved repetitions of every measurement on the 32k block.
const REPS: usize = 5;

/// Estimated flops per pair within the cut-off, counted from the kernels'
/// source (multiplications, additions, the division and square root as
/// one each; the taper's polynomial on the pairs that reach it; the
/// distance test of the listed pairs beyond the cut-off not counted).
const FLOPS_SPACING: f64 = 40.0;
const FLOPS_ORIENTED: f64 = 190.0;

/// One measurement's `key=value` figures.
type Measure = BTreeMap<String, f64>;
/// `(ours, lammps)` per repetition.
type Runs = Vec<(Measure, Measure)>;

/// One work both codes run.
struct Work {
    /// Its row label.
    name: &'static str,
    /// Its kind: `spacing` or `oriented` (the child's argument).
    kind: &'static str,
    /// The LAMMPS input in `../shared/peers/lammps/`.
    input: &'static str,
}

/// The two works, in table order.
const WORKS: [Work; 2] = [
    Work {
        name: "spacing only: LJ 2.5 sigma vs LAMMPS `lj/cut`",
        kind: "spacing",
        input: "in.lj",
    },
    Work {
        name: "full oriented vs LAMMPS `lj/cut/dipole/cut`",
        kind: "oriented",
        input: "in.dipole3d",
    },
];

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("child") {
        return child::child(&args[1..]);
    }
    report()
}

/// Measures both codes (interleaved) and the scaling, then writes
/// `reports/performance.md`.
fn report() -> Res<()> {
    let started = Instant::now();
    let load_before = load_average();
    let peers = op_experiments::workspace_root().join("../shared/peers/lammps");
    let have_lammps = Path::new("/usr/bin/lmp").exists() && peers.join("in.lj").exists();
    if !have_lammps {
        return Err("LAMMPS (/usr/bin/lmp) and ../shared/peers/lammps/ are needed".into());
    }
    let dir = std::env::temp_dir().join(format!("op-performance-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let (xv, lammps_pairs) = lammps_initial_state(&dir, &peers)?;
    // OP_QUICK=1: one repetition and the scaling at 100k only (a check
    // that the runner works, not a report to keep).
    let quick = std::env::var("OP_QUICK").is_ok_and(|v| v == "1");
    let reps = if quick { 1 } else { REPS };
    let peak = peak_gflops();
    eprintln!("peak {peak:.1} GFLOP/s ({})", op_dynamics::simd_isa());
    let results = interleaved_runs(&dir, &peers, &xv, reps)?;
    let fastest = fastest_runs(&dir, &peers, &xv, reps)?;
    let scaling = scaling_runs(quick)?;
    let load_after = load_average();

    let mut md = header(started, reps, (&load_before, &load_after), peak)?;
    md.push_str(&side_by_side(&results, lammps_pairs)?);
    md.push_str(&cpu_table(&results, lammps_pairs)?);
    md.push_str(&pairs_paragraph(&results, lammps_pairs)?);
    md.push_str(&speedup_section(&results)?);
    md.push_str(&memory_section(&results)?);
    md.push_str(&scaling_section(&scaling)?);
    md.push_str(&targets_section(&targets(
        &results,
        &scaling,
        lammps_pairs,
    ))?);
    md.push_str(&flops_section(&results, peak)?);
    md.push_str(&fastest_section(&fastest, &dir, lammps_pairs)?);
    let out = op_experiments::workspace_root().join("reports/performance.md");
    std::fs::write(&out, md)?;
    std::fs::remove_dir_all(&dir).ok();
    eprintln!("wrote {}", out.display());
    Ok(())
}
