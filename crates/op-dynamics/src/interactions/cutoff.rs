//! Smooth cut-off (taper) shared by every interaction term.
//!
//! Every potential `U` of this module is multiplied by a taper `s(r)` that is
//! 1 for `r <= r_on`, falls to 0 at the cut-off `r_c` with the C2 quintic
//! smoothstep `1 - 10x^3 + 15x^4 - 6x^5` (`x = (r - r_on)/(r_c - r_on)`), and
//! is 0 beyond. The tapered potential `U s` and its derivative
//! `U' s + U s'` are then continuous (with their first derivatives) at the
//! cut-off, so forces and energies have no jump when a pair leaves the
//! neighbour radius (docs/model.md §5).
//!
//! Parameter structs give the taper as a *fraction* of the cut-off radius
//! (`r_on = r_c (1 - taper)`), which is scale independent: scaling a scene's
//! lengths by `s` scales `r_on` and `r_c` alike.

use crate::error::{check, ParamError};
use crate::math::Real;

/// The C2 quintic smoothstep falling from 1 at `x <= 0` to 0 at `x >= 1`:
/// returns `(s(x), s'(x))`.
#[inline(always)]
pub fn smooth_fall(x: Real) -> (Real, Real) {
    if x <= 0.0 {
        (1.0, 0.0)
    } else if x >= 1.0 {
        (0.0, 0.0)
    } else {
        // 1 - S(x) = S(1 - x): evaluated in y = 1 - x so that s is exact
        // to relative round-off (never negative) near the cut-off.
        let y = 1.0 - x;
        let y2 = y * y;
        let s = y2 * y * (10.0 - 15.0 * y + 6.0 * y2);
        let ds = -30.0 * x * x * y2;
        (s, ds)
    }
}

/// [`smooth_fall`] without branches (for pairs in SIMD lanes): the
/// polynomial is evaluated at every `x` and the ends selected; bit for bit
/// the same values.
#[inline(always)]
pub fn smooth_fall_select(x: Real) -> (Real, Real) {
    let y = 1.0 - x;
    let y2 = y * y;
    let s = y2 * y * (10.0 - 15.0 * y + 6.0 * y2);
    let ds = -30.0 * x * x * y2;
    let (low, high) = (x <= 0.0, x >= 1.0);
    let s = if high { 0.0 } else { s };
    (if low { 1.0 } else { s }, if low | high { 0.0 } else { ds })
}

/// The C2 quintic smoothstep rising from 0 at `x <= 0` to 1 at `x >= 1`
/// (`1 - smooth_fall(x)`, evaluated directly so that it is exact to
/// relative round-off near 0, where it grows like `10 x³`): returns
/// `(S(x), S'(x))`.
#[inline]
pub fn smooth_rise(x: Real) -> (Real, Real) {
    if x <= 0.0 {
        (0.0, 0.0)
    } else if x >= 1.0 {
        (1.0, 0.0)
    } else {
        let y = 1.0 - x;
        (
            x * x * x * (10.0 - 15.0 * x + 6.0 * x * x),
            30.0 * x * x * y * y,
        )
    }
}

/// A taper `s(r)`: 1 up to `r_on`, quintic fall to 0 at `r_c`, 0 beyond.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Taper {
    r_on: Real,
    r_c: Real,
    inv_width: Real,
}

impl Taper {
    /// A taper that reaches 0 at `cutoff` and starts at
    /// `cutoff * (1 - fraction)`. Arguments must be valid (see
    /// [`validate_fraction`]); `cutoff > 0` and `0 < fraction <= 1`.
    pub fn new(cutoff: Real, fraction: Real) -> Self {
        let r_on = cutoff * (1.0 - fraction);
        Taper {
            r_on,
            r_c: cutoff,
            inv_width: 1.0 / (cutoff - r_on),
        }
    }

    /// Where the taper starts (`s = 1` below).
    #[inline]
    pub fn r_on(&self) -> Real {
        self.r_on
    }

    /// `1 / (r_c - r_on)`.
    #[inline]
    pub(crate) fn inv_width(&self) -> Real {
        self.inv_width
    }

    /// The cut-off radius (`s = 0` from here on).
    #[inline]
    pub fn cutoff(&self) -> Real {
        self.r_c
    }

    /// `(s(r), ds/dr)`.
    #[inline(always)]
    pub fn eval(&self, r: Real) -> (Real, Real) {
        if r <= self.r_on {
            (1.0, 0.0)
        } else {
            let (s, ds) = smooth_fall((r - self.r_on) * self.inv_width);
            (s, ds * self.inv_width)
        }
    }

