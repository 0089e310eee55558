//! Lennard-Jones spacing potential (seed 000 eq. 5, fig. 1).
//!
//! `φ_LJ(r) = B/rⁿ - A/rᵐ` with `n > m > 0`, parameterised by the well depth
//! `ε` and the rest distance `r0`:
//!
//! `U(r) = ε/(n-m) [m (r0/r)ⁿ - n (r0/r)ᵐ]`, i.e. `B = ε m r0ⁿ/(n-m)` and
//! `A = ε n r0ᵐ/(n-m)`,
//!
//! so `U(r0) = -ε` and `U'(r0) = 0`. `U` is multiplied by the taper of
//! [`super::cutoff`] (which must start beyond `r0` so the minimum is kept) and
//! is zero beyond the cut-off. The force on `j` is `-U'(r) r/|r|` (seed 000
//! eq. 5 and App. B `f_LJ`).

use super::cutoff::{validate_fraction, Taper};
use crate::error::{positive, ParamError};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// `x^n` for a small positive integer `n` by repeated squaring, inlined
/// (`powi` is a call into the runtime library in the hot pair loop).
#[inline(always)]
fn int_pow(mut x: Real, n: i32) -> Real {
    let mut n = n.unsigned_abs();
    let mut r = 1.0;
    while n > 0 {
        if n & 1 == 1 {
            r *= x;
        }
        x *= x;
        n >>= 1;
    }
    r
}

/// Parameters of the Lennard-Jones spacing potential.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LennardJonesParams {
    /// Well depth `ε` (> 0): `U(r0) = -ε`. Default: 1.
    pub epsilon: Real,
    /// Rest distance `r0` (> 0), where the force vanishes. Default: 1.
    pub r0: Real,
    /// Repulsive exponent `n` (> m). Default: 12.
    pub n: Real,
    /// Attractive exponent `m` (> 0). Default: 6.
    pub m: Real,
    /// Cut-off radius `r_c`; the taper must start beyond `r0`
    /// (`cutoff (1 - taper) > r0`). Default: 2.5.
    pub cutoff: Real,
    /// Fraction of the cut-off over which `U` is tapered to 0
    /// (`0 < taper <= 1`). Default: 0.2.
    pub taper: Real,
}

impl Default for LennardJonesParams {
    fn default() -> Self {
        LennardJonesParams {
            epsilon: 1.0,
            r0: 1.0,
            n: 12.0,
            m: 6.0,
            cutoff: 2.5,
            taper: 0.2,
        }
    }
}

impl LennardJonesParams {
    /// Rejects NaN, infinite and out-of-range values.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("epsilon", self.epsilon)?;
        positive("r0", self.r0)?;
        positive("m", self.m)?;
        positive("n", self.n)?;
        if self.n <= self.m {
            return Err(ParamError::OutOfRange {
                field: "n".into(),
                value: self.n,
                allowed: format!("must be > m = {}", self.m),
            });
        }
        positive("cutoff", self.cutoff)?;
        validate_fraction("taper", self.taper)?;
        let r_on = self.cutoff * (1.0 - self.taper);
        if r_on <= self.r0 {
            return Err(ParamError::Invalid {
                field: "cutoff".into(),
                message: format!(
                    "the taper starts at cutoff*(1-taper) = {r_on}, which must be beyond \
                     r0 = {} so the minimum stays at r0: raise cutoff or lower taper",
                    self.r0
                ),
            });
        }
        Ok(())
    }

    /// Validates and builds the evaluator.
    pub fn prepare(&self) -> Result<LennardJones, ParamError> {
        self.validate()?;
        let int = |x: Real| (x.fract() == 0.0 && x <= 64.0).then_some(x as i32);
        let integer_exponents = match (int(self.n), int(self.m)) {
            (Some(n), Some(m)) => Some((n, m)),
            _ => None,
        };
        Ok(LennardJones {
            scale: self.epsilon / (self.n - self.m),
            r0: self.r0,
            n: self.n,
            m: self.m,
            integer_exponents,
            taper: Taper::new(self.cutoff, self.taper),
        })
    }
}

/// The prepared Lennard-Jones potential.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LennardJones {
    /// `ε/(n-m)`.
    scale: Real,
    r0: Real,
    n: Real,
    m: Real,
    integer_exponents: Option<(i32, i32)>,
    taper: Taper,
}

impl LennardJones {
    /// The cut-off radius.
    #[inline]
    pub fn cutoff(&self) -> Real {
        self.taper.cutoff()
    }

    /// The rest distance `r0`.
    pub fn r0(&self) -> Real {
        self.r0
    }

