//! Heat (seed 000 §6 and §8, after Tonnesen 1991, "Modeling liquids and
//! solids using thermal particles"): every particle carries a temperature
//! that tools raise, that flows between neighbours and that decays toward
//! the ambient temperature; hot material is weak.
//!
//! Seed 000 uses heat twice: the knife of figure 7 "uses the heat of the
//! cutting tool to weaken the inter-particle bonds", and the handle of
//! figure 13 is formed by "heating the surface near the tool and only
//! allowing the hot parts of the surface to deform and stretch". The paper
//! gives no equations; this module is the simplest model with those
//! properties, every choice documented:
//!
//! - **Sources**: a heater or knife tool
//!   (op-modeling `tools::Role`, through [`crate::tooling::ToolSet::add_heat`]) raises the temperature of
//!   the particles within `reach` of its surface at
//!   `power * (1 - max(s, 0) / reach)` per unit time (`s` the signed
//!   distance, so the full power inside and a linear fall-off outside).
//! - **Conduction**: `dT_i/dt = c Σ_j w_ij (T_j - T_i)` over the pairs
//!   within the world's interaction cut-off `r_c`, `w_ij = 1 - r_ij / r_c`
//!   (the discrete heat equation on the neighbour graph, symmetric, so it
//!   conserves the total heat `Σ T_i`).
//! - **Cooling** (Newton's law): `dT_i/dt = -λ (T_i - T_ambient)`.
//! - **Weakening** ([`HeatResponse`]): a pair's bond strength
//!   `s ∈ [residual, 1]` falls linearly with its mean temperature up to the
//!   material's `melting` temperature; [`weakened_spacing`] scales the depth
//!   of the spacing well by `s` and the orientation terms (bending) by `s`.
//!   The temperatures are parameters of the energy, not degrees of freedom:
//!   at fixed temperatures forces and torques are still its exact
//!   gradients, so they conserve linear and angular momentum.
//! - **Gating**: the stretching rule can require hot particles
//!   (op-modeling `creation::StretchingParams::min_temperature`).
//!
//! The temperatures advance once per step, after the mechanical step
//! (operator splitting, first order in `dt`): sources, then conduction
//! (explicit, sub-stepped so that `dt_sub c Σ_j w_ij <= 1/2`, which keeps
//! every new temperature a convex combination of the old ones: no new
//! extremes, no oscillation), then cooling (exact exponential). Every sum
//! is gathered per particle in a fixed order, so the result does not depend
//! on the thread count.
//!
//! **Cost** (`cargo bench -p op-dynamics --bench step`, 10k-particle
//! sheet, 2 threads, criterion medians [low high]): spacing only 1.95 ms
//! [1.75 2.06] against 3.51 ms [3.36 3.79] heated; full oriented 8.82 ms
//! [8.52 9.36] against 18.4 ms [17.2 19.3]. Most of the difference is not
//! the heat update but a second force evaluation per step: when a material
//! weakens, changed temperatures invalidate the forces the integrator
//! cached at the end of the step (velocity Verlet reuses them otherwise).
//! Worlds without heat run none of this.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{self, ParamError};
use crate::math::{Point3, Real};
use crate::neighbours::PairList;
use crate::tooling::ToolSet;

/// How heat moves in a world (seed 000 §6, §8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct HeatParams {
    /// Conduction rate `c` between neighbours (>= 0, per unit time).
    /// Default: 1.
    pub conduction: Real,
    /// Cooling rate `λ` toward the ambient temperature (>= 0, per unit
    /// time). Default: 0.1.
    pub cooling: Real,
    /// Ambient temperature (finite). Default: 0.
    pub ambient: Real,
}

impl Default for HeatParams {
    fn default() -> Self {
        HeatParams {
            conduction: 1.0,
            cooling: 0.1,
            ambient: 0.0,
        }
    }
}

impl HeatParams {
    /// Checks the rates (>= 0) and the ambient temperature (finite).
    pub fn validate(&self) -> Result<(), ParamError> {
        error::non_negative("conduction", self.conduction)?;
        error::non_negative("cooling", self.cooling)?;
        error::finite("ambient", self.ambient)
    }
}

