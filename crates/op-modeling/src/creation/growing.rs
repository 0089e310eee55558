//! The growing rule (seed 000 §7, second rule; point-set fitting, figure
//! 10).
//!
//! For each particle, its *neighbours* are the particles of its object
//! within `radius` (a fraction of `r0`). When their count `n_N` is in
//! `[min_neighbours, max_neighbours]`, their directions are projected on the
//! particle's tangent plane (local x = the world tangent `R(q) x`, local y
//! = `n x x`) and sorted by angle; each angular gap `Δθ` between successive
//! neighbours (cyclically) with `min_gap <= Δθ <= max_gap` receives
//! `m = max(1, round(Δθ / 60°) - 1)` new particles at distance `r0`, at the
//! angles dividing the gap into `m + 1` equal parts. A hexagonal sheet has
//! six neighbours 60° apart, so `m` fills a gap with the lattice's missing
//! directions; a particle with no neighbour gets six, at 0°, 60°, ...,
//! 300° from its local x. An edge particle of a sheet has one 180° gap:
//! `max_gap` below 180° stops growth at edges while still filling holes
//! (the paper's limit on growth "in regions of few neighbouring
//! particles").
//!
//! A candidate is dropped when any particle (of any object) or a candidate
//! accepted before it lies strictly within `clearance` of it. New particles
//! copy their parent's frame, velocity and static attributes (not the fixed
//! flags). Candidates are accepted by parent id, then by angle.

use std::f64::consts::{FRAC_PI_3, TAU};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{child_of, world_tangent, Accepted, Neighbourhood};
use op_dynamics::error::{self, ParamError};
use op_dynamics::math::Real;
use op_dynamics::particles::{ParticleDesc, Particles};

/// Parameters of the growing rule; lengths are fractions of `r0`, angles
/// radians.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct GrowingParams {
    /// Neighbour radius, > 0. Default: 1.5 (the first ring of a hexagonal
    /// sheet, not the second at √3).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub radius: Real,
    /// Smallest neighbour count of a growing particle. Default: 0.
    pub min_neighbours: usize,
    /// Largest neighbour count of a growing particle, >= `min_neighbours`.
    /// Default: 5 (interior particles of a sheet, with six, never grow).
    pub max_neighbours: usize,
    /// Smallest angular gap that receives particles, in (0, 2π].
    /// Default: 100° (1.745 rad): the 60° gaps of a sheet, even distorted,
    /// do not; a missing neighbour's 120° gap does.
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = std::f64::consts::TAU))]
    pub min_gap: Real,
    /// Largest angular gap that receives particles, in [`min_gap`, 2π].
    /// Default: 2π (edges grow too).
    ///
    /// [`min_gap`]: GrowingParams::min_gap
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = std::f64::consts::TAU))]
    pub max_gap: Real,
    /// Smallest distance from a candidate to any particle or accepted
    /// candidate, in (0, 1]. Default: 0.7.
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = 1))]
    pub clearance: Real,
}

impl Default for GrowingParams {
    fn default() -> Self {
        GrowingParams {
            radius: 1.5,
            min_neighbours: 0,
            max_neighbours: 5,
            min_gap: 100f64.to_radians(),
            max_gap: TAU,
            clearance: 0.7,
        }
    }
}

impl GrowingParams {
    /// The radius around a particle that holds everything the rule reads
    /// of it (absolute, for spacing `r0`): its neighbours (`radius`) and
    /// every particle that can block a candidate at `r0` from it (`r0 +
    /// clearance`).
    pub(crate) fn search_radius(&self, r0: Real) -> Real {
        (self.radius * r0).max(r0 + self.clearance * r0)
    }

