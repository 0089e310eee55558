//! The relaxation of a creation round, local to the new particles.
//!
//! Seed 000 §7 fills the gaps between fixed samples by rounds of creation,
//! each followed by a relaxation of the new particles towards the
//! near-equilibrium the rules assume. The seeds are fixed and the particles
//! relaxed in earlier rounds are near equilibrium, so only the particles
//! within the interaction reach of the new ones move appreciably: the
//! round relaxes those (the *active* set: the new particles and the created
//! ones within the cohesion cut-off of one) in a world of their own, with
//! every particle within the cut-off plus a margin of an active one held
//! fixed around them. The fixed ring holds every particle an active one
//! can interact with as long as none moves more than the margin; a round
//! in which one did is run again from the same start with twice the margin
//! (at most [`MAX_TRIES`] times). A round then costs in proportion to the
//! particles it creates, not to the whole surface: on the 26,002 vertices
//! of a scanned armadillo, 20 whole-world rounds took 40 s.

use std::collections::HashMap;

use op_dynamics::{Flags, Material, Particles, Point3, Real, World, WorldParams};

use super::{at_rest, FitError};

/// Runs of a round with a growing margin before the last one is kept.
pub(super) const MAX_TRIES: usize = 4;

/// A uniform hash grid of particle slots with cells of side `cell`.
struct Cells {
    cell: Real,
    map: HashMap<[i64; 3], Vec<usize>>,
}

impl Cells {
    fn new(points: &[Point3], cell: Real) -> Self {
        let mut map: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (s, p) in points.iter().enumerate() {
            map.entry(key(p, cell)).or_default().push(s);
        }
        Cells { cell, map }
    }

    /// Calls `f` with every slot within `r <= cell` of `p`.
    fn within(&self, points: &[Point3], p: &Point3, r: Real, mut f: impl FnMut(usize)) {
        let k = key(p, self.cell);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let c = [
                        k[0].saturating_add(dx),
                        k[1].saturating_add(dy),
                        k[2].saturating_add(dz),
                    ];
                    for &s in self.map.get(&c).into_iter().flatten() {
                        if (points[s] - p).norm() <= r {
                            f(s);
                        }
                    }
                }
            }
        }
    }
}

fn key(p: &Point3, cell: Real) -> [i64; 3] {
    [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64)
}

/// Relaxes the particles `new` (ids) of `world` for time `t` with the
/// particles created in earlier rounds near them (see the module
/// documentation), from rest, and writes their positions and orientations
/// back. `cutoff` is the cohesion cut-off, `margin` the first margin of
/// the fixed ring; `material` and `params` are those of `world`.
///
/// Returns the number of active particles (the last run's).
///
/// # Errors
/// A sub-world that cannot be built or that diverged.
pub(super) fn relax_new(
    world: &mut World,
    new: &[u32],
    t: Real,
    cutoff: Real,
    margin: Real,
    material: &Material,
    params: &WorldParams,
) -> Result<usize, FitError> {
    let p = world.particles();
    let positions = p.positions();
    let flags = p.flags();
    let mut is_new = vec![false; p.len()];
    let mut new_slots = Vec::with_capacity(new.len());
    for &id in new {
        let s = p
            .slot_of(id)
            .ok_or_else(|| FitError::World(format!("created particle {id} is not in the world")))?;
        is_new[s] = true;
        new_slots.push(s);
    }
    // Active: the new particles and the free ones within the cut-off.
    let mut active = is_new.clone();
    let mut cells = Cells::new(positions, cutoff);
    for &s in &new_slots {
        cells.within(positions, &positions[s], cutoff, |j| {
            if !flags[j].contains(Flags::FIXED_POSITION) {
                active[j] = true;
            }
        });
    }
    let active_slots: Vec<usize> = (0..p.len()).filter(|&s| active[s]).collect();
    let mut margin = margin;
    let mut attempt = 1;
    let updates = loop {
        let reach = cutoff + margin;
        if cells.cell < reach {
            cells = Cells::new(positions, reach);
        }
        let mut ring = vec![false; p.len()];
        for &s in &active_slots {
            cells.within(positions, &positions[s], reach, |j| {
                if !active[j] {
                    ring[j] = true;
                }
            });
        }
        // Members in slot order: the sub-world is a function of the state.
        let mut sub = Particles::new();
        let mut members = Vec::new();
        for s in (0..p.len()).filter(|&s| active[s] || ring[s]) {
            let mut d = at_rest(p, s);
            d.flags = if active[s] {
                flags[s]
            } else {
                flags[s]
                    .union(Flags::FIXED_POSITION)
                    .union(Flags::FIXED_ORIENTATION)
            };
            let id = sub.push(d)?;
            if active[s] {
                members.push((s, id));
            }
        }
        let mut local = World::new(sub, std::slice::from_ref(material), params.clone())?;
        let end = local.time() + t;
        local.advance_to(end)?;
        let lp = local.particles();
        let mut updates = Vec::with_capacity(members.len());
        let mut moved: Real = 0.0;
        for &(s, id) in &members {
            let slot = lp
                .slot_of(id)
                .ok_or_else(|| FitError::World(format!("particle {id} left the round's world")))?;
            moved = moved.max((lp.positions()[slot] - positions[s]).norm());
            updates.push((s, lp.positions()[slot], lp.orientations()[slot]));
        }
        if moved <= margin || attempt == MAX_TRIES {
            break updates;
        }
        margin *= 2.0;
        attempt += 1;
    };
    let count = updates.len();
    let pm = world.particles_mut();
    for (s, x, q) in updates {
        pm.set_position(s, x);
        pm.set_orientation(s, q);
    }
    Ok(count)
}