/// How a material's bonds weaken with temperature (Tonnesen 1991; seed 000
/// §6: the knife's heat "weakens the inter-particle bonds").
///
/// Strength `s(T) = 1 - (1 - residual) clamp(T / melting, 0, 1)`: full at
/// `T <= 0`, falling linearly to `residual` at the melting temperature.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HeatResponse {
    /// Temperature at which the bonds are weakest, > 0.
    pub melting: Real,
    /// Strength left at and above `melting`, in `[0, 1]`. Default: 0.1.
    #[serde(default = "default_residual")]
    pub residual: Real,
    /// Drag coefficient `c` of cold particles of this material, >= 0: a
    /// particle at temperature `T` feels the extra damping force
    /// `-c w(T) v`, with `w = (s(T) - residual) / (1 - residual)` from 1
    /// when cold to 0 at the melting temperature. Seed 000 §8 (fig. 13)
    /// only lets "the hot parts of the surface deform and stretch": with a
    /// large `c` the cold parts creep so slowly that they keep the shape
    /// they had when they cooled (a tube pulled out of a sphere would
    /// otherwise round itself into lobes under co-circularity). Default:
    /// 0 (none).
    #[serde(default)]
    pub cold_drag: Real,
}

fn default_residual() -> Real {
    0.1
}

impl HeatResponse {
    /// Checks `melting > 0`, `0 <= residual <= 1` and `cold_drag >= 0`.
    pub fn validate(&self) -> Result<(), ParamError> {
        error::positive("melting", self.melting)?;
        error::non_negative("cold_drag", self.cold_drag)?;
        error::check(
            "residual",
            self.residual,
            (0.0..=1.0).contains(&self.residual),
            "must be in [0, 1]",
        )
    }

    /// The cold drag coefficient `c w(T)` at temperature `t` (see
    /// [`HeatResponse::cold_drag`]).
    #[inline]
    pub fn drag(&self, t: Real) -> Real {
        self.cold_drag * (1.0 - (t / self.melting).clamp(0.0, 1.0))
    }

    /// The bond strength `s(T)` at temperature `t`.
    #[inline]
    pub fn strength(&self, t: Real) -> Real {
        1.0 - (1.0 - self.residual) * (t / self.melting).clamp(0.0, 1.0)
    }
}

/// Strength of a pair of two particles at temperatures `ti`, `tj` whose
/// materials respond as `ri`, `rj` (`None`: does not weaken): the mean of
/// the two materials' strengths at the pair's mean temperature, so the
/// pair is symmetric.
#[inline]
pub fn pair_strength(
    ri: Option<&HeatResponse>,
    rj: Option<&HeatResponse>,
    ti: Real,
    tj: Real,
) -> Real {
    let t = 0.5 * (ti + tj);
    let s = |r: Option<&HeatResponse>| r.map_or(1.0, |r| r.strength(t));
    0.5 * (s(ri) + s(rj))
}

/// The weakened spacing potential `(U_s(r), dU_s/dr)` of strength `s` from
/// `(U(r), dU/dr)` and the well `(r_w, U_w)` (position and depth of the
/// minimum of `U`):
///
/// `U_s(r) = U(r) - (1 - s) U_w` for `r < r_w` (the repulsive core, only
/// shifted), `U_s(r) = s U(r)` beyond (the attraction, scaled). Continuous
/// with a continuous derivative at `r_w` (where `U' = 0`): the well is `s`
/// times as deep and the largest attraction force `s` times as strong,
/// while the core keeps particles apart as before.
#[inline]
pub fn weakened_spacing(u: Real, du: Real, r: Real, well: (Real, Real), s: Real) -> (Real, Real) {
    if r < well.0 {
        (u - (1.0 - s) * well.1, du)
    } else {
        (s * u, s * du)
    }
}

/// Rate of temperature rise a heating tool gives a particle at signed
/// distance `sd` from its surface: `power (1 - max(sd, 0) / reach)` within
/// `reach`, zero beyond.
#[inline]
pub fn heating_rate(power: Real, reach: Real, sd: Real) -> Real {
    if sd >= reach {
        0.0
    } else {
        power * (1.0 - sd.max(0.0) / reach)
    }
}

/// Reusable buffers of the heat update (no allocation once sized).
#[derive(Clone, Debug, Default)]
pub(crate) struct HeatScratch {
    /// First particle of each pair.
    sources: Vec<u32>,
    /// Conduction weight of each pair.
    weights: Vec<Real>,
    next: Vec<Real>,
}

