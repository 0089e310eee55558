//! The settings of a world: integrator and step, neighbour lists
//! (seed 000 §4.2), external actions (seed 000 eq. 12-13), divergence
//! detection and heat.

use serde::{Deserialize, Serialize};

use crate::error::{self, ParamError};
use crate::external::ExternalParams;
use crate::forces::Precision;
use crate::heat::HeatParams;
use crate::integrators::Scheme;
use crate::math::Real;
use crate::neighbours::NeighbourBackend;

/// Neighbour-list settings (seed 000 §4.2, docs/model.md §5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct NeighbourParams {
    /// Search structure for the per-step lists. Default: the measured
    /// faster one ([`NeighbourBackend::default`]).
    pub backend: NeighbourBackend,
    /// Skin as a fraction of the interaction cut-off: lists hold pairs
    /// within `cutoff * (1 + skin)` and are rebuilt when the two largest
    /// particle displacements since the last build add up to more than the
    /// skin. `0 < skin <= 10` ([`MAX_SKIN`]); the list
    /// radius `cutoff * (1 + skin)` of every material must also be finite
    /// ([`crate::World::new`] checks it). Default: 0.2.
    #[schemars(extend("exclusiveMinimum" = 0), range(max = MAX_SKIN))]
    pub skin: Real,
    /// Re-sort particles in spatial (Morton) order at each rebuild (column
    /// order in mixed precision, for compact clusters).
    /// Default: true.
    pub reorder: bool,
}

impl Default for NeighbourParams {
    fn default() -> Self {
        NeighbourParams {
            backend: NeighbourBackend::default(),
            skin: 0.2,
            reorder: true,
        }
    }
}

/// Largest neighbour skin (as a fraction of the cut-off): a list of radius
/// `(1 + skin)` cut-offs holds `(1 + skin)^3` times the pairs that interact,
/// so a skin of 10 already makes the list over 1000 times too long; larger
/// values only cost memory and time (and `1e308` overflows the radius).
pub const MAX_SKIN: Real = 10.0;

/// When a run is declared diverged (besides NaN / infinite values, which
/// always are).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DivergenceParams {
    /// Largest particle speed considered physical, > 0. Default: infinity.
    pub max_speed: Real,
}

impl Default for DivergenceParams {
    fn default() -> Self {
        DivergenceParams {
            max_speed: Real::INFINITY,
        }
    }
}

/// Settings of a world.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct WorldParams {
    /// Time integration scheme. Default: velocity Verlet.
    pub scheme: Scheme,
    /// Time step (fixed-step schemes) or initial and largest step
    /// (adaptive), > 0. Default: 1e-3.
    pub dt: Real,
    /// Neighbour lists.
    pub neighbours: NeighbourParams,
    /// Gravity, damping and force windows.
    pub external: ExternalParams,
    /// Divergence detection.
    pub divergence: DivergenceParams,
    /// Arithmetic of the pair kernels ([`Precision`]): `double` (the
    /// default) or `mixed` (`f32` pair lanes in the cluster kernels, sums
    /// and integration in `f64`). Default: double.
    #[serde(skip_serializing_if = "is_double")]
    pub precision: Precision,
    /// Heat conduction and cooling ([`crate::heat`]), or `None` for
    /// constant temperatures. Required by heater and knife tools.
    /// Default: `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heat: Option<HeatParams>,
}

impl Default for WorldParams {
    fn default() -> Self {
        WorldParams {
            scheme: Scheme::VelocityVerlet,
            dt: 1e-3,
            neighbours: NeighbourParams::default(),
            external: ExternalParams::default(),
            divergence: DivergenceParams::default(),
            precision: Precision::Double,
            heat: None,
        }
    }
}

fn is_double(p: &Precision) -> bool {
    *p == Precision::Double
}

impl WorldParams {
    /// Checks every field; `particle_count` bounds force-window ids.
    pub fn validate(&self, particle_count: usize) -> Result<(), ParamError> {
        error::positive("dt", self.dt)?;
        error::check(
            "neighbours.skin",
            self.neighbours.skin,
            self.neighbours.skin > 0.0 && self.neighbours.skin <= MAX_SKIN,
            "must be > 0 and <= 10 (a fraction of the cut-off; the lists hold pairs within \
             cutoff * (1 + skin))",
        )?;
        error::check(
            "divergence.max_speed",
            self.divergence.max_speed,
            self.divergence.max_speed > 0.0,
            "must be > 0 (infinity disables the check)",
        )?;
        self.scheme.validate().map_err(|e| e.within("scheme"))?;
        self.external
            .validate(particle_count)
            .map_err(|e| e.within("external"))?;
        if let Some(h) = &self.heat {
            h.validate().map_err(|e| e.within("heat"))?;
        }
        Ok(())
    }
}
