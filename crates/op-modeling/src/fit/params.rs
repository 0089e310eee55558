//! The settings of a fit ([`FitParams`]) and their checks.

use op_dynamics::Real;

use super::{FitError, MAX_RELAX_TIME, STEP};

/// Settings of [`fit`](super::fit); lengths in units of the spacing
/// unless said.
#[derive(Clone, Debug, PartialEq)]
pub struct FitParams {
    /// Sample spacing `h` (absolute length, > 0), or `None` for the median
    /// nearest-sample distance. [`fit`](super::fit) refuses one above the
    /// diagonal of the samples' bounding box, or so small that the surface
    /// would need more than [`MAX_PARTICLES`](super::MAX_PARTICLES)
    /// particles ([`FitError::Spacing`] gives the range). Default: `None`.
    pub spacing: Option<Real>,
    /// Open data (`Some(true)`): stretching only, holes wider than `d_max`
    /// stay. Closed data (`Some(false)`): growing too, and holes up to
    /// [`FitParams::max_hole`] are closed. `None`: open when the samples
    /// have a boundary (a chain of samples whose neighbours all lie to one
    /// side, [`Fit::open`](super::Fit::open)). Default: `None`.
    pub open: Option<bool>,
    /// Stretching range `[d_min, d_max]` (the search range). Default:
    /// 2.0 and 2.5 (seed 000 §7).
    pub d_min: Real,
    /// See `d_min`.
    pub d_max: Real,
    /// Largest number of creation rounds. Default: 20.
    pub max_rounds: usize,
    /// Relaxation time after release (unit-spacing time units, >= 0).
    /// Default: 0: the fit interpolates the samples (seed 000 §7, "surface
    /// interpolation"); give a time for noisy samples, which the release
    /// smooths (the paper's reason for it) at the price of leaving the
    /// data. Measured on 5,000 random samples of the shapes of
    /// [`shapes`](super::shapes) (exact, no noise) at 0, 0.3 and 1: the same topology; sample-to-mesh
    /// RMS 7e-5, 2e-4, 6.8e-4 on the ellipsoid (growing with the time, 2e-3
    /// at 3); median smallest angle 38°, 40°, 45° but triangles under 20°
    /// 10%, 10%, 17%; time 0.6, 1.4, 3.2 s. On the 26,002 vertices of a
    /// scanned armadillo, 0 against 1: RMS 0.0032 against 0.30 (spacing
    /// 1.31), 1.9% against 15% of triangles under 20°, 3.2 s against 19 s.
    pub relax_time: Real,
    /// Mutual-neighbour radius of the triangulation, > 0; keep it at
    /// least `d_min`. Default: 2.0 (the default `d_min`): a pair closer
    /// than `d_min` is no gap for the stretching rule, so nothing is
    /// created between them and the triangulation must bridge them. With
    /// the 1.7 of sheets, holes whose diagonals fall between 1.7 and
    /// `d_min` (quads of sides 1.1-1.7 with 90° corners, which the growing
    /// rule's 100° `min_gap` does not fill either) stayed open.
    pub triangulation_radius: Real,
    /// Number of nearest samples whose PCA gives a sample's normal when
    /// the file has none (Hoppe et al. 1992), >= 3. Default: 12.
    pub neighbours: usize,
    /// Drop outlier samples before seeding (stage 0,
    /// [`Fit::dropped_outliers`](super::Fit::dropped_outliers)). Default:
    /// true.
    pub drop_outliers: bool,
    /// Closed data: holes left after the relaxation narrower than this
    /// (in spacings; width `4 area / perimeter`) are closed by the final
    /// pass. Open data close those narrower than `d_max` instead.
    /// Default: 8.
    pub max_hole: Real,
    /// Approximate the samples within their noise instead of passing
    /// through each (`Some(true)`), interpolate them (`Some(false)`), or
    /// decide by the samples (`None`): samples whose estimated noise
    /// ([`Fit::noise_estimate`](super::Fit::noise_estimate)) exceeds a
    /// tenth of their spacing, or whose sparse parts need more than 2.5
    /// times the default spacing (a density step, scan lines), are
    /// approximated. Approximating seeds the particles on a smoothed
    /// estimate of the surface, thinned to a spacing of at least four
    /// noise levels (and to the sparse parts' spacing). Default: `None`.
    pub approximate: Option<bool>,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            spacing: None,
            open: None,
            d_min: 2.0,
            d_max: 2.5,
            max_rounds: 20,
            relax_time: 0.0,
            triangulation_radius: 2.0,
            neighbours: 12,
            drop_outliers: true,
            max_hole: 8.0,
            approximate: None,
        }
    }
}

impl FitParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), FitError> {
        let bad = |f: &str, v: Real, m: &str| Err(FitError::Input(format!("{f} = {v}: {m}")));
        if let Some(h) = self.spacing {
            if !(h.is_finite() && h > 0.0) {
                return bad("spacing", h, "must be finite and > 0");
            }
        }
        if !(self.d_min.is_finite() && self.d_min > 0.0) {
            return bad("d_min", self.d_min, "must be finite and > 0");
        }
        if !(self.d_max.is_finite() && self.d_max >= self.d_min) {
            return bad("d_max", self.d_max, "must be finite and >= d_min");
        }
        if !(self.relax_time.is_finite() && (0.0..=MAX_RELAX_TIME).contains(&self.relax_time)) {
            return bad(
                "relax_time",
                self.relax_time,
                &format!(
                    "must be finite, >= 0 and at most {MAX_RELAX_TIME} ({} relaxation steps of \
                     every particle; a relaxation of 10 already moves the surface off the \
                     samples by a fraction of a spacing)",
                    MAX_RELAX_TIME / STEP
                ),
            );
        }
        if !(self.triangulation_radius.is_finite() && self.triangulation_radius > 0.0) {
            return bad(
                "triangulation_radius",
                self.triangulation_radius,
                "must be finite and > 0",
            );
        }
        if !(self.max_hole.is_finite() && self.max_hole >= 0.0) {
            return bad("max_hole", self.max_hole, "must be finite and >= 0");
        }
        if self.neighbours < 3 {
            return bad("neighbours", self.neighbours as Real, "must be >= 3");
        }
        Ok(())
    }
}
