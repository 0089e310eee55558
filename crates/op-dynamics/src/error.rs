//! Errors of the dynamics crate.

use crate::math::Real;

/// A parameter that is NaN, infinite or out of its allowed range.
///
/// The message names the field, the bad value and what would be valid, so a
/// scene file author can fix it without reading the source.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    /// A numeric field outside its allowed range (or not finite).
    #[error("`{field}` = {value}: {allowed}")]
    OutOfRange {
        /// Dotted path of the field, e.g. `cohesion.alpha`.
        field: String,
        /// The rejected value.
        value: Real,
        /// What is allowed, e.g. "must be finite and > 0".
        allowed: String,
    },
    /// A combination of fields that is inconsistent.
    #[error("`{field}`: {message}")]
    Invalid {
        /// Dotted path of the field.
        field: String,
        /// What is wrong and what would be valid.
        message: String,
    },
}

impl ParamError {
    /// Prefixes the field path with `prefix.` (used when a parameter struct
    /// is nested in another, e.g. `material.cohesion.alpha`).
    pub fn within(self, prefix: &str) -> Self {
        self.renamed(|field| format!("{prefix}.{field}"))
    }

    /// Renames the field path with `rename` (used when a type's fields are
    /// set from a differently named description, e.g. a scene file's).
    pub fn renamed(self, rename: impl FnOnce(&str) -> String) -> Self {
        match self {
            ParamError::OutOfRange {
                field,
                value,
                allowed,
            } => ParamError::OutOfRange {
                field: rename(&field),
                value,
                allowed,
            },
            ParamError::Invalid { field, message } => ParamError::Invalid {
                field: rename(&field),
                message,
            },
        }
    }
}

/// Checks that `value` is finite and strictly positive.
pub fn positive(field: &str, value: Real) -> Result<(), ParamError> {
    check(
        field,
        value,
        value.is_finite() && value > 0.0,
        "must be finite and > 0",
    )
}

/// Checks that `value` is finite and not negative.
pub fn non_negative(field: &str, value: Real) -> Result<(), ParamError> {
    check(
        field,
        value,
        value.is_finite() && value >= 0.0,
        "must be finite and >= 0",
    )
}

/// Checks that `value` is finite (any sign).
pub fn finite(field: &str, value: Real) -> Result<(), ParamError> {
    check(field, value, value.is_finite(), "must be finite")
}

/// Returns an [`ParamError::OutOfRange`] for `field` unless `ok`.
pub fn check(field: &str, value: Real, ok: bool, allowed: &str) -> Result<(), ParamError> {
    if ok {
        Ok(())
    } else {
        Err(ParamError::OutOfRange {
            field: field.to_string(),
            value,
            allowed: allowed.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_field_value_and_rule() {
        let e = positive("cohesion.alpha", Real::NAN)
            .unwrap_err()
            .within("material");
        let s = e.to_string();
        assert!(s.contains("material.cohesion.alpha"), "{s}");
        assert!(s.contains("NaN"), "{s}");
        assert!(s.contains("> 0"), "{s}");
        assert!(non_negative("x", -1.0).is_err());
        assert!(non_negative("x", 0.0).is_ok());
        assert!(finite("x", Real::INFINITY).is_err());
    }
}
