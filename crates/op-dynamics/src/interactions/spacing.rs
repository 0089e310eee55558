//! The spacing potential of a material: Lennard-Jones (seed 000 eq. 5) or
//! cohesion (seed 002 §3), as a function of distance.

use super::cohesion::{Cohesion, CohesionParams};
use super::lennard_jones::{LennardJones, LennardJonesParams};
use crate::error::ParamError;
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Which spacing potential a material uses, with its parameters.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum Spacing {
    /// Lennard-Jones `B/rⁿ - A/rᵐ` (seed 000 eq. 5).
    LennardJones(LennardJonesParams),
    /// Cohesion force (seed 002 §3).
    Cohesion(CohesionParams),
}

impl Default for Spacing {
    fn default() -> Self {
        Spacing::Cohesion(CohesionParams::default())
    }
}

impl Spacing {
    /// Validates the parameters; errors are prefixed `lennard_jones.` or
    /// `cohesion.`.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Spacing::LennardJones(p) => p.validate().map_err(|e| e.within("lennard_jones")),
            Spacing::Cohesion(p) => p.validate().map_err(|e| e.within("cohesion")),
        }
    }

    /// Validates and builds the evaluator.
    pub fn prepare(&self) -> Result<SpacingKernel, ParamError> {
        match self {
            Spacing::LennardJones(p) => p
                .prepare()
                .map(SpacingKernel::LennardJones)
                .map_err(|e| e.within("lennard_jones")),
            Spacing::Cohesion(p) => p
                .prepare()
                .map(SpacingKernel::Cohesion)
                .map_err(|e| e.within("cohesion")),
        }
    }
}

/// A prepared spacing potential.
#[derive(Clone, Debug, PartialEq)]
pub enum SpacingKernel {
    /// Lennard-Jones.
    LennardJones(LennardJones),
    /// Cohesion (exact or tabulated).
    Cohesion(Cohesion),
}

impl SpacingKernel {
    /// `(U(r), dU/dr)` for `r > 0`; zero beyond the cut-off.
    #[inline]
    pub fn eval(&self, r: Real) -> (Real, Real) {
        match self {
            SpacingKernel::LennardJones(l) => l.eval(r),
            SpacingKernel::Cohesion(c) => c.eval(r),
        }
    }

    /// `(U(r), U'(r)/r)` from `d2 = r²` and `inv_d2 = 1/r²` (`r > 0`):
    /// Lennard-Jones without square root or division
    /// ([`LennardJones::eval_sq`]), cohesion through [`Self::eval`].
    #[inline(always)]
    pub fn eval_sq(&self, d2: Real, inv_d2: Real) -> (Real, Real) {
        match self {
            SpacingKernel::LennardJones(l) => l.eval_sq(d2, inv_d2),
            SpacingKernel::Cohesion(c) => {
                let r = d2.sqrt();
                let (u, du) = c.eval(r);
                (u, du * (r * inv_d2))
            }
        }
    }

    /// The cut-off radius.
    #[inline]
    pub fn cutoff(&self) -> Real {
        match self {
            SpacingKernel::LennardJones(l) => l.cutoff(),
            SpacingKernel::Cohesion(c) => c.cutoff(),
        }
    }

    /// `(r_m, f_max)`: distance and magnitude of the maximum attraction.
    pub fn max_attraction(&self) -> (Real, Real) {
        match self {
            SpacingKernel::LennardJones(l) => l.max_attraction(),
            SpacingKernel::Cohesion(c) => c.max_attraction(),
        }
    }

    /// `(r_w, U(r_w))`: position and value of the minimum of the potential
    /// (the bottom of the well), found by bisection of `dU/dr` between the
    /// repulsive core and the distance of maximum attraction.
    pub fn well(&self) -> (Real, Real) {
        let (r_m, _) = self.max_attraction();
        let slope = |r: Real| self.eval(r).1;
        let mut lo = 0.5 * r_m;
        for _ in 0..64 {
            if slope(lo) < 0.0 {
                break;
            }
            lo *= 0.5;
        }
        let mut hi = r_m;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if slope(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let r = 0.5 * (lo + hi);
        (r, self.eval(r).0)
    }

    /// The name of the potential (`"lennard_jones"` or `"cohesion"`).
    pub fn name(&self) -> &'static str {
        match self {
            SpacingKernel::LennardJones(_) => "lennard_jones",
            SpacingKernel::Cohesion(_) => "cohesion",
        }
    }
}