    /// [`Self::eval`] without branches: every case is computed and the
    /// result selected, so a loop over pairs in SIMD lanes vectorizes.
    /// Bit for bit the same as [`Self::eval`] (same operations in the
    /// same order; the selects only pick).
    #[inline(always)]
    pub fn eval_select(&self, r: Real) -> (Real, Real) {
        let x = (r - self.r_on) * self.inv_width;
        let (s, ds) = smooth_fall_select(x);
        let inner = r <= self.r_on;
        (
            if inner { 1.0 } else { s },
            if inner { 0.0 } else { ds * self.inv_width },
        )
    }

    /// Tapers a potential: given `(U(r), U'(r))` returns `(U s, U' s + U s')`.
    #[inline]
    pub fn apply(&self, r: Real, u: Real, du: Real) -> (Real, Real) {
        let (s, ds) = self.eval(r);
        (u * s, du * s + u * ds)
    }
}

/// Checks a taper fraction: finite, `0 < fraction <= 1`.
pub fn validate_fraction(field: &str, fraction: Real) -> Result<(), ParamError> {
    check(
        field,
        fraction,
        fraction.is_finite() && fraction > 0.0 && fraction <= 1.0,
        "must be a fraction of the cut-off with 0 < taper <= 1",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_fall_is_c2_at_both_ends() {
        let e = 1e-7;
        for x in [0.0, 1.0] {
            let (a, da) = smooth_fall(x - e);
            let (b, db) = smooth_fall(x + e);
            assert!((a - b).abs() < 1e-12);
            assert!((da - db).abs() < 1e-6);
        }
        // Second derivative vanishes at both ends: ds ~ x^2 near 0, (1-x)^2 near 1.
        assert!(smooth_fall(1e-4).1.abs() < 1e-6);
        assert!(smooth_fall(1.0 - 1e-4).1.abs() < 1e-6);
        assert_eq!(smooth_fall(0.5).0, 0.5);
    }

    #[test]
    fn smooth_rise_complements_smooth_fall() {
        for k in 0..=100 {
            let x = -0.1 + 1.2 * k as Real / 100.0;
            let (r, dr) = smooth_rise(x);
            let (f, df) = smooth_fall(x);
            assert!(
                (r + f - 1.0).abs() < 1e-15 && (dr + df).abs() < 1e-13,
                "x = {x}"
            );
        }
        // Relative accuracy near 0, where 1 - smooth_fall would cancel.
        let (r, _) = smooth_rise(1e-6);
        assert!((r / 1e-17 - 1.0).abs() < 1e-5, "{r}");
    }

    #[test]
    fn taper_derivative_matches_finite_difference() {
        let t = Taper::new(2.0, 0.3);
        assert!((t.r_on() - 1.4).abs() < 1e-15);
        for k in 0..50 {
            let r = 1.3 + 0.8 * (k as Real) / 49.0;
            let h = 1e-6;
            let fd = (t.eval(r + h).0 - t.eval(r - h).0) / (2.0 * h);
            assert!((fd - t.eval(r).1).abs() < 1e-7, "r = {r}");
        }
        assert_eq!(t.eval(2.0), (0.0, 0.0));
        assert_eq!(t.eval(1.0), (1.0, 0.0));
    }

    /// The branch-free forms used by the SIMD lanes give the same bits.
    #[test]
    fn select_forms_are_bit_identical() {
        let t = Taper::new(2.5, 0.1);
        let bits = |(a, b): (Real, Real)| (a.to_bits(), b.to_bits());
        for k in 0..=2000 {
            let x = -0.2 + 1.4 * k as Real / 2000.0;
            assert_eq!(bits(smooth_fall(x)), bits(smooth_fall_select(x)), "x = {x}");
            let r = 2.0 + 0.7 * k as Real / 2000.0;
            assert_eq!(bits(t.eval(r)), bits(t.eval_select(r)), "r = {r}");
        }
        for r in [t.r_on(), t.cutoff(), Real::NAN, 0.0] {
            assert_eq!(bits(t.eval(r)), bits(t.eval_select(r)), "r = {r}");
        }
    }

    #[test]
    fn fraction_validation() {
        assert!(validate_fraction("taper", 0.5).is_ok());
        assert!(validate_fraction("taper", 1.0).is_ok());
        for bad in [0.0, -0.1, 1.5, Real::NAN] {
            let e = validate_fraction("x.taper", bad).unwrap_err().to_string();
            assert!(e.contains("x.taper") && e.contains("0 < taper <= 1"), "{e}");
        }
    }
}
