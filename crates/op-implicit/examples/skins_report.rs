//! Writes `reports/skins.md`: the project's skin polygonization side by
//! side with splashsurf 0.14.1 on the same particles.
//!
//! Run: `cargo run -p op-implicit --profile ci --example skins_report`
//! (`SKINS_REPS=n` sets the interleaved repetitions, default 5; 3 at the
//! finest cube size). splashsurf is the binary installed by
//! `/work/shared/peers/install.sh splashsurf` (`$PEERS_HOME/bin`, default
//! `~/.cache/op-peers/bin`); without it the report holds our side only.
//!
//! Particles: a lattice of spacing 2 r filling a solid torus (major radius
//! 0.625, minor 0.255, r = 0.01): 100,052 particles. splashsurf: particle
//! radius r, smoothing length 2 r (kernel support 4 r), surface threshold
//! 0.6 (its default). Ours: a point primitive of support radius 4 r at each
//! particle (seed 002 §6), iso value 0.6 times the median field value at
//! the particles: the same fraction of the interior value as splashsurf's
//! threshold of its normalized density.

use op_dynamics::{Point3, Quat, Real, Vec3};
use op_implicit::{polygonize_with_stats, Field, PolygonizeParams, Primitive};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const R: Real = 0.01;

fn torus_particles() -> Vec<Point3> {
    let (major, minor, s) = (0.625, 0.255, 2.0 * R);
    let n = ((major + minor) / s) as i32 + 2;
    let m = (minor / s) as i32 + 2;
    let mut out = Vec::new();
    for k in -m..=m {
        for j in -n..=n {
            for i in -n..=n {
                let p = Point3::new(i as Real, j as Real, k as Real) * s;
                let q = p.x.hypot(p.y) - major;
                if q * q + p.z * p.z < minor * minor {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// A mesh as positions and triangles, for the checks common to both sides.
struct Tris {
    positions: Vec<[Real; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Tris {
    /// Closed, edge-manifold, consistently oriented
    /// ([`op_implicit::is_closed_oriented_manifold`]).
    fn closed_manifold(&self) -> bool {
        op_implicit::is_closed_oriented_manifold(&self.triangles)
    }

    /// Euler characteristic V - E + F over the referenced vertices.
    fn euler(&self) -> i64 {
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &i in t {
                used[i as usize] = true;
            }
        }
        let v = used.iter().filter(|u| **u).count() as i64;
        let f = self.triangles.len() as i64;
        v - 3 * f / 2 + f
    }

    /// Median over triangles of the smallest angle, degrees.
    fn median_min_angle(&self) -> Real {
        let mut angles: Vec<Real> = self
            .triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| Vec3::from(self.positions[i as usize]));
                (0..3)
                    .map(|k| {
                        let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                        a.angle(&b).to_degrees()
                    })
                    .fold(180.0, Real::min)
            })
            .filter(|a| a.is_finite())
            .collect();
        angles.sort_by(Real::total_cmp);
        angles.get(angles.len() / 2).copied().unwrap_or(Real::NAN)
    }
}

/// CPU seconds (user + system, 10 ms ticks) of this process, or of its
/// waited-for children, from `/proc/self/stat` (fields utime, stime,
/// cutime, cstime); 0 where it cannot be read.
fn cpu_seconds(children: bool) -> Real {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let at = if children { 13 } else { 11 };
    let tick = |k: usize| {
        fields
            .get(k)
            .and_then(|x| x.parse::<Real>().ok())
            .unwrap_or(0.0)
    };
    (tick(at) + tick(at + 1)) / 100.0
}

fn read_obj(path: &Path) -> Tris {
    let text = std::fs::read_to_string(path).expect("splashsurf's OBJ");
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let v: Vec<Real> = it.take(3).map(|x| x.parse().unwrap()).collect();
                positions.push([v[0], v[1], v[2]]);
            }
            Some("f") => {
                let f: Vec<u32> = it
                    .map(|x| x.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..f.len() - 1 {
                    triangles.push([f[0], f[k], f[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Tris {
        positions,
        triangles,
    }
}

struct Run {
    seconds: Real,
    /// CPU seconds (user + system) of the run: ours, the process's; the
    /// peer's, its child process's.
    cpu: Real,
    mesh: Option<Tris>,
    stats: Option<op_implicit::PolygonizeStats>,
}

fn ours(particles: &[Point3], iso: Real, cube: Real, threads: usize, keep: bool) -> Run {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let cpu0 = cpu_seconds(false);
        let start = Instant::now();
        let prims = particles
            .iter()
            .enumerate()
            .map(|(i, p)| {
                Primitive::point(Vec3::zeros(), 4.0 * R).posed(i as u32, p, &Quat::identity())
            })
            .collect();
        let field = Field::new(prims);
        let params = PolygonizeParams {
            iso,
            max_nodes_per_axis: 4096,
            ..PolygonizeParams::with_cell_size(cube * R)
        };
        let (mesh, stats) = polygonize_with_stats(&field, &params).unwrap();
        let seconds = start.elapsed().as_secs_f64();
        Run {
            seconds,
            cpu: cpu_seconds(false) - cpu0,
            mesh: keep.then(|| Tris {
                positions: mesh.positions().iter().map(|p| [p.x, p.y, p.z]).collect(),
                triangles: mesh.triangles().to_vec(),
            }),
            stats: Some(stats),
        }
    })
}

/// One splashsurf run; its time is its own "surface reconstruction
/// subdomain-grid" timing (reconstruction only: no file reading, writing
/// or checks), the process wall time beside it.
fn splashsurf(
    bin: &Path,
    input: &Path,
    out: &Path,
    cube: Real,
    threads: usize,
    keep: bool,
) -> (Run, Real) {
    let cpu0 = cpu_seconds(true);
    let start = Instant::now();
    let output = Command::new(bin)
        .args([
            "reconstruct",
            input.to_str().unwrap(),
            "-r",
            &R.to_string(),
            "-l",
            "2.0",
        ])
        .args([
            "-c",
            &cube.to_string(),
            "-n",
            &threads.to_string(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .expect("splashsurf runs");
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds(true) - cpu0;
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let log = String::from_utf8_lossy(&output.stdout).to_string()
        + &String::from_utf8_lossy(&output.stderr);
    let line = log
        .lines()
        .find(|l| {
            l.contains("surface reconstruction subdomain-grid:")
                || l.contains("surface reconstruction:")
        })
        .expect("splashsurf timing line");
    let ms: Real = line
        .split(", ")
        .nth(1)
        .and_then(|s| s.split("ms").next())
        .and_then(|s| s.trim().parse().ok())
        .expect("milliseconds");
    (
        Run {
            seconds: ms / 1e3,
            cpu,
            mesh: keep.then(|| read_obj(out)),
            stats: None,
        },
        wall,
    )
}

const PICTURES: &str = "
## The shipped skinned scenes

Contact sheets of the shipped scenes with skins, at their default skin shape (thickness half the
kernel radius for squares, smoothness 1.5), regenerated by `cargo run --release -p op-experiments
--example gallery`; every exported skin frame of every shipped scene is checked closed and
edge-manifold by `tests/shipped_scenes.rs`, and each skin of these four scenes is one closed surface
of Euler characteristic 2 in every frame (`tests/skinned_sheet.rs`): the skins keep their thickness to
a sheet's rim and as it stretches (op-implicit `stretch`, amplitudes normalized by the local density of
primitives), so the cloth is 0.8 r0 thick and stays whole over the ball. The shape of default skins (a tetrahedron of point
primitives round, a flat sheet flat at its thickness, curved ribbons without bumps, a closed shell
smooth, small squares still covering a sheet) is measured by the tests of
`crates/op-scene/src/skin_shape.rs` and `tests/skinned_sheet.rs` (`-- --nocapture` prints the
figures).

| `ball_vs_spiral` | `sheet_on_box` |
|---|---|
| ![ball vs spiral](../docs/gallery/ball_vs_spiral.png) | ![sheet on box](../docs/gallery/sheet_on_box.png) |
| `sheet_on_sphere` | `cookbook/skinned_hit` |
| ![sheet on sphere](../docs/gallery/sheet_on_sphere.png) | ![skinned hit](../docs/gallery/cookbook_skinned_hit.png) |
";

const NOTES: &str = "
## Reading the figures

- Both meshes are plain marching cubes of the same kind of field (a sum of compactly supported
  kernels of radius 4 r), at the same cube size, without smoothing or decimation; triangle counts
  differ by a few per cent because the kernels differ (Wyvill's polynomial here, splashsurf's cubic
  spline) and so the iso-surfaces differ slightly.
- The narrow band here skips the blocks no primitive reaches and those whose kernel bounds lie on
  one side of the iso value. For a solid particle cloud with support 4 r, those bounds cannot
  certify the interior at these block sizes (a block's half diagonal is 0.6-2.4 times the support
  radius, so the farthest-distance bound falls below the iso value; it would take blocks of half
  diagonal under about 0.1 of the support radius): the interior is sampled, as
  splashsurf's dense subdomains sample it. The sampled volume is then the support of the
  particles, and the time is set by the cost per kernel evaluation (ours: f64, 2-lane SSE2;
  splashsurf: f32 with AVX2). On thin skins (sheets, shells) the band follows the area (unit test
  `field_evaluations_follow_the_area`).
- Times on this shared 2-core machine drift between runs (other builds run beside); the runs are
  interleaved so the ratio is the figure to read.
";

fn median_spread(v: &[Real]) -> (Real, Real, Real) {
    let mut s = v.to_vec();
    s.sort_by(Real::total_cmp);
    (s[s.len() / 2], s[0], s[s.len() - 1])
}

fn sh(cmd: &str, args: &[&str]) -> String {
    Command::new(cmd)
        .args(args)
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|_| "?".into())
}

fn main() {
    let reps: usize = std::env::var("SKINS_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let particles = torus_particles();
    let tmp = std::env::temp_dir().join("skins_report");
    std::fs::create_dir_all(&tmp).unwrap();
    let input = tmp.join("torus.xyz");
    let bytes: Vec<u8> = particles
        .iter()
        .flat_map(|p| [p.x, p.y, p.z].map(|x| (x as f32).to_le_bytes()))
        .flatten()
        .collect();
    std::fs::write(&input, bytes).unwrap();
    let iso = iso_value(&particles);
    let peer = peer_binary();
    let cubes: Vec<Real> = std::env::var("SKINS_CUBES")
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or_else(|_| vec![1.0, 0.5, 0.25]);

    let thread_counts: Vec<usize> = std::env::var("SKINS_THREADS")
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or_else(|_| vec![1, 2]);
    let setup = Setup {
        particles: &particles,
        iso,
        input: &input,
        tmp: &tmp,
        peer: peer.as_deref(),
    };
    let mut tables = Tables::default();
    for &cube in &cubes {
        let reps = if cube < 0.3 { reps.min(3) } else { reps };
        for &threads in &thread_counts {
            measure(&setup, cube, threads, reps, &mut tables);
        }
    }
    let md = report(&setup, &tables);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../reports/skins.md");
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, md).unwrap();
    eprintln!("wrote {}", path.display());
}

/// The iso value: 0.6 of the median field value at the particles.
fn iso_value(particles: &[Point3]) -> Real {
    let field = Field::new(
        particles
            .iter()
            .enumerate()
            .map(|(i, p)| {
                Primitive::point(Vec3::zeros(), 4.0 * R).posed(i as u32, p, &Quat::identity())
            })
            .collect(),
    );
    let mut at = field.values(particles);
    at.sort_by(Real::total_cmp);
    0.6 * at[at.len() / 2]
}

/// The splashsurf binary under `$PEERS_HOME/bin` (default
/// `~/.cache/op-peers/bin`), unless missing or `SKINS_NO_PEER` is set.
fn peer_binary() -> Option<PathBuf> {
    let home = std::env::var("PEERS_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|_| {
            PathBuf::from(std::env::var("HOME").unwrap_or_default()).join(".cache/op-peers")
        });
    let bin = home.join("bin/splashsurf");
    (bin.exists() && std::env::var("SKINS_NO_PEER").is_err()).then_some(bin)
}

/// What every measurement shares: the particles, the iso value, the
/// particle file splashsurf reads, the directory of its output, the
/// splashsurf binary (if any).
struct Setup<'a> {
    particles: &'a [Point3],
    iso: Real,
    input: &'a Path,
    tmp: &'a Path,
    peer: Option<&'a Path>,
}

/// The rows of the report's tables, one per cube size and thread count
/// (`checks` and `band`: one per cube size, from the 1-thread run).
#[derive(Default)]
struct Tables {
    time: String,
    cpu: String,
    checks: String,
    band: String,
}

/// The measurements of one cube size and thread count: our times (`a`)
/// and splashsurf's (`b`, its own reconstruction timing), its process wall
/// times, the CPU times of both, the meshes of the 1-thread first run.
#[derive(Default)]
struct Samples {
    a: Vec<Real>,
    b: Vec<Real>,
    walls: Vec<Real>,
    cpu_a: Vec<Real>,
    cpu_b: Vec<Real>,
    mesh_a: Option<Tris>,
    mesh_b: Option<Tris>,
}

/// `reps` interleaved runs of ours and splashsurf at one cube size and
/// thread count; appends their rows to `tables` (the narrow band's from
/// the 1-thread first run).
fn measure(setup: &Setup, cube: Real, threads: usize, reps: usize, tables: &mut Tables) {
    let Setup {
        particles,
        iso,
        input,
        tmp,
        peer,
    } = *setup;
    let mut samples = Samples::default();
    for rep in 0..reps {
        let keep = rep == 0 && threads == 1;
        let run = ours(particles, iso, cube, threads, keep);
        samples.a.push(run.seconds);
        samples.cpu_a.push(run.cpu);
        if let (true, Some(st)) = (keep, run.stats) {
            let _ = writeln!(
                tables.band,
                "| {cube} r | {} | {} / {} | {} | {:.1} |",
                st.grid_nodes,
                st.sampled_blocks,
                st.blocks,
                st.sampled_nodes,
                st.field_evaluations as Real / 1e6
            );
        }
        samples.mesh_a = samples.mesh_a.or(run.mesh);
        if let Some(bin) = &peer {
            let (run, wall) = splashsurf(bin, input, &tmp.join("surface.obj"), cube, threads, keep);
            samples.b.push(run.seconds);
            samples.cpu_b.push(run.cpu);
            samples.walls.push(wall);
            samples.mesh_b = samples.mesh_b.or(run.mesh);
        }
        eprintln!(
            "cube {cube} threads {threads} rep {rep}: ours {:.3}s splashsurf {:?}",
            samples.a[rep],
            samples.b.get(rep)
        );
    }
    write_rows(tables, cube, threads, reps, samples);
}

/// The time, CPU time and mesh rows of one cube size and thread count.
fn write_rows(tables: &mut Tables, cube: Real, threads: usize, reps: usize, samples: Samples) {
    let Samples {
        a,
        b,
        walls,
        cpu_a,
        cpu_b,
        mesh_a,
        mesh_b,
    } = samples;
    let (table, cpu_table, checks) = (&mut tables.time, &mut tables.cpu, &mut tables.checks);
    let (ma, lo_a, hi_a) = median_spread(&a);
    let row_b = if b.is_empty() {
        (
            "not installed".to_string(),
            "-".to_string(),
            "-".to_string(),
        )
    } else {
        let (mb, lo_b, hi_b) = median_spread(&b);
        let (mw, _, _) = median_spread(&walls);
        (
            format!("{mb:.3} ({lo_b:.3}-{hi_b:.3}; process {mw:.3})"),
            format!("{:.2}x", ma / mb),
            String::new(),
        )
    };
    let _ = writeln!(
        table,
        "| {cube} r | {threads} | {ma:.3} ({lo_a:.3}-{hi_a:.3}) | {} | {} | {reps} |",
        row_b.0, row_b.1
    );
    let (ca, _, _) = median_spread(&cpu_a);
    let (cb, ratio) = if cpu_b.is_empty() {
        ("-".to_string(), "-".to_string())
    } else {
        let (cb, _, _) = median_spread(&cpu_b);
        (format!("{cb:.2}"), format!("{:.2}x", ca / cb))
    };
    let _ = writeln!(
        cpu_table,
        "| {cube} r | {threads} | {ca:.2} | {cb} | {ratio} |"
    );
    for (name, m) in [("ours", mesh_a), ("splashsurf", mesh_b)] {
        if let Some(m) = m {
            let _ = writeln!(
                checks,
                "| {cube} r | {name} | {} | {} | {} | {} | {:.1} |",
                m.triangles.len(),
                m.positions.len(),
                if m.closed_manifold() { "yes" } else { "no" },
                m.euler(),
                m.median_min_angle()
            );
        }
    }
}

/// The whole report: the machine (read at the end), the setup, the time,
/// CPU time, mesh and narrow-band tables, the notes.
fn report(setup: &Setup, tables: &Tables) -> String {
    let (particles, iso, peer) = (setup.particles, setup.iso, setup.peer);
    let mut md = String::new();
    let _ = writeln!(md, "# Skins: polygonization side by side with splashsurf\n");
    let _ = writeln!(
        md,
        "Generated by `cargo run -p op-implicit --profile ci --example skins_report` (issue 19).\n"
    );
    md += &machine_section(peer);
    let _ = writeln!(md, "## Setup\n");
    let _ = writeln!(
        md,
        "{} particles on a lattice of spacing 2 r filling a solid torus (major radius 0.625, minor 0.255, \
         r = {R}). splashsurf 0.14.1: `reconstruct -r {R} -l 2.0 -c <cube> -n <threads>` (kernel support \
         4 r, threshold 0.6, its defaults otherwise: no smoothing, no decimation). Ours: \
         `polygonize_with_stats` on a point primitive of support radius 4 r at each particle, iso value \
         0.6 x the median field value at the particles = {iso:.4} (splashsurf's threshold is the same \
         fraction of its normalized interior density), normals from the field gradient (splashsurf: none).\n",
        particles.len()
    );
    let _ = writeln!(
        md,
        "Times: our wall time of building the field and polygonizing (in process, rayon pool of \
         the given size); splashsurf's own `surface reconstruction subdomain-grid` timing (no file reading, \
         writing or checks), its process wall time in brackets. Runs interleaved (ours, splashsurf, ours, ...); \
         median and (min-max). Ratio = our median / splashsurf's median: the target is at most 1.0x.\n"
    );
    let _ = writeln!(md, "## Time\n\n| cube | threads | ours, s | splashsurf, s | ratio | runs |\n|---|---|---|---|---|---|");
    md += &tables.time;
    let _ = writeln!(
        md,
        "\n## CPU time\n\nUser + system CPU seconds (10 ms ticks), median over the same runs: ours of the \
         timed part, splashsurf of its whole process (reading the particles, reconstructing, writing \
         the OBJ: an upper bound of its reconstruction's CPU). On this shared machine the wall time \
         includes waiting for a core; the CPU time does not.\n\n\
         | cube | threads | ours, CPU s | splashsurf process, CPU s | ratio |\n|---|---|---|---|---|"
    );
    md += &tables.cpu;
    let _ = writeln!(
        md,
        "\n## Meshes (1-thread run)\n\nClosed/manifold: every directed edge once and its reverse once. Euler \
         characteristic V - E + F (a torus: 0). Quality: median over triangles of the smallest angle.\n\n\
         | cube | side | triangles | vertices | closed, manifold | Euler | median min angle, deg |\n|---|---|---|---|---|---|---|"
    );
    md += &tables.checks;
    let _ = writeln!(
        md,
        "\n## Our narrow band (1-thread run)\n\nBlocks of 16 x 8 x 8 cells; a block is sampled when some \
         primitive's support reaches it and the kernel bounds of its point primitives (nearest and \
         farthest distance to the block) straddle the iso value; nodes on block faces count once per \
         block. Evaluations: primitive kernels splatted onto nodes.\n\n\
         | cube | grid nodes | sampled blocks | sampled nodes | kernel evaluations, M |\n|---|---|---|---|---|"
    );
    md += &tables.band;
    md += NOTES;
    md += PICTURES;
    md
}

/// The machine's facts: CPU, cores, compiler, load at the end, date, the
/// splashsurf version.
fn machine_section(peer: Option<&Path>) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "## Machine\n\n| | |\n|---|---|");
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "?".into());
    let _ = writeln!(md, "| CPU | {cpu} |");
    let _ = writeln!(
        md,
        "| nproc | {} |",
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(0)
    );
    let _ = writeln!(md, "| rustc | {} |", sh("rustc", &["-V"]));
    let _ = writeln!(
        md,
        "| our splat's instruction set (runtime dispatch) | {} |",
        op_dynamics::simd_isa()
    );
    let _ = writeln!(
        md,
        "| load average at the end (1, 5, 15 min) | {} |",
        std::fs::read_to_string("/proc/loadavg")
            .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(", "))
            .unwrap_or_else(|_| "?".into())
    );
    let _ = writeln!(
        md,
        "| date | {} |",
        sh("date", &["-u", "+%Y-%m-%d %H:%M UTC"])
    );
    let _ = writeln!(
        md,
        "| splashsurf | {} |\n",
        peer.as_ref()
            .map(|b| sh(b.to_str().unwrap(), &["--version"]))
            .unwrap_or_else(|| "not installed (`/work/shared/peers/install.sh splashsurf`)".into())
    );
    md
}
