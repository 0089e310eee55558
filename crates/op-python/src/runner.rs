//! `Scene.run`: `opsim run` from Python.
//!
//! The scene is built and checked as `opsim run` builds and checks it
//! (`build_for_run`, the step refused beyond the edge of stability unless
//! asked, breakups accepted when asked), then op-scene's runner runs it
//! ([`op_scene::run_with_stop`]), so the files are the ones `opsim run`
//! writes. The run goes on a thread of its own (on a rayon pool of
//! `threads` threads when given) while the calling thread, the GIL
//! released, waits for it in slices of [`POLL`] and between them checks
//! for signals and reports progress: Ctrl-C asks the run to stop after the
//! frame being computed, then raises `KeyboardInterrupt`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use op_scene::export::FrameFormat;
use op_scene::{BuiltScene, CheckpointEvery, RunError, RunOptions, Summary};
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::scene::PyScene;
use crate::{divergence_error, error_chain, os_error, scene_error};

/// How often the waiting thread checks for signals and progress.
pub const POLL: Duration = Duration::from_millis(50);

/// What `Scene.run` was asked for (besides the progress display).
pub struct Request {
    /// Output folder (default `opsim-out/<name>`).
    pub out: Option<PathBuf>,
    /// Frame formats by name.
    pub formats: Vec<String>,
    /// Worker threads (default: rayon's global pool).
    pub threads: Option<usize>,
    /// Frames to write, overriding the duration.
    pub frames: Option<usize>,
    /// `--allow-breakup`.
    pub allow_breakup: bool,
    /// `--allow-unstable-step`.
    pub allow_unstable_step: bool,
    /// `--checkpoint-every`.
    pub checkpoint_every: Option<CheckpointEvery>,
    /// `--resume`.
    pub resume: bool,
}

