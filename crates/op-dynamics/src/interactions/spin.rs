//! Spin torque (seed 000 eq. 14-15): aligns the particles' local x axes
//! with principal curvature directions.
//!
//! With `x = t_i·r` (i's local x, [`crate::math::tangent_axis`] of its body
//! normal axis) and `z = n_i·r`:
//!
//! - [`SpinKind::MinCurvature`] (eq. 14): `φ_S = x² z`, aligns x with the
//!   direction of smallest (most negative) curvature;
//! - [`SpinKind::MinAbsCurvature`] (eq. 15): `φ_S = x² z²`, aligns x with the
//!   direction of smallest absolute curvature.
//!
//! Normalized variant: divided by `|r|³` and `|r|⁴` respectively
//! (dimensionless). The weighted energy is `α_S φ_S ψ`.
//!
//! As in the paper, the term is used **only** to compute a torque about i's
//! normal, `τ_i = -(n_i · ∂E/∂θ_i) n_i`, which only turns the frame within
//! the tangent plane; it produces no force and its energy is not added to
//! the pair energy. Its reaction is not applied to `j`, so this term does
//! **not** conserve angular momentum, by design ("in order not to disturb
//! the original dynamics of the surface", seed 000 §8).

use super::pair::PairGeometry;
use crate::math::{Real, Vec3};
use serde::{Deserialize, Serialize};

/// Which spin potential to use.
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum SpinKind {
    /// `x² z` (seed 000 eq. 14).
    #[default]
    MinCurvature,
    /// `x² z²` (seed 000 eq. 15).
    MinAbsCurvature,
}

/// The spin potential and its gradient with respect to i's tangent `t_i`
/// (the only part of i's frame that a rotation about `n_i` changes).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct SpinEval {
    /// `φ_S` (before weighting).
    pub energy: Real,
    /// `∂φ_S/∂t_i`.
    pub d_t: Vec3,
}

/// `φ_S` and `∂φ_S/∂t_i`, raw or normalized.
#[inline]
pub fn eval(kind: SpinKind, normalized: bool, g: &PairGeometry) -> SpinEval {
    let x = g.t_i.dot(&g.r);
    let z = g.n_i.dot(&g.r);
    let (e, d_x, norm) = match kind {
        SpinKind::MinCurvature => (x * x * z, 2.0 * x * z, g.dist * g.dist * g.dist),
        SpinKind::MinAbsCurvature => {
            let d2 = g.dist * g.dist;
            (x * x * z * z, 2.0 * x * z * z, d2 * d2)
        }
    };
    let scale = if normalized { 1.0 / norm } else { 1.0 };
    SpinEval {
        energy: e * scale,
        d_t: g.r * (d_x * scale),
    }
}

/// The torque about `n_i` from an energy gradient `d_t = ∂E/∂t_i`:
/// `τ = -(n_i · (t_i × d_t)) n_i` (for a rotation `dθ`, `dt = dθ × t`, so
/// `dE/dθ = t × ∂E/∂t`, projected on the normal).
#[inline]
pub fn torque(n_i: &Vec3, t_i: &Vec3, d_t: &Vec3) -> Vec3 {
    n_i * -n_i.dot(&t_i.cross(d_t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::material::Material;
    use crate::interactions::test_support::{geometry, term_suite, Rng};

    #[test]
    fn tangent_gradient_matches_finite_differences() {
        let mut rng = Rng::new(9);
        for kind in [SpinKind::MinCurvature, SpinKind::MinAbsCurvature] {
            for normalized in [false, true] {
                for _ in 0..100 {
                    let r = rng.unit_vector() * rng.range(0.3, 2.0);
                    let g = geometry(
                        r,
                        rng.unit_vector(),
                        rng.unit_vector(),
                        rng.unit_vector(),
                        0.0,
                    );
                    let s = eval(kind, normalized, &g);
                    for k in 0..3 {
                        let h = 1e-6;
                        let mut gp = g;
                        let mut gm = g;
                        gp.t_i[k] += h;
                        gm.t_i[k] -= h;
                        let fd = (eval(kind, normalized, &gp).energy
                            - eval(kind, normalized, &gm).energy)
                            / (2.0 * h);
                        assert!((fd - s.d_t[k]).abs() < 1e-8 * (1.0 + fd.abs()));
                    }
                }
            }
        }
    }

    #[test]
    fn normalized_spin_is_scale_invariant() {
        let g = geometry(
            Vec3::new(0.7, -0.3, 0.4),
            Vec3::z(),
            Vec3::y(),
            Vec3::x(),
            0.0,
        );
        let mut g2 = g;
        g2.r *= 3.0;
        g2.dist *= 3.0;
        for kind in [SpinKind::MinCurvature, SpinKind::MinAbsCurvature] {
            let (a, b) = (eval(kind, true, &g).energy, eval(kind, true, &g2).energy);
            assert!((a - b).abs() < 1e-15, "{a} {b}");
        }
    }

    /// Torque about n_i equal to the projected finite-difference rotational
    /// derivative, no force (checked inside `term_suite` for spin
    /// materials, which also skips the angular momentum check).
    #[test]
    fn pair_torque_is_the_projected_rotational_derivative() {
        for kind in [SpinKind::MinCurvature, SpinKind::MinAbsCurvature] {
            term_suite(
                Material {
                    spin: 0.7,
                    spin_kind: kind,
                    ..Material::empty()
                },
                105,
            );
        }
    }
}
