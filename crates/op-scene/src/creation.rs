//! Particle creation in scenes (seed 000 §7; op-dynamics
//! [`op_modeling::creation`]): the scene's `creation` section and what the
//! runner does with it.
//!
//! ```ron
//! creation: Some((
//!     stretching: Some((d_min: 2.0, d_max: 2.5)),
//!     growing: None,
//!     merging: Some((distance: 0.3)),
//!     interval: 10,
//! )),
//! ```
//!
//! The rules run at the start of the frames phase and then every
//! `interval` steps (not while settling), over all objects; a new particle joins the object of the
//! particle it was made from and is listed in that object's
//! [`BuiltObject::created`](crate::BuiltObject::created). Consequences for
//! the outputs:
//!
//! - OBJ frames and `summary.json` (`objects[].particles`) count every live
//!   particle, created ones included;
//! - the rest shape error is measured over the object's *original*
//!   particles (those of the generator, which the runner never removes)
//!   against their rest positions: created particles have no rest
//!   position.
//!
//! With `fit` (point-set interpolation, [`crate::schema::fit`]) the rules
//! act only near an object's samples and stop at the release time, when
//! the samples are freed.
//!
//! Created particles of a skinned object get the object's skin primitive,
//! merged ones lose theirs ([`crate::stages`]).

use op_dynamics::Real;
use op_modeling::creation::{CreationParams, GrowingParams, MergingParams, StretchingParams};
use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::schema::checks::positive;
use crate::schema::FitSettings;

/// The `creation` section of a scene: which rules, every how many steps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CreationSettings {
    /// The rest spacing `r0` the rules' lengths are fractions of, > 0.
    /// Default: the rest spacing of the first object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub spacing: Option<Real>,
    /// The stretching rule (`d_min`, `d_max`, `reach`, fractions of `r0`).
    /// Default: none.
    #[serde(default)]
    pub stretching: Option<StretchingParams>,
    /// The growing rule (`radius`, `min_neighbours`, `max_neighbours`,
    /// `min_gap`, `max_gap` in radians, `clearance`). Default: none.
    #[serde(default)]
    pub growing: Option<GrowingParams>,
    /// The merging rule (`distance`, a fraction of `r0`): particles of one
    /// object closer than that become one. Default: none.
    #[serde(default)]
    pub merging: Option<MergingParams>,
    /// Steps between two applications, >= 1. Default: 10.
    #[serde(default = "ten")]
    #[schemars(range(min = 1))]
    pub interval: u64,
    /// No particle is created once the world holds this many, >= 1.
    /// Default: 100 000.
    #[serde(default = "hundred_thousand")]
    #[schemars(range(min = 1))]
    pub max_particles: usize,
    /// Point-set interpolation (seed 000 §7): an object's particles are
    /// fixed samples, the rules fill only near them and stop at a release
    /// time (see [`crate::schema::fit`]). Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitSettings>,
}

fn ten() -> u64 {
    10
}

fn hundred_thousand() -> usize {
    100_000
}

impl CreationSettings {
    /// The op-dynamics parameters, with `r0` the spacing if given, else
    /// `default_r0`.
    pub fn params(&self, default_r0: Real) -> CreationParams {
        CreationParams {
            r0: self.spacing.unwrap_or(default_r0),
            stretching: self.stretching.clone(),
            growing: self.growing.clone(),
            merging: self.merging.clone(),
            interval: self.interval,
            max_particles: self.max_particles,
        }
    }

    /// Checks every field; errors name `creation.<field>`.
    pub(crate) fn validate(&self, file: &str) -> Result<(), SceneError> {
        if let Some(s) = self.spacing {
            positive(file, "creation.spacing", s)?;
        }
        if self.stretching.is_none() && self.growing.is_none() && self.merging.is_none() {
            return Err(SceneError::invalid(
                file,
                "creation",
                "enables no rule: give `stretching`, `growing` or `merging` (or remove `creation`)",
            ));
        }
        self.params(1.0)
            .validate()
            .map_err(|e| SceneError::param(file, "creation", e))
    }
}

/// The creation rules of a built scene and when they act next.
#[derive(Clone, Debug)]
pub struct CreationState {
    /// The rules, `r0` resolved.
    pub params: CreationParams,
    /// World step count at which the rules act next.
    pub next_step: u64,
    /// The running fit, when the section has `fit`.
    pub fit: Option<crate::fit::SceneFit>,
}
