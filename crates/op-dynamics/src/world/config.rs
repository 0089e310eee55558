//! What the particle set and the materials enable: the kernel, the
//! neighbour radius, the typing repulsion and the stages that need
//! particular materials.

use super::{NeighbourParams, World};
use crate::error::ParamError;
use crate::flags::Flags;
use crate::forces::Kernel;
use crate::interactions::PreparedMaterial;
use crate::math::Real;
use crate::neighbours::NeighbourList;
use crate::particles::{ParticleType, Particles};

/// True when some pair of particles does not interact completely (several
/// objects, several standard types, or two hinges), so the typing repulsion
/// of seed 002 §5 can act and its cut-off counts for the neighbour radius.
fn may_repel(p: &Particles) -> bool {
    let objects = p.objects();
    if objects.iter().any(|&o| Some(&o) != objects.first()) {
        return true;
    }
    let kinds = p.kinds();
    let hinges = kinds.iter().filter(|k| **k == ParticleType::Hinge).count();
    let mut standard = kinds.iter().filter(|k| **k != ParticleType::Hinge);
    let first = standard.next();
    hinges >= 2 || standard.any(|k| Some(k) != first)
}

/// What the particle set and the materials enable (fixed when the world is
/// built, recomputed when particles are inserted or removed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Config {
    pub(super) kernel: Kernel,
    /// Largest cut-off among the enabled terms of the materials in use.
    pub(super) cutoff: Real,
    pub(super) friction: bool,
    /// Some material in use weakens with heat.
    pub(super) heated: bool,
    pub(super) has_fixed: bool,
    pub(super) repulsion: bool,
    /// Some material in use has plasticity of its remembered curvature.
    pub(super) plastic: bool,
    /// Some material in use has a bond memory (it turns the particles).
    pub(super) memory: bool,
    /// Some material in use has a bond memory that flows.
    pub(super) memory_flows: bool,
}

impl Config {
    /// The configuration of `particles` with these (prepared) materials;
    /// every particle's material index must exist.
    pub(super) fn of(particles: &Particles, prepared: &[PreparedMaterial]) -> Config {
        let used: Vec<&PreparedMaterial> = {
            let mut seen = vec![false; prepared.len()];
            particles
                .materials()
                .iter()
                .for_each(|&m| seen[m as usize] = true);
            prepared
                .iter()
                .zip(seen)
                .filter(|(_, s)| *s)
                .map(|(m, _)| m)
                .collect()
        };
        // Bond-governed pairs of one object that are not bonded repel.
        let repulsion = may_repel(particles) || used.iter().any(|m| m.bonds().is_some());
        let cutoff = used
            .iter()
            .map(|m| {
                let c = m.spacing_cutoff().max(m.orientation_cutoff());
                if repulsion {
                    c.max(m.repulsion_cutoff())
                } else {
                    c
                }
            })
            .fold(0.0, Real::max);
        let friction = used.iter().any(|m| m.friction() > 0.0);
        let heated = used.iter().any(|m| m.heat_response().is_some());
        let oriented = used.iter().any(|m| m.has_orientation_terms());
        let kernel = if cutoff <= 0.0 || particles.len() < 2 {
            Kernel::None
        } else if oriented || friction {
            Kernel::Oriented
        } else {
            Kernel::Spacing
        };
        Config {
            kernel,
            cutoff,
            friction,
            heated,
            has_fixed: particles
                .flags()
                .iter()
                .any(|f| f.contains(Flags::FIXED_POSITION) || f.contains(Flags::FIXED_ORIENTATION)),
            repulsion,
            plastic: used.iter().any(|m| m.plasticity().is_some()),
            memory: used.iter().any(|m| m.bond_memory().is_some()),
            memory_flows: used
                .iter()
                .any(|m| m.bond_memory().is_some_and(|b| b.flow.is_some())),
        }
    }

    /// The neighbour list this configuration needs (none without a kernel).
    ///
    /// Cannot fail once [`neighbour_radius_check`] accepted every material:
    /// the configuration's cut-off is one of theirs.
    pub(super) fn neighbour_list(&self, params: &NeighbourParams) -> Option<NeighbourList> {
        (self.kernel != Kernel::None)
            .then(|| NeighbourList::new(params.backend, self.cutoff, self.cutoff * params.skin))
    }
}

impl World {
    /// Takes the kernel and the flags of `config` (what the materials in
    /// use enable), after its particles changed ([`World::insert_particles`]
    /// and the other edits) or were restored from a checkpoint; the
    /// neighbour list is the caller's.
    pub(super) fn apply_config(&mut self, config: &Config) {
        self.model.kernel = config.kernel;
        self.model.friction = config.friction;
        self.model.heated = config.heated;
        self.model.memory = config.memory;
        self.model.has_fixed = config.has_fixed;
        self.repulsion = config.repulsion;
        self.plastic = config.plastic;
        self.memory_flows = config.memory_flows;
    }
}

/// Checks that every material's cut-off with the skin gives a neighbour
/// list (a finite radius `cutoff * (1 + skin)`), so that no later choice of
/// the materials in use (particles inserted by [`World::insert_particles`]
/// included) can meet an impossible list.
pub(super) fn neighbour_radius_check(
    prepared: &[PreparedMaterial],
    params: &NeighbourParams,
) -> Result<(), ParamError> {
    for (k, m) in prepared.iter().enumerate() {
        let cutoff = m.cutoff();
        if NeighbourList::try_new(params.backend, cutoff, cutoff * params.skin).is_err() {
            return Err(ParamError::Invalid {
                field: format!("materials[{k}]"),
                message: format!(
                    "cut-off {cutoff} with neighbours.skin {}: the neighbour radius \
                     cutoff * (1 + skin) = {} is not a finite number; lower the cut-offs \
                     (spacing, weight, repulsion) or the skin",
                    params.skin,
                    cutoff + cutoff * params.skin
                ),
            });
        }
    }
    Ok(())
}
