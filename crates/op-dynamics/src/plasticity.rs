//! Plasticity of the remembered shape (seed 000 §8, fig. 12b).
//!
//! A shape-memory object (seed 002 §4) remembers its shape as each
//! particle's rest curvature `κ_i`, the curvature the form term
//! `|κ_i r + (n_i - n_j)|²` ([`crate::interactions::form`]) pulls its
//! neighbourhood towards. Plasticity lets that memory yield: after each
//! step, every particle whose material has a [`Plasticity`] compares its
//! remembered curvature with its current one and, when they differ by more
//! than a yield curvature, moves the remembered one towards the current
//! one. This is the plasticity of Terzopoulos & Fleischer 1988 ("Modeling
//! inelastic deformations: viscoelasticity, plasticity, fracture", cited by
//! seed 000 §8 for fig. 12b), where the rest curvature tensor of a
//! deformable surface flows towards the current one once the deformation
//! exceeds a yield limit, written for the oriented particles' scalar
//! curvature.
//!
//! **Current curvature.** The form term emitted by `i` vanishes when each
//! neighbour `j` lies on the sphere of radius `R_i = 1/κ_i` tangent to
//! `i`'s plane at `p_i`, centred at `c_i = p_i - R_i n_i`, with its normal
//! pointing away from `c_i` (seed 002 §4). `κ̂_i` is the curvature of the
//! sphere of that family (tangent at `p_i`, normal `n_i`) that best passes
//! through the neighbours' current positions: `|r + R n_i|² = R²` reads
//! `κ |r|² + 2 n_i·r = 0`, and its least-squares solution over the
//! neighbours `j` that couple completely with `i` and are oriented (seed
//! 002 §5), weighted by `i`'s orientation weight `ψ_ij` (seed 000 eq. 10),
//! is
//!
//! `κ̂_i = -2 Σ_j ψ_ij (n_i·r_ij) |r_ij|² / Σ_j ψ_ij |r_ij|⁴`.
//!
//! When the neighbours lie on a sphere (circle) of radius `R` with outward
//! normals, `κ̂_i = 1/R` exactly (negative for inward normals), so a
//! neighbourhood at rest under the form term (zero form energy, raw or
//! normalized) gives `κ̂_i = κ_i`. A particle without such neighbours (or
//! unoriented) keeps its `κ_i`. On an irregular sampling one ring of
//! neighbours makes the estimate noisy (a settled Fibonacci shell: RMS
//! 15% about the true curvature, `tests/plasticity.rs`): the yield band
//! should be wider than that noise, or the memory takes it in.
//!
//! Why positions: the form term's own least-squares curvature,
//! `Σ ψ r·(n_j - n_i) / Σ ψ |r|²`, reads the neighbours' normals, and the
//! form term keeps those at the remembered relative rotation while the
//! positions are pushed. Measured on the dented shell of
//! `scenes/fig_12_plastic.ron`, it moved by at most 0.035 where the
//! positions bent by 0.66 (remembered curvature 0.25): a dent was nearly
//! invisible to it, so the memory could not yield. Letting the fitted
//! sphere's normal tilt away from `n_i` (a three-unknown fit) did not
//! reduce the noise on the settled shell, and the plastic shell of that
//! scene flew apart with it (not investigated further): not used.
//!
//! **Known limit.** The target and the form term disagree
//! wherever the normals do not follow the positions, and under a push
//! they do not: the form term ties only normal differences to positions,
//! so the pushed cap of `scenes/fig_12_plastic.ron` keeps the sphere's
//! pattern of normals (its normals' curvature `Σ r·(n_j - n_i) / Σ |r|²`
//! measured +0.03 to +0.19) while its positions, and so `κ̂_i` and the
//! memory, go to -0.5 and, on the dent's rim where `n_i` stands 35-90°
//! from the neighbours' plane, -0.7 to -1.2. A remembered curvature of
//! the other sign than the normals makes the form term push the
//! particle's neighbours to its other side: the cap is pushed through
//! its ring, which reads as a still more negative `κ̂_i`. Bounding the
//! flow by the normals' reading stops that, and the dent then springs
//! back (the memory hardly moves); a fit with a free normal (above)
//! still runs away. A plastic dent that stays needs normals that take
//! the dent, and more than one curvature per particle: the rim of a dent
//! is a crease, sharply curved across and gently along, and a scalar
//! `κ_i` of -0.7 to -1.2 there pushes the particle through its ring along
//! the rim as well. The flow that only ever lowers the stored energy
//! (towards the `κ` that minimizes the particle's form energy, the
//! normals' reading above) is stable, and the dent springs back with it
//! (`scenes/fig_12_plastic.ron`: 2.48 -> 3.56). Seed 002 §7 names the
//! missing piece as future work: a form interaction whose curvature
//! depends on the direction to the neighbour.
//!
//! A per-bond form of it, measured on that scene, is not used: each bond
//! remembers, in each emitter's body frame, an
//! offset of the form residual `κ r + n_i - n_j`, and a shift of its rest
//! length, both flowing beyond a yield (forces and torques from the
//! energy `ψ |κ r + n_i - n_j - m|²` and `U(|r| - δ)`, checked against
//! finite differences). It never runs away and the shell stays closed,
//! but the dent springs back (the side 2.0 -> 3.3-3.5, with yields from
//! 0.005 to 0.2, with hardening, and with pushes of balls of radius 2.5
//! and 3.5): the dent stretches the shell, and elastic rest lengths, or
//! rest lengths that flow back to the bond's force at rest, pull it out
//! (the cohesion lattice's rest forces are large and balance only in the
//! shape they formed in). Rest lengths that flow to zero force keep the
//! dent (the side stays at 2.2), but the pushed particles then sink as a
//! plug and the pit's walls stretch open (15-29 of 101 frames closed).
//!
//! What holds a dent is a memory of positions, not of normals: the form
//! term holds positions only through `κ r` (a sixteenth of its stiffness
//! at `κ = 1/4`). [`crate::bond_memory`] remembers each bonded partner's
//! offset in the particle's frame, metric and bend at once, and lets it
//! flow; with it and no spacing law (no rest forces to push back) the
//! shell of `scenes/fig_12_plastic.ron` keeps its whole dent and stays one
//! closed surface in every frame.
//!
//! **Return mapping.** With `e = κ_i - κ̂_i` and the yield curvature
//! `y >= 0`: within the band `|e| <= y` nothing changes (elastic); beyond
//! it the excess `x = e - sign(e) y` relaxes at `rate`, integrated exactly
//! over the step `h` with `κ̂_i` held fixed:
//! `κ_i ← κ̂_i + sign(e) (y + x e^{-rate h})`. This is a viscoplastic
//! (Perzyna-type) return mapping of the remembered curvature: a large
//! `rate` returns to the yield surface within a step (rate-independent
//! plasticity), a small one lets the memory creep. The remembered
//! curvature never crosses the band edge, so it stops there.
//!
//! **Energy.** Plasticity changes the energy landscape between steps: the
//! form energy is evaluated with the new `κ_i` from the next step on, so
//! the elastic energy a held deformation stores beyond yield is released
//! (the deformed shape becomes the remembered one) rather than given back
//! as motion. Total energy is not conserved across a plastic step, by
//! design.
//!
//! **Determinism.** `κ̂_i` does not depend on any `κ`, so every particle's
//! update is independent of the others (no dependence on slot order
//! within a step). Each estimate sums its neighbours in a fixed order
//! (incoming pairs by ascending source, then the particle's row), one
//! particle per task: the same bits at any thread count.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bonds::Bonds;
use crate::error::{non_negative, positive, ParamError};
use crate::flags::Flags;
use crate::forces::{coupling, Unbonded};
use crate::interactions::{Coupling, PreparedMaterial};
use crate::math::Real;
use crate::neighbours::NeighbourList;
use crate::particles::Particles;

