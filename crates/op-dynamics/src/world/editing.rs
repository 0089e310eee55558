//! Particle insertion and deletion (seed 000 §7: the creation rules add
//! particles while the simulation runs; erasers and point-set fitting remove
//! them).
//!
//! Both edits keep everything sized by particle count consistent: the
//! particle store (every attribute, survivors keep their ids and relative
//! slot order), the world's force buffers, the previous positions of the
//! oscillation measure, the external accumulator (indexed by id), the
//! integrator's cached forces (invalidated; its buffers are resized at the
//! next step), and the neighbour list (marked stale, so the next step
//! re-sorts the particles in spatial order and rebuilds it, exactly as for a
//! freshly built world). What the particle set enables (kernel, neighbour
//! radius, typing repulsion, fixed particles) is recomputed as in
//! [`World::new`]. The result is deterministic: after an edit, stepping
//! gives the same bits as a world built directly from the edited particle
//! set in the same slot order (tested in `tests/world_editing.rs`).
//!
//! Merging ([`World::merge_particles`], (op-modeling `creation::merging`)) moves
//! each survivor and removes the other particle of its pair: one removal.
//!
//! Bonds ([`crate::bonds`]): inserted particles bond to every live particle
//! (old or inserted) within the bond radius at insertion, as at build; bonds
//! between old particles are left as they are (broken ones stay broken).
//! Bonds of removed particles are dropped.

use super::{Config, World, WorldError};
use crate::bonds::Bonds;
use crate::error::ParamError;
use crate::math::{Point3, Real, Vec3};
use crate::particles::ParticleDesc;

impl World {
    /// Inserts particles (validated first: nothing is inserted when one of
    /// them is invalid or names a material that does not exist) after the
    /// existing slots. Returns their new stable ids, in the order given. An
    /// empty list changes nothing (cached forces and the neighbour list
    /// stay).
    ///
    /// # Errors
    /// [`WorldError::Param`] naming `particles[k].<field>` for an invalid
    /// description.
    pub fn insert_particles(&mut self, descs: &[ParticleDesc]) -> Result<Vec<u32>, WorldError> {
        let materials = self.model.materials.len();
        for (k, d) in descs.iter().enumerate() {
            d.validate()
                .map_err(|e| e.within(&format!("particles[{k}]")))?;
            if d.material as usize >= materials {
                return Err(ParamError::Invalid {
                    field: format!("particles[{k}].material"),
                    message: format!(
                        "material index {} does not exist ({materials} materials defined)",
                        d.material
                    ),
                }
                .into());
            }
        }
        if descs.is_empty() {
            return Ok(Vec::new());
        }
        let mut ids = Vec::with_capacity(descs.len());
        for d in descs {
            self.may_rotate |= d.angular_velocity != Vec3::zeros()
                && !d.flags.contains(crate::flags::Flags::FIXED_ORIENTATION);
            ids.push(self.particles.push(d.clone())?);
        }
        if let Some(&first) = ids.first() {
            let (p, m) = (&self.particles, &self.model.materials);
            if self.model.bonds.is_none() && Bonds::needed(p, m) {
                self.model.bonds = Some(Bonds::new(m));
            }
            if let Some(b) = self.model.bonds.as_mut() {
                b.form(p, m, first);
            }
        }
        let p = self.particles.positions();
        let old = self.prev_positions.len();
        self.prev_positions.extend_from_slice(&p[old..]);
        self.after_edit();
        Ok(ids)
    }

    /// Removes the particles with the given ids; survivors keep their ids.
    /// Returns how many were removed. Repeated ids count once; an empty
    /// list changes nothing (cached forces and the neighbour list stay).
    ///
    /// # Errors
    /// [`WorldError::Param`] (field `ids`) when an id does not name a live
    /// particle; nothing is removed then.
    pub fn remove_particles(&mut self, ids: &[u32]) -> Result<usize, WorldError> {
        if let Some(&bad) = ids.iter().find(|&&id| self.particles.slot_of(id).is_none()) {
            return Err(ParamError::Invalid {
                field: "ids".into(),
                message: format!("particle id {bad} does not exist (never created or removed)"),
            }
            .into());
        }
        if ids.is_empty() {
            return Ok(0);
        }
        Ok(self.remove_live(ids))
    }