/// Advances the temperatures by `dt` (sources at time `t`, conduction over
/// the pairs of `pairs` closer than its cut-off, cooling) as described in
/// the module docs. `positions`, `objects` and `temperatures` are by slot,
/// the pair list by slot too.
#[allow(clippy::too_many_arguments)]
pub(crate) fn advance(
    params: &HeatParams,
    sources: Option<&dyn ToolSet>,
    t: Real,
    dt: Real,
    positions: &[Point3],
    objects: &[u32],
    pairs: Option<(&PairList, Real)>,
    temperatures: &mut [Real],
    scratch: &mut HeatScratch,
) {
    if let Some(sources) = sources.filter(|s| s.heats()) {
        sources.add_heat(t, dt, positions, objects, temperatures);
    }
    if let Some((list, cutoff)) = pairs.filter(|_| params.conduction > 0.0) {
        conduct(
            params.conduction,
            dt,
            positions,
            list,
            cutoff,
            temperatures,
            scratch,
        );
    }
    if params.cooling > 0.0 {
        let decay = (-params.cooling * dt).exp();
        let ambient = params.ambient;
        temperatures
            .par_iter_mut()
            .with_min_len(crate::MIN_PARALLEL_LEN)
            .for_each(|temp| *temp = ambient + (*temp - ambient) * decay);
    }
}

/// The fewest pairs whose conduction weights one parallel task computes:
/// a weight is a distance and a division, a few nanoseconds, so a task of
/// [`crate::MIN_PARALLEL_LEN`] pairs cost less than waking the other
/// thread for it (fig_07_knife's 192 particles and about 2,000 pairs: its
/// heat stage took 0.087-0.089 s at 2 threads against 0.051-0.068 s at 1,
/// the second thread woken at every step).
const PAIRS_PER_TASK: usize = 16 * crate::MIN_PARALLEL_LEN;

