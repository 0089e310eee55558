//! The pair entry point: energy, forces and torques of one unordered pair,
//! visited once, with both directions `E_ij` and `E_ji` evaluated
//! (seed 000 eq. 11 and App. B, seed 002 §4-5, docs/model.md §3).
//!
//! Conventions: for an ordered pair `i` emits and `j` feels, `r = p_j - p_i`,
//! `n = R(q) a`, `t = R(q) tangent_axis(a)`. Every force and torque is
//! derived from the energy:
//!
//! - force on `j` is `-∂E/∂r`, on `i` `+∂E/∂r` (so `F_i + F_j = 0`);
//! - for a small world rotation `dθ` of a particle, `dn = dθ × n`, so
//!   `∂E/∂θ = n × ∂E/∂n` and the torque is `τ = -n × ∂E/∂n = ∂E/∂n × n`.
//!
//! Every term is a rotation-invariant function of `(r, n_i, n_j)`, hence
//! `r × ∂E/∂r + n_i × ∂E/∂n_i + n_j × ∂E/∂n_j = 0`: internal forces and
//! torques conserve linear and angular momentum. The one exception is the
//! spin torque ([`super::spin`]), torque-only by design.
//!
//! Pair energy, for [`Coupling::Complete`]: spacing `½(U_i(r) + U_j(r))`
//! (each emitter's material gives half, so identical materials give `U`),
//! plus, when oriented, `E_ij + E_ji` where
//! `E_ij = ψ_i(r, n_i) Σ_term α_term φ_term(r, n_i, n_j, κ_i)` uses i's
//! material and `E_ji` the same seen from `j` (`r → -r`, roles swapped,
//! `κ_j`); plus spin torques from both sides (spin adds no energy). For
//! [`Coupling::RepulsionOnly`]: `½(Rep_i(r) + Rep_j(r))`.
//!
//! Coincident particles (`|r| = 0`, direction undefined) contribute nothing.

use super::material::{Direction, PreparedMaterial};
use crate::math::{Point3, Real, Vec3};

/// The geometry of an ordered pair as seen from the emitter `i`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PairGeometry {
    /// `r = p_j - p_i`.
    pub r: Vec3,
    /// `|r|` (> 0).
    pub dist: Real,
    /// Emitter's world normal.
    pub n_i: Vec3,
    /// Receiver's world normal.
    pub n_j: Vec3,
    /// Emitter's world tangent ("local x", used by the spin term only).
    pub t_i: Vec3,
    /// Emitter's rest curvature (form term).
    pub kappa_i: Real,
}

/// An orientation term's value and gradients, before weighting by `ψ`.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct TermGrad {
    /// `φ`.
    pub energy: Real,
    /// `∂φ/∂r`.
    pub d_r: Vec3,
    /// `∂φ/∂n_i`.
    pub d_ni: Vec3,
    /// `∂φ/∂n_j`.
    pub d_nj: Vec3,
}

impl TermGrad {
    /// `self += w * other`.
    #[inline]
    pub fn add_scaled(&mut self, w: Real, other: &TermGrad) {
        self.energy += w * other.energy;
        self.d_r += other.d_r * w;
        self.d_ni += other.d_ni * w;
        self.d_nj += other.d_nj * w;
    }
}

/// The weighted orientation energy `E_ij` emitted by one particle, its
/// gradients, and the spin torque on the emitter.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct OrientationGrad {
    /// `E_ij` (spin excluded).
    pub energy: Real,
    /// `∂E_ij/∂r`.
    pub d_r: Vec3,
    /// `∂E_ij/∂n_i`.
    pub d_ni: Vec3,
    /// `∂E_ij/∂n_j`.
    pub d_nj: Vec3,
    /// Spin torque on the emitter (along `n_i`).
    pub spin_torque: Vec3,
}

/// What the world knows about one particle of a pair.
#[derive(Copy, Clone, Debug)]
pub struct ParticleView<'a> {
    /// Position `p`.
    pub position: Point3,
    /// World normal `n = R(q) a` (unit).
    pub normal: Vec3,
    /// World tangent `t = R(q) tangent_axis(a)` (unit, orthogonal to `n`).
    pub tangent: Vec3,
    /// Rest curvature `κ` (form term).
    pub kappa: Real,
    /// The particle's prepared material.
    pub material: &'a PreparedMaterial,
}