/// Plasticity of a material's remembered curvature (Terzopoulos &
/// Fleischer 1988, cited by seed 000 §8): after each step, a particle whose
/// current curvature (the sphere through its neighbours' positions)
/// differs from its remembered one by more than `yield_curvature` moves
/// the memory towards it at `rate`, so a deformation beyond the yield is
/// kept. Needs the form term (`form > 0`) of the same material.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Plasticity {
    /// Yield curvature `y` (1/length, finite, >= 0): a particle whose
    /// current curvature is within `y` of its remembered one deforms
    /// elastically. 0 makes every deformation flow.
    pub yield_curvature: Real,
    /// Rate (1/time, finite, > 0) at which the excess beyond the yield band
    /// relaxes: the remembered curvature reaches the band edge with time
    /// constant `1 / rate`.
    pub rate: Real,
}

impl Plasticity {
    /// Rejects NaN, infinite and out-of-range values, naming the field.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("yield_curvature", self.yield_curvature)?;
        positive("rate", self.rate)
    }

    /// The remembered curvature after a step of length `dt` with current
    /// curvature `kappa_hat` (the return mapping of the module docs).
    /// Unchanged (the same bits) within the yield band.
    #[inline]
    pub fn relax(&self, kappa: Real, kappa_hat: Real, dt: Real) -> Real {
        let e = kappa - kappa_hat;
        let y = self.yield_curvature;
        if e.abs() <= y {
            return kappa;
        }
        let s = e.signum();
        let excess = e - s * y;
        kappa_hat + s * y + excess * (-self.rate * dt).exp()
    }
}

