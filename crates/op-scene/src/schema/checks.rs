//! Small value checks shared by scene and generator validation. Each returns
//! a [`SceneError::Invalid`] naming the file, the field path, the rejected
//! value and what is allowed.

use crate::error::SceneError;
use op_dynamics::Real;

/// Finite and > 0.
pub(crate) fn positive(file: &str, path: &str, v: Real) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::value(file, path, v, "must be finite and > 0"))
    }
}

/// Finite and >= 0.
pub(crate) fn non_negative(file: &str, path: &str, v: Real) -> Result<(), SceneError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::value(file, path, v, "must be finite and >= 0"))
    }
}

/// Finite (any sign).
pub(crate) fn finite(file: &str, path: &str, v: Real) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SceneError::value(file, path, v, "must be finite"))
    }
}

/// `[x, y, z]` for messages.
pub(crate) fn fmt3(v: &[Real; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

/// Every component finite.
pub(crate) fn finite3(file: &str, path: &str, v: &[Real; 3]) -> Result<(), SceneError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::value(
            file,
            path,
            fmt3(v),
            "every component must be finite",
        ))
    }
}

/// Every component finite and > 0.
pub(crate) fn positive3(file: &str, path: &str, v: &[Real; 3]) -> Result<(), SceneError> {
    if v.iter().all(|c| c.is_finite() && *c > 0.0) {
        Ok(())
    } else {
        Err(SceneError::value(
            file,
            path,
            fmt3(v),
            "every component must be finite and > 0",
        ))
    }
}

/// A finite direction that is not (nearly) zero: it is normalized.
pub(crate) fn direction(file: &str, path: &str, v: &[Real; 3]) -> Result<(), SceneError> {
    finite3(file, path, v)?;
    let norm = v.iter().map(|c| c * c).sum::<Real>().sqrt();
    if norm > 1e-12 {
        Ok(())
    } else {
        Err(SceneError::value(
            file,
            path,
            fmt3(v),
            "must be a non-zero direction (it is normalized)",
        ))
    }
}

/// An `f64` count converted to `usize` when it is at most `max`.
pub(crate) fn count_at_most(
    file: &str,
    path: &str,
    count: Real,
    max: usize,
    what: &str,
) -> Result<usize, SceneError> {
    if count.is_finite() && count <= max as Real {
        Ok(count.max(0.0) as usize)
    } else {
        Err(SceneError::invalid(
            file,
            path,
            format!("{what} would make about {count:.3e} particles; at most {max} are allowed"),
        ))
    }
}