/// How the two particles of a pair interact (seed 002 §5).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Coupling {
    /// Complete interaction: spacing, plus orientation terms when
    /// `oriented` (false when either particle is unoriented, seed 000 §6).
    Complete {
        /// Evaluate the orientation terms.
        oriented: bool,
    },
    /// Exponential repulsion only (different objects, or standard
    /// particles of different types).
    RepulsionOnly,
}

/// Energy, forces and torques of one pair.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct PairResult {
    /// Pair energy (spin excluded).
    pub energy: Real,
    /// Force on `i`.
    pub force_i: Vec3,
    /// Force on `j`.
    pub force_j: Vec3,
    /// Torque on `i`.
    pub torque_i: Vec3,
    /// Torque on `j`.
    pub torque_j: Vec3,
}

/// `½(f_i(r) + f_j(r))` of two per-material radial potentials, evaluated
/// once when both particles share the material.
#[inline(always)]
fn half_sum(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    x: Real,
    f: impl Fn(&PreparedMaterial, Real) -> (Real, Real),
) -> (Real, Real) {
    if std::ptr::eq(mi, mj) {
        f(mi, x)
    } else {
        let (a, b) = (f(mi, x), f(mj, x));
        (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1))
    }
}

/// Spacing-only fast path (no orientation data touched): returns the pair
/// spacing energy `½(U_i + U_j)` and the force on `j`; the force on `i` is
/// its negative. `r = p_j - p_i`; `dist = |r|` is only tested (zero or NaN
/// gives zero): the kernel works from `|r|²` ([`evaluate_spacing_sq`]).
#[inline]
pub fn evaluate_spacing(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    r: &Vec3,
    dist: Real,
) -> (Real, Vec3) {
    if dist.is_nan() || dist <= 0.0 {
        return (0.0, Vec3::zeros());
    }
    evaluate_spacing_sq(mi, mj, r, r.norm_squared())
}

/// [`evaluate_spacing`] from `d2 = |r|²` (zero when `d2` is 0 or NaN): one
/// division `1/d2` shared by both materials, no square root for
/// Lennard-Jones before its taper ([`PreparedMaterial::spacing_eval_sq`]).
#[inline(always)]
pub fn evaluate_spacing_sq(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    r: &Vec3,
    d2: Real,
) -> (Real, Vec3) {
    if d2.is_nan() || d2 <= 0.0 {
        return (0.0, Vec3::zeros());
    }
    let inv_d2 = 1.0 / d2;
    let (u, g) = if std::ptr::eq(mi, mj) {
        mi.spacing_eval_sq(d2, inv_d2)
    } else {
        let (a, b) = (
            mi.spacing_eval_sq(d2, inv_d2),
            mj.spacing_eval_sq(d2, inv_d2),
        );
        (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1))
    };
    (u, r * (-g))
}

/// Energy, forces and torques of the unordered pair `(i, j)` (see the
/// module docs). No allocation.
#[inline]
pub fn evaluate_pair(i: &ParticleView, j: &ParticleView, coupling: Coupling) -> PairResult {
    evaluate_pair_weakened(i, j, coupling, 1.0)
}

/// The spacing part of a complete pair weakened to strength `s < 1`
/// ([`crate::heat::weakened_spacing`] of each material's potential, then
/// halved and summed like [`evaluate_spacing`]): energy and force on `j`.
#[inline]
pub fn evaluate_spacing_weakened(
    mi: &PreparedMaterial,
    mj: &PreparedMaterial,
    r: &Vec3,
    dist: Real,
    s: Real,
) -> (Real, Vec3) {
    if dist.is_nan() || dist <= 0.0 {
        return (0.0, Vec3::zeros());
    }
    let weak = |m: &PreparedMaterial, d: Real| {
        let (u, du) = m.spacing_eval(d);
        crate::heat::weakened_spacing(u, du, d, m.spacing_well(), s)
    };
    let (u, du) = half_sum(mi, mj, dist, weak);
    (u, r * (-du / dist))
}

