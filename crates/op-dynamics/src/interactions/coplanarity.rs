//! Co-planarity (seed 000 eq. 6): `φ_P = (n_i · r)²`.
//!
//! Zero when `j` lies in i's tangent plane. Normalized variant (seed 002
//! footnote 6, docs/model.md §3): `φ_P / |r|² = cos²` of the angle between `n_i`
//! and `r`, dimensionless (faded out near coincidence, where it has no
//! limit: [`super::material`] docs). The weighted energy is `α_P φ_P ψ`;
//! force and torque follow from the gradients returned here (App. B of seed
//! 000 gives them for the raw variant: `f_P = -n_i (n_i·r) ψ - ...`; we
//! derive them from the energy instead, see [`super::pair`]).

use super::pair::{PairGeometry, TermGrad};
use crate::math::Vec3;

/// `(n_i·r)²` with its gradients.
#[inline]
pub fn raw(g: &PairGeometry) -> TermGrad {
    let z = g.n_i.dot(&g.r);
    TermGrad {
        energy: z * z,
        d_r: g.n_i * (2.0 * z),
        d_ni: g.r * (2.0 * z),
        d_nj: Vec3::zeros(),
    }
}

/// `(n_i·r)² / |r|²` with its gradients.
#[inline]
pub fn normalized(g: &PairGeometry) -> TermGrad {
    let inv = 1.0 / (g.dist * g.dist);
    let z = g.n_i.dot(&g.r);
    let e = z * z * inv;
    TermGrad {
        energy: e,
        d_r: (g.n_i * z - g.r * e) * (2.0 * inv),
        d_ni: g.r * (2.0 * z * inv),
        d_nj: Vec3::zeros(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::material::Material;
    use crate::interactions::test_support::{check_term_gradients, geometry, term_suite, Rng};

    #[test]
    fn gradients_match_finite_differences() {
        check_term_gradients(raw, 1);
        check_term_gradients(normalized, 2);
    }

    #[test]
    fn zero_in_the_tangent_plane() {
        let mut rng = Rng::new(5);
        for _ in 0..50 {
            let n_i = rng.unit_vector();
            let v = rng.unit_vector();
            let r = (v - n_i * n_i.dot(&v)) * rng.range(0.5, 2.0);
            let g = geometry(r, n_i, rng.unit_vector(), rng.unit_vector(), 0.7);
            assert!(raw(&g).energy < 1e-28 && normalized(&g).energy < 1e-28);
            assert!(raw(&g).d_ni.norm() < 1e-14 && normalized(&g).d_r.norm() < 1e-14);
        }
    }

    #[test]
    fn pair_forces_and_torques_match_energy() {
        term_suite(
            Material {
                coplanarity: 1.3,
                ..Material::empty()
            },
            101,
        );
    }
}