/// Explicit conduction over `dt`, sub-stepped for monotonicity. Each
/// particle gathers its pairs in a fixed order (those where it is second,
/// ascending, then its own row): the same sums at any thread count.
fn conduct(
    c: Real,
    dt: Real,
    positions: &[Point3],
    list: &PairList,
    cutoff: Real,
    temperatures: &mut [Real],
    scratch: &mut HeatScratch,
) {
    let n = temperatures.len();
    let HeatScratch {
        sources,
        weights,
        next,
    } = scratch;
    list.sources_into(sources);
    let targets = list.neighbours();
    weights.resize(targets.len(), 0.0);
    weights
        .par_iter_mut()
        .enumerate()
        .with_min_len(PAIRS_PER_TASK)
        .for_each(|(k, w)| {
            let r = (positions[targets[k] as usize] - positions[sources[k] as usize]).norm();
            *w = (1.0 - r / cutoff).max(0.0);
        });
    let (sources, weights) = (&*sources, &*weights);
    // Σ_j w_ij (T_j - T_i) for particle i at temperatures `t`.
    let flow = |i: usize, t: &[Real]| -> Real {
        let incoming: Real = list
            .incoming(i)
            .iter()
            .map(|&k| weights[k as usize] * (t[sources[k as usize] as usize] - t[i]))
            .sum();
        let own: Real = list
            .row_range(i)
            .map(|k| weights[k] * (t[targets[k] as usize] - t[i]))
            .sum();
        incoming + own
    };
    let degree = (0..n)
        .into_par_iter()
        .with_min_len(crate::MIN_PARALLEL_LEN)
        .map(|i| {
            list.incoming(i)
                .iter()
                .map(|&k| weights[k as usize])
                .chain(list.row_range(i).map(|k| weights[k]))
                .sum::<Real>()
        })
        .reduce(|| 0.0, Real::max);
    let substeps = (2.0 * c * dt * degree).ceil().max(1.0) as usize;
    let h = dt / substeps as Real;
    next.resize(n, 0.0);
    for _ in 0..substeps {
        let old = &*temperatures;
        next.par_iter_mut()
            .enumerate()
            .with_min_len(crate::MIN_PARALLEL_LEN)
            .for_each(|(i, out)| *out = old[i] + h * c * flow(i, old));
        temperatures.copy_from_slice(next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::neighbours::{search, NeighbourBackend};

    fn line(n: usize) -> Vec<Point3> {
        (0..n).map(|k| Point3::new(k as Real, 0.0, 0.0)).collect()
    }

    fn pairs_of(p: &[Point3], radius: Real) -> PairList {
        let mut list = PairList::new();
        search(NeighbourBackend::CellList, p, radius, &mut list);
        list
    }

    #[test]
    fn strength_falls_linearly_to_the_residual() {
        let r = HeatResponse {
            melting: 10.0,
            residual: 0.2,
            cold_drag: 0.0,
        };
        assert_eq!(r.strength(-5.0), 1.0);
        assert_eq!(r.strength(0.0), 1.0);
        assert!((r.strength(5.0) - 0.6).abs() < 1e-15);
        assert!((r.strength(10.0) - 0.2).abs() < 1e-15);
        assert_eq!(r.strength(100.0), r.strength(10.0));
        assert_eq!(pair_strength(None, None, 50.0, 50.0), 1.0);
        assert!((pair_strength(Some(&r), None, 0.0, 10.0) - 0.8).abs() < 1e-15);
    }

    #[test]
    fn weakened_spacing_is_continuous_with_a_shallower_well() {
        // U(r) = (r - 1)^2 - 1: well at r = 1, depth -1.
        let u = |r: Real| ((r - 1.0).powi(2) - 1.0, 2.0 * (r - 1.0));
        let well = (1.0, -1.0);
        let s = 0.3;
        let at = |r: Real| {
            let (v, d) = u(r);
            weakened_spacing(v, d, r, well, s)
        };
        let (below, above) = (at(1.0 - 1e-9), at(1.0 + 1e-9));
        assert!((below.0 - above.0).abs() < 1e-8, "{below:?} {above:?}");
        assert!((at(1.0).0 - s * well.1).abs() < 1e-15);
        // Core unchanged in slope, attraction scaled.
        assert_eq!(at(0.5).1, u(0.5).1);
        assert!((at(1.5).1 - s * u(1.5).1).abs() < 1e-15);
    }

    #[test]
    fn conduction_conserves_heat_and_makes_no_new_extremes() {
        let p = line(20);
        let list = pairs_of(&p, 1.5);
        let mut t: Vec<Real> = (0..20).map(|k| if k < 3 { 100.0 } else { 0.0 }).collect();
        let total: Real = t.iter().sum();
        let params = HeatParams {
            conduction: 5.0,
            cooling: 0.0,
            ambient: 0.0,
        };
        let objects = vec![0; 20];
        for _ in 0..50 {
            advance(
                &params,
                None,
                0.0,
                0.1,
                &p,
                &objects,
                Some((&list, 1.5)),
                &mut t,
                &mut HeatScratch::default(),
            );
            assert!(t.iter().all(|&x| (0.0..=100.0).contains(&x)), "{t:?}");
        }
        let after: Real = t.iter().sum();
        assert!((after - total).abs() < 1e-9 * total, "{total} -> {after}");
        // Heat spread: the far end warmed, the hot end cooled.
        assert!(t[19] > 1e-3 && t[0] < 90.0, "{t:?}");
        // Monotone profile from the hot end.
        assert!(t.windows(2).all(|w| w[0] >= w[1] - 1e-12), "{t:?}");
    }

    #[test]
    fn cooling_is_the_exact_exponential() {
        let p = line(3);
        let mut t = vec![10.0, 20.0, 30.0];
        let params = HeatParams {
            conduction: 0.0,
            cooling: 0.5,
            ambient: 5.0,
        };
        for _ in 0..10 {
            advance(
                &params,
                None,
                0.0,
                0.2,
                &p,
                &[0; 3],
                None,
                &mut t,
                &mut HeatScratch::default(),
            );
        }
        for (k, t0) in [10.0, 20.0, 30.0].iter().enumerate() {
            let exact = 5.0 + (t0 - 5.0) * (-0.5 * 2.0 as Real).exp();
            assert!((t[k] - exact).abs() < 1e-12, "{} vs {exact}", t[k]);
        }
    }

    #[test]
    fn heating_rate_is_full_inside_and_falls_off_outside() {
        assert_eq!(heating_rate(4.0, 2.0, -1.0), 4.0);
        assert_eq!(heating_rate(4.0, 2.0, 0.0), 4.0);
        assert_eq!(heating_rate(4.0, 2.0, 1.0), 2.0);
        assert_eq!(heating_rate(4.0, 2.0, 2.0), 0.0);
        assert_eq!(heating_rate(4.0, 2.0, 3.0), 0.0);
    }
}
