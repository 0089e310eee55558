//! The `fit` part of a scene's `creation` section: point-set interpolation
//! (seed 000 §7, figs. 10-11) run as a scene, so its frames show the
//! surface growing between the samples.
//!
//! ```ron
//! creation: Some((
//!     spacing: Some(1),
//!     stretching: Some((d_min: 2.0, d_max: 2.5)),
//!     growing: Some((max_gap: 2.967)),
//!     interval: 50,
//!     fit: Some((object: "samples", release: 3)),
//! )),
//! ```
//!
//! The named object's particles are the samples. The builder fixes their
//! positions and orientations (after the object's overrides); when they
//! come from a `Points` file without normals, their normals are estimated
//! as `opsim fit` does ([`crate::fit`] stage 2, over 2.5 spacings). The
//! creation rules then act only in the data's neighbourhood
//! ([`crate::fit::DataNeighbourhood`]: within reach of a sample, near its
//! tangent plane), and only until `release`; at `release` the seeds are
//! freed ([`crate::fit::release`]) and the surface relaxes under the
//! scene's material. The material, world settings and rules are the
//! scene's own; `opsim fit` uses cohesion with `r0` at the spacing and a
//! `1.5 r0` cut-off, co-circularity 5, damping 2 / 0.2, velocity Verlet at
//! `dt = 2e-3 r0`-units and a creation round every 0.1 time units
//! (`scenes/fig_10_interpolation.ron` uses the same).
//!
//! The spacing `r0` of the fitted surface is `creation.spacing`, by
//! default the median distance from a sample to its nearest other sample.
//! It is the object's rest spacing (triangulation radius, glyph size, unit
//! of the rest shape error), not the distance between samples; the rest
//! shape error measures how far the released samples drift from the data
//! (after the best rigid alignment), in spacings.

use op_dynamics::Real;
use serde::{Deserialize, Serialize};

use super::Scene;
use crate::creation::CreationSettings;
use crate::error::SceneError;

/// `creation.fit`: which object holds the samples, when they are
/// released, open or closed data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FitSettings {
    /// Name of the object whose particles are the samples. Required.
    pub object: String,
    /// Scene time at which the seeds are freed and creation stops, finite,
    /// >= 0 and below `world.duration`. Required.
    #[schemars(range(min = 0))]
    pub release: Real,
    /// Open data (seed 000 fig. 11): particles are created within
    /// `d_max / 2` spacings of a sample, so gaps up to the search range
    /// `d_max` close and wider ones stay holes; the creation rules must be
    /// stretching only (growing runs along the edges). Closed data (fig.
    /// 10): within `d_max / √3` of a sample. Default: false.
    #[serde(default)]
    pub open: bool,
}

impl FitSettings {
    /// Checks the section against the scene and its creation rules: a
    /// known object, a release time within the run, no settle phase, and
    /// rules that can
    /// fill (stretching, whose `d_max` is the search range; no growing for
    /// open data). Errors name `creation.fit.<field>` or the rule.
    pub(crate) fn validate(
        &self,
        scene: &Scene,
        creation: &CreationSettings,
        file: &str,
    ) -> Result<(), SceneError> {
        if !scene.objects.iter().any(|o| o.name == self.object) {
            let names = crate::error::quoted_list(scene.objects.iter().map(|o| o.name.as_str()));
            return Err(SceneError::value(
                file,
                "creation.fit.object",
                format!("{:?}", self.object),
                &format!("unknown object (defined objects: {names})"),
            ));
        }
        let duration = scene.world.duration;
        if !(self.release.is_finite() && self.release >= 0.0 && self.release < duration) {
            return Err(SceneError::value(
                file,
                "creation.fit.release",
                self.release,
                &format!(
                    "must be finite, >= 0 and below world.duration = {duration}{} (the seeds are released during the run)",
                    scene.set_by_frames()
                ),
            ));
        }
        if scene.world.settle != 0.0 {
            return Err(SceneError::value(
                file,
                "world.settle",
                scene.world.settle,
                "must be 0 with `creation.fit`: the samples stay fixed while settling, and the settle phase would replace the fitted object's rest spacing (the fit spacing) by the distance between samples",
            ));
        }
        if creation.stretching.is_none() {
            return Err(SceneError::invalid(
                file,
                "creation.stretching",
                "is required by `creation.fit`: its d_max is the search range that bounds how far from the samples particles are created",
            ));
        }
        if self.open && creation.growing.is_some() {
            return Err(SceneError::invalid(
                file,
                "creation.growing",
                "must be None with `creation.fit.open: true`: open data is filled by stretching only (seed 000 §7; growing would extend the surface along its edges); remove it or set open: false",
            ));
        }
        Ok(())
    }

    /// Index of the fitted object (validated).
    pub(crate) fn object_index(&self, scene: &Scene) -> usize {
        scene
            .objects
            .iter()
            .position(|o| o.name == self.object)
            .unwrap_or(0)
    }
}
