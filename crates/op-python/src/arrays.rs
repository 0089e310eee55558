//! numpy arrays in and out: rows of 3 or 4 float64 (positions, normals,
//! velocities, quaternions) and rows of 3 int64 (triangles).
//!
//! Arrays out are new arrays owning the data (handed to numpy without a
//! further copy): an object's particles are not contiguous in the world's
//! storage (the world re-sorts its particles in space between steps), so a
//! view of them cannot exist.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use op_dynamics::{Quat, Real, Vec3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// An (n, 3) float64 array of `rows`.
pub fn vectors<'py>(py: Python<'py>, rows: &[Vec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    owned(py, flat, rows.len(), 3)
}

/// An (n, 4) float64 array of unit quaternions as `(w, x, y, z)` (the order
/// of the VTU frames' `orientation`).
pub fn quaternions<'py>(py: Python<'py>, rows: &[Quat]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flat_map(|q| [q.w, q.i, q.j, q.k]).collect();
    owned(py, flat, rows.len(), 4)
}

/// A (k, 3) int64 array of triangles (vertex indices).
pub fn triangles<'py>(py: Python<'py>, rows: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = rows.iter().flat_map(|t| t.map(i64::from)).collect();
    owned(py, flat, rows.len(), 3)
}

/// `flat` as an (n, cols) array, without copying it.
fn owned<T: numpy::Element>(
    py: Python<'_>,
    flat: Vec<T>,
    n: usize,
    cols: usize,
) -> Bound<'_, PyArray2<T>> {
    Array2::from_shape_vec((n, cols), flat)
        .expect("n rows of cols values")
        .into_pyarray(py)
}

/// The rows of `value` (anything `numpy.asarray` takes: an array, a list
/// of rows) as vectors: an (n, 3) array of finite numbers, converted to
/// float64. `what` names it in messages, e.g. `positions`.
pub fn read_vectors(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vec3>> {
    let py = value.py();
    let array = py
        .import("numpy")?
        .call_method1("ascontiguousarray", (value, "float64"))
        .map_err(|e| PyValueError::new_err(format!("{what}: not an array of numbers: {e}")))?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an array of shape (n, 3), got shape {shape:?}"
        )));
    }
    let array: PyReadonlyArray2<'_, f64> = array.extract()?;
    let view = array.as_array();
    let rows: Vec<Vec3> = view
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect();
    if let Some(k) = rows.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
        return Err(PyValueError::new_err(format!(
            "{what}[{k}] = {:?}: must be finite",
            rows[k].as_slice()
        )));
    }
    debug_assert_eq!(array.shape()[0], rows.len());
    Ok(rows)
}

/// One finite 3-vector from `value` (a sequence of three numbers).
pub fn read_vector(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec3> {
    let v: [Real; 3] = value
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{what}: expected three numbers")))?;
    if !v.iter().all(|x| x.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "{what} = {v:?}: must be finite"
        )));
    }
    Ok(Vec3::from(v))
}
