//! Form (shape memory) interaction (seed 002 §4):
//! `φ_F = |r + R_i (n_i - n_j)|²` with `R_i = 1/κ_i`, i's rest curvature.
//!
//! `p - R n` is the centre of the circle (sphere) of radius `R` tangent at a
//! particle with outward normal `n`; `r + R(n_i - n_j)` is the difference
//! of the two particles' centres, so `φ_F = 0` exactly when both lie on the
//! same circle of radius `1/κ_i` with outward normals, and elsewhere the
//! force and torque push them onto it.
//!
//! - raw: `|r + R_i (n_i - n_j)|²` (length²). Undefined for `κ_i = 0`
//!   (infinite radius): we then contribute **zero** (use the normalized
//!   variant, or co-normality and co-planarity, for flat regions).
//! - normalized (docs/model.md §3): `|κ_i r + (n_i - n_j)|²`, the raw term divided
//!   by `R_i²`. Dimensionless and well defined for `κ_i = 0`, where it is
//!   co-normality. (Seed 002 footnote 6 divides by `(R|r|)²`, which is not
//!   scale invariant.)
//!
//! Seed 002 prints `τ_F = 2R[n_A × (r - R n_B)]ψ`; deriving the torque from
//! the energy (`τ_i = -n_i × ∂E/∂n_i`) gives the opposite sign with our
//! convention `r = p_j - p_i`. The finite-difference tests settle it.

use super::pair::{PairGeometry, TermGrad};

/// `|r + (n_i - n_j)/κ_i|²` with its gradients; zero when `κ_i == 0`.
#[inline]
pub fn raw(g: &PairGeometry) -> TermGrad {
    if g.kappa_i == 0.0 {
        return TermGrad::default();
    }
    let radius = 1.0 / g.kappa_i;
    let v = g.r + (g.n_i - g.n_j) * radius;
    let d_n = v * (2.0 * radius);
    TermGrad {
        energy: v.norm_squared(),
        d_r: v * 2.0,
        d_ni: d_n,
        d_nj: -d_n,
    }
}

/// `|κ_i r + (n_i - n_j)|²` with its gradients.
#[inline]
pub fn normalized(g: &PairGeometry) -> TermGrad {
    let v = g.r * g.kappa_i + (g.n_i - g.n_j);
    TermGrad {
        energy: v.norm_squared(),
        d_r: v * (2.0 * g.kappa_i),
        d_ni: v * 2.0,
        d_nj: v * -2.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::material::Material;
    use crate::interactions::pair::{evaluate_pair, Coupling};
    use crate::interactions::test_support::{check_term_gradients, geometry, term_suite, Rng};
    use crate::math::{Point3, Real, Vec3};

    #[test]
    fn gradients_match_finite_differences() {
        check_term_gradients(raw, 6);
        check_term_gradients(normalized, 7);
    }

    #[test]
    fn zero_on_the_circle_of_radius_one_over_kappa() {
        let mut rng = Rng::new(8);
        for _ in 0..50 {
            let kappa = rng.sign() * rng.range(0.3, 2.0);
            let radius = 1.0 / kappa;
            let centre = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0);
            // An orthonormal pair (u, w) spanning a random plane through the centre.
            let u = rng.unit_vector();
            let v = rng.unit_vector();
            let w = (v - u * u.dot(&v)).normalize();
            let t0: Real = rng.range(0.0, 6.0);
            let dir = |t: Real| u * t.cos() + w * t.sin();
            // With n = dir, p = c + R dir has p - R n = c for either sign of R
            // (outward normals for R > 0, inward for negative curvature).
            let (p_i, p_j) = (centre + dir(t0) * radius, centre + dir(t0 + 0.6) * radius);
            let g = geometry(p_j - p_i, dir(t0), dir(t0 + 0.6), u, kappa);
            assert!(raw(&g).energy < 1e-24, "{}", raw(&g).energy);
            assert!(normalized(&g).energy < 1e-24);
            // Pair level: no force, no torque.
            let m = Material {
                form: 1.0,
                ..Material::empty()
            }
            .prepare()
            .unwrap();
            let view = |p: Vec3, n: Vec3| crate::interactions::pair::ParticleView {
                position: Point3::from(p),
                normal: n,
                tangent: u.cross(&w),
                kappa,
                material: &m,
            };
            let res = evaluate_pair(
                &view(p_i, dir(t0)),
                &view(p_j, dir(t0 + 0.6)),
                Coupling::Complete { oriented: true },
            );
            assert!(res.energy.abs() < 1e-20 && res.force_i.norm() < 1e-11);
            assert!(res.torque_i.norm() < 1e-11 && res.torque_j.norm() < 1e-11);
        }
    }

    #[test]
    fn raw_form_is_zero_for_zero_curvature() {
        let g = geometry(
            Vec3::new(1.0, 0.2, 0.3),
            Vec3::z(),
            Vec3::y(),
            Vec3::x(),
            0.0,
        );
        assert_eq!(raw(&g), TermGrad::default());
        assert!(normalized(&g).energy > 0.0);
    }

    #[test]
    fn pair_forces_and_torques_match_energy() {
        term_suite(
            Material {
                form: 1.1,
                ..Material::empty()
            },
            104,
        );
    }
}
