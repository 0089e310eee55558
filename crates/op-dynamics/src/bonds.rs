//! Explicit bonds: which pairs of one object interact completely, and when
//! they tear (seed 000 §8, fig. 12a cloth draping and fig. 12c tearing;
//! seed 002 §5 for the repulsion of pairs that do not interact completely).
//!
//! Without bonds a pair of one object interacts completely whenever it is
//! within the cut-off, so two layers of a folded cloth bind to each other,
//! and a torn sheet necks and flows before it separates. A material with
//! [`BondParams`] fixes the topology instead:
//!
//! - **Formation.** When the world is built, every pair of particles that
//!   would interact completely (same object, compatible types, seed 002 §5)
//!   and of which at least one has a bonded material is *bonded* when its
//!   distance is at most the pair's bond radius. When particles are
//!   inserted ([`crate::World::insert_particles`]), each new particle bonds
//!   the same way to every live particle (old or new) within the radius at
//!   that moment; pairs of old particles are not revisited (a broken bond
//!   stays broken).
//! - **Coupling.** A bonded pair interacts completely (spacing and
//!   orientation terms, friction), exactly as an unbonded world would; a
//!   *bond-governed* pair (at least one bonded material) that is not bonded
//!   gets only the exponential repulsion (`Coupling::RepulsionOnly`), so
//!   folded layers of one cloth slide over each other instead of binding.
//!   Pairs of two particles without bonded materials are unaffected.
//! - **Breaking.** After each step (after integration, before erasers
//!   act), every bond whose length exceeds the pair's break length breaks
//!   for good. Tearing is then a clean break of the bond graph.
//!   A break length beyond the interaction cut-off leaves pairs bonded
//!   but without force once apart; they re-attract if they meet again.
//! - **Removal.** Bonds of removed particles are dropped (not counted as
//!   broken).
//!
//! Pair rule: when both materials are bonded the pair's radius and break
//! length are the smaller of the two; when one is, its own.
//!
//! Bonds are stored by stable particle id ([`crate::Particles::ids`]), so
//! they survive spatial re-sorting, insertion and removal, and every
//! decision is made in id order: the bond set is the same at any thread
//! count and slot order.
//!
//! The energy of a bonded pair is the energy of a complete pair, so forces
//! stay its gradient between breaks; a break is an irreversible event
//! between steps (the pair's energy jumps from the spacing potential to the
//! repulsion, both near zero at the break length of a cut-off potential).
//!
//! **Cost.** Worlds without bonded materials run the pair kernels with a
//! constant lookup (see the world's force pass, `forces.rs`): criterion `world_step/
//! spacing_only/10000` at one thread, medians of three alternated runs
//! each, 2.91 ms before bonds existed (runs 2.34-2.95) and 2.78 ms after
//! (2.39-2.96), on a 2-core machine at load 9 (other builds): no
//! difference beyond the noise. With bonds (`world_step/*_bonded/10000`
//! in the same bench: radius 1.2, breaking beyond 1.5, criterion medians
//! [low high] on 2 threads): cohesion only 1.78 ms [1.57 1.93] against
//! 1.95 ms [1.75 2.06] unbonded, the full oriented material 7.21 ms
//! [7.04 7.54] against 8.82 ms [8.52 9.36] (pairs beyond the bond radius
//! only repel and skip the orientation terms; the lookup and the breaking
//! pass cost less than that saves on this sheet).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bond_memory;
use crate::error::{self, ParamError};
use crate::interactions::PreparedMaterial;
use crate::math::{Real, Vec3};
use crate::neighbours::{search, NeighbourBackend, PairList};
use crate::particles::Particles;

