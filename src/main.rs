//! `opsim`: run oriented-particle scenes, check them, render pictures.
//!
//! Thin by design (after ripgrep): parse flags into validated
//! arguments in one place, call op-scene, print the error chain, map errors
//! to exit codes (README "Running scenes"): 0 done, 2 bad input, 3 simulation diverged.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{anyhow, Context, Result};
use clap::{Parser, Subcommand};
use op_render::FrameChoice;
use op_scene::export::FrameFormat;
use op_scene::{BuiltScene, CheckpointEvery, RunError, RunOptions};

/// `println!` that ends the program quietly when stdout is closed early (a
/// broken pipe, as in `opsim check SCENE | head -1`) instead of panicking;
/// any other write error is reported with exit code 1.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout().lock(), $($arg)*) {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
            eprintln!("opsim: error: writing to stdout: {e}");
            std::process::exit(1);
        }
    }};
}

mod render_cmd;

use render_cmd::{demo_contact_sheet, render_command, RenderArgs};

/// The default demo scene, embedded so `opsim` works from any directory.
const DEMO_SCENE: &str = include_str!("../scenes/spiral.ron");

#[derive(Parser, Debug)]
#[command(
    name = "opsim",
    version,
    about = "Shape-memory objects from oriented particles: run scenes, export OBJ frames, render pictures",
    long_about = "Shape-memory objects from oriented particles.\n\nWith no command, runs the default demo scene and writes it under ./opsim-out/<scene>/."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

