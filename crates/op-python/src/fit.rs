//! `fit`: point-set interpolation with oriented particles (seed 000 §7),
//! `opsim fit` from Python.

use std::path::PathBuf;

use op_dynamics::{Point3, Real};
use op_scene::fit::{FitError, FitParams, PointSet};
use op_scene::pointsets::PointSetError;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::{arrays, divergence_error, error_chain, os_error};

/// The result of `fit`: the mesh and the figures `opsim fit` prints.
#[pyclass(name = "FitResult", module = "oriented_particles", frozen)]
pub struct PyFit {
    /// Mesh vertices, float64 (m, 3), in the samples' coordinates.
    #[pyo3(get)]
    vertices: Py<PyAny>,
    /// Unit vertex normals, float64 (m, 3).
    #[pyo3(get)]
    normals: Py<PyAny>,
    /// Triangles as vertex indices, int64 (k, 3), wound along the normals.
    #[pyo3(get)]
    faces: Py<PyAny>,
    /// The figures `opsim fit` prints, as a dict: `particles`, `vertices`
    /// and `faces` (counts), `euler_characteristic`, `boundary_loops`,
    /// `pieces`, `closed`, `rms_distance`, `max_distance` (samples to
    /// mesh), `spacing`, `normals`, `dropped_outliers`, `noise_estimate`,
    /// `approximated`, `thin_features`.
    #[pyo3(get)]
    figures: Py<PyAny>,
    fit: op_scene::fit::Fit,
}

#[pymethods]
impl PyFit {
    /// Writes the mesh as `opsim fit --out` does (OBJ, `v`, `vn`,
    /// `f v//vn`, atomically).
    fn write_obj(&self, path: PathBuf) -> PyResult<()> {
        op_scene::fit::write_obj(&path, &self.fit)
            .map_err(|e| os_error(e.kind(), format!("cannot write {}: {e}", path.display())))
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "FitResult({})",
            self.figures
                .bind(py)
                .repr()
                .map(|r| r.to_string())
                .unwrap_or_default()
        )
    }
}

/// The samples: a points file (.xyz, .pwn, .ply, .obj, as `opsim fit` reads
/// it) or an (n, 3) array with optional (n, 3) normals.
fn samples(points: &Bound<'_, PyAny>, normals: Option<&Bound<'_, PyAny>>) -> PyResult<PointSet> {
    if let Ok(path) = points.extract::<PathBuf>() {
        if normals.is_some() {
            return Err(PyValueError::new_err(
                "normals: give them in the points file, or give the points as an array",
            ));
        }
        return op_scene::pointsets::read_point_set(&path).map_err(|e| match &e {
            PointSetError::Io { source, .. } => os_error(source.kind(), error_chain(&e)),
            _ => PyValueError::new_err(error_chain(&e)),
        });
    }
    let positions: Vec<Point3> = arrays::read_vectors(points, "points")?
        .into_iter()
        .map(Point3::from)
        .collect();
    let normals = match normals {
        Some(n) => {
            let n = arrays::read_vectors(n, "normals")?;
            if n.len() != positions.len() {
                return Err(PyValueError::new_err(format!(
                    "normals: {} rows for {} points",
                    n.len(),
                    positions.len()
                )));
            }
            Some(n)
        }
        None => None,
    };
    Ok(PointSet { positions, normals })
}

/// Fits a surface of oriented particles to a point set and triangulates
/// it, as `opsim fit` does: `points` is a points file (.xyz, .pwn, .ply, .obj)
/// or an (n, 3) array (optional `normals`, (n, 3)); `spacing` the sample
/// spacing (default: the median nearest-sample distance); `open` `True`
/// for open data (only gaps within the search range are filled), `False`
/// for closed data, `None` (default) open when the samples have a
/// boundary; `relax` a
/// relaxation time after the release (default 0: the surface passes
/// through the particles' seeds); `approximate` `True` seeds the particles
/// on a smoothed estimate of the surface (noisy samples), `False` on every
/// sample, `None` (default) decides by the samples' estimated noise (more
/// than a tenth of their spacing: approximated).
///
/// Returns a `FitResult`: `vertices`, `normals`, `faces` and `figures`
/// (what `opsim fit` prints). Raises `ValueError` for bad input (opsim's
/// message), `DivergenceError` when the relaxation diverged.
#[pyfunction]
#[pyo3(signature = (points, spacing = None, open = None, *, normals = None, relax = 0.0, approximate = None))]
pub fn fit(
    py: Python<'_>,
    points: &Bound<'_, PyAny>,
    spacing: Option<Real>,
    open: Option<bool>,
    normals: Option<&Bound<'_, PyAny>>,
    relax: Real,
    approximate: Option<bool>,
) -> PyResult<PyFit> {
    let data = samples(points, normals)?;
    let params = FitParams {
        spacing,
        open,
        relax_time: relax,
        approximate,
        ..Default::default()
    };
    let fit = py
        .detach(|| op_scene::fit::fit(&data, &params))
        .map_err(|e| match e {
            FitError::World(_) | FitError::Diverged(_) => {
                divergence_error(py, format!("cannot fit: {e}"), py.None())
            }
            e => PyValueError::new_err(format!("cannot fit: {}", error_chain(&e))),
        })?;
    let vertices: Vec<_> = fit.mesh.vertices.iter().map(|p| p.coords).collect();
    let figures = py
        .import("json")?
        .call_method1("loads", (op_scene::fit::figures_json(&fit),))?;
    Ok(PyFit {
        vertices: arrays::vectors(py, &vertices).into_any().unbind(),
        normals: arrays::vectors(py, &fit.mesh.normals).into_any().unbind(),
        faces: arrays::triangles(py, &fit.mesh.faces).into_any().unbind(),
        figures: figures.unbind(),
        fit,
    })
}
