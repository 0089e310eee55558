//! The runner (README "Running scenes"): steps a built scene frame by frame, writes the
//! frame files ([`crate::export`]), `metrics.csv` and `summary.json`, and detects divergence (NaN,
//! infinities, speeds above the limit, runaway energy) without ever writing
//! a bad frame: frames already on disk stay valid and the summary says
//! `diverged: true`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use op_dynamics::diagnostics::rest_shape_rms;
use op_dynamics::{Point3, Real};
use serde::Serialize;

use crate::built_scene::{BuiltObject, BuiltScene};
use crate::error::short;
use crate::export::{write_atomically, FrameFormat, FrameWriter, Sequence};
use crate::health::{energy_floor, Health, ObjectFindings, ENERGY_GAIN_WARNING};
use crate::skins::ContactStats;

pub mod checkpoint;
mod energy_watch;
mod output;
pub use checkpoint::CheckpointEvery;
use checkpoint::{Carried, Checkpoint};
use energy_watch::EnergyWatch;
pub use output::prepare_output;

/// How to run a scene.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// Number of frames to write, overriding the scene's duration: frame 0
    /// is the initial state, then one every `1 / frame_rate`.
    pub frames: Option<usize>,
    /// Frame file formats (`opsim run --format`); OBJ alone is the default
    /// of the CLI. Duplicates are ignored; none writes no frame file.
    pub formats: Vec<FrameFormat>,
    /// When to write a checkpoint ([`checkpoint`]; `checkpoint.bin` in the
    /// output directory), or never (`None`, the default of the library;
    /// `opsim run` writes one about every minute).
    pub checkpoints: Option<CheckpointEvery>,
    /// Go on from the checkpoint in the output directory instead of
    /// starting over (`opsim run --resume`): the frames and metrics
    /// already written stay, and the run ends as an uninterrupted one would.
    pub resume: bool,
}

/// The runner's own timing names in `summary.json` `stages` (besides the
/// scene's setup, `build` and `estimate`, and the pipeline's stages): no
/// stage of a scene may take them.
/// The runner's own first (`prepare`, `measure`, `export`, and
/// `checkpoint` in a run that writes checkpoints).
pub const RUNNER_STAGES: [&str; 6] = [
    "prepare",
    "measure",
    "export",
    "checkpoint",
    "build",
    "estimate",
];

/// Per-object figures of a run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ObjectSummary {
    /// Object name.
    pub name: String,
    /// Number of particles at the end of the run (created ones included).
    pub particles: usize,
    /// Rest shape error at the last frame: RMS distance to the rest shape
    /// after the best rigid alignment (Kabsch), divided by the object's
    /// mean rest spacing. Measured over the object's original particles
    /// (particles added by the creation rules have no rest position; see
    /// [`crate::creation`]).
    pub rest_shape_error_final: Real,
    /// Largest rest shape error over the frames.
    pub rest_shape_error_max: Real,
    /// Particles the creation rules added to the object over the run.
    pub created: usize,
    /// Connected components of the object's particles at the last frame,
    /// two particles joined when closer than its material's interaction
    /// range (see [`crate::health`]); absent when the material has none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pieces: Option<usize>,
    /// Largest bond stretch seen: the largest ratio of current to rest
    /// distance over the object's rest neighbour pairs, over the frames
    /// (see [`crate::health`]).
    pub bond_stretch_max: Real,
    /// Highest temperature of any of its particles over the frames, when
    /// the scene has `world.heat` (seed 000 §6, §8).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temperature_max: Option<Real>,
}

