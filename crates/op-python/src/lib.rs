//! # op-python: the `oriented_particles` Python package
//!
//! README "Python". The extension module `oriented_particles._native`,
//! built with maturin (`pyproject.toml` beside this crate) for CPython 3.9
//! and later (abi3), re-exported by the package's `__init__.py`:
//!
//! - [`scene::PyScene`] (`Scene`): a scene loaded from a file or a dict,
//!   validated as `opsim` validates it, written back as a dict, run as
//!   `opsim run` runs it ([`runner`]);
//! - [`simulation::PySimulation`] (`Simulation`): a built scene stepped
//!   from Python, its particles read and written as numpy arrays;
//! - [`fit::fit`] (`fit`): point-set interpolation as `opsim fit`;
//! - `DivergenceError`: a run or a step that diverged (`opsim`'s exit 3).
//!
//! Every computation runs with the GIL released; the calling thread waits
//! for it in short slices and checks for signals between them, so Ctrl-C
//! stops a run between two frames ([`runner`]).
//!
//! The crate has no `unsafe` of its own: the workspace forbids it, and
//! PyO3's macros keep theirs in code they generate (`#[allow]`ed there).

use pyo3::create_exception;
use pyo3::exceptions::{
    PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError, PyRuntimeError,
    PyValueError,
};
use pyo3::prelude::*;

pub mod arrays;
pub mod fit;
pub mod runner;
pub mod scene;
pub mod simulation;

create_exception!(
    oriented_particles,
    DivergenceError,
    PyRuntimeError,
    "The simulation diverged (a NaN or infinity, a speed above \
     world.divergence.max_speed, runaway energy, an explosion, an unexpected \
     breakup): `opsim run`'s exit code 3. The message is opsim's: it names the \
     step, the time and the particle. `summary` holds the run's summary (a \
     dict, as summary.json) for a run, None for a simulation stepped from Python."
);

/// An error and its sources, `: `-separated: what `opsim` prints after
/// `opsim: error: `.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// The Python exception for an operating-system error of kind `kind`
/// with the message `message`: `FileNotFoundError`, `PermissionError`,
/// `IsADirectoryError`, else `OSError`.
pub fn os_error(kind: std::io::ErrorKind, message: String) -> PyErr {
    match kind {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        std::io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// The Python exception for a scene that could not be read, validated or
/// built, with `opsim`'s message: an `OSError` (or subclass) when its file
/// could not be read, a `ValueError` for everything else (bad input).
pub fn scene_error(e: op_scene::SceneError) -> PyErr {
    match &e {
        op_scene::SceneError::Io { source, .. } => os_error(source.kind(), error_chain(&e)),
        _ => PyValueError::new_err(error_chain(&e)),
    }
}

/// A `DivergenceError` with `message` and `summary` (None or a dict)
/// attached.
pub fn divergence_error(py: Python<'_>, message: String, summary: Py<PyAny>) -> PyErr {
    let err = DivergenceError::new_err(message);
    // An exception instance takes attributes; this cannot fail.
    let _ = err.value(py).setattr("summary", summary);
    err
}

/// The extension module `oriented_particles._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::PyScene>()?;
    m.add_class::<simulation::PySimulation>()?;
    m.add_class::<fit::PyFit>()?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add("DivergenceError", m.py().get_type::<DivergenceError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