    /// Applies merges of the merging rule ((op-modeling `creation::merging`)):
    /// each survivor takes its merge's position, velocity and temperature,
    /// then the merged-away particles are removed. Returns how many were
    /// removed.
    ///
    /// # Errors
    /// [`WorldError::Param`] (field `merges`) when an id does not name a
    /// live particle or a particle appears in two merges; nothing changes
    /// then.
    pub fn merge_particles(&mut self, merges: &[Merge]) -> Result<usize, WorldError> {
        let mut seen = std::collections::HashSet::new();
        for m in merges {
            for id in [m.survivor, m.removed] {
                let problem = if self.particles.slot_of(id).is_none() {
                    "does not exist (never created or removed)"
                } else if !seen.insert(id) {
                    "appears in two merges"
                } else {
                    continue;
                };
                return Err(ParamError::Invalid {
                    field: "merges".into(),
                    message: format!("particle id {id} {problem}"),
                }
                .into());
            }
        }
        if merges.is_empty() {
            return Ok(0);
        }
        for m in merges {
            let s = self.particles.slot_of(m.survivor).expect("checked live");
            self.particles.set_position(s, m.position);
            self.particles.set_velocity(s, m.velocity);
            self.particles.set_temperature(s, m.temperature);
        }
        let removed: Vec<u32> = merges.iter().map(|m| m.removed).collect();
        Ok(self.remove_live(&removed))
    }

    /// [`World::remove_particles`] for ids known to name live particles
    /// (the eraser tools' hook in [`World::step`]).
    pub(super) fn remove_live(&mut self, ids: &[u32]) -> usize {
        let before = self.particles.len();
        let keep = self.particles.remove(ids);
        let prev: Vec<_> = keep
            .iter()
            .map(|&s| self.prev_positions[s as usize])
            .collect();
        self.prev_positions = prev;
        if Bonds::needed(&self.particles, &self.model.materials) {
            if let Some(b) = self.model.bonds.as_mut() {
                b.retain_live(&self.particles);
            }
        } else {
            self.model.bonds = None;
        }
        self.after_edit();
        before - self.particles.len()
    }

    /// Re-derives what depends on the particle set after an edit.
    fn after_edit(&mut self) {
        let n = self.particles.len();
        let config = Config::of(&self.particles, &self.model.materials);
        let same_list =
            self.model.neighbours.as_ref().is_some_and(|l| {
                config.kernel != super::Kernel::None && l.cutoff() == config.cutoff
            });
        if same_list {
            if let Some(list) = self.model.neighbours.as_mut() {
                list.invalidate();
            }
        } else {
            self.model.neighbours = config.neighbour_list(&self.params.neighbours);
        }
        self.apply_config(&config);
        self.may_rotate |= config.memory;
        self.accumulator.grow(self.particles.id_bound());
        self.forces.clear();
        self.forces.resize(n, Vec3::zeros());
        self.torques.clear();
        self.torques.resize(n, Vec3::zeros());
        self.integrator.invalidate();
        self.sync_built_in_stages();
    }
}

/// One merge of the merging rule (op-modeling `creation::merging`): particle `removed` joins particle `survivor`, which takes
/// the new `position`, `velocity` and `temperature`.
#[derive(Clone, Debug, PartialEq)]
pub struct Merge {
    /// Id of the particle that stays.
    pub survivor: u32,
    /// Id of the particle that is removed.
    pub removed: u32,
    /// The survivor's new position.
    pub position: Point3,
    /// The survivor's new velocity.
    pub velocity: Vec3,
    /// The survivor's new temperature.
    pub temperature: Real,
}
