//! The stretching rule (seed 000 §7, first rule; figure 9).
//!
//! Two particles of the same object `d` apart with `d_min <= d <= d_max`
//! (typically 2.0 and 2.5 `r0`) give a candidate at their midpoint `m`,
//! kept when no particle lies strictly within `d_min / 2` of `m`. The new
//! particle's position and frame are weighted averages over the particles
//! of the object within `reach` of `m`, with the compact weight
//! `w = (1 - |p_k - m|^2 / reach^2)^2`:
//!
//! - normal: the weighted mean of their world normals, renormalised;
//! - position: `m` moved along that normal onto the weighted mean
//!   position, `m + n (n . (p_mean - m))`, and kept only if the ball of
//!   `d_min / 2` around that final position is empty too. Only the normal
//!   component is averaged, so the candidate stays near `m` while
//!   following the surface across a curved gap (the chord's midpoint lies
//!   inside a convex surface);
//! - frame: built from the averaged normal and the weighted mean of their
//!   world tangents ("local x"), projected on the tangent plane;
//! - velocity, angular velocity and temperature: weighted means.
//!
//! **One sheet** (our addition): a pair whose normals make more than
//! [`StretchingParams::max_normal_angle`] (default 90°) does not stretch.
//! Two particles of one surface stretched apart keep nearly parallel
//! normals; two facing sheets of one object (the two dimples of a sphere
//! pushed in at its poles, seed 000 fig. 14, or a folded cloth) have
//! opposite normals, and filling between them would build a wall across
//! the gap instead of stretching the surface.
//!
//! **Heat gating** (seed 000 §8, fig. 13: "only allowing the hot parts of
//! the surface to deform and stretch"): with [`StretchingParams::min_temperature`]
//! set, a pair opens a gap only when both its particles are at least that
//! hot ([`op_dynamics::heat`]).
//!
//! Static attributes (mass, material, type, curvature, ...) are copied from
//! the pair's particle with the smaller id; fixed flags are not copied.
//! Candidates are accepted in the order of their pair ids `(min, max)`,
//! each dropped when within `d_min / 2` of one accepted before it.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{child_of, world_tangent, Accepted, Neighbourhood};
use op_dynamics::error::{self, ParamError};
use op_dynamics::math::{Point3, Real, Vec3};
use op_dynamics::particles::{ParticleDesc, Particles};

/// Parameters of the stretching rule, lengths as fractions of `r0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct StretchingParams {
    /// Smallest pair distance that opens a gap, > 0. Default: 2.0.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub d_min: Real,
    /// Largest pair distance considered, >= `d_min`. Default: 2.5.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub d_max: Real,
    /// Radius around the midpoint of the particles averaged for the new
    /// particle's position and frame, > `d_max / 2` (so the pair itself
    /// always counts). Default: 1.5.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub reach: Real,
    /// Only pairs whose two particles are at least this hot stretch
    /// (finite), or `None` for every pair. Default: `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_temperature: Option<Real>,
    /// Largest angle (radians) between the two particles' normals of a
    /// pair that stretches, in (0, pi]. Default: pi/2.
    #[serde(default = "right_angle")]
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = std::f64::consts::PI))]
    pub max_normal_angle: Real,
}

fn right_angle() -> Real {
    std::f64::consts::FRAC_PI_2
}

impl Default for StretchingParams {
    fn default() -> Self {
        StretchingParams {
            d_min: 2.0,
            d_max: 2.5,
            reach: 1.5,
            min_temperature: None,
            max_normal_angle: right_angle(),
        }
    }
}

impl StretchingParams {
    /// The radius around a particle that holds everything the rule reads
    /// of it (absolute, for spacing `r0`): its pairs (`d_max`) and the
    /// particles within `reach` of a pair's midpoint (`reach + d_max / 2`).
    pub(crate) fn search_radius(&self, r0: Real) -> Real {
        let (d_max, reach) = (self.d_max * r0, self.reach * r0);
        d_max.max(reach + 0.5 * d_max)
    }

    /// Checks `0 < d_min <= d_max` and `reach > d_max / 2`, all finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        error::positive("d_min", self.d_min)?;
        error::positive("d_max", self.d_max)?;
        error::check(
            "d_max",
            self.d_max,
            self.d_max >= self.d_min,
            "must be >= d_min",
        )?;
        error::positive("reach", self.reach)?;
        if let Some(t) = self.min_temperature {
            error::finite("min_temperature", t)?;
        }
        error::check(
            "max_normal_angle",
            self.max_normal_angle,
            self.max_normal_angle > 0.0 && self.max_normal_angle <= std::f64::consts::PI,
            "must be in (0, pi] radians",
        )?;
        error::check(
            "reach",
            self.reach,
            self.reach > 0.5 * self.d_max,
            "must be > d_max / 2 (the pair itself must be averaged)",
        )
    }
}