/// The bond rule of a material: pairs of one object within `radius` when
/// the world is built (or a particle is inserted) are bonded and interact
/// completely; unbonded pairs of a bonded material only repel; a bond
/// stretched beyond `break_length` breaks for good (seed 000 fig. 12).
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct BondParams {
    /// Pairs within this distance when the world is built (or when one of
    /// them is inserted) are bonded, > 0. Default: 1.2 (a hexagonal sheet
    /// of spacing 1 bonds its six nearest neighbours, not the next ones at
    /// 1.73).
    pub radius: Real,
    /// A bond breaks for good when its length exceeds this (finite,
    /// greater than `radius`); `None`: bonds never break. Default: `None`.
    pub break_length: Option<Real>,
}

impl Default for BondParams {
    fn default() -> Self {
        BondParams {
            radius: 1.2,
            break_length: None,
        }
    }
}

impl BondParams {
    /// Rejects NaN and out-of-range values: `radius` finite and > 0,
    /// `break_length` finite and > `radius` (bonds formed within the
    /// radius must not break at once).
    pub fn validate(&self) -> Result<(), ParamError> {
        error::positive("radius", self.radius)?;
        match self.break_length {
            Some(b) => error::check(
                "break_length",
                b,
                b.is_finite() && b > self.radius,
                &format!(
                    "must be finite and > radius = {} (omit it for bonds that never break)",
                    self.radius
                ),
            ),
            None => Ok(()),
        }
    }

    /// The break length as a number (infinity when bonds never break).
    fn limit(&self) -> Real {
        self.break_length.unwrap_or(Real::INFINITY)
    }

    /// The rule of a pair whose materials have these rules (`None`: not
    /// bond-governed).
    fn of_pair(a: Option<&BondParams>, b: Option<&BondParams>) -> Option<BondParams> {
        match (a, b) {
            (Some(a), Some(b)) => Some(BondParams {
                radius: a.radius.min(b.radius),
                break_length: match (a.break_length, b.break_length) {
                    (Some(x), Some(y)) => Some(x.min(y)),
                    (x, y) => x.or(y),
                },
            }),
            (Some(r), None) | (None, Some(r)) => Some(*r),
            (None, None) => None,
        }
    }
}

/// The bonds of a world, by stable particle id (built by the world; read
/// it through [`crate::World::bonds`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Bonds {
    /// Live bonds `(lower id, higher id)`, sorted.
    pairs: Vec<(u32, u32)>,
    /// Break length of each live bond (parallel to `pairs`; infinity for
    /// bonds that never break).
    break_lengths: Vec<Real>,
    /// Rest offsets of each live bond (parallel to `pairs`): the higher id
    /// seen from the lower id's body frame, and the reverse
    /// ([`crate::bond_memory`]; read only for memory materials).
    rest: Vec<[Vec3; 2]>,
    /// Partners of id `k`: `partners[offsets[k]..offsets[k + 1]]`, sorted.
    offsets: Vec<u32>,
    partners: Vec<u32>,
    /// Whether material `k` is bonded (pairs with one are governed).
    governed: Vec<bool>,
    /// Bonds broken since the world was built.
    broken: u64,
    /// Scratch of the breaking pass: bond `k` is over-stretched.
    #[serde(skip)]
    stretched: Vec<bool>,
}

impl Bonds {
    /// True when some particle of `particles` has a bonded material: the
    /// world needs a bond store.
    pub(crate) fn needed(particles: &Particles, materials: &[PreparedMaterial]) -> bool {
        particles
            .materials()
            .iter()
            .any(|&m| materials[m as usize].bonds().is_some())
    }

    /// An empty store for these materials.
    pub(crate) fn new(materials: &[PreparedMaterial]) -> Bonds {
        Bonds {
            pairs: Vec::new(),
            break_lengths: Vec::new(),
            rest: Vec::new(),
            offsets: vec![0],
            partners: Vec::new(),
            governed: materials.iter().map(|m| m.bonds().is_some()).collect(),
            broken: 0,
            stretched: Vec::new(),
        }
    }