/// The current curvature `κ̂` of the particle in `slot` (module docs), or
/// `None` when it has no complete oriented neighbour with a nonzero weight
/// (or is unoriented). `list` must be up to date for the current positions.
/// `bonds` are the world's ([`crate::World::bonds`]): a pair that bonds
/// govern counts only when bonded, as in the force evaluation.
pub fn current_curvature(
    particles: &Particles,
    materials: &[PreparedMaterial],
    list: &NeighbourList,
    slot: usize,
    bonds: Option<&Bonds>,
) -> Option<Real> {
    let a = particles.attributes();
    if a.flags[slot].contains(Flags::UNORIENTED) {
        return None;
    }
    let material = &materials[a.materials[slot] as usize];
    let x = particles.positions();
    let pairs = list.pairs();
    let cutoff2 = list.cutoff() * list.cutoff();
    let (p_i, n_i) = (x[slot], particles.normal(slot));
    // Least squares of `κ |r|² + 2 n_i·r = 0` over the neighbours.
    let (mut num, mut den) = (0.0, 0.0);
    let incoming = pairs
        .incoming(slot)
        .iter()
        .map(|&k| pairs.pair_source(k as usize));
    let row = pairs.row(slot).iter().map(|&j| j as usize);
    for j in incoming.chain(row) {
        let c = match bonds {
            Some(b) => coupling(&a, b, slot, j),
            None => coupling(&a, &Unbonded, slot, j),
        };
        if c != (Coupling::Complete { oriented: true }) {
            continue;
        }
        let r = x[j] - p_i;
        let d2 = r.norm_squared();
        if d2 > cutoff2 || d2 == 0.0 {
            continue;
        }
        let psi = material.orientation_weight(&r, d2.sqrt(), &n_i);
        num -= 2.0 * psi * n_i.dot(&r) * d2;
        den += psi * d2 * d2;
    }
    (den > 0.0).then(|| num / den)
}

/// Scratch buffers of the plasticity stage, owned by the world.
#[derive(Debug, Default)]
pub(crate) struct PlasticScratch {
    updated: Vec<Real>,
}

/// The plasticity stage of [`crate::World::step`]: brings `list` up to date
/// for the current positions (rebuilding it if needed, as a force
/// evaluation would), estimates every plastic particle's current
/// curvature and applies the return mapping over `dt`. Returns true when
/// some remembered curvature changed.
pub(crate) fn apply(
    particles: &mut Particles,
    materials: &[PreparedMaterial],
    list: &mut NeighbourList,
    bonds: Option<&Bonds>,
    dt: Real,
    scratch: &mut PlasticScratch,
) -> bool {
    list.update(particles.positions());
    list.build_incoming();
    let n = particles.len();
    let updated = &mut scratch.updated;
    updated.resize(n, 0.0);
    {
        let p = &*particles;
        let list = &*list;
        updated
            .par_iter_mut()
            .enumerate()
            .with_min_len(crate::MIN_PARALLEL_LEN)
            .for_each(|(i, out)| {
                let kappa = p.curvatures()[i];
                let plastic = materials[p.materials()[i] as usize].plasticity();
                *out = match plastic {
                    Some(rule) => current_curvature(p, materials, list, i, bonds)
                        .map_or(kappa, |hat| rule.relax(kappa, hat, dt)),
                    None => kappa,
                };
            });
    }
    let mut changed = false;
    for (i, &k) in updated.iter().enumerate() {
        if k != particles.curvatures()[i] {
            particles.set_curvature(i, k);
            changed = true;
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_the_band_nothing_changes() {
        let p = Plasticity {
            yield_curvature: 0.1,
            rate: 5.0,
        };
        for hat in [0.25, 0.3, 0.35, 0.2] {
            assert_eq!(p.relax(0.25, hat, 0.1), 0.25);
        }
    }

    #[test]
    fn beyond_the_band_the_excess_decays_exactly() {
        let p = Plasticity {
            yield_curvature: 0.1,
            rate: 2.0,
        };
        // e = 0.5 - 0.0 = 0.5, excess 0.4.
        let k = p.relax(0.5, 0.0, 0.3);
        assert!((k - (0.1 + 0.4 * (-0.6 as Real).exp())).abs() < 1e-15);
        // Negative side: e = -0.5.
        let k = p.relax(-0.5, 0.0, 0.3);
        assert!((k + (0.1 + 0.4 * (-0.6 as Real).exp())).abs() < 1e-15);
        // Two half steps compose into one step (exact exponential).
        let (a, b) = (p.relax(p.relax(0.5, 0.0, 0.15), 0.0, 0.15), k.abs());
        assert!((a - b).abs() < 1e-15, "{a} {b}");
        // Long times stop at the band edge, never inside it.
        let end = p.relax(0.5, 0.0, 1e3);
        assert!((end - 0.1).abs() < 1e-15 && end >= 0.1);
    }

    #[test]
    fn validation_names_the_field() {
        let ok = Plasticity {
            yield_curvature: 0.0,
            rate: 1.0,
        };
        assert!(ok.validate().is_ok());
        for (bad, field) in [
            (
                Plasticity {
                    yield_curvature: -0.1,
                    ..ok
                },
                "yield_curvature",
            ),
            (
                Plasticity {
                    yield_curvature: Real::NAN,
                    ..ok
                },
                "yield_curvature",
            ),
            (Plasticity { rate: 0.0, ..ok }, "rate"),
            (
                Plasticity {
                    rate: Real::INFINITY,
                    ..ok
                },
                "rate",
            ),
        ] {
            let e = bad.validate().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("must"), "{e}");
        }
    }
}
