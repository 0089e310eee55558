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
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub epsilon: Real,
    /// Rest distance `r0` (> 0), where the force vanishes. Default: 1.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub r0: Real,
    /// Repulsive exponent `n` (> m). Default: 12.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub n: Real,
    /// Attractive exponent `m` (> 0). Default: 6.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub m: Real,
    /// Cut-off radius `r_c`; the taper must start beyond `r0`
    /// (`cutoff (1 - taper) > r0`). Default: 2.5.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub cutoff: Real,
    /// Fraction of the cut-off over which `U` is tapered to 0
    /// (`0 < taper <= 1`). Default: 0.2.
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 1))]
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
        let scale = self.epsilon / (self.n - self.m);
        let taper = Taper::new(self.cutoff, self.taper);
        // Even integer exponents: powers of `(r0/r)^2`, no square root.
        let even = match integer_exponents {
            Some((n, m)) if n % 2 == 0 && m % 2 == 0 => Some((n / 2, m / 2)),
            _ => None,
        };
        Ok(LennardJones {
            scale,
            r0: self.r0,
            n: self.n,
            m: self.m,
            integer_exponents,
            taper,
            even,
            r0_sq: self.r0 * self.r0,
            c_n: scale * self.m,
            c_m: scale * self.n,
            c_g: scale * self.n * self.m / (self.r0 * self.r0),
            r_on_sq: taper.r_on() * taper.r_on(),
            rc_sq: self.cutoff * self.cutoff,
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
    /// `(n/2, m/2)` when both exponents are even integers.
    even: Option<(i32, i32)>,
    /// Constants folded for [`Self::eval_sq`]: `r0²`, `scale·m`,
    /// `scale·n`, `scale·n·m / r0²`, `r_on²`, `r_c²`.
    r0_sq: Real,
    c_n: Real,
    c_m: Real,
    c_g: Real,
    r_on_sq: Real,
    rc_sq: Real,
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

    /// `(U(r), U'(r)/r)` from `d2 = r²` and `inv_d2 = 1/r²` (`r > 0`),
    /// tapered; zero beyond the cut-off. The force on `j` is
    /// `-(U'(r)/r) (p_j - p_i)`. With even integer exponents (12-6) no
    /// division and, before the taper starts, no square root: powers of
    /// `x² = r0² / r²` (the pair kernel's fast path).
    #[inline(always)]
    pub fn eval_sq(&self, d2: Real, inv_d2: Real) -> (Real, Real) {
        match self.even {
            Some((6, 3)) => self.eval_sq_12_6(d2, inv_d2),
            Some((hn, hm)) => self.eval_sq_even(d2, inv_d2, |x2| {
                let xm = int_pow(x2, hm);
                let xn = if hn == 2 * hm {
                    xm * xm
                } else {
                    int_pow(x2, hn)
                };
                (xn, xm)
            }),
            None => {
                if d2 >= self.rc_sq {
                    return (0.0, 0.0);
                }
                let r = d2.sqrt();
                let (u, du) = self.eval(r);
                (u, du * (r * inv_d2))
            }
        }
    }

    /// True for the classic 12-6 exponents ([`Self::eval_sq_12_6`]).
    #[inline]
    pub fn is_12_6(&self) -> bool {
        self.even == Some((6, 3))
    }

    /// [`Self::eval_sq`] for `n = 12`, `m = 6` (check [`Self::is_12_6`]):
    /// the powers unrolled, for the dedicated spacing loop.
    #[inline(always)]
    pub fn eval_sq_12_6(&self, d2: Real, inv_d2: Real) -> (Real, Real) {
        self.eval_sq_even(d2, inv_d2, |x2| {
            let x6 = x2 * x2 * x2;
            (x6 * x6, x6)
        })
    }

    /// [`Self::eval_sq_12_6`] without branches, for pairs in SIMD lanes
    /// (`crate::lanes`): the untapered potential, the taper and the
    /// cut-off are all computed and the result selected. Bit for bit the
    /// same as [`Self::eval_sq_12_6`] (the same operations in the same
    /// order, no fused multiply-add), so the vectorized kernel sums the
    /// same bits as the scalar one on any CPU. `d2 > 0`.
    #[inline(always)]
    pub fn eval_sq_12_6_select(&self, d2: Real, inv_d2: Real) -> (Real, Real) {
        let x2 = self.r0_sq * inv_d2;
        let x6 = x2 * x2 * x2;
        let (xn, xm) = (x6 * x6, x6);
        let u = self.c_n * xn - self.c_m * xm;
        let g = self.c_g * (xm - xn) * x2;
        let r = d2.sqrt();
        let (s, ds) = self.taper.eval_select(r);
        let (ut, gt) = (u * s, g * s + u * ds * (r * inv_d2));
        let (outside, inner) = (d2 >= self.rc_sq, d2 <= self.r_on_sq);
        let (u, g) = (if inner { u } else { ut }, if inner { g } else { gt });
        (if outside { 0.0 } else { u }, if outside { 0.0 } else { g })
    }

    /// The folded constants the SIMD lanes evaluate
    /// [`Self::eval_sq_12_6_select`] with.
    pub(crate) fn lane_constants(&self) -> crate::lanes::LjLaneConstants {
        crate::lanes::LjLaneConstants {
            r0_sq: self.r0_sq,
            c_n: self.c_n,
            c_m: self.c_m,
            c_g: self.c_g,
            r_on_sq: self.r_on_sq,
            rc_sq: self.rc_sq,
            r_on: self.taper.r_on(),
            inv_width: self.taper.inv_width(),
        }
    }

    /// The even-exponent body: `powers(x²) = (x^n, x^m)`.
    #[inline(always)]
    fn eval_sq_even(
        &self,
        d2: Real,
        inv_d2: Real,
        powers: impl Fn(Real) -> (Real, Real),
    ) -> (Real, Real) {
        if d2 >= self.rc_sq {
            return (0.0, 0.0);
        }
        let x2 = self.r0_sq * inv_d2;
        let (xn, xm) = powers(x2);
        let u = self.c_n * xn - self.c_m * xm;
        let g = self.c_g * (xm - xn) * x2;
        if d2 <= self.r_on_sq {
            return (u, g);
        }
        let r = d2.sqrt();
        let (s, ds) = self.taper.eval(r);
        (u * s, g * s + u * ds * (r * inv_d2))
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

    /// The squared-distance fast path is the same potential: 12-6, an even
    /// pair with `n != 2m`, and a fractional pair (the fallback).
    #[test]
    fn eval_sq_matches_eval() {
        for (n, m) in [(12.0, 6.0), (10.0, 4.0), (9.0, 4.5)] {
            let l = LennardJonesParams {
                n,
                m,
                ..Default::default()
            }
            .prepare()
            .unwrap();
            for k in 0..300 {
                let r = 0.6 + 2.0 * k as Real / 299.0;
                let (u, du) = l.eval(r);
                let (us, g) = l.eval_sq(r * r, 1.0 / (r * r));
                assert!((u - us).abs() <= 1e-12 * (1.0 + u.abs()), "{n} {m} {r}");
                assert!((du / r - g).abs() <= 1e-12 * (1.0 + g.abs()), "{n} {m} {r}");
            }
        }
    }

    /// The branch-free 12-6 form of the SIMD lanes gives the same bits as
    /// the scalar one, inside, across the taper and beyond the cut-off.
    #[test]
    fn eval_sq_12_6_select_is_bit_identical() {
        let l = LennardJonesParams {
            taper: 0.1,
            ..Default::default()
        }
        .prepare()
        .unwrap();
        let bits = |(a, b): (Real, Real)| (a.to_bits(), b.to_bits());
        let r_on = l.taper.r_on();
        let mut d2s: Vec<Real> = (0..=5000)
            .map(|k| {
                let r = 0.5 + 2.5 * k as Real / 5000.0;
                r * r
            })
            .collect();
        d2s.extend([r_on * r_on, l.r_on_sq, l.rc_sq, 6.25, 1e-300, 1e300]);
        for d2 in d2s {
            let inv = 1.0 / d2;
            assert_eq!(
                bits(l.eval_sq_12_6(d2, inv)),
                bits(l.eval_sq_12_6_select(d2, inv)),
                "d2 = {d2}"
            );
        }
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
