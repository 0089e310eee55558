//! The fusion rule: two layers of one surface pressed against each other
//! open into each other (our addition, for seed 000 fig. 13: "the initial
//! surface is deformed upwards and then looped around. The new topology (a
//! handle) is created automatically").
//!
//! When the tip of a stem is pressed onto the body it grew from, the two
//! walls lie one on the other, their normals opposite. Seed 000 does not
//! say how the handle then opens; its fig. 14 deletes the particles trapped
//! between two shaping tools. This rule does the same without a tool:
//! particles where two layers touch are deleted, which leaves a hole in
//! each wall; the two rims lie about one spacing apart with opposite
//! normals, an arrangement the co-circularity potential (seed 000 eq. 9)
//! holds as a tight curve, so the rims close into the wall of a tunnel.
//!
//! **Rule.** Two particles `i`, `j` of the same object fuse (both are
//! deleted) when
//! - they are less than `distance · r0` apart,
//! - their normals make more than `min_angle` (opposite layers), and
//! - each lies within `max_offset` of the other's normal line, that is
//!   `|n_i · r̂| >= cos(max_offset)` and the same for `j` (one layer on top
//!   of the other, not two neighbours of one sheet folded sharply),
//! - and, with `min_temperature`, both are at least that hot (seed 000
//!   §8: only the heated parts of the surface deform).
//!
//! Fixed particles never fuse, nor do coincident ones (no direction: the
//! merging rule, [`super::merging`], is for them).
//!
//! **Determinism**: pairs are taken in ascending order of their id pairs,
//! each particle at most once per application.

use serde::{Deserialize, Serialize};

use crate::error::{self, ParamError};
use crate::flags::Flags;
use crate::math::Real;
use crate::neighbours::{search, NeighbourBackend, PairList};
use crate::particles::Particles;

/// Parameters of the fusion rule, lengths as fractions of `r0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FusionParams {
    /// Pairs closer than this fuse, in (0, 1). Default: 0.6.
    pub distance: Real,
    /// Smallest angle (radians) between the two normals, in [pi/2, pi).
    /// Default: 5 pi / 6 (150 degrees).
    pub min_angle: Real,
    /// Largest angle (radians) between the pair's direction and each
    /// particle's normal line, in (0, pi/2). Default: pi / 4.
    pub max_offset: Real,
    /// Only pairs whose two particles are at least this hot fuse
    /// (finite), or `None` for every pair. Default: `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_temperature: Option<Real>,
}

impl Default for FusionParams {
    fn default() -> Self {
        use std::f64::consts::PI;
        FusionParams {
            distance: 0.6,
            min_angle: 5.0 * PI / 6.0,
            max_offset: PI / 4.0,
            min_temperature: None,
        }
    }
}

impl FusionParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), ParamError> {
        use std::f64::consts::{FRAC_PI_2, PI};
        error::check(
            "distance",
            self.distance,
            self.distance > 0.0 && self.distance < 1.0,
            "must be in (0, 1) (a fraction of the rest spacing r0)",
        )?;
        error::check(
            "min_angle",
            self.min_angle,
            (FRAC_PI_2..PI).contains(&self.min_angle),
            "must be in [pi/2, pi) radians",
        )?;
        error::check(
            "max_offset",
            self.max_offset,
            self.max_offset > 0.0 && self.max_offset < FRAC_PI_2,
            "must be in (0, pi/2) radians",
        )?;
        if let Some(t) = self.min_temperature {
            error::finite("min_temperature", t)?;
        }
        Ok(())
    }
}

/// The ids of the particles the rule deletes now, pair by pair in
/// ascending order of the id pairs.
pub fn fusions(p: &Particles, r0: Real, params: &FusionParams) -> Vec<u32> {
    let radius = params.distance * r0;
    let mut pairs = PairList::new();
    search(
        NeighbourBackend::CellList,
        p.positions(),
        radius,
        &mut pairs,
    );
    let (ids, flags, objects, x) = (p.ids(), p.flags(), p.objects(), p.positions());
    let temperatures = p.temperatures();
    let movable = |k: usize| !flags[k].contains(Flags::FIXED_POSITION);
    let hot = |k: usize| params.min_temperature.is_none_or(|t| temperatures[k] >= t);
    let (cos_opposite, cos_offset) = (params.min_angle.cos(), params.max_offset.cos());
    let mut touching: Vec<(u32, u32, usize, usize)> = pairs
        .iter_pairs()
        .filter(|&(i, j)| {
            let d = x[j] - x[i];
            let r = d.norm();
            // Coincident particles have no direction (the merging rule
            // is for them).
            if objects[i] != objects[j] || r >= radius || r == 0.0 {
                return false;
            }
            let (ni, nj) = (p.normal(i), p.normal(j));
            let u = d / r;
            movable(i)
                && movable(j)
                && hot(i)
                && hot(j)
                && ni.dot(&nj) <= cos_opposite
                && ni.dot(&u).abs() >= cos_offset
                && nj.dot(&u).abs() >= cos_offset
        })
        .map(|(i, j)| {
            if ids[i] < ids[j] {
                (ids[i], ids[j], i, j)
            } else {
                (ids[j], ids[i], j, i)
            }
        })
        .collect();
    touching.sort_unstable_by_key(|c| (c.0, c.1));
    let mut taken = vec![false; p.len()];
    let mut out = Vec::new();
    for (a, b, i, j) in touching {
        if taken[i] || taken[j] {
            continue;
        }
        taken[i] = true;
        taken[j] = true;
        out.extend([a, b]);
    }
    out
}