    /// Forms the bonds of every pair with at least one particle of id
    /// `>= first_new` (all pairs for 0), by the rule of the module docs.
    pub(crate) fn form(
        &mut self,
        particles: &Particles,
        materials: &[PreparedMaterial],
        first_new: u32,
    ) {
        let radius = materials
            .iter()
            .filter_map(|m| m.bonds().map(|b| b.radius))
            .fold(0.0, Real::max);
        let mut list = PairList::new();
        search(
            NeighbourBackend::default(),
            particles.positions(),
            radius,
            &mut list,
        );
        let a = particles.attributes();
        let p = particles.positions();
        let mut added = 0;
        for (i, j) in list.iter_pairs() {
            let (id_i, id_j) = (a.ids[i], a.ids[j]);
            if id_i.max(id_j) < first_new
                || a.objects[i] != a.objects[j]
                || !a.kinds[i].complete_with(a.kinds[j])
            {
                continue;
            }
            let rule = BondParams::of_pair(
                materials[a.materials[i] as usize].bonds(),
                materials[a.materials[j] as usize].bonds(),
            );
            if let Some(rule) = rule {
                if (p[j] - p[i]).norm_squared() <= rule.radius * rule.radius {
                    self.pairs.push((id_i.min(id_j), id_i.max(id_j)));
                    self.break_lengths.push(rule.limit());
                    let (lo, hi) = if id_i < id_j { (i, j) } else { (j, i) };
                    self.rest.push(bond_memory::rest_offsets(particles, lo, hi));
                    added += 1;
                }
            }
        }
        if added > 0 {
            self.sort();
        }
        self.reindex(particles.id_bound());
    }

    /// Drops the bonds with an endpoint that is no longer alive.
    pub(crate) fn retain_live(&mut self, particles: &Particles) {
        let alive = |id: u32| particles.slot_of(id).is_some();
        let keep: Vec<bool> = self
            .pairs
            .iter()
            .map(|&(a, b)| alive(a) && alive(b))
            .collect();
        self.retain(&keep);
        self.reindex(particles.id_bound());
    }

    /// Breaks every bond longer than its break length at the current
    /// positions; returns how many broke. The test runs in parallel into a
    /// scratch mask, the removal in bond order: deterministic.
    pub(crate) fn break_stretched(&mut self, particles: &Particles) -> usize {
        let p = particles.positions();
        let slot_of = particles.attributes().slot_of;
        self.stretched.resize(self.pairs.len(), false);
        self.stretched
            .par_iter_mut()
            .zip(self.pairs.par_iter().zip(self.break_lengths.par_iter()))
            .with_min_len(4096)
            .for_each(|(s, (&(a, b), &limit))| {
                let (i, j) = (slot_of[a as usize] as usize, slot_of[b as usize] as usize);
                let d2 = (p[j] - p[i]).norm_squared();
                // NaN positions (a diverging run) break nothing here: the
                // world's divergence check reports them.
                *s = d2 > limit * limit;
            });
        let count = self.stretched.iter().filter(|&&s| s).count();
        if count > 0 {
            let keep: Vec<bool> = self.stretched.iter().map(|&s| !s).collect();
            self.retain(&keep);
            self.reindex(particles.id_bound());
            self.broken += count as u64;
        }
        count
    }

    /// Whether the pair of particles with ids `a` and `b` is bonded.
    #[inline]
    pub fn contains(&self, a: u32, b: u32) -> bool {
        let (lo, hi) = (a.min(b) as usize, a.max(b));
        match (self.offsets.get(lo), self.offsets.get(lo + 1)) {
            (Some(&s), Some(&e)) => self.partners[s as usize..e as usize].contains(&hi),
            _ => false,
        }
    }

    /// Whether a pair of particles with these material indices is governed
    /// by bonds (at least one bonded material).
    #[inline]
    pub fn governs(&self, material_a: u16, material_b: u16) -> bool {
        self.governed[material_a as usize] || self.governed[material_b as usize]
    }