/// The arguments of `opsim run`.
#[derive(clap::Args, Debug)]
struct RunArgs {
    /// Scene file (.ron or .json).
    scene: PathBuf,
    /// Output directory. Default: `./opsim-out/<scene name>`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Number of frames to write (overrides the scene's duration).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Worker threads (results are identical for any count).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    threads: Option<u64>,
    /// Lift the work limits (steps, frames, particle-steps, created
    /// particles) that keep every valid scene's run bounded.
    #[arg(long)]
    no_work_limits: bool,
    /// Largest number of particle-steps (particles times steps) the run
    /// may take, and 30 times as many pair-steps (interacting pairs
    /// times steps); a scene that needs more is refused before it
    /// starts. Default: 1e12.
    #[arg(long)]
    max_particle_steps: Option<f64>,
    /// Print the seconds spent in each stage of the step at the end.
    #[arg(long)]
    profile: bool,
    /// Accept objects breaking into pieces: a warning instead of a
    /// divergence (exit 3). A scene that tears on purpose says so in
    /// its header instead (`// expect-warning: object "NAME" broke
    /// into N pieces (why)`).
    #[arg(long)]
    allow_breakup: bool,
    /// Run a `dt` beyond the estimated edge of stability (`opsim check`
    /// prints it) instead of refusing it.
    #[arg(long)]
    allow_unstable_step: bool,
    /// Frame file formats, comma-separated: obj (one y-up OBJ file per
    /// object and frame, for Blender and other OBJ readers), ply
    /// (binary PLY, z-up), vtu (particle state with attributes, for
    /// ParaView), usd (one time-sampled USD file of the whole run,
    /// usd/run.usda).
    #[arg(long, value_delimiter = ',', default_value = "obj", value_parser = parse_format)]
    format: Vec<FrameFormat>,
    /// When to write `checkpoint.bin` into the output directory (what
    /// `--resume` goes on from; always after the last frame too): `60s`
    /// (the default) after the first frame a minute after the last
    /// checkpoint, `10` every 10 frames, `off` never.
    #[arg(long, default_value = "60s", value_parser = parse_checkpoint_every)]
    checkpoint_every: CheckpointSetting,
    /// Go on from the checkpoint in the output directory of an
    /// interrupted run (killed, out of disk, rebooted) instead of
    /// starting over: run it with the same scene file, --frames and
    /// --format; the frames, metrics and summary come out as an
    /// uninterrupted run's.
    #[arg(long)]
    resume: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene: OBJ frames, metrics.csv and summary.json.
    Run(RunArgs),
    /// Validate a scene, print what it enables and estimate its largest
    /// stable step (on a bounded sample of the scene: memory proportional to
    /// the scene file, not to its particles).
    Check {
        /// Scene file (.ron or .json).
        scene: PathBuf,
        /// Lift the work limits, as `run --no-work-limits`.
        #[arg(long)]
        no_work_limits: bool,
        /// As `run --max-particle-steps`.
        #[arg(long)]
        max_particle_steps: Option<f64>,
    },
    /// Fit a particle surface to a point set (seed 000 §7) and write its
    /// triangle mesh; prints one JSON line of figures.
    Fit {
        /// Samples: .xyz or .pwn (`x y z [nx ny nz]` per line), .ply (ascii
        /// or binary_little_endian) or .obj (`v`, optional `vn`).
        points: PathBuf,
        /// Output mesh (.obj), written atomically, in the samples' own
        /// coordinates (no axis change, so it overlays the input; run
        /// frames are written y-up instead, see the README).
        #[arg(long)]
        out: PathBuf,
        /// Sample spacing. Default: the median nearest-sample distance.
        #[arg(long)]
        spacing: Option<f64>,
        /// Open data: stretching only, so holes wider than the search range
        /// (2.5 spacings) and than the gaps random sampling leaves by chance
        /// at the samples' density (about 4.7 spacings on 5,000 samples)
        /// stay open. Default: open when the samples have a boundary (a
        /// chain of samples whose neighbours all lie to one side).
        #[arg(long, conflicts_with = "closed")]
        open: bool,
        /// Closed data: holes up to 8 spacings are closed even where the
        /// samples have a boundary.
        #[arg(long)]
        closed: bool,
        /// Relaxation time after the samples are released (in time units
        /// of a unit spacing): smooths noisy samples, moving the surface
        /// off them. At most 100 (20,000 relaxation steps). Default: 0 (the
        /// surface interpolates the samples).
        #[arg(long, default_value_t = 0.0)]
        relax: f64,
        /// Approximate the samples within their noise: seed the particles
        /// on a smoothed estimate of the surface, thinned to at least four
        /// noise levels apart, instead of on every sample. Default: when
        /// the estimated noise exceeds a tenth of the samples' spacing.
        #[arg(long, conflicts_with = "interpolate")]
        approximate: bool,
        /// Pass through every sample, however noisy (the paper's surface
        /// interpolation).
        #[arg(long)]
        interpolate: bool,
        /// Print the seconds of each stage (reading, the fit's own stages,
        /// writing) on standard error, as `run --profile` does; standard
        /// output keeps its one JSON line.
        #[arg(long)]
        profile: bool,
    },
    /// Print the scene format as a JSON Schema (for editors that complete
    /// and check JSON scenes), or with `--markdown` as the field reference
    /// of `docs/scenes.md` (every field with type, unit, default, meaning).
    Schema {
        /// The Markdown field reference instead of the JSON Schema.
        #[arg(long)]
        markdown: bool,
    },
    /// Render an OBJ frame, or a contact sheet of a run directory, to PNG;
    /// or animate a run directory's frames to GIF.
    Render(RenderArgs),
}

/// An error with the exit code it maps to.
struct Failure {
    code: u8,
    error: anyhow::Error,
}

impl<E: Into<anyhow::Error>> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure {
            code: 2,
            error: e.into(),
        }
    }
}

fn main() -> ExitCode {
    std::panic::set_hook(Box::new(|info| {
        eprintln!("opsim: internal error: {info}");
        eprintln!("this is a bug; please report it with the scene that caused it");
    }));
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("opsim: error: {:#}", f.error);
            ExitCode::from(f.code)
        }
    }
}

/// `opsim` alone: runs the demo scene (`scenes/spiral.ron`) into
/// `opsim-out/spiral`, draws its contact sheet and animates it
/// (`preview.gif`).
fn demo() -> Result<(), Failure> {
    let scene = op_scene::parse_scene(
        DEMO_SCENE,
        op_scene::Format::Ron,
        "<demo: scenes/spiral.ron>",
    )?;
    let built = scene.build_for_run(None, None)?;
    let out = Path::new("opsim-out").join(built.name());
    let opts = RunOptions {
        out_dir: out.clone(),
        formats: vec![FrameFormat::OBJ],
        ..Default::default()
    };
    run_built(built, &opts, false)?;
    demo_contact_sheet(&out)
}