/// What `summary.json` holds.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// Steps taken.
    pub steps: u64,
    /// Scene time reached (from frame 0, after the settle phase).
    pub sim_time: Real,
    /// Duration of the settle phase simulated before frame 0 (its steps
    /// count in `steps`).
    pub settle: Real,
    /// Wall-clock seconds of the run, the scene's making included
    /// ([`BuiltScene::setup_seconds`]).
    pub wall_seconds: f64,
    /// True when the run stopped because it diverged.
    pub diverged: bool,
    /// The divergence message, when it diverged (its step and time are the
    /// world's, settle phase included).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub divergence: Option<String>,
    /// What a user should know before trusting the frames: an object that
    /// broke into pieces, left the scene's bounds, a passive scene that
    /// gained energy, a step above the estimated stable step (see
    /// [`crate::health`]). Also printed by `opsim run`. A finding the
    /// scene's header expects is under `expected` instead.
    pub warnings: Vec<String>,
    /// The findings the scene's header expects (`// expect-warning: TEXT`,
    /// [`crate::Scene::expected_warnings`]), such as the tear of a tearing
    /// scene: what the scene is meant to do, so `opsim run` prints them as
    /// `expected:` lines, not as warnings. A breakup accepted by `opsim run
    /// --allow-breakup` alone stays a warning.
    pub expected: Vec<String>,
    /// Why the run stopped early other than by diverging (an output that
    /// could not be written, a skin that could not be polygonized), when
    /// it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Seconds spent per stage over the run: the scene's making (`build`,
    /// `estimate`: [`BuiltScene::setup_seconds`]), the world's own stages
    /// (integrate, neighbours, reorder, check, heat, bonds, plasticity,
    /// erase: those it has), the scene's stages ([`crate::stages`]: fit,
    /// creation, contact, skin), then the runner's `prepare` (output
    /// folders, checks before the first step), `measure` (energies, rest
    /// shape errors, health) and `export` (frames, with their polygonized
    /// skins and triangulations). `opsim run --profile` prints them.
    pub stages: std::collections::BTreeMap<String, f64>,
    /// Frames written.
    pub frames: usize,
    /// Frames per unit of scene time (the scene's `world.frame_rate`):
    /// frame `k` is at scene time `k / frame_rate`.
    pub frame_rate: Real,
    /// The scene's up direction in scene coordinates: `outputs.up` when
    /// given, else against gravity, or `+z` in a scene without gravity.
    /// Scenes are z-up by convention.
    pub up: [Real; 3],
    /// The direction the scene's pictures look along (`outputs.view`), in
    /// scene coordinates, when the scene gives one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<[Real; 3]>,
    /// The frame files: formats, axis conventions and sequences.
    pub files: FrameFiles,
    /// Rayon threads used.
    pub threads: usize,
    /// What the scene computes: [`BuiltScene::stages`] (the world's
    /// kernel, terms and external actions, then skin, polygonize, contact
    /// when used).
    pub enabled: Vec<String>,
    /// Contact figures, for scenes with implicit contact (two or more
    /// skinned objects; see [`crate::skins`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactStats>,
    /// Bonds broken over the run (settle phase included), for scenes with
    /// bonded materials (op-dynamics `bonds`; seed 000 fig. 12c tearing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bonds_broken: Option<u64>,
    /// What `linear_damping: "Critical"` resolved to, when the scene asked
    /// for it ([`crate::damping::CriticalDamping`]: the slowest mode, the
    /// damping, settle phase and duration run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_damping: Option<crate::damping::CriticalDamping>,
    /// Per-object figures.
    pub objects: Vec<ObjectSummary>,
}

/// The frame files of a run, as `summary.json` describes them for the
/// tools that read them (the Blender add-on, `opsim render`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FrameFiles {
    /// Formats written, e.g. `["obj", "ply"]`.
    pub formats: Vec<FrameFormat>,
    /// Axis convention per format (by extension): `"y_up"` for OBJ (scene
    /// `(x, y, z)` written as `(x, z, -y)`), `"z_up"` (scene coordinates)
    /// for PLY, VTU and USD (`usda`).
    pub axes: std::collections::BTreeMap<String, String>,
    /// One sequence per scene object's particles, skin, triangulation and
    /// tool: frame `k` of format `ext` is
    /// `frames/<stem>/<stem>_<k:05>.<ext>`.
    pub sequences: Vec<Sequence>,
    /// The particle state files, when VTU is written:
    /// `vtu/state_<k:05>.vtu`, listed in `vtu/state.vtu.series`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vtu_series: Option<String>,
    /// Every series file (ParaView's file-series JSON: a sequence's files
    /// with their scene times, `crate::export::series`), relative to the
    /// output directory: `frames/<stem>/<stem>.<ext>.series` per sequence
    /// and OBJ or PLY format, `vtu/<stem>.vtu.series` per skin, surface
    /// and tool when VTU is written, then `vtu/state.vtu.series`.
    pub series: Vec<String>,
    /// The USD cache, when USD is written ([`crate::export::usd`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub usd: Option<UsdFile>,
}

/// The USD cache of a run, as `summary.json` describes it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UsdFile {
    /// The file, relative to the output directory: `usd/run.usda`.
    pub file: String,
    /// Its default prim, `/Run`, parent of every sequence's prim.
    pub default_prim: String,
    /// The prim of each sequence (every scene object's particles, skin,
    /// triangulation and tool), in the order of the sequences.
    pub prims: Vec<UsdPrim>,
}