/// Offers the stretching candidates of `p` to `accepted`, in pair-id order,
/// reading the neighbours of `near` (searched at least as far as
/// [`StretchingParams::search_radius`]).
pub(crate) fn candidates(
    p: &Particles,
    near: &Neighbourhood,
    r0: Real,
    params: &StretchingParams,
    accepted: &mut Accepted,
) {
    let (d_min, d_max, reach) = (params.d_min * r0, params.d_max * r0, params.reach * r0);
    let pos = p.positions();
    let radius = params.search_radius(r0);
    let ids = p.ids();
    let temperatures = p.temperatures();
    let hot = |k: usize| params.min_temperature.is_none_or(|t| temperatures[k] >= t);
    let cos_max = params.max_normal_angle.cos();
    let one_sheet = |i: usize, j: usize| p.normal(i).dot(&p.normal(j)) >= cos_max;
    let mut found: Vec<((u32, u32), ParticleDesc)> = (0..p.len())
        .into_par_iter()
        .map_init(Vec::new, |around: &mut Vec<u32>, i| {
            let mut out = Vec::new();
            // The neighbours of `i`, gathered on its first stretching pair.
            let mut gathered = false;
            for j in near.above(i, radius) {
                let d2 = (pos[j] - pos[i]).norm_squared();
                if d2 < d_min * d_min
                    || d2 > d_max * d_max
                    || p.objects()[i] != p.objects()[j]
                    || !(hot(i) && hot(j))
                    || !one_sheet(i, j)
                {
                    continue;
                }
                if !gathered {
                    near.around_into(i, radius, around);
                    gathered = true;
                }
                let m = Point3::from((pos[i].coords + pos[j].coords) * 0.5);
                // Anything within d_min/2 of m is within d_max of i.
                let occupied = around.iter().any(|&k| {
                    let k = k as usize;
                    k != j && (pos[k] - m).norm_squared() < 0.25 * d_min * d_min
                });
                if occupied {
                    continue;
                }
                let (a, b) = if ids[i] < ids[j] { (i, j) } else { (j, i) };
                let averaged = if a == i {
                    averaged(p, around.iter().map(|&k| k as usize), a, m, reach)
                } else {
                    averaged(p, near.around(a, radius), a, m, reach)
                };
                let Some(d) = averaged else {
                    continue;
                };
                // The averaged position left the midpoint along the normal:
                // its own ball of d_min/2 must be empty too.
                let crowded = around
                    .iter()
                    .map(|&k| k as usize)
                    .chain([i, j])
                    .any(|k| (pos[k] - d.position).norm_squared() < 0.25 * d_min * d_min);
                if !crowded {
                    out.push(((ids[a], ids[b]), d));
                }
            }
            out
        })
        .flatten_iter()
        .collect();
    found.sort_by_key(|(key, _)| *key);
    for (_, d) in found {
        accepted.offer(d, 0.5 * d_min);
    }
}

/// The new particle at midpoint `m`, averaged over the particles of
/// `parent`'s object within `reach` of `m` (candidates: `parent` and its
/// neighbours `near`), summed in id order so the result does not depend on
/// slots. None when the averaged normal vanishes.
fn averaged(
    p: &Particles,
    near: impl Iterator<Item = usize>,
    parent: usize,
    m: Point3,
    reach: Real,
) -> Option<ParticleDesc> {
    let object = p.objects()[parent];
    let mut around: Vec<(u32, usize, Real)> = std::iter::once(parent)
        .chain(near)
        .filter_map(|k| {
            let r2 = (p.positions()[k] - m).norm_squared();
            (p.objects()[k] == object && r2 < reach * reach).then_some((p.ids()[k], k, r2))
        })
        .collect();
    around.sort_unstable_by_key(|a| a.0);
    let (mut wsum, mut temperature, mut pm, mut n, mut t, mut v, mut w) = (
        0.0,
        0.0,
        Vec3::zeros(),
        Vec3::zeros(),
        Vec3::zeros(),
        Vec3::zeros(),
        Vec3::zeros(),
    );
    for (_, k, r2) in around {
        let wk = (1.0 - r2 / (reach * reach)).powi(2);
        wsum += wk;
        temperature += wk * p.temperatures()[k];
        pm += wk * p.positions()[k].coords;
        n += wk * p.normal(k);
        t += wk * world_tangent(p, k);
        v += wk * p.velocities()[k];
        w += wk * p.angular_velocities()[k];
    }
    let nn = n.norm();
    if wsum <= 0.0 || nn.is_nan() || nn < 1e-9 * wsum {
        return None;
    }
    let n = n / nn;
    let pm = pm / wsum;
    let position = m + n * n.dot(&(pm - m.coords));
    let mut d = child_of(p, parent, position, &n, &t);
    d.velocity = v / wsum;
    d.angular_velocity = w / wsum;
    d.temperature = temperature / wsum;
    Some(d)
}
