//! The merging rule: two particles of one object that have come to lie on
//! top of each other become one (our counterpart of seed 000 §7's
//! stretching rule, which keeps the sampling from growing too sparse; this
//! one keeps it from growing too dense).
//!
//! Why it is needed: the cohesion force of seed 002 §3 has no hard core
//! (`f(r) = E (r0 - r)³ / r · exp(-α (r0 - r)²)` vanishes as `r → 0` for
//! the usual `α`, see [`op_dynamics::interactions::cohesion`]), so two particles
//! pushed past its repulsive barrier (by a tool pressing two layers of a
//! surface together, or by a rim welding onto another) stay together for
//! good. Such a pair is one surface element counted twice: the
//! triangulation (seed 000 §5) then builds slivers and edges shared by
//! three triangles around it. Seed 000's figure 14 (a sphere pushed into a
//! torus) leaves dozens of such pairs where the two dimples meet.
//!
//! **Rule.** Two particles of the same object less than `distance · r0`
//! apart merge: the survivor takes their mass-weighted mean position,
//! velocity and temperature, keeps its own frame, spin, mass and rest
//! curvature, and the other particle is removed. The survivor is the one
//! with a fixed position if there is one (it keeps its position and
//! velocity; two fixed particles never merge), otherwise the one with the
//! smaller id. Like the creation of particles, a merge changes the
//! discretisation, so it does not conserve momentum exactly (the removed
//! particle's mass goes with it).
//!
//! **Determinism**: pairs are taken in ascending order of their id pairs,
//! and a particle merges at most once per application (a cluster of three
//! coincident particles takes two applications). The result does not
//! depend on slots or the thread count.

use serde::{Deserialize, Serialize};

use op_dynamics::error::{self, ParamError};
use op_dynamics::flags::Flags;
use op_dynamics::math::{Point3, Real};
use op_dynamics::neighbours::{search, NeighbourBackend, PairList};
use op_dynamics::particles::Particles;
use op_dynamics::Merge;

/// Parameters of the merging rule, lengths as fractions of `r0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MergingParams {
    /// Pairs closer than this merge, in (0, 1). Default: 0.3.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    pub distance: Real,
}

impl Default for MergingParams {
    fn default() -> Self {
        MergingParams { distance: 0.3 }
    }
}

impl MergingParams {
    /// Checks `0 < distance < 1`.
    pub fn validate(&self) -> Result<(), ParamError> {
        error::check(
            "distance",
            self.distance,
            self.distance > 0.0 && self.distance < 1.0,
            "must be in (0, 1) (a fraction of the rest spacing r0)",
        )
    }
}

/// The merges the rule makes now, in ascending order of their id pairs.
pub fn merges(p: &Particles, r0: Real, params: &MergingParams) -> Vec<Merge> {
    let radius = params.distance * r0;
    let mut pairs = PairList::new();
    search(
        NeighbourBackend::CellList,
        p.positions(),
        radius,
        &mut pairs,
    );
    let (ids, flags, objects) = (p.ids(), p.flags(), p.objects());
    let fixed = |k: usize| flags[k].contains(Flags::FIXED_POSITION);
    let mut close: Vec<(u32, u32, usize, usize)> = pairs
        .iter_pairs()
        .filter(|&(i, j)| {
            objects[i] == objects[j]
                && !(fixed(i) && fixed(j))
                && (p.positions()[j] - p.positions()[i]).norm_squared() < radius * radius
        })
        .map(|(i, j)| {
            if ids[i] < ids[j] {
                (ids[i], ids[j], i, j)
            } else {
                (ids[j], ids[i], j, i)
            }
        })
        .collect();
    close.sort_unstable_by_key(|c| (c.0, c.1));
    let mut taken = vec![false; p.len()];
    let mut out = Vec::new();
    for (_, _, a, b) in close {
        if taken[a] || taken[b] {
            continue;
        }
        taken[a] = true;
        taken[b] = true;
        let (s, r) = if fixed(b) { (b, a) } else { (a, b) };
        out.push(merged(p, s, r));
    }
    out
}

/// The merge of the particle in slot `r` into the one in slot `s`.
fn merged(p: &Particles, s: usize, r: usize) -> Merge {
    let (ms, mr) = (p.masses()[s], p.masses()[r]);
    let (ws, wr) = (ms / (ms + mr), mr / (ms + mr));
    let (x, v) = (p.positions(), p.velocities());
    let temperature = ws * p.temperatures()[s] + wr * p.temperatures()[r];
    let (position, velocity) = if p.flags()[s].contains(Flags::FIXED_POSITION) {
        (x[s], v[s])
    } else {
        (
            Point3::from(ws * x[s].coords + wr * x[r].coords),
            ws * v[s] + wr * v[r],
        )
    };
    Merge {
        survivor: p.ids()[s],
        removed: p.ids()[r],
        position,
        velocity,
        temperature,
    }
}