/// `checkpoint_every` as `opsim run --checkpoint-every` reads it: `"60s"`
/// (the default, for None), `"10"` or `10` frames, `"off"`.
pub fn checkpoint_setting(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<CheckpointEvery>> {
    let Some(value) = value else {
        return Ok(Some(CheckpointEvery::Seconds(60.0)));
    };
    if let Ok(n) = value.extract::<usize>() {
        return match n {
            0 => Err(PyValueError::new_err(format!(
                "checkpoint_every = 0: {}",
                CheckpointEvery::EXPECTED
            ))),
            n => Ok(Some(CheckpointEvery::Frames(n))),
        };
    }
    let text: String = value.extract().map_err(|_| {
        PyValueError::new_err(format!("checkpoint_every: {}", CheckpointEvery::EXPECTED))
    })?;
    CheckpointEvery::parse_setting(&text)
        .map_err(|e| PyValueError::new_err(format!("checkpoint_every = {e}")))
}

/// A rayon pool of `threads` threads, or None for the global pool.
pub fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    let Some(k) = threads else {
        return Ok(None);
    };
    if !(1..=1024).contains(&k) {
        return Err(PyValueError::new_err(format!(
            "threads = {k}: must be between 1 and 1024"
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(k)
        .build()
        .map(Some)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start the thread pool: {e}")))
}

/// Runs `f` on `pool` (the global pool when None).
pub fn on_pool<R: Send>(pool: Option<&rayon::ThreadPool>, f: impl FnOnce() -> R + Send) -> R {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

/// The scene built and checked for the run, as `opsim run` does it.
fn prepare(py: Python<'_>, scene: &PyScene, request: &Request) -> PyResult<BuiltScene> {
    let validated = scene.for_frames(request.frames)?;
    let base = scene.base_dir.as_deref();
    let mut built = py
        .detach(|| validated.build_for_run(base, scene.source.clone()))
        .map_err(scene_error)?;
    if request.allow_breakup {
        built.accept_breakup();
    }
    if !request.allow_unstable_step {
        let dt = built.world().params().dt;
        let refusal = built
            .step_estimate()
            .and_then(|e| e.refusal(dt, validated.origin(), "allow_unstable_step=True"));
        if let Some(message) = refusal {
            return Err(PyValueError::new_err(message));
        }
    }
    Ok(built)
}

/// `Scene.run`: see [`PyScene`]'s `run`.
pub fn run<'py>(
    py: Python<'py>,
    scene: &PyScene,
    request: Request,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let formats = request
        .formats
        .iter()
        .map(|f| FrameFormat::named(f))
        .collect::<Result<Vec<_>, _>>()
        .map_err(PyValueError::new_err)?;
    let pool = pool(request.threads)?;
    let mut built = prepare(py, scene, &request)?;
    let opts = RunOptions {
        out_dir: request
            .out
            .clone()
            .unwrap_or_else(|| Path::new("opsim-out").join(built.name())),
        frames: request.frames,
        formats,
        checkpoints: request.checkpoint_every,
        resume: request.resume,
    };
    let mut display = Progress::new(progress.as_ref(), built.name());
    let callback = progress.filter(|p| p.is_callable()).map(Bound::unbind);
    let raised = std::sync::Mutex::new(None);
    let (result, interrupt) = watch(py, &mut display, |stop, done, total| {
        let mut on_frame = |k: usize, n: usize| {
            total.store(n, Ordering::Relaxed);
            done.store(k, Ordering::Relaxed);
            if let Some(f) = &callback {
                // Between two frames, on the run's thread: an exception
                // stops the run as Ctrl-C does.
                if let Err(e) = Python::attach(|py| f.call1(py, (k, n))) {
                    stop.store(true, Ordering::Relaxed);
                    let mut slot = raised.lock().unwrap_or_else(|p| p.into_inner());
                    slot.get_or_insert(e);
                }
            }
        };
        on_pool(pool.as_ref(), || {
            op_scene::run_with_stop(&mut built, &opts, &mut on_frame, stop)
        })
    });
    display.finish(py);
    let raised = raised.into_inner().unwrap_or_else(|p| p.into_inner());
    if let Some(e) = interrupt.or(raised) {
        return Err(e);
    }
    outcome(py, result, &opts.out_dir)
}

/// Runs `work` on a thread of its own while this thread, the GIL
/// released, waits for it in slices of [`POLL`], showing its progress
/// (`work` stores frames done and total) and checking for signals between
/// slices. A signal's exception (Ctrl-C: `KeyboardInterrupt`) sets `stop`
/// and is returned beside the result once `work` has stopped.
pub fn watch<R: Send>(
    py: Python<'_>,
    display: &mut Progress,
    work: impl FnOnce(&AtomicBool, &AtomicUsize, &AtomicUsize) -> R + Send,
) -> (R, Option<PyErr>) {
    let stop = AtomicBool::new(false);
    let (done, total) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let (tx, mut rx) = mpsc::channel::<()>();
    let mut interrupt = None;
    let result = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let r = work(&stop, &done, &total);
            let _ = tx.send(());
            r
        });
        loop {
            // The receiver is not Sync: it goes into the wait and back.
            let (waited, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            let finished = waited.is_ok();
            display.show(
                py,
                done.load(Ordering::Relaxed),
                total.load(Ordering::Relaxed),
            );
            if interrupt.is_none() {
                if let Err(e) = py.check_signals() {
                    stop.store(true, Ordering::Relaxed);
                    interrupt = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        worker.join()
    });
    match result {
        Ok(r) => (r, interrupt),
        // A panic in the run is a bug: report it as Python's.
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

/// The run's result as Python sees it: the summary, or the exception.
fn outcome<'py>(
    py: Python<'py>,
    result: Result<Summary, RunError>,
    out_dir: &Path,
) -> PyResult<Bound<'py, PyAny>> {
    match result {
        Ok(summary) => {
            warn(py, &summary.warnings)?;
            summary_dict(py, &summary)
        }
        Err(RunError::Diverged { message, summary }) => {
            warn(py, &summary.warnings)?;
            let message = format!(
                "{message}\n{} frames written to {} (summary.json says diverged: true)",
                summary.frames,
                out_dir.display()
            );
            Err(divergence_error(
                py,
                message,
                summary_dict(py, &summary)?.unbind(),
            ))
        }
        Err(e @ RunError::Interrupted { .. }) => Err(PyKeyboardInterrupt::new_err(e.to_string())),
        Err(e @ RunError::Resume { .. }) => Err(PyValueError::new_err(error_chain(&e))),
        Err(RunError::Io { path, source }) => {
            let kind = source.kind();
            let e = RunError::Io { path, source };
            Err(os_error(kind, error_chain(&e)))
        }
        Err(e @ RunError::Symlink { .. }) => {
            Err(os_error(std::io::ErrorKind::AlreadyExists, error_chain(&e)))
        }
        Err(e) => Err(PyRuntimeError::new_err(error_chain(&e))),
    }
}

/// The run's warnings (`opsim run` prints them) as Python warnings
/// (`RuntimeWarning`).
fn warn(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    let module = py.import("warnings")?;
    let category = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
    for w in warnings {
        // stacklevel 1: the line of Python that called `run` (no frame of
        // Python code lies between).
        module.call_method1("warn", (format!("opsim: {w}"), &category, 1))?;
    }
    Ok(())
}

/// The summary as a dict (summary.json's content).
pub fn summary_dict<'py>(py: Python<'py>, summary: &Summary) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(summary)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot encode the summary: {e}")))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The progress line on stderr (`progress=True`), or nothing.
pub struct Progress {
    line: bool,
    name: String,
    shown: (usize, usize),
}

impl Progress {
    /// The display `progress` asks for (True: a line; None, False or a
    /// callable, which the run calls itself: none) for the scene `name`.
    pub fn new(progress: Option<&Bound<'_, PyAny>>, name: &str) -> Self {
        let line = progress.is_some_and(|p| !p.is_callable() && p.is_truthy().unwrap_or(false));
        Progress {
            line,
            name: name.to_string(),
            shown: (0, 0),
        }
    }

    /// Shows `done` of `total` frames when that changed (a display that
    /// cannot be written is left alone).
    pub fn show(&mut self, py: Python<'_>, done: usize, total: usize) {
        if !self.line || (done, total) == self.shown || total == 0 {
            return;
        }
        self.shown = (done, total);
        let text = format!("\r{}: {done}/{total} frames", self.name);
        if let Ok(stderr) = py.import("sys").and_then(|s| s.getattr("stderr")) {
            let _ = stderr.call_method1("write", (text,));
            let _ = stderr.call_method0("flush");
        }
    }

    /// Ends the progress line, if one was shown.
    pub fn finish(&self, py: Python<'_>) {
        if self.line && self.shown.1 > 0 {
            if let Ok(stderr) = py.import("sys").and_then(|s| s.getattr("stderr")) {
                let _ = stderr.call_method1("write", ("\n",));
            }
        }
    }
}
