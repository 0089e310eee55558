//! Co-circularity (seed 000 eq. 8): `φ_C = ((n_i + n_j) · r)²`.
//!
//! Zero when the normals are antisymmetric with respect to `r`, the natural
//! configuration of normals on a sphere. Normalized variant (seed 002
//! footnote 6, docs/model.md §3): `φ_C / |r|²`, dimensionless; it has no limit at
//! `r = 0`, so the material fades it out near coincidence
//! ([`super::material`] docs).

use super::pair::{PairGeometry, TermGrad};

/// `((n_i + n_j)·r)²` with its gradients.
#[inline]
pub fn raw(g: &PairGeometry) -> TermGrad {
    let m = g.n_i + g.n_j;
    let c = m.dot(&g.r);
    let d_n = g.r * (2.0 * c);
    TermGrad {
        energy: c * c,
        d_r: m * (2.0 * c),
        d_ni: d_n,
        d_nj: d_n,
    }
}

/// `((n_i + n_j)·r)² / |r|²` with its gradients.
#[inline]
pub fn normalized(g: &PairGeometry) -> TermGrad {
    let inv = 1.0 / (g.dist * g.dist);
    let m = g.n_i + g.n_j;
    let c = m.dot(&g.r);
    let e = c * c * inv;
    let d_n = g.r * (2.0 * c * inv);
    TermGrad {
        energy: e,
        d_r: (m * c - g.r * e) * (2.0 * inv),
        d_ni: d_n,
        d_nj: d_n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::material::Material;
    use crate::interactions::test_support::{check_term_gradients, geometry, term_suite};
    use crate::math::{Real, Vec3};

    #[test]
    fn gradients_match_finite_differences() {
        check_term_gradients(raw, 4);
        check_term_gradients(normalized, 5);
    }

    #[test]
    fn zero_on_a_sphere() {
        // Two points of a sphere of radius 2 about the origin, outward normals.
        let (a, b): (Real, Real) = (0.3, 1.1);
        let p_i = Vec3::new(a.cos(), a.sin(), 0.2).normalize() * 2.0;
        let p_j = Vec3::new(b.cos(), 0.4, b.sin()).normalize() * 2.0;
        let g = geometry(p_j - p_i, p_i / 2.0, p_j / 2.0, Vec3::x(), 0.5);
        assert!(raw(&g).energy < 1e-28 && normalized(&g).energy < 1e-28);
    }

    #[test]
    fn pair_forces_and_torques_match_energy() {
        term_suite(
            Material {
                cocircularity: 0.9,
                ..Material::empty()
            },
            103,
        );
    }
}
