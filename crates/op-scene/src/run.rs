//! The runner (README "Running scenes"): steps a built scene frame by frame, writes the
//! frame files ([`crate::export`]), `metrics.csv` and `summary.json`, and detects divergence (NaN,
//! infinities, speeds above the limit, runaway energy) without ever writing
//! a bad frame: frames already on disk stay valid and the summary says
//! `diverged: true`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use op_dynamics::diagnostics::rest_shape_rms;
use op_dynamics::{Point3, Real};

use crate::built_scene::{BuiltObject, BuiltScene};
use crate::export::{write_atomically, FrameFormat, FrameWriter};
use crate::health::{energy_floor, Health};

pub mod checkpoint;
mod energy_watch;
mod metrics;
mod output;
mod summary;
mod tally;
pub use checkpoint::CheckpointEvery;
use checkpoint::{Carried, Checkpoint};
use energy_watch::EnergyWatch;
use metrics::Metrics;
pub use output::prepare_output;
pub use summary::{FrameFiles, ObjectSummary, Summary, UsdFile, UsdPrim};
use tally::{Frame, Tally};

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
            .write(&scene.world, path)
            .map_err(io(path))
    }
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
        // second apart catch it or not depending on the last bits.
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
        // check sees it. (Under velocity Verlet the chain does not gain
        // energy: the normalized terms fade out where its pairs pass
        // through coincidence.)
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
        // 1000 away: 4000 cells of 0.25, beyond the grid's 2048 nodes.
        let p = built.world_mut().particles_mut();
        let x = p.positions()[0];
        p.set_position(0, x + op_dynamics::Vec3::new(1000.0, 0.0, 0.0));
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