    /// `(U(r), dU/dr)` for `r > 0`, tapered; zero beyond the cut-off.
    #[inline]
    pub fn eval(&self, r: Real) -> (Real, Real) {
        if r >= self.taper.cutoff() {
            return (0.0, 0.0);
        }
        let x = self.r0 / r;
        let (xn, xm) = match self.integer_exponents {
            Some((n, m)) => (int_pow(x, n), int_pow(x, m)),
            None => (x.powf(self.n), x.powf(self.m)),
        };
        let u = self.scale * (self.m * xn - self.n * xm);
        let du = self.scale * self.n * self.m * (xm - xn) / r;
        self.taper.apply(r, u, du)
    }

    /// The maximum attraction: the force `-U'` is most negative at
    /// `r_m = r0 ((n+1)/(m+1))^(1/(n-m))`. Returns `(r_m, |U'(r_m)|)` of the
    /// untapered potential, for matching Lennard-Jones to cohesion
    /// (seed 002 §3). Assumes the taper starts beyond `r_m` (true for the
    /// defaults); otherwise the tapered force peaks elsewhere.
    pub fn max_attraction(&self) -> (Real, Real) {
        let (n, m) = (self.n, self.m);
        let r_m = self.r0 * ((n + 1.0) / (m + 1.0)).powf(1.0 / (n - m));
        let x = self.r0 / r_m;
        let du = self.scale * n * m * (x.powf(m) - x.powf(n)) / r_m;
        (r_m, du.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lj() -> LennardJones {
        LennardJonesParams::default().prepare().unwrap()
    }

    #[test]
    fn minimum_at_r0_with_depth_epsilon() {
        let p = LennardJonesParams {
            epsilon: 2.5,
            r0: 1.3,
            n: 9.0,
            m: 4.5,
            cutoff: 3.0,
            taper: 0.3,
        };
        let l = p.prepare().unwrap();
        let (u, du) = l.eval(1.3);
        assert!((u + 2.5).abs() < 1e-14 && du.abs() < 1e-13, "{u} {du}");
        assert!(l.eval(1.29).0 > u && l.eval(1.31).0 > u);
        let (u, du) = lj().eval(1.0);
        assert!((u + 1.0).abs() < 1e-15 && du.abs() < 1e-14);
    }

    #[test]
    fn derivative_matches_finite_difference_including_taper() {
        let l = lj();
        for k in 0..200 {
            let r = 0.7 + 1.79 * k as Real / 199.0;
            let h = 1e-6;
            let fd = (l.eval(r + h).0 - l.eval(r - h).0) / (2.0 * h);
            let du = l.eval(r).1;
            assert!(
                (fd - du).abs() < 1e-6 * (1.0 + du.abs()),
                "r={r}: {fd} vs {du}"
            );
        }
    }

    #[test]
    fn continuous_at_the_cutoff() {
        let l = lj();
        let (u, du) = l.eval(2.5 * (1.0 - 1e-7));
        assert!(u.abs() < 1e-18 && du.abs() < 1e-11, "{u} {du}");
        assert_eq!(l.eval(2.5), (0.0, 0.0));
        assert_eq!(l.eval(7.0), (0.0, 0.0));
    }

    #[test]
    fn max_attraction_is_where_the_force_peaks() {
        let l = lj();
        let (r_m, f_m) = l.max_attraction();
        let f = |r: Real| -l.eval(r).1;
        assert!((f(r_m) + f_m).abs() < 1e-12);
        assert!(f(r_m - 1e-3) > f(r_m) && f(r_m + 1e-3) > f(r_m));
    }

    #[test]
    fn validation_rejects_bad_values() {
        let base = LennardJonesParams::default();
        let cases = [
            (
                LennardJonesParams {
                    epsilon: Real::NAN,
                    ..base
                },
                "epsilon",
            ),
            (LennardJonesParams { r0: -1.0, ..base }, "r0"),
            (LennardJonesParams { n: 5.0, ..base }, "> m"),
            (LennardJonesParams { m: 0.0, ..base }, "m"),
            (
                LennardJonesParams {
                    cutoff: Real::INFINITY,
                    ..base
                },
                "cutoff",
            ),
            (
                LennardJonesParams {
                    cutoff: 1.1,
                    ..base
                },
                "beyond",
            ),
            (LennardJonesParams { taper: 2.0, ..base }, "taper"),
        ];
        for (p, needle) in cases {
            let e = p
                .validate()
                .unwrap_err()
                .within("lennard_jones")
                .to_string();
            assert!(e.contains("lennard_jones.") && e.contains(needle), "{e}");
        }
    }
}