/// One sequence's prim in the USD cache.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UsdPrim {
    /// The sequence's name (the OBJ `o` name).
    pub name: String,
    /// What it shows.
    pub kind: crate::export::SequenceKind,
    /// The prim's path: `/Run/<name>` (a `Points` prim for particles, a
    /// `Mesh` otherwise).
    pub path: String,
}

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// An output could not be written (the summary, with `failure` set,
    /// is written when it can be). The operating system's message is the
    /// source.
    #[error("cannot write {}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The output directory holds a symbolic link where opsim writes: it
    /// refuses to write through it.
    #[error("{}: is a symbolic link; opsim does not write through links inside the output directory (remove it or choose another --out)", path.display())]
    Symlink {
        /// The link.
        path: PathBuf,
    },
    /// The checkpoint to resume from is missing, damaged, of another
    /// version or of another scene: nothing was run or written.
    #[error("cannot resume from {}: {message}", path.display())]
    Resume {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// The simulation diverged; the summary (with `diverged: true`) and the
    /// frames before it were written.
    #[error("{message}")]
    Diverged {
        /// What diverged, where and when.
        message: String,
        /// The summary as written.
        summary: Box<Summary>,
    },
    /// The caller asked the run to stop ([`run_with_stop`]) and it stopped
    /// after frame `frames - 1`: those frames, `metrics.csv`, the summary
    /// (its `failure` says so) and, when the run writes checkpoints, a
    /// checkpoint to resume from were written.
    #[error("interrupted after {frames} frames")]
    Interrupted {
        /// Frames written.
        frames: usize,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Rest shape error of `object` in the world's current state, over its
/// original particles that still exist (eraser tools remove particles).
pub fn rest_shape_error(scene: &BuiltScene, object: &BuiltObject) -> Real {
    let p = scene.world.particles();
    let (rest, current): (Vec<Point3>, Vec<Point3>) = object
        .ids
        .iter()
        .zip(&object.rest)
        .filter_map(|(&id, r)| p.slot_of(id).map(|s| (*r, p.positions()[s])))
        .unzip();
    rest_shape_rms(&rest, &current) / object.rest_spacing.max(Real::MIN_POSITIVE)
}

/// `metrics.csv`, kept in memory and written atomically (like the frames)
/// at most every few seconds of wall time and at the end, so the file on
/// disk is always whole.
struct Metrics {
    path: PathBuf,
    text: String,
    saved: Instant,
}

impl Metrics {
    const HEADER: &'static str =
        "frame,time,kinetic,potential,total,oscillation,max_speed,wall_seconds\n";
    /// Seconds between two saves during a run.
    const SAVE_INTERVAL: f64 = 5.0;

    fn new(path: PathBuf) -> Self {
        Metrics {
            path,
            text: Self::HEADER.to_string(),
            saved: Instant::now(),
        }
    }

    fn push(&mut self, row: std::fmt::Arguments) -> Result<(), RunError> {
        use std::fmt::Write as _;
        let _ = writeln!(self.text, "{row}");
        if self.saved.elapsed().as_secs_f64() > Self::SAVE_INTERVAL {
            self.save()?;
        }
        Ok(())
    }

    fn save(&mut self) -> Result<(), RunError> {
        self.saved = Instant::now();
        write_atomically(&self.path, |w| w.write_all(self.text.as_bytes())).map_err(io(&self.path))
    }
}

/// Runs `scene`, writing into `opts.out_dir`; `on_frame(k, total)` is
/// called after each frame (progress display).
///
/// The output directory is prepared first ([`prepare_output`]). Each frame
/// is checked for divergence (non-finite or runaway energy, an energy gain
/// of a passive scene when asked for) and explosion (a particle far beyond
/// the scene's bounds, [`crate::health`]); either ends the run with
/// [`RunError::Diverged`] after writing the summary. The summary's
/// `warnings` say what else went wrong without stopping the run.
///
/// The run goes on a thread of the current rayon pool (the caller waits
/// when it is not one): each parallel pass of a stage (skin contact, the
/// polygonizer, creation) then hands its work to the other threads by work
/// stealing, instead of waking a pool thread and putting the caller to
/// sleep twice per pass, which on a skinned scene of 16,000 steps cost a
/// third of the run at one thread. The same work in the same order: the
/// same frames.
pub fn run(
    scene: &mut BuiltScene,
    opts: &RunOptions,
    on_frame: &mut (dyn FnMut(usize, usize) + Send),
) -> Result<Summary, RunError> {
    run_with_stop(scene, opts, on_frame, &AtomicBool::new(false))
}

/// [`run`], stopping early when `stop` becomes true (another thread sets
/// it: the Python package's Ctrl-C): after the frame being computed, the
/// run writes what an ended run writes (the frames so far, `metrics.csv`,
/// the summary with `failure` saying it was interrupted, and a checkpoint
/// when [`RunOptions::checkpoints`] asks for them, so that
/// [`RunOptions::resume`] goes on from it) and returns
/// [`RunError::Interrupted`]. A run that is not stopped is [`run`]'s.
pub fn run_with_stop(
    scene: &mut BuiltScene,
    opts: &RunOptions,
    on_frame: &mut (dyn FnMut(usize, usize) + Send),
    stop: &AtomicBool,
) -> Result<Summary, RunError> {
    if rayon::current_thread_index().is_some() {
        return run_here(scene, opts, on_frame, stop);
    }
    rayon::scope(|_| run_here(scene, opts, on_frame, stop))
}

/// [`run_with_stop`] on the calling thread.
fn run_here(
    scene: &mut BuiltScene,
    opts: &RunOptions,
    on_frame: &mut (dyn FnMut(usize, usize) + Send),
    stop: &AtomicBool,
) -> Result<Summary, RunError> {
    let clock = Instant::now();
    let writer = FrameWriter::new(
        &opts.out_dir,
        &opts.formats,
        &scene.objects,
        &scene.skins,
        &scene.tools,
        &scene.outputs,
        scene.frame_rate,
    )
    .with_sheet_gap(scene.sheet_gap());
    let checkpoint_path = opts.out_dir.join(checkpoint::FILE);
    let resume_error = |message| RunError::Resume {
        path: checkpoint_path.clone(),
        message,
    };
    // The checkpoint is read before anything in the folder changes.
    let resumed = match opts.resume {
        true => Some(Checkpoint::read(&checkpoint_path).map_err(resume_error)?),
        false => None,
    };
    if resumed.is_some() {
        output::prepare_resume(&opts.out_dir, &writer.folders())?;
    } else {
        prepare_output(&opts.out_dir, &writer.folders())?;
    }
    let total = opts
        .frames
        .unwrap_or_else(|| (scene.duration * scene.frame_rate).round() as usize + 1)
        .max(1);
    let mut run = Run::start(scene, opts, writer, total, &clock);
    // What identifies the run, taken before its first step.
    let inputs = if opts.checkpoints.is_some() || resumed.is_some() {
        checkpoint::run_inputs(scene, total, run.writer.formats())
    } else {
        0
    };
    let (first, t0, carried) = match resumed {
        Some(ck) => ck.restore(scene, &mut run, inputs).map_err(resume_error)?,
        None => {
            if let Err(d) = scene.settle() {
                run.tally.divergence = Some(format!("while settling: {d}"));
            }
            (0, scene.world.time(), Carried::default())
        }
    };
    let mut saved = Instant::now();
    for k in first..total {
        if run.tally.divergence.is_some() {
            break;
        }
        let wall = carried.wall_seconds + clock.elapsed().as_secs_f64();
        if !run.frame(scene, k, t0 + k as Real / scene.frame_rate, wall) {
            break;
        }
        on_frame(k + 1, total);
        let stopping = k + 1 < total && stop.load(Ordering::Relaxed);
        let due = match opts.checkpoints {
            None => false,
            Some(_) if k + 1 == total || stopping => true,
            Some(CheckpointEvery::Frames(n)) => (k + 1) % n.max(1) == 0,
            Some(CheckpointEvery::Seconds(s)) => saved.elapsed().as_secs_f64() >= s,
        };
        if due {
            let at = (k, t0, &carried, clock.elapsed().as_secs_f64());
            let saving = Instant::now();
            if let Err(e) = run.save_checkpoint(scene, at, inputs, &checkpoint_path) {
                run.tally.failure.get_or_insert(e);
                break;
            }
            run.tally.checkpoint_seconds += saving.elapsed().as_secs_f64();
            saved = Instant::now();
        }
        if stopping {
            run.tally
                .failure
                .get_or_insert(RunError::Interrupted { frames: k + 1 });
            break;
        }
    }
    run.finish(scene, &opts.out_dir, (&clock, &carried))
}

/// The runner's state over a run: the tally, the health and energy
/// watches, `metrics.csv`, the frame writer and the warnings so far.
struct Run {
    tally: Tally,
    health: Health,
    watch: EnergyWatch,
    metrics: Option<Metrics>,
    writer: FrameWriter,
    warnings: Vec<String>,
}

impl Run {
    /// The runner's state before the first step of a run of `total`
    /// frames (the scene not settled yet).
    fn start(
        scene: &BuiltScene,
        opts: &RunOptions,
        writer: FrameWriter,
        total: usize,
        clock: &Instant,
    ) -> Run {
        let duration = (total - 1) as Real / scene.frame_rate;
        let metrics = scene
            .outputs
            .metrics
            .then(|| Metrics::new(opts.out_dir.join("metrics.csv")));
        let mut tally = Tally::new(scene);
        let mut warnings = scene.step_warnings.clone();
        warnings.extend(crate::health::started_inside(scene));
        warnings.extend(crate::health::unbonded(scene));
        tally.prepare_seconds = clock.elapsed().as_secs_f64();
        // The scales of the checks come from the scene's inputs, before the
        // settle phase: an explosion while settling is measured against them.
        let measuring = Instant::now();
        let before = if scene.settled { 0.0 } else { scene.settle };
        tally.settles = before > 0.0;
        let health = Health::new(scene, before + duration, scene.extent_growth);
        let floor = energy_floor(scene, health.size(), duration);
        let watch = EnergyWatch::new(scene, floor, tally.settles);
        tally.measure_seconds += measuring.elapsed().as_secs_f64();
        Run {
            tally,
            health,
            watch,
            metrics,
            writer,
            warnings,
        }
    }

    /// Takes frame `k` at world time `t` ([`Tally::frame`]), `wall` seconds
    /// into the run. Returns whether the run goes on.
    fn frame(&mut self, scene: &mut BuiltScene, k: usize, t: Real, wall: f64) -> bool {
        let frame = Frame {
            k,
            t,
            wall,
            writer: &mut self.writer,
            metrics: self.metrics.as_mut(),
        };
        self.tally
            .frame(scene, &mut self.health, &mut self.watch, frame)
    }

    /// Ends the run: the last files written, the health concluded, the
    /// summary written into `out_dir`. `clock`: the run's clock, and what
    /// it carried over from the run it resumed.
    fn finish(
        mut self,
        scene: &BuiltScene,
        out_dir: &Path,
        (clock, carried): (&Instant, &Carried),
    ) -> Result<Summary, RunError> {
        let tally = &mut self.tally;
        let finishing = Instant::now();
        if let Err(f) = self.writer.finish() {
            tally.write_failed(f);
        }
        self.warnings.extend(self.writer.warnings());
        tally.export_seconds += finishing.elapsed().as_secs_f64();
        let measuring = Instant::now();
        if let Some(m) = self.metrics.as_mut() {
            if let Err(e) = m.save() {
                tally.failure.get_or_insert(e);
            }
        }
        let findings = tally.conclude(scene, &self.health, &self.watch, &mut self.warnings);
        tally.measure_seconds += measuring.elapsed().as_secs_f64();
        let wall = clock.elapsed().as_secs_f64();
        let summary = tally.summary(
            scene,
            &self.writer,
            findings,
            self.warnings,
            (wall, carried),
        );
        let path = out_dir.join("summary.json");
        let saved = write_atomically(&path, |w| {
            serde_json::to_writer_pretty(&mut *w, &summary).map_err(std::io::Error::other)?;
            writeln!(w)
        })
        .map_err(io(&path));
        if let Some(e) = self.tally.failure {
            return Err(e);
        }
        saved?;
        match self.tally.divergence {
            Some(message) => Err(RunError::Diverged {
                message,
                summary: Box::new(summary),
            }),
            None => Ok(summary),
        }
    }
}

impl Run {
    /// Writes the checkpoint after frame `at.0` ([`checkpoint`]): the frame
    /// files and `metrics.csv` first, so that the checkpoint never counts a
    /// frame that is not on disk, then `checkpoint.bin`, atomically. `at`:
    /// the frame, the world time of frame 0, what the run carried over and
    /// the seconds of its clock.
    fn save_checkpoint(
        &mut self,
        scene: &BuiltScene,
        at: (usize, Real, &Carried, f64),
        inputs: u64,
        path: &Path,
    ) -> Result<(), RunError> {
        let (k, t0, carried, elapsed) = at;
        if let Err(f) = self.writer.flush() {
            self.tally.written = self.tally.written.min(f.frame);
            return Err(io(&f.path)(f.error));
        }
        if let Some(m) = self.metrics.as_mut() {
            m.save()?;
        }
        let so_far = Carried {
            wall_seconds: carried.wall_seconds + elapsed,
            setup_seconds: carried.setup_seconds
                + scene.setup_seconds.iter().map(|(_, t)| t).sum::<f64>(),
            stages: self.tally.stage_table(scene, carried),
        };
        Checkpoint::take(scene, self, (k, t0), inputs, so_far)
            .write(path)
            .map_err(io(path))
    }
}

/// One frame to take: its index and time, the run's wall seconds so far,
/// where it goes.
struct Frame<'a> {
    k: usize,
    t: Real,
    wall: f64,
    writer: &'a mut FrameWriter,
    metrics: Option<&'a mut Metrics>,
}

/// What a run accumulates over its frames: per-object rest-shape errors and
/// temperatures, frames written, the stage timings of the runner, and how
/// it ended.
#[derive(serde::Serialize, serde::Deserialize)]
struct Tally {
    max_err: Vec<Real>,
    last_err: Vec<Real>,
    /// The world has heat: track each object's hottest particle.
    heat: bool,
    hottest: Vec<Real>,
    written: usize,
    measure_seconds: f64,
    export_seconds: f64,
    /// Checkpoints written ([`checkpoint`]).
    checkpoint_seconds: f64,
    /// The output folders prepared and the scene checked before its first
    /// step.
    prepare_seconds: f64,
    /// The run settles the scene before frame 0.
    settles: bool,
    divergence: Option<String>,
    #[serde(skip)]
    failure: Option<RunError>,
}

impl Tally {
    fn new(scene: &BuiltScene) -> Self {
        let n = scene.objects.len();
        Tally {
            max_err: vec![0.0; n],
            last_err: vec![0.0; n],
            heat: scene.world.params().heat.is_some(),
            hottest: vec![Real::NEG_INFINITY; n],
            written: 0,
            measure_seconds: 0.0,
            export_seconds: 0.0,
            checkpoint_seconds: 0.0,
            prepare_seconds: 0.0,
            settles: false,
            divergence: None,
            failure: None,
        }
    }

    /// Advances to the frame, checks it, measures and writes it. Returns
    /// whether the run goes on.
    fn frame(
        &mut self,
        scene: &mut BuiltScene,
        health: &mut Health,
        watch: &mut EnergyWatch,
        frame: Frame<'_>,
    ) -> bool {
        // Frame 0 poses the skins on the settled particles.
        let t = if frame.k == 0 {
            scene.world.time()
        } else {
            frame.t
        };
        if let Err(d) = scene.advance_to(t) {
            // A stage's failure ends the run as a divergence does (exit 3):
            // the state it left cannot be continued.
            self.divergence = Some(d.to_string());
            return false;
        }
        let measuring = Instant::now();
        let d = scene.world.diagnostics();
        // Frame 0 is the end of the settle phase: what went wrong there
        // went wrong while settling.
        let when = if frame.k == 0 && self.settles {
            "while settling: "
        } else {
            ""
        };
        if let Some(d) = watch
            .check(scene, &d)
            .err()
            .or_else(|| health.observe(scene))
            .or_else(|| crate::health::unwritable(scene))
        {
            self.divergence = Some(format!("{when}{d}"));
            return false;
        }
        self.measure(scene);
        self.measure_seconds += measuring.elapsed().as_secs_f64();
        let exporting = Instant::now();
        if frame.writer.writes_anything() {
            if let Err(f) = frame.writer.write_frame(
                frame.k,
                scene.scene_time(),
                &scene.world,
                &scene.objects,
                &scene.skins,
                &scene.skin_tools,
                &scene.tools,
                &scene.outputs,
            ) {
                self.write_failed(f);
                return false;
            }
        }
        self.written += 1;
        self.export_seconds += exporting.elapsed().as_secs_f64();
        if let Some(m) = frame.metrics {
            let kinetic = d.kinetic_translational + d.kinetic_rotational;
            if let Err(e) = m.push(format_args!(
                "{},{},{kinetic},{},{},{},{},{}",
                frame.k,
                scene.scene_time(),
                d.potential,
                d.total,
                d.oscillation,
                d.max_speed,
                frame.wall
            )) {
                self.failure = Some(e);
                return false;
            }
        }
        true
    }

    /// The health findings at the end of the run: its warnings (energy
    /// gained without input, the health report's, accepted breakups) go
    /// into `warnings`, and a breakup the scene does not expect ends the
    /// run as a divergence. After a divergence the state is the blown-up
    /// one: its pieces and escape say nothing the divergence does not.
    fn conclude(
        &mut self,
        scene: &BuiltScene,
        health: &Health,
        watch: &EnergyWatch,
        warnings: &mut Vec<String>,
    ) -> Vec<ObjectFindings> {
        if watch.gain_seen > ENERGY_GAIN_WARNING {
            warnings.push(format!(
                "the scene gained energy without input: the total energy rose {} times its \
                 energy scale above the lowest earlier frame (a step too large for the \
                 stiffness, or particles started on top of each other)",
                short(watch.gain_seen)
            ));
        }
        let (findings, health_warnings, breakups) = health.finish(scene);
        if self.divergence.is_some() {
            return findings;
        }
        warnings.extend(health_warnings);
        let (accepted, unexpected): (Vec<String>, Vec<String>) =
            breakups.into_iter().partition(|b| scene.accepts_breakup(b));
        warnings.extend(accepted);
        if let Some(first) = unexpected.first() {
            self.divergence = Some(format!(
                "{first}; the scene does not expect it (a scene that tears on purpose says so \
                 in its header, `// expect-warning: {}`; `opsim run --allow-breakup` accepts \
                 any breakup)",
                first.split(" (").next().unwrap_or(first)
            ));
        }
        findings
    }

    /// Each object's rest-shape error and hottest particle at this frame.
    fn measure(&mut self, scene: &BuiltScene) {
        for (o, obj) in scene.objects.iter().enumerate() {
            let e = rest_shape_error(scene, obj);
            self.last_err[o] = e;
            self.max_err[o] = Real::max(self.max_err[o], e);
            if self.heat {
                let p = scene.world.particles();
                self.hottest[o] = obj
                    .all_ids()
                    .filter_map(|id| p.slot_of(id))
                    .map(|s| p.temperatures()[s])
                    .fold(self.hottest[o], Real::max);
            }
        }
    }

    /// A frame file that could not be written ends the run: the frames
    /// before its frame are the ones written.
    fn write_failed(&mut self, f: crate::export::WriteFailure) {
        self.written = self.written.min(f.frame);
        self.failure.get_or_insert(io(&f.path)(f.error));
    }

    /// The run's summary (`summary.json`).
    fn summary(
        &self,
        scene: &BuiltScene,
        writer: &FrameWriter,
        findings: Vec<ObjectFindings>,
        warnings: Vec<String>,
        (wall, carried): (f64, &Carried),
    ) -> Summary {
        let (expected, warnings) = warnings.into_iter().partition(|w| scene.expects(w));
        Summary {
            scene: scene.name.clone(),
            steps: scene.world.steps(),
            sim_time: scene.scene_time(),
            settle: if scene.settled { scene.settle } else { 0.0 },
            wall_seconds: carried.wall_seconds
                + carried.setup_seconds
                + wall
                + scene.setup_seconds.iter().map(|(_, t)| t).sum::<f64>(),
            diverged: self.divergence.is_some(),
            divergence: self.divergence.clone(),
            warnings,
            expected,
            failure: self.failure.as_ref().map(error_chain),
            stages: self.stage_table(scene, carried),
            frames: self.written,
            frame_rate: scene.frame_rate,
            up: scene.outputs.up.unwrap_or_else(|| up_direction(scene)),
            view: scene.outputs.view,
            files: frame_files(writer),
            threads: rayon::current_num_threads(),
            enabled: scene.stages(),
            contact: scene.has_contact().then_some(scene.contact),
            bonds_broken: scene.world.bonds().map(|b| b.broken()),
            critical_damping: scene.critical_damping.clone(),
            objects: self.objects(scene, findings),
        }
    }

    /// Seconds per stage so far (the summary's `stages`): the scene's and
    /// the runner's, plus those `carried` over from the run this one
    /// resumed.
    fn stage_table(&self, scene: &BuiltScene, carried: &Carried) -> BTreeMap<String, f64> {
        let mut table = carried.stages.clone();
        let now = scene.timings().into_iter().chain(
            // `build` and `estimate` come with the scene's timings.
            RUNNER_STAGES[..4].iter().map(|s| s.to_string()).zip([
                self.prepare_seconds,
                self.measure_seconds,
                self.export_seconds,
                self.checkpoint_seconds,
            ]),
        );
        for (name, seconds) in now {
            if name == "checkpoint" && seconds == 0.0 {
                continue;
            }
            *table.entry(name).or_insert(0.0) += seconds;
        }
        table
    }

    /// A copy of the tally for a checkpoint: everything but a failure
    /// (checkpoints are taken only while the run goes well).
    fn snapshot(&self) -> Tally {
        Tally {
            max_err: self.max_err.clone(),
            last_err: self.last_err.clone(),
            heat: self.heat,
            hottest: self.hottest.clone(),
            written: self.written,
            measure_seconds: self.measure_seconds,
            export_seconds: self.export_seconds,
            checkpoint_seconds: self.checkpoint_seconds,
            prepare_seconds: self.prepare_seconds,
            settles: self.settles,
            divergence: self.divergence.clone(),
            failure: None,
        }
    }

    /// The per-object figures of the summary.
    fn objects(&self, scene: &BuiltScene, findings: Vec<ObjectFindings>) -> Vec<ObjectSummary> {
        scene
            .objects
            .iter()
            .zip(findings)
            .enumerate()
            .map(|(o, (obj, found))| ObjectSummary {
                name: obj.name.clone(),
                particles: obj
                    .all_ids()
                    .filter(|&id| scene.world.particles().slot_of(id).is_some())
                    .count(),
                rest_shape_error_final: self.last_err[o],
                rest_shape_error_max: self.max_err[o],
                created: obj.created.len(),
                pieces: found.pieces,
                bond_stretch_max: found.bond_stretch_max,
                temperature_max: (self.heat && self.hottest[o].is_finite())
                    .then_some(self.hottest[o]),
            })
            .collect()
    }
}

/// The frame files a writer wrote (the summary's `files`).
fn frame_files(writer: &FrameWriter) -> FrameFiles {
    FrameFiles {
        formats: writer.formats().to_vec(),
        axes: writer
            .formats()
            .iter()
            .map(|f| (f.extension().to_string(), f.axes().to_string()))
            .collect(),
        sequences: if writer.writes_sequences() {
            writer.sequences().to_vec()
        } else {
            Vec::new()
        },
        vtu_series: writer
            .series_files()
            .first()
            .map(|p| p.to_string_lossy().replace('\\', "/")),
        series: writer
            .all_series_files()
            .iter()
            .map(|p| p.to_string_lossy().replace('\\', "/"))
            .collect(),
        usd: writer.run_files().first().map(|(_, p)| {
            let root = format!("/{}", crate::export::usd::ROOT);
            let names = crate::export::usd::prim_names(writer.sequences());
            UsdFile {
                file: p.to_string_lossy().replace('\\', "/"),
                prims: writer
                    .sequences()
                    .iter()
                    .zip(names)
                    .map(|(s, n)| UsdPrim {
                        name: s.name.clone(),
                        kind: s.kind,
                        path: format!("{root}/{n}"),
                    })
                    .collect(),
                default_prim: root,
            }
        }),
    }
}

/// The scene's up direction: against gravity, `+z` without gravity.
fn up_direction(scene: &BuiltScene) -> [Real; 3] {
    let g = scene.world.params().external.gravity();
    match (-g).try_normalize(0.0) {
        // `+ 0.0` turns the `-0.0` of a negated zero into `0`.
        Some(u) if u.iter().all(|c| c.is_finite()) => u.map(|c| c + 0.0).into(),
        _ => [0.0, 0.0, 1.0],
    }
}

/// An error and its sources, `: `-separated (one line for the summary).
fn error_chain(e: &RunError) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tight_curvature() -> crate::Scene {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/extreme/tight_curvature.ron");
        crate::load_scene(&path).expect("the extreme scene loads")
    }

    fn run_into(scene: &crate::Scene, name: &str) -> Result<Summary, RunError> {
        let dir = std::env::temp_dir().join(format!("op-scene-gain-{name}-{}", std::process::id()));
        let mut built = scene.build(None, None).expect("the scene builds");
        // The check compares frames: two per second over 8 s. The gain
        // comes in bursts (e.g. +1.0 between t = 6 and 6.5 against a
        // threshold of 0.17) whose timing moves with round-off, so frames a
        // second apart caught it or not depending on the last bits
        // (renormalizing velocity Verlet's quaternions made it miss).
        built.frame_rate = 2.0;
        let opts = RunOptions {
            out_dir: dir.clone(),
            frames: Some(17),
            formats: vec![crate::export::FrameFormat::OBJ],
            ..Default::default()
        };
        let result = run(&mut built, &opts, &mut |_, _| {});
        let _ = std::fs::remove_dir_all(&dir);
        result
    }

    #[test]
    fn energy_gain_of_a_passive_scene_is_a_divergence_when_asked_for() {
        // Chain with rest curvature 100/r0 under explicit Euler, which gains
        // energy on every conservative problem (its amplification factor
        // exceeds 1), damping off: bounded over the run, so only the energy
        // check sees it. (Under velocity Verlet the chain used to gain
        // energy by bursts as its pairs passed through coincidence; the
        // normalized terms now fade out there and it does not.)
        let mut scene = tight_curvature();
        scene.world.integrator = op_dynamics::Scheme::ExplicitEuler;
        scene.world.linear_damping = 0.0.into();
        scene.world.angular_damping = 0.0;
        assert_eq!(scene.world.divergence.energy_gain, 1e-6);
        match run_into(&scene, "on") {
            Err(RunError::Diverged { message, summary }) => {
                assert!(message.contains("energy gain"), "{message}");
                assert!(summary.diverged);
            }
            other => panic!("expected an energy-gain divergence, got {other:?}"),
        }
        // Off by default: the run goes on to its end, where the chain the
        // gain tore apart is caught as an unexpected breakup instead.
        scene.world.divergence.energy_gain = Real::INFINITY;
        match run_into(&scene, "off") {
            Err(RunError::Diverged { message, summary }) => {
                assert!(!message.contains("energy gain"), "{message}");
                assert!(message.contains("broke into"), "{message}");
                assert_eq!(summary.frames, 17, "every frame written");
            }
            other => panic!("expected a breakup at the end, got {other:?}"),
        }
    }

    /// A run asked to stop stops after the frame being computed, writes
    /// its summary (saying so) and a checkpoint, and resuming from that
    /// checkpoint ends with the frames of an uninterrupted run.
    #[test]
    fn a_stopped_run_stops_between_frames_and_resumes() {
        let dir = std::env::temp_dir().join(format!("op-scene-stop-{}", std::process::id()));
        let opts = |resume| RunOptions {
            out_dir: dir.clone(),
            frames: Some(6),
            formats: vec![crate::export::FrameFormat::PLY],
            checkpoints: Some(CheckpointEvery::Frames(100)),
            resume,
        };
        let frame = |k: usize| std::fs::read(dir.join(format!("frames/chain/chain_{k:05}.ply")));
        let mut built = tight_curvature().build(None, None).expect("builds");
        let whole = run(&mut built, &opts(false), &mut |_, _| {}).expect("runs");
        let last = frame(5).expect("the last frame");
        let stop = AtomicBool::new(false);
        let mut built = tight_curvature().build(None, None).expect("builds");
        let result = run_with_stop(
            &mut built,
            &opts(false),
            &mut |k, _| stop.store(k == 3, Ordering::Relaxed),
            &stop,
        );
        assert!(
            matches!(result, Err(RunError::Interrupted { frames: 3 })),
            "{result:?}"
        );
        let summary = std::fs::read_to_string(dir.join("summary.json")).expect("a summary");
        assert!(summary.contains("interrupted after 3 frames"), "{summary}");
        assert!(frame(2).is_ok() && frame(3).is_err());
        let mut built = tight_curvature().build(None, None).expect("builds");
        let resumed = run(&mut built, &opts(true), &mut |_, _| {}).expect("resumes");
        assert_eq!(resumed.frames, whole.frames);
        assert_eq!(frame(5).expect("the last frame"), last);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A value no frame file can hold ends the run before that frame is
    /// written: exit 3, naming the particle and its object, and no file of
    /// the run holds a non-finite value.
    #[test]
    fn a_state_no_frame_can_hold_is_a_divergence() {
        for (what, edit) in [
            (
                "temperature",
                (|p: &mut op_dynamics::Particles| p.set_temperature(3, Real::INFINITY))
                    as fn(&mut op_dynamics::Particles),
            ),
            ("position", |p: &mut op_dynamics::Particles| {
                p.set_position(3, op_dynamics::Point3::new(1e39, 0.0, 0.0))
            }),
        ] {
            let dir = std::env::temp_dir()
                .join(format!("op-scene-unwritable-{what}-{}", std::process::id()));
            let mut built = tight_curvature().build(None, None).expect("builds");
            edit(built.world_mut().particles_mut());
            let opts = RunOptions {
                out_dir: dir.clone(),
                frames: Some(3),
                formats: vec![
                    crate::export::FrameFormat::OBJ,
                    crate::export::FrameFormat::PLY,
                    crate::export::FrameFormat::VTU,
                ],
                ..Default::default()
            };
            match run(&mut built, &opts, &mut |_, _| {}) {
                Err(RunError::Diverged { message, summary }) => {
                    // The temperature is caught by the writability check; the far
                    // position already by the explosion check.
                    let expected = if what == "temperature" {
                        "temperature inf in object \"chain\""
                    } else {
                        "object \"chain\""
                    };
                    assert!(message.contains(expected), "{message}");
                    assert_eq!(summary.frames, 0, "{what}: no frame written: {message}");
                }
                other => panic!("{what}: expected a divergence, got {other:?}"),
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    /// A skin whose particles are far apart outgrows the polygonizer's
    /// grid: it is written coarser, with a warning, instead of ending the
    /// run with a write error.
    #[test]
    fn a_skin_that_outgrows_its_grid_is_written_coarser() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sheet_on_box.ron");
        let scene = crate::load_scene(&path).expect("the scene loads");
        let mut built = scene.build(None, None).expect("builds");
        // 300 away: 1200 cells of 0.25, beyond the 512 nodes of the grid.
        let p = built.world_mut().particles_mut();
        let x = p.positions()[0];
        p.set_position(0, x + op_dynamics::Vec3::new(300.0, 0.0, 0.0));
        let dir = std::env::temp_dir().join(format!("op-scene-coarser-{}", std::process::id()));
        let opts = RunOptions {
            out_dir: dir.clone(),
            frames: Some(2),
            formats: vec![crate::export::FrameFormat::OBJ],
            ..Default::default()
        };
        let result = run(&mut built, &opts, &mut |_, _| {});
        let _ = std::fs::remove_dir_all(&dir);
        // The particle starts apart (two pieces from the start, no breakup):
        // the run ends normally, with the warning.
        let summary = result.expect("runs to the end");
        assert_eq!(summary.frames, 2);
        assert!(
            summary
                .warnings
                .iter()
                .any(|w| w.contains("skin \"sheet_skin\" outgrew its polygonization grid")),
            "{:?}",
            summary.warnings
        );
    }
}
