//! `Scene`: a scene file's content, validated as `opsim` validates it.
//!
//! A scene comes from a file (`Scene.load`, as `opsim run` reads it)
//! or from a dict of the same schema (`Scene.from_dict`: the dict is
//! the JSON form of a scene file, docs/scenes.md), and goes back to a dict
//! (`Scene.to_dict`). The errors are `opsim`'s, with a field path for
//! a dict that does not match the schema (a dict has no lines).

use std::path::{Path, PathBuf};

use op_scene::load::{parse_unvalidated, Format};
use op_scene::{Scene, SceneError, WorkLimits};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::scene_error;
use crate::simulation::PySimulation;

/// The origin of a scene made from a dict, in messages, unless given.
pub const DICT_ORIGIN: &str = "<dict>";

/// The work limits of `opsim run --no-work-limits` and
/// `--max-particle-steps`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LimitFlags {
    /// Lift the work limits.
    pub no_work_limits: bool,
    /// The particle-step limit, when given.
    pub max_particle_steps: Option<f64>,
}

impl LimitFlags {
    /// The limits the flags ask for, or a `ValueError`.
    pub fn limits(self) -> PyResult<WorkLimits> {
        let mut limits = if self.no_work_limits {
            WorkLimits::unlimited()
        } else {
            WorkLimits::default()
        };
        if let Some(m) = self.max_particle_steps {
            if m.is_nan() || m <= 0.0 {
                return Err(PyValueError::new_err(format!(
                    "max_particle_steps = {m}: must be > 0"
                )));
            }
            limits = limits.with_particle_steps(m);
        }
        Ok(limits)
    }
}

/// A validated scene: what to simulate, for how long, what to write
/// (docs/scenes.md). Immutable: edit its dict (`to_dict`) and make a new
/// one (`from_dict`).
#[pyclass(name = "Scene", module = "oriented_particles", frozen)]
pub struct PyScene {
    /// The scene, validated under its limits.
    pub(crate) scene: Scene,
    /// Where its points files are found: the scene file's folder, or the
    /// folder given to `from_dict` (`None`: the working directory).
    pub(crate) base_dir: Option<PathBuf>,
    /// The scene file, when it came from one.
    pub(crate) source: Option<PathBuf>,
    /// The work limits it was validated under.
    pub(crate) flags: LimitFlags,
}

impl PyScene {
    /// The scene validated under `flags` from unvalidated `scene`.
    fn validated(
        mut scene: Scene,
        base_dir: Option<PathBuf>,
        source: Option<PathBuf>,
        flags: LimitFlags,
    ) -> PyResult<Self> {
        scene.limits = flags.limits()?;
        scene.validate(base_dir.as_deref()).map_err(scene_error)?;
        Ok(PyScene {
            scene,
            base_dir,
            source,
            flags,
        })
    }

    /// The scene for a run of `frames` frames (the duration set to them,
    /// as `opsim run --frames`), validated again when that changes it.
    pub(crate) fn for_frames(&self, frames: Option<usize>) -> PyResult<Scene> {
        let mut scene = self.scene.clone();
        if let Some(n) = frames {
            let before = scene.world.duration;
            scene.set_frames(n);
            if scene.world.duration != before {
                scene
                    .validate(self.base_dir.as_deref())
                    .map_err(scene_error)?;
            }
        }
        Ok(scene)
    }
}

/// The JSON text of `d` for the scene parser: numpy scalars and arrays as
/// numbers and lists, indented so that a parse error's excerpt is short.
fn json_text(d: &Bound<'_, PyAny>) -> PyResult<String> {
    let py = d.py();
    let kwargs = PyDict::new(py);
    kwargs.set_item("indent", 1)?;
    kwargs.set_item("allow_nan", false)?;
    kwargs.set_item("default", wrap_pyfunction!(json_default, py)?)?;
    py.import("json")?
        .call_method("dumps", (d,), Some(&kwargs))
        .map_err(|e| {
            PyValueError::new_err(format!(
                "the scene dict is not JSON data (numbers, strings, lists, dicts; \
                 leave out a field for its infinite default): {e}"
            ))
        })?
        .extract()
}

/// `json.dumps`' fallback: numpy values (anything with `tolist`) as
/// Python numbers and lists.
#[pyfunction]
fn json_default<'py>(value: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if value.hasattr("tolist")? {
        return value.call_method0("tolist");
    }
    Err(PyTypeError::new_err(format!(
        "{} is not a number, string, list or dict",
        value.get_type().name()?
    )))
}

/// The parse error of `text` (the JSON of a dict) with the field path
/// where it went wrong, `origin: path: message` (serde's message without
/// its position: a dict has no lines).
fn dict_parse_error(text: &str, origin: &str, e: SceneError) -> PyErr {
    let mut de = serde_json::Deserializer::from_str(text);
    match serde_path_to_error::deserialize::<_, Scene>(&mut de) {
        Err(at) => {
            let message = at.inner().to_string();
            let message = match message.rfind(" at line ") {
                Some(k) => message[..k].to_string(),
                None => message,
            };
            let path = at.path().to_string();
            PyValueError::new_err(format!("{origin}: {path}: {message}"))
        }
        Ok(_) => scene_error(e),
    }
}