    /// Number of live bonds.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// True when no bond is live.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Live bonds as `(lower id, higher id)`, sorted.
    pub fn pairs(&self) -> &[(u32, u32)] {
        &self.pairs
    }

    /// Rest offsets of the live bonds, parallel to [`Bonds::pairs`]: the
    /// higher id's offset in the lower id's body frame, and the reverse, as
    /// remembered ([`crate::bond_memory`]).
    pub fn rest_offsets(&self) -> &[[Vec3; 2]] {
        &self.rest
    }

    /// The live bonds with their remembered offsets, to flow them.
    pub(crate) fn pairs_and_rest_mut(&mut self) -> (&[(u32, u32)], &mut [[Vec3; 2]]) {
        (&self.pairs, &mut self.rest)
    }

    /// Bonds broken by over-stretching since the world was built.
    pub fn broken(&self) -> u64 {
        self.broken
    }

    fn sort(&mut self) {
        let mut order: Vec<usize> = (0..self.pairs.len()).collect();
        order.sort_unstable_by_key(|&k| self.pairs[k]);
        self.pairs = order.iter().map(|&k| self.pairs[k]).collect();
        self.break_lengths = order.iter().map(|&k| self.break_lengths[k]).collect();
        self.rest = order.iter().map(|&k| self.rest[k]).collect();
    }

    fn retain(&mut self, keep: &[bool]) {
        let mut k = 0;
        self.pairs.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        let mut k = 0;
        self.break_lengths.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        let mut k = 0;
        self.rest.retain(|_| {
            k += 1;
            keep[k - 1]
        });
    }

    /// Rebuilds the by-id partner index (lower id -> higher ids).
    fn reindex(&mut self, id_bound: usize) {
        self.offsets.clear();
        self.offsets.resize(id_bound + 1, 0);
        for &(a, _) in &self.pairs {
            self.offsets[a as usize + 1] += 1;
        }
        for k in 0..id_bound {
            self.offsets[k + 1] += self.offsets[k];
        }
        // `pairs` is sorted, so each id's partners come out sorted.
        self.partners.clear();
        self.partners.extend(self.pairs.iter().map(|&(_, b)| b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_field_and_the_rule() {
        assert!(BondParams::default().validate().is_ok());
        for (b, needle) in [
            (
                BondParams {
                    radius: Real::NAN,
                    ..Default::default()
                },
                "`radius` = NaN",
            ),
            (
                BondParams {
                    radius: 0.0,
                    ..Default::default()
                },
                "`radius` = 0",
            ),
            (
                BondParams {
                    radius: 1.2,
                    break_length: Some(1.2),
                },
                "must be finite and > radius",
            ),
            (
                BondParams {
                    radius: 1.2,
                    break_length: Some(Real::NAN),
                },
                "`break_length` = NaN",
            ),
            (
                BondParams {
                    radius: 1.2,
                    break_length: Some(Real::INFINITY),
                },
                "`break_length` = inf",
            ),
        ] {
            let e = b.validate().unwrap_err().to_string();
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }

    #[test]
    fn pair_rule_takes_the_smaller_values() {
        let a = BondParams {
            radius: 1.2,
            break_length: Some(2.0),
        };
        let b = BondParams {
            radius: 1.5,
            break_length: Some(1.4),
        };
        let never = BondParams {
            radius: 1.1,
            break_length: None,
        };
        assert_eq!(
            BondParams::of_pair(Some(&a), Some(&b)),
            Some(BondParams {
                radius: 1.2,
                break_length: Some(1.4)
            })
        );
        assert_eq!(
            BondParams::of_pair(Some(&never), Some(&b)),
            Some(BondParams {
                radius: 1.1,
                break_length: Some(1.4)
            })
        );
        assert_eq!(BondParams::of_pair(None, Some(&b)), Some(b));
        assert_eq!(BondParams::of_pair(None, None), None);
        assert_eq!(never.limit(), Real::INFINITY);
    }
}