fn dispatch(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        None => demo(),
        Some(Command::Run(args)) => run_command(args),
        Some(Command::Check {
            scene,
            no_work_limits,
            max_particle_steps,
        }) => check(&scene, limits(no_work_limits, max_particle_steps)?),
        Some(Command::Fit {
            points,
            out,
            spacing,
            open,
            closed,
            relax,
            approximate,
            interpolate,
            profile,
        }) => run_fit(
            &points,
            &out,
            op_scene::fit::FitParams {
                spacing,
                open: (open || closed).then_some(open),
                relax_time: relax,
                approximate: (approximate || interpolate).then_some(approximate),
                ..Default::default()
            },
            profile,
        ),
        Some(Command::Schema { markdown }) => {
            if markdown {
                outln!("{}", op_scene::reference::field_reference().trim_end());
            } else {
                let schema = op_scene::reference::json_schema();
                outln!("{}", serde_json::to_string_pretty(&schema)?);
            }
            Ok(())
        }
        Some(Command::Render(args)) => render_command(args),
    }
}

/// `opsim run`.
fn run_command(args: RunArgs) -> Result<(), Failure> {
    if let Some(k) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(k as usize)
            .build_global()
            .context("cannot start the thread pool")?;
    }
    let frames = args
        .frames
        .map(|f| usize::try_from(f).unwrap_or(usize::MAX));
    let limits = limits(args.no_work_limits, args.max_particle_steps)?;
    let mut built = load(&args.scene, limits, frames)?;
    if args.allow_breakup {
        built.accept_breakup();
    }
    if !args.allow_unstable_step {
        refuse_unstable_step(&args.scene, &built)?;
    }
    let opts = RunOptions {
        out_dir: args
            .out
            .unwrap_or_else(|| Path::new("opsim-out").join(built.name())),
        frames,
        formats: args.format,
        checkpoints: args.checkpoint_every.0,
        resume: args.resume,
    };
    run_built(built, &opts, args.profile)
}