    /// Checks ranges: positive radius, ordered counts, gaps in (0, 2π],
    /// clearance in (0, 1].
    pub fn validate(&self) -> Result<(), ParamError> {
        error::positive("radius", self.radius)?;
        if self.max_neighbours < self.min_neighbours {
            return Err(ParamError::Invalid {
                field: "max_neighbours".into(),
                message: format!(
                    "{} is below min_neighbours = {}",
                    self.max_neighbours, self.min_neighbours
                ),
            });
        }
        error::check(
            "min_gap",
            self.min_gap,
            self.min_gap > 0.0 && self.min_gap <= TAU,
            "must be in (0, 2π] radians",
        )?;
        error::check(
            "max_gap",
            self.max_gap,
            self.max_gap >= self.min_gap && self.max_gap <= TAU,
            "must be in [min_gap, 2π] radians",
        )?;
        error::check(
            "clearance",
            self.clearance,
            self.clearance > 0.0 && self.clearance <= 1.0,
            "must be in (0, 1] (a fraction of r0)",
        )
    }
}

/// Offers the growing candidates of `p` to `accepted`, by parent id then
/// angle, reading the neighbours of `near` (searched at least as far as
/// [`GrowingParams::search_radius`]).
pub(crate) fn candidates(
    p: &Particles,
    near: &Neighbourhood,
    r0: Real,
    params: &GrowingParams,
    accepted: &mut Accepted,
) {
    let pos = p.positions();
    let radius = params.radius * r0;
    let clearance = params.clearance * r0;
    let ids = p.ids();
    let mut found: Vec<(u32, Vec<ParticleDesc>)> = (0..p.len())
        .into_par_iter()
        .map_init(Vec::new, |around: &mut Vec<u32>, i| {
            if !pos[i].iter().all(|c| c.is_finite()) {
                return None;
            }
            near.around_into(i, params.search_radius(r0), around);
            let n = p.normal(i);
            let x = {
                let t = world_tangent(p, i);
                (t - n * n.dot(&t)).normalize()
            };
            let y = n.cross(&x);
            let mut angles: Vec<Real> = around
                .iter()
                .map(|&k| k as usize)
                .filter(|&k| {
                    p.objects()[k] == p.objects()[i]
                        && (pos[k] - pos[i]).norm_squared() <= radius * radius
                })
                .map(|k| {
                    let r = pos[k] - pos[i];
                    r.dot(&y).atan2(r.dot(&x))
                })
                .collect();
            if angles.len() < params.min_neighbours || angles.len() > params.max_neighbours {
                return None;
            }
            angles.sort_by(|a, b| a.total_cmp(b));
            let dirs = gap_directions(&angles, params.min_gap, params.max_gap);
            let out: Vec<ParticleDesc> = dirs
                .into_iter()
                .filter_map(|theta| {
                    let c = pos[i] + r0 * (theta.cos() * x + theta.sin() * y);
                    let blocked = around
                        .iter()
                        .any(|&k| (pos[k as usize] - c).norm_squared() < clearance * clearance);
                    if blocked {
                        return None;
                    }
                    let mut d = child_of(p, i, c, &n, &x);
                    d.orientation = p.orientations()[i];
                    d.velocity = p.velocities()[i];
                    d.angular_velocity = p.angular_velocities()[i];
                    Some(d)
                })
                .collect();
            (!out.is_empty()).then_some((ids[i], out))
        })
        .flatten_iter()
        .collect();
    found.sort_by_key(|(id, _)| *id);
    for d in found.into_iter().flat_map(|(_, v)| v) {
        accepted.offer(d, clearance);
    }
}

/// The directions (angles) of new particles in the gaps of the sorted
/// neighbour angles `sorted` (radians in (-π, π]).
fn gap_directions(sorted: &[Real], min_gap: Real, max_gap: Real) -> Vec<Real> {
    if sorted.is_empty() {
        return (0..6).map(|s| s as Real * FRAC_PI_3).collect();
    }
    let mut out = Vec::new();
    for (k, &a) in sorted.iter().enumerate() {
        let b = if k + 1 < sorted.len() {
            sorted[k + 1]
        } else {
            sorted[0] + TAU
        };
        let gap = b - a;
        // Within a relative 1e-9 of the bounds counts as inside (a
        // perfect lattice sits exactly on 60° multiples).
        if gap < min_gap * (1.0 - 1e-9) || gap > max_gap * (1.0 + 1e-9) {
            continue;
        }
        let m = ((gap / FRAC_PI_3).round() as usize)
            .saturating_sub(1)
            .max(1);
        out.extend((1..=m).map(|s| a + gap * s as Real / (m + 1) as Real));
    }
    out
}