#[pymethods]
impl PyScene {
    /// Reads a scene file (.ron or .json) and validates it, as `opsim run`
    /// does: points files are found beside it, and a RON file's
    /// `// expect-warning:` header lines are kept.
    ///
    /// `no_work_limits` and `max_particle_steps` are `opsim run`'s
    /// `--no-work-limits` and `--max-particle-steps`.
    ///
    /// Raises `ValueError` (with opsim's message: the file, the line and
    /// column or the field path, the value and what is allowed) for a bad
    /// scene, `OSError` when the file cannot be read.
    #[staticmethod]
    #[pyo3(signature = (path, *, no_work_limits = false, max_particle_steps = None))]
    fn load(
        path: PathBuf,
        no_work_limits: bool,
        max_particle_steps: Option<f64>,
    ) -> PyResult<Self> {
        let flags = LimitFlags {
            no_work_limits,
            max_particle_steps,
        };
        let scene = op_scene::load_scene_with(&path, flags.limits()?, None).map_err(scene_error)?;
        Ok(PyScene {
            scene,
            base_dir: path.parent().map(Path::to_path_buf),
            source: Some(path),
            flags,
        })
    }

    /// Makes a scene from a dict of the scene schema (the JSON form of a
    /// scene file, docs/scenes.md: `to_dict` gives one), validated as a
    /// file is. numpy numbers and arrays may stand for numbers and lists.
    ///
    /// `origin` names the scene in messages (default `<dict>`);
    /// `base_dir` is where relative points files are found (default: the
    /// working directory); `expected_warnings` are the scene's expected
    /// warnings (what a RON file's `// expect-warning: TEXT` lines give,
    /// e.g. `object "sheet" broke into 2 pieces`); `no_work_limits` and
    /// `max_particle_steps` as in `load`.
    ///
    /// Raises `ValueError` for a bad scene: an unknown field, a wrong type
    /// or a missing field with its field path (`<dict>:
    /// objects[0].generator.HexSheet: unknown field ...`), a value out of
    /// range with opsim's message (`<dict>: objects[0] "sheet".mass = -1:
    /// must be finite and > 0`).
    #[staticmethod]
    #[pyo3(signature = (
        d, *, origin = None, base_dir = None, expected_warnings = None,
        no_work_limits = false, max_particle_steps = None
    ))]
    fn from_dict(
        d: &Bound<'_, PyAny>,
        origin: Option<String>,
        base_dir: Option<PathBuf>,
        expected_warnings: Option<Vec<String>>,
        no_work_limits: bool,
        max_particle_steps: Option<f64>,
    ) -> PyResult<Self> {
        if !d.is_instance_of::<PyDict>() {
            return Err(PyTypeError::new_err(format!(
                "from_dict takes a dict, not {}",
                d.get_type().name()?
            )));
        }
        let origin = origin.unwrap_or_else(|| DICT_ORIGIN.to_string());
        let text = json_text(d)?;
        let mut scene = parse_unvalidated(&text, Format::Json, &origin)
            .map_err(|e| dict_parse_error(&text, &origin, e))?;
        scene.expected_warnings = expected_warnings.unwrap_or_default();
        let flags = LimitFlags {
            no_work_limits,
            max_particle_steps,
        };
        Self::validated(scene, base_dir, None, flags)
    }

    /// The scene as a dict of the scene schema: the JSON form of a scene
    /// file, with every default filled in and preset materials resolved.
    /// `Scene.from_dict(scene.to_dict())` is the same scene (give it the
    /// same `base_dir` and `expected_warnings`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.scene)
            .map_err(|e| PyValueError::new_err(format!("cannot write the scene: {e}")))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The scene's name (the summary's `scene`, the default output folder
    /// `opsim-out/<name>`).
    #[getter]
    fn name(&self) -> &str {
        &self.scene.name
    }

    /// Where the scene came from, in messages: the file path, or the
    /// `origin` given to `from_dict`.
    #[getter]
    fn origin(&self) -> &str {
        self.scene.origin()
    }

    /// The scene file, or None for a scene made from a dict.
    #[getter]
    fn source(&self) -> Option<PathBuf> {
        self.source.clone()
    }

    /// Where relative points files are found (None: the working
    /// directory).
    #[getter]
    fn base_dir(&self) -> Option<PathBuf> {
        self.base_dir.clone()
    }

    /// The warnings the scene expects (a RON file's `// expect-warning:`
    /// lines): a breakup one of them begins is a warning, not a divergence.
    #[getter]
    fn expected_warnings(&self) -> Vec<String> {
        self.scene.expected_warnings.clone()
    }

    /// The names of the scene's objects, in scene order.
    #[getter]
    fn object_names(&self) -> Vec<String> {
        self.scene.objects.iter().map(|o| o.name.clone()).collect()
    }

    /// The estimated edge of stability of `world.dt` (`opsim check`): a
    /// dict with `dt_max` (None when unbounded: the adaptive scheme, or no
    /// stiffness), `recommended` (0.7 of it), `omega_squared` (the
    /// stiffest mode, 1/time²) and `object` (where it is).
    fn stable_step<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = py
            .detach(|| op_scene::stability::estimate(&self.scene, self.base_dir.as_deref()))
            .map_err(scene_error)?;
        let d = PyDict::new(py);
        d.set_item("dt_max", e.dt_max)?;
        d.set_item("recommended", e.recommended())?;
        d.set_item("omega_squared", e.lambda)?;
        d.set_item("object", e.object)?;
        Ok(d)
    }

    /// Builds the scene into a simulation to step from Python, at frame 0:
    /// the settle phase (`world.settle`), if any, already run, as a run's
    /// first frame is. `threads`: worker threads of its steps (default:
    /// every core); the results are the same for any count.
    ///
    /// Raises `ValueError` when the scene cannot be built,
    /// `DivergenceError` when it diverges while settling.
    #[pyo3(signature = (*, threads = None))]
    fn build(&self, py: Python<'_>, threads: Option<usize>) -> PyResult<PySimulation> {
        PySimulation::build(py, self, threads)
    }

    /// Runs the scene as `opsim run` does and writes what it writes into
    /// `out` (default `opsim-out/<name>`): the frames in `formats` (`obj`,
    /// `ply`, `vtu`), `metrics.csv`, `summary.json` and `checkpoint.bin`.
    /// Returns the summary (summary.json as a dict).
    ///
    /// `threads`: worker threads (default: every core; the frames are the
    /// same for any count). `progress`: True prints a progress line on
    /// stderr; a callable is called as `progress(frames_done, total)` after
    /// every frame, and an exception it raises stops the run there, as
    /// Ctrl-C does, and is raised. `frames`, `allow_breakup`, `allow_unstable_step`,
    /// `checkpoint_every` (`"60s"`, a number of frames, or `"off"`) and
    /// `resume` are `opsim run`'s flags.
    ///
    /// Raises `DivergenceError` when the run diverged (opsim's exit 3; its
    /// `summary` attribute holds the summary, every frame before the
    /// divergence is written), `ValueError` for a step beyond the edge of
    /// stability or a checkpoint it cannot resume from, `OSError` for an
    /// output it cannot write, `KeyboardInterrupt` on Ctrl-C (the run stops
    /// after the frame being computed, writes its summary and a checkpoint
    /// to resume from).
    #[pyo3(signature = (
        out = None, *, formats = None, threads = None, progress = None, frames = None,
        allow_breakup = false, allow_unstable_step = false, checkpoint_every = None,
        resume = false
    ))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &self,
        py: Python<'py>,
        out: Option<PathBuf>,
        formats: Option<Vec<String>>,
        threads: Option<usize>,
        progress: Option<Bound<'py, PyAny>>,
        frames: Option<usize>,
        allow_breakup: bool,
        allow_unstable_step: bool,
        checkpoint_every: Option<Bound<'py, PyAny>>,
        resume: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let request = crate::runner::Request {
            out,
            formats: formats.unwrap_or_else(|| vec!["obj".to_string()]),
            threads,
            frames,
            allow_breakup,
            allow_unstable_step,
            checkpoint_every: crate::runner::checkpoint_setting(checkpoint_every.as_ref())?,
            resume,
        };
        crate::runner::run(py, self, request, progress)
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.cast::<PyScene>() {
            Ok(o) => {
                let o = o.get();
                o.scene == self.scene && o.base_dir == self.base_dir
            }
            Err(_) => false,
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(name={:?}, objects={:?}, origin={:?})",
            self.scene.name,
            self.object_names(),
            self.scene.origin()
        )
    }

    /// Pickling (Dask ships scenes to its workers): the dict and what
    /// `from_dict` needs besides.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.get();
        let restore = py.get_type::<PyScene>().getattr("_restore")?;
        let args = (
            this.to_dict(py)?,
            this.scene.origin().to_string(),
            this.base_dir.clone(),
            this.scene.expected_warnings.clone(),
            this.flags.no_work_limits,
            this.flags.max_particle_steps,
            this.source.clone(),
        );
        PyTuple::new(py, [restore, args.into_pyobject(py)?.into_any()])
    }

    /// `__reduce__`'s inverse.
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    fn _restore(
        d: &Bound<'_, PyAny>,
        origin: String,
        base_dir: Option<PathBuf>,
        expected_warnings: Vec<String>,
        no_work_limits: bool,
        max_particle_steps: Option<f64>,
        source: Option<PathBuf>,
    ) -> PyResult<Self> {
        let mut scene = Self::from_dict(
            d,
            Some(origin),
            base_dir,
            Some(expected_warnings),
            no_work_limits,
            max_particle_steps,
        )?;
        scene.source = source;
        Ok(scene)
    }
}
