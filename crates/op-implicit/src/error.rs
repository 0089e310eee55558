//! Errors of the skinning and polygonization stages.

use thiserror::Error;

/// Building or re-posing a [`crate::Skin`] failed.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SkinError {
    /// A primitive names a particle id the world does not hold. Fix: give
    /// the id of an existing particle (ids are assigned by
    /// `Particles::push`), or drop primitives of deleted particles.
    #[error("primitive {index} is attached to particle {id}, which does not exist")]
    UnknownParticle {
        /// Index of the primitive in the skin's list.
        index: usize,
        /// The missing particle id.
        id: u32,
    },
    /// A primitive has a non-finite number, a radius <= 0 or a negative
    /// size (ellipsoid scales must be > 0). Fix the primitive's fields.
    #[error("primitive {index} is invalid: finite values, radius > 0 and sizes >= 0 (ellipsoid scales > 0) are required")]
    InvalidPrimitive {
        /// Index of the primitive in the skin's list.
        index: usize,
    },
    /// A checkpoint's state of the skin does not fit it
    /// ([`crate::object_skin::ObjectSkin::restore`]).
    #[error("{0}")]
    State(String),
}

/// Polygonizing a field failed.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum PolygonizeError {
    /// The cell size is not finite and > 0. Fix: give a positive size in
    /// world units.
    #[error("cell size must be finite and > 0, got {0}")]
    InvalidCellSize(f64),
    /// The iso value is not finite and > 0 (the field is 0 far from the
    /// skeleton, so the surface must lie above 0). Fix: give a positive iso
    /// value, at most the field's largest value.
    #[error("iso value must be finite and > 0, got {0}")]
    InvalidIso(f64),
    /// The sampling grid would need more nodes along an axis than allowed.
    /// Fix: raise the cell size or `max_nodes_per_axis`.
    #[error(
        "the skin spans {needed} nodes along an axis at this cell size; at most {max} allowed"
    )]
    TooManyNodes {
        /// Nodes needed along the longest axis.
        needed: usize,
        /// The configured limit.
        max: usize,
    },
    /// The region to sample is not finite: a primitive sits at a
    /// non-finite position (a simulation that diverged).
    #[error("the skin's region is not finite: a particle is at a non-finite position (the simulation diverged)")]
    NonFiniteRegion,
}
