//! The measuring child process (`performance_report child ...`): builds the
//! fcc block of LAMMPS' `in.lj` (spacing only or the full oriented
//! material), steps it and prints its timings, pair counts, neighbour-list
//! rebuilds and peak memory on one `key=value` line.

use op_dynamics::interactions::{LennardJonesParams, Spacing, WeightParams};
use op_dynamics::{
    Material, NeighbourParams, ParticleDesc, Particles, Point3, Precision, Quat, Real, Scheme,
    Vec3, World, WorldParams,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::{Res, CELLS};

/// LAMMPS' `lattice fcc 0.8442`.
const DENSITY: Real = 0.8442;
/// LAMMPS' time step (lj units) and neighbour skin.
const DT: Real = 0.005;
const LAMMPS_SKIN: Real = 0.3;
const CUTOFF: Real = 2.5;

/// The fcc block of `in.lj` with `cells` lattice cells a side (20: 32,000
/// particles).
fn fcc_block(cells: usize) -> Vec<Point3> {
    let a = (4.0 / DENSITY).powf(1.0 / 3.0);
    let basis = [
        [0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0],
        [0.5, 0.0, 0.5],
        [0.0, 0.5, 0.5],
    ];
    let mut p = Vec::with_capacity(4 * cells * cells * cells);
    for k in 0..cells {
        for j in 0..cells {
            for i in 0..cells {
                for b in basis {
                    p.push(Point3::new(
                        a * (i as Real + b[0]),
                        a * (j as Real + b[1]),
                        a * (k as Real + b[2]),
                    ));
                }
            }
        }
    }
    p
}

/// A small deterministic generator (random orientations, fallback velocities).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> Real {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as Real / (1u64 << 53) as Real
    }
    fn normal(&mut self) -> Real {
        let (u, v) = (self.next().max(1e-300), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// Positions and velocities: from a LAMMPS dump (`id x y z vx vy vz`
/// lines) when given, else the fcc block of `cells` a side with Maxwell
/// velocities at 1.44.
fn initial_state(xv: Option<&Path>, cells: usize) -> Res<Vec<(Point3, Vec3)>> {
    if let Some(path) = xv {
        let text = std::fs::read_to_string(path)?;
        let mut rows = Vec::new();
        for line in text.lines() {
            let v: Vec<Real> = line
                .split_whitespace()
                .map(|s| s.parse::<Real>())
                .collect::<Result<_, _>>()
                .unwrap_or_default();
            if v.len() == 7 {
                rows.push((
                    v[0] as u64,
                    Point3::new(v[1], v[2], v[3]),
                    Vec3::new(v[4], v[5], v[6]),
                ));
            }
        }
        rows.sort_by_key(|r| r.0);
        return Ok(rows.into_iter().map(|(_, p, v)| (p, v)).collect());
    }
    let mut rng = Rng(87287);
    let s = 1.44f64.sqrt();
    Ok(fcc_block(cells)
        .into_iter()
        .map(|p| {
            let v = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * s;
            (p, v)
        })
        .collect())
}

/// Our materials: LJ spacing (LAMMPS `lj/cut 2.5`: epsilon 1, sigma 1, so
/// the well at `2^(1/6)`; our smooth taper over the last 10% of the
/// cut-off), and the full oriented material on top of it.
fn material(oriented: bool) -> Material {
    let lj = Spacing::LennardJones(LennardJonesParams {
        epsilon: 1.0,
        r0: (2.0 as Real).powf(1.0 / 6.0),
        cutoff: CUTOFF,
        taper: 0.1,
        ..Default::default()
    });
    if !oriented {
        return Material {
            spacing: Some(lj),
            ..Material::empty()
        };
    }
    Material {
        spacing: Some(lj),
        weight: WeightParams {
            cutoff: CUTOFF,
            ..Default::default()
        },
        // The per-pair work does not depend on the weights; these keep the
        // randomly oriented block about as agitated as LAMMPS' dipoles, so
        // both rebuild their lists about as often.
        coplanarity: 0.1,
        conormality: 0.05,
        cocircularity: 0.05,
        form: 0.1,
        ..Material::empty()
    }
}

fn world(oriented: bool, precision: Precision, xv: Option<&Path>, cells: usize) -> Res<World> {
    let mut particles = Particles::new();
    let mut rng = Rng(98934);
    for (p, v) in initial_state(xv, cells)? {
        let mut d = ParticleDesc::at(p);
        d.velocity = v;
        if oriented {
            let axis = Vec3::new(rng.normal(), rng.normal(), rng.normal());
            d.orientation =
                Quat::from_scaled_axis(axis.normalize() * (rng.next() * std::f64::consts::PI));
            d.curvature = 0.1;
        }
        particles.push(d)?;
    }
    let params = WorldParams {
        scheme: Scheme::VelocityVerlet,
        dt: DT,
        neighbours: NeighbourParams {
            skin: std::env::var("OP_SKIN")
                .ok()
                .and_then(|v| v.parse::<Real>().ok())
                .unwrap_or(LAMMPS_SKIN)
                / CUTOFF,
            ..Default::default()
        },
        precision,
        ..Default::default()
    };
    Ok(World::new(particles, &[material(oriented)], params)?)
}

/// Peak resident memory of this process (`VmHWM`, kB).
fn peak_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0)
}

/// CPU seconds (user + system) this process used so far, from
/// `/proc/self/stat` (clock ticks of 10 ms).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
            Some(ticks / 100.0)
        })
        .unwrap_or(0.0)
}

/// Pairs within the cut-off at the current positions.
fn pairs_within(w: &mut World) -> usize {
    let pairs = w.neighbour_pairs().expect("a neighbour list").clone();
    let p = w.particles().positions();
    pairs
        .iter_pairs()
        .filter(|&(i, j)| (p[j] - p[i]).norm_squared() < CUTOFF * CUTOFF)
        .count()
}

/// One measurement: prints `key=value` pairs on one line.
pub(crate) fn child(args: &[String]) -> Res<()> {
    let oriented = args[0] == "oriented";
    // `spacing-mixed`: the spacing block in mixed precision.
    let precision = if args[0] == "spacing-mixed" {
        Precision::Mixed
    } else {
        Precision::Double
    };
    let threads: usize = args[1].parse()?;
    let steps: usize = args[2].parse()?;
    let xv = args.get(3).filter(|a| *a != "-").map(PathBuf::from);
    let cells: usize = args.get(4).map_or(Ok(CELLS), |a| a.parse())?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()?;
    let mut w = world(oriented, precision, xv.as_deref(), cells)?;
    w.step()?;
    let pairs = pairs_within(&mut w);
    let listed = w.neighbour_pairs().map_or(0, |l| l.num_pairs());
    let rebuilds0 = w.neighbours().map_or(0, |l| l.rebuilds());
    let mut neighbour_s = 0.0;
    let cpu0 = cpu_seconds();
    let clock = Instant::now();
    for _ in 0..steps {
        neighbour_s += w.step()?.seconds_of("neighbours");
    }
    let secs = clock.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu0;
    let rebuilds = w.neighbours().map_or(0, |l| l.rebuilds()) - rebuilds0;
    println!(
        "seconds={secs} cpu={cpu} steps={steps} pairs={pairs} listed={listed} rebuilds={rebuilds} \
         neighbour_seconds={neighbour_s} peak_kb={}",
        peak_kb()
    );
    Ok(())
}
