//! Matching Lennard-Jones to cohesion (seed 002 §3: "parameters chosen in
//! order to get similar behaviours").
//!
//! **The rule.** Given cohesion parameters `(E, r0, α, cut-off)`, the
//! matched Lennard-Jones potential is the 12-6 one with
//!
//! 1. the same rest distance `r0` (both forces vanish there);
//! 2. the same cut-off radius (so both act on the same neighbours), with
//!    Lennard-Jones' default taper fraction 0.2;
//! 3. the same maximum attraction force `f_max` (the force that breaks a
//!    bond under a static load) **of the forces actually used**, tapers
//!    included: `ε = f_max / f_LJ,max(ε = 1)`. The untapered 12-6 force
//!    peaks at `r_m = (13/7)^(1/6) r0 ≈ 1.109 r0` with `2.69 ε / r0`, but
//!    tapering the energy (`U s(r)`) adds an attraction `-U s'` where the
//!    taper acts: with a cut-off of `1.5 r0` the tapered force peaks near
//!    `1.3 r0` at about `3.0 ε / r0`. Cohesion's taper multiplies the force
//!    and never adds to it. [`max_attraction`] finds the peak numerically.
//!
//! What stays different is the shape of the well: Lennard-Jones is stiff at
//! rest (`U''(r0) = 72 ε / r0²`) with a hard core, cohesion has zero
//! stiffness at rest (`f'(r0) = 0`) and a soft core whose repulsion peaks
//! and then decays under strong compression (docs/model.md §7).

use op_dynamics::interactions::{CohesionParams, LennardJonesParams, Spacing};
use op_dynamics::Real;

/// The cohesion parameters of the comparison: `E = 200`, `r0 = 1`,
/// `α = 16`, cut-off `1.5 r0` (next neighbours of a hexagonal lattice
/// only, docs/model.md §7), i.e. the default cohesion with a shorter cut-off.
pub fn reference_cohesion() -> CohesionParams {
    CohesionParams {
        e: 200.0,
        r0: 1.0,
        alpha: 16.0,
        cutoff: Some(1.5),
        ..CohesionParams::default()
    }
}

/// `(r, f)`: where the attraction `-dU/dr` of `spacing` (taper included)
/// is largest on `(r0, cut-off)`, and its value: 20 000 samples, then a
/// golden-section search around the best one.
pub fn max_attraction(spacing: &Spacing) -> (Real, Real) {
    let k = spacing.prepare().expect("a valid spacing potential");
    let r0 = match spacing {
        Spacing::Cohesion(c) => c.r0,
        Spacing::LennardJones(l) => l.r0,
    };
    let attraction = |r: Real| k.eval(r).1;
    let (a, b) = (r0, k.cutoff());
    let n = 20_000;
    let h = (b - a) / n as Real;
    let best = (1..n)
        .map(|i| a + h * i as Real)
        .max_by(|x, y| attraction(*x).total_cmp(&attraction(*y)))
        .unwrap_or(a);
    let (mut lo, mut hi) = (best - h, best + h);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if attraction(m1) > attraction(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    let r = 0.5 * (lo + hi);
    (r, attraction(r))
}

/// The 12-6 Lennard-Jones potential matched to `c` by the rule of the
/// module docs.
pub fn matched_lennard_jones(c: &CohesionParams) -> LennardJonesParams {
    let (_, f_max) = max_attraction(&Spacing::Cohesion(*c));
    let unit = LennardJonesParams {
        epsilon: 1.0,
        r0: c.r0,
        n: 12.0,
        m: 6.0,
        cutoff: c.effective_cutoff(),
        taper: 0.2,
    };
    let (_, f_unit) = max_attraction(&Spacing::LennardJones(unit));
    LennardJonesParams {
        epsilon: f_max / f_unit,
        ..unit
    }
}

/// Cohesion with the same maximum attraction as `c` but Gaussian decay
/// `alpha` (E rescaled), for the robustness-against-α sweep.
pub fn cohesion_with_alpha(c: &CohesionParams, alpha: Real) -> CohesionParams {
    let (_, f_max) = c.max_attraction();
    let unit = CohesionParams {
        e: 1.0,
        alpha,
        ..*c
    };
    let (_, f_unit) = unit.max_attraction();
    CohesionParams {
        e: f_max / f_unit,
        ..unit
    }
}

/// The compressions (fractions of `r0`) of
/// [`PotentialFigures::compression_energy`].
pub const COMPRESSIONS: [Real; 5] = [0.2, 0.6, 0.8, 0.85, 0.9];

/// Figures of a spacing potential for the report's comparison table.
#[derive(Clone, Debug, PartialEq)]
pub struct PotentialFigures {
    /// `"cohesion"` or `"lennard_jones"`.
    pub name: &'static str,
    /// Rest distance.
    pub r0: Real,
    /// Distance of the maximum attraction (taper included).
    pub r_max_attraction: Real,
    /// Maximum attraction force (taper included).
    pub max_attraction: Real,
    /// Well depth `-U(r0)`.
    pub depth: Real,
    /// Stiffness at rest `U''(r0)` (central difference).
    pub stiffness: Real,
    /// Cut-off radius.
    pub cutoff: Real,
    /// Energy above the well bottom at the distances of
    /// [`COMPRESSIONS`] (times `r0`).
    pub compression_energy: [Real; 5],
}

/// The figures of `spacing`.
pub fn figures(spacing: &Spacing) -> PotentialFigures {
    let k = spacing.prepare().expect("a valid spacing potential");
    let r0 = match spacing {
        Spacing::Cohesion(c) => c.r0,
        Spacing::LennardJones(l) => l.r0,
    };
    let (r_m, f_max) = max_attraction(spacing);
    let u = |r: Real| k.eval(r).0;
    let h = 1e-4 * r0;
    let stiffness = (u(r0 + h) - 2.0 * u(r0) + u(r0 - h)) / (h * h);
    PotentialFigures {
        name: k.name(),
        r0,
        r_max_attraction: r_m,
        max_attraction: f_max,
        depth: -u(r0),
        stiffness,
        cutoff: k.cutoff(),
        compression_energy: COMPRESSIONS.map(|p| u(p * r0) - u(r0)),
    }
}
