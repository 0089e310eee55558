//! Co-normality (seed 000 eq. 7): `φ_N = |n_i - n_j|²`.
//!
//! Aligns neighbouring normals (like magnetic dipoles) and controls twist.
//! Already dimensionless, so the raw and normalized variants coincide. With
//! `E = α_N φ_N ψ`, the torque on i is `-n_i × ∂E/∂n_i = 2 α_N ψ n_i × n_j`
//! (plus `-α_N φ_N n_i × ∂ψ/∂n_i` for the anisotropic weight); seed 000
//! App. B writes `n_i × n_j ψ` and puts the factor 2 in eq. 20. We derive it
//! from the energy in [`super::pair`].

use super::pair::{PairGeometry, TermGrad};
use crate::math::Vec3;

/// `|n_i - n_j|²` with its gradients (does not depend on `r`).
#[inline]
pub fn eval(g: &PairGeometry) -> TermGrad {
    let d = g.n_i - g.n_j;
    TermGrad {
        energy: d.norm_squared(),
        d_r: Vec3::zeros(),
        d_ni: d * 2.0,
        d_nj: d * -2.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::material::Material;
    use crate::interactions::test_support::{check_term_gradients, term_suite};

    #[test]
    fn gradients_match_finite_differences() {
        check_term_gradients(eval, 3);
    }

    #[test]
    fn zero_for_parallel_normals() {
        let n = Vec3::new(0.3, -0.4, 0.5).normalize();
        let g = crate::interactions::test_support::geometry(Vec3::x(), n, n, Vec3::y(), 0.0);
        assert_eq!(eval(&g).energy, 0.0);
    }

    #[test]
    fn pair_forces_and_torques_match_energy() {
        term_suite(
            Material {
                conormality: 0.8,
                ..Material::empty()
            },
            102,
        );
    }
}