/// [`evaluate_pair`] with the complete interaction weakened by heat to
/// strength `s` in `[0, 1]` ([`crate::heat`]): the spacing well `s` times
/// as deep (core unchanged), the orientation terms and spin torques scaled
/// by `s`. Repulsion-only pairs are not weakened. `s = 1` is exactly
/// [`evaluate_pair`].
///
/// Both directions `E_ij` and `E_ji` come from one shared geometry
/// (`|r|²`, one division `1/|r|²`, one square root, the dot products
/// `n_i·r`, `n_j·r` and the cross products `r × n_i`, `r × n_j`,
/// `n_i × n_j`), and the weight `ψ` is evaluated once when both particles
/// share an isotropic material (`PreparedMaterial::direction`, crate-private).
#[inline(always)]
pub fn evaluate_pair_weakened(
    i: &ParticleView,
    j: &ParticleView,
    coupling: Coupling,
    s: Real,
) -> PairResult {
    let r = j.position - i.position;
    let d2 = r.norm_squared();
    let mut out = PairResult::default();
    if d2.is_nan() || d2 <= 0.0 {
        return out;
    }
    let oriented = match coupling {
        Coupling::RepulsionOnly => {
            let dist = d2.sqrt();
            let (u, du) = half_sum(
                i.material,
                j.material,
                dist,
                PreparedMaterial::repulsion_eval,
            );
            out.energy = u;
            out.force_j = r * (-du / dist);
            out.force_i = -out.force_j;
            return out;
        }
        Coupling::Complete { oriented } => oriented,
    };
    let weak = s < 1.0;
    let (u, f_j) = if weak {
        evaluate_spacing_weakened(i.material, j.material, &r, d2.sqrt(), s)
    } else {
        evaluate_spacing_sq(i.material, j.material, &r, d2)
    };
    out.energy = u;
    out.force_j = f_j;
    if oriented {
        oriented_terms(i, j, &r, d2, weak.then_some(s), &mut out);
    }
    out.force_i = -out.force_j;
    out
}