/// Whether `path` names an OBJ file (extension `.obj`, any case): what
/// `render` reads and `fit` writes.
fn is_obj(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// `opsim fit`: read, fit, write the mesh, print the figures as JSON (and
/// with `profile` the stages' seconds on standard error).
fn run_fit(
    points: &Path,
    out: &Path,
    params: op_scene::fit::FitParams,
    profile: bool,
) -> Result<(), Failure> {
    let started = std::time::Instant::now();
    let relax = params.relax_time;
    // Checked before the fit, which may take minutes.
    if !is_obj(out) {
        return Err(anyhow!(
            "--out {}: the fitted mesh is written as Wavefront OBJ: give a path ending in .obj",
            out.display()
        )
        .into());
    }
    let most = op_modeling::fit::MAX_RELAX_TIME;
    if !(0.0..=most).contains(&relax) {
        return Err(anyhow!(
            "--relax {relax}: must be between 0 and {most} (time units of a unit spacing; a \
             relaxation of 10 already moves the surface off the samples by a fraction of a \
             spacing)"
        )
        .into());
    }
    // Refused from the file's header or point lines, before its points
    // are read, when it holds more samples than a fit takes.
    let data =
        op_scene::pointsets::read_point_set_at_most(points, op_modeling::fit::MAX_PARTICLES)?;
    let mut stages = vec![("read", started.elapsed().as_secs_f64())];
    let (fit, fitted) = op_scene::fit::fit_with_stages(&data, &params).map_err(|e| Failure {
        // A relaxation that diverged is a simulation failure (exit 3).
        code: if matches!(
            e,
            op_scene::fit::FitError::World(_) | op_scene::fit::FitError::Diverged(_)
        ) {
            3
        } else {
            2
        },
        // The spacing's message names the flag it came from.
        error: match e {
            op_scene::fit::FitError::Spacing { .. } => anyhow!("--{e}"),
            e => anyhow!(e),
        }
        .context(format!("cannot fit {}", points.display())),
    })?;
    stages.extend(fitted);
    let writing = std::time::Instant::now();
    op_scene::fit::write_obj(out, &fit)
        .with_context(|| format!("cannot write {}", out.display()))?;
    stages.push(("write", writing.elapsed().as_secs_f64()));
    outln!("{}", op_scene::fit::figures_json(&fit));
    if profile {
        print_fit_profile(&stages, started.elapsed().as_secs_f64());
    }
    Ok(())
}

/// `opsim fit --profile`'s table on standard error: seconds and share of
/// the wall time per stage, in the fit's order.
fn print_fit_profile(stages: &[(&str, f64)], wall: f64) {
    let width = stages
        .iter()
        .map(|(n, _)| n.len())
        .max()
        .unwrap_or(5)
        .max(5);
    eprintln!("{:<width$} {:>10} {:>7}", "stage", "seconds", "share");
    for (name, secs) in stages {
        eprintln!(
            "{name:<width$} {secs:>10.4} {:>6.1}%",
            100.0 * secs / wall.max(f64::MIN_POSITIVE)
        );
    }
    eprintln!("{:<width$} {wall:>10.4} {:>6.1}%", "wall", 100.0);
}

/// `--view` and `--up`'s parser: `X,Y,Z`, finite and not all zero.
pub(crate) fn parse_direction(text: &str) -> Result<[f64; 3], String> {
    let c: Vec<f64> = text
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{text:?}: {e}; expected X,Y,Z"))?;
    let v =
        <[f64; 3]>::try_from(c).map_err(|_| format!("{text:?}: expected three numbers X,Y,Z"))?;
    if v.iter().any(|x| !x.is_finite()) || v.iter().all(|&x| x == 0.0) {
        return Err(format!("{text:?}: a direction must be finite and non-zero"));
    }
    Ok(v)
}

/// `opsim render --frames`: `N` frames chosen evenly, or `A:B:S`.
pub(crate) fn parse_frame_choice(text: &str) -> Result<FrameChoice, String> {
    let expected = "expected a count N >= 1 or frame numbers A:B:S (first, last, step >= 1)";
    let parts: Vec<&str> = text.split(':').collect();
    let number = |t: &str| {
        t.trim()
            .parse::<u64>()
            .map_err(|_| format!("{text:?}: {expected}"))
    };
    match parts.as_slice() {
        [n] => match number(n)? {
            0 => Err(format!("{text:?}: {expected}")),
            n => Ok(FrameChoice::Spread(
                usize::try_from(n).unwrap_or(usize::MAX),
            )),
        },
        [a, b, step] => {
            let (first, last, step) = (number(a)?, number(b)?, number(step)?);
            if step == 0 || last < first {
                return Err(format!("{text:?}: {expected}, A <= B"));
            }
            Ok(FrameChoice::Numbers { first, last, step })
        }
        _ => Err(format!("{text:?}: {expected}")),
    }
}

/// `--format`'s parser: one format name.
fn parse_format(name: &str) -> Result<FrameFormat, String> {
    FrameFormat::named(name)
}

/// `--checkpoint-every`: when to write checkpoints, or never.
#[derive(Clone, Copy, Debug)]
struct CheckpointSetting(Option<CheckpointEvery>);

fn parse_checkpoint_every(text: &str) -> Result<CheckpointSetting, String> {
    CheckpointEvery::parse_setting(text).map(CheckpointSetting)
}

/// The work limits the flags ask for.
fn limits(no_work_limits: bool, max_particle_steps: Option<f64>) -> Result<op_scene::WorkLimits> {
    let mut limits = if no_work_limits {
        op_scene::WorkLimits::unlimited()
    } else {
        op_scene::WorkLimits::default()
    };
    if let Some(m) = max_particle_steps {
        if m.is_nan() || m <= 0.0 {
            return Err(anyhow!("--max-particle-steps {m}: must be > 0"));
        }
        limits = limits.with_particle_steps(m);
    }
    Ok(limits)
}

fn load(path: &Path, limits: op_scene::WorkLimits, frames: Option<usize>) -> Result<BuiltScene> {
    let scene = op_scene::load_scene_with(path, limits, frames)?;
    let base = path.parent().map(Path::to_path_buf);
    Ok(scene.build_for_run(base.as_deref(), Some(path.to_path_buf()))?)
}

/// Refuses a `dt` beyond the estimated edge of stability (exit 2), naming
/// the edge, the recommended step and the flag that runs it anyway.
fn refuse_unstable_step(path: &Path, built: &BuiltScene) -> Result<(), Failure> {
    let dt = built.world().params().dt;
    let refusal = built
        .step_estimate()
        .and_then(|e| e.refusal(dt, &path.display().to_string(), "--allow-unstable-step"));
    match refusal {
        Some(message) => Err(anyhow!(message).into()),
        None => Ok(()),
    }
}

fn run_built(mut built: BuiltScene, opts: &RunOptions, profile: bool) -> Result<(), Failure> {
    let out_dir = &opts.out_dir;
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} frames  {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let result = op_scene::run(&mut built, opts, &mut |k, total| {
        bar.set_length(total as u64);
        bar.set_position(k as u64);
    });
    bar.finish_and_clear();
    let summary = match &result {
        Ok(s) => Some(s),
        Err(RunError::Diverged { summary, .. }) => Some(&**summary),
        Err(_) => None,
    };
    if let Some(s) = summary {
        for w in &s.warnings {
            eprintln!("opsim: warning: {w}");
        }
        for e in &s.expected {
            eprintln!("opsim: expected: {e}");
        }
    }
    if let (true, Some(s)) = (profile, summary) {
        print_profile(s);
    }
    match result {
        Ok(summary) => {
            outln!(
                "{}: {} frames, {} steps, t = {:.4}, {:.2} s -> {}",
                summary.scene,
                summary.frames,
                summary.steps,
                summary.sim_time,
                summary.wall_seconds,
                out_dir.display()
            );
            Ok(())
        }
        Err(RunError::Diverged { message, summary }) => Err(Failure {
            code: 3,
            error: anyhow!(
                "{message}\n{} frames written to {} (summary.json says diverged: true)",
                summary.frames,
                out_dir.display()
            ),
        }),
        Err(e) => Err(e.into()),
    }
}

/// The `--profile` table: seconds and share of the wall time per stage, in
/// decreasing order.
fn print_profile(s: &op_scene::Summary) {
    let mut rows: Vec<(&String, &f64)> = s.stages.iter().collect();
    rows.sort_by(|a, b| b.1.total_cmp(a.1).then(a.0.cmp(b.0)));
    outln!("{:<12} {:>10} {:>7}", "stage", "seconds", "share");
    for (name, secs) in rows {
        outln!(
            "{name:<12} {secs:>10.4} {:>6.1}%",
            100.0 * secs / s.wall_seconds.max(f64::MIN_POSITIVE)
        );
    }
    outln!("{:<12} {:>10.4} {:>6.1}%", "wall", s.wall_seconds, 100.0);
}

/// Particle-steps `opsim check` spends at most on finding the slowest mode
/// of a scene that does not ask for it, each pair's evaluation counted as
/// one and each step's fixed cost as 50 (`op_scene::damping::resolve_within`),
/// so that check stays within seconds. Measured with `/usr/bin/time opsim check` on this project's
/// 2-core machine: a particle-step of the shipped figures' searches costs
/// about 0.2 µs and a pair 35-50 ns, the densest (`fig_06_weld`: 2.2e6
/// particle-steps and 2.1e7 pair-steps) taking 1.1 s; a cohesion pair
/// inside the start of its material's table (exact quadrature of the
/// energy) about 150 ns: 3e7 of them about 4.5 s.
const CHECK_MODE_WORK: f64 = 3e7;

/// What `opsim check` adds to the line of an object made by a `HexSheet`
/// that is not square within 5%: its extent, and the `ny` that would make
/// it square (rows are `spacing √3/2` apart, so `nx = ny` is longer than
/// wide; [`op_scene::Generator::sheet_extent`]).
fn sheet_note(g: &op_scene::Generator) -> String {
    let (Some((w, l)), op_scene::Generator::HexSheet { spacing, .. }) = (g.sheet_extent(), g)
    else {
        return String::new();
    };
    if w <= 0.0 || l <= 0.0 || (l / w - 1.0).abs() <= 0.05 {
        return String::new();
    }
    let square_ny = 1.0 + (w / (spacing * 3f64.sqrt() / 2.0)).round();
    format!(
        ", a sheet {w:.1} wide and {l:.1} long (rows are spacing √3/2 apart: ny = \
         {square_ny} makes it square)"
    )
}

/// `opsim check`: validates the scene, builds a bounded sample of it
/// (`op_scene::stability`) and prints what it enables, its objects and the
/// stable-step estimate, with a warning when `dt` exceeds it, then the
/// slowest mode and its critical damping (`op_scene::damping`) when the
/// scene is small enough. A scene with `linear_damping: "Critical"` is
/// checked as it runs, with the numbers of the rule (or refused).
fn check(path: &Path, limits: op_scene::WorkLimits) -> Result<(), Failure> {
    let (written, counts, estimate) = op_scene::load_scene_estimated(path, limits, None)?;
    // The slowest mode and its critical damping, for any scene small
    // enough; a scene that asks for them runs with them (or cannot run).
    let mut as_critical = written.clone();
    as_critical.world.linear_damping = op_scene::Damping::Critical;
    as_critical.world.angular_damping = 0.0;
    let asks = written.world.linear_damping.is_critical();
    let budget = if asks {
        written.limits.max_particle_steps
    } else {
        CHECK_MODE_WORK
    };
    let found = op_scene::damping::resolve_within(&as_critical, path.parent(), budget);
    let (critical, scene) = match found {
        Ok((resolved, c)) => (Ok(c), if asks { resolved } else { written.clone() }),
        Err(e) if asks => return Err(e.into()),
        Err(e) => (Err(e), written.clone()),
    };
    let sample = op_scene::stability::sample(&scene, path.parent())?;
    let built = &sample.built;
    let w = &built.world();
    // Names as long as the scene file allows are cut in what is printed.
    let name = |n: &str| op_scene::input::excerpt(n);
    outln!("scene {:?} ({}): valid", name(&scene.name), path.display());
    for ((o, n), b) in scene.objects.iter().zip(&counts).zip(built.objects()) {
        outln!(
            "  object {:?}: {n} particles, rest spacing {:.4}{}",
            name(&o.name),
            b.rest_spacing,
            sheet_note(&o.generator)
        );
    }
    outln!("  enabled: {}", sample.stages.join(", "));
    match w.neighbours() {
        Some(n) => outln!(
            "  neighbours: {:?}, cut-off {:.4}, skin {:.4}",
            n.backend(),
            n.cutoff(),
            n.skin()
        ),
        None => outln!("  neighbours: none (no interaction enabled)"),
    }
    let p = w.params();
    outln!(
        "  integrator: {:?}, dt {}, duration {}, {} frames per unit time",
        p.scheme,
        p.dt,
        scene.world.duration,
        scene.world.frame_rate
    );
    let e = &sample.estimate;
    let contact = e.contact.as_ref().map_or(String::new(), |(l, o)| {
        format!(
            ", of which skin contact at most {l:.3e}, object {:?}",
            name(o)
        )
    });
    match (e.dt_max, e.recommended()) {
        _ if e.no_stable_step() => outln!(
            "  stable step: none for {:?}: {}",
            p.scheme,
            op_scene::stability::StepEstimate::NO_STABLE_STEP
        ),
        (Some(max), Some(recommended)) => outln!(
            "  stable step: recommended at most {recommended:.3e} ({} of the edge of stability), \
             edge {max:.3e} for {:?} (stiffest mode ω² = {:.3e} 1/time², object {:?}{contact})",
            op_scene::stability::RECOMMENDED_FRACTION,
            p.scheme,
            e.lambda,
            name(&e.object)
        ),
        _ => outln!(
            "  stable step: not bounded for {:?} (ω² = {:.3e} 1/time²)",
            p.scheme,
            e.lambda
        ),
    }
    outln!("  outputs: {}", scene.outputs_summary());
    outln!("  work: {}", work_line(&estimate));
    // On the sample's particles (at most a bounded number per object).
    let health = op_scene::health::started_inside(built)
        .into_iter()
        .chain(op_scene::health::unbonded(built));
    for warning in health {
        eprintln!("opsim: warning: {warning}");
    }
    print_critical_damping(&written, critical.as_ref());
    if let Some(warning) = e.warning(scene.world.dt, &scene.world.integrator) {
        eprintln!("opsim: warning: {warning}");
    }
    Ok(())
}

/// `opsim check`'s line on the run's estimated work (what the work limits
/// are checked against): steps, particles, pairs, and the skins' and
/// triangulations' evaluations when the scene has them.
fn work_line(e: &op_scene::WorkEstimate) -> String {
    let created = if e.created > 0.0 {
        format!(" (up to {:.0} with creation)", e.particles + e.created)
    } else {
        String::new()
    };
    let mut line = format!(
        "about {:.3e} steps of {:.0} particles{created} and {:.3e} interacting pairs ({:.3e} \
         pair-steps)",
        e.steps,
        e.particles,
        e.pairs,
        e.pair_steps()
    );
    for (what, n) in [
        (
            "skin field evaluations per frame",
            e.skin_evaluations_per_frame,
        ),
        (
            "contact field evaluations per step",
            e.contact_evaluations_per_step,
        ),
        (
            "triangulation pairs per frame",
            e.triangulation_pairs_per_frame,
        ),
    ] {
        if n > 0.0 {
            line.push_str(&format!(", {n:.3e} {what}"));
        }
    }
    line
}

/// `opsim check`'s lines on the slowest deformation mode and its critical
/// damping (`op_scene::damping`), for the scene as `written`: what
/// `linear_damping: "Critical"` resolves to (or why it cannot), and how the
/// scene's own damping and times compare.
fn print_critical_damping(
    written: &op_scene::Scene,
    critical: Result<&op_scene::damping::CriticalDamping, &op_scene::SceneError>,
) {
    let c = match critical {
        Ok(c) => c,
        Err(e) => {
            let e = e.to_string();
            let why = e.split("\"Critical\": ").last().unwrap_or(&e);
            outln!("  slowest mode: not found: {why}");
            return;
        }
    };
    let (m, tau) = (&c.mode, c.tau);
    outln!(
        "  slowest mode: ω1 = {:.4} 1/time (τ = 1/ω1 = {tau:.4}, period 2π/ω1 = {:.4}), among {} {} deformation modes of the settled scene",
        m.omega1,
        std::f64::consts::TAU * tau,
        m.modes,
        match m.basis {
            op_scene::modes::Basis::Planar => "planar (in z = 0)",
            op_scene::modes::Basis::Spatial => "spatial",
        },
    );
    let release = c.release.map_or_else(
        || "no force window ends before the run does: duration unchanged".to_string(),
        |r| {
            format!(
                "duration {:.4} (at least 20 τ after the last force window ends at {r})",
                c.duration
            )
        },
    );
    outln!(
        "  critical damping (Lombardo & Puech §5): linear_damping {:.4} (2 ω1 m, m = {:.4}), angular {:.4} (2 ω1 I, I = {:.4}); settle {:.4} (at least 12 τ); {release}",
        c.linear_damping,
        m.mass,
        c.angular_damping,
        m.inertia,
        c.settle,
    );
    let w = &written.world;
    match w.linear_damping.value() {
        None => outln!(
            "  linear_damping: \"Critical\": the scene runs with these numbers ({} settle passes)",
            c.passes
        ),
        Some(beta) => {
            let after = c.release.map_or_else(String::new, |r| {
                format!(
                    ", {:.1} τ after its last force window",
                    (w.duration - r) / tau
                )
            });
            outln!(
                "  the scene as written: linear_damping {beta} (damping ratio of the slowest mode {:.2}), settle {:.1} τ{after}; `linear_damping: \"Critical\"` runs with the numbers above",
                beta / (2.0 * m.omega1 * m.mass),
                w.settle / tau,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
