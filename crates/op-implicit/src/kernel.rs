//! The compact-support field kernel: Wyvill's soft-object polynomial.
//!
//! Wyvill, McPheeters & Wyvill 1986 ("Data structure for soft objects"),
//! the potential of seed 002 §6 ("potentials are decreasing functions of the
//! distance of the emitting skeleton"):
//!
//! ```text
//! f(d) = 1 - 22/9 (d/R)^2 + 17/9 (d/R)^4 - 4/9 (d/R)^6   for d < R,
//! f(d) = 0                                                 for d >= R.
//! ```
//!
//! `R` is the support radius. `f(0) = 1`, `f(R) = 0` and `f'(R) = 0`
//! (C1 at the support boundary), `f'(0) = 0`, and `f` is monotone on
//! `[0, R]`. The skin is the iso-surface `f = ISO = 1/2`. Solving
//! `f(d) = 1/2` gives exactly `d = R/2` (with `s = (d/R)^2 = 1/4`:
//! `1 - 22/36 + 17/144 - 4/576 = 72/144`): an isolated point primitive of
//! support radius `R` is skinned by a sphere of radius `R/2`
//! ([`iso_radius`]). The slope there, `f'(R/2) = -19/(12 R)`, sets the
//! stiffness of the skin (seed 002 §6).
//!
//! The polynomial is even in `d`, so it is evaluated from the squared
//! reduced distance `s = (d/R)^2`: no square root, and a gradient that stays
//! smooth on the skeleton itself, where `d` is not differentiable.

use op_dynamics::Real;

/// The iso value of the skin: the surface is `{p : field(p) = ISO}`, the
/// inside `field > ISO`.
pub const ISO: Real = 0.5;

/// `f` as a function of the squared reduced distance `s = (d/R)^2`:
/// `1 - 22/9 s + 17/9 s^2 - 4/9 s^3` for `s < 1`, else 0.
#[inline]
pub fn value_sq(s: Real) -> Real {
    if s >= 1.0 {
        return 0.0;
    }
    1.0 + s * (-22.0 / 9.0 + s * (17.0 / 9.0 - s * (4.0 / 9.0)))
}

/// `df/ds` for `s = (d/R)^2`: `-22/9 + 34/9 s - 12/9 s^2` for `s < 1`, else 0.
/// Vanishes at `s = 1` (C1 support boundary).
#[inline]
pub fn derivative_sq(s: Real) -> Real {
    if s >= 1.0 {
        return 0.0;
    }
    -22.0 / 9.0 + s * (34.0 / 9.0 - s * (12.0 / 9.0))
}

/// `d^2f/ds^2` for `s = (d/R)^2`: `34/9 - 24/9 s` for `s < 1`, else 0
/// (`f` is C1, not C2, at the support's boundary).
#[inline]
pub fn second_derivative_sq(s: Real) -> Real {
    if s >= 1.0 {
        return 0.0;
    }
    34.0 / 9.0 - s * (24.0 / 9.0)
}

/// `f(d)` for support radius `radius` (see the module doc).
#[inline]
pub fn value(d: Real, radius: Real) -> Real {
    let r = d / radius;
    value_sq(r * r)
}

/// `df/dd` for support radius `radius`: `2 d / R^2 * df/ds`.
#[inline]
pub fn derivative(d: Real, radius: Real) -> Real {
    let r = d / radius;
    2.0 * d / (radius * radius) * derivative_sq(r * r)
}

/// The distance at which `f = ISO` for support radius `radius`: exactly
/// `radius / 2`.
#[inline]
pub fn iso_radius(radius: Real) -> Real {
    0.5 * radius
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_and_iso() {
        assert_eq!(value(0.0, 2.0), 1.0);
        assert_eq!(value(2.0, 2.0), 0.0);
        assert_eq!(value(3.0, 2.0), 0.0);
        assert!((value(iso_radius(2.0), 2.0) - ISO).abs() < 1e-15);
        assert!(derivative(2.0 - 1e-12, 2.0).abs() < 1e-10);
        assert!((derivative(1.0, 2.0) + 19.0 / 24.0).abs() < 1e-14);
    }

    #[test]
    fn derivative_matches_finite_differences_and_is_monotone() {
        let r = 1.3;
        let h = 1e-6;
        let mut last = 1.0;
        for k in 1..100 {
            let d = r * k as Real / 100.0;
            let fd = (value(d + h, r) - value(d - h, r)) / (2.0 * h);
            assert!((fd - derivative(d, r)).abs() < 1e-7, "d = {d}");
            let v = value(d, r);
            assert!(v < last);
            last = v;
        }
    }
}