/// The orientation terms of both directions, added to `out` (energy, force
/// on `j`, torques); `s` weakens them by heat.
#[inline(always)]
fn oriented_terms(
    i: &ParticleView,
    j: &ParticleView,
    r: &Vec3,
    d2: Real,
    s: Option<Real>,
    out: &mut PairResult,
) {
    let (mi, mj) = (i.material, j.material);
    let dist = d2.sqrt();
    let on_i = mi.has_orientation_terms() && dist < mi.orientation_cutoff();
    let on_j = mj.has_orientation_terms() && dist < mj.orientation_cutoff();
    if !(on_i || on_j) {
        return;
    }
    let inv_d2 = 1.0 / d2;
    let inv_dist = dist * inv_d2;
    let (ni, nj) = (&i.normal, &j.normal);
    let (zi, zj) = (ni.dot(r), nj.dot(r));
    let d = ni - nj;
    let dd = d.norm_squared();
    let weight = |m: &PreparedMaterial, z: Real| {
        let (psi, wr, wn) = m.weight().eval_scalar(d2, dist, inv_dist, z);
        match s {
            Some(s) => (s * psi, s * wr, s * wn),
            None => (psi, wr, wn),
        }
    };
    let mut wi = (0.0, 0.0, 0.0);
    let mut di = Direction::default();
    if on_i {
        wi = weight(mi, zi);
        di = mi.direction(dist, inv_d2, zi, zj, dd, r, &d, i.kappa, wi);
    }
    let mut wj = (0.0, 0.0, 0.0);
    let mut dj = Direction::default();
    if on_j {
        // Seen from j: r -> -r, so n_j·r_e = -zj and n_i·r_e = -zi.
        wj = if on_i && std::ptr::eq(mi, mj) && mi.weight().is_isotropic() {
            wi
        } else {
            weight(mj, -zj)
        };
        dj = mj.direction(dist, inv_d2, -zj, -zi, dd, r, &d, j.kappa, wj);
    }
    let rxi = r.cross(ni);
    let rxj = r.cross(nj);
    let nxn = ni.cross(nj);
    let bt = di.b + dj.b;
    out.energy += di.energy + dj.energy;
    out.force_j += r * (-di.g_r - dj.g_r) + ni * (dj.g_n - di.g_e) + nj * (dj.g_e - di.g_n);
    out.torque_i += rxi * (di.g_e - dj.g_n) + nxn * bt;
    out.torque_j += rxj * (di.g_n - dj.g_e) - nxn * bt;
    if on_i && mi.has_spin() {
        let g = PairGeometry {
            r: *r,
            dist,
            n_i: *ni,
            n_j: *nj,
            t_i: i.tangent,
            kappa_i: i.kappa,
        };
        out.torque_i += mi.spin_torque(&g, wi.0);
    }
    if on_j && mj.has_spin() {
        let g = PairGeometry {
            r: -r,
            dist,
            n_i: *nj,
            n_j: *ni,
            t_i: j.tangent,
            kappa_i: j.kappa,
        };
        out.torque_j += mj.spin_torque(&g, wj.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interactions::cohesion::{CohesionMode, CohesionParams};
    use crate::interactions::lennard_jones::LennardJonesParams;
    use crate::interactions::material::Material;
    use crate::interactions::spacing::Spacing;
    use crate::interactions::spin::SpinKind;
    use crate::interactions::test_support::{check_fd, check_momentum, random_pair, Body, Rng};
    use crate::interactions::weight::{WeightParams, WeightShape};
    use crate::math::{Quat, Real};

    fn all_terms(normalized: bool, anisotropic: bool, spin: Real) -> Material {
        Material {
            spacing: Some(Spacing::LennardJones(LennardJonesParams::default())),
            weight: WeightParams {
                shape: if anisotropic {
                    WeightShape::Anisotropic { b: 0.6 }
                } else {
                    WeightShape::Isotropic
                },
                ..Default::default()
            },
            coplanarity: 0.7,
            conormality: 0.4,
            cocircularity: 0.3,
            form: 0.9,
            spin,
            spin_kind: SpinKind::MinAbsCurvature,
            normalized,
            ..Material::default()
        }
    }

    const COMPLETE: Coupling = Coupling::Complete { oriented: true };

    #[test]
    fn spacing_potentials_match_energy_and_conserve_momentum() {
        let lj = Material {
            spacing: Some(Spacing::LennardJones(LennardJonesParams::default())),
            ..Material::empty()
        };
        let exact = Material {
            spacing: Some(Spacing::Cohesion(CohesionParams {
                mode: CohesionMode::Exact,
                ..Default::default()
            })),
            ..Material::empty()
        };
        let tab = Material {
            spacing: Some(Spacing::Cohesion(CohesionParams::default())),
            ..Material::empty()
        };
        let (lj, exact, tab) = (
            lj.prepare().unwrap(),
            exact.prepare().unwrap(),
            tab.prepare().unwrap(),
        );
        let mut rng = Rng::new(21);
        let pairs = [
            (&lj, &lj),
            (&exact, &exact),
            (&tab, &tab),
            (&lj, &tab),
            (&exact, &lj),
        ];
        for (mi, mj) in pairs {
            for _ in 0..40 {
                let d = rng.range(0.3, mi.cutoff().max(mj.cutoff()));
                let (bi, bj) = random_pair(&mut rng, d);
                for oriented in [false, true] {
                    let c = Coupling::Complete { oriented };
                    check_fd(mi, mj, &bi, &bj, c);
                    check_momentum(mi, mj, &bi, &bj, c);
                }
                let r = bj.p - bi.p;
                let (e, f) = evaluate_spacing(mi, mj, &r, r.norm());
                let full = evaluate_pair(&bi.view(mi), &bj.view(mj), COMPLETE);
                assert_eq!((e, f), (full.energy, full.force_j));
            }
        }
        // Same material: half of two equal halves is U itself.
        let (u, _) = evaluate_spacing(&lj, &lj, &Vec3::x(), 1.0);
        assert!((u + 1.0).abs() < 1e-15);
    }

    #[test]
    fn repulsion_only_matches_energy() {
        let a = Material::default().prepare().unwrap();
        let b = Material {
            repulsion: crate::interactions::repulsion::RepulsionParams {
                strength: 3.0,
                lambda: 0.2,
                ..Default::default()
            },
            ..all_terms(true, true, 0.5)
        }
        .prepare()
        .unwrap();
        let mut rng = Rng::new(22);
        for (mi, mj) in [(&a, &a), (&a, &b)] {
            for _ in 0..40 {
                let (bi, bj) = {
                    let d = rng.range(0.3, 2.0);
                    random_pair(&mut rng, d)
                };
                check_fd(mi, mj, &bi, &bj, Coupling::RepulsionOnly);
                check_momentum(mi, mj, &bi, &bj, Coupling::RepulsionOnly);
                let res = evaluate_pair(&bi.view(mi), &bj.view(mj), Coupling::RepulsionOnly);
                assert_eq!(res.torque_i, Vec3::zeros());
                // Repulsive: force on j points away from i (before the taper).
                if (bj.p - bi.p).norm() < 1.6 {
                    assert!(res.force_j.dot(&(bj.p - bi.p)) > 0.0);
                }
            }
        }
    }

    /// Every term at once, different materials on both sides, spin
    /// included: forces and torques against central differences.
    #[test]
    fn all_terms_with_different_materials_match_energy() {
        let mut rng = Rng::new(23);
        for normalized in [false, true] {
            for anisotropic in [false, true] {
                let mi = all_terms(normalized, anisotropic, 0.6).prepare().unwrap();
                let mj = Material {
                    spacing: Some(Spacing::Cohesion(CohesionParams::default())),
                    weight: WeightParams {
                        a: 0.8,
                        cutoff: 2.2,
                        ..Default::default()
                    },
                    coplanarity: 1.5,
                    form: 0.2,
                    spin_kind: SpinKind::MinCurvature,
                    ..all_terms(normalized, !anisotropic, 0.3)
                }
                .prepare()
                .unwrap();
                for _ in 0..30 {
                    let (bi, bj) = {
                        let d = rng.range(0.5, 2.5);
                        random_pair(&mut rng, d)
                    };
                    check_fd(&mi, &mj, &bi, &bj, COMPLETE);
                    check_fd(&mj, &mi, &bj, &bi, COMPLETE);
                }
            }
        }
    }

    /// The fused kernel against the term-by-term reference
    /// ([`PreparedMaterial::orientation`] of each direction, each term
    /// evaluated on its own): same energy, forces and torques to round-off,
    /// for every term, both normalizations and weight shapes, spin, heat.
    #[test]
    fn fused_kernel_matches_the_term_by_term_reference() {
        fn reference(i: &ParticleView, j: &ParticleView, s: Real) -> PairResult {
            let r = j.position - i.position;
            let dist = r.norm();
            let (u, mut f_j) = if s < 1.0 {
                evaluate_spacing_weakened(i.material, j.material, &r, dist, s)
            } else {
                evaluate_spacing(i.material, j.material, &r, dist)
            };
            let mut out = PairResult {
                energy: u,
                ..Default::default()
            };
            for (e, rcv, re, sign) in [(i, j, r, -1.0), (j, i, -r, 1.0)] {
                let m = e.material;
                if !(m.has_orientation_terms() && dist < m.orientation_cutoff()) {
                    continue;
                }
                let g = PairGeometry {
                    r: re,
                    dist,
                    n_i: e.normal,
                    n_j: rcv.normal,
                    t_i: e.tangent,
                    kappa_i: e.kappa,
                };
                let o = m.orientation(&g);
                out.energy += s * o.energy;
                f_j += o.d_r * (sign * s);
                let te = (o.d_ni.cross(&e.normal) + o.spin_torque) * s;
                let tr = o.d_nj.cross(&rcv.normal) * s;
                if sign < 0.0 {
                    out.torque_i += te;
                    out.torque_j += tr;
                } else {
                    out.torque_j += te;
                    out.torque_i += tr;
                }
            }
            out.force_j = f_j;
            out.force_i = -f_j;
            out
        }
        let mut rng = Rng::new(29);
        for normalized in [false, true] {
            for anisotropic in [false, true] {
                let mi = all_terms(normalized, anisotropic, 0.6).prepare().unwrap();
                let mj = all_terms(normalized, !anisotropic, 0.2).prepare().unwrap();
                for (a, b) in [(&mi, &mi), (&mi, &mj), (&mj, &mi)] {
                    for s in [1.0, 0.4] {
                        for _ in 0..40 {
                            let d = rng.range(0.4, 2.6);
                            let (bi, bj) = random_pair(&mut rng, d);
                            let (vi, vj) = (bi.view(a), bj.view(b));
                            let got = evaluate_pair_weakened(&vi, &vj, COMPLETE, s);
                            let want = reference(&vi, &vj, s);
                            let scale = 1.0
                                + want.energy.abs()
                                + want.force_j.norm()
                                + want.torque_i.norm()
                                + want.torque_j.norm();
                            assert!((got.energy - want.energy).abs() <= 1e-12 * scale);
                            for (g, w) in [
                                (got.force_j, want.force_j),
                                (got.torque_i, want.torque_i),
                                (got.torque_j, want.torque_j),
                            ] {
                                assert!((g - w).norm() <= 1e-12 * scale, "{g} vs {w}");
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn momentum_is_conserved_without_spin() {
        let mut rng = Rng::new(24);
        for normalized in [false, true] {
            for anisotropic in [false, true] {
                let mi = all_terms(normalized, anisotropic, 0.0).prepare().unwrap();
                let mj = all_terms(normalized, !anisotropic, 0.0).prepare().unwrap();
                for _ in 0..50 {
                    let (bi, bj) = {
                        let d = rng.range(0.3, 2.5);
                        random_pair(&mut rng, d)
                    };
                    check_momentum(&mi, &mj, &bi, &bj, COMPLETE);
                    check_momentum(&mi, &mi, &bi, &bj, COMPLETE);
                }
            }
        }
    }

    #[test]
    fn rigid_motion_leaves_energy_unchanged_and_rotates_forces() {
        let mut rng = Rng::new(25);
        let mi = all_terms(true, true, 0.5).prepare().unwrap();
        let mj = all_terms(false, false, 0.3).prepare().unwrap();
        for _ in 0..50 {
            let (bi, bj) = {
                let d = rng.range(0.4, 2.4);
                random_pair(&mut rng, d)
            };
            let rot: Quat = rng.rotation();
            let shift = rng.unit_vector() * rng.range(0.0, 10.0);
            let moved = |b: &Body| Body {
                p: rot * b.p + shift,
                q: rot * b.q,
                ..*b
            };
            let (ci, cj) = (moved(&bi), moved(&bj));
            for c in [COMPLETE, Coupling::RepulsionOnly] {
                let a = evaluate_pair(&bi.view(&mi), &bj.view(&mj), c);
                let b = evaluate_pair(&ci.view(&mi), &cj.view(&mj), c);
                let scale = a.force_i.norm() + a.torque_i.norm() + a.torque_j.norm() + 1e-12;
                assert!((a.energy - b.energy).abs() <= 1e-12 * (1.0 + a.energy.abs()));
                for (u, v) in [
                    (a.force_i, b.force_i),
                    (a.force_j, b.force_j),
                    (a.torque_i, b.torque_i),
                    (a.torque_j, b.torque_j),
                ] {
                    assert!((rot * u - v).norm() <= 1e-11 * scale, "{u} {v}");
                }
            }
        }
    }

    /// docs/model.md §3: with normalized terms, scaling every length by `s` (and
    /// each parameter by dimensional analysis: lengths by `s`, cohesion
    /// `α` by `1/s²` and `E` by `1/s³`, curvatures by `1/s`) leaves energies
    /// and torques unchanged and scales forces by `1/s`.
    #[test]
    fn normalized_terms_are_scale_invariant() {
        fn scaled(m: &Material, s: Real) -> Material {
            let spacing = match m.spacing {
                Some(Spacing::Cohesion(c)) => Some(Spacing::Cohesion(CohesionParams {
                    r0: c.r0 * s,
                    alpha: c.alpha / (s * s),
                    e: c.e / (s * s * s),
                    cutoff: c.cutoff.map(|x| x * s),
                    ..c
                })),
                Some(Spacing::LennardJones(l)) => Some(Spacing::LennardJones(LennardJonesParams {
                    r0: l.r0 * s,
                    cutoff: l.cutoff * s,
                    ..l
                })),
                None => None,
            };
            let shape = match m.weight.shape {
                WeightShape::Anisotropic { b } => WeightShape::Anisotropic { b: b * s },
                WeightShape::Isotropic => WeightShape::Isotropic,
            };
            Material {
                spacing,
                weight: WeightParams {
                    a: m.weight.a * s,
                    cutoff: m.weight.cutoff * s,
                    shape,
                    ..m.weight
                },
                repulsion: crate::interactions::repulsion::RepulsionParams {
                    sigma: m.repulsion.sigma * s,
                    lambda: m.repulsion.lambda * s,
                    cutoff: m.repulsion.cutoff * s,
                    ..m.repulsion
                },
                ..*m
            }
        }
        let mut rng = Rng::new(28);
        let base_i = all_terms(true, true, 0.5);
        let base_j = Material {
            spacing: Some(Spacing::Cohesion(CohesionParams::default())),
            ..all_terms(true, false, 0.2)
        };
        for s in [0.01, 3.7, 250.0] {
            let (mi, mj) = (base_i.prepare().unwrap(), base_j.prepare().unwrap());
            let (si, sj) = (
                scaled(&base_i, s).prepare().unwrap(),
                scaled(&base_j, s).prepare().unwrap(),
            );
            assert!((si.cutoff() / mi.cutoff() - s).abs() < 1e-12 * s);
            for _ in 0..30 {
                let d = rng.range(0.4, 2.4);
                let (bi, bj) = random_pair(&mut rng, d);
                let grow = |b: &Body| Body {
                    p: Point3::from(b.p.coords * s),
                    kappa: b.kappa / s,
                    ..*b
                };
                for c in [COMPLETE, Coupling::RepulsionOnly] {
                    let a = evaluate_pair(&bi.view(&mi), &bj.view(&mj), c);
                    let b = evaluate_pair(&grow(&bi).view(&si), &grow(&bj).view(&sj), c);
                    let scale = a.force_i.norm() + a.torque_i.norm() + a.torque_j.norm() + 1e-300;
                    assert!(
                        (a.energy - b.energy).abs() <= 1e-9 * (a.energy.abs() + 1e-6),
                        "s={s}: {} vs {}",
                        a.energy,
                        b.energy
                    );
                    assert!((a.force_j - b.force_j * s).norm() <= 1e-9 * scale, "s={s}");
                    assert!((a.torque_i - b.torque_i).norm() <= 1e-9 * scale, "s={s}");
                    assert!((a.torque_j - b.torque_j).norm() <= 1e-9 * scale, "s={s}");
                }
            }
        }
    }

    #[test]
    fn unoriented_pairs_keep_only_spacing() {
        let m = all_terms(true, false, 0.5).prepare().unwrap();
        let mut rng = Rng::new(26);
        let (bi, bj) = random_pair(&mut rng, 1.2);
        let res = evaluate_pair(
            &bi.view(&m),
            &bj.view(&m),
            Coupling::Complete { oriented: false },
        );
        let r = bj.p - bi.p;
        let (e, f) = evaluate_spacing(&m, &m, &r, r.norm());
        assert_eq!(res.energy, e);
        assert_eq!(res.force_j, f);
        assert_eq!(res.torque_i, Vec3::zeros());
        assert_eq!(res.torque_j, Vec3::zeros());
    }

    #[test]
    fn coincident_particles_contribute_nothing() {
        let m = all_terms(true, true, 0.5).prepare().unwrap();
        let b = Body {
            p: Point3::new(0.1, 0.2, 0.3),
            q: Quat::identity(),
            a: Vec3::z(),
            kappa: 0.3,
        };
        for c in [COMPLETE, Coupling::RepulsionOnly] {
            assert_eq!(
                evaluate_pair(&b.view(&m), &b.view(&m), c),
                PairResult::default()
            );
        }
        assert_eq!(
            evaluate_spacing(&m, &m, &Vec3::zeros(), 0.0),
            (0.0, Vec3::zeros())
        );
    }

    #[test]
    fn energy_and_forces_vanish_continuously_at_the_cutoff() {
        let mut rng = Rng::new(27);
        for normalized in [false, true] {
            for anisotropic in [false, true] {
                let m = all_terms(normalized, anisotropic, 0.5).prepare().unwrap();
                let rc = m.cutoff();
                for c in [COMPLETE, Coupling::RepulsionOnly] {
                    for _ in 0..10 {
                        let (bi, bj) = random_pair(&mut rng, rc * (1.0 - 1e-7));
                        let res = evaluate_pair(&bi.view(&m), &bj.view(&m), c);
                        assert!(res.energy.abs() < 1e-12, "{}", res.energy);
                        for v in [res.force_i, res.torque_i, res.torque_j] {
                            assert!(v.norm() < 1e-9, "{v}");
                        }
                        let (bi, bj) = random_pair(&mut rng, rc * (1.0 + 1e-9));
                        let res = evaluate_pair(&bi.view(&m), &bj.view(&m), c);
                        assert_eq!(res, PairResult::default());
                    }
                }
            }
        }
    }
}
